"""bad_input matrix: every World method and module function that takes arguments, called with bad ones.

(World.contains answers False for anything that is not a live id of this world; it raises nothing.)

Each row: the call, the exception type it must raise, and a word its message must contain (the argument's
name). After every row the world's state hash is unchanged.
"""
import math

import numpy as np
import pytest

import handsim

NAN = math.nan


@pytest.fixture(scope="module")
def scene():
    world = handsim.World()
    box = handsim.build_jewelry_box(world)
    hand = world.add_hand(handsim.HandDef())
    palm = box.lid_pinch_palm(world, handsim.Handedness.RIGHT, 0.0, 0.0)
    frame = handsim.make_hand_frame(handsim.Handedness.RIGHT, palm)
    for _ in range(3):
        world.step(1 / 60, {hand: frame})
    other = handsim.World()
    foreign = other.add_body(handsim.BodyDef(shape=handsim.Shape.sphere(0.1)))
    return world, box, hand, frame, foreign


def bad_frame(frame, **change):
    positions = frame.positions.copy()
    orientations = frame.orientations.copy()
    radii = frame.radii.copy()
    valid = frame.valid.copy()
    if "position" in change:
        positions[10, 0] = change["position"]
    if "orientation" in change:
        orientations[1] = change["orientation"]
    if "radius" in change:
        radii[4] = change["radius"]
    return handsim.HandFrame(frame.handedness, positions, orientations, radii, valid)


def rows(world, box, hand, frame, foreign):
    box_def = lambda **kw: handsim.BodyDef(shape=handsim.Shape.box([0.1] * 3), **kw)  # noqa: E731
    err = handsim.InvalidArgumentError
    stale = handsim.StaleIdError
    foreign_hand = handsim.HandId.unpack(12345 << 32)
    state = handsim.InvalidStateError
    return [
        ("step dt=0", lambda: world.step(0.0), err, "dt"),
        ("step dt<0", lambda: world.step(-1.0), err, "dt"),
        ("step dt=nan", lambda: world.step(NAN), err, "dt"),
        ("step dt huge", lambda: world.step(1e300), err, "dt"),
        ("step foreign hand", lambda: world.step(1 / 60, {foreign_hand: frame}), stale, "hands[HandId"),
        ("step key not an id", lambda: world.step(1 / 60, {0: frame}), TypeError, "hands"),
        ("step nan joint", lambda: world.step(1 / 60, {hand: bad_frame(frame, position=NAN)}), err, "joints[10]"),
        ("step zero quaternion", lambda: world.step(1 / 60, {hand: bad_frame(frame, orientation=[0, 0, 0, 0])}),
         err, "joints[1]"),
        ("step negative radius", lambda: world.step(1 / 60, {hand: bad_frame(frame, radius=-1)}), err, "joints[4]"),
        ("step wrong type", lambda: world.step(1 / 60, {hand: "frame"}), TypeError, "hands[HandId"),
        ("step not a dict", lambda: world.step(1 / 60, frame), TypeError, "hands"),
        ("add_body negative mass", lambda: world.add_body(box_def(mass=-1.0)), err, "mass"),
        ("add_body nan pose", lambda: world.add_body(box_def(pose=[NAN, 0, 0, 0, 0, 0, 1])), err, "pose"),
        ("add_body far pose", lambda: world.add_body(box_def(pose=[1e300, 0, 0, 0, 0, 0, 1])), err, "pose"),
        ("add_body bad quaternion", lambda: world.add_body(box_def(pose=[0, 0, 0, 0, 0, 0, 2])), err, "orientation"),
        ("add_body negative size",
         lambda: world.add_body(handsim.BodyDef(shape=handsim.Shape.box([-1, 1, 1]))), err, "half_extents"),
        ("shape wrong shape", lambda: handsim.Shape.box([1, 1]), ValueError, "half_extents"),
        ("remove_body foreign", lambda: world.remove_body(foreign), stale, "body"),
        ("remove_body jointed", lambda: world.remove_body(box.lid), state, "joint"),
        ("body_pose foreign", lambda: world.body_pose(foreign), stale, "body"),
        ("set_body_pose nan", lambda: world.set_body_pose(box.base, [NAN, 0, 0, 0, 0, 0, 1]), err, "pose"),
        ("set_body_pose shape", lambda: world.set_body_pose(box.base, [0, 0, 0]), ValueError, "pose"),
        ("set_body_pose hard child", lambda: world.set_body_pose(box.lid, [0, 1, 0, 0, 0, 0, 1]), state, "body"),
        ("set_body_velocity nan", lambda: world.set_body_velocity(box.base, [NAN, 0, 0], [0, 0, 0]), err, "linear"),
        ("set_body_velocity fast", lambda: world.set_body_velocity(box.base, [1e9, 0, 0], [0, 0, 0]), err, "linear"),
        ("set_body_velocity static", lambda: world.set_body_velocity(box.table, [1, 0, 0], [0, 0, 0]), state, "body"),
        ("set_joint_value nan", lambda: world.set_joint_value(box.hinge, NAN), err, "value"),
        ("add_joint child=parent",
         lambda: world.add_joint(handsim.HingeDef(parent=box.base, child=box.base)), err, "child"),
        ("add_joint lower>upper",
         lambda: world.add_joint(handsim.HingeDef(parent=box.base, child=box.lid, lower=1.0, upper=0.0)), err,
         "lower"),
        ("add_joint zero axis",
         lambda: world.add_joint(handsim.HingeDef(parent=box.base, child=box.lid, axis_parent=[0, 0, 0])), err,
         "axis"),
        ("add_hand bad count", lambda: world.add_hand(handsim.HandDef(particle_count=-5)), err, "particle_count"),
        ("grasp settings wrong type", lambda: handsim.GraspSettings(across_parts="yes"), TypeError,
         "GraspSettings.across_parts"),
        ("flag set to None", lambda: handsim.GraspSettings(across_parts=None), TypeError,
         "GraspSettings.across_parts: expected True or False, got NoneType"),
        ("flag set to 0", lambda: setattr(handsim.BodyDef(), "kinematic", 0), TypeError, "BodyDef.kinematic"),
        ("hand def wrong type", lambda: world.add_hand(handsim.HandDef(particle_count="many")), TypeError,
         "HandDef.particle_count"),
        ("hand_particles foreign", lambda: world.hand_particles(handsim.HandId.unpack(12345 << 32)), stale, "hand"),
        ("body_contact_count foreign", lambda: world.body_contact_count(foreign, hand), stale, "body"),
        ("joint_state stale", lambda: world.joint_state(handsim.JointId.unpack((77 << 32) | 5)), stale, "joint"),
        ("scenario_frames frame<0", lambda: handsim.scenario_frames(box, world, -1), err, "frame"),
        ("body_grasp foreign", lambda: world.body_grasp(foreign), stale, "body"),
        ("body_mass foreign", lambda: world.body_mass(foreign), stale, "body"),
        ("body_motion foreign", lambda: world.body_motion(foreign), stale, "body"),
        ("body_shape foreign", lambda: world.body_shape(foreign), stale, "body"),
        ("body_velocity foreign", lambda: world.body_velocity(foreign), stale, "body"),
        ("hand_model foreign", lambda: world.hand_model(foreign_hand), stale, "hand"),
        ("hand_palm_pose foreign", lambda: world.hand_palm_pose(foreign_hand), stale, "hand"),
        ("hand_render_vertices foreign", lambda: world.hand_render_vertices(foreign_hand), stale, "hand"),
        ("hand_tracked foreign", lambda: world.hand_tracked(foreign_hand), stale, "hand"),
        ("remove_hand foreign", lambda: world.remove_hand(foreign_hand), stale, "hand"),
        ("remove_joint stale", lambda: world.remove_joint(handsim.JointId.unpack((77 << 32) | 5)), stale, "joint"),
        ("bind_frame scale<0", lambda: handsim.bind_frame(handsim.Handedness.RIGHT, scale=-1.0), err, "scale"),
        ("bind_frame handedness", lambda: handsim.bind_frame("up"), TypeError, "handedness"),
        ("collide_particles radius<0",
         lambda: handsim.collide_particles([[0, 0, 0]], -0.01, handsim.Shape.sphere(0.1), [0, 0, 0, 0, 0, 0, 1]), err,
         "radius"),
        ("hinge_from_world zero axis",
         lambda: handsim.hinge_from_world(box.base, world.body_pose(box.base), box.lid, world.body_pose(box.lid),
                                          [0, 0, 0], [0, 0, 0]), err, "axis_world"),
        ("make_hand_mesh too few vertices",
         lambda: handsim.make_hand_mesh(handsim.bind_frame(handsim.Handedness.RIGHT), target_vertices=-5), err,
         "target_vertices"),
    ]


def test_bad_input_matrix(scene):
    world, box, hand, frame, foreign = scene
    covered = 0
    for name, call, exc, word in rows(world, box, hand, frame, foreign):
        before = world.state_hash()
        try:
            call()
        except exc as e:
            assert word in str(e), f"{name}: message {e!r} does not name {word!r}"
        else:
            pytest.fail(f"{name}: did not raise {exc.__name__}")
        assert world.state_hash() == before, f"{name}: the world changed"
        covered += 1
    assert covered >= 51
