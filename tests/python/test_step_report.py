"""The typed step report (World.step returns it, World.last_step keeps it): skip reasons, warnings, and the
joint solve fields cleared each step."""
import handsim
import pytest

DT = 1 / 60


def test_an_empty_world_reports_each_skipped_stage_with_its_reason():
    world = handsim.World()
    report = world.step(DT)
    assert isinstance(report, handsim.StepReport)
    assert report.stage(handsim.Stage.SKINNING).skip == handsim.SkipReason.NO_TRACKED_HAND
    assert not report.stage(handsim.Stage.SKINNING).ran
    assert report.stage(handsim.Stage.JOINTS).skip == handsim.SkipReason.NO_JOINTS
    dynamics = report.stage(handsim.Stage.DYNAMICS)
    assert dynamics.ran and dynamics.skip == handsim.SkipReason.NONE and dynamics.work == 4  # 4 substeps of 1/240 s
    assert report.warnings == 0 and report.substeps == 4
    assert world.last_step().stage(handsim.Stage.JOINTS).skip == handsim.SkipReason.NO_JOINTS
    assert "skip: no tracked hand" in str(report) and str(report) == world.stage_summary()
    # Below one substep, dynamics waits for the accumulator.
    assert world.step(0.5 / 240).stage(handsim.Stage.DYNAMICS).skip == handsim.SkipReason.BELOW_SUBSTEP


def test_a_huge_dt_raises_substeps_dropped_for_that_step_only():
    world = handsim.World()
    world.add_body(handsim.BodyDef(shape=handsim.Shape.box([0.05] * 3), pose=[0, 1, 0, 0, 0, 0, 1]))
    report = world.step(1.0)  # 240 substeps owed, max_substeps 8 run
    assert report.has(handsim.StepWarning.SUBSTEPS_DROPPED)
    assert report.warnings == 1 << int(handsim.StepWarning.SUBSTEPS_DROPPED)
    assert report.substeps == 8 and report.bullet
    assert report.dropped_seconds == pytest.approx(1 - 8 / 240, abs=1e-12)
    assert "beyond max_substeps dropped" in world.stage_summary()
    assert not world.step(DT).has(handsim.StepWarning.SUBSTEPS_DROPPED)


def test_a_teleporting_palm_warns():
    world = handsim.World()
    hand = world.add_hand(handsim.HandDef())
    here = handsim.make_hand_frame(handsim.Handedness.RIGHT, [0, 0.3, 0, 0, 0, 0, 1])
    assert world.step(DT, {hand: here}).warnings == 0
    assert world.step(DT, {hand: here}).warnings == 0
    far = handsim.make_hand_frame(handsim.Handedness.RIGHT, [1e6, 0.3, 0, 0, 0, 0, 1])
    assert world.step(DT, {hand: far}).has(handsim.StepWarning.HAND_TELEPORTED)
    assert not world.step(DT, {hand: far}).has(handsim.StepWarning.HAND_TELEPORTED)


def test_joint_solved_is_false_the_frame_after_the_hand_leaves():
    world = handsim.World()
    box = handsim.build_jewelry_box(world)
    hand = world.add_hand(handsim.HandDef())
    pinch = handsim.lid_pinch_shape()
    for i in range(50):  # the hand closes its pinch on the lip (closing_grip: 15 frames), then swings
        angle = min(max((i - 20) / 30, 0.0), 1.0) * 0.5
        palm = box.lid_pinch_palm(world, handsim.Handedness.RIGHT, angle)
        world.step(DT, {hand: handsim.make_hand_frame(handsim.Handedness.RIGHT, palm,
                                                      params=handsim.closing_grip(pinch, i * DT))})
    assert world.body_grasp(box.lid).grasped and world.joint_state(box.hinge).solved
    world.remove_hand(hand)
    world.step(DT)
    state = world.joint_state(box.hinge)
    assert not state.solved and state.cost == 0 and state.iterations == 0 and state.solve_seconds == 0


def test_a_kept_report_is_never_rewritten_by_a_later_step():
    """World.step reuses a report object nothing else refers to (docs/performance.md "Session 18"); one a caller
    keeps, directly, in a list or through a weak reference, keeps its own step's report."""
    import weakref
    world = handsim.World()
    world.add_body(handsim.BodyDef(shape=handsim.Shape.box([0.05] * 3), pose=[0, 1, 0, 0, 0, 0, 1]))
    first = world.step(1.0)  # substeps dropped: a report unlike the next ones
    kept = [world.step(DT) for _ in range(3)]
    assert len({id(r) for r in kept}) == 3
    weak_target = world.step(0.5 / 240)  # below one substep: dynamics skipped
    weak = weakref.ref(weak_target)
    del weak_target
    for _ in range(4):
        world.step(DT)  # dropped at once: reusable
    last = None
    for _ in range(4):
        last = world.step(DT)  # the previous one held by `last` while the step runs
    assert first.has(handsim.StepWarning.SUBSTEPS_DROPPED) and first.substeps == 8
    assert all(not r.has(handsim.StepWarning.SUBSTEPS_DROPPED) and r.substeps == 4 for r in kept)
    if weak() is not None:
        assert weak().stage(handsim.Stage.DYNAMICS).skip == handsim.SkipReason.BELOW_SUBSTEP
    assert last.substeps == 4 and world.last_step().substeps == 4
