"""The graph method of plan_cyclogram certified by the LP: 10^4 random networks with windows and
syncs solved at once (block-diagonal), positive cycles against Bellman-Ford, the compiled passes
against numpy's, a million events certified by duality, and the hard cases."""
import dataclasses
import math

import numpy as np
import pytest
import scipy.sparse as sp
from scipy.optimize import linprog

from mechopt import registry
from mechopt.kit.result import Status
from mechopt.models.cyclogram import Cyclogram
from mechopt.solvers.cyclogram import plan_cyclogram
from mechopt.solvers.cyclogram.conflicts import positive_cycle
from mechopt.solvers.cyclogram.graph import BackArcs, Levels, PositiveCycle


def random_blocks(count, size, seed):
    """`count` random networks of `size` events each, feasible by construction: each event gets a
    time p0 (integers, so some tie), an arc x -> y has a bound at most p0(y) - p0(x), a window at
    least it, a sync joins two events of equal p0. Event 0 of a block is first (arcs to all),
    the last is last. Returns (n, arcs, windows, syncs, firsts, lasts) as index arrays."""
    rng = np.random.default_rng(seed)
    p0 = np.sort(rng.integers(0, 3 * size, (count, size)), axis=1).astype(float)
    p0[:, -1] += 1.0
    base = np.arange(count)[:, None] * size
    i, j = np.triu_indices(size, 1)
    pick = rng.random((count, i.size)) < 3.0 / size
    pick[:, (i == 0) | (j == size - 1)] = True                       # one first, one last
    blk, arc = np.nonzero(pick)
    tails, heads = base[blk, 0] + i[arc], base[blk, 0] + j[arc]
    gap = (p0.ravel()[heads] - p0.ravel()[tails])
    lb = gap * rng.random(gap.size)
    wb = rng.integers(0, count * size, count)                         # one window per block
    a, b = np.sort(rng.integers(1, size - 1, (2, count)), axis=0)
    wa, wb = base[:, 0] + a, base[:, 0] + b
    wmax = p0.ravel()[wb] - p0.ravel()[wa] + rng.random(count) * 2.0 * (rng.random(count) < 0.7)
    ties = [(base[k, 0] + x, base[k, 0] + x + 1) for k in range(count) for x in range(1, size - 2)
            if p0[k, x] == p0[k, x + 1] and rng.random() < 0.5]
    return count * size, (tails, heads, lb), (wa, wb, wmax), np.array(ties).reshape(-1, 2), base[:, 0], \
        base[:, 0] + size - 1


def test_ten_thousand_random_networks_with_windows_and_syncs_agree_with_the_lp():
    count, size = 10_000, 8
    n, (tails, heads, lb), (wa, wb, wmax), syncs, firsts, lasts = random_blocks(count, size, seed=22)
    # the graph: a root joined to every block's first event by a 0 arc, so one pass solves them all
    root = n
    levels = Levels(n + 1, np.r_[tails, np.full(count, root)], np.r_[heads, firsts])
    back = BackArcs(np.r_[wb, syncs[:, 0], syncs[:, 1]], np.r_[wa, syncs[:, 1], syncs[:, 0]],
                    np.r_[-wmax, np.zeros(2 * len(syncs))])
    dist = levels.longest_from(root, np.r_[lb, np.zeros(count)], back)
    graph_span = dist[lasts] - dist[firsts]
    # the LP: minimise the sum of the spans, every block anchored; separable, so each block is optimal
    D = lambda t, h: sp.csr_matrix((np.r_[np.ones(len(t)), -np.ones(len(t))],
                                    (np.r_[np.arange(len(t)), np.arange(len(t))], np.r_[h, t])), shape=(len(t), n))
    c = np.zeros(n)
    c[lasts], c[firsts] = 1.0, -1.0
    a_ub = sp.vstack([-D(tails, heads), D(wa, wb)])
    a_eq = sp.vstack([D(syncs[:, 0], syncs[:, 1]), sp.csr_matrix((np.ones(count), (np.arange(count), firsts)),
                                                                   shape=(count, n))])
    res = linprog(c, A_ub=a_ub, b_ub=np.r_[-lb, wmax], A_eq=a_eq, b_eq=np.zeros(a_eq.shape[0]),
                  bounds=(None, None), method="highs")
    assert res.status == 0, res.message
    lp_span = res.x[lasts] - res.x[firsts]
    assert len(syncs) > 1000 and np.count_nonzero(np.isclose(dist[wb] - dist[wa], wmax)) > 100     # syncs, tight windows
    np.testing.assert_allclose(graph_span, lp_span, rtol=1e-9, atol=1e-9)


def test_positive_cycles_found_by_the_graph_are_those_of_bellman_ford():
    rng = np.random.default_rng(7)
    found = 0
    for _ in range(300):
        size = 6
        n, (tails, heads, lb), (wa, wb, wmax), syncs, _, _ = random_blocks(1, size, seed=int(rng.integers(1 << 30)))
        wmax = wmax - rng.random() * 6.0             # often too tight now
        levels = Levels(n, tails, heads)
        back = BackArcs(wb, wa, -wmax)
        arcs = [(int(t), int(h), float(w), "") for t, h, w in zip(tails, heads, lb)] + \
               [(int(wb[0]), int(wa[0]), float(-wmax[0]), "")]
        try:
            levels.longest_from(0, lb, back)
            conflict = False
        except PositiveCycle:
            conflict = found = found + 1
        assert bool(conflict) == bool(positive_cycle(arcs))
    assert found > 30


def net(edges, **kw):
    names = dict.fromkeys(str(v) for e in edges for v in e[:2])
    return Cyclogram(events={v: {} for v in names},
                     operations=[{"from": str(x), "to": str(y), "min_deg": float(w)} for x, y, w in edges], **kw)


def test_a_timing_table_past_ten_thousand_operations_reports_arrays_and_agrees_with_the_lp():
    """Past PER_NAME_MAX_OPS the plan's per-event and per-operation figures are the result's
    arrays (no p_* / t_* values, float_deg a note), consistent with the span, and the LP beside
    it (check = true) gives the same span."""
    from mechopt.benchmarks.loom import layered
    from mechopt.solvers.cyclogram.net import PER_NAME_MAX_OPS
    n = 4_000
    tails, heads, w = layered(n)
    assert len(tails) > PER_NAME_MAX_OPS
    ops = [{"from": f"e{a}", "to": f"e{b}", "min_deg": float(x), "group": f"g{a * 2 // n}"}
           for a, b, x in zip(tails.tolist(), heads.tolist(), w.tolist())]
    r = plan_cyclogram(Cyclogram(operations=ops), check=True)
    assert r.status is Status.SOLVED and r.values["check_rel"] <= 1e-9
    assert not any(k.startswith(("p_", "t_")) for k in r.values)
    assert isinstance(r.diagnostics["float_deg"], str)
    a = r.arrays
    bound = {f"{op['from']}->{op['to']}": op["min_deg"] for op in ops}
    assert len(a["operation"]) == len(tails) and set(a["operation"]) == set(bound)
    np.testing.assert_allclose(a["duration_deg"], a["end_deg"] - a["start_deg"])
    assert np.all(a["duration_deg"] >= np.array([bound[op] for op in a["operation"]]) - 1e-9)
    assert a["float_deg"].min() > -1e-9
    assert a["end_deg"].max() == pytest.approx(r.values["span_deg"], rel=1e-12)
    crit = set(r.diagnostics["critical_ops"])
    assert all(a["float_deg"][k] <= 1e-6 for k, op in enumerate(a["operation"]) if op in crit)


# ---------------------------------------------------------------- hard cases

def test_zero_length_operations_and_a_sync_ring():
    task = net([(1, 2, 0), (2, 3, 0), (1, 3, 0), (3, 4, 5)], syncs=[{"events": ["1", "2", "3"]}])
    r = plan_cyclogram(task)
    assert r.status is Status.SOLVED and r.values["span_deg"] == 5.0 and r.values["p_3_deg"] == 0.0


def test_a_window_exactly_tight_is_attained_with_zero_float():
    task = net([(1, 2, 10), (2, 3, 20), (1, 3, 5)], windows=[{"from": "1", "to": "3", "max_deg": 30.0}])
    r = plan_cyclogram(task)
    assert r.status is Status.SOLVED and r.values["span_deg"] == 30.0
    assert r.diagnostics["float_deg"]["1->2"] == 0.0 and r.diagnostics["float_deg"]["2->3"] == 0.0
    assert r.values["sens_window_1_3_deg_per_deg"] == 0.0         # tight but not binding the span


def test_ranging_ends_where_the_critical_chain_changes():
    # 1-2-4 (30) is critical, 1-3-4 (25) the next: (1,2) may fall 5 deg before the chain changes
    task = net([(1, 2, 10), (2, 4, 20), (1, 3, 15), (3, 4, 10)])
    r = plan_cyclogram(task)
    assert r.diagnostics["ranging_deg"]["1->2"] == [5.0, None]
    assert r.diagnostics["ranging_deg"]["1->3"] == [None, 5.0]
    shorter = plan_cyclogram(dataclasses.replace(task, operations=[dict(task.operations[0], min_deg=5.0)]
                                                 + task.operations[1:]))
    assert shorter.values["span_deg"] == 25.0 and "1->3" in shorter.diagnostics["critical_ops"]


def test_a_time_based_operation_as_the_speed_goes_to_zero():
    for rpm in (1e-6, 1.0, 600.0):
        task = net([(1, 2, 10), (2, 3, 20)], speed_rpm=rpm)
        task = dataclasses.replace(task, operations=[dict(task.operations[0], min_ms=50.0), task.operations[1]])
        r = plan_cyclogram(task)
        assert r.values["span_deg"] == pytest.approx(max(10.0, 0.006 * rpm * 50.0) + 20.0, rel=1e-12)


def test_two_independent_conflicts_are_both_named():
    task = net([(1, 2, 10), (2, 3, 20), (3, 4, 10), (4, 5, 30)],
               windows=[{"from": "1", "to": "3", "max_deg": 25.0}, {"from": "3", "to": "5", "max_deg": 35.0}])
    r = plan_cyclogram(task)
    assert r.status is Status.INFEASIBLE and r.values == {}
    assert "window p(3) - p(1) <= 25 deg" in r.message and "window p(5) - p(3) <= 35 deg" in r.message
    assert "needs 5 deg more" in r.message and "independent of it" in r.message
    assert r.diagnostics["conflict_excess_deg"] == pytest.approx(5.0)
    assert r.diagnostics["conflicts"][0]["conflict_excess_deg"] == pytest.approx(5.0)


def _numpy_levels(levels):
    """The same Levels with the compiled passes switched off (the numpy reference)."""
    plain = Levels.__new__(Levels)
    plain.__dict__.update(levels.__dict__, _compiled=False)
    return plain


def test_the_compiled_passes_give_the_numpy_passes_answers_with_windows_and_syncs():
    """kernel.py (numba) on a network past COMPILED_MIN_ARCS: every distance from the first and
    to the last event, with windows and a sync as back arcs, equals the numpy levels' bit for bit."""
    from mechopt.benchmarks.loom import random_dag
    from mechopt.solvers.cyclogram.kernel import COMPILED_MIN_ARCS, kernels
    if kernels() is None:
        pytest.skip("numba not installed: the numpy passes are the only ones")
    n = 20_000
    tails, heads, w, (a, b, wmax) = random_dag(n, windows=200, seed=3)
    assert len(tails) >= COMPILED_MIN_ARCS
    levels = Levels(n, tails, heads, compiled=True)
    assert levels._passes()
    back = BackArcs(np.r_[b, 5, 6], np.r_[a, 6, 5], np.r_[-wmax, 0.0, 0.0])
    plain = _numpy_levels(levels)
    for fast, slow in ((levels.longest_from(0, w, back), plain.longest_from(0, w, back)),
                       (levels.longest_to(n - 1, w, back), plain.longest_to(n - 1, w, back))):
        np.testing.assert_array_equal(fast, slow)


def test_a_network_of_windows_only_no_dag_order():
    """Every constraint a back arc (no precedence among the events, bounds of both signs as
    windows would give): the Bellman-Ford rounds alone give each event's least time, the LP's
    (scipy HiGHS: minimise p(v) with p(0) = 0) for every v; a ring of them is feasible by construction."""
    rng = np.random.default_rng(7)
    n = 40
    p0 = rng.uniform(0.0, 100.0, n)
    p0[0] = 0.0
    pairs = np.array([(u, v) for u in range(n) for v in range(n) if u != v and rng.random() < 0.08] +
                     [(k, (k + 1) % n) for k in range(n)])              # a ring reaches every event
    u, v = pairs[:, 0], pairs[:, 1]
    w = (p0[v] - p0[u]) - rng.uniform(0.0, 5.0, len(u)) * (rng.random(len(u)) < 0.8)   # some exactly tight
    levels = Levels(n, np.zeros(0, np.int64), np.zeros(0, np.int64))
    dist = levels.longest_from(0, np.zeros(0), BackArcs(u, v, w))
    D = sp.csr_matrix((np.r_[np.ones(len(u)), -np.ones(len(u))], (np.r_[np.arange(len(u)), np.arange(len(u))],
                                                                      np.r_[v, u])), shape=(len(u), n))
    for target in (5, 17, n - 1):
        c = np.zeros(n)
        c[target] = 1.0
        res = linprog(c, A_ub=-D, b_ub=-w, A_eq=sp.csr_matrix(([1.0], ([0], [0])), shape=(1, n)), b_eq=[0.0],
                      bounds=(None, None), method="highs")
        assert res.status == 0
        assert dist[target] == pytest.approx(res.fun, rel=1e-9, abs=1e-9)
    assert np.all(dist[v] - dist[u] >= w - 1e-9)                      # every window holds


@pytest.mark.slow
def test_a_million_events_certified_by_duality():
    """10^6 events (a layered network as the bench's, 3 x 10^6 arcs, parallel ones kept): the earliest times meet every
    bound, and a chain of bounds met with equality leads first -> last summing (fsum) to the span:
    a primal and a dual solution of the same value, so the span is the LP's optimum."""
    import math

    from mechopt.solvers.cyclogram.graph import a_path, tight_arcs
    n, width = 1_000_000, 100                 # layers of 100 events, each fed by 3 of the layer before
    rng = np.random.default_rng(0)
    inner = np.arange(1, n - 1)
    layer = (inner - 1) // width
    tails = np.concatenate([np.where(layer == 0, 0, (layer - 1) * width + 1 + rng.integers(0, width, inner.size))
                            for _ in range(3)])
    heads = np.tile(inner, 3)
    leaves = np.flatnonzero(np.bincount(tails, minlength=n)[:n - 1] == 0)
    tails, heads = np.r_[tails, leaves], np.r_[heads, np.full(leaves.size, n - 1)]
    w = rng.uniform(0.0, 30.0, tails.size)
    dist = Levels(n, tails, heads).longest_from(0, w)
    span = dist[n - 1]
    assert np.all(np.isfinite(dist)) and np.all(dist[heads] - dist[tails] >= w - 1e-9 * span)
    tight = tight_arcs(tails, heads, w, dist, 1e-9 * span)
    chain = a_path(n, tails[tight], heads[tight], 0, n - 1)
    assert chain and tails[tight[chain[0]]] == 0 and heads[tight[chain[-1]]] == n - 1
    assert math.fsum(w[tight[chain]].tolist()) == pytest.approx(span, rel=1e-12)


def test_a_conflict_the_limiting_operation_cannot_reach_is_infeasible_not_unbounded():
    """limiting_op 1 -> 2 with no cycle_deg: nothing leads from 2 back to 1 (unbounded, were the
    machine possible); the sync of 3 and 4 with t(3->4) >= 5 is a positive cycle out of 2's reach,
    so no schedule exists at all, as the LP says."""
    task = net([(1, 2, 10), (1, 3, 0), (3, 4, 5), (2, 5, 0), (4, 5, 0)], syncs=[{"events": ["3", "4"]}],
               limiting_op=["1", "2"])
    for method in ("graph", "lp"):
        r = plan_cyclogram(task, method=method)
        assert r.status is Status.INFEASIBLE, (method, r.message)
    assert "t(3->4)" in plan_cyclogram(task, method="graph").message


def test_a_zero_float_is_reported_as_zero_not_minus_zero():
    """loom/packaging: start->feed.start has no float; the report says 0, not -0 (the latest
    times are negated longest paths)."""
    run = registry.run(registry.find("loom/packaging"))
    floats = run.diagnostics["float_deg"]
    assert floats["start->feed.start"] == 0.0
    assert not [op for op, f in floats.items() if f == 0.0 and math.copysign(1.0, f) < 0]
