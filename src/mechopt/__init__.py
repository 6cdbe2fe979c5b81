"""mechopt: formal optimisation models for machine mechanisms, from published studies.

The Python API (the `mechopt` command does the same from a terminal)::

    import mechopt
    scene = mechopt.load("cam-cutter/minimax")         # a registry id, or a scene file's path
    run = mechopt.solve(scene, a_mm=40, h_mm=3)         # overrides are validated like the file
    run.status, run.values["H_mm"], run.with_units()    # values carry their unit in the name
    run.arrays                                          # what the solver computed along the way
    run.figures()                                       # matplotlib Figures, by name (no files)
    mechopt.describe(scene)                             # every key you can override, unit, range
    run.success, run.ok                                 # SOLVED?; the answer asked for, checks passed?
    table = mechopt.sweep("loom/group1", grid={"amplitude_limit_mm": (0.05, 0.2, 31)})   # pyarrow Table

`mechopt.scenes()` lists the registry (the package's scenes plus `add_cases(folder)` and the
MECHOPT_CASES folders); `mechopt.sweep` runs what-if studies (the module `mechopt.sweep`, callable,
holds the machinery: chunks, Dask, resuming a stopped sweep); `mechopt.clear_caches()`
drops every solver build kept in this process. Where a mechanism has several methods, one door
takes `method=`: `mechopt.solvers.press.simulate`, `mechopt.solvers.cam_cutter.fit_linkage`,
`mechopt.solvers.stop_impact.rebound`.
"""
import re
import types
from contextlib import contextmanager
from importlib.metadata import PackageNotFoundError, version

from mechopt import sweep as _studies
from mechopt.cache import clear as clear_caches
from mechopt.errors import MechoptError, ModelError, SceneError, SettingError, SolverError
from mechopt.registry import Run, add_cases
from mechopt.registry import all_scenes as scenes
from mechopt.registry import find as load
from mechopt.solvers.result import Result, Status

try:
    __version__ = version("mechopt")
except PackageNotFoundError:        # imported from a source tree that was never installed
    __version__ = "0+unknown"

__all__ = ["load", "solve", "sweep", "describe", "scenes", "add_cases", "clear_caches", "Run", "Result", "Status",
           "MechoptError", "ModelError", "SceneError", "SettingError", "SolverError", "__version__"]


def solve(scene, overrides: dict | None = None, **more) -> Run:
    """Solve a scene (a Scene, a registry id or a scene file's path) with overrides of its
    parameters, solver settings or structure paths, given as a dict or as keywords; returns the
    Run (status, values, arrays, checks, figures). The source's checks are made only when no
    parameter was changed."""
    from mechopt import registry
    with _python_words():
        return registry.run(scene, {**(overrides or {}), **more})


def describe(scene) -> list[dict[str, str]]:
    """Every key an override reaches, with its kind, unit, mark, allowed range and current value."""
    return load(scene).describe()


def _sweep(scene, grid: dict | None = None, random: dict | None = None, *, samples: int = 0, seed: int = 0,
           out=None, progress: bool = False, **options):
    """Every variant of a scene (a Scene, a registry id or a scene file's path) as one pyarrow Table.

    grid : {key: (start, stop, num)}, num evenly spaced values each, all combinations.
    random : {key: (low, high)}, `samples` uniform draws (seeded) combined with every grid point.
    out : a Parquet file to write (and to resume from); further options as `mechopt.sweep.sweep`
    (workers, scheduler, chunk, max_variants). A variant that fails is a row with its status.
    """
    with _python_words():
        axes = [_axis("grid", key, bounds, 3) for key, bounds in (grid or {}).items()]
        draws = [_axis("random", key, bounds, 2) for key, bounds in (random or {}).items()]
        return _studies.sweep(load(scene), axes, draws, samples=samples, seed=seed, out=out, progress=progress,
                              **options)


def _axis(kind, key, bounds, size):
    form = "(start, stop, num)" if size == 3 else "(low, high)"
    if not isinstance(bounds, (tuple, list)) or len(bounds) != size:
        raise SceneError(f"{kind}[{key!r}] = {bounds!r}: expected {form}", key=key)
    low, high, *num = bounds
    if any(isinstance(x, bool) or not isinstance(x, (int, float)) for x in (low, high)):
        raise SceneError(f"{kind}[{key!r}] = {bounds!r}: expected numbers {form}", key=key)
    for end in (low, high):
        if _studies.axis_value_problem(float(end)):
            raise SceneError(f"{kind}[{key!r}] = {bounds!r}: {end!r} {_studies.axis_value_problem(float(end))}", key=key)
    if low > high:
        raise SceneError(f"{kind}[{key!r}] = {bounds!r}: {low:g} > {high:g}; give the range low to high", key=key)
    if num and (isinstance(num[0], bool) or not isinstance(num[0], int) or num[0] < 1):
        raise SceneError(f"{kind}[{key!r}] = {bounds!r}: num = {num[0]!r}; expected a whole number >= 1", key=key)
    return _studies.Axis(key, float(low), float(high), *num)


class _CallableStudies(types.ModuleType):
    """`mechopt.sweep(...)` runs a study while `mechopt.sweep.<name>` stays the module."""

    def __call__(self, *args, **kwargs):
        return _sweep(*args, **kwargs)

    __call__.__doc__ = _sweep.__doc__


_studies.__class__ = _CallableStudies


_FLAG = re.compile(r"--set '?([^\s:']+?)'?(?=:)")


@contextmanager
def _python_words():
    """Errors of the Python API name keywords, not the command line's `--set` flag."""
    try:
        yield
    except (SceneError, ModelError) as exc:
        text = str(exc)
        if "--set" not in text:
            raise
        text = re.sub(r"--set (\S+?): unknown key", r"unknown keyword \1", text)
        raise type(exc)(_FLAG.sub(r"keyword \1", text), key=exc.key) from None
