"""The jewelry-box experiments: simulated users are deterministic for a seed, a clean user succeeds under
every method, the report's JSON has the issue's keys."""
import dataclasses
import math

import numpy as np
import pytest

import handsim
from conftest import with_grasp_rule
from handsim import experiments as X
from handsim.experiments import __main__ as X_main
from handsim import users as U


def clean(task, hands, style):
    """A calm user without glove errors, the box where the scene puts it."""
    u = U.draw_user(3, task, hands)
    return dataclasses.replace(u, style=style, speed=1.0, scale=1.0, approach=(0.0, 0.0, 0.002),
                               finger_noise=0.0, finger_drift=0.0, palm_noise=0.0, palm_drift=0.0,
                               yaw_drift=0.0, dropouts=(), box_shift=(0.0, 0.0, 0.0))


def frames_of(user, n=90):
    bench = X.Bench("exact", -0.7)
    box = bench.new_box(user)
    sim = U.SimulatedUser(user, bench.world, box, X.DT)
    out = []
    for _ in range(n):
        fr = sim.frames()
        out.append(np.concatenate([np.asarray(fr[h].positions).ravel() if h in fr else np.zeros(3 * handsim.JOINT_COUNT)
                                   for h in (bench.right, bench.left)]))
        bench.world.step(X.DT, fr)
    return np.array(out), bench.world.state_hash()


def test_users_are_deterministic_for_a_seed_and_differ_between_seeds():
    assert U.draw_user(7, "open", 2) == U.draw_user(7, "open", 2)
    assert U.draw_user(7, "open", 2) != U.draw_user(8, "open", 2)
    assert U.draw_user(7, "open", 1) != U.draw_user(7, "close", 1)
    a, ha = frames_of(U.draw_user(11, "open", 2))
    b, hb = frames_of(U.draw_user(11, "open", 2))
    np.testing.assert_array_equal(a, b)
    assert ha == hb
    c, _ = frames_of(U.draw_user(12, "open", 2))
    assert a.shape == c.shape and not np.array_equal(a, c)


def test_draws_cover_the_styles_and_stay_in_range():
    users = [U.draw_user(i, t, 1) for i in range(200) for t in U.TASKS]
    assert {u.style for u in users} == set(U.OPEN_STYLES) | set(U.CLOSE_STYLES)
    assert all(0.5 <= u.speed <= 2.2 and 0.85 <= u.scale <= 1.15 for u in users)
    assert 0.05 < np.mean([len(u.dropouts) > 0 for u in users]) < 0.4
    with pytest.raises(ValueError):
        U.draw_user(0, "lift", 1)


def test_untracked_frame_is_untracked():
    f = handsim.untracked_frame(handsim.Handedness.RIGHT)
    assert not np.asarray(f.valid).any()


@pytest.mark.parametrize("method", ["exact", "paper"])
def test_a_clean_two_hand_open_trial_succeeds(method):
    r = X.Bench(method, -0.7).run(clean("open", 2, "thumb_under"))
    assert r.success, r
    assert r.final_angle >= X.OPEN_GOAL
    assert r.grasp_begins >= 1 and not r.drop and not r.knocked
    assert r.max_violation_m < 1e-9 and r.max_overshoot_rad < 1e-9
    assert 0.5 < r.time_s < 6


@pytest.mark.parametrize("task, hands, style", [("open", 1, "pinch"), ("open", 2, "thumb_under"),
                                               ("close", 1, "carry"), ("close", 2, "carry")])
def test_clean_users_close_their_hands_and_succeed_with_either_grasp_rule(task, hands, style, grasp_rule,
                                                                          monkeypatch):
    """The users travel open and close onto the lip (and the left hand onto the base), so the intent rule's
    closing (a grasp begins only while the hand closes) grasps the lid as eq. 3 alone does."""
    world_def = X.world_def
    monkeypatch.setattr(X, "world_def", lambda *a, **k: with_grasp_rule(grasp_rule, world_def(*a, **k)))
    r = X.Bench("exact", -0.7).run(clean(task, hands, style))
    assert r.success and r.grasp_begins >= 1 and not r.drop and not r.knocked, r
    assert hands == 1 or r.base_held


def test_a_clean_close_trial_succeeds_under_every_method_and_soft_stretches(tmp_path):
    results = {m: X.Bench(m, -0.7).run(clean("close", 1, "push"), trace=True) for m in X.METHODS}
    for m, r in results.items():
        assert r.success, (m, r)
        assert r.final_angle <= X.CLOSED_GOAL
        assert not r.false_grasp
    assert results["exact"].max_violation_m < 1e-9
    assert results["soft"].max_violation_m > 1e3 * results["exact"].max_violation_m
    rows = X.summarize(list(results.values()))
    doc = X.json_rows(rows)
    assert list(doc) == ["conditions"] and len(doc["conditions"]) == 3
    for row in doc["conditions"]:
        assert tuple(row) == X.JSON_KEYS
        assert row["method"] in X.METHODS and row["threshold"] == -0.7 and row["trials"] == 1
        assert row["success_rate"] == 1.0 and row["median_time_s"] > 0
    # the report and the plots are made from the same rows
    from handsim import plots
    from handsim.experiments.__main__ import report
    check = {"trials": 1, "same_outcome": 1, "max_angle_diff_rad": 0.0, "step_ms_full": 20.0, "step_ms_lean": 0.5}
    text = report(rows, list(results.values()), 1, check, 1.0, "python -m handsim.experiments --trials 1", 1)
    assert "**1 of 1** ended the same" in text
    assert "## Table I" in text and "## Table II" in text and "100.0 %" in text
    assert "88.2 %" in text and "4.34 ± 1.71" in text
    plots.success_rates(rows, str(tmp_path / "s.png"))
    plots.time_kde(list(results.values()), str(tmp_path / "k.png"))
    assert (tmp_path / "s.png").stat().st_size > 1000 and (tmp_path / "k.png").stat().st_size > 1000


def test_paper_cross_check_replays_the_same_users_with_the_full_pipeline():
    lean = X.run_condition("paper", -0.7, 1, cells=(("close", 1),))
    check = X.paper_cross_check(lean, 0)  # nothing replayed: nothing compared
    assert check["trials"] == 0 and check["same_outcome"] == 0
    full = X.run_condition("paper", -0.7, 1, cells=(("close", 1),), full_paper=True)
    assert [(r.seed, r.success, r.grasp_begins) for r in full] == [(r.seed, r.success, r.grasp_begins) for r in lean]


def test_kde_integrates_to_one():
    from handsim.plots import kde
    grid = np.linspace(-5, 15, 4001)
    density = kde([2.0, 3.0, 3.5, 7.0], grid)
    assert abs(float(np.sum(density) * (grid[1] - grid[0])) - 1.0) < 1e-3
    assert grid[np.argmax(density)] < 4.5


def test_world_def_of_the_conditions():
    wd = X.world_def("paper", 0.7, full_paper=True)
    assert wd.paper_pipeline and wd.particle_contacts == handsim.ParticleContacts.BULLET_OBJECTS
    assert wd.grasp.cos_threshold == 0.7
    assert not X.world_def("paper", 0.7).paper_pipeline  # the 300-trial run: the paper's solver only
    assert X.box_def("paper").solver == (handsim.JointSolver.LM_CERES if handsim.WITH_CERES
                                         else handsim.JointSolver.LM)
    assert not X.world_def("exact", -0.7).paper_pipeline
    assert X.box_def("soft").model == handsim.JointModel.SOFT
    with pytest.raises(ValueError):
        X.world_def("magic", -0.7)


def test_a_rule_replaces_the_grasp_settings_and_the_push_but_not_the_conditions_threshold():
    """--rule SPEC (the judge's syntax) runs every condition under another grasp rule or push model."""
    wd = X.world_def("exact", -0.7, rule="physical:push_model=physical,pinch_reach=0.065")
    assert wd.push_model == handsim.PushModel.PHYSICAL and wd.grasp.pinch_reach == 0.065
    assert wd.grasp.cos_threshold == -0.7
    assert X.world_def("exact", 0.7, rule="contacts").grasp.closing_distance == 0
    assert X.world_def("exact", -0.7).push_model == handsim.PushModel.WRAP
    with pytest.raises(ValueError, match="pinch_reach"):
        X.world_def("exact", -0.7, rule="bad:pinch_reach=-1")
    with pytest.raises(SystemExit):
        X_main.main(["--quick", "--rule", "bad:no_such_field=1"])
    one = X.run_condition("exact", -0.7, 1, cells=(("close", 1),), rule="physical:push_model=physical")
    assert len(one) == 1


def test_methods_and_thresholds_pick_the_conditions_run(capsys):
    """--methods / --thresholds run a subset of the conditions (one cell row each per task and hands); the report
    (--docs) needs them all, and an unknown name is an error naming the option."""
    X_main.main(["--trials", "1", "--workers", "1", "--paper-check", "0", "--methods", "exact", "--thresholds", "-0.7"])
    rows = [line for line in capsys.readouterr().out.splitlines() if "success" in line]
    assert len(rows) == len(X.CELLS) and all(line.startswith("exact c=-0.7") for line in rows)
    for argv, option in ((["--methods", "exact,bogus"], "--methods"), (["--thresholds", "0.5"], "--thresholds"),
                         (["--thresholds", "x"], "--thresholds"), (["--docs", "/nonexistent", "--methods", "exact"],
                                                                   "--docs")):
        with pytest.raises(SystemExit):
            X_main.main(argv)
        assert option in capsys.readouterr().err


def test_under_the_physical_push_the_left_hand_takes_the_base_and_does_not_knock_it():
    """Issue 20 item 6 under the physical push (docs/grasp.md "A resting body's support bears the press"): the
    two-hand users' left hand closes its fingers into the base; the base rests on the table,
    whose support and friction hold it against the pulp, so the hand closes on it and eq. 3 grasps it. Before the
    support bore the press, the overlap was pushed out at once and 8 of the first 10 open users knocked the base."""
    for task in ("open", "close"):
        trials = X.run_condition("exact", -0.7, 10, cells=((task, 2),), rule="physical:push_model=physical")
        assert all(r.base_held for r in trials), (task, [r.seed for r in trials if not r.base_held])
        assert not any(r.knocked for r in trials), (task, [r.seed for r in trials if r.knocked])
