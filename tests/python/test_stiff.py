"""stiff: the named stiff and extreme cases of tests/cpp/test_stiff.cpp, replayed through the Python bindings.

A table: each row is a case name (the C++ test it mirrors), a script that drives the jewelry box and asserts
the case's stated behaviour, and the scene size for the violation bound. Every frame of every row also checks
that every body's pose and velocity are finite, the hinge is inside its limits and its violation is at most
1e-9 x scene size. docs/reliability.md lists the expected behaviours.
"""
import math
import re

import numpy as np
import pytest

import handsim
from conftest import with_grasp_rule

DT = 1 / 60
DEG = math.pi / 180
RIGHT, LEFT = handsim.Handedness.RIGHT, handsim.Handedness.LEFT


def rotate(q, v):
    """v rotated by the unit quaternion q = (x, y, z, w)."""
    u, w = np.asarray(q[:3], float), float(q[3])
    v = np.asarray(v, float)
    return v + 2 * np.cross(u, np.cross(u, v) + w * v)


class Scene:
    rule = "contacts"  # the running case's grasp rule (test_stiff sets it)

    def __init__(self, size=1.0, world_def=None, hands=(RIGHT,), **box):
        self.world = handsim.World(with_grasp_rule(Scene.rule, world_def))
        self.box = handsim.build_jewelry_box(self.world, handsim.JewelryBoxDef(**box))
        self.hands = [self.world.add_hand(handsim.HandDef(handedness=h)) for h in hands]
        self.size = size
        self.shape = handsim.lid_pinch_shape()
        self.time = 0.0  # s stepped: a pinch closes (closing_grip) from the time its hand arrives
        self.arrived = {}

    def pinch(self, angle, lift=0.0, offset=(0, 0, 0), handedness=RIGHT):
        palm = np.array(self.box.lid_pinch_palm(self.world, handedness, angle, lift))
        palm[:3] += offset
        since = self.time - self.arrived.setdefault(handedness, self.time)
        return handsim.make_hand_frame(handedness, palm, params=handsim.closing_grip(self.shape, since))

    def step(self, frames=(), dt=DT):
        """frames[k] drives self.hands[k]."""
        self.world.step(dt, dict(zip(self.hands, frames)))
        self.time += dt
        self.check()

    def check(self):
        w = self.world
        for b in w.bodies():
            assert np.all(np.isfinite(w.body_pose(b)))
            linear, angular = w.body_velocity(b)
            assert np.all(np.isfinite(linear)) and np.all(np.isfinite(angular))
        s = w.joint_state(self.box.hinge)
        d = self.box.definition
        assert math.isfinite(s.value) and d.lower <= s.value <= d.upper
        assert s.violation <= 1e-9 * self.size

    def grasped(self):
        return self.world.body_grasp(self.box.lid).grasped

    def angle(self):
        return self.world.joint_state(self.box.hinge).value


def hand_teleports_1m_and_100m(s):
    for jump in (1.0, 100.0):
        for _ in range(20):  # (back) at the lip, closing the pinch
            s.step([s.pinch(0)])
        assert s.grasped(), jump
        for _ in range(10):
            s.step([s.pinch(0, lift=jump)])
        assert not s.grasped(), jump  # the contacts vanish, the grasp ends; the hinge held every frame
        for _ in range(60):  # away while the lid settles
            s.step([s.pinch(0, lift=jump)])
        s.arrived.clear()  # the hand comes back open


def tracking_lost_for_1_30_300_frames(s):
    for lost in (1, 30, 300):
        s.world.set_joint_value(s.box.hinge, 0.0)
        s.arrived.clear()  # the hand (back) at the lip, open: it closes its pinch, then turns the lid 10 deg
        for i in range(40):
            s.step([s.pinch(10 * DEG * min(1.0, max(0.0, (i - 15) / 20)))])
        assert s.grasped()
        frame = s.pinch(0)
        valid = frame.valid.copy()
        valid[handsim.PALM] = False
        positions = frame.positions.copy()
        positions[handsim.PALM] = math.nan  # NaN in an invalid joint is legal
        gone = handsim.HandFrame(RIGHT, positions, frame.orientations, frame.radii, valid)
        for _ in range(lost):
            s.step([gone])
        assert s.grasped() == (lost * DT <= 0.2), lost  # 0.2 s grace: 1 frame held, 30 and 300 released
        for _ in range(30):
            s.step([s.pinch(0, lift=0.05)])


def bad_frames_and_time_steps_change_nothing(s):
    for _ in range(5):
        s.step([s.pinch(0)])
    before = s.world.state_hash()
    good = s.pinch(0)

    def frame(joint, position=None, orientation=None):
        positions, orientations = good.positions.copy(), good.orientations.copy()
        if position is not None:
            positions[joint] = position
        if orientation is not None:
            orientations[joint] = orientation
        return handsim.HandFrame(RIGHT, positions, orientations, good.radii, good.valid)

    tip, wrist = handsim.INDEX_TIP, handsim.WRIST
    rows = [  # a HandFrame checks its joints when it is made; step checks dt
        (lambda: frame(tip, position=[math.nan, 0.8, -0.3]), "joints[10].position"),
        (lambda: frame(tip, position=[0, math.inf, -0.3]), "joints[10].position"),
        (lambda: frame(wrist, orientation=[0, 0, 0, 0]), "joints[1].orientation"),
        (lambda: frame(wrist, orientation=[2, 0, 0, 0]), "joints[1].orientation"),
        *[(lambda dt=dt: s.world.step(dt, {s.hands[0]: good}), "dt") for dt in (0.0, -DT, math.nan, math.inf)],
    ]
    for call, word in rows:
        with pytest.raises(handsim.InvalidArgumentError, match=re.escape(word)):
            call()
        assert s.world.state_hash() == before, word
    s.step([frame(wrist, orientation=good.orientations[wrist] * (1 + 1e-7))])  # normalized, not rejected


def extreme_time_steps(s):
    for _ in range(20):  # the pinch closes at 60 Hz first
        s.step([s.pinch(0)])
    for dt in (1.0, 1e-6, 1e-6, 0.5, DT):
        for _ in range(5):
            s.step([s.pinch(0)], dt=dt)
    assert s.grasped()  # a 1 s frame runs at most max_substeps of physics


def mass_ratio_1_to_1000(s):
    del s
    for lid_mass in (0.0005, 500.0):
        free = Scene(lid_mass=lid_mass, damping=0.0)
        free.world.set_joint_value(free.box.hinge, 80 * DEG)
        for _ in range(120):
            free.step()
        assert free.angle() == 0.0, lid_mass  # without hinge friction both fall shut within 2 s


def limit_overdrive_at_10_m_per_s(s):
    for _ in range(20):
        s.step([s.pinch(0)])
    assert s.grasped()
    for _ in range(5):  # 180 degrees in 4 frames at ~0.2 m from the hinge: ~10 m/s, and back
        for i in range(9):
            s.step([s.pinch(math.pi * (i / 4 if i <= 4 else (8 - i) / 4))])


def spawned_inside_and_swipe_at_10_m_per_s(s):
    centre = np.array(s.world.body_pose(s.box.base)[:3])
    for _ in range(30):
        s.step([handsim.make_hand_frame(RIGHT, [*centre, 0, 0, 0, 1])])
    for i in range(12):
        palm = centre + [-1.0 + i * 10 * DT, 0.06, 0]
        s.step([handsim.make_hand_frame(RIGHT, [*palm, 0, 0, 0, 1])])


def grasp_dithering_every_frame(s):
    events = 0
    for i in range(240):
        s.step([s.pinch(0, lift=(i % 2) * 0.003)])
        events += sum(e.type in (handsim.EventType.GRASP_BEGIN, handsim.EventType.GRASP_END)
                      for e in s.world.events())
    assert events <= 4


def opens_to_60_degrees(s):
    for i in range(90):
        s.step([s.pinch(60 * DEG * min(1.0, max(0.0, (i - 20) / 60)))])
    assert s.grasped()
    assert abs(s.angle() - 60 * DEG) <= 3 * DEG


def scaled_box_keeps_its_hinge(s):
    s.world.set_joint_value(s.box.hinge, 80 * DEG)
    for _ in range(int(60 * 2 * math.sqrt(s.size) / 5) + 120):
        s.step()
    assert s.angle() == 0.0


def two_hands_pull_the_lid_apart(s):
    right, left = s.hands
    side = rotate(s.world.body_pose(s.box.base)[3:], [1.0, 0, 0])  # the base's x axis, along the lip
    front = rotate(s.world.body_pose(s.box.base)[3:], [0, 0, 1.0])  # the base's z axis, away from the hinge
    frames = lambda angle, apart, reach=0.0: [  # noqa: E731
        s.pinch(angle, offset=(0.05 + apart) * side),
        s.pinch(angle, offset=-(0.05 + apart) * side + reach * front, handedness=LEFT)]
    # the left hand closes once there, after reaching its place from 5 cm in front, sliding in over and under the lip
    # (a hand that appeared on the lid would not be seen reaching it: appeared_inside)
    s.arrived[LEFT] = 20 * DT
    for i in range(20):
        s.step(frames(0, 0, 0.05 * (1 - i / 20)))
    for _ in range(20):
        s.step(frames(0, 0))
    for i in range(1, 41):
        s.step(frames(30 * DEG * i / 40, 0))
    g = s.world.body_grasp(s.box.lid)
    assert g.grasped and g.primary == right and g.secondary == left
    held = s.angle()
    ended = []
    for i in range(1, 61):
        s.step(frames(30 * DEG, 0.3 * min(1.0, i / 30)))
        ended += [(e.hand, e.reason) for e in s.world.events()
                  if e.type == handsim.EventType.GRASP_END and e.body == s.box.lid]
        if s.grasped():
            assert abs(s.angle() - held) <= 2 * DEG  # a pull along the hinge axis is not a rotation
    assert sorted(h.packed for h, _ in ended) == sorted([right.packed, left.packed])
    assert all(r == handsim.EventReason.RELEASED for _, r in ended)
    assert not s.grasped() and s.angle() < held  # let go, the lid falls shut


CASES = [
    # (name, C++ test it mirrors, scene factory, script)
    ("teleport", "HandTeleports1mAnd100mInOneFrame", Scene, hand_teleports_1m_and_100m),
    ("tracking_lost", "TrackingLostFor1_30_300FramesThenBack", Scene, tracking_lost_for_1_30_300_frames),
    ("bad_frames", "BadFramesAndTimeStepsAreRejectedAndChangeNothing", Scene, bad_frames_and_time_steps_change_nothing),
    ("extreme_dt", "ExtremeTimeSteps", Scene, extreme_time_steps),
    ("mass_ratio", "MassRatio1To1000BetweenLidAndBase", Scene, mass_ratio_1_to_1000),
    ("limit_overdrive", "LimitOverdriveAt10MetresPerSecond", Scene, limit_overdrive_at_10_m_per_s),
    ("spawn_inside_swipe", "HandSpawnedInsideTheBoxAndSwipingThroughAt10MetresPerSecond", Scene,
     spawned_inside_and_swipe_at_10_m_per_s),
    ("dithering", "GraspDitheringEveryFrameDoesNotFlicker", Scene, grasp_dithering_every_frame),
    ("origin_1mm", "SceneFarFromTheOriginAndScaled",
     lambda: Scene(position=[0.001, 0.75, -0.35]), opens_to_60_degrees),
    ("origin_100m", "SceneFarFromTheOriginAndScaled",
     lambda: Scene(size=math.hypot(100, 100), position=[100, 0.75, 99.65]), opens_to_60_degrees),
    ("origin_10km", "SceneFarFromTheOriginAndScaled",
     lambda: Scene(size=math.hypot(1e4, 1e4), position=[1e4, 0.75, -1e4 - 0.35]), opens_to_60_degrees),
    *[(f"scale_{name}", "TinyAndHugeBoxesKeepTheirHinge",
       lambda k=k: Scene(size=max(1.0, k), world_def=handsim.WorldDef(ground=False), table=False, base_mass=0.0,
                         damping=0.0, position=[0, 0.75 * k, -0.35 * k], base_half_extents=[0.09 * k, 0.035 * k, 0.06 * k],
                         lid_half_thickness=0.0075 * k, lid_overhang=0.015 * k),
       scaled_box_keeps_its_hinge) for name, k in (("1_to_1000", 1e-3), ("1000_to_1", 1e3))],
    ("two_hands_pull_apart", "TwoHandsPullAGraspedObjectApart", lambda: Scene(hands=(RIGHT, LEFT)),
     two_hands_pull_the_lid_apart),
]


@pytest.mark.parametrize("name, cpp, make, script", CASES, ids=[c[0] for c in CASES])
def test_stiff(name, cpp, make, script, grasp_rule, monkeypatch):
    monkeypatch.setattr(Scene, "rule", grasp_rule)
    script(make())
