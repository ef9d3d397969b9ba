"""The step benchmark's JSON shape (never its times: no timed asserts)."""
import json
import subprocess
import sys

SCENES = {"jewelry_box", "free_box", "far_hand", "ten_objects", "particles_sweep", "render_sweep"}


def test_step_quick_json():
    out = subprocess.run([sys.executable, "-m", "handsim.bench", "step", "--quick", "--json"],
                         check=True, capture_output=True, text=True, timeout=300).stdout
    doc = json.loads(out)
    steps = doc["steps"]
    assert {s["scene"] for s in steps} == SCENES
    for s in steps:
        assert {"scene", "pipeline", "particles", "render_vertices", "median_s", "p99_s", "stages"} <= set(s)
        assert s["pipeline"] in ("lean", "paper")
        assert 0 < s["median_s"] <= s["p99_s"]
        assert "skinning" in s["stages"] and all(v >= 0 for v in s["stages"].values())
    # both pipelines for every configuration, in the same run
    assert len(doc["ratios"]) * 2 == len(steps)
