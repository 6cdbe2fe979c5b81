"""What a user's fresh process pays on the graph path: numba's compiled passes loaded from the
on-disk cache (a second process does not compile), numba not imported at all by a one-off solve
of a shallow network, and no LP modelling layer (cvxpy) imported by `method = "graph"`."""
import subprocess
import sys

import pytest

FRESH = [sys.executable, "-c"]


def _run(code, env=None):
    out = subprocess.run(FRESH + [code], capture_output=True, text=True, env=env, timeout=600)
    assert out.returncode == 0, out.stderr[-2000:]
    return out


def test_a_second_process_loads_the_compiled_passes_from_the_disk_cache():
    """NUMBA_DEBUG_CACHE reports each cache index and data load or save: after a first process
    (which may compile and save), a second one loads both kernels and saves nothing."""
    pytest.importorskip("numba")
    import os
    code = "from mechopt.solvers.cyclogram.kernel import kernels; assert kernels() is not None"
    env = dict(os.environ, NUMBA_DEBUG_CACHE="1")
    env.pop("MECHOPT_NO_NUMBA", None)
    _run(code, env)
    second = _run(code, env).stdout + _run(code, env).stderr
    assert second.count("[cache] data loaded") == 2, second
    assert "data saved" not in second and "index saved" not in second, second


def test_a_one_off_solve_of_a_shallow_network_imports_neither_numba_nor_cvxpy():
    """A ~3 x 10^4-operation layered network (past COMPILED_MIN_ARCS, 102 levels) solved once on
    the graph: the numpy levels' passes cost less than numba's import, so it is not imported; nor
    is cvxpy (the LP's layer) on the graph path. The span equals networkx's longest path."""
    code = """
import sys
import networkx as nx
import numpy as np
from mechopt.models.cyclogram import Cyclogram
from mechopt.solvers.cyclogram import plan_cyclogram
from mechopt.solvers.cyclogram.kernel import COMPILED_MIN_ARCS
rng = np.random.default_rng(0)                 # 100 layers of 100 events, 3 arcs into each from the layer before
h = np.repeat(np.arange(100, 10_000), 3)
t = (h // 100 - 1) * 100 + rng.integers(0, 100, h.size)
t, h = np.unique(np.c_[t, h], axis=0).T
t, h = np.r_[np.zeros(100, int), t, np.arange(10_000)], np.r_[np.arange(100), h, np.full(10_000, 10_000)]
t, h = t[t != h], h[t != h]
w = rng.uniform(0, 30, t.size)
assert len(t) >= COMPILED_MIN_ARCS
ops = [{"from": f"e{a}", "to": f"e{b}", "min_deg": float(x)} for a, b, x in zip(t.tolist(), h.tolist(), w.tolist())]
r = plan_cyclogram(Cyclogram(operations=ops), method="graph")
g = nx.DiGraph()
g.add_weighted_edges_from(zip(t.tolist(), h.tolist(), w.tolist()))
assert abs(r.values["span_deg"] - nx.dag_longest_path_length(g)) <= 1e-9 * r.values["span_deg"], r.values
print("numba" in sys.modules, "cvxpy" in sys.modules)
"""
    assert _run(code).stdout.split() == ["False", "False"]


def _plain_ops():
    """A small plain timing table (angles, names, groups): two chains from s to e."""
    return [{"from": "s", "to": "a", "min_deg": 10, "name": "feed", "group": "g1"},
            {"from": "a", "to": "e", "min_deg": 20.5, "why": "a note"},
            {"from": "s", "to": "b", "min_deg": 0.0},
            {"from": "b", "to": "e", "min_deg": 31.25, "group": "g2"}]


def test_a_plain_table_is_built_at_once_into_the_row_by_row_graph():
    """Network._add_plain_operations (whole columns) gives the arcs, in order, with the
    attributes `_add_operations` (row by row) gives them; the span is the longest chain, 31.25 deg."""
    import networkx as nx

    from mechopt.models.cyclogram import Cyclogram
    from mechopt.solvers.cyclogram import plan_cyclogram
    task = Cyclogram(operations=_plain_ops())
    slow = nx.DiGraph()
    slow.add_nodes_from(task.graph.nodes(data=True))
    task._add_operations(slow)
    assert list(task.graph.edges(data=True)) == list(slow.edges(data=True))
    assert plan_cyclogram(task).values["span_deg"] == pytest.approx(31.25, abs=1e-12)


@pytest.mark.parametrize("bad, message", [
    ({"min_deg": -1.0}, "operations[s->a].min_deg=-1.0: a minimum phase angle must be >= 0"),
    ({"min_deg": float("nan")}, "operations[s->a].min_deg=nan: expected a finite number"),
    ({"min_deg": True}, "operations[s->a].min_deg=True: expected a finite number"),
    ({"to": "s"}, "operations[s->s]: an operation must join two different events"),
    ({"to": "e", "from": "a"}, "operations[a->e]: given twice"),
])
def test_a_bad_row_of_a_plain_table_is_named_as_row_by_row(bad, message):
    """A plain table the column checks refuse goes row by row: the error names the first bad row."""
    from mechopt.kit.errors import ModelError
    from mechopt.models.cyclogram import Cyclogram
    ops = _plain_ops()
    ops[0] = ops[0] | bad
    with pytest.raises(ModelError) as err:
        Cyclogram(operations=ops)
    assert message in str(err.value)


@pytest.mark.parametrize("text, message", [
    ("from,to,min_deg\ns,a,10\na,e,1_0\n", "line 3, column min_deg: expected a number, got '1_0'"),
    ("from,to,min_deg\ns,a,inf\n", "line 2, column min_deg: expected a number, got 'inf'"),
    ("from,to,min_deg\ns,a,1.2.3\n", "line 2, column min_deg: expected a number"),
    ("from,to,min_deg\ns,,3\n", "line 2: empty to (required)"),
    ("from,to,min_deg\ns,a,3,4\n", "line 2: 4 cells, the header names 3"),
])
def test_a_bad_cell_is_named_by_its_line_and_column(tmp_path, text, message):
    """tables.read_records on a timing table: what it refuses, named by line and column."""
    from mechopt import tables
    from mechopt.kit.errors import ModelError
    from mechopt.models.cyclogram_tables import OPERATION_COLUMNS
    path = tmp_path / "ops.csv"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(ModelError) as err:
        tables.read_records(path, ["from", "to"], OPERATION_COLUMNS, required=("from", "to"), what="a table",
                            example="from,to")
    assert message in str(err.value)
