"""handsim: direct hand manipulation of constrained virtual objects.

The C++ core lives in ``handsim._core``; this package re-exports it and adds pure-Python helpers.
Conventions: right-handed, Y-up, metres, seconds; quaternions x, y, z, w; poses as (7,) arrays
``[x, y, z, qx, qy, qz, qw]``.
"""
from ._core import *  # noqa: F401,F403
from ._core import __version__, Error  # noqa: F401
