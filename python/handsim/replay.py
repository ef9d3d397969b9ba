"""Replay hand input on a scene and report what happened: ``python -m handsim.replay FILE [options]``.

FILE is a handsim recording (``.npz``, :mod:`handsim.recording`), a Leap Motion recording (``.json.lz`` /
``.json`` of leapjs-playback) or a BVH file (``.bvh``). Leap and BVH input is first turned into a recording
(:func:`session_from_motion`): resampled to 60 Hz (each step takes the newest tracker frame at or before its
time), driving a right and a left hand, and placed in the scene by the placement rule below. A handsim
recording replays as recorded (``--scene`` is then ignored) and its state hashes are checked.

Placement (deterministic, from the motion alone): the whole recording is translated so that the mean palm
position over all frames and hands lies over the middle of the jewelry box's closed lid front edge (the scene's
default box) and the lowest point any hand reaches (a joint centre less its radius) 1 cm below the lid's top;
no rotation (a Leap's device frame already has +Y up and +Z towards the user).
Scene ``free_box`` then puts a cube where the hand closes. The closing hand is the one whose Leap grab or pinch
strength gets highest, if that reaches 0.95: a pinch (its pinch strength is the larger one) gets a 1.6 cm cube,
its grip the middle between the thumb and index tips; a grab a 4 cm cube, its grip the middle between the palm
and the mean of the four fingertips. A closure of that hand is a rise of its strength from below 0.05 (open) to
0.5 (half closed); the next one begins once it was open again. The cube may start at the grip of any frame of a
closure while the hand stays at least half closed, moved out of the palm (along the palm joint's normal, the way
the fingers close) in 1 mm steps until it is 1 mm clear of the hand in every frame up to the last one it was
open before that closure, so that only the closing hand reaches it (a grab: the particles of the simulated hand,
posed frame by frame as the replay will pose it; a pinch: the index finger, capsules along its bones with the
joint radii; the thumb is the anvil either closes against and may rest at the cube, a grab leaves out the
particles nearest its proximal, distal and tip joints), and clear of the palm (the particles nearest the palm,
wrist and finger metacarpal joints) from then to that frame, so that the hand does not come at it back first.
These grips are tried in time order; the cube starts at the first one the closing hand (all its particles, from
the last open frame until it is less than half closed again) reaches half the cube's half extent into (10 mm, a
pinch 4 mm), or at the deepest if none is reached so far. The rule says which closure and frame it took, how far
the cube was moved and how deep the hand reaches.
Without a closing hand the 4 cm cube goes under the first hand's mean palm, its top 1 cm above the lowest point any joint of
that hand reaches, so the hand brushes it. The table top is moved to the cube's bottom.

Writes ``<out>/<name>_<scene>.png`` (key frames and a timeline), ``<out>/<name>.txt`` (the summary) and with
``--save`` the recording as ``<out>/<name>_<scene>.npz``.
"""
from __future__ import annotations

import argparse
import dataclasses
import json
import math
import sys
from pathlib import Path
from typing import Dict, List, Optional, Sequence

import numpy as np

from . import _core
from . import recording as _rec
from . import render as _render
from . import scenes as _scenes
from .plots import save_figure
from .adapters import skeleton as _sk
from .adapters.motion import HANDS, Motion, with_strengths  # noqa: F401 (part of this module's API)

DT = 1.0 / 60.0
DIP = 0.01
CLOSED = 0.95
HALF_CLOSED = 0.5
BRUSH = 0.01
PINCH_HALF = 0.008  # pinch: a 1.6 cm cube
OPEN = 0.05        # a hand counts as open below this Leap strength
CLEAR = 0.001      # ... by this much
REACH = 0.5        # the closing hand is to reach this share of the cube's half extent into it
THUMB_ANVIL = (_core.THUMB_PROXIMAL, _core.THUMB_DISTAL, _core.THUMB_TIP)
PALM_JOINTS = (_core.PALM, _core.WRIST, _core.INDEX_METACARPAL, _core.MIDDLE_METACARPAL, _core.RING_METACARPAL,
               _core.LITTLE_METACARPAL)


def _default_lid_front():
    w = _core.World()
    box = _core.build_jewelry_box(w)
    return np.asarray(box.lid_front(w), float)


def motion_from_leap(leap) -> Motion:
    return with_strengths(Motion(leap.name, leap.times, leap.frames, leap.grab, leap.pinch, "leap", dict(leap.notes)))


def closing_hand(motion: Motion):
    """(side, kind, strength (N,)) of the hand whose Leap grab or pinch strength gets highest, if it reaches
    CLOSED; None otherwise (no closing hand, or no strengths)."""
    best = None
    for col, side in enumerate(HANDS):
        for kind, arr in (("grab", motion.grab), ("pinch", motion.pinch)):
            if arr is None or np.all(np.isnan(arr[:, col])):
                continue
            m = float(np.nanmax(arr[:, col]))
            if m >= CLOSED and (best is None or m > best[0] + 1e-12):
                best = (m, side, col)
    if best is None:
        return None
    _, side, col = best
    grab_max = np.nanmax(motion.grab[:, col]) if motion.grab is not None else 0
    pinch_max = np.nanmax(motion.pinch[:, col]) if motion.pinch is not None else 0
    kind = "pinch" if pinch_max > grab_max else "grab"
    return side, kind, (motion.pinch if kind == "pinch" else motion.grab)[:, col]


def closure_start(motion: Motion) -> Optional[float]:
    """Time (s from the motion's start) the closing hand's strength last rose from below OPEN before it first
    reached HALF_CLOSED; None without a closing hand."""
    c = closing_hand(motion)
    return None if c is None else float(motion.times[_closure_start_index(c[2])])


def _closure_start_index(strength: np.ndarray) -> int:
    """Index of the last frame the strength was below OPEN before it first reached HALF_CLOSED (0 if never)."""
    closures = _closures(strength)
    return closures[0][0] if closures else 0


def _closures(strength: np.ndarray) -> List[tuple]:
    """Every closure of a hand as (k0, k, end): its strength rises from below OPEN (last open frame k0, 0 if it
    never was) to HALF_CLOSED (first frame k) and stays at least half closed until frame `end` (exclusive). The
    next closure begins only once the hand has been open again: half opening and closing again is the same
    closure. NaN (no strength) counts as open."""
    s = np.nan_to_num(strength, nan=0.0)
    out, start = [], 0
    while True:
        half = np.nonzero(s[start:] >= HALF_CLOSED)[0]
        if not len(half):
            return out
        k = start + int(half[0])
        opened = np.nonzero(s[:k] < OPEN)[0]
        below_half = np.nonzero(s[k:] < HALF_CLOSED)[0]
        end = k + int(below_half[0]) if len(below_half) else len(s)
        out.append((int(opened[-1]) if len(opened) else 0, k, end))
        reopened = np.nonzero(s[end:] < OPEN)[0]
        if not len(reopened):
            return out
        start = end + int(reopened[0])


def placement(motion: Motion) -> np.ndarray:
    """Translation (3,) of the recording into the scenes: the mean palm over the lid's front edge (x, z) and
    the lowest point any hand reaches (a joint's centre less its radius) DIP below the lid's top face."""
    palms = motion.palms()
    if len(palms) == 0:
        return np.zeros(3)  # no tracked hand in any frame (a tracker left running): nothing to place
    lowest = min(float(np.min(np.asarray(a.frame.positions)[np.asarray(a.frame.valid), 1]
                              - np.asarray(a.frame.radii)[np.asarray(a.frame.valid)]))
                 for f in motion.frames for a in f.values() if a.frame.tracked)
    front = _default_lid_front()
    d = _core.JewelryBoxDef()
    lid_top = front[1] + d.lid_half_thickness
    mean = palms.mean(axis=0)
    return np.array([front[0] - mean[0], lid_top - DIP - lowest, front[2] - mean[2]])


def _bone_samples(frames, fingers=("thumb",) + _sk.FINGERS, per_bone=6):
    """Points along the bones of `fingers` (metacarpal to tip) in every frame, with radii interpolated between
    the joints': a capsule model of those fingers."""
    pairs = []
    for f in fingers:
        joints = _sk.chain(f)
        pairs += list(zip(joints[:-1], joints[1:]))
    a, b = np.array(pairs).T
    t = np.linspace(0, 1, per_bone)[:, None]
    qs, rs = [], []
    for frame in frames:
        p, r, v = np.asarray(frame.positions), np.asarray(frame.radii), np.asarray(frame.valid)
        keep = v[a] & v[b]
        pa, pb, ra, rb = p[a[keep]], p[b[keep]], r[a[keep]], r[b[keep]]
        qs.append((pa[None] * (1 - t[..., None]) + pb[None] * t[..., None]).reshape(-1, 3))
        rs.append((ra[None] * (1 - t) + rb[None] * t).reshape(-1))
    if not qs:
        return np.zeros((0, 3)), np.zeros(0)
    return np.concatenate(qs), np.concatenate(rs)


def _particles(frames, hand_def, skip=()):
    """Centres (M, 3) and radii (M,) of the simulated hand's particles in every one of `frames` (a World with
    only that hand, skinned frame by frame): the volume the hand will occupy in the replay. Particles whose
    nearest joint is one of `skip` (joint indices) are left out."""
    q, radius = _particles_by_frame(frames, hand_def, skip)
    q = np.concatenate(q) if q else np.zeros((0, 3))
    return q, np.full(len(q), radius)


def _particles_by_frame(frames, hand_def, skip=()):
    """The centres of _particles, one (M_i, 3) array per frame ((0, 3) where the hand is untracked), and their
    radius."""
    world = _core.World(_core.WorldDef(ground=False, gravity=[0, 0, 0]))
    hand = world.add_hand(hand_def)
    points = []
    for frame in frames:
        world.step(DT, {hand: frame})
        q = np.asarray(world.hand_particles(hand)) if world.hand_tracked(hand) else np.zeros((0, 3))
        points.append(_without_nearest(q, frame, skip) if skip else q)
    return points, world.hand_model(hand).particle_radius


def _without_nearest(q, frame, joints):
    """The particles `q` of `frame` whose nearest joint is not one of `joints` (indices)."""
    if not len(q):
        return q
    nearest = np.argmin(np.linalg.norm(q[:, None] - np.asarray(frame.positions)[None], axis=2), axis=1)
    return q[~np.isin(nearest, joints)]


def _gaps(q, r, centre, half):
    """Signed distance (m) from each sphere (centres q, radii r) to an axis-aligned cube; negative: it
    overlaps by that much."""
    d = np.abs(q - centre) - half
    o = np.maximum(d, 0)
    # column by column: the same numbers as norm(o, axis=1) and d.max(axis=1), three times as fast (the
    # placement evaluates it for every grip it tries)
    inside = np.minimum(np.maximum(np.maximum(d[:, 0], d[:, 1]), d[:, 2]), 0)
    return np.sqrt(o[:, 0] * o[:, 0] + o[:, 1] * o[:, 1] + o[:, 2] * o[:, 2]) + inside - r


def _move_out(q, r, centre, out, half, limit=200) -> int:
    """Whole mm (at most `limit`) the cube must move along the unit vector `out` until every sphere (centres q,
    radii r) clears it by CLEAR: the first clear one of 0, 1, 2 ... mm."""
    # only spheres near the cube's path can block it (within its circumradius of the segment it may travel;
    # 1 µm more against rounding)
    rel = q - centre
    perp = rel - np.clip(rel @ out, 0, limit * 1e-3)[:, None] * out
    near = np.einsum("ij,ij->i", perp, perp) < (half * math.sqrt(3) + r + CLEAR + 1e-6) ** 2
    q, r = q[near], r[near]
    moved = 0
    while moved < limit:
        gap = _gaps(q, r, centre + moved * 1e-3 * out, half).min() if len(q) else math.inf
        if gap >= CLEAR:
            return moved
        # a gap changes by at most as much as the cube moves: the next CLEAR - gap of steps are all blocked
        # too, so they are skipped (the answer is that of trying every mm, found in a few tries)
        moved += max(1, math.ceil((CLEAR - gap) * 1000 - 1e-6))
    return limit


def _grip(frame, pinch: bool) -> np.ndarray:
    """Where the hand of `frame` holds a cube: between the thumb and index tips (a pinch) or between the palm
    and the mean of the four fingertips (a grab)."""
    p = np.asarray(frame.positions)
    if pinch:
        return 0.5 * (p[_core.THUMB_TIP] + p[_core.INDEX_TIP])
    return 0.5 * (p[_core.PALM] + p[[_core.INDEX_TIP, _core.MIDDLE_TIP, _core.RING_TIP, _core.LITTLE_TIP]].mean(axis=0))


def free_box_params(motion: Motion, shift: np.ndarray, hand_defs=None, reach: float = REACH) -> (dict, str):
    """The free_box scene parameters for this motion (see the module docstring) and the rule used; `reach`:
    the share of the cube's half extent the closing hand is to reach into it."""
    h = _scenes.FREE_BOX_DEFAULTS["half_extent"]
    closing = closing_hand(motion)
    if closing is not None:
        side = closing[0]
        hand_def = next((d for d in (hand_defs or []) if d.handedness.name.lower() == side),
                        _core.HandDef(handedness=_core.Handedness.RIGHT if side == "right" else _core.Handedness.LEFT))
        centre, h, rule = _cube_for_closing_hand(motion, closing, hand_def, reach)
        centre = centre + shift
        return {"position": [float(centre[0]), float(centre[1] - h), float(centre[2])], "half_extent": h}, rule
    side = next((s for s in HANDS if len(motion.palms(s))), None)
    if side is None:
        return {"position": list(_scenes.FREE_BOX_DEFAULTS["position"])}, "no tracked hand: the default cube"
    palms = motion.palms(side) + shift
    lowest = min(float(np.nanmin(np.asarray(f[side].frame.positions)[np.asarray(f[side].frame.valid), 1]))
                 for f in motion.frames if side in f and f[side].frame.tracked) + shift[1]
    centre = palms.mean(axis=0)
    top = lowest + BRUSH
    return ({"position": [float(centre[0]), float(top - 2 * h), float(centre[2])]},
            f"no closing hand: cube under the {side} hand's mean palm, top {BRUSH * 100:.0f} cm above its lowest joint")


def _cube_for_closing_hand(motion: Motion, closing, hand_def, reach: float = REACH) -> (np.ndarray, float, str):
    """Centre (motion coordinates), half extent and description of the cube the closing hand is to grasp."""
    side, kind, strength = closing
    pinch = kind == "pinch"
    h = PINCH_HALF if pinch else _scenes.FREE_BOX_DEFAULTS["half_extent"]
    where = "between the thumb and index tips" if pinch else "between the palm and the fingertips"
    closures = _closures(strength)
    # The first grip (in time order) that the closing hand reaches REACH deep into wins. The grip of the first
    # half-closed frame may be out of the fist's way, e.g. when the hand rises while it closes (confidence2); a
    # later grip of the same closure lies where the fist went. Not the deepest grip: reach saturates near the
    # cube's centre, so the deepest wins by fractions of a mm, often lies late in a long hold, and finding it
    # takes every grip. The first deep enough grip leaves every placement whose first grip was reached as it
    # was.
    need = reach * h
    tried = []
    for candidate in _grip_candidates(motion, side, pinch, h, closures, hand_def):
        tried.append(candidate)
        if candidate[0] >= need:
            break
    else:
        candidate = max(tried, key=lambda c: c[0])  # none is reached so deep: the deepest, the earliest of equals
    reach, n, k, j, moved, centre = candidate
    rule = f"{kind} of the {side} hand" + (f", closure {n + 1} of {len(closures)}," if len(closures) > 1 else "")
    rule += f" half closed at t={motion.times[k]:.2f} s (frame {k}): {2 * h * 100:.1f} cm cube {where}"
    if j != k:
        rule += f" at t={motion.times[j]:.2f} s (frame {j})"
    if reach < need:
        rule += f" (no grip of the {len(tried)} half-closed frames is reached {need * 1000:.0f} mm deep: the deepest)"
    elif len(tried) > 1:
        rule += (f" (the grips of the {len(tried) - 1} half-closed frames before it are reached less than "
                 f"{need * 1000:.0f} mm deep)")
    if moved > 0:
        rule += f", moved {moved} mm out of the palm to clear the opening hand and the closing palm"
    if math.isfinite(reach):
        rule += f"; the closing hand reaches {round(1000 * reach)} mm into it"
    return centre, h, rule


def _grip_candidates(motion: Motion, side: str, pinch: bool, h: float, closures, hand_def):
    """(reach m, closure index, its first half-closed frame, frame, mm moved, centre) of the cube placed at the
    grip of every frame of every closure while the hand is at least half closed, in time order."""
    not_palm = tuple(i for i in range(_core.JOINT_COUNT) if i not in PALM_JOINTS)
    for n, (k0, k, end) in enumerate(closures):
        # the hand must not touch the cube before it closes: every one of its frames up to k0, the last one it
        # was open before this closure, must clear the cube. A grab: no particle of the simulated hand (posed as
        # the replay will pose it) but the thumb's; a pinch: not the index finger. The thumb is the anvil either
        # closes against: it may rest at the cube.
        before = [fr[side].frame for fr in motion.frames[:k0 + 1] if side in fr]
        q, r = _bone_samples(before, fingers=("index",)) if pinch else _particles(before, hand_def, THUMB_ANVIL)
        closing = [i for i in range(k0 + 1, end) if side in motion.frames[i]]
        frames = [motion.frames[i][side].frame for i in closing]
        # nor may the palm go through the cube on its way to the grip (from k0 to the grip's frame): the fingers
        # close around the cube; a hand that gets to its grip back first (e.g. palm down and rising while it
        # closes) would push the cube away before it
        every, radius = _particles_by_frame(frames, hand_def)
        palm = [_without_nearest(qf, frame, not_palm) for qf, frame in zip(every, frames)]
        # how deep the closing hand (all of it) goes where the cube starts, from k0 until it is less than half
        # closed again: a hand that barely reaches it cannot be expected to grasp it
        qc = np.concatenate(every) if every else np.zeros((0, 3))
        rc = np.full(len(qc), radius)
        for m, j in enumerate(closing):
            if j < k:
                continue
            frame = motion.frames[j][side].frame
            # out of the palm (along its normal, OpenXR's -Y of the palm joint): the way the fingers close, so
            # the closing hand still sweeps through the cube whichever way the palm faces
            out = -_sk.quat_matrix(np.asarray(frame.orientations)[_core.PALM])[:, 1]
            grip = _grip(frame, pinch)
            qp = np.concatenate([q] + palm[:m + 1])
            moved = _move_out(qp, np.r_[r, np.full(len(qp) - len(q), radius)], grip, out, h)
            centre = grip + moved * 1e-3 * out
            reach = -_gaps(qc, rc, centre, h).min() if len(qc) else -math.inf
            yield reach, n, k, j, moved, centre


def step_frames(motion: Motion, dt: float = DT) -> np.ndarray:
    """For every step of a replay at `dt`, the index of the motion frame it takes: the newest at or before the
    step's start."""
    n = int(math.floor(motion.times[-1] / dt + 1e-9)) + 1
    return np.searchsorted(motion.times, np.arange(n) * dt + 1e-12, side="right") - 1


def hand_strength(motion: Motion, side: str, frame: int) -> float:
    """Leap's grab or pinch strength of one hand in one frame, whichever is larger; 0 where it has none."""
    col = HANDS.index(side)
    values = [a[frame, col] for a in (motion.grab, motion.pinch) if a is not None]
    return float(np.nanmax(values)) if values and not np.all(np.isnan(values)) else 0.0


def session_from_motion(motion: Motion, scene: str, dt: float = DT, hand_defs: Sequence = None,
                        world_def=None, reach: float = REACH) -> _rec.Recording:
    """A handsim Recording of `motion` on `scene` (placement and resampling of the module docstring; `reach`
    as for free_box_params)."""
    if hand_defs is None:
        hand_defs = [_core.HandDef(handedness=_core.Handedness.RIGHT), _core.HandDef(handedness=_core.Handedness.LEFT)]
    shift = placement(motion)
    params, rule = {}, "default jewelry box"
    if scene == "free_box":
        params, rule = free_box_params(motion, shift, hand_defs, reach)
    elif scene != "jewelry_box":
        raise ValueError(f"scene: expected 'jewelry_box' or 'free_box' for tracker input, got {scene!r}")
    pose = np.array([*shift, 0, 0, 0, 1.0])
    index = step_frames(motion, dt)
    n = len(index)
    J = _core.JOINT_COUNT
    H = len(hand_defs)
    present = np.ones((n, H), bool)
    positions = np.full((n, H, J, 3), np.nan)
    orientations = np.tile([0.0, 0, 0, 1], (n, H, J, 1))
    radii = np.full((n, H, J), 0.01)
    valid = np.zeros((n, H, J), bool)
    cache = {}
    for i, k in enumerate(index):
        for h, d in enumerate(hand_defs):
            side = "right" if d.handedness == _core.Handedness.RIGHT else "left"
            a = motion.frames[k].get(side)
            if a is None:
                continue
            key = (int(k), side)
            if key not in cache:
                cache[key] = a.frame.transformed(pose)
            f = cache[key]
            positions[i, h], orientations[i, h] = f.positions, f.orientations
            radii[i, h], valid[i, h] = f.radii, f.valid
    synthesized = sorted({n_ for f in motion.frames for a in f.values() for n_ in a.synthesized})
    info = {"source": motion.source, "name": motion.name, "translation": [float(v) for v in shift],
            "placement": rule, "resampled_dt": dt, "synthesized_joints": synthesized, "adapter_notes": motion.notes}
    return _rec.Recording(scene, params, _rec.world_def_to_dict(world_def or _core.WorldDef()),
                          [_rec.hand_def_to_dict(d) for d in hand_defs], np.full(n, dt), present, positions,
                          orientations, radii, valid, [], None, info)


@dataclasses.dataclass
class Summary:
    name: str
    scene: str
    steps: int
    duration_s: float
    grasps: Dict[str, int]          # GRASP_BEGIN per scene object
    drops: int                      # grasps ended by tracking loss
    releases: int                   # grasps ended by opening the hand
    contacts: Dict[str, int]        # CONTACT_BEGIN per scene object
    held_s: Dict[str, float]        # time each object spent grasped
    finite: bool                    # every body pose finite after every step
    max_lid_deg: Optional[float]
    max_hinge_violation_m: Optional[float]
    max_lift_m: Optional[float]     # free box: highest rise of the cube above its start
    max_shift_m: Optional[float]    # free box: largest horizontal displacement of the cube
    hash_matches: Optional[bool]
    final_hash: int
    first_grasp_s: Optional[float] = None  # time of the first GRASP_BEGIN
    # every GRASP_BEGIN as (step index, object, "right" or "left"): who grasped what, and with which input frame
    grasp_log: List[tuple] = dataclasses.field(default_factory=list)


    def _grasps_by_hand(self) -> Dict[str, int]:
        out = {}
        for _, _, hand in self.grasp_log:
            out[hand] = out.get(hand, 0) + 1
        return out

    def lines(self) -> List[str]:
        out = [f"{self.name} on {self.scene}: {self.steps} steps, {self.duration_s:.2f} s",
               f"  grasps: {self.grasps or 'none'}"
               + (f" (first at {self.first_grasp_s:.2f} s)" if self.first_grasp_s is not None else "")
               + "".join(f"; {hand} hand {n}" for hand, n in self._grasps_by_hand().items())
               + f"; held s: { {k: round(v, 2) for k, v in self.held_s.items()} or 'none'}",
               f"  grasp ends: {self.releases} released, {self.drops} dropped (tracking lost)",
               f"  contacts begun: {self.contacts or 'none'}",
               f"  all state finite: {self.finite}"]
        if self.max_lid_deg is not None:
            out.append(f"  lid angle max {self.max_lid_deg:.1f} deg, hinge violation max {self.max_hinge_violation_m:.2e} m")
        if self.max_lift_m is not None:
            out.append(f"  cube lifted max {self.max_lift_m * 100:.1f} cm, moved max {self.max_shift_m * 100:.1f} cm")
        if self.hash_matches is not None:
            out.append(f"  state hashes match the recording: {self.hash_matches}")
        out.append(f"  final state_hash {self.final_hash:#018x}")
        return out


def run(rec: _rec.Recording, name: str = "", picture: Optional[Path] = None, steps: Optional[int] = None,
        motion: Optional[Motion] = None, store: Optional[dict] = None) -> Summary:
    """Replays `rec` (its first `steps` only, if given), collects the summary and (with `picture`) writes the
    PNG. With `store` (a dict), also leaves the timeline ("trace") and the key frames ("snaps") there."""
    names = {}
    trace = {"t": [], "lid": [], "lift": [], "grasped": []}
    snaps = []
    state = {"finite": True, "viol": 0.0, "lid": -1e9, "lift": 0.0, "shift": 0.0, "start": None}
    counts = {"grasps": {}, "contacts": {}, "drops": 0, "releases": 0, "held": {}, "first": None, "log": []}
    n_total = rec.steps if steps is None else min(steps, rec.steps)
    keys = set(np.linspace(0, n_total - 1, 4).round().astype(int).tolist())

    def on_step(i, world, scene):
        if not names:
            names.update({v: k for k, v in scene.objects.items()})
            if "box" in scene.objects:
                state["start"] = np.asarray(world.body_pose(scene["box"]), float)
        for body in world.bodies():
            if not np.isfinite(world.body_pose(body)).all():
                state["finite"] = False
        for e in world.events():
            label = names.get(e.body, "?")
            if e.type == _core.EventType.GRASP_BEGIN:
                counts["grasps"][label] = counts["grasps"].get(label, 0) + 1
                counts["log"].append((i, label, world.hand_model(e.hand).handedness.name.lower()))
                if counts["first"] is None:
                    counts["first"] = world.time
            elif e.type == _core.EventType.CONTACT_BEGIN:
                counts["contacts"][label] = counts["contacts"].get(label, 0) + 1
            elif e.type == _core.EventType.GRASP_END:
                if e.reason == _core.EventReason.TRACKING_LOST:
                    counts["drops"] += 1
                elif e.reason == _core.EventReason.RELEASED:
                    counts["releases"] += 1
        grasped = []
        for label, body in scene.objects.items():
            if isinstance(body, _core.BodyId) and label != "table" and world.body_grasp(body).grasped:
                counts["held"][label] = counts["held"].get(label, 0.0) + float(rec.dt[i])
                grasped.append(label)
        trace["t"].append(world.time)
        trace["grasped"].append(bool(grasped))
        if "hinge" in scene.objects:
            s = world.joint_state(scene["hinge"])
            state["viol"] = max(state["viol"], s.violation)
            state["lid"] = max(state["lid"], math.degrees(s.value))
            trace["lid"].append(math.degrees(s.value))
        if state["start"] is not None:
            p = np.asarray(world.body_pose(scene["box"]), float)
            lift = p[1] - state["start"][1]
            state["lift"] = max(state["lift"], lift)
            state["shift"] = max(state["shift"], float(np.hypot(*(p[[0, 2]] - state["start"][[0, 2]]))))
            trace["lift"].append(100 * lift)
        if (picture is not None or store is not None) and i in keys:
            bodies = {k: v for k, v in scene.objects.items() if isinstance(v, _core.BodyId) and k != "table"}
            snaps.append(_render.snapshot(world, bodies, f"t={world.time:.2f} s" + ("  grasped" if grasped else "")))

    result = _rec.replay(rec, on_step, steps=steps)
    jewelry = rec.scene == "jewelry_box"
    summary = Summary(name, rec.scene, result.steps, float(np.sum(rec.dt[:result.steps])), counts["grasps"],
                      counts["drops"], counts["releases"], counts["contacts"], counts["held"], state["finite"],
                      state["lid"] if jewelry else None, state["viol"] if jewelry else None,
                      state["lift"] if rec.scene == "free_box" else None,
                      state["shift"] if rec.scene == "free_box" else None,
                      None if rec.hashes is None else result.matches, result.final_hash, counts["first"], counts["log"])
    if picture is not None:
        _picture(picture, rec, summary, snaps, trace, motion)
    if store is not None:
        store.update(trace=trace, snaps=snaps)
    return summary


def _picture(path: Path, rec, summary: Summary, snaps, trace, motion: Optional[Motion]):
    plt = _render.pyplot()
    fig = plt.figure(figsize=(12, 5.6))
    grid = fig.add_gridspec(2, 4, height_ratios=[1.25, 1])
    if rec.scene == "jewelry_box":
        centre, axes, view = _default_lid_front() + [0, 0.04, -0.05], (2, 1), "side view, user at the right"
    else:
        centre = np.asarray(rec.scene_params["position"], float) + [0, 0.05, 0]
        axes, view = (0, 1), "front view"
    for k, snap in enumerate(snaps[:4]):
        _render.draw(fig.add_subplot(grid[0, k]), snap, centre, half_width=0.16, axes=axes)
    ax = fig.add_subplot(grid[1, :])
    t = np.asarray(trace["t"])
    if rec.scene == "jewelry_box":
        ax.plot(t, trace["lid"], color="darkgoldenrod", label="lid angle (deg)")
    else:
        ax.plot(t, trace["lift"], color="tab:green", label="cube lift (cm)")
    g = np.asarray(trace["grasped"], bool)
    if g.any():
        ax.fill_between(t, 0, 1, where=g, transform=ax.get_xaxis_transform(), color="0.8", label="grasped")
    if motion is not None and motion.grab is not None:
        ax2 = ax.twinx()
        for col, side, colour in ((0, "right", "tab:blue"), (1, "left", "tab:red")):
            if not np.all(np.isnan(motion.grab[:, col])):
                ax2.plot(motion.times + t[0], motion.grab[:, col], ":", color=colour, lw=1, label=f"Leap grab {side}")
                ax2.plot(motion.times + t[0], motion.pinch[:, col], "--", color=colour, lw=0.8, label=f"Leap pinch {side}")
        ax2.set_ylim(-0.05, 1.05)
        ax2.set_ylabel("Leap strength")
        ax2.legend(fontsize=7, loc="upper right")
    ax.set_xlabel("time (s)")
    ax.legend(fontsize=7, loc="upper left")
    fig.suptitle(f"{summary.name} on {rec.scene} ({view}; blue right hand, red left): grasps {summary.grasps or 'none'}",
                 fontsize=10)
    save_figure(fig, path, dpi=80)


def load_motion(path: Path) -> Motion:
    suffixes = "".join(path.suffixes[-2:]).lower()
    if suffixes.endswith(".json.lz") or path.suffix.lower() == ".json":
        from .adapters.leap import load_leap_recording
        return motion_from_leap(load_leap_recording(path))
    if path.suffix.lower() == ".bvh":
        from .adapters.bvh import load_bvh_motion
        return load_bvh_motion(path)
    raise ValueError(f"path: expected .npz, .json.lz, .json or .bvh, got {path.name!r}")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m handsim.replay", description=__doc__.split("\n\n")[0])
    ap.add_argument("files", nargs="+", type=Path, help="recordings: .npz (handsim), .json.lz/.json (Leap), .bvh")
    ap.add_argument("--scene", choices=("jewelry_box", "free_box"), action="append",
                    help="scene(s) for tracker input (default: jewelry_box); repeat for several")
    ap.add_argument("--out", type=Path, default=Path("out/replay"), help="output folder (default out/replay)")
    ap.add_argument("--save", action="store_true", help="also save each tracker input as a handsim recording")
    ap.add_argument("--json", action="store_true", help="print the summaries as one JSON document")
    args = ap.parse_args(argv)
    scenes = args.scene or ["jewelry_box"]
    docs = []
    for path in args.files:
        if not path.is_file():
            print(f"error: path: no such file: {path}", file=sys.stderr)
            return 2
        base = path.name.split(".")[0]
        if path.suffix.lower() == ".npz":
            rec = _rec.load(path)
            runs = [(rec, rec.scene, None)]
        else:
            motion = load_motion(path)
            runs = [(session_from_motion(motion, s), s, motion) for s in scenes]
        lines = []
        for rec, scene, motion in runs:
            summary = run(rec, base, args.out / f"{base}_{scene}.png", motion=motion)
            if args.save and motion is not None:
                rec.save(args.out / f"{base}_{scene}.npz")
            lines += summary.lines()
            if rec.info.get("placement"):
                lines.append(f"  placement: {rec.info['placement']}; translation "
                             f"{np.round(rec.info['translation'], 4).tolist()} m")
                lines.append(f"  input: {rec.info['source']}" + "".join(
                    f"; {case}: {n}" for case, n in sorted(rec.info.get("adapter_notes", {}).items())))
            docs.append({**dataclasses.asdict(summary), "placement": rec.info.get("placement"),
                         "source": rec.info.get("source"), "adapter_notes": rec.info.get("adapter_notes"),
                         "synthesized_joints": rec.info.get("synthesized_joints")})
        (args.out / f"{base}.txt").write_text("\n".join(lines) + "\n")
        if not args.json:
            print("\n".join(lines))
    if args.json:
        print(json.dumps(docs, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
