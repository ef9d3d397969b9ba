"""The demo session: the paper's jewelry box opened and closed by a calm two-handed simulated user.

The left hand holds the base; the right hand pinches the lid's lip with the thumb under it, swings the lid open
and lets go, then tips the open lid over from behind with a flat hand and it falls shut. ``samples/demo.py``
(``make demo``) records it as pictures; ``python -m handsim.view --demo`` shows it live. One place, so both
show the same session.
"""
from __future__ import annotations

import dataclasses
import math
import time
from typing import Callable, List, Optional

import numpy as np

from . import experiments, users

TASKS = (("open", 3), ("close", 4))


@dataclasses.dataclass
class TaskResult:
    task: str
    success: bool
    seconds: float       # simulated time the task took


@dataclasses.dataclass
class DemoState:
    """What on_step gets after each step."""
    bench: object        # experiments.Bench: .world, .right, .left
    box: object          # the JewelryBox
    task: str            # "open" | "close"
    t: float             # seconds since the session began (both tasks)
    lid_deg: float
    violation: float     # hinge violation, m
    step_seconds: float  # wall time of this World.step


def calm_user(task: str, seed: int) -> users.UserParams:
    """The experiments' user of `seed`, without their noise (dropouts, box shift, approach error), at 1x."""
    user = users.draw_user(seed, task, 2)
    return users.UserParams(**{**user.__dict__, "dropouts": (), "box_shift": (0.0, 0.0, 0.0),
                               "style": "thumb_under" if task == "open" else "push", "speed": 1.0,
                               "approach": (0.0, 0.0, 0.002), "scale": 1.0})


def run(on_step: Optional[Callable[[DemoState], None]] = None, tasks=TASKS) -> List[TaskResult]:
    """Runs the session, calling ``on_step(state)`` after every World.step; returns one result per task.
    A task succeeds when the user finished in time, the lid reached the goal and (closing) the base moved at
    most experiments.MAX_SHIFT_M."""
    bench = experiments.Bench("exact", -0.7)
    world = bench.world
    results = []
    t_offset = 0.0
    base0 = None
    for task, seed in tasks:
        user = calm_user(task, seed)
        if task == "open" or bench.box is None:
            box = bench.new_box(user)
            base0 = np.asarray(world.body_pose(box.base))
        else:  # keep the box where the open task left it
            box = bench.box
        sim = users.SimulatedUser(user, world, box, experiments.DT, hands=(bench.right, bench.left))
        t0 = world.time
        while not sim.done and world.time - t0 < experiments.TIME_LIMIT_S:
            frames = sim.frames()
            c = time.perf_counter()
            world.step(experiments.DT, frames)
            cost = time.perf_counter() - c
            if on_step is not None:
                s = world.joint_state(box.hinge)
                on_step(DemoState(bench, box, task, t_offset + world.time - t0, math.degrees(s.value), s.violation,
                                  cost))
        angle = world.joint_state(box.hinge).value
        goal = angle >= experiments.OPEN_GOAL if task == "open" else angle <= experiments.CLOSED_GOAL
        moved = float(np.linalg.norm(np.asarray(world.body_pose(box.base))[:3] - base0[:3]))
        ok = sim.done and goal and (task == "open" or moved <= experiments.MAX_SHIFT_M)
        results.append(TaskResult(task, bool(ok), world.time - t0))
        t_offset += world.time - t0
    return results


def names(bench, box) -> dict:
    """Object names for the viewer and the pictures."""
    out = {"base": box.base, "lid": box.lid, "hinge": box.hinge}
    if box.table is not None:
        out["table"] = box.table
    return out
