"""The cyclogram engine's old paths (under the loom's name) answer for one release: each old module
that moved whole is the engine's own module (so a monkeypatch through either reaches both); the two
that were split (models/loom.py, solvers/loom/plan.py) re-export every name they had, the same
objects; a scene saying `loom.Cyclogram` / `loom.plan_cyclogram` runs as one saying `cyclogram.*`."""
import importlib

import pytest

from mechopt.scene import loads

OLD_MODULES = {"mechopt.models.loom_motions": "mechopt.models.cyclogram_motions",
               **{f"mechopt.solvers.loom.{m}": f"mechopt.solvers.cyclogram.{m}"
                  for m in ("graph", "kernel", "event_time", "cycle_time", "motions", "speed")}}
# the public names the split modules had (models/loom.py, solvers/loom/plan.py before the split), less the
# three longest-path functions the LP path no longer has (graph.Levels' passes serve it)
OLD_NAMES = {
    "mechopt.models.loom": ("AMPLITUDE_LAWS", "LEAST_ANGLE", "MAX_CYCLES", "MAX_DEG", "MAX_MPA", "MAX_MS", "MAX_RPM",
                            "OPERATION_COLUMNS", "STRESS_FORMS", "SYNC_COLUMNS", "TASK_COLUMNS", "WINDOW_COLUMNS",
                            "Cyclogram", "amplitude_bound_deg", "amplitude_mm", "lever_stop", "stress_MPa",
                            "stress_bound_deg", "task_operations", "time_floor_deg"),
    "mechopt.solvers.loom.plan": ("LP_BUILDS", "MAX_CONFLICTS", "ONE_SIDED_STEP", "PER_NAME_MAX_OPS", "RANGING_MAX_OPS",
                                  "RANGING_MAX_TABLE", "SENSITIVITY_CONVENTION", "SENS_LIMITS", "Net", "back_arcs",
                                  "certified", "certify", "conflict_chain", "constraint_arcs", "float_array",
                                  "graph_floats", "limit_diagnostics", "one_sided_sensitivity", "per_name",
                                  "plan_arrays", "plan_cyclogram", "positive_cycle", "schedule_values",
                                  "set_parameters")}
NEW_HOMES = ("mechopt.models.cyclogram", "mechopt.models.cyclogram_bounds", "mechopt.models.cyclogram_motions",
             "mechopt.models.cyclogram_tables", "mechopt.models.loom_limits", "mechopt.solvers.cyclogram.certify",
             "mechopt.solvers.cyclogram.conflicts", "mechopt.solvers.cyclogram.graph_method",
             "mechopt.solvers.cyclogram.lp_method", "mechopt.solvers.cyclogram.net", "mechopt.solvers.cyclogram.plan",
             "mechopt.solvers.cyclogram.schedule")
ENGINE_NAMES = ("HeldLP", "build_event_time_lp", "conflict_chain", "incidence", "least_cycle_time", "max_machine_speed",
                "plan_cyclogram", "plan_motions", "positive_cycle")


@pytest.mark.parametrize("old, new", OLD_MODULES.items())
def test_an_old_module_path_is_the_engines_module(old, new):
    assert importlib.import_module(old) is importlib.import_module(new)


@pytest.mark.parametrize("old", OLD_NAMES)
def test_a_split_modules_old_path_gives_each_of_its_names_from_its_new_home(old):
    module = importlib.import_module(old)
    homes = [vars(importlib.import_module(m)) for m in NEW_HOMES]
    for name in OLD_NAMES[old]:
        value = getattr(module, name)
        assert any(home.get(name) is value for home in homes), name
    assert sorted(module.__all__) == (sorted(OLD_NAMES[old]) if old.endswith("plan") else ["Cyclogram"])


def test_the_loom_door_gives_the_engines_functions_and_keeps_its_own():
    from mechopt.solvers import cyclogram, loom
    assert all(getattr(loom, name) is getattr(cyclogram, name) for name in ENGINE_NAMES)
    assert set(cyclogram.__all__) == set(ENGINE_NAMES)
    assert {"repair_cyclogram", "codesign_machine_speed", "exact_amplitude_bound"} <= set(loom.__all__) - set(ENGINE_NAMES)
    assert loom.repair_cyclogram.__module__ == "mechopt.solvers.loom.repair"


SCENE = '''id = "my/four"
title = "four events"
source = "test"
task = "{wing}.Cyclogram"
solver = "{wing}.plan_cyclogram"
[params]
cycle_deg = 360
[structure]
operations = [{{from = "a", to = "b", min_deg = 30}}, {{from = "b", to = "d", min_deg = 50}},
              {{from = "a", to = "c", min_deg = 100}}, {{from = "c", to = "d", min_deg = 10}}]
'''


def test_a_scene_naming_the_loom_runs_as_one_naming_the_cyclogram(tmp_path):
    runs = {}
    for wing in ("loom", "cyclogram"):
        scene = loads(SCENE.format(wing=wing), tmp_path / f"{wing}.toml")
        assert scene.task_class.__name__ == "Cyclogram" and scene.solver.__name__ == "plan_cyclogram"
        runs[wing] = scene
    assert runs["loom"].task_class is runs["cyclogram"].task_class and runs["loom"].solver is runs["cyclogram"].solver
    result = runs["loom"].solver(runs["loom"].build()[0])
    assert result.success and result.values["span_deg"] == pytest.approx(110.0)      # a -> c -> d: 100 + 10
