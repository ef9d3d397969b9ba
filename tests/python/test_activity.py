"""Idle physics (issue 25): Bullet is skipped only when it would change nothing, and whatever Bullet would wake
still wakes. No times here: what is checked is which stage ran and where the bodies are."""
import handsim
import numpy as np

DT = 1 / 60
BOX = 0.05


def _bullet_ran(world):
    """Whether Bullet simulated the last step's substeps (not only the clock and hard joints)."""
    return world.last_step().bullet


def _settled_box_on_table():
    world = handsim.World()
    table = world.add_body(handsim.BodyDef(shape=handsim.Shape.box([0.3, 0.2, 0.3]), mass=0.0,
                                           pose=[0, 0.2, 0, 0, 0, 0, 1]))
    box = world.add_body(handsim.BodyDef(shape=handsim.Shape.box([BOX] * 3), mass=0.5,
                                         pose=[0, 0.4 + BOX, 0, 0, 0, 0, 1]))
    for _ in range(240):  # Bullet puts a body at rest to sleep after 2 s
        world.step(DT)
    return world, table, box


def test_a_settled_scene_skips_bullet_and_stays_put():
    world, _, box = _settled_box_on_table()
    before = world.body_pose(box)
    world.step(DT)
    assert not _bullet_ran(world)
    assert np.array_equal(world.body_pose(box), before)


def test_moving_the_support_away_wakes_what_rests_on_it():
    world, table, box = _settled_box_on_table()
    world.set_body_pose(table, [2, 0.2, 0, 0, 0, 0, 1])
    for _ in range(60):
        world.step(DT)
    assert world.body_pose(box)[1] < 0.2  # fell towards the ground


def test_removing_the_support_wakes_what_rests_on_it():
    world, table, box = _settled_box_on_table()
    world.remove_body(table)
    world.step(DT)
    assert _bullet_ran(world)
    for _ in range(60):
        world.step(DT)
    assert world.body_pose(box)[1] < 0.2


def test_a_push_wakes_a_sleeping_box():
    world, _, box = _settled_box_on_table()
    world.set_body_velocity(box, [1.0, 0, 0], [0, 0, 0])
    world.step(DT)
    assert _bullet_ran(world)
    assert world.body_pose(box)[0] > 0.01


def test_a_kinematic_body_moved_into_a_sleeping_box_pushes_it():
    world, _, box = _settled_box_on_table()
    pusher = world.add_body(handsim.BodyDef(shape=handsim.Shape.box([0.03] * 3), kinematic=True,
                                            pose=[-0.5, 0.4 + BOX, 0, 0, 0, 0, 1]))
    for _ in range(240):  # let the new body's wake-up settle again
        world.step(DT)
    x0 = world.body_pose(box)[0]
    for i in range(60):  # glide through where the box is, by set_body_pose (as a host moves a prop)
        world.set_body_pose(pusher, [-0.5 + 0.01 * i, 0.4 + BOX, 0, 0, 0, 0, 1])
        world.step(DT)
    assert world.body_pose(box)[0] > x0 + 0.01


def test_a_thousand_static_boxes_and_a_far_hand_skip_bullet():
    world = handsim.World()
    for i in range(1000):
        world.add_body(handsim.BodyDef(shape=handsim.Shape.box([0.02] * 3), mass=0.0,
                                       pose=[0.1 * (i % 32), 0.02, 0.1 * (i // 32), 0, 0, 0, 1]))
    hand = world.add_hand(handsim.HandDef(handedness=handsim.Handedness.RIGHT))
    far = handsim.make_hand_frame(handsim.Handedness.RIGHT, [-5, 1.5, -5, 0, 0, 0, 1])
    world.step(DT, {hand: far})
    world.step(DT, {hand: far})
    report = world.last_step()
    assert not report.bullet and report.stage(handsim.Stage.DYNAMICS).work == 4  # 4 substeps, Bullet idle
    assert report.stage(handsim.Stage.CONTACTS).skip == handsim.SkipReason.NO_HAND_NEAR_BODY  # the broadphase
    assert world.hand_tracked(hand)
