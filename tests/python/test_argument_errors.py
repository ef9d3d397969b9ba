"""Issue 22 item 7: pybind11's generic "incompatible function arguments" never reaches the user.

A walk, like the table walks: every function, method, static method, constructor and field setter of
handsim._core (and its submodules) gets, in each typed parameter in turn, values of the wrong type (a string,
None, a complex number, a list, a float where an integer or object is expected, a bare object), with values
of the right type in every other parameter. Whatever the call does, no message may be pybind11's generic one;
where the parameter's type refuses the value, the call must raise TypeError naming the parameter (the field,
for a setter). Parameters typed ``object`` are converted by the bindings' own named converters (convert.h)
and the core's checks; their messages are covered by test_bad_input.py.
"""
import re

import numpy as np
import pytest

import handsim
from handsim import _core, argument_errors
from handsim.argument_errors import accepts, parameters

BAD_VALUES = ["x", None, 1j, [1, 2], 1.5, object(), np.zeros(2), np.float64(2.5)]
GENERIC = argument_errors.GENERIC + (argument_errors.UNMATCHED,)


def _instances():
    """One instance of every class of the module that has no default constructor, made the ordinary way (the
    walk needs a `self` and values for class-typed parameters)."""
    world = _core.World()
    box = _core.build_jewelry_box(world)
    hand = world.add_hand(_core.HandDef(particle_count=50))
    events = []
    for frame in range(60):
        world.step(1 / 60, {hand: _core.scenario_frames(box, world, frame)[0]})  # the right hand's frame
        events += world.events()
    bind = _core.bind_frame(_core.Handedness.RIGHT)
    hinge = _core.solvers.make_hinge_frame(_core.HingeDef(lower=-1.0, upper=1.0))
    vertices = _core.solvers.make_joint_vertices(np.eye(3), about=np.zeros(3))
    identity = np.array([0, 0, 0, 0, 0, 0, 1.0])
    return {
        "World": world, "JewelryBox": box, "HandId": hand, "BodyId": box.lid, "JointId": box.hinge,
        "HandFrame": bind, "HandModel": _core.HandModel(_core.HandDef(particle_count=50)),
        "SkinnedMesh": _core.make_hand_mesh(bind, 400), "BulletParticleCollider": _core.BulletParticleCollider(4, 0.01),
        "Event": events[0], "GraspInfo": world.body_grasp(box.lid), "StageReport": world.last_step().stages[0], "StepReport": world.last_step(),
        "Glove": _core.Glove(_core.Handedness.RIGHT),
        "JointState": world.joint_state(box.hinge), "HingeFrame": hinge, "JointVertices": vertices,
        "JointSolveResult": _core.solvers.solve_hinge(_core.JointSolver.EXACT, hinge, vertices, identity, identity, 0.0),
    }


@pytest.fixture(scope="module")
def instances():
    return _instances()


def _good(kind, instances):
    """A value of the right type for a parameter type."""
    kind = kind.removesuffix(", /").strip()
    if kind.endswith(" | None") or kind in ("object", ""):
        return None
    if kind == argument_errors._NUMBER:
        return 0.5
    if kind == argument_errors._INTEGER:
        return 1
    if kind == "bool":
        return True
    if kind == "tuple":
        return ()
    if kind.startswith("collections.abc.Sequence["):
        return [0, 1, 2]
    name = kind.rsplit(".", 1)[-1]
    cls = getattr(_core, name, None) or getattr(_core.solvers, name)
    if hasattr(cls, "__members__"):
        return next(iter(cls.__members__.values()))
    if name in instances:
        return instances[name]
    return cls()


def callables():
    """(where, how, owner, name, overloads) of every wrapped callable; how: function, method, static, init,
    field."""
    out = []
    for module in (_core, _core.solvers):
        for name, obj in vars(module).items():
            if callable(obj) and hasattr(obj, "__wrapped_core__"):
                out.append((name, "function", module, name, parameters(obj.__wrapped_core__.__doc__)))
            elif isinstance(obj, type) and obj.__module__ == module.__name__:
                for attr_name, attr in vars(obj).items():
                    where = f"{name}.{attr_name}"
                    if isinstance(attr, property) and attr.fset is not None:
                        out.append((where, "field", obj, attr_name, parameters(attr.fset.__wrapped_core__.__doc__)))
                    elif isinstance(attr, staticmethod) and hasattr(attr.__func__, "__wrapped_core__"):
                        out.append((where, "static", obj, attr_name, parameters(attr.__func__.__wrapped_core__.__doc__)))
                    elif hasattr(attr, "__wrapped_core__"):
                        out.append((where, "init" if attr_name == "__init__" else "method", obj, attr_name,
                                    parameters(attr.__wrapped_core__.__doc__)))
    return out


def test_every_pybind11_callable_is_wrapped():
    """No function, method or setter of the module is left with pybind11's generic message."""
    unwrapped = []
    for module in (_core, _core.solvers):
        for name, obj in vars(module).items():
            if type(obj).__name__ == "builtin_function_or_method":
                unwrapped.append(name)
            elif isinstance(obj, type) and obj.__module__ == module.__name__:
                for attr_name, attr in vars(obj).items():
                    fn = attr.fset if isinstance(attr, property) else getattr(attr, "__func__", attr)
                    if type(fn).__name__ in ("builtin_function_or_method", "instancemethod") and \
                            not attr_name.startswith("_pybind11"):
                        unwrapped.append(f"{name}.{attr_name}")
    assert unwrapped == []
    assert len(callables()) > 250


def test_every_parameter_has_a_name():
    """pybind11 calls an unnamed parameter arg0; a message naming it would name nothing the caller wrote
    (a setter's value is named by its field, a dunder's by Python)."""
    unnamed = [where for where, how, _, name, overloads in callables() if how != "field" and not name.startswith("__")
               for params in overloads for p in params if re.fullmatch(r"arg\d+", p[0])]
    assert unnamed == []


def _call(how, owner, name, params, values, instances):
    if how == "field":
        return setattr(values[0], name, values[1])
    positional = [v for p, v in zip(params, values) if not p[3]]
    keywords = {p[0]: v for p, v in zip(params, values) if p[3]}
    if how == "function":
        return getattr(owner, name)(*positional, **keywords)
    if how == "static":
        return getattr(owner, name)(*positional, **keywords)
    if how == "init":
        return owner(*positional[1:], **keywords)
    if name == "__setstate__":  # unpickling calls it on a fresh, uninitialised instance (else it is a no-op)
        positional[0] = owner.__new__(owner)
    return getattr(positional[0], name)(*positional[1:], **keywords)


CASES = [(where, how, owner, name, k, i) for where, how, owner, name, overloads in callables()
         for k, params in enumerate(overloads) for i, p in enumerate(params)
         if p[1].removesuffix(", /").strip() not in ("object", "") and not (i == 0 and how in ("field", "method", "init"))
         and len(overloads) == 1]


@pytest.mark.parametrize("where,how,owner,name,k,i", CASES, ids=[f"{c[0]}:{c[5]}" for c in CASES])
def test_a_wrong_type_names_the_argument(where, how, owner, name, k, i, instances):
    params = dict((w, o) for w, _, _, _, o in callables())[where][k]
    label = where if how == "field" else params[i][0]
    for bad in BAD_VALUES:
        values = [_good(p[1], instances) for p in params]
        values[i] = bad
        try:
            _call(how, owner, name, params, values, instances)
        except Exception as e:  # noqa: BLE001 (any outcome but pybind11's generic message is fine here)
            assert not any(g in str(e) for g in GENERIC), f"{where}({label}={bad!r}): {e}"
            if not accepts(params[i][1], bad, _core):
                assert isinstance(e, TypeError) and label in str(e), f"{where}({label}={bad!r}): {e}"
            continue
        assert accepts(params[i][1], bad, _core), f"{where}({label}={bad!r}) was taken"


def test_the_issue_cases():
    """The cases issue 22 names: a wrong type to step's dt, a float into an int field."""
    world = handsim.World()
    with pytest.raises(TypeError, match=r"World.step\(\) argument 'dt': expected a number, got str"):
        world.step("0.016")
    with pytest.raises(TypeError, match=r"World.step\(\) missing argument 'dt'"):
        world.step()
    with pytest.raises(TypeError, match=r"HandDef.particle_count: expected an integer, got float 1.5"):
        handsim.HandDef().particle_count = 1.5
    with pytest.raises(TypeError, match=r"HandDef.particle_count: expected an integer, got float"):
        handsim.HandDef(particle_count=1.5)
    with pytest.raises(TypeError, match=r"BodyDef.mass: expected a number, got complex"):
        handsim.BodyDef().mass = 1j
    with pytest.raises(TypeError, match=r"World.step\(\) got an unexpected keyword argument 'delta'"):
        world.step(delta=0.1)
    assert world.state_hash() == handsim.World().state_hash()
