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
