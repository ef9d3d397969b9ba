"""Named scenes for recordings, replays and tests: one builder per scene, so that a recording names its scene
and its parameters and every replay rebuilds exactly the same world.

* ``"jewelry_box"``: :func:`handsim.build_jewelry_box` (the C++ scene builder); parameters are
  :class:`handsim.JewelryBoxDef` fields (``position``, ``yaw``, ``lid_overhang``, ...). Objects: ``table``,
  ``base``, ``lid`` (bodies) and ``hinge`` (joint).
* ``"free_box"``: a free cube on a static table. Parameters: ``position`` (centre of the cube's bottom face,
  on the table top; default (0, 0.75, -0.35), where the jewelry box stands), ``half_extent`` (m, default 0.02:
  a 4 cm cube), ``mass`` (kg, default 0.1), ``friction`` (default 0.6). Objects: ``table``, ``box``.
* ``"empty"``: no objects (the ground plane of the WorldDef only).

Scene objects are named so that recorded edits can refer to them (``{"op": "set_body_pose", "body": "lid"}``).
"""
from __future__ import annotations

from typing import Dict

import numpy as np

from . import _core

SCENES = ("jewelry_box", "free_box", "empty")
FREE_BOX_DEFAULTS = {"position": (0.0, 0.75, -0.35), "half_extent": 0.02, "mass": 0.1, "friction": 0.6}


class Scene:
    """What a builder added: ``name``, ``params`` (JSON-ready), ``objects`` (name -> BodyId / JointId) and, for
    the jewelry box, ``box`` (the JewelryBox)."""

    def __init__(self, name, params, objects, box=None):
        self.name, self.params, self.objects, self.box = name, params, objects, box

    def __getitem__(self, key):
        try:
            return self.objects[key]
        except KeyError:
            raise KeyError(f"scene {self.name!r} has no object {key!r} (it has {sorted(self.objects)})") from None


def _vec3(value, argument):
    a = np.asarray(value, float)
    if a.shape != (3,) or not np.isfinite(a).all():
        raise ValueError(f"{argument}: expected 3 finite numbers, got {value!r}")
    return [float(v) for v in a]


def _enum(kind, value, argument):
    try:
        return kind.__members__[value]
    except KeyError:
        raise ValueError(f"{argument}: expected one of {sorted(kind.__members__)}, got {value!r}") from None


def build_scene(world, name: str, params: Dict = None) -> Scene:
    """Adds scene `name` with `params` (a dict, see the module docstring) to `world`."""
    params = dict(params or {})
    if name == "jewelry_box":
        d = _core.JewelryBoxDef()
        for key, value in params.items():
            if not hasattr(d, key):
                raise ValueError(f"scene_params.{key}: not a JewelryBoxDef field")
            if key == "model" and isinstance(value, str):
                value = _enum(_core.JointModel, value, "scene_params.model")
            elif key == "solver" and isinstance(value, str):
                value = _enum(_core.JointSolver, value, "scene_params.solver")
            setattr(d, key, value)
        box = _core.build_jewelry_box(world, d)
        objects = {"base": box.base, "lid": box.lid, "hinge": box.hinge}
        if box.table is not None:
            objects["table"] = box.table
        return Scene(name, params, objects, box)
    if name == "free_box":
        unknown = set(params) - set(FREE_BOX_DEFAULTS)
        if unknown:
            raise ValueError(f"scene_params.{sorted(unknown)[0]}: not a free_box parameter "
                             f"(known: {sorted(FREE_BOX_DEFAULTS)})")
        p = {**FREE_BOX_DEFAULTS, **params}
        x, y, z = _vec3(p["position"], "scene_params.position")
        h = float(p["half_extent"])
        if not (np.isfinite(h) and h > 0):
            raise ValueError(f"scene_params.half_extent: expected a positive size, got {p['half_extent']!r}")
        if not y > 0:
            raise ValueError(f"scene_params.position: the table top (y) must be above the ground, got {y}")
        table = world.add_body(_core.BodyDef(shape=_core.Shape.box([0.6, 0.5 * y, 0.4]), mass=0.0,
                                             pose=[x, 0.5 * y, z, 0, 0, 0, 1], friction=float(p["friction"])))
        box = world.add_body(_core.BodyDef(shape=_core.Shape.box([h, h, h]), mass=float(p["mass"]),
                                           pose=[x, y + h, z, 0, 0, 0, 1], friction=float(p["friction"])))
        return Scene(name, params, {"table": table, "box": box})
    if name == "empty":
        if params:
            raise ValueError(f"scene_params: the empty scene takes no parameters, got {sorted(params)}")
        return Scene(name, params, {})
    raise ValueError(f"scene: expected one of {SCENES}, got {name!r}")
