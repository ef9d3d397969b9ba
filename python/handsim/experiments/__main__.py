"""python -m handsim.experiments [--trials N] [--json] [--quick] [--workers W] [--ray [ADDRESS]] [--docs DIR]

Runs the jewelry-box experiments and prints one line per condition; with --docs DIR it also writes
DIR/experiments.md and DIR/img/*.png (`--docs docs` regenerates the repo's page; nothing is written without it).
--quick runs 10 trials per cell (1 paper cross-check user per cell).
--json prints {"conditions": [...]} on stdout instead of the lines.
--ray runs the trials as Ray tasks: on a local Ray (no ADDRESS; --workers CPUs) or on the cluster at ADDRESS;
the results are the same as the local runner's, seed for seed.
"""
from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time

from . import (CELLS, METHODS, SUCCESS, THRESHOLDS, TIME_LIMIT_S, have_ceres, json_rows, paper_cross_check,
               run_all, summarize)
from .. import plots
from . import core_issues

# The issue asks for >= 300 trials per task and condition; every method gets them. The paper method's
# trials leave out the stages of its pipeline that cost time without changing the result (see
# experiments.world_def); PAPER_CHECK users per paper cell are replayed with the whole paper pipeline
# (~12-45 ms per step on this machine against ~0.2-1 ms) to show the outcomes agree.
DEFAULT_TRIALS = 300
PAPER_CHECK = 3

PAPER_TABLE_I = {"open": [("Open 2D", 221, 88.2), ("Open 3D", 238, 90.3)],
                 "close": [("Close 2D", 302, 99.0), ("Close 3D", 263, 98.9)]}
PAPER_TABLE_II = {"open": [("Open 2D", 4.34, 1.71), ("Open 3D", 4.31, 1.44)],
                  "close": [("Close 2D", 2.96, 1.17), ("Close 3D", 3.12, 1.34)]}


def _fmt(x, spec, none="–"):
    return none if x is None else format(x, spec)


def _ci95(p, n):
    return 1.96 * math.sqrt(max(p * (1 - p), 0.25 / n) / n)


def _findings(rows):
    """Sentences about the run, every number taken from `rows`."""
    def pick(**kw):
        return [r for r in rows if all(r[k] == v for k, v in kw.items())]
    hard = [r for r in rows if r["method"] != "soft"]
    soft = pick(method="soft")
    soft_open = pick(method="soft", task="open")
    out = [f"- Hard hinge (exact and paper): the largest hinge violation in any frame of any trial was "
           f"{max((r['max_violation_m'] for r in hard), default=0.0):.1e} m and the largest limit overshoot "
           f"{max((r['max_overshoot_rad'] for r in hard), default=0.0):.1e} rad (rounding). Soft baseline: up to "
           f"{max((r['max_violation_m'] for r in soft), default=0.0):.2f} m and {max((r['max_overshoot_rad'] for r in soft), default=0.0):.1f} rad; "
           f"it opened the lid in at most {100 * max((r['success_rate'] for r in soft_open), default=0.0):.1f} % of the trials of a "
           f"cell, because the kinematically held lid pulls the constraint apart (the rubber band of Sec. III)."]
    for m in ("exact", "paper"):
        neg = pick(method=m, threshold=-0.7, task="close")
        pos = pick(method=m, threshold=0.7, task="close")
        if neg and pos:
            rates_neg = ", ".join(f"{100 * r['success_rate']:.1f} %" for r in pick(method=m, threshold=-0.7, task="open"))
            rates_pos = ", ".join(f"{100 * r['success_rate']:.1f} %" for r in pick(method=m, threshold=0.7, task="open"))
            out.append(f"- Threshold, {m}: push-only closing trials that grasped the lid: "
                       f"{sum(r['false_grasps'] for r in neg)} of {sum(r['push_trials'] for r in neg)} with c = -0.7, "
                       f"{sum(r['false_grasps'] for r in pos)} of {sum(r['push_trials'] for r in pos)} with c = +0.7. "
                       f"Opening (one hand, two hands): {rates_neg} with c = -0.7, {rates_pos} with c = +0.7."
                       + (" The looser threshold grasps more, wanted or not." if
                          sum(r["false_grasps"] for r in pos) > sum(r["false_grasps"] for r in neg) else ""))
    keys = ("success_rate", "median_time_s", "drops", "false_grasps", "knocked")
    pairs = [(e, p) for e in pick(method="exact") for p in pick(method="paper")
             if (e["threshold"], e["task"], e["hands"]) == (p["threshold"], p["task"], p["hands"])]
    if pairs:
        same = sum(all(e[k] == p[k] for k in keys) for e, p in pairs)
        out.append(f"- Exact against the paper's LM micro-simulator: {same} of {len(pairs)} cells have the same "
                   "success rate, median time, drops, false grasps and knocked boxes. On a box lid (8 vertices, "
                   "warm-started one frame away) LM lands close enough to the closed form's answer that no "
                   "outcome changes; the difference is cost per solve (`python -m handsim.bench joints`), which "
                   "the step column cannot show: one solve is a small part of a step and the machine is shared.")
    knocked1 = sum(r["knocked"] for r in pick(method="exact", hands=1))
    knocked2 = sum(r["knocked"] for r in pick(method="exact", hands=2))
    n1 = sum(r["trials"] for r in pick(method="exact", hands=1))
    n2 = sum(r["trials"] for r in pick(method="exact", hands=2))
    out.append(f"- Knocked boxes, exact: {knocked1} of {n1} one-hand trials, {knocked2} of {n2} two-hand trials"
               + ("; a left hand that holds the base keeps it in place more often."
                                          if n1 and n2 and knocked2 / n2 < knocked1 / n1 else "."))
    return out


def _paper_table(rows, paper_header, paper_cell, our_cell):
    """Markdown rows: one line per task cell, the paper's numbers, then ours per method and threshold."""
    out = ["| task | " + paper_header + " | " + " | ".join(f"{m} c={c:+.1f}" for m in METHODS for c in THRESHOLDS) + " |",
           "|---|---|" + "---|" * (len(METHODS) * len(THRESHOLDS))]
    for task, hands in CELLS:
        cells = []
        for m in METHODS:
            for c in THRESHOLDS:
                r = next((x for x in rows if x["method"] == m and x["threshold"] == c and x["task"] == task
                          and x["hands"] == hands), None)
                cells.append("–" if r is None else our_cell(r))
        out.append(f"| {task}, {hands} hand{'s' if hands > 1 else ''} | {paper_cell(task)} | " + " | ".join(cells) + " |")
    return out


def report(rows, results, trials, check, seconds, command, where) -> str:
    import handsim
    cond_names = {"exact": "hard hinge + exact micro-simulator (ours)",
                  "paper": "the paper's micro-simulator, Ceres LM 10 its"
                           + ("" if have_ceres() else " (built without Ceres: Eigen LM)"),
                  "soft": "soft baseline: Bullet btHingeConstraint, forces only"}
    L = []
    L.append("# Jewelry-box experiments (Sec. IV of Kim & Park) with simulated users\n")
    L.append(f"Generated by `{command}` ({trials} trials per task and condition, "
             f"{len(results)} trials in all, plus {check['trials']} replayed with the paper's full pipeline; "
             f"{seconds:.0f} s wall time on {where}, handsim {handsim.__version__}). Every number "
             "below comes from that run; rerun the command to regenerate this file and `docs/img/`.\n")
    L.append("**The paper's numbers are of people** (IMU glove, 2D display or HMD, a human judge); **ours are of "
             "scripted simulated users** (`handsim/users.py`) judged by fixed criteria. They are set side by side "
             "for orientation, not as a replication of the user study.\n")
    L.append("## Scene\n")
    L.append("`build_jewelry_box` with its defaults (base 18 x 7 x 12 cm, 0.5 kg, on a 75 cm table; lid 1.5 cm "
             "thick, 0.15 kg, its lip 1.5 cm past the base's front; hinge on the back top edge, limits 0–90°). "
             "Each trial drops the box at a "
             "random spot (±5 cm sideways, ±3 cm in depth, ±15° yaw). 60 Hz frames, 240 Hz physics substeps.\n")
    L.append("## Simulated users\n")
    L.append("Each trial draws, from its seed: speed (log-normal, σ 0.3, 0.5–2.2x), hand size (scale N(1, 0.07)), "
             "aim error at the lip (σ 12 mm sideways, 1.5 mm height, 2 mm depth), grasp style, how far it swings "
             "the lid (N(93°, 2.5°)), reaction time (0.25–0.5 s), glove errors like an IMU glove's: per-frame "
             "finger noise (σ 0.005–0.02 of full curl/opposition), finger drift (Ornstein-Uhlenbeck, σ up to 0.03, "
             "τ 1 s), palm jitter (σ 0.5–2 mm), uncorrected palm drift (OU, σ up to 4 mm, τ 0.7 s), heading drift "
             "(σ up to 3°), and tracking dropouts (Poisson 0.25 per trial, lengths exponential, mean 0.12 s). The "
             "glove is `handsim.Glove` in the core (the per-frame hot path; the users' random numbers still come "
             "from their numpy generators, so a seed gives the same trial). "
             "The users are closed-loop like a person at a screen: they aim at where the lid is, notice when it "
             "no longer follows the hand (lag > 20° for longer than their reaction time) or fell back after they "
             "let go, and start again (at most 3 retries).\n")
    L.append("Every hand travels open and closes its grip only on the object, from the open hand over the "
             "close-in (`HandShape.opened`, i.e. `handsim.open_grip`: curls and thumb opposition from 0 to the "
             "style's), and opens it to let go, as people do and as the intent rule (docs/grasp.md) requires; "
             "a retry first opens the hand.\n")
    L.append("- **open**: reach over the lip, descend in front of it, close in with the thumb under the lip and the "
             "fingers on the lid (styles *thumb_under*: `lid_pinch_shape()`; *pinch*: thumb bent and pressed "
             "harder), swing the lid about the hinge to the drawn angle, open the fingers, withdraw upwards.")
    L.append("- **close**: from 90°, *carry*: grip the top edge and swing it down to closed; *push*: a flat hand "
             "from behind tips the lid to 30° and lets it fall (push-only trials: any grasp of the lid is a false "
             "grasp).")
    L.append("- **two hands**: the left hand holds the base first (it reaches open from beside the box to the "
             "base's left end, palm towards it, and curls its fingers into it: eq. 3 grasps the base) and keeps "
             "holding it, with its own glove errors, while the right hand works (the paper's Fig. 6).\n")
    L.append(f"**Success**: {SUCCESS}. **Completion time**: from the first touch of the box to the last time "
             "the lid entered the goal, successful trials only. **Drops**: trials where the lid's grasp ended "
             "while the user still meant to hold it. **False grasps**: push-only trials in which the lid got "
             "grasped. **Max violation / overshoot**: the largest hinge separation (m) and limit overshoot (rad) "
             "measured from the body poses in any frame of any trial of the cell.\n")

    L.append("## Table I: success rate\n")
    L.append("The paper's tasks were two-handed (one hand picks the box up, the other opens or closes the lid); "
             "its numbers are repeated in the one-hand rows for comparison only.\n")
    L += _paper_table(rows, "paper (people)",
                      lambda task: ", ".join(f"{n} {p:.1f} % (n={k})" for n, k, p in PAPER_TABLE_I[task]),
                      lambda r: f"{100 * r['success_rate']:.1f} %")
    L.append("")
    L.append("## Table II: completion time of successful trials (s)\n")
    L.append("The paper gives mean and standard deviation; we give median; mean ± sd.\n")
    L += _paper_table(rows, "paper (people), mean ± sd",
                      lambda task: ", ".join(f"{n} {m:.2f} ± {s:.2f}" for n, m, s in PAPER_TABLE_II[task]),
                      lambda r: "–" if r["median_time_s"] is None else
                      f"{r['median_time_s']:.2f}; {r['mean_time_s']:.2f} ± {_fmt(r['std_time_s'], '.2f')}")
    L.append("")
    L.append("## Ablations: every condition and task\n")
    L.append("Success ± the half-width of its 95 % confidence interval (normal approximation). Step: mean wall "
             "time of `World.step` per frame.\n")
    L.append("| method | c | task | hands | trials | success | median time (s) | max violation (m) | "
             "max overshoot (rad) | false grasps (of push trials) | drops | knocked | retried | step (ms) |")
    L.append("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        L.append(f"| {r['method']} | {r['threshold']:+.1f} | {r['task']} | {r['hands']} | {r['trials']} | "
                 f"{100 * r['success_rate']:.1f} ± {100 * _ci95(r['success_rate'], r['trials']):.1f} % | "
                 f"{_fmt(r['median_time_s'], '.2f')} | {r['max_violation_m']:.2e} | "
                 f"{r['max_overshoot_rad']:.2e} | {r['false_grasps']} ({r['push_trials']}) | {r['drops']} | "
                 f"{r['knocked']} | {r['retries']} | {r['step_ms']:.2f} |")
    L.append("")
    L.append("### What the run shows\n")
    L += _findings(rows)
    L.append("")
    L.append("Methods: " + "; ".join(f"**{k}**: {v}" for k, v in cond_names.items()) + ". Threshold c is eq. 3's "
             "grasp threshold: −0.7 (our reading: opposing contacts) or +0.7 (the paper's literal text).\n")
    L.append("The paper method's trials run its micro-simulator in our pipeline. The rest of the paper's pipeline "
             "(every stage every step, the ~39k-vertex render mesh skinned every step, one Bullet collision "
             "object per particle) changes the cost of a step, not its result; to check that, the first "
             f"{check['trials'] // max(1, 2 * len(CELLS))} user(s) of every paper cell were replayed with it on: "
             f"**{check['same_outcome']} of {check['trials']}** ended the same (success, grasp count, drop), the "
             f"final lid angles differ by at most {check['max_angle_diff_rad']:.1e} rad, and a step cost "
             f"{_fmt(check['step_ms_full'], '.1f')} ms against {_fmt(check['step_ms_lean'], '.2f')} ms.\n")
    L.append("Success per grasp style:\n")
    for r in rows:
        L.append(f"- {r['method']} c={r['threshold']:+.1f} {r['task']}/{r['hands']}: " +
                 ", ".join(f"{k} {100 * v:.0f} %" for k, v in r["style_success"].items()))
    L.append("")
    L.append("## Plots\n")
    L.append("![success rates](img/exp_success.png)\n")
    L.append("![completion time densities](img/exp_time_kde.png)\n")
    L.append("The paper's time densities are its Fig. 9 (the issue calls it Fig. 8, which shows the task).\n")
    L.append("![lid angle and hinge violation](img/exp_traces.png)\n")
    L.append("## Core faults found by these experiments, fixed\n")
    L.append("An earlier run of these experiments (with the lip raised to 2.5 cm to make them rarer) found two faults in the core: a base touched by the hand that holds its lid was thrown "
             "metres, and a lid held past its upper limit was slammed shut when the grasp ended. Both are fixed "
             "(docs/grasp.md, *Contacts keep their entry face*); the noise-free reproductions "
             "(`python -m handsim.experiments.core_issues`, default box, one scripted right hand) now print:\n")
    L.append("```")
    L += core_issues.summary()
    L.append("```\n")
    L.append("## Bases knocked over in the two-hand closing cell, explained (not yet fixed)\n")
    L.append("The run before (docs at 390be57) gave close, two hands, exact c = -0.7 87.3 % with 36 of 300 bases "
             "knocked over. Traced trial by trial (the user's phase, both hands' contacts on the base, the base's "
             "shift and tilt every frame): every knocked base of that cell was knocked in `left_reach`, before the "
             "right hand did anything: the left hand appears beside the base and curls its fingers and thumb into "
             "it, and the base is shoved before the grasp begins (then the left hand grasps it where it was "
             "knocked to and holds it there). In seed 80012 the base moved 8 cm and turned 34 deg in one frame: "
             "two thumb particles at the base's top edge had been given the base's far side face (+x, 18 cm away) "
             "as their entry face the frame before, when the search for the face they entered through "
             "(`entry_face`, core/src/contacts.cpp) failed but still wrote the far candidate into its outputs; "
             "kept the next frame, their contacts were 178 mm deep (measured with a temporary print in "
             "`keep_entry_faces`). Writing the face only on success (what contacts.h documents) removed that "
             "knock (the cell's first 60 users: 1 knocked instead of 2) but made an open hand grasp the cube at the "
             "end of the Leap recording confidence-demo-eighth-res under the default rule, which `make test` "
             "checks, so it is not in this run. Slowing the left hand's closing (0.6 s instead of 0.25 s) did not "
             "help (14 knocked of the first 100 users instead of 6): the cause is not the user model's speed.\n")
    L.append("## Limits of this reproduction\n")
    L.append("- Times are of scripted motions whose speeds are drawn; they reflect the user model as much as the "
             "simulation (retries, lost grasps and the closed loop make the difference between conditions).")
    L.append("- The left hand reaches the base open and closes its grip beside it, where the open hand touches "
             "nothing (a hand that closed while still coming in carried the base it had grasped along). "
             "Trials in which the left hand grasped the base: " +
             ", ".join(f"{r['method']} c={r['threshold']:+.1f} {r['task']}: {r['base_held']}/{r['trials']}"
                       for r in rows if r["hands"] == 2) + ".")
    L.append("")
    return "\n".join(L)


def main(argv=None):
    ap = argparse.ArgumentParser(prog="python -m handsim.experiments", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--trials", type=int, default=DEFAULT_TRIALS, help=f"trials per task and condition (default {DEFAULT_TRIALS})")
    ap.add_argument("--paper-check", type=int, default=PAPER_CHECK,
                    help=f"users per paper cell replayed with the paper's full pipeline (default {PAPER_CHECK})")
    ap.add_argument("--json", action="store_true", help="print the conditions as JSON on stdout")
    ap.add_argument("--quick", action="store_true", help="10 trials per cell")
    ap.add_argument("--workers", type=int, default=min(2, os.cpu_count() or 1), help="parallel processes")
    ap.add_argument("--ray", nargs="?", const="", default=False, metavar="ADDRESS",
                    help="run the trials on Ray: a local Ray without ADDRESS, else the cluster at ADDRESS")
    ap.add_argument("--docs", default=None, help="folder to write experiments.md and img/ into (none: write nothing)")
    ap.add_argument("--rule", default=None, metavar="SPEC",
                    help="grasp rule for every condition, in the judge's syntax (python -m handsim.intent --rule): "
                         "'contacts', 'paper' or 'NAME:field=value,...' (the condition still sets c)")
    ap.add_argument("--methods", default=",".join(METHODS), metavar="LIST",
                    help=f"comma-separated methods to run (default all: {','.join(METHODS)}); not with --docs")
    ap.add_argument("--thresholds", default=",".join(str(c) for c in THRESHOLDS), metavar="LIST",
                    help="comma-separated grasp thresholds c to run (default all: "
                         f"{','.join(str(c) for c in THRESHOLDS)}); not with --docs")
    args = ap.parse_args(argv)
    methods = tuple(m for m in args.methods.split(",") if m)
    if not methods or any(m not in METHODS for m in methods):
        ap.error(f"--methods: expected a comma-separated subset of {','.join(METHODS)}, got {args.methods!r}")
    try:
        thresholds = tuple(float(c) for c in args.thresholds.split(",") if c)
    except ValueError:
        thresholds = ()
    if not thresholds or any(c not in THRESHOLDS for c in thresholds):
        ap.error(f"--thresholds: expected a comma-separated subset of {','.join(str(c) for c in THRESHOLDS)}, "
                 f"got {args.thresholds!r}")
    if args.docs is not None and (set(methods) != set(METHODS) or set(thresholds) != set(THRESHOLDS)):
        ap.error("--docs: the report needs every method and threshold (drop --methods / --thresholds)")
    if args.rule is not None:
        from ..intent import parse_rule
        try:
            parse_rule(args.rule)
        except ValueError as e:
            ap.error(f"--rule: {e}")
    trials = 10 if args.quick else args.trials
    if trials < 1:
        ap.error("--trials must be >= 1")
    docs = args.docs
    if docs is not None:
        os.makedirs(os.path.join(docs, "img"), exist_ok=True)
    t0 = time.perf_counter()
    from ..runners import make_runner
    runner = make_runner(args.ray, args.workers)
    results = run_all(trials, methods, thresholds, runner=runner, rule=args.rule)
    n_check = min(trials, max(0, args.paper_check), 1 if args.quick else trials)
    check = paper_cross_check(results, n_check, runner=runner, rule=args.rule)
    seconds = time.perf_counter() - t0
    rows = summarize(results)
    if docs is not None:
        plots.success_rates(rows, os.path.join(docs, "img", "exp_success.png"))
        plots.time_kde(results, os.path.join(docs, "img", "exp_time_kde.png"))
        plots.traces(results, os.path.join(docs, "img", "exp_traces.png"))
        command = "python -m handsim.experiments --docs docs" + (
            "" if trials == DEFAULT_TRIALS and not args.quick else (" --quick" if args.quick else f" --trials {trials}"))
        if args.paper_check != PAPER_CHECK:
            command += f" --paper-check {args.paper_check}"
        if args.rule is not None:
            command += f" --rule {args.rule}"
        with open(os.path.join(docs, "experiments.md"), "w") as f:
            f.write(report(rows, results, trials, check, seconds, command, runner.describe()))
    if args.json:
        json.dump(json_rows(rows), sys.stdout, indent=1)
        print()
    else:
        for r in rows:
            print(f"{r['method']:5s} c={r['threshold']:+.1f} {r['task']:5s} {r['hands']}h: success "
                  f"{100 * r['success_rate']:5.1f} %  median {_fmt(r['median_time_s'], '.2f')} s  viol "
                  f"{r['max_violation_m']:.1e} m  overshoot {r['max_overshoot_rad']:.1e} rad  false grasps "
                  f"{r['false_grasps']}  drops {r['drops']}  knocked {r['knocked']}  retried {r['retries']}")
        print(f"{len(results)} trials in {seconds:.0f} s on {runner.describe()} "
              f"({len(results) / seconds / runner.cores():.2f} trials/s per core)"
              + (f"; report: {os.path.join(docs, 'experiments.md')}" if docs is not None else ""))
    return 0


if __name__ == "__main__":
    sys.exit(main())
