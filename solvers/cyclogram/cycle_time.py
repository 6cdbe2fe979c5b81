"""The least cycle time of a recurrent machine: the maximum cycle ratio of its constraints.

Every limit of the cyclogram is a uniform constraint (Hanen & Munier 1995, the basic cyclic
scheduling problem; in max-plus terms, Baccelli et al. 1992, "Synchronization and Linearity",
section 2.3, the cycle time of a timed event graph):

    p(v) - p(u) >= d - k T        an operation (k = 0), a recurrent one (cycles = k > 0),
                                  a window (v <- u, d = -w, k = 0), a sync (both ways, 0, 0)

In a time-based network (T in ms) an angle is a fraction of the cycle: an operation of at least
phi deg is d = 0, k = cycles - phi / 360 (its duration phi T / 360 grows with T), a window of at
most w deg is d = 0, k = w / 360 (Hanen & Munier's uniform constraints take real heights).

A cycle T fits when no circuit C of these arcs has a positive sum D(C) - K(C) T. The least T is
therefore the maximum cycle ratio D(C) / K(C) over the circuits with K(C) > 0 (at least 0: T >= 0),
and no T fits when a circuit with K(C) <= 0 is positive at a T the other circuits ask for (a
height 0 with D(C) > 0, or angles that fill more than their cycles: INFEASIBLE, that circuit named).

Solved exactly on the graph by Dinkelbach's (Lawler's) iteration, as `speed.SpeedGraph` solves the
highest speed: from T = 0, a Bellman-Ford pass at T either finds no positive circuit (T is the
answer) or a positive circuit C, whose ratio D(C) / K(C) > T is the next T. T rises strictly and
takes a circuit's ratio each time, so it ends at the maximum ratio after finitely many passes (in
practice a handful; counted, never timed). A positive circuit with K(C) <= 0 stays positive at
every larger T: no cycle fits (INFEASIBLE). The last circuit is critical; at T* the arcs tight for
the pass's times hold every critical circuit (each is a zero circuit there), so ties are named.
The LP in (p, T), minimise T, is the certificate (check = true), solved by cvxpy and HiGHS.
"""
import math
from dataclasses import dataclass
from typing import Literal

import numpy as np
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import connected_components

from mechopt.kit.errors import NAMED, ModelError, some_of
from mechopt.kit.result import Clock, Result, Status, from_cvxpy
from mechopt.kit.settings import check_settings
from mechopt.models.cyclogram import Cyclogram
from mechopt.models.cyclogram_bounds import time_floor_deg
from mechopt.solvers.cyclogram.certify import certified
from mechopt.solvers.cyclogram.graph import ROUND_OFF, a_path, level_segments, topological_levels

MAX_STEPS = 10_000           # Dinkelbach steps (each one Bellman-Ford pass): LIMIT past it
FLOAT_MAX_EVENTS = 500       # floats by a max-plus Floyd-Warshall (n^3) for networks up to this many events
PER_NAME_MAX_EVENTS = 10_000  # event times p_* among the values up to this many events
CHECK_RTOL = 1e-9            # the LP's least T against the graph's, relative (per unit above 1)


@dataclass(frozen=True)
class Uniform:
    """The cyclogram's constraints p(heads) - p(tails) >= d - k T as arrays over every event."""
    names: list
    tails: np.ndarray
    heads: np.ndarray
    d: np.ndarray
    k: np.ndarray
    labels: np.ndarray       # how the designer names each arc ("a->b", "a->b[+1]", "window ...", "sync ...")
    operations: int          # arcs [0, operations) are operations (ordinary, then recurrent); windows and syncs follow
    unit: str                # "ms" (time-based operations) or "deg"

    def weights(self, T: float) -> np.ndarray:
        return self.d - self.k * T


def uniform_constraints(task: Cyclogram) -> Uniform:
    """The task's operations, recurrent operations, windows and syncs as uniform constraints. Time-
    based when an operation gives min_ms and the task no speed_rpm (T in ms; an angle a fraction
    phi / 360 of the cycle, module docstring; no stress or amplitude, whose angles are not
    fractions of T); else angle-based, each operation at its bound of every limit (a min_ms as the
    angle the shaft turns in it at speed_rpm)."""
    dag_names, dag_tails, dag_heads = task.index_arrays     # cached on the task: the one cycle's operations
    names = list(dag_names) + task.isolated_events             # events of recurrent operations alone come last
    index = task.event_index | {v: len(dag_names) + i for i, v in enumerate(task.isolated_events)}
    rec = task.recurrences
    timed = (bool(task.time_arcs()) or any(op["min_ms"] is not None for op in rec)) and task.speed_rpm is None
    if timed:
        _check_time_based(task)
        d_ops, k_ops, more = _time_based_operations(task)
        windows = [(str(w["from"]), str(w["to"]), *((-float(w["max_ms"]), 0.0) if "max_ms" in w
                                                     else (0.0, float(w["max_deg"]) / 360.0)),
                    f"{w.get('max_ms', w.get('max_deg')):.6g} {'ms' if 'max_ms' in w else 'deg'}")
                   for w in task.windows]
    else:
        d_ops, k_ops = task.lower_bounds_deg("exact")[0], np.zeros(len(dag_tails))
        d_rec = [op["min_deg"] if op["min_ms"] is None else max(op["min_deg"], time_floor_deg(op["min_ms"], task.speed_rpm))
                 for op in rec]
        more = [(op["from"], op["to"], d, op["cycles"], _recurrent_label(op)) for op, d in zip(rec, d_rec)]
        windows = [(a, b, -w, 0.0, f"{w:.6g} deg") for a, b, w in task.window_arcs()]
    operations = len(dag_tails) + len(more)
    more += [(b, a, d, k, f"window p({b}) - p({a}) <= {text}") for a, b, d, k, text in windows]
    more += [(u, v, 0.0, 0, f"sync p({a}) = p({b})") for a, b in task.sync_pairs() for u, v in ((a, b), (b, a))]
    tails = np.r_[dag_tails, np.array([index[m[0]] for m in more], dtype=np.int64)]
    heads = np.r_[dag_heads, np.array([index[m[1]] for m in more], dtype=np.int64)]
    d = np.r_[d_ops, np.array([m[2] for m in more], dtype=float)]
    k = np.r_[k_ops, np.array([m[3] for m in more], dtype=float)]
    labels = np.concatenate([task.operation_labels, np.array([m[4] for m in more], dtype=str)])
    return Uniform(names, tails, heads, d, k, labels, operations, "ms" if timed else "deg")


def _recurrent_label(op) -> str:
    return f"{op['from']}->{op['to']}[+{op['cycles']}]"


def _time_based_operations(task):
    """(d, k of the one cycle's operations, [recurrent and extra arcs]) in ms: a duration is d = min_ms,
    an angle phi is d = 0, k = cycles - phi / 360; an operation with both gets a second arc (its floor
    is the larger of the two at every T)."""
    d_ops, k_ops, more = [], [], []
    for x, y, data in task.graph.edges(data=True):      # `arcs` order
        phi, ms = data["min_deg"], data["min_ms"]
        d_ops.append(0.0 if ms is None else ms)
        k_ops.append(-phi / 360.0 if ms is None else 0.0)
        if ms is not None and phi > 0:
            more.append((x, y, 0.0, -phi / 360.0, f"{x}->{y}"))
    for op in task.recurrences:
        label, k = _recurrent_label(op), float(op["cycles"])
        if op["min_ms"] is not None:
            more.append((op["from"], op["to"], op["min_ms"], k, label))
        if op["min_ms"] is None or op["min_deg"] > 0:
            more.append((op["from"], op["to"], 0.0, k - op["min_deg"] / 360.0, label))
    return np.array(d_ops, dtype=float), np.array(k_ops, dtype=float), more


def _check_time_based(task):
    """A time-based network's angles are fractions of its cycle; a stress or rebound bound is an angle
    at a speed, not a fraction of T: refused, named."""
    mixed = [f"operations[{x}->{y}].stress" for x, y in (task.arcs[k] for k in task.stress_arcs())]
    mixed += [f"operations[{x}->{y}].amplitude" for x, y in (task.arcs[k] for k in task.amplitude_arcs())]
    if mixed:
        raise ModelError(f"{mixed[0]}: the least cycle time of a time-based network (min_ms) takes durations "
                         f"and angles (fractions of the cycle), not a bound set at a speed (also "
                         f"{some_of(mixed[1:], sep=', ') or 'nothing else'}); give speed_rpm, or use "
                         f"cyclogram.max_machine_speed", key=mixed[0].split(".")[0])


class Circuits:
    """Longest paths on the uniform constraints at a given T from a virtual root (every time
    starts at 0), the predecessor arcs watched for a circuit. A round is one pass over the
    operations of one cycle (a DAG) in topological order, a level at a time (`graph.Levels`'s
    grouping), then the other arcs (recurrent operations, windows, syncs) relaxed together: a
    DAG settles in one pass, so the rounds number about the back arcs on a longest path, not the
    events. Every update must gain more than ROUND_OFF of the largest |weight|; with such strict
    updates a circuit of predecessor arcs has a positive sum (Cormen et al., Introduction to
    Algorithms, lemma 24.16: the arc into the circuit's last-updated event was set from an
    older, smaller time of its tail), so the first one seen is returned."""

    def __init__(self, u: Uniform, dag: int):
        self.u, self.n, self.dag = u, len(u.names), dag
        tails, heads = u.tails[:dag], u.heads[:dag]
        self.order, segments = level_segments(topological_levels(self.n, tails, heads), heads, self.n, reverse=False)
        self.t_fwd = tails[self.order]
        # per level: its slice, reduce starts, targets and each arc's group (its target's place)
        self.segments = [(a, b, starts, targets, np.repeat(np.arange(len(starts)), np.diff(np.r_[starts, b - a])))
                         for a, b, starts, targets in segments]
        self.back = np.arange(dag, len(u.tails))
        self.passes = 0

    def longest(self, T: float):
        """(times p, None) when no circuit is positive at T; else (None, a positive circuit's arcs in order)."""
        self.passes += 1
        u, n = self.u, self.n
        w = u.weights(T)
        dist, pred = np.zeros(n), np.full(n, -1, dtype=np.int64)
        if not len(w):
            return dist, None
        eps = ROUND_OFF * max(1.0, float(np.abs(w).max()))
        w_fwd = w[:self.dag][self.order]
        back, bt, bh = self.back, u.tails[self.back], u.heads[self.back]
        for _ in range(len(back) + n + 2):
            gained = False
            for a, b, starts, targets, group in self.segments:
                gained |= _relax(dist, pred, self.t_fwd[a:b], w_fwd[a:b], starts, targets, group,
                                 self.order[a:b], eps)
            if len(back):
                cand = dist[bt] + w[back]
                gain = cand > dist[bh] + eps
                if gain.any():
                    # the best gaining arc into each event: sorted by (event, value), the last of each event
                    idx = np.flatnonzero(gain)
                    idx = idx[np.lexsort((cand[idx], bh[idx]))]
                    last = np.r_[bh[idx][1:] != bh[idx][:-1], True]
                    dist[bh[idx[last]]] = cand[idx[last]]
                    pred[bh[idx[last]]] = back[idx[last]]
                    gained = True
            if not gained:
                return dist, None
            circuit = _predecessor_circuit(n, u.tails, pred)
            if circuit is not None:
                return None, circuit
        raise _Undecided(f"longest paths still improving after {len(back) + n + 2} rounds without a circuit "
                         f"of predecessors")


def _relax(dist, pred, ends, w, starts, targets, group, arcs, eps) -> bool:
    """One level: each target takes the best of its arcs' tail time + weight when that gains more
    than eps, its predecessor the first arc reaching it; whether any did."""
    cand = dist[ends] + w
    best = np.maximum.reduceat(cand, starts)
    gain = best > dist[targets] + eps
    if not gain.any():
        return False
    at_best = np.flatnonzero((cand == best[group]) & gain[group])
    first = at_best[np.r_[True, group[at_best][1:] != group[at_best][:-1]]]
    dist[targets[gain]] = best[gain]
    pred[targets[gain]] = arcs[first]
    return True


class _Undecided(Exception):
    """Round-off stopped the iteration: no answer to trust."""


class _StepLimit(_Undecided):
    """The iteration's count of steps ran out (LIMIT)."""


def _predecessor_circuit(n, tails, pred) -> list[int] | None:
    """The arcs of a circuit of predecessor arcs (pred[v]: the arc into v), in order; None when none."""
    has = np.flatnonzero(pred >= 0)
    if not len(has):
        return None
    src = tails[pred[has]]
    graph = csr_matrix((np.ones(len(has)), (src, has)), shape=(n, n))
    count, label = connected_components(graph, directed=True, connection="strong")
    sizes = np.bincount(label, minlength=count)
    self_loop = has[src == has]
    cyclic = np.flatnonzero(sizes[label] > 1)
    start = int(cyclic[0]) if len(cyclic) else (int(self_loop[0]) if len(self_loop) else None)
    if start is None:
        return None
    arcs, v = [], start
    while True:                         # back along the predecessors until the start comes round
        k = int(pred[v])
        arcs.append(k)
        v = int(tails[k])
        if v == start:
            return arcs[::-1]


def least_cycle_time(task: Cyclogram, *, check: bool = False,
                     backend: Literal["HIGHS", "CLARABEL"] = "HIGHS") -> Result:
    """The least cycle time T of a recurrent machine and the circuit that sets it (module docstring).

    Returns cycle_time_ms (time-based operations: min_ms and no speed_rpm) or cycle_deg (angle-
    based: min_deg and every limit's bound, a min_ms at speed_rpm) and p_<event>_ms / _deg, the
    earliest times of a schedule repeating every T (networks up to PER_NAME_MAX_EVENTS events);
    diagnostics: critical_circuit {events
    in order, operations ("a->b", a recurrent one "a->b[+k]"), cycles, length}, critical_circuits
    (one per group of critical circuits sharing events: a tie names each), critical_ops (every
    operation on a critical circuit), float_ms / float_deg per operation (how far its duration may
    grow with T unchanged; None: it lies on no circuit, any growth leaves T; networks up to
    FLOAT_MAX_EVENTS events), tasks (a task table's: per task its start, float, critical),
    dinkelbach_steps. LIMIT past MAX_STEPS steps. INFEASIBLE when a circuit of height 0 has a
    positive length (no cycle time fits), that circuit named. check = true solves the LP in
    (p, T) (minimise T; cvxpy and `backend`) beside it: a least T differing by more than 1e-9
    relative makes the answer INACCURATE (values check_rel, diagnostics check).
    """
    check_settings(least_cycle_time, backend=backend)
    task.check_plain("cyclogram.least_cycle_time")
    clock = Clock()
    u = uniform_constraints(task)
    bf = Circuits(u, len(task.arcs))
    clock.built()
    name = f"cycle_time_{u.unit}" if u.unit == "ms" else "cycle_deg"
    diagnostics = {"method": "graph (Dinkelbach on positive circuits)", "unit": u.unit, "events": len(u.names),
                   "operations": u.operations, "recurrent_operations": len(task.recurrences)}
    try:
        T, circuit, steps, p = _dinkelbach(u, bf)
    except _StepLimit as exc:
        return clock.result(Status.LIMIT, {}, message=f"graph: {exc}", diagnostics=diagnostics)
    except _Undecided as exc:
        return clock.result(Status.FAILED, {}, message=f"graph: {exc} (round-off)", diagnostics=diagnostics)
    diagnostics |= {"dinkelbach_steps": steps, "passes": bf.passes}
    if T is None:
        diagnostics |= {"conflict_circuit": _describe(u, circuit)}
        result = clock.result(Status.INFEASIBLE, {}, diagnostics=diagnostics,
                              violated=tuple(str(u.labels[a]) for a in circuit[:NAMED]),
                              message="infeasible at every cycle time: the circuit " + _circuit_text(u, circuit)
                              + _why_no_cycle(u, circuit))
        return _checked(result, u, name, backend) if check else result
    values = {name: T}
    if len(u.names) <= PER_NAME_MAX_EVENTS:
        values |= {f"p_{v}_{u.unit}": float(p[i]) for i, v in enumerate(u.names)}
    critical = _critical(u, p, T, circuit)
    diagnostics |= critical
    if len(u.names) <= FLOAT_MAX_EVENTS:
        diagnostics[f"float_{u.unit}"] = _floats(u, T)
    if task.tasks and len(u.names) <= PER_NAME_MAX_EVENTS:
        diagnostics["tasks"] = _per_task(task, u, p, diagnostics.get(f"float_{u.unit}"), set(critical["critical_ops"]))
    if circuit is None:
        message = f"{name} = 0: no recurrent circuit needs time (any cycle time fits)"
    else:
        ties = len(critical["critical_circuits"])
        message = (f"{name} = {T:.9g}: critical circuit {_circuit_text(u, circuit)}"
                   + (f"; {ties} circuits tie for critical" if ties > 1 else "")
                   + f" (graph, {steps} Dinkelbach steps)")
    result = clock.result(Status.SOLVED, values, message=message, diagnostics=diagnostics,
                          arrays={f"start_{u.unit}": np.asarray(p, dtype=float)})   # by event, in `names` order
    return _checked(result, u, name, backend) if check else result


def _dinkelbach(u, bf):
    """(T*, the critical circuit (None at T* = 0), steps, times at T*); T* None when a circuit of
    height K <= 0 is positive at a T every circuit before it asks for (the circuit then returned)."""
    if np.array_equal(u.k, np.round(u.k)):       # whole heights: a zero-height conflict found in one pass
        big = math.fsum(np.maximum(u.d, 0.0)) + 1.0      # above every ratio: a circuit of K >= 1 is negative there
        _, zero = bf.longest(big)
        if zero is not None:
            if u.k[zero].any() or not math.fsum(u.d[zero]) > 0:
                raise _Undecided(f"a circuit taken as positive at T = {big!r} that is not one of height 0")
            return None, zero, 0, None
    T, critical = 0.0, None
    for step in range(MAX_STEPS + 1):
        p, circuit = bf.longest(T)
        if circuit is None:
            return T, critical, step, p
        D, K = math.fsum(u.d[circuit]), math.fsum(u.k[circuit])
        if K <= 0:          # D - K T > 0 here stays so at every larger T, and T may not fall: no cycle fits
            return None, circuit, step, None
        if not D / K > T:
            raise _Undecided(f"a positive circuit at T = {T!r} whose ratio does not rise above it")
        T, critical = D / K, circuit
    raise _StepLimit(f"no answer after {MAX_STEPS} Dinkelbach steps")


def _why_no_cycle(u, circuit) -> str:
    D, K = math.fsum(u.d[circuit]), math.fsum(u.k[circuit])
    if K == 0:
        return f" spans no cycle (height 0) yet needs {D:.6g} {u.unit}"
    if D < 0:               # D - K T <= 0 holds for T <= D / K only
        return (f" holds at a cycle time of at most {D / K:.6g} {u.unit} (its angles grow with the cycle), less "
                f"than the machine's other circuits ask for")
    return (f" asks for {-K * 360:.6g} deg more than its cycles hold (height {K:.6g})"
            + (f" and {D:.6g} {u.unit} besides" if D > 0 else "") + ": a longer cycle only lengthens its angles")


def _describe(u, circuit) -> dict:
    events = [u.names[u.tails[a]] for a in circuit]
    ops = [str(u.labels[a]) for a in circuit]
    return {"events": events[:NAMED], "operations": ops[:NAMED], "arcs": len(circuit),
            "cycles": _height(u, circuit), f"length_{u.unit}": math.fsum(u.d[circuit])}


def _height(u, circuit) -> int | float:
    """K(C): whole cycles, or (angles in a time-based network) a real number of them."""
    K = math.fsum(u.k[circuit])
    return int(round(K)) if abs(K - round(K)) <= 1e-12 else K


def _circuit_text(u, circuit) -> str:
    return some_of((u.labels[a] for a in circuit), sep=", ")


def _critical(u, p, T, circuit) -> dict:
    """The critical circuits at T*: the arcs tight for the times p (every critical circuit is a
    zero circuit there, so all of its arcs are tight) grouped in strongly connected components;
    a component holding a recurrent arc holds a critical circuit, one named per component."""
    if circuit is None:
        return {"critical_circuit": None, "critical_circuits": [], "critical_ops": []}
    w = u.weights(T)
    tol = 1e-9 * max(1.0, abs(T), float(np.abs(u.d).max(initial=0.0)))
    tight = np.flatnonzero(p[u.heads] - p[u.tails] - w <= tol)
    t_tails, t_heads = u.tails[tight], u.heads[tight]
    n = len(u.names)
    _, label = connected_components(csr_matrix((np.ones(len(tight)), (t_tails, t_heads)), shape=(n, n)),
                                    directed=True, connection="strong")
    inside = tight[label[t_tails] == label[t_heads]]
    components = list(dict.fromkeys(int(label[u.tails[a]]) for a in inside if u.k[a] > 0))
    first = int(label[u.tails[circuit[0]]])
    circuits = [_describe(u, circuit)]
    for c in components:
        if c == first:
            continue
        arcs = inside[label[u.tails[inside]] == c]
        closing = int(arcs[u.k[arcs] > 0][0])
        back = a_path(n, u.tails[arcs], u.heads[arcs], int(u.heads[closing]), int(u.tails[closing]))
        circuits.append(_describe(u, [closing] + [int(arcs[j]) for j in back]))
    ops = [str(u.labels[a]) for a in inside if a < u.operations and label[u.tails[a]] in components]
    return {"critical_circuit": circuits[0], "critical_circuits": circuits, "critical_ops": ops}


def _floats(u, T) -> dict:
    """Per operation, -(its weight + the longest path back from its head to its tail) at T*: how
    far its duration may grow before a circuit through it closes (T rises, or, on a circuit of
    height 0, no T fits); None when no path leads back (on no circuit). A max-plus Floyd-Warshall."""
    n, w = len(u.names), u.weights(T)
    L = np.full((n, n), -np.inf)
    np.maximum.at(L, (u.tails, u.heads), w)
    np.fill_diagonal(L, np.maximum(np.diag(L), 0.0))          # the empty path (a station's own recurrence)
    for m in range(n):
        L = np.maximum(L, L[:, m, None] + L[None, m, :])
    out = {}
    for a in range(u.operations):
        back = L[u.heads[a], u.tails[a]]
        out[str(u.labels[a])] = None if not np.isfinite(back) else max(0.0, -(w[a] + back)) + 0.0
    return out


def _per_task(task, u, p, floats, critical) -> dict:
    """Per task of a task table (`task_operations`): its start in the earliest schedule repeating
    every T*, its float (how far its duration may grow with T* unchanged; None: on no circuit, or
    not computed past FLOAT_MAX_EVENTS) and whether it lies on a critical circuit."""
    at = {v: i for i, v in enumerate(u.names)}
    out = {}
    for row in task.tasks:
        name = str(row["task"]).strip()
        op = f"{name}.start->{name}.end"
        out[name] = {f"start_{u.unit}": float(p[at[f"{name}.start"]]),
                     f"float_{u.unit}": None if floats is None else floats.get(op), "critical": op in critical}
    return out


def cycle_time_lp(u: Uniform, backend: str = "HIGHS"):
    """(status, least T or None): minimise T over (p, T) s.t. D p >= d - k T, T >= 0, p(0) = 0."""
    import cvxpy as cp  # the certificate alone needs it: the graph does not wait for it

    from mechopt.solvers.cyclogram.event_time import incidence
    n = len(u.names)
    p, T = cp.Variable(n, name="p"), cp.Variable(nonneg=True, name="T")
    cons = [p[0] == 0]
    if len(u.tails):
        cons.append(incidence(n, u.tails, u.heads) @ p + T * u.k >= u.d)
    problem = cp.Problem(cp.Minimize(T), cons)
    try:
        problem.solve(solver=backend)
    except cp.error.SolverError as exc:
        return Status.FAILED, None, str(exc)
    status = from_cvxpy(problem.status)
    return status, (float(T.value) if status is Status.SOLVED else None), problem.status


def _checked(result: Result, u: Uniform, name: str, backend: str) -> Result:
    """`result` with the LP's answer beside it: the same status and T to CHECK_RTOL (per unit above 1)."""
    status, T, said = cycle_time_lp(u, backend)
    diagnostics = result.diagnostics | {"check": {"method": f"lp ({backend})", "status": status.value,
                                                  "solver_status": said}}
    values, problems = result.values, []
    if status is not result.status:
        problems.append(f"the LP says {status.value} ({said})")
    elif status is Status.SOLVED:
        rel = abs(result.values[name] - T) / max(1.0, abs(T))
        values = values | {"check_rel": rel}
        diagnostics["check"] |= {name: T, "rel": rel}
        if not rel <= CHECK_RTOL:
            problems.append(f"{name} {result.values[name]!r} against the LP's {T!r}")
    return certified(result, values, diagnostics, problems, by=f"the LP ({backend})")
