"""handsim: direct hand manipulation of constrained virtual objects.

The C++ core lives in ``handsim._core``; this package re-exports it and adds pure-Python helpers
(``handsim.gltf`` loads rigged glTF hands). Conventions: right-handed, Y-up, metres, seconds; quaternions
x, y, z, w; poses as (7,) arrays ``[x, y, z, qx, qy, qz, qw]``; hand joints in OpenXR order.
"""
import enum as _enum

from . import _core
from .argument_errors import name_bad_arguments as _name_bad_arguments

_name_bad_arguments(_core)  # before the re-export below, so handsim.X is the wrapped X

from ._core import *  # noqa: F401,F403
from ._core import __version__, Error, JOINT_NAMES  # noqa: F401

#: The 26 OpenXR hand joints as an IntEnum (``HandJoint.INDEX_TIP == handsim.INDEX_TIP == 10``).
HandJoint = _enum.IntEnum("HandJoint", {name.upper(): i for i, name in enumerate(JOINT_NAMES)})
HandJoint.__doc__ = "The 26 OpenXR hand joints in order: HandJoint.INDEX_TIP == handsim.INDEX_TIP == 10."

from . import gltf  # noqa: E402,F401  (pygltflib itself is imported only when a file is loaded)
