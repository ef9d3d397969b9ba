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


def _result(choice):
    rows = [_row(s, n, 0.1, 0.0, 1e-5, series) for series in particles.SERIES
            for s, n in (("RANDOM", 1182), ("all", 34021))]
    ref = {"particles": 34021, "radius_m": 0.0037, "grasped_frames": 120, "push_mm": 1.0, "depth_sensitivity": 0.2}
    return {"rows": rows, "presses": 6, "pinch_frames": 120, "default_radius_m": 0.0037, "load_average": [1, 1],
            "wall_s": 1.0, "references": {s: ref for s in particles.SERIES},
            "default": {"fit_tol": 0.2, "grasp_tol": 0.02, "choice": choice}}


def test_report_has_both_series_and_says_whether_the_default_came_from_the_study():
    chosen = particles.report(_result({"sampling": "RANDOM", "particles": 1182}))
    assert "## Fixed radius" in chosen and "## Radius from the spacing" in chosen
    assert "the default is chosen from this study" in chosen
    other = particles.report(_result({"sampling": "EVEN", "particles": 3000}))
    assert "pending decision" in other and "3000 particles" in other
    assert "pending decision" in particles.report(_result(None))
    assert "chosen (fixed radius): RANDOM 1182" in particles.table(_result({"sampling": "RANDOM", "particles": 1182}))


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
        world.step(particles.DT, [handsim.make_hand_frame(particles.R, palm)])
        v = world.hand_render_vertices(hand)
        low = v[v[:, 1] < hy + reach]
        assert len(low) > 0
        assert np.all(np.abs(low[:, 0]) < hx) and np.all(np.abs(low[:, 2]) < hz)
