"""The step benchmark's JSON shape and its report (never its times: no timed asserts)."""
import json
import re
import shutil
import subprocess
import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parents[2] / "docs"

SCENES = {"jewelry_box", "free_box", "far_hand", "ten_objects", "particles_sweep", "render_sweep"}


def test_step_quick_json_and_report_keep_every_marked_section(tmp_path):
    # The report regenerates docs/performance.md around the sections other benchmarks and people write: run on a
    # copy of the repo's page, every marked section comes back verbatim (a regeneration once dropped the
    # hand-written analyses, and the CLI then failed calling the wrong write_doc).
    (tmp_path / "img").mkdir()
    shutil.copy(DOCS / "performance.md", tmp_path / "performance.md")
    out = subprocess.run([sys.executable, "-m", "handsim.bench", "step", "--quick", "--json", "--doc", str(tmp_path)],
                         check=True, capture_output=True, text=True, timeout=300).stdout
    section = re.compile(r"<!-- section (\w+) -->.*?<!-- /section \1 -->", re.S)
    before = {m.group(1): m.group(0) for m in section.finditer((DOCS / "performance.md").read_text())}
    after = {m.group(1): m.group(0) for m in section.finditer((tmp_path / "performance.md").read_text())}
    assert {"peers", "peers_instructions", "peers_notes", "sweeps", "sweeps_notes"} <= set(before)
    assert after == before
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
    # scene (a) measures a held lid: its hand reaches and closes its pinch in the warm-up, so every timed frame holds
    # it (a hand that appeared already pinching never grasped, and the scene measured a touch instead)
    for s in steps:
        if s["scene"] == "jewelry_box":
            assert s["grasped_frames"] == s["frames"], s["pipeline"]
