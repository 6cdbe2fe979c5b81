"""Event times of a network cyclogram as a linear program in cvxpy (paper 004, problem (1)).

    minimise p(N) - p(1)   subject to   p(y) - p(x) >= [phi(x, y)]                 every operation
                                        p(y) - p(x) >= sigma-bound(x, y; [sigma_H])  cam pairs
                                        slope (p(7) - p(3)) + intercept <= a_lim    amplitude law
                                        p(y) - p(x) <= w,  p(a) = p(b)             windows, syncs
                                        p(1) = 0                                     anchor

or, for a machine with a limiting operation (x*, y*), maximise p(y*) - p(x*) with p(N) - p(1) <=
cycle. Constraints are built from the incidence matrix (one vectorised row block per kind); every
limit is a cvxpy Parameter, so a what-if re-solve reuses the compiled problem (DPP). The anchor
p(1) = 0 removes the shift invariance that otherwise slows HiGHS a hundredfold.

Entry points: `plan_cyclogram` (this LP); `repair_cyclogram` (its optimum checked against the
exact rebound and contact stress, re-linearised and re-solved until they hold, with the exact
bound `exact_amplitude_bound` where the wavy rebound's tangent cannot be trusted: issue 14, part
4); `max_machine_speed` (the largest main-shaft speed: an LP in (p, n) when every law is a
function of n / t, which a probe checks; bisection on n as the general route and its check: part 5). `HeldLP` keeps
the LP in HiGHS for many solves that change bounds only.

Sensitivities are reported in user terms with one sign convention: d(objective)/d(limit), the
change of the objective (span_deg, or limiting_op_deg on a machine) per unit *increase* of the
limit. Raising [sigma_H] or the amplitude limit loosens a bound: the span falls (<= 0); raising a
critical [phi] lengthens it (+1 deg/deg).
"""
import dataclasses
import functools
import math
import time
from collections import deque
from dataclasses import dataclass
from typing import Annotated, Literal

import cvxpy as cp
import highspy
import networkx as nx
import numpy as np
import scipy.sparse as sp
from cvxpy.reductions.solvers.conic_solvers.highs_conif import HIGHS as HIGHS_SOLVER
from scipy.optimize import brentq

from mechopt.models.cache import BuildCache
from mechopt.models.errors import ModelError, SolverError
from mechopt.models.loom import MAX_RPM, Cyclogram, amplitude_mm, stress_bound_deg, stress_MPa
from mechopt.solvers.result import Result, Status, Timing, from_cvxpy
from mechopt.solvers.settings import Interval, Tolerance
from mechopt.solvers.stop_impact.law import rebound_amplitude_mm

__all__ = ["max_machine_speed", "plan_cyclogram", "repair_cyclogram"]

SENSITIVITY_CONVENTION = ("sens_* = d(objective)/d(limit): change of the objective [deg] per unit increase "
                          "of the limit; negative means a looser limit shortens the span")


@dataclass
class EventTimeLP:
    """A built, DPP-compiled event-time LP: the problem, its Parameters and its constraint blocks."""
    problem: cp.Problem
    p: cp.Variable
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
    no model hand-over (about 0.07 ms against cvxpy's 1 ms on group 1; benchmarks/loom.py).

    Rows: arcs p(y) - p(x) >= lb, windows <= w, syncs = 0, the cycle p(last) - p(first) <=
    cycle; p(first) = 0 as a column bound. Minimises the span. HiGHS's status words are read
    through cvxpy's own table (HIGHS.STATUS_MAP) and `from_cvxpy`: one table of them.
    """

    def __init__(self, n, tails, heads, *, first, last, window_arcs=(), sync_arcs=(), with_cycle=False):
        rows = [incidence(n, tails, heads)]
        self.arcs, self.windows = len(tails), len(window_arcs)
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
        self.highs = highspy.Highs()
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
            self.upper[-1] = cycle_deg
        self.highs.changeRowsBounds(len(self.index), self.index, self.lower, self.upper)
        self.highs.run()
        status = from_cvxpy(HIGHS_SOLVER.STATUS_MAP.get(self.highs.getModelStatus().name, "unknown"))
        return status, (np.array(self.highs.getSolution().col_value) if status is Status.SOLVED else None)


# structural signature -> EventTimeLP, compiled once and re-solved with new Parameters; the newest
# few only: a 10^5-event build holds ~100 MB
_BUILDS = BuildCache("loom.event_time_lp", maxsize=8)


def plan_cyclogram(task: Cyclogram, *, backend: Literal["HIGHS", "CLARABEL"] = "HIGHS",
                   stress_form: Literal["exact", "linear"] = "exact", warm_start: bool = False,
                   tol_deg: Tolerance = 1e-6) -> Result:
    """Event times minimising the span p(N) - p(1) of a cyclogram (paper 004, problem (1)), or
    maximising the machine's limiting operation inside its cycle.

    Parameters
    ----------
    task : the network and its limits (models/loom.py).
    backend : LP solver behind cvxpy.
    stress_form : "exact" sigma_max(t) <= [sigma_H] as t >= K/[sigma_H]; "linear" its tangent at t_ref.
    warm_start : pass cvxpy's warm start to the back end (with HiGHS it can slow re-solves).
    tol_deg : tolerance [deg] for float = 0 (critical), binding constraints and the cross-check.

    Returns
    -------
    Result with values span_deg, longest_path_deg (networkx / Bellman-Ford cross-check),
    p_<event>_deg, t_<x>_<y>_deg, amplitude_<x>_<y>_mm, sigma_<x>_<y>_MPa, span_<group>_deg,
    limiting_op_deg (machines) and sens_* sensitivities (see SENSITIVITY_CONVENTION);
    diagnostics: float_deg, critical_ops, critical_chain, binding (with duals), sens_min_deg.
    An infeasible problem names its conflicting chain (a positive cycle of the difference
    constraints) in `message` and `violated`, its events and excess [deg] in `diagnostics`.

    The back end's answer is checked against the exact certificate, whatever it says: a positive
    cycle (above 1e-12 of the largest angle: round-off) makes the result INFEASIBLE, an optimum
    differing from the longest path by more than tol_deg * max(1, |longest path|) INACCURATE.

    Examples
    --------
    >>> from mechopt import registry
    >>> r = plan_cyclogram(registry.find("loom/group1").build()[0])
    >>> r.status.value, r.diagnostics["critical_chain"][:3]                             # doctest: +SKIP
    ('SOLVED', ['1', '3', '7'])
    """
    start = time.perf_counter()
    net = _Net(task, stress_form)
    def build():
        lp = build_event_time_lp(len(net.names), net.tails, net.heads, first=net.first, last=net.last,
                                 stress_rows=net.stress_rows, stress_ref=net.stress_ref, stress_form=stress_form,
                                 amplitude_rows=net.amp_rows, window_arcs=net.window_idx, sync_arcs=net.sync_idx,
                                 limiting=net.limiting, with_cycle=task.cycle_deg is not None)
        set_parameters(lp, task, net)
        lp.problem.get_problem_data(backend)      # compile now, so build and solve time separate
        return lp
    # cvxpy caches one compiled chain per problem and solver
    key = (backend, *net.signature())
    fresh = key not in _BUILDS
    lp, _ = _BUILDS.get(key, build)
    set_parameters(lp, task, net)
    build_s = time.perf_counter() - start
    try:
        lp.problem.solve(solver=backend, warm_start=warm_start)
    except cp.error.SolverError as exc:
        return Result(Status.FAILED, {}, Timing(build_s, time.perf_counter() - start - build_s),
                      message=f"{backend} failed: {exc}")
    status = from_cvxpy(lp.problem.status)
    diagnostics = {"backend": backend, "stress_form": stress_form, "compiled_now": fresh,
                   "events": len(net.names), "operations": len(net.tails), "isolated_events": task.isolated_events,
                   "solver_status": lp.problem.status, "solve_time_backend_s": lp.problem.solver_stats.solve_time}
    timing = lambda: Timing(build_s, time.perf_counter() - start - build_s)      # noqa: E731
    # the certificate: an optimum is only trusted when the difference constraints hold no positive cycle
    chain = conflict_chain(net) if status is Status.INFEASIBLE or _may_conflict(net) else []
    if chain:
        excess = math.fsum(w for _, _, w in chain)
        diagnostics |= {"conflict_events": [v for v, _, _ in chain], "conflict_excess_deg": excess}
        message = "infeasible: conflicting chain " + "; ".join(label for _, label, _ in chain)
        message += f" (needs {excess:.6g} deg more than its limits allow)"
        if status is not Status.INFEASIBLE:
            message += f"; {backend} reported {lp.problem.status}, the longest-path certificate overrules it"
        return Result(Status.INFEASIBLE, {}, timing(), message=message,
                      violated=tuple(label for _, label, _ in chain), diagnostics=diagnostics)
    if status is not Status.SOLVED:
        message = f"{backend}: {lp.problem.status}"
        if status is Status.INFEASIBLE:
            message += " (no positive cycle among the difference constraints: a numerical failure?)"
        return Result(status, {}, timing(), message=message, diagnostics=diagnostics)
    values, more, overstressed, disagreement = _report(task, net, lp, tol_deg)
    diagnostics |= more
    solve_s = time.perf_counter() - start - build_s
    if disagreement:
        return Result(Status.INACCURATE, values, Timing(build_s, solve_s), message=disagreement,
                      violated=overstressed, diagnostics=diagnostics)
    objective = "limiting_op_deg" if net.limiting else "span_deg"
    message = (f"{objective} = {values[objective]:.6g} ({backend}, {stress_form} stress, "
               f"{'compiled' if fresh else 'DPP re-solve'}); {SENSITIVITY_CONVENTION}")
    if overstressed:      # the tangent under-estimates sigma_max: the linearised optimum breaks the true limit
        message += f"; the linearised stress limit lets sigma_max exceed [sigma_H] on {', '.join(overstressed)}"
    return Result(Status.SOLVED, values, Timing(build_s, solve_s), message=message, violated=overstressed,
                  diagnostics=diagnostics)


def _may_conflict(net) -> bool:
    """Whether the constraints can hold a positive cycle: windows and syncs can; a DAG of
    operations only with its cycle, when its longest path (linear time) is longer than it."""
    task = net.task
    if task.windows or task.syncs:
        return True
    if task.cycle_deg is None:
        return False
    early, _ = _dag_times(len(net.names), net.tails, net.heads, net.lb, net.first, net.last, 0.0)
    return early[net.last] > task.cycle_deg


def set_parameters(lp: EventTimeLP, task: Cyclogram, net) -> None:
    """Write the task's limits into the LP's Parameters (no recompilation)."""
    prm = lp.params
    prm["min_deg"].value = task.min_angles_deg()
    if "sigma_H_MPa" in prm:
        prm["sigma_H_MPa"].value = task.sigma_H_limit_MPa
    if "inv_sigma_H_per_MPa" in prm:
        prm["inv_sigma_H_per_MPa"].value = 1.0 / task.sigma_H_limit_MPa
    if "slope_mm_per_deg" in prm:
        prm["slope_mm_per_deg"].value = task.amplitude_slope_mm_per_deg
        prm["intercept_mm"].value = task.amplitude_intercept_mm
        prm["amplitude_limit_mm"].value = task.amplitude_limit_mm
    if "window_deg" in prm:
        prm["window_deg"].value = np.array([w for _, _, w in task.window_arcs()])
    if "cycle_deg" in prm:
        prm["cycle_deg"].value = task.cycle_deg


class _Net:
    """The task as index arrays (events in graph order, isolated events left out)."""

    def __init__(self, task: Cyclogram, stress_form: str):
        self.stress_form = stress_form
        self._index_arrays(task)
        self.stress_rows = task.stress_arcs()
        refs = [task.stress_reference(k) for k in self.stress_rows]
        self.stress_ref = (np.array([r[0] for r in refs]), np.array([r[1] for r in refs]))
        self.amp_rows = task.amplitude_arcs()
        if self.amp_rows and not task.has_linear_amplitude:
            raise ModelError("amplitude_slope_mm_per_deg: the LP needs the linear amplitude law; with the lever's "
                             "exact law alone use loom.repair_cyclogram or loom.max_machine_speed",
                             key="amplitude_slope_mm_per_deg")
        self.lb, self.lb_why = task.lower_bounds_deg(stress_form)

    @classmethod
    def structure(cls, task: Cyclogram) -> "_Net":
        """The index arrays alone (events, arcs, ends, windows, syncs), for LPs with their own bounds."""
        net = cls.__new__(cls)
        net._index_arrays(task)
        return net

    def _index_arrays(self, task):
        self.task = task
        isolated = set(task.isolated_events)
        self.names = [v for v in task.event_names if v not in isolated]
        index = {v: i for i, v in enumerate(self.names)}
        self.index = index
        arcs = task.arcs
        self.arcs = arcs
        self.tails = np.fromiter((index[x] for x, _ in arcs), dtype=np.int64, count=len(arcs))
        self.heads = np.fromiter((index[y] for _, y in arcs), dtype=np.int64, count=len(arcs))
        self.first, self.last = index[task.first_event], index[task.last_event]
        self.window_idx = [(index[a], index[b]) for a, b, _ in task.window_arcs()]
        self.sync_idx = [(index[a], index[b]) for a, b in task.sync_pairs()]
        lim = task.limiting_op
        self.limiting = None if lim is None else (index[str(lim[0])], index[str(lim[1])])

    def signature(self):
        """What the compiled problem depends on (everything except the Parameters' values)."""
        return (self.stress_form, len(self.names), self.tails.tobytes(), self.heads.tobytes(), self.first,
                self.last, tuple(self.stress_rows), self.stress_ref[0].tobytes(), self.stress_ref[1].tobytes(),
                tuple(self.amp_rows), tuple(self.window_idx), tuple(self.sync_idx), self.limiting,
                self.task.cycle_deg is not None)

    def arc_label(self, k):
        x, y = self.arcs[k]
        return f"t({x}->{y}) >= {self.lb[k]:.6g} deg ({self.lb_why[k]})"


def conflict_chain(net) -> list[tuple[str, str, float]]:
    """A positive cycle of the difference constraints (operations with their bounds, windows,
    syncs and the machine cycle), as [(event, label and bound [deg] of the arc leaving it)]: the
    bounds sum to more than 0 (a cycle cannot hold them, p(v) - p(u) >= w all round); empty when there is
    none. Our own Bellman-Ford: networkx's find_negative_cycle can detect a cycle and then fail
    to extract it ("Negative cycle is detected but not found", networkx issue #5916)."""
    tight: dict = {}                       # (u, v) -> (w, label): the tightest constraint per pair

    def add(u, v, w, label):               # p(v) - p(u) >= w
        if (u, v) not in tight or w > tight[u, v][0]:
            tight[u, v] = (w, label)

    for k, (x, y) in enumerate(net.arcs):
        add(x, y, float(net.lb[k]), net.arc_label(k))
    for a, b, w in net.task.window_arcs():
        add(b, a, -w, f"window p({b}) - p({a}) <= {w:.6g} deg")
    for a, b in net.task.sync_pairs():
        add(a, b, 0.0, f"sync p({a}) = p({b})")
        add(b, a, 0.0, f"sync p({b}) = p({a})")
    if net.task.cycle_deg is not None:
        first, last = net.names[net.first], net.names[net.last]
        add(last, first, -net.task.cycle_deg, f"cycle p({last}) - p({first}) <= {net.task.cycle_deg:.6g} deg")
    arcs = [(u, v, w, label) for (u, v), (w, label) in tight.items()]
    return [(u, label, w) for u, _, w, label in positive_cycle(arcs)]


def positive_cycle(arcs) -> list[tuple]:
    """A cycle of difference constraints (u, v, w, label), p(v) - p(u) >= w, whose w sum to more
    than 0, in order around the cycle; [] when there is none.

    Longest-path Bellman-Ford from a virtual root (every distance starts at 0), queue order; a
    relaxation counts only when it gains more than 1e-12 of the largest |w| (round-off, so a
    zero cycle of windows or syncs is not taken for a positive one): cycles above that are
    found. Every n relaxations the predecessor arcs are searched for a cycle, which (all
    relaxations strict) is a positive one; its sum is re-checked with math.fsum.
    """
    if not arcs:
        return []
    nodes = list(dict.fromkeys(v for a in arcs for v in a[:2]))
    index = {v: i for i, v in enumerate(nodes)}
    n = len(nodes)
    out = [[] for _ in range(n)]
    for k, (u, v, w, _) in enumerate(arcs):
        out[index[u]].append((index[v], float(w), k))
    eps = 1e-12 * max(1.0, max(abs(float(a[2])) for a in arcs))
    dist, pred = [0.0] * n, [-1] * n
    queue, queued = deque(range(n)), [True] * n
    relaxed, cap = 0, n * len(arcs) + n         # Bellman-Ford's bound: past it a cycle must exist
    while queue:
        u = queue.popleft()
        queued[u] = False
        for v, w, k in out[u]:
            if dist[u] + w > dist[v] + eps:
                dist[v], pred[v] = dist[u] + w, k
                relaxed += 1
                if relaxed % n == 0 or relaxed > cap:
                    cycle = _predecessor_cycle(arcs, index, pred)
                    if cycle:
                        return cycle
                if not queued[v]:
                    queue.append(v)
                    queued[v] = True
    return []


def _predecessor_cycle(arcs, index, pred):
    """A cycle of the predecessor arcs with a positive sum, in forward order, or []."""
    seen = [0] * len(pred)                       # 0 unseen, else the walk that reached it
    for start in range(len(pred)):
        walk, v = start + 1, start
        while v != -1 and not seen[v]:
            seen[v] = walk
            v = -1 if pred[v] < 0 else index[arcs[pred[v]][0]]
        if v == -1 or seen[v] != walk:
            continue
        cycle, u = [], v                         # v lies on a cycle of this walk: unroll it
        while True:
            k = pred[u]
            cycle.append(arcs[k])
            u = index[arcs[k][0]]
            if u == v:
                break
        cycle.reverse()
        if math.fsum(a[2] for a in cycle) > 0:
            return cycle
    return []


def _report(task, net, lp, tol):
    """Values and diagnostics of a solved LP: times, angles, floats, duals, the cross-check."""
    p = lp.p.value
    p = p - p[net.first]                      # the anchor holds to solver precision; make it exact
    t = p[net.heads] - p[net.tails]
    span = float(p[net.last] - p[net.first])
    values = {"span_deg": span}
    if net.limiting:
        values["limiting_op_deg"] = float(p[net.limiting[1]] - p[net.limiting[0]])
    values |= {f"p_{v}_deg": float(p[i]) for i, v in enumerate(net.names)}
    values |= {f"t_{x}_{y}_deg": float(t[k]) for k, (x, y) in enumerate(net.arcs)}
    for k in net.amp_rows:
        x, y = net.arcs[k]
        values[f"amplitude_{x}_{y}_mm"] = float(amplitude_mm(task.amplitude_slope_mm_per_deg,
                                                              task.amplitude_intercept_mm, t[k]))
    for k in net.stress_rows:
        x, y = net.arcs[k]
        values[f"sigma_{x}_{y}_MPa"] = float(stress_MPa(*task.stress_reference(k), t[k]))
    for group, members in task.groups.items():
        times = [p[net.index[v]] for v in members if v in net.index]
        if times:
            values[f"span_{group}_deg"] = float(max(times) - min(times))
    overstressed = [f"contact_stress[{x}->{y}]" for k, (x, y) in ((k, net.arcs[k]) for k in net.stress_rows)
                    if values[f"sigma_{x}_{y}_MPa"] > task.sigma_H_limit_MPa * (1 + 1e-9)]

    longest, disagreement = _cross_check(task, net, values, tol)
    if longest is not None:
        values["longest_path_deg"] = longest
    sens, binding, sens_min = _sensitivities(task, net, lp, t, tol)
    values |= sens
    floats = _floats(task, net, p, values, tol)
    diagnostics = {"binding": binding, "sens_min_deg": sens_min, "sensitivity_convention": SENSITIVITY_CONVENTION,
                   "bound_source": {f"{x}->{y}": net.lb_why[k] for k, (x, y) in enumerate(net.arcs)},
                   "stress_gap_deg": {f"{x}->{y}": _stress_gap(task, k) for k, (x, y) in
                                      ((k, net.arcs[k]) for k in net.stress_rows)}}
    diagnostics |= floats
    return values, diagnostics, tuple(overstressed), disagreement


def _stress_gap(task, k):
    """Exact minus linearised stress bound of arc k [deg]: >= 0, the tangent lies under sigma_max."""
    ref = task.stress_reference(k)
    return float(stress_bound_deg(*ref, task.sigma_H_limit_MPa, "exact")
                 - stress_bound_deg(*ref, task.sigma_H_limit_MPa, "linear"))


def _cross_check(task, net, values, tol):
    """The LP's optimum against the exact longest-path certificate: (longest first -> last [deg],
    None or why the LP is not to be trusted). Tolerance: tol * max(1, |certificate|) [deg].

    Without windows or syncs: networkx's DAG longest path (span), and for a machine the cycle
    minus the longest chains before and after the limiting operation. With them: Bellman-Ford
    on every difference constraint; max t(x*, y*) is minus the longest path y* -> x* through
    the cycle's arc (the shortest-path dual of the LP)."""
    lb = net.lb
    if np.array_equal(lb, task.min_angles_deg()):      # no stress or amplitude bound: the model's graph as it is
        g, weight = task.graph, "min_deg"
    else:
        g, weight = nx.DiGraph(), "weight"
        g.add_weighted_edges_from((x, y, lb[k]) for k, (x, y) in enumerate(net.arcs))
    first, last = net.names[net.first], net.names[net.last]
    arcs = _constraint_arcs(net, lb)
    try:
        if task.windows or task.syncs:
            longest = _longest(arcs, first)[last]
            route = "Bellman-Ford on the difference constraints"
        else:
            longest = nx.dag_longest_path_length(g, weight=weight)
            route = "networkx dag_longest_path_length"
        if net.limiting:
            x, y = net.names[net.limiting[0]], net.names[net.limiting[1]]
            got, what = values["limiting_op_deg"], "limiting_op_deg"
            if task.windows or task.syncs:
                cycle = [] if task.cycle_deg is None else [(last, first, -task.cycle_deg)]
                back = _longest(arcs + cycle, y).get(x)
                expected = np.inf if back is None else -back
            else:
                before = nx.dag_longest_path_length(g.subgraph(nx.ancestors(g, x) | {x}), weight=weight)
                after = nx.dag_longest_path_length(g.subgraph(nx.descendants(g, y) | {y}), weight=weight)
                expected = task.cycle_deg - before - after
        else:
            expected, got, what = longest, values["span_deg"], "span_deg"
    except nx.NetworkXUnbounded:       # a cycle within round-off of zero that Bellman-Ford takes as positive
        return None, ("cross-check failed: the LP reports an optimum but Bellman-Ford finds a positive cycle "
                      "that the conflict search (1e-12 round-off margin) does not: not certified")
    longest = float(longest) if np.isfinite(longest) else None
    if not abs(expected - got) <= tol * max(1.0, abs(expected)):
        return longest, (f"cross-check failed: LP {what} = {got!r} but {route} gives {expected!r} "
                         f"(tolerance {tol:g} deg per degree above 1): not certified")
    return longest, None


def _constraint_arcs(net, lb):
    """Every difference constraint as (u, v, w): p(v) - p(u) >= w [deg]."""
    arcs = [(x, y, float(lb[k])) for k, (x, y) in enumerate(net.arcs)]
    arcs += [(b, a, -w) for a, b, w in net.task.window_arcs()]
    arcs += [arc for a, b in net.task.sync_pairs() for arc in ((a, b, 0.0), (b, a, 0.0))]
    return arcs


def _longest(arcs, source, reverse=False):
    """Longest distances from `source` over difference constraints (u, v, w) by Bellman-Ford on
    negated weights [deg]; `reverse` follows the arcs backwards (distances *to* source)."""
    g = nx.DiGraph()
    for u, v, w in arcs:
        u, v = (v, u) if reverse else (u, v)
        if not g.has_edge(u, v) or g.edges[u, v]["weight"] > -w:      # keep the tightest
            g.add_edge(u, v, weight=-w)
    return {v: -d for v, d in nx.single_source_bellman_ford_path_length(g, source).items()}


def _sensitivities(task, net, lp, t, tol):
    """d(objective)/d(limit) from the duals, and the binding constraints by name."""
    s, blocks = lp.sign, lp.blocks
    sens, binding = {}, []
    dual_phi = np.asarray(blocks["min_angle"].dual_value, dtype=float).ravel()
    sens_min, phi = {}, task.min_angles_deg()
    for k, (x, y) in enumerate(net.arcs):
        if t[k] - phi[k] <= tol:
            binding.append({"constraint": f"min_angle[{x}->{y}]", "dual_deg_per_deg": float(s * dual_phi[k]) + 0.0})
        if abs(dual_phi[k]) > tol:
            sens_min[f"{x}->{y}"] = float(s * dual_phi[k])
    if "contact_stress" in blocks:
        dual = np.asarray(blocks["contact_stress"].dual_value, dtype=float).ravel()
        sigma = task.sigma_H_limit_MPa
        if "sigma_H_MPa" in lp.params:
            drhs = lp.stress_coeffs[1]                       # d(rhs)/d(sigma_H), tangent form
        else:
            drhs = -lp.stress_coeffs[0] / sigma**2           # d(K / sigma_H)/d(sigma_H)
        sens["sens_sigma_H_deg_per_MPa"] = float(s * np.dot(dual, drhs))
        rhs = (lp.stress_coeffs[0] + lp.stress_coeffs[1] * sigma if len(lp.stress_coeffs) == 2
               else lp.stress_coeffs[0] / sigma)
        for j, k in enumerate(net.stress_rows):
            if t[k] - rhs[j] <= tol:
                x, y = net.arcs[k]
                binding.append({"constraint": f"contact_stress[{x}->{y}]",
                                "dual_deg_per_MPa": float(s * dual[j] * drhs[j])})
    if "amplitude" in blocks:
        dual = np.asarray(blocks["amplitude"].dual_value, dtype=float).ravel()
        sens["sens_amplitude_limit_deg_per_mm"] = float(-s * dual.sum())     # <= form: d/d(limit) = -dual
        for j, k in enumerate(net.amp_rows):
            a = amplitude_mm(task.amplitude_slope_mm_per_deg, task.amplitude_intercept_mm, t[k])
            if task.amplitude_limit_mm - a <= tol * abs(task.amplitude_slope_mm_per_deg):
                x, y = net.arcs[k]
                binding.append({"constraint": f"amplitude[{x}->{y}]", "dual_deg_per_mm": float(-s * dual[j])})
    if "window" in blocks:
        dual = np.asarray(blocks["window"].dual_value, dtype=float).ravel()
        for j, (a, b, w) in enumerate(task.window_arcs()):
            sens[f"sens_window_{a}_{b}_deg_per_deg"] = float(-s * dual[j])
            if w - (lp.p.value[net.index[b]] - lp.p.value[net.index[a]]) <= tol:
                binding.append({"constraint": f"window[{a}->{b}]", "dual_deg_per_deg": float(-s * dual[j])})
    if "cycle" in blocks:
        dual = float(np.asarray(blocks["cycle"].dual_value))
        sens["sens_cycle_deg_per_deg"] = -s * dual
        binding.append({"constraint": "cycle", "dual_deg_per_deg": -s * dual}) if abs(dual) > tol else None
    return sens, binding, sens_min


def _floats(task, net, p, values, tol):
    """Total float of every operation, LS(y) - ES(x) - lb, for the found span (a machine: with the
    limiting operation held at its optimum); critical = float <= tol."""
    names, lb = net.names, net.lb.copy()
    if net.limiting:
        k = next(k for k, (x, y) in enumerate(net.arcs) if (net.index[x], net.index[y]) == net.limiting)
        lb[k] = values["limiting_op_deg"] - tol / 10      # held at its optimum (a hair under: no 0+ cycle)
    first, last = names[net.first], names[net.last]
    span = values["span_deg"]
    try:
        if task.windows or task.syncs:
            arcs = _constraint_arcs(net, lb)
            early = _longest(arcs, first)
            to_last, to_first = _longest(arcs, last, reverse=True), _longest(arcs, first, reverse=True)
            late = {v: min(span - to_last.get(v, -np.inf), -to_first.get(v, -np.inf)) for v in names}
        else:
            e, l = _dag_times(len(names), net.tails, net.heads, lb, net.first, net.last, span)
            early, late = dict(zip(names, e.tolist())), dict(zip(names, l.tolist()))
    except nx.NetworkXUnbounded:
        return {"floats": "not available: round-off made a zero cycle positive"}
    floats = {f"{x}->{y}": float(late[y] - early[x] - lb[k]) for k, (x, y) in enumerate(net.arcs)}
    critical = [k for k, v in floats.items() if v <= tol]
    crit = nx.DiGraph([tuple(k.split("->")) for k in critical])
    linked = first in crit and last in crit and nx.has_path(crit, first, last)
    chain = nx.shortest_path(crit, first, last) if linked else []     # one of the critical chains
    return {"float_deg": floats, "critical_ops": critical, "critical_chain": chain}


def _dag_times(n, tails, heads, lb, first, last, span):
    """Earliest and latest event times of a DAG (arcs tails -> heads, durations lb) [deg], by
    Kahn's topological order on index arrays: no graph objects, linear in the arcs."""
    out_start = np.r_[0, np.cumsum(np.bincount(tails, minlength=n))]
    by_tail = np.argsort(tails, kind="stable")
    indeg = np.bincount(heads, minlength=n)
    order, stack = [], [v for v in range(n) if indeg[v] == 0]
    succ, lbl, hl = by_tail.tolist(), lb.tolist(), heads.tolist()
    bounds = out_start.tolist()
    indeg = indeg.tolist()
    while stack:
        u = stack.pop()
        order.append(u)
        for k in succ[bounds[u]:bounds[u + 1]]:
            v = hl[k]
            indeg[v] -= 1
            if indeg[v] == 0:
                stack.append(v)
    early, late = [-np.inf] * n, [np.inf] * n
    early[first], late[last] = 0.0, span
    for u in order:
        for k in succ[bounds[u]:bounds[u + 1]]:
            if early[u] + lbl[k] > early[hl[k]]:
                early[hl[k]] = early[u] + lbl[k]
    for u in reversed(order):
        for k in succ[bounds[u]:bounds[u + 1]]:
            if late[hl[k]] - lbl[k] < late[u]:
                late[u] = late[hl[k]] - lbl[k]
    return np.array(early), np.array(late)


# ------------------------------------------------------------------ check and repair after the LP (issue 14, part 4)

def exact_amplitude_mm(task: Cyclogram, t_deg, speed_rpm=None, lost=None):
    """The lever's exact first rebound a(t, n) [mm] (the chain cam -> approach velocity -> impact
    -> eq. (2), solvers/stop_impact/law.py) at `speed_rpm`, by default the task's speed;
    vectorised over t and n. Where the roller leaves its cam: RollerLeftCam, or `lost`."""
    speed = task.speed_rpm if speed_rpm is None else speed_rpm
    if speed is None:
        raise ModelError("speed_rpm: the exact rebound law needs the main shaft's speed", key="speed_rpm")
    return rebound_amplitude_mm(task.lever_model, speed, t_deg, lost=lost)


@dataclass(frozen=True)
class AmplitudeBound:
    """Where the exact rebound keeps its limit at one speed, on the stated range [lo_deg, to_deg]
    of t: a(t) <= limit for every t in [from_deg, to_deg] (on the scan's grid of step_deg, the
    crossing polished by brentq). `why`: "crossing" (a crosses the limit at from_deg),
    "roller_left" (the roller leaves its cam below from_deg), "range" (a holds on the whole
    range: from_deg = lo_deg) or "none" (a exceeds the limit already at to_deg: from_deg None)."""
    speed_rpm: float
    from_deg: float | None
    lo_deg: float
    to_deg: float
    step_deg: float
    amplitude_mm: float       # a at from_deg (at to_deg when none holds)
    why: str
    evaluations: int

    def statement(self) -> str:
        if self.from_deg is None:
            return (f"a({self.to_deg:.6g} deg, {self.speed_rpm:.6g} rpm) = {self.amplitude_mm:.6g} mm exceeds the limit "
                    f"at the top of the stated range [{self.lo_deg:.6g}, {self.to_deg:.6g}] deg: no t there keeps it")
        return (f"a <= limit for every t in [{self.from_deg:.9g}, {self.to_deg:.6g}] deg at {self.speed_rpm:.6g} rpm "
                f"(scan step {self.step_deg:g} deg from {self.to_deg:.6g} down, {self.why}"
                f"{', brentq' if self.why == 'crossing' else ''}; {self.evaluations} evaluations)")


def exact_amplitude_bound(task: Cyclogram, speed_rpm: float, lo_deg: float, to_deg: float,
                          step_deg: float) -> AmplitudeBound:
    """The smallest t in [lo_deg, to_deg] beyond which the exact rebound stays <= its limit up to
    to_deg, at speed n: a walk down from to_deg in steps of step_deg to the first point over the
    limit (or where the roller leaves its cam), the crossing in that last step by brentq
    (bisection where the roller leaves: no rebound there to take a root of). a(t) is wavy (the
    lever rings during the rise), so no tangent can give this bound; wiggles narrower than the
    step are not resolved (tests/test_loom_repair.py checks the step against a dense scan)."""
    limit, count = task.amplitude_limit_mm, [0]

    def excess(t):
        count[0] += 1
        return float(np.ravel(exact_amplitude_mm(task, t, speed_rpm, lost=np.inf))[0]) - limit

    def bound(from_deg, amplitude, why):
        return AmplitudeBound(speed_rpm, from_deg, lo_deg, to_deg, step_deg, amplitude, why, count[0])
    top = excess(to_deg)
    if top > 0:
        return bound(None, top + limit, "none")
    hi = to_deg
    while hi > lo_deg:
        lo = max(hi - step_deg, lo_deg)
        over = excess(lo)
        if over > 0 and math.isfinite(over):
            root = brentq(excess, lo, hi, xtol=1e-12 * hi, rtol=4 * np.finfo(float).eps)
            return bound(root, excess(root) + limit, "crossing")
        if over > 0:                            # the roller leaves its cam at lo: its edge by bisection
            while hi - lo > 1e-10 * hi:
                mid = 0.5 * (lo + hi)
                lo, hi = (mid, hi) if excess(mid) > 0 else (lo, mid)
            return bound(hi, excess(hi) + limit, "roller_left")
        hi = lo
    return bound(lo_deg, excess(lo_deg) + limit, "range")


@dataclass
class _ExactLimit:
    """One exact limit f(t) <= limit on arc k (f falls in t: convex for the stress, possibly wavy
    for the rebound), the tangent the LP takes of it (slope, intercept), the lower bound on t that
    tangent gives, and for the rebound its exact bound on the stated range (found once, on demand)."""
    kind: str                 # "amplitude" [mm] or "contact_stress" [MPa]
    k: int
    limit: float
    exact: object             # t [deg] -> f(t)
    slope: float
    intercept: float
    find_range_bound: object = None     # () -> AmplitudeBound (the rebound only)
    _range_bound: AmplitudeBound | None = None

    def bound_deg(self) -> float:
        return (self.limit - self.intercept) / self.slope if self.slope < 0 else -np.inf

    def relinearise(self, t: float) -> None:
        """The tangent at t; a central difference (the laws are smooth away from the preload's kinks)."""
        h = 1e-6 * max(t, 1e-3)
        lo, mid, hi = (float(v) for v in np.ravel(self.exact(np.array([t - h, t, t + h]))))
        self.slope = (hi - lo) / (2 * h)
        self.intercept = mid - self.slope * t

    def range_bound(self) -> AmplitudeBound:
        if self._range_bound is None:
            self._range_bound = self.find_range_bound()
        return self._range_bound

    def cut(self, t: float) -> tuple[float, str]:
        """The next round's lower bound on t from the tangent at t, and how it was found: "newton"
        (the tangent's root) where that is safe, else "exact" (the range bound). The stress is
        convex: always Newton. The rebound may rise or be flat at t (no root ahead), or its tangent
        may overshoot the range bound (not under a wavy law): then the range bound."""
        newton = self.bound_deg()
        if self.kind == "contact_stress":
            return newton, "newton"
        exact = self.range_bound().from_deg
        if exact is None:
            return math.inf, "exact"
        if math.isfinite(newton) and t < newton <= exact:
            return newton, "newton"
        return exact, "exact"


def _exact_limits(task: Cyclogram, stress_form: str, scan_to_deg: float, scan_step_deg: float) -> list[_ExactLimit]:
    """The limits the LP linearised, each with its exact law and the tangent the first LP takes."""
    out = []
    for k in task.stress_arcs():
        sigma_ref, t_ref = task.stress_reference(k)
        exact = functools.partial(stress_MPa, sigma_ref, t_ref)
        at = t_ref if stress_form == "linear" else stress_bound_deg(sigma_ref, t_ref, task.sigma_H_limit_MPa)
        law = _ExactLimit("contact_stress", k, task.sigma_H_limit_MPa, exact, 0.0, 0.0)
        law.relinearise(at)
        if stress_form == "linear":     # exactly the model's tangent, not its difference quotient
            law.slope, law.intercept = -sigma_ref / t_ref, 2.0 * sigma_ref
        out.append(law)
    phi = task.min_angles_deg()
    for k in task.amplitude_arcs():
        find = functools.partial(cached_amplitude_bound, task, task.speed_rpm, float(phi[k]), scan_to_deg, scan_step_deg)
        law = _ExactLimit("amplitude", k, task.amplitude_limit_mm,
                          functools.partial(exact_amplitude_mm, task, lost=np.inf), 0.0, 0.0, find)
        if task.has_linear_amplitude:
            law.slope, law.intercept = task.amplitude_slope_mm_per_deg, task.amplitude_intercept_mm
        else:       # the lever alone: the tangent at the exact bound (a tangent elsewhere may overshoot it)
            at = law.range_bound().from_deg
            law.relinearise(at if at is not None else scan_to_deg)
            if at is not None and not law.slope < 0:     # flat or rising there: a line whose bound is it
                law.slope, law.intercept = -1.0, law.limit + at
        out.append(law)
    return out


def repair_cyclogram(task: Cyclogram, *, backend: Literal["HIGHS", "CLARABEL"] = "HIGHS",
                     stress_form: Literal["exact", "linear"] = "linear",
                     max_rounds: Annotated[int, Interval(ge=1, le=100)] = 20,
                     scan_to_deg: Annotated[float, Interval(gt=0.0, le=360.0)] = 60.0,
                     scan_step_deg: Annotated[float, Interval(ge=1e-3, le=10.0)] = 0.25,
                     tol_mm: Tolerance = 1e-9, tol_MPa: Tolerance = 1e-6, tol_deg: Tolerance = 1e-6) -> Result:
    """The LP of `plan_cyclogram`, checked against the exact laws at its optimum and repaired by
    sequential LP (issue 14, part 4).

    Round 1 solves the LP with the linear laws the task gives (the amplitude tangent; the stress
    tangent at t_ref when stress_form = "linear"; with the lever alone, the rebound's tangent at
    its exact bound). At its optimum each linearised limit is
    evaluated exactly: the lever's rebound a(t, n) (the chain, `exact_amplitude_mm`), sigma_max =
    sigma_ref t_ref / t. While one exceeds its limit by more than tol_mm / tol_MPa, every limit is
    re-linearised at the current angle and the LP re-solved with a cut (the largest met so far) as
    the arc's lower bound: a DPP re-solve. The stress is convex and falls in t: its tangent lies
    under it and the cuts are Newton steps on its root (quadratic convergence). The chain's a(t)
    is wavy, so a tangent is trusted only where it falls and its root lies between t and the
    exact bound; otherwise the cut is the exact bound itself: the smallest t beyond which a stays
    <= limit up to scan_to_deg (the stated range [phi, scan_to_deg]; `exact_amplitude_bound`: a
    walk down in steps of scan_step_deg and brentq). An LP bound t >= b must hold for every t the
    LP may pick above b, hence a bound on the range and not a root. When the laws hold at t, the
    rebound is also checked on the range: a t below the exact bound (a Newton step that stopped at
    a crossing of a wiggle) is cut there too.

    Returns the last round's event times (p_*, t_*, span_deg ...), rounds, exact_amplitude_*_mm
    (at the final t), amplitude_holds_from_*_deg and amplitude_holds_to_*_deg (a <= limit on that
    range), exact_sigma_*_MPa and linearisation_error_*: exact minus linear at round 1's optimum;
    diagnostics["rounds"]: per round and limit t, exact, linear, error, excess, the cut and how it
    was found ("newton" or "exact"). SOLVED when the exact laws hold to the tolerances; LIMIT after
    max_rounds without it; INFEASIBLE when the rebound exceeds its limit even at scan_to_deg (no
    values; diagnostics best_t_deg and best_amplitude_mm, the least rebound on the range); an
    LP that fails in a round returns its status, with the rounds so far.
    """
    start = time.perf_counter()
    laws = _exact_limits(task, stress_form, scan_to_deg, scan_step_deg)
    unit = {"amplitude": "mm", "contact_stress": "MPa"}
    tol = {"amplitude": tol_mm, "contact_stress": tol_MPa}
    op_of = {(str(op["from"]), str(op["to"])): i for i, op in enumerate(task.operations)}
    cuts: dict[int, float] = {}
    history, current = [], task
    amplitude = [law for law in laws if law.kind == "amplitude"]
    if amplitude and not task.has_linear_amplitude:     # the lever alone: round 1 takes its tangent
        current = dataclasses.replace(task, amplitude_slope_mm_per_deg=amplitude[0].slope,
                                      amplitude_intercept_mm=amplitude[0].intercept)
    for round_ in range(1, max_rounds + 1):
        result = plan_cyclogram(current, backend=backend, stress_form=stress_form, tol_deg=tol_deg)
        if result.status is not Status.SOLVED:
            return dataclasses.replace(result, message=f"round {round_}: {result.message}",
                                       diagnostics=result.diagnostics | {"rounds": history})
        rows = []
        for law in laws:
            x, y = task.arcs[law.k]
            t = result.values[f"t_{x}_{y}_deg"]
            exact, linear = float(np.ravel(law.exact(t))[0]), law.slope * t + law.intercept
            rows.append({"limit": f"{law.kind}[{x}->{y}]", "t_deg": t, f"exact_{unit[law.kind]}": exact,
                         f"linear_{unit[law.kind]}": linear, "error": exact - linear, "excess": exact - law.limit})
        history.append({"round": round_, "span_deg": result.values["span_deg"], "limits": rows})
        over = [r["limit"] for r, law in zip(rows, laws) if r["excess"] > tol[law.kind]]
        # a rebound that holds at t but not on the whole range above it: cut at the range bound
        short = [law for r, law in zip(rows, laws) if law.kind == "amplitude" and r["limit"] not in over
                 and (law.range_bound().from_deg is None or r["t_deg"] < law.range_bound().from_deg - tol_deg)]
        if not over and not short:
            return _repaired(task, result, laws, history, start, Status.SOLVED,
                             f"exact laws hold after {round_} round(s) (tol {tol_mm:g} mm, {tol_MPa:g} MPa); "
                             + "; ".join(law.range_bound().statement() for law in amplitude))
        if round_ == max_rounds:
            break
        for row, law in zip(rows, laws):
            law.relinearise(row["t_deg"])
            if row["limit"] in over:
                bound, how = law.cut(row["t_deg"])
            elif law in short:
                bound, how = law.range_bound().from_deg, "exact"
            else:
                bound, how = law.bound_deg(), "newton"
            if bound is None or bound == math.inf:      # the rebound exceeds its limit on all the range
                best = law.range_bound()        # the least rebound the range offers: at its top
                return Result(Status.INFEASIBLE, {}, Timing(result.timing.build_s, time.perf_counter() - start),
                              message=f"round {round_}: {row['limit']}: {best.statement()}", violated=(row["limit"],),
                              diagnostics={"rounds": history, "best_t_deg": best.to_deg,
                                           "best_amplitude_mm": best.amplitude_mm})
            cuts[law.k] = max(cuts.get(law.k, -np.inf), bound)
            row["cut_deg"], row["cut"] = cuts[law.k], how
        ops = [dict(op) for op in task.operations]
        for k, bound in cuts.items():
            op = ops[op_of[task.arcs[k]]]
            op["min_deg"] = max(float(op["min_deg"]), bound)
        current = dataclasses.replace(current, operations=ops)
    worst = max((r for r in history[-1]["limits"]), key=lambda r: r["excess"])
    return _repaired(task, result, laws, history, start, Status.LIMIT,
                     f"not converged in {max_rounds} round(s): exact {worst['limit']} exceeds its limit by "
                     f"{worst['excess']:.3g} (raise max_rounds or loosen the tolerances)", violated=tuple(over))


def _repaired(task, result, laws, history, start, status, message, violated=()):
    """The last LP round's values with the linear-law readings replaced by the exact ones."""
    values = {k: v for k, v in result.values.items() if not k.startswith(("amplitude_", "sigma_", "sens_"))}
    values["rounds"] = float(len(history))
    for law, first, last in zip(laws, history[0]["limits"], history[-1]["limits"]):
        x, y = task.arcs[law.k]
        name, unit = ("amplitude", "mm") if law.kind == "amplitude" else ("sigma", "MPa")
        values[f"exact_{name}_{x}_{y}_{unit}"] = last[f"exact_{unit}"]
        if law.kind == "amplitude" and law._range_bound is not None and law._range_bound.from_deg is not None:
            values[f"amplitude_holds_from_{x}_{y}_deg"] = law._range_bound.from_deg
            values[f"amplitude_holds_to_{x}_{y}_deg"] = law._range_bound.to_deg
        values[f"linearisation_error_{name}_{x}_{y}_{unit}"] = first["error"]
    diagnostics = {k: v for k, v in result.diagnostics.items() if k not in ("binding", "sens_min_deg",
                                                                            "sensitivity_convention")}
    diagnostics["rounds"] = history
    return Result(status, values, Timing(result.timing.build_s, time.perf_counter() - start - result.timing.build_s),
                  message=message, violated=violated, diagnostics=diagnostics)


# ------------------------------------------------------------------ the whole machine at its highest speed (part 5)

def _angle_floors_deg(task: Cyclogram) -> np.ndarray:
    """Each arc's [phi] as given, without the time floor of `min_ms` (that one grows with n) [deg]."""
    return np.fromiter((phi for _, _, phi in task.graph.edges(data="min_deg")), dtype=float, count=len(task.arcs))


MIN_RPM = 1e-6                   # bisection: below it the machine is at rest
N_OVER_T_RTOL = 1e-9             # the probe: a(c t, c n) = a(t, n) to this (the chain meets it to 1e-16)
N_OVER_T_FACTORS = (0.5, 2.0)
_AMPLITUDE_BOUNDS = BuildCache("loom.amplitude_bound", maxsize=64)


def cached_amplitude_bound(task: Cyclogram, speed_rpm: float, lo_deg: float, to_deg: float,
                           step_deg: float) -> AmplitudeBound:
    """`exact_amplitude_bound` on [lo_deg, to_deg], from one walk per lever, limit, speed and top
    (kept: a walk of the chain is about a hundred rises, a second). The walk goes down to
    WALK_FLOOR_DEG; an arc whose [phi] lies above its crossing is shown to hold from [phi] on
    (the walk saw a <= limit on all of [phi, to_deg]), so arcs with different [phi] share it."""
    if speed_rpm is None:
        raise ModelError("speed_rpm: the exact rebound law needs the main shaft's speed", key="speed_rpm")
    key = (_frozen(task.lever), task.amplitude_limit_mm, float(speed_rpm), float(to_deg),
           float(step_deg))
    walk, _ = _AMPLITUDE_BOUNDS.get(key, lambda: exact_amplitude_bound(task, speed_rpm, min(WALK_FLOOR_DEG, to_deg),
                                                                       to_deg, step_deg))
    if walk.from_deg is not None and walk.from_deg <= lo_deg:
        return dataclasses.replace(walk, from_deg=lo_deg, lo_deg=lo_deg, why="range",
                                   amplitude_mm=float(np.ravel(exact_amplitude_mm(task, lo_deg, speed_rpm))[0]))
    return dataclasses.replace(walk, lo_deg=lo_deg)


WALK_FLOOR_DEG = 1.0             # the walk's lowest t: below it no cam rise of a loom


def _frozen(value):
    """A table (dicts, lists, numbers, names) as a hashable key."""
    if isinstance(value, dict):
        return tuple(sorted((k, _frozen(v)) for k, v in value.items()))
    if isinstance(value, (list, tuple)):
        return tuple(_frozen(v) for v in value)
    return value


def n_over_t_probe(task: Cyclogram, scan_to_deg: float) -> tuple[bool, float]:
    """Whether every speed-dependent law is a function of n / t alone, and the largest relative
    change seen. The time floor (0.006 n T) and the stress (sigma_ref t_ref n / (t n_ref)) are by
    their form; the rebound is probed: a(c t, c n) against a(t, n) for c = 0.5, 2 at t =
    scan_to_deg and 3/4 of it, n the task's speed. (The chain passes: its rise in its own time
    depends on lambda = omega t / Omega only, and the impact on v0 only; see models/loom.py.)"""
    if not task.amplitude_arcs():
        return True, 0.0
    n, worst = _reference_rpm(task), 0.0
    for t in (scan_to_deg, 0.75 * scan_to_deg):
        base = float(np.ravel(exact_amplitude_mm(task, t, n, lost=np.nan))[0])
        for c in N_OVER_T_FACTORS:
            other = float(np.ravel(exact_amplitude_mm(task, c * t, c * n, lost=np.nan))[0])
            if np.isnan(base) and np.isnan(other):
                continue
            worst = max(worst, abs(other - base) / max(abs(base), 1e-300) if np.isfinite(other - base) else math.inf)
    return worst <= N_OVER_T_RTOL, worst


def _reference_rpm(task):
    if task.speed_rpm is None:
        raise ModelError("speed_rpm: the rebound's exact bound is found at a reference speed; give speed_rpm",
                         key="speed_rpm")
    return task.speed_rpm


def speed_coeffs_deg_per_rpm(task: Cyclogram, scan_to_deg: float = 60.0, scan_step_deg: float = 0.25
                             ) -> tuple[np.ndarray, list[str], dict]:
    """Per arc, the angle every rpm of speed asks for [deg/rpm], which law sets it ("min_time",
    "contact_stress", "amplitude" or "" for none), and per amplitude arc its exact bound at the
    task's speed. Each law is f(n / t) <= limit, so it is t >= n / r*: a bound proportional to n.
    For the wavy rebound r* = n_ref / T, T the exact bound at n_ref on [phi, scan_to_deg]
    (`exact_amplitude_bound`): a <= limit for every n / t in [n_ref / scan_to_deg, r*]."""
    g = task.time_coeffs_deg_per_rpm()
    why = ["min_time" if c > 0 else "" for c in g]
    for k in task.stress_arcs():
        c = task.stress_coeff_deg_per_rpm(k)
        if c > g[k]:
            g[k], why[k] = c, "contact_stress"
    bounds, phi = {}, _angle_floors_deg(task)
    for k in task.amplitude_arcs():
        n_ref = _reference_rpm(task)
        bounds[k] = cached_amplitude_bound(task, n_ref, float(phi[k]), scan_to_deg, scan_step_deg)
        c = math.inf if bounds[k].from_deg is None else bounds[k].from_deg / n_ref
        if c > g[k]:
            g[k], why[k] = c, "amplitude"
    return g, why, bounds


def max_machine_speed(task: Cyclogram, *, method: Literal["auto", "lp", "bisection"] = "auto",
                      backend: Literal["HIGHS", "CLARABEL"] = "HIGHS",
                      rtol: Annotated[float, Interval(ge=1e-9, le=1e-2)] = 1e-7,
                      scan_to_deg: Annotated[float, Interval(gt=0.0, le=360.0)] = 60.0,
                      scan_step_deg: Annotated[float, Interval(ge=1e-3, le=10.0)] = 0.25) -> Result:
    """The largest main-shaft speed n at which every group fits the machine's cycle (issue 14,
    part 5), with the event times there.

    Every limit is a lower bound on a phase angle. [phi] does not depend on n; a time `min_ms`
    (the microshuttle's flight) asks for 0.006 n T deg; the contact stress, sigma_ref (t_ref / t)
    (n / n_ref) <= [sigma_H] (n_ref = stress_speed_rpm), and the lever's exact rebound
    a(t, n) = h(n / t) <= a_lim depend on n and t only through r = n / t. The first two grow with
    r; the chain's h is wavy, so its r* is where h first crosses the limit going up from the
    stated range's start (`speed_coeffs_deg_per_rpm`): a <= limit for every r in [n_ref /
    scan_to_deg, r*], n_ref = speed_rpm. Each law is then r <= r*, i.e.

        t(x, y) >= g(x, y) n,      g = 1 / r*  [deg/rpm]  (0.006 T; sigma_ref t_ref / ([sigma_H] n_ref); 1 / r*_a)

    homogeneous and linear in (p, n): maximise n s.t. D p >= [phi], D p >= g n, windows, syncs,
    p(first) = 0, p(last) - p(first) <= cycle is an LP (method "lp"). (In times rather than
    angles, tau = t / (6 n), the same bounds read tau >= [phi] / 6 (1/n) and tau >= g / 6 and the
    cycle 60 (1/n): an LP in (tau, 1/n), minimising 1/n.) A law that is not a function of n / t
    alone (a dwell over which a vibration must decay, a time with an angle) breaks this; then
    method "bisection" is the general route: bisection on n, each step the exact bounds at that n
    (the rebound's by `exact_amplitude_bound` at that n on [phi, scan_to_deg], not through r*)
    and the event-time LP's feasibility, its status checked. It is also the independent check of
    the LP. Method "auto" takes the LP when `n_over_t_probe` finds the rebound a function of n / t
    (diagnostics: method, n_over_t_probe_rel), else bisection. rtol (relative) on n: the answer
    is certified by the longest-path certificate at n (1 - tol) (fits) and n (1 + tol) (does not);
    below 1e-9 the LP's own feasibility tolerance (1e-7 deg on a 360 deg cycle) decides.

    Returns max_speed_rpm, cycle_time_ms, span_deg, p_*, t_*, amplitude_*_mm and sigma_*_MPa
    (exact, at max speed), limiting_op_deg (machines with one); diagnostics: limiting_group,
    limiting_constraint, limiting (the speed-bound constraints on the critical chain, each with
    its group and deg/rpm), critical_chain, sens_cycle_rpm_per_deg. INFEASIBLE when the cycle
    cannot hold the groups at any speed (the conflicting chain named, as in plan_cyclogram),
    UNBOUNDED when no limit grows with n on a chain the cycle closes, LIMIT when bisection finds
    every speed up to its search bound feasible or the rebound exceeds its limit on the whole
    stated range. With a rebound: amplitude_holds_from_*_deg and amplitude_holds_to_*_deg, the
    range of t at the answer on which a <= limit is shown.
    """
    if task.cycle_deg is None:
        raise ModelError("cycle_deg: the machine's speed is limited by its cycle; give cycle_deg", key="cycle_deg")
    start = time.perf_counter()
    net = _Net.structure(task)        # the speed LP has its own bounds
    phi = _angle_floors_deg(task)
    g, why, amp_bounds = speed_coeffs_deg_per_rpm(task, scan_to_deg, scan_step_deg)
    scales, probe = n_over_t_probe(task, scan_to_deg)
    chosen = ("lp" if scales else "bisection") if method == "auto" else method
    def timing():
        return Timing(0.0, time.perf_counter() - start)
    diagnostics = {"method": chosen, "method_asked": method, "n_over_t_probe_rel": probe, "backend": backend,
                   "amplitude_bounds_at_reference": {f"{task.arcs[k][0]}->{task.arcs[k][1]}": b.statement()
                                                     for k, b in amp_bounds.items()}}
    unreached = [b for b in amp_bounds.values() if b.from_deg is None]
    if unreached:
        return Result(Status.LIMIT, {}, timing(), message=f"the rebound's bound is not on the stated range: "
                      f"{unreached[0].statement()} (raise scan_to_deg)", diagnostics=diagnostics)
    if chosen == "lp":
        n_max, status, message, build_s, extra = _speed_lp(task, net, phi, g, backend)
        bounds_at = functools.partial(_lp_bounds_at, phi, g, why)
    else:
        bounds_at = functools.partial(_exact_bounds_at, task, phi, scan_to_deg, scan_step_deg)
        n_max, status, message, build_s, extra = _speed_bisection(task, net, bounds_at, rtol)
    def timing():
        return Timing(build_s, time.perf_counter() - start - build_s)
    diagnostics |= {"speed_coeffs_deg_per_rpm":
                    {f"{x}->{y}": float(g[k]) for k, (x, y) in enumerate(task.arcs) if g[k] > 0}} | extra
    if status is Status.SOLVED and n_max * g.max(initial=0.0) <= 1e-6:   # below a micro-degree: at rest
        status = Status.INFEASIBLE
    if status is Status.INFEASIBLE:
        chain = _conflict_at(task, net, phi) or _conflict_at(task, net, np.maximum(phi, g * rtol))
        groups = list(dict.fromkeys(task.graph.nodes[v]["group"] or "-" for v, _, _ in chain))
        diagnostics["conflict_groups"] = groups
        message = ("no speed fits: conflicting chain " + "; ".join(label for _, label, _ in chain)
                   + f" (needs {math.fsum(w for _, _, w in chain):.6g} deg more than its limits allow as n -> 0;"
                   + f" groups {', '.join(groups)})")
        return Result(Status.INFEASIBLE, {}, timing(), message=message,
                      violated=tuple(label for _, label, _ in chain), diagnostics=diagnostics)
    if status is Status.UNBOUNDED:
        message += ": no limit grows with the speed on a chain the cycle closes (no stress, rebound or min_ms there)"
    if status is not Status.SOLVED:
        return Result(status, {}, timing(), message=message, diagnostics=diagnostics)
    lb, why_at = bounds_at(n_max)
    certified = _certify_speed(task, net, bounds_at, n_max, rtol)
    values, more = _speed_report(task, net, lb, why_at, n_max, rtol)
    for k, b in amp_bounds.items():      # the range of t on which the rebound was shown to hold, at n_max
        x, y = task.arcs[k]
        at = b if chosen == "lp" else _exact_amplitude_bounds(task, phi, scan_to_deg, scan_step_deg, n_max)[k]
        scale = n_max / b.speed_rpm if chosen == "lp" else 1.0
        values[f"amplitude_holds_from_{x}_{y}_deg"] = at.from_deg * scale
        values[f"amplitude_holds_to_{x}_{y}_deg"] = at.to_deg * scale
    diagnostics |= more
    if certified:
        return Result(Status.INACCURATE, values, timing(), message=certified, diagnostics=diagnostics)
    reason = ("every law a function of n / t" if scales else "the rebound is not a function of n / t") \
        + f" (probe {probe:.2g})"
    message = (f"max_speed_rpm = {n_max:.6g} ({chosen}{': ' + reason if method == 'auto' else ''}); limiting "
               f"group {more['limiting_group']}, constraint {more['limiting_constraint']}")
    return Result(Status.SOLVED, values, timing(), message=message, diagnostics=diagnostics)


def _speed_lp(task, net, phi, g, backend):
    """maximise n over (p, n): the LP of the docstring, built once per structure (DPP)."""
    rows = np.flatnonzero(g > 0)
    key = ("speed", backend, len(net.names), net.tails.tobytes(), net.heads.tobytes(), net.first, net.last,
           rows.tobytes(), tuple(net.window_idx), tuple(net.sync_idx))

    def build():
        D = incidence(len(net.names), net.tails, net.heads)
        p, n = cp.Variable(len(net.names), name="p_deg"), cp.Variable(nonneg=True, name="n_rpm")
        prm = {"min_deg": cp.Parameter(len(net.tails), name="min_deg"),
               "g": cp.Parameter(len(rows), nonneg=True, name="g_deg_per_rpm"),
               "cycle_deg": cp.Parameter(nonneg=True, name="cycle_deg")}
        cons = [D @ p >= prm["min_deg"], p[net.first] == 0, p[net.last] - p[net.first] <= prm["cycle_deg"]]
        if len(rows):
            cons.append(D[rows] @ p >= cp.multiply(prm["g"], n))
        if net.window_idx:
            w = np.asarray(net.window_idx)
            prm["window_deg"] = cp.Parameter(len(w), name="window_deg")
            cons.append(incidence(len(net.names), w[:, 0], w[:, 1]) @ p <= prm["window_deg"])
        if net.sync_idx:
            s = np.asarray(net.sync_idx)
            cons.append(incidence(len(net.names), s[:, 0], s[:, 1]) @ p == 0)
        problem = cp.Problem(cp.Maximize(n), cons)
        set_values(prm)
        problem.get_problem_data(backend)          # compile now, so build and solve time separate
        return problem, n, prm

    def set_values(prm):
        prm["min_deg"].value, prm["g"].value, prm["cycle_deg"].value = phi, g[rows], task.cycle_deg
        if "window_deg" in prm:
            prm["window_deg"].value = np.array([w for _, _, w in task.window_arcs()])
    start = time.perf_counter()
    (problem, n, prm), _ = _BUILDS.get(key, build)
    set_values(prm)
    build_s = time.perf_counter() - start
    try:
        problem.solve(solver=backend, warm_start=False)
    except cp.error.SolverError as exc:
        return None, Status.FAILED, f"{backend} failed: {exc}", build_s, {}
    status = from_cvxpy(problem.status)
    extra = {"solver_status": problem.status}
    if status is Status.SOLVED:
        return float(n.value), status, "", build_s, extra
    return None, status, f"{backend}: {problem.status}", build_s, extra


def _lp_bounds_at(phi, g, why, n_rpm):
    """The LP's bounds at speed n: max([phi], g n) [deg], and which law sets each ("" for [phi])."""
    lb = np.maximum(phi, g * n_rpm)
    return lb, [w if g[k] * n_rpm >= phi[k] else "" for k, w in enumerate(why)]


def _exact_amplitude_bounds(task, phi, scan_to_deg, scan_step_deg, n_rpm):
    """Per amplitude arc, the rebound's exact bound at speed n on [phi, scan_to_deg]."""
    return {k: cached_amplitude_bound(task, n_rpm, float(phi[k]), scan_to_deg, scan_step_deg)
            for k in task.amplitude_arcs()}


def _exact_bounds_at(task, phi, scan_to_deg, scan_step_deg, n_rpm):
    """Each arc's smallest angle at speed n from the exact laws directly [deg], and which law sets
    it: the time floor, the stress bound sigma_ref t_ref n / ([sigma_H] n_ref), the rebound's
    exact bound on [phi, scan_to_deg] (inf where none holds there). At n = 0: [phi]."""
    lb = np.maximum(phi, task.time_coeffs_deg_per_rpm() * n_rpm)
    why = ["min_time" if b > p else "" for b, p in zip(lb, phi)]
    for k in task.stress_arcs():
        bound = task.stress_coeff_deg_per_rpm(k) * n_rpm
        if bound > lb[k]:
            lb[k], why[k] = bound, "contact_stress"
    if n_rpm > 0:
        for k, b in _exact_amplitude_bounds(task, phi, scan_to_deg, scan_step_deg, n_rpm).items():
            bound = math.inf if b.from_deg is None else b.from_deg
            if bound > lb[k]:
                lb[k], why[k] = bound, "amplitude"
    return lb, why


def _speed_bisection(task, net, bounds_at, rtol):
    """Bisection on n: feasible when the event-time LP with the exact bounds at n fits the cycle
    (one HiGHS model held through the steps, `HeldLP`; `backend` is the LP method's)."""
    start = time.perf_counter()
    lp = HeldLP(len(net.names), net.tails, net.heads, first=net.first, last=net.last,
                window_arcs=net.window_idx, sync_arcs=net.sync_idx, with_cycle=True)
    windows = [w for _, _, w in task.window_arcs()]
    build_s = time.perf_counter() - start
    steps = []

    def feasible(n_rpm):
        lb, _ = bounds_at(n_rpm)
        if not np.all(np.isfinite(lb)):          # a rebound over its limit on the whole stated range
            steps.append((n_rpm, "no bound on the range"))
            return False
        status, _ = lp.solve(lb, windows, task.cycle_deg)
        steps.append((n_rpm, status.value))
        if status not in (Status.SOLVED, Status.INFEASIBLE):
            raise _Undecided(f"HiGHS: {status.value} at n = {n_rpm:.9g} rpm")
        return status is Status.SOLVED
    try:
        if not feasible(0.0):
            return None, Status.INFEASIBLE, "", build_s, {"bisection_steps": len(steps)}
        lo, hi = 0.0, 1.0
        while feasible(hi):
            lo, hi = hi, 2.0 * hi
            if hi > MAX_RPM:
                return None, Status.LIMIT, (f"every speed up to the search bound {MAX_RPM:g} rpm fits: no limit "
                                            f"grows with the speed"), build_s, {"bisection_steps": len(steps)}
        while hi - lo > 0.25 * rtol * hi and hi > MIN_RPM:   # a quarter: the certificate's margin is rtol
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if feasible(mid) else (lo, mid)
    except _Undecided as exc:
        return None, Status.FAILED, str(exc), build_s, {"bisection_steps": len(steps)}
    return (lo if hi > MIN_RPM else 0.0), Status.SOLVED, "", build_s, {"bisection_steps": len(steps),
                                                                     "bisection_bracket_rpm": [lo, hi]}


class _Undecided(Exception):
    """A feasibility LP that was neither optimal nor infeasible: bisection cannot go on."""


def _arcs_at(task, net, lb):
    """The difference constraints with the arcs' bounds `lb` and the cycle, for `positive_cycle`."""
    first, last = net.names[net.first], net.names[net.last]
    arcs = [(u, v, w, f"t({u}->{v}) >= {w:.6g} deg") for u, v, w in _constraint_arcs(net, lb)]
    return arcs + [(last, first, -task.cycle_deg, f"cycle p({last}) - p({first}) <= {task.cycle_deg:.6g} deg")]


def _conflict_at(task, net, lb):
    return [(u, label, w) for u, _, w, label in positive_cycle(_arcs_at(task, net, lb))]


def _certify_speed(task, net, bounds_at, n_max, tol):
    """'' when the bounds at n_max (1 - tol) leave no positive cycle and those at n_max (1 + tol)
    do (so n_max is the largest speed to tol); else why not."""
    below, above = n_max * (1 - tol), n_max * (1 + tol)
    lb_below, lb_above = bounds_at(below)[0], bounds_at(above)[0]
    if not np.all(np.isfinite(lb_below)) or _conflict_at(task, net, lb_below):
        return f"certificate failed: n = {below:.9g} rpm (just under the answer) does not fit the cycle"
    if np.all(np.isfinite(lb_above)) and not _conflict_at(task, net, lb_above):
        return f"certificate failed: n = {above:.9g} rpm (just over the answer) still fits the cycle"
    return ""


def _speed_report(task, net, lb, why, n_max, tol):
    """Event times at max speed (earliest start), exact readings, and which constraints limit it."""
    first = net.names[net.first]
    if task.windows or task.syncs:
        early = _longest(_constraint_arcs(net, lb), first)
        p = np.array([early.get(v, 0.0) for v in net.names])
    else:
        p, _ = _dag_times(len(net.names), net.tails, net.heads, lb, net.first, net.last, task.cycle_deg)
    t = p[net.heads] - p[net.tails]
    values = {"max_speed_rpm": n_max, "cycle_time_ms": 60_000.0 / n_max, "span_deg": float(p[net.last] - p[net.first])}
    if task.limiting_op is not None:
        x, y = (net.index[str(v)] for v in task.limiting_op)
        values["limiting_op_deg"] = float(p[y] - p[x])
    values |= {f"p_{v}_deg": float(p[i]) for i, v in enumerate(net.names)}
    values |= {f"t_{x}_{y}_deg": float(t[k]) for k, (x, y) in enumerate(net.arcs)}
    for k in task.amplitude_arcs():
        x, y = net.arcs[k]
        values[f"amplitude_{x}_{y}_mm"] = float(np.ravel(exact_amplitude_mm(task, t[k], n_max))[0])
    for k in task.stress_arcs():
        x, y = net.arcs[k]
        values[f"sigma_{x}_{y}_MPa"] = float(task.stress_at_MPa(k, t[k], n_max))
    span = task.cycle_deg
    e, l_ = (_dag_times(len(net.names), net.tails, net.heads, lb, net.first, net.last, span)
             if not (task.windows or task.syncs) else (p, p))
    group = dict(task.graph.nodes(data="group"))
    floats = {f"{x}->{y}": float(l_[net.index[y]] - e[net.index[x]] - lb[k]) for k, (x, y) in enumerate(net.arcs)}
    critical = [a for a, f in floats.items() if f <= tol * max(1.0, span)]
    crit = nx.DiGraph([tuple(a.split("->")) for a in critical])
    end = net.names[net.last]
    chain = nx.shortest_path(crit, first, end) if first in crit and end in crit and nx.has_path(crit, first, end) else []
    limiting = []
    for k, (x, y) in enumerate(net.arcs):
        if why[k] and f"{x}->{y}" in critical:      # set by a law that grows with n (deg/rpm: its secant)
            limiting.append({"constraint": f"{why[k]}[{x}->{y}]", "group": group[x] or group[y] or "-",
                             "deg_per_rpm": float(lb[k] / n_max), "deg": float(lb[k])})
    by_group: dict = {}
    for row in limiting:
        by_group[row["group"]] = by_group.get(row["group"], 0.0) + row["deg_per_rpm"]
    slope = sum(by_group.values())
    more = {"limiting": limiting, "float_deg": floats, "critical_ops": critical, "critical_chain": chain,
            "limiting_group": max(by_group, key=by_group.get) if by_group else "-",
            "limiting_constraint": max(limiting, key=lambda r: r["deg_per_rpm"])["constraint"] if limiting else "-",
            "sens_cycle_rpm_per_deg": 1.0 / slope if slope > 0 else math.inf}
    return values, more
