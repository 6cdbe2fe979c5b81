"""Allowed ranges of solver settings, declared in the solver's own signature and checked when a
scene is loaded or a `--set` is given, before anything runs:

    def events(task, *, tol: Tolerance = 1e-10, samples: Annotated[int, Interval(ge=1, le=10_000)] = 8)

The scene loader reads the `annotated_types` constraints (Gt, Ge, Lt, Le, Interval) and names
the range in its error; `mechopt describe` lists it.
"""
import inspect
import math
import operator
from typing import Annotated, Literal, get_args, get_origin

from annotated_types import Ge, Gt, Interval, Le

from mechopt.kit.errors import SettingError

Positive = Annotated[float, Gt(0)]
NonNegative = Annotated[float, Ge(0)]
Tolerance = Annotated[float, Interval(gt=0, le=0.1)]        # relative or absolute, of an iterative method
Count = Annotated[int, Interval(ge=1, le=10_000_000)]

__all__ = ["Positive", "NonNegative", "Tolerance", "Count", "Ge", "Gt", "Interval", "Le", "Annotated",
           "check_settings", "setting_problem", "declared_range", "describe_range"]


def check_settings(solver, **values) -> None:
    """Settings of a direct call against the ranges the solver's signature declares, as the scene
    loader checks them: a one-line SettingError naming the key, never a traceback from inside."""
    options = inspect.signature(solver).parameters
    for key, value in values.items():
        problem = setting_problem(options[key], value)
        if problem:
            raise SettingError(f"{key}={value!r}: {problem}", key=key)


def setting_problem(option: inspect.Parameter, value) -> str:
    """What is wrong with a value for a solver setting ('' when nothing): its type, its choices
    (a Literal) or its range (annotated_types constraints in the signature, see src/mechopt/kit/settings.py)."""
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
    low, high = declared_range(annotation)
    if (low and not low[1](value, low[0])) or (high and not high[1](value, high[0])):
        return f"allowed {describe_range(low, high)}"
    return ""


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
    text = lambda x: f"{x:,}" if isinstance(x, int) else f"{x:g}"        # noqa: E731
    if low and high:
        return f"{'' if low[2] == 'ge' else '> '}{text(low[0])} ... {text(high[0])}{'' if high[2] == 'le' else ' (excl.)'}"
    if low:
        return f"{sign[low[2]]} {text(low[0])}"
    if high:
        return f"{sign[high[2]]} {text(high[0])}"
    return "any"
