"""The lift cam's law synthesised as a spline under the rebound limit, and
checked by the chain (CVODES rise, eq. (2)) that did not design it."""
import dataclasses

import numpy as np
import pytest

from mechopt import registry
from mechopt.kit.errors import SettingError
from mechopt.kit.result import Status
from mechopt.models.cam_follower import law_values
from mechopt.models.cam_law import SplineBasis, elastic_response
from mechopt.solvers.stop_impact.cam_follower import follow_cam, follower_data
from mechopt.solvers.stop_impact.synthesis import law_of, synthesise_law
from mechopt.solvers.stop_impact.synthesis_search import design_law
from mechopt.solvers.stop_impact.window_lp import predicted_rebounds_mm

ACCEL = 570.0       # mm/rad^2: the cycloid's peak at the chain's t = 35.59 deg


@pytest.fixture(scope="module")
def lever():
    return registry.find("stop-impact/amplitude-law").build()[0]


@pytest.mark.parametrize("continuity", [2, 3])
def test_a_spline_law_rests_and_dwells_to_its_continuity(continuity):
    basis = SplineBasis(12, continuity)
    law = basis.law(np.random.default_rng(1).uniform(-1, 2, basis.size))
    ends = [np.array(v) for v in law.values([0.0, 1.0])]
    assert ends[0] == pytest.approx([0.0, 1.0], abs=1e-12)
    for d in range(1, continuity + 1):
        assert ends[d] == pytest.approx([0.0, 0.0], abs=1e-9)
    s = law.values([-0.5, 1.5])
    assert s[0] == pytest.approx([0.0, 1.0]) and all(np.all(v == 0) for v in s[1:])


def test_the_superposed_response_matches_cvodes_on_a_spline_law(lever):
    """The linear model's X' at the contact against follow_cam on the same spline (cycloid fitted)."""
    basis = SplineBasis(40)
    xi = np.linspace(0, 1, 801)
    (s0, B), *_ = basis.matrices(xi, order=0)
    law = basis.law(np.linalg.lstsq(B.toarray(), law_values("cycloidal", xi)[0] - s0, rcond=None)[0])
    rise = follow_cam(dataclasses.replace(lever, law=law), 420.0)
    predicted = predicted_rebounds_mm(lever, law, lever.t_deg, [420.0])[0]
    assert rise.status is Status.SOLVED
    assert predicted[1] == pytest.approx(rise.contact_xi, rel=1e-5)
    assert predicted[2] == pytest.approx(rise.approach_velocity_m_s, rel=1e-4)


@pytest.mark.parametrize("continuity", [2, 3])
def test_the_sparse_basis_matrices_match_scipys_spline_derivatives(continuity):
    """S^(k) = s0 + B c from the design matrices and de Boor's differences, against scipy's own
    BSpline.derivative on the full coefficients, at random xi (ends included)."""
    basis = SplineBasis(50, continuity)
    free = np.random.default_rng(3).uniform(-1, 2, basis.size)
    xi = np.concatenate([[0.0, 1.0], np.random.default_rng(4).uniform(0, 1, 300)])
    for d, (s0, B) in enumerate(basis.matrices(xi, order=3)):
        assert s0 + B @ free == pytest.approx(basis.law(free).values(xi)[d], rel=1e-9, abs=1e-6)


def test_the_lps_two_forms_of_the_lever_give_the_same_law(lever, monkeypatch):
    """The dense superposition and the states tied by the exact step are one map: the same LP's
    value in both forms, at a size each form would not pick by itself."""
    from mechopt.solvers.stop_impact import window_lp
    answers = []
    for first in (10**9, 0):                        # dense, then states
        monkeypatch.setattr(window_lp, "STATE_FORM_FROM", first)
        window_lp.BASES.clear()
        lp_lever = window_lp.linear_lever(250, 2)
        speed = window_lp.speed_response(lever, lp_lever, 420.0, lever.t_deg)
        lines = window_lp.rebound_envelope(lever, 4 * window_lp.v0_limit_m_s(lever, lever.amplitude_limit_mm))
        lp = window_lp.WindowLP(lever, lp_lever, [speed], lever.t_deg, objective="least_rebound",
                                limit_mm=lever.amplitude_limit_mm, bounds={"max_acceleration_mm_per_rad2": ACCEL},
                                lines=lines)
        answers.append(lp.solve(0.85))
    assert [a[0] for a in answers] == [Status.SOLVED, Status.SOLVED]
    assert answers[1][2] == pytest.approx(answers[0][2], rel=1e-7)


def test_the_elastic_response_is_linear_in_its_input(lever):
    lam, zeta, *_ = follower_data(lever, 350.0, 30.0)
    u = np.random.default_rng(2).normal(size=(200, 2))
    both = elastic_response(u @ [2.0, -3.0], lam, zeta, 0.005)[0]
    parts = elastic_response(u, lam, zeta, 0.005)[0]
    assert both == pytest.approx(parts @ [2.0, -3.0], abs=1e-12)


def test_a_phase_angle_below_the_kinematic_minimum_is_infeasible_naming_the_bound(lever):
    """Any rest-to-rest rise needs |S''| >= 4: under the cycloid's peak acceleration the least t is
    35.59 sqrt(4 / (2 pi)) = 28.4 deg; at 20 deg the acceleration bound binds."""
    task = dataclasses.replace(lever, t_deg=20.0)
    run = synthesise_law(task, objective="least_rebound", coefficients=16, band_low_rpm=420.0, sample_speeds=1,
                         max_acceleration_mm_per_rad2=ACCEL, verify=False, compare=False)
    assert run.status is Status.INFEASIBLE
    assert "acceleration" in run.violated and "acceleration" in run.message


def test_a_law_that_holds_at_sampled_speeds_but_not_between_is_caught(lever):
    """Two sampled speeds: the least-rebound law between them breaks its own bound, the dense check
    says so (one round), and with more rounds the failing speed is sampled and the LP re-solved."""
    band = (340.0, 420.0)
    once = design_law(lever, lever.t_deg, band, coefficients=10, sample_speeds=2, rounds=1,
                      bounds={"max_acceleration_mm_per_rad2": ACCEL})
    assert once.status is Status.LIMIT and "dense check" in once.message
    more = design_law(lever, lever.t_deg, band, coefficients=10, sample_speeds=2, rounds=4,
                      bounds={"max_acceleration_mm_per_rad2": ACCEL})
    assert len(more.speeds) > 2
    if more.status is Status.SOLVED:
        dense = np.arange(340.0, 421.0, 5.0)
        worst = max(p[0] for p in predicted_rebounds_mm(lever, more.law, lever.t_deg, dense))
        assert worst <= more.value * (1 + 1e-3) + 1e-9


def test_a_synthesised_law_is_verified_by_the_chain_and_beats_the_cycloid(lever):
    run = synthesise_law(lever, objective="least_rebound", coefficients=20, band_low_rpm=420.0, sample_speeds=1,
                         max_acceleration_mm_per_rad2=ACCEL, compare=False)
    assert run.status is Status.SOLVED, run.message
    assert run.values["chain_rel_diff"] < 2e-3
    cycloid = predicted_rebounds_mm(lever, "cycloidal", lever.t_deg, [420.0])[0][0]
    assert run.values["rebound_chain_mm_420"] < cycloid
    assert run.values["peak_acceleration_mm_per_rad2"] <= ACCEL * (1 + 1e-6)
    law = law_of(run)
    assert law.values([1.0])[0] == pytest.approx([1.0])


def test_a_limit_no_law_keeps_gives_the_best_rebound_and_its_speed(lever):
    task = dataclasses.replace(lever, amplitude_limit_mm=1e-3)
    run = synthesise_law(task, objective="least_phase", coefficients=12, band_low_rpm=400.0, sample_speeds=2,
                         max_acceleration_mm_per_rad2=ACCEL, phase_from_deg=30.0, phase_to_deg=31.0, verify=False,
                         compare=False)
    assert run.status is Status.INFEASIBLE
    assert run.values["rebound_best_mm"] > 1e-3 and 400.0 <= run.values["rebound_best_speed_rpm"] <= 420.0


def test_bad_band_and_bracket_are_named(lever):
    with pytest.raises(SettingError, match="band_low_rpm=500.*band is empty"):
        synthesise_law(lever, band_low_rpm=500.0)
    with pytest.raises(SettingError, match="phase_from_deg=40.*empty bracket"):
        synthesise_law(lever, phase_from_deg=40.0, phase_to_deg=30.0)


def test_the_least_peak_acceleration_keeping_the_limit_is_below_the_cycloids(lever):
    """At the chain's t and 420 rpm the cycloid (570 mm/rad^2) rebounds 0.101 mm; a law keeping
    0.1 mm needs less acceleration than that, and no rest-to-rest rise needs less than 4 / (2 pi) of it."""
    run = synthesise_law(lever, objective="least_acceleration", coefficients=16, band_low_rpm=420.0, sample_speeds=1,
                         compare=False)
    assert run.status is Status.SOLVED, run.message
    assert 4 / (2 * np.pi) * ACCEL * (1 - 1e-3) < run.values["peak_acceleration_mm_per_rad2"] < ACCEL
    assert run.values["rebound_max_chain_mm"] <= lever.amplitude_limit_mm * (1 + 2e-3)


def test_a_c3_law_is_verified_by_the_chain_with_its_jerk_zero_at_the_dwells(lever):
    """C3 (quartic) is checked by the chain like C2: its linear prediction agrees with CVODES +
    eq. (2) within the tolerance (a quartic's S'' is not linear between nodes: the first-order hold
    errs by O(h^2), stated in models/cam_law.py), and its jerk is zero where the rise meets the dwells."""
    run = synthesise_law(lever, objective="least_rebound", coefficients=24, continuity=3, band_low_rpm=280.0,
                         max_acceleration_mm_per_rad2=ACCEL, compare=False)
    assert run.status is Status.SOLVED
    assert run.values["chain_rel_diff"] < 2e-3
    law = law_of(run)
    assert law.degree == 4
    jerk_peak = np.abs(law.values(np.linspace(0, 1, 2001))[3]).max()
    assert np.abs(law.values([0.0, 1.0])[3]).max() < 1e-9 * jerk_peak


def test_the_kinematic_conflict_names_only_the_bound_that_binds(lever):
    """Below the kinematic minimum with a generous velocity bound beside the acceleration's: one
    small LP refuses the angle before any window, and names the acceleration alone (a rise over
    20 deg needs ~100 mm/rad on average, far below 1000; its |S''| >= 4 needs 1150 mm/rad^2, twice 570)."""
    from mechopt.solvers.stop_impact.window_lp import kinematic_conflict, linear_lever
    both = {"max_velocity_mm_per_rad": 1000.0, "max_acceleration_mm_per_rad2": ACCEL}
    assert kinematic_conflict(linear_lever(16, 2), 20.0, lever.stroke_mm, both) == ("acceleration",)
    assert kinematic_conflict(linear_lever(16, 2), 40.0, lever.stroke_mm, both) == ()


# ---------------------------------------------------------------- the window LP as sparse rows held in HiGHS

@pytest.fixture(scope="module")
def window_lp(lever):
    from mechopt.solvers.stop_impact import window_lp
    lp_lever = window_lp.linear_lever(24, 2)
    speeds = [window_lp.speed_response(lever, lp_lever, n, 31.0) for n in (280.0, 420.0)]
    lines = window_lp.rebound_envelope(lever, 4 * window_lp.v0_limit_m_s(lever, lever.amplitude_limit_mm))
    return lambda: window_lp.WindowLP(lever, lp_lever, speeds, 31.0, objective="least_rebound",
                               limit_mm=lever.amplitude_limit_mm, bounds={"max_acceleration_mm_per_rad2": ACCEL},
                               lines=lines)


def test_the_held_lp_is_the_lp_of_its_unscaled_rows(window_lp):
    """The rows scaled by powers of two and the bounds changed in place solve the LP that scipy's
    linprog solves from the unscaled rows and this window's bounds, built here (its own HiGHS call)."""
    from scipy.optimize import linprog
    from scipy.sparse import csr_matrix
    lp = window_lp()
    status, c, value, _ = lp.solve(0.85)
    A = csr_matrix(lp.rows.matrix())
    lower, upper, col_lo, col_hi, cost = lp.rows.bounds()
    upper[lp.held.movable] = lp.upper_at(0.85)
    eq, le = lower == upper, np.isfinite(upper) & (lower != upper)
    ref = linprog(cost, A_ub=A[le], b_ub=upper[le], A_eq=A[eq] if eq.any() else None,
                  b_eq=upper[eq] if eq.any() else None, bounds=list(zip(np.where(np.isinf(col_lo), None, col_lo), np.where(np.isinf(col_hi), None, col_hi))),
                  method="highs")
    assert status is Status.SOLVED and ref.status == 0
    assert value == pytest.approx(ref.fun, rel=1e-7)
    # the scaled LP's vertex, mapped back, keeps the unscaled rows
    x = np.asarray(lp.held.highs.getSolution().col_value) * lp.held.s
    assert np.array_equal(lp.held.block(x, "c"), c)
    assert np.all(A[le] @ x <= upper[le] + 1e-7 * (1 + abs(upper[le])))
    assert A[eq] @ x == pytest.approx(upper[eq], abs=1e-9)


def test_the_scaling_is_by_powers_of_two_and_brings_the_rows_near_one(window_lp):
    from mechopt.solvers.stop_impact.window_rows import coefficient_range
    lp = window_lp()
    r, s = lp.held.r, lp.held.s
    assert np.all(np.log2(r) == np.round(np.log2(r))) and np.all(np.log2(s) == np.round(np.log2(s)))
    raw_low, raw_high = coefficient_range(lp.rows.matrix())
    low, high = coefficient_range(lp.held.A)
    assert raw_high / raw_low > 1e10                 # the rows as assembled: 1e-8 ... 1e3
    assert 0.5 <= high <= 2.0
    row_max = abs(lp.held.A).max(axis=1).toarray().ravel()
    row_max = row_max[row_max > 0]                  # rows of zeros (S'' at a rest node) stay so
    assert np.all((row_max >= 0.5) & (row_max <= 2.0))


def test_a_window_does_not_depend_on_the_windows_solved_before_it(window_lp):
    fresh = window_lp().solve(0.85)
    lp = window_lp()
    for xa in (0.7, 0.9, 0.75):
        lp.solve(xa)
    again = lp.solve(0.85)
    assert again[0] is fresh[0] is Status.SOLVED
    assert np.array_equal(again[1], fresh[1]) and again[2] == fresh[2]


def test_a_window_neither_method_settles_is_given_up_and_counted_never_solved(window_lp, monkeypatch):
    from mechopt.solvers.stop_impact import window_rows as wr
    monkeypatch.setitem(wr.SIMPLEX_OPTIONS, "simplex_iteration_limit", 1)
    monkeypatch.setitem(wr.IPM_OPTIONS, "ipm_iteration_limit", 1)
    lp = window_lp()
    status, c, value, _ = lp.solve(0.85)
    assert status is Status.LIMIT and c is None and value == np.inf
    assert lp.given_up == 1 and lp.held.retried == 1


@pytest.mark.parametrize("zeta", [0.0, 0.05, 1.0, 2.5])
def test_the_step_matrices_exponential_matches_scipys_expm(zeta):
    """The first-order hold's 4 x 4 exponential (a scaled Taylor series, vectorised) against scipy's
    Pade expm, matrix by matrix, over the lambdas the scenes reach (lambda = omega T: <= ~300 at the
    plate's 768 Hz x 1.1 over a 60 deg rise at 180 rpm) and beyond, at the grids' steps h; both are
    rounding-limited (~1e-12 of the entries at lambda 2000, where 18 squarings amplify it)."""
    from scipy.linalg import expm

    from mechopt.models.cam_law import small_expm
    lam = np.geomspace(0.1, 500.0, 41)
    for h in (1 / 600, 1 / 200):
        M = np.zeros(lam.shape + (4, 4))
        M[:, 0, 1], M[:, 1, 0], M[:, 1, 1], M[:, 1, 2], M[:, 2, 3] = 1.0, -lam**2, -2 * zeta * lam, -1.0, 1.0
        ours = small_expm(M * h)
        for k in range(lam.size):
            ref = expm(M[k] * h)
            assert np.abs(ours[k] - ref).max() <= 1e-12 * max(1.0, np.abs(ref).max())
    X = np.random.default_rng(5).normal(size=(20, 3, 3)) * 4
    ref = np.array([expm(x) for x in X])
    assert np.all(np.abs(small_expm(X) - ref).max(axis=(1, 2)) <= 1e-12 * np.maximum(1.0, np.abs(ref).max(axis=(1, 2))))


def test_highs_statuses_read_as_cvxpys_table_reads_them():
    """kit.highs' own table of HiGHS' model statuses gives, for every status HiGHS has, what cvxpy's
    HIGHS.STATUS_MAP and from_cvxpy give (the loom's held LP reads them that way)."""
    import highspy
    from cvxpy.reductions.solvers.conic_solvers.highs_conif import HIGHS

    from mechopt.kit.highs import status_of
    from mechopt.kit.result import from_cvxpy

    class Done:
        def __init__(self, status):
            self.status = status

        def getModelStatus(self):
            return self.status
    names = [n for n in dir(highspy.HighsModelStatus) if n.startswith("k")]
    assert len(names) > 10
    for name in names:
        status = getattr(highspy.HighsModelStatus, name)
        assert status_of(Done(status)) is from_cvxpy(HIGHS.STATUS_MAP.get(name, "unknown")), name
    assert status_of(Done(highspy.HighsModelStatus.kOptimal)) is Status.SOLVED
