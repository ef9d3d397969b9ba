"""handsim.lid_grip_palm, the simulated user's palm on the lid, against the Python it replaced
(SimulatedUser._grip_pose of handsim.users, with its swing_pose), on made-up boxes, lid angles and shifts."""
import math

import numpy as np
import pytest

import handsim
from handsim import users as U
from handsim.quat import quat_rotate


def reference(world, box, angle, palm_shift, box_shift):
    """The former SimulatedUser._grip_pose (palm_shift None: the push style's, no thumb aim)."""
    base = np.asarray(world.body_pose(box.base), float)
    closed = np.asarray(box.lid_pinch_palm(world, handsim.Handedness.RIGHT, 0.0), float)
    if palm_shift is not None:
        closed[:3] += quat_rotate(closed[3:], palm_shift)
    closed[:3] += quat_rotate(base[3:], box_shift)
    return U.swing_pose(closed, box.hinge_pivot(world), box.hinge_axis(world), angle)


def made_up_box(rng):
    world = handsim.World()
    box = handsim.build_jewelry_box(world, handsim.JewelryBoxDef(
        position=[rng.uniform(-0.1, 0.1), 0.75, -0.35 + rng.uniform(-0.05, 0.05)], yaw=rng.uniform(-0.5, 0.5)))
    for _ in range(int(rng.integers(0, 3))):
        world.step(1 / 60)  # the base settles a little: a pose that is not the one it was built with
    return world, box


def test_lid_grip_palm_is_the_python_grip_pose():
    rng = np.random.default_rng(5)
    worst = 0.0
    for _ in range(8):
        world, box = made_up_box(rng)
        for _ in range(60):
            angle = float(rng.uniform(-0.2, 1.8))
            box_shift = rng.normal(0, 0.02, 3)
            palm_shift = None if rng.uniform() < 0.3 else np.array([0.0, *rng.normal(0, 0.005, 2)])
            want = reference(world, box, angle, palm_shift, box_shift)
            got = handsim.lid_grip_palm(world, box, angle, np.zeros(3) if palm_shift is None else palm_shift, box_shift)
            # Equal to the bit on x86-64 (numpy's dot sums with fused multiply-adds there, as the core does);
            # 1e-12 leaves room for a numpy whose dot sums otherwise.
            worst = max(worst, float(np.abs(got - want).max()))
    assert worst <= 1e-12


def test_lid_grip_palm_bad_input_names_the_argument():
    world, box = made_up_box(np.random.default_rng(1))
    for args, name in [((math.nan, [0, 0, 0], [0, 0, 0]), "angle"), ((0.1, [0, math.inf, 0], [0, 0, 0]), "palm_shift"),
                       ((0.1, [0, 0, 0], [0, 0]), "box_shift")]:
        with pytest.raises((ValueError, handsim.Error), match=name):
            handsim.lid_grip_palm(world, box, *args)
