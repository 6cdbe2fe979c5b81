"""A user's own machine from a CSV timing table: operations read from a
CSV beside the scene, events named by the operations, per-operation windows and times, and the
reader's errors naming file, line and column."""
from pathlib import Path

import pytest

from mechopt import registry
from mechopt.kit.errors import ModelError, SceneError
from mechopt.kit.result import Status
from mechopt.models.cyclogram import Cyclogram
from mechopt.scene import load
from mechopt.solvers.cyclogram import plan_cyclogram

CASES = Path(registry.cases_dir()) / "loom"


def _scene(tmp_path, csv_text, columns='["from", "to", "min_deg"]', extra="[params]"):
    (tmp_path / "ops.csv").write_text(csv_text, encoding="utf-8")
    path = tmp_path / "m.toml"
    path.write_text(f'id = "t/m"\ntitle = "t"\nsource = "test"\ntask = "loom.Cyclogram"\n'
                    f'solver = "loom.plan_cyclogram"\n{extra}\n[structure]\n'
                    f'operations = {{ csv = "ops.csv", columns = {columns} }}\n', encoding="utf-8")
    return path


def test_text_event_names_semicolons_decimal_commas_and_an_operation_window(tmp_path):
    path = _scene(tmp_path, "from;to;min_deg;max_deg;group\n"
                            "feed.start;10.1;12,5;;feed\n10.1;10.2;30;40;feed\n10.2;seal.end;5;;seal\n")
    task = load(path).build()[0]
    assert task.arcs == [("feed.start", "10.1"), ("10.1", "10.2"), ("10.2", "seal.end")]
    assert task.windows == [{"from": "10.1", "to": "10.2", "max_deg": 40.0}]
    assert task.events["seal.end"]["group"] == "seal"
    r = plan_cyclogram(task)
    assert r.status is Status.SOLVED and r.values["span_deg"] == pytest.approx(47.5)


def test_a_time_based_operation_needs_no_angle_and_scales_with_speed(tmp_path):
    path = _scene(tmp_path, "from,to,min_deg,min_ms\na,b,10,\nb,c,,50\n",
                  extra='[params]\nspeed_rpm = { value = 120.0, mark = "assumed", why = "test" }')
    task = load(path).build()[0]
    r = plan_cyclogram(task)
    assert r.values["t_b_c_deg"] == pytest.approx(6 * 120 * 0.050)      # 6 n T deg at n rpm


@pytest.mark.parametrize("csv_text, match", [
    ("from,to,min_deg\na,b,ten\n", r"ops.csv: line 2, column min_deg: expected a number, got 'ten'"),
    ("from,to,min_deg,colour\na,b,1,red\n", r"ops.csv: header .*unknown column 'colour'.*allowed columns: from"),
    ("from,to\na,b\n", r"ops.csv: header .*lacks min_deg"),
    ("from,to,min_deg\na,,1\n", r"ops.csv: line 2: empty to \(required\)"),
    ("from,to,min_deg\na,b,1,2\n", r"ops.csv: line 2: 4 cells, the header names 3"),
    ("from,to,min_deg\n" + "x" * 300 + ",b,1\n", r"line 2, column from: 'xxx.*longer than 200 characters"),
    ("from,to,min_deg,min_deg\na,b,1,1\n", r"'min_deg' given twice"),
    ("from,to,min_deg\na,b,-1\n", r"operations\[a->b\].min_deg=-1.0: a minimum phase angle must be >= 0"),
    ("from,to,min_deg\na,b,1\nb,a,1\n", r"precedence cycle"),
])
def test_bad_timing_table_is_refused_naming_file_line_and_column(tmp_path, csv_text, match):
    with pytest.raises((SceneError, ModelError), match=match):
        load(_scene(tmp_path, csv_text)).build()


def test_columns_must_be_known_and_numeric_tables_stay_strict(tmp_path):
    with pytest.raises(SceneError, match=r"structure.operations.columns: unknown 'speed'"):
        load(_scene(tmp_path, "from,to,min_deg\na,b,1\n", columns='["from", "to", "speed"]'))


def test_events_table_still_checks_names_when_given():
    with pytest.raises(ModelError, match=r"unknown event 'c'"):
        Cyclogram(events={"a": {}, "b": {}}, operations=[{"from": "a", "to": "c", "min_deg": 1.0}])
    task = Cyclogram(operations=[{"from": "a", "to": "b", "min_deg": 1.0, "group": "g"}])
    assert task.events == {"a": {"group": "g"}, "b": {"group": "g"}}


def test_new_cyclogram_template_is_a_packaging_machine_that_runs(tmp_path):
    from mechopt.cli import main
    path = tmp_path / "my" / "machine.toml"
    path.parent.mkdir()
    assert main(["new", "cyclogram", str(path)]) == 0
    text = path.read_text(encoding="utf-8")
    assert 'csv = "machine-ops.csv"' in text and "\n[expect" not in text
    table = (path.parent / "machine-ops.csv").read_text(encoding="utf-8").splitlines()
    assert table[0].startswith("from,to,") and all(",assumed," in row for row in table[1:])
    run = registry.run(load(path))
    assert run.result.status is Status.SOLVED
    assert set(run.task.groups) == {"feed", "fold", "seal"}          # three groups, not the loom
    assert run.result.values["limiting_op_deg"] == pytest.approx(170.0)
    assert all(p.mark == "assumed" for p in run.scene.spec.params.values())
    assert main(["new", "cyclogram", str(path)]) == 2                 # never overwritten


def _layered_table(folder, n, width, groups=4):
    """A timing table of a random layered network of n events (benchmarks' `layered`) with
    `groups` groups by event index, and its scene."""
    from mechopt.benchmarks.loom import layered
    tails, heads, angles = layered(n, width=width)
    rows = "".join(f"e{a},e{b},{w:.6f},g{a * groups // n}\n" for a, b, w in zip(tails.tolist(), heads.tolist(),
                                                                              angles.tolist()))
    (folder / "ops.csv").write_text("from,to,min_deg,group\n" + rows, encoding="utf-8")
    path = folder / "big.toml"
    path.write_text('id = "t/big"\ntitle = "t"\nsource = "generated"\ntask = "loom.Cyclogram"\n'
                    'solver = "loom.plan_cyclogram"\n[params]\n[structure]\n'
                    'operations = { csv = "ops.csv", columns = ["from", "to", "min_deg"] }\n', encoding="utf-8")
    return path, len(tails)


def test_timing_diagram_of_about_100_operations_groups_its_rows_and_drops_bar_labels(tmp_path):
    from mechopt.figures.cyclogram import gantt
    path, arcs = _layered_table(tmp_path, 40, width=6)
    run = registry.run(load(path))
    assert 80 <= arcs <= 120 and run.result.status is Status.SOLVED
    ax = gantt(run)["cyclogram"].axes[0]
    rows = [t.get_text() for t in ax.get_yticklabels()]
    assert len(rows) == arcs
    ends = [r.rsplit("(", 1)[1].rstrip(")").split("-") for r in rows]
    groups = [run.task.graph.edges[x, y]["group"] for x, y in ends]
    assert groups == sorted(groups)                       # one block per group, in the order they start
    assert [t.get_text() for t in ax.texts] == ["g0", "g1", "g2", "g3"]    # group names only, no bar labels
    chain = run.result.diagnostics["critical_chain"]
    assert ax.get_title().endswith(" - ".join(chain))      # 9 events: named in full (past 12 shortened)


def test_graph_and_lp_agree_on_a_1000_event_table_read_from_csv(tmp_path):
    path, _ = _layered_table(tmp_path, 1_000, width=100)
    task = load(path).build()[0]
    graph, lp = plan_cyclogram(task, method="graph"), plan_cyclogram(task, method="lp")
    assert graph.status is Status.SOLVED and lp.status is Status.SOLVED
    assert graph.values["span_deg"] == pytest.approx(lp.values["span_deg"], rel=1e-9)
    assert graph.values["span_deg"] == pytest.approx(graph.values["longest_path_deg"], rel=1e-12)


def _chain_scene(tmp_path, n, windows, syncs=None):
    """A chain s.0 -> s.1 -> ... of 10 deg steps (text names), its windows (and syncs) in their own CSVs."""
    ops = "from,to,min_deg\n" + "".join(f"s.{k},s.{k + 1},10\n" for k in range(n))
    (tmp_path / "ops.csv").write_text(ops, encoding="utf-8")
    (tmp_path / "win.csv").write_text("from,to,max_deg,why\n" + "".join(f"{a},{b},{w},spacing\n" for a, b, w in windows),
                                      encoding="utf-8")
    more = ""
    if syncs is not None:
        (tmp_path / "sync.csv").write_text("events\n" + "".join(f"{e}\n" for e in syncs), encoding="utf-8")
        more = 'syncs = { csv = "sync.csv", columns = ["events"] }\n'
    path = tmp_path / "m.toml"
    path.write_text('id = "t/m"\ntitle = "t"\nsource = "test"\ntask = "loom.Cyclogram"\nsolver = "loom.plan_cyclogram"\n'
                    '[params]\n[structure]\noperations = { csv = "ops.csv", columns = ["from", "to", "min_deg"] }\n'
                    'windows = { csv = "win.csv", columns = ["from", "to", "max_deg"] }\n' + more, encoding="utf-8")
    return path


def test_windows_and_syncs_from_csv_take_text_names_past_the_inline_limit(tmp_path):
    """150 windows (past the 100 of an inline list) of 25 deg over every two steps, none binding but one of
    15 deg over s.3 -> s.5, which the steps cannot meet: INFEASIBLE, naming it; widened, the span is the
    chain's 10 n. A sync row 's.2;s.3' (events separated by ';') ties two events 10 deg apart: INFEASIBLE too."""
    n = 152
    windows = [(f"s.{k}", f"s.{k + 2}", 25.0) for k in range(n - 1) if k != 3] + [("s.3", "s.5", 15.0)]
    assert len(windows) > 100
    task = load(_chain_scene(tmp_path, n, windows)).build()[0]
    assert len(task.windows) == len(windows)
    assert task.windows[-1] == {"from": "s.3", "to": "s.5", "max_deg": 15.0, "why": "spacing"}
    r = plan_cyclogram(task)
    assert r.status is Status.INFEASIBLE and "s.3" in r.message and "s.5" in r.message
    windows[-1] = ("s.3", "s.5", 20.0)
    r = plan_cyclogram(load(_chain_scene(tmp_path, n, windows)).build()[0])
    assert r.status is Status.SOLVED and r.values["span_deg"] == pytest.approx(10.0 * n)
    tied = load(_chain_scene(tmp_path, n, windows, syncs=["s.2;s.3"])).build()[0]
    assert tied.syncs == [{"events": ["s.2", "s.3"]}]
    assert plan_cyclogram(tied).status is Status.INFEASIBLE


def test_ten_thousand_windows_from_csv(tmp_path):
    n = 10_001
    windows = [(f"s.{k}", f"s.{k + 2}", 20.0 + (k == 5000) * 5.0) for k in range(n - 1)]
    task = load(_chain_scene(tmp_path, n, windows)).build()[0]
    assert len(task.windows) == 10_000
    r = plan_cyclogram(task, method="graph")
    assert r.status is Status.SOLVED and r.values["span_deg"] == pytest.approx(10.0 * n)
