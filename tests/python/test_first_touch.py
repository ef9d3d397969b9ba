"""First touch through the binding (issue 22 item 8; docs/grasp.md "First touch"): with the contact skin
(WorldDef.skin_depth) a palm laid onto a resting plate presses it onto the ground instead of tilting it."""
import math

import numpy as np
import pytest

import handsim
from handsim import recording

RIGHT = handsim.Handedness.RIGHT
HALF = (0.06, 0.005, 0.06)  # the plate: 12 x 1 x 12 cm, 150 g


def lower_palm_onto_plate(world_def, speed=0.10, hz=60.0, rest=0.002):
    """Largest displacement (m) and turn (deg) of the plate while the palm-down hand is lowered onto it at
    `speed` from 2 cm above until its lowest particle over the plate overlaps the top by `rest`, then held."""
    world = handsim.World(world_def)
    hand = world.add_hand(handsim.HandDef(handedness=RIGHT, particle_count=1182))
    plate = world.add_body(handsim.BodyDef(shape=handsim.Shape.box(list(HALF)), mass=0.15,
                                           pose=[0, HALF[1], 0, 0, 0, 0, 1]))
    dt = 1 / hz
    for _ in range(int(0.5 * hz)):
        world.step(dt)
    start = np.array(world.body_pose(plate))
    world.step(dt, {hand: handsim.make_hand_frame(RIGHT, [0, 1, 0, 0, 0, 0, 1])})  # far above: where the skin is
    particles = np.array(world.hand_particles(hand, False))
    over = (np.abs(particles[:, 0]) < HALF[0]) & (np.abs(particles[:, 2]) < HALF[2])
    lowest = particles[over, 1].min() - 1
    end_y = 2 * HALF[1] + world.hand_model(hand).particle_radius - rest - lowest
    y, moved, turned = end_y + 0.02, 0.0, 0.0
    for i in range(int(1.5 * hz)):
        y = max(end_y, y - speed * dt)
        world.step(dt, {hand: handsim.make_hand_frame(RIGHT, [0, y, 0, 0, 0, 0, 1])})
        pose = np.array(world.body_pose(plate))
        moved = max(moved, float(np.linalg.norm(pose[:3] - start[:3])))
        turned = max(turned, math.degrees(2 * math.acos(min(1.0, abs(float(pose[6]))))))
    return moved, turned


def test_the_skin_keeps_a_plate_still_under_a_lowered_palm():
    moved, turned = lower_palm_onto_plate(handsim.WorldDef(skin_depth=0.003))
    assert moved <= 1e-3 and turned <= 1.0
    # eq. 2 alone (PushModel.FIT, no skin): the tilt; the physical push needs no skin (the test below)
    moved, turned = lower_palm_onto_plate(handsim.WorldDef(skin_depth=0.0, push_model=handsim.PushModel.FIT))
    assert moved > 5e-3 and turned > 5.0


def test_under_the_physical_push_the_plates_support_bears_the_palm_without_a_skin():
    """docs/grasp.md "A resting body's support bears the press": the ground takes the press, nothing is pushed out."""
    for hz in (30.0, 60.0, 120.0):
        moved, turned = lower_palm_onto_plate(handsim.WorldDef(push_model=handsim.PushModel.PHYSICAL), speed=0.2, hz=hz)
        assert moved <= 1e-3 and turned <= 1.0, (hz, moved, turned)


def test_skin_settings_round_trip_and_are_checked():
    d = handsim.WorldDef(skin_depth=0.003, skin_pressure=15e3)
    back = recording.world_def_from_dict(recording.world_def_to_dict(d))
    assert back.skin_depth == 0.003 and back.skin_pressure == 15e3
    with pytest.raises(ValueError, match=r"world\.skin_depth"):
        handsim.World(handsim.WorldDef(skin_depth=0.1))
    with pytest.raises(ValueError, match=r"world\.skin_pressure"):
        handsim.World(handsim.WorldDef(skin_pressure=-1.0))


def test_push_model_round_trips_and_is_checked():
    assert handsim.WorldDef().push_model == handsim.PushModel.WRAP
    d = handsim.WorldDef(push_model=handsim.PushModel.PHYSICAL)
    back = recording.world_def_from_dict(recording.world_def_to_dict(d))
    assert back.push_model == handsim.PushModel.PHYSICAL
    w = handsim.WorldDef(push_model=handsim.PushModel.WRAP)
    assert recording.world_def_from_dict(recording.world_def_to_dict(w)).push_model == handsim.PushModel.WRAP

