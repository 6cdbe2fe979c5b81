"""The event-time LP as matrices (incidence rows per kind of limit) and `HeldLP`, the LP held in
HiGHS with its basis for many solves that change bounds only (bisection on the speed, re-solves)."""
from dataclasses import dataclass
from typing import TYPE_CHECKING

import highspy
import numpy as np
import scipy.sparse as sp

from mechopt.kit.errors import SolverError
from mechopt.kit.highs import InterruptibleHighs, interruptible_everywhere, status_of
from mechopt.kit.result import Status

if TYPE_CHECKING:
    import cvxpy as cp

interruptible_everywhere()  # every HiGHS model, ours or cvxpy's: no banner, and Ctrl-C stops an LP at its next iteration


@dataclass
class EventTimeLP:
    """A built, DPP-compiled event-time LP: the problem, its Parameters and its constraint blocks."""
    problem: "cp.Problem"
    p: "cp.Variable"
    params: dict            # name -> cp.Parameter
    blocks: dict            # name -> cvxpy constraint (vector rows) or None
    stress_coeffs: tuple    # linear: (c0, c1) with rhs = c0 + c1 sigma_H; exact: (K,) with rhs = K / sigma_H
    sign: float             # +1 minimise, -1 maximise: d(objective)/d(rhs) = sign * dual


def incidence(n: int, tails: np.ndarray, heads: np.ndarray) -> sp.csr_matrix:
    """Arc-by-event incidence D with (D p)_e = p(head_e) - p(tail_e)."""
    m = len(tails)
    rows = np.repeat(np.arange(m), 2)
    cols = np.column_stack([heads, tails]).ravel()
    vals = np.tile([1.0, -1.0], m)
    return sp.csr_matrix((vals, (rows, cols)), shape=(m, n))


def build_event_time_lp(n, tails, heads, *, first, last, stress_rows=(), stress_ref=None,
                        stress_form="exact", amplitude_rows=(), window_arcs=(), sync_arcs=(),
                        limiting=None, with_cycle=False) -> EventTimeLP:
    """The event-time LP over n events, arcs tails[k] -> heads[k] (indices), Parameters unset.

    stress_ref : (sigma_ref_MPa, t_ref_deg) arrays for `stress_rows`.
    window_arcs, sync_arcs : (from, to) index pairs; limiting : (x, y) index pair to maximise.
    Parameters: min_deg (per arc), sigma_H_MPa or inv_sigma_H_per_MPa, amplitude slope,
    intercept and limit, window_deg, cycle_deg.
    """
    import cvxpy as cp  # here: seconds to import, and a held LP or a graph run never needs it
    tails, heads = np.asarray(tails, dtype=np.int64), np.asarray(heads, dtype=np.int64)
    D = incidence(n, tails, heads)
    p = cp.Variable(n, name="p_deg")
    params = {"min_deg": cp.Parameter(len(tails), name="min_deg")}
    blocks = {"min_angle": D @ p >= params["min_deg"], "anchor": p[first] == 0}
    coeffs = ()
    if len(stress_rows):
        rows = np.asarray(stress_rows)
        sigma_ref, t_ref = (np.asarray(a, dtype=float) for a in stress_ref)
        if stress_form == "linear":     # tangent at t_ref: t >= 2 t_ref - (t_ref / sigma_ref) sigma_H
            params["sigma_H_MPa"] = cp.Parameter(nonneg=True, name="sigma_H_MPa")
            coeffs = (2.0 * t_ref, -t_ref / sigma_ref)
            rhs = coeffs[0] + coeffs[1] * params["sigma_H_MPa"]
        else:                            # exact: t >= K / sigma_H, with 1/sigma_H the Parameter (DPP)
            params["inv_sigma_H_per_MPa"] = cp.Parameter(nonneg=True, name="inv_sigma_H_per_MPa")
            coeffs = (sigma_ref * t_ref,)
            rhs = coeffs[0] * params["inv_sigma_H_per_MPa"]
        blocks["contact_stress"] = D[rows] @ p >= rhs
    if len(amplitude_rows):
        for name in ("slope_mm_per_deg", "intercept_mm", "amplitude_limit_mm"):
            params[name] = cp.Parameter(name=name)
        t = D[np.asarray(amplitude_rows)] @ p
        blocks["amplitude"] = (params["slope_mm_per_deg"] * t + params["intercept_mm"]
                               <= params["amplitude_limit_mm"])
    if len(window_arcs):
        w = np.asarray(window_arcs)
        params["window_deg"] = cp.Parameter(len(w), name="window_deg")
        blocks["window"] = incidence(n, w[:, 0], w[:, 1]) @ p <= params["window_deg"]
    if len(sync_arcs):
        s = np.asarray(sync_arcs)
        blocks["sync"] = incidence(n, s[:, 0], s[:, 1]) @ p == 0
    if with_cycle:
        params["cycle_deg"] = cp.Parameter(nonneg=True, name="cycle_deg")
        blocks["cycle"] = p[last] - p[first] <= params["cycle_deg"]
    if limiting is None:
        objective, sign = cp.Minimize(p[last] - p[first]), 1.0
    else:
        objective, sign = cp.Maximize(p[limiting[1]] - p[limiting[0]]), -1.0
    problem = cp.Problem(objective, list(blocks.values()))
    if not problem.is_dpp():       # a re-solve would recompile: a bug in this builder, not in the input
        raise SolverError("event-time LP is not DPP; what-if re-solves would recompile")
    return EventTimeLP(problem, p, params, blocks, coeffs, sign)


class HeldLP:
    """The event-time LP held in HiGHS itself (highspy) with its basis: for many solves that change
    only bounds ([phi] per arc, the cycle), as bisection and what-if re-solves do. A re-solve is
    a hot-started dual simplex on the bounds changed in place: no cvxpy parameter application,
    no model hand-over (about 0.07 ms against cvxpy's 1 ms on the STB loom's group 1; benchmarks/loom.py).

    Rows: arcs p(y) - p(x) >= lb, windows <= w, syncs = 0, the cycle p(last) - p(first) <=
    cycle; p(first) = 0 as a column bound. Minimises the span. HiGHS's status words are read
    by `kit.highs.status_of` (the statuses cvxpy's HIGHS.STATUS_MAP and `from_cvxpy` give: no
    cvxpy import for a held LP).
    """

    def __init__(self, n, tails, heads, *, first, last, window_arcs=(), sync_arcs=(), with_cycle=False):
        rows = [incidence(n, tails, heads)]
        self.arcs, self.windows, self.with_cycle = len(tails), len(window_arcs), with_cycle
        for pairs in (window_arcs, sync_arcs):
            if len(pairs):
                pairs = np.asarray(pairs)
                rows.append(incidence(n, pairs[:, 0], pairs[:, 1]))
        if with_cycle:
            rows.append(sp.csr_matrix(([1.0, -1.0], ([0, 0], [last, first])), shape=(1, n)))
        A = sp.vstack(rows, format="csr")
        inf = highspy.kHighsInf
        self.upper = np.r_[np.full(self.arcs, inf), np.zeros(self.windows), np.zeros(len(sync_arcs)),
                           np.zeros(int(with_cycle))]
        self.lower = np.r_[np.zeros(self.arcs), np.full(self.windows, -inf), np.zeros(len(sync_arcs)),
                           np.full(int(with_cycle), -inf)]
        self.highs = InterruptibleHighs()
        self.highs.setOptionValue("output_flag", False)
        col_lo, col_hi = np.full(n, -inf), np.full(n, inf)
        col_lo[first] = col_hi[first] = 0.0                      # the anchor
        self.highs.addVars(n, col_lo, col_hi)
        cost = np.zeros(n)
        cost[last], cost[first] = 1.0, -1.0
        self.highs.changeColsCost(n, np.arange(n, dtype=np.int32), cost)
        self.highs.addRows(A.shape[0], self.lower, self.upper, A.nnz, A.indptr[:-1].astype(np.int32),
                           A.indices.astype(np.int32), A.data)
        self.index = np.arange(A.shape[0], dtype=np.int32)

    def solve(self, lb_deg, window_deg=(), cycle_deg=None):
        """(Status, event times or None) with the arcs' lower bounds `lb_deg` [deg]."""
        self.lower[:self.arcs] = lb_deg
        if self.windows:
            self.upper[self.arcs:self.arcs + self.windows] = window_deg
        if cycle_deg is not None:
            if not self.with_cycle:         # the last row is an arc, a window or a sync here
                raise SolverError("HeldLP.solve(cycle_deg=...): this LP was built without the cycle row")
            self.upper[-1] = cycle_deg
        self.highs.changeRowsBounds(len(self.index), self.index, self.lower, self.upper)
        self.highs.run()
        status = status_of(self.highs)
        return status, (np.array(self.highs.getSolution().col_value) if status is Status.SOLVED else None)
