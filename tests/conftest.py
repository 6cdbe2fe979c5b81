"""Shared test settings: property tests draw the same examples on every run, so CI cannot flake,
and nothing the suite runs leaves files in the checkout (hypothesis keeps its folder in a temp dir)."""
import os
import tempfile

os.environ.setdefault("HYPOTHESIS_STORAGE_DIRECTORY", os.path.join(tempfile.gettempdir(), "mechopt-hypothesis"))

from hypothesis import settings  # noqa: E402  (after the storage folder is set)

settings.register_profile("mechopt", derandomize=True, database=None, deadline=None)
settings.load_profile("mechopt")


# -- a package scene solved as its file says is solved once per test session -----------------------
# validate, the report and the README's commands each solve the whole registry (the report with each
# headline's drivers, one re-solve per input, and every scene's figures): a test that asks for
# `solved_once` gets registry.run remembering those runs, and the report drawing a remembered run's
# figures once, so the second command to need a scene reads the first one's Run and PNGs. What-ifs
# (overrides) and the user's scene files always solve afresh.
import shutil  # noqa: E402
from pathlib import Path  # noqa: E402

import pytest  # noqa: E402

from mechopt import registry  # noqa: E402

_SOLVED: dict = {}        # (scene file, its bytes, drivers) -> Run
_DRAWN: dict = {}         # (scene file, its bytes) -> the PNGs first drawn of a remembered run of it


def _remembered_run(real):
    def run(scene, overrides=None, *, drivers=False):
        scene = registry.find(scene)
        if overrides or not scene.path.resolve().is_relative_to(registry.cases_dir().resolve()):
            return real(scene, overrides, drivers=drivers)
        key = (str(scene.path.resolve()), scene.path.read_bytes(), bool(drivers))
        kept = _SOLVED.get(key)
        if kept is None or kept.scene != scene:      # the same file, but a scene changed in memory: solve it
            kept = _SOLVED[key] = real(scene, overrides, drivers=drivers)
        return kept
    return run


def _remembered_figures(real, folder):
    # by scene file, with or without drivers: the figures read a result's values and arrays, which
    # the drivers (an entry of its diagnostics) leave as they are
    def plot_run(run, out_dir):
        key = next((key[:2] for key, kept in _SOLVED.items() if kept is run), None)
        if key is None:
            return real(run, out_dir)
        if key not in _DRAWN:
            _DRAWN[key] = real(run, folder / str(len(_DRAWN)))
        Path(out_dir).mkdir(parents=True, exist_ok=True)
        return [Path(shutil.copy(png, Path(out_dir) / png.name)) for png in _DRAWN[key]]
    return plot_run


@pytest.fixture(scope="session")
def _figure_folder(tmp_path_factory):
    return tmp_path_factory.mktemp("figures-drawn-once")


@pytest.fixture(scope="session")
def solve_once_patches(_figure_folder):
    """Put the remembering registry.run and report figures into a MonkeyPatch (for a fixture of a
    wider scope than `monkeypatch`'s)."""
    def apply(patch):
        from mechopt import report
        patch.setattr(registry, "run", _remembered_run(registry.run))
        patch.setattr(report, "plot_run", _remembered_figures(report.plot_run, _figure_folder))
    return apply


@pytest.fixture
def solved_once(monkeypatch, solve_once_patches):
    """registry.run with the package's scenes (no overrides) solved once per session (per xdist
    worker), and the report's figures of such a run drawn once."""
    solve_once_patches(monkeypatch)


# -- with pytest-xdist (`-n auto --dist loadgroup`, the README's test command) ---------------------
# each file's tests stay on one worker (its module fixtures are built once), and the files that solve
# the whole registry share one worker, so that `solved_once` solves each scene once there.
WHOLE_REGISTRY = {"test_readme_commands.py", "test_report.py", "test_scenes.py", "test_drivers.py"}


@pytest.hookimpl(tryfirst=True)
def pytest_collection_modifyitems(items):
    for item in items:
        name = item.path.name
        item.add_marker(pytest.mark.xdist_group("whole-registry" if name in WHOLE_REGISTRY else name))
