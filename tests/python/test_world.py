"""The foundation through the bindings: analytic answers, determinism, bad input."""
import math

import numpy as np
import pytest

import handsim


def box_def(y=0.5, half=0.05, mass=1.0, **kw):
    return handsim.BodyDef(shape=handsim.Shape.box([half] * 3), mass=mass, pose=[0, y, 0, 0, 0, 0, 1], **kw)


def test_version_is_defined_once():
    import re
    from pathlib import Path
    cmake = (Path(__file__).parents[2] / "CMakeLists.txt").read_text()
    assert re.search(r"project\(handsim VERSION ([0-9.]+)", cmake).group(1) == handsim.__version__


def test_box_rests_at_half_height():
    world = handsim.World()
    box = world.add_body(box_def(mass=0.2))
    for _ in range(180):
        world.step(1 / 60)
    for _ in range(600):
        world.step(1 / 60)
        assert world.body_pose(box)[1] == pytest.approx(0.05, abs=1e-3)


def test_free_fall_matches_half_g_t_squared():
    world = handsim.World(handsim.WorldDef(ground=False))
    body = world.add_body(box_def(y=10.0))
    h, n = world.definition.fixed_substep, 240
    for _ in range(n // 4):
        world.step(4 * h)
    t = n * h
    drop = 10.0 - world.body_pose(body)[1]
    assert drop == pytest.approx(9.81 * h * h * n * (n + 1) / 2, abs=1e-9)  # semi-implicit Euler
    assert abs(drop - 0.5 * 9.81 * t * t) <= 0.5 * 9.81 * h * t + 1e-9


def test_numpy_in_and_out():
    world = handsim.World()
    box = world.add_body(box_def())
    pose = world.body_pose(box)
    assert pose.shape == (7,) and pose.dtype == np.float64
    world.set_body_pose(box, np.array([1.0, 2.0, 3.0, 0, 0, math.sin(0.5), math.cos(0.5)]))
    np.testing.assert_allclose(world.body_pose(box)[:3], [1, 2, 3])
    world.set_body_velocity(box, [1, 0, 0], (0, 2, 0))
    lin, ang = world.body_velocity(box)
    np.testing.assert_array_equal(lin, [1, 0, 0])
    np.testing.assert_array_equal(ang, [0, 2, 0])


def test_determinism_across_worlds():
    def run(x0):
        world = handsim.World()
        for i in range(4):
            world.add_body(handsim.BodyDef(shape=handsim.Shape.box([0.05] * 3), mass=1.0,
                                           pose=[x0 + 0.01 * i, 0.2 + 0.12 * i, 0, 0, 0, 0, 1]))
        for _ in range(1000):
            world.step(1 / 60)
        return world.state_hash()
    assert run(0.0) == run(0.0)
    assert run(0.0) != run(1e-6)


def test_stale_and_foreign_ids():
    world, other = handsim.World(), handsim.World()
    a = world.add_body(box_def())
    world.remove_body(a)
    b = world.add_body(box_def())
    assert a.index == b.index and a != b
    assert not world.contains(a) and world.contains(b)
    with pytest.raises(handsim.StaleIdError, match="^body: "):
        world.body_pose(a)
    foreign = other.add_body(box_def())
    with pytest.raises(handsim.StaleIdError):
        world.body_pose(foreign)
    assert handsim.BodyId.unpack(b.packed) == b


NAN = float("nan")


def bad_input_cases(world, box, removed):
    """(name, call, exception type, argument named at the start of the message)."""
    def add(**kw):
        return lambda: world.add_body(handsim.BodyDef(**{"shape": handsim.Shape.box([0.05] * 3), **kw}))
    return [
        ("dt zero", lambda: world.step(0.0), handsim.InvalidArgumentError, "dt"),
        ("dt negative", lambda: world.step(-0.1), ValueError, "dt"),
        ("dt nan", lambda: world.step(NAN), ValueError, "dt"),
        ("dt string", lambda: world.step("x"), TypeError, None),
        ("negative size", add(shape=handsim.Shape.box([-1, 1, 1])), ValueError, "body.shape.half_extents"),
        ("size wrong shape", lambda: handsim.Shape.box([1, 1]), ValueError, "half_extents"),
        ("zero radius", add(shape=handsim.Shape.sphere(0.0)), ValueError, "body.shape.radius"),
        ("negative mass", add(mass=-1.0), ValueError, "body.mass"),
        ("nan mass", add(mass=NAN), ValueError, "body.mass"),
        ("pose wrong shape", lambda: handsim.BodyDef(pose=[0, 0, 0]), ValueError, "body.pose"),
        ("pose nan", add(pose=[NAN, 0, 0, 0, 0, 0, 1]), ValueError, "body.pose.position"),
        ("pose non-unit quat", add(pose=[0, 0, 0, 0, 0, 0, 0.5]), ValueError, "body.pose.orientation"),
        ("pose zero quat", add(pose=[0, 0, 0, 0, 0, 0, 0]), ValueError, "body.pose.orientation"),
        ("velocity inf", add(linear_velocity=[0, float("inf"), 0]), ValueError, "body.linear_velocity"),
        ("unknown field", lambda: handsim.BodyDef(colour=1), TypeError, None),
        ("hull too small", add(shape=handsim.Shape.convex_hull(np.zeros((2, 3)))), ValueError, "body.shape.points"),
        ("hull wrong shape", lambda: handsim.Shape.convex_hull(np.zeros((4, 2))), ValueError, "points"),
        ("stale id pose", lambda: world.body_pose(removed), handsim.StaleIdError, "body"),
        ("stale id remove", lambda: world.remove_body(removed), handsim.StaleIdError, "body"),
        ("not an id", lambda: world.body_pose(0), TypeError, "body"),
        ("set pose wrong shape", lambda: world.set_body_pose(box, [0, 0, 0]), ValueError, "pose"),
        ("set pose nan", lambda: world.set_body_pose(box, [0, NAN, 0, 0, 0, 0, 1]), ValueError, "pose.position"),
        ("set pose bad quat", lambda: world.set_body_pose(box, [0, 0, 0, 0, 0, 0, 2]), ValueError, "pose.orientation"),
        ("set pose text", lambda: world.set_body_pose(box, "pose"), TypeError, "pose"),
        ("set velocity nan", lambda: world.set_body_velocity(box, [NAN, 0, 0], [0, 0, 0]), ValueError, "linear"),
        ("set velocity shape", lambda: world.set_body_velocity(box, [0, 0, 0], [0, 0]), ValueError, "angular"),
        ("world substep", lambda: handsim.World(handsim.WorldDef(fixed_substep=0.0)), ValueError, "world.fixed_substep"),
        ("world gravity", lambda: handsim.World(handsim.WorldDef(gravity=[0, NAN, 0])), ValueError, "world.gravity"),
    ]


def test_bad_input_table_leaves_world_intact():
    world = handsim.World()
    box = world.add_body(box_def())
    removed = world.add_body(box_def(y=2))
    world.remove_body(removed)
    for _ in range(10):
        world.step(1 / 60)
    before, n_bodies = world.state_hash(), len(world.bodies())
    for name, call, exc, argument in bad_input_cases(world, box, removed):
        with pytest.raises(exc) as info:
            call()
        if argument is not None:
            assert str(info.value).startswith(argument + ":"), f"{name}: {info.value}"
        assert world.state_hash() == before, name
        assert len(world.bodies()) == n_bodies, name


def test_errors_share_a_base_class():
    for cls in (handsim.InvalidArgumentError, handsim.StaleIdError, handsim.InvalidStateError,
                handsim.UnsupportedError, handsim.InternalError):
        assert issubclass(cls, handsim.Error)


def test_hands_are_addressed_by_id_after_a_slot_is_reused():
    """Issue 21 item 4: after remove_hand(a); add_hand(c), c takes a's slot; a frame keyed by b drives b."""
    right = handsim.Handedness.RIGHT
    world = handsim.World()
    a = world.add_hand(handsim.HandDef(handedness=right))
    b = world.add_hand(handsim.HandDef(handedness=right))
    world.remove_hand(a)
    c = world.add_hand(handsim.HandDef(handedness=right))
    assert c.index == a.index and world.hands() == [c, b]
    there = [0.3, 0.5, -0.2, 0, 0, 0, 1]
    world.step(1 / 60, {b: handsim.make_hand_frame(right, there)})
    assert world.hand_tracked(b) and not world.hand_tracked(c)   # no entry: untracked this step
    np.testing.assert_allclose(world.hand_palm_pose(b), there, atol=1e-12)
    # The stale a is refused naming it, and nothing changes.
    before = world.state_hash()
    with pytest.raises(handsim.StaleIdError, match=r"^hands\[HandId\(index=0, generation=\d+\)\]: names no live"):
        world.step(1 / 60, {b: handsim.make_hand_frame(right, there), a: handsim.make_hand_frame(right)})
    assert world.state_hash() == before and world.hand_tracked(b)


def test_step_hand_errors_name_the_key():
    right = handsim.Handedness.RIGHT
    world = handsim.World()
    hand = world.add_hand(handsim.HandDef(handedness=right))
    world.step(1 / 60, {hand: handsim.make_hand_frame(right)})
    key = rf"hands\[HandId\(index={hand.index}, generation={hand.generation}\)\]"
    left = handsim.make_hand_frame(handsim.Handedness.LEFT)
    frame = handsim.make_hand_frame(right)
    cases = [
        ({hand: left}, handsim.InvalidArgumentError, key + r"\.handedness: does not match"),
        ({hand: 3}, TypeError, key + ": expected a HandFrame, got int"),
        ({hand.packed: frame}, TypeError, r"hands: key \d+ \(int\) is not a HandId"),
        ({handsim.HandId.unpack(7): frame}, handsim.StaleIdError, r"hands\[HandId\(index=7, generation=0\)\]: is the null id"),
        (frame, TypeError, "hands: expected a dict"),
    ]
    before = world.state_hash()
    for hands, exc, message in cases:
        with pytest.raises(exc, match="^" + message):
            world.step(1 / 60, hands)
        assert world.state_hash() == before and world.hand_tracked(hand)


def test_step_list_form_is_deprecated_and_still_positional():
    right = handsim.Handedness.RIGHT
    world = handsim.World()
    hand = world.add_hand(handsim.HandDef(handedness=right))
    with pytest.warns(DeprecationWarning, match=r"pass \{hand_id: frame, \.\.\.\} instead"):
        world.step(1 / 60, [handsim.make_hand_frame(right)])
    assert world.hand_tracked(hand)
    # Its own argument errors: the items are checked one by one, and there are no more frames than hands.
    before = world.state_hash()
    frame = handsim.make_hand_frame(right)
    with pytest.warns(DeprecationWarning), pytest.raises(TypeError, match=r"^hands\[0\]: expected a HandFrame, got ndarray$"):
        world.step(1 / 60, [frame.positions])
    with pytest.warns(DeprecationWarning), pytest.raises(
            handsim.InvalidArgumentError, match="^hands: got 2 frames but the world has 1 hands$"):
        world.step(1 / 60, [frame, frame])
    assert world.state_hash() == before
