"""The main demo: the paper's jewelry box, opened and closed by a two-handed simulated user.

The left hand holds the base; the right hand pinches the lid's lip, swings it open and lets go, then
tips the open lid over from behind with a flat hand, and it falls shut. Writes under out/demo/ (or the
folder given as the first argument): filmstrip.png (key frames), demo.gif (animation), lid_angle.png and summary.txt; rendered headless with
matplotlib (hand particles, box and lid as wireframes).
"""
import math
import os
import sys
import time

import numpy as np

import handsim
from handsim import experiments, render, users
from handsim.plots import save_figure


def draw(ax, snap, title):
    """Side view from the left (world Z to the right, the user at the right; Y up)."""
    render.draw(ax, {**snap, "title": title}, centre=(0, 0.92, -0.32), half_width=0.3, axes=(2, 1))


def main(out_dir="out/demo"):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from PIL import Image

    os.makedirs(out_dir, exist_ok=True)
    bench = experiments.Bench("exact", -0.7)
    world = bench.world
    record = {"t": [], "angle": [], "violation": []}
    snaps = []
    step_s, steps = 0.0, 0
    t_offset = 0.0
    results = []
    for task, seed in (("open", 3), ("close", 4)):
        user = users.draw_user(seed, task, 2)
        # a calm, clean demo user: the experiments draw the noisy ones
        user = users.UserParams(**{**user.__dict__, "dropouts": (), "box_shift": (0.0, 0.0, 0.0),
                                   "style": "thumb_under" if task == "open" else "push", "speed": 1.0,
                                   "approach": (0.0, 0.0, 0.002), "scale": 1.0})
        if task == "open":
            box = bench.new_box(user)
            base0 = np.asarray(world.body_pose(box.base))
        else:  # keep the box where the open task left it
            box = bench.box
        sim = users.SimulatedUser(user, world, box, experiments.DT)
        t0 = world.time
        while not sim.done and world.time - t0 < experiments.TIME_LIMIT_S:
            frames = sim.frames()
            c = time.perf_counter()
            world.step(experiments.DT, frames)
            step_s += time.perf_counter() - c
            steps += 1
            s = world.joint_state(box.hinge)
            record["t"].append(t_offset + world.time - t0)
            record["angle"].append(math.degrees(s.value))
            record["violation"].append(s.violation)
            if steps % 6 == 0:
                e = np.asarray(box.definition.base_half_extents, float)
                lid_half = np.array([e[0], box.definition.lid_half_thickness, e[2] + 0.5 * box.definition.lid_overhang])
                snaps.append({"t": record["t"][-1], "angle": record["angle"][-1],
                              "boxes": [("base", render.box_corners(world.body_pose(box.base), e)),
                                        ("lid", render.box_corners(world.body_pose(box.lid), lid_half))],
                              "hands": [np.asarray(world.hand_particles(h, True)) if world.hand_tracked(h) else None
                                        for h in (bench.right, bench.left)],
                              "task": task})
        goal = (lambda a: a >= experiments.OPEN_GOAL) if task == "open" else (lambda a: a <= experiments.CLOSED_GOAL)
        moved = np.linalg.norm(np.asarray(world.body_pose(box.base))[:3] - base0[:3]) if task == "close" else 0.0
        results.append((task, sim.done and goal(world.joint_state(box.hinge).value) and moved <= experiments.MAX_SHIFT_M,
                        world.time - t0))
        t_offset = record["t"][-1]

    # filmstrip: 8 key frames spread over the run
    keys = [snaps[int(i)] for i in np.linspace(0, len(snaps) - 1, 8)]
    fig, axes = plt.subplots(2, 4, figsize=(12, 6))
    for ax, snap in zip(axes.flat, keys):
        draw(ax, snap, f"{snap['task']}  t={snap['t']:.2f} s  lid {snap['angle']:.0f}°")
    fig.suptitle("handsim: two hands open and close the jewelry box (side view; blue right, red left)")
    strip = os.path.join(out_dir, "filmstrip.png")
    save_figure(fig, strip, dpi=90)

    # GIF
    images = []
    for snap in snaps[::2]:
        fig, ax = plt.subplots(figsize=(4, 3))
        draw(ax, snap, f"{snap['task']}  t={snap['t']:.2f} s  lid {snap['angle']:.0f}°")
        fig.tight_layout()
        fig.canvas.draw()
        images.append(Image.fromarray(np.asarray(fig.canvas.buffer_rgba())[..., :3]))
        plt.close(fig)
    gif = os.path.join(out_dir, "demo.gif")
    images[0].save(gif, save_all=True, append_images=images[1:], duration=100, loop=0)

    fig, (a1, a2) = plt.subplots(2, 1, figsize=(7, 5), sharex=True)
    a1.plot(record["t"], record["angle"])
    a1.axhline(80, ls=":", c="g")
    a1.axhline(5, ls=":", c="g")
    a1.set_ylabel("lid angle (deg)")
    a2.semilogy(record["t"], np.maximum(record["violation"], 1e-17))
    a2.set_ylabel("hinge violation (m)")
    a2.set_xlabel("time (s)")
    plot = os.path.join(out_dir, "lid_angle.png")
    save_figure(fig, plot, dpi=100)

    ok = all(r[1] for r in results)
    lines = [f"handsim {handsim.__version__}: jewelry box, two hands, open then close (simulated user, exact method)"]
    lines += [f"  {task}: {'success' if good else 'FAILED'} in {t:.2f} s" for task, good, t in results]
    lines += [f"  overall: {'success' if ok else 'failure'}",
              f"  max hinge violation: {max(record['violation']):.2e} m",
              f"  {steps} steps, {1e3 * step_s / steps:.3f} ms per step (World.step wall time)"]
    summary = os.path.join(out_dir, "summary.txt")
    with open(summary, "w") as f:
        f.write("\n".join(lines) + "\n")
    print("\n".join(lines))
    print(f"pictures: {strip}, {gif}, {plot}; summary: {summary}")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main(*sys.argv[1:]))
