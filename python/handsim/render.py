"""Key-frame pictures of a World for the replay and input reports: shaded 3D renders of the viewer's scene
description (:mod:`handsim.view.raster`), drawn into matplotlib axes.

:func:`snapshot` takes what a picture needs from a world (a :class:`handsim.view.scene.Frame`, float32);
:func:`draw` renders it around `centre`, `half_width` m to each side, seen from the side named by `axes`
(``(2, 1)``: from the left, world Z to the right and Y up, a little from above and in front; ``(0, 1)``: from
the front, X to the right and Y up, a little from above and the right).
"""
from __future__ import annotations

import math
from typing import Dict, Sequence

import numpy as np


def pyplot():
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def snapshot(world, bodies: Dict[str, object], title: str = "") -> dict:
    """The scene description of `world` now (bodies named as in `bodies`; touching particles shown)."""
    from .view.scene import Describer
    frame = Describer(world, bodies).frame()
    for m in frame.meshes:
        m.vertices = np.asarray(m.vertices, np.float32)
    return {"frame": frame, "title": title}


# view direction (from the target towards the eye) for each pair of picture axes
_VIEWS = {(2, 1): (-1.0, 0.35, 0.45), (0, 1): (0.35, 0.35, 1.0)}


def camera(centre: Sequence[float], half_width: float, axes=(2, 1), width: int = 400, height: int = 300):
    from .view.raster import Camera
    if tuple(axes) not in _VIEWS:
        raise ValueError(f"axes: expected one of {sorted(_VIEWS)}, got {axes!r}")
    d = np.asarray(_VIEWS[tuple(axes)], float)
    d /= np.linalg.norm(d)
    fov = 35.0
    hfov = 2 * math.atan(math.tan(math.radians(fov) / 2) * width / height)
    dist = half_width / math.tan(hfov / 2)
    c = np.asarray(centre, float)
    return Camera(c + d * dist, c, fov_deg=fov, width=width, height=height)


def draw(ax, snap: dict, centre: Sequence[float], half_width: float = 0.3, axes=(2, 1), aspect: float = 0.75):
    """Renders `snap` into `ax` around `centre` (3,)."""
    from .view.raster import render
    cam = camera(centre, half_width, axes, 400, int(round(400 * aspect)))
    ax.imshow(render(snap["frame"], cam, labels=False))
    ax.set_xticks([])
    ax.set_yticks([])
    if snap.get("title"):
        ax.set_title(snap["title"], fontsize=8)
