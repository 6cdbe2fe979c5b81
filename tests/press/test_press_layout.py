"""The press wing's layout: one public problem module the methods stand on, no private
name imported across modules, and one door (`METHODS`) whose method names are a Literal."""
import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
PRESS = [ROOT / "models" / "press.py", *sorted((ROOT / "solvers" / "press").glob("*.py")),
         ROOT / "benchmarks" / "press.py", ROOT / "src" / "mechopt" / "figures" / "press.py",
         *sorted((ROOT / "tests").glob("test_press_*.py"))]


def private_imports(path: Path) -> list[str]:
    """`from mechopt.x import _y` (and `import mechopt.x._y`) in one file."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    out = []
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and (node.module or "").startswith("mechopt"):
            out += [f"{node.module}.{a.name}" for a in node.names if a.name.startswith("_")]
            out += [node.module] if any(part.startswith("_") for part in node.module.split(".")) else []
    return out


def test_no_press_module_imports_a_private_name_of_another():
    bad = {str(p.relative_to(ROOT)): private_imports(p) for p in PRESS if private_imports(p)}
    assert bad == {}


def test_the_rule_sees_a_private_import(tmp_path):
    sample = tmp_path / "sample.py"
    sample.write_text("import numpy as _np\nfrom mechopt.solvers.press.periodic import _hidden, steady_state\n")
    assert private_imports(sample) == ["mechopt.solvers.press.periodic._hidden"]


def test_the_methods_are_siblings_over_the_problem_module():
    """fixed_step, event_driven, periodic and scipy_peer import the problem and none of each other."""
    siblings = {"fixed_step", "event_driven", "periodic", "scipy_peer"}
    for name in siblings:
        tree = ast.parse((ROOT / "solvers" / "press" / f"{name}.py").read_text(encoding="utf-8"))
        modules = {n.module for n in ast.walk(tree) if isinstance(n, ast.ImportFrom) and n.module}
        assert "mechopt.solvers.press.problem" in modules, name
        assert not {f"mechopt.solvers.press.{s}" for s in siblings - {name}} & modules, name


def test_a_scene_reaches_the_method_through_its_settings(tmp_path):
    """`press.simulate` with `method` in the solver settings: one door, the Literal checked like
    any setting (a name outside it is refused, naming the allowed ones)."""
    from typing import get_args

    import pytest

    import mechopt
    from mechopt.solvers.press import METHODS, Method
    assert set(get_args(Method)) == set(METHODS)
    scene = tmp_path / "door.toml"
    base = ROOT / "cases" / "press" / "kd2322.toml"
    scene.write_text(f'id = "door"\ntitle = "the press by its door"\nsource = "test"\ntask = "press.PressDrive"\n'
                     f'solver = "press.simulate"\nbase = {{ scene = "{base}" }}\n\n'
                     f'[solver_settings]\nmethod = "steady_state"\n')
    run = mechopt.solve(str(scene))
    direct = mechopt.solvers.press.steady_state(run.task)
    assert run.status is mechopt.Status.SOLVED and run.result.message.startswith("periodic orbit")
    assert run.values["omega_mean_rad_s"] == pytest.approx(direct.values["omega_mean_rad_s"], rel=1e-9)
    with pytest.raises(mechopt.SceneError, match="method"):
        mechopt.solve(str(scene), method="radau")
