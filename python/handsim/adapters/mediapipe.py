"""MediaPipe Hands' 21 landmarks (positions only) as an OpenXR HandFrame.

Landmarks: 0 wrist; 1-4 thumb CMC, MCP, IP, tip; 5-8 index MCP, PIP, DIP, tip; 9-12 middle; 13-16 ring;
17-20 pinky. They map to OpenXR as WRIST; THUMB_METACARPAL, _PROXIMAL, _DISTAL, _TIP; and for each finger
PROXIMAL (the MCP knuckle), INTERMEDIATE, DISTAL, TIP. MediaPipe has no palm and no finger metacarpal bases:
those five joints are synthesized by :mod:`handsim.adapters.skeleton` (metacarpal 15 % of the way from the
wrist to the knuckle, palm at the middle of the middle metacarpal) and reported in ``synthesized``. Joint
orientations come from the landmark chain (:func:`handsim.adapters.skeleton.orientations`); radii are
handsim's adult hand scaled to this hand's size.

Coordinates:

* ``"world"`` (``multi_hand_world_landmarks``): metres, origin near the hand's centre, camera axes with +X
  right, +Y down, +Z away from the camera. Converted to handsim's camera-like frame (+X right, +Y up, +Z
  towards the viewer) by (x, y, z) -> (x, -y, -z), then moved so the wrist is at ``origin``.
* ``"image"`` (``multi_hand_landmarks``): x and y normalised by the image width and height, z a relative depth
  on the scale of x. ``image_size`` (width, height) in pixels makes them isotropic; the hand is then scaled so
  that the wrist lies ``palm_length`` m (default: handsim's adult hand, 9 cm) from the middle knuckle, the
  axes converted as above and the wrist put at ``origin``. That reads the image as an orthographic view;
  with the camera's ``focal_length`` (pixels; ``principal_point`` defaults to the image centre) the landmarks
  are unprojected through a pinhole instead: a landmark z pixels (z times the width) deeper than the wrist
  at the wrist's depth Z0 lies z·W·Z0/f deeper, and its x, y are its pixel's ray at that depth. Z0 only
  scales the whole hand, so ``palm_length`` still sets the size; the perspective no longer bends the angles
  (a fist or a pinch 30 cm from a 60 degree camera: more than 5 degrees without it, the tests check).

Pass the hand's real side: the legacy ``mediapipe.solutions.hands`` labels handedness as seen in a mirrored
(selfie) image, while the Tasks ``HandLandmarker`` of mediapipe 1.2.3 named the real side of an unmirrored
image in 15 of 16 renders (tests/python/data, ``scripts/mediapipe_fixtures``). Landmarks with
``visibility`` below ``min_visibility`` (or NaN landmarks, when ``visibility`` marks them) are invalid, and so
are the joints built from them.
"""
from __future__ import annotations

import numpy as np

from .. import _core
from . import _args
from .skeleton import JOINT, AdaptedFrame, adapted_frame

LANDMARK_COUNT = 21
LANDMARK_NAMES = ("wrist", "thumb_cmc", "thumb_mcp", "thumb_ip", "thumb_tip", "index_mcp", "index_pip", "index_dip",
                  "index_tip", "middle_mcp", "middle_pip", "middle_dip", "middle_tip", "ring_mcp", "ring_pip",
                  "ring_dip", "ring_tip", "pinky_mcp", "pinky_pip", "pinky_dip", "pinky_tip")
#: OpenXR joint index of each landmark.
LANDMARK_TO_JOINT = np.array([JOINT["wrist"]] + list(range(JOINT["thumb_metacarpal"], JOINT["thumb_tip"] + 1)) + [
    j for f in ("index", "middle", "ring", "little") for j in range(JOINT[f + "_proximal"], JOINT[f + "_tip"] + 1)])
DEFAULT_PALM_LENGTH = 0.09  # m, wrist to middle knuckle of make_hand_frame's adult hand


def from_mediapipe(landmarks, handedness, coordinates="world", image_size=None, palm_length=None,
                   origin=None, visibility=None, min_visibility=0.5, focal_length=None,
                   principal_point=None) -> AdaptedFrame:
    """An AdaptedFrame from (21, 3) landmarks (see the module docstring)."""
    h = _args.handedness(handedness)
    if coordinates not in ("world", "image"):
        raise ValueError(f"coordinates: expected 'world' or 'image', got {coordinates!r}")
    ok = np.ones(LANDMARK_COUNT, bool)
    if visibility is not None:
        vis = _args.array(visibility, (LANDMARK_COUNT,), "visibility", finite=False)
        ok = np.nan_to_num(vis, nan=0.0) >= float(min_visibility)
    lm = _args.array(landmarks, (LANDMARK_COUNT, 3), "landmarks", rows_ok=ok)
    lm = np.where(ok[:, None], lm, np.nan)
    if coordinates == "image":
        if image_size is None:
            raise ValueError("image_size: (width, height) in pixels is needed for image coordinates")
        size = _args.array(image_size, (2,), "image_size")
        if not (size > 0).all():
            raise ValueError(f"image_size: expected positive width and height, got {size.tolist()}")
        lm = lm * np.array([size[0], size[1], size[0]])
        if focal_length is not None:
            lm = _unproject(lm, size, focal_length, principal_point, ok)
        elif principal_point is not None:
            raise ValueError("principal_point: only used with focal_length")
        if not (ok[0] and ok[9]):
            raise ValueError("landmarks: the wrist (0) and middle knuckle (9) are needed to scale image coordinates")
        length = float(np.linalg.norm(lm[9] - lm[0]))
        if not length > 0:
            raise ValueError("landmarks: the wrist (0) and middle knuckle (9) coincide")
        target = DEFAULT_PALM_LENGTH if palm_length is None else float(palm_length)
        lm = (lm - lm[0]) * (target / length)
    elif focal_length is not None or principal_point is not None:
        raise ValueError("focal_length: only used with image coordinates (world landmarks are metric already)")
    elif palm_length is not None:
        if not (ok[0] and ok[9]):
            raise ValueError("landmarks: the wrist (0) and middle knuckle (9) are needed to rescale")
        lm = (lm - lm[0]) * (float(palm_length) / float(np.linalg.norm(lm[9] - lm[0]))) + lm[0]
    if palm_length is not None and not (np.isfinite(palm_length) and palm_length > 0):
        raise ValueError(f"palm_length: expected a positive length in metres, got {palm_length!r}")
    lm = lm * np.array([1.0, -1.0, -1.0])
    if origin is not None:
        o = _args.array(origin, (3,), "origin")
        if not ok[0]:
            raise ValueError("origin: the wrist landmark (0) is invalid, so it cannot be placed")
        lm = lm - lm[0] + o
    pos = np.full((_core.JOINT_COUNT, 3), np.nan)
    given = np.zeros(_core.JOINT_COUNT, bool)
    valid = np.zeros(_core.JOINT_COUNT, bool)
    pos[LANDMARK_TO_JOINT] = lm
    given[LANDMARK_TO_JOINT] = True
    valid[LANDMARK_TO_JOINT] = ok
    return adapted_frame(h, pos, given, valid)


def _unproject(px, size, focal_length, principal_point, ok):
    """Pixel landmarks (u, v, depth in pixels at the wrist's depth) as camera-frame points (+X right, +Y down,
    +Z away) in units of the wrist's depth Z0 (see the module docstring)."""
    f = float(focal_length) if isinstance(focal_length, (int, float)) and not isinstance(focal_length, bool) else np.nan
    if not (np.isfinite(f) and f > 0):
        raise ValueError(f"focal_length: expected a positive number of pixels, got {focal_length!r}")
    centre = size / 2 if principal_point is None else _args.array(principal_point, (2,), "principal_point")
    if not ok[0]:
        raise ValueError("landmarks: the wrist (0) is needed to unproject image coordinates")
    depth = 1.0 + (px[:, 2] - px[0, 2]) / f  # Z / Z0
    if not (depth[ok] > 0).all():
        raise ValueError("landmarks: a landmark lies behind the camera at this focal_length")
    return np.c_[(px[:, 0] - centre[0]) / f * depth, (px[:, 1] - centre[1]) / f * depth, depth]


def landmarks_of(frame, coordinates="world") -> np.ndarray:
    """The (21, 3) landmarks MediaPipe would report for a HandFrame (world coordinates, axes converted
    back; ``"image"``: x and y of a 1 m wide orthographic view, z on the scale of x). For tests and tools."""
    p = np.asarray(frame.positions, float)[LANDMARK_TO_JOINT] * np.array([1.0, -1.0, -1.0])
    if coordinates == "world":
        return p
    return p - p.min(axis=0) + 0.1
