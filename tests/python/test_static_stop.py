"""A held body stops at static geometry (docs/grasp.md, "Static geometry stops a held body"), through the binding."""
import numpy as np
import pytest

import handsim

RIGHT = handsim.Handedness.RIGHT
HALF = 0.008  # the README's 16 mm cube


def pinch_and_press(slip_distance, press, push_model):
    """The README's pinch (the thumb opposed on the way, the pads closing) takes the cube off the ground, then the
    hand goes `press` (m) down past where it took it; returns the cube's deepest penetration of the ground (m) and
    whether it is still held."""
    world = handsim.World(handsim.WorldDef(gravity=[0, -9.81, 0], push_model=push_model,
                                           grasp=handsim.GraspSettings(slip_distance=slip_distance)))
    hand = world.add_hand(handsim.HandDef(handedness=RIGHT))
    pinch = handsim.HandPoseParams(curl=[0.2, 0.3, 0, 0, 0], thumb_opposition=1.0)
    tips = handsim.make_hand_frame(RIGHT, params=pinch).positions[[handsim.THUMB_TIP, handsim.INDEX_TIP]]
    cube = world.add_body(handsim.BodyDef(shape=handsim.Shape.box([HALF] * 3), mass=0.05, pose=[0, HALF, 0, 0, 0, 0, 1]))
    palm = np.array([0, HALF, 0, 0, 0, 0, 1.0])
    palm[:3] -= tips.mean(axis=0)
    deepest = 0.0
    for frame in range(15 + 30):
        palm[1] -= press / 30 if frame >= 15 else 0
        grip = handsim.closing_grip(pinch, frame / 60)
        grip.thumb_opposition = pinch.thumb_opposition
        world.step(1 / 60, {hand: handsim.make_hand_frame(RIGHT, palm, params=grip)})
        if frame == 14:
            assert world.body_grasp(cube).grasped
        corners = np.array([[x, y, z] for x in (-HALF, HALF) for y in (-HALF, HALF) for z in (-HALF, HALF)])
        pose = world.body_pose(cube)
        x, y, z, w = pose[3:]
        rot = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])
        deepest = max(deepest, -(corners @ rot.T + pose[:3])[:, 1].min())
    return deepest, world.body_grasp(cube).grasped


# The stop holds whichever push moved the cube before the grasp.
@pytest.mark.parametrize("push_model", [handsim.PushModel.FIT, handsim.PushModel.WRAP])
def test_a_held_cube_pressed_into_the_ground_stays_on_it(push_model):
    deepest, held = pinch_and_press(0.005, 0.01, push_model)
    assert deepest <= 0.002 and held
    assert pinch_and_press(0.0, 0.01, push_model)[0] <= 0.002  # the grip slips at once; still on the surface


def test_slip_distance_is_checked():
    assert handsim.GraspSettings().slip_distance == 0.005
    with pytest.raises(handsim.InvalidArgumentError, match=r"^world.grasp.slip_distance: "):
        handsim.World(handsim.WorldDef(grasp=handsim.GraspSettings(slip_distance=-0.001)))
