"""The Python front end: `mechopt.solve` and `mechopt.describe` (the command line's twins are in
cli.py; errors name the key, which is the keyword here and the `--set` key there)."""
from mechopt import registry


def solve(scene, overrides: dict | None = None, **more) -> registry.Run:
    """Solve a scene (a Scene, a registry id or a scene file's path) with overrides of its
    parameters, solver settings or structure paths, given as a dict or as keywords; returns the
    Run (status, values, arrays, checks, figures). The source's checks are made only when no
    parameter was changed."""
    return registry.run(scene, {**(overrides or {}), **more})


def describe(scene) -> list[dict[str, str]]:
    """Every key an override reaches, with its kind, unit, mark, allowed range and current value."""
    return registry.find(scene).describe()
