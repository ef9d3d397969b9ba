"""Record a session's inputs and replay them to the same ``state_hash()``, bit for bit.

A recording holds what goes into a World: the scene (a named builder of :mod:`handsim.scenes` and its
parameters), the WorldDef, the hands (HandDef fields), and per step the ``dt``, each hand's HandFrame (or
none) and the scene edits made before the step. It also keeps the ``state_hash()`` after every step, so a
replay checks itself. The file format (``FORMAT_VERSION`` 1) is documented in ``docs/input.md``: a
``numpy.savez_compressed`` archive of plain arrays plus one JSON header, loadable with ``numpy.load``
alone.

    rec = Recorder("jewelry_box", hands=[HandDef(handedness=Handedness.RIGHT)])
    rec.step(1 / 60, {rec.hands[0]: frame})   # drives rec.world
    rec.set_joint_value("hinge", 0.3)          # an edit, recorded with the step it precedes
    rec.save("session.npz")
    result = replay(load("session.npz"))       # result.matches: every step's hash equal
"""
from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path
from typing import Callable, List, Optional, Sequence

import numpy as np

from . import _core
from . import scenes as _scenes

FORMAT = "handsim-recording"
FORMAT_VERSION = 1
J = _core.JOINT_COUNT
# The fields each def is saved with: the core's def table (handsim/def_table.h), so a field added to a def is
# recorded without touching this file.
_DEF_FIELDS = _core.def_fields()
EDIT_OPS = ("set_body_pose", "set_body_velocity", "set_joint_value", "add_box", "remove_body")


class RecordingError(ValueError):
    """A recording file that cannot be read (wrong format, unknown version, inconsistent arrays)."""


def _def_to_dict(obj) -> dict:
    """Every field of a mirrored def as JSON values: enums by name, vectors as lists, nested defs as dicts."""
    out = {}
    for k in _DEF_FIELDS[type(obj).__name__]:
        v = getattr(obj, k)
        if type(v).__name__ in _DEF_FIELDS:
            v = _def_to_dict(v)
        elif hasattr(type(v), "__members__"):
            v = v.name
        elif isinstance(v, np.ndarray):
            v = [float(x) for x in v]
        out[k] = v
    return out


def _def_from_dict(cls, data: dict, where: str):
    """The def of type `cls` with the fields `data` names (the rest default); unknown names are errors."""
    obj = cls()
    fields = _DEF_FIELDS[cls.__name__]
    for k, v in data.items():
        if k not in fields:
            raise RecordingError(f"{where}.{k}: unknown field")
        current = getattr(obj, k)
        if type(current).__name__ in _DEF_FIELDS:
            v = _def_from_dict(type(current), v, f"{where}.{k}")
        elif hasattr(type(current), "__members__"):
            if v not in type(current).__members__:
                raise RecordingError(f"{where}.{k}: {v!r} is not a {type(current).__name__}")
            v = type(current).__members__[v]
        setattr(obj, k, v)
    return obj


def world_def_to_dict(d) -> dict:
    """The fields of a WorldDef as JSON-ready values (enums by name), as the header stores them."""
    return _def_to_dict(d)


def world_def_from_dict(data: dict):
    """The WorldDef of :func:`world_def_to_dict`'s output; an unknown field is a RecordingError naming it."""
    return _def_from_dict(_core.WorldDef, data, "header.world")


def hand_def_to_dict(h) -> dict:
    """The fields of a HandDef as JSON-ready values (enums by name), as the header stores them."""
    return _def_to_dict(h)


def hand_def_from_dict(data: dict):
    """The HandDef of :func:`hand_def_to_dict`'s output; an unknown field is a RecordingError naming it."""
    return _def_from_dict(_core.HandDef, data, "header.hands[]")


@dataclasses.dataclass
class Recording:
    """The inputs of a session (see the module docstring); arrays are indexed [step, hand, joint, ...]."""
    scene: str
    scene_params: dict
    world: dict                 # WorldDef fields
    hands: List[dict]           # HandDef fields, in the order of world.hands()
    dt: np.ndarray              # (S,) float64
    present: np.ndarray         # (S, H) bool: a frame was given for the hand
    positions: np.ndarray       # (S, H, 26, 3) float64
    orientations: np.ndarray    # (S, H, 26, 4) float64
    radii: np.ndarray           # (S, H, 26) float64
    valid: np.ndarray           # (S, H, 26) bool
    edits: List[dict] = dataclasses.field(default_factory=list)  # {"step": i, "op": ..., ...} before step i
    hashes: Optional[np.ndarray] = None  # (S,) uint64 state_hash after each step (None: not recorded)
    info: dict = dataclasses.field(default_factory=dict)  # free-form: source file, placement, notes

    @property
    def steps(self) -> int:
        """Number of recorded steps (S)."""
        return int(len(self.dt))

    def inputs(self, step: int, hands: Sequence) -> dict:
        """What World.step takes at `step`: {hands[h]: HandFrame} for each recorded hand h given a frame then
        (a hand without one is untracked that step). `hands`: the HandIds of the recording's hands, in the
        recording's order, as :func:`build_world` returns them."""
        if len(hands) != len(self.hands):
            raise ValueError(f"hands: {len(hands)} ids for the recording's {len(self.hands)} hands")
        return {hands[h]: _core.HandFrame(_core.Handedness.__members__[hand["handedness"]], self.positions[step, h],
                                          self.orientations[step, h], self.radii[step, h], self.valid[step, h])
                for h, hand in enumerate(self.hands) if self.present[step, h]}

    def save(self, path) -> Path:
        """Writes the recording as a format-1 ``.npz`` archive (docs/input.md); returns the path written."""
        path = Path(path)
        header = {"format": FORMAT, "version": FORMAT_VERSION, "handsim": _core.__version__, "scene": self.scene,
                  "scene_params": self.scene_params, "world": self.world, "hands": self.hands, "edits": self.edits,
                  "info": self.info}
        arrays = dict(header=np.array(json.dumps(header)), dt=np.asarray(self.dt, np.float64),
                      present=np.asarray(self.present, bool), positions=np.asarray(self.positions, np.float64),
                      orientations=np.asarray(self.orientations, np.float64),
                      radii=np.asarray(self.radii, np.float64), valid=np.asarray(self.valid, bool))
        if self.hashes is not None:
            arrays["hashes"] = np.asarray(self.hashes, np.uint64)
        with open(path, "wb") as f:  # a file object: numpy would otherwise append .npz to other suffixes
            np.savez_compressed(f, **arrays)
        return path


def load(path) -> Recording:
    """Reads a recording written by :meth:`Recording.save`. Raises FileNotFoundError naming `path`, and
    RecordingError on another format, an unknown version or inconsistent arrays."""
    p = Path(path)
    if not p.is_file():
        raise FileNotFoundError(f"path: no such file: {p}")
    try:
        z = np.load(p, allow_pickle=False)
        names = set(z.files)
    except Exception as e:  # not a zip / npz
        raise RecordingError(f"path ({p.name}): not a handsim recording (numpy .npz): {e}") from None
    with z:
        if "header" not in names:
            raise RecordingError(f"path ({p.name}): not a handsim recording (no 'header' array)")
        try:
            header = json.loads(str(z["header"][()]))
        except (json.JSONDecodeError, ValueError) as e:
            raise RecordingError(f"path ({p.name}): header is not JSON: {e}") from None
        if header.get("format") != FORMAT:
            raise RecordingError(f"path ({p.name}): format {header.get('format')!r}, expected {FORMAT!r}")
        version = header.get("version")
        if version != FORMAT_VERSION:
            raise RecordingError(f"path ({p.name}): recording version {version!r} is not supported: this handsim "
                                 f"({_core.__version__}) reads version {FORMAT_VERSION} only")
        missing = {"dt", "present", "positions", "orientations", "radii", "valid"} - names
        if missing:
            raise RecordingError(f"path ({p.name}): arrays missing: {sorted(missing)}")
        rec = Recording(header["scene"], header.get("scene_params", {}), header.get("world", {}), header["hands"],
                        z["dt"], z["present"], z["positions"], z["orientations"], z["radii"], z["valid"],
                        header.get("edits", []), z["hashes"] if "hashes" in names else None, header.get("info", {}))
    check(rec, p.name)
    return rec


def check(rec: Recording, name: str = "recording"):
    """Raises RecordingError, naming `name` and the array, unless every array has the shape and dtype the
    recording's step and hand counts call for and every edit is a known op before an existing step."""
    s, h = rec.steps, len(rec.hands)
    shapes = {"dt": (s,), "present": (s, h), "positions": (s, h, J, 3), "orientations": (s, h, J, 4),
              "radii": (s, h, J), "valid": (s, h, J)}
    for key, shape in shapes.items():
        got = np.shape(getattr(rec, key))
        if got != shape:
            raise RecordingError(f"{name}: {key} has shape {got}, expected {shape}")
    dtypes = {"dt": np.float64, "positions": np.float64, "orientations": np.float64, "radii": np.float64,
              "present": np.bool_, "valid": np.bool_}
    for key, dtype in dtypes.items():
        if np.asarray(getattr(rec, key)).dtype != dtype:
            raise RecordingError(f"{name}: {key} has dtype {np.asarray(getattr(rec, key)).dtype}, expected "
                                 f"{np.dtype(dtype)}")
    if rec.hashes is not None and np.shape(rec.hashes) != (s,):
        raise RecordingError(f"{name}: hashes has shape {np.shape(rec.hashes)}, expected {(s,)}")
    for i, e in enumerate(rec.edits):
        if e.get("op") not in EDIT_OPS or not isinstance(e.get("step"), int) or not 0 <= e["step"] <= s:
            raise RecordingError(f"{name}: edits[{i}] is not a known edit before a step: {e!r}")


def build_world(rec: Recording):
    """A fresh World with the recording's WorldDef, scene and hands: (world, scene, hand ids in the
    recording's order)."""
    world = _core.World(world_def_from_dict(rec.world))
    scene = _scenes.build_scene(world, rec.scene, rec.scene_params)
    hands = [world.add_hand(hand_def_from_dict(hand)) for hand in rec.hands]
    return world, scene, hands


def apply_edit(world, scene, edit: dict):
    """Applies one recorded scene edit (``{"op": ..., ...}``, objects named as in `scene`) to `world`."""
    op = edit["op"]
    if op == "set_body_pose":
        world.set_body_pose(scene[edit["body"]], edit["pose"])
    elif op == "set_body_velocity":
        world.set_body_velocity(scene[edit["body"]], edit["linear"], edit["angular"])
    elif op == "set_joint_value":
        world.set_joint_value(scene[edit["joint"]], edit["value"])
    elif op == "add_box":
        if edit["body"] in scene.objects:
            raise RecordingError(f"edit: add_box: the scene already has an object named {edit['body']!r}")
        d = _core.BodyDef(shape=_core.Shape.box(edit["half_extents"]), mass=edit["mass"], pose=edit["pose"])
        d.friction = edit["friction"]
        scene.objects[edit["body"]] = world.add_body(d)
    elif op == "remove_body":
        world.remove_body(scene[edit["body"]])
        del scene.objects[edit["body"]]
    else:
        raise RecordingError(f"edit: unknown op {op!r} (known: {EDIT_OPS})")


class Recorder:
    """Builds a world from a named scene and records everything that drives it.

    ``hands``: HandDefs (default: one right hand); ``recorder.hands`` are their HandIds in that order, the
    keys :meth:`step` takes. Drive the world only through :meth:`step` and the edit methods; read it freely
    through ``recorder.world``."""

    def __init__(self, scene: str = "jewelry_box", scene_params: dict = None, world_def=None,
                 hands: Sequence = None, info: dict = None):
        if hands is None:
            hands = [_core.HandDef(handedness=_core.Handedness.RIGHT)]
        for i, h in enumerate(hands):
            if not isinstance(h, _core.HandDef):
                raise TypeError(f"hands[{i}]: expected a HandDef, got {type(h).__name__}")
        if world_def is not None and not isinstance(world_def, _core.WorldDef):
            raise TypeError(f"world_def: expected a WorldDef, got {type(world_def).__name__}")
        self._rec = Recording(scene, dict(scene_params or {}),
                              world_def_to_dict(world_def if world_def is not None else _core.WorldDef()),
                              [hand_def_to_dict(h) for h in hands], np.zeros(0), np.zeros((0, len(hands)), bool),
                              np.zeros((0, len(hands), J, 3)), np.zeros((0, len(hands), J, 4)),
                              np.zeros((0, len(hands), J)), np.zeros((0, len(hands), J), bool), [], np.zeros(0, np.uint64),
                              dict(info or {}))
        self.world, self.scene, self.hands = build_world(self._rec)
        self._rows = []

    def step(self, dt: float, hands: dict = None):
        """Steps ``self.world`` with {HandId: HandFrame} (keys from ``self.hands``; a hand without an entry is
        untracked) and records the inputs and the resulting state hash; a step the world rejects raises and
        records nothing."""
        hands = dict(hands or {})
        self.world.step(dt, hands)  # validates everything first (an id not of this world too); records nothing then
        n = len(self._rec.hands)
        row = {"dt": float(dt), "present": np.zeros(n, bool), "positions": np.zeros((n, J, 3)),
               "orientations": np.tile([0.0, 0, 0, 1], (n, J, 1)), "radii": np.full((n, J), 0.01),
               "valid": np.zeros((n, J), bool), "hash": self.world.state_hash()}
        for h, hand in enumerate(self.hands):
            f = hands.get(hand)
            if f is None:
                continue
            row["present"][h] = True
            row["positions"][h] = f.positions
            row["orientations"][h] = f.orientations
            row["radii"][h] = f.radii
            row["valid"][h] = f.valid
        self._rows.append(row)

    def _edit(self, edit):
        apply_edit(self.world, self.scene, edit)  # raises before anything is recorded
        self._rec.edits.append({"step": len(self._rows), **edit})

    def set_body_pose(self, body: str, pose):
        """Teleports the scene body named `body` to `pose` (7,) now, recorded before the next step."""
        self._edit({"op": "set_body_pose", "body": body, "pose": [float(v) for v in np.asarray(pose, float)]})

    def set_body_velocity(self, body: str, linear, angular):
        """Sets the named body's linear and angular velocity (3,) each now, recorded before the next step."""
        self._edit({"op": "set_body_velocity", "body": body, "linear": [float(v) for v in np.asarray(linear, float)],
                    "angular": [float(v) for v in np.asarray(angular, float)]})

    def set_joint_value(self, joint: str, value: float):
        """Sets the named joint's value (rad or m) now, recorded before the next step."""
        self._edit({"op": "set_joint_value", "joint": joint, "value": float(value)})

    def add_box(self, body: str, half_extents, pose, mass: float = 1.0, friction: float = 0.5):
        """Adds a box body named `body` to the scene (mass 0: static); later edits can name it."""
        if not isinstance(body, str) or not body:
            raise TypeError(f"body: expected a non-empty name, got {body!r}")
        self._edit({"op": "add_box", "body": body, "half_extents": [float(v) for v in np.asarray(half_extents, float)],
                    "pose": [float(v) for v in np.asarray(pose, float)], "mass": float(mass),
                    "friction": float(friction)})

    def remove_body(self, body: str):
        """Removes the named body from the world and the scene now, recorded before the next step."""
        self._edit({"op": "remove_body", "body": body})

    @property
    def recording(self) -> Recording:
        """A Recording of everything so far (a snapshot: later steps do not change it)."""
        r, rows = self._rec, self._rows
        n = len(r.hands)
        stack = lambda key, shape, dtype: (np.stack([row[key] for row in rows]).astype(dtype) if rows
                                           else np.zeros((0,) + shape, dtype))
        return dataclasses.replace(
            r, dt=np.array([row["dt"] for row in rows], np.float64), present=stack("present", (n,), bool),
            positions=stack("positions", (n, J, 3), np.float64), orientations=stack("orientations", (n, J, 4), np.float64),
            radii=stack("radii", (n, J), np.float64), valid=stack("valid", (n, J), bool),
            edits=list(r.edits), hashes=np.array([row["hash"] for row in rows], np.uint64))

    def save(self, path) -> Path:
        """Saves :attr:`recording` to `path`; returns the path written."""
        return self.recording.save(path)


@dataclasses.dataclass
class ReplayResult:
    """What :func:`replay` ends with: the replayed world and scene, the steps run, the last state hash and
    the first step whose hash differs from the recorded one."""
    world: object
    scene: object
    steps: int
    final_hash: int
    first_mismatch: Optional[int]  # first step whose hash differs from the recorded one (None: all equal)

    @property
    def matches(self) -> bool:
        """Every replayed step's state hash equals the recorded one."""
        return self.first_mismatch is None


def replay(rec: Recording, on_step: Callable = None, steps: Optional[int] = None) -> ReplayResult:
    """Rebuilds the recording's world and steps it through the recorded inputs (the first `steps` only, if
    given). ``on_step(i, world, scene)`` is called after every step. Compares each step's state_hash with the
    recorded one when the recording has them; a recording without them (made from tracker input) gets them
    from a full replay, so that it can be saved and checked later."""
    check(rec)
    world, scene, hands = build_world(rec)
    edits = sorted(rec.edits, key=lambda e: e["step"])  # stable: same-step edits keep their order
    k = 0
    mismatch = None
    n = rec.steps if steps is None else min(int(steps), rec.steps)
    hashes = np.zeros(n, np.uint64)
    for i in range(n):
        while k < len(edits) and edits[k]["step"] == i:
            apply_edit(world, scene, edits[k])
            k += 1
        world.step(float(rec.dt[i]), rec.inputs(i, hands))
        hashes[i] = world.state_hash()
        if rec.hashes is not None and mismatch is None and int(rec.hashes[i]) != world.state_hash():
            mismatch = i
        if on_step is not None:
            on_step(i, world, scene)
    if rec.hashes is None and n == rec.steps:
        rec.hashes = hashes
    return ReplayResult(world, scene, n, world.state_hash(), mismatch)
