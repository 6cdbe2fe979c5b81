"""The cyclogram engine's old paths (under the loom's name) answer for one release: each old module
is the engine's own module (so a monkeypatch through either reaches both), each old name the same
object, and a scene saying `loom.Cyclogram` / `loom.plan_cyclogram` runs as one saying `cyclogram.*`."""
import importlib

import pytest

from mechopt.scene import loads

OLD_MODULES = {"mechopt.models.loom": "mechopt.models.cyclogram",
               "mechopt.models.loom_motions": "mechopt.models.cyclogram_motions",
               **{f"mechopt.solvers.loom.{m}": f"mechopt.solvers.cyclogram.{m}"
                  for m in ("plan", "graph", "kernel", "event_time", "cycle_time", "motions", "speed")}}
ENGINE_NAMES = ("HeldLP", "build_event_time_lp", "conflict_chain", "incidence", "least_cycle_time", "max_machine_speed",
                "plan_cyclogram", "plan_motions", "positive_cycle")


@pytest.mark.parametrize("old, new", OLD_MODULES.items())
def test_an_old_module_path_is_the_engines_module(old, new):
    assert importlib.import_module(old) is importlib.import_module(new)


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
