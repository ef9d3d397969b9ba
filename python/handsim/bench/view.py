"""Viewer frame rate: the jewelry box with two tracked hands (39,099 render vertices each), per frame:

* ``step``: World.step (the scripted two-hand scenario of the determinism tests);
* ``describe``: the scene description (Describer.frame: skinning both render meshes, contacts, shapes);
* ``send``: the viser viewer's update (describe + serialising and queueing the changes), no page open;
* ``send_page``: the same with a headless Chromium page open and drawing (SwiftShader, on the CPU);
* ``page_fps``: frames the page drew per second meanwhile (requestAnimationFrame callbacks);
* ``raster``: one offline picture (handsim.view.raster) at 640x480, supersampled 2x and not.

Also the installed size of viser and of what it pulls in. Skipped (with the reason) without the 'view' extra;
the page figures are skipped without Chromium.
"""
from __future__ import annotations

import importlib.metadata as md
import time

import numpy as np

import handsim as _h

REQUIRES_VIEW = "the 'view' extra (viser) is not installed"


def _world():
    world = _h.World(_h.WorldDef())
    box = _h.build_jewelry_box(world)
    hands = (world.add_hand(_h.HandDef(handedness=_h.Handedness.RIGHT)),
             world.add_hand(_h.HandDef(handedness=_h.Handedness.LEFT)))
    return world, box, hands


def _dist_size(name: str) -> int:
    try:
        files = md.distribution(name).files or []
    except md.PackageNotFoundError:
        return 0
    total = 0
    for f in files:
        try:
            total += f.locate().stat().st_size
        except OSError:
            pass
    return total


def _closure(name: str, seen=None) -> set:
    """`name` and every distribution it requires (extras left out), as installed here."""
    seen = set() if seen is None else seen
    key = name.lower().replace("_", "-")
    if key in seen:
        return seen
    try:
        reqs = md.distribution(name).requires or []
    except md.PackageNotFoundError:
        return seen
    seen.add(key)
    for r in reqs:
        if "extra ==" in r:
            continue
        dep = r.split(";")[0].strip()
        for sep in "<>=!~[ (":
            dep = dep.split(sep)[0]
        _closure(dep, seen)
    return seen


def run(quick: bool = False) -> dict:
    try:
        import viser  # noqa: F401
    except ImportError:
        return {"skipped": REQUIRES_VIEW}
    from handsim.view import raster, scene
    from handsim.view.browser import Browser, find_chromium
    from handsim.view.viewer import Viewer, default_camera

    frames = 60 if quick else 240
    world, box, hands = _world()
    names = {"base": box.base, "lid": box.lid, "hinge": box.hinge, "table": box.table}
    out = {"frames": frames, "render_vertices_per_hand": int(world.hand_model(world.hands()[0]).vertex_count)}
    t = {"step": [], "describe": [], "send": [], "send_page": []}
    i = 0

    def advance():
        nonlocal i
        c = time.perf_counter()
        world.step(1 / 60, dict(zip(hands, _h.scenario_frames(box, world, i % _h.SCENARIO_FRAMES))))  # right, left
        t["step"].append(time.perf_counter() - c)
        i += 1

    d = scene.Describer(world, names)
    for _ in range(frames):
        advance()
        c = time.perf_counter()
        d.frame()
        t["describe"].append(time.perf_counter() - c)
    with Viewer(world, names, port=0) as v:
        for _ in range(frames):
            advance()
            c = time.perf_counter()
            v.update()
            t["send"].append(time.perf_counter() - c)
        if find_chromium() is not None:
            with Browser(960, 600, timeout=60) as b:
                b.goto(v.url)
                b.wait_for("document.querySelector('canvas') !== null", timeout=60)
                time.sleep(2.0)
                b.evaluate("window.__frames = 0; (function tick(){ window.__frames++; "
                           "requestAnimationFrame(tick); })(); 0")
                c0 = time.perf_counter()
                for _ in range(frames):
                    advance()
                    c = time.perf_counter()
                    v.update()
                    t["send_page"].append(time.perf_counter() - c)
                    # 60 Hz pacing, as a live session would run
                    time.sleep(max(0.0, 1 / 60 - (time.perf_counter() - c)))
                wall = time.perf_counter() - c0
                drawn = b.evaluate("window.__frames")
                out["page_fps"] = float(drawn) / wall
                out["page_wall_s"] = wall
        else:
            out["page_skipped"] = "no Chromium"
        f = v.last_frame
    cam = default_camera(f, 640, 480)
    for ss in (1, 2):
        reps = 2 if quick else 5
        c = time.perf_counter()
        for _ in range(reps):
            raster.render(f, cam, supersample=ss)
        out[f"raster_ss{ss}_ms"] = 1e3 * (time.perf_counter() - c) / reps
    for k, v_ in t.items():
        if v_:
            a = np.asarray(v_) * 1e3
            out[f"{k}_ms"] = {"median": float(np.median(a)), "p90": float(np.percentile(a, 90))}
    sizes = {k: _dist_size(k) for k in sorted(_closure("viser"))}
    out["installed_mb"] = {"viser": sizes.get("viser", 0) / 1e6,
                           "viser_with_dependencies": sum(sizes.values()) / 1e6,
                           "dependencies": sorted(sizes)}
    return out


def table(r: dict) -> str:
    if "skipped" in r:
        return f"view: skipped ({r['skipped']})"
    rows = [("World.step (two hands, jewelry box)", r["step_ms"]),
            ("scene description (Describer.frame)", r["describe_ms"]),
            ("viewer update, no page open", r["send_ms"])]
    if "send_page_ms" in r:
        rows.append(("viewer update, headless Chromium page open", r["send_page_ms"]))
    lines = [f"viewer, {r['render_vertices_per_hand']:,} render vertices per hand, {r['frames']} frames per row",
             f"{'what':48s} {'median ms':>10s} {'p90 ms':>8s} {'frames/s':>9s}"]
    for name, s in rows:
        lines.append(f"{name:48s} {s['median']:10.2f} {s['p90']:8.2f} {1e3 / s['median']:9.0f}")
    if "page_fps" in r:
        lines.append(f"{'page redraws per second while updates arrive':48s} {'':10s} {'':8s} {r['page_fps']:9.1f}")
    lines.append(f"offline picture 640x480: {r['raster_ss1_ms']:.0f} ms, supersampled 2x {r['raster_ss2_ms']:.0f} ms "
                 f"({r['raster_ss2_ms'] / r['raster_ss1_ms']:.1f}x)")
    lines.append(f"describe / update without page: {r['describe_ms']['median'] / r['send_ms']['median']:.2f}")
    m = r["installed_mb"]
    lines.append(f"installed: viser {m['viser']:.1f} MB, with its {len(m['dependencies']) - 1} dependencies "
                 f"{m['viser_with_dependencies']:.1f} MB")
    return "\n".join(lines)
