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


# Closure strengths from the skeleton, for trackers that give none (BVH, Leap before 2.0), calibrated on the
# development Leap recordings against Leap's own strengths (`python -m handsim.input_report` prints the
# calibration and the agreement): Leap's open and closed hands, and its pinching and open thumb-index gaps,
# fall on either side of these ranges.
GRAB_FLEXION = (0.32, 0.45)   # closure_measures' flexion share mapped to grab 0 .. 1
PINCH_GAP_M = (0.055, 0.025)  # thumb-index tip distance mapped to pinch 0 .. 1
_FLEXING = [JOINT[f + "_" + b] for f in FINGERS for b in ("proximal", "intermediate", "distal")]
_FIST_FLEXION = None


def closure_measures(frame) -> Tuple[float, float]:
    """(flexion share, thumb-index gap m) of a hand frame: the mean flexion of the index..little finger joints
    as a share of make_hand_frame's fist's, and the distance between the thumb and index tips; NaN where the
    joints are invalid."""
    global _FIST_FLEXION
    if _FIST_FLEXION is None:
        _FIST_FLEXION = float(np.mean(joint_angles(_core.make_hand_frame(_core.Handedness.RIGHT, curl=1.0))[_FLEXING]))
    flexion = float(np.mean(joint_angles(frame)[_FLEXING])) / _FIST_FLEXION
    p, v = np.asarray(frame.positions), np.asarray(frame.valid)
    gap = float(np.linalg.norm(p[_core.THUMB_TIP] - p[_core.INDEX_TIP])) if v[_core.THUMB_TIP] and v[_core.INDEX_TIP] \
        else math.nan
    return flexion, gap


def closure_strengths(frame) -> Tuple[float, float]:
    """(grab, pinch) in 0..1 of a hand frame, as Leap's grabStrength and pinchStrength would roughly say
    (see GRAB_FLEXION, PINCH_GAP_M); NaN for an untracked frame or one without those joints."""
    flexion, gap = closure_measures(frame)
    lo, hi = GRAB_FLEXION
    far, near = PINCH_GAP_M
    grab = float(np.clip((flexion - lo) / (hi - lo), 0, 1)) if np.isfinite(flexion) else math.nan
    pinch = float(np.clip((far - gap) / (far - near), 0, 1)) if np.isfinite(gap) else math.nan
    return grab, pinch
