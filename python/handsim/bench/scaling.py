"""Scaling of the lean step (issue 25), part of ``python -m handsim.bench step``: cost should follow what is
touched, not what exists.

* ``hover``: one still right hand 2 cm above a static 10 cm box, nothing touching, 100 .. 10,000 particles:
  only the particles within reach of the box are skinned. Goal: 10,000 <= 2x 100.
* ``far_hand``: one hand 3 m from N settled boxes (N = 1 .. 1,000, asleep after 3 s): the hand-body
  broadphase and idle physics. Goal: 1,000 <= 2x 1.
* ``no_hand``: N settled (dynamic) boxes or N static boxes and no hand. Goal: 1,000 settled <= 100 us; static
  bodies cost nothing (compared with an empty world).
* ``hands``: 1, 2 and 4 hands, each hovering over its own static box.

Every world is built first; then the timing runs in rounds, each round timing a block of steps of every world
in turn (interleaved), and a world's figure is the median over rounds of its block medians.
"""
import time

import numpy as np

import handsim

DT = 1 / 60
HOVER_COUNTS = (100, 300, 1182, 3000, 10000)
BODY_COUNTS = (1, 10, 100, 1000)
HAND_COUNTS = (1, 2, 4)
HOVER_GAP = 0.02
SETTLE_FRAMES = 180  # Bullet puts a body at rest to sleep after 2 s


def _lowest_offset(world, hand, handedness):
    """How far the lowest particle centre of a flat palm-down hand sits below its palm joint."""
    probe = handsim.make_hand_frame(handedness, [0, 5.0, 0, 0, 0, 0, 1])
    world.step(DT, {hand: probe})
    return 5.0 - float(world.hand_particles(hand)[:, 1].min())


def _static_box(world, x, z=0.0, half=0.05):
    return world.add_body(handsim.BodyDef(shape=handsim.Shape.box([half] * 3), mass=0.0,
                                          pose=[x, half, z, 0, 0, 0, 1]))


def hover_world(particles, hands=1):
    """`hands` right hands, each 2 cm above its own static box, nothing touching."""
    world = handsim.World()
    R = handsim.Handedness.RIGHT
    ids = [world.add_hand(handsim.HandDef(handedness=R, particle_count=particles)) for _ in range(hands)]
    drop = _lowest_offset(world, ids[0], R)
    frames = {}
    for k, hand in enumerate(ids):
        _static_box(world, 0.5 * k)
        # fingers along -Z: the palm a little behind the box centre so the fingers lie over it
        frames[hand] = handsim.make_hand_frame(R, [0.5 * k, 0.1 + drop + HOVER_GAP, 0.04, 0, 0, 0, 1])
    return world, frames


def boxes_world(n, static=False, hand=True):
    """n boxes (5 cm) on a grid on the ground, settled; optionally one hand 3 m away."""
    world = handsim.World()
    side = int(np.ceil(np.sqrt(n)))
    for i in range(n):
        world.add_body(handsim.BodyDef(shape=handsim.Shape.box([0.025] * 3), mass=0.0 if static else 0.2,
                                       pose=[0.1 * (i % side), 0.025, 0.1 * (i // side), 0, 0, 0, 1]))
    for _ in range(SETTLE_FRAMES):
        world.step(DT)
    frames = {}
    if hand:
        R = handsim.Handedness.RIGHT
        far = world.add_hand(handsim.HandDef(handedness=R))
        frames = {far: handsim.make_hand_frame(R, [-3.0, 1.5, -3.0, 0, 0, 0, 1])}
    return world, frames


def _configs(quick):
    out = []
    for n in (HOVER_COUNTS if not quick else (100, 10000)):
        out.append(({"table": "hover", "particles": n}, lambda n=n: hover_world(n)))
    for n in (BODY_COUNTS if not quick else (1, 1000)):
        out.append(({"table": "far_hand", "bodies": n}, lambda n=n: boxes_world(n)))
    out.append(({"table": "no_hand", "bodies": 0, "kind": "empty"}, lambda: boxes_world(0, hand=False)))
    out.append(({"table": "no_hand", "bodies": 1000, "kind": "settled"}, lambda: boxes_world(1000, hand=False)))
    out.append(({"table": "no_hand", "bodies": 1000, "kind": "static"},
                lambda: boxes_world(1000, static=True, hand=False)))
    for k in (HAND_COUNTS if not quick else (1, 2)):
        out.append(({"table": "hands", "hands": k}, lambda k=k: hover_world(1182, hands=k)))
    return out


def _in_reach(world):
    """Particles skinned within reach of a body in the last step (from the skinning stage's report)."""
    return world.last_step().stage(handsim.Stage.SKINNING).particles


def run(quick=False):
    rounds, block = (3, 20) if quick else (9, 60)
    built = []
    for meta, make in _configs(quick):
        world, frames = make()
        for _ in range(5):
            world.step(DT, frames)
        built.append((meta, world, frames, []))
    for _ in range(rounds):
        for meta, world, frames, medians in built:
            t = np.empty(block)
            for i in range(block):
                t0 = time.perf_counter()
                world.step(DT, frames)
                t[i] = time.perf_counter() - t0
            medians.append(float(np.median(t)))
    rows = []
    for meta, world, frames, medians in built:
        report = world.last_step()
        dynamics = "ran" if report.bullet else ("skipped" if report.substeps else "-")
        rows.append({**meta, "median_s": float(np.median(medians)), "in_reach": _in_reach(world),
                     "dynamics": dynamics})
    return {"rows": rows, "rounds": rounds, "block": block, "goals": goals(rows)}


def _find(rows, **kw):
    for r in rows:
        if all(r.get(k) == v for k, v in kw.items()):
            return r
    return None


def goals(rows):
    """The issue's scaling goals, each with its measured figure (None when the run did not measure it)."""
    out = []

    def ratio(name, a, b, limit):
        if a and b:
            value = a["median_s"] / b["median_s"]
            out.append({"goal": name, "value": value, "limit": limit, "unit": "x", "met": value <= limit})

    ratio("hover: 10,000 particles / 100 particles", _find(rows, table="hover", particles=10000),
          _find(rows, table="hover", particles=100), 2.0)
    ratio("hand far from 1,000 bodies / from 1", _find(rows, table="far_hand", bodies=1000),
          _find(rows, table="far_hand", bodies=1), 2.0)
    settled = _find(rows, table="no_hand", kind="settled")
    if settled:
        out.append({"goal": "1,000 settled boxes, no hand", "value": settled["median_s"] * 1e6, "limit": 100.0,
                    "unit": "us", "met": settled["median_s"] * 1e6 <= 100.0})
    ratio("1,000 static boxes / empty world (no hand)", _find(rows, table="no_hand", kind="static"),
          _find(rows, table="no_hand", kind="empty"), 2.0)
    return out


def table_rows(result):
    rows = []
    for r in result["rows"]:
        what = {"hover": f"{r.get('particles')} particles",
                "far_hand": f"{r.get('bodies')} bodies",
                "no_hand": f"{r.get('bodies')} {r.get('kind')}" if r.get("bodies") else "empty world",
                "hands": f"{r.get('hands')} hand(s)"}[r["table"]]
        rows.append((r["table"], what, f"{r['median_s'] * 1e6:.1f}", r["in_reach"],
                     r["dynamics"]))
    return ["table", "configuration", "step median us", "particles in reach", "Bullet"], rows


def goal_rows(result):
    return ["goal", "measured", "limit", "met"], [
        (g["goal"], f"{g['value']:.2f} {g['unit']}", f"{g['limit']:g} {g['unit']}", "yes" if g["met"] else "no")
        for g in result["goals"]]
