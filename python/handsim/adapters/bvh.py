"""BVH motion capture (Perception Neuron style) as OpenXR hand frames, and a small BVH writer.

The parser is handsim's own (numpy only): ``HIERARCHY`` with ``ROOT`` / ``JOINT`` / ``End Site`` blocks,
``OFFSET`` and ``CHANNELS``, then ``MOTION`` with ``Frames:``, ``Frame Time:`` and one line of channel values
per frame. Forward kinematics follows the BVH convention: a joint's local transform is the translation by its
``OFFSET`` followed by its rotation channels applied in the order the file lists them (``Yrotation Xrotation
Zrotation`` gives R = Ry Rx Rz), in degrees; an End Site is a point at its offset. A position channel replaces
the offset along its axis, as Blender's importer and the maintained ``bvhio`` library read it (adding them
moved a root with a non-zero offset by its offset twice). The tests check the forward kinematics against
``bvhio`` on a random hierarchy with mixed channel orders and on the hand files :func:`write_bvh` writes.

Perception Neuron writes centimetres (``scale`` 0.01 turns them into metres) in a right-handed, Y-up space.
Its finger joints map to OpenXR as (side ``Right`` or ``Left``):

=======================  ==========================
``<Side>Hand``           WRIST
``<Side>HandThumb1..3``  THUMB_METACARPAL, _PROXIMAL, _DISTAL; the End Site of Thumb3 is THUMB_TIP
``<Side>InHand<F>``      <F>_METACARPAL (Index, Middle, Ring, Pinky -> LITTLE)
``<Side>Hand<F>1..3``    <F>_PROXIMAL, _INTERMEDIATE, _DISTAL; the End Site of <F>3 is <F>_TIP
=======================  ==========================

Only joint positions are used; orientations are rebuilt in the OpenXR convention from them
(:mod:`handsim.adapters.skeleton`), since BVH rest poses and bone axes differ between exporters. The palm is
synthesized; finger metacarpals too when the file has no ``InHand`` joints (older Neuron skeletons).
"""
from __future__ import annotations

import dataclasses
import math
from pathlib import Path
from typing import Dict, List, Optional, Sequence

import numpy as np

from .. import _core
from . import _args
from .motion import Motion, with_strengths
from .skeleton import JOINT, AdaptedFrame, adapted_frame, quat_matrix

_AXES = {"X": 0, "Y": 1, "Z": 2}


@dataclasses.dataclass
class BvhJoint:
    """One joint of a BVH hierarchy: its parent, offset, channels and where its channels start in a frame."""
    name: str
    parent: int                 # index into Bvh.joints, -1 for a root
    offset: np.ndarray          # (3,) in file units
    channels: List[str]
    end_site: Optional[np.ndarray] = None  # (3,) offset of the End Site below this joint, if any
    first_channel: int = 0


@dataclasses.dataclass
class Bvh:
    """A parsed BVH file: the joint hierarchy and one row of channel values per frame."""
    joints: List[BvhJoint]
    frame_time: float
    motion: np.ndarray          # (frames, channels)

    def index(self, name):
        """Index of the joint called `name` in :attr:`joints`, or None."""
        for i, j in enumerate(self.joints):
            if j.name == name:
                return i
        return None

    def global_transforms(self, frame: int, scale: float = 1.0):
        """(rotations (J, 3, 3), positions (J, 3), end sites {joint index: (3,)}) of `frame`, positions
        multiplied by `scale`."""
        values = self.motion[frame]
        rots = np.zeros((len(self.joints), 3, 3))
        pos = np.zeros((len(self.joints), 3))
        ends = {}
        for i, j in enumerate(self.joints):
            local_t = j.offset.astype(float).copy()
            local_r = np.eye(3)
            for k, ch in enumerate(j.channels):
                v = values[j.first_channel + k]
                kind, axis = ch[1:].lower(), _AXES[ch[0].upper()]
                if kind == "position":
                    local_t[axis] = v
                else:
                    local_r = local_r @ _axis_rotation(axis, math.radians(v))
            if j.parent < 0:
                rots[i], pos[i] = local_r, local_t * scale
            else:
                rots[i] = rots[j.parent] @ local_r
                pos[i] = pos[j.parent] + rots[j.parent] @ (local_t * scale)
            if j.end_site is not None:
                ends[i] = pos[i] + rots[i] @ (j.end_site * scale)
        return rots, pos, ends


def _axis_rotation(axis, angle):
    c, s = math.cos(angle), math.sin(angle)
    if axis == 0:
        return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])
    if axis == 1:
        return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


class BvhError(ValueError):
    """A BVH file that cannot be parsed; the message names the line."""


def parse_bvh(text: str, name: str = "bvh") -> Bvh:
    """Parses BVH text; a malformed file is a BvhError (a ValueError) naming `name` and the line."""
    tokens = []
    for n, line in enumerate(text.splitlines(), 1):
        for tok in line.split():
            tokens.append((tok, n))
    pos = 0

    def take(expected=None):
        nonlocal pos
        if pos >= len(tokens):
            raise BvhError(f"{name}: unexpected end of file" + (f" (expected {expected})" if expected else ""))
        tok, line = tokens[pos]
        pos += 1
        if expected is not None and tok.upper() != expected.upper():
            raise BvhError(f"{name}: line {line}: expected {expected}, got {tok!r}")
        return tok, line

    def number():
        tok, line = take()
        try:
            v = float(tok)
        except ValueError:
            raise BvhError(f"{name}: line {line}: expected a number, got {tok!r}") from None
        if not math.isfinite(v):
            raise BvhError(f"{name}: line {line}: number must be finite, got {tok!r}")
        return v

    joints: List[BvhJoint] = []
    channel_count = 0

    def joint_block(parent, jname):
        nonlocal channel_count
        take("{")
        take("OFFSET")
        offset = np.array([number(), number(), number()])
        joint = BvhJoint(jname, parent, offset, [])
        index = len(joints)
        joints.append(joint)
        while True:
            tok, line = take()
            key = tok.upper()
            if key == "CHANNELS":
                count = int(number())
                for _ in range(count):
                    ch, cl = take()
                    if len(ch) < 9 or ch[0].upper() not in _AXES or ch[1:].lower() not in ("position", "rotation"):
                        raise BvhError(f"{name}: line {cl}: unknown channel {ch!r}")
                    joint.channels.append(ch[0].upper() + ch[1:].lower())
                joint.first_channel = channel_count
                channel_count += count
            elif key == "JOINT":
                child, _ = take()
                joint_block(index, child)
            elif key == "END":
                take("Site")
                take("{")
                take("OFFSET")
                joint.end_site = np.array([number(), number(), number()])
                take("}")
            elif key == "}":
                return
            else:
                raise BvhError(f"{name}: line {line}: unexpected {tok!r} in joint {jname!r}")

    take("HIERARCHY")
    while pos < len(tokens) and tokens[pos][0].upper() == "ROOT":
        take("ROOT")
        root, _ = take()
        joint_block(-1, root)
    if not joints:
        raise BvhError(f"{name}: no ROOT joint")
    take("MOTION")
    take("Frames:")
    frames = int(number())
    take("Frame")
    take("Time:")
    frame_time = number()
    if frames < 0 or not frame_time > 0:
        raise BvhError(f"{name}: Frames must be >= 0 and Frame Time > 0, got {frames} and {frame_time}")
    values = tokens[pos:]
    if len(values) != frames * channel_count:
        raise BvhError(f"{name}: MOTION has {len(values)} values, expected {frames} frames x {channel_count} channels")
    try:
        motion = np.array([float(t) for t, _ in values], float).reshape(frames, channel_count)
    except ValueError:
        bad = next((t, n) for t, n in values if not _is_float(t))
        raise BvhError(f"{name}: line {bad[1]}: expected a number, got {bad[0]!r}") from None
    if not np.isfinite(motion).all():
        raise BvhError(f"{name}: MOTION values must be finite")
    return Bvh(joints, frame_time, motion)


def _is_float(t):
    try:
        float(t)
        return True
    except ValueError:
        return False


def neuron_joint_map(side: str) -> Dict[str, str]:
    """BVH joint name -> OpenXR joint name of a Perception Neuron hand (``side``: 'Right' or 'Left');
    ``"<name>/end"`` names the End Site below a joint."""
    m = {f"{side}Hand": "wrist"}
    for k, b in enumerate(("metacarpal", "proximal", "distal"), 1):
        m[f"{side}HandThumb{k}"] = f"thumb_{b}"
    m[f"{side}HandThumb3/end"] = "thumb_tip"
    for pn, xr in (("Index", "index"), ("Middle", "middle"), ("Ring", "ring"), ("Pinky", "little")):
        m[f"{side}InHand{pn}"] = f"{xr}_metacarpal"
        for k, b in enumerate(("proximal", "intermediate", "distal"), 1):
            m[f"{side}Hand{pn}{k}"] = f"{xr}_{b}"
        m[f"{side}Hand{pn}3/end"] = f"{xr}_tip"
    return m


_REQUIRED = ["wrist", "thumb_metacarpal", "thumb_proximal", "thumb_distal", "thumb_tip"] + [
    f"{f}_{b}" for f in ("index", "middle", "ring", "little") for b in ("proximal", "intermediate", "distal", "tip")]


def hand_frames(bvh: Bvh, handedness, scale: float = 0.01, joint_map: Dict[str, str] = None,
                pose=None) -> List[AdaptedFrame]:
    """One AdaptedFrame per BVH frame for the hand of `handedness`. `joint_map`: BVH name -> OpenXR name
    (default :func:`neuron_joint_map`); `pose` (7,) moves the result rigidly."""
    h = _args.handedness(handedness)
    if not (isinstance(scale, (int, float)) and math.isfinite(scale) and scale > 0):
        raise ValueError(f"scale: expected a positive number (metres per file unit), got {scale!r}")
    side = "Right" if h == _core.Handedness.RIGHT else "Left"
    mapping = neuron_joint_map(side) if joint_map is None else dict(joint_map)
    sources = {}
    for bvh_name, xr in mapping.items():
        if xr not in JOINT:
            raise ValueError(f"joint_map[{bvh_name!r}]: {xr!r} is not an OpenXR joint name")
        base, _, end = bvh_name.partition("/")
        i = bvh.index(base)
        if i is None or (end and bvh.joints[i].end_site is None):
            continue
        sources[xr] = (i, bool(end))
    missing = [n for n in _REQUIRED if n not in sources]
    if missing:
        raise ValueError(f"bvh: the {side.lower()} hand lacks joints {missing} (joint_map names BVH joints such "
                         f"as {next(iter(mapping))!r})")
    out = []
    for f in range(bvh.motion.shape[0]):
        _, pos, ends = bvh.global_transforms(f, scale)
        p = np.full((_core.JOINT_COUNT, 3), np.nan)
        given = np.zeros(_core.JOINT_COUNT, bool)
        for xr, (i, end) in sources.items():
            p[JOINT[xr]] = ends[i] if end else pos[i]
            given[JOINT[xr]] = True
        a = adapted_frame(h, p, given)
        out.append(a if pose is None else AdaptedFrame(a.frame.transformed(pose), a.synthesized, a.invalid))
    return out


def load_bvh(path) -> Bvh:
    """Reads and parses the BVH file at `path` (:func:`parse_bvh`)."""
    p = Path(path)
    if not p.is_file():
        raise FileNotFoundError(f"path: no such file: {p}")
    return parse_bvh(p.read_text(errors="replace"), p.name)


def load_bvh_motion(path, scale: float = 0.01):
    """A :class:`handsim.replay.Motion` with every hand the BVH file has (Perception Neuron names)."""
    bvh = load_bvh(path)
    hands = {}
    for side, h in (("right", _core.Handedness.RIGHT), ("left", _core.Handedness.LEFT)):
        if bvh.index(f"{side.capitalize()}Hand") is not None:
            hands[side] = hand_frames(bvh, h, scale)
    if not hands:
        raise ValueError(f"path ({Path(path).name}): no RightHand or LeftHand joint")
    n = bvh.motion.shape[0]
    frames = [{side: seq[i] for side, seq in hands.items()} for i in range(n)]
    return with_strengths(Motion(Path(path).name.split(".")[0], np.arange(n) * bvh.frame_time, frames, source="bvh"))


# ---------------------------------------------------------------------------------------------------------
# Writer: a Perception-Neuron-named BVH of HandFrames (for tests and for exporting handsim motion).

_PARENT = {"thumb_metacarpal": "wrist", "index_metacarpal": "wrist", "middle_metacarpal": "wrist",
           "ring_metacarpal": "wrist", "little_metacarpal": "wrist"}
for _f in ("thumb", "index", "middle", "ring", "little"):
    _names = [n for n in _core.JOINT_NAMES if n.startswith(_f + "_")]
    for _a, _b in zip(_names, _names[1:]):
        _PARENT[_b] = _a


def _euler(m, order):
    """Angles (deg) a, b, c with m = R_order[0](a) R_order[1](b) R_order[2](c) (order e.g. 'YXZ')."""
    i, j, k = (_AXES[c] for c in order)
    sign = 1.0 if (j - i) % 3 == 1 else -1.0  # even permutation of XYZ
    b = math.asin(max(-1.0, min(1.0, sign * m[i, k])))
    if abs(m[i, k]) < 1 - 1e-12:
        a = math.atan2(-sign * m[j, k], m[k, k])
        c = math.atan2(-sign * m[i, j], m[i, i])
    else:  # gimbal lock: put everything in a
        a = math.atan2(sign * m[k, j], m[j, j])
        c = 0.0
    return [math.degrees(a), math.degrees(b), math.degrees(c)]


def write_bvh(path, frames: Sequence, frame_time: float = 1 / 60, scale: float = 100.0, order: str = "YXZ",
              root: str = "Hips") -> Path:
    """Writes HandFrames of one hand (all joints valid, one rigid skeleton: bone lengths as in frames[0]) as
    a BVH with Perception Neuron names, `scale` file units per metre (100: centimetres) and rotation
    channels in `order`. A `root` joint (6 channels) carries the wrist's offset; the wrist and fingers have
    rotation channels; tips are End Sites. Each joint's BVH frame is its OpenXR frame, so reading the file
    back gives the positions of the frames."""
    if not frames:
        raise ValueError("frames: expected at least one HandFrame")
    if sorted(order.upper()) != ["X", "Y", "Z"]:
        raise ValueError(f"order: expected a permutation of 'XYZ', got {order!r}")
    order = order.upper()
    h = frames[0].handedness
    for i, f in enumerate(frames):
        if not isinstance(f, _core.HandFrame):
            raise TypeError(f"frames[{i}]: expected a HandFrame, got {type(f).__name__}")
        if f.handedness != h or not np.asarray(f.valid).all():
            raise ValueError(f"frames[{i}]: every frame must be of one hand with all joints valid")
    side = "Right" if h == _core.Handedness.RIGHT else "Left"
    names = {xr: bvh for bvh, xr in neuron_joint_map(side).items() if not bvh.endswith("/end")}
    first = frames[0]
    P0, Q0 = np.asarray(first.positions), np.asarray(first.orientations)
    rot0 = {n: quat_matrix(Q0[JOINT[n]]) for n in _core.JOINT_NAMES}
    channels = " ".join(f"{c}rotation" for c in order)
    lines = ["HIERARCHY", f"ROOT {root}", "{", "  OFFSET 0 0 0",
             f"  CHANNELS 6 Xposition Yposition Zposition {channels}"]
    motion_order = []  # joints with rotation channels, in file order

    def emit(xr, depth):
        pad = "  " * depth
        parent = _PARENT.get(xr)
        if parent is None:
            off = P0[JOINT[xr]] * scale  # wrist below the root, which stays at the identity
        else:
            off = rot0[parent].T @ (P0[JOINT[xr]] - P0[JOINT[parent]]) * scale
        lines.extend([f"{pad}JOINT {names[xr]}", f"{pad}{{", f"{pad}  OFFSET {off[0]:.9g} {off[1]:.9g} {off[2]:.9g}",
                      f"{pad}  CHANNELS 3 {channels}"])
        motion_order.append(xr)
        children = [c for c, p in _PARENT.items() if p == xr and not c.endswith("_tip")]
        tip = [c for c, p in _PARENT.items() if p == xr and c.endswith("_tip")]
        for c in children:
            emit(c, depth + 1)
        if tip:
            e = rot0[xr].T @ (P0[JOINT[tip[0]]] - P0[JOINT[xr]]) * scale
            lines.extend([f"{pad}  End Site", f"{pad}  {{", f"{pad}    OFFSET {e[0]:.9g} {e[1]:.9g} {e[2]:.9g}",
                          f"{pad}  }}"])
        lines.append(f"{pad}}}")

    emit("wrist", 1)
    lines += ["}", "MOTION", f"Frames: {len(frames)}", f"Frame Time: {frame_time:.9g}"]
    for f in frames:
        Q = np.asarray(f.orientations)
        values = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
        for xr in motion_order:
            parent = _PARENT.get(xr)
            r = quat_matrix(Q[JOINT[xr]])
            local = r if parent is None else quat_matrix(Q[JOINT[parent]]).T @ r
            values += _euler(local, order)
        lines.append(" ".join(f"{v:.12g}" for v in values))
    p = Path(path)
    p.write_text("\n".join(lines) + "\n")
    return p
