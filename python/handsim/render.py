"""Headless wireframe pictures of a World (matplotlib, Agg): the demo's and the replay's drawings.

:func:`snapshot` takes what a picture needs from a world (box corners of the chosen bodies, hand particles);
:func:`draw` draws a snapshot in a 2-D view (``axes=(2, 1)``: side view from the left, world Z to the right
and Y up; ``(0, 1)``: front view, X to the right and Y up).
"""
from __future__ import annotations

from typing import Dict, Optional, Sequence

import numpy as np

EDGES = [(0, 1), (2, 3), (4, 5), (6, 7), (0, 2), (1, 3), (4, 6), (5, 7), (0, 4), (1, 5), (2, 6), (3, 7)]
HAND_COLOURS = ("tab:blue", "tab:red")
BOX_COLOURS = ("saddlebrown", "darkgoldenrod", "tab:green", "tab:purple")


def pyplot():
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def rotate(q, v):
    """v (3,) rotated by the unit quaternion q (x, y, z, w)."""
    q = np.asarray(q, float)
    u, w = q[:3], q[3]
    t = 2 * np.cross(u, v)
    return v + w * t + np.cross(u, t)


def box_corners(pose, half):
    """(8, 3) corners of a box of half extents `half` at `pose` (7,)."""
    pose = np.asarray(pose, float)
    signs = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)], float)
    return np.array([pose[:3] + rotate(pose[3:], s * np.asarray(half, float)) for s in signs])


def snapshot(world, bodies: Dict[str, object], title: str = "") -> dict:
    """Corners of the named box bodies and the deformed particles of every tracked hand (None if untracked)."""
    boxes = []
    for name, body in bodies.items():
        shape = world.body_shape(body)
        boxes.append((name, box_corners(world.body_pose(body), shape.half_extents)))
    hands = [np.asarray(world.hand_particles(h, True)) if world.hand_tracked(h) else None for h in world.hands()]
    return {"boxes": boxes, "hands": hands, "title": title}


def draw(ax, snap: dict, centre: Sequence[float], half_width: float = 0.3, axes=(2, 1), aspect: float = 0.67):
    """Draws `snap` into `ax` around `centre` (3,), `half_width` m to each side."""
    a, b = axes
    for k, (_, corners) in enumerate(snap["boxes"]):
        for i, j in EDGES:
            ax.plot([corners[i, a], corners[j, a]], [corners[i, b], corners[j, b]],
                    color=BOX_COLOURS[k % len(BOX_COLOURS)], lw=1.1)
    for pts, colour in zip(snap["hands"], HAND_COLOURS):
        if pts is not None:
            ax.scatter(pts[:, a], pts[:, b], s=0.6, color=colour, alpha=0.5, linewidths=0)
    ax.set_xlim(centre[a] - half_width, centre[a] + half_width)
    ax.set_ylim(centre[b] - aspect * half_width, centre[b] + aspect * half_width)
    ax.set_aspect("equal")
    ax.set_xticks([])
    ax.set_yticks([])
    if snap.get("title"):
        ax.set_title(snap["title"], fontsize=8)
