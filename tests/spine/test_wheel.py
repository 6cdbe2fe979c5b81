"""The wheel holds every module of the repository's mapped folders and every scene: built from the
checkout, put first on the path of a fresh interpreter, each module imports from the wheel itself."""
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
ROOTS = {"mechopt": ROOT / "src" / "mechopt", "mechopt.models": ROOT / "models", "mechopt.solvers": ROOT / "solvers",
         "mechopt.cases": ROOT / "cases", "mechopt.benchmarks": ROOT / "benchmarks"}


def _modules():
    out = set()
    for name, folder in ROOTS.items():
        for path in folder.rglob("*.py"):
            parts = path.relative_to(folder).with_suffix("").parts
            parts = parts[:-1] if parts[-1] == "__init__" else parts
            out.add(".".join((name, *parts)))
    return sorted(out)


@pytest.fixture(scope="module")
def wheel(tmp_path_factory):
    """Built from a copy of the checkout: setuptools builds in the source's build/,
    which another build of the checkout at the same time (a `pip install .`) would share."""
    out = tmp_path_factory.mktemp("wheel")
    source = tmp_path_factory.mktemp("source") / "mechopt"
    shutil.copytree(ROOT, source, ignore=shutil.ignore_patterns(".git", "build", "dist", "site", "out", "*.egg-info",
                                                               "__pycache__", ".pytest_cache", ".hypothesis"))
    done = subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "-q", "-w", str(out), str(source)],
                          cwd=source, capture_output=True, text=True)
    assert done.returncode == 0, f"pip wheel exited {done.returncode}: {done.stderr[-3000:]}"     # say why
    return next(out.glob("mechopt-*.whl"))


@pytest.fixture(scope="module")
def unpacked(wheel, tmp_path_factory):
    """The wheel as pip installs it: unpacked into a folder of its own."""
    folder = tmp_path_factory.mktemp("site")
    zipfile.ZipFile(wheel).extractall(folder)
    return folder


def test_the_wheel_holds_every_module_and_scene(wheel):
    names = set(zipfile.ZipFile(wheel).namelist())
    missing_modules = sorted(m for m in _modules()
                             if "/".join(m.split(".")) + ".py" not in names
                             and "/".join(m.split(".")) + "/__init__.py" not in names)
    assert missing_modules == [] and len(_modules()) > 50
    data = {str(p.relative_to(ROOT / "cases")) for p in (ROOT / "cases").rglob("*") if p.suffix in (".toml", ".csv")}
    assert sorted(d for d in data if f"mechopt/cases/{d}" not in names) == []


def test_every_module_and_scene_imports_from_the_wheel(unpacked):
    code = ("import importlib, sys; sys.path.insert(0, sys.argv[1]); mods = sys.argv[2:]\n"
            "for m in mods:\n"
            "    f = importlib.import_module(m).__file__\n"
            "    assert f.startswith(sys.argv[1]), (m, f)\n"
            "from mechopt import registry\n"
            "print(len(registry.all_scenes()))\n")
    importable = [m for m in _modules() if not m.endswith(".__main__")]     # __main__ runs the CLI
    done = subprocess.run([sys.executable, "-c", code, str(unpacked), *importable], capture_output=True, text=True,
                          cwd=unpacked, timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    assert int(done.stdout.split()[-1]) == len(list((ROOT / "cases").rglob("*.toml")))
