"""One table per enum and per def (issue 21): every enum value and every mirrored field is named in Python."""
import collections

import numpy as np
import pytest

import handsim
from handsim import recording


def test_every_enum_value_of_the_core_table_is_named_in_python():
    rows = handsim.enum_values()
    by_type = collections.defaultdict(dict)
    for type_name, _cpp_name, value, upper, constant in rows:
        by_type[type_name][upper] = value
        assert constant.startswith("HANDSIM_")
    assert len(by_type) == 16
    for type_name, values in by_type.items():
        cls = getattr(handsim, type_name)
        assert {name: int(v) for name, v in cls.__members__.items()} == values, type_name
        for name, value in values.items():
            assert getattr(cls, name).name == name  # a named value, not "EventReason.???"
            assert int(cls(value)) == value


def test_hand_removed_is_named():
    assert handsim.EventReason.HAND_REMOVED.name == "HAND_REMOVED"
    assert str(handsim.EventReason(4)) == "EventReason.HAND_REMOVED"


def test_exceptions_carry_their_status():
    assert handsim.InvalidArgumentError.status == handsim.Status.INVALID_ARGUMENT
    assert handsim.StaleIdError.status == handsim.Status.STALE_ID
    assert handsim.InvalidStateError.status == handsim.Status.INVALID_STATE
    assert handsim.UnsupportedError.status == handsim.Status.UNSUPPORTED
    assert handsim.InternalError.status == handsim.Status.INTERNAL
    with pytest.raises(handsim.InvalidArgumentError) as e:
        handsim.World().step(-1)
    assert e.value.status == handsim.Status.INVALID_ARGUMENT


def _properties(cls):
    return {n for n in dir(cls) if not n.startswith("_") and isinstance(getattr(cls, n), property)}


@pytest.mark.parametrize("def_name", sorted(handsim.def_fields()))
def test_every_mirrored_field_is_a_python_property_and_nothing_else(def_name):
    fields = handsim.def_fields()[def_name]
    cls = getattr(handsim, def_name)
    assert _properties(cls) == set(fields)
    d = cls()
    for f in fields:  # each reads and takes back its own value
        setattr(d, f, getattr(d, f))


def test_world_def_round_trips_through_a_recording_header_with_every_field():
    d = handsim.WorldDef(paper_pipeline=True, render_threads=3, max_substeps=5, gravity=[0, -3, 0.5],
                         particle_contacts=handsim.ParticleContacts.BULLET_OBJECTS)
    d.grasp.grasp_time_s = 0.05
    data = recording.world_def_to_dict(d)
    assert set(data) == set(handsim.def_fields()["WorldDef"])
    assert set(data["grasp"]) == set(handsim.def_fields()["GraspSettings"])
    back = recording.world_def_from_dict(data)
    assert back.paper_pipeline and back.render_threads == 3 and back.max_substeps == 5
    assert back.particle_contacts == handsim.ParticleContacts.BULLET_OBJECTS
    assert back.grasp.grasp_time_s == 0.05
    np.testing.assert_array_equal(back.gravity, [0, -3, 0.5])
    with pytest.raises(recording.RecordingError, match=r"header.world.grasp.colour: unknown field"):
        recording.world_def_from_dict({"grasp": {"colour": 1}})
    with pytest.raises(recording.RecordingError, match=r"header.world.particle_contacts: 'FAST' is not a"):
        recording.world_def_from_dict({"particle_contacts": "FAST"})


def test_hand_def_round_trips_through_a_recording_header():
    h = handsim.HandDef(handedness=handsim.Handedness.LEFT, sampling=handsim.ParticleSampling.EVEN, seed=7)
    back = recording.hand_def_from_dict(recording.hand_def_to_dict(h))
    assert (back.handedness, back.sampling, back.seed) == (handsim.Handedness.LEFT, handsim.ParticleSampling.EVEN, 7)
