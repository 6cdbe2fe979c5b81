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


# -- the highest speed's fresh solve: the probe in one call, the lever's preparation on disk ---------

@pytest.fixture
def machine():
    return registry.find("loom/machine-speed").build()[0]


def test_the_n_over_t_probe_in_one_call_is_the_probe_point_by_point(machine):
    """The probe's six points in one call of the chain give the values each has alone (the
    largest relative change the same to the bit)."""
    from mechopt.solvers.cyclogram.speed_laws import N_OVER_T_FACTORS, n_over_t_probe_at
    from mechopt.solvers.loom.repair import exact_amplitude_mm

    def alone(t, n):
        return float(np.ravel(exact_amplitude_mm(machine, t, n, lost=np.nan))[0])
    worst = 0.0
    for t in (60.0, 45.0):
        base = alone(t, 420.0)
        worst = max([worst] + [abs(alone(c * t, c * 420.0) - base) / abs(base) for c in N_OVER_T_FACTORS])
    assert n_over_t_probe_at(machine, 60.0) == (worst <= 1e-9, worst)


def _walk(machine):
    from mechopt.solvers.loom.repair import cached_amplitude_bound
    return cached_amplitude_bound(machine, 420.0, 36.0, 60.0, 0.25)


def test_the_walk_is_stored_on_disk_and_read_back_whole(machine, tmp_path, monkeypatch):
    """MECHOPT_CACHE_DIR set: the first walk is written, a walk after the caches are cleared is
    read (the walk itself not run) and equals it field by field; other code (its fingerprint)
    or an unreadable file (named in a warning) walks anew; unset, nothing is written."""
    from mechopt.kit import store as walk_store
    from mechopt.kit.cache import clear as clear_caches
    from mechopt.solvers.loom import repair
    monkeypatch.delenv(walk_store.ENV, raising=False)
    clear_caches()
    walked = _walk(machine)
    assert not list(tmp_path.iterdir())                     # the store is off without the variable
    monkeypatch.setenv(walk_store.ENV, str(tmp_path))
    clear_caches()
    assert _walk(machine) == walked
    files = list(tmp_path.glob("walk-*.json"))
    assert len(files) == 1

    def no_walk(*args):
        raise AssertionError("walked again")
    monkeypatch.setattr(repair, "exact_amplitude_bound", no_walk)
    clear_caches()
    assert _walk(machine) == walked and walked.from_deg == pytest.approx(38.6655398, rel=1e-8)
    files[0].write_text("{not json", encoding="utf-8")
    clear_caches()
    with pytest.warns(walk_store.StoreWarning, match=files[0].name), \
            pytest.raises(AssertionError, match="walked again"):
        _walk(machine)                                      # the damaged file named, walked anew
    monkeypatch.setattr(walk_store, "code_fingerprint", lambda sources: "edited code")
    clear_caches()
    with pytest.raises(AssertionError, match="walked again"):
        _walk(machine)
    clear_caches()


def test_a_law_put_in_the_chain_s_place_is_not_stored(machine, tmp_path, monkeypatch):
    from mechopt.kit import store as walk_store
    from mechopt.kit.cache import clear as clear_caches
    from mechopt.solvers.loom import repair
    monkeypatch.setenv(walk_store.ENV, str(tmp_path))
    monkeypatch.setattr(repair, "rebound_amplitude_mm", lambda lever, n, t, lost=None: 0.05 * 40.0 / np.asarray(t))
    clear_caches()
    _walk(machine)
    assert not list(tmp_path.iterdir())
    clear_caches()


def test_the_highest_speed_from_the_store_is_the_fresh_one(machine, tmp_path, monkeypatch):
    """loom/machine-speed's highest speed and every value the same from a fresh solve, and from
    one whose walk and probe the store holds."""
    from mechopt.kit import store as walk_store
    from mechopt.kit.cache import clear as clear_caches
    from mechopt.solvers.cyclogram import max_machine_speed
    monkeypatch.delenv(walk_store.ENV, raising=False)
    clear_caches()
    fresh = max_machine_speed(machine, check=True)
    monkeypatch.setenv(walk_store.ENV, str(tmp_path))
    clear_caches()
    max_machine_speed(machine, check=True)
    assert sorted(p.name.split("-")[0] for p in tmp_path.iterdir()) == ["n_over_t_probe", "walk"]
    clear_caches()
    stored = max_machine_speed(machine, check=True)
    assert stored.status is fresh.status is Status.SOLVED
    assert stored.values == fresh.values and stored.values["max_speed_rpm"] == pytest.approx(469.555918, rel=1e-8)
    clear_caches()
