"""The rebound's exact bound made cheap: the chain's batch path (rises by their exact solution,
many t in one pass) against CVODES' per-point rise, the batched walk against a walk stepped point
by point, one walk shared between machines with one lever, and a bound that does not depend on
what ran before (another speed on the same grid of n / t, other threads).

Independent references: follow_cam (CVODES, the chain's own integrator) at reltol 1e-12 (the
chain's) and 1e-13; the crossing found by brentq on the CVODES chain in the walk's last cell; a
fresh walk at the scaled speed and range. Counts of walks and evaluations, never a clock."""
import dataclasses

import numpy as np
import pytest
from scipy.optimize import brentq

import mechopt.solvers.loom.repair as repair
from mechopt import clear_caches, registry
from mechopt.kit.result import Status
from mechopt.models.cam_law import SplineBasis
from mechopt.solvers.stop_impact.cam_follower import follow_cam
from mechopt.solvers.stop_impact.law import RollerLeftCam, chain_rebounds_mm, rebound_amplitude_mm
from mechopt.solvers.stop_impact.rise_batch import NOT_TAKEN, ROLLER_LEFT, TAKEN, rise_batch

N_RPM = 420.0


@pytest.fixture(scope="module")
def task():
    return registry.find("loom/machine-speed").build()[0]


@pytest.fixture(scope="module")
def spline_lever(task):
    """The machine's lever with a synthesised-type law (a cubic B-spline, knots inside the rise)."""
    return dataclasses.replace(task.lever_model, law=SplineBasis(8).law(np.linspace(0.1, 0.9, 5)))


def _lever(task, spline_lever, law):
    return spline_lever if law == "spline" else dataclasses.replace(task.lever_model, law=law)


@pytest.mark.parametrize("law", ["cycloidal", "spline", "modified_sine"])
def test_the_batch_rise_is_nearer_a_tighter_cvodes_than_the_chains_own_cvodes(task, spline_lever, law):
    """v0 from the exact solution against CVODES at the chain's reltol 1e-12 and at 1e-13: the
    chain itself moves by ~1e-10 between the two; the batch lies within 5e-11 of the tighter
    (modified sine: its pieces join at 1/8 and 7/8, on the sample grid's nodes)."""
    lever = _lever(task, spline_lever, law)
    t = np.array([60.0, 45.0, 38.7, 36.0])
    v0, outcome = rise_batch(lever, np.full(t.size, N_RPM), t)
    assert list(outcome) == [TAKEN] * t.size
    for tt, v in zip(t, v0):
        chain, tight = (follow_cam(lever, N_RPM, tt, reltol=tol).approach_velocity_m_s for tol in (1e-12, 1e-13))
        assert abs(v / tight - 1) < 5e-11
        assert abs(v / chain - 1) < 5e-10
        assert abs(v / tight - 1) < abs(chain / tight - 1)


@pytest.mark.parametrize("law", ["cycloidal", "spline"])
def test_the_batch_says_where_the_roller_leaves_its_cam_as_follow_cam_does(task, spline_lever, law):
    lever = _lever(task, spline_lever, law)
    t = np.arange(20.0, 41.0, 2.0)
    _, outcome = rise_batch(lever, np.full(t.size, N_RPM), t)
    statuses = [follow_cam(lever, N_RPM, tt).status for tt in t]
    assert [o == ROLLER_LEFT for o in outcome] == [s is Status.INFEASIBLE for s in statuses]
    assert ROLLER_LEFT in outcome and TAKEN in outcome and NOT_TAKEN not in outcome
    left = float(t[list(outcome).index(ROLLER_LEFT)])
    assert chain_rebounds_mm(lever, N_RPM, [left], lost=np.inf)[0] == np.inf
    with pytest.raises(RollerLeftCam):          # without `lost`: the chain's own error, its message
        chain_rebounds_mm(lever, N_RPM, [left])


def test_a_law_with_two_joins_in_one_cell_goes_to_the_per_point_chain(task):
    dense = dataclasses.replace(task.lever_model, law=SplineBasis(2000).law(np.linspace(0.001, 0.999, 1995)))
    _, outcome = rise_batch(dense, np.array([N_RPM]), np.array([40.0]))
    assert list(outcome) == [NOT_TAKEN]


def test_the_batch_rebound_is_the_chains_to_its_own_error(task):
    lever = task.lever_model
    t = np.array([60.0, 52.5, 44.25, 39.0])
    batch = chain_rebounds_mm(lever, N_RPM, t)
    chain = rebound_amplitude_mm(lever, N_RPM, t)
    assert np.allclose(batch, chain, rtol=1e-9, atol=0.0)
    one = [chain_rebounds_mm(lever, N_RPM, [x])[0] for x in t]         # one point a call: the same numbers
    assert np.allclose(batch, one, rtol=1e-14, atol=0.0)


def _walk_point_by_point(task, n, lo, to, step):
    """The walk as it was written before the batch: one evaluation per step, brentq in the cell."""
    limit = task.amplitude_limit_mm

    def excess(t):
        return float(repair.exact_amplitude_mm(task, t, n, lost=np.inf)[()]) - limit
    hi = to
    while hi > lo:
        low = max(hi - step, lo)
        if excess(low) > 0:
            return brentq(excess, low, hi, xtol=1e-12 * hi, rtol=4 * np.finfo(float).eps), low, hi
        hi = low
    return None, None, None


def test_the_batched_walk_is_the_walk_point_by_point_and_the_cvodes_chains_crossing(task):
    clear_caches()
    bound = repair.exact_amplitude_bound(task, N_RPM, 1.0, 60.0, 0.25)
    root, low, high = _walk_point_by_point(task, N_RPM, 1.0, 60.0, 0.25)
    assert bound.why == "crossing"
    assert bound.from_deg == pytest.approx(root, rel=1e-12)
    lever = task.lever_model          # CVODES' chain, brentq in the same last cell
    cvodes = brentq(lambda t: float(rebound_amplitude_mm(lever, N_RPM, t)) - task.amplitude_limit_mm, low, high,
                    xtol=1e-13)
    assert bound.from_deg == pytest.approx(cvodes, rel=1e-9)
    assert bound.from_deg == pytest.approx(38.6655398, abs=1e-7)         # loom/machine-speed's dense scan
    points = round((60.0 - low) / 0.25)
    assert points <= bound.evaluations <= points + repair.WALK_BATCH + 60      # the walk, its batch's rest, brentq


def test_a_walk_at_twice_the_speed_over_twice_the_range_is_the_walk_scaled(task, monkeypatch):
    """a(t, n) = h(n / t): the walk at 2 n on [2, 120] deg in steps of 0.5 meets the points n / t
    of the walk at n on [1, 60] in steps of 0.25, so its bound is twice the other's. The cache
    walks each speed itself (one walk a speed, none for a second call) and gives the fresh walk's
    bound."""
    clear_caches()
    fresh = repair.exact_amplitude_bound(task, 2 * N_RPM, 1.0, 120.0, 0.5)
    clear_caches()
    walks = []
    real = repair.exact_amplitude_bound
    monkeypatch.setattr(repair, "exact_amplitude_bound", lambda *a: walks.append(a[1:]) or real(*a))
    at_n = repair.cached_amplitude_bound(task, N_RPM, 30.0, 60.0, 0.25)
    at_2n = repair.cached_amplitude_bound(task, 2 * N_RPM, 60.0, 120.0, 0.5)
    assert [w[0] for w in walks] == [N_RPM, 2 * N_RPM]
    assert fresh.from_deg == pytest.approx(2 * at_n.from_deg, rel=1e-12)
    assert at_2n.from_deg == fresh.from_deg and at_2n.amplitude_mm == fresh.amplitude_mm
    assert at_2n.speed_rpm == 2 * N_RPM and at_2n.to_deg == 120.0 and at_2n.step_deg == 0.5
    assert repair.cached_amplitude_bound(task, 2 * N_RPM, 70.0, 120.0, 0.5).from_deg == at_2n.from_deg
    assert len(walks) == 2
    other = repair.cached_amplitude_bound(task, 2 * N_RPM, 60.0, 60.0, 0.25)      # another grid of n / t: a walk
    assert len(walks) == 3 and other.why == "none" and other.from_deg is None       # 60 deg < 2 x 38.67 deg


def test_machines_with_one_lever_share_its_walk_and_another_lever_walks_anew(task, monkeypatch):
    clear_caches()
    walks = []
    real = repair.exact_amplitude_bound
    monkeypatch.setattr(repair, "exact_amplitude_bound", lambda *a: walks.append(a[1:]) or real(*a))
    first = repair.cached_amplitude_bound(task, N_RPM, 30.0, 60.0, 0.25)
    reported_elsewhere = dataclasses.replace(task, cycle_deg=400.0, lever={**task.lever, "t_deg": 33.0})
    assert repair.cached_amplitude_bound(reported_elsewhere, N_RPM, 20.0, 60.0, 0.25).from_deg == first.from_deg
    assert len(walks) == 1
    damped = dataclasses.replace(task, lever={**task.lever, "damping_ratio": 0.06})
    assert repair.cached_amplitude_bound(damped, N_RPM, 30.0, 60.0, 0.25).from_deg != first.from_deg
    assert len(walks) == 2
    clear_caches()


def test_the_fresh_highest_speed_walks_once_and_its_re_solve_never(task, monkeypatch):
    from mechopt.solvers.loom import max_machine_speed
    clear_caches()
    walks = []
    real = repair.exact_amplitude_bound
    monkeypatch.setattr(repair, "exact_amplitude_bound", lambda *a: walks.append(a[1:]) or real(*a))
    first = max_machine_speed(task)
    again = max_machine_speed(dataclasses.replace(task, lever={**task.lever, "t_deg": 33.0}))
    assert len(walks) == 1
    assert first.values["max_speed_rpm"] == again.values["max_speed_rpm"] == pytest.approx(469.555918, rel=1e-6)
    clear_caches()


def test_in_a_groove_the_batch_leaves_a_crossover_to_the_per_point_chain(task):
    """Where a force closure's roller would leave its cam, a groove's crosses to the other wall: the
    batch must not call it lift-off (ROLLER_LEFT) but hand it to the per-point chain, whose groove
    model (the flight across the backlash) gives the rebound, the same as rebound_amplitude_mm's."""
    groove = dataclasses.replace(task.lever_model, closure="groove", backlash_mm=0.05)
    t = np.arange(20.0, 41.0, 2.0)
    _, force_outcome = rise_batch(task.lever_model, np.full(t.size, N_RPM), t)
    _, outcome = rise_batch(groove, np.full(t.size, N_RPM), t)
    crossing = force_outcome == ROLLER_LEFT
    assert crossing.any() and not (outcome == ROLLER_LEFT).any()
    assert list(outcome[crossing]) == [NOT_TAKEN] * int(crossing.sum())
    a = chain_rebounds_mm(groove, N_RPM, t[crossing])
    assert np.all(np.isfinite(a)) and np.all(a > 0)


# -- a result that does not depend on what ran before ------------------------------------------------

# speeds c N over [30 c, 60 c] deg in steps of 0.25 c: one grid of n / t (c a short binary fraction:
# the same (to / n, step / n) to the bit), so a cache keyed by n / t alone would hand each the walk of
# whichever speed came first, rescaled (it did: 1.5 N's crossing then moved by 5.5e-13 deg)
SCALED = (1.0, 1.25, 0.75, 1.5)


def _at(task, c):
    return repair.cached_amplitude_bound(task, c * N_RPM, 30.0 * c, 60.0 * c, 0.25 * c)


@pytest.fixture(scope="module")
def alone(task):
    """Each speed's bound with nothing before it in the process (the caches cleared each time)."""
    out = {}
    for c in SCALED:
        clear_caches()
        out[c] = _at(task, c)
    clear_caches()
    return out


def test_a_solve_after_one_at_another_speed_is_the_solve_alone_bit_for_bit(task, alone):
    """The bound at 1.25 N (0.75 N, 1.5 N) after the one at N, same grid of n / t, equals the bound at
    that speed alone, every field; and alone it is the walk at that speed (`exact_amplitude_bound`),
    whose crossing is c times N's to the root's tolerance (a = h(n / t))."""
    clear_caches()
    _at(task, 1.0)
    for c in SCALED[1:]:
        assert _at(task, c) == alone[c]
        assert alone[c].from_deg == repair.exact_amplitude_bound(task, c * N_RPM, 1.0, 60.0 * c, 0.25 * c).from_deg
        assert alone[c].from_deg == pytest.approx(c * alone[1.0].from_deg, rel=1e-11)
    clear_caches()


def test_four_threads_racing_for_one_grid_each_get_their_speeds_bound_alone(task, alone):
    """Four threads, each at its own speed on one grid of n / t, started together and in turn in
    another order: each gets its speed's bound alone, bit for bit."""
    import threading
    from concurrent.futures import ThreadPoolExecutor
    for order in (SCALED, SCALED[::-1]):
        clear_caches()
        start = threading.Barrier(len(order))

        def solve(c):
            start.wait()
            return c, _at(task, c)
        with ThreadPoolExecutor(len(order)) as pool:
            got = dict(pool.map(solve, order))
        assert got == alone
    clear_caches()


def test_a_walk_stored_by_a_run_at_another_speed_is_not_read_at_this_one(task, alone, tmp_path, monkeypatch):
    """MECHOPT_CACHE_DIR set (another process's walks on disk): the bound at 1.25 N after N's walk
    was stored, the caches cleared, is 1.25 N's alone; each speed its own file."""
    from mechopt.kit import store
    monkeypatch.setenv(store.ENV, str(tmp_path))
    clear_caches()
    _at(task, 1.0)
    clear_caches()
    assert _at(task, 1.25) == alone[1.25]
    assert len(list(tmp_path.glob("walk-*.json"))) == 2
    clear_caches()
    assert _at(task, 1.25) == alone[1.25]          # read back from its own file, the same bits
    clear_caches()
