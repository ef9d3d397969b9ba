"""Typed, documented Python API (issue 23): the generated stubs type-check the docs' examples, every public
class and method has a docstring, and arrays handsim returns are read-only copies.

The public API is the top-level ``handsim`` namespace and the modules users import (``handsim.gltf``,
``handsim.recording``, ``handsim.frame_stream``, ``handsim.scenes``, ``handsim.adapters.*``); the command-line
tools (bench, experiments, replay, input_report, users, plots, render) are not walked."""
import importlib
import inspect
import math
import os
import pkgutil
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import handsim
from handsim import adapters

from test_docs import BLOCKS, ROOT, block_id, skip_reason

RIGHT = handsim.Handedness.RIGHT
API_MODULES = ["handsim", "handsim.gltf", "handsim.recording", "handsim.frame_stream", "handsim.scenes"] + [
    f"handsim.adapters.{m.name}" for m in pkgutil.iter_modules(adapters.__path__) if not m.name.startswith("_")]


def own_doc(obj, name):
    """The docstring without the signature lines pybind11 puts first (a bare signature documents nothing)."""
    signature = re.compile(rf"^(\d+\. )?{re.escape(name)}\(.*\)( -> .*)?$")
    lines = [line.strip() for line in (inspect.getdoc(obj) or "").splitlines()]
    return " ".join(line for line in lines if line and line != "Overloaded function." and not signature.match(line))


def public_api():
    """(qualified name, object, name) of every public class, function and method of API_MODULES, once each."""
    seen, out = set(), []
    for module_name in API_MODULES:
        module = importlib.import_module(module_name)
        names = getattr(module, "__all__", None) or [n for n in vars(module) if not n.startswith("_")]
        for name in names:
            obj = getattr(module, name)
            home = getattr(obj, "__module__", "") or ""
            if not (inspect.isclass(obj) or inspect.isroutine(obj)) or not home.startswith("handsim"):
                continue  # constants, and names imported from numpy, typing, ...
            key = (home, obj.__qualname__)
            if key in seen:
                continue
            seen.add(key)
            out.append((f"{home}.{obj.__qualname__}", obj, name))
            if inspect.isclass(obj) and not issubclass(obj, BaseException):
                for attr, member in vars(obj).items():
                    if not attr.startswith("_") and inspect.isroutine(member):
                        out.append((f"{home}.{obj.__qualname__}.{attr}", member, attr))
    return out


def test_every_public_class_and_method_has_a_docstring():
    api = public_api()
    assert len(api) > 150  # the walk reaches the bound classes and their methods, not just a few names
    assert any(name == "handsim._core.World.body_grasp" for name, _, _ in api)
    missing = [name for name, obj, short in api if not own_doc(obj, short)]
    assert not missing, f"{len(missing)} without a docstring: {missing}"


def quick_world():
    """A world with a body, a joint and a tracked hand after one step: every kind of getter has something."""
    world = handsim.World()
    hand = world.add_hand(handsim.HandDef(handedness=RIGHT))
    box = handsim.build_jewelry_box(world)
    world.step(1 / 60, {hand: handsim.make_hand_frame(RIGHT, [0, 0.3, 0.3, 0, 0, 0, 1])})
    return world, hand, box


def attribute_arrays():
    """(what, array) for the array attributes of each kind of bound object."""
    world, hand, box = quick_world()
    frame = handsim.make_hand_frame(RIGHT, [0, 0.3, 0, 0, 0, 0, 1])
    model = world.hand_model(hand)
    grasp_world = handsim.World(handsim.WorldDef(ground=False, gravity=[0, 0, 0]))
    grasp_hand = grasp_world.add_hand(handsim.HandDef())
    plate = grasp_world.add_body(handsim.BodyDef(shape=handsim.Shape.box([0.05, 0.001, 0.02]), mass=0.1,
                                                 pose=[0, 0.5, -0.08, 0, 0, 0, 1]))
    for _ in range(math.ceil(grasp_world.definition.grasp.grasp_time_s * 60 - 1e-9)):  # 60 Hz frames
        grasp_world.step(1 / 60, {grasp_hand: handsim.make_hand_frame(RIGHT, [0, 0.5, 0, 0, 0, 0, 1])})
    out = {
        "HandFrame.positions": frame.positions, "HandFrame.orientations": frame.orientations,
        "HandFrame.radii": frame.radii, "HandFrame.valid": frame.valid, "HandFrame.palm_pose": frame.palm_pose,
        "HandModel.bind_vertices": model.bind_vertices, "HandModel.triangles": model.triangles,
        "HandModel.exposed": model.exposed, "HandModel.particle_vertex": model.particle_vertex,
        "SkinnedMesh.positions": model.mesh.positions, "SkinnedMesh.weights": model.mesh.weights,
        "BodyDef.pose": handsim.BodyDef().pose, "BodyDef.linear_velocity": handsim.BodyDef().linear_velocity,
        "WorldDef.gravity": handsim.WorldDef().gravity, "Shape.half_extents": handsim.Shape.box([0.1] * 3).half_extents,
        "JointState.rotation": world.joint_state(box.hinge).rotation, "HandPoseParams.curl": handsim.HandPoseParams().curl,
        "GraspInfo.primary_relative": grasp_world.body_grasp(plate).primary_relative,
    }
    return out


def test_array_attributes_are_read_only_copies():
    """A write into an attribute's array would look like a change of the object but could never reach it:
    it raises instead of being silently lost. A copy is writable."""
    for what, array in attribute_arrays().items():
        assert isinstance(array, np.ndarray) and array.size, what
        assert not array.flags.writeable, f"{what} is writable"
        with pytest.raises(ValueError, match="read-only"):
            array[(0,) * array.ndim] = array[(0,) * array.ndim]
        array.copy()[(0,) * array.ndim] = 0


def test_method_results_are_the_callers_writable_arrays():
    """What a method or function computes is a fresh array the caller owns (the README lifts a palm pose
    in place); changing it changes nothing in the world."""
    world, hand, box = quick_world()
    before = world.state_hash()
    contacts = handsim.collide_particles(world.hand_particles(hand), 0.004, handsim.Shape.box([0.1] * 3),
                                         world.hand_palm_pose(hand))
    results = {"World.body_pose": world.body_pose(box.lid), "World.body_velocity[0]": world.body_velocity(box.lid)[0],
               "World.hand_particles": world.hand_particles(hand), "World.hand_palm_pose": world.hand_palm_pose(hand),
               "World.hand_render_vertices": world.hand_render_vertices(hand),
               "HandFrame.joint_pose": handsim.make_hand_frame(RIGHT).joint_pose(handsim.INDEX_TIP),
               "JewelryBox.lid_pinch_palm": box.lid_pinch_palm(world, RIGHT, 0.0),
               "collide_particles['depth']": contacts["depth"]}
    for what, array in results.items():
        assert isinstance(array, np.ndarray) and array.size and array.flags.writeable, what
        array[(0,) * array.ndim] = 99
    assert world.state_hash() == before
    assert world.body_pose(box.lid)[0] != 99


def test_a_write_into_frame_positions_raises_and_the_frame_is_unchanged():
    frame = handsim.make_hand_frame(RIGHT, [0, 0.3, 0, 0, 0, 0, 1])
    with pytest.raises(ValueError, match="read-only"):
        frame.positions[0, 0] = 99
    assert frame.positions[0, 0] == 0
    # Changing a frame means building one from (writable copies of) its arrays:
    positions = frame.positions.copy()
    positions[0, 0] = 0.05
    moved = handsim.HandFrame(RIGHT, positions, frame.orientations, frame.radii, frame.valid)
    assert moved.positions[0, 0] == 0.05


def stub_package(tmp_path):
    """A folder holding handsim as a type checker sees it installed: the Python sources, py.typed and the
    _core stubs that the build generated beside the extension module."""
    stubs = Path(handsim._core.__file__).parent / "_core"
    assert (stubs / "__init__.pyi").is_file(), f"no generated stubs at {stubs} (scripts/build makes them)"
    source = Path(handsim.__file__).parent
    assert (source / "py.typed").is_file()
    package = tmp_path / "mypy_path" / "handsim"
    package.mkdir(parents=True)
    for entry in source.iterdir():
        if entry.name not in ("__pycache__", "_core"):
            (package / entry.name).symlink_to(entry)
    (package / "_core").symlink_to(stubs)
    return package.parent


def test_the_docs_examples_type_check(tmp_path):
    """mypy, with the generated stubs, over every python block of README.md and docs/*.md (the blocks
    test_docs.py runs); errors are reported for the blocks only (--follow-imports=silent)."""
    pytest.importorskip("mypy")
    files = []
    for block in BLOCKS:
        if skip_reason(block[2]) is not None:
            continue
        name = re.sub(r"\W", "_", block_id(block)) + ".py"
        (tmp_path / name).write_text(block[2])
        files.append(name)
    assert files
    env = {**os.environ, "MYPYPATH": str(stub_package(tmp_path))}
    result = subprocess.run(
        [sys.executable, "-m", "mypy", "--follow-imports=silent", "--no-error-summary", "--show-error-codes",
         "--cache-dir", str(tmp_path / "cache"), *files],
        cwd=tmp_path, env=env, capture_output=True, text=True)
    assert result.returncode == 0, result.stdout + result.stderr


def test_the_stubs_describe_the_module():
    """The generated stub names what the module exports and types what the README calls."""
    stub = (Path(handsim._core.__file__).parent / "_core" / "__init__.pyi").read_text()
    for name in handsim._core.__all__ if hasattr(handsim._core, "__all__") else []:
        assert name in stub
    for needle in ("class World:", "def body_grasp(self, body", "class HandFrame:", "def make_hand_frame("):
        assert needle in stub
