"""The synthesis spends no work it does not need: a dense-check round's windows bounded by
the round before, the LP's scaling without matrix products, eq. (2) for every speed at once; each
against the computation it replaces, done here independently."""
import numpy as np
import pytest
from scipy import sparse

from mechopt import registry
from mechopt.kit.result import Status
from mechopt.solvers.stop_impact import window_lp as W
from mechopt.solvers.stop_impact.synthesis_search import scan_windows
from mechopt.solvers.stop_impact.window_rows import HeldLP, equilibrate

ACCEL = 570.0       # mm/rad^2: the scenes' bound


@pytest.fixture(scope="module")
def lever():
    return registry.find("stop-impact/amplitude-law").build()[0]


def _lp(lever, speeds, t_deg=31.0):
    lp_lever = W.linear_lever(24, 2)
    lines = W.lever_lines(lever, lever.amplitude_limit_mm)
    responses = [W.speed_response(lever, lp_lever, n, t_deg, lines) for n in speeds]
    return W.WindowLP(lever, lp_lever, responses, t_deg, objective="least_rebound",
                      limit_mm=lever.amplitude_limit_mm, bounds={"max_acceleration_mm_per_rad2": ACCEL}, lines=lines)


def test_a_round_bounded_by_the_round_before_finds_the_same_law_with_fewer_lps(lever):
    """A sample more is rows more: the round before's values bound this round's from below, its
    infeasible windows stay infeasible (each checked here by solving the window), and the scan
    that skips what they rule out ends on the same window with the same coefficients, bit for bit."""
    first = list(np.linspace(280.0, 420.0, 5))
    _, _, floors = scan_windows(_lp(lever, first), around=0.85)
    more = _lp(lever, sorted(first + [300.0]))
    (status, c, value, xa), full, _ = scan_windows(more, around=0.85)
    again = _lp(lever, sorted(first + [300.0]))
    (status_b, c_b, value_b, xa_b), bounded, _ = scan_windows(again, around=0.85, floors=floors)
    assert status is status_b is Status.SOLVED and xa == xa_b and value == value_b and np.array_equal(c, c_b)
    assert bounded < full
    for window, (was, low) in floors.items():
        now, _, exact, _ = more.solve(window)
        if was is Status.INFEASIBLE:
            assert now is Status.INFEASIBLE
        else:
            assert exact >= low * (1 - 1e-6)          # the LP's tolerances: ~3e-7 here, BOUND_MARGIN 1e-3


def test_the_scaling_is_ruizs_by_matrix_products_bit_for_bit(lever):
    """`equilibrate` and the held matrix scale the nonzeros directly; Ruiz's passes written with
    sparse diagonal products (as the scaling was first written) give the same factors and matrix."""
    lp = _lp(lever, [280.0, 420.0])
    A = lp.rows.matrix()
    r, s = np.ones(A.shape[0]), np.ones(A.shape[1])
    absA = abs(sparse.csr_matrix(A))
    for _ in range(8):
        B = sparse.diags(r) @ absA @ sparse.diags(s)
        rows, cols = B.max(axis=1).toarray().ravel(), B.max(axis=0).toarray().ravel()
        r /= np.exp2(np.round(np.log2(np.sqrt(np.where(rows > 0, rows, 1.0)))))
        s /= np.exp2(np.round(np.log2(np.sqrt(np.where(cols > 0, cols, 1.0)))))
    got_r, got_s = equilibrate(A)
    assert np.array_equal(got_r, r) and np.array_equal(got_s, s)
    held = HeldLP(lp.rows, lp.held.movable)
    product = sparse.csc_matrix(sparse.diags(r) @ A @ sparse.diags(s))
    product.data[np.abs(product.data) <= 1e-9] = 0.0
    product.eliminate_zeros()
    assert (held.A != product).nnz == 0


def test_the_dense_checks_rebounds_are_eq2s_at_each_speed(lever):
    """The predictions take eq. (2) for every speed's v0 at once (its envelope); each against the
    closed form with its own Newton at that v0 (`rebound_of_v0_mm`), to 1e-12 of the rebound."""
    speeds = np.arange(280.0, 421.0, 10.0)
    predicted = W.predicted_rebounds_mm(lever, "cycloidal", 33.0, speeds)
    assert all(p[0] > 0 for p in predicted)
    for mm, _, v0 in predicted:
        assert mm == pytest.approx(W.rebound_of_v0_mm(lever, v0), rel=1e-12)


def test_a_held_window_lp_runs_in_the_calling_thread_and_stops_at_ctrl_c(lever, monkeypatch):
    """A window LP of more than THREADED_ROWS rows starts no worker thread (its presolve takes ms),
    and Ctrl-C still stops it within an iteration: the callbacks poll it in the main thread, and the
    KeyboardInterrupt comes when the run returns."""
    import os
    import signal

    from highspy._core import _Highs

    from mechopt.kit import highs, interrupt
    lp = _lp(lever, list(np.linspace(280.0, 420.0, 6)))
    assert lp.held.A.shape[0] >= highs.THREADED_ROWS

    def no_thread(*args, **kwargs):
        raise AssertionError("a worker thread for a held window LP")
    monkeypatch.setattr(highs.threading, "Thread", no_thread)
    assert lp.solve(0.85)[0] is Status.SOLVED
    iterations = []

    def interrupted_run(self):              # Ctrl-C arrives as the run starts
        os.kill(os.getpid(), signal.SIGINT)
        status = _Highs.run(self)
        iterations.append(self.getInfo().simplex_iteration_count)
        return status
    monkeypatch.setattr(highs.RealHighs, "run", interrupted_run, raising=False)
    with pytest.raises(KeyboardInterrupt), interrupt.honoured():
        lp.solve(0.85)
    with pytest.raises(KeyboardInterrupt):
        interrupt.check()                   # the spine consumes the Ctrl-C
    assert iterations and iterations[0] <= 1


def test_a_synthesis_without_its_shop_cam_finds_the_same_law_and_cuts_no_cam(lever):
    """shop_cam false (the co-design cuts its own cam at its t(3,7)): the same law and values, no
    cam tables, the cam's geometry alone in diagnostics."""
    from mechopt.solvers.stop_impact.synthesis import synthesise_law
    settings = dict(objective="least_rebound", coefficients=12, sample_speeds=2, band_low_rpm=380.0,
                    verify=False, compare=False, max_acceleration_mm_per_rad2=ACCEL)
    cut, bare = synthesise_law(lever, **settings), synthesise_law(lever, shop_cam=False, **settings)
    assert cut.status is bare.status is Status.SOLVED and cut.values == bare.values
    assert cut.diagnostics["law_coefficients"] == bare.diagnostics["law_coefficients"]
    assert any(k.startswith("cam_") for k in cut.arrays) and not any(k.startswith("cam_") for k in bare.arrays)
    assert bare.diagnostics["cam"] == {"geometry": cut.diagnostics["cam"]["geometry"]}
