"""The OpenXR hand skeleton built from joint positions: what every position-only adapter (MediaPipe, Leap, BVH)
and the glTF loader share, so that all of them orient and fill joints the same way.

* :func:`orientations` gives each joint an OpenXR frame from the positions alone (-Z along the bone towards
  the fingertip, +Y out of the back of the hand): palm and wrist -Z from the wrist towards the middle proximal
  joint and X across the knuckles (index to little on a right hand); finger bones -Z towards the next joint
  and X the palm's X made orthogonal (the flexion axis); thumb bones -Z towards the next joint, +Y of the
  metacarpal halfway between the back of the hand and the thumb's side and +Y of each further thumb bone its
  parent's +Y made orthogonal; a tip takes its distal joint's frame.
* :func:`fill_missing` places the joints a tracker does not give: a finger metacarpal 15 % of the way from
  the wrist to its proximal joint, the palm at the middle of the middle metacarpal bone (the OpenXR
  definition), the wrist (when only the metacarpal bases are known) by the inverse of the 15 % rule.
* :func:`adapted_frame` turns positions, a mask of the joints the source gave and a mask of the valid ones into
  an :class:`AdaptedFrame`: the HandFrame plus the names of the synthesized and of the invalid joints. A joint
  whose frame needs an invalid joint (or a bone of zero length) is invalid itself; invalid joints hold NaN
  positions and the identity orientation.
"""
from __future__ import annotations

import dataclasses
import math
from typing import Optional, Sequence, Tuple

import numpy as np

from .. import _core
from ..quat import matrix_quat, quat_matrix  # noqa: F401 (adapters use them from here)

JOINT = {name: i for i, name in enumerate(_core.JOINT_NAMES)}
FINGERS = ("index", "middle", "ring", "little")
METACARPAL_FRACTION = 0.15  # a finger metacarpal joint lies this far from the wrist towards the proximal joint


@dataclasses.dataclass(frozen=True)
class AdaptedFrame:
    """One hand frame from a tracker, with what the adapter had to make up.

    ``synthesized``: names of joints the source did not give (placed by the rules of this module);
    ``invalid``: names of joints flagged invalid (missing or unusable in the source)."""
    frame: _core.HandFrame
    synthesized: Tuple[str, ...] = ()
    invalid: Tuple[str, ...] = ()


def chain(finger: str):
    """OpenXR joint indices of a finger from its first joint (metacarpal) to its tip."""
    first = JOINT[finger + "_metacarpal"]
    return list(range(first, JOINT[finger + "_tip"] + 1))


def cross(a, b):
    """a x b of two 3-vectors (plain arithmetic: numpy's cross costs microseconds per call)."""
    a0, a1, a2 = float(a[0]), float(a[1]), float(a[2])
    b0, b1, b2 = float(b[0]), float(b[1]), float(b[2])
    return np.array([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0])


def unit(v, what):
    """v / |v|, or ValueError "cannot orient <what>" when v is (nearly) zero: two joints coincide."""
    n = math.sqrt(float(v[0]) ** 2 + float(v[1]) ** 2 + float(v[2]) ** 2)
    if not n > 1e-9:
        raise ValueError(f"cannot orient {what}: its joints coincide")
    return v / n


def orientation(z, x_hint=None, y_hint=None):
    """OpenXR frame with +Z along z and X (or Y) as close as possible to the hint."""
    z = unit(z, "a bone")
    if x_hint is not None:
        x = unit(x_hint - x_hint.dot(z) * z, "a bone (parallel to its flexion axis)")
        y = cross(z, x)
    else:
        y = unit(y_hint - y_hint.dot(z) * z, "a bone (parallel to its back direction)")
        x = cross(y, z)
    return matrix_quat(np.array([x, y, z]).T)


def palm_orientation(pos, handedness):
    """The OpenXR palm orientation (x, y, z, w) of joint positions pos (26, 3): -Z from the wrist towards
    the middle knuckle, X across the knuckles towards the little finger of a right hand (mirrored for left)."""
    along = pos[_core.MIDDLE_PROXIMAL] - pos[_core.WRIST]
    across = pos[_core.LITTLE_PROXIMAL] - pos[_core.INDEX_PROXIMAL]
    if handedness == _core.Handedness.LEFT:
        across = -across
    return orientation(-along, x_hint=across)


def orientations(pos, handedness, ok=None):
    """(26, 4) OpenXR orientations from (26, 3) positions (see the module docstring). With `ok` (26,) bool,
    joints whose frame cannot be built (it needs a joint that is not ok, or a bone has zero length) get NaN
    and the others are still built; without it such a joint raises ValueError."""
    pos = np.asarray(pos, float)
    strict = ok is None
    ok = np.ones(_core.JOINT_COUNT, bool) if ok is None else np.asarray(ok, bool)
    quats = np.full((_core.JOINT_COUNT, 4), np.nan)

    def attempt(j, needs, build):
        if not all(ok[k] for k in needs):
            return
        try:
            quats[j] = build()
        except ValueError:
            if strict:
                raise

    palm_needs = (_core.WRIST, _core.MIDDLE_PROXIMAL, _core.INDEX_PROXIMAL, _core.LITTLE_PROXIMAL)
    attempt(_core.PALM, palm_needs + (_core.PALM,), lambda: palm_orientation(pos, handedness))
    attempt(_core.WRIST, palm_needs, lambda: palm_orientation(pos, handedness))
    if np.isnan(quats[_core.WRIST]).any():
        return quats  # every finger frame is built relative to the palm's axes
    palm = quat_matrix(quats[_core.WRIST])
    thumb_side = -palm[:, 0] if handedness == _core.Handedness.RIGHT else palm[:, 0]
    nail = palm[:, 1] + thumb_side
    for f in ("thumb",) + FINGERS:
        joints = chain(f)
        for j in joints[:-1]:
            bone = pos[j] - pos[j + 1]
            if f == "thumb":
                # the metacarpal's back is the nail direction; each further bone takes its parent's back, so
                # the roll stays continuous along a curled thumb
                hint = nail if j == joints[0] or np.isnan(quats[j - 1]).any() else quat_matrix(quats[j - 1])[:, 1]
                attempt(j, (j, j + 1), lambda: orientation(bone, y_hint=hint))
            else:
                attempt(j, (j, j + 1), lambda: orientation(bone, x_hint=palm[:, 0]))
        tip = joints[-1]
        if ok[tip] and not np.isnan(quats[tip - 1]).any():
            quats[tip] = quats[tip - 1]
    return quats


def fill_missing(pos, have):
    """Places the finger metacarpals (15 % rule) and the palm (middle of the middle metacarpal bone) where
    `have` is False; returns the names filled. `pos` is changed in place."""
    filled = []
    for f in FINGERS:
        meta, prox = JOINT[f + "_metacarpal"], JOINT[f + "_proximal"]
        if not have[meta]:
            pos[meta] = pos[_core.WRIST] + METACARPAL_FRACTION * (pos[prox] - pos[_core.WRIST])
            filled.append(f + "_metacarpal")
    if not have[_core.PALM]:
        pos[_core.PALM] = 0.5 * (pos[_core.MIDDLE_METACARPAL] + pos[_core.MIDDLE_PROXIMAL])
        filled.append("palm")
    return filled


def wrist_from_metacarpal(metacarpal, proximal):
    """The wrist that the 15 % rule would have put `metacarpal` 15 % of the way from, towards `proximal`."""
    return (metacarpal - METACARPAL_FRACTION * proximal) / (1 - METACARPAL_FRACTION)


_BIND_RADII = None
_BIND_PALM_LENGTH = None


def scaled_radii(pos):
    """Joint radii of handsim's adult hand (make_hand_frame) scaled by this hand's size (wrist to middle
    proximal joint): for trackers that give no radii."""
    global _BIND_RADII, _BIND_PALM_LENGTH
    if _BIND_RADII is None:
        bind = _core.bind_frame(_core.Handedness.RIGHT)
        _BIND_RADII = np.asarray(bind.radii, float)
        bp = np.asarray(bind.positions)
        _BIND_PALM_LENGTH = float(np.linalg.norm(bp[_core.MIDDLE_PROXIMAL] - bp[_core.WRIST]))
    length = float(np.linalg.norm(pos[_core.MIDDLE_PROXIMAL] - pos[_core.WRIST]))
    scale = length / _BIND_PALM_LENGTH if np.isfinite(length) and length > 1e-6 else 1.0
    return _BIND_RADII * scale


def adapted_frame(handedness, pos, given, valid=None, radii=None, synthesized: Sequence[str] = ()):
    """An AdaptedFrame from (26, 3) positions in metres. `given` (26,) bool: joints the source gave (the
    others are filled by :func:`fill_missing`); `valid` (26,) bool: source joints that are usable (default:
    the given ones with finite positions). Joints computed from invalid ones are invalid."""
    pos = np.array(pos, float)
    given = np.asarray(given, bool)
    valid = given.copy() if valid is None else np.asarray(valid, bool) & given
    valid &= np.isfinite(pos).all(axis=1)
    have = given & valid
    synthesized = list(synthesized)
    filled = fill_missing(pos, have)
    synthesized += [n for n in filled if n not in synthesized]
    ok = valid.copy()
    for f in FINGERS:  # a filled metacarpal needs the wrist and its proximal joint
        meta, prox = JOINT[f + "_metacarpal"], JOINT[f + "_proximal"]
        if not have[meta]:
            ok[meta] = valid[_core.WRIST] and valid[prox]
    if not have[_core.PALM]:
        ok[_core.PALM] = ok[_core.MIDDLE_METACARPAL] and valid[_core.MIDDLE_PROXIMAL]
    quats = orientations(pos, handedness, ok)
    ok &= ~np.isnan(quats).any(axis=1)
    if radii is None:
        radii = scaled_radii(pos) if ok[_core.WRIST] and ok[_core.MIDDLE_PROXIMAL] else scaled_radii(
            np.zeros((_core.JOINT_COUNT, 3)))
    pos[~ok] = np.nan
    quats[~ok] = (0.0, 0.0, 0.0, 1.0)
    frame = _core.HandFrame(handedness, pos, quats, np.asarray(radii, float), ok)
    names = _core.JOINT_NAMES
    return AdaptedFrame(frame, tuple(n for n in names if n in synthesized),
                        tuple(names[j] for j in range(_core.JOINT_COUNT) if not ok[j]))


def untracked(handedness):
    """A frame with every joint invalid (the hand is not seen)."""
    q = np.zeros((_core.JOINT_COUNT, 4))
    q[:, 3] = 1
    return _core.HandFrame(handedness, np.full((_core.JOINT_COUNT, 3), np.nan), q,
                           np.full(_core.JOINT_COUNT, 0.01), np.zeros(_core.JOINT_COUNT, bool))


def joint_angles(frame) -> np.ndarray:
    """(26,) flexion angle (rad) of each joint: the angle between its bone and its parent's bone (metacarpals
    relative to the wrist's -Z, palm and wrist 0); NaN where a joint or its parent is invalid. Used to compare
    skeletons from different trackers (tests, replay summaries)."""
    q = np.asarray(frame.orientations, float)
    v = np.asarray(frame.valid, bool)
    out = np.zeros(_core.JOINT_COUNT)
    for f in ("thumb",) + FINGERS:
        joints = chain(f)
        for j in joints[:-1]:
            parent = _core.WRIST if j == joints[0] else j - 1
            if not (v[j] and v[parent]):
                out[j] = np.nan
                continue
            a, b = quat_matrix(q[j])[:, 2], quat_matrix(q[parent])[:, 2]
            out[j] = np.arccos(np.clip(a @ b, -1, 1))
        out[joints[-1]] = 0.0 if v[joints[-1]] else np.nan
    return out


# Closure strengths from the skeleton, for trackers that give none (BVH, Leap before 2.0), with the meaning Leap
# documents for its own (Ultraleap's LEAP_HAND and Hand.GrabAngle): grab is 0 for an open hand and 1 for all four
# fingers (not the thumb) curled into a fist, measured by the grab angle, the mean angle between each finger's
# direction and the hand's (0 open, pi a tight fist); pinch is 0 for an open hand and 1 when the thumb pinches
# any other finger. Nothing here is fitted to a recording: the anchors are handsim's own hand (make_hand_frame)
# and the fingers' pulps; `python -m handsim.input_report` prints how often the result agrees with Leap's labels.
# grab = grab angle / that of make_hand_frame's fist (165 deg: its fingers point back at the wrist);
# pinch = 1 - pulp gap / that of make_hand_frame's flat hand between the thumb and the index (56.8 mm), where
# the pulp gap is the smallest distance between the surfaces of the thumb's distal phalanx and a finger's (the
# capsules of the joint radii: the pulps touch at 0, pinch 1) and is scaled to the adult hand by the hand's size.
_GRAB_FINGERS = [(JOINT[f + "_intermediate"], JOINT[f + "_distal"]) for f in FINGERS]  # Leap's finger direction
_PULPS = [(JOINT[f + "_distal"], JOINT[f + "_tip"]) for f in FINGERS]
_ANCHORS = None  # (fist grab angle rad, flat hand thumb-index pulp gap m, adult hand size m)


def _hand_size(p) -> float:
    """Wrist to middle knuckle: what scales a hand (make_hand_frame's adult hand: 9 cm)."""
    return float(np.linalg.norm(p[_core.MIDDLE_PROXIMAL] - p[_core.WRIST]))


def _grab_angle(p, q) -> float:
    """Mean angle (rad) between the index..little fingers' direction (intermediate bone) and the hand's (the
    palm joint's -Z), as Leap defines its grab angle; NaN when a bone has no length."""
    hand = -quat_matrix(q[_core.PALM])[:, 2]
    bones = [p[b] - p[a] for a, b in _GRAB_FINGERS]
    lengths = [float(np.linalg.norm(u)) for u in bones]
    if not min(lengths) > 1e-9:
        return math.nan
    return float(np.mean([math.acos(max(-1.0, min(1.0, float(u @ hand) / n))) for u, n in zip(bones, lengths)]))


def pulp_gap(p, r, finger: int) -> float:
    """Distance (m) between the surfaces of the thumb's distal phalanx and finger `finger`'s (0 index .. 3
    little): capsules round the distal -> tip bones with the joint radii, linear along the bone; < 0 pressed.
    The core's capsule_gap, the one the grip span's thumb term uses."""
    j0, j1 = _PULPS[finger]
    return _core.capsule_gap(p[_core.THUMB_DISTAL], p[_core.THUMB_TIP], r[_core.THUMB_DISTAL], r[_core.THUMB_TIP],
                             p[j0], p[j1], r[j0], r[j1])


def _anchors():
    global _ANCHORS
    if _ANCHORS is None:
        fist = _core.make_hand_frame(_core.Handedness.RIGHT, curl=1.0)
        flat = _core.make_hand_frame(_core.Handedness.RIGHT)
        fp, fr = np.asarray(flat.positions), np.asarray(flat.radii)
        _ANCHORS = (_grab_angle(np.asarray(fist.positions), np.asarray(fist.orientations)), pulp_gap(fp, fr, 0),
                    _hand_size(fp))
    return _ANCHORS


def closure_measures(frame) -> Tuple[float, float]:
    """(grab angle share, pulp gap m) of a hand frame: the grab angle as a share of make_hand_frame's fist's,
    and the smallest pulp gap between the thumb and a finger, scaled to the adult hand; NaN where the joints
    are invalid."""
    fist_angle, _, adult = _anchors()
    p, q, r, v = (np.asarray(a) for a in (frame.positions, frame.orientations, frame.radii, frame.valid))
    grab_joints = [_core.PALM] + [j for bone in _GRAB_FINGERS for j in bone]
    share = _grab_angle(p, q) / fist_angle if v[grab_joints].all() else math.nan
    pinch_joints = [_core.WRIST, _core.MIDDLE_PROXIMAL, _core.THUMB_DISTAL, _core.THUMB_TIP]
    gaps = [pulp_gap(p, r, k) for k, bone in enumerate(_PULPS) if v[list(bone)].all()]
    gap = min(gaps) * adult / _hand_size(p) if gaps and v[pinch_joints].all() else math.nan
    return share, gap


def closure_strengths(frame) -> Tuple[float, float]:
    """(grab, pinch) in 0..1 of a hand frame in the meaning Leap documents for grabStrength and pinchStrength
    (see closure_measures and the note above it); NaN for an untracked frame or one without those joints."""
    share, gap = closure_measures(frame)
    flat_gap = _anchors()[1]
    grab = float(np.clip(share, 0, 1)) if np.isfinite(share) else math.nan
    pinch = float(np.clip(1 - gap / flat_gap, 0, 1)) if np.isfinite(gap) else math.nan
    return grab, pinch
