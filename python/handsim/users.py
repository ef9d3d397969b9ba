"""Scripted simulated users for the jewelry-box tasks of Kim & Park, Sec. IV.

The paper's subjects wore an IMU glove (Perception Neuron: 21 DOF per hand including the 6-DOF hand pose,
noisy fingers). A :class:`SimulatedUser` stands in for one subject doing one trial: it is drawn from a seed
(:func:`draw_user`), looks at the box every frame the way a person looks at the screen (closed loop: it aims
at where the lid is now and tries again when the lid got away), and produces the glove's hand frames, with
the glove's errors added on top of what the user means to do.

Tasks (``task``, ``hands``):

* ``"open"``: the lid starts closed. The right hand reaches the lid's front lip, grasps it (style ``"pinch"``:
  thumb and index/middle pads pinching the lip; ``"thumb_under"``: flat fingers on top, thumb hooked under the
  lip), swings it up past upright, lets go and withdraws.
* ``"close"``: the lid starts open (90 deg). Style ``"carry"`` grasps the lid's top edge and swings it down
  to closed; style ``"push"`` only pushes: a flat hand from behind tips the lid over and follows it down
  without ever meaning to grasp it (the trials that count false grasps).
* ``hands == 2``: the left hand holds the base at its left end first (palm towards the left face, fingers
  curled into the base: eq. 3 grasps it) and keeps holding it while the right hand works, as in the paper's
  Fig. 6. It reaches open from its rest on the user's left to beside the base's left face and closes its grip
  there, as a person's hand reaches a box before it holds it: the tracker sees the whole reach.

Every random choice comes from ``numpy.random.default_rng(seed)``: the same seed gives the same user and,
with the same world, the same frames.
"""
from __future__ import annotations

import dataclasses
import functools
import math
from typing import List, Optional, Sequence, Tuple

import numpy as np

from . import _core as _h
from .quat import axis_angle, quat_mul, quat_rotate

# ---------------------------------------------------------------------------------------------------------
# Small pose helpers (quaternions x, y, z, w as everywhere in handsim; the quaternion algebra is handsim.quat).


def swing_pose(pose, pivot, axis, angle):
    """`pose` (7,) rotated by `angle` about the line through `pivot` along `axis`."""
    q = axis_angle(axis, angle)
    pivot = np.asarray(pivot, float)
    p = pivot + quat_rotate(q, np.asarray(pose[:3], float) - pivot)
    r = quat_mul(q, pose[3:])
    return np.concatenate([p, r / math.sqrt(float(r @ r))])


def min_jerk(s):
    """Minimum-jerk profile 0..1 of a reaching movement (Flash & Hogan), s clamped to 0..1."""
    s = min(max(s, 0.0), 1.0)
    return s * s * s * (10.0 - 15.0 * s + 6.0 * s * s)


def lerp_pose(a, b, s):
    """Position lerp and quaternion nlerp (shortest arc)."""
    a = np.asarray(a, float)
    b = np.asarray(b, float)
    qb = b[3:] if np.dot(a[3:], b[3:]) >= 0 else -b[3:]
    q = (1 - s) * a[3:] + s * qb
    return np.concatenate([(1 - s) * a[:3] + s * b[:3], q / np.linalg.norm(q)])


# ---------------------------------------------------------------------------------------------------------
# Hand shapes of the styles: make_hand_frame parameters (HandShape, not handsim.Shape, the collision shape).

@dataclasses.dataclass(frozen=True)
class HandShape:
    curl: Tuple[float, float, float, float, float] = (0, 0, 0, 0, 0)
    thumb_opposition: float = 0.0
    spread: float = 0.0

    def params(self):
        return _h.HandPoseParams(curl=list(self.curl), thumb_opposition=self.thumb_opposition, spread=self.spread)

    def opened(self, openness: float) -> "HandShape":
        """This grip opened by `openness` (0 the grip .. 1 the open hand) the way every synthetic hand of handsim
        opens and closes its grips (handsim.open_grip): people reach with the hand open and close it onto what
        they grasp, and the intent rule (GraspSettings.closing_distance) grasps only a closing hand."""
        return _opened(self, float(min(max(openness, 0.0), 1.0)))


@functools.lru_cache(maxsize=64)
def _opened(shape: HandShape, openness: float) -> HandShape:
    """HandShape.opened, remembered: most frames hold a grip (0) or an open hand (1), and a HandShape is immutable."""
    p = _h.open_grip(shape.params(), openness)
    return HandShape(tuple(float(c) for c in p.curl), float(p.thumb_opposition), float(p.spread))


FLAT_HAND = HandShape()
# The scene's lid_pinch_shape(): fingers straight on the lid, thumb half opposed under the lip.
THUMB_UNDER = HandShape(thumb_opposition=0.5)
# Thumb bent and pressed harder up under the lip, fingers straight on the lid (bent fingers would poke
# through the 1.5 cm lid into the base).
PINCH = HandShape(curl=(0.2, 0.0, 0.0, 0.0, 0.0), thumb_opposition=0.6)
# The left hand holding the base's left end (see BASE_HOLD_* below).
BASE_HOLD = HandShape(curl=(0.18, 0.6, 0.6, 0.6, 0.6), thumb_opposition=0.5)

GRASP_SHAPES = {"pinch": PINCH, "thumb_under": THUMB_UNDER, "carry": THUMB_UNDER, "push": FLAT_HAND}


# ---------------------------------------------------------------------------------------------------------
# The user of one trial.

TASKS = ("open", "close")
OPEN_STYLES = ("pinch", "thumb_under")
CLOSE_STYLES = ("carry", "push")
FRAME_RATE = 60.0  # Hz, the glove's and the paper's frame rate


@dataclasses.dataclass(frozen=True)
class UserParams:
    """Everything drawn for one trial (units: m, s, rad)."""
    seed: int
    task: str
    hands: int
    style: str
    speed: float            # multiplies every movement's speed (1: a calm adult)
    scale: float            # hand size (1: adult hand, palm 9 cm)
    approach: Tuple[float, float, float]  # aim error at the lip in the box frame: lateral, height, depth
    target_angle: float     # open: how far past the limit the user swings (the lid stops at 90 deg)
    reaction_s: float       # how long the user takes to notice that the lid got away
    finger_noise: float     # per-frame finger-sensor noise (curl / opposition units)
    finger_drift: float     # slow finger drift (same units; Ornstein-Uhlenbeck, tau 1 s)
    palm_noise: float       # per-frame palm-position jitter (m)
    palm_drift: float       # residual palm drift the user does not correct (m; OU, tau 0.7 s)
    yaw_drift: float        # residual heading drift (rad; OU, tau 1 s)
    dropouts: Tuple[Tuple[float, float], ...]  # (start s, duration s) tracking losses of the working hand
    box_shift: Tuple[float, float, float]  # where the box was dropped: dx, dz (m), yaw (rad)


def draw_user(seed: int, task: str, hands: int) -> UserParams:
    """One simulated user for one trial; the same arguments always give the same user."""
    if task not in TASKS:
        raise ValueError(f"task: expected one of {TASKS}, got {task!r}")
    if hands not in (1, 2):
        raise ValueError(f"hands: expected 1 or 2, got {hands!r}")
    rng = np.random.default_rng([seed, TASKS.index(task), hands])
    style = str(rng.choice(OPEN_STYLES if task == "open" else CLOSE_STYLES))
    speed = float(np.clip(rng.lognormal(0.0, 0.3), 0.5, 2.2))
    scale = float(np.clip(rng.normal(1.0, 0.07), 0.85, 1.15))
    approach = (float(rng.normal(0, 0.012)), float(rng.normal(0, 0.0015)), float(rng.normal(0.002, 0.002)))
    target = math.radians(float(np.clip(rng.normal(93.0, 2.5), 88.0, 99.0)))
    reaction = float(rng.uniform(0.25, 0.5))
    finger_noise = float(rng.uniform(0.005, 0.02))
    finger_drift = float(rng.uniform(0.0, 0.03))
    palm_noise = float(rng.uniform(0.0005, 0.002))
    palm_drift = float(rng.uniform(0.0, 0.004))
    yaw_drift = math.radians(float(rng.uniform(0.0, 3.0)))
    dropouts = []
    n_drop = rng.poisson(0.25)  # about one trial in five loses tracking at least once
    for _ in range(int(n_drop)):
        dropouts.append((float(rng.uniform(0.3, 5.0)), float(rng.exponential(0.12)) + 1 / FRAME_RATE))
    box_shift = (float(rng.uniform(-0.05, 0.05)), float(rng.uniform(-0.03, 0.03)),
                 math.radians(float(rng.uniform(-15, 15))))
    return UserParams(seed, task, hands, style, speed, scale, approach, target, reaction, finger_noise,
                      finger_drift, palm_noise, palm_drift, yaw_drift, tuple(sorted(dropouts)), box_shift)


class SeededGlove:
    """The IMU glove of one user, between its intent and the hand frames: finger noise and drift, palm jitter and
    residual drift, heading drift (handsim.Glove, in the core: it is the per-frame hot path of a trial), and
    tracking dropouts (untracked frames). Its random numbers come from this glove's own seeded generator,
    drawn ahead in blocks: the glove takes them in the order it always did, so a seed gives the same frames."""

    NORMALS_BLOCK = 4096  # variates drawn per refill: about 200 frames

    def __init__(self, params: UserParams, handedness, seed_offset: int, dt: float):
        p = params
        self.p, self.handedness, self.dt = p, handedness, dt
        self.rng = np.random.default_rng([p.seed, 7919, seed_offset])
        self.core = _h.Glove(handedness, finger_noise=p.finger_noise, finger_drift=p.finger_drift,
                             palm_noise=p.palm_noise, palm_drift=p.palm_drift, yaw_drift=p.yaw_drift,
                             scale=p.scale, dt=dt)
        self._z = np.empty(0)
        self._next = 0
        self.core.start(self._normals(self.core.start_normals))
        self.dropouts = p.dropouts if seed_offset == 0 else ()

    def _normals(self, count: int):
        """The next `count` standard normal variates of this glove's generator."""
        if self._next + count > len(self._z):
            self._z = np.concatenate([self._z[self._next:], self.rng.standard_normal(self.NORMALS_BLOCK)])
            self._next = 0
        self._next += count
        return self._z[self._next - count:self._next]

    def tracked(self, t: float) -> bool:
        return not any(start <= t < start + length for start, length in self.dropouts)

    def frame(self, t: float, palm, shape: HandShape):
        return self.core.frame(palm, shape.curl, shape.thumb_opposition, shape.spread, self.tracked(t),
                               self._normals(self.core.frame_normals))


# ---------------------------------------------------------------------------------------------------------
# What the user means to do, frame by frame (closed loop on the box it sees).

_NO_SHIFT = (0.0, 0.0, 0.0)


class SimulatedUser:
    """Produces the hand frames of one trial. Call :meth:`frames` once per frame before ``World.step``; it
    reads the box's current state (as a subject reads the screen) and returns ``{HandId: HandFrame}`` for
    ``hands`` = (right, left) (default: the world's first two hands; a hand without a frame is untracked, and
    one-hand trials never drive the left).

    The right hand goes through: ``reach`` (to a hover pose above the lip, then down in front of it, the hand
    open), ``close_in`` (onto the lip, closing the grasp shape from the open hand), ``grip``, ``swing`` (about the hinge, to
    the goal angle), ``hold``, ``let_go`` (fingers open, hand backs off), ``withdraw`` and ``watch``. When
    the lid stops following the hand for longer than the user's reaction time, or is not where it should
    be after letting go, the user starts again from ``reach`` at the lid's current angle (three retries).
    """

    MAX_RETRIES = 3

    def __init__(self, params: UserParams, world, box, dt: float = 1 / FRAME_RATE, hands: Sequence = None):
        self.p, self.world, self.box, self.dt = params, world, box, dt
        self.right_hand, self.left_hand = (list(hands) if hands is not None else world.hands()[:2] + [None])[:2]
        self.right = SeededGlove(params, _h.Handedness.RIGHT, 0, dt)
        self.left = SeededGlove(params, _h.Handedness.LEFT, 1, dt) if params.hands == 2 else None
        self.grasp_shape = GRASP_SHAPES[params.style]
        self.phase = "left_reach" if params.hands == 2 else "reach"
        self.phase_t = 0.0
        self.t = 0.0
        self.attempts = 0
        self.lost_since: Optional[float] = None
        self.intent_hold = False  # the right hand means to hold (or drive) the lid in this frame
        self.done = False
        self.right_pose = None
        self.left_pose = None
        self._waypoints = None
        self._start_angle = 0.0
        self._left_hold = None
        self._left_rest = None
        self._thumb_fix = self._thumb_compensation()
        self._openness = 1.0  # how open the right hand's grip is (HandShape.opened): it starts open
        self._reach_openness = 1.0  # and at the start of the current reach

    # --- geometry of the box as the user sees it ---
    def _angle(self):
        return self.world.joint_state(self.box.hinge).value

    def _base(self):
        return np.asarray(self.world.body_pose(self.box.base), float)

    def _thumb_compensation(self):
        """A person aims the virtual thumb, not the palm: the palm shift (palm frame) that puts this hand's
        thumb tip where the scene's lid_pinch_palm puts an adult hand's (hand size changes the thumb's
        reach)."""
        shape = self.grasp_shape
        ident = np.array([0, 0, 0, 0, 0, 0, 1.0])
        tips = []
        for scale in (1.0, self.p.scale):
            f = _h.make_hand_frame(_h.Handedness.RIGHT, ident, curl=np.asarray(shape.curl, float),
                                   thumb_opposition=shape.thumb_opposition, spread=shape.spread, scale=scale)
            tips.append(np.asarray(f.positions)[5])
        d = tips[0] - tips[1]
        d[0] = 0.0  # sideways it does not matter
        return d

    def _grip_pose(self, angle, up=0.0, out=0.0):
        """Palm pose on the lid's lip as if the lid were open by `angle`, with the user's aim error; `out`
        backs it off past the lip and `up` raises it (both in the lid's frame, before the swing). The pose
        itself is handsim.lid_grip_palm (in the core: the user aims every frame, some frames twice)."""
        ax, ay, az = self.p.approach
        thumb_fix = self._thumb_fix
        if self.p.style == "push":
            ay, az = ay + 0.004, az + 0.03  # a flat hand: fingertips short of the lip, nothing under it
            thumb_fix = _NO_SHIFT  # and no thumb to aim
        return _h.lid_grip_palm(self.world, self.box, angle, thumb_fix, (ax, ay + up, az + out))

    def _up(self, pose, height):
        q = np.asarray(pose, float).copy()
        q[1] += height
        return q

    def _rest_pose(self):
        """Where the right hand starts and withdraws to: 20 cm towards the user and 15 cm above the lip."""
        base = self._base()
        p = self._grip_pose(self._angle() if self.p.task == "close" else 0.0)
        p[:3] += quat_rotate(base[3:], [0.0, 0.15, 0.2])
        return p

    def _left_hold_pose(self, away=0.0):
        """The left hand at the base's left end: palm on the left face (palm normal +X of the box)."""
        base = self._base()
        e = np.asarray(self.box.definition.base_half_extents, float)
        local = np.array(BASE_HOLD_OFFSET) + np.array([-e[0] - away, 0.0, 0.0])
        p = base[:3] + quat_rotate(base[3:], local)
        q = quat_mul(base[3:], BASE_HOLD_ROTATION)
        return np.concatenate([p, q])

    def _left_rest_pose(self):
        """Where the left hand starts its reach: LEFT_REST from where it holds the base (box frame), turned as there."""
        base = self._base()
        p = self._left_hold_pose()
        p[:3] += quat_rotate(base[3:], LEFT_REST)
        return p

    def _set(self, phase):
        self.phase, self.phase_t = phase, 0.0

    def durations(self):
        s = self.p.speed
        return {"reach": 0.6 / s, "descend": 0.25 / s, "close_in": 0.3 / s, "grip": 0.15 / s,
                "swing": 1.2 / s, "hold": 0.15, "let_go": 0.25 / s, "withdraw": 0.5 / s,
                "left_reach": 0.6 / s, "left_grip": 0.25}

    def _goal(self):
        if self.p.style == "push":
            return math.radians(30)  # tip it past the balance point and follow it down; gravity does the rest
        return self.p.target_angle if self.p.task == "open" else math.radians(1)

    # --- the state machine ---
    def frames(self) -> dict:
        d = self.durations()
        angle = self._angle()
        p = self.p
        self.intent_hold = False

        # The left hand (two-hand trials): reach open from its rest to beside the base's left end, close the grip
        # there, keep holding.
        left_pose, left_shape = None, FLAT_HAND
        if self.left is not None:
            if self._left_hold is None:
                self._left_hold = self._left_hold_pose()
                self._left_rest = self._left_rest_pose()
            if self.phase == "left_reach":
                if self.phase_t < d["left_reach"]:
                    left_pose = lerp_pose(self._left_rest, self._left_hold, min_jerk(self.phase_t / d["left_reach"]))
                else:
                    left_pose = self._left_hold
                    left_shape = BASE_HOLD.opened(1 - min_jerk((self.phase_t - d["left_reach"]) / d["left_grip"]))
                    if self.phase_t >= d["left_reach"] + d["left_grip"]:
                        self._set("reach")
            else:
                left_pose, left_shape = self._left_hold, BASE_HOLD

        grasping = self.grasp_shape
        openness = 1.0
        if self.phase == "left_reach":
            palm = self._rest_pose()
        elif self.phase == "reach":
            # The hand travels open (a retry first opens the hand it held the lid with) and closes only on the lip.
            if self._waypoints is None:
                self._start_angle = angle
                self._reach_openness = self._openness
                start = self.right_pose if self.right_pose is not None else self._rest_pose()
                pre = self._grip_pose(angle, 0.004, 0.045)
                self._waypoints = (start, self._up(pre, 0.06), pre)
            start, hover, pre = self._waypoints
            opening = min_jerk(3 * self.phase_t / d["reach"])
            openness = self._reach_openness + (1 - self._reach_openness) * opening
            if self.phase_t < d["reach"]:
                palm = lerp_pose(start, hover, min_jerk(self.phase_t / d["reach"]))
            else:
                s = min_jerk((self.phase_t - d["reach"]) / d["descend"])
                palm = lerp_pose(hover, pre, s)
                if self.phase_t >= d["reach"] + d["descend"]:
                    self._set("close_in")
        elif self.phase == "close_in":
            s = min_jerk(self.phase_t / d["close_in"])
            palm = lerp_pose(self._waypoints[2], self._grip_pose(self._start_angle), s)
            openness = 1 - s
            if self.phase_t >= d["close_in"]:
                self._set("grip")
        elif self.phase == "grip":
            palm = self._grip_pose(self._start_angle)
            openness = 0.0
            self.intent_hold = p.style != "push" and self.phase_t >= 0.1
            if self.phase_t >= d["grip"]:
                self._set("swing")
        elif self.phase == "swing":
            goal = self._goal()
            cmd = self._start_angle + (goal - self._start_angle) * min_jerk(self.phase_t / d["swing"])
            palm = self._grip_pose(cmd)
            openness = 0.0
            self.intent_hold = p.style != "push"
            # Does the lid follow the hand? (Past a limit it cannot; that is not the lid getting away.)
            target = min(max(cmd, 0.0), 0.5 * math.pi)
            lag = abs(target - angle) if p.style != "push" else max(0.0, angle - target)
            if lag > math.radians(20) and self.attempts < self.MAX_RETRIES:
                self.lost_since = self.t if self.lost_since is None else self.lost_since
                if self.t - self.lost_since >= p.reaction_s:
                    self._retry()
            else:
                self.lost_since = None
            if self.phase == "swing" and self.phase_t >= d["swing"]:
                self._set("hold")
        elif self.phase == "hold":
            palm = self._grip_pose(self._goal())
            openness = 0.0
            self.intent_hold = p.style != "push"
            if self.phase_t >= d["hold"]:
                self._set("let_go")
        elif self.phase == "let_go":
            # open the fingers first, then back off (dragging a hooked thumb over the lid would pull it)
            s = min_jerk(2 * self.phase_t / d["let_go"])
            m = min_jerk(2 * self.phase_t / d["let_go"] - 1)
            palm = self._grip_pose(self._goal(), 0.02 * m, 0.03 * m)
            openness = s
            if self.phase_t >= d["let_go"]:
                self._waypoints = (palm,)
                self._set("withdraw")
        elif self.phase == "withdraw":
            # straight up first (clear of the lid's edge), then back to where the hand started
            up = self._up(self._waypoints[0], 0.12)
            if self.phase_t < 0.5 * d["withdraw"]:
                palm = lerp_pose(self._waypoints[0], up, min_jerk(2 * self.phase_t / d["withdraw"]))
            else:
                palm = lerp_pose(up, self._rest_pose(), min_jerk(2 * self.phase_t / d["withdraw"] - 1))
            if self.phase_t >= d["withdraw"]:
                self._waypoints = None
                self._set("watch")
        else:  # watch: is the task done? If the lid went back, try again.
            palm = self._rest_pose()
            ok = angle >= math.radians(80) if p.task == "open" else angle <= math.radians(5)
            if not ok and self.phase_t >= p.reaction_s and self.attempts < self.MAX_RETRIES:
                self._retry()
            elif ok and self.phase_t >= 0.5:
                self.done = True
        self._openness = openness
        return self._emit(palm, grasping.opened(openness), left_pose, left_shape)

    def _retry(self):
        self.attempts += 1
        self.lost_since = None
        self._waypoints = None
        self._set("reach")

    def _emit(self, palm, shape, left_pose, left_shape):
        self.right_pose = np.asarray(palm, float)
        self.left_pose = left_pose
        frames = {self.right_hand: self.right.frame(self.t, palm, shape)}
        if self.left is not None and left_pose is not None:  # the glove has not picked the left hand up yet
            frames[self.left_hand] = self.left.frame(self.t, left_pose, left_shape)
        self.t += self.dt
        self.phase_t += self.dt
        return frames


# Left hand holding the base (box frame): palm centre 3.5 cm outside the left face, 2 cm below the base's
# middle and 2 cm towards the front, palm facing +X, fingers towards the back, curled into the base. Virtual
# fingers curl into the box (nothing stops them); the grasp comes from the opposing penetration directions inside
# it. The hand arrives open and closes there, so the open hand must be clear of the box: 1.5 cm outside (the pose a
# search once found for a hand that appeared in place) the open hand lay 169 particles deep in the base and 47 in
# the lid, 2 cm further out it touches neither (a /tmp script stepping the open and the closed BASE_HOLD at 0-3 cm
# further out; closed it reaches 238 particles into the base). A hand that closed while it still came in carried
# the base it had grasped on with it (10 mm).
BASE_HOLD_OFFSET = (-0.035, -0.02, 0.02)
BASE_HOLD_ROTATION = axis_angle([0, 0, 1], 0.5 * math.pi)  # palm (-Y) turned to face +X
# Where the left hand's reach starts (box frame, from the hold): to the left, above and towards the user, where a
# hand rests beside the box. It travels open to the hold in the reach's time (durations: left_reach), as the right
# hand reaches the lid.
LEFT_REST = (-0.15, 0.12, 0.15)
