"""The registry: every scene reproduces its source, bad scenes are refused by name, the CLI speaks JSON."""
import json
import shutil
from pathlib import Path

import pytest

import mechopt
from mechopt import registry, verdicts
from mechopt.cli import main
from mechopt.figures import plot_run
from mechopt.kit.errors import SceneError
from mechopt.kit.result import Status
from mechopt.scene import load, parse_overrides
from mechopt.solvers.cam_cutter.deviation import verified_deviation

GOOD = registry.cases_dir() / "cam-cutter" / "paper-grid.toml"


@pytest.mark.parametrize("scene", registry.all_scenes(), ids=lambda s: s.id)
def test_scene_reproduces_its_expectations(scene, solved_once):
    run = registry.run(scene)
    failed = [f"{c.name}: got {c.got}, expected {c.expected} ({c.kind}, {c.where})" for c in run.checks if not c.ok]
    assert not failed, f"{scene.id} ({scene.spec.source}): " + "; ".join(failed)
    assert run.checks, f"{scene.id} checks nothing"


def test_minimax_bound_is_the_paper_linkages_own_deviation():
    # the scene's bound must be the published linkage measured by the same dense check
    bound = registry.find("cam-cutter/minimax").spec.expect["max_deviation_mm"].max
    task, _ = registry.find("cam-cutter/minimax").build()
    paper, _ = verified_deviation(task.a_mm, task.h_mm, 59.45, 47.52, task.t_finish_rad)
    assert paper == pytest.approx(bound, abs=1e-7)


def _edited(tmp_path, old, new, name="bad.toml"):
    text = GOOD.read_text()
    assert old in text, old
    path = tmp_path / name
    path.write_text(text.replace(old, new, 1))
    return path


@pytest.mark.parametrize("old, new, match", [
    ('title = ', 'colour = "red"\ntitle = ', r"bad\.toml: colour: unknown key; allowed: id, title"),
    ('a_mm = { value = 25.0,', 'a_mm = { value = "x",', r"bad\.toml: params\.a_mm='x': expected a number"),
    ('a_mm = { value = 25.0, mark = "given", where = "Sec. IV: a = 25 mm" }\n', '', r"bad\.toml: params: missing a_mm"),
    ('a_mm = { value = 25.0,', 'a_mm = { value = -25.0,', r"bad\.toml: params\.a_mm=-25\.0: allowed 1e-06 \.\.\. 1e\+06"),
    ('H_max_mm = { value = 65.0,', 'H_max_mm = { value = 50.0,', r"params\.H_min_mm: bounds reversed: H_min_mm=55\.0 > H_max_mm=50\.0"),
    ('H_min_mm = { value = 55.0,', 'H_min_mm = { value = -5.0,', r"params\.H_min_mm=-5\.0: allowed > 0 \.\.\. 100 a_mm = 2500"),
    ('abs = 0.005', 'abs = 0.0', r"expect\.H_mm\.abs: Input should be greater than 0"),
    ('abs = 0.005', 'rel = -1.0', r"expect\.H_mm\.rel: Input should be greater than 0"),
    ('value = 59.45\nabs = 0.005', 'value = 59.45', r"expect\.H_mm: .*needs a tolerance"),
    ('kind = "published"', 'kind = "rumoured"', r"expect\.H_mm\.kind: Input should be 'published', 'experimental', 'derived' or 'follows'"),
    ('effects = ["torch_offset"]', 'effects = ["torch_offset", "wind"]', r"effects: unknown \['wind'\]; LinkageFit knows torch_offset"),
    ('effects = ["torch_offset"]', 'effects = []', r"params\.h_mm belongs to effect 'torch_offset'"),
    ('solver = "cam_cutter.grid_scan"', 'solver = "cam_cutter.grid_scna"',
     r"unknown solver 'cam_cutter\.grid_scna'; known: cam_cutter\.grid_scan, cam_cutter\.minimax"),
    ('task = "cam_cutter.LinkageFit"', 'task = "cam_cutter.LinkageFix"', r"unknown task 'cam_cutter\.LinkageFix'; known: cam_cutter\.LinkageFit"),
    ('task = "cam_cutter.LinkageFit"', 'task = "nowhere.LinkageFit"', r"no module mechopt\.models\.nowhere"),
    ('count = 1000 ', 'count = "many" ', r"solver_settings\.count='many': expected int"),
    ('count = 1000 ', 'cuont = 1000 ', r"solver_settings\.cuont: unknown setting of grid_scan; allowed: count, nodes"),
    ('nodes = "half_open"', 'nodes = "both"', r"solver_settings\.nodes='both': allowed half_open, closed, open_start"),
    ('mark = "assumed", why = "LOW_H is an input the paper does not print; a 10 mm box around its answer"',
     'mark = "assumed"', r"params\.H_min_mm: Value error, a parameter marked 'assumed' needs a 'why'"),
    ('id = ', 'id = = ', r"bad\.toml: not valid TOML"),
    ('[solver_settings]', '[structure]\nnetwork = []\n\n[solver_settings]',
     r"bad\.toml: structure\.network: unknown or given twice; LinkageFit takes nothing more"),
])
def test_bad_scene_is_refused_naming_file_key_and_what_is_allowed(tmp_path, old, new, match):
    with pytest.raises(SceneError, match=match):
        load(_edited(tmp_path, old, new))


@pytest.fixture
def cases_in(tmp_path, monkeypatch):
    """The registry reading its scenes from tmp_path (restored afterwards)."""
    monkeypatch.setattr(registry, "cases_dir", lambda: tmp_path)
    mechopt.clear_caches()
    yield tmp_path
    mechopt.clear_caches()


def test_duplicate_ids_are_refused(cases_in):
    for name in ("a", "b"):
        (cases_in / name).mkdir()
        shutil.copy(GOOD, cases_in / name / "x.toml")
    with pytest.raises(SceneError, match=r"scene ids used twice: cam-cutter/paper-grid"):
        registry.all_scenes()


def test_override_is_validated_like_the_file_and_changes_nothing():
    scene = registry.find("cam-cutter/minimax")
    before = scene.params()
    with pytest.raises(SceneError, match=r"colour: unknown key; parameters: a_mm, .*; solver settings: count"):
        registry.run(scene, {"colour": 1})
    with pytest.raises(SceneError, match=r"params\.err_width_mm=-1: allowed > 0"):
        registry.run(scene, {"err_width_mm": -1})
    with pytest.raises(SceneError, match=r"solver_settings\.count=2\.5: expected int"):
        registry.run(scene, {"count": 2.5})
    assert scene.params() == before


def test_parameter_override_skips_the_sources_checks_but_a_setting_override_keeps_them():
    what_if = registry.run(registry.find("cam-cutter/minimax"), {"a_mm": 40.0, "h_mm": 3.0})
    assert what_if.checks == [] and what_if.result.values["H_mm"] > 80      # a different cardioid
    coarse = registry.run(registry.find("cam-cutter/paper-grid"), {"count": 100})
    assert coarse.checks and coarse.ok                                      # COUNT 100 still gives 59.45/47.52


def test_parse_overrides_reads_toml_literals_else_text():
    assert parse_overrides(["a_mm=40", "h_mm=3.5", "nodes=closed", "x=true"]) == \
        {"a_mm": 40, "h_mm": 3.5, "nodes": "closed", "x": True}
    with pytest.raises(SceneError, match=r"expected KEY=VALUE"):
        parse_overrides(["a_mm"])


def test_cli_run_writes_the_documented_json(tmp_path):
    out = tmp_path / "r.json"
    assert main(["run", "cam-cutter/paper-grid", "--json", str(out), "--plot", str(tmp_path)]) == 0
    data = json.loads(out.read_text())
    assert {"case", "status", "values", "checks", "timing"} <= data.keys()
    assert data["values"]["H_mm"] == pytest.approx(59.45) and data["status"] == "SOLVED"
    assert {"name", "expected", "got", "tol", "ok"} <= data["checks"][0].keys()
    assert {"build_s", "solve_s"} == data["timing"].keys()
    assert (tmp_path / "cam-cutter_paper-grid_paths.png").stat().st_size > 10_000


def test_cli_validate_passes_and_reports_every_check(tmp_path, capsys, solved_once):
    out = tmp_path / "v.json"
    assert main(["validate", "--json", str(out)]) == 0
    runs = json.loads(out.read_text())
    assert {r["case"] for r in runs} == {s.id for s in registry.all_scenes()}
    printed = capsys.readouterr().out
    assert f"{sum(len(r['checks']) for r in runs)} passed, 0 failed" in printed
    checks = [c for r in runs for c in r["checks"]]
    assert all(c["verdict"] in verdicts.VERDICTS for c in checks)
    summary = next(line for line in printed.splitlines() if line.startswith(f"{len(checks)} checks: "))
    counts = {v: sum(c["verdict"] == v for c in checks) for v in verdicts.VERDICTS}
    assert f"{counts['reproduced']} reproduced" in summary and f"{counts['derived']} derived" in summary
    # the README states the same counts: it must not drift from the registry
    readme = " ".join((Path(__file__).parents[2] / "README.md").read_text(encoding="utf-8").split())
    assert f"Today: `{summary}`" in readme


def test_cli_names_an_unknown_case_and_exits_2(capsys):
    assert main(["run", "cam-cutter/minimx"]) == 2
    assert "did you mean cam-cutter/minimax" in capsys.readouterr().err


def test_infeasible_grid_scan_reports_the_best_achievable_not_a_grid_point():
    run = registry.run(registry.find("cam-cutter/paper-grid"), {"nodes": "closed"})
    assert run.result.status is Status.INFEASIBLE and "H_mm" not in run.result.values
    assert 0.05 < run.result.values["best_deviation_mm"] < 0.075
    assert not run.ok      # the published H, L are not reproduced under this node rule


def test_ci_runs_exactly_the_readme_test_command():
    root = Path(__file__).resolve().parents[2]
    readme_test_line = (root / "README.md").read_text().split("```bash\n", 1)[1].splitlines()[1]
    assert readme_test_line in (root / ".ci" / "run").read_text().splitlines()


def test_cvxpy_status_words_map_without_passing_inaccurate_as_optimal():
    from mechopt.kit.result import from_cvxpy
    assert from_cvxpy("optimal") is Status.SOLVED
    assert from_cvxpy("optimal_inaccurate") is Status.INACCURATE
    assert from_cvxpy("infeasible") is Status.INFEASIBLE and from_cvxpy("solver_error") is Status.FAILED


def test_a_calibrated_parameter_names_its_figure_and_that_check_is_marked(tmp_path):
    with pytest.raises(SceneError, match=r"params\.H_min_mm: Value error, 'on' \(the value a parameter was fitted to\)"):
        load(_edited(tmp_path, 'mark = "assumed", why = "LOW_H', 'mark = "calibrated", why = "LOW_H'))
    fitted = load(_edited(tmp_path, 'mark = "assumed", why = "LOW_H', 'mark = "calibrated", on = "H_mm", why = "LOW_H'))
    checks = {c.name: c for c in verdicts.check(fitted.spec, registry.run(fitted).result)}
    assert checks["H_mm"].calibrated and not checks["L_mm"].calibrated


def test_a_derived_parameter_is_the_other_scenes_value():
    chained = registry.run(registry.find("loom/group1-stop-model"))
    law = registry.run(registry.find("stop-impact/amplitude-law")).result.values
    published = registry.run(registry.find("loom/group1")).result.values
    bound = (law["intercept_mm"] - 0.1) / -law["slope_mm_per_deg"]          # a(t) = 0.1 mm on the tangent
    assert chained.result.values["t_3_7_deg"] == pytest.approx(bound, abs=1e-7)
    assert chained.result.values["span_deg"] - published["span_deg"] == pytest.approx(bound - 36.0, abs=1e-7)


@pytest.mark.parametrize("ref, match", [
    ('"nowhere/scene:x"', r"unknown case 'nowhere/scene'"),
    ('"stop-impact/amplitude-law:nothing"', r"derive\.amplitude_slope_mm_per_deg: scene stop-impact/amplitude-law gave "
                                            r"status SOLVED and no value 'nothing'; it has slope_mm_per_deg"),
    ('"no-colon"', r"derive\.amplitude_slope_mm_per_deg = 'no-colon': expected a parameter of Cyclogram"),
])
def test_a_bad_derivation_is_refused_by_name(tmp_path, ref, match):
    text = (registry.cases_dir() / "loom" / "group1-stop-model.toml").read_text()
    path = tmp_path / "chain.toml"
    (tmp_path / "group1.toml").write_text((registry.cases_dir() / "loom" / "group1.toml").read_text())   # its base
    path.write_text(text.replace('"stop-impact/amplitude-law:slope_mm_per_deg"', ref))
    with pytest.raises(SceneError, match=match):
        registry.run(load(path))


def test_a_number_from_an_unexpected_status_does_not_pass():
    scene = registry.find("cam-cutter/minimax")
    from mechopt.kit.result import Result, Timing
    inaccurate = Result(Status.INACCURATE, {"max_deviation_mm": 0.06, "H_mm": 59.6, "L_mm": 47.4}, Timing(0.0, 0.0))
    checks = {c.name: c for c in verdicts.check(scene.spec, inaccurate)}
    assert not checks["max_deviation_mm"].ok and not checks["status"].ok
    robust = registry.run(registry.find("cam-cutter/robust"))       # INFEASIBLE is what that scene expects
    assert robust.ok and robust.result.status is Status.INFEASIBLE


def test_set_reaches_a_structure_entry_by_path_and_changes_nothing_else():
    scene = registry.find("loom/group1")
    base = registry.run(scene).result.values
    longer = registry.run(scene, parse_overrides(["operations[from=3,to=7].min_deg=40"]))
    assert longer.checks == []                                          # the source's figures no longer apply
    assert longer.result.values["t_3_7_deg"] == pytest.approx(40.0, abs=1e-7)
    assert longer.result.values["span_deg"] - base["span_deg"] == pytest.approx(4.0, abs=1e-7)   # (3,7) is critical
    assert registry.run(scene).result.values["span_deg"] == pytest.approx(base["span_deg"])      # the file is intact


@pytest.mark.parametrize("pair, match", [
    ("operations[from=3,to=9].min_deg=40", r"\[from=3,to=9\] matches 0 entries of 'operations', not one"),
    ("operations[from=3].min_deg=40", r"\[from=3\] matches 2 entries of 'operations', not one"),
    ("operations[from=3,to=7]=40", r"name the entry to change after the selector"),
    ("operations[from=3,to=7].min_deg=-4", r"operations\[3->7\]\.min_deg=-4\.0: a minimum phase angle must be >= 0"),
    ("oprations.x=1", r"oprations\.x: unknown key; .*structure entries as PATH, e\.g\. 'operations\[from=1,to=2\]"),
])
def test_a_bad_structure_path_is_refused_by_name(pair, match):
    with pytest.raises(SceneError, match=match):
        registry.run(registry.find("loom/group1"), parse_overrides([pair]))


def test_a_calibration_target_no_scene_expects_is_refused(cases_in):
    (cases_in / "cam").mkdir()
    _edited(cases_in / "cam", 'mark = "assumed", why = "LOW_H', 'mark = "calibrated", on = "H_nm", why = "LOW_H', "x.toml")
    with pytest.raises(SceneError, match=r"params\.H_min_mm\.on = 'H_nm': no scene expects that value; did you mean H_mm"):
        registry.all_scenes()


@pytest.mark.parametrize("case, name", [("cam-cutter/linkage-check", "cam-cutter_linkage-check_paths.png"),
                                        ("stop-impact/rebound-map", "stop-impact_rebound-map_histories.png")])
def test_what_if_scenes_draw_their_operating_point(case, name, tmp_path):
    # a checked linkage has no H_mm among its values (it is an input), an operating point no speeds_rpm
    paths = plot_run(registry.run(registry.find(case)), tmp_path)
    assert [p.name for p in paths] == [name]
    assert paths[0].stat().st_size > 10_000


def test_a_scene_with_no_params_table_runs(tmp_path):
    """Every input in structure: no empty [params] table is needed (it was refused: "params: missing")."""
    (tmp_path / "ops.csv").write_text("from,to,min_deg\na,b,10\nb,c,5\n", encoding="utf-8")
    (tmp_path / "m.toml").write_text('id = "t/m"\ntitle = "t"\nsource = "test"\ntask = "loom.Cyclogram"\n'
                                     'solver = "loom.plan_cyclogram"\n[structure]\n'
                                     'operations = { csv = "ops.csv", columns = ["from", "to", "min_deg"] }\n',
                                     encoding="utf-8")
    assert registry.run(str(tmp_path / "m.toml")).values["span_deg"] == 15.0
