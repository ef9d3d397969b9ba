"""The particle-count study runs, holds the radius fixed where it says so, and its default rule picks what it
says (no timing is asserted)."""
import numpy as np

import handsim
from handsim.bench import particles


def test_press_and_pinch_run_on_a_small_hand():
    place = particles.press_placement()
    p = particles.press(100, handsim.ParticleSampling.RANDOM, place)
    assert p["particles"] == 100
    assert len(p["linear"]) == len(particles.PRESSES)
    assert all(d >= 0 for d in p["penetration_m"])
    g = particles.pinch(100, handsim.ParticleSampling.EVEN)
    assert g.shape == (particles.PINCH_FRAMES,)


def test_fixed_series_uses_the_default_hands_radius_at_every_count():
    radius = particles.default_radius()
    assert radius == handsim.HandModel(handsim.HandDef()).particle_radius > 0
    place = particles.press_placement()
    small = particles.press(100, handsim.ParticleSampling.EVEN, place, radius)
    spacing = particles.press(100, handsim.ParticleSampling.EVEN, place)
    assert small["radius_m"] == radius
    assert spacing["radius_m"] > radius  # fewer particles, wider spacing, bigger spheres
    g = particles.pinch(100, handsim.ParticleSampling.RANDOM, radius)
    assert g.shape == (particles.PINCH_FRAMES,)


def test_pressing_deeper_asks_for_a_bigger_push():
    place = particles.press_placement()
    radius = particles.default_radius()
    base = particles.press(3000, handsim.ParticleSampling.EVEN, place, radius)
    deeper = particles.press(3000, handsim.ParticleSampling.EVEN, place, radius, extra_depth=particles.DEPTH_STEP)
    assert np.median([np.linalg.norm(v) for v in deeper["linear"]]) > \
        np.median([np.linalg.norm(v) for v in base["linear"]])


def _row(sampling, n, fit, grasp, t, series="fixed"):
    return {"series": series, "sampling": sampling, "particles": n, "radius_m": 0.0037, "fit_linear_rel_error": fit,
            "fit_angular_error_rad_s": 0.0, "grasp_disagreement": grasp, "grasped_frames": 120,
            "visible_penetration_m": 0.004, "step_median_s": t}


def test_default_rule_takes_the_fewest_particles_within_tolerance_then_the_smaller_fit_error():
    rows = [_row("RANDOM", 100, 2.0, 0.0, 1e-5), _row("RANDOM", 3000, 0.2, 0.0, 3e-5),
            _row("EVEN", 3000, 0.1, 0.0, 4e-5), _row("EVEN", 1182, 0.1, 0.5, 1e-5),
            _row("RANDOM", 10000, 0.1, 0.0, 9e-5), _row("all", 34021, 0, 0, 2e-4)]
    assert particles.choose_default(rows, fit_tol=0.25)["choice"] == {"sampling": "EVEN", "particles": 3000}
    assert particles.choose_default(rows, fit_tol=0.15)["choice"] == {"sampling": "EVEN", "particles": 3000}
    assert particles.choose_default(rows, fit_tol=0.05)["choice"] is None
    assert particles.choose_default(rows[:1], fit_tol=0.25)["choice"] is None


def _result(choice, default=("EVEN", 3000)):
    rows = [_row(s, n, 0.1, 0.0, 1e-5, series) for series in particles.SERIES
            for s, n in (("RANDOM", 1182), ("EVEN", 3000), ("all", 34021))]
    ref = {"particles": 34021, "radius_m": 0.0037, "grasped_frames": 120, "push_mm": 1.0, "depth_sensitivity": 0.2}
    return {"rows": rows, "presses": 6, "pinch_frames": 120, "default_radius_m": 0.0037, "load_average": [1, 1],
            "wall_s": 1.0, "references": {s: ref for s in particles.SERIES}, "project_default": list(default),
            "default": {"fit_tol": 0.2, "grasp_tol": 0.02, "choice": choice}}


def test_report_has_both_series_and_says_whether_the_default_came_from_the_study():
    chosen = particles.report(_result({"sampling": "EVEN", "particles": 3000}))
    assert "## Fixed radius" in chosen and "## Radius from the spacing" in chosen
    assert "the default is chosen from this study" in chosen
    assert "The project default (3000 even)" in chosen and "The paper's (1182 random)" in chosen
    other = particles.report(_result({"sampling": "RANDOM", "particles": 1182}))
    assert "fit rule picks **random sampling, 1182 particles**" in other
    paper = particles.report(_result({"sampling": "EVEN", "particles": 3000}, default=("RANDOM", 1182)))
    assert paper.count("(1182 random) fits") == 1 and "The project default, the paper's (1182 random)" in paper
    assert "not backed by this run" in particles.report(_result(None))
    assert particles.table(_result({"sampling": "EVEN", "particles": 3000})).endswith(
        "chosen (fixed radius): EVEN 3000; project default: EVEN 3000")


def test_the_project_default_is_read_from_the_hand_it_builds():
    sampling, count = particles.project_default()
    d = handsim.HandDef()
    assert (sampling, count) == (d.sampling.name, d.particle_count)


def test_random_rows_average_their_draws_and_keep_the_spread():
    draws = [dict(_row("RANDOM", 3000, fit, 0.0, t), seeds=1) for fit, t in ((0.1, 1e-5), (0.3, 3e-5))]
    row = particles.mean_row(draws)
    assert row["fit_linear_rel_error"] == 0.2 and row["fit_range"] == [0.1, 0.3] and row["seeds"] == 2
    assert row["step_median_s"] == 2e-5 and row["particles"] == 3000
    assert "0.200 (0.100-0.300)" in particles._cells(row, 120)


def test_every_press_touches_the_top_face_only():
    """The skin that reaches below the box's top (plus the default radius) lies inside the top face: no press
    hangs over an edge, where contacts would get side-face normals."""
    drop, cx, cz = particles.press_placement()
    reach = particles.default_radius()
    world = handsim.World(handsim.WorldDef(ground=False))
    hand = world.add_hand(handsim.HandDef(particle_count=100))
    hx, hy, hz = particles.BOX_HALF
    for x, z, depth, roll in particles.PRESSES:
        palm = particles._palm(x - cx, hy + drop - depth, z - cz, roll)
        world.step(particles.DT, {hand: handsim.make_hand_frame(particles.R, palm)})
        v = world.hand_render_vertices(hand)
        low = v[v[:, 1] < hy + reach]
        assert len(low) > 0
        assert np.all(np.abs(low[:, 0]) < hx) and np.all(np.abs(low[:, 2]) < hz)


def test_behaviour_gate_runs_the_core_checks_on_a_small_hand():
    b = particles.behaviour(300, handsim.ParticleSampling.RANDOM)
    assert b["base_push_m"] >= 0 and np.isfinite(b["lid_slam_deg_s"]) and 0 <= b["lid_final_deg"] <= 90.5
    assert b["core_ok"] == (b["base_push_m"] < particles.GATE_BASE_PUSH_M and
                            b["lid_slam_deg_s"] < particles.GATE_LID_SLAM_DEG_S and
                            b["lid_final_deg"] > particles.GATE_LID_FINAL_DEG)
    assert "leap_missed" not in b  # no recordings asked for


def _canned(push_m, missed):
    return {"base_push_m": push_m, "lid_slam_deg_s": 10.0, "lid_final_deg": 89.0,
            "core_ok": push_m < particles.GATE_BASE_PUSH_M, "leap_missed": missed}


def test_gate_passes_a_candidate_only_if_it_is_no_worse_than_the_default(monkeypatch):
    canned = {("RANDOM", 1182): _canned(0.007, {"three-claps": ["no grasp"]}),
              ("EVEN", 3000): _canned(0.036, {"three-claps": ["no grasp"]}),
              ("RANDOM", 3000): _canned(0.001, {"three-claps": ["no grasp"], "grab": ["cube grasped"]})}
    monkeypatch.setattr(particles, "project_default", lambda: ("RANDOM", 1182))
    monkeypatch.setattr(particles, "behaviour", lambda n, s, r, recordings=None: canned[(s.name, n)])
    rows = particles.gate({"sampling": "EVEN", "particles": 3000}, 0.0037, recordings="folder")
    assert [(g["sampling"], g["particles"], g["passes"]) for g in rows] == \
        [("RANDOM", 1182, True), ("EVEN", 3000, False), ("RANDOM", 3000, False)]
    assert [g["radius_m"] for g in rows] == [particles.default_radius(), 0.0037, 0.0037]
    result = _result({"sampling": "EVEN", "particles": 3000}, default=("RANDOM", 1182))
    result.update(gate=rows, gate_recordings=True)
    text = particles.report(result)
    assert "fails the behaviour gate" in text and "### Behaviour gate" in text
    assert "grab: cube grasped" in text and "| even 3000 | 3.70 | 36.0 |" in text
    rows[1]["passes"] = True
    assert "the default does not follow this run yet" in particles.report(result)
