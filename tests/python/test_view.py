"""The viewer's scene description, the offline renderer, viewing without side effects, and (when the 'view'
extra and Chromium are there) the real viewer in a real headless browser."""
import importlib.util
import json
import math
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

import handsim
from handsim import recording
from handsim.view import check, raster, scene


def _jewelry_world():
    world = handsim.World(handsim.WorldDef())
    box = handsim.build_jewelry_box(world)
    hand = world.add_hand(handsim.HandDef(handedness=handsim.Handedness.RIGHT))
    return world, box, hand


def _lid_pinch(world, box, lift=0.0, t=handsim.GRIP_CLOSING_S):
    """The lid pinch, `t` s after the hand began to close it (closing_grip)."""
    palm = box.lid_pinch_palm(world, handsim.Handedness.RIGHT, 0.0, lift)
    return handsim.make_hand_frame(handsim.Handedness.RIGHT, palm,
                                   params=handsim.closing_grip(handsim.lid_pinch_shape(), t))


def _pinch_recording(steps=40):
    """The right hand closes on the lid's lip and lifts it a little: a hand and the box in contact."""
    rec = recording.Recorder("jewelry_box", hands=[handsim.HandDef(handedness=handsim.Handedness.RIGHT)])
    box = rec.scene.box
    for i in range(steps):
        rec.step(1 / 60, {rec.hands[0]: _lid_pinch(rec.world, box, lift=0.0004 * i, t=i / 60)})
    return rec.recording


def test_import_handsim_does_not_import_viser():
    code = "import sys, handsim, handsim.view, handsim.view.scene; print('viser' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


def test_describe_reads_without_changing_the_world():
    """Same state hash, step by step, with a Describer reading the world after every step and without."""
    hashes = []
    for viewing in (False, True):
        world, box, hand = _jewelry_world()
        d = scene.Describer(world, {"base": box.base, "lid": box.lid, "hinge": box.hinge}, particles="all")
        h = []
        for i in range(30):
            world.step(1 / 60, {hand: _lid_pinch(world, box, 0.001 * i)})
            if viewing:
                d.frame()
                scene.Describer(world, particles="part").frame()
            h.append(world.state_hash())
        hashes.append(h)
    assert hashes[0] == hashes[1]


def test_frame_has_hand_box_contacts_and_hinge():
    world, box, hand = _jewelry_world()
    names = {"base": box.base, "lid": box.lid, "hinge": box.hinge, "table": box.table}
    d = scene.Describer(world, names)
    for i in range(20):
        world.step(1 / 60, {hand: _lid_pinch(world, box)})
        f = d.frame()
    meshes = {m.name: m for m in f.meshes}
    model = world.hand_model(hand)
    assert meshes["hand_right"].vertices.shape == (model.vertex_count, 3)
    assert np.array_equal(meshes["hand_right"].triangles, model.triangles)
    assert {"base", "lid", "table"} <= set(meshes)
    # the contacts are the core's: as many red particles as body_contact_count says
    touching = sum(world.body_contact_count(b, hand) for b in world.bodies())
    assert touching > 0
    shown = sum(len(p.positions) for p in f.points if p.name.startswith("contacts_"))
    assert shown == touching
    parts, points, normals, depths = world.body_contacts(box.lid, hand)
    assert len(parts) == world.body_contact_count(box.lid, hand)
    assert np.isfinite(depths).all() and np.isfinite(points).all()
    assert np.allclose(np.linalg.norm(normals, axis=1), 1)
    # hinge: axis, limit arc from 0 to 90 degrees, current value
    s = world.joint_state(box.hinge)
    assert np.allclose(s.anchor, box.hinge_pivot(world)) and np.allclose(s.axis, box.hinge_axis(world))
    assert s.lower == pytest.approx(0.0) and s.upper == pytest.approx(math.pi / 2)
    assert {"hinge/axis", "hinge/limits", "hinge/value"} <= {ln.name for ln in f.lines}
    assert f.joint_values["hinge"] == pytest.approx(s.value)


def test_grasped_body_is_highlighted_and_events_are_labelled():
    world, box, hand = _jewelry_world()
    d = scene.Describer(world, {"base": box.base, "lid": box.lid, "hinge": box.hinge})
    grasped_frame = None
    for i in range(60):
        world.step(1 / 60, {hand: _lid_pinch(world, box, 0.0005 * i, i / 60)})
        f = d.frame()
        if world.body_grasp(box.lid).grasped and grasped_frame is None:
            grasped_frame = f
    assert grasped_frame is not None, "the pinch should grasp the lid"
    lid = next(m for m in grasped_frame.meshes if m.name == "lid")
    assert lid.color != scene.BODY_COLOURS["lid"] and grasped_frame.grasped == {"lid": "right"}
    outline = next(ln for ln in grasped_frame.lines if ln.name == "lid/edges")
    assert outline.color == scene.GRASPED
    assert any("right grasps lid" in lab.text for lab in grasped_frame.labels)


def test_particle_parts_cover_every_finger():
    model = handsim.HandModel(handsim.HandDef())
    parts = scene.particle_parts(model)
    assert len(parts) == model.particle_count
    assert set(np.unique(parts)) == set(range(len(scene.PARTS)))


def test_describer_rejects_a_bad_mode():
    world, _, _ = _jewelry_world()
    with pytest.raises(ValueError, match="particles"):
        scene.Describer(world, particles="rainbow")


def test_shapes_tessellate_closed():
    for shape in (handsim.Shape.box([0.1, 0.2, 0.3]), handsim.Shape.sphere(0.1), handsim.Shape.capsule(0.05, 0.1),
                  handsim.Shape.convex_hull(np.random.default_rng(1).normal(size=(30, 3)))):
        v, t, _ = scene.shape_mesh(shape)
        edges = {}
        for a, b, c in t:
            for e in ((a, b), (b, c), (c, a)):
                edges[e] = edges.get(e, 0) + 1
        # closed and consistently oriented: every directed edge once, and its reverse once
        assert all(n == 1 and (e[1], e[0]) in edges for e, n in edges.items()), shape
        # ... and outward: the signed volume it encloses is positive
        volume = np.einsum("ij,ij->i", v[t[:, 0]], np.cross(v[t[:, 1]], v[t[:, 2]])).sum() / 6
        assert volume > 0, shape


def test_camera_rejects_bad_arguments():
    with pytest.raises(ValueError, match="camera.position"):
        raster.Camera([0, float("nan"), 0], [0, 0, 0])
    with pytest.raises(ValueError, match="camera.target"):
        raster.Camera([0, 0, 0], [0, 0, 0])
    with pytest.raises(ValueError, match="fov"):
        raster.Camera([0, 0, 1], [0, 0, 0], fov_deg=0)


def test_render_puts_the_hand_and_box_where_the_camera_sees_them():
    """The offline renderer's picture passes the same check the browser screenshot must pass."""
    world, box, hand = _jewelry_world()
    for i in range(10):
        world.step(1 / 60, {hand: _lid_pinch(world, box)})
    f = scene.Describer(world, {"base": box.base, "lid": box.lid, "table": box.table}).frame()
    from handsim.view.viewer import default_camera
    cam = default_camera(f, 400, 300)
    img = raster.render(f, cam)
    assert img.shape == (300, 400, 3) and img.dtype == np.uint8
    expected = check.expected_masks(f, cam)
    cov = check.coverage(img, expected)
    assert check.passes(cov), cov
    # and a picture without the hand fails it: the check can fail
    no_hand = scene.Frame(f.time, [m for m in f.meshes if m.kind != "hand"], [], [], [], {}, {})
    assert not check.passes(check.coverage(raster.render(no_hand, cam), expected))


# ---- the real viewer -------------------------------------------------------------------------------------

# Only these need the 'view' extra; the scene description and the offline renderer above run without it.
needs_viser = pytest.mark.skipif(importlib.util.find_spec("viser") is None,
                                 reason="the 'view' extra (viser) is not installed")


@needs_viser
def test_viewer_does_not_change_the_simulation():
    from handsim.view.viewer import Viewer
    rec = _pinch_recording(30)
    plain = recording.replay(rec)
    world, sc, hands = recording.build_world(rec)
    with Viewer(world, sc.objects, port=0) as v:
        hashes = []
        for i in range(rec.steps):
            world.step(float(rec.dt[i]), rec.inputs(i, hands))
            v.update()
            hashes.append(world.state_hash())
    assert np.array_equal(np.asarray(hashes, np.uint64), rec.hashes)
    assert plain.matches and v.frames_sent == rec.steps


@needs_viser
def test_viewer_rejects_a_bad_port_and_mode():
    from handsim.view.viewer import Viewer
    world, _, _ = _jewelry_world()
    with pytest.raises(ValueError, match="port"):
        Viewer(world, port=-1)
    with pytest.raises(ValueError, match="particles"):
        Viewer(world, port=0, particles="rainbow")


@needs_viser
def test_replay_app_seeks_back_and_forth_to_the_same_state():
    from handsim.view.replay import ReplayApp
    rec = _pinch_recording(30)
    recording.replay(rec)
    app = ReplayApp(rec, "pinch", step=0, playing=False, port=0)
    try:
        app.seek(25)
        assert app.world.state_hash() == int(rec.hashes[25])
        app.seek(7)  # backwards: rebuilt and replayed
        assert app.world.state_hash() == int(rec.hashes[7])
        app.seek(10_000)  # clamped
        assert app.index == rec.steps - 1 and app.world.state_hash() == int(rec.hashes[-1])
    finally:
        app.close()
    with pytest.raises(ValueError, match="step"):
        ReplayApp(rec, step=rec.steps, port=0)


@needs_viser
def test_view_command_rejects_bad_input(tmp_path):
    from handsim.view.__main__ import main
    assert main([str(tmp_path / "missing.npz")]) == 2
    bad = tmp_path / "bad.npz"
    bad.write_bytes(b"not a zip")
    assert main([str(bad), "--port", "0", "--seconds", "0"]) == 2


@needs_viser
def test_browser_shows_the_hand_and_the_box(tmp_path):
    """The viewer on a recording, opened in headless Chromium: the screenshot shows the skin where the hand
    should be and the box's teal where the box should be (recall and precision of each, check.py)."""
    from handsim.view.browser import find_chromium
    if find_chromium() is None:
        pytest.fail("Chromium is missing: scripts/setup installs it (apt chromium)")
    path = tmp_path / "pinch.npz"
    _pinch_recording(40).save(path)
    shot = tmp_path / "shot.png"
    t0 = time.monotonic()
    out = subprocess.run([sys.executable, "-m", "handsim.view", str(path), "--port", "0", "--step", "39",
                          "--screenshot", str(shot), "--size", "960x600"],
                         capture_output=True, text=True, timeout=240)
    assert out.returncode == 0, out.stdout + out.stderr
    assert shot.is_file()
    cov = json.loads(out.stdout.split("coverage: ", 1)[1].splitlines()[0])  # printed by --screenshot
    assert check.passes(cov), cov
    assert time.monotonic() - t0 < 240


@needs_viser
def test_view_command_opens_a_bvh_and_a_leap_recording(tmp_path):
    """Tracker input goes through replay.session_from_motion into the same replay app (served 0 s)."""
    from handsim.adapters.bvh import write_bvh
    from handsim.view.__main__ import main
    frames = [handsim.make_hand_frame(handsim.Handedness.RIGHT, [0, 0.9, -0.2, 0, 0, 0, 1], curl=0.02 * i)
              for i in range(20)]
    bvh = write_bvh(tmp_path / "hand.bvh", frames)
    assert main([str(bvh), "--port", "0", "--seconds", "0", "--paused"]) == 0
    root = os.environ.get("HANDSIM_SHARED_ASSETS") or Path(__file__).resolve().parents[3] / "shared" / "assets"
    leap = Path(root) / "leap_recordings" / "pinch.json.lz"
    if leap.is_file():  # the shared assets are optional: without them only the BVH is opened
        assert main([str(leap), "--port", "0", "--seconds", "0", "--scene", "free_box"]) == 0
