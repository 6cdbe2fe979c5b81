"""Event times of a cyclogram whose operations are motions: clearances between them and the least
of several motions' angles maximised, in one LP (cvxpy + HiGHS).

    maximise z  (maximize = "least_angle" or "least_scaled_angle")  or  minimise p(last) - p(first)
    subject to  p(y) - p(x) >= lb(x, y)                        every operation (its limits at speed_rpm)
                p(y) - p(x) <= w,  p(a) = p(b)                 windows, syncs
                p(last) - p(first) <= cycle                    unless span_within_cycle = false
                s (p_a(x_a) - p_b(x_b) - k cycle) <= 0         clearances (s = +1 before, -1 after)
                p(y) - p(x) >= z w_k                           each operation k of least_angle_of
                p(first) = 0

p_k(x) = p(from_k) + x (p(to_k) - p(from_k)) is the instant operation k reaches the fraction of
its stroke whose angle fraction is x (S(x) = c, models/cyclogram_motions.py): a fixed fraction for a
fixed law, so the row is linear in the event times, though not a difference of two of them unless
both angles are fixed. This is why the clearances and the objective live here and not on the
graph (plan_cyclogram's method "graph" and the highest-speed solvers take difference constraints
only, and refuse them). A clearance with `cycles` = k names the other operation of k cycles later
(its instants k cycle_deg on): a machine whose die rises into the turret's next index is posed
over one cycle, not unrolled by hand. With span_within_cycle = false the events of one cycle may
spread over more than a turn (each motion's repetition is then its own clearance of cycles = 1).

w_k = 1 maximises the least angle; w_k = sqrt(Ca_k h_k) ("least_scaled_angle",
models/cyclogram_motions.objective_weights) minimises the largest peak acceleration Ca_k h_k
(6 n)^2 / t_k^2 of motions of different laws and strokes, still one LP: at the answer the motions
whose rows bind share that peak, (6 n)^2 / z^2.
"""
import math

import cvxpy as cp
import numpy as np

from mechopt.kit.errors import NAMED, ModelError, some_of
from mechopt.kit.result import Clock, Result, Status, from_cvxpy
from mechopt.models.cyclogram import Cyclogram
from mechopt.models.cyclogram_motions import LEAST_ANGLE, LEAST_SCALED_ANGLE
from mechopt.solvers.cyclogram.event_time import incidence

DUAL_TOL = 1e-7        # a constraint whose dual exceeds this binds (it stops the objective)
FEAS_TOL_DEG = 1e-6    # the answer's rows re-checked in numpy to this [deg]
CULPRIT_TRIES = 50     # an infeasible LP: rows dropped one at a time, at most these (one LP each)


def plan_motions(task: Cyclogram, *, backend: str = "HIGHS") -> Result:
    """Event times with clearances between motions, maximising the least angle of a named set of
    operations (`maximize = "least_angle"`, `least_angle_of`), minimising the largest peak
    acceleration of that set (`"least_scaled_angle"`), or minimising the span.

    Returns least_angle_deg ("least_angle") or least_scaled_angle_deg_per_sqrt_m (_rad) and at
    speed_rpm highest_peak_accel_m_s2 (_rad_s2) ("least_scaled_angle"), span_deg, p_<event>_deg,
    t_<x>_<y>_deg, per clearance clearance_<j>_slack_deg (how far its instants are apart, >= 0),
    and at speed_rpm the motions' peak accel_<x>_<y>_m_s2 and velocity_<x>_<y>_m_s (rad_s2, rad_s
    for stroke_deg); diagnostics limited_by: the constraints whose duals are nonzero (what stops
    the objective, in the table's words), with their duals [deg per deg], kind and the operations
    or events they join (also as binding_rows, which the cyclogram marks), objective_binds: the
    objective's operations whose rows bind. The LP's status is checked and its answer re-checked
    row by row (INACCURATE past FEAS_TOL_DEG)."""
    task.check_one_cycle("plan_motions")
    clock = Clock()
    names, tails, heads = task.index_arrays
    index = task.event_index
    first, last = index[task.first_event], index[task.last_event]
    lb, why = task.lower_bounds_deg()
    rows, meta = _rows(task, names, tails, heads, first, last)
    p = cp.Variable(len(names), name="p_deg")
    z = cp.Variable(name="least_angle_deg")
    cons = [incidence(len(names), tails, heads) @ p >= lb, p[first] == 0]
    labels, infos = ["operations", "anchor"], [{}, {}]
    for (A, rhs, label), info in zip(rows, meta):           # A p <= rhs, one row each
        cons.append(A @ p <= rhs)
        labels.append(label)
        infos.append(info)
    least, weights = task.least_angle_arcs, task.objective_weights
    if task.maximize is not None:
        for k, w in zip(least, weights):
            cons.append(p[heads[k]] - p[tails[k]] >= w * z)
            labels.append(f"least_angle_of {_op(task, k)}")
            infos.append({"kind": "objective", "ops": [_arc(task, k)]})
        objective = cp.Maximize(z)
    else:
        objective = cp.Minimize(p[last] - p[first])
    problem = cp.Problem(objective, cons)
    clock.built()
    try:
        problem.solve(solver=backend)
    except cp.error.SolverError as exc:
        return clock.result(Status.FAILED, {}, message=f"{backend}: {exc}")
    status = from_cvxpy(problem.status)
    if status is Status.INFEASIBLE:
        culprits, tried = _culprits(len(names), tails, heads, lb, first, rows, backend)
        more = f" (the first {tried} of {len(rows)} rows tried)" if tried < len(rows) else ""
        return clock.result(status, {}, violated=tuple(culprits[:NAMED]), message=(
            "infeasible: the operations' bounds with " + (f"the rows {some_of(culprits, sep='; ')}: each one "
                                                          f"dropped leaves a schedule{more}" if culprits else
                                                          f"no single row dropped leaves a schedule{more}")))
    if status is not Status.SOLVED:
        return clock.result(status, {}, message=f"the motions' LP: {problem.status}")
    pv = np.asarray(p.value, dtype=float)
    t = pv[heads] - pv[tails]
    values = {"span_deg": float(pv[last] - pv[first])}
    if task.maximize == LEAST_ANGLE:
        values["least_angle_deg"] = float(min(t[k] for k in least))
    elif task.maximize == LEAST_SCALED_ANGLE:
        values |= _scaled(task, t, least, weights)
    values |= {f"p_{v}_deg": float(pv[i]) for i, v in enumerate(names)}
    values |= {f"t_{x}_{y}_deg": float(t[k]) for k, (x, y) in enumerate(task.arcs)}
    for j, (A, rhs, label) in enumerate(rows):
        if label.startswith("clearance"):
            values[f"clearance_{j - _n_plain(rows)}_slack_deg"] = float(rhs - A @ pv)
    values |= task.motion_values(t, task.speed_rpm)
    worst = max([float(np.max(lb - t, initial=-math.inf))] + [float(A @ pv - rhs) for A, rhs, _ in rows])
    limited = [{"constraint": label, "dual": float(np.max(np.abs(np.atleast_1d(c.dual_value))))} | info
               for c, label, info in zip(cons, labels, infos) if label != "anchor" and c.dual_value is not None
               and np.max(np.abs(np.atleast_1d(c.dual_value))) > DUAL_TOL]
    limited += [{"constraint": f"{why[k]}[{_op(task, k)}] t >= {lb[k]:.6g} deg", "dual": float(d),
                 "kind": "operation", "ops": [_arc(task, k)]}
                for k, d in enumerate(np.atleast_1d(cons[0].dual_value)) if d > DUAL_TOL]
    # the objective's own rows bind by definition: what stops it are the others
    at_objective = [row["ops"][0] for row in limited if row.get("kind") == "objective"]
    limited = [row for row in limited if row["constraint"] != "operations"
               and not row["constraint"].startswith("least_angle_of")]
    diagnostics = {"limited_by": limited, "backend": backend, "worst_row_deg": worst,
                   "angle_fractions": {row.label: [row.x_a, row.x_b] for row in task.clearance_rows},
                   "objective_binds": at_objective,
                   # each binding row's kind, the operations ("from->to") or events it joins: the chart marks them
                   "binding_rows": [{k: row[k] for k in ("constraint", "kind", "ops", "events") if k in row}
                                    for row in limited]}
    objective_text = _objective_text(task, values, least)
    message = f"{objective_text}; limited by {some_of((r['constraint'] for r in limited), sep='; ') or 'nothing'}"
    arrays = {"operation": task.operation_labels, "start_deg": pv[tails], "end_deg": pv[heads], "duration_deg": t}
    if worst > FEAS_TOL_DEG:
        return clock.result(Status.INACCURATE, values, message=f"a row is violated by {worst:.3g} deg; {message}",
                            diagnostics=diagnostics, arrays=arrays)
    return clock.result(Status.SOLVED, values, message=message, diagnostics=diagnostics, arrays=arrays)


def _scaled(task, t, least, weights) -> dict:
    """The least scaled angle z = min t_k / w_k [deg / sqrt(m), or sqrt(rad)] and at speed_rpm the
    largest peak acceleration of the set, (6 n)^2 / z^2 [m/s^2, or rad/s^2]."""
    unit = task.motion_arcs[least[0]].units
    z = float(min(t[k] / w for k, w in zip(least, weights)))
    out = {f"least_scaled_angle_deg_per_sqrt_{'rad' if unit[0] == 'deg' else 'm'}": z}
    if task.speed_rpm:
        out[f"highest_peak_accel_{unit[1]}"] = (6.0 * task.speed_rpm / z) ** 2
    return out


def _objective_text(task, values, least) -> str:
    ops = some_of((_op(task, k) for k in least), sep=", ")
    if task.maximize == LEAST_ANGLE:
        return f"least angle of {ops} = {values['least_angle_deg']:.6g} deg"
    if task.maximize == LEAST_SCALED_ANGLE:
        unit = task.motion_arcs[least[0]].units[1]
        peak = values.get(f"highest_peak_accel_{unit}")
        peak = "" if peak is None else f" (largest peak acceleration {peak:.6g} {unit.replace('_s2', '/s^2')})"
        return f"least scaled angle t / sqrt(Ca h) of {ops} maximised{peak}"
    return f"span {values['span_deg']:.6g} deg"


def _culprits(n, tails, heads, lb, first, rows, backend) -> tuple[list[str], int]:
    """The rows (windows, syncs, the cycle, clearances) without any one of which the bounds hold:
    one feasibility LP per row, up to CULPRIT_TRIES rows; and how many were tried."""
    D, out = incidence(n, tails, heads), []
    tried = rows[:CULPRIT_TRIES]
    for j in range(len(tried)):
        p = cp.Variable(n)
        cons = [D @ p >= lb, p[first] == 0] + [A @ p <= rhs for i, (A, rhs, _) in enumerate(tried) if i != j]
        cons += [A @ p <= rhs for A, rhs, _ in rows[CULPRIT_TRIES:]]
        problem = cp.Problem(cp.Minimize(0), cons)
        problem.solve(solver=backend)
        if from_cvxpy(problem.status) is Status.SOLVED:
            out.append(tried[j][2])
    return out, len(tried)


def _arc(task, k) -> str:
    x, y = task.arcs[k]
    return f"{x}->{y}"


def _op(task, k) -> str:
    x, y = task.arcs[k]
    name = task.arc_data(k)["name"]
    return f'"{name}"' if name else f"{x}->{y}"


def _n_plain(rows) -> int:
    return sum(1 for *_, label in rows if not label.startswith("clearance"))


def _rows(task, names, tails, heads, first, last) -> tuple[list, list]:
    """Every constraint but the operations' and the anchor as (a row over p, rhs, label): A p <= rhs.
    Windows, syncs and the cycle first, then the clearances in table order; and per row its kind
    and the events ("window", "sync", "cycle") or operations ("clearance") it joins."""
    n, index, out, meta = len(names), task.event_index, [], []

    def row(pairs):
        a = np.zeros(n)
        for i, c in pairs:
            a[i] += c
        return a

    for a, b, w in task.window_arcs():
        out.append((row([(index[b], 1.0), (index[a], -1.0)]), w, f"window p({b}) - p({a}) <= {w:.6g} deg"))
        meta.append({"kind": "window", "events": [a, b]})
    for a, b in task.sync_pairs():
        out += [(row([(index[a], 1.0), (index[b], -1.0)]), 0.0, f"sync p({a}) = p({b})"),
                (row([(index[b], 1.0), (index[a], -1.0)]), 0.0, f"sync p({b}) = p({a})")]
        meta += [{"kind": "sync", "events": [a, b]}] * 2
    if task.cycle_deg is not None and task.span_within_cycle:
        out.append((row([(last, 1.0), (first, -1.0)]), task.cycle_deg,
                    f"cycle p({names[last]}) - p({names[first]}) <= {task.cycle_deg:.6g} deg"))
        meta.append({"kind": "cycle", "events": [names[first], names[last]]})
    for c in task.clearance_rows:
        # s (p_a(x_a) - p_b(x_b)) <= s k cycle, p_k(x) = (1 - x) p(from_k) + x p(to_k)
        shift = c.cycles * (task.cycle_deg or 0.0)
        out.append((c.sign * row([(tails[c.a], 1.0 - c.x_a), (heads[c.a], c.x_a),
                                  (tails[c.b], c.x_b - 1.0), (heads[c.b], -c.x_b)]), c.sign * shift, c.label))
        meta.append({"kind": "clearance", "ops": [_arc(task, c.a), _arc(task, c.b)]})
    if not out and task.maximize is not None:
        raise ModelError("least_angle_of: with no window, cycle or clearance the angles grow without end",
                         key="least_angle_of")
    return out, meta
