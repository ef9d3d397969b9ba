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
frame): the fingertip end lies 1.2987 times as far from the dip joint as ``tipPosition``; the middle
metacarpal is 1.4475 times as long as the middle proximal bone and points along
0.9885 ``direction`` + 0.1483 ``palmNormal`` ± 0.0295 (``direction`` x ``palmNormal``) (+ for a right hand);
the other metacarpal bases follow from the wrist by the 15 % rule. Those joints are reported as synthesized.
Joint orientations are built from the positions (:func:`handsim.adapters.skeleton.orientations`).
"""
from __future__ import annotations

import dataclasses
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
MIDDLE_METACARPAL_PER_PROXIMAL = 1.4475
METACARPAL_DIRECTION = (0.9885, 0.1483, 0.0295)  # in (direction, palmNormal, direction x palmNormal), right hand
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
    v = obj.get(key)
    if v is None:
        return None
    a = np.asarray(v, float)
    if a.shape != (3,) or not np.isfinite(a).all():
        raise ValueError(f"{where}.{key}: expected 3 finite numbers, got {v!r}")
    return a


def leap_hand_frame(hand: dict, fingers: Dict[int, dict], where: str = "hand") -> skeleton.AdaptedFrame:
    """One Leap hand (a frame's ``hands[i]`` object) and its five pointables keyed by finger type 0..4 as an
    AdaptedFrame in metres."""
    kind = hand.get("type")
    if kind not in ("left", "right"):
        raise ValueError(f"{where}.type: expected 'left' or 'right', got {kind!r}")
    handedness = _core.Handedness.RIGHT if kind == "right" else _core.Handedness.LEFT
    missing = [t for t in range(5) if t not in fingers]
    if missing:
        raise ValueError(f"{where}: pointables of finger types {missing} are missing")
    pos = np.full((_core.JOINT_COUNT, 3), np.nan)
    given = np.zeros(_core.JOINT_COUNT, bool)
    synthesized = []
    for t, name in enumerate(_LEAP_FINGERS):
        p = fingers[t]
        w = f"{where}.pointables[type {t}]"
        mcp, pip, dip = (_vec(p, k, w) for k in ("mcpPosition", "pipPosition", "dipPosition"))
        if mcp is None or pip is None or dip is None:
            raise ValueError(f"{w}: mcpPosition, pipPosition and dipPosition are needed (a Leap v2 skeleton)")
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
    # the wrist, from the middle metacarpal base
    meta, prox = _J["middle_metacarpal"], _J["middle_proximal"]
    if not given[meta]:
        d, n = _vec(hand, "direction", where), _vec(hand, "palmNormal", where)
        if d is None or n is None:
            raise ValueError(f"{where}: direction and palmNormal are needed without carpPosition")
        a, b, c = METACARPAL_DIRECTION
        if handedness == _core.Handedness.LEFT:
            c = -c
        axis = a * d + b * n + c * np.cross(d, n)
        length = MIDDLE_METACARPAL_PER_PROXIMAL * np.linalg.norm(pos[_J["middle_intermediate"]] - pos[prox])
        base = pos[prox] - length * axis / np.linalg.norm(axis)
        pos[_core.WRIST] = skeleton.wrist_from_metacarpal(base, pos[prox])
    else:
        pos[_core.WRIST] = skeleton.wrist_from_metacarpal(pos[meta], pos[prox])
    given[_core.WRIST] = True
    synthesized = ["wrist"] + synthesized
    return skeleton.adapted_frame(handedness, pos, given, synthesized=synthesized)


def _unpack_v2(frames):
    keys = frames[0]
    try:
        hand_keys = keys[2]["hands"][0]
        pointable_keys = keys[3]["pointables"][0]
    except (IndexError, KeyError, TypeError):
        raise ValueError("frames[0]: not a formatVersion 2 packing structure") from None
    out = []
    for i, fr in enumerate(frames[1:], 1):
        hands = [dict(zip(hand_keys, h)) for h in fr[2]]
        pointables = []
        for p in fr[3]:
            obj = dict(zip(pointable_keys, p))
            obj["type"] = int(obj["id"]) - 10 * int(obj["handId"])
            pointables.append(obj)
        out.append({"id": fr[0], "timestamp": fr[1], "hands": hands, "pointables": pointables})
    return out


def read_leap_json(doc, name: str = "recording") -> LeapRecording:
    """A LeapRecording from the decoded JSON document (a dict)."""
    if not isinstance(doc, dict) or "frames" not in doc or not isinstance(doc.get("metadata"), dict):
        raise ValueError(f"{name}: not a Leap recording (expected an object with 'metadata' and 'frames')")
    meta = doc["metadata"]
    version = meta.get("formatVersion")
    if version not in SUPPORTED_FORMATS:
        raise ValueError(f"{name}: Leap recording formatVersion {version!r} is not supported "
                         f"(supported: {', '.join(map(str, SUPPORTED_FORMATS))})")
    frames = _unpack_v2(doc["frames"]) if version == 2 else doc["frames"]
    if not frames:
        raise ValueError(f"{name}: the recording has no frames")
    times, converted = [], []
    strengths = {k: np.full((len(frames), 2), np.nan) for k in ("grabStrength", "pinchStrength", "confidence")}
    for i, fr in enumerate(frames):
        times.append(float(fr["timestamp"]) * 1e-6)
        hands = {}
        for k, hand in enumerate(fr.get("hands", [])):
            kind = hand.get("type")
            if kind in hands:
                continue  # a second hand of the same side: keep the first the tracker listed
            fingers = {int(p["type"]): p for p in fr.get("pointables", []) if p.get("handId") == hand.get("id")}
            hands[kind] = leap_hand_frame(hand, fingers, f"{name}.frames[{i}].hands[{k}]")
            col = 0 if kind == "right" else 1
            for key, arr in strengths.items():
                if hand.get(key) is not None:
                    arr[i, col] = float(hand[key])
        converted.append(hands)
    t = np.asarray(times)
    if np.any(np.diff(t) < 0):
        raise ValueError(f"{name}: timestamps go backwards")
    return LeapRecording(name, meta, t - t[0], converted, strengths["grabStrength"], strengths["pinchStrength"],
                         strengths["confidence"])


def load_leap_recording(path) -> LeapRecording:
    """Reads a leapjs-playback recording: ``.json.lz`` (LZ-String Base64) or plain ``.json``."""
    p = Path(path)
    if not p.is_file():
        raise FileNotFoundError(f"path: no such file: {p}")
    text = p.read_text(encoding="ascii", errors="replace").strip()
    if not text.startswith("{"):
        text = decompress_from_base64(text, f"path ({p.name})")
    try:
        doc = json.loads(text)
    except json.JSONDecodeError as e:
        raise ValueError(f"path ({p.name}): not JSON after decompression: {e}") from None
    return read_leap_json(doc, p.name.split(".")[0])


def measure_hand_model(path) -> dict:
    """The proportions of Leap's hand model that :func:`leap_hand_frame` uses for older frames, measured on a
    formatVersion 2 recording (mean and spread over every hand of every frame)."""
    text = Path(path).read_text().strip()
    doc = json.loads(text if text.startswith("{") else decompress_from_base64(text, "path"))
    if doc.get("metadata", {}).get("formatVersion") != 2:
        raise ValueError("path: the hand model is measured on a formatVersion 2 recording (it has carp/btip)")
    rows = {"tip_extension": [], "middle_metacarpal_per_proximal": [], "metacarpal_direction": [],
            "palm_offset_mm": []}
    for fr in _unpack_v2(doc["frames"]):
        for hand in fr["hands"]:
            fingers = {p["type"]: p for p in fr["pointables"] if p["handId"] == hand["id"]}
            v = lambda t, k: np.asarray(fingers[t][k], float)
            for t in range(5):
                rows["tip_extension"].append(np.linalg.norm(v(t, "btipPosition") - v(t, "dipPosition")) /
                                             np.linalg.norm(v(t, "tipPosition") - v(t, "dipPosition")))
            meta = v(2, "mcpPosition") - v(2, "carpPosition")
            rows["middle_metacarpal_per_proximal"].append(
                np.linalg.norm(meta) / np.linalg.norm(v(2, "pipPosition") - v(2, "mcpPosition")))
            d, n = np.asarray(hand["direction"], float), np.asarray(hand["palmNormal"], float)
            u = meta / np.linalg.norm(meta)
            rows["metacarpal_direction"].append([u @ d, u @ n, u @ np.cross(d, n)])
            palm = 0.5 * (v(2, "mcpPosition") + v(2, "carpPosition"))
            rows["palm_offset_mm"].append(np.linalg.norm(palm - np.asarray(hand["palmPosition"], float)))
    return {k: (np.mean(r, axis=0).round(4).tolist(), float(np.std(r, axis=0).max())) for k, r in rows.items()}


if __name__ == "__main__":
    import sys
    for key, (mean, spread) in measure_hand_model(sys.argv[1]).items():
        print(f"{key}: {mean} (largest standard deviation {spread:.1e})")
