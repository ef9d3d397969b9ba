"""Argument checks shared by the adapters: every error names the argument."""
from __future__ import annotations

import numpy as np

from .. import _core


def handedness(value, argument="handedness"):
    if isinstance(value, _core.Handedness):
        return value
    if isinstance(value, str) and value.lower() in ("left", "right"):
        return _core.Handedness.LEFT if value.lower() == "left" else _core.Handedness.RIGHT
    raise TypeError(f"{argument}: expected handsim.Handedness or 'left'/'right', got {value!r}")


def array(value, shape, argument, finite=True, rows_ok=None):
    """float64 array of `shape` (None: any length). With `rows_ok` (bool per row), only those rows must be
    finite."""
    if isinstance(value, (str, bytes)) or value is None:
        raise TypeError(f"{argument}: expected an array of shape {_fmt(shape)}, got {type(value).__name__}")
    try:
        a = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise TypeError(f"{argument}: expected numbers, got {type(value).__name__}") from None
    if a.ndim != len(shape) or any(s is not None and s != n for s, n in zip(shape, a.shape)):
        raise ValueError(f"{argument}: expected shape {_fmt(shape)}, got {a.shape}")
    if finite:
        rows = a.reshape(a.shape[0], -1) if a.ndim > 1 else a.reshape(-1, 1)
        check = rows if rows_ok is None else rows[np.asarray(rows_ok, bool)]
        bad = np.nonzero(~np.isfinite(check).all(axis=1))[0]
        if len(bad):
            index = bad[0] if rows_ok is None else np.nonzero(np.asarray(rows_ok, bool))[0][bad[0]]
            raise ValueError(f"{argument}[{index}]: must be finite, got {a[index].tolist()}")
    return a


def mask(value, n, argument):
    if value is None:
        return np.ones(n, bool)
    a = np.asarray(value)
    if a.shape != (n,):
        raise ValueError(f"{argument}: expected shape ({n},), got {a.shape}")
    if a.dtype != bool:
        raise TypeError(f"{argument}: expected booleans, got dtype {a.dtype}")
    return a


def _fmt(shape):
    return "(" + ", ".join("N" if s is None else str(s) for s in shape) + ("," if len(shape) == 1 else "") + ")"
