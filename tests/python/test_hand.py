"""The virtual hand through the bindings: frames, skinning, particles, deformation, events, the glTF loader."""
import json
import math
import os
import pickle
import sys
from pathlib import Path

import numpy as np
import pytest

import handsim
from handsim import Handedness

RIGHT, LEFT = Handedness.RIGHT, Handedness.LEFT
DT = 1 / 60


def quat_matrix(q):
    x, y, z, w = np.asarray(q, dtype=float) / np.linalg.norm(q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def unit_quat(*q):
    q = np.array(q, dtype=float)
    return q / np.linalg.norm(q)


# An arbitrary rigid motion: a turn of ~0.8 rad about a skew axis and a translation.
MOTION = np.array([0.3, 1.1, -0.4, *unit_quat(0.3, -0.5, 0.2, 0.8)])


def frame_arrays(frame):
    """Writable copies of the frame's arrays (its attributes are read-only)."""
    return frame.positions.copy(), frame.orientations.copy(), frame.radii.copy(), frame.valid.copy()


@pytest.fixture(scope="module")
def hand_world():
    """A world with one default right hand and nothing else."""
    world = handsim.World(handsim.WorldDef(ground=False))
    return world, world.add_hand(handsim.HandDef())


# --- frames ---------------------------------------------------------------------------------------------

def test_joint_constants_follow_openxr_order():
    assert len(handsim.JOINT_NAMES) == handsim.JOINT_COUNT == 26
    assert (handsim.PALM, handsim.WRIST, handsim.THUMB_TIP, handsim.INDEX_TIP, handsim.LITTLE_TIP) == (0, 1, 5, 10, 25)
    assert handsim.JOINT_NAMES[handsim.MIDDLE_INTERMEDIATE] == "middle_intermediate"
    assert handsim.HandJoint.RING_DISTAL == handsim.RING_DISTAL == 19


def test_frame_round_trips_its_arrays():
    rng = np.random.default_rng(3)
    positions = rng.normal(size=(26, 3))
    quats = rng.normal(size=(26, 4))
    quats /= np.linalg.norm(quats, axis=1, keepdims=True)
    radii = rng.uniform(0.005, 0.02, 26)
    valid = rng.uniform(size=26) > 0.3
    valid[:2] = True
    f = handsim.HandFrame(LEFT, positions, quats, radii, valid)
    assert f.handedness == LEFT and f.tracked
    np.testing.assert_array_equal(f.positions, positions)
    np.testing.assert_array_equal(f.orientations, quats)
    np.testing.assert_array_equal(f.radii, radii)
    np.testing.assert_array_equal(f.valid, valid)
    assert f.valid.dtype == bool and f.positions.dtype == np.float64
    np.testing.assert_array_equal(f.palm_pose, np.concatenate([positions[0], quats[0]]))
    np.testing.assert_array_equal(f.joint_pose(handsim.INDEX_TIP), np.concatenate([positions[10], quats[10]]))
    g = pickle.loads(pickle.dumps(f))
    for a, b in zip(frame_arrays(f), frame_arrays(g)):
        np.testing.assert_array_equal(a, b)
    defaults = handsim.HandFrame(RIGHT, positions, quats)
    assert defaults.valid.all() and (defaults.radii == 0.01).all()


def test_untracked_frame_without_palm_or_wrist():
    f = handsim.bind_frame(RIGHT)
    p, q, r, v = frame_arrays(f)
    v[handsim.WRIST] = False
    assert not handsim.HandFrame(RIGHT, p, q, r, v).tracked


@pytest.mark.parametrize("field, value, message", [
    ("positions", np.zeros((25, 3)), r"^positions: expected shape \(26, 3\), got \(25, 3\)$"),
    ("positions", np.zeros(78), r"^positions: expected shape \(26, 3\), got \(78,\)$"),
    ("orientations", np.zeros((26, 3)), r"^orientations: expected shape \(26, 4\), got \(26, 3\)$"),
    ("radii", np.zeros((26, 1)), r"^radii: expected shape \(26,\), got \(26, 1\)$"),
    ("valid", np.ones(27, dtype=bool), r"^valid: expected shape \(26,\), got \(27,\)$"),
    ("valid", np.full(26, 0.5), r"^valid: expected booleans, got 0.5 at joint 0$"),
])
def test_frame_shape_errors_name_the_argument(field, value, message):
    args = dict(zip(["positions", "orientations", "radii", "valid"], frame_arrays(handsim.bind_frame(RIGHT))))
    args[field] = value
    with pytest.raises(ValueError, match=message):
        handsim.HandFrame(RIGHT, **args)


def test_frame_type_errors_name_the_argument():
    p, q, r, v = frame_arrays(handsim.bind_frame(RIGHT))
    with pytest.raises(TypeError, match="^handedness: expected a Handedness, got int$"):
        handsim.HandFrame(1, p, q)
    with pytest.raises(TypeError, match="^positions: expected an array of numbers, got str$"):
        handsim.HandFrame(RIGHT, "joints", q)
    with pytest.raises(TypeError, match="^orientations: expected an array of numbers, got NoneType$"):
        handsim.HandFrame(RIGHT, p, None)


@pytest.mark.parametrize("joint, field, bad, argument", [
    (7, "positions", [np.nan, 0, 0], "frame.joints[7].position"),
    (12, "positions", [0, np.inf, 0], "frame.joints[12].position"),
    (3, "orientations", [0, 0, 0, 1.1], "frame.joints[3].orientation"),
    (3, "orientations", [0, 0, 0, 0], "frame.joints[3].orientation"),
    (20, "orientations", [np.nan, 0, 0, 1], "frame.joints[20].orientation"),
    (12, "radii", -0.001, "frame.joints[12].radius"),
])
def test_bad_valid_joint_is_rejected_naming_it(joint, field, bad, argument):
    arrays = dict(zip(["positions", "orientations", "radii", "valid"], frame_arrays(handsim.bind_frame(RIGHT))))
    arrays[field][joint] = bad
    with pytest.raises(handsim.InvalidArgumentError, match="^" + argument.replace("[", r"\[").replace("]", r"\]") + ": "):
        handsim.HandFrame(RIGHT, **arrays)
    # The same values in an invalid joint are legal (an untracked joint may hold anything).
    arrays["valid"][joint] = False
    f = handsim.HandFrame(RIGHT, **arrays)
    assert not f.valid[joint]


def test_nearly_unit_quaternions_are_accepted():
    p, q, r, v = frame_arrays(handsim.bind_frame(RIGHT))
    q[4] *= 1 + 5e-4
    handsim.HandFrame(RIGHT, p, q, r, v)


def test_make_hand_frame_places_the_palm_and_mirrors_the_left_hand():
    f = handsim.make_hand_frame(RIGHT, MOTION)
    np.testing.assert_allclose(f.palm_pose, MOTION, atol=1e-15)
    right, left = handsim.bind_frame(RIGHT), handsim.bind_frame(LEFT)
    assert right.positions[handsim.THUMB_TIP, 0] < -0.05 and left.positions[handsim.THUMB_TIP, 0] > 0.05
    np.testing.assert_array_equal(left.positions, right.positions * [-1, 1, 1])
    np.testing.assert_allclose(left.orientations, right.orientations * [1, -1, -1, 1], atol=1e-15)
    # Scalar curl = the same curl on every finger; keywords override params.
    a = handsim.make_hand_frame(RIGHT, curl=0.5)
    b = handsim.make_hand_frame(RIGHT, curl=[0.5] * 5)
    c = handsim.make_hand_frame(RIGHT, params=handsim.HandPoseParams(curl=[1] * 5, scale=0.9), curl=0.5, scale=1)
    np.testing.assert_array_equal(a.positions, b.positions)
    np.testing.assert_array_equal(a.positions, c.positions)
    assert handsim.HandPoseParams(spread=0.5).spread == 0.5


def test_make_hand_frame_errors_name_the_argument():
    with pytest.raises(ValueError, match=r"^curl: expected shape \(5,\), got \(4,\)$"):
        handsim.make_hand_frame(RIGHT, curl=[0, 0, 0, 0])
    with pytest.raises(ValueError, match=r"^palm_pose: expected shape \(7,\), got \(3,\)$"):
        handsim.make_hand_frame(RIGHT, [0, 0, 0])
    with pytest.raises(handsim.InvalidArgumentError, match="^params.scale: "):
        handsim.make_hand_frame(RIGHT, scale=-1)
    with pytest.raises(TypeError, match="^spread: expected an array of numbers, got str$"):
        handsim.make_hand_frame(RIGHT, spread="wide")
    with pytest.raises(ValueError, match=r"^scale: expected shape \(\), got \(2,\)$"):
        handsim.make_hand_frame(RIGHT, scale=[1, 2])
    with pytest.raises(TypeError, match="^params: expected a HandPoseParams, got dict$"):
        handsim.make_hand_frame(RIGHT, params={})


def test_transformed_moves_every_joint_rigidly():
    f = handsim.make_hand_frame(RIGHT, curl=0.4).transformed(MOTION)
    g = handsim.make_hand_frame(RIGHT, MOTION, curl=0.4)
    np.testing.assert_allclose(f.positions, g.positions, atol=1e-15)
    np.testing.assert_allclose(f.orientations, g.orientations, atol=1e-15)
    with pytest.raises(handsim.InvalidArgumentError, match=r"^pose.orientation: .* got length 2$"):
        f.transformed([0, 0, 0, 0, 0, 0, 2])


# --- meshes and models ----------------------------------------------------------------------------------

def tiny_mesh():
    positions = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1.0]]) * 0.01
    bones = np.array([[1, 0, 0, 0]] * 4)
    weights = np.array([[1.0, 0, 0, 0]] * 4)
    triangles = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    return positions, bones, weights, triangles


def test_skinned_mesh_round_trip_and_errors():
    positions, bones, weights, triangles = tiny_mesh()
    mesh = handsim.SkinnedMesh(positions, bones, weights, triangles)
    assert (mesh.vertex_count, mesh.triangle_count) == (4, 4)
    np.testing.assert_array_equal(mesh.positions, positions)
    np.testing.assert_array_equal(mesh.bones, bones)
    np.testing.assert_array_equal(mesh.weights, weights)
    np.testing.assert_array_equal(mesh.triangles, triangles)
    with pytest.raises(TypeError, match="^bones: expected an array of integers, got dtype float64$"):
        handsim.SkinnedMesh(positions, bones.astype(float), weights, triangles)
    with pytest.raises(ValueError, match=r"^weights: expected shape \(4, 4\), got \(3, 4\)$"):
        handsim.SkinnedMesh(positions, bones, weights[:3], triangles)
    with pytest.raises(ValueError, match=r"^triangles: expected shape \(N, 3\), got \(12,\)$"):
        handsim.SkinnedMesh(positions, bones, weights, triangles.reshape(-1))
    with pytest.raises(handsim.InvalidArgumentError, match=r"^mesh.weights: must sum to 1, got 0.5 \(vertex 2\)$"):
        handsim.SkinnedMesh(positions, bones, np.where(np.arange(4)[:, None] == 2, weights * 0.5, weights), triangles)
    with pytest.raises(handsim.InvalidArgumentError, match="^mesh.bones: joint index 26 not in 0..25"):
        handsim.SkinnedMesh(positions, bones + 25, weights, triangles)
    with pytest.raises(handsim.InvalidArgumentError, match="^mesh.triangles: index 4 is out of range$"):
        handsim.SkinnedMesh(positions, bones, weights, triangles + 1)
    with pytest.raises(handsim.InvalidArgumentError, match="^mesh.positions: must be finite$"):
        handsim.SkinnedMesh(np.where(positions == 0.01, np.nan, positions), bones, weights, triangles)


def test_model_of_a_supplied_mesh_and_its_errors():
    bind = handsim.bind_frame(RIGHT)
    mesh = handsim.make_hand_mesh(bind, 3000)
    model = handsim.HandModel(handsim.HandDef(particle_count=300), mesh, bind)
    assert model.vertex_count == mesh.vertex_count and model.particle_count == 300
    np.testing.assert_array_equal(model.bind_vertices, mesh.positions[model.source_vertex])
    np.testing.assert_array_equal(np.sort(model.source_vertex), np.arange(mesh.vertex_count))
    with pytest.raises(handsim.InvalidArgumentError, match="^bind: mesh and bind go together"):
        handsim.HandModel(handsim.HandDef(), mesh)
    with pytest.raises(handsim.InvalidArgumentError, match="^bind.handedness: differs from def.handedness$"):
        handsim.HandModel(handsim.HandDef(handedness=LEFT), mesh, bind)
    with pytest.raises(handsim.InvalidArgumentError, match="^def.particle_count: "):
        handsim.HandModel(handsim.HandDef(particle_count=0))
    with pytest.raises(handsim.InvalidArgumentError, match="^target_vertices: "):
        handsim.make_hand_mesh(bind, 10)


# --- skinning (eq. 1) -----------------------------------------------------------------------------------

def test_bind_pose_gives_the_bind_mesh(hand_world):
    world, hand = hand_world
    model = world.hand_model(hand)
    assert 38000 <= model.vertex_count <= 40000 and model.particle_count == 1182
    world.step(DT, {hand: model.bind})
    assert world.hand_tracked(hand)
    vertices = world.hand_render_vertices(hand)
    assert vertices.shape == (model.vertex_count, 3)
    # Exact up to the rounding of B = bind * bind^-1 (one ulp-level rotation error).
    assert np.abs(vertices - model.bind_vertices).max() <= 1e-15
    particles = world.hand_particles(hand)
    assert particles.shape == (1182, 3)
    assert np.abs(particles - model.bind_vertices[model.particle_vertex]).max() <= 1e-15
    np.testing.assert_array_equal(world.hand_particles(hand, deformed=True), particles)


def test_rigid_motion_of_all_joints_moves_the_mesh_rigidly(hand_world):
    world, hand = hand_world
    model = world.hand_model(hand)
    world.step(DT, {hand: model.bind.transformed(MOTION)})
    expected = model.bind_vertices @ quat_matrix(MOTION[3:]).T + MOTION[:3]
    assert np.abs(world.hand_render_vertices(hand) - expected).max() <= 1e-12
    assert np.abs(world.hand_particles(hand) - expected[model.particle_vertex]).max() <= 1e-12
    np.testing.assert_allclose(world.hand_palm_pose(hand), MOTION, atol=1e-15)


def test_bending_one_finger_moves_only_its_vertices(hand_world):
    world, hand = hand_world
    model = world.hand_model(hand)
    world.step(DT, {hand: handsim.make_hand_frame(RIGHT, curl=[0, 1, 0, 0, 0])})
    moved = np.linalg.norm(world.hand_render_vertices(hand) - model.bind_vertices, axis=1)
    mesh = model.mesh
    index_bones = [handsim.INDEX_PROXIMAL, handsim.INDEX_INTERMEDIATE, handsim.INDEX_DISTAL, handsim.INDEX_TIP]
    on_index = (np.isin(mesh.bones, index_bones) & (mesh.weights > 0)).any(axis=1)
    assert moved[~on_index].max() <= 1e-15
    assert np.median(moved[on_index]) > 0.01


def test_same_seed_same_particles_different_seed_different():
    def model(seed):
        return handsim.HandModel(handsim.HandDef(particle_count=1182, sampling=handsim.ParticleSampling.RANDOM,
                                                 seed=seed))
    a, b, c = model(7), model(7), model(8)
    np.testing.assert_array_equal(a.particle_vertex, b.particle_vertex)
    assert len(np.setdiff1d(a.particle_vertex, c.particle_vertex)) > 500
    assert np.all(a.exposed[a.particle_vertex])


def test_even_sampling_has_a_smaller_largest_gap():
    def model(sampling, seed=1):  # radius 0: from the spacing, which the gap is compared with
        return handsim.HandModel(handsim.HandDef(particle_count=1182, sampling=sampling, seed=seed, particle_radius=0))
    random = [model(handsim.ParticleSampling.RANDOM, s).largest_particle_gap() for s in (1, 2)]
    even = model(handsim.ParticleSampling.EVEN)
    assert even.particle_count == 1182
    assert even.largest_particle_gap() < 0.75 * min(random)
    # A hexagonal covering of the skin with 1,182 points leaves gaps of about a particle radius.
    assert even.largest_particle_gap() < 2 * even.particle_radius


# --- contacts and local deformation ---------------------------------------------------------------------

BOX_HALF = np.array([0.2, 0.1, 0.2])
BOX_CENTRE = np.array([0, -0.1, -0.05])  # top face at y = 0


def box_signed_distance(points):
    local = points - BOX_CENTRE
    outside = np.linalg.norm(np.maximum(np.abs(local) - BOX_HALF, 0), axis=1)
    inside = np.minimum((np.abs(local) - BOX_HALF).max(axis=1), 0)
    return outside + inside


def pressed_world(with_box=True):
    """A flat right hand, palm down, whose lowest particle centre is 1 cm below the top of a static box."""
    world = handsim.World(handsim.WorldDef(ground=False))
    hand = world.add_hand(handsim.HandDef())
    box = None
    if with_box:
        box = world.add_body(handsim.BodyDef(shape=handsim.Shape.box(BOX_HALF), mass=0,
                                             pose=[*BOX_CENTRE, 0, 0, 0, 1]))
    model = world.hand_model(hand)
    lowest = model.bind_vertices[model.particle_vertex, 1].min()
    frame = handsim.make_hand_frame(RIGHT, [0, -lowest - 0.01, 0, 0, 0, 0, 1])
    world.step(DT, {hand: frame})
    return world, hand, box, frame


def test_hand_pressed_into_a_box_is_drawn_on_its_surface():
    world, hand, box, frame = pressed_world()
    model = world.hand_model(hand)
    tracked = world.hand_particles(hand)
    deformed = world.hand_particles(hand, deformed=True)
    # Tracked particles are the skinned ones: the frame is the bind frame translated.
    shift = frame.palm_pose[:3]
    assert np.abs(tracked - (model.bind_vertices[model.particle_vertex] + shift)).max() <= 1e-15
    sd_tracked, sd_deformed = box_signed_distance(tracked), box_signed_distance(deformed)
    sunk = sd_tracked < 0
    assert sunk.sum() > 50 and sd_tracked.min() == pytest.approx(-0.01, abs=1e-12)
    assert sd_deformed.min() >= -1e-6
    assert np.abs(sd_deformed[sunk]).max() <= 1e-6  # moved exactly onto the surface
    np.testing.assert_array_equal(deformed[~sunk], tracked[~sunk])
    # Every particle within a radius of the box touches it; the static box does not move.
    touching = int((sd_tracked < model.particle_radius).sum())
    assert world.body_contact_count(box, hand) == touching
    np.testing.assert_array_equal(world.body_pose(box), [*BOX_CENTRE, 0, 0, 0, 1])
    events = world.events()
    assert [(e.type, e.hand, e.body) for e in events] == [(handsim.EventType.CONTACT_BEGIN, hand, box)]

    # The render mesh follows the particles; the back of the hand, far from the box, does not move.
    free_world, free_hand, _, _ = pressed_world(with_box=False)
    undeformed = free_world.hand_render_vertices(free_hand)
    drawn = world.hand_render_vertices(hand)
    back = undeformed[:, 1] > 0.03
    assert back.sum() > 1000
    np.testing.assert_array_equal(drawn[back], undeformed[back])
    pressed = (box_signed_distance(undeformed) < 0) & model.exposed
    assert box_signed_distance(undeformed[pressed]).min() < -0.009
    assert box_signed_distance(drawn[pressed]).min() > -model.particle_radius


def test_closed_form_and_bullet_contacts_agree():
    world, hand, box, _ = pressed_world()
    centres = world.hand_particles(hand)
    radius = world.hand_model(hand).particle_radius
    shape = handsim.Shape.box(BOX_HALF)
    pose = [*BOX_CENTRE, 0, 0, 0, 1]
    closed = handsim.collide_particles(centres, radius, shape, pose)
    collider = handsim.BulletParticleCollider(len(centres), radius)
    assert collider.add_body(shape, pose) == 0
    (bullet,) = collider.collide(centres)
    assert len(closed["particle"]) == world.body_contact_count(box, hand)
    np.testing.assert_array_equal(np.sort(closed["particle"]), np.sort(bullet["particle"]))
    order_c, order_b = np.argsort(closed["particle"]), np.argsort(bullet["particle"])
    np.testing.assert_allclose(closed["depth"][order_c], bullet["depth"][order_b], atol=1e-6)
    np.testing.assert_allclose(closed["normal"][order_c], bullet["normal"][order_b], atol=1e-6)
    # The closed form, analytically: depth = radius - signed distance, normal +Y on the top face.
    np.testing.assert_allclose(closed["depth"], radius - box_signed_distance(centres[closed["particle"]]), atol=1e-12)
    top = centres[closed["particle"], 1] > 0
    np.testing.assert_allclose(closed["normal"][top], [[0, 1, 0]] * top.sum(), atol=1e-12)
    with pytest.raises(ValueError, match=r"^centres: expected shape \(N, 3\), got \(3,\)$"):
        handsim.collide_particles([0, 0, 0], radius, shape, pose)
    with pytest.raises(handsim.InvalidArgumentError, match="^radius: "):
        handsim.collide_particles(centres, -1, shape, pose)


# --- the world: hands, steps, events --------------------------------------------------------------------

def test_world_hand_ids_and_errors():
    world = handsim.World()
    a = world.add_hand(handsim.HandDef(render_vertices=2000))
    b = world.add_hand(handsim.HandDef(handedness=LEFT, render_vertices=2000))
    assert world.hands() == [a, b] and world.contains(a) and isinstance(a, handsim.HandId)
    view = world.hand_model(a)
    assert view.handedness == RIGHT
    world.remove_hand(a)
    assert world.hands() == [b] and not world.contains(a)
    with pytest.raises(handsim.StaleIdError, match="^hand: "):
        world.hand_tracked(a)
    with pytest.raises(handsim.StaleIdError, match="^hand: "):
        view.vertex_count
    with pytest.raises(TypeError, match="^hand: expected a HandId, got BodyId$"):
        world.hand_model(world.add_body(handsim.BodyDef(shape=handsim.Shape.sphere(0.1))))
    with pytest.raises(handsim.InvalidArgumentError, match="^mesh: mesh and bind go together"):
        world.add_hand(handsim.HandDef(), bind=handsim.bind_frame(RIGHT))
    with pytest.raises(TypeError, match="^definition: expected a HandDef, got NoneType$"):
        world.add_hand(None)


def test_rejected_step_leaves_the_world_unchanged():
    world = handsim.World()
    hand = world.add_hand(handsim.HandDef(render_vertices=2000))
    world.add_body(handsim.BodyDef(shape=handsim.Shape.box([0.05] * 3), mass=1, pose=[0, 0.5, 0, 0, 0, 0, 1]))
    right = handsim.make_hand_frame(RIGHT, [0, 0.3, 0.3, 0, 0, 0, 1])
    for _ in range(10):
        world.step(DT, {hand: right})
    before, time, particles = world.state_hash(), world.time, world.hand_particles(hand)
    bad_calls = [
        (handsim.InvalidArgumentError, "^dt: ", lambda: world.step(0.0, {hand: right})),
        (handsim.InvalidArgumentError, "^dt: ", lambda: world.step(math.nan, {hand: right})),
        (TypeError, r"^hands: expected a dict \{HandId: HandFrame\}, got HandFrame$", lambda: world.step(DT, right)),
        (handsim.InvalidArgumentError, r"^hands\[HandId\(index=0, generation=\d+\)\]\.handedness: ",
         lambda: world.step(DT, {hand: handsim.bind_frame(LEFT)})),
        (TypeError, r"^hands\[HandId\(index=0, generation=\d+\)\]: expected a HandFrame, got ndarray$",
         lambda: world.step(DT, {hand: right.positions})),
    ]
    for error, message, call in bad_calls:
        with pytest.raises(error, match=message):
            call()
        assert world.state_hash() == before and world.time == time
        np.testing.assert_array_equal(world.hand_particles(hand), particles)


def test_grasp_events_and_stage_reports():
    """A thin plate slicing through the flat fingers is touched from both faces: an opposing grasp (eq. 3). The
    hand does not close, so this is eq. 3 without the closing rule (which would rightly refuse it)."""
    wd = handsim.WorldDef(ground=False, gravity=[0, 0, 0])
    g = wd.grasp
    g.closing_distance = g.opening_distance = 0.0
    wd.grasp = g
    world = handsim.World(wd)
    hand = world.add_hand(handsim.HandDef())
    plate = world.add_body(handsim.BodyDef(shape=handsim.Shape.box([0.05, 0.001, 0.02]), mass=0.1,
                                           pose=[0, 0.5, -0.08, 0, 0, 0, 1]))
    palm = np.array([0, 0.5, 0, 0, 0, 0, 1.0])
    frames_to_grasp = math.ceil(world.definition.grasp.grasp_time_s / DT - 1e-9)  # grasp_time_s at 60 Hz
    types = []
    for _ in range(frames_to_grasp):
        world.step(DT, {hand: handsim.make_hand_frame(RIGHT, palm)})
        types += [e.type for e in world.events()]
    assert types == [handsim.EventType.CONTACT_BEGIN, handsim.EventType.GRASP_BEGIN]
    grasp = world.body_grasp(plate)
    assert grasp.grasped and grasp.primary == hand and grasp.secondary is None
    assert world.body_motion(plate) == handsim.BodyMotion.KINEMATIC

    # Held: the plate keeps its pose in the palm frame exactly while the hand rises and turns.
    relative = grasp.primary_relative
    for i in range(10):
        palm[1] += 0.001
        palm[3:] = unit_quat(0, math.sin(0.005 * i), 0, math.cos(0.005 * i))
        world.step(DT, {hand: handsim.make_hand_frame(RIGHT, palm)})
        R = quat_matrix(palm[3:])
        assert np.abs(world.body_pose(plate)[:3] - (R @ relative[:3] + palm[:3])).max() <= 1e-9
    assert world.body_grasp(plate).grasped

    report = world.last_step()
    names = [r.name for r in report.stages]
    assert names == ["skinning", "contacts", "deformation", "grasp", "attach", "pose_fit", "dynamics", "joints", "slip"]
    assert [r.stage for r in report.stages] == list(handsim.Stage.__members__.values())
    reports = {r.name: r for r in report.stages}
    assert reports["skinning"].ran and reports["attach"].ran and reports["skinning"].seconds > 0
    assert reports["attach"].work == 1  # the plate follows the hand
    assert not reports["joints"].ran and reports["joints"].skip == handsim.SkipReason.NO_JOINTS
    assert "attach" in world.stage_summary() and "skip: no joints" in world.stage_summary()

    # Tracking lost beyond the grace time (0.2 s): the grasp ends, naming the reason.
    ended = []
    for _ in range(20):
        world.step(DT)
        ended += [e for e in world.events() if e.type == handsim.EventType.GRASP_END]
    assert [(e.hand, e.body, e.reason) for e in ended] == [(hand, plate, handsim.EventReason.TRACKING_LOST)]
    assert not world.hand_tracked(hand) and not world.body_grasp(plate).grasped


def test_grasp_settings_and_particle_contacts_on_the_world_def():
    assert handsim.OPPOSING_COS == -0.7 and handsim.PAPER_LITERAL_COS == 0.7
    d = handsim.WorldDef(grasp=handsim.GraspSettings(cos_threshold=handsim.PAPER_LITERAL_COS, grasp_time_s=0.05),
                         particle_contacts=handsim.ParticleContacts.BULLET_OBJECTS)
    d.grasp.release_time_s = 0.08
    d.grasp.closing_distance = 0.02
    d.grasp.opening_distance = 0.03
    assert d.grasp.across_parts  # docs/grasp.md: one rigid part of the hand does not grasp
    d.grasp.across_parts = False
    world = handsim.World(d)
    g = world.definition.grasp
    assert g.cos_threshold == 0.7 and g.grasp_time_s == 0.05 and g.release_time_s == 0.08
    assert g.closing_distance == 0.02 and g.opening_distance == 0.03 and not g.across_parts
    assert world.definition.particle_contacts == handsim.ParticleContacts.BULLET_OBJECTS
    with pytest.raises(TypeError, match="unexpected keyword argument 'threshold'"):
        handsim.GraspSettings(threshold=1)


def test_grasp_rules_to_compare_with():
    """GraspSettings.contacts() is the default without the hand's closing and opening; paper() is it with eq. 3
    as printed (docs/grasp.md)."""
    fields = [f for f in dir(handsim.GraspSettings()) if not f.startswith("_") and f not in ("contacts", "paper")]
    d, c, p = handsim.GraspSettings(), handsim.GraspSettings.contacts(), handsim.GraspSettings.paper()
    assert c.closing_distance == 0 and c.opening_distance == 0
    assert [f for f in fields if getattr(c, f) != getattr(d, f)] == ["closing_distance", "opening_distance"]
    assert sorted(f for f in fields if getattr(p, f) != getattr(c, f)) == [
        "across_parts", "cos_threshold", "grasp_time_s", "release_time_s"]
    assert p.cos_threshold == handsim.PAPER_LITERAL_COS and not p.across_parts
    assert p.grasp_time_s == 0 and p.release_time_s == 0


# --- glTF hands -----------------------------------------------------------------------------------------

def hands_dir():
    candidates = []
    if os.environ.get("HANDSIM_SHARED_ASSETS"):
        candidates.append(Path(os.environ["HANDSIM_SHARED_ASSETS"]) / "hands")
    repo = Path(__file__).resolve().parents[2]
    candidates += [repo.parent / "shared" / "assets" / "hands", Path("/work/shared/assets/hands")]
    for c in candidates:
        if (c / "Hand_low_L.gltf").is_file() and (c / "Hand_low_R.gltf").is_file():
            return c
    return None


@pytest.fixture(scope="module")
def gltf_hands():
    pytest.importorskip("pygltflib")
    where = hands_dir()
    if where is None:
        pytest.skip("the CC0 glTF hands are not there (set HANDSIM_SHARED_ASSETS)")
    from handsim.gltf import load_gltf_hand
    return where, {side: load_gltf_hand(where / f"Hand_low_{side}.gltf") for side in "LR"}


def test_gltf_hand_loads_onto_the_openxr_joints(gltf_hands):
    _, hands = gltf_hands
    for side, handedness in (("L", LEFT), ("R", RIGHT)):
        mesh, bind = hands[side]
        assert bind.handedness == handedness and bind.valid.all()
        assert (mesh.vertex_count, mesh.triangle_count) == (603, 938)
        np.testing.assert_allclose(mesh.weights.sum(axis=1), 1, atol=1e-12)
        used = np.unique(mesh.bones[mesh.weights > 0])
        tips = [handsim.THUMB_TIP, handsim.INDEX_TIP, handsim.MIDDLE_TIP, handsim.RING_TIP, handsim.LITTLE_TIP]
        assert len(used) == 20 and not np.isin(used, tips + [handsim.PALM]).any()  # README: 20 weighted joints
        # README: Wrist (0, 0, 0.027) and Index_Tip (-0.007, 0.043, -0.170) in the left file.
        mirror = 1 if side == "L" else -1
        np.testing.assert_allclose(bind.positions[handsim.WRIST], [0, 0, 0.027], atol=6e-4)
        np.testing.assert_allclose(bind.positions[handsim.INDEX_TIP], [mirror * -0.007, 0.043, -0.170], atol=6e-4)
        # OpenXR convention: -Z of every bone joint points at the next joint.
        for first, tip in [(2, 5), (6, 10), (11, 15), (16, 20), (21, 25)]:
            for j in range(first, tip):
                bone = bind.positions[j + 1] - bind.positions[j]
                minus_z = -quat_matrix(bind.orientations[j])[:, 2]
                assert minus_z @ bone / np.linalg.norm(bone) > 1 - 1e-12
        # In the palm frame: fingers along -Z, thumb on -X for a right hand (+X left), fingertips curl to -Y.
        R = quat_matrix(bind.palm_pose[3:])
        local = (bind.positions - bind.palm_pose[:3]) @ R
        assert (local[[10, 15, 20, 25], 2] < -0.08).all()
        assert np.sign(local[handsim.THUMB_TIP, 0]) == (-1 if handedness == RIGHT else 1)
        assert (local[[10, 15, 20, 25], 1] < 0).all()
        # Within a few cm of the synthetic hand (a different, relaxed hand), and turned the same way: joint
        # frames within 50 degrees (measured up to 45, the relaxed curl of the distal joints), the thumb's
        # within 20 (measured 17).
        synthetic = handsim.bind_frame(handedness)
        assert np.linalg.norm(local - synthetic.positions, axis=1).max() < 0.05
        for j in range(26):
            A, B = R.T @ quat_matrix(bind.orientations[j]), quat_matrix(synthetic.orientations[j])
            angle = math.degrees(math.acos(np.clip((np.trace(A.T @ B) - 1) / 2, -1, 1)))
            assert angle < (20 if handsim.THUMB_METACARPAL <= j <= handsim.THUMB_TIP else 50), j
    # The two files mirror each other across X; so do the bind frames (quaternion x, -y, -z, w). The right
    # mesh sits 0.59 mm off the exact mirror of the left one along x (measured; the skeletons mirror exactly).
    (mesh_l, bind_l), (mesh_r, bind_r) = hands["L"], hands["R"]
    np.testing.assert_allclose(bind_r.positions, bind_l.positions * [-1, 1, 1], atol=1e-6)
    np.testing.assert_allclose(bind_r.orientations, bind_l.orientations * [1, -1, -1, 1], atol=1e-5)
    mirrored = mesh_l.positions * [-1, 1, 1]
    nearest = np.linalg.norm(mesh_r.positions[:, None] - mirrored[None], axis=2).min(axis=1)
    assert nearest.max() < 1e-3


def test_gltf_hand_skins_in_the_world(gltf_hands):
    _, hands = gltf_hands
    mesh, bind = hands["R"]
    world = handsim.World(handsim.WorldDef(ground=False))
    hand = world.add_hand(handsim.HandDef(handedness=RIGHT), mesh, bind)
    model = world.hand_model(hand)
    assert model.vertex_count == 603 and model.particle_count == 603  # 1,182 clamped to the vertex count
    world.step(DT, {hand: bind})
    np.testing.assert_allclose(world.hand_render_vertices(hand), mesh.positions[model.source_vertex], rtol=0, atol=1e-15)
    world.step(DT, {hand: bind.transformed(MOTION)})
    expected = mesh.positions[model.source_vertex] @ quat_matrix(MOTION[3:]).T + MOTION[:3]
    assert np.abs(world.hand_render_vertices(hand) - expected).max() <= 1e-12

    # Bend the index finger 60 degrees about its proximal joint's X axis: compare with eq. 1 in numpy.
    p, q, r, v = frame_arrays(bind)
    pivot = p[handsim.INDEX_PROXIMAL].copy()
    axis = quat_matrix(q[handsim.INDEX_PROXIMAL])[:, 0]
    turn = np.array([*(math.sin(math.pi / 6) * axis), math.cos(math.pi / 6)])
    Rt = quat_matrix(turn)
    chain = list(range(handsim.INDEX_PROXIMAL, handsim.INDEX_TIP + 1))
    p[chain] = (p[chain] - pivot) @ Rt.T + pivot
    q[chain] = [quat_multiply(turn, qj) for qj in q[chain]]
    world.step(DT, {hand: handsim.HandFrame(RIGHT, p, q, r, v)})
    bones = np.zeros((26, 3, 4))
    for j in range(26):
        Rj, Rb = quat_matrix(q[j]), quat_matrix(bind.orientations[j])
        bones[j, :, :3] = Rj @ Rb.T
        bones[j, :, 3] = p[j] - Rj @ Rb.T @ bind.positions[j]
    homogeneous = np.hstack([mesh.positions, np.ones((mesh.vertex_count, 1))])
    reference = np.einsum("vk,vkij,vj->vi", mesh.weights, bones[mesh.bones], homogeneous)
    skinned = world.hand_render_vertices(hand)
    assert np.abs(skinned - reference[model.source_vertex]).max() <= 1e-12
    assert np.linalg.norm(skinned - mesh.positions[model.source_vertex], axis=1).max() > 0.02


def quat_multiply(a, b):
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return np.array([aw * bx + ax * bw + ay * bz - az * by, aw * by - ax * bz + ay * bw + az * bx,
                     aw * bz + ax * by - ay * bx + az * bw, aw * bw - ax * bx - ay * by - az * bz])


def edited_gltf(where, tmp_path, rename):
    """A copy of the left hand with some joint nodes renamed (the geometry buffer is embedded)."""
    doc = json.loads((where / "Hand_low_L.gltf").read_text())
    for node in doc["nodes"]:
        node["name"] = rename.get(node.get("name"), node.get("name"))
    out = tmp_path / "edited.gltf"
    out.write_text(json.dumps(doc))
    return out


def test_gltf_missing_joints_are_synthesized_or_reported(gltf_hands, tmp_path):
    from handsim.gltf import load_gltf_hand
    where, hands = gltf_hands
    _, bind = hands["L"]
    tips = {f"{f}_Tip_L": f"Helper{i}" for i, f in enumerate(["Thumb", "Index", "Middle", "Ring", "Little"])}
    metacarpal = {"Ring_Metacarpal_L": "Helper9"}
    mesh2, bind2 = load_gltf_hand(edited_gltf(where, tmp_path, {**tips, **metacarpal}))
    assert bind2.handedness == LEFT
    for tip in (handsim.THUMB_TIP, handsim.INDEX_TIP, handsim.MIDDLE_TIP, handsim.RING_TIP, handsim.LITTLE_TIP):
        assert np.linalg.norm(bind2.positions[tip] - bind.positions[tip]) < 0.015
    wrist, prox = bind.positions[handsim.WRIST], bind.positions[handsim.RING_PROXIMAL]
    np.testing.assert_allclose(bind2.positions[handsim.RING_METACARPAL], wrist + 0.15 * (prox - wrist), atol=1e-15)
    np.testing.assert_array_equal(mesh2.positions, hands["L"][0].positions)
    # Without side markers the geometry tells the side; joint_map names rig joints the matcher cannot read.
    unsided = {n: n[:-2] for n in ["Wrist_L"] + [f"{f}_{b}_L" for f in ["Thumb", "Index", "Middle", "Ring", "Little"]
                                                for b in ["Metacarpal", "Proximal", "Intermediate", "Distal", "Tip"]]}
    unsided["Palm_L"] = "Palm"
    assert load_gltf_hand(edited_gltf(where, tmp_path, unsided))[1].handedness == LEFT
    mapped = load_gltf_hand(edited_gltf(where, tmp_path, {"Index_Distal_L": "Bone_7"}), joint_map={"Bone_7": "index_distal"})
    np.testing.assert_array_equal(mapped[1].positions, bind.positions)
    with pytest.raises(ValueError, match="lacks the OpenXR joints index_distal, ring_intermediate"):
        load_gltf_hand(edited_gltf(where, tmp_path, {"Index_Distal_L": "Bone_7", "Ring_Intermediate_L": "Bone_8"}))
    with pytest.raises(ValueError, match=r"joint_map\['Nope'\]: 'nothing' is not an OpenXR joint"):
        load_gltf_hand(where / "Hand_low_L.gltf", joint_map={"Nope": "nothing"})
    with pytest.raises(FileNotFoundError, match="^path: no such file"):
        load_gltf_hand(tmp_path / "absent.gltf")


def test_gltf_rest_pose_is_the_skinned_bind_mesh(gltf_hands, tmp_path):
    """Bend the rig's index finger in the file (node rotation, rest pose != bind pose): the loaded mesh must be
    the original mesh skinned by the core to the loaded joint frames (eq. 1 consistent with glTF skinning)."""
    from handsim.gltf import load_gltf_hand, _Reader
    import pygltflib
    where, hands = gltf_hands
    mesh0, bind0 = hands["L"]
    doc = json.loads((where / "Hand_low_L.gltf").read_text())
    names = [n.get("name") for n in doc["nodes"]]
    node = names.index("Index_Proximal_L")
    reader = _Reader(pygltflib.GLTF2().load(str(where / "Hand_low_L.gltf")))
    parent = reader.global_transform(reader.parent[node])[:3, :3]
    own = reader.global_transform(node)[:3, :3]
    palm_x = quat_matrix(bind0.palm_pose[3:])[:, 0]
    turn = quat_matrix([*(math.sin(0.4) * palm_x), math.cos(0.4)])  # 46 degrees of flexion about the palm's X
    local = parent.T @ turn @ own
    w = math.sqrt(max(0.0, 1 + np.trace(local))) / 2
    doc["nodes"][node]["rotation"] = [(local[2, 1] - local[1, 2]) / (4 * w), (local[0, 2] - local[2, 0]) / (4 * w),
                                      (local[1, 0] - local[0, 1]) / (4 * w), w]
    path = tmp_path / "bent.gltf"
    path.write_text(json.dumps(doc))
    mesh1, bind1 = load_gltf_hand(path)
    moved = np.linalg.norm(bind1.positions - bind0.positions, axis=1)
    assert moved[handsim.INDEX_TIP] > 0.05 and moved[handsim.MIDDLE_TIP] == 0
    world = handsim.World(handsim.WorldDef(ground=False))
    hand = world.add_hand(handsim.HandDef(handedness=LEFT), mesh0, bind0)
    world.step(DT, {hand: bind1})
    model = world.hand_model(hand)
    # Not exact: the file's node transforms match its inverse bind matrices only to float32 precision
    # (measured 4e-9 m here).
    assert np.abs(world.hand_render_vertices(hand) - mesh1.positions[model.source_vertex]).max() < 1e-7


def test_gltf_binary_container_loads_the_same_hand(gltf_hands, tmp_path):
    import pygltflib
    from handsim.gltf import load_gltf_hand
    where, hands = gltf_hands
    doc = pygltflib.GLTF2().load(str(where / "Hand_low_R.gltf"))
    doc.convert_buffers(pygltflib.BufferFormat.BINARYBLOB)
    doc.save_binary(str(tmp_path / "hand.glb"))
    mesh, bind = load_gltf_hand(tmp_path / "hand.glb")
    np.testing.assert_array_equal(mesh.positions, hands["R"][0].positions)
    np.testing.assert_array_equal(mesh.triangles, hands["R"][0].triangles)
    np.testing.assert_array_equal(bind.orientations, hands["R"][1].orientations)


def test_openxr_joint_names():
    from handsim.gltf import openxr_joint
    assert openxr_joint("Index_Proximal_L") == (handsim.INDEX_PROXIMAL, LEFT)
    assert openxr_joint("XR_HAND_JOINT_LITTLE_TIP_EXT") == (handsim.LITTLE_TIP, None)
    assert openxr_joint("RightPinkyDistal") == (handsim.LITTLE_DISTAL, RIGHT)
    assert openxr_joint("hand.thumb.metacarpal.r") == (handsim.THUMB_METACARPAL, RIGHT)
    assert openxr_joint("Armature") == (None, None)


def test_gltf_needs_pygltflib_only_when_loading(monkeypatch, tmp_path):
    from handsim import gltf
    monkeypatch.setitem(sys.modules, "pygltflib", None)  # import pygltflib now raises ImportError
    path = tmp_path / "hand.gltf"
    path.write_text("{}")
    with pytest.raises(ImportError, match=r"needs pygltflib.*pip install 'handsim\[gltf\]'"):
        gltf.load_gltf_hand(path)


def test_hand_bench_times_the_model_build_of_the_default_and_the_study_pick():
    from handsim.bench import hand as hand_bench
    rows = hand_bench.bench_model_build(1)
    assert [r["hand"] for r in rows] == ["default (HandDef())", "3,000 even"]
    assert all(0 < r["median_s"] <= r["p99_s"] for r in rows)


def _numpy_pulp_gap(p, r, a0, a1, b0, b1):
    """The pads' gap as skeleton.pulp_gap computed it in numpy before it called the core (the reference): the
    segments' closest points (s from the lines, t for that s, s again for that t, each clamped) less the radii."""
    u, v, w = p[a1] - p[a0], p[b1] - p[b0], p[a0] - p[b0]
    uu, vv, uv, uw, vw = u @ u, v @ v, u @ v, u @ w, v @ w
    den = uu * vv - uv * uv
    s = float(np.clip((uv * vw - vv * uw) / den, 0, 1)) if den > 1e-18 else 0.0
    t = float(np.clip((uv * s + vw) / vv, 0, 1)) if vv > 1e-18 else 0.0
    s = float(np.clip((uv * t - uw) / uu, 0, 1)) if uu > 1e-18 else 0.0
    gap = np.linalg.norm(w + s * u - t * v)
    return gap - (r[a0] + s * (r[a1] - r[a0])) - (r[b0] + t * (r[b1] - r[b0]))


def test_pulp_gap_is_the_cores_capsule_gap_on_synthetic_hands():
    """skeleton.pulp_gap (the core's capsule_gap, which the grip span uses) equals the numpy formula it replaced on
    make_hand_frame hands: flat, pinching, curled, spread, scaled, turned, both sides, every finger."""
    from handsim.adapters import skeleton as sk
    rng = np.random.default_rng(3)
    fingers = [(handsim.INDEX_DISTAL, handsim.INDEX_TIP), (handsim.MIDDLE_DISTAL, handsim.MIDDLE_TIP),
               (handsim.RING_DISTAL, handsim.RING_TIP), (handsim.LITTLE_DISTAL, handsim.LITTLE_TIP)]
    checked = 0
    for side in (RIGHT, LEFT):
        for k in range(25):
            q = rng.normal(size=4)
            pose = np.concatenate([rng.uniform(-0.5, 0.5, 3), q / np.linalg.norm(q)])
            f = handsim.make_hand_frame(side, pose, curl=rng.uniform(0, 1, 5), thumb_opposition=rng.uniform(0, 1),
                                        spread=rng.uniform(-0.3, 1), scale=rng.uniform(0.8, 1.2))
            p, r = np.asarray(f.positions), np.asarray(f.radii)
            for finger, (b0, b1) in enumerate(fingers):
                want = _numpy_pulp_gap(p, r, handsim.THUMB_DISTAL, handsim.THUMB_TIP, b0, b1)
                assert sk.pulp_gap(p, r, finger) == pytest.approx(want, abs=1e-12)
                checked += 1
    assert checked == 200
    flat = handsim.make_hand_frame(RIGHT)
    # The flat hand's thumb-index pad gap, skeleton.py's anchor of pinch 0 (56.8 mm).
    assert sk.pulp_gap(np.asarray(flat.positions), np.asarray(flat.radii), 0) == pytest.approx(0.05675, abs=1e-5)
