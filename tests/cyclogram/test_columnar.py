"""A plain CSV timing table read as whole columns (mechopt.tables.read_columns) and built into the
cyclogram's network as arrays (models/cyclogram_columns.py) gives what the row-by-row reader and
build give: the same rows, the same network (events, arc order, groups, graph) and the same plan;
anything else falls back to the rows, whose errors name the row."""
import json
import subprocess
import sys
from collections import deque

import numpy as np
import pytest

from mechopt.benchmarks.loom import layered
from mechopt.kit.errors import MechoptError, ModelError
from mechopt.models.cyclogram import Cyclogram
from mechopt.models.cyclogram_tables import OPERATION_COLUMNS
from mechopt.solvers.cyclogram import plan_cyclogram
from mechopt.tables import read_columns, read_records

REQUIRED = ("from", "to")


def _read(path, columns=("from", "to")):
    kw = dict(required=REQUIRED, what="a table of operations", example="from,to,min_deg")
    return read_columns(path, list(columns), OPERATION_COLUMNS, **kw), read_records(path, list(columns),
                                                                                    OPERATION_COLUMNS, **kw)


def _write(tmp_path, text, name="ops.csv", encoding="utf-8"):
    path = tmp_path / name
    path.write_bytes(text.encode(encoding) if isinstance(text, str) else text)
    return path


PLAIN_FILES = {
    "plain": "from,to,min_deg\na,b,10\nb,c,2.5\n",
    "crlf, bom, no last line break": "\ufefffrom,to,min_deg,name\r\na,b,10,first\r\nb,c,-0,\r\nc,d,1e3,x",
    "semicolons and decimal commas": "from;to;min_deg;group\na;b;10,25;g1\nb;c;0,5;\n",
    "numbers of every plain form": ("from,to,min_deg,min_ms\n" + "".join(
        f"e{k},e{k + 1},{v},{m}\n" for k, (v, m) in enumerate(
            [("20.622425926", "1"), ("+3", ""), (".5", "5."), ("1E-3", "-0.0"), ("1234567890123456", "0.1"),
             ("00000000000000001.5", "12345678901234567890"), ("-.25", "9007199254740993"),
             ("1e999", "0.30000000000000004"), ("123456789012345", "99999999999999.9")]))),
}


@pytest.mark.parametrize("text", PLAIN_FILES.values(), ids=PLAIN_FILES)
def test_a_plain_file_read_as_columns_gives_the_rows_read_records_gives(tmp_path, text):
    columns, records = _read(_write(tmp_path, text))
    assert columns is not None
    rows = [row for _, row in records]
    assert columns.rows() == rows and list(columns) == rows and columns == rows
    for got, want in zip(columns.rows(), rows):          # floats bit for bit, -0.0 kept
        assert {k: (type(v), np.copysign(1, v) if isinstance(v, float) else v) for k, v in got.items()} == \
               {k: (type(v), np.copysign(1, v) if isinstance(v, float) else v) for k, v in want.items()}


NOT_PLAIN = {
    "a quoted cell": 'from,to,min_deg\n"a",b,1\n',
    "a blank line": "from,to,min_deg\na,b,1\n\nb,c,2\n",
    "spaces around a cell": "from,to,min_deg\na , b,1\n",
    "fewer cells": "from,to,min_deg,name\na,b,1\n",
    "text beyond ASCII": "from,to,min_deg\nZuführung,b,1\n",
    "a lone CR": "from,to,min_deg\ra,b,1\r",
    "a number float() refuses": "from,to,min_deg\na,b,1.2.3\n",
    "nan": "from,to,min_deg\na,b,nan\n",
    "a required cell empty": "from,to,min_deg\n,b,1\n",
    "a long name": f"from,to,min_deg\n{'a' * 201},b,1\n",
}


@pytest.mark.parametrize("text", NOT_PLAIN.values(), ids=NOT_PLAIN)
def test_any_other_file_is_left_to_read_records(tmp_path, text):
    """None: read_records then reads the file (the same rows) or names the fault by line."""
    path = _write(tmp_path, text)
    kw = dict(required=REQUIRED, what="a table of operations", example="from,to,min_deg")
    assert read_columns(path, ["from", "to"], OPERATION_COLUMNS, **kw) is None
    try:
        read_records(path, ["from", "to"], OPERATION_COLUMNS, **kw)
    except ModelError as exc:
        assert "line" in str(exc)


def test_a_bad_header_is_refused_as_read_records_refuses_it(tmp_path):
    path = _write(tmp_path, "from,to,min_deg,colour\na,b,1\n")
    kw = dict(required=REQUIRED, what="a table of operations", example="from,to,min_deg")
    messages = []
    for reader in (read_columns, read_records):
        with pytest.raises(ModelError) as exc:
            reader(path, ["from", "to"], OPERATION_COLUMNS, **kw)
        messages.append(str(exc.value))
    assert messages[0] == messages[1] and "unknown column 'colour'" in messages[0]


# -- the network and the plan --------------------------------------------------------------------

def _layered_rows(n, seed=0, shuffle=False):
    """`layered`'s DAG as rows with text names; `shuffle`: rows in random order and events named
    by a permutation, so that their first mention is no precedence order."""
    tails, heads, angles = layered(n, seed=seed)
    names = np.random.default_rng(seed).permutation(n) if shuffle else np.arange(n)
    rows = [{"from": f"e{names[a]}", "to": f"e{names[b]}", "min_deg": round(w, 6), "group": f"g{a * 3 // n}"}
            for a, b, w in zip(tails.tolist(), heads.tolist(), angles.tolist())]
    if shuffle:
        rows = [rows[k] for k in np.random.default_rng(seed + 1).permutation(len(rows))]
    return rows


def _junction_rows():
    """Groups and mechanisms that agree at some events and differ at others (junctions), names on
    some operations, dotted event names, an event first mentioned as a `to`."""
    return [{"from": "feed.start", "to": "feed.end", "min_deg": 30.0, "group": "feed", "mechanism": "cam1",
             "name": "feed"},
            {"from": "feed.end", "to": "cut.start", "min_deg": 0.0, "group": "cut", "mechanism": "cam2"},
            {"from": "clamp.end", "to": "cut.start", "min_deg": 5.0, "group": "clamp", "mechanism": "cam2"},
            {"from": "feed.start", "to": "clamp.end", "min_deg": 12.5, "group": "clamp", "mechanism": "cam3",
             "name": "clamp"},
            {"from": "cut.start", "to": "cut.end", "min_deg": 40.0, "group": "cut", "mechanism": "cam2"},
            {"from": "cut.end", "to": "done", "min_deg": 1.0, "name": "eject"},
            {"from": "clamp.end", "to": "done", "min_deg": 90.0, "group": "clamp"}]


SHAPES = {"layered": lambda: _layered_rows(400), "shuffled": lambda: _layered_rows(400, seed=3, shuffle=True),
          "junctions": _junction_rows, "one operation": lambda: [{"from": "a", "to": "b", "min_deg": 7.0}]}
HEADER = ("from", "to", "min_deg", "name", "group", "mechanism")


def _csv(tmp_path, rows):
    header = [c for c in HEADER if any(c in r for r in rows)]
    lines = [",".join(header)] + [",".join(str(r.get(c, "")) for c in header) for r in rows]
    columns, records = _read(_write(tmp_path, "\n".join(lines) + "\n"))
    assert columns is not None
    return columns, [row for _, row in records]


def _longest_path(rows) -> float:
    """The span by hand: Kahn's order over the rows, each event's earliest time (an independent check)."""
    succ, indeg, p = {}, {}, {}
    for r in rows:
        succ.setdefault(r["from"], []).append((r["to"], r["min_deg"]))
        indeg[r["to"]] = indeg.get(r["to"], 0) + 1
        indeg.setdefault(r["from"], 0)
    ready = deque(v for v, d in indeg.items() if d == 0)
    p = {v: 0.0 for v in ready}
    while ready:
        v = ready.popleft()
        for w, d in succ.get(v, ()):
            p[w] = max(p.get(w, -np.inf), p[v] + d)
            indeg[w] -= 1
            if not indeg[w]:
                ready.append(w)
    return max(p.values())


@pytest.mark.parametrize("shape", SHAPES.values(), ids=SHAPES)
def test_the_columnar_network_is_the_row_by_row_one(tmp_path, shape):
    columns, rows = _csv(tmp_path, shape())
    fast, slow = Cyclogram(operations=columns), Cyclogram(operations=rows)
    assert fast._columnar is not None and slow._columnar is None
    assert list(fast.arcs) == slow.arcs and fast.event_names == slow.event_names
    assert fast.groups == slow.groups and (fast.first_event, fast.last_event) == (slow.first_event, slow.last_event)
    assert fast.end_indices == slow.end_indices
    assert {k: v.tolist() for k, v in fast.group_indices.items()} == {k: v.tolist() for k, v in slow.group_indices.items()}
    assert fast.operation_labels.tolist() == slow.operation_labels.tolist()
    assert fast.operation_names == slow.operation_names
    np.testing.assert_array_equal(fast.min_angles_deg(), slow.min_angles_deg())
    assert [list(a) for a in fast.index_arrays] == [list(a) for a in slow.index_arrays]
    assert fast.recurrences == slow.recurrences == ()
    # the graph, built from the arrays when asked, is the rows' graph: nodes, arcs, attributes, order
    assert list(fast.graph.nodes(data=True)) == list(slow.graph.nodes(data=True))
    assert list(fast.graph.edges(data=True)) == list(slow.graph.edges(data=True))


@pytest.mark.parametrize("shape", SHAPES.values(), ids=SHAPES)
def test_the_columnar_plan_is_the_row_by_row_plan(tmp_path, shape):
    columns, rows = _csv(tmp_path, shape())
    fast, slow = (plan_cyclogram(Cyclogram(operations=ops)) for ops in (columns, rows))
    assert fast.status == slow.status and fast.values == slow.values and fast.message == slow.message
    assert json.dumps(fast.diagnostics, sort_keys=True) == json.dumps(slow.diagnostics, sort_keys=True)
    assert fast.arrays.keys() == slow.arrays.keys()
    for key in fast.arrays:
        assert fast.arrays[key].tolist() == slow.arrays[key].tolist(), key
    assert fast.values["span_deg"] == pytest.approx(_longest_path(rows), rel=1e-12)


BROKEN = {
    "a precedence cycle": [{"from": "a", "to": "b", "min_deg": 1.0}, {"from": "b", "to": "c", "min_deg": 1.0},
                           {"from": "c", "to": "b", "min_deg": 1.0}, {"from": "c", "to": "d", "min_deg": 1.0}],
    "a pair twice": [{"from": "a", "to": "b", "min_deg": 1.0}, {"from": "a", "to": "b", "min_deg": 2.0}],
    "an event joined to itself": [{"from": "a", "to": "a", "min_deg": 1.0}, {"from": "a", "to": "b", "min_deg": 1.0}],
    "two first events": [{"from": "a", "to": "c", "min_deg": 1.0}, {"from": "b", "to": "c", "min_deg": 1.0}],
    "an angle out of range": [{"from": "a", "to": "b", "min_deg": -1.0}],
}


@pytest.mark.parametrize("rows", BROKEN.values(), ids=BROKEN)
def test_a_table_breaking_a_rule_gets_the_row_by_row_error(tmp_path, rows):
    columns, rows = _csv(tmp_path, rows)
    messages = []
    for ops in (columns, rows):
        with pytest.raises(ModelError) as exc:
            Cyclogram(operations=ops)
        messages.append(str(exc.value))
    assert messages[0] == messages[1]


def test_a_table_with_more_than_plain_columns_is_built_row_by_row(tmp_path):
    """A min_ms or mark column is not plain: the rows are built as they always were."""
    path = _write(tmp_path, "from,to,min_deg,min_ms,mark,why\na,b,10,5,assumed,a guess\nb,c,2,,,\n")
    columns, records = _read(path)
    task = Cyclogram(operations=columns, speed_rpm=100.0)
    assert task._columnar is None and task.operations == [row for _, row in records]
    assert task.time_arcs() == [0]


# -- the scene and the command line ---------------------------------------------------------------

SCENE = """\
id = "test/columnar"
title = "a plain timing table"
source = "tests/cyclogram/test_columnar.py"
task = "cyclogram.Cyclogram"
solver = "cyclogram.plan_cyclogram"
[params]
[solver_settings]
method = "graph"
[structure]
operations = { csv = "ops.csv", columns = ["from", "to", "min_deg"] }
"""


def _scene(tmp_path, rows):
    _csv(tmp_path, rows)
    path = tmp_path / "big.toml"
    path.write_text(SCENE, encoding="utf-8")
    return path


def test_a_scene_builds_its_plain_table_once_as_columns(tmp_path, monkeypatch):
    from mechopt import registry
    rows = _layered_rows(300)
    path = _scene(tmp_path, rows)
    built = []
    original = Cyclogram.__post_init__
    monkeypatch.setattr(Cyclogram, "__post_init__", lambda self: (built.append(self), original(self))[1])
    run = registry.run(registry.find(str(path)))
    assert len(built) == 1 and built[0]._columnar is not None
    assert run.result.values["span_deg"] == pytest.approx(_longest_path(rows), rel=1e-12)
    # a --set path into the table reads it as rows, changes one, and builds them
    task, _ = registry.find(str(path)).build({"operations[from=e0,to=e1].min_deg": 500.0})
    assert task._columnar is None
    assert next(op for op in task.operations if (op["from"], op["to"]) == ("e0", "e1"))["min_deg"] == 500.0


def test_a_plain_table_run_imports_no_graph_library_and_no_back_end(tmp_path):
    """`mechopt run` on a plain table: neither networkx (the graph is not built) nor scipy (the
    critical path's breadth-first search is Python's), cvxpy or numba."""
    path = _scene(tmp_path, _layered_rows(300))
    code = (f"import sys\nfrom mechopt.cli import main\n"
            f"assert main(['run', {str(path)!r}, '--json', {str(tmp_path / 'out.json')!r}]) == 0\n"
            "print([m for m in ('networkx', 'scipy', 'cvxpy', 'numba') if m in sys.modules])")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.strip().splitlines()[-1] == "[]"
    assert json.loads((tmp_path / "out.json").read_text())["status"] == "SOLVED"


def test_a_broken_plain_table_is_refused_naming_the_scene(tmp_path):
    from mechopt import registry
    path = _scene(tmp_path, BROKEN["a precedence cycle"])
    with pytest.raises(MechoptError, match="precedence cycle"):
        registry.find(str(path))


@pytest.mark.parametrize("seed", range(6))
def test_topological_levels_are_each_events_longest_chain_of_arcs(seed):
    """The Kahn levels (solvers/cyclogram/graph.py), which the columnar build's acyclicity check and
    the graph method share, against a plain-Python pass; an arc closing a cycle is refused."""
    from mechopt.models.cyclogram_columns import topological_levels
    rng = np.random.default_rng(seed)
    n = int(rng.integers(2, 60))
    order = rng.permutation(n)                       # a hidden precedence order, events numbered at random
    pairs = {(int(order[a]), int(order[b])) for a, b in rng.integers(0, n, (3 * n, 2)) if a < b}
    tails, heads = (np.array(side, dtype=np.int64) for side in zip(*pairs)) if pairs else (np.zeros(0, int),) * 2
    level = {int(v): 0 for v in order}
    for v in order:                                  # in precedence order: every arc into v is settled
        for t, h in pairs:
            if h == v:
                level[h] = max(level[h], level[t] + 1)
    assert topological_levels(n, tails, heads).tolist() == [level[v] for v in range(n)]
    if pairs:
        t, h = next(iter(pairs))
        with pytest.raises(ValueError, match="precedence cycle"):
            topological_levels(n, np.r_[tails, h], np.r_[heads, t])


@pytest.mark.parametrize("extra", [
    {"windows": [{"from": "feed.end", "to": "cut.end", "max_deg": 45.0}]},
    {"syncs": [{"events": ["cut.start", "clamp.end"]}]},
    {"limiting_op": ["feed.start", "feed.end"], "cycle_deg": 150.0},
    {"windows": [{"from": "feed.start", "to": "done", "max_deg": 60.0}]},          # infeasible: named alike
], ids=["window", "sync", "machine", "conflict"])
def test_windows_syncs_and_a_limiting_operation_on_a_columnar_table(tmp_path, extra):
    """They name events, so the graph is built to check them; the plan is still the rows' plan."""
    columns, rows = _csv(tmp_path, _junction_rows())
    fast, slow = (plan_cyclogram(Cyclogram(operations=ops, **extra)) for ops in (columns, rows))
    assert fast.status == slow.status and fast.values == slow.values and fast.message == slow.message
    assert json.dumps(fast.diagnostics, sort_keys=True) == json.dumps(slow.diagnostics, sort_keys=True)


@pytest.mark.parametrize("seed", range(8))
def test_the_breadth_first_predecessors_are_scipys(seed):
    """a_path's breadth-first search without scipy: the predecessors scipy's breadth_first_order
    gives on the same arcs' CSR matrix (so the critical chain named on a small network is unchanged)."""
    sparse = pytest.importorskip("scipy.sparse")
    from scipy.sparse.csgraph import breadth_first_order

    from mechopt.solvers.cyclogram.graph import breadth_first_predecessors
    rng = np.random.default_rng(seed)
    n = int(rng.integers(2, 80))
    pairs = np.unique(rng.integers(0, n, size=int(rng.integers(1, 4 * n))) * n + rng.integers(0, n, 1))
    pairs = np.unique(np.r_[pairs, rng.integers(0, n * n, size=3 * n)])
    tails, heads = pairs // n, pairs % n
    source = int(rng.integers(0, n))
    graph = sparse.csr_matrix((np.ones(pairs.size), (tails, heads)), shape=(n, n))
    _, want = breadth_first_order(graph, source, directed=True, return_predecessors=True)
    assert breadth_first_predecessors(n, tails, heads, source) == want.tolist()


def test_a_table_with_marked_rows_is_read_as_rows_and_its_marks_reach_the_inputs(tmp_path):
    """A `mark` column (an assumed angle, say) is beyond a plain table's columns: the file is read
    row by row, so the marked angle is one of the scene's uncertain inputs (what elasticities vary)."""
    from mechopt import registry
    from mechopt.drivers import uncertain_inputs
    (tmp_path / "ops.csv").write_text("from,to,min_deg,mark,why\na,b,10,assumed,a guess\nb,c,20,,\n", encoding="utf-8")
    (tmp_path / "marked.toml").write_text(SCENE.replace('["from", "to", "min_deg"]', '["from", "to", "min_deg", "mark"]'),
                                          encoding="utf-8")
    scene = registry.load(tmp_path / "marked.toml")
    assert isinstance(scene.spec.structure["operations"], list)
    assert [(i.key, i.value, i.mark) for i in uncertain_inputs(scene)] == [
        ("operations[from=a,to=b].min_deg", 10.0, "assumed")]
