"""Full-step cost per scene (issue 11): the lean, scene-driven pipeline against the paper's pipeline.

Scenes, built with the shared builders: "jewelry_box" (build_jewelry_box, the right hand reaching its pinch
from in front and closing it in the warm-up, then pinching the lid via lid_pinch_palm while the angle grows, the
left hand beside the base), "free_box" (one hand resting on one free box on
the ground, swaying), "far_hand" (one hand a metre away from every object) and
"ten_objects" (ten boxes on the ground, the hand resting on one). Sweeps: "particles_sweep" (one still hand
resting 3 mm deep on a static box, 100 .. 10,000 particles) and "render_sweep" (the same, 1k .. 100k render
vertices, the render mesh read after every step).

Pipelines: "lean" = WorldDef() (culling, render skinning only when read, closed-form particle contacts);
"paper" = WorldDef(paper_pipeline=True, particle_contacts=BULLET_OBJECTS) (every stage every step, render mesh
skinned every step, particles as Bullet objects, Ceres LM joints when built with Ceres).

Each row: median and p99 of world.step (time.perf_counter around the call, single thread, after warm-up) and the
median of every stage's C++ time (the StepReport World.step returns). "render_read_*" is a second pass over the same frames
that reads every hand's render vertices after the step (for lean that is where render skinning happens).
A full run (not --quick) also writes docs/img/step_scaling.png and regenerates docs/performance.md.
"""
import math
import os
import platform
import time
from pathlib import Path

import numpy as np

import handsim

from . import format_table, write_doc
from ..plots import save_figure
from ..quat import quat_rotate

DT = 1 / 60
PIPELINES = ("lean", "paper")
SCENES = ("jewelry_box", "free_box", "far_hand", "ten_objects")
PARTICLE_SWEEP = (100, 300, 1182, 3000, 10000)
RENDER_SWEEP = (1000, 3000, 10000, 39000, 100000)
DEFAULT_PARTICLES = 1182
DEFAULT_RENDER = 39000
BOX_HALF = 0.05
OPEN_DEG = 90.0  # scene (a): the pinch angle grows from 0 to this over the timed frames
# Scene (a)'s warm-up: the right hand reaches its pinch open from REACH_M in front of it (away from the hinge) over
# REACH_FRAMES, closes it (closing_grip, 0.25 s) and holds still CLOSED_FRAMES, so the grasp forms as a hand's does: a
# hand that appeared already pinching, particle centres inside the lid, begins no grasp of it (docs/grasp.md,
# "The appeared rule").
REACH_M, REACH_FRAMES, CLOSING_FRAMES, CLOSED_FRAMES = 0.03, 10, 15, 5
SETTLE = REACH_FRAMES + CLOSING_FRAMES + CLOSED_FRAMES


def world_def(pipeline, render_threads=1):
    if pipeline == "paper":
        return handsim.WorldDef(paper_pipeline=True, particle_contacts=handsim.ParticleContacts.BULLET_OBJECTS)
    return handsim.WorldDef(render_threads=render_threads)


def _hand(world, handedness, particles, render):
    return world.add_hand(handsim.HandDef(handedness=handedness, particle_count=particles, render_vertices=render))


def _lowest_offset(world, hand, handedness, palm_y=0.5):
    """How far the lowest particle centre sits below the palm joint of a flat, palm-down hand."""
    probe = handsim.make_hand_frame(handedness, [0, palm_y, 0, 0, 0, 0, 1])
    world.step(DT, {hand: probe})
    return palm_y - float(world.hand_particles(hand)[:, 1].min())


def _pressing(world, hand, target, frames_total, sway_m=0.01):
    """Frames of a flat right hand resting on `target` (x, top_y, z of a box top): its lowest particles 3 mm
    into the box, swaying 1 cm sideways over a 60-frame cycle (the box may end up held and carried)."""
    x, top_y, z = target
    drop = _lowest_offset(world, hand, handsim.Handedness.RIGHT)

    def frame(i):
        sway = sway_m * math.sin(2 * math.pi * (i % 60) / 60)
        # fingers along -Z: put the palm a little behind the box centre so the fingers lie over it
        palm = [x + sway, top_y + drop - 0.003, z + 0.04, 0, 0, 0, 1]
        return {hand: handsim.make_hand_frame(handsim.Handedness.RIGHT, palm)}
    return frame


def _box(world, x, z=0.0, mass=0.5):
    return world.add_body(handsim.BodyDef(shape=handsim.Shape.box([BOX_HALF] * 3), mass=mass,
                                          pose=[x, BOX_HALF, z, 0, 0, 0, 1]))


def build(scene, pipeline, particles=DEFAULT_PARTICLES, render=DEFAULT_RENDER, frames_total=300, render_threads=1):
    """(world, hands, frame_fn, warmup): frame_fn(i) gives the step's {HandId: HandFrame} for timed frame i."""
    world = handsim.World(world_def(pipeline, render_threads))
    R, L = handsim.Handedness.RIGHT, handsim.Handedness.LEFT
    if scene == "jewelry_box":
        box = handsim.build_jewelry_box(world)
        right, left = _hand(world, R, particles, render), _hand(world, L, particles, render)
        shape = handsim.lid_pinch_shape()
        d = box.definition
        base = world.body_pose(box.base)[:3]
        # the left hand palm down beside the base, on its -X side, fingers reaching towards the base
        left_palm = [base[0] - d.base_half_extents[0] - 0.07, base[1], base[2] + 0.05, 0, 0, 0, 1]
        left_frame = handsim.make_hand_frame(L, left_palm)

        base_orientation = world.body_pose(box.base)[3:]

        def frame(i):
            if i >= 0:  # timed: the pinch swings the lid open
                angle = math.radians(OPEN_DEG) * min(1.0, i / frames_total)
                palm, params = box.lid_pinch_palm(world, R, angle), shape
            else:  # warm-up, i = -SETTLE .. -1: reach open, close, hold
                k = i + SETTLE
                palm = np.asarray(box.lid_pinch_palm(world, R, 0.0), float)
                palm[:3] += quat_rotate(base_orientation, [0.0, 0.0, REACH_M * max(0.0, 1 - k / REACH_FRAMES)])
                params = handsim.closing_grip(shape, max(0, k - REACH_FRAMES) * DT)
            return {right: handsim.make_hand_frame(R, palm, params=params), left: left_frame}
        return world, [right, left], frame, SETTLE, box.lid
    if scene == "far_hand":
        _box(world, 0.0)
        hand = _hand(world, R, particles, render)
        far = handsim.make_hand_frame(R, [2.0, 1.5, 2.0, 0, 0, 0, 1])
        return world, [hand], (lambda i: {hand: far}), 5, None
    sway = 0.01
    if scene == "free_box":
        body = _box(world, 0.0)
    elif scene in ("particles_sweep", "render_sweep"):
        body = _box(world, 0.0, mass=0.0)  # static, the hand still: the same contact patch every frame
        sway = 0.0
    elif scene == "ten_objects":
        bodies = [_box(world, 0.15 * (k % 5), 0.15 * (k // 5)) for k in range(10)]
        body = bodies[0]
    else:
        raise ValueError(f"unknown scene {scene!r}")
    hand = _hand(world, R, particles, render)
    return world, [hand], _pressing(world, hand, (0.0, 2 * BOX_HALF, 0.0), frames_total, sway), 10, body


def measure(scene, pipeline, particles=DEFAULT_PARTICLES, render=DEFAULT_RENDER, frames=300, read_frames=None):
    world, hands, frame, warmup, watched = build(scene, pipeline, particles, render, frames)
    for i in range(-warmup, 0):
        world.step(DT, frame(i))
    inputs = [frame(i) for i in range(frames)] if scene != "jewelry_box" else None
    times = np.empty(frames)
    stages = {}
    touching, grasped = [], 0
    for i in range(frames):
        f = inputs[i] if inputs is not None else frame(i)
        t0 = time.perf_counter()
        report = world.step(DT, f)
        times[i] = time.perf_counter() - t0
        for r in report.stages:
            stages.setdefault(r.name, []).append(r.seconds)
        if watched is not None:
            touching.append(sum(world.body_contact_count(watched, h) for h in hands))
            grasped += bool(world.body_grasp(watched).grasped)
    # second pass: the same kind of frames, every hand's render mesh read after the step
    reads = np.empty(read_frames or max(20, frames // 3))
    for i in range(len(reads)):
        world.step(DT, inputs[i % frames] if inputs is not None else frame(min(i, frames - 1)))
        t0 = time.perf_counter()
        for h in hands:
            world.hand_render_vertices(h)
        reads[i] = time.perf_counter() - t0
    model = world.hand_model(hands[0])
    return {"scene": scene, "pipeline": pipeline, "particles": int(model.particle_count),
            "render_vertices": int(model.vertex_count), "hands": len(hands), "frames": frames,
            "median_s": float(np.median(times)), "p99_s": float(np.percentile(times, 99)),
            "stages": {k: float(np.median(v)) for k, v in stages.items()},
            "render_read_median_s": float(np.median(reads)), "render_read_p99_s": float(np.percentile(reads, 99)),
            "touching_particles_median": float(np.median(touching)) if touching else 0.0,
            "grasped_frames": grasped}


def render_threads(frames, threads=(1, 2)):
    """Scene (a), lean: median time to read both render meshes after a step, with 1 and 2 skinning threads
    (WorldDef.render_threads; the vertices are bit-identical, see tests/cpp/test_world.cpp)."""
    out = {}
    for n in threads:
        world, hands, frame, warmup, _ = build("jewelry_box", "lean", frames_total=frames, render_threads=n)
        for i in range(-warmup, 0):
            world.step(DT, frame(i))
        reads = np.empty(frames)
        for i in range(frames):
            world.step(DT, frame(i))
            t0 = time.perf_counter()
            for h in hands:
                world.hand_render_vertices(h)
            reads[i] = time.perf_counter() - t0
        out[str(n)] = float(np.median(reads))
    return out


def _load():
    try:
        return os.getloadavg()[0]
    except OSError:
        return None


def run(quick=False, doc=None):
    frames = 40 if quick else 400
    sweep_frames = 30 if quick else 240
    load_before = _load()
    t_start = time.perf_counter()
    steps = []
    for scene in SCENES:
        for p in PIPELINES:
            steps.append(measure(scene, p, frames=frames))
    for n in (PARTICLE_SWEEP if not quick else (100, 1182, 3000)):
        for p in PIPELINES:
            steps.append(measure("particles_sweep", p, particles=n, frames=sweep_frames))
    for v in (RENDER_SWEEP if not quick else (1000, 39000)):
        for p in PIPELINES:
            steps.append(measure("render_sweep", p, render=v, frames=sweep_frames, read_frames=sweep_frames))
    threads = render_threads(sweep_frames)
    from . import scaling
    result = {"steps": steps, "ratios": ratios(steps), "render_threads_read_median_s": threads,
              "scaling": scaling.run(quick),
              "quick": quick, "frames": frames,
              "sweep_frames": sweep_frames, "machine": f"{platform.machine()} {platform.processor()}".strip(),
              "cpu_count": os.cpu_count(), "load_average": [load_before, _load()],
              "wall_s": time.perf_counter() - t_start}
    if doc is not None:
        write_report(result, doc)
    return result


def _key(s):
    return (s["scene"], s["particles"], s["render_vertices"])


def ratios(steps):
    """paper / lean median step time for every configuration measured with both pipelines."""
    by = {}
    for s in steps:
        by.setdefault(_key(s), {})[s["pipeline"]] = s
    out = []
    for (scene, n, v), pair in by.items():
        if "lean" in pair and "paper" in pair:
            out.append({"scene": scene, "particles": n, "render_vertices": v,
                        "paper_over_lean": pair["paper"]["median_s"] / pair["lean"]["median_s"],
                        "paper_over_lean_with_render": (pair["paper"]["median_s"] + pair["paper"]["render_read_median_s"])
                        / (pair["lean"]["median_s"] + pair["lean"]["render_read_median_s"])})
    return out


def _us(s):
    return f"{s * 1e6:.1f}"


STAGE_ORDER = ("skinning", "contacts", "deformation", "grasp", "attach", "pose_fit", "dynamics", "joints", "slip")


def _rows(result, markdown=False):
    rows = []
    for s in result["steps"]:
        top = sorted(s["stages"].items(), key=lambda kv: -kv[1])[:3]
        rows.append((s["scene"], s["pipeline"], s["hands"], s["particles"], s["render_vertices"],
                     _us(s["median_s"]), _us(s["p99_s"]), _us(s["render_read_median_s"]),
                     f"{s['touching_particles_median']:.0f}",
                     ", ".join(f"{k} {_us(v)}" for k, v in top)))
    return ["scene", "pipeline", "hands", "particles", "render verts", "step median us", "step p99 us",
            "render read us", "touching", "top stages (median us)"], rows


def _ratio_rows(result):
    return ["scene", "particles", "render verts", "paper/lean step", "paper/lean step+render read"], [
        (r["scene"], r["particles"], r["render_vertices"], f"{r['paper_over_lean']:.1f}x",
         f"{r['paper_over_lean_with_render']:.1f}x") for r in result["ratios"]]


def table(result):
    h, rows = _rows(result)
    rh, rr = _ratio_rows(result)
    load = result["load_average"]
    from . import scaling
    return (f"full step, one thread ({result['frames']} frames per scene, {result['sweep_frames']} per sweep point; "
            f"load average {load[0]:.2f} -> {load[1]:.2f})\n" + format_table(h, rows) + "\n\n" + format_table(rh, rr)
            + "\n\nscaling (issue 25)\n" + format_table(*scaling.table_rows(result["scaling"])) + "\n\n"
            + format_table(*scaling.goal_rows(result["scaling"])))


# --- the report (docs/performance.md and docs/img/step_scaling.png) -------------------------------------

def markdown_table(headers, rows):
    out = ["| " + " | ".join(map(str, headers)) + " |", "|" + "---|" * len(headers)]
    out += ["| " + " | ".join(map(str, r)) + " |" for r in rows]
    return "\n".join(out)


def plot(result, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (a, b) = plt.subplots(1, 2, figsize=(11, 4.2))
    for p, style in (("lean", "o-"), ("paper", "s--")):
        rows = sorted((s for s in result["steps"] if s["scene"] == "particles_sweep" and s["pipeline"] == p),
                      key=lambda s: s["particles"])
        n = [s["particles"] for s in rows]
        a.loglog(n, [s["median_s"] * 1e3 for s in rows], style, label=f"{p}: full step")
        a.loglog(n, [s["stages"].get("contacts", 0) * 1e3 for s in rows], style, alpha=0.5,
                 label=f"{p}: contacts stage")
        rows = sorted((s for s in result["steps"] if s["scene"] == "render_sweep" and s["pipeline"] == p),
                      key=lambda s: s["render_vertices"])
        v = [s["render_vertices"] for s in rows]
        b.loglog(v, [(s["median_s"] + s["render_read_median_s"]) * 1e3 for s in rows], style,
                 label=f"{p}: step + render read")
        b.loglog(v, [s["render_read_median_s"] * 1e3 for s in rows], style, alpha=0.5, label=f"{p}: render read")
    a.set(xlabel="particles per hand", ylabel="median ms", title="particle sweep (one still hand on a static box)")
    b.set(xlabel="render vertices per hand", ylabel="median ms", title="render sweep (mesh read every step)")
    for ax in (a, b):
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    save_figure(fig, path, dpi=110)


def _find(result, scene, pipeline, particles=DEFAULT_PARTICLES, render=None):
    for s in result["steps"]:
        if s["scene"] == scene and s["pipeline"] == pipeline and s["particles"] == particles and \
                (render is None or abs(s["render_vertices"] - render) < 0.2 * render):
            return s
    return None


def _verdict(value, target):
    r = value / target
    return ("met" if r <= 1 else f"missed by {100 * (r - 1):.0f}%" if r < 2 else f"missed by {r:.1f}x") + f" ({_us(value)} us vs {_us(target)} us)"


def write_report(result, docs):
    # Sections other benchmarks write into this file (peers, sweeps with --doc) are kept as they are.
    from . import kept_sections
    text = kept_sections(Path(docs) / "performance.md", report(result))
    write_doc(docs, "performance.md", "step_scaling.png", plot, text, result)


def report(result):
    load = result["load_average"]
    a_lean, a_paper = _find(result, "jewelry_box", "lean"), _find(result, "jewelry_box", "paper")
    c_lean = _find(result, "far_hand", "lean")
    lines = []
    w = lines.append
    w("# Performance: the full step, lean against the paper's pipeline")
    w("")
    w("Generated by `python -m handsim.bench step --doc docs` (a full run) from")
    w("`python/handsim/bench/step.py`. Do not edit by hand.")
    w("")
    w(f"Machine: {result['machine'] or 'unknown'}, {result['cpu_count']} cores, shared with other jobs: the 1-minute "
      f"load average was **{load[0]:.2f}** at the start and **{load[1]:.2f}** at the end of the run "
      f"({result['wall_s']:.0f} s). Every time below is single-threaded and, on a machine this loaded, an "
      "**upper bound**: other processes take the core away mid-step, which shows most in the p99 column.")
    w("")
    w("Method: each scene is built with the shared builders (`build_jewelry_box`, `lid_pinch_palm`, "
      "`make_hand_frame`), warmed up, then `world.step(1/60, frames)` is timed with `time.perf_counter` for "
      f"{result['frames']} frames ({result['sweep_frames']} per sweep point). Stage times are medians of "
      "the `StepReport` `World.step` returns (C++ clocks). \"render read\" is a second pass that reads every hand's "
      "`hand_render_vertices` after the step: in the lean pipeline that is where render skinning happens; the "
      "paper pipeline skins the render mesh inside the step (stage `skinning`) and the read is a copy. "
      "\"touching\" is the median number of particle contacts on the scene's watched body (the lid, the box).")
    w("")
    w("- **lean**: `WorldDef()` — a hand whose coarse bounds (from its bones, before skinning) are far from every "
      "body leaves its particles unskinned until read, and a hand near one skins only the particle runs whose "
      "bone-derived box comes within contact reach of a body; particles skinned in runs of one bone set "
      "(structure of arrays, an AVX2 clone chosen at load time); a sweep-and-prune broadphase of hand-body pairs "
      "and bounds culling of particle runs before the closed-form particle contacts; render skinning only when "
      "read; closed-form hard joints; Bullet skipped in frames where no dynamic body is awake.")
    w("- **paper**: `WorldDef(paper_pipeline=True, particle_contacts=ParticleContacts.BULLET_OBJECTS)` — every "
      "stage every step, render mesh skinned every step, one Bullet collision object per particle, Ceres LM joints "
      "(when built with Ceres).")
    w("")
    w("## Targets (issue 11)")
    w("")
    rows = []
    if a_lean:
        rows.append(("scene (a) jewelry box, 2 hands x 1,182 particles, full step without render skinning, median",
                     "<= 100 us", _verdict(a_lean["median_s"], 100e-6)))
        rows.append(("render skinning 2 x ~39k vertices (lean: hand_render_vertices of both hands after the step, "
                     "numpy copy included)", "<= 200 us", _verdict(a_lean["render_read_median_s"], 200e-6)))
        if a_paper:
            copy_only = a_paper["render_read_median_s"]  # the paper pipeline skinned inside the step: a copy
            diff = a_lean["render_read_median_s"] - copy_only
            rows.append(("  the same without the numpy copy (lean read - paper read, which is a copy only)", "<= 200 us",
                         _verdict(diff, 200e-6) if diff > 0 else
                         f"not measured in this run: the copy alone ({_us(copy_only)} us) took longer than the lean "
                         f"read ({_us(a_lean['render_read_median_s'])} us), i.e. noise"))
            in_step = a_paper["stages"]["skinning"] - a_lean["stages"]["skinning"]
            rows.append(("  the same from the C++ clocks of scene (a) (paper skinning stage - lean skinning stage; "
                         "the paper's Bullet contacts evict the skinning data from the caches every step)",
                         "<= 200 us", _verdict(max(in_step, 0), 200e-6)))
    c_paper = _find(result, "far_hand", "paper")
    if c_lean and c_paper:
        # Scene (c) has no Bullet particle objects to evict the caches, so its paper-minus-lean skinning stage is
        # the render skinning of one hand with warm caches.
        per_hand = c_paper["stages"]["skinning"] - c_lean["stages"]["skinning"]
        rows.append(("  the same from the C++ clocks of scene (c) (paper skinning stage - lean skinning stage, one "
                     "hand, x 2)", "<= 200 us", _verdict(max(2 * per_hand, 0), 200e-6)))
    if c_lean:
        rows.append(("scene (c) one hand far from every object, median", "<= 20 us",
                     _verdict(c_lean["median_s"], 20e-6)))
    lin = _linearity(result)
    rows.append(("cost linear in touching particles, not in all particles", "-", lin))
    w(markdown_table(["target", "goal", "measured"], rows))
    w("")
    if a_lean and a_paper:
        w(f"Scene (a): lean {_us(a_lean['median_s'])} us against paper {_us(a_paper['median_s'])} us per step "
          f"({a_paper['median_s'] / a_lean['median_s']:.1f}x); with the render meshes read every frame "
          f"{_us(a_lean['median_s'] + a_lean['render_read_median_s'])} us against "
          f"{_us(a_paper['median_s'] + a_paper['render_read_median_s'])} us. The lid was grasped in "
          f"{a_lean['grasped_frames']} / {a_lean['frames']} lean frames and {a_paper['grasped_frames']} / "
          f"{a_paper['frames']} paper frames.")
        w("")
    w("## Where the time goes (median us per stage)")
    w("")
    stage_names = [n for n in STAGE_ORDER if any(n in s["stages"] for s in result["steps"])]
    srows = []
    for s in result["steps"]:
        if s["scene"] in SCENES:
            srows.append([s["scene"], s["pipeline"], _us(s["median_s"])] +
                         [_us(s["stages"].get(n, 0.0)) for n in stage_names] +
                         [_us(s["median_s"] - sum(s["stages"].values()))])
    w(markdown_table(["scene", "pipeline", "step"] + stage_names + ["outside stages"], srows))
    w("")
    w("\"outside stages\" is (approximately: a difference of medians) the step time measured from Python minus the sum of the stage clocks: the binding "
      "(converting the hand frames), input validation and the stage bookkeeping.")
    w("")
    w(_stage_prose(result))
    w("")
    w(_reading(result))
    w("")
    thr = result.get("render_threads_read_median_s")
    if thr:
        w("## Multi-threaded render skinning")
        w("")
        w("Scene (a), lean, both render meshes read after every step (numpy copy included), "
          "`WorldDef(render_threads=n)`: " + ", ".join(f"{n} thread(s) {_us(v)} us" for n, v in thr.items()) +
          ". The vertices are bit-identical to one thread (`LeanPipeline.ThreadedRenderSkinningIsBitIdentical`, "
          "`HandSkinning.ThreadedRenderSkinningIsBitIdenticalToOneThread`). " +
          ("Here the second thread made the read slower: it is started per read and, on 2 cores shared with "
           "other jobs, waits for a core. " if thr.get("2", 0) > thr.get("1", 0) else
           "The threads are started per read, so the gain is bounded by that start-up. ") +
          "Every other figure here is one thread.")
        w("")
    w("## All measurements")
    w("")
    h, r = _rows(result)
    w(markdown_table(h, r))
    w("")
    w("## Paper / lean")
    w("")
    h, r = _ratio_rows(result)
    w(markdown_table(h, r))
    w("")
    w("## Scaling")
    w("")
    w("![step time against particle count and render vertex count](img/step_scaling.png)")
    w("")
    w("## Below the stages: perf")
    w("")
    w("`scripts/profile [scene] [frames]` records the lean step of a scene with `perf` (from `linux-perf`) and "
      "prints the hottest functions. Before this work, scene (a) spent most of its time in the per-particle "
      "skinning loop (`skin_points`, a 3x4 matrix product and a gather per influence per particle), in "
      "`pose_hand`'s strided min/max over the 3 x N particle matrix and its copy of tracked into deformed positions, "
      "in `collide_particles` over every particle of a hand near a body, in re-validating the frames, and in "
      "allocations. Each of those is now either vectorized (runs of one bone set), fused into the skinning loop "
      "(each run's box), skipped (far hands, far runs, the deformed copy when nothing was pushed) or done once. "
      "Frame validation also built an argument name per joint (three strings, every step); it now builds them only "
      "for a bad joint. After all this, the same profile of scene (a) has no dominant per-step function: apart "
      "from the setup (model building), its samples spread over the Python loop, Bullet's substeps, the hinge "
      "joint and small allocations, each a few percent at most.")
    w("")
    sc = result.get("scaling")
    if sc:
        from . import scaling
        w("## Scaling: cost follows what is touched (issue 25)")
        w("")
        w("From the same run (`python/handsim/bench/scaling.py`): every world built first, then timed in "
          f"{sc['rounds']} interleaved rounds of {sc['block']} steps; a figure is the median over rounds of the "
          "block medians. \"particles in reach\" is how many particles the skinning stage skinned because their "
          "group's bone-derived box came within contact reach of a body; \"Bullet\" whether the dynamics stage "
          "ran Bullet or skipped it (no dynamic body awake).")
        w("")
        w(markdown_table(*scaling.goal_rows(sc)))
        w("")
        w(markdown_table(*scaling.table_rows(sc)))
        w("")
        w("- hover: a still hand 2 cm over a static box, nothing touching; far_hand: one hand 3 m from N settled "
          "5 cm boxes; no_hand: N settled or static boxes and no hand; hands: 1-4 hands, each over its own box.")
        w("- A settled world costs the step's bookkeeping only: Bullet is not stepped when no dynamic body is "
          "awake, nothing was written to it and no moving kinematic body is near a dynamic one.")
        w("")
    w("<!-- section peers -->")
    w("<!-- /section peers -->")
    w("")
    w("<!-- section peers_instructions -->")
    w("<!-- /section peers_instructions -->")
    w("")
    # Hand-written analyses (per-session profiles, what was cut and why) live in marked sections too, so a
    # regeneration keeps them where they are instead of dropping every line it does not generate.
    w("<!-- section peers_notes -->")
    w("<!-- /section peers_notes -->")
    w("")
    w("<!-- section sweeps -->")
    w("<!-- /section sweeps -->")
    w("")
    w("<!-- section sweeps_notes -->")
    w("<!-- /section sweeps_notes -->")
    w("")
    w("## The particle count")
    w("")
    w("The error-against-run-time study of the particle count (100 to every exposed vertex, both samplings) is "
      "in [performance_particles.md](performance_particles.md) (`python -m handsim.bench particles --doc docs --assets ../shared/assets/leap_recordings`).")
    w("")
    return "\n".join(lines)


def _linearity(result):
    rows = {s["particles"]: s for s in result["steps"] if s["scene"] == "particles_sweep" and s["pipeline"] == "lean"}
    if len(rows) < 2:
        return "not measured"
    lo, hi = rows[min(rows)], rows[max(rows)]
    grow_all = hi["particles"] / lo["particles"]
    grow_touch = max(hi["touching_particles_median"], 1) / max(lo["touching_particles_median"], 1)
    grow_contacts = hi["stages"].get("contacts", 0) / max(lo["stages"].get("contacts", 1e-9), 1e-9)
    grow_step = hi["median_s"] / lo["median_s"]
    per = ", ".join(f"{n}: {r['stages'].get('contacts', 0) * 1e9 / max(r['touching_particles_median'], 1):.0f}"
                    for n, r in sorted(rows.items()))
    verdict = ("missed: the contacts stage grows with all particles of a hand near a body"
               if grow_contacts > 3 * max(grow_touch, 1) else "met")
    return (f"{verdict}. {lo['particles']} -> {hi['particles']} particles ({grow_all:.0f}x all; touching "
            f"{lo['touching_particles_median']:.0f} -> {hi['touching_particles_median']:.0f}): contacts stage "
            f"{grow_contacts:.1f}x, full step {grow_step:.1f}x (lean). Contacts stage per touching particle, ns: {per}")


def _reading(result):
    """Data-driven remarks on the rows the targets depend on."""
    out = ["Reading the numbers:", ""]
    a, c = _find(result, "jewelry_box", "lean"), _find(result, "far_hand", "lean")
    b, d = _find(result, "free_box", "lean"), _find(result, "ten_objects", "lean")
    if c:
        out.append(f"- Scene (c): the hand's coarse bounds are far from the box, so stage `skinning` only poses the "
                   f"26 bones ({_us(c['stages']['skinning'])} us) and leaves the 1,182 particles for a read; contacts "
                   f"{_us(c['stages'].get('contacts', 0))} us. What remains is the dynamics stage (the one box, "
                   f"asleep once it has rested for 2 s, the median frame: {_us(c['stages']['dynamics'])} us) and the "
                   f"binding (~{_us(c['median_s'] - sum(c['stages'].values()))} us outside the stages).")
    if a:
        out.append(f"- Scene (a): particle skinning of 2 x 1,182 particles is {_us(a['stages']['skinning'])} us "
                   f"of the {_us(a['median_s'])} us step (the issue's naive figure is ~48 us); contacts "
                   f"{_us(a['stages']['contacts'])} us, Bullet `dynamics` {_us(a['stages']['dynamics'])} us.")
    if b:
        out.append(f"- free_box: median touching particles {b['touching_particles_median']:.0f}, grasped in "
                   f"{b['grasped_frames']} / {b['frames']} frames" +
                   (": the swaying hand pushes the free box out from under itself (it slides ~10 cm along +Z within the first second), so this row "
                    "mostly measures a hand next to a box, not pressing it." if b["touching_particles_median"] == 0
                    else "."))
    if d:
        top = max(d["stages"], key=d["stages"].get)
        out.append(f"- ten_objects: `dynamics` takes {_us(d['stages']['dynamics'])} us for ten free boxes (Bullet "
                   "runs only in frames where one of them is awake); the largest stage is "
                   f"`{top}` ({_us(d['stages'][top])} us), and the hand stages barely change from free_box.")
    out.append("- The paper pipeline's cost is mostly `contacts` (one Bullet collision object per particle, "
               "collided against every body every step) and, per hand, skinning the ~39k-vertex render mesh "
               "every step whether it is read or not.")
    out.append("- p99 values in the milliseconds are the shared machine preempting the benchmark, not the step; "
               "on this shared machine medians of consecutive full runs can differ by up to ~2x, so a target met or "
               "missed by less than that is within the noise.")
    return "\n".join(out)


def _stage_prose(result):
    out = []
    for scene in SCENES:
        for p in PIPELINES:
            s = _find(result, scene, p)
            if not s:
                continue
            total = sum(s["stages"].values()) or 1e-12
            top = sorted(s["stages"].items(), key=lambda kv: -kv[1])[:2]
            out.append(f"- {scene}, {p}: " + ", ".join(f"`{k}` {100 * v / total:.0f}%" for k, v in top) +
                       " of the stage time.")
    return "\n".join(out)
