"""Shaded perspective pictures from the viewer's scene description (:mod:`handsim.view.raster`).

    python -m handsim.view.pictures --out out/demo     the demo's pictures (what ``make demo`` writes)
    python -m handsim.view.pictures --doc docs         docs/img/view_hand.png, view_grasp.png (hand, grasp pages)
    python -m handsim.view.pictures --out out/demo --doc docs    both, and the demo's filmstrip and close-ups
                                                       copied to docs/img/view_filmstrip.png, view_closeup_lip.png

The demo pictures: ``filmstrip.png`` (eight moments of the open and the close), ``demo.gif`` (the whole session),
``closeup_lip.png`` (the thumb under the lid's lip as the grasp begins, and while it swings the lid), and
``lid_angle.png`` with ``summary.txt``. Nothing is written without --out or --doc.
"""
from __future__ import annotations

import argparse
import math
import shutil
import sys
import time
from pathlib import Path
from typing import List

import numpy as np

from .. import _core
from . import raster
from .scene import Describer, Frame

STRIP_SIZE = (480, 360)
GIF_SIZE = (400, 300)


def overview_camera(box, world, width, height) -> raster.Camera:
    """The user's view of the jewelry box: from in front (+Z, where the user stands), to the left and above,
    so that the left hand holding the base's left side and the right hand at the lid's front lip are both in
    sight; aimed at a fixed point above the base, so the picture does not move when the lid does."""
    base = np.asarray(world.body_pose(box.base), float)[:3]
    target = base + [0.0, 0.08, 0.0]
    return raster.Camera(target + [-0.25, 0.24, 0.38], target, fov_deg=38, width=width, height=height)


def lip_camera(box, world, width, height) -> raster.Camera:
    """Close to the lid's front lip, from in front, a little to the right and just below the lid, looking
    up under the lip: the right thumb's pad under it and the fingers on top are both in sight."""
    front = np.asarray(box.lid_front(world), float)
    return raster.Camera(front + [0.10, -0.02, 0.21], front + [0.0, -0.004, 0.0], fov_deg=45, width=width,
                         height=height)


def _slim(frame: Frame) -> Frame:
    """The frame with float32 vertices: a demo keeps a few hundred of them."""
    for m in frame.meshes:
        m.vertices = np.asarray(m.vertices, np.float32)
    return frame


def demo(out_dir: Path, gif_every: int = 6) -> int:
    """Runs the demo session and writes its pictures into `out_dir`. Returns 0 when both tasks succeed."""
    from .. import demo as _demo
    from ..plots import save_figure
    from ..render import pyplot
    from PIL import Image

    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    kept: List[tuple] = []           # (what the caption says, Frame, overview camera)
    lip_frames: List[tuple] = []     # (caption, Frame, close-up camera) while the right hand holds the lid
    record = {"t": [], "angle": [], "violation": []}
    state = {"describer": None, "n": 0, "step_s": 0.0}

    def on_step(s):
        world = s.bench.world
        if state["describer"] is None or state["describer"].world is not world:
            state["describer"] = Describer(world, _demo.names(s.bench, s.box))
        d = state["describer"]
        d.names = {b: n for n, b in _demo.names(s.bench, s.box).items()}
        state["n"] += 1
        state["step_s"] += s.step_seconds
        record["t"].append(s.t)
        record["angle"].append(s.lid_deg)
        record["violation"].append(s.violation)
        g = world.body_grasp(s.box.lid)
        right_holds_lid = g.grasped and g.primary == s.bench.right
        # the moment the right hand's grasp of the lid begins, and every few degrees of the swing after it
        lip_moment = s.task == "open" and right_holds_lid and (not lip_frames or s.lid_deg - lip_frames[-1][0]["lid"] >= 8)
        if state["n"] % gif_every == 0 or lip_moment:
            f = _slim(d.frame())
            info = {"t": s.t, "task": s.task, "lid": s.lid_deg, "held": right_holds_lid}
            if state["n"] % gif_every == 0:
                kept.append((info, f, overview_camera(s.box, world, *GIF_SIZE)))
            if lip_moment:
                lip_frames.append((info, f, lip_camera(s.box, world, 640, 480)))

    t0 = time.perf_counter()
    results = _demo.run(on_step)
    sim_s = time.perf_counter() - t0

    def caption(info):
        what = "right hand holds the lid" if info["held"] else ("opening" if info["task"] == "open" else "closing")
        return f"{info['task']}  t = {info['t']:.2f} s  lid {info['lid']:.0f}°: {what}"

    t1 = time.perf_counter()
    # filmstrip: eight moments spread over the session
    keys = [kept[int(i)] for i in np.linspace(0, len(kept) - 1, 8)]
    tiles = [raster.render(f, raster.Camera(**{**cam.__dict__, "width": STRIP_SIZE[0], "height": STRIP_SIZE[1]}),
                           title=caption(info), labels=False) for info, f, cam in keys]
    strip = np.concatenate([np.concatenate(tiles[:4], 1), np.concatenate(tiles[4:], 1)], 0)
    strip_path = raster.save_png(strip, out_dir / "filmstrip.png")

    # GIF of the whole session at 60 / gif_every frames per second of simulated time, played at real speed
    images = [Image.fromarray(raster.render(f, cam, supersample=1, title=caption(info), labels=False))
              for info, f, cam in kept]
    gif_path = out_dir / "demo.gif"
    images[0].save(gif_path, save_all=True, append_images=images[1:], duration=int(1000 * gif_every / 60), loop=0)

    # close-ups of the lip: the grasp as it begins, and mid-swing
    shots = [lip_frames[0], lip_frames[min(len(lip_frames) - 1, 4)]] if lip_frames else []
    # no shadows this close: the overhead light's shadow of the fingers falls on the tops at a grazing angle
    close = [raster.render(f, cam, labels=False, shadows=False,
                           title=f"t = {info['t']:.2f} s, lid {info['lid']:.0f}°: thumb under the lip, fingers on top")
             for info, f, cam in shots]
    close_path = raster.save_png(np.concatenate(close, 1), out_dir / "closeup_lip.png") if close else None
    render_s = time.perf_counter() - t1

    plt = pyplot()
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(7, 5), sharex=True)
    a1.plot(record["t"], record["angle"])
    a1.axhline(80, ls=":", c="g")
    a1.axhline(5, ls=":", c="g")
    a1.set_ylabel("lid angle (deg)")
    a2.semilogy(record["t"], np.maximum(record["violation"], 1e-17))
    a2.set_ylabel("hinge violation (m)")
    a2.set_xlabel("time (s)")
    plot_path = out_dir / "lid_angle.png"
    save_figure(fig, plot_path, dpi=100)

    ok = all(r.success for r in results)
    lines = [f"handsim {_core.__version__}: jewelry box, two hands, open then close (simulated user, exact method)"]
    lines += [f"  {r.task}: {'success' if r.success else 'FAILED'} in {r.seconds:.2f} s" for r in results]
    lines += [f"  overall: {'success' if ok else 'failure'}",
              f"  max hinge violation: {max(record['violation']):.2e} m",
              f"  {state['n']} steps, {1e3 * state['step_s'] / state['n']:.3f} ms per step (World.step wall time)",
              f"  pictures: {len(kept)} frames kept, rendered in {render_s:.1f} s (simulation {sim_s:.1f} s)"]
    (out_dir / "summary.txt").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    print(f"pictures: {strip_path}, {gif_path}, {close_path}, {plot_path}; summary: {out_dir / 'summary.txt'}")
    return 0 if ok else 1


# ---- docs pictures ------------------------------------------------------------------------------------------

def _hand_world(curl=0.0):
    world = _core.World(_core.WorldDef(ground=False))
    hand = world.add_hand(_core.HandDef(handedness=_core.Handedness.RIGHT))
    frame = _core.make_hand_frame(_core.Handedness.RIGHT, [0, 0.3, 0, 0, 0, 0, 1], curl=curl)
    world.step(1 / 60, {hand: frame})
    return world, hand


def docs(doc_dir: Path) -> List[Path]:
    """docs/img/view_hand.png (the skinned hand and its particles by part) and view_grasp.png (the demo's
    grasp of the lid, touching particles in red)."""
    img_dir = Path(doc_dir) / "img"
    written = []
    world, _ = _hand_world()
    skin = Describer(world, particles="none").frame()
    parts = Describer(world, particles="part").frame()
    lo, hi = skin.bounds()
    tiles = []
    for f, direction, title in ((skin, (0.2, 0.9, 0.5), "skinned render mesh (39,099 vertices)"),
                                (parts, (0.2, 0.9, 0.5), "1,182 particles: grey palm, red thumb, orange index,"),
                                (parts, (0.3, -0.9, 0.4), "green middle, blue ring, purple little (palm side)")):
        cam = raster.look_at_bounds(lo, hi, direction=direction, fov_deg=30, width=560, height=460, margin=1.0)
        tiles.append(raster.render(f, cam, title=title, shadows=False))
    written.append(raster.save_png(np.concatenate(tiles, 1), img_dir / "view_hand.png"))

    from .. import demo as _demo
    grabbed = {}

    def on_step(s):
        if "frame" in grabbed or s.task != "open":
            return
        held = s.bench.world.body_grasp(s.box.lid).grasped
        if held and s.lid_deg > 12:
            d = Describer(s.bench.world, _demo.names(s.bench, s.box), particles="contact")
            grabbed["frame"] = d.frame()
            grabbed["cams"] = (overview_camera(s.box, s.bench.world, 640, 480),
                               lip_camera(s.box, s.bench.world, 640, 480))

    _demo.run(on_step, tasks=(("open", 3),))
    f = grabbed["frame"]
    ov, lip = grabbed["cams"]
    tiles = [raster.render(f, ov, title="held (gold outline): the lid by the right hand, the base by the left"),
             raster.render(f, lip, labels=False, shadows=False,
                           title="touching particles (red): thumb under the lip, fingers on top")]
    written.append(raster.save_png(np.concatenate(tiles, 1), img_dir / "view_grasp.png"))
    for p in written:
        print(f"wrote {p}")
    return written


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m handsim.view.pictures", description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", type=Path, help="write the demo's pictures into this folder")
    ap.add_argument("--doc", type=Path, help="write docs pictures into DOC/img (e.g. --doc docs)")
    args = ap.parse_args(argv)
    if args.out is None and args.doc is None:
        ap.error("nothing to do: give --out DIR and/or --doc DIR")
    status = 0
    if args.out is not None:
        status |= demo(args.out)
    if args.doc is not None:
        docs(args.doc)
        if args.out is not None:  # both: the demo's filmstrip and close-ups go to the docs too
            for name in ("filmstrip", "closeup_lip"):
                target = args.doc / "img" / f"view_{name}.png"
                shutil.copyfile(args.out / f"{name}.png", target)
                print(f"wrote {target}")
    return status


if __name__ == "__main__":
    sys.exit(main())
