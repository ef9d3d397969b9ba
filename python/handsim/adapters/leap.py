"""Leap Motion recordings (leapjs-playback ``.json.lz`` / ``.json``) as OpenXR hand frames.

A recording is LZ-String ``compressToBase64`` text of a JSON document ``{"metadata", "frames"}``
(formatVersion 0.1 or 1: every frame a Leap WebSocket v6 frame object; formatVersion 2: packed, ``frames[0]``
lists the keys and every later frame is a positional array). See ``docs/input.md``.

Mapping of one Leap hand (millimetres, Leap device frame: right-handed, +Y up, +Z towards the user) to the
26 OpenXR joints (metres; the device frame's axes are kept, so a Leap on the desk in front of the user gives
a Y-up scene with the user at +Z, as in handsim):

* fingers: ``carpPosition`` -> METACARPAL, ``mcpPosition`` -> PROXIMAL, ``pipPosition`` -> INTERMEDIATE,
  ``dipPosition`` -> DISTAL, ``btipPosition`` -> TIP;
* thumb (Leap gives it a zero-length metacarpal, so its mcp/pip/dip are the CMC, MCP and IP joints):
  ``mcpPosition`` -> THUMB_METACARPAL, ``pipPosition`` -> THUMB_PROXIMAL, ``dipPosition`` -> THUMB_DISTAL,
  ``btipPosition`` -> THUMB_TIP;
* PALM: the middle of the middle metacarpal bone (the OpenXR definition), not Leap's ``palmPosition``
  (13 mm away from it in the version 2 recording);
* WRIST: no recording has wrist or arm fields; it is put where handsim's 15 % metacarpal rule
  (:mod:`handsim.adapters.skeleton`) would have placed the middle metacarpal base from it.

Older frames (formatVersion 0.1/1) lack ``carpPosition`` and ``btipPosition``. They are rebuilt with Leap's
own hand model, whose proportions are fixed (measured on the formatVersion 2 recording, constant in every
frame): the fingertip end lies 1.2987 times as far from the dip joint as ``tipPosition``; each finger's
metacarpal bone is rigid in the palm frame (``METACARPALS``: its length in middle proximal bones and its
direction in (``direction``, ``palmNormal``, ``direction`` x ``palmNormal``), the last mirrored for a left
hand), so its base is the mcp joint less that bone. Leap scales its model as a whole by the middle proximal
bone (:func:`model_scale`). Those joints are reported as synthesized.
Joint orientations are built from the positions (:func:`handsim.adapters.skeleton.orientations`).

What a real recording may lack is not an error (``LeapRecording.notes`` counts each case):

* a hand without ``type`` (Leap SDKs before 2.0 did not tell left from right) takes the side its thumb is on
  when the thumb is typed and has a skeleton (a right thumb lies on +(``direction`` x ``palmNormal``)), else
  the side whose synthetic hand (below) its untyped fingers fit better in most frames of its hand id (hand
  ids persist while a hand is tracked), else the side its id had earlier in the recording, else the side of
  the device it is on (x < 0: left); two hands of a frame never get the same side;
* a hand whose five fingers do not all have ``mcp/pip/dip`` (no skeleton, or fingers Leap lost) is rebuilt
  from its palm: handsim's synthetic hand (:func:`handsim.make_hand_frame`) with its palm joint where Leap's
  palm puts OpenXR's (``palmPosition`` + the measured offset), each finger Leap reports curled as far as the
  angle of its ``direction`` from the flat hand's says (the thumb also swung across the palm as far as its
  direction says), and each finger it does not report curled by its grab strength, or without one as far as
  the other fingers it reports (fully when it reports none: Leap drops the fingers it cannot see). Untyped
  pointables go to the fingers by the least total distance between their tips and the synthetic hand's,
  each finger curled as its pointable's direction says. Every joint of such a hand is synthesized;
* a hand without ``palmPosition``, ``direction`` or ``palmNormal`` that cannot use its skeleton is untracked in
  that frame; tools and pointables of no listed hand are ignored; a frame whose timestamp goes back is
  dropped; a second hand of a side keeps the first one the tracker listed.
"""
from __future__ import annotations

import collections
import dataclasses
import itertools
import json
import math
from pathlib import Path
from typing import Dict, List, Optional

import numpy as np

from .. import _core
from . import skeleton
from .lzstring import decompress_from_base64

MM = 0.001
TIP_EXTENSION = 1.2987
# Leap's metacarpal bones (carp -> mcp joint), rigid in its palm frame and scaled with the hand (measure_hand_model,
# model_scale): per finger, the length in middle proximal bones (mcp -> pip) and the unit direction in
# (direction, palmNormal, direction x palmNormal) of a right hand (the last component mirrored for a left one)
METACARPALS = {"index": (1.5263, (0.9749, 0.1483, 0.1660)), "middle": (1.4475, (0.9885, 0.1483, 0.0295)),
               "ring": (1.2996, (0.9815, 0.1483, -0.1213)), "little": (1.2030, (0.9600, 0.1059, -0.2593))}
PALM_OFFSET_MM = (-9.0783, -9.1987, 1.9203)  # OpenXR palm - Leap palmPosition, same axes, right hand
LIMIT_MM = 1e6  # 1 km: far beyond any tracker, near enough that squares and products stay finite
MATCH_MM = 80.0  # an untyped pointable further than this from every flat fingertip is not matched
SUPPORTED_FORMATS = (0.1, 1, 2)
_J = skeleton.JOINT
_LEAP_FINGERS = ("thumb", "index", "middle", "ring", "little")


@dataclasses.dataclass
class LeapRecording:
    """A Leap recording converted to OpenXR hand frames.

    ``times`` (N,) s from the first frame; ``frames[i]`` maps ``"right"``/``"left"`` to the AdaptedFrame of
    that hand (absent: not seen in frame i); ``grab`` / ``pinch`` / ``confidence`` (N, 2) Leap's own
    strengths of the [right, left] hand (NaN when absent or not recorded)."""
    name: str
    metadata: dict
    times: np.ndarray
    frames: List[Dict[str, skeleton.AdaptedFrame]]
    grab: np.ndarray
    pinch: np.ndarray
    confidence: np.ndarray
    # what the recording lacked and how it was made up: {case: number of hands (or frames) it applied to}
    notes: Dict[str, int] = dataclasses.field(default_factory=dict)

    @property
    def format_version(self):
        return self.metadata.get("formatVersion")

    def hand_counts(self):
        """{number of hands: frames}."""
        out: Dict[int, int] = {}
        for f in self.frames:
            out[len(f)] = out.get(len(f), 0) + 1
        return out


def _vec(obj, key, where):
    """obj[key] as a (3,) array; None when absent or null. Anything but 3 finite numbers within LIMIT_MM
    (a Leap sees about half a metre) is an error naming the field."""
    v = obj.get(key)
    if v is None:
        return None
    try:
        a = np.asarray(v, float)
    except (TypeError, ValueError):
        a = None
    if a is None or a.shape != (3,) or not np.isfinite(a).all() or np.abs(a).max() > LIMIT_MM:
        raise ValueError(f"{where}.{key}: expected 3 finite numbers within ±{LIMIT_MM:g}, got {v!r}")
    return a


def _finite_number(v) -> Optional[float]:
    """v as a float when it is a finite JSON number (not a bool), else None."""
    return float(v) if isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) else None


def _palm_axes(hand: dict, where: str):
    """Unit (direction, palmNormal, direction x palmNormal) of a Leap hand, the normal made orthogonal to the
    direction; None when either is missing or degenerate."""
    d, n = _vec(hand, "direction", where), _vec(hand, "palmNormal", where)
    if d is None or n is None or np.linalg.norm(d) < 1e-6:
        return None
    d = d / np.linalg.norm(d)
    n = n - (n @ d) * d
    if np.linalg.norm(n) < 1e-6:
        return None
    n = n / np.linalg.norm(n)
    return d, n, np.cross(d, n)


def _typed_fingers(pointables) -> Dict[int, dict]:
    """{finger type 0..4: pointable} of the pointables that say their type (the first of each type)."""
    out = {}
    for p in pointables:
        t = _finite_number(p.get("type"))
        if t is not None and t in (0, 1, 2, 3, 4) and int(t) not in out:
            out[int(t)] = p
    return out


def thumb_side(hand: dict, pointables, where: str = "hand") -> Optional[str]:
    """"right" or "left" from where the thumb is (a right thumb lies on +(direction x palmNormal) of the palm:
    it tells the type of every hand of every development recording, test_input checks); None without a typed
    thumb with a pipPosition and the palm's axes."""
    thumb = _typed_fingers(pointables).get(0)
    axes, palm = _palm_axes(hand, where), _vec(hand, "palmPosition", where)
    pip = None if thumb is None else _vec(thumb, "pipPosition", f"{where}.pointables[type 0]")
    if axes is None or palm is None or pip is None:
        return None
    return "right" if (pip - palm) @ axes[2] > 0 else "left"


_SKELETON_KEYS = ("mcpPosition", "pipPosition", "dipPosition")


def leap_hand_frame(hand: dict, pointables, where: str = "hand", side: Optional[str] = None):
    """One Leap hand (a frame's ``hands[i]`` object) and its pointables (a list, or a dict of them by finger
    type) as (AdaptedFrame in metres, "skeleton" or "palm"), or (None, reason) when the hand cannot be placed.
    `side` ("right"/"left") overrides the hand's ``type``; without either the thumb tells it."""
    pointables = list(pointables.values()) if isinstance(pointables, dict) else list(pointables)
    kind = side or hand.get("type")
    if kind is None:
        kind = thumb_side(hand, pointables, where)
        if kind is None:
            return None, "untracked: no side (no type, no typed thumb)"
    if kind not in ("left", "right"):
        raise ValueError(f"{where}.type: expected 'left' or 'right', got {kind!r}")
    handedness = _core.Handedness.RIGHT if kind == "right" else _core.Handedness.LEFT
    fingers = _typed_fingers(pointables)
    if len(fingers) == 5 and all(fingers[t].get(k) is not None for t in range(5) for k in _SKELETON_KEYS):
        return _skeleton_frame(hand, fingers, handedness, where), "skeleton"
    frame = _palm_frame(hand, pointables, fingers, handedness, where)
    return (frame, "palm") if frame is not None else (None, "untracked: no palm pose")


def _skeleton_frame(hand: dict, fingers: Dict[int, dict], handedness, where: str) -> skeleton.AdaptedFrame:
    """The hand from Leap's bone joints (every finger has mcp/pip/dip)."""
    pos = np.full((_core.JOINT_COUNT, 3), np.nan)
    given = np.zeros(_core.JOINT_COUNT, bool)
    synthesized = []
    for t, name in enumerate(_LEAP_FINGERS):
        p = fingers[t]
        w = f"{where}.pointables[type {t}]"
        mcp, pip, dip = (_vec(p, k, w) for k in _SKELETON_KEYS)
        tip = _vec(p, "btipPosition", w)
        if tip is None:
            short = _vec(p, "tipPosition", w)
            if short is None:
                raise ValueError(f"{w}: neither btipPosition nor tipPosition")
            tip = dip + TIP_EXTENSION * (short - dip)
            synthesized.append(f"{name}_tip")
        chain = skeleton.chain(name)
        if name == "thumb":
            points = (mcp, pip, dip, tip)
        else:
            carp = _vec(p, "carpPosition", w)
            points = (carp, mcp, pip, dip, tip)
        for j, point in zip(chain, points):
            if point is not None:
                pos[j] = point * MM
                given[j] = True
    synthesized += _rebuild_metacarpals(hand, pos, given, handedness, where)
    # the wrist, from the middle metacarpal base
    pos[_core.WRIST] = skeleton.wrist_from_metacarpal(pos[_J["middle_metacarpal"]], pos[_J["middle_proximal"]])
    given[_core.WRIST] = True
    synthesized = ["wrist"] + synthesized
    return skeleton.adapted_frame(handedness, pos, given, synthesized=synthesized)


def _rebuild_metacarpals(hand: dict, pos: np.ndarray, given: np.ndarray, handedness, where: str) -> List[str]:
    """Places the finger metacarpal bases a frame lacks (no carpPosition) where Leap's own hand model has them:
    the finger's mcp joint less its METACARPALS bone, scaled by the hand's middle proximal bone (Leap scales its
    whole model alike: model_scale). `pos` (26, 3) m and `given` are changed in place; returns the names."""
    missing = [f for f in METACARPALS if not given[_J[f + "_metacarpal"]]]
    if not missing:
        return []
    d, n = _vec(hand, "direction", where), _vec(hand, "palmNormal", where)
    if d is None or n is None:
        raise ValueError(f"{where}: direction and palmNormal are needed without carpPosition")
    # Leap's left hand is the mirror of its right (model_scale: its knuckles are)
    c = np.cross(d, n) if handedness == _core.Handedness.RIGHT else -np.cross(d, n)
    scale = np.linalg.norm(pos[_J["middle_intermediate"]] - pos[_J["middle_proximal"]])
    for f in missing:
        length, (a, b, e) = METACARPALS[f]
        axis = a * d + b * n + e * c
        j = _J[f + "_metacarpal"]
        pos[j] = pos[_J[f + "_proximal"]] - length * scale * axis / np.linalg.norm(axis)
        given[j] = True
    return [f + "_metacarpal" for f in missing]


# Leap's finger `direction` is that of the intermediate bone (pip -> dip): for the thumb, whose Leap mcp is
# the CMC joint, the OpenXR proximal bone.
_DIRECTION_BONE = {0: (_core.THUMB_PROXIMAL, _core.THUMB_DISTAL)}
_DIRECTION_BONE.update({t: (_J[f + "_intermediate"], _J[f + "_distal"]) for t, f in enumerate(_LEAP_FINGERS) if t})
_CURLS = np.linspace(0.0, 1.0, 41)
_FINGER_TABLES = {}


def _bend(u: np.ndarray, flat: np.ndarray) -> float:
    """How far a finger's direction bone `u` (unit, palm frame) is bent from `flat`: the signed angle about
    the palm's X (towards the palm positive, past 180 deg for a bone pointing back and up, so that it keeps
    growing with the curl)."""
    angle = math.atan2(-float(u[1]), -float(u[2]))
    return angle + 2 * math.pi if angle < -math.pi / 2 else angle


@dataclasses.dataclass(frozen=True)
class _FingerTable:
    """make_hand_frame's fingers in its palm frame. Fingers 1-4 at the curls of _CURLS: their flat direction
    bone (4, 3), its _bend (4, 41; it grows with the curl, so a lookup inverts it) and their tips (41, 4, 3).
    The thumb, which also swings across the palm, over a grid of (curl, thumb_opposition) (M, 2): its direction
    bone (M, 3) and tip (M, 3); a direction takes the grid point whose bone points most nearly along it."""
    flat: np.ndarray
    bends: np.ndarray
    tips: np.ndarray
    thumb_grid: np.ndarray
    thumb_dirs: np.ndarray
    thumb_tips: np.ndarray

    def fit(self, t: int, u: np.ndarray):
        """(curl, thumb_opposition or None) that point finger t's direction bone along unit palm-frame u."""
        if t == 0:
            c, o = self.thumb_grid[int(np.argmax(self.thumb_dirs @ u))]
            return float(c), float(o)
        return float(np.interp(_bend(u, self.flat[t - 1]), self.bends[t - 1], _CURLS)), None

    def tip(self, t: int, fit) -> np.ndarray:
        if t == 0:
            return self.thumb_tips[int(np.argmin(np.abs(self.thumb_grid - fit).sum(axis=1)))]
        return np.array([np.interp(fit[0], _CURLS, self.tips[:, t - 1, k]) for k in range(3)])


def _finger_table(handedness) -> _FingerTable:
    key = int(handedness == _core.Handedness.RIGHT)
    if key not in _FINGER_TABLES:
        def bone(p, t):
            a, b = _DIRECTION_BONE[t]
            return (p[b] - p[a]) / np.linalg.norm(p[b] - p[a])

        dirs, tips = [], []
        for c in _CURLS:
            p = np.asarray(_core.make_hand_frame(handedness, curl=float(c)).positions)
            dirs.append([bone(p, t) for t in range(1, 5)])
            tips.append([p[skeleton.chain(f)[-1]] for f in _LEAP_FINGERS[1:]])
        dirs = np.asarray(dirs)
        bends = np.array([[_bend(d[t], dirs[0, t]) for d in dirs] for t in range(4)])
        grid, thumb_dirs, thumb_tips = [], [], []
        for c in _CURLS[::2]:
            for o in np.linspace(0.0, 1.0, 11):
                p = np.asarray(_core.make_hand_frame(handedness, curl=[float(c), 0, 0, 0, 0],
                                                     thumb_opposition=float(o)).positions)
                grid.append((c, o))
                thumb_dirs.append(bone(p, 0))
                thumb_tips.append(p[_core.THUMB_TIP])
        _FINGER_TABLES[key] = _FingerTable(dirs[0], bends, np.asarray(tips), np.asarray(grid),
                                           np.asarray(thumb_dirs), np.asarray(thumb_tips))
    return _FINGER_TABLES[key]


def _match_fingers(cost: np.ndarray, slots):
    """({finger type: pointable index}, total cost): untyped pointables (rows of `cost`, squared m) given to
    the free finger `slots` (columns) by the assignment of least total cost (at most 5 x 5: every injective
    assignment is tried); a pair further apart than MATCH_MM is dropped from the assignment, not from the
    total. Nearest-first greedy matching mislabels a hand that is wider than the synthetic one."""
    k, m = cost.shape
    if k <= m:
        candidates = ([(i, j) for i, j in enumerate(perm)] for perm in itertools.permutations(range(m), k))
    else:
        candidates = ([(i, j) for j, i in enumerate(perm)] for perm in itertools.permutations(range(k), m))
    pairs = min(candidates, key=lambda cand: sum(cost[i, j] for i, j in cand))
    return ({slots[j]: i for i, j in pairs if cost[i, j] <= (MATCH_MM * MM) ** 2},
            float(sum(cost[i, j] for i, j in pairs)))


def _fit_fingers(hand: dict, pointables, fingers: Dict[int, dict], handedness, where: str):
    """(palm pose (7,), {finger type: (curl, thumb_opposition or None)}, matching cost in squared m or None when
    no untyped pointable was matched) of the synthetic hand rebuilt from a Leap hand's palm and finger
    directions (see the module docstring); None without a palm pose."""
    axes, palm = _palm_axes(hand, where), _vec(hand, "palmPosition", where)
    if axes is None or palm is None:
        return None
    d, n, c = axes
    right = handedness == _core.Handedness.RIGHT
    a, b, e = PALM_OFFSET_MM
    origin = (palm + a * d + b * n + (e if right else -e) * c) * MM
    rot = np.array([-c, -n, -d]).T  # OpenXR palm: +X index -> little (right hand), +Y back of the hand, -Z fingers
    table = _finger_table(handedness)

    def local_direction(p, label):
        u = _vec(p, "direction", f"{where}.pointables[{label}]")
        return None if u is None or np.linalg.norm(u) < 1e-6 else rot.T @ (u / np.linalg.norm(u))

    fits = {t: table.fit(t, u) for t, p in fingers.items() if (u := local_direction(p, f"type {t}")) is not None}
    untyped = []  # (tip, direction) in the palm frame of each pointable without a type
    for p in pointables:
        if p.get("type") is None:
            label = f"id {p.get('id')}"
            tip, u = _vec(p, "tipPosition", f"{where}.pointables[{label}]"), local_direction(p, label)
            if tip is not None and u is not None:
                untyped.append((rot.T @ (tip * MM - origin), u))
    slots = [t for t in range(5) if t not in fits]
    total = None
    if untyped and slots:
        # each pointable against each free finger bent as the pointable's direction says
        guess = [[table.fit(t, u) for t in slots] for _, u in untyped]
        cost = np.array([[float(np.sum((tip - table.tip(t, guess[i][j])) ** 2)) for j, t in enumerate(slots)]
                         for i, (tip, _) in enumerate(untyped)])
        matched, total = _match_fingers(cost, slots)
        fits.update({t: guess[i][slots.index(t)] for t, i in matched.items()})
    return np.r_[origin, skeleton.matrix_quat(rot)], fits, total


def _palm_frame(hand: dict, pointables, fingers: Dict[int, dict], handedness, where: str):
    """The hand rebuilt from its palm pose and finger directions (see the module docstring); None without a
    palm pose."""
    fitted = _fit_fingers(hand, pointables, fingers, handedness, where)
    if fitted is None:
        return None
    pose, fits, _ = fitted
    # a finger Leap does not report: as curled as its grab strength says; without one, as curled as the
    # fingers it does report (a hand that hides some fingers while others point out is not a fist), and
    # curled fully when it reports none
    grab = hand.get("grabStrength")
    seen = [fit[0] for t, fit in fits.items() if t > 0]
    if _finite_number(grab) is not None:
        unseen = min(max(float(grab), 0.0), 1.0)
    else:
        unseen = float(np.mean(seen)) if seen else 1.0
    extra = {} if 0 not in fits else {"thumb_opposition": fits[0][1]}
    frame = _core.make_hand_frame(handedness, pose, curl=[fits[t][0] if t in fits else unseen for t in range(5)],
                                  **extra)
    return skeleton.AdaptedFrame(frame, synthesized=tuple(_core.JOINT_NAMES))


def fit_side(hand: dict, pointables, where: str = "hand") -> Optional[str]:
    """The side whose synthetic hand the hand's untyped pointables fit better (least total distance of their
    tips to its fingertips: a thumb lies on one side only); None with fewer than 3 such pointables or
    without a palm pose. Right in 4185 of the 4407 such hands of the development recordings stripped of their
    types, 450 of 636 in flapping, whose hands are edge-on (python -m handsim.input_report), which is why
    read_leap_json takes it by majority over a hand id's frames rather than frame by frame."""
    untyped = [p for p in pointables if p.get("type") is None and p.get("tipPosition") is not None]
    if len(untyped) < 3:
        return None
    costs = {}
    for side, handedness in (("right", _core.Handedness.RIGHT), ("left", _core.Handedness.LEFT)):
        fitted = _fit_fingers(hand, untyped, {}, handedness, where)
        if fitted is None or fitted[2] is None:
            return None
        costs[side] = fitted[2]
    return min(costs, key=costs.get)


def _unpack_v2(frames):
    if not isinstance(frames, list) or not frames:
        raise ValueError("frames: expected a list of the packing structure and the packed frames")
    keys = frames[0]
    try:
        hand_keys = keys[2]["hands"][0]
        pointable_keys = keys[3]["pointables"][0]
    except (IndexError, KeyError, TypeError):
        hand_keys = pointable_keys = None
    if not all(isinstance(k, list) and all(isinstance(x, str) for x in k) for k in (hand_keys, pointable_keys)):
        raise ValueError("frames[0]: not a formatVersion 2 packing structure")
    out = []
    for i, fr in enumerate(frames[1:], 1):
        if not (isinstance(fr, list) and len(fr) >= 4 and all(isinstance(fr[k], list) for k in (2, 3))
                and all(isinstance(x, list) for x in fr[2] + fr[3])):
            raise ValueError(f"frames[{i}]: not a packed frame ([id, timestamp, [hands], [pointables], ...])")
        hands = [dict(zip(hand_keys, h)) for h in fr[2]]
        pointables = []
        for p in fr[3]:
            obj = dict(zip(pointable_keys, p))
            # the packed format has no finger type: Leap numbers a hand's fingers id = 10 * handId + type
            if "type" not in obj and isinstance(obj.get("id"), int) and isinstance(obj.get("handId"), int):
                t = obj["id"] - 10 * obj["handId"]
                if 0 <= t < 5:
                    obj["type"] = t
            pointables.append(obj)
        out.append({"id": fr[0], "timestamp": fr[1], "hands": hands, "pointables": pointables})
    return out


def _checked_frames(frames, name: str) -> List[dict]:
    """The frames as {"timestamp", "hands", "pointables"} with hands and pointables lists of objects, tools
    left out; anything of another shape is an error naming it (a missing list is an empty one)."""
    if not isinstance(frames, list):
        raise ValueError(f"{name}.frames: expected a list, got {type(frames).__name__}")
    out = []
    for i, fr in enumerate(frames):
        where = f"{name}.frames[{i}]"
        if not isinstance(fr, dict):
            raise ValueError(f"{where}: expected an object, got {type(fr).__name__}")
        stamp = fr.get("timestamp")
        if _finite_number(stamp) is None:
            raise ValueError(f"{where}.timestamp: expected a number (microseconds), got {stamp!r}")
        lists = {}
        for key in ("hands", "pointables"):
            items = fr.get(key) or []
            if not isinstance(items, list) or not all(isinstance(x, dict) for x in items):
                raise ValueError(f"{where}.{key}: expected a list of objects")
            lists[key] = items
        for k, hand in enumerate(lists["hands"]):
            for key, kinds in (("id", (int, str)), ("type", (str,))):
                if hand.get(key) is not None and (isinstance(hand[key], bool) or not isinstance(hand[key], kinds)):
                    raise ValueError(f"{where}.hands[{k}].{key}: expected {' or '.join(t.__name__ for t in kinds)}, "
                                     f"got {hand[key]!r}")
        out.append({"timestamp": stamp, "hands": lists["hands"],
                    "pointables": [p for p in lists["pointables"] if not p.get("tool")]})
    return out


def _fitted_sides(frames, name: str) -> Dict:
    """{hand id: side} for the hand ids that have neither a type nor a typed thumb: the side fit_side gives
    in most of their frames. Two ids seen in one frame are two hands: the one whose frames agree the more
    decides first, and the other takes the other side (by its own majority, flapping's edge-on right hand
    took the left side too, and the test of the stripped recordings caught it)."""
    votes = collections.defaultdict(collections.Counter)
    together = collections.defaultdict(set)
    for i, fr in enumerate(frames):
        hands, pointables = fr["hands"], fr["pointables"]
        ids = [h.get("id") for h in hands if h.get("id") is not None]
        for hand_id in ids:
            together[hand_id].update(ids)
        for k, hand in enumerate(hands):
            if hand.get("type") is not None or hand.get("id") is None:
                continue
            own = [p for p in pointables if p.get("handId") == hand.get("id")]
            where = f"{name}.frames[{i}].hands[{k}]"
            side = None if thumb_side(hand, own, where) is not None else fit_side(hand, own, where)
            if side is not None:
                votes[hand["id"]][side] += 1
    out = {}
    agreement = lambda hand_id: max(votes[hand_id].values()) / sum(votes[hand_id].values())
    for hand_id in sorted(votes, key=agreement, reverse=True):  # stable: equals keep their first-seen order
        side = votes[hand_id].most_common(1)[0][0]
        if any(out.get(other) == side for other in together[hand_id] - {hand_id}):
            side = "left" if side == "right" else "right"
        out[hand_id] = side
    return out


def _frame_sides(hands, pointables, known: Dict, fitted: Dict, where: str, notes) -> List[Optional[str]]:
    """The side of each hand of one frame, the surest first: its type; else its thumb's side; else the side
    its fingers fit over its hand id's frames (`fitted`); else the side its hand id had before; else the
    device side it is on (x < 0: left). A side already taken in the frame by a surer hand goes to the other
    side. `known` ({hand id: side}) is updated."""
    sides = [h.get("type") for h in hands]
    taken = {s for s in sides if s is not None}

    def by_thumb(k, hand):
        return thumb_side(hand, [p for p in pointables if p.get("handId") == hand.get("id")], f"{where}.hands[{k}]")

    def by_device(k, hand):
        palm = _vec(hand, "palmPosition", f"{where}.hands[{k}]")
        return "left" if palm is not None and palm[0] < 0 else "right"

    rules = ((by_thumb, "side from the thumb (no type)"),
             (lambda k, hand: fitted.get(hand.get("id")), "side from the finger fit (no type)"),
             (lambda k, hand: known.get(hand.get("id")), "side from the hand id (no type)"),
             (by_device, "side from the device side (no type)"))
    for rule, how in rules:
        for k, hand in enumerate(hands):
            if sides[k] is not None:
                continue
            side = rule(k, hand)
            if side is None:
                continue
            if side in taken:
                side, how_ = ("left" if side == "right" else "right"), how + ", the other hand's side taken"
            else:
                how_ = how
            sides[k] = side
            taken.add(side)
            notes[how_] += 1
    for hand, side in zip(hands, sides):
        if hand.get("id") is not None:
            known[hand.get("id")] = side
    return sides


def read_leap_json(doc, name: str = "recording") -> LeapRecording:
    """A LeapRecording from the decoded JSON document (a dict)."""
    if not isinstance(doc, dict) or "frames" not in doc or not isinstance(doc.get("metadata"), dict):
        raise ValueError(f"{name}: not a Leap recording (expected an object with 'metadata' and 'frames')")
    meta = doc["metadata"]
    version = meta.get("formatVersion")
    if version not in SUPPORTED_FORMATS:
        raise ValueError(f"{name}: Leap recording formatVersion {version!r} is not supported "
                         f"(supported: {', '.join(map(str, SUPPORTED_FORMATS))})")
    frames = _checked_frames(_unpack_v2(doc["frames"]) if version == 2 else doc["frames"], name)
    if not frames:
        raise ValueError(f"{name}: the recording has no frames")
    notes = collections.Counter()
    known_sides: Dict = {}
    fitted = _fitted_sides(frames, name)
    times, converted, rows = [], [], []
    for i, fr in enumerate(frames):
        where = f"{name}.frames[{i}]"
        stamp = fr["timestamp"]
        if times and stamp * 1e-6 < times[-1]:
            notes["frames out of time order, dropped"] += 1
            continue
        hands_in, pointables = fr["hands"], fr["pointables"]
        sides = _frame_sides(hands_in, pointables, known_sides, fitted, where, notes)
        hands, row = {}, np.full((3, 2), np.nan)
        for k, (hand, side) in enumerate(zip(hands_in, sides)):
            if side in hands:
                notes["second hand of a side, dropped"] += 1
                continue  # keep the first the tracker listed
            own = [p for p in pointables if p.get("handId") == hand.get("id")]
            adapted, how = leap_hand_frame(hand, own, f"{where}.hands[{k}]", side)
            if adapted is None:
                notes[how] += 1
                continue
            if how == "palm":
                notes["rebuilt from the palm (no full skeleton)"] += 1
            hands[side] = adapted
            for r, key in enumerate(("grabStrength", "pinchStrength", "confidence")):
                value = hand.get(key)
                if _finite_number(value) is not None:
                    row[r, 0 if side == "right" else 1] = min(max(float(value), 0.0), 1.0)
        times.append(stamp * 1e-6)
        converted.append(hands)
        rows.append(row)
    t = np.asarray(times)
    rows = np.asarray(rows)
    return LeapRecording(name, meta, t - t[0], converted, rows[:, 0], rows[:, 1], rows[:, 2], dict(notes))


def read_leap_document(path) -> dict:
    """The decoded JSON document of a leapjs-playback recording: ``.json.lz`` (LZ-String Base64) or ``.json``."""
    p = Path(path)
    if not p.is_file():
        raise FileNotFoundError(f"path: no such file: {p}")
    text = p.read_text(encoding="ascii", errors="replace").strip()
    if not text.startswith("{"):
        text = decompress_from_base64(text, f"path ({p.name})")
    try:
        return json.loads(text)
    except json.JSONDecodeError as e:
        raise ValueError(f"path ({p.name}): not JSON after decompression: {e}") from None


def load_leap_recording(path) -> LeapRecording:
    """Reads a leapjs-playback recording (see :func:`read_leap_document`) as OpenXR hand frames."""
    return read_leap_json(read_leap_document(path), Path(path).name.split(".")[0])


def without_skeleton(doc: dict) -> dict:
    """A copy of a formatVersion 0.1/1 document as a Leap SDK before 2.0 would have sent it: no hand type or
    strengths, no finger type or bone joints, and only the fingers Leap calls extended (it did not report the
    others). Measures how well :func:`leap_hand_frame` rebuilds such hands (input_report, tests)."""
    if doc.get("metadata", {}).get("formatVersion") == 2:
        raise ValueError("doc: a formatVersion 0.1 or 1 document is expected (frames as objects)")
    frames = []
    for fr in doc["frames"]:
        hands = [{k: v for k, v in h.items() if k not in ("type", "grabStrength", "pinchStrength", "confidence")}
                 for h in fr.get("hands", [])]
        pointables = [{k: v for k, v in p.items() if k not in ("type", "carpPosition", "btipPosition", "bases")
                       + _SKELETON_KEYS} for p in fr.get("pointables", []) if p.get("extended", True)]
        frames.append({**fr, "hands": hands, "pointables": pointables})
    return {"metadata": doc["metadata"], "frames": frames}


def _v2_frames(path):
    """The frame objects of a formatVersion 2 recording (the one that has carpPosition and btipPosition)."""
    doc = read_leap_document(path)
    if doc.get("metadata", {}).get("formatVersion") != 2:
        raise ValueError("path: the hand model is measured on a formatVersion 2 recording (it has carp/btip)")
    return doc, _unpack_v2(doc["frames"])


def _own_fingers(fr: dict, hand: dict) -> Dict[int, dict]:
    return {p["type"]: p for p in fr["pointables"] if p.get("handId") == hand["id"] and "type" in p}


def _in_palm_axes(hand: dict, v: np.ndarray) -> np.ndarray:
    """v in (direction, palmNormal, direction x palmNormal) of the hand, the last mirrored for a left hand."""
    d, n = np.asarray(hand["direction"], float), np.asarray(hand["palmNormal"], float)
    c = np.cross(d, n) * (1 if hand.get("type") != "left" else -1)
    return np.array([v @ d, v @ n, v @ c])


def measure_hand_model(path) -> dict:
    """The proportions of Leap's hand model that :func:`leap_hand_frame` uses for older frames, measured on a
    formatVersion 2 recording (mean and spread over every hand of every frame)."""
    _, frames = _v2_frames(path)
    rows = collections.defaultdict(list)
    for fr in frames:
        for hand in fr["hands"]:
            fingers = _own_fingers(fr, hand)
            v = lambda t, k: np.asarray(fingers[t][k], float)
            for t in range(5):
                rows["tip_extension"].append(np.linalg.norm(v(t, "btipPosition") - v(t, "dipPosition")) /
                                             np.linalg.norm(v(t, "tipPosition") - v(t, "dipPosition")))
            proximal = np.linalg.norm(v(2, "pipPosition") - v(2, "mcpPosition"))
            for t, f in enumerate(_LEAP_FINGERS[1:], 1):
                bone = v(t, "mcpPosition") - v(t, "carpPosition")
                rows[f"{f}_metacarpal_per_middle_proximal"].append(np.linalg.norm(bone) / proximal)
                rows[f"{f}_metacarpal_direction"].append(_in_palm_axes(hand, bone / np.linalg.norm(bone)))
            palm = 0.5 * (v(2, "mcpPosition") + v(2, "carpPosition"))
            offset = palm - np.asarray(hand["palmPosition"], float)
            rows["palm_offset_mm"].append(np.linalg.norm(offset))
            rows["palm_offset_in_palm_axes_mm"].append(_in_palm_axes(hand, offset))
    return {k: (np.mean(r, axis=0).round(4).tolist(), float(np.std(r, axis=0).max())) for k, r in rows.items()}


def without_carp(doc: dict) -> dict:
    """A formatVersion 2 document as formatVersion 1 frames: objects, without the carpPosition, btipPosition and
    bone bases that older frames lack (what :func:`metacarpal_errors` rebuilds and checks)."""
    frames = [{**fr, "pointables": [{k: v for k, v in p.items() if k not in ("carpPosition", "btipPosition", "bases")}
                                    for p in fr["pointables"]]} for fr in _unpack_v2(doc["frames"])]
    return {"metadata": {**doc["metadata"], "formatVersion": 1}, "frames": frames}


def metacarpal_errors(path) -> Dict[str, float]:
    """{finger: largest distance (mm) over all frames between the metacarpal base rebuilt from a formatVersion 2
    recording stripped of carpPosition (:func:`without_carp`) and Leap's own carpPosition}."""
    doc, frames = _v2_frames(path)
    rebuilt = read_leap_json(without_carp(doc), "stripped")
    out = {f: 0.0 for f in skeleton.FINGERS}
    for fr, conv in zip(frames, rebuilt.frames):
        for hand in fr["hands"]:
            fingers = _own_fingers(fr, hand)
            p = np.asarray(conv[hand["type"]].frame.positions) / MM
            for t, f in enumerate(_LEAP_FINGERS[1:], 1):
                miss = np.linalg.norm(p[_J[f + "_metacarpal"]] - np.asarray(fingers[t]["carpPosition"], float))
                out[f] = max(out[f], float(miss))
    return out


def model_scale(paths) -> Dict[str, dict]:
    """How Leap scales its hand model, from the knuckles (mcp joints), which every skeleton frame has. Per
    formatVersion ("2", "0.1/1": the two generations of Leap's service in the recordings), pooled over the
    recordings: the range of middle proximal bone lengths (mm) of its hands, each knuckle's place relative to
    the middle knuckle in the palm axes (left hands mirrored) in middle proximal bones, and the largest spread
    of that place over all hands, in mm at the largest hand. A spread near 0 over hands of several sizes and
    both sides: the model is scaled as a whole by that bone, and a left hand is the mirror of a right one."""
    sizes, rows = collections.defaultdict(list), collections.defaultdict(list)
    for path in paths:
        doc = read_leap_document(path)
        version = "2" if doc["metadata"].get("formatVersion") == 2 else "0.1/1"
        for fr in _unpack_v2(doc["frames"]) if version == "2" else doc["frames"]:
            for hand in fr.get("hands", []):
                fingers = _own_fingers(fr, hand)
                if len(fingers) < 5 or any(fingers[t].get(k) is None for t in range(5) for k in _SKELETON_KEYS):
                    continue
                mcp = lambda t: np.asarray(fingers[t]["mcpPosition"], float)
                proximal = float(np.linalg.norm(np.asarray(fingers[2]["pipPosition"], float) - mcp(2)))
                sizes[version].append(proximal)
                rows[version].append([_in_palm_axes(hand, mcp(t) - mcp(2)) / proximal for t in (1, 3, 4)])
    out = {}
    for version, r in rows.items():
        r, size = np.asarray(r), np.asarray(sizes[version])
        out[version] = {"proximal_mm": (float(size.min()), float(size.max())), "hands": len(r),
                        "knuckles_per_proximal": r.mean(axis=0),
                        "spread_mm": float((r.max(axis=0) - r.min(axis=0)).max() * size.max())}
    return out


if __name__ == "__main__":
    import sys
    for key, (mean, spread) in measure_hand_model(sys.argv[1]).items():
        print(f"{key}: {mean} (largest standard deviation {spread:.1e})")
    errors = metacarpal_errors(sys.argv[1])
    print("metacarpal bases rebuilt without carpPosition, largest distance to Leap's carpPosition (mm): " +
          ", ".join(f"{f} {e:.2f}" for f, e in errors.items()))
    scales = model_scale(dict.fromkeys(sys.argv[1:]))
    for version, m in sorted(scales.items()):
        print(f"formatVersion {version}: {m['hands']} hands, middle proximal {m['proximal_mm'][0]:.2f}-"
              f"{m['proximal_mm'][1]:.2f} mm; index, ring, little knuckle from the middle one in middle proximals "
              f"{m['knuckles_per_proximal'].round(4).tolist()}, largest spread {m['spread_mm']:.3f} mm")
    if len(scales) == 2:
        old, new = scales["0.1/1"], scales["2"]
        gap = np.linalg.norm(old["knuckles_per_proximal"] - new["knuckles_per_proximal"], axis=1) * old["proximal_mm"][1]
        print("knuckle layouts of the two generations differ by (index, ring, little, mm at the largest 0.1/1 "
              "hand): " + ", ".join(f"{g:.1f}" for g in gap))
