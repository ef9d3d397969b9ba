"""save_state() / restore_state() from Python: a world restored from the bytes continues with the same
state_hash() every frame for 1,000 frames (jointed lid held by one hand, the other hand on the base, free
bodies under Bullet); bad bytes raise handsim.Error naming 'state' and leave the world as it was."""
import pytest

import handsim

SAVE_AT = 300  # the lid is held, half way through its first swing
FRAMES = 1000


def build():
    """The determinism scenario's box and two hands, and free bodies Bullet moves beside it."""
    world = handsim.World()
    box = handsim.build_jewelry_box(world)
    world.add_hand(handsim.HandDef())
    world.add_hand(handsim.HandDef(handedness=handsim.Handedness.LEFT))
    top = box.definition.position
    for offset, velocity in (((0.25, 0.03, 0.0), (0, 0, 0)), ((0.25, 0.09, 0.0), (0, 0, 0)),
                             ((-0.3, 0.3, 0.1), (0.3, 0.0, -0.1))):
        world.add_body(handsim.BodyDef(shape=handsim.Shape.box([0.03] * 3), mass=0.2,
                                       pose=[*(top + offset), 0, 0, 0, 1], linear_velocity=velocity))
    return world, box


def run(world, box, start, count):
    hashes = []
    for i in range(start, start + count):
        world.step(1 / 60, dict(zip(world.hands(), handsim.scenario_frames(box, world, i))))  # no hand removed: hands() is right, left
        hashes.append(world.state_hash())
    return hashes


@pytest.fixture(scope="module")
def saved():
    world, box = build()
    run(world, box, 0, SAVE_AT)
    assert world.body_grasp(box.lid).grasped
    before = world.state_hash()
    state = world.save_state()
    assert isinstance(state, bytes) and world.state_hash() == before
    return state, before, run(world, box, SAVE_AT, FRAMES)


def test_restored_world_continues_bit_identically(saved):
    state, before, expected = saved
    world, box = build()
    run(world, box, 0, 30)  # another past
    world.restore_state(bytearray(state))
    assert world.state_hash() == before and world.events() == []
    got = run(world, box, SAVE_AT, FRAMES)
    first = next((i for i, (a, b) in enumerate(zip(expected, got)) if a != b), None)
    assert first is None, f"the restored world diverged {first} frames after the restore"


@pytest.mark.parametrize("name, change, words", [
    ("truncated", lambda b: b[:-1], "is truncated"),
    ("header only", lambda b: b[:30], "shorter than"),
    ("another version", lambda b: b[:8] + bytes([9]) + b[9:], "format version 9"),
    ("a flipped bit", lambda b: b[:len(b) // 2] + bytes([b[len(b) // 2] ^ 4]) + b[len(b) // 2 + 1:], "corrupt"),
])
def test_bad_bytes_are_refused_naming_state(saved, name, change, words):
    world, box = build()
    run(world, box, 0, 5)
    before, time = world.state_hash(), world.time
    with pytest.raises(handsim.Error, match=f"^state: .*{words}") as error:
        world.restore_state(change(saved[0]))
    assert error.value.status == handsim.Status.INVALID_ARGUMENT
    assert world.state_hash() == before and world.time == time, name


def test_a_world_built_otherwise_is_refused(saved):
    world, _ = build()
    world.add_body(handsim.BodyDef())
    before = world.state_hash()
    with pytest.raises(handsim.Error, match="^state: was saved from a world with other"):
        world.restore_state(saved[0])
    assert world.state_hash() == before
    with pytest.raises(TypeError, match="^state: expected bytes"):
        world.restore_state("not bytes")
