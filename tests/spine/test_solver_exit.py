"""One exit per solver and one error kind for a bad setting: every solver returns the Result a
`Clock` builds (timed the same way everywhere), and a refused `method=` is a SettingError worded
as the scene loader words it (`method='x': allowed a, b, c`)."""
import ast
import time
from pathlib import Path

import pytest

import mechopt
from mechopt.kit.errors import SettingError
from mechopt.kit.result import Clock, Status, Timing

SOLVERS = Path(__file__).resolve().parents[2] / "solvers"


def _calls_and_names(path: Path):
    """(names called, names mentioned) in one module: `Result(...)` is a call of Result,
    `time.perf_counter` a mention of perf_counter."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    called, named = set(), set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Call):
            func = node.func
            called.add(func.id if isinstance(func, ast.Name) else getattr(func, "attr", ""))
        elif isinstance(node, ast.Name):
            named.add(node.id)
        elif isinstance(node, ast.Attribute):
            named.add(node.attr)
        elif isinstance(node, ast.alias):
            named.add(node.name)
    return called, named


def test_the_walk_sees_every_solver_module():
    modules = sorted(SOLVERS.rglob("*.py"))
    assert len(modules) >= 30 and SOLVERS / "press" / "design.py" in modules


@pytest.mark.parametrize("path", sorted(SOLVERS.rglob("*.py")), ids=lambda p: str(p.relative_to(SOLVERS)))
def test_no_solver_builds_a_result_or_times_itself(path):
    called, named = _calls_and_names(path)
    assert not {"Result", "Timing"} & called, f"{path.name}: return clock.result(...) (kit.result.Clock)"
    assert "perf_counter" not in named, f"{path.name}: time a phase with Clock().elapsed()"


def test_the_walk_would_see_a_hand_built_result():
    # the rule above can fail: a module written the old way is caught
    source = ("import time\nfrom mechopt.kit.result import Result, Status, Timing\n"
              "def solve(task):\n    start = time.perf_counter()\n"
              "    return Result(Status.SOLVED, {}, Timing(0.0, time.perf_counter() - start))\n")
    tree = ast.parse(source)
    calls = {n.func.id for n in ast.walk(tree) if isinstance(n, ast.Call) and isinstance(n.func, ast.Name)}
    attrs = {n.attr for n in ast.walk(tree) if isinstance(n, ast.Attribute)}
    assert {"Result", "Timing"} <= calls and "perf_counter" in attrs


def test_a_clock_splits_construction_from_the_rest():
    clock = Clock()
    time.sleep(0.002)
    clock.built()
    built = clock.build_s
    time.sleep(0.002)
    result = clock.result(Status.INFEASIBLE, {"x_mm": 1.5}, "why", ("limit",), {"k": 1}, warnings=("w",))
    assert result.timing.build_s == built > 0 and result.timing.solve_s > 0
    assert (result.status, result.values, result.message, result.violated, result.diagnostics, result.warnings) == \
        (Status.INFEASIBLE, {"x_mm": 1.5}, "why", ("limit",), {"k": 1}, ("w",))


def test_a_clock_without_a_build_counts_everything_as_solving():
    clock = Clock()
    timing = clock.timing()
    assert isinstance(timing, Timing) and timing.build_s == 0.0 and timing.solve_s >= 0.0


def test_a_build_counted_elsewhere_is_taken_as_given():
    clock = Clock()
    time.sleep(0.002)
    clock.build_s = 0.001          # a cache's own count of its build, or a sub-solve's
    clock.build_s += 0.0005
    timing = clock.timing()
    assert timing.build_s == 0.0015 and timing.solve_s >= 0.0005


def test_a_clock_does_not_make_a_status():
    # the solver's status is passed on as it is: never SOLVED for an answer that is not
    assert Clock().result(Status.LIMIT, {}).status is Status.LIMIT


def _task(scene_id):
    return mechopt.load(scene_id).build()[0]


# every dispatcher of the package, its door and what it allows, in its signature's order
DISPATCHERS = [
    ("press.simulate", "press/kd2322", "rk4, events, steady_state, ivp"),
    ("press.ivp", "press/kd2322", "Radau, LSODA, DOP853, RK45, BDF"),
    ("cam_cutter.fit_linkage", "cam-cutter/paper-grid", "grid_scan, minimax, robust, evolve"),
    ("stop_impact.rebound", "stop-impact/rebound-177rpm", "closed_form, quadrature, ode"),
    ("loom.plan_cyclogram", "loom/group1", "graph, lp"),
    ("loom.max_machine_speed", "loom/machine-speed", "auto, graph, lp, bisection"),
]


@pytest.mark.parametrize("solver, scene_id, allowed", DISPATCHERS, ids=[d[0] for d in DISPATCHERS])
def test_a_bad_method_is_a_setting_error_in_one_wording(solver, scene_id, allowed):
    import importlib
    package, name = solver.split(".")
    door = getattr(importlib.import_module(f"mechopt.solvers.{package}"), name)
    with pytest.raises(SettingError, match=rf"^method='newton': allowed {allowed}$") as err:
        door(_task(scene_id), method="newton")
    assert err.value.key == "method"


@pytest.mark.parametrize("solver, settings, key", [
    ("press.events", {"tol": 0.0}, "tol"),
    ("press.events", {"samples": 0}, "samples"),
    ("press.rk4", {"step_s": -1e-4}, "step_s"),
    ("press.steady_state", {"tol": -1.0}, "tol"),
    ("press.ivp", {"duration_s": 0.0}, "duration_s"),
])
def test_a_press_setting_out_of_its_declared_range_is_a_setting_error(solver, settings, key):
    # the range the signature declares is the one checked (as a scene's is), not a copy of it
    import importlib
    package, name = solver.split(".")
    run = getattr(importlib.import_module(f"mechopt.solvers.{package}"), name)
    with pytest.raises(SettingError, match=rf"^{key}=\S+: allowed ") as err:
        run(_task("press/kd2322"), **settings)
    assert err.value.key == key
