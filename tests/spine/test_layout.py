"""The package's layout rules: data flows one way (models <- solvers <- spine), every figure and
benchmark is registered, and nothing at the repository root shadows the installed package."""
import ast
import inspect
import subprocess
import sys
from pathlib import Path

import pytest

import mechopt
from mechopt import registry
from mechopt.benchmarks import STUDIES, study
from mechopt.figures import FIGURES
from mechopt.mechanisms import mechanisms

ROOT = Path(__file__).resolve().parents[2]
KIT = ROOT / "src" / "mechopt" / "kit"     # importable from every layer; imports nothing of mechopt outside itself
SPINE = {"mechopt." + p.stem for p in (ROOT / "src" / "mechopt").glob("*.py")} | {"mechopt.figures", "mechopt.benchmarks"}
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


def test_the_kit_imports_nothing_of_mechopt_outside_itself():
    modules = sorted(KIT.glob("*.py"))
    assert {p.stem for p in modules} >= {"errors", "cache", "result", "settings", "interrupt", "highs"}
    for path in modules:
        assert not {m for m in imports_of(path) if m.startswith("mechopt") and not m.startswith("mechopt.kit")}, path


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
    assert "mechopt.kit.result" in imports_of(ROOT / "solvers" / "cyclogram" / "plan.py")


def test_no_package_folder_at_the_root_shadows_the_installed_one():
    assert not (ROOT / "mechopt").exists()
    assert Path(mechopt.__file__).resolve().parent != ROOT / "mechopt"


def test_every_scenes_solver_has_registered_figures():
    missing = sorted({f"{s.id}: {s.solver.__name__}" for s in registry.all_scenes() if s.solver not in FIGURES})
    assert missing == []


def test_every_public_solver_of_a_mechanism_has_registered_figures():
    """A scene may name any function a solver package exports (`press.simulate`): each draws."""
    import importlib

    from mechopt.kit.result import Result
    missing = []
    for m in mechanisms():
        package = importlib.import_module(m.solvers)
        for name in package.__all__:
            fn = getattr(package, name)
            if not inspect.isfunction(fn) or fn in FIGURES:
                continue
            signature = inspect.signature(fn)          # a solver takes a task and returns a Result (a door: unannotated)
            if list(signature.parameters)[:1] == ["task"] and signature.return_annotation in (Result, signature.empty):
                missing.append(f"{m.solvers}.{name}")
    assert missing == []


def test_a_solver_without_figures_is_an_error_not_an_empty_list():
    from mechopt.figures.registry import figures_of
    from mechopt.kit.errors import MechoptError
    scene = registry.find("loom/group1")

    def unregistered(task):
        pass
    run = registry.Run(scene.__class__(scene.path, scene.spec, scene.task_class, unregistered), None, [])
    with pytest.raises(MechoptError, match=r"no figures registered for solver .*unregistered .*@figure\(unregistered\)"):
        figures_of(run)


def test_figures_register_by_solver_and_the_old_form_fails_loudly():
    from mechopt.figures.registry import figure, register
    from mechopt.kit.errors import MechoptError
    from mechopt.models.press import PressDrive
    from mechopt.solvers.press import steady_state
    with pytest.raises(MechoptError, match=r"registered by solver now.*@figure\(solver_fn"):
        register(PressDrive)
    with pytest.raises(MechoptError, match="steady_state registered twice"):
        figure(steady_state)(lambda run: {})


def test_no_figure_calls_a_solver():
    """Figures draw the Result: from the solvers they take the functions they register for, from
    the packages' doors, never a solver module's own pieces to compute with."""
    doors = {m.solvers for m in mechanisms()}
    bad = []
    for path in sorted((ROOT / "src" / "mechopt" / "figures").glob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.ImportFrom) and (node.module or "").startswith("mechopt.solvers"):
                bad += [f"{path.name}: {node.module}"] if node.module not in doors else []
            elif isinstance(node, ast.Import):
                bad += [f"{path.name}: {a.name}" for a in node.names if a.name.startswith("mechopt.solvers")]
    assert bad == []


# One table of mechanisms: a fifth mechanism is one row plus its own files.

SHARED_MODELS = {"__init__", "effects", "provenance", "validity"}          # of every mechanism
SPINE_FIGURES = {"__init__", "registry", "files", "sweep", "text"}    # the registry, saving, sweep maps, user text


def test_every_mechanism_file_is_named_by_exactly_one_row():
    named = lambda pick: sorted(n.rpartition(".")[2] for m in mechanisms() for n in pick(m))
    models = {p.stem for p in (ROOT / "models").glob("*.py")} - SHARED_MODELS
    assert named(lambda m: m.models) == sorted(models)
    assert named(lambda m: [m.solvers]) == sorted(p.parent.name for p in (ROOT / "solvers").glob("*/__init__.py"))
    assert named(lambda m: m.figures) == sorted({p.stem for p in (ROOT / "src" / "mechopt" / "figures").glob("*.py")}
                                                - SPINE_FIGURES)
    assert sorted({m.folder for m in mechanisms()}) == sorted(p.name for p in (ROOT / "cases").iterdir() if p.is_dir()
                                                               and not p.name.startswith("_"))


def test_every_row_has_its_own_test_folder_and_every_test_folder_a_row():
    """A mechanism's or a wing's tests live in tests/<its row's name, - as _>/ (the cyclogram wing's
    in tests/cyclogram/, its case the loom's in tests/loom/), the spine's in tests/spine/."""
    folders = {p.name for p in (ROOT / "tests").iterdir() if p.is_dir() and any(p.glob("test_*.py"))}
    assert folders == {m.name.replace("-", "_") for m in mechanisms()} | {"spine"}


def test_every_row_imports_and_its_templates_are_scenes():
    import importlib
    for m in mechanisms():
        for name in (*m.models, m.solvers, *m.figures, m.benchmark):
            importlib.import_module(name)
        for _, scene in m.templates:
            assert registry.find(scene).id.startswith(m.folder + "/")


def test_the_readers_hold_no_list_of_mechanisms():
    """The CLI's templates, the benchmark list and the figure registry read the table: no module
    or scene of a row is written in them."""
    readers = [ROOT / "src" / "mechopt" / "cli.py", ROOT / "benchmarks" / "__init__.py",
               ROOT / "src" / "mechopt" / "figures" / "__init__.py", ROOT / "src" / "mechopt" / "figures" / "registry.py"]
    names = {n for m in mechanisms() for n in (*m.figures, m.benchmark)}     # (cli imports a solver to use it)
    names |= {scene for m in mechanisms() for _, scene in m.templates}
    hits = {p.name: sorted(n for n in names if n in p.read_text(encoding="utf-8")) for p in readers}
    assert {k: v for k, v in hits.items() if v} == {}


def test_a_fifth_row_reaches_the_cli_and_the_benchmarks(monkeypatch):
    from mechopt import cli
    from mechopt import mechanisms as table
    from mechopt.benchmarks import studies
    fifth = table.Mechanism("press-copy", "A fifth", ("mechopt.models.press",), "mechopt.solvers.press",
                            ("mechopt.figures.press",), "mechopt.benchmarks.press", (("my-press", "press/kd2322"),))
    monkeypatch.setattr(table, "MECHANISMS", (*table.MECHANISMS, fifth))
    assert studies()["press-copy"] == "mechopt.benchmarks.press"
    assert table.templates()["my-press"] == "press/kd2322"
    parser = cli._parser()
    assert parser.parse_args(["new", "my-press", "x.toml"]).mechanism == "my-press"
    assert parser.parse_args(["bench", "press-copy"]).study == "press-copy"


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


def _python(code: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=300)


@pytest.mark.parametrize("folder", ["models", "solvers", "cases", "benchmarks"])
def test_a_root_folder_imported_by_its_bare_name_says_which_package_it_is(folder):
    done = _python(f"import {folder}")
    assert done.returncode != 0 and f"import mechopt.{folder}" in done.stderr.splitlines()[-1]


def test_import_mechopt_loads_no_numerics_until_a_name_is_used():
    heavy = ["numpy", "cvxpy", "casadi", "numba", "matplotlib", "pandas", "scipy", "networkx", "pyarrow"]
    done = _python(f"import sys, mechopt; print([m for m in {heavy!r} if m in sys.modules]); "
                   "print(mechopt.__version__, callable(mechopt.sweep), 'numpy' in sys.modules)")
    assert done.returncode == 0, done.stderr
    first, second = done.stdout.splitlines()
    assert first == "[]"
    assert second.endswith("True True")       # mechopt.sweep imported the sweep machinery, and it is callable
