"""The particle-count study runs and its default rule picks what it says (no timing is asserted)."""
import handsim
from handsim.bench import particles


def test_press_and_pinch_run_on_a_small_hand():
    drop = particles.lowest_vertex_drop()
    p = particles.press(100, handsim.ParticleSampling.RANDOM, drop)
    assert p["particles"] == 100
    assert len(p["linear"]) == len(particles.PRESSES)
    assert all(d >= 0 for d in p["penetration_m"])
    g = particles.pinch(100, handsim.ParticleSampling.EVEN)
    assert g.shape == (particles.PINCH_FRAMES,)


def test_default_rule_takes_the_cheapest_row_within_tolerance():
    def row(sampling, n, fit, grasp, t):
        return {"sampling": sampling, "particles": n, "fit_linear_rel_error": fit, "grasp_disagreement": grasp,
                "step_median_s": t}
    rows = [row("RANDOM", 100, 2.0, 0.0, 1e-5), row("RANDOM", 3000, 0.2, 0.0, 3e-5),
            row("EVEN", 3000, 0.1, 0.5, 2e-5), row("RANDOM", 10000, 0.1, 0.0, 9e-5), row("all", 34021, 0, 0, 2e-4)]
    assert particles.choose_default(rows)["choice"] == {"sampling": "RANDOM", "particles": 3000}
    assert particles.choose_default(rows[:1])["choice"] is None
