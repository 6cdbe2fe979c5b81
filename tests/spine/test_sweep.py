"""Sweeps: variants expanded as specified, every row equal to a direct `registry.run`, failures kept
as rows, resume without recomputation, refusal to mix sweeps, and the Dask path equal to the
in-process one (also after a worker is killed mid-sweep)."""
import dataclasses
import itertools
import os
import signal

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from mechopt import registry
from mechopt import sweep as sw
from mechopt.cli import main
from mechopt.figures.sweep import outputs_of, plot_sweep
from mechopt.kit.errors import SceneError, SolverError

CAM = "cam-cutter/minimax"
LOOM = "loom/group1"
TIMES = {"build_s", "solve_s"}


def _grid(*texts):
    return [sw.parse_grid(t) for t in texts]


def _assert_rows_match_direct_runs(scene, table):
    """Each row against its own `registry.run` in this process: status, message and every value."""
    keys = table.column_names[:table.column_names.index("variant")]
    for row in table.to_pylist():
        direct = registry.run(scene, {k: row[k] for k in keys}).result
        assert row["status"] == direct.status.value
        assert row["warnings"] == "; ".join(direct.warnings)
        for name, value in direct.values.items():
            assert row[name] == pytest.approx(float(value), rel=1e-9, abs=1e-12), (row, name)
        extra = {c for c in table.column_names if row[c] is not None} - set(direct.values) - set(keys) \
            - {"variant", "status", "message", "warnings"} - TIMES
        assert not extra


def _without_times(table):
    return table.drop_columns([c for c in ("build_s", "solve_s", "message") if c in table.column_names])


def test_grid_expands_to_every_combination_in_order():
    scene = registry.find(CAM)
    spec, variants = sw.plan(scene, _grid("a_mm=20:30:3", "h_mm=1:2:2"))
    expected = [{"a_mm": a, "h_mm": h} for a, h in itertools.product([20.0, 25.0, 30.0], [1.0, 2.0])]
    assert variants == expected
    assert spec.keys == ["a_mm", "h_mm"]
    assert sw.plan(scene, _grid("a_mm=25:25:1"))[1] == [{"a_mm": 25.0}]


def test_whole_number_setting_is_swept_in_whole_numbers():
    _, variants = sw.plan(registry.find(CAM), _grid("count=100:200:3"))
    assert [v["count"] for v in variants] == [100, 150, 200]
    assert all(type(v["count"]) is int for v in variants)


def test_random_draws_are_seeded_within_bounds_and_crossed_with_the_grid():
    scene = registry.find(LOOM)
    args = (_grid("sigma_H_limit_MPa=700:900:2"), [sw.parse_random("amplitude_limit_mm=0.05:0.15")])
    _, a = sw.plan(scene, *args, samples=5, seed=7)
    _, b = sw.plan(scene, *args, samples=5, seed=7)
    _, c = sw.plan(scene, *args, samples=5, seed=8)
    assert a == b and a != c
    assert len(a) == 10
    draws = np.random.default_rng(7).uniform(0.05, 0.15, size=(5, 1))[:, 0]
    assert [v["amplitude_limit_mm"] for v in a] == pytest.approx(np.repeat(draws, 2))
    assert [v["sigma_H_limit_MPa"] for v in a] == [700.0, 900.0] * 5


def test_cam_minimax_grid_equals_direct_runs():
    scene = registry.find(CAM)
    # 2 x 2 (each row a cam NLP, again in _assert_rows_match_direct_runs): the wiring, in two chunks
    table = sw.sweep(scene, _grid("a_mm=24:26:2", "h_mm=1.5:2.5:2"), chunk=3, progress=False)
    assert table.num_rows == 4
    assert table.column("variant").to_pylist() == list(range(4))
    assert table.column_names[:2] == ["a_mm", "h_mm"]
    _assert_rows_match_direct_runs(scene, table)
    assert all(t >= 0 for t in table.column("solve_s").to_pylist())


def test_loom_grid_equals_direct_runs_and_holds_the_published_point():
    scene = registry.find(LOOM)
    table = sw.sweep(scene, _grid("amplitude_limit_mm=0.08:0.12:3", "sigma_H_limit_MPa=700:900:3"),
                     chunk=2, progress=False)
    assert table.num_rows == 9
    _assert_rows_match_direct_runs(scene, table)
    # the scene's own parameters are the middle variant: its published t(3,7) comes out of the sweep
    middle = table.to_pylist()[4]
    assert (middle["amplitude_limit_mm"], middle["sigma_H_limit_MPa"]) == (0.1, 800.0)
    assert middle["t_3_7_deg"] == pytest.approx(scene.spec.expect["t_3_7_deg"].value, abs=1e-6)
    assert middle["span_deg"] == pytest.approx(scene.spec.expect["span_deg"].value, abs=1e-6)


def test_hl_map_on_the_step_lattice_finds_the_published_linkage_first():
    # the paper's scan takes the first passing lattice point, H ascending then L ascending; the
    # dense deviation, swept over the lattice around it, must pick out the same point
    table = sw.sweep(registry.find("cam-cutter/linkage-check"), _grid("H_mm=59.43:59.47:5", "L_mm=47.45:47.59:15"),
                     progress=False).to_pylist()
    feasible = sorted((r["H_mm"], r["L_mm"]) for r in table if r["status"] == "SOLVED")
    assert feasible[0] == pytest.approx((59.45, 47.52), abs=1e-9)       # Podchasov (2021), Sec. IV
    assert all((r["nodes_failing"] == 0) == (r["status"] == "SOLVED") for r in table)


def test_failed_variants_are_rows_and_the_sweep_goes_on():
    scene = registry.find(CAM)
    table = sw.sweep(scene, _grid("a_mm=30:30:1", "h_mm=-1:4:2"), progress=False)
    bad, infeasible = table.to_pylist()
    assert bad["status"] == "INVALID" and "params.h_mm=-1.0: allowed >= 0" in bad["message"]
    assert bad["max_deviation_mm"] is None and bad["solve_s"] is None
    assert infeasible["status"] == "INFEASIBLE"
    width = scene.params()["err_width_mm"]
    assert infeasible["max_deviation_mm"] > width       # the best it could do misses the band


def test_solver_crash_and_unexpected_exception_are_rows(monkeypatch):
    real = registry.run

    def flaky(scene, overrides):
        if overrides["sigma_H_limit_MPa"] == 700.0:
            raise SolverError("back end crashed")
        if overrides["sigma_H_limit_MPa"] == 800.0:
            raise ZeroDivisionError("division by zero")
        return real(scene, overrides)
    monkeypatch.setattr(sw.registry, "run", flaky)
    rows = sw.sweep(registry.find(LOOM), _grid("sigma_H_limit_MPa=700:900:3"), progress=False).to_pylist()
    assert [r["status"] for r in rows] == ["FAILED", "ERROR", "SOLVED"]
    assert rows[0]["message"] == "back end crashed"
    assert rows[1]["message"] == "ZeroDivisionError: division by zero"


def _counting(monkeypatch):
    calls = []
    real = registry.run

    def counted(scene, overrides):
        calls.append(dict(overrides))
        return real(scene, overrides)
    monkeypatch.setattr(sw.registry, "run", counted)
    return calls


class _Stop(Exception):
    pass


def test_resume_skips_done_variants(tmp_path, monkeypatch):
    scene, grid, out = registry.find(LOOM), _grid("amplitude_limit_mm=0.05:0.15:10"), tmp_path / "s.parquet"
    calls = _counting(monkeypatch)

    def stop_after_two(rows):
        if len(calls) >= 6:
            raise _Stop
    with pytest.raises(_Stop):
        sw.sweep(scene, grid, out=out, chunk=3, progress=False, on_chunk=stop_after_two)
    assert not out.exists()
    assert len(list((tmp_path / "s.parquet.parts").glob("*.parquet"))) == 2    # nothing computed is lost
    calls.clear()
    table = sw.sweep(scene, grid, out=out, chunk=3, progress=False)
    assert sorted(c["amplitude_limit_mm"] for c in calls) == pytest.approx(np.linspace(0.05, 0.15, 10)[6:])
    assert table.column("variant").to_pylist() == list(range(10))
    assert not (tmp_path / "s.parquet.parts").exists()
    calls.clear()
    again = sw.sweep(scene, grid, out=out, chunk=3, progress=False)
    assert calls == []
    assert _without_times(again).equals(_without_times(table))
    assert pq.read_table(out).num_rows == 10


def test_out_file_of_another_sweep_is_refused_and_kept(tmp_path):
    scene, out = registry.find(LOOM), tmp_path / "s.parquet"
    sw.sweep(scene, _grid("amplitude_limit_mm=0.05:0.15:3"), out=out, progress=False)
    before = out.read_bytes()
    with pytest.raises(SceneError, match=r"holds another sweep \(case loom/group1, amplitude_limit_mm=0.05:0.15:3.*"
                                         r"this one is case loom/group1, amplitude_limit_mm=0.05:0.15:4"):
        sw.sweep(scene, _grid("amplitude_limit_mm=0.05:0.15:4"), out=out, progress=False)
    with pytest.raises(SceneError, match="holds another sweep.*case cam-cutter/minimax"):
        sw.sweep(registry.find(CAM), _grid("a_mm=24:26:3"), out=out, progress=False)
    assert out.read_bytes() == before
    other = tmp_path / "plain.parquet"
    pq.write_table(pa.table({"x": [1.0]}), other)
    with pytest.raises(SceneError, match="a Parquet file but not a mechopt sweep"):
        sw.sweep(scene, _grid("amplitude_limit_mm=0.05:0.15:3"), out=other, progress=False)
    (tmp_path / "junk.parquet").write_text("not parquet")
    with pytest.raises(SceneError, match="not a readable Parquet file"):
        sw.sweep(scene, _grid("amplitude_limit_mm=0.05:0.15:3"), out=tmp_path / "junk.parquet", progress=False)


@pytest.mark.parametrize("text, message", [
    ("a_mm=20:30:0", r"NUM = 0; a range needs at least 1 point"),
    ("a_mm=30:20:3", r"START = 30 > STOP = 20; give the range low to high"),
    ("a_mm=20:30", r"expected KEY=START:STOP:NUM"),
    ("a_mm=20:x:3", r"STOP = 'x' is not a finite number"),
    ("a_mm=20:30:2.5", r"NUM = '2.5' is not a whole number"),
    ("a_mm=20:inf:3", r"STOP = 'inf' is not a finite number"),
])
def test_bad_grid_is_refused(text, message):
    with pytest.raises(SceneError, match=message):
        sw.parse_grid(text)


def test_bad_random_is_refused():
    with pytest.raises(SceneError, match=r"LOW = 2 > HIGH = 1; give the range low to high"):
        sw.parse_random("h_mm=2:1")
    with pytest.raises(SceneError, match=r"expected KEY=LOW:HIGH"):
        sw.parse_random("h_mm=1:2:3")


def test_bad_sweep_spec_is_refused():
    scene = registry.find(CAM)
    with pytest.raises(SceneError, match=r"'b_mm' cannot be swept.*numeric parameters: .*a_mm") as err:
        sw.plan(scene, _grid("b_mm=1:2:2"))
    assert err.value.key == "b_mm"
    with pytest.raises(SceneError, match=r"did you mean h_mm"):
        sw.plan(scene, _grid("hh_mm=1:2:2"))
    with pytest.raises(SceneError, match=r"'backend' cannot be swept"):
        sw.plan(registry.find(LOOM), _grid("backend=1:2:2"))
    with pytest.raises(SceneError, match=r"swept twice: a_mm"):
        sw.plan(scene, _grid("a_mm=1:2:2", "a_mm=3:4:2"))
    with pytest.raises(SceneError, match=r"at least one --grid"):
        sw.plan(scene)
    with pytest.raises(SceneError, match=r"--random needs --samples N with N >= 1"):
        sw.plan(scene, random=[sw.parse_random("a_mm=20:30")])
    with pytest.raises(SceneError, match=r"--samples 3 given without any --random"):
        sw.plan(scene, _grid("a_mm=20:30:2"), samples=3)
    with pytest.raises(SceneError, match=r"chunk = 0: expected a whole number of variants >= 1"):
        sw.sweep(scene, _grid("a_mm=20:30:2"), chunk=0, progress=False)


def test_unreachable_scheduler_is_refused_and_nothing_is_written(tmp_path):
    out = tmp_path / "s.parquet"
    with pytest.raises(SceneError, match=r"--scheduler tcp://127.0.0.1:9: cannot reach a Dask scheduler within 1 s"):
        sw.sweep(registry.find(LOOM), _grid("amplitude_limit_mm=0.05:0.15:3"), out=out,
                 scheduler="tcp://127.0.0.1:9", connect_timeout_s=1.0, progress=False)
    assert list(tmp_path.iterdir()) == []


def test_plots_one_line_per_expected_output_and_a_map(tmp_path):
    scene = registry.find(LOOM)
    line = sw.sweep(scene, _grid("amplitude_limit_mm=0.05:0.15:4"), progress=False)
    assert outputs_of(line, scene) == ["t_3_7_deg", "span_deg", "check_rel"]
    paths = plot_sweep(line, tmp_path, scene=scene)
    assert [p.name for p in paths] == [f"sweep_{o}_vs_amplitude_limit_mm.png" for o in outputs_of(line, scene)]
    cam = registry.find(CAM)
    grid = sw.sweep(cam, _grid("a_mm=30:30:1", "h_mm=-1:2:2"), progress=False)
    (path,) = plot_sweep(grid, tmp_path, scene=cam)
    assert path.name == "sweep_max_deviation_mm_vs_a_mm_h_mm.png"
    assert all(p.stat().st_size > 5000 for p in [*paths, path])


def test_cli_sweep_writes_table_and_reports_bad_input(tmp_path, capsys):
    out = tmp_path / "t.parquet"
    assert main(["sweep", LOOM, "--grid", "sigma_H_limit_MPa=700:900:3", "--out", str(out),
                 "--plot", str(tmp_path / "fig")]) == 0
    table, meta = sw.read_table(out)
    assert table.column("sigma_H_limit_MPa").to_pylist() == [700.0, 800.0, 900.0]
    assert meta["case"] == LOOM
    assert "3 variants (3 SOLVED)" in capsys.readouterr().out
    assert main(["sweep", LOOM, "--grid", "sigma_H_limit_MPa=900:700:3", "--out", str(out)]) == 2
    assert "START = 900 > STOP = 700" in capsys.readouterr().err


# --- Dask: a real LocalCluster with two worker processes -------------------------------------

@pytest.fixture(scope="module")
def cluster():
    distributed = pytest.importorskip("distributed")
    # dashboard_address ":0": any free port; a taken 8787 would warn, and warnings are errors here
    with distributed.LocalCluster(n_workers=2, processes=True, threads_per_worker=1,
                                  dashboard_address=":0") as local:
        yield local


@pytest.mark.slow
def test_dask_table_equals_in_process_table(cluster, tmp_path):
    scene, grid = registry.find(LOOM), _grid("amplitude_limit_mm=0.05:0.15:5", "sigma_H_limit_MPa=600:1000:4")
    here = sw.sweep(scene, grid, chunk=3, progress=False)
    there = sw.sweep(scene, grid, chunk=3, scheduler=cluster.scheduler_address, out=tmp_path / "d.parquet",
                     progress=False)
    assert there.num_rows == 20
    assert _without_times(there).equals(_without_times(here))


@pytest.mark.slow
def test_local_processes_give_the_in_process_table():
    scene, grid = registry.find(LOOM), _grid("amplitude_limit_mm=0.05:0.15:5", "sigma_H_limit_MPa=600:1000:4")
    here = sw.sweep(scene, grid, chunk=3, progress=False)
    pooled = sw.sweep(scene, grid, chunk=3, workers=2, progress=False)
    assert _without_times(pooled).equals(_without_times(here))


@pytest.mark.parametrize("kwargs, match", [
    ({"workers": 0}, r"workers = 0: expected a whole number of processes >= 1"),
    ({"workers": 2, "scheduler": "tcp://127.0.0.1:1"}, r"give either --scheduler .* or --workers, not both"),
])
def test_bad_worker_settings_are_refused(kwargs, match):
    with pytest.raises(SceneError, match=match):
        sw.sweep(registry.find(LOOM), _grid("amplitude_limit_mm=0.05:0.15:2"), progress=False, **kwargs)


@pytest.mark.slow
def test_worker_killed_mid_sweep_loses_no_variant(cluster):
    from distributed import Client
    with Client(cluster.scheduler_address) as client:
        pids = list(client.run(os.getpid).values())
    # 8 cam NLPs (~1 s each) in 4 chunks over 2 workers: when the first chunk arrives, each worker
    # still holds one in hand or queued, so the kill loses work that must be sent again
    scene, grid = registry.find(CAM), _grid("a_mm=22:28:2", "h_mm=1:3:4")
    arrived = []

    def kill_one_worker(rows):
        arrived.append(len(rows))
        if len(arrived) == 1:
            os.kill(pids[0], signal.SIGKILL)
    table = sw.sweep(scene, grid, chunk=2, scheduler=cluster.scheduler_address, progress=False,
                     on_chunk=kill_one_worker)
    assert len(arrived) == 4 and sum(arrived) == 8        # the kill came with 3 chunks still to go
    assert table.column("variant").to_pylist() == list(range(8))
    _assert_rows_match_direct_runs(scene, table)
    with Client(cluster.scheduler_address) as client:     # the nanny restarted the killed worker
        client.wait_for_workers(2, timeout=30)
        after = set(client.run(os.getpid).values())
    assert pids[0] not in after and pids[1] in after


def test_worker_refuses_a_scene_text_changed_on_the_way():
    sent = sw.SceneText.of(registry.find(LOOM))
    assert sent.sha256 == sw.scene_hash(registry.find(LOOM))
    with pytest.raises(SceneError, match=r"group1.toml: the scene file this worker received differs from the sweep's"):
        sw.run_chunk(sw.SceneText(sent.text + " ", sent.path, sent.sha256), [(0, {"sigma_H_limit_MPa": 800.0})])


@pytest.mark.slow
def test_variants_lost_on_the_cluster_are_named_not_hidden(cluster, monkeypatch):
    real = sw.SceneText.of
    monkeypatch.setattr(sw.SceneText, "of", lambda scene: dataclasses.replace(real(scene), sha256="f" * 64))
    with pytest.raises(SolverError, match=r"3 of 3 variants were not computed \(SceneError: .*scene file this "
                                          r"worker received differs"):
        sw.sweep(registry.find(LOOM), _grid("sigma_H_limit_MPa=700:900:3"), chunk=1,
                 scheduler=cluster.scheduler_address, progress=False)
