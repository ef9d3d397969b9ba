"""How many particles does the hand need? Error against run time, from 100 particles to every exposed vertex.

The paper kept 1,182 of its mesh's vertices as particles without saying why. For each particle count and both
samplings (random, even) this measures, against the reference that uses every exposed vertex as a particle:

- pose fit: a free box (no gravity, no ground) pressed by a flat hand in several places, the hand's skin 2-6 mm
  into the box (the same hand poses for every count); one step; the box's velocity comes from the eq. 2 fit. Error = |v - v_ref| / |v_ref| (linear) and |w - w_ref| (angular, rad/s),
  medians over the presses.
- grasp decision: the jewelry-box lid pinch of the step benchmark (build_jewelry_box, lid_pinch_palm, the angle
  growing to 90 degrees); error = fraction of frames whose "lid grasped" differs from the reference.
- visible penetration: after each press, the deepest render vertex inside the box (the render mesh is what
  the user sees; particles only push back the vertices near them).
- step time: median world.step of a press held still (lean pipeline, one thread).

A full run writes docs/img/particle_tradeoff.png and docs/performance_particles.md (linked from
docs/performance.md); --quick measures fewer counts and writes nothing.
"""
import math
import os
import time
from pathlib import Path

import numpy as np

import handsim

from . import format_table
from . import step as step_bench

DT = 1 / 60
COUNTS = (100, 300, 1182, 3000, 10000)
QUICK_COUNTS = (100, 1182)
ALL = 10 ** 6  # clamped by the model to every exposed vertex
BOX_HALF = (0.06, 0.03, 0.06)
# (x, z offset of the palm from the box centre, depth of the lowest skin vertex m, roll rad): the presses
PRESSES = ((0.0, 0.04, 0.003, 0.0), (0.02, 0.05, 0.004, 0.0), (-0.02, 0.03, 0.002, 0.05),
           (0.01, 0.06, 0.005, -0.08), (-0.015, 0.045, 0.003, 0.12), (0.025, 0.035, 0.006, -0.04))
PINCH_FRAMES = 120
TIME_FRAMES = 120
ROOT = Path(__file__).resolve().parents[3]
R = handsim.Handedness.RIGHT


def _palm(x, y, z, roll):
    return [x, y, z, math.sin(roll / 2), 0, 0, math.cos(roll / 2)]


def _box_depth(vertices, half):
    """Deepest penetration of points (N, 3, box frame = world here) into an axis-aligned box at the origin."""
    inside = np.asarray(half) - np.abs(vertices)
    depth = inside.min(axis=1)
    return float(max(depth.max(), 0.0))


def lowest_vertex_drop():
    """How far the lowest render vertex of the flat default hand sits below its palm joint: every count presses
    with the same hand poses (placed from the skin, not from its own particles)."""
    world = handsim.World(handsim.WorldDef(ground=False))
    hand = world.add_hand(handsim.HandDef(particle_count=100))
    world.step(DT, [handsim.make_hand_frame(R, [0, 1.0, 0, 0, 0, 0, 1])])
    return 1.0 - float(world.hand_render_vertices(hand)[:, 1].min())


def press(count, sampling, drop):
    """Pose-fit velocities, visible penetration and step time of one hand of `count` particles."""
    world = handsim.World(handsim.WorldDef(gravity=[0, 0, 0], ground=False))
    hand = world.add_hand(handsim.HandDef(particle_count=count, sampling=sampling))
    box = world.add_body(handsim.BodyDef(shape=handsim.Shape.box(BOX_HALF), mass=0.5, pose=[0, 0, 0, 0, 0, 0, 1]))
    rows, frames = [], []
    for x, z, depth, roll in PRESSES:
        frame = handsim.make_hand_frame(R, _palm(x, BOX_HALF[1] + drop - depth, z, roll))
        frames.append(frame)
        world.step(DT, [])  # untracked: the hand's motion history restarts, so the fit sees a still hand
        world.set_body_pose(box, [0, 0, 0, 0, 0, 0, 1])
        world.set_body_velocity(box, [0, 0, 0], [0, 0, 0])
        world.step(DT, [frame])
        linear, angular = world.body_velocity(box)
        rows.append((np.array(linear), np.array(angular), _box_depth(world.hand_render_vertices(hand), BOX_HALF)))
    times = np.empty(TIME_FRAMES)
    for i in range(TIME_FRAMES):
        world.set_body_pose(box, [0, 0, 0, 0, 0, 0, 1])
        world.set_body_velocity(box, [0, 0, 0], [0, 0, 0])
        t0 = time.perf_counter()
        world.step(DT, [frames[0]])
        times[i] = time.perf_counter() - t0
    model = world.hand_model(hand)
    return {"particles": int(model.particle_count), "radius_m": float(model.particle_radius),
            "linear": [r[0] for r in rows], "angular": [r[1] for r in rows],
            "penetration_m": [r[2] for r in rows], "step_median_s": float(np.median(times))}


def pinch(count, sampling):
    """Per frame: is the lid grasped, along the step benchmark's lid-opening pinch."""
    world, hands, frame, warmup, lid = _jewelry_with(sampling, count)
    out = []
    for i in range(-warmup, PINCH_FRAMES):
        world.step(DT, frame(i))
        if i >= 0:
            out.append(bool(world.body_grasp(lid).grasped))
    return np.array(out)


def _jewelry_with(sampling, count):
    """The step benchmark's jewelry-box scene with hands of another sampling."""
    original = step_bench._hand

    def hand(world, handedness, particles, render):
        return world.add_hand(handsim.HandDef(handedness=handedness, particle_count=particles,
                                              render_vertices=render, sampling=sampling))
    step_bench._hand = hand
    try:
        return step_bench.build("jewelry_box", "lean", particles=count, frames_total=PINCH_FRAMES)
    finally:
        step_bench._hand = original


def run(quick=False, write=None):
    load_before = os.getloadavg()[0]
    t_start = time.perf_counter()
    samplings = (handsim.ParticleSampling.RANDOM, handsim.ParticleSampling.EVEN)
    drop = lowest_vertex_drop()
    ref_press = press(ALL, samplings[0], drop)
    ref_pinch = pinch(ALL, samplings[0])
    rows = []
    for sampling in samplings:
        for n in (QUICK_COUNTS if quick else COUNTS):
            p, g = press(n, sampling, drop), pinch(n, sampling)
            rows.append(_row(sampling.name, p, g, ref_press, ref_pinch))
    rows.append(_row("all", ref_press, ref_pinch, ref_press, ref_pinch))
    result = {"rows": rows, "quick": quick, "presses": len(PRESSES), "pinch_frames": PINCH_FRAMES,
              "reference_particles": ref_press["particles"], "reference_grasped_frames": int(ref_pinch.sum()),
              "load_average": [load_before, os.getloadavg()[0]], "wall_s": time.perf_counter() - t_start}
    result["default"] = choose_default(rows)
    if (not quick) if write is None else write:
        write_report(result)
    return result


def _row(sampling, p, g, ref_p, ref_g):
    lin = [np.linalg.norm(a - b) / max(np.linalg.norm(b), 1e-9) for a, b in zip(p["linear"], ref_p["linear"])]
    ang = [np.linalg.norm(a - b) for a, b in zip(p["angular"], ref_p["angular"])]
    return {"sampling": sampling, "particles": p["particles"], "radius_m": p["radius_m"],
            "fit_linear_rel_error": float(np.median(lin)), "fit_angular_error_rad_s": float(np.median(ang)),
            "grasp_disagreement": float(np.mean(g != ref_g)), "grasped_frames": int(g.sum()),
            "visible_penetration_m": float(max(p["penetration_m"])), "step_median_s": p["step_median_s"]}


def choose_default(rows, fit_tol=0.25, grasp_tol=0.02):
    """The cheapest row whose grasp decision and pose fit are within tolerance of the reference. The visible
    penetration is reported but not part of the rule: it is set by the render deformation's falloff, and every
    count short of all vertices leaves a few millimetres."""
    ok = [r for r in rows if r["sampling"] != "all" and r["fit_linear_rel_error"] <= fit_tol and
          r["grasp_disagreement"] <= grasp_tol]
    best = min(ok, key=lambda r: r["step_median_s"]) if ok else None
    return {"fit_tol": fit_tol, "grasp_tol": grasp_tol,
            "choice": None if best is None else {"sampling": best["sampling"], "particles": best["particles"]}}


def _headers():
    return ["sampling", "particles", "radius mm", "fit |dv|/|v|", "fit |dw| rad/s", "grasp frames differing",
            "grasped frames", "deepest visible penetration mm", "step median us"]


def _cells(r, frames):
    return (r["sampling"], r["particles"], f"{r['radius_m'] * 1e3:.2f}", f"{r['fit_linear_rel_error']:.3f}",
            f"{r['fit_angular_error_rad_s']:.3f}", f"{r['grasp_disagreement'] * 100:.1f}%",
            f"{r['grasped_frames']} / {frames}", f"{r['visible_penetration_m'] * 1e3:.2f}",
            f"{r['step_median_s'] * 1e6:.1f}")


def table(result):
    rows = [_cells(r, result["pinch_frames"]) for r in result["rows"]]
    c = result["default"]["choice"]
    return (f"particle count against error (reference: {result['reference_particles']} particles, every exposed "
            f"vertex; load {result['load_average'][0]:.2f} -> {result['load_average'][1]:.2f})\n" +
            format_table(_headers(), rows) + "\n\nchosen: " +
            ("none within tolerance" if c is None else f"{c['sampling']} {c['particles']}"))


def plot(result, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (a, b) = plt.subplots(1, 2, figsize=(11, 4.2))
    for sampling, style in (("RANDOM", "o-"), ("EVEN", "s--")):
        rows = sorted((r for r in result["rows"] if r["sampling"] == sampling), key=lambda r: r["particles"])
        t = [r["step_median_s"] * 1e6 for r in rows]
        a.semilogx(t, [r["fit_linear_rel_error"] for r in rows], style, label=f"{sampling.lower()}: fit |dv|/|v|")
        a.semilogx(t, [r["grasp_disagreement"] for r in rows], style, alpha=0.5,
                   label=f"{sampling.lower()}: grasp frames differing")
        b.semilogx(t, [r["visible_penetration_m"] * 1e3 for r in rows], style, label=sampling.lower())
        for r, x in zip(rows, t):
            a.annotate(str(r["particles"]), (x, r["fit_linear_rel_error"]), fontsize=7)
    a.set(xlabel="median step us (one hand pressing a box)", ylabel="error against every vertex",
          title="pose fit and grasp decision error")
    b.set(xlabel="median step us", ylabel="mm", title="deepest visible penetration")
    for ax in (a, b):
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def write_report(result, root=ROOT):
    img = root / "docs" / "img" / "particle_tradeoff.png"
    img.parent.mkdir(parents=True, exist_ok=True)
    plot(result, img)
    (root / "docs" / "performance_particles.md").write_text(report(result))


def report(result):
    c = result["default"]
    lines = ["# Performance: how many particles the hand needs", "",
             "Generated by `python -m handsim.bench particles` (a full run) from `python/handsim/bench/particles.py`. "
             "Do not edit by hand.", "",
             f"The 1-minute load average was **{result['load_average'][0]:.2f}** at the start and "
             f"**{result['load_average'][1]:.2f}** at the end ({result['wall_s']:.0f} s); step times are one "
             "thread and upper bounds on a machine this loaded.", "",
             f"Reference: every exposed vertex of the default ~39k-vertex mesh as a particle "
             f"({result['reference_particles']} particles). Pose fit: {result['presses']} presses of a flat hand "
             "into a free box (no gravity, no ground), one step each; the box velocity is the eq. 2 fit. Grasp: the "
             f"jewelry-box lid pinch of the step benchmark, {result['pinch_frames']} frames (the reference grasps the "
             f"lid in {result['reference_grasped_frames']}). Visible penetration: the deepest render vertex inside "
             "the box over the presses. Step: median world.step of one press held still.", "",
             "| " + " | ".join(_headers()) + " |", "|" + "---|" * len(_headers())]
    lines += ["| " + " | ".join(map(str, _cells(r, result["pinch_frames"]))) + " |" for r in result["rows"]]
    lines += ["", "![error against step time](img/particle_tradeoff.png)", ""]
    rule = (f"Rule: the cheapest configuration whose pose-fit error is <= {c['fit_tol']:.0%} and whose grasp decision "
            f"differs from the reference in <= {c['grasp_tol']:.0%} of the frames. ")
    if c["choice"]:
        lines.append(rule + f"By this run: **{c['choice']['sampling'].lower()} sampling, "
                     f"{c['choice']['particles']} particles**.")
    else:
        lines.append(rule + "No configuration below the reference met it in this run.")
    lines += ["", "Reading the table:", "",
              "- The particle radius follows the spacing (`HandDef.particle_radius = 0`), so fewer particles means "
              "bigger spheres, which reach deeper into the box for the same hand pose and ask the eq. 2 fit for a "
              "bigger push: the fit error is mostly the radius, not missing contacts.",
              "- Random sampling decides the lid grasp like the reference at every count measured; even "
              "(farthest-point) sampling misses it in many frames at some counts (its particles land on the finger "
              "pads differently), which the grasp column shows.",
              "- Step times of neighbouring rows differ by less than this machine's noise, so where the rule picks "
              "between two samplings at one count, the count is the finding, not the sampling.",
              "- The deepest visible penetration is a few millimetres at every count short of all vertices: the render "
              "mesh is pushed out only near displaced particles (falloff), so it does not choose the count.",
              "- The project default stays the paper's 1,182 random particles in this change: the issue's targets are "
              "stated for it, and moving the default changes every tuned grasp threshold and the golden hash. A "
              "count chosen by the rule above is a follow-up decision, taken from this table.", ""]
    return "\n".join(lines)
