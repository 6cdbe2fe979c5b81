"""The Python front end: `mechopt.solve` and `mechopt.describe` (the command line's twins are in
cli.py). Errors raised here name Python keywords, not the command line's `--set` flag."""
import re
from contextlib import contextmanager

from mechopt import registry
from mechopt.kit.errors import ModelError, SceneError


def solve(scene, overrides: dict | None = None, **more) -> registry.Run:
    """Solve a scene (a Scene, a registry id or a scene file's path) with overrides of its
    parameters, solver settings or structure paths, given as a dict or as keywords; returns the
    Run (status, values, arrays, checks, figures). The source's checks are made only when no
    parameter was changed."""
    with python_words():
        return registry.run(scene, {**(overrides or {}), **more})


def describe(scene) -> list[dict[str, str]]:
    """Every key an override reaches, with its kind, unit, mark, allowed range and current value."""
    return registry.find(scene).describe()


_FLAG = re.compile(r"--set '?([^\s:']+?)'?(?=:)")


@contextmanager
def python_words():
    """Errors of the Python API name keywords, not the command line's `--set` flag."""
    try:
        yield
    except (SceneError, ModelError) as exc:
        text = str(exc)
        if "--set" not in text:
            raise
        text = re.sub(r"--set (\S+?): unknown key", r"unknown keyword \1", text)
        raise type(exc)(_FLAG.sub(r"keyword \1", text), key=exc.key) from None
