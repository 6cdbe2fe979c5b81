"""Allowed ranges of inputs, declared once as `annotated_types` constraints (Gt, Ge, Lt, Le,
Interval) and read from there by every check and by `mechopt describe`:

* a solver's settings, in its own signature, checked when a scene is loaded, a `--set` is given
  or the solver is called directly (`check_settings`):

      def events(task, *, tol: Tolerance = 1e-10, samples: Annotated[int, Interval(ge=1, le=10_000)] = 8)

* a model's inputs, on its dataclass fields, checked when the model is built, from a scene or
  from Python alike (`check_fields`, called early in the model's `__post_init__`):

      crank_radius_mm: Annotated[float, Gt(0), Le(1000)]

A value out of its range is one sentence wherever it is caught (`range_fault`): "key=value:
allowed range"; the scene layer puts the file name in front.
"""
import dataclasses
import functools
import inspect
import math
import numbers
import operator
import sys
import types
from typing import Annotated, Literal, Union, get_args, get_origin

from annotated_types import Ge, Gt, Interval, Le

from mechopt.kit.errors import ModelError, SettingError, quote

Positive = Annotated[float, Gt(0)]
NonNegative = Annotated[float, Ge(0)]
Tolerance = Annotated[float, Interval(gt=0, le=0.1)]        # relative or absolute, of an iterative method
Count = Annotated[int, Interval(ge=1, le=10_000_000)]

__all__ = ["Positive", "NonNegative", "Tolerance", "Count", "Ge", "Gt", "Interval", "Le", "Annotated",
           "check_settings", "setting_problem", "check_fields", "field_problem", "range_fault", "declared_range",
           "describe_range"]


def check_settings(solver, **values) -> None:
    """Settings of a direct call against the ranges the solver's signature declares, as the scene
    loader checks them: a one-line SettingError naming the key, never a traceback from inside."""
    options = inspect.signature(solver).parameters
    for key, value in values.items():
        problem = setting_problem(options[key], value)
        if problem:
            raise SettingError(range_fault(key, value, problem), key=key)


def setting_problem(option: inspect.Parameter, value) -> str:
    """What is wrong with a value for a solver setting ('' when nothing): its type, its choices
    (a Literal) or its range (annotated_types constraints in the signature)."""
    annotation, default = option.annotation, option.default
    if get_origin(annotation) is Literal:
        choices = get_args(annotation)
        return "" if value in choices else f"allowed {', '.join(map(str, choices))}"
    expected = type(default)
    ok = (isinstance(value, (int, float)) and not isinstance(value, bool) if expected is float
          else type(value) is expected)
    if not ok:
        return f"expected {expected.__name__} (default {default!r})"
    if isinstance(value, float) and not math.isfinite(value):
        return "expected a finite number"
    return _range_problem(annotation, value)


def range_fault(key: str, value, problem: str) -> str:
    """The one sentence for an input out of its range or of the wrong kind: `key=value: problem`
    (`problem` from `field_problem`, or "allowed <= 100 a_mm = 2500" for a range relative to another
    input). The scene layer puts its file and table in front; a Python caller sees it as is."""
    return f"{key}={quote(value)}: {problem}"


def check_fields(task) -> None:
    """Every field of the dataclass `task` against its declared type and range: a ModelError
    `range_fault` naming the first field at fault. Called early in a model's `__post_init__`, so a
    model built from Python is held to the same rules as one read from a scene. Fields typed as
    something else (a table, a list, a law) are the model's own to check."""
    for name, annotation in _field_types(type(task)):
        value = getattr(task, name)
        problem = field_problem(annotation, value)
        if problem:
            raise ModelError(range_fault(name, value, problem), key=name)


def field_problem(annotation, value) -> str:
    """What is wrong with a value for a model's field ('' when nothing): its kind as declared (a
    finite number for a float, a whole number for an int, bool, str, one of a Literal's choices;
    None only where the type allows it) and its range (annotated_types constraints)."""
    base = get_args(annotation)[0] if get_origin(annotation) is Annotated else annotation
    kinds = get_args(base) if get_origin(base) in (Union, types.UnionType) else (base,)
    if value is None:
        return "" if type(None) in kinds or None in _choices(kinds) else "expected a value, not None"
    choices = _choices(kinds)
    if choices and not any(k is str and isinstance(value, str) for k in kinds):
        return "" if value in choices else f"allowed {', '.join(map(str, choices))}"
    if float in kinds or int in kinds:
        if any(isinstance(k, type) and k not in (float, int) and isinstance(value, k) for k in kinds):
            return ""           # another kind the field takes (`float | SomeLaw`): the model checks it
        if isinstance(value, bool) or not isinstance(value, numbers.Real):
            return "expected a number"
        if not abs(value) <= sys.float_info.max:     # inf, nan, or an integer no float holds
            return "expected a finite number"
        if float not in kinds and value != int(value):      # a scene's 5.0 is a whole number
            return "expected a whole number"
    elif bool in kinds and not isinstance(value, bool):
        return "expected true or false"
    elif kinds == (str,) and not isinstance(value, str):
        return "expected text"
    return _range_problem(annotation, value)


def _range_problem(annotation, value) -> str:
    """'allowed <range>' when `value` is outside the range `annotation` declares, else ''."""
    low, high = declared_range(annotation)
    if (low and not low[1](value, low[0])) or (high and not high[1](value, high[0])):
        return f"allowed {describe_range(low, high)}"
    return ""


def _choices(kinds) -> tuple:
    return tuple(c for k in kinds if get_origin(k) is Literal for c in get_args(k))


@functools.cache
def _field_types(cls) -> tuple:
    """(name, annotation) of the fields a caller gives (init fields), looked up once per class: a
    model built in a solver's loop pays a look-up, not a walk of its class."""
    return tuple((f.name, f.type) for f in dataclasses.fields(cls) if f.init)


def declared_range(annotation):
    """(low, high), each (bound, test, "gt"|"ge"|"lt"|"le") or None: the limits an annotation
    declares with annotated_types (a solver setting, or a task field)."""
    low = high = None
    if get_origin(annotation) is Annotated:
        for mark in get_args(annotation)[1:]:
            for name, test in (("gt", operator.gt), ("ge", operator.ge)):
                if getattr(mark, name, None) is not None:
                    low = (getattr(mark, name), test, name)
            for name, test in (("lt", operator.lt), ("le", operator.le)):
                if getattr(mark, name, None) is not None:
                    high = (getattr(mark, name), test, name)
    return low, high


def describe_range(low, high) -> str:
    """'> 0', '1 ... 10,000', 'any' for a range from `declared_range`."""
    sign = {"gt": ">", "ge": ">=", "lt": "<", "le": "<="}
    # by value, not type: typing caches Annotated[float, Le(1e5)] and Annotated[float, Le(100_000)] as one
    # (their marks compare equal), so which of the two a field holds depends on the import order
    text = lambda x: f"{int(x):,}" if float(x).is_integer() and (isinstance(x, int) or abs(x) < 1e6) \
        else f"{x:g}"       # noqa: E731
    if low and high:
        return f"{'' if low[2] == 'ge' else '> '}{text(low[0])} ... {text(high[0])}{'' if high[2] == 'le' else ' (excl.)'}"
    if low:
        return f"{sign[low[2]]} {text(low[0])}"
    if high:
        return f"{sign[high[2]]} {text(high[0])}"
    return "any"
