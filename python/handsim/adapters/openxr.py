"""OpenXR hand joints (XR_EXT_hand_tracking): handsim's canonical form, and Unity's left-handed convention.

:func:`from_openxr` takes the 26 joints as an OpenXR runtime reports them (XrHandJointLocationEXT: position,
orientation, radius, and the POSITION_VALID / ORIENTATION_VALID flags) in a right-handed, Y-up space in
metres; nothing is converted. :func:`from_unity` takes the same joints in Unity's left-handed space (+X right,
+Y up, +Z forward), as Unity's XR Hands package and MRTK report them, with each joint's +Z along the bone
towards the fingertip and +Y out of the back of the hand. Mirroring Z turns the space right-handed and, in
the same stroke, the joint frames into OpenXR's (-Z along the bone, +Y dorsal):

    position (x, y, z) -> (x, y, -z)        rotation (x, y, z, w) -> (-x, -y, z, w)
"""
from __future__ import annotations

import numpy as np

from .. import _core
from . import _args
from .skeleton import AdaptedFrame

J = _core.JOINT_COUNT


def _frame(handedness, positions, orientations, radii, valid, names=("positions", "orientations")):
    h = _args.handedness(handedness)
    valid = _args.mask(valid, J, "valid")
    p = _args.array(positions, (J, 3), names[0], rows_ok=valid)
    q = _args.array(orientations, (J, 4), names[1], rows_ok=valid)
    r = np.full(J, 0.01) if radii is None else _args.array(radii, (J,), "radii", rows_ok=valid)
    return h, p, q, r, valid


def from_openxr(handedness, positions, orientations, radii=None, valid=None) -> AdaptedFrame:
    """The 26 OpenXR joints as they are: (26, 3) m, (26, 4) x, y, z, w, radii (26,) m (default 0.01), valid
    (26,) bool (default all; an invalid joint may hold NaN). Nothing is synthesized."""
    h, p, q, r, v = _frame(handedness, positions, orientations, radii, valid)
    frame = _core.HandFrame(h, p, q, r, v)
    return AdaptedFrame(frame, (), tuple(n for n, ok in zip(_core.JOINT_NAMES, v) if not ok))


def unity_to_openxr(positions, rotations):
    """Arrays in Unity's left-handed convention (..., 3) and (..., 4) to handsim's right-handed one."""
    p = np.array(positions, float, copy=True)
    q = np.array(rotations, float, copy=True)
    p[..., 2] *= -1
    q[..., 0] *= -1
    q[..., 1] *= -1
    return p, q


def from_unity(handedness, positions, rotations, radii=None, valid=None) -> AdaptedFrame:
    """The 26 joints in OpenXR order from Unity's left-handed space (see the module docstring); rotations are
    normalised (Unity's serialised quaternions are often off unit length by a few 1e-4)."""
    h, p, q, r, v = _frame(handedness, positions, rotations, radii, valid, ("positions", "rotations"))
    norms = np.linalg.norm(q, axis=1)
    bad = np.nonzero(v & ~(norms > 0.5))[0]
    if len(bad):
        raise ValueError(f"rotations[{bad[0]}]: not a rotation quaternion (length {norms[bad[0]]:.3g})")
    q = np.where(v[:, None], q / np.where(norms > 0, norms, 1)[:, None], q)
    p, q = unity_to_openxr(p, q)
    q[~v] = (0, 0, 0, 1)
    frame = _core.HandFrame(h, p, q, r, v)
    return AdaptedFrame(frame, (), tuple(n for n, ok in zip(_core.JOINT_NAMES, v) if not ok))
