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

Solved exactly on the graph by Dinkelbach's (Lawler's) iteration, as `speed_graph.SpeedGraph` solves the
highest speed: from T = 0, a Bellman-Ford pass at T either finds no positive circuit (T is the
answer) or a positive circuit C, whose ratio D(C) / K(C) > T is the next T. T rises strictly and
takes a circuit's ratio each time, so it ends at the maximum ratio after finitely many passes (in
practice a handful; counted, never timed). A positive circuit with K(C) <= 0 stays positive at
every larger T: no cycle fits (INFEASIBLE). The last circuit is critical; at T* the arcs tight for
the pass's times hold every critical circuit (each is a zero circuit there), so ties are named.
The LP in (p, T), minimise T, is the certificate (check = true), solved by cvxpy and HiGHS.

Here the solver and Dinkelbach's iteration; the uniform constraints (cycle_uniform), the pass
that finds a positive circuit (cycle_circuits), the report's critical circuits, floats and tasks
(cycle_report) and the LP certificate (cycle_lp) are their own modules.
"""
import math
from typing import Literal

import numpy as np

from mechopt.kit.errors import NAMED
from mechopt.kit.result import Clock, Result, Status
from mechopt.kit.settings import check_settings
from mechopt.models.cyclogram import Cyclogram
from mechopt.solvers.cyclogram.cycle_circuits import Circuits, StepLimit, Undecided
from mechopt.solvers.cyclogram.cycle_lp import checked_by_lp
from mechopt.solvers.cyclogram.cycle_report import (
    circuit_text,
    critical_of,
    describe_circuit,
    floats_of,
    per_task,
    why_no_cycle,
)
from mechopt.solvers.cyclogram.cycle_uniform import uniform_constraints

MAX_STEPS = 10_000           # Dinkelbach steps (each one Bellman-Ford pass): LIMIT past it
FLOAT_MAX_EVENTS = 500       # floats by a max-plus Floyd-Warshall (n^3) for networks up to this many events
PER_NAME_MAX_EVENTS = 10_000  # event times p_* among the values up to this many events


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
    except StepLimit as exc:
        return clock.result(Status.LIMIT, {}, message=f"graph: {exc}", diagnostics=diagnostics)
    except Undecided as exc:
        return clock.result(Status.FAILED, {}, message=f"graph: {exc} (round-off)", diagnostics=diagnostics)
    diagnostics |= {"dinkelbach_steps": steps, "passes": bf.passes}
    if T is None:
        diagnostics |= {"conflict_circuit": describe_circuit(u, circuit)}
        result = clock.result(Status.INFEASIBLE, {}, diagnostics=diagnostics,
                              violated=tuple(str(u.labels[a]) for a in circuit[:NAMED]),
                              message="infeasible at every cycle time: the circuit " + circuit_text(u, circuit)
                              + why_no_cycle(u, circuit))
        return checked_by_lp(result, u, name, backend) if check else result
    values = {name: T}
    if len(u.names) <= PER_NAME_MAX_EVENTS:
        values |= {f"p_{v}_{u.unit}": float(p[i]) for i, v in enumerate(u.names)}
    critical = critical_of(u, p, T, circuit)
    diagnostics |= critical
    if len(u.names) <= FLOAT_MAX_EVENTS:
        diagnostics[f"float_{u.unit}"] = floats_of(u, T)
    if task.tasks and len(u.names) <= PER_NAME_MAX_EVENTS:
        diagnostics["tasks"] = per_task(task, u, p, diagnostics.get(f"float_{u.unit}"), set(critical["critical_ops"]))
    if circuit is None:
        message = f"{name} = 0: no recurrent circuit needs time (any cycle time fits)"
    else:
        ties = len(critical["critical_circuits"])
        message = (f"{name} = {T:.9g}: critical circuit {circuit_text(u, circuit)}"
                   + (f"; {ties} circuits tie for critical" if ties > 1 else "")
                   + f" (graph, {steps} Dinkelbach steps)")
    arrays = {"event": list(u.names), f"start_{u.unit}": np.asarray(p, dtype=float)}     # `--csv`: a row per event
    result = clock.result(Status.SOLVED, values, message=message, diagnostics=diagnostics, arrays=arrays)
    return checked_by_lp(result, u, name, backend) if check else result


def _dinkelbach(u, bf):
    """(T*, the critical circuit (None at T* = 0), steps, times at T*); T* None when a circuit of
    height K <= 0 is positive at a T every circuit before it asks for (the circuit then returned)."""
    if np.array_equal(u.k, np.round(u.k)):       # whole heights: a zero-height conflict found in one pass
        big = math.fsum(np.maximum(u.d, 0.0)) + 1.0      # above every ratio: a circuit of K >= 1 is negative there
        _, zero = bf.longest(big)
        if zero is not None:
            if u.k[zero].any() or not math.fsum(u.d[zero]) > 0:
                raise Undecided(f"a circuit taken as positive at T = {big!r} that is not one of height 0")
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
            raise Undecided(f"a positive circuit at T = {T!r} whose ratio does not rise above it")
        T, critical = D / K, circuit
    raise StepLimit(f"no answer after {MAX_STEPS} Dinkelbach steps")
