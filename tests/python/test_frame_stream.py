"""handsim.frame_stream: the flat session file engine hosts read (the Godot sample)."""
import numpy as np
import pytest

import handsim
from handsim import frame_stream, recording


def _session(steps=12, hands=None):
    rec = recording.Recorder("jewelry_box", hands=hands)
    box = rec.scene.box
    for i in range(steps):
        palm = box.lid_pinch_palm(rec.world, handsim.Handedness.RIGHT, 0.01 * i, 0.0)
        rec.step(1 / 60, {rec.hands[0]: handsim.make_hand_frame(handsim.Handedness.RIGHT, palm,
                                                            params=handsim.lid_pinch_shape())})
    return rec


def test_round_trip_replays_to_the_recorded_hashes(tmp_path):
    rec = _session().recording
    path = frame_stream.save(rec, tmp_path / "s.hsframes")
    # header 24 + handedness 4 + 12 steps of (16 + 8 + 26 * 72)
    assert path.stat().st_size == 24 + 4 + 12 * (16 + 8 + 26 * 72)
    back = frame_stream.load(path)
    np.testing.assert_array_equal(back.positions, rec.positions)
    np.testing.assert_array_equal(back.hashes, rec.hashes)
    assert recording.replay(back).matches


def test_a_hand_without_frames_and_a_left_hand(tmp_path):
    hands = [handsim.HandDef(handedness=handsim.Handedness.RIGHT), handsim.HandDef(handedness=handsim.Handedness.LEFT)]
    rec = _session(4, hands).recording
    back = frame_stream.load(frame_stream.save(rec, tmp_path / "s.hsframes"))
    assert [h["handedness"] for h in back.hands] == ["RIGHT", "LEFT"]
    assert not back.present[:, 1].any() and recording.replay(back).matches


@pytest.mark.parametrize("change, field", [
    (dict(scene="free_box"), "scene"),
    (dict(scene_params={"yaw": 0.5}), "scene_params"),
    (dict(edits=[{"step": 0, "op": "set_joint_value", "joint": "hinge", "value": 0.2}]), "edits"),
])
def test_what_a_host_cannot_rebuild_is_refused(tmp_path, change, field):
    import dataclasses
    rec = dataclasses.replace(_session(2).recording, **change)
    with pytest.raises(recording.RecordingError, match=field):
        frame_stream.save(rec, tmp_path / "s.hsframes")
    assert not (tmp_path / "s.hsframes").exists()


def test_non_default_world_or_hand_is_refused(tmp_path):
    rec = _session(2).recording
    rec.world = dict(rec.world, fixed_substep=1 / 120)
    with pytest.raises(recording.RecordingError, match=r"world\.fixed_substep"):
        frame_stream.save(rec, tmp_path / "a.hsframes")
    rec = _session(2).recording
    rec.hands = [dict(rec.hands[0], particle_count=500)]
    with pytest.raises(recording.RecordingError, match=r"hands\[0\]\.particle_count"):
        frame_stream.save(rec, tmp_path / "b.hsframes")


def test_bad_files_name_the_problem(tmp_path):
    good = frame_stream.save(_session(3).recording, tmp_path / "s.hsframes").read_bytes()
    cases = {"foreign": b"PK\x03\x04 a zip", "cut": good[:-1], "version": good[:8] + b"\x02" + good[9:]}
    for name, data in cases.items():
        (tmp_path / name).write_bytes(data)
        with pytest.raises(recording.RecordingError, match="path"):
            frame_stream.load(tmp_path / name)
