"""The package's layout rules: data flows one way (models <- solvers <- spine), every figure and
benchmark is registered, and nothing at the repository root shadows the installed package."""
import ast
import inspect
from pathlib import Path

import pytest

import mechopt
from mechopt import registry
from mechopt.benchmarks import STUDIES, study
from mechopt.figures import FIGURES

ROOT = Path(__file__).resolve().parents[1]
KIT = {"mechopt.errors", "mechopt.cache"}          # importable from every layer; imports nothing of mechopt
SPINE = ({"mechopt." + p.stem for p in (ROOT / "src" / "mechopt").glob("*.py")} - KIT) | {"mechopt.figures", "mechopt.benchmarks"}
IO = {"tomllib", "json", "pyarrow", "pickle", "shelve", "csv", "sqlite3", "shutil", "tempfile", "dask", "distributed"}


def imports_of(path: Path) -> set[str]:
    tree = ast.parse(path.read_text(encoding="utf-8"))
    out = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out |= {a.name for a in node.names}
        elif isinstance(node, ast.ImportFrom) and node.module:
            out.add(node.module)
            out |= {f"{node.module}.{a.name}" for a in node.names}
    return out


def offending(folder: str, forbidden) -> dict[str, list[str]]:
    bad = {}
    for path in sorted((ROOT / folder).rglob("*.py")):
        hits = sorted(m for m in imports_of(path) if any(m == f or m.startswith(f + ".") for f in forbidden))
        if hits:
            bad[str(path.relative_to(ROOT))] = hits
    return bad


def test_the_kit_imports_nothing_of_mechopt():
    for name in KIT:
        path = ROOT / "src" / "mechopt" / f"{name.split('.')[1]}.py"
        assert not {m for m in imports_of(path) if m.startswith("mechopt")}, path


def test_no_model_imports_a_solver_the_spine_or_io():
    assert offending("models", {"mechopt.solvers", *SPINE, *IO}) == {}


def test_no_solver_imports_the_spine_or_io():
    assert offending("solvers", {*SPINE, *IO}) == {}


def test_no_model_or_solver_opens_a_file():
    calls = {}
    for folder in ("models", "solvers"):
        for path in (ROOT / folder).rglob("*.py"):
            tree = ast.parse(path.read_text(encoding="utf-8"))
            names = [n.func.id if isinstance(n.func, ast.Name) else n.func.attr for n in ast.walk(tree)
                     if isinstance(n, ast.Call) and isinstance(n.func, (ast.Name, ast.Attribute))]
            hits = sorted({n for n in names if n in ("open", "read_text", "write_text", "read_bytes", "write_bytes")})
            if hits:
                calls[str(path.relative_to(ROOT))] = hits
    assert calls == {}


def test_the_rule_is_checked_on_the_code_it_names():
    # the test above would pass on an empty tree: make sure it reads the real folders
    assert len(list((ROOT / "models").glob("*.py"))) >= 5 and len(list((ROOT / "solvers").rglob("*.py"))) >= 10
    assert "mechopt.solvers.result" in imports_of(ROOT / "solvers" / "loom" / "plan.py")


def test_no_package_folder_at_the_root_shadows_the_installed_one():
    assert not (ROOT / "mechopt").exists()
    assert Path(mechopt.__file__).resolve().parent != ROOT / "mechopt"


def test_every_scenes_task_class_has_registered_figures():
    missing = sorted({s.task_class.__name__ for s in registry.all_scenes()} - {c.__name__ for c in FIGURES})
    assert missing == []


def test_a_task_without_figures_is_an_error_not_an_empty_list():
    from mechopt.errors import MechoptError
    from mechopt.figures.registry import figures_of
    scene = registry.find("loom/group1")

    class Unregistered:
        pass
    run = registry.Run(scene.__class__(scene.path, scene.spec, Unregistered, scene.solver), None, [])
    with pytest.raises(MechoptError, match="no figures registered for task .*Unregistered"):
        figures_of(run)


@pytest.mark.parametrize("name", sorted(STUDIES))
def test_every_registered_benchmark_imports_and_has_its_entry_point(name):
    module = study(name)
    assert list(inspect.signature(module.cli).parameters)[:2] == ["repeats", "out_dir"]


def test_every_benchmark_file_is_registered():
    files = {p.stem for p in (ROOT / "benchmarks").glob("*.py")} - {"__init__"}
    assert files == {m.rpartition(".")[2] for m in STUDIES.values()}


def test_no_module_imports_another_modules_private_name():
    """What two modules share is public: a private name (`_x`) stays in its module."""
    bad = []
    for folder in ("src", "models", "solvers", "benchmarks", "cases"):
        for path in (ROOT / folder).rglob("*.py"):
            for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
                if isinstance(node, ast.ImportFrom) and ((node.module or "").startswith("mechopt") or node.level):
                    bad += [f"{path.relative_to(ROOT)}: {node.module}.{a.name}" for a in node.names
                            if a.name.startswith("_") and not a.name.startswith("__")]
    assert bad == []
