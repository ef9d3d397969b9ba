"""Hand input (issue 12): tracker adapters, record and replay, real recorded motion.

Tests that use ../shared/assets (Leap recordings, MRTK poses) skip when the folder is absent; the rest build
their input from make_hand_frame."""
import json
import math
import os
from pathlib import Path

import numpy as np
import pytest

import handsim
from handsim import recording, replay
from handsim.adapters import bvh, leap, lzstring, mediapipe, mrtk, openxr, skeleton
from handsim.adapters.leap import (MM, TIP_EXTENSION, load_leap_recording, read_leap_json)

RIGHT, LEFT = handsim.Handedness.RIGHT, handsim.Handedness.LEFT
PALM_POSE = [0.05, 1.0, -0.2, 0, math.sin(0.3), 0, math.cos(0.3)]
POSES = {"flat": {}, "fist": {"curl": 1.0},
         "pinch": {"curl": [0.2, 0.3, 0.0, 0.0, 0.0], "thumb_opposition": 1.0}}
FLEX = [handsim.THUMB_PROXIMAL, handsim.THUMB_DISTAL] + [
    j for f in ("INDEX", "MIDDLE", "RING", "LITTLE") for j in (getattr(handsim, f + "_INTERMEDIATE"),
                                                             getattr(handsim, f + "_DISTAL"))]


def shared(sub):
    candidates = []
    if os.environ.get("HANDSIM_SHARED_ASSETS"):
        candidates.append(Path(os.environ["HANDSIM_SHARED_ASSETS"]) / sub)
    candidates.append(Path(__file__).resolve().parents[2].parent / "shared" / "assets" / sub)
    for c in candidates:
        if c.is_dir() and any(c.iterdir()):
            return c
    return None


def source(name, handedness=RIGHT):
    return handsim.make_hand_frame(handedness, PALM_POSE, **POSES[name])


def flexion_deg(frame):
    return np.degrees(skeleton.joint_angles(frame))


# --- LZ-String -----------------------------------------------------------------------------------------

def lz_compress_base64(text):
    """LZ-String compressToBase64, written from the format description for this test only."""
    out, val, pos = [], 0, 0

    def bits(value, n):
        nonlocal val, pos
        for _ in range(n):
            val = (val << 1) | (value & 1)
            value >>= 1
            if pos == 5:
                out.append(val)
                val, pos = 0, 0
            else:
                pos += 1

    dictionary, fresh = {}, set()
    size, num_bits, enlarge = 3, 2, 2
    w = ""

    def emit(word):
        nonlocal enlarge, num_bits
        if word in fresh:
            code = ord(word[0])
            bits(0 if code < 256 else 1, num_bits)
            bits(code, 8 if code < 256 else 16)
            enlarge -= 1
            if enlarge == 0:
                enlarge, num_bits = 1 << num_bits, num_bits + 1
            fresh.discard(word)
        else:
            bits(dictionary[word], num_bits)
        enlarge -= 1
        if enlarge == 0:
            enlarge, num_bits = 1 << num_bits, num_bits + 1

    for c in text:
        if c not in dictionary:
            dictionary[c] = size
            size += 1
            fresh.add(c)
        if w + c in dictionary:
            w = w + c
        else:
            emit(w)
            dictionary[w + c] = size
            size += 1
            w = c
    if w:
        emit(w)
    bits(2, num_bits)
    while True:
        val <<= 1
        if pos == 5:
            out.append(val)
            break
        pos += 1
    alphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/"
    s = "".join(alphabet[v] for v in out)
    return s + "=" * (-len(s) % 4)


@pytest.mark.parametrize("text", ["", "a", "hello hello hello", '{"frames": [1, 2, 3], "x": "ü€"}',
                                  "".join(chr(32 + (i * 7919) % 400) for i in range(3000))])
def test_lzstring_round_trip(text):
    assert lzstring.decompress_from_base64(lz_compress_base64(text)) == text


def test_lzstring_bad_input_names_the_argument():
    with pytest.raises(lzstring.LZStringError, match=r"^blob: not Base64 LZ-String data \(character '\*' at 4\)"):
        lzstring.decompress_from_base64("N4Ig*", "blob")
    good = lz_compress_base64("a fairly long text " * 20)
    with pytest.raises(lzstring.LZStringError, match="^text: LZ-String data ends in the middle of a code"):
        lzstring.decompress_from_base64(good[:40])
    with pytest.raises(TypeError, match="^text: expected str, got bytes"):
        lzstring.decompress_from_base64(b"abc")


# --- Leap -------------------------------------------------------------------------------------------------

def leap_objects(frame, version, hand_id=7, grab=0.0):
    """A Leap hand and its pointables (v0.1 fields, plus carp/btip for v2) made from a HandFrame, in mm."""
    p = np.asarray(frame.positions) / MM
    R = skeleton.quat_matrix(frame.orientations[handsim.PALM])
    hand = {"id": hand_id, "type": "right" if frame.handedness == RIGHT else "left",
            "direction": list(-R[:, 2]), "palmNormal": list(-R[:, 1]), "palmPosition": list(p[handsim.PALM]),
            "grabStrength": grab, "pinchStrength": 0.0, "confidence": 1.0}
    pointables = []
    for t, f in enumerate(("thumb", "index", "middle", "ring", "little")):
        c = skeleton.chain(f)
        pts = ([p[c[0]]] + [p[j] for j in c]) if f == "thumb" else [p[j] for j in c]
        carp, mcp, pip, dip, btip = pts
        obj = {"id": 10 * hand_id + t, "handId": hand_id, "type": t, "mcpPosition": list(mcp),
               "pipPosition": list(pip), "dipPosition": list(dip),
               "tipPosition": list(dip + (btip - dip) / TIP_EXTENSION)}
        if version == 2:
            obj.update(carpPosition=list(carp), btipPosition=list(btip))
        pointables.append(obj)
    return hand, pointables


def leap_doc(frames, version):
    if version != 2:
        out = []
        for i, f in enumerate(frames):
            hand, pointables = leap_objects(f, version)
            out.append({"id": i, "timestamp": 1000 + 9000 * i, "hands": [hand], "pointables": pointables})
        return {"metadata": {"formatVersion": version}, "frames": out}
    hand_keys = ["id", "type", "direction", "palmNormal", "palmPosition", "grabStrength", "pinchStrength"]
    pointable_keys = ["id", "direction", "handId", "tipPosition", "carpPosition", "mcpPosition", "pipPosition",
                      "dipPosition", "btipPosition"]
    packed = [["id", "timestamp", {"hands": [hand_keys]}, {"pointables": [pointable_keys]},
               {"interactionBox": ["center", "size"]}]]
    for i, f in enumerate(frames):
        hand, pointables = leap_objects(f, 2)
        packed.append([i, 1000 + 17000 * i, [[hand.get(k) for k in hand_keys]],
                       [[p.get(k, [0, 0, 1]) for k in pointable_keys] for p in pointables], [[0, 200, 0], [1, 1, 1]]])
    return {"metadata": {"formatVersion": 2}, "frames": packed}


@pytest.mark.parametrize("version", [0.1, 2])
def test_leap_frames_map_to_the_openxr_joints(version, tmp_path):
    frames = [source(name) for name in POSES]
    path = tmp_path / "synthetic.json"
    path.write_text(json.dumps(leap_doc(frames, version)))
    rec = load_leap_recording(path)
    assert rec.format_version == version and rec.hand_counts() == {1: 3}
    np.testing.assert_allclose(rec.times, np.arange(3) * (0.009 if version != 2 else 0.017), atol=1e-12)
    for f, conv in zip(frames, rec.frames):
        a = conv["right"]
        assert a.invalid == ()
        given = [j for j in range(26) if j not in (handsim.PALM, handsim.WRIST) and
                 (version == 2 or handsim.JOINT_NAMES[j].split("_")[1] != "metacarpal" or j == handsim.THUMB_METACARPAL)]
        np.testing.assert_allclose(np.asarray(a.frame.positions)[given], np.asarray(f.positions)[given], atol=1e-9)
        p = np.asarray(a.frame.positions)
        np.testing.assert_allclose(p[handsim.PALM], 0.5 * (p[handsim.MIDDLE_METACARPAL] + p[handsim.MIDDLE_PROXIMAL]))
        np.testing.assert_allclose(flexion_deg(a.frame)[FLEX], flexion_deg(f)[FLEX], atol=1e-6)
        expected = {"palm", "wrist"} | ({"thumb_tip"} | {g + "_" + b for g in ("index", "middle", "ring", "little")
                                                           for b in ("metacarpal", "tip")} if version != 2 else set())
        assert set(a.synthesized) == expected
    flat, fist = (flexion_deg(rec.frames[i]["right"].frame) for i in (0, 1))
    assert flat[handsim.INDEX_INTERMEDIATE] < 5 and fist[handsim.INDEX_INTERMEDIATE] > 60


def test_leap_errors_name_what_is_wrong(tmp_path):
    doc = leap_doc([source("flat")], 0.1)
    with pytest.raises(ValueError, match=r"formatVersion 3 is not supported"):
        read_leap_json({**doc, "metadata": {"formatVersion": 3}})
    doc["frames"][0]["pointables"][1]["dipPosition"] = [1, float("nan"), 2]
    with pytest.raises(ValueError, match=r"pointables\[type 1\]\.dipPosition: expected 3 finite numbers"):
        read_leap_json(doc)
    doc = leap_doc([source("flat")], 0.1)
    doc["frames"][0]["hands"][0]["type"] = "middle"
    with pytest.raises(ValueError, match=r"^recording\.frames\[0\]\.hands\[0\]\.type: expected 'left' or 'right'"):
        read_leap_json(doc)
    doc = leap_doc([source("flat")], 0.1)
    del doc["frames"][0]["timestamp"]
    with pytest.raises(ValueError, match=r"^recording\.frames\[0\]\.timestamp: expected a number"):
        read_leap_json(doc)
    with pytest.raises(FileNotFoundError, match="^path: no such file"):
        load_leap_recording(tmp_path / "missing.json.lz")
    (tmp_path / "bad.json.lz").write_text("!!!")
    with pytest.raises(lzstring.LZStringError, match=r"^path \(bad\.json\.lz\): not Base64"):
        load_leap_recording(tmp_path / "bad.json.lz")


@pytest.mark.parametrize("version", [0.1, 2])
def test_fuzzed_leap_documents_load_or_name_what_is_wrong(version):
    """Seeded mutations of a small document (fields dropped, or set to null, strings, numbers, lists,
    objects, NaN, 1e300): each reads as a recording, or raises ValueError naming where; nothing else."""
    import copy
    import random
    base = leap_doc([source("flat"), source("fist"), source("pinch")], version)

    def places(obj, at=()):
        items = obj.items() if isinstance(obj, dict) else enumerate(obj) if isinstance(obj, list) else ()
        for k, v in items:
            yield at + (k,)
            yield from places(v, at + (k,))

    where = list(places(base))
    rng = random.Random(12)
    values = [None, "x", 3, -1.5, True, [], {}, [1, 2], [float("nan"), 0, 0], [1e300, 0, 0], {"a": 1}]
    loaded = named = 0
    for _ in range(400):
        doc = copy.deepcopy(base)
        for _ in range(rng.randint(1, 3)):
            *path, last = rng.choice(where)
            try:
                parent = doc
                for k in path:
                    parent = parent[k]
                if isinstance(parent, dict) and rng.random() < 0.4:
                    parent.pop(last, None)
                else:
                    parent[last] = rng.choice(values)
            except (KeyError, IndexError, TypeError):
                pass  # an earlier mutation took that place away
        try:
            rec = read_leap_json(doc, "fuzz")
            loaded += 1
            assert all(np.isfinite(np.asarray(a.frame.positions)[np.asarray(a.frame.valid)]).all()
                       for f in rec.frames for a in f.values())
        except ValueError as e:
            assert str(e).startswith(("fuzz", "frames")), e
            named += 1
    assert loaded > 50 and named > 50, (loaded, named)


def leap_v1_objects(frame, hand_id=7, seen=(0, 1, 2, 3, 4)):
    """A hand as Leap SDKs before 2.0 sent it, made from a HandFrame (mm): no hand or finger type, no bone
    joints; a pointable (tipPosition and direction) for each finger in `seen` only, in a shuffled order."""
    p = np.asarray(frame.positions) / MM
    R = skeleton.quat_matrix(frame.orientations[handsim.PALM])
    d, n = -R[:, 2], -R[:, 1]
    right = frame.handedness == RIGHT
    a, b, e = leap.PALM_OFFSET_MM
    palm = p[handsim.PALM] - (a * d + b * n + (e if right else -e) * np.cross(d, n))
    hand = {"id": hand_id, "direction": list(d), "palmNormal": list(n), "palmPosition": list(palm)}
    pointables = []
    for t in reversed(seen):
        c = skeleton.chain(("thumb", "index", "middle", "ring", "little")[t])
        u, v = (c[1], c[2]) if t == 0 else (c[2], c[3])  # Leap's direction: the bone from pip to dip
        pointables.append({"id": 100 + t, "handId": hand_id, "tipPosition": list(p[c[-1]]),
                           "direction": list((p[v] - p[u]) / np.linalg.norm(p[v] - p[u])), "tool": False})
    return hand, pointables


FINGER_JOINTS = [j for f in ("INDEX", "MIDDLE", "RING", "LITTLE") for j in
                 (getattr(handsim, f + "_PROXIMAL"), getattr(handsim, f + "_INTERMEDIATE"),
                  getattr(handsim, f + "_DISTAL"), getattr(handsim, f + "_TIP"))]


@pytest.mark.parametrize("handedness", [RIGHT, LEFT])
def test_leap_hands_without_a_skeleton_or_type_are_rebuilt_from_the_palm(handedness):
    """Leap before 2.0: the side comes from how the fingers fit each side's hand (over the hand id's frames,
    even on the other side of the device), the palm joint from palmPosition, the fingers it reports bend as
    their directions say, the ones it does not report curl as the grab strength says, or fully."""
    poses = [handsim.make_hand_frame(handedness, PALM_POSE, curl=[0.0, c, c, 0.5 * c, c]) for c in (0.0, 0.4, 0.8)]
    fist = handsim.make_hand_frame(handedness, PALM_POSE, curl=1.0)
    sign = 1 if handedness == RIGHT else -1

    def doc(frames, shift_mm, seen):
        out = []
        for i, f in enumerate(frames):
            hand, pointables = leap_v1_objects(f, seen=seen(i))
            for obj in [hand] + pointables:
                obj["palmPosition" if obj is hand else "tipPosition"][0] += shift_mm
            out.append({"id": i, "timestamp": 9000 * i, "hands": [hand], "pointables": pointables})
        return {"metadata": {"formatVersion": 1}, "frames": out}

    side = "right" if handedness == RIGHT else "left"
    # 40 cm on the other side of the device: the fingers, not the place, tell the side
    rec = read_leap_json(doc(poses + [fist], -sign * 400, lambda i: (0, 1, 2, 3, 4) if i < 3 else (0,)))
    assert [list(f) for f in rec.frames] == [[side]] * 4
    assert rec.notes == {"side from the finger fit (no type)": 4, "rebuilt from the palm (no full skeleton)": 4}
    for f, conv in zip(poses + [fist], rec.frames):
        a = conv[side]
        assert set(a.synthesized) == set(handsim.JOINT_NAMES) and a.invalid == ()
        got, want = np.asarray(a.frame.positions), np.asarray(f.positions) - [sign * 0.4, 0, 0]
        np.testing.assert_allclose(got[handsim.PALM], want[handsim.PALM], atol=1e-9)
        np.testing.assert_allclose(a.frame.orientations[handsim.PALM], f.orientations[handsim.PALM], atol=1e-9)
        assert np.abs(got[FINGER_JOINTS] - want[FINGER_JOINTS]).max() < 1e-3  # curl recovered to 1 mm
        np.testing.assert_allclose(flexion_deg(a.frame)[FLEX], flexion_deg(f)[FLEX], atol=1.0)
    # too few fingers to fit (a fist showing its thumb only): the device side, then the hand id
    rec = read_leap_json(doc([fist, fist], sign * 400, lambda i: (0,)))
    assert [list(f) for f in rec.frames] == [[side]] * 2
    assert rec.notes == {"side from the device side (no type)": 1, "side from the hand id (no type)": 1,
                         "rebuilt from the palm (no full skeleton)": 2}
    np.testing.assert_allclose(np.asarray(rec.frames[1][side].frame.positions)[FINGER_JOINTS],
                               (np.asarray(fist.positions) + [sign * 0.4, 0, 0])[FINGER_JOINTS], atol=1e-9)


def test_leap_frames_with_missing_parts_are_kept():
    """A real recording may lack what a frame usually has: none of it stops the recording."""
    flat = source("flat")
    hand, pointables = leap_objects(flat, 0.1)
    typed_v1, untyped = leap_v1_objects(flat, hand_id=8)
    del typed_v1["palmNormal"]  # a hand without a palm pose and without a type: untracked in that frame
    del pointables[2]["pipPosition"]  # a finger without its bone joints: the hand is rebuilt from its palm
    tool = {"id": 99, "handId": 7, "tool": True, "tipPosition": [0, 0, 0], "direction": [0, 0, 1]}
    left = leap_objects(source("flat", LEFT), 0.1, hand_id=9)
    left[0].pop("type")  # its thumb tells the side
    twin = leap_objects(source("fist"), 0.1, hand_id=10)  # a second right hand: the first listed is kept
    frames = [{"id": 0, "timestamp": 0, "hands": [hand, typed_v1, left[0], twin[0]],
               "pointables": pointables + untyped + [tool] + left[1] + twin[1]},
              {"id": 1, "timestamp": -5, "hands": [hand], "pointables": pointables},  # back in time: dropped
              {"id": 2, "timestamp": 9000, "hands": [], "pointables": []}]
    rec = read_leap_json({"metadata": {"formatVersion": 0.1}, "frames": frames})
    assert len(rec.frames) == 2 and sorted(rec.frames[0]) == ["left", "right"] and rec.frames[1] == {}
    assert rec.notes == {"side from the thumb (no type)": 1, "untracked: no palm pose": 1,
                         "rebuilt from the palm (no full skeleton)": 1, "second hand of a side, dropped": 1,
                         "frames out of time order, dropped": 1,
                         "side from the device side (no type), the other hand's side taken": 1}
    assert "thumb_proximal" in rec.frames[0]["right"].synthesized  # rebuilt: every joint made up
    assert "index_proximal" not in rec.frames[0]["left"].synthesized  # its skeleton was complete
    np.testing.assert_allclose(rec.times, [0, 0.009])


@pytest.fixture(scope="module")
def leap_recordings():
    where = shared("leap_recordings")
    if where is None:
        pytest.skip("the Leap recordings are not there (../shared/assets/leap_recordings)")
    return {p.name.split(".")[0]: load_leap_recording(p) for p in sorted(where.glob("*.json.lz"))}


# frames and hands per frame as listed in the recordings' README
README_COUNTS = {"grab": (374, {1: 374}), "pinch": (307, {1: 307}), "pinch-half-res": (154, {1: 154}),
                 "pinch-57fps": (133, {1: 133}), "three-claps": (403, {2: 403}), "flapping": (328, {2: 328}),
                 "confidence2": (368, {2: 368}), "confidence2-49fps": (171, {1: 39, 2: 132}),
                 "confidence-demo": (1080, {1: 1080}), "confidence-demo-half-res": (540, {1: 540}),
                 "confidence-demo-quarter-res": (270, {1: 270}), "confidence-demo-eighth-res": (135, {1: 135})}


def dev_recording(leap_recordings, name):
    """One recording of the development half by name; skips when the folder holds other recordings."""
    if name not in leap_recordings:
        pytest.skip(f"{name} is not among the recordings of {shared('leap_recordings')}")
    return leap_recordings[name]


def recording_names():
    """Every recording in the folder (tests replay whatever is there), else the README's names (they skip)."""
    where = shared("leap_recordings")
    return sorted(p.name.split(".")[0] for p in where.glob("*.json.lz")) if where else sorted(README_COUNTS)


def test_real_leap_recordings_decode_and_map(leap_recordings):
    for name, rec in leap_recordings.items():
        if name in README_COUNTS:
            frames, hands = README_COUNTS[name]
            assert (len(rec.frames), rec.hand_counts()) == (frames, hands), name
            assert rec.notes == {}, name  # every hand of the development half has type and skeleton
        assert len(rec.frames) > 0 and np.all(np.diff(rec.times) >= 0), name
        for f in rec.frames[::10]:
            for a in f.values():
                assert a.frame.tracked and a.invalid == ()
                assert np.isfinite(a.frame.positions).all()


@pytest.mark.parametrize("name", recording_names())
def test_real_hands_without_their_skeleton_are_rebuilt_near_it(name, leap_recordings):
    """Every hand of a recording given to the adapter as a Leap SDK before 2.0 sent it (no types, no bone
    joints, no curled fingers) lands on the right side, its palm joint within 5 mm of the skeleton's and its
    fingertips within a few centimetres (docs/input.md has the figures: the synthetic hand's proportions are
    not the person's)."""
    from handsim import input_report
    from handsim.adapters.leap import read_leap_document
    where = shared("leap_recordings")
    doc = read_leap_document(where / f"{name}.json.lz")
    if doc["metadata"].get("formatVersion") == 2:
        pytest.skip("a packed formatVersion 2 recording: without_skeleton takes frame objects")
    e = input_report.rebuild_error(doc, name)
    if e is None:
        pytest.skip("no hand in the recording")
    if name in README_COUNTS:  # bounds from the development half; other recordings need only rebuild
        assert e["side_right"] == 1.0 and e["palm_max_mm"] < 5, e
        assert max(e["tip_median_mm"]) < 75 and np.median(e["tip_median_mm"]) < 45, e


@pytest.mark.parametrize("name", sorted(README_COUNTS))
def test_the_thumb_tells_the_side_of_every_development_hand(name, leap_recordings):
    """adapters.leap.thumb_side, the first rule for a hand without a type, against the type of every hand of
    every frame of a development recording."""
    from handsim.adapters.leap import read_leap_document, thumb_side
    dev_recording(leap_recordings, name)  # skips when the folder holds other recordings
    where = shared("leap_recordings") / f"{name}.json.lz"
    doc = read_leap_document(where)
    frames = leap._unpack_v2(doc["frames"]) if doc["metadata"]["formatVersion"] == 2 else doc["frames"]
    hands = [(h, [p for p in fr["pointables"] if p["handId"] == h["id"]]) for fr in frames for h in fr["hands"]]
    assert hands and all(thumb_side(h, own) == h["type"] for h, own in hands)


def test_pinch_half_res_is_every_second_frame_of_pinch(leap_recordings):
    full, half = dev_recording(leap_recordings, "pinch"), dev_recording(leap_recordings, "pinch-half-res")
    for i in (0, 40, 153):
        np.testing.assert_array_equal(half.frames[i]["right"].frame.positions, full.frames[2 * i]["right"].frame.positions)


def test_a_formatversion_2_recording_gives_its_metacarpals(leap_recordings):
    doc = dev_recording(leap_recordings, "pinch-57fps")
    assert doc.format_version == 2 and "middle_metacarpal" not in doc.frames[0]["right"].synthesized


def test_rebuilt_metacarpal_bases_are_leaps_own(leap_recordings):
    """Issue 20 item 5: pinch-57fps given as formatVersion 1 frames (no carpPosition, btipPosition, bases) gets
    every finger's metacarpal base from Leap's hand model (leap.METACARPALS) within 5 mm of Leap's carpPosition
    (the 15 % rule put the index, ring and little ones 8.8, 8.9 and 19.0 mm off; the model is rigid in the palm
    frame, so it is 0.00 mm but for the constants' four digits)."""
    dev_recording(leap_recordings, "pinch-57fps")
    errors = leap.metacarpal_errors(shared("leap_recordings") / "pinch-57fps.json.lz")
    assert set(errors) == {"index", "middle", "ring", "little"} and max(errors.values()) < 0.1, errors


def test_leap_scales_its_hand_model_as_a_whole(leap_recordings):
    """The metacarpals are scaled by the middle proximal bone: Leap's knuckles, in units of that bone, lie at
    one place in the palm axes (left hands mirrored) over every hand of the 0.1 recordings, whose hands are
    44.6 to 47.0 mm in that bone (the formatVersion 2 recording has one size only)."""
    dev_recording(leap_recordings, "confidence-demo")
    scales = leap.model_scale(sorted(shared("leap_recordings").glob("*.json.lz")))
    old = scales["0.1/1"]
    assert old["proximal_mm"][1] - old["proximal_mm"][0] > 2 and old["spread_mm"] < 0.01, old
    assert scales["2"]["spread_mm"] < 0.01, scales["2"]


# The skeleton's strengths in Leap's documented meaning (skeleton.closure_strengths) agree with Leap's labels in
# fewer than 95 % of the labelled frames of these recordings (docs/input.md, `python -m handsim.input_report`):
# Leap calls a hand fully grabbing long before its own skeleton is a fist. Strict: an entry goes when it is met.
LABELS_SHORT = {"confidence-demo-eighth-res": 81.2, "confidence-demo-half-res": 81.1,
                "confidence-demo-quarter-res": 80.9, "confidence-demo": 81.0, "confidence2-49fps": 93.9,
                "confidence2": 85.6, "grab": 91.9, "pinch-half-res": 89.6, "pinch": 89.2}


@pytest.mark.parametrize("name", [pytest.param(n, marks=pytest.mark.xfail(
    strict=True, reason=f"issue 20: {LABELS_SHORT[n]} % of Leap's labels")) if n in LABELS_SHORT else n
    for n in sorted(README_COUNTS)])
def test_skeleton_strengths_agree_with_leaps_labels_frame_by_frame(name, leap_recordings):
    """Issue 20: the skeleton's max(grab, pinch) (skeleton.closure_strengths, for trackers without strengths)
    labels >= 95 % of the frames Leap calls closed (>= 0.9) or open (< 0.3) the same (the judge's labels,
    handsim.intent.labels), in every development recording, not only which hand closes. The strengths have
    Leap's documented meaning with anchors on make_hand_frame's hand, nothing set from these recordings."""
    from handsim import input_report
    a = input_report.label_agreement(dev_recording(leap_recordings, name))
    agree = (a["closed"][0] + a["open"][0]) / (a["closed"][1] + a["open"][1])
    assert agree >= 0.95, (name, round(100 * agree, 1), a)


def test_a_grab_closes_the_fingers_as_leaps_grab_strength_says(leap_recordings):
    grab = dev_recording(leap_recordings, "grab")
    flex = np.array([flexion_deg(f["right"].frame)[handsim.INDEX_INTERMEDIATE] for f in grab.frames])
    assert flex[grab.grab[:, 0] >= 0.99].min() > 50 and flex[grab.grab[:, 0] <= 0.01].max() < 40


# --- OpenXR, Unity, MRTK --------------------------------------------------------------------------------------

def test_openxr_is_the_identity_and_unity_converts_handedness():
    f = source("pinch")
    a = openxr.from_openxr("right", f.positions, f.orientations, f.radii, f.valid)
    for attr in ("positions", "orientations", "radii", "valid"):
        np.testing.assert_array_equal(getattr(a.frame, attr), getattr(f, attr))
    assert a.synthesized == () and a.invalid == ()
    up, uq = openxr.unity_to_openxr(f.positions, f.orientations)  # the map is its own inverse
    b = openxr.from_unity(RIGHT, up, uq * 1.0004, f.radii)
    np.testing.assert_allclose(b.frame.positions, f.positions, atol=1e-15)
    np.testing.assert_allclose(b.frame.orientations, f.orientations, atol=1e-12)
    # in Unity's space a joint's +Z points along its bone (OpenXR: -Z)
    for j in (handsim.INDEX_PROXIMAL, handsim.THUMB_PROXIMAL):
        bone = up[j + 1] - up[j]
        assert skeleton.quat_matrix(uq[j])[:, 2] @ bone > 0.999 * np.linalg.norm(bone)


def test_openxr_and_unity_errors_name_the_argument():
    f = source("flat")
    p = np.asarray(f.positions).copy()
    p[7, 1] = np.nan
    with pytest.raises(ValueError, match=r"^positions\[7\]: must be finite"):
        openxr.from_openxr(RIGHT, p, f.orientations)
    valid = np.ones(26, bool)
    valid[7] = False
    a = openxr.from_openxr(RIGHT, p, f.orientations, valid=valid)
    assert a.invalid == ("index_proximal",)
    with pytest.raises(ValueError, match=r"^orientations: expected shape \(26, 4\), got \(26, 3\)"):
        openxr.from_openxr(RIGHT, f.positions, f.positions)
    with pytest.raises(TypeError, match="^handedness: expected handsim.Handedness or 'left'/'right', got 3"):
        openxr.from_openxr(3, f.positions, f.orientations)
    with pytest.raises(ValueError, match=r"^rotations\[0\]: not a rotation quaternion"):
        openxr.from_unity(RIGHT, f.positions, np.zeros((26, 4)))
    with pytest.raises(TypeError, match="^valid: expected booleans"):
        openxr.from_openxr(RIGHT, f.positions, f.orientations, valid=np.ones(26))


@pytest.fixture(scope="module")
def mrtk_poses():
    where = shared("poses")
    if where is None:
        pytest.skip("the MRTK poses are not there (../shared/assets/poses)")
    return {p.stem.split("_")[-1].split("-")[-1]: p for p in sorted(where.glob("ArticulatedHandPose*.json"))}


def test_mrtk_poses_give_the_named_shapes(mrtk_poses):
    poses = {k: mrtk.load_mrtk_pose(p).frame for k, p in mrtk_poses.items()}
    flex = {k: flexion_deg(f) for k, f in poses.items()}
    fingers_pip = [handsim.INDEX_INTERMEDIATE, handsim.MIDDLE_INTERMEDIATE, handsim.RING_INTERMEDIATE]
    assert flex["Flat"][fingers_pip].max() < 15
    assert flex["Grab"][fingers_pip].min() > 60
    tip_gap = lambda f: np.linalg.norm(np.asarray(f.positions)[handsim.THUMB_TIP] - np.asarray(f.positions)[handsim.INDEX_TIP])
    assert tip_gap(poses["Pinch"]) < 0.015 and tip_gap(poses["Flat"]) > 0.08
    for name, f in poses.items():
        p, q = np.asarray(f.positions), np.asarray(f.orientations)
        palm = skeleton.quat_matrix(q[handsim.PALM])
        assert (palm.T @ (p[handsim.THUMB_PROXIMAL] - p[handsim.PALM]))[0] < 0, name  # right thumb on -X
        if name not in ("Open", "Pinch"):  # the README: their tips carry their own rotations
            for j in (handsim.INDEX_PROXIMAL, handsim.MIDDLE_INTERMEDIATE, handsim.LITTLE_DISTAL):
                bone = (p[j + 1] - p[j]) / np.linalg.norm(p[j + 1] - p[j])
                assert -skeleton.quat_matrix(q[j])[:, 2] @ bone > 0.999, (name, j)
    left = mrtk.load_mrtk_pose(mrtk_poses["Flat"], "left").frame
    palm = skeleton.quat_matrix(left.orientations[handsim.PALM])
    assert (palm.T @ (np.asarray(left.positions)[handsim.THUMB_PROXIMAL] - left.positions[handsim.PALM]))[0] > 0


def test_mrtk_pose_through_mediapipe_keeps_its_joint_angles(mrtk_poses):
    """Device orientations (MRTK) vs orientations rebuilt from 21 positions: the flexion angles agree; the
    knuckles' (MCP) less closely, since MediaPipe has no metacarpals and the adapter puts their bases on the
    wrist-knuckle line (docs/input.md)."""
    knuckles = [handsim.INDEX_PROXIMAL, handsim.MIDDLE_PROXIMAL, handsim.RING_PROXIMAL, handsim.LITTLE_PROXIMAL]
    for name in ("Flat", "Grab", "PinchSteadyWrist", "Poke", "ThumbsUp"):  # not Open, Pinch: see the README
        f = mrtk.load_mrtk_pose(mrtk_poses[name]).frame
        a = mediapipe.from_mediapipe(mediapipe.landmarks_of(f), RIGHT)
        finger = [j for j in FLEX if j > handsim.THUMB_TIP]
        diff = np.abs(flexion_deg(a.frame) - flexion_deg(f))
        assert diff[finger].max() < 4.0, (name, diff[finger].round(1))
        assert diff[knuckles].max() < 8.0, (name, diff[knuckles].round(1))


def test_mrtk_errors(tmp_path):
    with pytest.raises(FileNotFoundError, match="^path: no such file"):
        mrtk.load_mrtk_pose(tmp_path / "none.json")
    with pytest.raises(ValueError, match=r"items\[0\]\.joint: unknown MRTK joint 'Elbow'"):
        mrtk.read_mrtk_pose({"items": [{"joint": "Elbow", "pose": {}}]})
    with pytest.raises(ValueError, match=r"^pose: joints missing: \['palm', 'wrist'"):
        mrtk.read_mrtk_pose({"items": []})


# --- MediaPipe ----------------------------------------------------------------------------------------------

@pytest.mark.parametrize("name", list(POSES))
@pytest.mark.parametrize("coordinates", ["world", "image"])
def test_mediapipe_landmarks_give_the_pose(name, coordinates):
    f = source(name)
    lm = mediapipe.landmarks_of(f, coordinates)
    if coordinates == "image":  # normalise by a 640 x 480 image, z on the scale of x
        lm = lm * 1000 / np.array([640, 480, 640])
    a = mediapipe.from_mediapipe(lm, RIGHT, coordinates, image_size=(640, 480) if coordinates == "image" else None,
                                 origin=f.positions[handsim.WRIST])
    assert set(a.synthesized) == {"palm", "index_metacarpal", "middle_metacarpal", "ring_metacarpal",
                                  "little_metacarpal"} and a.invalid == ()
    given = mediapipe.LANDMARK_TO_JOINT
    np.testing.assert_allclose(np.asarray(a.frame.positions)[given], np.asarray(f.positions)[given], atol=1e-9)
    np.testing.assert_allclose(flexion_deg(a.frame)[FLEX], flexion_deg(f)[FLEX], atol=1e-6)
    # the knuckles bend on the synthesized metacarpals: make_hand_frame's bases lie off the wrist-knuckle line
    knuckles = [handsim.INDEX_PROXIMAL, handsim.MIDDLE_PROXIMAL, handsim.RING_PROXIMAL, handsim.LITTLE_PROXIMAL]
    assert np.abs(flexion_deg(a.frame) - flexion_deg(f))[knuckles].max() < 10.5
    # finger frames match make_hand_frame's; thumb frames only up to the roll about the bone
    q, r = np.asarray(a.frame.orientations), np.asarray(f.orientations)
    angle = np.degrees(2 * np.arccos(np.clip(np.abs((q * r).sum(axis=1)), 0, 1)))
    fingers = [j for j in given if j > handsim.THUMB_TIP]
    assert angle[fingers].max() < 1.0
    for j in (handsim.THUMB_PROXIMAL, handsim.THUMB_DISTAL):
        assert skeleton.quat_matrix(q[j])[:, 2] @ skeleton.quat_matrix(r[j])[:, 2] > 0.9999


def pinhole_landmarks(frame, width=640, height=480, fov_deg=60.0):
    """The image landmarks a camera at the origin looking along -Z (+Y up; MediaPipe's image axes: +X right,
    +Y down) sees of `frame`: x, y normalised by the image size, z the depth behind the wrist in pixels at
    the wrist's depth over the width, as MediaPipe defines it; and the focal length in pixels."""
    f = width / 2 / math.tan(math.radians(fov_deg) / 2)
    cam = np.asarray(frame.positions, float)[mediapipe.LANDMARK_TO_JOINT] * np.array([1.0, -1.0, -1.0])
    u, v = f * cam[:, 0] / cam[:, 2] + width / 2, f * cam[:, 1] / cam[:, 2] + height / 2
    z = (cam[:, 2] - cam[0, 2]) * f / cam[0, 2] / width
    return np.c_[u / width, v / height, z], f


@pytest.mark.parametrize("name", sorted(POSES))
def test_mediapipe_image_landmarks_through_a_pinhole_camera(name):
    """A hand 30 cm in front of a 60 deg camera: with focal_length the image landmarks give the hand back
    (positions to 1e-9 m about the wrist, the flexion angles to 1e-5 deg; the knuckles' depend on the
    synthesized metacarpals, as in every MediaPipe test); read as an orthographic view the perspective bends
    the angles of the fist and the pinch by more than 5 deg (the flat hand, nearly at one depth, by 0.2)."""
    facing = np.array([[-1.0, 0, 0], [0, 0, -1], [0, -1, 0]])  # palm towards the camera, fingers up
    f = handsim.make_hand_frame(RIGHT, [0.02, -0.03, -0.3, *skeleton.matrix_quat(facing)], **POSES[name])
    lm, focal = pinhole_landmarks(f)
    p = np.asarray(f.positions)
    palm = float(np.linalg.norm(p[handsim.MIDDLE_PROXIMAL] - p[handsim.WRIST]))
    a = mediapipe.from_mediapipe(lm, RIGHT, "image", image_size=(640, 480), palm_length=palm,
                                 origin=p[handsim.WRIST], focal_length=focal)
    given = mediapipe.LANDMARK_TO_JOINT
    np.testing.assert_allclose(np.asarray(a.frame.positions)[given], p[given], atol=1e-9)
    np.testing.assert_allclose(flexion_deg(a.frame)[FLEX], flexion_deg(f)[FLEX], atol=1e-5)
    flat = mediapipe.from_mediapipe(lm, RIGHT, "image", image_size=(640, 480), palm_length=palm)
    assert np.abs(flexion_deg(flat.frame) - flexion_deg(f))[FLEX].max() > (0.1 if name == "flat" else 5.0)
    with pytest.raises(ValueError, match="^focal_length: expected a positive number of pixels"):
        mediapipe.from_mediapipe(lm, RIGHT, "image", image_size=(640, 480), focal_length=-5)
    with pytest.raises(ValueError, match="^focal_length: only used with image coordinates"):
        mediapipe.from_mediapipe(lm, RIGHT, "world", focal_length=focal)
    with pytest.raises(ValueError, match="^principal_point: only used with focal_length"):
        mediapipe.from_mediapipe(lm, RIGHT, "image", image_size=(640, 480), principal_point=(320, 240))
    with pytest.raises(ValueError, match=r"^principal_point: expected shape \(2,\)"):
        mediapipe.from_mediapipe(lm, RIGHT, "image", image_size=(640, 480), focal_length=focal,
                                 principal_point=(1, 2, 3))


def test_mediapipe_invalid_landmarks_and_errors():
    f = source("flat")
    lm = mediapipe.landmarks_of(f)
    vis = np.ones(21)
    vis[8] = 0.1  # the index tip is not seen
    lm_nan = lm.copy()
    lm_nan[8] = np.nan
    a = mediapipe.from_mediapipe(lm_nan, RIGHT, visibility=vis)
    assert a.invalid == ("index_distal", "index_tip")  # the distal bone needs its tip
    assert a.frame.tracked
    vis[0] = 0.0  # no wrist: the palm frame cannot be built, nor anything relative to it
    assert not mediapipe.from_mediapipe(lm, RIGHT, visibility=vis).frame.tracked
    with pytest.raises(ValueError, match=r"^landmarks\[8\]: must be finite"):
        mediapipe.from_mediapipe(lm_nan, RIGHT)
    with pytest.raises(ValueError, match=r"^landmarks: expected shape \(21, 3\), got \(20, 3\)"):
        mediapipe.from_mediapipe(lm[:20], RIGHT)
    with pytest.raises(ValueError, match="^image_size: .* is needed for image coordinates"):
        mediapipe.from_mediapipe(lm, RIGHT, "image")
    with pytest.raises(ValueError, match="^coordinates: expected 'world' or 'image', got 'pixels'"):
        mediapipe.from_mediapipe(lm, RIGHT, "pixels")
    with pytest.raises(TypeError, match="^landmarks: expected an array"):
        mediapipe.from_mediapipe("lm", RIGHT)


# --- BVH --------------------------------------------------------------------------------------------------

@pytest.mark.parametrize("order", ["YXZ", "ZXY", "XYZ"])
def test_bvh_written_and_read_back_gives_the_poses(order, tmp_path):
    frames = [source(name) for name in POSES]
    path = bvh.write_bvh(tmp_path / "hand.bvh", frames, order=order)
    text = path.read_text()
    assert "JOINT RightInHandIndex" in text and f"CHANNELS 3 {order[0]}rotation" in text
    parsed = bvh.load_bvh(path)
    assert parsed.motion.shape == (3, 6 + 3 * 20) and parsed.frame_time == pytest.approx(1 / 60)
    out = bvh.hand_frames(parsed, RIGHT)  # centimetres -> metres
    for f, a in zip(frames, out):
        assert a.synthesized == ("palm",) and a.invalid == ()
        given = [j for j in range(26) if j != handsim.PALM]
        np.testing.assert_allclose(np.asarray(a.frame.positions)[given], np.asarray(f.positions)[given], atol=1e-8)
        np.testing.assert_allclose(flexion_deg(a.frame)[FLEX], flexion_deg(f)[FLEX], atol=1e-5)


def test_bvh_euler_order_matters():
    """The same numbers under another channel order are another pose: the parser honours the file's order."""
    text = ("HIERARCHY\nROOT A\n{\n OFFSET 0 0 0\n CHANNELS 3 {o}\n End Site\n {\n  OFFSET 0 0 10\n }\n}\n"
            "MOTION\nFrames: 1\nFrame Time: 0.1\n30 40 50\n")
    ends = []
    for order in ("Xrotation Yrotation Zrotation", "Zrotation Yrotation Xrotation"):
        b = bvh.parse_bvh(text.replace("{o}", order))
        ends.append(b.global_transforms(0)[2][0])
    assert np.linalg.norm(ends[0] - ends[1]) > 1.0
    rx, ry, rz = (bvh._axis_rotation(k, math.radians(a)) for k, a in ((0, 30), (1, 40), (2, 50)))
    np.testing.assert_allclose(ends[0], rx @ ry @ rz @ [0, 0, 10], atol=1e-12)


def random_bvh(path, rng, joints=6):
    """A chain of `joints` joints below a root with a non-zero offset and position channels in an odd order,
    each joint with its own rotation order and random angles over 4 frames."""
    orders = ["Xrotation Yrotation Zrotation", "Zrotation Xrotation Yrotation", "Yrotation Zrotation Xrotation",
              "Zrotation Yrotation Xrotation"]
    lines = ["HIERARCHY", "ROOT Hips", "{", " OFFSET 1.5 -2 3",
             " CHANNELS 6 Yposition Xposition Zposition Zrotation Xrotation Yrotation"]
    for j in range(joints):
        pad, off = " " * (j + 1), rng.normal(0, 5, 3)
        lines += [f"{pad}JOINT J{j}", pad + "{", f"{pad} OFFSET {off[0]:.4f} {off[1]:.4f} {off[2]:.4f}",
                  f"{pad} CHANNELS 3 {orders[j % 4]}"]
    pad = " " * (joints + 1)
    lines += [pad + "End Site", pad + "{", pad + " OFFSET 0 0 4", pad + "}"] + [" " * j + "}" for j in range(joints, -1, -1)]
    motion = np.c_[rng.normal(0, 10, (4, 3)), rng.uniform(-170, 170, (4, 3 + 3 * joints))]
    lines += ["MOTION", "Frames: 4", "Frame Time: 0.0333"] + [" ".join(f"{v:.5f}" for v in row) for row in motion]
    path.write_text("\n".join(lines) + "\n")
    return path


def test_bvh_forward_kinematics_agree_with_bvhio(tmp_path):
    """The maintained bvhio library reads the same joint positions from a random hierarchy (position channels
    replace the root's offset, mixed rotation orders) and from write_bvh's hand files in three orders; it
    computes in single precision (glm), hence 1e-4 file units."""
    bvhio = pytest.importorskip("bvhio")
    frames = [source(name) for name in POSES]
    paths = [random_bvh(tmp_path / "random.bvh", np.random.default_rng(1))]
    paths += [bvh.write_bvh(tmp_path / f"hand_{o}.bvh", frames, order=o) for o in ("YXZ", "ZXY", "XYZ")]
    for path in paths:
        ours, root = bvh.load_bvh(path), bvhio.readAsHierarchy(str(path))
        for i in range(ours.motion.shape[0]):
            root.loadPose(i, recursive=True)
            _, pos, _ = ours.global_transforms(i)
            for joint, _, _ in root.layout():
                np.testing.assert_allclose(np.array(joint.PositionWorld), pos[ours.index(joint.Name)], atol=1e-4,
                                           err_msg=f"{path.name} frame {i} {joint.Name}")


def test_bvh_errors_name_the_line(tmp_path):
    good = bvh.write_bvh(tmp_path / "h.bvh", [source("flat")]).read_text()
    with pytest.raises(bvh.BvhError, match=r"line 5: unknown channel 'Wrotation'"):
        bvh.parse_bvh(good.replace("Yrotation Xrotation Zrotation", "Wrotation Xrotation Zrotation", 1))
    with pytest.raises(bvh.BvhError, match=r"MOTION has 65 values, expected 1 frames x 66 channels"):
        bvh.parse_bvh(good.rsplit(" ", 1)[0])
    with pytest.raises(ValueError, match=r"the left hand lacks joints \['wrist'"):
        bvh.hand_frames(bvh.parse_bvh(good), LEFT)
    with pytest.raises(FileNotFoundError, match="^path: no such file"):
        bvh.load_bvh(tmp_path / "none.bvh")


# --- Record and replay --------------------------------------------------------------------------------------

def record_session(path):
    rec = recording.Recorder("jewelry_box", hands=[handsim.HandDef(handedness=RIGHT), handsim.HandDef(handedness=LEFT)])
    world, box = rec.world, rec.scene.box
    for i in range(90):
        if i == 10:
            rec.set_joint_value("hinge", 0.2)
        if i == 20:
            rec.set_body_velocity("base", [0, 0.1, 0], [0, 0, 0])
        if i == 30:
            rec.add_box("weight", [0.02, 0.02, 0.02], [0.0, 0.9, -0.3, 0, 0, 0, 1], mass=0.2)
        if i == 70:
            rec.remove_body("weight")
        palm = box.lid_pinch_palm(world, RIGHT, 0.2 * i / 90, 0.0)
        right = handsim.make_hand_frame(RIGHT, palm, **vars_of(handsim.lid_pinch_shape()))
        right_hand, left_hand = rec.hands
        frames = {right_hand: right} if i % 30 else {right_hand: right, left_hand: skeleton.untracked(LEFT)}
        rec.step(1 / 60, frames if i != 45 else {})
    rec.save(path)
    return rec


def test_bad_scene_edits_are_refused_and_not_recorded():
    rec = recording.Recorder("free_box")
    with pytest.raises(KeyError, match="has no object 'ghost'"):
        rec.remove_body("ghost")
    with pytest.raises(recording.RecordingError, match="already has an object named 'box'"):
        rec.add_box("box", [0.01] * 3, [0, 1, 0, 0, 0, 0, 1])
    with pytest.raises(handsim.Error, match="half_extents|size|extent"):
        rec.add_box("slab", [-0.01, 0.01, 0.01], [0, 1, 0, 0, 0, 0, 1])
    assert rec.recording.edits == [] and "slab" not in rec.scene.objects


def vars_of(shape):
    return {"curl": np.asarray(shape.curl), "thumb_opposition": shape.thumb_opposition, "spread": shape.spread}


def test_record_and_replay_bit_for_bit(tmp_path):
    rec = record_session(tmp_path / "s.npz")
    loaded = recording.load(tmp_path / "s.npz")
    assert loaded.steps == 90 and [e["op"] for e in loaded.edits] == ["set_joint_value", "set_body_velocity", "add_box",
                                                                   "remove_body"]
    with np.load(tmp_path / "s.npz") as z:  # plain numpy arrays
        assert z["positions"].dtype == np.float64 and z["positions"].shape == (90, 2, 26, 3)
        assert json.loads(str(z["header"][()]))["version"] == recording.FORMAT_VERSION
    result = recording.replay(loaded)
    assert result.matches and result.final_hash == rec.world.state_hash()
    # a changed input changes the state: the replay notices where
    loaded.positions[50, 0, :, 1] += 1e-6
    assert recording.replay(loaded).first_mismatch == 50


def test_recording_errors(tmp_path):
    record_session(tmp_path / "s.npz")
    with np.load(tmp_path / "s.npz") as z:
        arrays = {k: z[k] for k in z.files}
    header = json.loads(str(arrays["header"][()]))
    for change, message in (({"version": 99}, r"recording version 99 is not supported: this handsim .* reads version 1"),
                            ({"format": "other"}, r"format 'other', expected 'handsim-recording'")):
        arrays["header"] = np.array(json.dumps({**header, **change}))
        np.savez_compressed(tmp_path / "bad.npz", **arrays)
        with pytest.raises(recording.RecordingError, match=message):
            recording.load(tmp_path / "bad.npz")
    arrays["header"] = np.array(json.dumps(header))
    arrays["valid"] = arrays["valid"][:, :, :25]
    np.savez_compressed(tmp_path / "bad.npz", **arrays)
    with pytest.raises(recording.RecordingError, match=r"valid has shape \(90, 2, 25\), expected \(90, 2, 26\)"):
        recording.load(tmp_path / "bad.npz")
    with pytest.raises(FileNotFoundError, match="^path: no such file"):
        recording.load(tmp_path / "none.npz")
    (tmp_path / "text.npz").write_text("not a zip")
    with pytest.raises(recording.RecordingError, match=r"not a handsim recording"):
        recording.load(tmp_path / "text.npz")
    rec = recording.Recorder("jewelry_box")
    with pytest.raises(handsim.InvalidStateError, match="^body: is the child of a hard joint"):
        rec.set_body_velocity("lid", [0, 1, 0], [0, 0, 0])
    rec = recording.Recorder("free_box")
    with pytest.raises(KeyError, match="scene 'free_box' has no object 'lid'"):
        rec.set_body_pose("lid", [0, 1, 0, 0, 0, 0, 1])
    with pytest.raises(TypeError, match=r"^hands\[0\]: expected a HandDef, got str"):
        recording.Recorder("free_box", hands=["right"])
    with pytest.raises(ValueError, match="^scene: expected one of"):
        recording.Recorder("kitchen")
    with pytest.raises(ValueError, match=r"^scene_params\.size: not a free_box parameter"):
        recording.Recorder("free_box", {"size": 1})
    assert rec.recording.steps == 0  # nothing was recorded by the rejected calls


def test_replay_command_on_a_bvh_and_on_its_recording(tmp_path):
    """python -m handsim.replay: a BVH (tracker input) on the free box, saved, and the saved recording replayed
    with its hashes checked."""
    frames = [handsim.make_hand_frame(RIGHT, [0, 0.9, -0.3, 0, 0, 0, 1], curl=c) for c in np.linspace(0, 0.6, 20)]
    path = bvh.write_bvh(tmp_path / "close.bvh", frames, frame_time=1 / 30)
    out = tmp_path / "out"
    assert replay.main([str(path), "--scene", "free_box", "--out", str(out), "--save"]) == 0
    assert (out / "close_free_box.png").stat().st_size > 10000
    summary = (out / "close.txt").read_text()
    assert "close on free_box: 38 steps" in summary and "all state finite: True" in summary
    assert "input: bvh (grab and pinch of the right hand from the skeleton)" in summary
    assert replay.main([str(out / "close_free_box.npz"), "--out", str(out)]) == 0
    assert "state hashes match the recording: True" in (out / "close_free_box.txt").read_text()


def test_input_report_arguments(tmp_path, capsys):
    """The report refuses a folder without recordings and a depth share outside (0, 2], naming the option."""
    from handsim import input_report
    assert input_report.main(["--assets", str(tmp_path)]) == 2
    assert "--assets: no .json.lz recordings" in capsys.readouterr().err
    (tmp_path / "x.json.lz").write_text("{}")
    assert input_report.main(["--assets", str(tmp_path), "--reach", "0"]) == 2
    assert "--reach: expected a share in (0, 2]" in capsys.readouterr().err
    with pytest.raises(SystemExit):  # the recordings are never looked for in a default place
        input_report.main([])
    assert "--assets" in capsys.readouterr().err


def test_a_leap_recording_without_any_hand_replays_and_grasps_nothing():
    """A tracker left running with nobody in front of it: no error, nothing grasped, every check met."""
    from handsim import input_report
    frames = [{"id": i, "timestamp": 9000 * i, "hands": [], "pointables": []} for i in range(40)]
    motion = replay.motion_from_leap(read_leap_json({"metadata": {"formatVersion": 0.1}, "frames": frames}))
    rec = replay.session_from_motion(motion, "free_box")
    assert rec.info["placement"] == "no tracked hand: the default cube" and not rec.valid.any()
    jewelry, free = replay.run(replay.session_from_motion(motion, "jewelry_box")), replay.run(rec)
    assert not jewelry.grasps and not free.grasps and free.finite
    assert all(input_report.expectations(motion, jewelry, free).values())


def test_a_bvh_hand_that_closes_grasps_the_cube_by_its_skeletons_strength(tmp_path):
    """BVH gives no grab strength: the skeleton's (replay.with_strengths) finds the closing hand, the cube
    goes where it closes, and every expectation of a Leap replay holds. The hand closes to a fist: grab is the
    grab angle as a share of make_hand_frame's fist's (a hand closed to curl 0.8 has 0.945, short of replay's
    0.95 for a closed hand)."""
    from handsim import input_report
    curls = np.r_[np.zeros(10), np.linspace(0, 1.0, 20), np.full(20, 1.0)]
    frames = [handsim.make_hand_frame(RIGHT, [0, 0.9, -0.3, 0, 0, 0, 1], curl=c) for c in curls]
    motion = replay.load_motion(bvh.write_bvh(tmp_path / "close.bvh", frames, frame_time=1 / 30))
    assert "grab and pinch of the right hand from the skeleton" in motion.source
    assert np.nanmax(motion.grab[:, 0]) == 1.0 and motion.grab[:10, 0].max() == 0.0
    assert np.all(np.isnan(motion.grab[:, 1]))  # no left hand in the file
    jewelry = replay.run(replay.session_from_motion(motion, "jewelry_box"))
    free = replay.run(replay.session_from_motion(motion, "free_box"))
    checks = input_report.expectations(motion, jewelry, free)
    assert "cube grasped by the closing hand" in checks and all(checks.values()), checks


# Where the skeleton's strengths (Leap's documented meaning, skeleton.closure_strengths) do not pick Leap's closing
# hand, kind and closure start (docs/input.md): in confidence-demo the skeleton's strength never falls to
# replay's open 0.05 before the grab (closure start 0.00 s, Leap's 4.8 s); in confidence2 and -49fps it never
# reaches replay's closed 0.95 (no closing hand); in grab the thumb's pulp lies on the curling fingers, so the
# pinch reaches 0.95 before the grab angle does. Strict: an entry goes when it is met.
CLOSING_SHORT = {"confidence-demo-eighth-res", "confidence-demo-half-res", "confidence-demo-quarter-res",
                 "confidence-demo", "confidence2-49fps", "confidence2", "grab"}


@pytest.mark.parametrize("name", [pytest.param(n, marks=pytest.mark.xfail(strict=True, reason="issue 20"))
                                  if n in CLOSING_SHORT else n for n in sorted(README_COUNTS)])
def test_skeleton_strengths_find_leaps_closing_hand(name, leap_recordings):
    """On every development recording the skeleton's strengths pick the hand and the kind of closure Leap's
    pick, with the closure starting within 0.15 s of Leap's (docs/input.md has the table)."""
    from handsim import input_report
    g = input_report.strength_agreement(replay.motion_from_leap(dev_recording(leap_recordings, name)))
    if g["leap"] is None:
        assert g["skeleton"] is None, g
    else:
        assert g["skeleton"] is not None and g["skeleton"][:2] == g["leap"][:2], g
        assert abs(g["skeleton"][2] - g["leap"][2]) < 0.15, g


def closing_motion(palm_q, rise=0.0, forward=0.0):
    """A right hand that is open for 20 frames, closes to a fist over 30 (Leap grab strength = curl) and holds
    it for 30, at 60 Hz, its palm turned by `palm_q` (x, y, z, w); it rises by `rise` (m) while it closes and
    moves `forward` (m, along -Z) while it holds the fist."""
    curls = np.r_[np.zeros(20), np.linspace(0, 1, 30), np.ones(30)]
    y = 0.2 + rise * np.r_[np.zeros(20), np.linspace(0, 1, 30), np.ones(30)]
    z = -forward * np.r_[np.zeros(50), np.linspace(0, 1, 30)]
    frames = [{"right": skeleton.AdaptedFrame(handsim.make_hand_frame(RIGHT, [0, y[i], z[i], *palm_q], curl=c))}
              for i, c in enumerate(curls)]
    grab = np.c_[curls, np.full(len(curls), np.nan)]
    return replay.Motion("closing", np.arange(len(curls)) / 60, frames, grab, np.zeros_like(grab), "test")


@pytest.mark.parametrize("palm_q, normal, rise, forward", [
    ([0, 0, 0, 1], [0, -1, 0], 0, 0),                          # palm down
    ([0, 0, math.sqrt(0.5), math.sqrt(0.5)], [1, 0, 0], 0, 0),  # sideways
    ([0, 0, 1, 0], [0, 1, 0], 0, 0),                           # palm up
    ([0, 0, 0, 1], [0, -1, 0], 0.08, 0.1)])                    # palm down, rising 8 cm as it closes, then forward
def test_the_cube_goes_where_the_hand_closes_whichever_way_the_palm_faces(palm_q, normal, rise, forward):
    """The free cube starts between the palm and the fingertips of the first half-closed frame whose grip the
    closing hand reaches 10 mm into (frame 35, the first one, when the hand closes in place; a later one when it
    rises as it closes), moved out of the palm along its normal until the open hand clears it and the closing
    palm does on its way there; the closing hand then grasps it, as it closes."""
    from handsim import input_report
    motion = closing_motion(palm_q, rise, forward)
    shift = replay.placement(motion)
    params, rule = replay.free_box_params(motion, shift)
    half = params["half_extent"]
    centre = np.asarray(params["position"]) + [0, half, 0]
    j = int(rule.split("(frame ")[-1].split(")")[0])  # the frame whose grip the cube starts at
    assert (j == 35) == (rise == 0), rule  # frame 35: the first half-closed one
    p = np.asarray(motion.frames[j]["right"].frame.positions) + shift
    mid = 0.5 * (p[handsim.PALM] + p[[handsim.INDEX_TIP, handsim.MIDDLE_TIP, handsim.RING_TIP,
                                       handsim.LITTLE_TIP]].mean(axis=0))
    moved = centre - mid
    assert "moved" in rule and np.linalg.norm(np.cross(moved, normal)) < 1e-9 and np.dot(moved, normal) > 0.005
    reach = float(rule.split("reaches ")[-1].split(" mm")[0])
    assert reach >= 1000 * replay.REACH * half  # ... and the closing hand reaches 10 mm into it
    frames = [f["right"].frame.transformed([*shift, 0, 0, 0, 1]) for f in motion.frames]
    k0 = replay._closure_start_index(motion.grab[:, 0])  # the last open frame
    not_palm = [i for i in range(handsim.JOINT_COUNT) if i not in replay.PALM_JOINTS]
    for seen, skip in ((frames[:k0 + 1], replay.THUMB_ANVIL), (frames[k0 + 1:j + 1], not_palm)):
        q, r = replay._particles(seen, handsim.HandDef(), skip)
        gap = np.linalg.norm(np.maximum(np.abs(q - centre) - half, 0), axis=1) - r
        assert gap.min() >= replay.CLEAR - 1e-12  # the open hand clears it, and so does the palm on its way there
    jewelry = replay.run(replay.session_from_motion(motion, "jewelry_box"))
    free = replay.run(replay.session_from_motion(motion, "free_box"))
    assert free.grasp_log and all(hand == "right" for _, _, hand in free.grasp_log)
    assert f"right hand {len(free.grasp_log)}" in free.lines()[1]  # the summary says who grasped
    checks = input_report.expectations(motion, jewelry, free)
    assert all(checks.values()), checks


def test_expectations_name_the_grasp_a_watcher_would_not_expect():
    """A grasp by the other hand, or by the closing hand while it is still open, does not count."""
    import dataclasses
    from handsim import input_report
    motion = closing_motion([0, 0, 0, 1])
    jewelry = replay.run(replay.session_from_motion(motion, "jewelry_box"))
    free = replay.run(replay.session_from_motion(motion, "free_box"))
    missed = lambda log: {k for k, ok in input_report.expectations(
        motion, jewelry, dataclasses.replace(free, grasp_log=log)).items() if not ok}
    assert missed(free.grasp_log) == set()
    assert missed([]) == {"cube grasped by the closing hand", "as it closes"}
    assert missed([(40, "box", "left")]) == {"cube grasped by the closing hand", "as it closes",
                                             "no grasp by an open hand"}  # the left hand has no strength: open
    assert missed([(5, "box", "right"), (40, "box", "right")]) == {"as it closes", "no grasp by an open hand"}
    assert missed([(40, "box", "right"), (5, "table", "right")]) == set()  # only grasps of the cube count


# --- Real recorded motion --------------------------------------------------------------------------------

# The confidence-demo session is 10 s long and in the folder four times (full, 1/2, 1/4, 1/8 of its frames):
# the eighth-res copy replays in full, the other three for their first 4 s (hands before the grab).
BOUNDED = {"confidence-demo": 240, "confidence-demo-half-res": 240, "confidence-demo-quarter-res": 240}
# Expectations the default grasp rule (the closing rule, issue 20 item 2) does not meet with the formatVersion 0.1
# hands' own metacarpal bases (issue 20 item 5, docs/input.md): open hands grasp the replay's cube (the judge's
# false grasps). The rule before (GraspSettings.contacts()) missed confidence-demo, confidence2-49fps, grab and
# three-claps instead (docs/input.md before the change); the judge passes confidence2's right hand with the closing
# rule and fails confidence-demo-eighth-res with both (docs/grasp.md). Since entry_face leaves no stale far face
# (5304fd1), confidence-demo-eighth-res meets every expectation with the closing rule. Since a grasp begins only
# when the digits touching the body close (docs/grasp.md "The touching digits close"), confidence2-49fps' left hand
# no longer grasps the cube while open (step 108), and nothing grasps it: the closing hand misses it. Since Wrap is
# the default push (docs/grasp.md "Wrap as the default, measured"), confidence2 and grab meet every expectation
# (under the fit: confidence2 "no grasp by an open hand", grab "as it closes" and "no grasp by an open hand" not
# met), and confidence2-49fps' closing left hand grasps the cube as it closes (step 51, strength 1.00) but grasps it
# again while open (step 109, strength 0.00): one expectation missed where the fit missed two. Since a held body
# follows its hand before the contacts (docs/grasp.md "The hold path", session 18), the release at step 58 takes its
# contacts, and the entry faces the let-go carries on, against the cube where the hand carried it; the let-go cube
# rests about 1 mm elsewhere (step 60: (-34.6, 921.9, -289.2) mm against (-35.7, 922.4, -288.5)), and the open
# left hand that closed onto it at step 109 no longer does: every expectation met. Not a rule for open hands: a mm
# of difference in where the cube lies decided it.
# Strict: the entry must go when the rule meets the expectation again.
OPEN_HAND_GRASPS = {}


@pytest.mark.parametrize("name", recording_names())
def test_real_recording_replays_near_the_box_and_the_cube(name, leap_recordings):
    from handsim import input_report
    motion = replay.motion_from_leap(leap_recordings[name])
    steps = BOUNDED.get(name)
    jewelry = replay.run(replay.session_from_motion(motion, "jewelry_box"), name, steps=steps)
    free = replay.run(replay.session_from_motion(motion, "free_box"), name, steps=steps)
    assert jewelry.finite and free.finite
    assert jewelry.max_hinge_violation_m <= 1e-6 and -0.5 <= jewelry.max_lid_deg <= 90.5
    if steps is None:
        checks = input_report.expectations(motion, jewelry, free)
        known = OPEN_HAND_GRASPS.get(name, set()) if name in README_COUNTS else set()
        assert {k for k, ok in checks.items() if not ok} == known, checks
        if known:
            pytest.xfail(f"issue 20: expectations not met ({', '.join(sorted(known))})")


@pytest.mark.xfail(strict=True, reason="issue 20: with Leap's own metacarpal bases the clapping hand's edge touches "
                                      "with two parts, so across_parts no longer keeps it from a grasp (docs/grasp.md)")
def test_three_claps_grasps_only_without_the_two_part_rule(leap_recordings):
    """docs/grasp.md, eq. 3: the clapping hand's palm drapes over the cube's top edges. Without
    GraspSettings.across_parts eq. 3 from the contacts alone (GraspSettings.contacts(), the rule it was measured
    with) calls that a grasp (from 0.83 s); with it, nothing is grasped. Since the metacarpal bases are Leap's own
    (issue 20 item 5) the rule grasps from 0.25 s without across_parts and from 0.85 s with it: the hand's edge now
    touches the cube with the little metacarpal and the little finger's proximal phalanx (71 and 14 contacts when
    it begins), two rigid parts."""
    motion = replay.motion_from_leap(dev_recording(leap_recordings, "three-claps"))

    def grasps(grasp):
        return replay.run(replay.session_from_motion(motion, "free_box", world_def=handsim.WorldDef(grasp=grasp)),
                          "three-claps")
    one_part = handsim.GraspSettings.contacts()
    one_part.across_parts = False
    before, after = grasps(one_part), grasps(handsim.GraspSettings.contacts())
    assert before.grasps.get("box", 0) >= 1 and abs(before.first_grasp_s - 0.83) < 0.01
    assert not after.grasps


@pytest.mark.parametrize("push_model", [handsim.PushModel.FIT, handsim.PushModel.WRAP])
def test_three_claps_grasps_nothing_with_the_closing_rule(leap_recordings, push_model):
    """The default (closing) rule, with or without across_parts: the clapping hand never closes its grip onto the
    box, so whatever its edge touches is not grasped (docs/grasp.md, "Intent"). Under Wrap the edge stays in the
    box its table supports, and the hand's thumb closes on its index by 16-25 mm as the palms meet; the digits on the
    box (the little finger's) close by 3-6 mm, and under Wrap it is they that must close (docs/grasp.md "The touching
    digits close")."""
    motion = replay.motion_from_leap(dev_recording(leap_recordings, "three-claps"))
    for across_parts in (True, False):
        world_def = handsim.WorldDef(grasp=handsim.GraspSettings(across_parts=across_parts), push_model=push_model)
        assert not replay.run(replay.session_from_motion(motion, "free_box", world_def=world_def),
                              "three-claps").grasps, across_parts


@pytest.mark.parametrize("name", ["flat", "fist", "pinch"])
def test_real_mediapipe_output_gives_the_pose_within_mediapipes_error(name):
    """Real MediaPipe output through the adapter: tests/python/data/mediapipe_<pose>.json, made by
    scripts/mediapipe_fixtures (mediapipe 1.2.3's HandLandmarker on a rendered glTF hand posed by make_hand_frame:
    right and left hand, palm towards the camera and turned 30 deg either way, fingers up, image not mirrored).

    What the adapter decides is checked closely: its flexion angles are the angles of MediaPipe's own landmark
    bones (1e-6 deg, so the landmark-to-joint map and the image scaling are right); given the true side, the
    thumb is on the palm frame's -X (right hand) or +X (left), the palm frame is turned as the rendered palm
    (measured within 50 deg; a wrong side or a y flip gives about 180), and the fist's fingertips come out on
    the palm side, which in these views only the sign of z decides (z not negated puts them behind the hand).
    How near the flexion comes to make_hand_frame's is MediaPipe's accuracy on these renders, not the
    adapter's: `tolerance` is the worst joint of any finger in any detection, measured, plus 3-5 deg. MediaPipe
    sees the fist about half closed (its joints 23-47 deg short on average per finger, up to 77) and bends the
    flat fingers by 6-20 deg on average; still,
    skeleton.closure_strengths (grab: the grab angle as a share of make_hand_frame's fist's) labels every flat and
    pinch detection open (grab < 0.3) and gives every fist at least 0.4, the fingers half curled as seen."""
    from handsim.adapters import mediapipe as mp_adapter, skeleton as sk
    path = Path(__file__).resolve().parent / "data" / f"mediapipe_{name}.json"
    if not path.is_file():
        pytest.skip(f"{path.name} is not there (scripts/mediapipe_fixtures makes it)")
    doc = json.loads(path.read_text())
    size = doc["render"]["image_size"]
    fingers = {"thumb": [handsim.THUMB_PROXIMAL, handsim.THUMB_DISTAL]}
    fingers.update({f.lower(): [getattr(handsim, f"{f}_{b}") for b in ("PROXIMAL", "INTERMEDIATE", "DISTAL")]
                    for f in ("INDEX", "MIDDLE", "RING", "LITTLE")})
    # Worst |flexion - make_hand_frame's| of one joint over the fingers and detections, measured (deg): flat
    # world 46.4, image 25.9; fist world 76.9, image 76.8; pinch world 42.2, image 30.9.
    tolerance = {"flat": {"world": 50, "image": 30}, "fist": {"world": 80, "image": 80},
                 "pinch": {"world": 45, "image": 35}}[name]
    tips = [handsim.INDEX_TIP, handsim.MIDDLE_TIP, handsim.RING_TIP, handsim.LITTLE_TIP]
    deg = lambda a, b: math.degrees(math.acos(np.clip(a @ b / np.linalg.norm(a) / np.linalg.norm(b), -1, 1)))

    def bone_angles(lm):  # flexion straight from the landmarks: wrist 0, thumb 1-4, then 4 per finger
        out = {handsim.THUMB_PROXIMAL: deg(lm[2] - lm[1], lm[3] - lm[2]),
               handsim.THUMB_DISTAL: deg(lm[3] - lm[2], lm[4] - lm[3])}
        for k, finger in enumerate(("index", "middle", "ring", "little")):
            w, m, p, d, t = lm[0], *lm[5 + 4 * k: 9 + 4 * k]
            out.update(zip(fingers[finger], (deg(m - w, p - m), deg(p - m, d - p), deg(d - p, t - d))))
        return out

    assert doc["detections"], "no detections in the fixture"
    named_right = 0
    for det in doc["detections"]:
        hand = handsim.Handedness.RIGHT if det["hand"] == "right" else handsim.Handedness.LEFT
        named_right += det["handedness_label"].lower() == det["hand"]
        made = handsim.make_hand_frame(hand, det["palm_pose"], **doc["pose"]["make_hand_frame"])
        ref = np.degrees(sk.joint_angles(made))
        true_palm = sk.quat_matrix(made.orientations[handsim.PALM])
        for coords in ("world", "image"):
            where = (det["hand"], det["yaw_deg"], coords)
            lm = np.asarray(det[coords + "_landmarks"], float)
            a = mp_adapter.from_mediapipe(lm, hand, coords, image_size=size if coords == "image" else None)
            got = np.degrees(sk.joint_angles(a.frame))
            for j, angle in bone_angles(lm * ([size[0], size[1], size[0]] if coords == "image" else 1)).items():
                assert abs(got[j] - angle) < 1e-6, (where, handsim.JOINT_NAMES[j])
            p, palm = np.asarray(a.frame.positions), sk.quat_matrix(a.frame.orientations[handsim.PALM])
            local = (p - p[handsim.PALM]) @ palm
            assert np.sign(local[handsim.THUMB_PROXIMAL, 0]) == (-1 if det["hand"] == "right" else 1), where
            turn = math.degrees(math.acos(np.clip((np.trace(palm.T @ true_palm) - 1) / 2, -1, 1)))
            assert turn < 55, (where, round(turn, 1))
            for finger, joints in fingers.items():
                worst = np.abs(got[joints] - ref[joints]).max()
                assert worst <= tolerance[coords], (where, finger, round(worst, 1))
            grab, _ = sk.closure_strengths(a.frame)
            if name == "fist":  # MediaPipe sees the fist about half closed: grab 0.42-0.84
                assert local[tips, 1].mean() < -0.005 and grab >= 0.4, (where, local[tips, 1], grab)
            else:  # open by the judge's label (< 0.3): 0.07-0.26
                assert grab < 0.3, (where, grab)
    # mediapipe 1.2.3's HandLandmarker names the true side of a hand in an unmirrored image: 15 of the 16
    # detections (not the right flat hand facing the camera, "Left" at 0.70). The legacy
    # mediapipe.solutions.hands of 0.10.21, same model, names the other side (its selfie-image convention).
    assert named_right >= len(doc["detections"]) - 1, (named_right, len(doc["detections"]))
