"""The virtual hand (issue 5): render skinning, particle update, particle contacts (the core's closed form vs
one Bullet object per particle, the paper's way) and the largest particle gap of both samplings.

Every figure is a median over repeated single-threaded calls. Times measured through Python include the
numpy conversion of the arguments and results; the stage times come from the StepReport World.step returns (C++ clocks).
"""
import numpy as np

import handsim

from . import format_table, summary, time_calls

DT = 1 / 60
# The box of the pressing test: top face at y = 0.
BOX_HALF = [0.2, 0.1, 0.2]
BOX_POSE = [0, -0.1, -0.05, 0, 0, 0, 1]


def _pressing_frame(world, hand, depth=0.01):
    """A flat right hand, palm down, lowered until its lowest particle centre is `depth` below y = 0."""
    world.step(DT, {hand: handsim.make_hand_frame(handsim.Handedness.RIGHT)})
    lowest = world.hand_particles(hand)[:, 1].min()
    return handsim.make_hand_frame(handsim.Handedness.RIGHT, [0, -lowest - depth, 0, 0, 0, 0, 1])


def _stage_seconds(world, hand, frames, stage, repeats):
    """Median and p99 of one stage's C++ time over `repeats` steps of `hand` cycling through `frames`."""
    out = np.empty(repeats)
    for i in range(repeats):
        report = world.step(DT, {hand: frames[i % len(frames)]})
        out[i] = next(r.seconds for r in report.stages if r.name == stage)
    return summary(out)


def bench_skinning(repeats):
    world = handsim.World(handsim.WorldDef(ground=False))
    hand = world.add_hand(handsim.HandDef())
    model = world.hand_model(hand)
    frames = [handsim.make_hand_frame(handsim.Handedness.RIGHT, [0, 0.3, 0, 0, 0, 0, 1], curl=c)
              for c in np.linspace(0, 1, 8)]
    # A step (it marks the render mesh stale), then the first call (skinning + copy into numpy) against a second call (the copy alone).
    first, copy = np.empty(repeats), np.empty(repeats)
    for i in range(repeats):
        world.step(DT, {hand: frames[i % len(frames)]})
        first[i] = time_calls(lambda: world.hand_render_vertices(hand), 1, warmup=0)[0]
        copy[i] = time_calls(lambda: world.hand_render_vertices(hand), 1, warmup=0)[0]
    return {
        "render": {"vertices": model.vertex_count, "first_call": summary(first), "copy_only": summary(copy),
                   "skinning_median_s": float(np.median(first) - np.median(copy))},
        "particles": {"particles": model.particle_count, **_stage_seconds(world, hand, frames, "skinning", repeats)},
    }


def bench_contacts(repeats):
    world = handsim.World(handsim.WorldDef(ground=False))
    hand = world.add_hand(handsim.HandDef())
    shape = handsim.Shape.box(BOX_HALF)
    world.add_body(handsim.BodyDef(shape=shape, mass=0, pose=BOX_POSE))
    frame = _pressing_frame(world, hand)
    world_stage = _stage_seconds(world, hand, [frame], "contacts", repeats)
    centres = world.hand_particles(hand)
    radius = world.hand_model(hand).particle_radius

    collider = handsim.BulletParticleCollider(len(centres), radius)
    collider.add_body(shape, BOX_POSE)
    closed = handsim.collide_particles(centres, radius, shape, BOX_POSE)
    bullet = collider.collide(centres)[0]
    same = np.array_equal(np.sort(closed["particle"]), np.sort(bullet["particle"]))
    closed_t = summary(time_calls(lambda: handsim.collide_particles(centres, radius, shape, BOX_POSE), repeats))
    bullet_t = summary(time_calls(lambda: collider.collide(centres), repeats))
    return {
        "particles": len(centres), "contacts": int(len(closed["particle"])), "press_depth_m": 0.01,
        "world_contacts_stage": world_stage,
        "closed_form": closed_t, "bullet_objects": bullet_t,
        "bullet_over_closed_form": bullet_t["median_s"] / closed_t["median_s"],
        "same_particles": bool(same),
        "max_depth_difference_m": float(np.abs(np.sort(closed["depth"]) - np.sort(bullet["depth"])).max())
        if same and len(closed["depth"]) else None,
    }


def bench_gaps(seeds):
    rows = []
    for sampling in (handsim.ParticleSampling.RANDOM, handsim.ParticleSampling.EVEN):
        for seed in (seeds if sampling == handsim.ParticleSampling.RANDOM else seeds[:1]):
            model = handsim.HandModel(handsim.HandDef(sampling=sampling, seed=seed))
            rows.append({"sampling": sampling.name, "seed": seed, "particles": model.particle_count,
                         "largest_gap_m": model.largest_particle_gap(),
                         "particle_radius_m": model.particle_radius})
    return rows


def bench_model_build(repeats):
    """World.add_hand builds its model afresh (mesh, sampling, render falloff): the default hand and the
    particle study's pick (3,000 evenly sampled particles)."""
    rows = []
    for label, d in (("default (HandDef())", handsim.HandDef()),
                     ("3,000 even", handsim.HandDef(particle_count=3000, sampling=handsim.ParticleSampling.EVEN))):
        rows.append({"hand": label, **summary(time_calls(lambda: handsim.HandModel(d), repeats, warmup=1))})
    return rows


def run(quick=False):
    repeats = 100 if quick else 1000
    return {
        "repeats": repeats,
        **bench_skinning(repeats),
        "contacts": bench_contacts(repeats),
        "gaps": bench_gaps([1] if quick else [1, 2, 3, 4, 5]),
        "model_build": bench_model_build(2 if quick else 7),
    }


def _us(seconds):
    return f"{seconds * 1e6:.1f}"


def table(result):
    r, p, c = result["render"], result["particles"], result["contacts"]
    timing = format_table(["what", "median us", "p99 us"], [
        (f"render skinning, {r['vertices']} vertices (first call - copy)", _us(r["skinning_median_s"]), "-"),
        ("  hand_render_vertices after a step", _us(r["first_call"]["median_s"]), _us(r["first_call"]["p99_s"])),
        ("  hand_render_vertices again (copy only)", _us(r["copy_only"]["median_s"]), _us(r["copy_only"]["p99_s"])),
        (f"particle update, {p['particles']} particles (stage 'skinning'; no body near: bones only)",
         _us(p["median_s"]), _us(p["p99_s"])),
        (f"contacts in the world (stage 'contacts', {c['contacts']} contacts)",
         _us(c["world_contacts_stage"]["median_s"]), _us(c["world_contacts_stage"]["p99_s"])),
        ("  closed form, collide_particles", _us(c["closed_form"]["median_s"]), _us(c["closed_form"]["p99_s"])),
        ("  Bullet objects, BulletParticleCollider", _us(c["bullet_objects"]["median_s"]),
         _us(c["bullet_objects"]["p99_s"])),
    ])
    gaps = format_table(["sampling", "seed", "particles", "largest gap mm", "radius mm"], [
        (g["sampling"], g["seed"], g["particles"], f"{g['largest_gap_m'] * 1e3:.2f}", f"{g['particle_radius_m'] * 1e3:.2f}")
        for g in result["gaps"]])
    agree = (f"same particles, depths within {c['max_depth_difference_m']:.1e} m" if c["same_particles"]
             else "DIFFERENT particles")
    build = format_table(["hand model", "median ms"], [(b["hand"], f"{b['median_s'] * 1e3:.0f}")
                                                       for b in result["model_build"]])
    return (f"virtual hand (medians of {result['repeats']} repeats, one thread)\n{timing}\n"
            f"Bullet objects / closed form: {c['bullet_over_closed_form']:.1f}x ({agree}; "
            f"{c['particles']} particles of a hand pressed {c['press_depth_m'] * 100:.0f} cm into a box)\n\n"
            f"largest particle gap (bind pose)\n{gaps}\n\nbuilding a hand model (World.add_hand)\n{build}")
