"""An independent judge of grasp intent on real tracking: ``python -m handsim.intent [DIR|FILE ...]``.

The judge asks what a user of a hand-interaction library notices first: does the hand grasp when the person
means to, and only then? What the person means comes from the tracker alone, never from the simulation being
judged (issue 20). Every placement and threshold below is fixed before looking at any result; each has its
reason next to it. Nothing here depends on :mod:`handsim.replay`'s placement rule.

Labels. A hand's strength is max(grab, pinch) of the tracker (Leap's own; for trackers without them, the
skeleton's, :func:`handsim.adapters.skeleton.closure_strengths`). The hand is *closed* at strength >= 0.9 and
*open* below 0.3; in between it is neither (a judge must not decide the ambiguous middle). A *closure* of a
hand begins at the frame 0.3 s before its strength reaches 0.9 (a hand takes a few tenths of a second to close
on an object, so the grip may form before the tracker calls the hand closed) and ends at the first frame it is
open again (or at the end of the recording); the next closure is the next time it reaches 0.9.

Objects. A *cube* is a free 5 cm box of 0.2 kg with gravity off (so that only the hand moves it), aligned
with the palm frame of the frame it is placed at (a person reaching for a cube turns the hand to its faces);
a pinch (grab stays below 0.9 while pinch reaches it) gets a 2 cm cube instead. The *jewelry box* is the
paper's scene (:func:`handsim.build_jewelry_box`, its table and gravity included) facing the user (+Z, the
Leap device frame's user side), placed by the middle of its lid's front edge. An object is placed at a
point, then moved along the palm normal (out of the palm, the way the fingers close) in 1 mm steps until it is
1 mm clear of every tracked hand's particles at that frame: the hands must reach it by moving, never begin
inside it. The world steps at the recording's own frame times from the placement frame on, both hands
driven, no ground plane (the Leap device is not a floor); the recording is lifted 1 m (TRACKER_HEIGHT) so that
the box's table, which reaches down to y = 0, fits under it.

Checks (per recording, per hand):

* *closing hands*: the cube whose centre is 4 cm along the palm normal from the palm joint at the beginning
  of the hand's first closure (a pure pinch: the 2 cm cube centred between the thumb and index tips),
  moved clear. Pass: it is grasped by that hand during the closure; no grasp begins while the grasping hand
  is open; no hand holds it through more than 0.2 s of open hand. A hand that never closes gets the 5 cm cube
  centred at its index tip at its middle tracked frame, the world stepped from the first frame: it must never
  grasp.
* *placement sweep*: at evenly spaced frames of every tracked hand, the cube (the one its closing check
  uses: 2 cm for a hand whose first closure is a pure pinch, 5 cm otherwise) and the jewelry box placed at
  points of the hand's path (4 cm along the palm normal and at the thumb, index and middle tips: the digits
  every grip of the hand uses), each moved clear and judged
  from that frame on. Rates: *false grasps* (placements where a grasp begins while the grasping hand is
  open), *misses* (closures within reach of the object that the hand never grasps it in; each hand's first
  closure that begins at or after the placement frame only: a hand closed before cannot be closing on the
  object, and the object stands where it was placed only until a hand first acts on it) and *held open*
  (placements held through more than 0.2 s of open hand). *Within reach*: in a closed frame of the closure,
  the hand's particles lie over two opposite faces of the object as placed (their centres within the faces'
  outline), closer together than the object's size less 2 mm: the object cannot fit between them wherever it
  slides along that axis. A grasp holds by forces that cancel, so a grip needs the hand on both sides; the
  object may slide between them (a closing finger pushes a free cube against the palm), so their distance
  counts, not where the object stood; 1 mm each side is the placement clearance, so a touch by tracker noise
  alone is not counted. The object as placed, not as the simulation moved it: the judge does not depend on the
  simulator it judges.
* *frame-rate invariance*: the recording resampled to 30, 45, 60, 90 and 120 Hz (positions and radii linearly,
  orientations by slerp between tracker frames, strengths linearly; the grid starts at the placement frame, so
  every rate starts from the same hand pose) and run with the closing-hand cube and with the jewelry box
  placed at the same point. Pass: every closure (times from the tracker) is grasped at every rate or at none,
  and the largest lid angle differs by at most 2 deg across rates.

The grasp settings judged are selectable (``--rule default``, ``--rule contacts``, ``--rule paper``, or
``--rule NAME:field=value,...`` of :class:`handsim.GraspSettings`, or of the :class:`handsim.WorldDef` fields in
``RULE_WORLD_FIELDS``: the contact skin, which decides how the hand pushes what it has not grasped); several
rules are judged side by side.
``--out DIR`` writes one picture per rule and failure kind, ``--doc FILE`` the table into a Markdown file
between ``<!-- intent begin -->`` and ``<!-- intent end -->``; nothing is written without them.
"""
from __future__ import annotations

import argparse
import dataclasses
import json
import math
import sys
import time
from pathlib import Path
from typing import Dict, List, Optional, Sequence, Tuple

import numpy as np

from . import _core
from .adapters import skeleton as _sk

CLOSED = 0.9            # strength at or above: the hand is closed (issue 20)
OPEN = 0.3              # strength below: the hand is open (issue 20)
LEAD_S = 0.3            # a closure begins this long before the strength reaches CLOSED (issue 20)
CUBE_HALF = 0.025       # the 5 cm cube of the closing-hand check
PINCH_HALF = 0.01       # the 2 cm cube of a pure pinch
CUBE_MASS = 0.2         # kg
PALM_DEPTH = 0.04       # the cube's centre along the palm normal from the palm joint
STEP_M = 0.001          # the object is moved out in steps of this much ...
CLEAR_M = 0.001         # ... until every particle is this far from it
MOVE_LIMIT_M = 0.3      # a placement that needs more than this to clear the hands is skipped (said so)
HELD_OPEN_S = 0.2       # longest a hand may hold an object while open (issue 20)
REACH_M = 0.001         # within reach: the closed hand's particles this deep into the object from opposite faces
RATES = (30, 45, 60, 90, 120)
LID_SPREAD_DEG = 2.0    # largest allowed difference of the lid swing across rates (issue 20)
SWEEP_FRAMES = 4        # evenly spaced placement frames per hand (CLI default; tests may use the same)
SWEEP_POINTS = ("palm", "thumb", "index", "middle")  # points of the hand's path an object is placed at
TRACKER_HEIGHT = 1.0    # m: the tracker's origin this far above the world's, so the jewelry box's table fits below
HANDS = ("right", "left")
HANDEDNESS = {"right": _core.Handedness.RIGHT, "left": _core.Handedness.LEFT}
TIPS = {"thumb": _core.THUMB_TIP, "index": _core.INDEX_TIP, "middle": _core.MIDDLE_TIP, "ring": _core.RING_TIP,
        "little": _core.LITTLE_TIP}


# --- input ---------------------------------------------------------------------------------------------

@dataclasses.dataclass
class Track:
    """A recording as the judge sees it: ``times`` (N,) s, strictly increasing; ``frames[i]`` maps "right" /
    "left" to the HandFrame of each tracked hand; ``grab``, ``pinch`` (N, 2) of [right, left] (NaN: none)."""
    name: str
    times: np.ndarray
    frames: List[Dict[str, object]]
    grab: np.ndarray
    pinch: np.ndarray

    @property
    def strength(self) -> np.ndarray:
        """max(grab, pinch) (N, 2); NaN where the tracker gave neither."""
        both = np.stack([self.grab, self.pinch])
        out = np.full(self.grab.shape, np.nan)
        have = ~np.all(np.isnan(both), axis=0)
        out[have] = np.nanmax(both[:, have], axis=0)
        return out

    def tracked(self, side: str) -> np.ndarray:
        return np.array([side in f for f in self.frames], bool)


def track_from_motion(motion) -> Track:
    """A :class:`Track` of a :class:`handsim.replay.Motion` (the readers' common form), lifted by
    TRACKER_HEIGHT (a Leap's hands are a few decimetres above the device; the scene's table reaches from the
    box down to y = 0). Strengths the tracker did not give are derived from the skeleton; frames whose time
    does not advance are dropped (a step needs a positive dt)."""
    from .replay import with_strengths
    motion = with_strengths(motion)
    n = len(motion.frames)
    grab = np.full((n, 2), np.nan) if motion.grab is None else np.asarray(motion.grab, float)
    pinch = np.full((n, 2), np.nan) if motion.pinch is None else np.asarray(motion.pinch, float)
    times = np.asarray(motion.times, float)
    keep = np.r_[True, np.diff(times) > 0] if n else np.zeros(0, bool)
    lift = [0.0, TRACKER_HEIGHT, 0.0, 0.0, 0.0, 0.0, 1.0]
    frames = [{s: a.frame.transformed(lift) for s, a in f.items()} for f, k in zip(motion.frames, keep) if k]
    return Track(motion.name, times[keep], frames, grab[keep], pinch[keep])


def labels(strength: np.ndarray) -> Tuple[np.ndarray, np.ndarray]:
    """(closed, open) boolean arrays of the strengths: closed >= CLOSED, open < OPEN; NaN (no label) neither."""
    s = np.asarray(strength, float)
    with np.errstate(invalid="ignore"):
        return s >= CLOSED, s < OPEN


@dataclasses.dataclass(frozen=True)
class Closure:
    side: str
    begin: int        # the frame LEAD_S before `closed`
    closed: int       # the first frame at CLOSED
    end: int          # the first open frame after `closed` (exclusive end; N if it never opens)
    pinch: bool       # grab stays below CLOSED in [closed, end) while the hand is closed by its pinch


def closures(track: Track, side: str) -> List[Closure]:
    col = HANDS.index(side)
    closed, opened = labels(track.strength[:, col])
    with np.errstate(invalid="ignore"):
        grab_closed = np.asarray(track.grab[:, col]) >= CLOSED
    out, start, floor = [], 0, 0
    n = len(track.times)
    while start < n:
        hits = np.nonzero(closed[start:])[0]
        if not len(hits):
            break
        k = start + int(hits[0])
        begin = max(floor, int(np.searchsorted(track.times, track.times[k] - LEAD_S + 1e-9, side="right")) - 1, 0)
        later_open = np.nonzero(opened[k:])[0]
        end = k + int(later_open[0]) if len(later_open) else n
        out.append(Closure(side, begin, k, end, not bool(grab_closed[k:end].any())))
        start = floor = end
    return out


def resample(track: Track, rate: float, start: float = 0.0) -> Track:
    """`track` from time `start` on at `rate` Hz: positions, radii and strengths interpolated linearly and
    joint orientations by slerp between the two tracker frames around each time; a hand is tracked at a time
    when it is in both (joints valid in both)."""
    if not (isinstance(rate, (int, float)) and math.isfinite(rate) and rate > 0):
        raise ValueError(f"rate: expected a positive number of Hz, got {rate!r}")
    t = track.times
    grid = start + np.arange(int(math.floor((t[-1] - start) * rate + 1e-9)) + 1) / rate
    j = np.clip(np.searchsorted(t, grid + 1e-12, side="right") - 1, 0, len(t) - 1)
    frames, grab, pinch = [], np.full((len(grid), 2), np.nan), np.full((len(grid), 2), np.nan)
    for i, (g, a) in enumerate(zip(grid, j)):
        b = min(a + 1, len(t) - 1)
        w = 0.0 if b == a else (g - t[a]) / (t[b] - t[a])
        if w < 1e-9:
            b, w = a, 0.0
        out = {}
        for side in HANDS:
            fa, fb = track.frames[a].get(side), track.frames[b].get(side)
            if fa is not None and fb is not None:
                out[side] = _blend(fa, fb, w, HANDEDNESS[side])
        frames.append(out)
        for arr, src in ((grab, track.grab), (pinch, track.pinch)):
            arr[i] = (1 - w) * src[a] + w * src[b]
    return Track(f"{track.name}@{rate:g}Hz", grid, frames, grab, pinch)


def _blend(fa, fb, w: float, handedness):
    if w == 0.0:
        return fa
    pa, pb = np.asarray(fa.positions), np.asarray(fb.positions)
    valid = np.asarray(fa.valid) & np.asarray(fb.valid)
    pos = np.where(valid[:, None], (1 - w) * pa + w * pb, np.nan)
    radii = (1 - w) * np.asarray(fa.radii) + w * np.asarray(fb.radii)
    q = slerp(np.asarray(fa.orientations), np.asarray(fb.orientations), w)
    return _core.HandFrame(handedness, pos, q, radii, valid)


def slerp(qa: np.ndarray, qb: np.ndarray, w: float) -> np.ndarray:
    """Row-wise spherical interpolation of unit quaternions (x, y, z, w) by the shorter arc."""
    qa = qa / np.linalg.norm(qa, axis=-1, keepdims=True)
    qb = qb / np.linalg.norm(qb, axis=-1, keepdims=True)
    dot = np.sum(qa * qb, axis=-1, keepdims=True)
    qb = np.where(dot < 0, -qb, qb)
    dot = np.abs(dot)
    theta = np.arccos(np.clip(dot, -1.0, 1.0))
    s = np.sin(theta)
    small = s < 1e-9
    ka = np.where(small, 1 - w, np.sin((1 - w) * theta) / np.where(small, 1, s))
    kb = np.where(small, w, np.sin(w * theta) / np.where(small, 1, s))
    q = ka * qa + kb * qb
    return q / np.linalg.norm(q, axis=-1, keepdims=True)


# --- geometry -------------------------------------------------------------------------------------------

def palm_frame(frame) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(palm joint position, rotation matrix of the palm joint, unit palm normal: out of the palm = -Y)."""
    p = np.asarray(frame.positions)[_core.PALM]
    r = _sk.quat_matrix(np.asarray(frame.orientations)[_core.PALM])
    return p, r, -r[:, 1]


class Particles:
    """The simulated hand's particles per frame and side (a World holding only that hand), computed once per
    track: the volume each hand occupies in the judged worlds."""

    def __init__(self, track: Track, hand_defs: Dict[str, object]):
        self.radius = 0.0
        self.by_side = {}
        for side in HANDS:
            world = _core.World(_core.WorldDef(ground=False, gravity=[0, 0, 0]))
            hand = world.add_hand(hand_defs[side])
            self.radius = world.hand_model(hand).particle_radius
            rows = []
            for i, f in enumerate(track.frames):
                frame = f.get(side)
                world.step(_dt(track, i), {hand: frame} if frame is not None else None)  # None: untracked
                rows.append(np.asarray(world.hand_particles(hand)) if world.hand_tracked(hand) else None)
            self.by_side[side] = rows

    def at(self, frame: int, side: Optional[str] = None) -> np.ndarray:
        rows = [self.by_side[s][frame] for s in HANDS if side in (None, s)]
        rows = [r for r in rows if r is not None]
        return np.concatenate(rows) if rows else np.zeros((0, 3))


@dataclasses.dataclass(frozen=True)
class Box:
    """An oriented box: centre (3,), rotation (3, 3) (columns: its axes in the world), half extents (3,)."""
    centre: np.ndarray
    rotation: np.ndarray
    half: np.ndarray

    def local(self, q: np.ndarray) -> np.ndarray:
        return (np.asarray(q) - self.centre) @ self.rotation

    def gaps(self, q: np.ndarray, radius: float) -> np.ndarray:
        """Signed distance of spheres (centres q) to the box; negative: they overlap by that much."""
        d = np.abs(self.local(q)) - self.half
        outside = np.linalg.norm(np.maximum(d, 0), axis=1)
        return outside + np.minimum(d.max(axis=1), 0) - radius

    def moved(self, offset) -> "Box":
        return Box(self.centre + offset, self.rotation, self.half)


def move_clear(boxes: Sequence[Box], q: np.ndarray, radius: float, direction: np.ndarray) -> Optional[float]:
    """Metres (a whole number of STEP_M) the boxes must move along unit `direction` until every sphere clears
    every box by CLEAR_M; None beyond MOVE_LIMIT_M."""
    steps = 0
    while steps * STEP_M <= MOVE_LIMIT_M + 1e-12:
        offset = steps * STEP_M * direction
        gap = min((b.moved(offset).gaps(q, radius).min() for b in boxes), default=math.inf) if len(q) else math.inf
        if gap >= CLEAR_M - 1e-12:
            return steps * STEP_M
        # a gap grows by at most the distance moved: the steps that cannot clear yet are skipped
        steps += max(1, int(math.ceil((CLEAR_M - gap) / STEP_M - 1e-9)))
    return None


def squeezed(box: Box, q: np.ndarray, radius: float) -> bool:
    """Whether spheres (centres q) lie on both sides of `box` along one of its axes, over its face (their
    centres within the face's outline), closer together than the box's size less 2 REACH_M: the box cannot fit
    between them wherever it slides along that axis, so the hand squeezes it."""
    if not len(q):
        return False
    c = box.local(q)
    for a in range(3):
        b = [k for k in range(3) if k != a]
        over = np.all(np.abs(c[:, b]) <= box.half[b], axis=1)
        plus, minus = over & (c[:, a] >= 0), over & (c[:, a] < 0)
        if plus.any() and minus.any():
            room = (c[plus, a] - radius).min() - (c[minus, a] + radius).max()
            if room <= 2 * box.half[a] - 2 * REACH_M:
                return True
    return False


# --- objects --------------------------------------------------------------------------------------------

@dataclasses.dataclass
class Placement:
    """One object put into the judged world: `kind` "cube" or "jewelry_box"; `side` the hand it was placed
    for; `frame` the frame the world starts at; `boxes` its dynamic bodies as placed (for the reach check);
    `what` how it was placed."""
    kind: str
    side: str
    frame: int
    boxes: Dict[str, Box]
    what: str
    half: float = CUBE_HALF
    rotation: Optional[np.ndarray] = None
    box_position: Optional[np.ndarray] = None


_BOX_TEMPLATE = {}


def _jewelry_template():
    """Bodies of the default jewelry box (name -> Box) and its lid's front-edge middle."""
    if not _BOX_TEMPLATE:
        w = _core.World(_core.WorldDef(ground=False))
        jb = _core.build_jewelry_box(w)
        for name in ("base", "lid"):
            body = getattr(jb, name)
            pose = np.asarray(w.body_pose(body), float)
            _BOX_TEMPLATE[name] = Box(pose[:3], _sk.quat_matrix(pose[3:]), np.asarray(w.body_shape(body).half_extents))
        _BOX_TEMPLATE["front"] = np.asarray(jb.lid_front(w), float)
        _BOX_TEMPLATE["position"] = np.asarray(_core.JewelryBoxDef().position, float)
    return _BOX_TEMPLATE


def place_cube(track: Track, particles: Particles, side: str, frame: int, point: np.ndarray, half: float,
               what: str) -> Optional[Placement]:
    """A cube centred at `point`, aligned with the hand's palm frame at `frame`, moved along the palm normal
    until clear of every hand; None if it cannot be cleared."""
    hand = track.frames[frame].get(side)
    if hand is None:
        return None
    _, rot, normal = palm_frame(hand)
    box = Box(np.asarray(point, float), rot, np.full(3, half))
    moved = move_clear([box], particles.at(frame), particles.radius, normal)
    if moved is None:
        return None
    return Placement("cube", side, frame, {"cube": box.moved(moved * normal)},
                     f"{what}, moved {moved * 1000:.0f} mm out", half, rot)


def place_jewelry_box(track: Track, particles: Particles, side: str, frame: int, point: np.ndarray,
                      what: str) -> Optional[Placement]:
    """The jewelry box with its lid's front-edge middle at `point`, moved along the palm normal until clear."""
    hand = track.frames[frame].get(side)
    if hand is None:
        return None
    _, _, normal = palm_frame(hand)
    tpl = _jewelry_template()
    shift = np.asarray(point, float) - tpl["front"]
    boxes = {name: tpl[name].moved(shift) for name in ("base", "lid")}
    moved = move_clear(list(boxes.values()), particles.at(frame), particles.radius, normal)
    if moved is None:
        return None
    shift = shift + moved * normal
    return Placement("jewelry_box", side, frame, {n: b.moved(moved * normal) for n, b in boxes.items()},
                     f"{what}, moved {moved * 1000:.0f} mm out", box_position=tpl["position"] + shift)


def grip_point(track: Track, side: str, frame: int, pinch: bool) -> np.ndarray:
    p = np.asarray(track.frames[frame][side].positions)
    if pinch:
        return 0.5 * (p[_core.THUMB_TIP] + p[_core.INDEX_TIP])
    palm, _, normal = palm_frame(track.frames[frame][side])
    return palm + PALM_DEPTH * normal


def path_point(track: Track, side: str, frame: int, where: str) -> np.ndarray:
    if where == "palm":
        return grip_point(track, side, frame, False)
    return np.asarray(track.frames[frame][side].positions)[TIPS[where]]


# --- running one placement -------------------------------------------------------------------------------

@dataclasses.dataclass
class Trace:
    """What happened from the placement frame on: `frames` the track frames stepped; `begins` every grasp
    begin as (frame, side, body); `held` (steps, 2) whether each hand holds the object; `lid_deg` (steps,)."""
    frames: np.ndarray
    begins: List[Tuple[int, str, str]]
    held: np.ndarray
    lid_deg: Optional[np.ndarray]
    snapshot: Optional[dict] = None
    snapshot_centre: Optional[np.ndarray] = None


def _dt(track: Track, i: int) -> float:
    if i > 0:
        return float(track.times[i] - track.times[i - 1])
    return float(np.median(np.diff(track.times))) if len(track.times) > 1 else 1 / 60


def build_world(placement: Placement, settings, hand_defs):
    """The judged world: both hands and the placed object. Returns (world, {name: body}, hinge or None)."""
    wd = _world_def_with(settings)
    if placement.kind == "cube":
        wd.gravity = [0, 0, 0]
    world = _core.World(wd)
    for side in HANDS:
        world.add_hand(hand_defs[side])
    if placement.kind == "cube":
        box = placement.boxes["cube"]
        pose = [*box.centre, *_sk.matrix_quat(box.rotation)]
        body = world.add_body(_core.BodyDef(shape=_core.Shape.box([placement.half] * 3), mass=CUBE_MASS, pose=pose))
        return world, {"cube": body}, None
    d = _core.JewelryBoxDef()
    d.position = [float(v) for v in placement.box_position]
    jb = _core.build_jewelry_box(world, d)
    return world, {"base": jb.base, "lid": jb.lid}, jb.hinge


def run(track: Track, placement: Placement, settings, hand_defs, start: Optional[int] = None,
        snap_at: Optional[int] = None) -> Trace:
    """Steps the judged world through the track from `start` (default: the placement frame) to the end."""
    world, bodies, hinge = build_world(placement, settings, hand_defs)
    names = {b: n for n, b in bodies.items()}
    hands = world.hands()  # in HANDS order: build_world adds them so to a new world
    first = placement.frame if start is None else start
    frames = np.arange(first, len(track.times))
    held = np.zeros((len(frames), 2), bool)
    lid = np.zeros(len(frames)) if hinge is not None else None
    begins, snap, snap_centre = [], None, None
    for s, i in enumerate(frames):
        given = {hand: track.frames[i][side] for hand, side in zip(hands, HANDS)
                 if track.frames[i].get(side) is not None}
        world.step(_dt(track, i), given)  # a side without a frame is untracked
        for e in world.events():
            if e.type == _core.EventType.GRASP_BEGIN and e.body in names:
                begins.append((int(i), HANDS[hands.index(e.hand)], names[e.body]))
        for body in bodies.values():
            g = world.body_grasp(body)
            if g.grasped:
                for h, hand in enumerate(hands):
                    if g.primary == hand or g.secondary == hand:
                        held[s, h] = True
        if hinge is not None:
            lid[s] = math.degrees(world.joint_state(hinge).value)
        if snap_at is not None and i == snap_at:
            from . import render
            snap = render.snapshot(world, bodies, f"{track.name} t={track.times[i]:.2f} s")
            # the view's centre: the object where it is then (the jewelry box: its lid)
            snap_centre = np.asarray(world.body_pose(list(bodies.values())[-1]), float)[:3]
    return Trace(frames, begins, held, lid, snap, snap_centre)


# --- judging a trace -------------------------------------------------------------------------------------

def false_grasps(track: Track, trace: Trace) -> List[Tuple[int, str, str]]:
    """Grasp begins while the grasping hand is open."""
    _, opened = labels(track.strength)
    return [b for b in trace.begins if opened[b[0], HANDS.index(b[1])]]


def held_open_s(track: Track, trace: Trace) -> Tuple[float, Optional[int]]:
    """The longest time any hand held the object while open (from the first such frame to the first frame it
    no longer does), and the frame that run began at."""
    _, opened = labels(track.strength)
    worst, at = 0.0, None
    t = track.times
    for h in range(2):
        bad = trace.held[:, h] & opened[trace.frames, h]
        k = 0
        while k < len(bad):
            if not bad[k]:
                k += 1
                continue
            e = k
            while e < len(bad) and bad[e]:
                e += 1
            stop = t[trace.frames[e]] if e < len(bad) else t[trace.frames[-1]] + _dt(track, trace.frames[-1])
            if stop - t[trace.frames[k]] > worst:
                worst, at = float(stop - t[trace.frames[k]]), int(trace.frames[k])
            k = e
    return worst, at


def grasped_in(trace: Trace, closure: Closure, t0: Optional[float] = None, t1: Optional[float] = None,
               times: Optional[np.ndarray] = None) -> bool:
    """Whether the closure's hand holds the object at some step of the closure (frames begin..end-1, or the
    times [t0, t1) when given, with the trace's own `times`)."""
    h = HANDS.index(closure.side)
    if t0 is None:
        inside = (trace.frames >= closure.begin) & (trace.frames < closure.end)
    else:
        ts = times[trace.frames]
        inside = (ts >= t0 - 1e-9) & (ts < t1 - 1e-9)
    return bool(trace.held[inside, h].any())


def reachable(track: Track, particles: Particles, placement: Placement, closure: Closure) -> bool:
    """Within reach (module docstring): in a closed frame of the closure, the hand's particles squeeze one of
    the object's bodies as placed (:func:`squeezed`)."""
    closed, _ = labels(track.strength[:, HANDS.index(closure.side)])
    for i in range(max(closure.closed, placement.frame), closure.end):
        if not closed[i]:
            continue
        q = particles.at(i, closure.side)
        if any(squeezed(b, q, particles.radius) for b in placement.boxes.values()):
            return True
    return False


# --- the three checks -------------------------------------------------------------------------------------

def fixed_placement(track: Track, particles: Particles,
                    side: str) -> Tuple[Optional[Placement], Optional[Closure], str]:
    """The closing-hand check's cube for one hand: (placement, the closure judged or None, note)."""
    if not track.tracked(side).any():
        return None, None, "not tracked"
    cl = closures(track, side)
    if cl:
        c = cl[0]
        if side not in track.frames[c.begin]:
            return None, c, "not tracked at the closure's beginning"
        half = PINCH_HALF if c.pinch else CUBE_HALF
        what = ("2 cm cube between thumb and index tips" if c.pinch else "5 cm cube 4 cm along the palm normal")
        p = place_cube(track, particles, side, c.begin, grip_point(track, side, c.begin, c.pinch), half,
                       f"{what} at {track.times[c.begin]:.2f} s")
        return p, c, "placed" if p else "could not be cleared"
    seen = np.nonzero(track.tracked(side))[0]
    mid = int(seen[np.argmin(np.abs(track.times[seen] - 0.5 * track.times[-1]))])
    tip = np.asarray(track.frames[mid][side].positions)[_core.INDEX_TIP]
    hand = track.frames[mid][side]
    _, rot, _ = palm_frame(hand)
    box = Box(tip, rot, np.full(3, CUBE_HALF))
    return (Placement("cube", side, 0, {"cube": box}, f"5 cm cube at the index tip at {track.times[mid]:.2f} s "
                      f"(never closes)", CUBE_HALF, rot), None, "never closes")


def judge_fixed(track: Track, particles: Particles, settings, hand_defs) -> Dict[str, dict]:
    out = {}
    for side in HANDS:
        placement, closure, note = fixed_placement(track, particles, side)
        if placement is None:
            out[side] = {"judged": False, "note": note}
            continue
        trace = run(track, placement, settings, hand_defs)
        false = false_grasps(track, trace)
        held, held_at = held_open_s(track, trace)
        row = {"judged": True, "placement": placement.what, "false_grasps": len(false),
               "false_grasp_s": [round(float(track.times[f[0]]), 3) for f in false],
               "held_open_s": round(held, 3), "held_open_at_s": None if held_at is None else
               round(float(track.times[held_at]), 3)}
        if closure is not None:
            row["closure_s"] = [round(float(track.times[k]), 3)
                                for k in (closure.begin, closure.closed, min(closure.end, len(track.times) - 1))]
            row["grasped"] = grasped_in(trace, closure)
            row["reachable"] = reachable(track, particles, placement, closure)
            row["pass"] = row["grasped"] and not false and held <= HELD_OPEN_S
        else:
            row["grasps"] = len(trace.begins)
            row["pass"] = not trace.begins
        out[side] = row
        out[side]["_trace"] = (placement, closure, trace)
    return out


def sweep_placements(track: Track, particles: Particles, frames_per_hand: int = SWEEP_FRAMES,
                     points: Sequence[str] = SWEEP_POINTS,
                     kinds=("cube", "jewelry_box")) -> Tuple[List[Placement], int]:
    """The sweep's placements (and how many could not be cleared): for every tracked hand, `frames_per_hand`
    evenly spaced frames of its tracked frames, at each of `points`, each kind of object."""
    out, skipped = [], 0
    for side in HANDS:
        seen = np.nonzero(track.tracked(side))[0]
        if not len(seen):
            continue
        picks = seen[np.unique(np.linspace(0, len(seen) - 1, frames_per_hand + 2).round().astype(int))[1:-1]]
        first = closures(track, side)[:1]
        half = PINCH_HALF if first and first[0].pinch else CUBE_HALF  # the cube this hand can hold
        for k in picks:
            for where in points:
                point = path_point(track, side, int(k), where)
                what = f"{side} {where} at {track.times[k]:.2f} s"
                for kind in kinds:
                    p = (place_cube(track, particles, side, int(k), point, half, what) if kind == "cube"
                         else place_jewelry_box(track, particles, side, int(k), point, what))
                    if p is None:
                        skipped += 1
                    else:
                        out.append(p)
    return out, skipped


def judge_sweep(track: Track, particles: Particles, settings, hand_defs, placements: List[Placement]) -> dict:
    cl = {side: closures(track, side) for side in HANDS}
    runs = []
    for p in placements:
        trace = run(track, p, settings, hand_defs)
        false = false_grasps(track, trace)
        held, _ = held_open_s(track, trace)
        reach, missed = 0, 0
        for side in HANDS:
            # each hand's first closure that begins once the object is there: a hand closed before cannot be
            # closing on it, and the object stands where it was placed only until a hand first acts on it
            c = next((c for c in cl[side] if c.begin >= p.frame), None)
            if c is not None and reachable(track, particles, p, c):
                reach += 1
                missed += not grasped_in(trace, c)
        runs.append({"placement": f"{p.kind}: {p.what}", "false_grasps": len(false),
                     "held_open": held > HELD_OPEN_S, "reachable": reach, "missed": missed})
    n = len(runs)
    reach = sum(r["reachable"] for r in runs)
    return {"placements": n, "false": sum(r["false_grasps"] > 0 for r in runs),
            "held_open": sum(r["held_open"] for r in runs), "reachable_closures": reach,
            "missed": sum(r["missed"] for r in runs), "runs": runs}


def judge_rates(track: Track, particles: Particles, settings, hand_defs, rates=RATES) -> dict:
    """Frame-rate invariance with the closing-hand cubes and the jewelry box at the first judged hand's point."""
    cases = []
    for side in HANDS:
        p, c, _ = fixed_placement(track, particles, side)
        if p is not None and c is not None:
            cases.append(p)
    if not cases:
        return {"judged": False, "note": "no closing hand"}
    first = cases[0]
    c0 = closures(track, first.side)[0]
    box = place_jewelry_box(track, particles, first.side, first.frame,
                            grip_point(track, first.side, first.frame, c0.pinch), "lid front at the grip")
    if box is not None:
        cases.append(box)
    per_rate = {}
    for rate in rates:
        rows = []
        for p in cases:
            r = resample(track, rate, float(track.times[p.frame]))
            q = dataclasses.replace(p, frame=0)
            trace = run(r, q, settings, hand_defs)
            grasped = [grasped_in(trace, c, track.times[c.begin], track.times[c.end] if c.end < len(track.times)
                                  else math.inf, r.times)
                       for side in HANDS for c in closures(track, side) if c.end > p.frame]
            rows.append({"kind": p.kind, "grasped": grasped,
                         "lid_deg": None if trace.lid_deg is None else round(float(trace.lid_deg.max()), 2)})
        per_rate[str(rate)] = rows
    same = all(per_rate[str(r)][k]["grasped"] == per_rate[str(rates[0])][k]["grasped"]
               for r in rates for k in range(len(cases)))
    lids = [per_rate[str(r)][-1]["lid_deg"] for r in rates] if box is not None else []
    spread = (max(lids) - min(lids)) if lids else None
    return {"judged": True, "same_grasps": same, "lid_deg": lids, "lid_spread_deg": spread,
            "pass": same and (spread is None or spread <= LID_SPREAD_DEG), "per_rate": per_rate}


# --- rules, recordings, report ----------------------------------------------------------------------------

# WorldDef fields a rule may set besides the GraspSettings: the contact skin (docs/grasp.md "First touch") and
# the push model (docs/grasp.md "Push models"; by name: push_model=physical).
RULE_WORLD_FIELDS = ("skin_depth", "skin_pressure", "push_model")


def parse_rule(spec: str) -> Tuple[str, object]:
    """(name, WorldDef) of a rule: "default", "contacts" (GraspSettings.contacts(): the rule before the hand's
    intent was read), "paper" (GraspSettings.paper(): eq. 3 as printed, c = +0.7, any two contacts, grasp and
    release on the first frame), or "NAME:field=value,..." (GraspSettings fields and the WorldDef fields of
    RULE_WORLD_FIELDS over the default). The judge builds its worlds from the WorldDef's grasp settings and
    those fields only."""
    expected = "expected 'default', 'contacts', 'paper' or 'NAME:field=value,...'"
    if not isinstance(spec, str) or not spec:
        raise ValueError(f"rule: {expected}, got {spec!r}")
    presets = {"default": _core.GraspSettings, "contacts": _core.GraspSettings.contacts,
               "paper": _core.GraspSettings.paper}
    world = _core.WorldDef(ground=False)
    if spec in presets:
        world.grasp = presets[spec]()
        return spec, world
    s = _core.GraspSettings()
    name, _, fields = spec.partition(":")
    if not name or not fields:
        raise ValueError(f"rule: {expected}, got {spec!r}")
    for item in fields.split(","):
        key, eq, value = item.partition("=")
        key = key.strip()
        target = world if key in RULE_WORLD_FIELDS else s
        if not eq or not hasattr(target, key) or key.startswith("_"):
            raise ValueError(f"rule {name}: {item!r} is not field=value of a GraspSettings field "
                             f"or of {', '.join(RULE_WORLD_FIELDS)}")
        current = getattr(target, key)
        try:
            if isinstance(current, bool):
                if value.strip().lower() not in ("true", "false", "1", "0"):
                    raise ValueError(value)
                parsed = value.strip().lower() in ("true", "1")
            elif hasattr(type(current), "__members__"):  # an enum, by name
                members = type(current).__members__
                if value.strip().upper() not in members:
                    raise ValueError(f"not one of {', '.join(m.lower() for m in members)}")
                parsed = members[value.strip().upper()]
            else:
                parsed = type(current)(value)
            setattr(target, key, parsed)
        except (ValueError, TypeError) as e:
            owner = "WorldDef" if target is world else "GraspSettings"
            raise ValueError(f"rule {name}: {owner}.{key}: bad value {value!r} ({e})") from None
    world.grasp = s
    try:
        _core.World(_world_def_with(world))  # the world validates its settings
    except Exception as e:
        raise ValueError(f"rule {name}: {e}") from None
    return name, world


def apply_rule(target, rule):
    """`target` (a WorldDef) with a rule's settings: a WorldDef of parse_rule gives its grasp settings and
    RULE_WORLD_FIELDS, GraspSettings alone the grasp settings; the rest of `target` stays. Returns `target`."""
    if isinstance(rule, _core.WorldDef):
        target.grasp = rule.grasp
        for field in RULE_WORLD_FIELDS:
            setattr(target, field, getattr(rule, field))
    else:
        target.grasp = rule
    return target


def _world_def_with(settings):
    """A fresh judged WorldDef (no ground) from a rule (apply_rule)."""
    return apply_rule(_core.WorldDef(ground=False), settings)


def default_hand_defs():
    return {side: _core.HandDef(handedness=HANDEDNESS[side]) for side in HANDS}


def model_keeper(hand_defs):
    """A world holding the hands of `hand_defs`: while it lives, every world the judge builds shares their
    built models instead of building each anew (~0.2 s a hand; World.add_hand shares the model of an equal
    HandDef among live worlds)."""
    keeper = _core.World(_core.WorldDef(ground=False))
    for side in HANDS:
        keeper.add_hand(hand_defs[side])
    return keeper


def load_track(path: Path) -> Track:
    from .replay import load_motion
    return track_from_motion(load_motion(path))


def recordings(paths: Sequence[Path]) -> List[Path]:
    """The recordings named: files, or every .json.lz / .json / .bvh in a folder (sorted)."""
    out = []
    for p in paths:
        p = Path(p)
        if p.is_dir():
            out += sorted(q for q in p.iterdir() if q.name.lower().endswith((".json.lz", ".json", ".bvh")))
        elif p.is_file():
            out.append(p)
        else:
            raise FileNotFoundError(f"paths: no such file or folder: {p}")
    return out


def judge_track(track: Track, rules: Dict[str, object], sweep_frames: int = SWEEP_FRAMES,
                sweep_points: Sequence[str] = SWEEP_POINTS, rates=RATES, keep_traces: bool = False) -> dict:
    """Every check of the module docstring for every rule: {rule: {"fixed", "sweep", "rates"}}."""
    hand_defs = default_hand_defs()
    keeper = model_keeper(hand_defs)  # noqa: F841 (kept alive until the judging is done)
    particles = Particles(track, hand_defs)
    placements, skipped = sweep_placements(track, particles, sweep_frames, sweep_points)
    out = {"name": track.name, "frames": len(track.times), "duration_s": round(float(track.times[-1]), 3),
           "closures": {side: [[round(float(track.times[c.begin]), 3), round(float(track.times[c.closed]), 3),
                                "pinch" if c.pinch else "grab"] for c in closures(track, side)] for side in HANDS},
           "sweep_skipped": skipped, "rules": {}}
    for name, settings in rules.items():
        fixed = judge_fixed(track, particles, settings, hand_defs)
        traces = {side: row.pop("_trace") for side, row in fixed.items() if "_trace" in row}
        sweep = judge_sweep(track, particles, settings, hand_defs, placements)
        res = {"fixed": fixed, "sweep": sweep, "rates": judge_rates(track, particles, settings, hand_defs, rates)}
        if keep_traces:
            res["_traces"] = traces
        out["rules"][name] = res
    return out


def _pct(a: int, b: int) -> str:
    return f"{100.0 * a / b:.1f} %" if b else "-"


def table(results: List[dict], rules: Sequence[str]) -> List[str]:
    """The human table: one row per recording and hand, a column group per rule."""
    head = f"{'recording':<30} {'hand':<5} " + " ".join(f"| {r[:33]:<33}" for r in rules)
    lines = [head, f"{'':<30} {'':<5} " + " ".join(f"| {'fixed':<8} {'sweep F/M/H':<13} {'rate':<10}"
                                                    for _ in rules),
             "-" * len(head)]
    totals = {r: {"fixed_fail": 0, "fixed": 0, "place": 0, "false": 0, "held": 0, "reach": 0, "miss": 0,
                  "rate_fail": 0, "rate": 0, "false_fixed": 0} for r in rules}
    for res in results:
        for k, side in enumerate(HANDS):
            cells = []
            for r in rules:
                rr = res["rules"][r]
                f = rr["fixed"][side]
                t = totals[r]
                if f.get("judged"):
                    t["fixed"] += 1
                    t["fixed_fail"] += not f["pass"]
                    t["false_fixed"] += f["false_grasps"]
                    why = ("" if f["pass"] else "-" + ("F" if f["false_grasps"] else "")
                           + ("M" if f.get("grasped") is False else "")
                           + ("H" if f["held_open_s"] > HELD_OPEN_S else "") + ("G" if f.get("grasps") else ""))
                    fixed = ("pass" if f["pass"] else "FAIL") + why
                else:
                    fixed = "-"
                if k == 0:
                    s = rr["sweep"]
                    t["place"] += s["placements"]
                    t["false"] += s["false"]
                    t["held"] += s["held_open"]
                    t["reach"] += s["reachable_closures"]
                    t["miss"] += s["missed"]
                    sw = f"{s['false']}/{s['missed']}of{s['reachable_closures']}/{s['held_open']}"
                    ra = rr["rates"]
                    if ra.get("judged"):
                        t["rate"] += 1
                        t["rate_fail"] += not ra["pass"]
                        rate = ("pass" if ra["pass"] else "FAIL") + (
                            f" {ra['lid_spread_deg']:.1f}d" if ra["lid_spread_deg"] is not None else "")
                    else:
                        rate = "-"
                else:
                    sw, rate = "", ""
                cells.append(f"| {fixed:<8} {sw:<13} {rate:<10}")
            if any(res["rules"][r]["fixed"][side].get("judged") for r in rules) or k == 0:
                lines.append(f"{res['name'][:30]:<30} {side:<5} " + " ".join(cells))
    lines.append("-" * len(head))
    for r in rules:
        t = totals[r]
        lines.append(f"{r}: fixed protocol {t['fixed'] - t['fixed_fail']} of {t['fixed']} hands pass "
                     f"({t['false_fixed']} false grasps); sweep {t['place']} placements: false grasps {t['false']} "
                     f"({_pct(t['false'], t['place'])}), reachable closures grasped {t['reach'] - t['miss']} of "
                     f"{t['reach']} ({_pct(t['reach'] - t['miss'], t['reach'])}), held open > {HELD_OPEN_S} s "
                     f"{t['held']} ({_pct(t['held'], t['place'])}); frame rates {t['rate'] - t['rate_fail']} of "
                     f"{t['rate']} recordings pass")
    lines.append(f"(fixed: F false grasp, M closure not grasped, H held open > {HELD_OPEN_S} s, G a never-closing "
                 f"hand grasped; sweep F/M/H: placements with a false grasp / reachable closures missed of all "
                 f"reachable / placements held open; rate: lid swing spread in deg)")
    lines.append(f"(within reach: the closed hand's particles over two opposite faces of the placed object, closer "
                 f"than its size less {2 * REACH_M * 1000:g} mm; closed >= {CLOSED}, open < {OPEN}; rates "
                 f"{', '.join(map(str, RATES))} Hz)")
    return lines


def summary(results: List[dict], rule: str) -> dict:
    """The issue's figures for one rule over all results."""
    fixed = [r["rules"][rule]["fixed"][s] for r in results for s in HANDS if r["rules"][rule]["fixed"][s].get("judged")]
    sweeps = [r["rules"][rule]["sweep"] for r in results]
    rates = [r["rules"][rule]["rates"] for r in results if r["rules"][rule]["rates"].get("judged")]
    place = sum(s["placements"] for s in sweeps)
    reach = sum(s["reachable_closures"] for s in sweeps)
    return {"fixed_hands": len(fixed), "fixed_pass": sum(f["pass"] for f in fixed),
            "fixed_false_grasps": sum(f["false_grasps"] for f in fixed),
            "fixed_missed": sum(f.get("grasped") is False for f in fixed),
            "fixed_held_open": sum(f["held_open_s"] > HELD_OPEN_S for f in fixed),
            "fixed_never_closing_grasped": sum(bool(f.get("grasps")) for f in fixed),
            "sweep_placements": place, "sweep_false": sum(s["false"] for s in sweeps),
            "sweep_false_rate": sum(s["false"] for s in sweeps) / place if place else 0.0,
            "sweep_reachable": reach, "sweep_missed": sum(s["missed"] for s in sweeps),
            "sweep_grasped_rate": (reach - sum(s["missed"] for s in sweeps)) / reach if reach else 1.0,
            "sweep_held_open": sum(s["held_open"] for s in sweeps),
            "rate_recordings": len(rates), "rate_pass": sum(r["pass"] for r in rates),
            "rate_worst_lid_spread_deg": max((r["lid_spread_deg"] or 0.0 for r in rates), default=0.0)}


# --- pictures --------------------------------------------------------------------------------------------

FAILURE_KINDS = ("false_grasp", "missed_closure", "held_open", "frame_rate")


def first_failures(results: List[dict], rule: str) -> Dict[str, Tuple[str, str]]:
    """{failure kind: (recording, hand or "")} of the first failure of each kind in the fixed protocol and the
    rate check (the sweep's are the same kinds over other placements)."""
    out = {}
    for r in results:
        rr = r["rules"][rule]
        for side in HANDS:
            f = rr["fixed"][side]
            if not f.get("judged"):
                continue
            if (f["false_grasps"] or f.get("grasps")) and "false_grasp" not in out:
                out["false_grasp"] = (r["name"], side)
            if f.get("grasped") is False and "missed_closure" not in out:
                out["missed_closure"] = (r["name"], side)
            if f["held_open_s"] > HELD_OPEN_S and "held_open" not in out:
                out["held_open"] = (r["name"], side)
        if rr["rates"].get("judged") and not rr["rates"]["pass"] and "frame_rate" not in out:
            out["frame_rate"] = (r["name"], "")
    return out


def picture(path: Path, kind: str, track: Track, side: str, settings, rule: str):
    """One failure drawn: the hand's strength and labels over time, when the object was held, and the hands
    and object at the moment of the failure (front view)."""
    from . import render
    from .plots import save_figure
    plt = render.pyplot()
    hand_defs = default_hand_defs()
    keeper = model_keeper(hand_defs)  # noqa: F841
    particles = Particles(track, hand_defs)
    fig = plt.figure(figsize=(11, 4.2))
    if kind == "frame_rate":
        ax = fig.add_subplot(1, 1, 1)
        res = judge_rates(track, particles, settings, hand_defs)
        lids = res["lid_deg"] or [0.0] * len(RATES)
        ax.bar([str(r) for r in RATES], lids, color="darkgoldenrod")
        ax.set_xlabel("rate (Hz)")
        ax.set_ylabel("largest lid angle (deg)")
        ax.set_title(f"{track.name}, rule {rule}: lid swing by frame rate (spread {res['lid_spread_deg'] or 0:.1f} "
                     f"deg); above each bar, per object, each closure grasped (G) or not (-)", fontsize=9)
        for k, r in enumerate(RATES):
            text = "; ".join(f"{row['kind'].replace('jewelry_box', 'box')} "
                             + " ".join("G" if g else "-" for g in row["grasped"]) for row in res["per_rate"][str(r)])
            ax.text(k, lids[k] + 0.5, text, ha="center", fontsize=8)
        save_figure(fig, path, dpi=80)
        return
    grid = fig.add_gridspec(1, 3)
    ax = fig.add_subplot(grid[0, :2])
    placement, closure, _ = fixed_placement(track, particles, side)
    trace = run(track, placement, settings, hand_defs)
    h = HANDS.index(side)
    if kind == "false_grasp":
        frame = (false_grasps(track, trace) or trace.begins)[0][0]
    elif kind == "held_open":
        frame = held_open_s(track, trace)[1]
    else:
        closed = [i for i in range(closure.closed, closure.end)]
        frame = closed[len(closed) // 2] if closed else closure.closed
    trace = run(track, placement, settings, hand_defs, snap_at=frame)
    t = track.times
    ax.plot(t, track.strength[:, h], color="k", lw=1, label=f"{side} strength max(grab, pinch)")
    ax.axhline(CLOSED, color="tab:green", ls=":", lw=0.8)
    ax.axhline(OPEN, color="tab:red", ls=":", lw=0.8)
    _, opened = labels(track.strength[:, h])
    ax.fill_between(t, 0, 1, where=opened, transform=ax.get_xaxis_transform(), color="tab:red", alpha=0.08,
                    label="open")
    held = np.zeros(len(t), bool)
    held[trace.frames] = trace.held[:, h]
    ax.fill_between(t, 0, 1, where=held, transform=ax.get_xaxis_transform(), color="0.6", alpha=0.5,
                    label="held by this hand")
    if closure is not None:
        ax.axvspan(t[closure.begin], t[min(closure.end, len(t) - 1)], color="tab:green", alpha=0.08, label="closure")
    ax.axvline(t[frame], color="tab:purple", lw=1)
    ax.set_ylim(-0.05, 1.05)
    ax.set_xlabel("time (s)")
    ax.legend(fontsize=7, loc="upper left")
    ax.set_title(f"{track.name} {side} hand, rule {rule}: {kind.replace('_', ' ')}\n{placement.what}", fontsize=9)
    if trace.snapshot is not None:
        render.draw(fig.add_subplot(grid[0, 2]), trace.snapshot, trace.snapshot_centre, half_width=0.12, axes=(0, 1))
    save_figure(fig, path, dpi=80)


DOC_BEGIN, DOC_END = "<!-- intent begin -->", "<!-- intent end -->"


def write_doc(path: Path, lines: List[str], seconds: float):
    """Replaces the text between DOC_BEGIN and DOC_END of `path` with the table; the markers must be there."""
    text = path.read_text()
    if DOC_BEGIN not in text or DOC_END not in text:
        raise ValueError(f"doc: {path} has no {DOC_BEGIN} ... {DOC_END} markers")
    head, rest = text.split(DOC_BEGIN, 1)
    _, tail = rest.split(DOC_END, 1)
    body = "\n".join(["```"] + lines + ["```", f"(judged in {seconds:.0f} s of wall time)"])
    path.write_text(f"{head}{DOC_BEGIN}\n{body}\n{DOC_END}{tail}")


# --- CLI ------------------------------------------------------------------------------------------------

def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m handsim.intent", description=__doc__.split("\n\n")[0])
    ap.add_argument("paths", nargs="*", type=Path,
                    help="recordings or folders of them (the docs use ../shared/assets/leap_recordings; "
                         "none are looked for elsewhere)")
    ap.add_argument("--rule", action="append",
                    help="grasp settings to judge: default, contacts, paper, or NAME:field=value,... of GraspSettings "
                         f"or {', '.join(RULE_WORLD_FIELDS)} (repeat to compare)")
    ap.add_argument("--sweep-frames", type=int, default=SWEEP_FRAMES,
                    help=f"placement frames per hand in the sweep (default {SWEEP_FRAMES})")
    ap.add_argument("--json", action="store_true", help="print the results as one JSON document")
    ap.add_argument("--out", type=Path, help="write one picture per rule and failure kind here")
    ap.add_argument("--doc", type=Path, help="rewrite the table between the intent markers of this Markdown file")
    args = ap.parse_args(argv)
    try:
        rules = dict(parse_rule(s) for s in (args.rule or ["default"]))
        if args.sweep_frames < 1:
            raise ValueError(f"--sweep-frames: expected at least 1, got {args.sweep_frames}")
        paths = args.paths
        if not paths:
            raise FileNotFoundError("paths: none given (e.g. ../shared/assets/leap_recordings)")
        files = recordings(paths)
        if args.doc is not None and not (args.doc.is_file() and DOC_BEGIN in args.doc.read_text()):
            raise ValueError(f"--doc: {args.doc} is not a file with the {DOC_BEGIN} ... {DOC_END} markers")
    except (ValueError, FileNotFoundError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    began = time.perf_counter()
    results, tracks = [], {}
    for f in files:
        track = load_track(f)
        tracks[track.name] = track
        results.append(judge_track(track, rules, args.sweep_frames))
        if not args.json:
            print(f"  judged {track.name} ({time.perf_counter() - began:.0f} s)", file=sys.stderr)
    doc = {"rules": list(rules), "summary": {r: summary(results, r) for r in rules}, "recordings": results,
           "seconds": round(time.perf_counter() - began, 1)}
    if args.json:
        print(json.dumps(doc, indent=1))
    else:
        print("\n".join(table(results, list(rules))))
    if args.doc is not None:
        write_doc(args.doc, table(results, list(rules)), doc["seconds"])
    if args.out is not None:
        for rule, settings in rules.items():
            for kind, (name, side) in first_failures(results, rule).items():
                picture(args.out / f"intent_{rule}_{kind}.png", kind, tracks[name], side, settings, rule)
    return 0


if __name__ == "__main__":
    sys.exit(main())
