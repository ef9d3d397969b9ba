"""The jewelry-box experiments of Kim & Park, Sec. IV, with simulated users (``handsim.users``).

``python -m handsim.experiments [--trials N] [--json] [--quick]`` runs every task (open / close, one or two
hands) under every condition (method exact / paper / soft, grasp threshold -0.7 / +0.7) and regenerates
``docs/experiments.md`` and its plots (``--docs``); ``--methods exact --thresholds -0.7`` runs only those
conditions (a quicker measurement; not with ``--docs``). This module holds the trial runner and the statistics; ``__main__``
holds the command line and the report.

Success of one trial (``SUCCESS`` in words, used by the report):

* open: the lid is at >= 80 deg when the trial ends (it stays open once the user has let go), close: <= 5 deg;
* within ``TIME_LIMIT_S`` of the trial's start;
* the box was not knocked about: the base is still on the table, moved <= 5 cm and tilted <= 15 deg.

Completion time: from the first touch of the box by any hand to the last moment the lid entered the goal
(open >= 80 deg, closed <= 5 deg), successful trials only (the paper: "from the grasping of the first hand
until the given task is accomplished").
"""
from __future__ import annotations

import dataclasses
import math
import time
from typing import Dict, List, Optional

import numpy as np

from .. import _core as _h
from .. import users as _users
from ..quat import quat_rotate

METHODS = ("exact", "paper", "soft")
THRESHOLDS = (-0.7, 0.7)
CELLS = (("open", 1), ("open", 2), ("close", 1), ("close", 2))
TIME_LIMIT_S = 10.0
OPEN_GOAL = math.radians(80)
CLOSED_GOAL = math.radians(5)
MAX_SHIFT_M = 0.05
MAX_TILT = math.radians(15)
DT = 1.0 / _users.FRAME_RATE

SUCCESS = (f"open: lid >= {math.degrees(OPEN_GOAL):.0f} deg at the end; close: lid <= "
           f"{math.degrees(CLOSED_GOAL):.0f} deg at the end; within {TIME_LIMIT_S:.0f} s; base still on the "
           f"table, moved <= {MAX_SHIFT_M * 100:.0f} cm and tilted <= {math.degrees(MAX_TILT):.0f} deg")


def have_ceres() -> bool:
    return bool(getattr(_h, "WITH_CERES", False))


def world_def(method: str, threshold: float, full_paper: bool = False, rule: Optional[str] = None):
    """The WorldDef of a condition. The paper method differs from ours in its micro-simulator (Ceres LM, 10
    iterations: ``box_def``); ``full_paper`` also runs the paper's whole pipeline (every stage every step, the
    render mesh skinned every step, one Bullet object per particle). Those stages change what a step costs,
    not what it computes (the contacts agree to 1e-17 m, ``bench hand``), so the 300-trial run leaves them
    out and ``paper_cross_check`` replays users with them on to show the outcomes are the same. ``rule``: a
    grasp rule in the judge's syntax (``handsim.intent.parse_rule``: "contacts", "NAME:field=value,...") whose
    GraspSettings and push/skin fields replace the defaults; the condition's threshold still sets c."""
    if method not in METHODS:
        raise ValueError(f"method: expected one of {METHODS}, got {method!r}")
    wd = _h.WorldDef()
    if rule is not None:
        from ..intent import apply_rule, parse_rule
        apply_rule(wd, parse_rule(rule)[1])
    grasp = wd.grasp
    grasp.cos_threshold = float(threshold)
    wd.grasp = grasp
    if method == "paper" and full_paper:
        wd.paper_pipeline = True
        wd.particle_contacts = _h.ParticleContacts.BULLET_OBJECTS
    return wd


def box_def(method: str, user: Optional[_users.UserParams] = None):
    """The scene's default JewelryBoxDef with the condition's joint model / solver, dropped where the user's
    trial put it (``user.box_shift``)."""
    d = _h.JewelryBoxDef()
    if method == "soft":
        d.model = _h.JointModel.SOFT
    elif method == "paper":
        d.solver = _h.JointSolver.LM_CERES if have_ceres() else _h.JointSolver.LM
    if user is not None:
        dx, dz, yaw = user.box_shift
        p = np.asarray(d.position, float)
        d.position = [p[0] + dx, p[1], p[2] + dz]
        d.yaw = yaw
    return d


@dataclasses.dataclass
class TrialResult:
    seed: int
    method: str
    threshold: float
    task: str
    hands: int
    style: str
    success: bool
    time_s: Optional[float]          # completion time, successful trials only
    duration_s: float                 # simulated time the trial ran
    final_angle: float
    max_violation_m: float
    max_overshoot_rad: float
    grasp_begins: int                 # GRASP_BEGIN events on the lid
    false_grasp: bool                 # push-only trial and the lid got grasped
    drop: bool                        # the lid's grasp ended while the user still meant to hold it
    knocked: bool                     # the base left the table, moved or tilted too far
    base_held: bool                   # two hands: the left hand grasped the base at some point
    attempts: int
    step_ms: float                    # mean wall time of World.step
    trace: Optional[Dict[str, list]] = None


_MODEL_KEEPER = None  # see _share_hand_models


def _share_hand_models():
    """Keeps a world holding the benches' two hands alive for the rest of this process, so that every Bench
    built here (one per job: a condition and cell on a runner's worker) shares their built models instead of
    building them anew (~0.1-0.4 s a hand; World.add_hand shares the model of an equal HandDef among live
    worlds). A shared model is the same numbers as a rebuilt one, so no trial changes."""
    global _MODEL_KEEPER
    if _MODEL_KEEPER is None:
        from ..intent import default_hand_defs, model_keeper
        _MODEL_KEEPER = model_keeper(default_hand_defs())


class Bench:
    """One world per condition with a right and a left hand, reused for every trial of the condition: the
    hand models are built once per process (they cost ~0.1-0.4 s each); each trial rebuilds only the box."""

    def __init__(self, method: str, threshold: float, full_paper: bool = False, rule: Optional[str] = None):
        _share_hand_models()
        self.method, self.threshold = method, threshold
        self.world = _h.World(world_def(method, threshold, full_paper, rule))
        self.right = self.world.add_hand(_h.HandDef(handedness=_h.Handedness.RIGHT))
        self.left = self.world.add_hand(_h.HandDef(handedness=_h.Handedness.LEFT))
        self.box = None

    def new_box(self, user: _users.UserParams):
        w = self.world
        if self.box is not None:
            w.remove_joint(self.box.hinge)
            for body in (self.box.lid, self.box.base, self.box.table):
                if body is not None:
                    w.remove_body(body)
        self.box = _h.build_jewelry_box(w, box_def(self.method, user))
        if user.task == "close":
            w.set_joint_value(self.box.hinge, 0.5 * math.pi)
        w.step(DT)  # one frame without hands: nothing carries over from the last trial
        return self.box

    def run(self, user: _users.UserParams, trace: bool = False) -> TrialResult:
        w = self.world
        box = self.new_box(user)
        sim = _users.SimulatedUser(user, w, box, DT, hands=(self.right, self.left))
        base0 = np.asarray(w.body_pose(box.base), float)
        table_top = float(np.asarray(box.definition.position, float)[1])
        goal_ok = (lambda a: a >= OPEN_GOAL) if user.task == "open" else (lambda a: a <= CLOSED_GOAL)
        max_v = max_o = 0.0
        begins = 0
        drop = base_held = False
        t_touch = None
        t_goal = None
        step_s = 0.0
        n = 0
        rec = {"t": [], "angle": [], "violation": []} if trace else None
        angle = w.joint_state(box.hinge).value
        was_ok = goal_ok(angle)
        t0 = w.time
        while True:
            frames = sim.frames()
            holding = sim.intent_hold
            c0 = time.perf_counter()
            w.step(DT, frames)
            step_s += time.perf_counter() - c0
            n += 1
            t = w.time - t0
            s = w.joint_state(box.hinge)
            angle = s.value
            max_v = max(max_v, s.violation)
            max_o = max(max_o, s.overshoot)
            for e in w.events():
                if e.body == box.lid and e.type == _h.EventType.GRASP_BEGIN:
                    begins += 1
                elif e.body == box.lid and e.type == _h.EventType.GRASP_END and e.hand == self.right and holding:
                    drop = True
                elif e.body == box.base and e.type == _h.EventType.GRASP_BEGIN and e.hand == self.left:
                    base_held = True
                if t_touch is None and e.type == _h.EventType.CONTACT_BEGIN and e.body in (box.lid, box.base):
                    t_touch = t
            ok = goal_ok(angle)
            if ok and not was_ok:
                t_goal = t
            was_ok = ok
            if rec is not None:
                rec["t"].append(t)
                rec["angle"].append(math.degrees(angle))
                rec["violation"].append(s.violation)
            if sim.done or t >= TIME_LIMIT_S - 1e-9:
                break
        base = np.asarray(w.body_pose(box.base), float)
        shift = float(np.hypot(base[0] - base0[0], base[2] - base0[2]))
        up = quat_rotate(base[3:], [0, 1, 0])
        tilt = math.acos(max(-1.0, min(1.0, float(up[1]))))
        on_table = base[1] > table_top
        knocked = shift > MAX_SHIFT_M or tilt > MAX_TILT or not on_table
        success = bool(goal_ok(angle) and sim.done and not knocked)
        if t_goal is None and was_ok:
            t_goal = 0.0
        time_s = None
        if success:
            time_s = float(t_goal - (t_touch if t_touch is not None else 0.0))
        return TrialResult(user.seed, self.method, self.threshold, user.task, user.hands, user.style, success,
                           time_s, float(w.time - t0), float(angle), float(max_v), float(max_o), begins,
                           user.style == "push" and begins > 0, drop, knocked, base_held, sim.attempts,
                           1e3 * step_s / max(n, 1), rec)


def trial_seed(index: int, task: str, hands: int) -> int:
    """Seed of the index-th user of a cell; the same users take part under every condition."""
    return 1000 * index + 10 * _users.TASKS.index(task) + hands


def run_condition(method: str, threshold: float, trials: int, cells=CELLS, trace_seed_index: int = 0,
                  progress=None, full_paper: bool = False, rule: Optional[str] = None) -> List[TrialResult]:
    """Every trial of one condition, in a fixed order (deterministic); ``rule`` as in ``world_def``."""
    bench = Bench(method, threshold, full_paper, rule)
    out = []
    for task, hands in cells:
        for i in range(trials):
            user = _users.draw_user(trial_seed(i, task, hands), task, hands)
            out.append(bench.run(user, trace=(i == trace_seed_index)))
            if progress is not None:
                progress()
    return out


def _cell_job(args):
    method, threshold, trials, cell, full_paper, rule = args
    return run_condition(method, threshold, trials, (cell,), full_paper=full_paper, rule=rule)


def _run_jobs(jobs, workers: int = 1, runner=None):
    """Every job's trials, in job order, on `runner` (handsim.runners; default: local, `workers` processes).
    A job is one (method, threshold, cell): the same jobs in the same order on every runner."""
    from ..runners import LocalRunner
    runner = runner or LocalRunner(workers)
    parts = runner.map(_cell_job, jobs)
    return [r for part in parts for r in part]


def run_all(trials: int, methods=METHODS, thresholds=THRESHOLDS, cells=CELLS, workers: int = 1, runner=None,
            rule: Optional[str] = None):
    """All conditions; with workers > 1 (or a runner, e.g. handsim.runners.RayRunner) the (condition, task)
    cells run in parallel (same results); ``rule`` as in ``world_def``, for every condition."""
    return _run_jobs([(m, c, trials, cell, False, rule) for m in methods for c in thresholds for cell in cells],
                     workers, runner)


def paper_cross_check(results: List[TrialResult], trials: int, workers: int = 1, runner=None,
                      rule: Optional[str] = None) -> dict:
    """Replays the first `trials` users of every paper-method cell with the paper's full pipeline and compares
    each with the same user's trial in `results`: how many ended the same (success, grasp count, drop), and
    the largest difference of the final lid angle (rad)."""
    full = _run_jobs([("paper", c, trials, cell, True, rule) for c in THRESHOLDS for cell in CELLS], workers, runner)
    lean = {(r.threshold, r.task, r.hands, r.seed): r for r in results if r.method == "paper"}
    same, compared, angle = 0, 0, 0.0
    for f in full:
        r = lean.get((f.threshold, f.task, f.hands, f.seed))
        if r is None:
            continue
        compared += 1
        same += (r.success, r.grasp_begins, r.drop) == (f.success, f.grasp_begins, f.drop)
        angle = max(angle, abs(r.final_angle - f.final_angle))
    return {"trials": compared, "same_outcome": same, "max_angle_diff_rad": angle,
            "step_ms_full": float(np.mean([f.step_ms for f in full])) if full else None,
            "step_ms_lean": float(np.mean([r.step_ms for r in lean.values()])) if lean else None}


def summarize(results: List[TrialResult]) -> List[dict]:
    """One row per (method, threshold, task, hands), with the issue's JSON keys plus a few extras
    (mean/std time, per-style success) that the report uses; ``json_rows`` keeps only the JSON keys."""
    groups: Dict[tuple, List[TrialResult]] = {}
    for r in results:
        groups.setdefault((r.method, r.threshold, r.task, r.hands), []).append(r)
    rows = []
    for (method, threshold, task, hands), rs in groups.items():
        times = np.array([r.time_s for r in rs if r.success and r.time_s is not None])
        styles = {}
        for r in rs:
            styles.setdefault(r.style, []).append(r.success)
        rows.append({
            "method": method, "threshold": threshold, "task": task, "hands": hands, "trials": len(rs),
            "success_rate": float(np.mean([r.success for r in rs])),
            "median_time_s": float(np.median(times)) if len(times) else None,
            "max_violation_m": float(max(r.max_violation_m for r in rs)),
            "max_overshoot_rad": float(max(r.max_overshoot_rad for r in rs)),
            "false_grasps": int(sum(r.false_grasp for r in rs)),
            "drops": int(sum(r.drop for r in rs)),
            # extras
            "mean_time_s": float(np.mean(times)) if len(times) else None,
            "std_time_s": float(np.std(times, ddof=1)) if len(times) > 1 else None,
            "push_trials": int(sum(r.style == "push" for r in rs)),
            "knocked": int(sum(r.knocked for r in rs)),
            "base_held": int(sum(r.base_held for r in rs)),
            "retries": int(sum(r.attempts > 0 for r in rs)),
            "style_success": {k: float(np.mean(v)) for k, v in sorted(styles.items())},
            "step_ms": float(np.mean([r.step_ms for r in rs])),
        })
    order = {m: i for i, m in enumerate(METHODS)}
    rows.sort(key=lambda r: (order[r["method"]], r["threshold"], TASK_ORDER[(r["task"], r["hands"])]))
    return rows


TASK_ORDER = {cell: i for i, cell in enumerate(CELLS)}
JSON_KEYS = ("method", "threshold", "task", "hands", "trials", "success_rate", "median_time_s",
             "max_violation_m", "max_overshoot_rad", "false_grasps", "drops")


def json_rows(rows: List[dict]) -> dict:
    return {"conditions": [{k: r[k] for k in JSON_KEYS} for r in rows]}
