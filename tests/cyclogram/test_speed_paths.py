"""The cyclogram's fast paths give the answers of the paths they stand in for: the held span's
plain-Python pass on small networks (solvers/cyclogram/plain_pass.py) against the numpy levels."""
import numpy as np
import pytest

from mechopt import registry
from mechopt.kit.result import Status
from mechopt.solvers.cyclogram.graph import BackArcs, HeldSpan, PositiveCycle
from mechopt.solvers.cyclogram.net import Net, back_arcs


def _random_network(rng):
    """(n, tails, heads, first, last, back, lb): a DAG in a random topological order (parallel arcs
    and events unreached from first now and then), back arcs of both signs (windows: negative;
    positive ones close positive cycles with the DAG's paths), bounds U(0, 30) deg."""
    n = int(rng.integers(2, 16))
    order = rng.permutation(n)
    pairs = [(order[i], order[i + 1]) for i in range(n - 1) if rng.random() < 0.9]     # mostly a chain
    for _ in range(int(rng.integers(0, 2 * n))):
        i, j = sorted(rng.choice(n, 2, replace=False).tolist())
        pairs.append((order[i], order[j]))
    if not pairs:
        pairs.append((order[0], order[-1]))
    tails, heads = (np.array(x, dtype=np.int64) for x in zip(*pairs))
    back = [(int(rng.integers(n)), int(rng.integers(n)), float(rng.uniform(-40.0, 5.0)))
            for _ in range(int(rng.integers(0, 5)))]
    if rng.random() < 0.3:                  # a sync: p(a) = p(b), a zero cycle the walk back may go round
        a, b = (int(v) for v in rng.choice(n, 2, replace=False))
        back += [(a, b, 0.0), (b, a, 0.0)]
    back = BackArcs.of(back)
    lb = rng.uniform(0.0, 30.0, len(tails))
    lb[rng.random(len(tails)) < 0.1] = 0.0
    first, last = int(order[0]), int(order[-1]) if rng.random() < 0.8 else int(rng.integers(n))
    return n, tails, heads, first, last, back, lb


def _span_or_cycle(held, lb):
    try:
        return held.span(lb)
    except PositiveCycle:
        return "positive cycle"


def test_the_plain_pass_gives_the_numpy_levels_answers_on_random_small_networks(monkeypatch):
    """Status, span and every event time equal bit for bit (the same relaxations in the same
    level order), the span alone and an LP's certificate too; positive cycles, back arcs,
    unreached events and walks back that go round a sync's zero cycle all among the cases."""
    rng = np.random.default_rng(20261129)
    seen = {"back solved": 0, "infeasible": 0, "not certified": 0, "walk round a sync": 0}
    walk_failed = HeldSpan._walk_failed

    def counted(self, *args):
        seen["walk round a sync"] += 1
        return walk_failed(self, *args)
    monkeypatch.setattr(HeldSpan, "_walk_failed", counted)
    for _ in range(400):
        n, tails, heads, first, last, back, lb = _random_network(rng)
        plain = HeldSpan(n, tails, heads, first, last, back, plain=True)
        numpy = HeldSpan(n, tails, heads, first, last, back, plain=False)
        assert plain._plain is not None and numpy._plain is None
        got, want = plain.solve(lb), numpy.solve(lb)
        assert got[0] is want[0] and got[1] == want[1]
        if want[2] is None:
            assert got[2] is None
        else:
            assert isinstance(got[2], np.ndarray) and np.array_equal(got[2], want[2])
        assert _span_or_cycle(plain, lb) == _span_or_cycle(numpy, lb)
        if want[1] is not None:
            for lp_span in (want[1], want[1] + 1e-3, None):
                assert plain.certify(lb, lp_span) == numpy.certify(lb, lp_span)
        seen["back solved"] += want[0] is Status.SOLVED and len(back) > 0
        seen["infeasible"] += want[0] is Status.INFEASIBLE
        seen["not certified"] += want[0] is Status.INACCURATE
    assert min(seen.values()) >= 3, seen


def test_a_bound_cut_to_minus_infinity_takes_the_numpy_levels():
    """An arc cut for ranging (-inf): the plain pass declines the bounds, the answer is numpy's."""
    tails, heads = np.array([0, 0, 1]), np.array([1, 2, 2])
    held = HeldSpan(3, tails, heads, 0, 2, plain=True)
    lb = np.array([10.0, 5.0, -np.inf])
    assert held._plain_bounds(lb) is None
    status, span, p = held.solve(lb)
    assert status is Status.SOLVED and span == 5.0 and p.tolist() == [0.0, 10.0, 5.0]


def test_loom_group1_what_if_takes_the_plain_pass_with_the_levels_answer():
    """loom/group1 (10 events, 11 operations): its what-if is on the plain pass by default, and
    a moved [sigma_H] gives the numpy levels' span and times (114.75 deg at the scene's 800 MPa)."""
    task = registry.find("loom/group1").build()[0]
    net = Net(task, "exact")
    args = (len(net.names), net.tails, net.heads, net.first, net.last, back_arcs(net, with_cycle=False)[0])
    held, levels = HeldSpan(*args), HeldSpan(*args, plain=False)
    assert held._plain is not None
    status, span, p = held.solve(net.lb)
    assert status is Status.SOLVED and span == pytest.approx(114.75, abs=1e-9)
    rows = np.asarray(net.stress_rows, dtype=np.int64)
    for scale in (0.8, 1.0, 1.3):
        lb = net.lb.copy()
        lb[rows] *= scale
        got, want = held.solve(lb), levels.solve(lb)
        assert got[0] is want[0] is Status.SOLVED and got[1] == want[1] and np.array_equal(got[2], want[2])
