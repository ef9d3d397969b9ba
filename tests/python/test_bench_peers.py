"""The peers benchmark (issue 25): its JSON shape and handsim's accuracy in it, never its times."""
import numpy as np

import handsim
from handsim.bench import peers


def test_peers_one_repetition():
    doc = peers.run(quick=True, repeats=1)
    assert set(doc["scenes"]) == {"lid_drag", "cube_carry"}
    for scene, rows in doc["scenes"].items():
        mine = [r for r in rows if r["engine"].startswith("handsim")]
        assert mine and all(r["median_s"] > 0 for r in mine)
        for r in mine:
            # the hand holds the lid on its hinge and where the grip puts it, the cube where the hand holds it
            assert r["hinge_error_m"] < 1e-9
            assert r["lag"] < 1e-6
        for r in rows:
            assert "skipped" in r or r["fastest_s"] <= r["median_s"]
            if "handsim_over_peer" in r:
                assert set(r["handsim_over_peer"]) == {m["engine"] for m in mine}
    assert isinstance(doc["goal_met"], bool)
    assert "lid_drag" in peers.table(doc)


def test_the_cube_carry_pinch_grasps_under_wrap():
    """The cube rests on the ground; the hand comes down with the thumb open and closes thumb and index pads on it.
    Under PushModel.WRAP the closing digits leave the supported cube where it is (docs/grasp.md "A closing digit does
    not displace a free body"), so the pads meet its opposite faces and grasp it where it rests."""
    cube = peers.HandsimCube(push_model=handsim.PushModel.WRAP)
    cube.build()  # raises when the pinch does not grasp
    assert np.linalg.norm(cube.offset) < 0.01


def test_contact_changes():
    # The still hold's contacts change depth by rounding only, and so do the eased carry's since the held cube
    # follows its hand before the contacts (docs/performance.md, docs/grasp.md "The hold path")
    doc = peers.contact_changes()
    lid, = doc["scenes"]["lid_drag"]
    assert lid["pairs"] == peers.FRAMES - 1 and lid["touching_median"] > 0
    assert lid["largest_change_median_m"] < 1e-12
    for r in doc["scenes"]["cube_carry"]:
        assert r["pairs"] == peers.FRAMES - 1 and r["touching_min"] >= 2 and r["largest_change_max_m"] < 1e-12
    assert "cube_carry" in peers.contact_changes_table(doc)
