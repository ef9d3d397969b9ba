"""The independent judge of grasp intent (handsim.intent, issue 20).

The machinery is checked on made-up input whose answer is known; then the judge runs on the development Leap
recordings (skipped when ../shared/assets/leap_recordings is absent) and the issue's targets are asserted.
The targets today's grasp rule does not meet are marked xfail(strict=True): whoever makes the rule meet one
must remove its mark (a strict xfail that passes fails the suite)."""
import math

import numpy as np
import pytest

import handsim
from handsim import intent
from test_input import shared  # noqa: E402 (tests/python is on sys.path)

RIGHT = handsim.Handedness.RIGHT


def quat_about_y(angle):
    return [0.0, math.sin(angle / 2), 0.0, math.cos(angle / 2)]


def synthetic_track(curls, palm_poses, times, name="synthetic"):
    """A right hand from make_hand_frame at the given curls and palm poses; Leap-like strengths = the curl."""
    frames = [{"right": handsim.make_hand_frame(RIGHT, pose, curl=float(c))} for c, pose in zip(curls, palm_poses)]
    grab = np.c_[np.asarray(curls, float), np.full(len(curls), np.nan)]
    return intent.Track(name, np.asarray(times, float), frames, grab, np.full_like(grab, np.nan))


def test_labels_come_from_the_strengths_alone():
    closed, opened = intent.labels([0.95, 0.9, 0.89, 0.5, 0.3, 0.29, 0.0, np.nan])
    assert closed.tolist() == [True, True, False, False, False, False, False, False]
    assert opened.tolist() == [False, False, False, False, False, True, True, False]
    # strength = max(grab, pinch); a hand with neither has no label
    t = intent.Track("s", np.arange(3.0), [{}, {}, {}], np.array([[0.2, np.nan], [0.95, np.nan], [np.nan] * 2]),
                     np.array([[0.5, np.nan], [0.1, np.nan], [np.nan] * 2]))
    np.testing.assert_array_equal(t.strength[:, 0], [0.5, 0.95, np.nan])


def test_closures_begin_0_3_s_before_closing_and_end_when_open():
    times = np.arange(0, 3.0, 0.01)
    s = np.interp(times, [0, 0.5, 1.0, 1.5, 2.0, 2.4, 2.6], [0, 0, 1, 1, 0, 0.95, 0.95])
    t = intent.Track("c", times, [{"right": None}] * len(times), np.c_[s, np.full_like(s, np.nan)],
                     np.full((len(s), 2), np.nan))
    c = intent.closures(t, "right")
    assert len(c) == 2
    assert times[c[0].closed] == pytest.approx(0.95, abs=0.011)
    assert times[c[0].closed] - times[c[0].begin] == pytest.approx(0.3, abs=0.011)
    assert s[c[0].end] < intent.OPEN and s[c[0].end - 1] >= intent.OPEN
    assert c[1].end == len(times) and not c[0].pinch


def test_resampling_keeps_a_constant_velocity_motion_exact():
    rng = np.random.default_rng(3)
    times = np.cumsum(np.r_[0, rng.uniform(1 / 70, 1 / 45, 80)])  # an uneven tracker clock
    v, w = np.array([0.1, -0.05, 0.2]), 1.3  # m/s, rad/s about +Y
    poses = [[*(np.array([0, 1.2, 0]) + v * t), *quat_about_y(w * t)] for t in times]
    track = synthetic_track(np.full(len(times), 0.4), poses, times)
    track.grab[:, 0] = 0.2 + 0.3 * times  # a strength rising at a constant rate
    start = float(times[5])
    for rate in intent.RATES:
        r = intent.resample(track, rate, start)
        assert r.times[0] == start and np.allclose(np.diff(r.times), 1 / rate)
        for i in range(0, len(r.times), 7):
            exact = handsim.make_hand_frame(RIGHT, [*(np.array([0, 1.2, 0]) + v * r.times[i]),
                                                   *quat_about_y(w * r.times[i])], curl=0.4)
            got = r.frames[i]["right"]
            np.testing.assert_allclose(got.positions, exact.positions, atol=1e-4)  # joints move on arcs
            dots = np.abs(np.sum(np.asarray(got.orientations) * np.asarray(exact.orientations), axis=1))
            np.testing.assert_allclose(dots, 1.0, atol=1e-12)  # slerp of a constant rotation rate is exact
            np.testing.assert_allclose(got.positions[handsim.PALM], exact.positions[handsim.PALM], atol=1e-12)
            assert r.grab[i, 0] == pytest.approx(0.2 + 0.3 * r.times[i], abs=1e-12)


def test_resample_rejects_a_bad_rate():
    track = synthetic_track([0, 0], [[0, 1.2, 0, 0, 0, 0, 1]] * 2, [0, 0.1])
    for bad in (0, -30, float("nan"), "60"):
        with pytest.raises(ValueError, match="rate"):
            intent.resample(track, bad)


def closing_hand():
    """A palm-down hand, open for 0.5 s, closing to a fist over 1 s, holding 1 s, then opening over 0.5 s while
    it rises 10 cm (a person lets go and withdraws the hand) and staying open for 1 s: 60 Hz."""
    times = np.arange(0, 4.0, 1 / 60)
    curls = np.interp(times, [0, 0.5, 1.5, 2.5, 3.0, 4.0], [0, 0, 1, 1, 0, 0])
    heights = np.interp(times, [0, 2.5, 3.0, 4.0], [1.2, 1.2, 1.3, 1.3])
    return synthetic_track(curls, [[0, y, 0, 0, 0, 0, 1] for y in heights], times, "closes")


# Eq. 2's fit (PushModel.FIT), pinned: this synthetic hand's grasp is the fit's. The judge's cube lies under the
# palm joint, where the fingers, bending from knuckles 43 mm ahead of it, meet only its far face and the thumb
# closes on the same side; the fit throws the cube up and through the fingertips into a grasp, while a push that
# moves it only at the hand's own speeds (Wrap) presses it towards the wrist, where nothing opposes (docs/grasp.md
# "Wrap as the default, measured" (c), (d)). What this checks is the judge's reading of a closing hand's grasp.
FIT = handsim.WorldDef(push_model=handsim.PushModel.FIT)


def test_a_hand_that_closes_on_a_cube_passes():
    track = closing_hand()
    particles = intent.Particles(track, intent.default_hand_defs())
    fixed = intent.judge_fixed(track, particles, FIT, intent.default_hand_defs())
    row = fixed["right"]
    assert row["grasped"] and row["reachable"] and row["false_grasps"] == 0
    assert row["held_open_s"] <= intent.HELD_OPEN_S and row["pass"]
    assert fixed["left"] == {"judged": False, "note": "not tracked"}


def sweeping_open_hand():
    """An open flat hand (strength 0) waving 30 cm sideways in 0.3 s (1 m/s), palm down, at 60 Hz."""
    times = np.arange(0, 0.3, 1 / 60)
    return synthetic_track(np.zeros(len(times)), [[-0.15 + t, 1.2, 0, 0, 0, 0, 1] for t in times], times,
                           "sweeps")


def test_an_open_hand_sweeping_through_a_cube_is_a_false_grasp():
    track = sweeping_open_hand()
    hand_defs = intent.default_hand_defs()
    particles = intent.Particles(track, hand_defs)
    # the cube where the middle fingertip is halfway; the world starts when the hand is 15 cm away
    tip = np.asarray(track.frames[len(track.times) // 2]["right"].positions)[handsim.MIDDLE_TIP]
    cube = intent.Box(tip, np.eye(3), np.full(3, intent.CUBE_HALF))
    assert intent.move_clear([cube], particles.at(0), particles.radius, np.array([0, -1.0, 0])) == 0
    placement = intent.Placement("cube", "right", 0, {"cube": cube}, "in the sweep's path")
    # the paper's rule as printed grasps on any two contacts 46 deg apart: the pass-through is grasped ...
    trace = intent.run(track, placement, intent.parse_rule("paper")[1], hand_defs)
    assert trace.begins, "the paper rule grasped nothing: the made-up input no longer tests the judge"
    # ... and the judge calls it a false grasp, with the frame and hand
    false = intent.false_grasps(track, trace)
    assert false and false[0][1] == "right" and track.grab[false[0][0], 0] < intent.OPEN


def test_the_judge_reads_a_trace_as_written():
    """false_grasps, held_open_s and grasped_in on a hand-made trace (no simulation)."""
    times = np.arange(10) * 0.1
    s = np.array([0, 0, 0.5, 0.95, 0.95, 0.95, 0.1, 0.1, 0.1, 0.1])
    track = intent.Track("t", times, [{"right": None}] * 10, np.c_[s, s], np.full((10, 2), np.nan))
    held = np.zeros((10, 2), bool)
    held[3:9, 0] = True           # the right hand holds from frame 3 to 8: open from 6, i.e. 0.3 s open
    held[1, 1] = True             # the left (open) hand grasps at frame 1
    trace = intent.Trace(np.arange(10), [(3, "right", "cube"), (1, "left", "cube")], held, None)
    assert intent.false_grasps(track, trace) == [(1, "left", "cube")]
    worst, at = intent.held_open_s(track, trace)
    assert worst == pytest.approx(0.3) and at == 6
    (c,) = intent.closures(track, "right")
    assert intent.grasped_in(trace, c) and c.begin == 0 and c.end == 6


def test_reach_needs_the_hand_on_opposite_faces_closer_than_the_object():
    box = intent.Box(np.zeros(3), np.eye(3), np.full(3, 0.01))
    r = 0.005
    above, below = [0.0, 0.014, 0], [0.0, -0.014, 0]
    assert not intent.squeezed(box, np.array([above]), r)                    # one side only
    assert intent.squeezed(box, np.array([above, below]), r)                 # 1 mm in from each side
    assert intent.squeezed(box, np.array([[0.0, 0.0155, 0], [0.0, -0.0125, 0]]), r)  # or 2 mm from one side
    assert not intent.squeezed(box, np.array([[0.0, 0.0145, 0], [0.0, -0.0145, 0]]), r)  # 0.5 mm: a touch
    assert not intent.squeezed(box, np.array([above, [0.014, 0, 0]]), r)     # neighbouring faces
    assert not intent.squeezed(box, np.array([above, [0.011, -0.014, 0]]), r)  # beside the face, not over it


def test_bad_rules_name_the_field():
    for bad in ("", "mine", "mine:", "mine:nonsense=1", "mine:cos_threshold=abc", "mine:grasp_time_s=-1",
                "mine:across_parts=maybe"):
        with pytest.raises(ValueError, match="rule"):
            intent.parse_rule(bad)
    name, w = intent.parse_rule("strict:cos_threshold=-0.9,grasp_time_s=0.05,across_parts=false")
    s = w.grasp
    assert name == "strict" and s.cos_threshold == -0.9 and s.grasp_time_s == 0.05 and not s.across_parts
    name, w = intent.parse_rule("skin:skin_depth=0.003,closing_distance=0.015")  # the contact skin too
    assert w.skin_depth == 0.003 and w.grasp.closing_distance == 0.015
    assert intent._world_def_with(w).skin_depth == 0.003
    with pytest.raises(ValueError, match=r"WorldDef.skin_depth"):
        intent.parse_rule("skin:skin_depth=abc")
    with pytest.raises(ValueError, match=r"world.skin_depth"):
        intent.parse_rule("skin:skin_depth=1")
    name, w = intent.parse_rule("physical:push_model=physical")  # the push model, by name
    assert intent._world_def_with(w).push_model == handsim.PushModel.PHYSICAL
    name, w = intent.parse_rule("wrap:push_model=wrap")  # a closing hand only presses (docs/grasp.md "Wrap")
    assert intent._world_def_with(w).push_model == handsim.PushModel.WRAP
    with pytest.raises(ValueError, match=r"WorldDef.push_model: bad value 'shove'"):
        intent.parse_rule("physical:push_model=shove")


def test_the_cli_writes_nowhere_without_out(tmp_path, capsys):
    assert intent.main(["--rule", "bad rule"]) == 2
    assert "rule" in capsys.readouterr().err
    assert intent.main([str(tmp_path / "absent")]) == 2
    assert "no such file" in capsys.readouterr().err


# --- the development recordings ---------------------------------------------------------------------------

# a reduced sweep (3 placement frames per hand instead of the CLI's 4: 3 x 4 points x 2 objects = 24 per hand,
# so >= 20 per recording) keeps make test short
TEST_SWEEP_FRAMES = 3


@pytest.fixture(scope="module")
def judged():
    where = shared("leap_recordings")
    if where is None:
        pytest.skip("the Leap recordings are not there (../shared/assets/leap_recordings)")
    rules = dict([intent.parse_rule("default")])
    results = [intent.judge_track(intent.load_track(p), rules, TEST_SWEEP_FRAMES)
               for p in intent.recordings([where])]
    return results, intent.summary(results, "default")


def test_the_judge_runs_on_every_development_recording(judged):
    results, total = judged
    for r in results:
        rr = r["rules"]["default"]
        assert any(rr["fixed"][s].get("judged") for s in intent.HANDS), r["name"]
        assert rr["sweep"]["placements"] >= 20, r["name"]
        assert not np.isnan([x["reachable"] for x in rr["sweep"]["runs"]]).any()
    assert total["sweep_placements"] >= 20 * len(results)
    assert total["sweep_reachable"] > 0  # the miss rate is over something


# Passes since the appeared rule (docs/grasp.md "The appeared rule, landed"): confidence2-49fps' left hand, already inside the
# right hand's cube in its first tracked frame, no longer grasps it. The judge's full fixed protocol (this fixture
# shortens only the sweep) gives 0 false grasps and 0 never-closing hands grasped under the default rule.
def test_no_false_grasps_in_the_fixed_protocol(judged):
    assert judged[1]["fixed_false_grasps"] == 0 and judged[1]["fixed_never_closing_grasped"] == 0


@pytest.mark.xfail(strict=True, reason="issue 20: today's grasp rule misses closing hands in the fixed protocol")
def test_every_closing_hand_grasps_its_cube(judged):
    assert judged[1]["fixed_missed"] == 0


@pytest.mark.xfail(strict=True, reason="issue 20: today's grasp rule holds on through open hands")
def test_release_within_0_2_s_of_opening(judged):
    assert judged[1]["fixed_held_open"] == 0 and judged[1]["sweep_held_open"] == 0


@pytest.mark.xfail(strict=True, reason="issue 20: today's grasp rule grasps with open hands over the sweep")
def test_at_most_1_percent_false_grasps_over_the_sweep(judged):
    assert judged[1]["sweep_false_rate"] <= 0.01


@pytest.mark.xfail(strict=True, reason="issue 20: today's grasp rule misses reachable closures over the sweep")
def test_at_least_95_percent_of_reachable_closures_grasped(judged):
    assert judged[1]["sweep_grasped_rate"] >= 0.95


@pytest.mark.xfail(strict=True, reason="issue 20: today's grasp rule depends on the frame rate")
def test_frame_rate_invariance(judged):
    assert judged[1]["rate_pass"] == judged[1]["rate_recordings"]


def test_worlds_alive_together_share_a_hand_model_of_an_equal_definition():
    """World.add_hand shares the built model among live worlds (the judge builds a world per placement):
    an equal definition gives the same particles, another seed other ones."""
    frame = handsim.make_hand_frame(RIGHT, [0, 1.2, 0, 0, 0, 0, 1], curl=0.3)
    worlds = [handsim.World() for _ in range(3)]
    defs = [handsim.HandDef(), handsim.HandDef(), handsim.HandDef(seed=7)]
    hands = [w.add_hand(d) for w, d in zip(worlds, defs)]
    particles = []
    for w, h in zip(worlds, hands):
        w.step(1 / 60, {h: frame})
        particles.append(np.asarray(w.hand_particles(h)))
    np.testing.assert_array_equal(particles[0], particles[1])
    assert worlds[0].state_hash() == worlds[1].state_hash()
    assert particles[2].shape != particles[0].shape or not np.array_equal(particles[2], particles[0])


def test_failure_pictures_are_drawn(tmp_path):
    pytest.importorskip("matplotlib")
    track = closing_hand()
    for kind in ("false_grasp", "missed_closure"):
        intent.picture(tmp_path / f"{kind}.png", kind, track, "right", FIT, "fit")  # its grasp is the fit's
        assert (tmp_path / f"{kind}.png").stat().st_size > 1000


def test_pinch_reach_is_a_checked_rule_setting():
    """GraspSettings.pinch_reach (the grip span's thumb term: the thumb-index pad gap up to the reach; 0 the tip
    joints' distance): selectable in the judge, 0 in the rules to compare with, and checked by name."""
    assert handsim.GraspSettings.contacts().pinch_reach == 0 and handsim.GraspSettings.paper().pinch_reach == 0
    name, w = intent.parse_rule("pads:pinch_reach=0.065")
    assert name == "pads" and w.grasp.pinch_reach == 0.065
    for bad in (-0.001, 1.5, math.nan):
        with pytest.raises(handsim.InvalidArgumentError, match=r"^world.grasp.pinch_reach: "):
            handsim.World(handsim.WorldDef(grasp=handsim.GraspSettings(pinch_reach=bad)))
