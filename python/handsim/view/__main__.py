"""python -m handsim.view: the 3D viewer in a browser.

    python -m handsim.view FILE            a handsim recording (.npz), a Leap recording (.json.lz/.json) or a BVH
    python -m handsim.view --demo          the two-handed simulated user on the jewelry box, live

Open the printed address in a browser. The page has a timeline slider, play/pause and speed for a recording,
the lid angle and grasp state plotted beside the view, and particle colouring by contact or hand part.
``--screenshot PNG`` opens the page in headless Chromium instead, writes what it shows and exits.
"""
from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path


def _recording(path: Path, scene: str):
    from .. import recording as _rec
    from .. import replay as _replay
    if path.suffix.lower() == ".npz":
        return _rec.load(path)
    return _replay.session_from_motion(_replay.load_motion(path), scene)


def _screenshot(viewer, path: Path, width: int, height: int, timeout: float) -> int:
    from . import raster
    from .browser import Browser
    from .check import wait_until_drawn
    from .check import passes
    with Browser(width, height, timeout=timeout) as b:
        b.goto(viewer.url)
        wait_until_drawn(b, viewer, timeout)
    raster.save_png(b.page, path)  # the whole page: the 3D view (which the coverage is measured on) and controls
    print(f"screenshot: {path}")
    print(f"coverage: {json.dumps(b.coverage)}")
    if not passes(b.coverage):
        print(f"error: screenshot: the page did not show the hand and the box where expected within {timeout:.0f} s",
              file=sys.stderr)
        return 1
    return 0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m handsim.view", description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter, epilog=__doc__)
    ap.add_argument("file", nargs="?", type=Path, help=".npz (handsim), .json.lz / .json (Leap) or .bvh")
    ap.add_argument("--demo", action="store_true", help="run the simulated two-handed user live")
    ap.add_argument("--scene", choices=("jewelry_box", "free_box"), default="jewelry_box",
                    help="scene for tracker input (Leap, BVH); default jewelry_box")
    ap.add_argument("--host", default="127.0.0.1", help="address to serve on (default 127.0.0.1: this machine only)")
    ap.add_argument("--port", type=int, default=8080, help="port (default 8080; taken: the next free one; 0: any)")
    ap.add_argument("--step", type=int, default=0, help="recording: the step shown first")
    ap.add_argument("--paused", action="store_true", help="recording: do not start playing")
    ap.add_argument("--particles", choices=("contact", "all", "part", "none"), default="contact",
                    help="touching particles only (default), all, all by hand part, none")
    ap.add_argument("--seconds", type=float, default=None, help="serve this long, then exit (default: until Ctrl-C)")
    ap.add_argument("--screenshot", type=Path, help="write a headless-Chromium screenshot of the page and exit")
    ap.add_argument("--size", default="960x600", help="screenshot size WxH (default 960x600)")
    args = ap.parse_args(argv)
    if args.demo == (args.file is not None):
        ap.error("give a FILE or --demo (one of them)")
    if args.demo and args.screenshot:
        ap.error("--screenshot: takes a FILE (a recording), not --demo")
    try:
        width, height = (int(v) for v in args.size.lower().split("x"))
    except ValueError:
        ap.error(f"--size: expected WxH, e.g. 1280x800, got {args.size!r}")
    if args.file is not None and not args.file.is_file():
        print(f"error: file: no such file: {args.file}", file=sys.stderr)
        return 2
    try:
        from .viewer import _viser
        _viser()
    except ImportError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    if args.demo:
        return _demo(args, width, height)
    from .replay import ReplayApp
    try:
        rec = _recording(args.file, args.scene)
        app = ReplayApp(rec, args.file.name, step=args.step, playing=not args.paused and not args.screenshot,
                        host=args.host, port=args.port, particles=args.particles)
    except (ValueError, OSError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    try:
        if args.screenshot:
            return _screenshot(app.viewer, args.screenshot, width, height, 150.0)
        print(f"handsim viewer: {app.viewer.url}  ({args.file.name}, {rec.steps} steps; Ctrl-C to stop)", flush=True)
        app.run(args.seconds)
    except KeyboardInterrupt:
        pass
    finally:
        app.close()
    return 0


def _demo(args, width, height) -> int:
    from .. import demo
    from .viewer import Viewer
    state = {"viewer": None, "next": time.monotonic(), "frames": 0}
    end = None if args.seconds is None else time.monotonic() + args.seconds

    def on_step(s):
        v = state["viewer"]
        if v is None:
            v = state["viewer"] = Viewer(s.bench.world, demo.names(s.bench, s.box), host=args.host, port=args.port,
                                         particles=args.particles)
            print(f"handsim viewer: {v.url}  (the simulated user, live; Ctrl-C to stop)", flush=True)
        v.describer.names = {b: n for n, b in demo.names(s.bench, s.box).items()}
        v.update(f"{s.task} · lid {s.lid_deg:.1f}° · step {1e3 * s.step_seconds:.2f} ms")
        state["frames"] += 1
        # real time: one 60 Hz step per 1/60 s of wall clock (a slow machine just runs slower)
        state["next"] += 1 / 60
        time.sleep(max(0.0, state["next"] - time.monotonic()))
        if end is not None and time.monotonic() > end:
            raise KeyboardInterrupt

    try:
        while True:
            results = demo.run(on_step)
            print("  ".join(f"{r.task}: {'success' if r.success else 'FAILED'} in {r.seconds:.2f} s"
                            for r in results), flush=True)
    except KeyboardInterrupt:
        pass
    finally:
        if state["viewer"] is not None:
            state["viewer"].close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
