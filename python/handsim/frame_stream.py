"""The frame stream (``.hsframes``): a recorded session's hand frames as flat little-endian records that an
engine host reads with plain file I/O (no zip, no JSON), e.g. the Godot sample's C library
(``samples/godot/handsim_godot.c``), which steps them one per physics tick and checks every recorded hash.

It carries only what a host cannot rebuild itself: per step the ``dt``, the ``state_hash()`` the step must
reach, and each hand's 26 joints. The host builds the scene itself, so :func:`save` accepts only what every
host builds the same way: the ``jewelry_box`` scene with its default parameters, the default WorldDef, hands
with default HandDef fields (any handedness) and no scene edits; anything else is a RecordingError naming the
field (use the ``.npz`` recording and :func:`handsim.recording.replay` for those).

Layout (version 1), all little-endian::

    header   char magic[8] = "HSFRAMES"; u32 version = 1; u32 hand_count H; u32 step_count S;
             u32 joint_count = 26; i32 handedness[H] (0 left, 1 right: the C ABI's HANDSIM_LEFT/RIGHT)
    S steps  f64 dt; u64 state_hash after the step;
             H hands: i32 present; i32 reserved (0); 26 joints: f64 position[3], f64 orientation[4] (x, y, z, w),
             f64 radius, i32 valid, i32 reserved (0)

A joint record is byte for byte the C ABI's ``handsim_joint_pose`` (72 bytes), so a C host can read a hand's
joints straight into ``handsim_joint_pose[26]``. A hand that is not ``present`` gets no frame that step (it is
untracked), as in :meth:`handsim.recording.Recording.inputs`.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from . import _core
from . import recording as _rec

MAGIC = b"HSFRAMES"
VERSION = 1
J = _core.JOINT_COUNT
_HANDEDNESS = {"LEFT": 0, "RIGHT": 1}
_HEADER = np.dtype([("magic", "S8"), ("version", "<u4"), ("hands", "<u4"), ("steps", "<u4"), ("joints", "<u4")])
_JOINT = np.dtype([("position", "<f8", 3), ("orientation", "<f8", 4), ("radius", "<f8"), ("valid", "<i4"),
                   ("reserved", "<i4")])


def _step_dtype(hands: int) -> np.dtype:
    hand = np.dtype([("present", "<i4"), ("reserved", "<i4"), ("joints", _JOINT, J)])
    return np.dtype([("dt", "<f8"), ("hash", "<u8"), ("hands", hand, hands)])


def _check_defaults(rec: _rec.Recording, name: str):
    """What a host cannot read from the stream must be what it builds by default."""
    if rec.scene != "jewelry_box":
        raise _rec.RecordingError(f"{name}: scene: the frame stream is for the default jewelry_box scene, "
                                  f"got {rec.scene!r}")
    if rec.scene_params:
        raise _rec.RecordingError(f"{name}: scene_params: the frame stream needs the default jewelry box, got "
                                  f"{sorted(rec.scene_params)}")
    default_world = _rec.world_def_to_dict(_core.WorldDef())
    for key, value in rec.world.items():
        if default_world.get(key) != value:
            raise _rec.RecordingError(f"{name}: world.{key}: the frame stream needs the default WorldDef "
                                      f"({default_world.get(key)!r}), got {value!r}")
    default_hand = _rec.hand_def_to_dict(_core.HandDef())
    for h, hand in enumerate(rec.hands):
        for key, value in hand.items():
            if key != "handedness" and default_hand.get(key) != value:
                raise _rec.RecordingError(f"{name}: hands[{h}].{key}: the frame stream needs the default HandDef "
                                          f"({default_hand.get(key)!r}), got {value!r}")
    if rec.edits:
        raise _rec.RecordingError(f"{name}: edits: the frame stream carries hand frames only; this recording has "
                                  f"{len(rec.edits)} scene edit(s)")


def save(rec: _rec.Recording, path, name: str = "recording") -> Path:
    """Writes `rec` as a frame stream. A recording without hashes is replayed first to get them."""
    _rec.check(rec, name)
    _check_defaults(rec, name)
    if rec.hashes is None:
        _rec.replay(rec)  # fills rec.hashes
    steps, hands = rec.steps, len(rec.hands)
    header = np.zeros((), _HEADER)
    header["magic"], header["version"], header["hands"], header["steps"], header["joints"] = MAGIC, VERSION, hands, \
        steps, J
    handedness = np.array([_HANDEDNESS[h["handedness"]] for h in rec.hands], "<i4")
    body = np.zeros(steps, _step_dtype(hands))
    body["dt"] = rec.dt
    body["hash"] = rec.hashes
    body["hands"]["present"] = rec.present
    joints = body["hands"]["joints"]
    joints["position"] = rec.positions
    joints["orientation"] = rec.orientations
    joints["radius"] = rec.radii
    joints["valid"] = rec.valid
    path = Path(path)
    with open(path, "wb") as f:
        f.write(header.tobytes() + handedness.tobytes() + body.tobytes())
    return path


def load(path) -> _rec.Recording:
    """Reads a frame stream back as a Recording (default scene, world and hands; hashes included)."""
    p = Path(path)
    data = p.read_bytes()
    if len(data) < _HEADER.itemsize or data[:8] != MAGIC:
        raise _rec.RecordingError(f"path ({p.name}): not a handsim frame stream (magic {MAGIC!r})")
    header = np.frombuffer(data, _HEADER, 1)[0]
    if header["version"] != VERSION or header["joints"] != J:
        raise _rec.RecordingError(f"path ({p.name}): frame stream version {int(header['version'])} with "
                                  f"{int(header['joints'])} joints; this handsim reads version {VERSION} with {J}")
    hands, steps = int(header["hands"]), int(header["steps"])
    offset = _HEADER.itemsize + 4 * hands
    expected = offset + steps * _step_dtype(hands).itemsize
    if len(data) != expected:
        raise _rec.RecordingError(f"path ({p.name}): {len(data)} bytes, expected {expected} for {hands} hand(s) "
                                  f"and {steps} step(s)")
    handedness = np.frombuffer(data, "<i4", hands, _HEADER.itemsize)
    names = {v: k for k, v in _HANDEDNESS.items()}
    if any(int(h) not in names for h in handedness):
        raise _rec.RecordingError(f"path ({p.name}): handedness {handedness.tolist()}: expected 0 or 1 each")
    body = np.frombuffer(data, _step_dtype(hands), steps, offset)
    joints = body["hands"]["joints"]
    hand_dicts = []
    for h in handedness:
        d = _rec.hand_def_to_dict(_core.HandDef())
        d["handedness"] = names[int(h)]
        hand_dicts.append(d)
    return _rec.Recording("jewelry_box", {}, _rec.world_def_to_dict(_core.WorldDef()), hand_dicts,
                          body["dt"].copy(), body["hands"]["present"] != 0, joints["position"].copy(),
                          joints["orientation"].copy(), joints["radius"].copy(), joints["valid"] != 0, [],
                          body["hash"].copy(), {"source": p.name})
