"""Shared test settings: property tests draw the same examples on every run, so CI cannot flake,
and nothing the suite runs leaves files in the checkout (hypothesis keeps its folder in a temp dir)."""
import os
import tempfile

os.environ.setdefault("HYPOTHESIS_STORAGE_DIRECTORY", os.path.join(tempfile.gettempdir(), "mechopt-hypothesis"))

from hypothesis import settings  # noqa: E402  (after the storage folder is set)

settings.register_profile("mechopt", derandomize=True, database=None, deadline=None)
settings.load_profile("mechopt")


# -- a package scene solved as its file says is solved once per test run ---------------------------
# validate, the report and the README's commands each solve the whole registry (the report with each
# headline's drivers, and every scene's figures): a test that asks for `solved_once` gets registry.run
# remembering those runs, and the report drawing a remembered run's figures once, so the second command
# to need a scene reads the first one's Run and PNGs. The memory is a folder shared by the run's xdist
# workers (pickled Runs, a lock a key): a scene another worker is solving is waited for, not solved
# again. A run with drivers is the plain run with its drivers added, and a plain run one with drivers
# less that entry, so the scene itself is solved once either way. What-ifs (overrides) and the user's
# scene files always solve afresh.
import dataclasses  # noqa: E402
import fcntl  # noqa: E402
import hashlib  # noqa: E402
import pickle  # noqa: E402
import shutil  # noqa: E402
from pathlib import Path  # noqa: E402

import cloudpickle  # noqa: E402  (distributed's own dependency)
import pytest  # noqa: E402

from mechopt import registry  # noqa: E402

_SOLVED: dict = {}        # (scene file, its bytes, drivers) -> Run, in this process


class _Shared:
    """Values made once per test run in `folder` (shared by the xdist workers), each under a lock."""

    def __init__(self, folder):
        self.folder = folder

    def path(self, *key):
        return self.folder / hashlib.sha256(repr(key).encode()).hexdigest()[:24]

    def get(self, key, make):
        path = self.path(*key)
        with open(path.with_suffix(".lock"), "w") as lock:
            fcntl.flock(lock, fcntl.LOCK_EX)           # another worker making it: wait for its value
            if path.exists():
                return pickle.loads(path.read_bytes())
            value = make()
            try:                # cloudpickle: a task may hold a parsed expression's lambda
                path.with_suffix(".part").write_bytes(cloudpickle.dumps(value))
            except Exception:   # noqa: BLE001 -- not shareable: this worker keeps it, another makes its own
                path.with_suffix(".part").unlink(missing_ok=True)
            else:
                path.with_suffix(".part").rename(path)
            return value


def _read_only(run):
    """A Run as the solver gave it: its arrays read-only again (pickle gives them back writable)."""
    for array in run.result.arrays.values():
        array.flags.writeable = False
    return run


def _without_drivers(run):
    diagnostics = {k: v for k, v in run.result.diagnostics.items() if k != "drivers"}
    return dataclasses.replace(run, result=dataclasses.replace(run.result, diagnostics=diagnostics))


def _remembered_run(real, shared):
    def solve(scene, drivers):
        if not drivers:
            return real(scene, None)
        plain = run(scene)
        if not scene.spec.headline:            # no headline, no drivers: the plain run is the answer
            return plain
        if not hasattr(registry, "_with_drivers"):
            return real(scene, None, drivers=True)
        return dataclasses.replace(plain, result=registry._with_drivers(scene, {}, plain.result))

    def run(scene, overrides=None, *, drivers=False):
        scene = registry.find(scene)
        if overrides or not scene.path.resolve().is_relative_to(registry.cases_dir().resolve()):
            return real(scene, overrides, drivers=drivers)
        key = (str(scene.path.resolve()), scene.path.read_bytes(), bool(drivers))
        kept = _SOLVED.get(key)
        if kept is None or kept.scene != scene:      # the same file, but a scene changed in memory: solve it
            if kept is None and not drivers and (key[0], key[1], True) in _SOLVED:
                kept = _without_drivers(_SOLVED[key[0], key[1], True])
            elif kept is None:      # (a lock a key: the drivers' run takes the plain one's inside its own)
                kept = _read_only(shared.get(("run", *key), lambda: solve(scene, drivers)))
            else:
                kept = real(scene, overrides, drivers=drivers)
            _SOLVED[key] = kept
        return kept
    run.remembers = True
    return run


def _remembered_figures(real, shared):
    # by scene file, with or without drivers: the figures read a result's values and arrays, which
    # the drivers (an entry of its diagnostics) leave as they are
    def plot_run(run, out_dir):
        key = next((key[:2] for key, kept in _SOLVED.items() if kept is run), None)
        if key is None:
            return real(run, out_dir)

        def draw():
            folder = shared.path("figures", *key).with_suffix(".drawn")
            return [png.name for png in real(run, folder)]
        names = shared.get(("figures", *key), draw)
        drawn = shared.path("figures", *key).with_suffix(".drawn")
        Path(out_dir).mkdir(parents=True, exist_ok=True)
        return [Path(shutil.copy(drawn / name, Path(out_dir) / name)) for name in names]
    return plot_run


@pytest.fixture(scope="session")
def _shared_folder(tmp_path_factory):
    """A folder of this test run that every xdist worker sees (the parent of the workers' own)."""
    import os
    base = tmp_path_factory.getbasetemp()
    folder = (base.parent if os.environ.get("PYTEST_XDIST_WORKER") else base) / "solved-once"
    folder.mkdir(exist_ok=True)
    return folder


@pytest.fixture(scope="session")
def solve_once_patches(_shared_folder):
    """Put the remembering registry.run and report figures into a MonkeyPatch (for a fixture of a
    wider scope than `monkeypatch`'s)."""
    shared = _Shared(_shared_folder)

    def apply(patch):
        from mechopt import report
        if getattr(registry.run, "remembers", False):     # patched already (a wider fixture's patch)
            return
        patch.setattr(registry, "run", _remembered_run(registry.run, shared))
        patch.setattr(report, "plot_run", _remembered_figures(report.plot_run, shared))
    return apply


@pytest.fixture
def solved_once(monkeypatch, solve_once_patches):
    """registry.run with the package's scenes (no overrides) solved once per test run (shared by the
    xdist workers), and the report's figures of such a run drawn once."""
    solve_once_patches(monkeypatch)


# -- with pytest-xdist (`-n auto --dist loadgroup`, the README's test command) ---------------------
# the tests of a file that builds a module fixture stay on one worker (the fixture is built once);
# a test that names its own group keeps it (the README's commands: each with the commands whose files
# it reads); any other test goes wherever a worker is free. The package's scenes are solved once for
# all workers (`solved_once` above), so no group needs to hold every test that solves them.
def _builds_a_module_fixture(item):
    defs = getattr(item, "_fixtureinfo", None)
    return defs is None or any(d.scope in ("module", "class", "package")
                               for chain in defs.name2fixturedefs.values() for d in chain)


@pytest.hookimpl(tryfirst=True)
def pytest_collection_modifyitems(items):
    for item in items:
        if item.get_closest_marker("xdist_group") is None and _builds_a_module_fixture(item):
            item.add_marker(pytest.mark.xdist_group(item.path.name))
