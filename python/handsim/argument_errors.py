"""Type errors that name the argument, for every function, method and field of ``handsim._core``.

pybind11 converts the typed parameters (numbers, ints, flags, bound classes and enums) before a call runs;
when one does not convert it raises its generic "incompatible function arguments. The following argument
types are supported: ..." and never says which argument was wrong. :func:`name_bad_arguments` walks the
module once at import (every function, every class's methods, static methods, constructors and property
setters, and the submodules) and wraps each so that this one message is replaced by a TypeError naming the
argument, what it takes and what it got: ``World.step() argument 'dt': expected a number, got str 'x'``,
``HandDef.particle_count: expected an integer, got float 1.5``. The wrapper reads the parameters from the
signatures pybind11 writes into each docstring and checks each value the way pybind11's converters do;
``tests/python/test_argument_errors.py`` walks every wrapped callable and field with wrong values and fails
on any message that does not name the argument. The wrapper is C (``_core._name_errors``): a call that succeeds
costs one forwarding of its arguments, and only a TypeError reaches the Python that names the argument; errors
of the core itself (``handsim.Error``) and of the bindings' own converters already name their argument and pass
through unchanged.
"""
from __future__ import annotations

import functools
import re
import sys
from typing import Callable, Dict, List, Optional, Tuple

GENERIC = ("incompatible function arguments", "incompatible constructor arguments")
_SIGNATURE = re.compile(r"^(?:\d+\. )?(\w*)\((.*)\) -> ", re.M)
_NUMBER = "typing.SupportsFloat | typing.SupportsIndex"
_INTEGER = "typing.SupportsInt | typing.SupportsIndex"


def parameters(doc: Optional[str]) -> List[List[Tuple[str, str, bool, bool]]]:
    """The overloads of a pybind11 function from its docstring: for each, [(name, type, has default,
    keyword only)]."""
    out = []
    for match in _SIGNATURE.finditer(doc or ""):
        params, keyword_only = [], False
        for part in _split(match.group(2)):
            part = part.strip()
            if part == "*":
                keyword_only = True
            if part in ("", "/", "*"):
                continue
            name, _, rest = part.partition(": ")
            kind, _, default = rest.partition(" = ")
            params.append((name, kind, bool(default), keyword_only))
        out.append(params)
    return out


def _split(text: str) -> List[str]:
    """Splits a parameter list at its top-level commas (types like list[tuple[int, int]] hold commas)."""
    parts, depth, start = [], 0, 0
    for i, ch in enumerate(text):
        depth += ch in "[(" and 1 or (-1 if ch in "])" else 0)
        if ch == "," and depth == 0:
            parts.append(text[start:i])
            start = i + 1
    parts.append(text[start:])
    return parts


def expected(kind: str) -> str:
    """What a parameter type takes, in words."""
    kind = kind.removesuffix(", /").strip()
    if kind.endswith(" | None"):
        return expected(kind[: -len(" | None")]) + " or None"
    if kind in ("object", "typing.Any", ""):
        return "a value"
    if kind == _NUMBER:
        return "a number"
    if kind == _INTEGER:
        return "an integer"
    if kind == "bool":
        return "True or False"
    if kind.startswith("collections.abc.Sequence[") or kind.startswith("list["):
        return "a sequence of " + re.sub(r"^an? ", "", expected(kind[kind.index("[") + 1:-1])) + "s"
    return "a " + kind.rsplit(".", 1)[-1]


def accepts(kind: str, value, module) -> bool:
    """Whether pybind11's converter for `kind` (a docstring type) takes `value` (implicit conversions on)."""
    kind = kind.removesuffix(", /").strip()
    if kind in ("object", "typing.Any", "") or kind.startswith("*"):
        return True
    if kind.endswith(" | None"):
        return value is None or accepts(kind[: -len(" | None")], value, module)
    cls = type(value)
    if kind == _NUMBER:  # pybind11 calls __float__ (else __index__): a 2-element array has one that raises
        return not isinstance(value, (str, bytes)) and (_converts(cls, "__float__", value) or
                                                         _converts(cls, "__index__", value))
    if kind == _INTEGER:
        return _converts(cls, "__index__", value)
    if kind == "bool":
        # with conversions pybind11 takes None and anything with __bool__ except strings; the bound flags that
        # must be exactly True/False check that themselves (convert.h to_flag)
        return value is None or _converts(cls, "__bool__", value)
    if kind == "tuple":
        return isinstance(value, tuple)
    if kind.startswith("collections.abc.Sequence[") or kind.startswith("list["):
        inner = kind[kind.index("[") + 1:-1]
        return (hasattr(cls, "__len__") and hasattr(cls, "__getitem__") and not isinstance(value, (str, bytes))
                and all(accepts(inner, v, module) for v in value))
    if kind.startswith(module.__name__ + "."):
        target = module
        for part in kind[len(module.__name__) + 1:].split("."):
            target = getattr(target, part, None)
        return not isinstance(target, type) or isinstance(value, target)
    return True  # a type this module does not use: leave the judgement to pybind11


def _converts(cls, method: str, value) -> bool:
    try:
        getattr(cls, method)(value)
        return True
    except Exception:  # noqa: BLE001 (whatever the conversion raises, pybind11 refuses the value)
        return False


def _got(value) -> str:
    text = repr(value)
    return f"{type(value).__name__} {text if len(text) <= 40 else text[:37] + '...'}"


def explain(where: str, doc: Optional[str], args, kwargs, module, field: Optional[str] = None) -> Optional[str]:
    """The message naming what pybind11 refused in `where(*args, **kwargs)`, or None if nothing is found.
    `field`: the call is a property setter (`where` is "Class.field" and its one argument the value)."""
    problems = []
    for params in parameters(doc):
        problem = _first_problem(where, params, args, kwargs, module, field)
        if problem is None:
            return None  # this overload takes them: the refusal was not about types
        problems.append(problem)
    # the overload with the most arguments matched decides (the one the caller most likely meant)
    return max(problems, key=lambda p: p[0])[1] if problems else None


def _first_problem(where, params, args, kwargs, module, field):
    positional = [p for p in params if not p[3]]
    if len(args) > len(positional):
        return 0, f"{where}() takes at most {len(positional)} positional arguments ({len(args)} given)"
    bound: Dict[str, object] = {p[0]: v for p, v in zip(positional, args)}
    names = [p[0] for p in params]
    for key in kwargs:
        if key not in names:
            return 0, f"{where}() got an unexpected keyword argument '{key}'"
        if key in bound:
            return 0, f"{where}() got multiple values for argument '{key}'"
        bound[key] = kwargs[key]
    for good, (name, kind, has_default, _) in enumerate(params):
        if name not in bound:
            if not has_default:
                return good, f"{where}() missing argument '{name}'"
            continue
        value = bound[name]
        if not accepts(kind, value, module):
            label = where if field else f"{where}() argument '{name}'"
            return good, f"{label}: expected {expected(kind)}, got {_got(value)}"
    return None


UNMATCHED = "arguments do not match"


def _unmatched(where, doc, args, kwargs) -> str:
    """The fallback when no single argument is to blame: the signatures and what was given, in our words."""
    given = ", ".join([type(a).__name__ for a in args] + [f"{k}={type(v).__name__}" for k, v in kwargs.items()])
    takes = " or ".join("(" + ", ".join(f"{p[0]}: {expected(p[1])}" for p in params) + ")"
                        for params in parameters(doc))
    return f"{where}: {UNMATCHED} {takes}; got ({given})"


def _wrapped(function: Callable, where: str, module, field: Optional[str] = None) -> Callable:
    doc = function.__doc__

    def refused(error, args, kwargs):
        if not any(g in str(error) for g in GENERIC):
            raise error
        message = explain(where, doc, args, kwargs, module, field)
        raise TypeError(message or _unmatched(where, doc, args, kwargs)) from None

    # A Python wrapper cost every successful call its own frame (1.5k instructions a World.step); the C one
    # forwards the call to `function` and hands only a TypeError to `refused`.
    call = functools.update_wrapper(_name_errors(module)(function, refused), function)
    call.__wrapped_core__ = function
    return call


def _name_errors(module):
    """The C wrapper's maker, from the module or the package's root module (a submodule has none)."""
    root = module
    while not hasattr(root, "_name_errors"):
        root = sys.modules[root.__name__.rpartition(".")[0]]
    make = root._name_errors
    return getattr(make, "__wrapped_core__", make)


def _is_core_function(obj) -> bool:
    return type(obj).__name__ == "builtin_function_or_method" and obj.__doc__ is not None


def name_bad_arguments(module) -> List[str]:
    """Wraps every pybind11 callable of `module` (and its submodules) as the module docstring says; returns
    the names wrapped ("World.step", "BodyDef.mass" for a field). Idempotent."""
    done: List[str] = []
    for name, obj in list(vars(module).items()):
        if type(obj).__name__ == "module" and obj.__name__.startswith(module.__name__ + "."):
            done += name_bad_arguments(obj)
        elif _is_core_function(obj):
            setattr(module, name, _wrapped(obj, name, module))
            done.append(name)
        elif isinstance(obj, type) and obj.__module__ == module.__name__:
            done += _wrap_class(obj, module)
    return done


def _wrap_class(cls, module) -> List[str]:
    done = []
    for name, attr in list(vars(cls).items()):
        where = f"{cls.__name__}.{name}"
        if name.startswith("_pybind11"):
            continue  # pybind11's own cross-module hook
        if type(attr).__name__ == "instancemethod":
            setattr(cls, name, _wrapped(attr.__func__, cls.__name__ if name == "__init__" else where, module))
            done.append(where)
        elif isinstance(attr, staticmethod) and _is_core_function(attr.__func__):
            setattr(cls, name, staticmethod(_wrapped(attr.__func__, where, module)))
            done.append(where)
        elif isinstance(attr, property) and attr.fset is not None and not hasattr(attr.fset, "__wrapped_core__"):
            setattr(cls, name, property(attr.fget, _wrapped(attr.fset, where, module, field=name), attr.fdel,
                                        attr.__doc__))
            done.append(where)
    return done
