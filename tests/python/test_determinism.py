"""determinism through the Python driver: the same state_hash() as the C++ golden value, in another process,
and as the native (C ABI) host driving the same scenario.
"""
import os
import pathlib
import re
import subprocess
import sys

import pytest

import handsim

ROOT = pathlib.Path(__file__).resolve().parents[2]
C_HOST = ROOT / "build" / "dev" / "tests" / "c_abi" / "c_abi_host"


def golden_hash():
    """The golden value checked in by tests/cpp/test_determinism.cpp (one source of truth)."""
    text = (ROOT / "tests" / "cpp" / "test_determinism.cpp").read_text()
    return int(re.search(r"kGoldenHash = (0x[0-9a-fA-F]+)ull", text).group(1), 16)


def run_two_hand_scenario(frames):
    """scenario_frames (scenes.h) replayed from Python: the box, a right and a left hand, 60 Hz."""
    world = handsim.World()
    box = handsim.build_jewelry_box(world)
    world.add_hand(handsim.HandDef())
    world.add_hand(handsim.HandDef(handedness=handsim.Handedness.LEFT))
    for i in range(frames):
        world.step(1 / 60, dict(zip(world.hands(), handsim.scenario_frames(box, world, i))))  # hands(): right, left
    return world.state_hash()


def test_two_hand_scenario_matches_the_cpp_golden_hash():
    assert handsim.SCENARIO_FRAMES == 1000
    assert run_two_hand_scenario(handsim.SCENARIO_FRAMES) == golden_hash()


def test_hash_is_the_same_in_another_process():
    here = run_two_hand_scenario(120)
    code = "import sys; sys.path[:0] = [sys.argv[1]]; import test_determinism as t; print(t.run_two_hand_scenario(120))"
    out = subprocess.run([sys.executable, "-c", code, str(pathlib.Path(__file__).parent)], check=True,
                         capture_output=True, text=True, env=dict(os.environ, PYTHONHASHSEED="123"))
    assert int(out.stdout.strip()) == here


def c_abi_scenario_angle(frame):
    """tests/c_abi/scenario.h, operation for operation (+, -, *, / only, so bit-identical to C)."""
    t = (frame - 20) / 120.0  # SCENARIO_SWING_FROM
    t = min(max(t, 0.0), 1.0)
    return t * (100.0 * 3.14159265358979323846 / 180.0)


def test_python_driver_matches_the_c_abi_host(tmp_path):
    if not C_HOST.exists():
        pytest.skip(f"{C_HOST} not built (scripts/build builds it)")
    out = tmp_path / "hash.txt"
    subprocess.run([str(C_HOST), str(out)], check=True, capture_output=True)
    native = int(out.read_text().strip(), 16)

    world = handsim.World()
    box = handsim.build_jewelry_box(world)
    hand = world.add_hand(handsim.HandDef())
    pinch = handsim.lid_pinch_shape()
    for i in range(160):  # SCENARIO_FRAMES of scenario.h
        palm = box.lid_pinch_palm(world, handsim.Handedness.RIGHT, c_abi_scenario_angle(i), 0.0)
        shape = handsim.closing_grip(pinch, i * (1.0 / 60.0), 0.25)  # scenario_grip_t, SCENARIO_CLOSING_S
        world.step(1.0 / 60.0, {hand: handsim.make_hand_frame(handsim.Handedness.RIGHT, palm, params=shape)})
    assert world.state_hash() == native, f"Python 0x{world.state_hash():016x} vs C ABI host 0x{native:016x}"
