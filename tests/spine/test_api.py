"""The public Python API and scenes from anywhere: a designer's own scene files, outside the
package, loaded by path or from a folder added to the registry."""
import os
import re
import subprocess
import sys
from pathlib import Path

import networkx as nx
import numpy as np
import pytest
from matplotlib.figure import Figure

import mechopt
from mechopt import registry
from mechopt.cli import main, scene_template

ROOT = Path(__file__).resolve().parents[2]

SIX_EVENTS = '''id = "my/loom-six"
title = "A loom group of my own: six events"
source = "a designer's own network (test)"
task = "loom.Cyclogram"
solver = "loom.plan_cyclogram"
effects = ["contact_stress", "stop_vibration"]

[params]
amplitude_slope_mm_per_deg = -0.003
amplitude_intercept_mm = 0.208
amplitude_limit_mm = 0.1
sigma_H_limit_MPa = { value = 800.0, mark = "assumed", why = "a hardened steel cam" }

[structure.events]
"1" = { mechanism = "lift", group = "mine", what = "start" }
"2" = { mechanism = "returner", group = "mine", what = "returner starts" }
"3" = { mechanism = "lift", group = "mine", what = "lift leaves its lower stop" }
"4" = { mechanism = "lift", group = "mine", what = "lift at its upper stop" }
"5" = { mechanism = "returner", group = "mine", what = "weft presented" }
"6" = { mechanism = "returner", group = "mine", what = "done" }

[structure.stress_models]
lift_cam = { sigma_ref_MPa = 700.0, t_ref_deg = 36.0, mark = "assumed", why = "test" }

[[structure.operations]]
from = "1"
to = "2"
min_deg = 10.0
[[structure.operations]]
from = "1"
to = "3"
min_deg = 20.0
[[structure.operations]]
from = "3"
to = "4"
min_deg = 30.0
stress = "lift_cam"
amplitude = "linear"
[[structure.operations]]
from = "2"
to = "5"
min_deg = 40.0
[[structure.operations]]
from = "4"
to = "6"
min_deg = 10.0
[[structure.operations]]
from = "5"
to = "6"
min_deg = 5.0
'''


def copy_scene(case_id, folder, new_id, replace=()):
    """A registry scene as a user's starting point (`mechopt new`: new id, the source's
    expectations dropped) in `folder`, with text replacements."""
    text = scene_template(registry.find(case_id), new_id)
    for old, new in replace:
        assert old in text, old
        text = text.replace(old, new)
    path = folder / f"{new_id.replace('/', '_')}.toml"
    path.write_text(text, encoding="utf-8")
    return path


@pytest.fixture
def own(tmp_path, monkeypatch):
    """A folder of a designer's own scenes, outside the package: another cardioid, a six-event
    loom group, a press with another flywheel; the registry is restored afterwards."""
    folder = tmp_path / "my-scenes"
    folder.mkdir()
    copy_scene("cam-cutter/pure-cardioid", folder, "my/cardioid-30", [("a_mm = { value = 25.0", "a_mm = { value = 30.0")])
    (folder / "loom-six.toml").write_text(SIX_EVENTS, encoding="utf-8")
    copy_scene("press/kd2322", folder, "my/press-heavy-flywheel",
               [("flywheel_inertia_kgm2 = { value = 5.0", "flywheel_inertia_kgm2 = { value = 7.5")])
    monkeypatch.setattr(registry, "_USER_FOLDERS", [])
    mechopt.clear_caches()
    yield folder
    mechopt.clear_caches()


def test_a_scene_file_outside_the_package_runs_by_its_path(own):
    run = mechopt.solve(own / "my_cardioid-30.toml")
    # a pure cardioid is followed exactly by H = L = 2a: 60 mm for a = 30 mm
    assert run.status is mechopt.Status.SOLVED
    assert run.values["H_mm"] == pytest.approx(60.0, abs=1e-6) and run.values["L_mm"] == pytest.approx(60.0, abs=1e-6)


def test_a_loom_group_of_my_own_is_planned_to_its_longest_path(own):
    run = mechopt.solve(own / "loom-six.toml")
    # independent: the amplitude law binds t(3,4) at (0.208 - 0.1) / 0.003 = 36 deg; longest path 1-3-4-6
    g = nx.DiGraph([("1", "2", {"w": 10}), ("1", "3", {"w": 20}), ("3", "4", {"w": 36}), ("2", "5", {"w": 40}),
                    ("4", "6", {"w": 10}), ("5", "6", {"w": 5})])
    assert run.status is mechopt.Status.SOLVED
    assert run.values["span_deg"] == pytest.approx(nx.dag_longest_path_length(g, weight="w"), abs=1e-6)


def test_a_press_with_another_flywheel_turns_more_evenly(own):
    base, heavy = mechopt.solve("press/kd2322"), mechopt.solve(own / "my_press-heavy-flywheel.toml")
    assert heavy.status is mechopt.Status.SOLVED
    # more inertia, less fluctuation; but never below 2/3 of it (the ratio of flywheels alone:
    # motor, crank and the elastic belt's share do not grow with the flywheel)
    ratio = heavy.values["speed_fluctuation"] / base.values["speed_fluctuation"]
    assert 2 / 3 < ratio < 0.95


def test_a_users_folder_joins_the_registry_and_a_bad_file_is_named_not_fatal(own, capsys):
    (own / "broken.toml").write_text('id = "my/broken"\ntitle = 3\n', encoding="utf-8")
    mechopt.add_cases(own)
    catalogue = registry.catalogue()
    ids = {s.id for s in catalogue.scenes}
    assert {"my/cardioid-30", "my/loom-six", "my/press-heavy-flywheel", "cam-cutter/minimax"} <= ids
    assert len(catalogue.problems) == 1 and "broken.toml" in catalogue.problems[0]
    assert main(["cases", "--cases", str(own)]) == 0
    assert "warning: skipped" in capsys.readouterr().err


def test_the_environment_variable_adds_a_folder_too(own, monkeypatch):
    monkeypatch.setenv("MECHOPT_CASES", str(own))
    assert mechopt.load("my/loom-six").path == own / "loom-six.toml"
    monkeypatch.setenv("MECHOPT_CASES", str(own / "nowhere"))
    with pytest.raises(mechopt.SceneError, match="MECHOPT_CASES: no such folder .*nowhere"):
        registry.catalogue()


def test_a_users_scene_may_not_take_a_registry_id(own):
    copy_scene("loom/group1", own, "loom/group1")
    mechopt.add_cases(own)
    problems = registry.catalogue().problems
    assert any("id 'loom/group1' is already taken" in p for p in problems)


def test_validate_and_report_take_a_folder(own, tmp_path, capsys):
    assert main(["validate", str(own)]) == 0
    out = capsys.readouterr().out
    assert "scenes with no expectations" in out and "my/loom-six" in out
    assert main(["report", "--cases", str(own), "--case", str(own), "--out", str(tmp_path / "rep"),
                 "--bench", str(tmp_path / "none")]) == 0
    page = (tmp_path / "rep" / "index.html").read_text(encoding="utf-8")
    assert "my/cardioid-30" in page and "my/loom-six" in page and "my/press-heavy-flywheel" in page


def test_new_writes_a_commented_scene_that_runs_and_never_overwrites(tmp_path, capsys):
    path = tmp_path / "mine.toml"
    assert main(["new", "loom", str(path)]) == 0
    text = path.read_text(encoding="utf-8")
    assert text.startswith("# A scene of your own") and 'id = "my/mine"' in text
    assert not re.search(r"^\[expect", text, flags=re.M)
    assert main(["run", str(path)]) == 0
    before = path.read_text(encoding="utf-8")
    assert main(["new", "press", str(path)]) == 2
    assert "exists" in capsys.readouterr().err and path.read_text(encoding="utf-8") == before


def test_describe_lists_every_key_with_unit_mark_range_and_value(capsys):
    rows = {r["key"]: r for r in mechopt.describe("press/kd2322")}
    assert rows["flywheel_inertia_kgm2"]["unit"] == "kg m²" and rows["flywheel_inertia_kgm2"]["mark"] == "assumed"
    assert rows["tol"]["range"] == "> 0 ... 0.1" and rows["tol"]["value"] == "1e-10"
    assert rows["kinematics"]["kind"] == "structure"
    assert main(["describe", "press/kd2322"]) == 0
    assert "samples" in capsys.readouterr().out


def test_the_result_carries_its_arrays_and_its_figures_need_no_files(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    run = mechopt.solve("press/kd2322")
    t, w = run.arrays["t_s"], run.arrays["omega_rad_s"]
    assert t.shape == w.shape and t[0] == 0 and not t.flags.writeable
    # one revolution of the periodic orbit: the mean speed is 2 pi / period
    assert np.trapezoid(w, t) / (t[-1] - t[0]) == pytest.approx(run.values["omega_mean_rad_s"], rel=1e-3)
    figures = run.figures()
    assert list(figures) == ["cycle"] and isinstance(figures["cycle"], Figure)
    assert list(tmp_path.iterdir()) == []
    assert run.with_units()["peak_belt_torque_Nm"][1] == "N m"


def test_overrides_reach_structure_entries_and_dotted_event_names():
    run = mechopt.solve("loom/machine", {"operations[from=10.1,to=10.2].min_deg": 5.0})
    assert run.status is mechopt.Status.SOLVED and not run.checks
    assert mechopt.solve("stop-impact/rebound-177rpm", speeds_rpm=[150, 177]).values.keys() >= {
        "rebound_mm_150", "rebound_mm_177"}
    assert mechopt.solve("press/kd2322", kinematics="exact").status is mechopt.Status.SOLVED


def test_version_on_the_package_the_command_and_python_m():
    assert re.fullmatch(r"\d+\.\d+\.\d+.*", mechopt.__version__)
    out = subprocess.run([sys.executable, "-m", "mechopt", "--version"], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == f"mechopt {mechopt.__version__}"


def test_readme_python_examples_run(tmp_path, monkeypatch):
    # the front door's examples and those of the manual it links to (docs/commands.md)
    text = "\n".join((ROOT / page).read_text(encoding="utf-8") for page in ("README.md", "docs/commands.md"))
    blocks = re.findall(r"```python\n(.*?)```", text, flags=re.S)
    assert len(blocks) >= 5                       # the front door's, and one per mechanism at least
    monkeypatch.chdir(tmp_path)
    for block in blocks:
        exec(compile(block, "README.md", "exec"), {"__name__": "readme"})


def test_importing_from_the_repository_root_gives_the_installed_package():
    code = "import mechopt.models, mechopt.solvers, mechopt; print(mechopt.__file__)"
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True,
                         env={**os.environ, "PYTHONPATH": ""})
    assert out.returncode == 0, out.stderr
    assert Path(out.stdout.strip()).parent.name == "mechopt"


def test_one_door_per_question_takes_method():
    from mechopt.solvers.cam_cutter import fit_linkage
    from mechopt.solvers.press import simulate
    cam, _ = mechopt.load("cam-cutter/paper-grid").build()
    by_grid, by_nlp = fit_linkage(cam, method="grid_scan"), fit_linkage(cam, method="minimax")
    # the NLP's optimum is no worse than any lattice point the scan accepts
    assert by_nlp.values["max_deviation_mm"] <= by_grid.values["max_deviation_mm"] + 1e-12
    with pytest.raises(mechopt.SceneError, match=r"method='newton': allowed grid_scan, minimax, robust, evolve"):
        fit_linkage(cam, method="newton")
    press, _ = mechopt.load("press/kd2322").build()
    with pytest.raises(mechopt.SceneError, match=r"method='euler': allowed rk4, events, steady_state, ivp"):
        simulate(press, method="euler")


@pytest.mark.parametrize("name, unit, words", [("err_width_mm", "mm", "err width [mm]"),
                                              ("belt_stiffness_Nm_rad", "N m/rad", "belt stiffness [N m/rad]"),
                                              ("speed_fluctuation", "", "speed fluctuation"),
                                              ("c_stop_N_per_mm", "N/mm", "c stop [N/mm]")])
def test_units_are_read_from_names_and_axes_say_them(name, unit, words):
    from mechopt.units import label, unit_of
    assert unit_of(name) == unit and label(name) == words


def test_a_calibration_typo_in_a_users_scene_is_named_and_the_others_load(own):
    text = SIX_EVENTS.replace('id = "my/loom-six"', 'id = "my/typo"').replace(
        'sigma_H_limit_MPa = { value = 800.0, mark = "assumed", why = "a hardened steel cam" }',
        'sigma_H_limit_MPa = { value = 800.0, mark = "calibrated", on = "spam_deg", why = "fitted" }')
    (own / "typo.toml").write_text(text, encoding="utf-8")
    mechopt.add_cases(own)
    catalogue = registry.catalogue()
    assert any("typo.toml: params.sigma_H_limit_MPa.on = 'spam_deg'" in p for p in catalogue.problems)
    assert "my/loom-six" in {s.id for s in catalogue.scenes} and "my/typo" not in {s.id for s in catalogue.scenes}


def test_a_press_of_ones_own_takes_the_registry_press_as_its_base(tmp_path):
    """`base = { scene = ... }`: the press and its data from one file, only the question's changes
    here; `mechopt new`-style copies of a scene with a base still find it from elsewhere."""
    heavy = copy_scene("press/start-up", tmp_path, "my/heavy-start",
                       [('flywheel_inertia_kgm2 = { value = 5.0, mark = "assumed", why = "your value" }',
                         'flywheel_inertia_kgm2 = { value = 7.5, mark = "assumed", why = "a heavier flywheel" }')])
    assert 'scene = "/' in heavy.read_text(encoding="utf-8")            # the base's path made absolute
    task, _ = mechopt.load(heavy).build()
    source, _ = mechopt.load("press/start-up").build()
    assert task.flywheel_inertia_kgm2 == 7.5 and source.flywheel_inertia_kgm2 == 5.0
    assert task.tool_mass_kg == source.tool_mass_kg            # the rest from the base
    rows = {r["key"]: r for r in mechopt.describe(heavy)}
    # the copy's values are the user's: a calibration of the source's is to be re-derived, not trusted
    assert rows["tool_mass_kg"]["mark"] == "assumed" and rows["gear_ratio"]["mark"] == "assumed"


def test_a_base_that_drops_what_it_does_not_have_is_named(tmp_path):
    path = copy_scene("press/kd2322-rigid-belt", tmp_path, "my/rigid",
                      [('drop = ["belt_stiffness_Nm_rad", "belt_damping_Nms_rad"]', 'drop = ["belt_colour"]')])
    with pytest.raises(mechopt.SceneError, match=r"base\.drop: belt_colour not in .*kd2322\.toml"):
        mechopt.load(path)


def test_status_is_true_only_when_solved_and_success_says_so_as_scipy_does():
    from mechopt import Status
    assert [s for s in Status if s] == [Status.SOLVED]
    run = mechopt.solve("press/flywheel-design")
    assert run.success is run.result.success is True and run.status


def test_a_what_if_with_no_checks_is_not_ok_when_it_finds_no_answer():
    tight = mechopt.solve("loom/group1", cycle_deg=100.0)          # the chain of minimum spans needs more
    assert tight.status is mechopt.Status.INFEASIBLE and not tight.checks
    assert not tight.success and not tight.ok and not tight.status
    # a scene that asks whether its network is feasible expects INFEASIBLE: that answer is the one asked for
    conflict = mechopt.solve("loom/group1-window-conflict", amplitude_limit_mm=0.12)
    assert conflict.status is mechopt.Status.INFEASIBLE and not conflict.checks
    assert conflict.ok and not conflict.success


def test_run_and_result_show_compactly_in_a_notebook():
    run = mechopt.solve("press/flywheel-design")
    text = repr(run)
    assert len(text) < 400 and "press/flywheel-design" in text and "SOLVED" in text and "5/5 checks pass" in text
    assert repr(run.result).startswith("Result(SOLVED, values={") and "more}" in repr(run.result)
    page = run._repr_html_()
    inertia = run.values["flywheel_inertia_kgm2"]
    shown = f"{inertia:.6g}"                            # as the command prints it
    assert round(inertia, 3) == 5.118                  # the least flywheel
    assert f"<td>flywheel_inertia_kgm2</td><td title='{inertia!r}'>{shown}</td><td>kg m²</td><td>computed</td>" in page
    assert f"<td>flywheel_inertia_kgm2</td><td title='{inertia!r}'>{shown}</td>" in run.result._repr_html_()
    assert "<td>speed_fluctuation</td>" in page and "<td>derived</td>" in page        # a checked value says so


def test_sweep_takes_an_id_and_a_dict_grid_as_solve_does():
    table = mechopt.sweep("loom/group1", grid={"amplitude_limit_mm": (0.05, 0.2, 3)})
    assert table.column("amplitude_limit_mm").to_pylist() == [0.05, 0.125, 0.2]
    assert set(table.column("status").to_pylist()) <= {"SOLVED", "INFEASIBLE"}
    assert mechopt.sweep.parse_grid("a_mm=1:2:2").num == 2               # still the module of the machinery
    with pytest.raises(mechopt.SceneError, match=r"grid\['amplitude_limit_mm'\] = \(0.2, 0.05, 3\): 0.2 > 0.05"):
        mechopt.sweep("loom/group1", grid={"amplitude_limit_mm": (0.2, 0.05, 3)})
    with pytest.raises(mechopt.SceneError, match=r"num = 2.5; expected a whole number"):
        mechopt.sweep("loom/group1", grid={"amplitude_limit_mm": (0.05, 0.2, 2.5)})


def test_errors_of_the_python_api_name_the_key_not_the_command_lines_flag():
    with pytest.raises(mechopt.SceneError, match="a_m: unknown key; parameters: ") as caught:
        mechopt.solve("loom/group1", a_m=3)
    assert "--set" not in str(caught.value) and caught.value.key == "a_m"
    with pytest.raises(mechopt.SceneError, match=r"operations\[from=1,to=9\]\.min_deg: .*matches 0 entries") as caught:
        mechopt.solve("loom/group1", {"operations[from=1,to=9].min_deg": 3.0})
    assert "--set" not in str(caught.value)


def test_plot_of_a_run_with_no_solution_says_why_nothing_was_drawn(tmp_path, capsys):
    assert main(["run", "loom/group1", "--set", "cycle_deg=100", "--plot", str(tmp_path / "figs")]) == 3
    err = capsys.readouterr().err
    assert f"plot: nothing drawn into {tmp_path / 'figs'} (status INFEASIBLE: no solution to draw)" in err


def test_progress_goes_to_stderr_a_line_a_scene_off_a_terminal_and_quiet_silences_it(capsys):
    assert main(["validate", "loom/group1", "cam-cutter/minimax"]) == 0
    said = capsys.readouterr()
    assert "running loom/group1 ...\nrunning cam-cutter/minimax ...\n" in said.err and "running" not in said.out
    assert main(["validate", "--quiet", "loom/group1"]) == 0
    assert "running" not in capsys.readouterr().err


def test_a_template_makes_every_value_the_users_own_and_says_a_calibration_must_be_redone(tmp_path):
    path = tmp_path / "drive.toml"
    assert main(["new", "press-design", str(path)]) == 0
    mine = registry.find(str(path))
    source = registry.find("press/flywheel-design")
    assert mine.spec.params.keys() == source.spec.params.keys()
    assert {p.mark for p in mine.spec.params.values()} == {"assumed"}
    assert all(p.why.startswith("your value") for p in mine.spec.params.values())
    assert mine.params() == source.params()                               # the same numbers, the user's now
    gear = mine.spec.params["gear_ratio"]
    assert source.spec.params["gear_ratio"].mark == "calibrated"
    assert "re-derive it when its inputs change" in gear.why and "omega_mean_rad_s" in gear.why
    assert not mine.spec.expect


def test_a_cam_of_ones_own_as_a_point_table_runs_from_its_template(tmp_path):
    path = tmp_path / "cam.toml"
    assert main(["new", "cam-table", str(path)]) == 0
    table = (tmp_path / "cam-points.csv").read_text(encoding="utf-8").splitlines()
    assert table[0] == "x_mm,y_mm" and len(table) == 38 and table[1] == "54.0000,0.0000"   # r = 50 + 4 at theta 0
    assert "x_expr" not in path.read_text(encoding="utf-8")
    run = mechopt.solve(str(path))
    assert run.success and len(run.task.points_mm) == 37
    assert main(["new", "cam-table", str(path.with_name("other.toml"))]) == 0     # beside it: its own table


# bounds set by other parameters (a_mm, H, L): the model checks them
RELATIVE = {"H_min_mm", "H_max_mm", "L_min_mm", "L_max_mm", "crank_centre_mm", "link_centre_mm"}


def test_a_range_relative_to_another_input_is_shown_as_declared():
    rows = {r["key"]: r for r in mechopt.describe("cam-cutter/paper-grid")}
    assert rows["H_min_mm"]["range"] == "> 0 ... 100 a_mm"
    assert all(not r["range"].startswith("checked by") for r in mechopt.describe("cam-cutter/joint-reactions")
               if r["kind"] == "parameter")


@pytest.mark.parametrize("scene", mechopt.scenes(), ids=lambda s: s.id)
def test_describe_shows_the_declared_range_of_every_number(scene):
    """Ranges are declared on the model's fields (Annotated): describe and the loader read them there."""
    from mechopt.kit.settings import declared_range
    from mechopt.scene import task_fields
    fields = task_fields(scene.task_class)
    for row in scene.describe():
        if row["kind"] != "parameter" or row["key"] in RELATIVE or "float" not in str(fields[row["key"]].type):
            continue
        assert not row["range"].startswith("checked by"), (scene.id, row["key"])
        low, high = declared_range(fields[row["key"]].type)
        value = scene.spec.params[row["key"]].value if row["key"] in scene.spec.params else None
        if value is not None:                                      # the scene's own value is inside it
            assert (not low or low[1](value, low[0])) and (not high or high[1](value, high[0]))


def test_describe_prints_structure_paths_whole_and_each_values_why(capsys):
    assert main(["describe", "loom/group1"]) == 0
    out = capsys.readouterr().out
    assert "operations[from=1,to=2].min_deg " in out
    sigma = next(line for line in out.splitlines() if line.startswith("sigma_H_limit_MPa "))
    assert "> 0 ... 1e+06" in sigma and "a usual allowable Hertz stress" in sigma
    with pytest.raises(mechopt.SceneError, match=r"params.sigma_H_limit_MPa=-1.0: allowed > 0 ... 1e\+06"):
        mechopt.solve("loom/group1", sigma_H_limit_MPa=-1.0)


def test_a_table_names_its_rows_in_a_label_column(tmp_path):
    run = mechopt.solve("press/sensitivity")
    names = list(run.arrays["parameter"])
    assert names == run.result.diagnostics["parameters"] and "flywheel_inertia_kgm2" in names
    assert len(run.arrays["elasticity_speed_fluctuation"]) == len(names)
    out = tmp_path / "sens.csv"
    assert main(["run", "press/sensitivity", "--csv", str(out)]) == 0
    lines = out.read_text(encoding="utf-8").splitlines()
    header = lines[0].split(",")
    assert header[0] == "parameter" and lines[1].split(",")[0] == names[0] and len(lines) == len(names) + 1
    row = dict(zip(header, lines[1 + names.index("flywheel_inertia_kgm2")].split(",")))
    assert float(row["elasticity_speed_fluctuation"]) == pytest.approx(
        run.values["speed_fluctuation_elasticity_flywheel_inertia_kgm2"], rel=1e-9)


@pytest.mark.parametrize("bounds, message", [((float("nan"), 0.2, 2), r"nan is not a finite number"),
                                             ((0.1, 1e300, 2), r"1e\+300 is beyond")])
def test_an_api_sweep_axis_meets_the_command_lines_rule(bounds, message):
    # the API's axis ends pass the --grid rule (sweep.axis_value_problem) before any variant is solved
    with pytest.raises(mechopt.SceneError, match=message):
        mechopt.sweep("loom/group1", grid={"amplitude_limit_mm": bounds})
