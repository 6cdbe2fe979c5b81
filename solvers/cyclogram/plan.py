"""Event times of a network cyclogram (paper 004, problem (1)): on the graph (the LP's dual, longest
paths; the default) or as a linear program in cvxpy (method "lp").

    minimise p(N) - p(1)   subject to   p(y) - p(x) >= [phi(x, y)]                 every operation
                                        p(y) - p(x) >= sigma-bound(x, y; [sigma_H])  cam pairs
                                        slope (p(7) - p(3)) + intercept <= a_lim    amplitude law
                                        p(y) - p(x) <= w,  p(a) = p(b)             windows, syncs
                                        p(1) = 0                                     anchor

or, for a machine with a limiting operation (x*, y*), maximise p(y*) - p(x*) with p(N) - p(1) <=
cycle. Constraints are built from the incidence matrix (one vectorised row block per kind); every
limit is a cvxpy Parameter, so a what-if re-solve reuses the compiled problem (DPP). The anchor
p(1) = 0 removes the shift invariance that otherwise slows HiGHS a hundredfold.

Sensitivities are reported in user terms with one sign convention: d(objective)/d(limit), the
change of the objective (span_deg, or limiting_op_deg on a machine) per unit *increase* of the
limit. Raising [sigma_H] or the amplitude limit loosens a bound: the span falls (<= 0); raising a
critical [phi] lengthens it (+1 deg/deg).
"""
import dataclasses
import functools
import math
from collections import deque
from typing import TYPE_CHECKING, Literal

import networkx as nx
import numpy as np

from mechopt.kit.cache import BuildCache
from mechopt.kit.errors import NAMED, ModelError, some_of
from mechopt.kit.result import Clock, Result, Status, from_cvxpy
from mechopt.kit.settings import Tolerance, check_settings
from mechopt.models.cyclogram import Cyclogram, amplitude_mm, stress_bound_deg, stress_MPa
from mechopt.solvers.cyclogram.graph import BackArcs, Levels, PositiveCycle, a_path, tight_arcs

if TYPE_CHECKING:      # the LP's modules (cvxpy: seconds to import) load only when the LP is asked for
    from mechopt.solvers.cyclogram.event_time import EventTimeLP

SENSITIVITY_CONVENTION = ("sens_* = d(objective)/d(limit): change of the objective [deg] per unit increase "
                          "of the limit; negative means a looser limit shortens the span")

LP_BUILDS = BuildCache("loom.event_time_lp", maxsize=8)


def plan_cyclogram(task: Cyclogram, *, method: Literal["graph", "lp"] = "graph",
                   backend: Literal["HIGHS", "CLARABEL"] = "HIGHS",
                   stress_form: Literal["exact", "linear"] = "exact", warm_start: bool = False,
                   tol_deg: Tolerance = 1e-6, check: bool = False) -> Result:
    """Event times minimising the span p(N) - p(1) of a cyclogram (paper 004, problem (1)), or
    maximising the machine's limiting operation inside its cycle.

    Parameters
    ----------
    task : the network and its limits (models/loom.py).
    method : "graph" (longest paths on the difference constraints, solvers/loom/graph.py: the
        LP's dual solved exactly) or "lp" (the cvxpy model of the design card).
    backend : LP solver behind cvxpy (method "lp", and the check).
    stress_form : "exact" sigma_max(t) <= [sigma_H] as t >= K/[sigma_H]; "linear" its tangent at t_ref.
    warm_start : pass cvxpy's warm start to the back end (with HiGHS it can slow re-solves).
    tol_deg : tolerance [deg] for float = 0 (critical), binding constraints and the cross-check.
    check : also solve by the other method and compare: status, span (or limiting_op_deg) to
        tol_deg and, where the critical chain is unique, every sens_*; a mismatch makes the result
        INACCURATE. The value check_rel is the objectives' difference per degree above 1 (the
        loom scenes expect it below 1e-9: the LP as certificate in `mechopt validate`).

    Returns
    -------
    Result with values span_deg, longest_path_deg (networkx / Bellman-Ford cross-check),
    p_<event>_deg, t_<x>_<y>_deg, amplitude_<x>_<y>_mm, sigma_<x>_<y>_MPa, span_<group>_deg,
    limiting_op_deg (machines) and sens_* sensitivities (see SENSITIVITY_CONVENTION);
    diagnostics: float_deg, critical_ops, critical_chain, binding (with duals), sens_min_deg.
    An infeasible problem names its conflicting chain (a positive cycle of the difference
    constraints) in `message` and `violated`, its events and excess [deg] in `diagnostics`.

    Method "graph" also gives ranging_deg: per operation [how far its bound may fall, rise]
    [deg] before its dual changes (None: without end).

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
    check_settings(plan_cyclogram, method=method, backend=backend, stress_form=stress_form)
    solve = _plan_graph if method == "graph" else functools.partial(_plan_lp, backend=backend, warm_start=warm_start)
    result = solve(task, stress_form=stress_form, tol_deg=tol_deg)
    if not check:
        return result
    other = (_plan_lp(task, stress_form=stress_form, tol_deg=tol_deg, backend=backend, warm_start=warm_start)
             if method == "graph" else _plan_graph(task, stress_form=stress_form, tol_deg=tol_deg))
    graph = functools.partial(_plan_graph, stress_form=stress_form, tol_deg=tol_deg)
    return certify(result, other, tol_deg, one_sided=lambda key: one_sided_sensitivity(task, key, graph, result))


# a limit a sens_* is taken with respect to: its task field (window and cycle duals are compared as they are)
SENS_LIMITS = {"sens_sigma_H_deg_per_MPa": "sigma_H_limit_MPa", "sens_amplitude_limit_deg_per_mm": "amplitude_limit_mm"}
ONE_SIDED_STEP = 1e-6          # relative step of the limit for the one-sided derivatives


def one_sided_sensitivity(task, key, solve, at: Result) -> tuple[float, float] | None:
    """d(objective)/d(limit) from below and from above, by `solve` (the graph) at the limit -+ h:
    where two bounds tie at the optimum they differ, and every value between them is a dual (the
    LP and the graph may each return a different one); `at` is the solved result at the limit.
    None for a sens_* of no scalar limit."""
    field = SENS_LIMITS.get(key)
    limit = getattr(task, field, None) if field else None
    if limit is None:
        return None
    h = ONE_SIDED_STEP * max(1.0, abs(limit))
    spans = []
    for value in (limit - h, None, limit + h):
        r = at if value is None else solve(dataclasses.replace(task, **{field: value}))
        if r.status is not Status.SOLVED:
            return None
        spans.append(r.values.get("limiting_op_deg", r.values["span_deg"]))
    return (spans[1] - spans[0]) / h, (spans[2] - spans[1]) / h


def _plan_lp(task, *, stress_form, tol_deg, backend, warm_start) -> Result:
    """The event-time LP in cvxpy, checked against the longest-path certificate."""
    from mechopt.solvers.cyclogram.event_time import build_event_time_lp
    clock = Clock()
    net = Net(task, stress_form)
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
    # its parameters, the solve and the reading of values and duals are one state: one thread at a time
    with LP_BUILDS.held(key, build) as (lp, compiled_s):
        return _solve_held_lp(task, net, lp, clock, compiled_s > 0, stress_form=stress_form, tol_deg=tol_deg,
                              backend=backend, warm_start=warm_start)


def _solve_held_lp(task, net, lp, clock, fresh, *, stress_form, tol_deg, backend, warm_start) -> Result:
    """The cached event-time LP `lp` (held by this thread) solved for `task`: parameters set,
    solved, its answer checked and read."""
    import cvxpy as cp
    set_parameters(lp, task, net)
    clock.built()
    try:
        lp.problem.solve(solver=backend, warm_start=warm_start)
    except cp.error.SolverError as exc:
        return clock.result(Status.FAILED, {}, message=f"{backend} failed: {exc}")
    status = from_cvxpy(lp.problem.status)
    diagnostics = {"method": "lp", "backend": backend, "stress_form": stress_form, "compiled_now": fresh,
                   "events": len(net.names), "operations": len(net.tails), "isolated_events": task.isolated_events,
                   "solver_status": lp.problem.status, "solve_time_backend_s": lp.problem.solver_stats.solve_time}
    # the certificate: an optimum is only trusted when the difference constraints hold no positive cycle
    chain = conflict_chain(net) if status is Status.INFEASIBLE or _may_conflict(net) else []
    if chain:
        note = "" if status is Status.INFEASIBLE else \
            f"; {backend} reported {lp.problem.status}, the longest-path certificate overrules it"
        return _infeasible(chain, clock, diagnostics, note)
    if status is not Status.SOLVED:
        message = f"{backend}: {lp.problem.status}"
        if status is Status.INFEASIBLE:
            message += " (no positive cycle among the difference constraints: a numerical failure?)"
        return clock.result(status, {}, message=message, diagnostics=diagnostics)
    values, more, overstressed, disagreement, (p, floats) = _report(task, net, lp, tol_deg)
    diagnostics |= more
    if disagreement:
        return clock.result(Status.INACCURATE, values, message=disagreement, violated=overstressed,
                            diagnostics=diagnostics, arrays=plan_arrays(net, values, diagnostics, p, floats))
    objective = "limiting_op_deg" if net.limiting else "span_deg"
    message = (f"{objective} = {values[objective]:.6g} ({backend}, {stress_form} stress, "
               f"{'compiled' if fresh else 'DPP re-solve'}); {SENSITIVITY_CONVENTION}")
    if overstressed:      # the tangent under-estimates sigma_max: the linearised optimum breaks the true limit
        message += f"; the linearised stress limit lets sigma_max exceed [sigma_H] on {some_of(overstressed, sep=', ')}"
    return clock.result(Status.SOLVED, values, message=message, violated=overstressed,
                        diagnostics=diagnostics, arrays=plan_arrays(net, values, diagnostics, p, floats))


PER_NAME_MAX_OPS = 10_000   # above it, per-event and per-operation figures live in Result.arrays only


def per_name(net) -> bool:
    """Whether the values and diagnostics name every event and operation (p_*, t_*, float_deg, ...):
    up to PER_NAME_MAX_OPS operations. A timing table of 10^5 rows gets its figures as arrays: a
    dict entry per operation costs more than the solve (measured: 0.4 s of dicts against 10 ms)."""
    return len(net.tails) <= PER_NAME_MAX_OPS


def plan_arrays(net, values, diagnostics, p=None, floats=None) -> dict:
    """The plan as a table, one row per operation named `operation` ("3->7"): its start and end
    event times, its duration and its total float [deg] (`--csv`; for networks up to
    PER_NAME_MAX_OPS operations the values hold the same by name). `p` (event times in net order)
    and `floats` (per operation) default to the values' p_* and the diagnostics' float_deg."""
    if p is None:
        p = np.array([values[f"p_{v}_deg"] for v in net.names])
    arrays = {"operation": net.task.operation_labels, "start_deg": p[net.tails], "end_deg": p[net.heads],
              "duration_deg": p[net.heads] - p[net.tails]}
    if floats is None and isinstance(diagnostics.get("float_deg"), dict):    # else "not available" (round-off)
        floats = list(diagnostics["float_deg"].values())
    if floats is not None:
        arrays["float_deg"] = floats
    return arrays


def _infeasible(chain, clock, diagnostics, note="") -> Result:
    """INFEASIBLE, naming the conflicting chain (a positive cycle of the constraints): its first
    NAMED constraints and events, and its length (a chain of 10^6 operations is counted, not listed)."""
    excess = math.fsum(w for _, _, w in chain)
    diagnostics = diagnostics | {"conflict_events": [v for v, _, _ in chain[:NAMED]], "conflict_length": len(chain),
                                 "conflict_excess_deg": excess}
    message = "infeasible: conflicting chain " + some_of(label for _, label, _ in chain)
    message += f" (needs {excess:.6g} deg more than its limits allow){note}"
    return clock.result(Status.INFEASIBLE, {}, message=message,
                        violated=tuple(label for _, label, _ in chain[:NAMED]), diagnostics=diagnostics)


def _may_conflict(net) -> bool:
    """Whether the constraints can hold a positive cycle: windows and syncs can; a DAG of
    operations only with its cycle, when its longest path (linear time) is longer than it."""
    task = net.task
    if task.windows or task.syncs:
        return True
    if task.cycle_deg is None:
        return False
    early, _ = dag_times(len(net.names), net.tails, net.heads, net.lb, net.first, net.last, 0.0)
    return early[net.last] > task.cycle_deg


def set_parameters(lp: "EventTimeLP", task: Cyclogram, net) -> None:
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


class Net:
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
    def structure(cls, task: Cyclogram) -> "Net":
        """The index arrays alone (events, arcs, ends, windows, syncs), for LPs with their own bounds."""
        net = cls.__new__(cls)
        net._index_arrays(task)
        return net

    def _index_arrays(self, task):
        task.check_one_cycle("plan_cyclogram, max_machine_speed and repair_cyclogram")
        task.check_plain("plan_cyclogram (graph and lp), max_machine_speed and repair_cyclogram")
        self.task = task
        names, self.tails, self.heads = task.index_arrays       # cached on the task: built once per network
        self.names = list(names)
        self.index = index = task.event_index                   # shared with the task: read only
        self.arcs = task.arcs
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
        return f"t({x}->{y}) >= {self.lb[k]:.6g} deg ({self.lb_why[k]}){self.task.operation_names.get((x, y), '')}"


def conflict_chain(net, max_conflicts: int = 1) -> list:
    """A positive cycle of the difference constraints (operations with their bounds, windows,
    syncs and the machine cycle), as [(event, label and bound [deg] of the arc leaving it)]: the
    bounds sum to more than 0 (a cycle cannot hold them, p(v) - p(u) >= w all round); empty when there is
    none. With max_conflicts > 1: a list of up to that many such chains, each sharing no
    constraint with those before (independent conflicts, every one named). Our own Bellman-Ford: networkx's find_negative_cycle can detect a cycle and then fail
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
    chains = []
    for _ in range(max_conflicts):
        cycle = positive_cycle(arcs)
        if not cycle:
            break
        chains.append([(u, label, w) for u, _, w, label in cycle])
        used = {label for *_, label in cycle}
        arcs = [a for a in arcs if a[3] not in used]       # the next conflict shares no constraint
    return chains if max_conflicts > 1 else (chains[0] if chains else [])


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
    values, overstressed = schedule_values(task, net, p)
    t = p[net.heads] - p[net.tails]

    longest, disagreement = _cross_check(task, net, values, tol)
    if longest is not None:
        values["longest_path_deg"] = longest
    sens, binding, sens_min = _sensitivities(task, net, lp, t, tol)
    values |= sens
    floats = _floats(task, net, p, values, tol)
    diagnostics = {"binding": binding, "sens_min_deg": sens_min} | limit_diagnostics(task, net)
    diagnostics |= floats
    float_deg = floats.get("float_deg")
    float_deg = np.fromiter(float_deg.values(), dtype=float, count=len(float_deg)) if isinstance(float_deg, dict) else None
    if float_deg is not None and not per_name(net):      # large: the floats as the result's array only
        diagnostics["float_deg"] = f"{len(float_deg)} operations: in the result's arrays (float_deg)"
    return values, diagnostics, tuple(overstressed), disagreement, (p, float_deg)


def limit_diagnostics(task, net) -> dict:
    """Which limit sets each operation's bound, and the linearised stress bound's gap."""
    why = net.lb_why
    keep = range(len(why)) if per_name(net) else [k for k in (*net.stress_rows, *net.amp_rows, *task.time_arcs())
                                                  if why[k] != "min_angle"]   # large: the laws' arcs only
    return {"sensitivity_convention": SENSITIVITY_CONVENTION,
            "bound_source": {"{}->{}".format(*net.arcs[k]): why[k] for k in sorted(set(keep))},
            "stress_gap_deg": {f"{x}->{y}": _stress_gap(task, k) for k, (x, y) in
                               ((k, net.arcs[k]) for k in net.stress_rows)}}


def schedule_values(task, net, p):
    """Values of event times p [deg]: span, limiting operation, times, angles, amplitudes,
    stresses, group spans; and the operations whose stress exceeds [sigma_H]."""
    t = p[net.heads] - p[net.tails]
    span = float(p[net.last] - p[net.first])
    values = {"span_deg": span}
    if net.limiting:
        values["limiting_op_deg"] = float(p[net.limiting[1]] - p[net.limiting[0]])
    if per_name(net):
        values |= {f"p_{v}_deg": float(p[i]) for i, v in enumerate(net.names)}
        values |= {f"t_{x}_{y}_deg": float(t[k]) for k, (x, y) in enumerate(net.arcs)}
    for k in net.amp_rows:
        x, y = net.arcs[k]
        values[f"amplitude_{x}_{y}_mm"] = float(amplitude_mm(task.amplitude_slope_mm_per_deg,
                                                              task.amplitude_intercept_mm, t[k]))
    for k in net.stress_rows:
        x, y = net.arcs[k]
        values[f"sigma_{x}_{y}_MPa"] = float(stress_MPa(*task.stress_reference(k), t[k]))
    values |= task.motion_values(t, task.speed_rpm)
    for group, members in task.group_indices.items():
        if members.size:
            values[f"span_{group}_deg"] = float(p[members].max() - p[members].min())
    overstressed = [f"contact_stress[{x}->{y}]" for k, (x, y) in ((k, net.arcs[k]) for k in net.stress_rows)
                    if values[f"sigma_{x}_{y}_MPa"] > task.sigma_H_limit_MPa * (1 + 1e-9)]
    return values, tuple(overstressed)


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
    arcs = constraint_arcs(net, lb)
    try:
        if task.windows or task.syncs:
            longest = longest_distances(arcs, first)[last]
            route = "Bellman-Ford on the difference constraints"
        else:
            longest = nx.dag_longest_path_length(g, weight=weight)
            route = "networkx dag_longest_path_length"
        if net.limiting:
            x, y = net.names[net.limiting[0]], net.names[net.limiting[1]]
            got, what = values["limiting_op_deg"], "limiting_op_deg"
            if task.windows or task.syncs:
                cycle = [] if task.cycle_deg is None else [(last, first, -task.cycle_deg)]
                back = longest_distances(arcs + cycle, y).get(x)
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


def constraint_arcs(net, lb):
    """Every difference constraint as (u, v, w): p(v) - p(u) >= w [deg]."""
    arcs = [(x, y, float(lb[k])) for k, (x, y) in enumerate(net.arcs)]
    arcs += [(b, a, -w) for a, b, w in net.task.window_arcs()]
    arcs += [arc for a, b in net.task.sync_pairs() for arc in ((a, b, 0.0), (b, a, 0.0))]
    return arcs


def longest_distances(arcs, source, reverse=False):
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
    """Total float of every operation for the found span (a machine: with the limiting operation
    held at its optimum, a hair under: no 0+ cycle); see `schedule_floats`."""
    lb = net.lb.copy()
    if net.limiting:
        k = next(k for k, (x, y) in enumerate(net.arcs) if (net.index[x], net.index[y]) == net.limiting)
        lb[k] = values["limiting_op_deg"] - tol / 10
    return schedule_floats(task, net, lb, values["span_deg"], tol)


def schedule_floats(task, net, lb, span, tol):
    """Total float LS(y) - ES(x) - lb of every operation with bounds `lb` in a span `span` [deg]:
    {float_deg, critical_ops (float <= tol), critical_chain (one critical path, first to last)}."""
    names = net.names
    first, last = names[net.first], names[net.last]
    try:
        if task.windows or task.syncs:
            arcs = constraint_arcs(net, lb)
            early = longest_distances(arcs, first)
            to_last, to_first = longest_distances(arcs, last, reverse=True), longest_distances(arcs, first, reverse=True)
            late = {v: min(span - to_last.get(v, -np.inf), -to_first.get(v, -np.inf)) for v in names}
        else:
            e, l = dag_times(len(names), net.tails, net.heads, lb, net.first, net.last, span)
            early, late = dict(zip(names, e.tolist())), dict(zip(names, l.tolist()))
    except nx.NetworkXUnbounded:
        return {"floats": "not available: round-off made a zero cycle positive"}
    floats = {f"{x}->{y}": float(late[y] - early[x] - lb[k]) for k, (x, y) in enumerate(net.arcs)}
    critical = [k for k, v in floats.items() if v <= tol]
    crit = nx.DiGraph([tuple(k.split("->")) for k in critical])
    linked = first in crit and last in crit and nx.has_path(crit, first, last)
    chain = nx.shortest_path(crit, first, last) if linked else []     # one of the critical chains
    return {"float_deg": floats, "critical_ops": critical, "critical_chain": chain}


def dag_times(n, tails, heads, lb, first, last, span):
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




# ---------------------------------------------------------------- the graph method

MAX_CONFLICTS = 4          # independent conflicting chains named in one INFEASIBLE result
RANGING_MAX_OPS = 64       # ranging of the critical operations: one pass each, for chains up to this long
RANGING_MAX_TABLE = 10_000  # a ranging table per operation for networks up to this many operations


def back_arcs(net, with_cycle=True):
    """Windows, syncs and (with_cycle) the machine cycle as BackArcs over event indices, with
    their kinds ("window", "sync", "cycle"), in that order (windows in task order)."""
    task, arcs, kinds = net.task, [], []
    for (a, b), (_, _, w) in zip(net.window_idx, task.window_arcs()):
        arcs.append((b, a, -w))
        kinds.append("window")
    for a, b in net.sync_idx:
        arcs += [(a, b, 0.0), (b, a, 0.0)]
        kinds += ["sync", "sync"]
    if with_cycle and task.cycle_deg is not None:
        arcs.append((net.last, net.first, -task.cycle_deg))
        kinds.append("cycle")
    return BackArcs.of(arcs), kinds


def _plan_graph(task, *, stress_form, tol_deg) -> Result:
    """Event times, floats, duals and ranging by longest paths (solvers/loom/graph.py)."""
    clock = Clock()
    net = Net(task, stress_form)
    levels = Levels.of(len(net.names), net.tails, net.heads)
    back, kinds = back_arcs(net)
    clock.built()
    diagnostics = {"method": "graph", "stress_form": stress_form, "events": len(net.names),
                   "operations": len(net.tails), "isolated_events": task.isolated_events}
    try:
        solved = _longest_schedule(net, levels, back, tol_deg)
    except PositiveCycle:
        chains = conflict_chain(net, MAX_CONFLICTS)
        if len(chains) < 2:
            return _infeasible(chains[0] if chains else [], clock, diagnostics)
        first = _infeasible(chains[0], clock, diagnostics)
        more = [_infeasible(chain, clock, {}) for chain in chains[1:]]
        message = first.message + "".join(f"; and, independent of it, {r.message.removeprefix('infeasible: ')}"
                                          for r in more)
        return dataclasses.replace(first, message=message, violated=sum((r.violated for r in [first, *more]), ()),
                                   diagnostics=first.diagnostics | {"conflicts": [r.diagnostics for r in more]})
    if solved is None:
        x, y = (net.names[i] for i in net.limiting)
        return clock.result(Status.UNBOUNDED, {}, diagnostics=diagnostics,
                            message=f"unbounded: no chain of limits leads from {y} back to {x} (give cycle_deg), so "
                                    f"t({x}->{y}) can grow without end")
    p, objective, uses, back_uses, lb_at = solved
    values, overstressed = schedule_values(task, net, p)
    sign = -1.0 if net.limiting else 1.0
    sens, binding, sens_min = _graph_sensitivities(task, net, p, sign * uses, sign * back_uses, kinds, tol_deg)
    values |= sens
    values["longest_path_deg"] = objective if not net.limiting else \
        float(levels.longest_from(net.first, net.lb, back_arcs(net, with_cycle=False)[0])[net.last])
    float_deg = float_array(net, levels, back, lb_at, values["span_deg"], early=p)    # p: the earliest times
    floats = graph_floats(net, levels, back, lb_at, values["span_deg"], tol_deg, float_deg)
    diagnostics |= {"binding": binding, "sens_min_deg": sens_min} | limit_diagnostics(task, net) | floats
    if not net.limiting and len(net.tails) <= RANGING_MAX_TABLE:
        diagnostics["ranging_deg"] = _ranging(net, levels, back, uses, floats, objective)
    name = "limiting_op_deg" if net.limiting else "span_deg"
    message = f"{name} = {values[name]:.6g} (graph, {stress_form} stress); {SENSITIVITY_CONVENTION}"
    if overstressed:
        message += f"; the linearised stress limit lets sigma_max exceed [sigma_H] on {some_of(overstressed, sep=', ')}"
    return clock.result(Status.SOLVED, values, message=message, violated=overstressed, diagnostics=diagnostics,
                        arrays=plan_arrays(net, values, diagnostics, p, float_deg))


def _longest_schedule(net, levels, back, tol):
    """The optimum by longest paths: (earliest event times p, objective, per operation and per
    back arc the times it lies on the objective's path, the bounds p meets); None: unbounded.

    Span: the longest path first -> last. Machine: max t(x*, y*) = -(longest path y* -> x*)
    through the cycle's arc (the shortest-path dual of the LP); p then holds t(x*, y*) at it."""
    lb = net.lb
    source, target = (net.limiting[1], net.limiting[0]) if net.limiting else (net.first, net.last)
    dist = levels.longest_from(source, lb, back)
    if not np.isfinite(dist[target]):
        if levels.has_positive_cycle(lb, back):     # a conflict out of the source's reach: no schedule at all
            raise PositiveCycle
        return None          # a machine's limiting operation with nothing to hold it: unbounded
    objective = float(-dist[target] if net.limiting else dist[target])
    lb_at = lb
    if net.limiting:
        lb_at = lb.copy()
        lb_at[_limiting_arc(net)] = objective
        p = levels.longest_from(net.first, lb_at, back)
    else:
        p = dist
    m = len(net.tails)
    tails, heads, w = ((net.tails, net.heads, lb) if not len(back) else     # no copies of a large DAG's arcs
                       (np.r_[net.tails, back.tails], np.r_[net.heads, back.heads], np.r_[lb, back.weights]))
    eps = tol * 1e-3 * max(1.0, abs(objective))
    tight = tight_arcs(tails, heads, w, dist, eps)
    path = np.asarray(a_path(len(net.names), tails[tight], heads[tight], source, target), dtype=np.int64)
    counts = np.bincount(tight[path], minlength=m + len(back))
    return p, objective, counts[:m].astype(float), counts[m:].astype(float), lb_at


def _limiting_arc(net):
    return next(k for k in range(len(net.tails)) if (net.tails[k], net.heads[k]) == net.limiting)


def float_array(net, levels, back, lb, span, early=None):
    """Total float LS(y) - ES(x) - lb of every operation for bounds lb in a span [deg] (None:
    round-off made a zero cycle positive): earliest times from first (`early`, when the caller
    holds them), latest from the longest paths to first with p(last) - p(first) <= span as one
    more back arc."""
    early = levels.longest_from(net.first, lb, back) if early is None else early
    closed = BackArcs(np.r_[back.tails, net.last], np.r_[back.heads, net.first], np.r_[back.weights, -span])
    try:
        late = -levels.longest_to(net.first, lb, closed)
    except PositiveCycle:
        return None
    return late[net.heads] - early[net.tails] - lb


def graph_floats(net, levels, back, lb, span, tol, floats=None):
    """The floats of `float_array` (or `floats`, computed before) as `schedule_floats` gives
    them: {float_deg (by operation; a note for networks past PER_NAME_MAX_OPS, whose floats are
    the result's float_deg array), critical_ops (float <= tol), critical_chain}."""
    floats = float_array(net, levels, back, lb, span) if floats is None else floats
    if floats is None:
        return {"floats": "not available: round-off made a zero cycle positive"}
    critical = np.flatnonzero(floats <= tol)
    path = a_path(len(net.names), net.tails[critical], net.heads[critical], net.first, net.last)
    chain = [] if path is None else [net.names[net.first]] + [net.names[net.heads[critical[k]]] for k in path]
    labels = net.task.operation_labels
    float_deg = (dict(zip(labels.tolist(), floats.tolist())) if per_name(net)
                 else f"{len(floats)} operations: in the result's arrays (float_deg)")
    return {"float_deg": float_deg, "critical_ops": labels[critical].tolist(), "critical_chain": chain}


def _graph_sensitivities(task, net, p, d_lb, d_back, kinds, tol):
    """d(objective)/d(limit) from the path's arcs (d_lb: per operation d objective / d bound;
    d_back: per back arc d objective / d weight), and the binding constraints, as the LP's."""
    t = p[net.heads] - p[net.tails]
    phi, why = task.min_angles_deg(), net.lb_why
    sens, binding, sens_min = {}, [], {}
    phi_set = np.ones(len(why), dtype=bool)          # [phi] sets the bound, except where a law does
    laws = np.array([k for k in (*net.stress_rows, *net.amp_rows) if why[k] not in ("min_angle", "min_time", "max_accel", "max_velocity")],
                    dtype=np.int64)
    phi_set[laws] = False
    d_phi = np.where(phi_set, d_lb, 0.0) + 0.0
    # past PER_NAME_MAX_OPS the binding [phi] are those with a dual (on the path), not every tight one
    listed = (t - phi <= tol) | (d_phi != 0) if per_name(net) else d_phi != 0
    for k in np.flatnonzero(listed).tolist():
        x, y = net.arcs[k]
        if t[k] - phi[k] <= tol:
            binding.append({"constraint": f"min_angle[{x}->{y}]", "dual_deg_per_deg": float(d_phi[k])})
        if d_phi[k]:
            sens_min[f"{x}->{y}"] = float(d_phi[k])
    if net.stress_rows:
        sigma, total = task.sigma_H_limit_MPa, 0.0
        for k in net.stress_rows:
            sigma_ref, t_ref = task.stress_reference(k)
            slope = -sigma_ref * t_ref / sigma**2 if net.stress_form == "exact" else -t_ref / sigma_ref
            dual = float(d_lb[k] * slope) if why[k] == "contact_stress" else 0.0
            total += dual
            if t[k] - stress_bound_deg(sigma_ref, t_ref, sigma, net.stress_form) <= tol:
                x, y = net.arcs[k]
                binding.append({"constraint": f"contact_stress[{x}->{y}]", "dual_deg_per_MPa": dual + 0.0})
        sens["sens_sigma_H_deg_per_MPa"] = float(total) + 0.0
    if net.amp_rows:
        total = 0.0
        for k in net.amp_rows:
            dual = float(d_lb[k] / task.amplitude_slope_mm_per_deg) if why[k] == "amplitude" else 0.0
            total += dual
            a = amplitude_mm(task.amplitude_slope_mm_per_deg, task.amplitude_intercept_mm, t[k])
            if task.amplitude_limit_mm - a <= tol * abs(task.amplitude_slope_mm_per_deg):
                x, y = net.arcs[k]
                binding.append({"constraint": f"amplitude[{x}->{y}]", "dual_deg_per_mm": dual + 0.0})
        sens["sens_amplitude_limit_deg_per_mm"] = float(total) + 0.0
    windows = [j for j, kind in enumerate(kinds) if kind == "window"]
    for j, (a, b, w) in zip(windows, task.window_arcs()):
        dual = float(-d_back[j]) + 0.0           # the back arc's weight is -w
        sens[f"sens_window_{a}_{b}_deg_per_deg"] = dual
        if w - (p[net.index[b]] - p[net.index[a]]) <= tol:
            binding.append({"constraint": f"window[{a}->{b}]", "dual_deg_per_deg": dual})
    if "cycle" in kinds:
        dual = float(-d_back[kinds.index("cycle")]) + 0.0
        sens["sens_cycle_deg_per_deg"] = dual
        if abs(dual) > tol:
            binding.append({"constraint": "cycle", "dual_deg_per_deg": dual})
    return sens, binding, sens_min


def _ranging(net, levels, back, uses, floats, span):
    """Per operation [how far its bound may fall, how far rise] [deg] with its dual (d span /
    d bound) unchanged; None: without end. Off the path: rise by its float, fall without end.
    On it: fall until the longest path without it is as long (one pass each, for paths up to
    RANGING_MAX_OPS); rise without end in a DAG, else until the constraints close a positive
    cycle (one pass from its head each)."""
    if "float_deg" not in floats:
        return {}
    keys = list(floats["float_deg"])
    out = {key: [None, max(0.0, fl)] for key, fl in floats["float_deg"].items()}
    on_path = np.flatnonzero(uses)
    if len(on_path) > RANGING_MAX_OPS:          # the path's own ranging left out: too many passes
        return {key: r for (key, r), used in zip(out.items(), uses.tolist()) if not used}
    for k in on_path:
        lb = net.lb.copy()
        lb[k] = -np.inf
        try:
            without = levels.longest_from(net.first, lb, back)[net.last]
        except PositiveCycle:
            without = np.inf
        down = float(span - without) if np.isfinite(without) else None
        up = None
        if len(back):
            back_dist = levels.longest_from(net.heads[k], net.lb, back)[net.tails[k]]
            up = float(-back_dist - net.lb[k]) if np.isfinite(back_dist) else None
        out[keys[k]] = [down, up]
    return out


def _between(x, sides, rtol=1e-4):
    lo, hi = min(sides), max(sides)
    return lo - rtol * max(1.0, abs(lo)) <= x <= hi + rtol * max(1.0, abs(hi))


def certify(result: Result, other: Result, tol_deg: float, one_sided=None) -> Result:
    """`result` checked against the other method's `other`: the same status, objective to
    tol_deg (per degree above 1) and, where the critical chain is unique, the same sens_*; where
    `one_sided(key)` gives a limit's derivatives from below and above that differ (two bounds tie:
    the dual is not unique), both sens_* must lie between them instead (named in
    diagnostics["sens_not_unique"]). A mismatch makes it INACCURATE, named in the message."""
    name = "limiting_op_deg" if "limiting_op_deg" in result.values else "span_deg"
    diagnostics = result.diagnostics | {"check": other.diagnostics.get("method", "?"), "check_status":
                                        other.status.value}
    problems, values = [], result.values
    if other.status is not result.status:
        problems.append(f"{other.diagnostics.get('method')} says {other.status.value}")
    elif result.status is Status.SOLVED:
        mine, theirs = result.values[name], other.values[name]
        values = values | {"check_rel": abs(mine - theirs) / max(1.0, abs(theirs))}    # validate's certificate
        if not abs(mine - theirs) <= tol_deg * max(1.0, abs(theirs)):
            problems.append(f"{name} {mine!r} against {theirs!r}")
        chain = result.diagnostics.get("critical_chain", [])
        if len(result.diagnostics.get("critical_ops", ())) == max(len(chain) - 1, 0) > 0:
            for key in (k for k in result.values if k.startswith("sens_")):
                mine_s, theirs_s = result.values[key], other.values.get(key)
                if theirs_s is None or abs(mine_s - theirs_s) <= 1e-6 * max(1.0, abs(theirs_s)):
                    continue
                sides = one_sided(key) if one_sided else None
                if sides and _between(mine_s, sides) and _between(theirs_s, sides):
                    diagnostics.setdefault("sens_not_unique", {})[key] = list(sides)
                    continue
                problems.append(f"{key} {mine_s!r} against {theirs_s!r}")
        diagnostics["check_abs_deg"] = abs(mine - theirs)
    return certified(result, values, diagnostics, problems, by=diagnostics["check"])


def certified(result, values, diagnostics, problems, *, by) -> Result:
    """`result` with its certificate's outcome: checked `by` the other method when `problems` is
    empty; else INACCURATE, whichever said what (the methods disagree: an INFEASIBLE the LP solves
    too is not certified either), the disagreements named."""
    if not problems:
        return dataclasses.replace(result, values=values, diagnostics=diagnostics,
                                   message=result.message + f"; checked by {by}")
    status = Status.INACCURATE if result.status in (Status.SOLVED, Status.INFEASIBLE) else result.status
    return dataclasses.replace(result, status=status, values=values, diagnostics=diagnostics,
                               message=result.message + "; check failed: " + ", ".join(problems))
