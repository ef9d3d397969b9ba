"""MRTK articulated hand poses (``ArticulatedHandPose_*.json`` of Mixed Reality Toolkit 2.x) as HandFrames.

A file is Unity ``JsonUtility`` output: ``{"items": [{"joint": name, "pose": {"position": {x,y,z},
"rotation": {x,y,z,w}}}, ...]}`` with a padding item ``"None"`` and 26 joints named after MRTK's
``TrackedHandJoint`` (``Wrist``, ``Palm``, ``ThumbMetacarpalJoint``, ``IndexKnuckle``, ``PinkyTip``, ...).
Poses are right hands in Unity's left-handed camera space, in metres; a left hand is MRTK's mirror image of
the right one (position (-x, y, z), rotation (x, -y, -z, w)). The joints are matched by name, converted
with :func:`handsim.adapters.openxr.from_unity` and optionally moved by ``pose`` (7,).
"""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from .. import _core
from . import _args
from .openxr import from_unity
from .skeleton import AdaptedFrame

MRTK_TO_OPENXR = {"Wrist": "wrist", "Palm": "palm",
                  "ThumbMetacarpalJoint": "thumb_metacarpal", "ThumbProximalJoint": "thumb_proximal",
                  "ThumbDistalJoint": "thumb_distal", "ThumbTip": "thumb_tip"}
for _mrtk, _xr in (("Index", "index"), ("Middle", "middle"), ("Ring", "ring"), ("Pinky", "little")):
    MRTK_TO_OPENXR.update({f"{_mrtk}Metacarpal": f"{_xr}_metacarpal", f"{_mrtk}Knuckle": f"{_xr}_proximal",
                           f"{_mrtk}MiddleJoint": f"{_xr}_intermediate", f"{_mrtk}DistalJoint": f"{_xr}_distal",
                           f"{_mrtk}Tip": f"{_xr}_tip"})
_INDEX = {name: i for i, name in enumerate(_core.JOINT_NAMES)}


def read_mrtk_pose(doc, handedness="right", pose=None, name="pose") -> AdaptedFrame:
    """An AdaptedFrame from the decoded JSON of an MRTK pose file."""
    h = _args.handedness(handedness)
    items = doc.get("items") if isinstance(doc, dict) else None
    if not isinstance(items, list):
        raise ValueError(f"{name}: not an MRTK articulated hand pose (no 'items' list)")
    p = np.full((_core.JOINT_COUNT, 3), np.nan)
    q = np.full((_core.JOINT_COUNT, 4), np.nan)
    for i, item in enumerate(items):
        joint = item.get("joint")
        if joint == "None":
            continue
        if joint not in MRTK_TO_OPENXR:
            raise ValueError(f"{name}.items[{i}].joint: unknown MRTK joint {joint!r}")
        try:
            pos, rot = item["pose"]["position"], item["pose"]["rotation"]
            j = _INDEX[MRTK_TO_OPENXR[joint]]
            p[j] = [pos["x"], pos["y"], pos["z"]]
            q[j] = [rot["x"], rot["y"], rot["z"], rot["w"]]
        except (KeyError, TypeError):
            raise ValueError(f"{name}.items[{i}].pose: expected position x, y, z and rotation x, y, z, w") from None
    missing = [_core.JOINT_NAMES[j] for j in range(_core.JOINT_COUNT) if np.isnan(p[j]).any()]
    if missing:
        raise ValueError(f"{name}: joints missing: {missing}")
    if h == _core.Handedness.LEFT:
        p[:, 0] *= -1
        q[:, 1] *= -1
        q[:, 2] *= -1
    adapted = from_unity(h, p, q)
    if pose is None:
        return adapted
    return AdaptedFrame(adapted.frame.transformed(pose), adapted.synthesized, adapted.invalid)


def load_mrtk_pose(path, handedness="right", pose=None) -> AdaptedFrame:
    """Reads an MRTK ``ArticulatedHandPose_*.json`` file (see the module docstring)."""
    p = Path(path)
    if not p.is_file():
        raise FileNotFoundError(f"path: no such file: {p}")
    try:
        doc = json.loads(p.read_text())
    except json.JSONDecodeError as e:
        raise ValueError(f"path ({p.name}): not JSON: {e}") from None
    return read_mrtk_pose(doc, handedness, pose, p.name)
