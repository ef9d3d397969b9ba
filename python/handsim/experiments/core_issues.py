"""Reproductions of two core faults the experiments ran into (``python -m handsim.experiments.core_issues``):
a base thrown by the hand that holds its lid, and a lid held past its limit slammed shut. Both are fixed
(docs/grasp.md, "Contacts keep their entry face"); tests/python/test_joints.py keeps them fixed.

Each function runs one scripted, noise-free hand against the default jewelry box and returns the numbers the
report quotes; nothing here is random.
"""
from __future__ import annotations

import math

import numpy as np

from .. import _core as _h
from .. import users as _users
from ..quat import quat_rotate

R = _h.Handedness.RIGHT


# The hand reaches its pinch open, from REACH_M in front of it (away from the hinge) over REACH_FRAMES frames, sliding
# in over and under the lip: a hand that appeared there, a particle's centre already in the lid or the base, would
# begin no grasp of it under the intent rule (appeared_inside: the tracker never saw it close onto the surface).
REACH_M, REACH_FRAMES = 0.03, 10


def base_thrown_by_a_touch(depth_m: float = 0.004, swing_deg: float = 95.0, lid_overhang: float = 0.015,
                           hand_def=None, world_def=None):
    """A right hand arrives open at the closed lid (from REACH_M in front) and closes its pinch there (lid_pinch_palm, closing_grip of
    lid_pinch_shape) with its palm `depth_m` closer to the hinge than the scene's pose, so the thumb grazes the
    base's front face, and swings the lid open over one second. Returns (base displacement m, max particles touching the base, lid grasped). `hand_def`:
    a right-hand HandDef (default: HandDef()); `world_def` (default: WorldDef()), e.g. to choose the grasp rule."""
    w = _h.World(world_def if world_def is not None else _h.WorldDef())
    d = _h.JewelryBoxDef()
    d.lid_overhang = lid_overhang
    box = _h.build_jewelry_box(w, d)
    hand = w.add_hand(hand_def or _h.HandDef())
    b0 = np.asarray(w.body_pose(box.base), float)
    touching, grasped = 0, False
    pinch = _h.lid_pinch_shape()
    for i in range(-REACH_FRAMES, 110):
        angle = min(max((i - 20) / 60, 0.0), 1.0) * math.radians(swing_deg)
        p = np.asarray(box.lid_pinch_palm(w, R, 0.0), float)
        p[:3] += quat_rotate(b0[3:], [0.0, 0.0, REACH_M * max(0.0, -i / REACH_FRAMES) - depth_m])
        p = _users.swing_pose(p, np.asarray(box.hinge_pivot(w)), np.asarray(box.hinge_axis(w)), angle)
        w.step(1 / 60, {hand: _h.make_hand_frame(R, p, params=_h.closing_grip(pinch, max(i, 0) / 60))})
        touching = max(touching, w.body_contact_count(box.base, hand))
        grasped = grasped or w.body_grasp(box.lid).grasped
    moved = float(np.linalg.norm(np.asarray(w.body_pose(box.base))[:3] - b0[:3]))
    return moved, touching, grasped


def lid_bounces_off_upper_limit(swing_deg: float = 105.0, lid_overhang: float = 0.015, hand_def=None,
                                world_def=None):
    """The hand closes its pinch on the lid (closing_grip), swings it (min-jerk, 1.2 s) to `swing_deg`, past
    the 90 deg limit, and holds still there. Returns (largest closing rate after the lid first reached 90 deg, deg/s; final angle deg).
    `hand_def`: a right-hand HandDef (default: HandDef()); `world_def` as in base_thrown_by_a_touch."""
    w = _h.World(world_def if world_def is not None else _h.WorldDef())
    d = _h.JewelryBoxDef()
    d.lid_overhang = lid_overhang
    box = _h.build_jewelry_box(w, d)
    hand = w.add_hand(hand_def or _h.HandDef())
    closed = np.asarray(box.lid_pinch_palm(w, R, 0.0), float)
    reached, worst = False, 0.0
    pinch = _h.lid_pinch_shape()
    for i in range(210):
        angle = _users.min_jerk((i - 20) / 72) * math.radians(swing_deg)
        p = _users.swing_pose(closed, np.asarray(box.hinge_pivot(w)), np.asarray(box.hinge_axis(w)), angle)
        w.step(1 / 60, {hand: _h.make_hand_frame(R, p, params=_h.closing_grip(pinch, i / 60))})
        s = w.joint_state(box.hinge)
        reached = reached or s.value >= 0.5 * math.pi - 1e-9
        if reached:
            worst = max(worst, -math.degrees(s.rate))
    return worst, math.degrees(w.joint_state(box.hinge).value)


def dense_hand():
    """A right hand of 3,000 random particles at the default radius (3.70 mm): the particle study's count,
    with the sampling that drove its thumb through the lid (see lid_bounces_off_upper_limit)."""
    return _h.HandDef(handedness=R, particle_count=3000, sampling=_h.ParticleSampling.RANDOM, particle_radius=0.0037)


def summary() -> list:
    lines = []
    for depth in (0.0, 0.002, 0.004):
        moved, touching, grasped = base_thrown_by_a_touch(depth)
        lines.append(f"pinch {depth * 1000:.0f} mm deeper than lid_pinch_palm, swing to 95 deg in 1 s (1.5 cm lip): "
                     f"lid grasped {grasped}, up to {touching} particles on the base, base moved {moved:.2f} m")
    for swing in (100.0, 105.0, 112.0):
        rate, final = lid_bounces_off_upper_limit(swing)
        lines.append(f"swing a held lid to {swing:.0f} deg (past the 90 deg limit) in 1.2 s and hold still (1.5 cm "
                     f"lip): fastest closing rate after reaching 90 deg {rate:.0f} deg/s, final angle {final:.1f} deg")
    rate, final = lid_bounces_off_upper_limit(105.0, hand_def=dense_hand())
    lines.append(f"the same to 105 deg with a hand of 3,000 random particles (its thumb leaves through the lid's "
                 f"outer face): fastest closing rate {rate:.0f} deg/s, final angle {final:.1f} deg")
    return lines


if __name__ == "__main__":
    print("\n".join(summary()))
