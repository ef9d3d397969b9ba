"""Replays every Leap recording of a folder near the jewelry box and a free cube and prints the results of
``docs/input.md``: ``python -m handsim.input_report --assets DIR [--doc docs/input.md] [--img docs/img]``
(``--assets ../shared/assets/leap_recordings`` for the 12 recordings the docs use; files are written only where
``--doc`` and ``--img`` say).

For each recording it runs :func:`handsim.replay.session_from_motion` on both scenes (60 Hz, the placement
rule of :mod:`handsim.replay`), checks the expectations of :func:`expectations`, draws one PNG (key frames of
both scenes and a timeline) and rewrites the table between the ``<!-- results -->`` markers of the doc.
"""
from __future__ import annotations

import argparse
import dataclasses
import math
import sys
import time
from pathlib import Path
from typing import Dict, List

import numpy as np

from . import _core
from . import render as _render
from . import replay as _replay
from .plots import save_figure
from .adapters import skeleton as _sk
from .adapters.leap import fit_side, read_leap_document, read_leap_json, without_skeleton

BEGIN, END = "<!-- results begin -->", "<!-- results end -->"
HINGE_TOLERANCE_M = 1e-6
SAME_HAND_M = 0.02  # a rebuilt hand of a side with its palm this near the skeleton's is that hand (the rebuild's palm error is 4 mm at most)


def expectations(motion: "_replay.Motion", jewelry: "_replay.Summary", free: "_replay.Summary") -> Dict[str, bool]:
    """What a person watching the recording would expect, as named checks (all must be True):

    * always: every body pose finite; the hinge holds (violation <= 1e-6 m) and the lid stays within its
      0..90 deg limits;
    * a recording with a closing hand (Leap grab or pinch strength >= 0.95): that hand grasps the cube, the
      first time as it closes (not before it began to close, and not open: strength at least OPEN), and no hand
      grasps the cube while open;
    * a recording without one: nothing is grasped, neither the cube (which the hand brushes) nor the lid."""
    out = {"finite": jewelry.finite and free.finite,
           "hinge holds": jewelry.max_hinge_violation_m <= HINGE_TOLERANCE_M,
           "lid within limits": -0.5 <= jewelry.max_lid_deg <= 90.5}
    start = _replay.closure_start(motion)
    if start is not None:
        side = _replay.closing_hand(motion)[0]
        frames = _replay.step_frames(motion)
        grasps = [(int(frames[i]), hand) for i, body, hand in free.grasp_log if body == "box"]
        own = [k for k, hand in grasps if hand == side]
        out["cube grasped by the closing hand"] = bool(own)
        out["as it closes"] = bool(own) and motion.times[own[0]] >= start and \
            _replay.hand_strength(motion, side, own[0]) >= _replay.OPEN
        out["no grasp by an open hand"] = all(_replay.hand_strength(motion, hand, k) >= _replay.OPEN
                                              for k, hand in grasps)
    else:
        out["no grasp of the cube"] = not free.grasps
        out["no grasp of the lid"] = not jewelry.grasps
    return out


def _figure(path: Path, name: str, motion, runs):
    plt = _render.pyplot()
    fig = plt.figure(figsize=(12, 7.2))
    grid = fig.add_gridspec(3, 4, height_ratios=[1, 1, 1])
    for row, (rec, summary, store) in enumerate(runs):
        if rec.scene == "jewelry_box":
            centre, axes = _replay._default_lid_front() + [0, 0.04, -0.05], (2, 1)
        else:
            centre, axes = np.asarray(rec.scene_params["position"], float) + [0, 0.05, 0], (0, 1)
        for k, snap in enumerate(store["snaps"][:4]):
            ax = fig.add_subplot(grid[row, k])
            _render.draw(ax, snap, centre, half_width=0.16, axes=axes)
            if k == 0:
                ax.set_ylabel("jewelry box, side" if rec.scene == "jewelry_box" else "free cube, front", fontsize=8)
    ax = fig.add_subplot(grid[2, :])
    (jrec, jsum, jstore), (frec, fsum, fstore) = runs
    t = np.asarray(jstore["trace"]["t"])
    ax.plot(t, jstore["trace"]["lid"], color="darkgoldenrod", label="lid angle (deg)")
    tf = np.asarray(fstore["trace"]["t"])
    ax.plot(tf, 10 * np.asarray(fstore["trace"]["lift"]), color="tab:green", label="cube lift (mm)")
    for store, colour, label in ((jstore, "darkgoldenrod", "lid grasped"), (fstore, "tab:green", "cube grasped")):
        g = np.asarray(store["trace"]["grasped"], bool)
        tt = np.asarray(store["trace"]["t"])
        if g.any():
            ax.fill_between(tt, 0, 1, where=g, transform=ax.get_xaxis_transform(), color=colour, alpha=0.15,
                            label=label)
    ax2 = ax.twinx()
    for col, side, colour in ((0, "right", "tab:blue"), (1, "left", "tab:red")):
        if motion.grab is not None and not np.all(np.isnan(motion.grab[:, col])):
            ax2.plot(motion.times, motion.grab[:, col], ":", color=colour, lw=1, label=f"Leap grab, {side}")
            ax2.plot(motion.times, motion.pinch[:, col], "--", color=colour, lw=0.8, label=f"Leap pinch, {side}")
    ax2.set_ylim(-0.05, 1.05)
    ax2.set_ylabel("Leap strength", fontsize=8)
    ax2.legend(fontsize=7, loc="upper right")
    ax.set_xlabel("time (s)")
    ax.legend(fontsize=7, loc="upper left")
    fig.suptitle(f"{name}: blue right hand, red left; key frames at 0, 1/3, 2/3 and the end", fontsize=10)
    save_figure(fig, path, dpi=72)


def replay_on_both_scenes(motion, name: str = "", hand_defs=None, reach: float = _replay.REACH) -> list:
    """(recording, summary, store) of `motion` replayed near the jewelry box and near the free cube, in the
    order expectations() takes them; `hand_defs` and `reach` as for replay.session_from_motion (default hands
    if None)."""
    runs = []
    for scene in ("jewelry_box", "free_box"):
        rec = _replay.session_from_motion(motion, scene, hand_defs=hand_defs, reach=reach)
        store = {}
        runs.append((rec, _replay.run(rec, name, motion=motion, store=store), store))
    return runs


def rebuild_error(doc: dict, name: str = "recording") -> dict:
    """How far the hands of a formatVersion 0.1/1 document land from their skeleton when the adapter gets them
    as a Leap SDK before 2.0 sent them (adapters.leap.without_skeleton): the share of hands given the right
    side (the rebuilt hand of that side has its palm within SAME_HAND_M of the skeleton's), and over those,
    the largest palm joint distance and each fingertip's median distance (mm); None for a recording without
    hands."""
    stripped = without_skeleton(doc)
    ref, bare = read_leap_json(doc, name), read_leap_json(stripped, name)
    tips = [_core.THUMB_TIP, _core.INDEX_TIP, _core.MIDDLE_TIP, _core.RING_TIP, _core.LITTLE_TIP]
    # the side rules frame by frame, against the types the stripped hands had: the finger fit (hands with at
    # least 3 fingers) and the device side
    fit, device = [], []
    for fr, fr_bare in zip(doc["frames"], stripped["frames"]):
        for hand, bare_hand in zip(fr.get("hands", []), fr_bare["hands"]):
            own = [p for p in fr_bare["pointables"] if p.get("handId") == bare_hand.get("id")]
            side = fit_side(bare_hand, own)
            if side is not None:
                fit.append(side == hand.get("type"))
            device.append((bare_hand["palmPosition"][0] < 0) == (hand.get("type") == "left"))
    right, palm, dist = [], [], []
    for a, b in zip(ref.frames, bare.frames):
        for side, fa in a.items():
            pa = np.asarray(fa.frame.positions)
            pb = np.asarray(b[side].frame.positions) if side in b else np.full_like(pa, np.inf)
            right.append(np.linalg.norm(pa[_core.PALM] - pb[_core.PALM]) < SAME_HAND_M)
            if right[-1]:
                palm.append(np.linalg.norm(pa[_core.PALM] - pb[_core.PALM]))
                dist.append(np.linalg.norm(pa[tips] - pb[tips], axis=1))
    if not palm:
        return None
    return {"hands": len(right), "side_right": float(np.mean(right)), "palm_max_mm": 1000 * float(np.max(palm)),
            "tip_median_mm": (1000 * np.median(dist, axis=0)).tolist(),
            "fit_side_right": (int(np.sum(fit)), len(fit)), "device_side_right": (int(np.sum(device)), len(device))}


def strength_agreement(motion: "_replay.Motion") -> dict:
    """The closing hand and closure start (replay's rules) from Leap's strengths and from the skeleton's
    (replay.with_strengths on the motion without Leap's): what a tracker without strengths would get."""
    bare = _replay.with_strengths(dataclasses.replace(motion, grab=None, pinch=None))
    out = {}
    for key, m in (("leap", motion), ("skeleton", bare)):
        c = _replay.closing_hand(m)
        out[key] = None if c is None else (c[0], c[1], _replay.closure_start(m))
    return out


def label_agreement(leap) -> Dict[str, tuple]:
    """How the skeleton's strengths (skeleton.closure_strengths, max(grab, pinch)) label the frames that Leap's own
    label (the judge's labels, handsim.intent.labels: closed >= 0.9, open < 0.3), every hand of every frame:
    {"closed": (agreeing, of), "open": (agreeing, of)}."""
    from . import intent
    leap_s, skel_s = [], []
    for i, f in enumerate(leap.frames):
        for side, a in f.items():
            col = 0 if side == "right" else 1
            leap_s.append(np.nanmax([leap.grab[i, col], leap.pinch[i, col]]))
            skel_s.append(max(_sk.closure_strengths(a.frame)))
    (lc, lo), (sc, so) = intent.labels(np.array(leap_s)), intent.labels(np.array(skel_s))
    return {"closed": (int(np.sum(lc & sc)), int(np.sum(lc))), "open": (int(np.sum(lo & so)), int(np.sum(lo)))}


def label_table(rows) -> str:
    """Per recording, the share of Leap's labelled frames that the skeleton's strengths label the same."""
    pct = lambda k_n: f"{100 * k_n[0] / k_n[1]:.1f} % of {k_n[1]}" if k_n[1] else "–"
    out = ["| recording | closed (Leap ≥ 0.9) | open (Leap < 0.3) | all labelled |", "|---|---:|---:|---:|"]
    for r in rows:
        a = r["labels"]
        both = (a["closed"][0] + a["open"][0], a["closed"][1] + a["open"][1])
        out.append(f"| {r['name']} | {pct(a['closed'])} | {pct(a['open'])} | {pct(both)} |")
    return "\n".join(out)


def strength_calibration(rows) -> str:
    """The ranges of the skeleton's closure measures (adapters.skeleton.closure_measures) over every hand of
    every recording, where Leap called it open or closed (grab <= OPEN or >= CLOSED) and not pinching or
    pinching (pinch <= OPEN or >= CLOSED): where Leap draws its lines, for comparison with the anchors."""
    flex = {"open": [], "closed": []}
    gap = {"open": [], "pinching": []}
    for r in rows:
        leap = r["leap"]
        for i, f in enumerate(leap.frames):
            for side, a in f.items():
                col = 0 if side == "right" else 1
                share, pulps = _sk.closure_measures(a.frame)
                g, p = leap.grab[i, col], leap.pinch[i, col]
                for store, key, value, low, high in ((flex, ("open", "closed"), share, g, g),
                                                     (gap, ("open", "pinching"), pulps, p, p)):
                    if low <= _replay.OPEN:
                        store[key[0]].append(value)
                    elif high >= _replay.CLOSED:
                        store[key[1]].append(value)
    span = lambda v, scale=1.0, digits=2: f"{scale * min(v):.{digits}f}–{scale * max(v):.{digits}f}" if v else "–"
    return (f"Skeleton closure measures where Leap's strengths are decided (grab or pinch ≤ {_replay.OPEN} or "
            f"≥ {_replay.CLOSED}), every hand of every recording: grab angle as a share of make_hand_frame's fist "
            f"open {span(flex['open'])}, closed {span(flex['closed'])} (the skeleton's grab is that share); "
            f"thumb–finger pulp gap not pinching {span(gap['open'], 1000, 0)} mm, pinching "
            f"{span(gap['pinching'], 1000, 0)} mm (the skeleton's pinch: 1 at 0 mm, the pulps touching, 0 at the "
            f"flat hand's {1000 * _sk._anchors()[1]:.0f} mm).")


def run_all(assets: Path, img: Path = None, reach: float = _replay.REACH) -> List[dict]:
    rows = []
    for path in sorted(assets.glob("*.json.lz")):
        name = path.name.split(".")[0]
        c0 = time.process_time()
        doc = read_leap_document(path)
        leap = read_leap_json(doc, name)
        motion = _replay.motion_from_leap(leap)
        runs = replay_on_both_scenes(motion, name, reach=reach)
        if img is not None:
            _figure(img / f"input_{name}.png", name, motion, runs)
        checks = expectations(motion, runs[0][1], runs[1][1])
        rebuilt = rebuild_error(doc, name) if leap.format_version != 2 else None
        rows.append({"name": name, "leap": leap, "motion": motion, "jewelry": runs[0][1], "free": runs[1][1],
                     "placement": runs[1][0].info["placement"], "checks": checks, "rebuilt": rebuilt,
                     "strengths": strength_agreement(motion), "labels": label_agreement(leap),
                     "cpu_s": time.process_time() - c0})
    return rows


def table(rows) -> str:
    out = ["| recording | fmt | frames | s | hands | Leap grab / pinch max | jewelry box: grasps, lid max, hinge "
           "violation max | free cube: placement | free cube: grasps (first at), held, lift | expectations |",
           "|---|---|---:|---:|---|---|---|---|---|---|"]
    for r in rows:
        leap, j, f = r["leap"], r["jewelry"], r["free"]
        hands = ", ".join(f"{k}:{v}" for k, v in sorted(leap.hand_counts().items()))
        hands += "".join(f"; {case}: {n}" for case, n in sorted(leap.notes.items()))  # what the adapter made up
        gp = " / ".join(f"{np.nanmax(a):.2f}" if not np.all(np.isnan(a)) else "–" for a in (leap.grab, leap.pinch))
        jg = ", ".join(f"{k} {v}" for k, v in sorted(j.grasps.items())) or "none"
        fg = (f"{f.grasps.get('box', 0)} ({f.first_grasp_s:.2f} s)" if f.grasps else "none")
        held = f.held_s.get("box", 0.0)
        failed = [k for k, ok in r["checks"].items() if not ok]
        verdict = "all met" if not failed else "NOT MET: " + ", ".join(failed)
        out.append(f"| {r['name']} | {leap.format_version} | {len(leap.frames)} | {leap.times[-1]:.2f} | {hands} | "
                   f"{gp} | {jg}; {j.max_lid_deg:.1f}°; {j.max_hinge_violation_m:.1e} m | {r['placement']} | "
                   f"{fg}; {held:.2f} s; {f.max_lift_m * 1000:.0f} mm | {verdict} |")
    return "\n".join(out)


def rebuild_table(rows) -> str:
    out = ["| recording | hands | right side | per frame: finger fit / device side right | palm joint max | "
           "fingertip median: thumb, index, middle, ring, little | closing hand, closure start: Leap's strengths "
           "/ the skeleton's |", "|---|---:|---:|---|---:|---|---|"]
    say = lambda c: "none" if c is None else f"{c[0]} {c[1]} {c[2]:.2f} s"
    share = lambda k_n: f"{k_n[0]}/{k_n[1]}"
    for r in rows:
        e, g = r["rebuilt"], r["strengths"]
        cells = ["–"] * 5 if e is None else [
            str(e["hands"]), f"{100 * e['side_right']:.1f} %",
            f"{share(e['fit_side_right'])} / {share(e['device_side_right'])}", f"{e['palm_max_mm']:.1f} mm",
            ", ".join(f"{v:.0f}" for v in e["tip_median_mm"]) + " mm"]
        out.append(f"| {r['name']} | " + " | ".join(cells) + f" | {say(g['leap'])} / {say(g['skeleton'])} |")
    return "\n".join(out)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m handsim.input_report", description=__doc__.split("\n\n")[0])
    ap.add_argument("--assets", type=Path, required=True,
                    help="folder of .json.lz recordings (the docs use ../shared/assets/leap_recordings)")
    ap.add_argument("--doc", type=Path, default=None, help="doc whose results table to rewrite (none: print only)")
    ap.add_argument("--img", type=Path, default=None, help="folder for the PNGs (none: no pictures)")
    ap.add_argument("--reach", type=float, default=_replay.REACH,
                    help=f"placement: the share of the cube's half extent the closing hand is to reach into it "
                         f"(default {_replay.REACH}); another value prints the table only (a sensitivity run)")
    args = ap.parse_args(argv)
    if not 0 < args.reach <= 2:
        print(f"error: --reach: expected a share in (0, 2], got {args.reach}", file=sys.stderr)
        return 2
    sensitivity = args.reach != _replay.REACH
    if not args.assets.is_dir() or not list(args.assets.glob("*.json.lz")):
        print(f"error: --assets: no .json.lz recordings in {args.assets}", file=sys.stderr)
        return 2
    c0 = time.perf_counter()
    rows = run_all(args.assets, None if sensitivity else args.img, args.reach)
    text = table(rows) + "\n\nPictures: " + ", ".join(f"[{r['name']}](img/input_{r['name']}.png)" for r in rows)
    text += ("\n\nThe same hands as a Leap SDK before 2.0 sent them (`adapters.leap.without_skeleton`: no types, "
             "bone joints or strengths, no curled fingers), rebuilt from the palm, against the skeleton's joints "
             "(right side: the rebuilt hand of the hand's side has its palm within 2 cm of the skeleton's; per "
             "frame: the finger fit, where at least 3 fingers are reported, and the device side alone); "
             "and the closing hand from Leap's strengths and from the skeleton's (`replay.with_strengths`; a "
             "formatVersion 2 file is not stripped):\n\n" + rebuild_table(rows))
    text += "\n\n" + strength_calibration(rows)
    text += ("\n\nLeap's open and closed labels (the judge's: max(grab, pinch) ≥ 0.9 closed, < 0.3 open) given the "
             "same by the skeleton's strengths (`skeleton.closure_strengths`), every hand of every frame:\n\n"
             + label_table(rows))
    text += (f"\n\n{len(rows)} recordings, {sum(len(r['checks']) for r in rows)} checks, "
             f"{sum(not ok for r in rows for ok in r['checks'].values())} not met; "
             f"{time.perf_counter() - c0:.0f} s wall for the whole run.")
    print(text)
    if sensitivity:
        print(f"--reach {args.reach}: the doc and the pictures are left as they are")
    elif args.doc is not None and args.doc.is_file():
        doc = args.doc.read_text()
        if BEGIN in doc and END in doc:
            a, b = doc.index(BEGIN) + len(BEGIN), doc.index(END)
            args.doc.write_text(doc[:a] + "\n" + text + "\n" + doc[b:])
            print(f"rewrote the results of {args.doc}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
