"""The press drive designed by optimisation: an NLP whose constraints contain
the periodic steady motion itself.

Multiple shooting over one revolution in the crank angle (shooting.py): the cut's start and end
are interval boundaries, so the switched force is kept exactly; the crank-speed extremes found on
the way are boundaries too, so the speed fluctuation the NLP limits is the continuous one, not a
sampled one. IPOPT solves it with exact first derivatives (CVODES forward sensitivities through
the integrators) and a limited-memory Hessian.

Every answer is then simulated again by the event-located integrator (`events`' march from the
optimum's state at phi = 0, one period): its period, mean speed, speed fluctuation, RMS motor
torque and energy per stroke must agree with the NLP's to `VERIFY_REL` or the answer is at best
INACCURATE. Active limits are reported with their multipliers in the user's terms (what a unit
more of the limit is worth in the objective), and a variable on its bound is named.

Start and retries (a designer's own press must come out SOLVED at the default settings).
Every number the NLP sees is of order 1 (`_scales`: variables by the start, states by the nominal
speed and the belt's twist under the mean torque, limits by their value). With a speed-fluctuation
limit and the flywheel free, the start is the textbook flywheel I = Delta E / (C_s omega^2) from the
load diagram (`models.press.rule_of_thumb_flywheel_kgm2`), not the press's own flywheel. Then, each
step only while the one before has not certified its answer (`RETRIES`, in this order):

1. `rule_of_thumb`: coarse passes (CVODES at `COARSE_TOL`) place the speed extremes as nodes, a
   fine pass at `tol` from there; an event-located check that misses re-solves once at tol / 10.
2. `press_start`: the same from the press's own values (when they differ from step 1's start).
3. `cut_continuation`: the design with the cut force at `CONTINUATION` of itself, then from its
   optimum (nodes, design, orbit) at the full force.

INFEASIBLE (the limits conflict: phase 1 says so), a stall and the rigid-belt limit end the ladder
at once: a retry cannot change them. When no step certifies, the best attempt is returned with a hint that names the
settings to try (`tol`, `max_iter`, `samples`, `start`; also `diagnostics["hint"]`), and
`diagnostics["attempts"]` lists each step.
"""
from dataclasses import dataclass, replace
from itertools import pairwise
from typing import Literal

import casadi as ca
import numpy as np
from scipy.integrate import simpson

from mechopt.kit.cache import memoised
from mechopt.kit.errors import ModelError
from mechopt.kit.result import Clock, Result, Status, from_ipopt
from mechopt.kit.settings import Annotated, Interval, Tolerance, check_settings
from mechopt.models.press_design import BOUNDS, PressDesign, single_stroke_margin_J
from mechopt.models.press_energy import breakdown_torque_at_crank_Nm, required_mean_torque_Nm, stall_check
from mechopt.models.press_equations import Dynamics, structure
from mechopt.models.press_laws import FORCE_KEYS
from mechopt.solvers.press.periodic import steady_state
from mechopt.solvers.press.problem import (
    TWO_PI,
    Samples,
    Trace,
    belt_mode,
    belt_too_fast_per_revolution,
    dynamics_of,
    locate,
    march,
    piece_by_time,
    refuse_jumps,
    refuse_neutral_speed,
    revolution,
    summarise,
    top_speed_rad_s,
)
from mechopt.solvers.press.shooting import QUADRATURES, cutting_on, intervals, probe, reach, stage_angles

TIGHTEST_TOL = 1e-12         # CVODES tolerance the retry after a missed check goes no further than
VERIFY_REL = 1e-6            # the event-located simulation must give the NLP's figures to this
NODE_MOVE_RAD = 1e-4         # a speed extreme further than this from a stage boundary becomes a node
MISSED_SPREAD = 3e-7         # re-solve while the samples' speed spread misses the dense one by more (relative)
STEPS_PER_REVOLUTION = 300   # belt-mode steps (a tenth of its period) per revolution the NLP takes on (~120 Hz)
RIGID_RATIO = 1000           # belt mode / revolution frequency past which the rigid belt is its limit (SOLVED there)
COARSE_TOL = 1e-7             # CVODES tolerance of the first pass, which only finds where the extremes go
COARSE_ITER = 60              # and its IPOPT iterations
COARSE_MISSED = 1e-4          # a coarse pass whose spread misses the dense one by less is followed by a fine one
COARSE_PASSES = 3             # passes at COARSE_TOL at most before the ones at the asked tolerance
# IPOPT from a coarse pass's optimum: its primal and multipliers, pushed only slightly off the bounds
WARM_START = {"ipopt.warm_start_init_point": "yes", "ipopt.warm_start_bound_push": 1e-6,
              "ipopt.warm_start_bound_frac": 1e-6, "ipopt.warm_start_slack_bound_push": 1e-6,
              "ipopt.warm_start_slack_bound_frac": 1e-6, "ipopt.warm_start_mult_bound_push": 1e-6}
MAX_PASSES = 8               # NLP solves, each with the extremes of the one before as nodes
CANDIDATES = 3               # local speed peaks (and troughs) refined to find the largest (smallest)
DENSE = 400                  # samples per interval when locating the speed extremes (error ~1e-5 rad)
CONTINUATION = 0.5           # the cut force's share in the first solve of the continuation retry
RETRIES = ("rule_of_thumb", "press_start", "cut_continuation")     # the order the module doc explains
MIN_SPEED_SHARE = 0.05       # omega >= this x nominal everywhere: the crank turns forward (d/dphi = d/dt / omega)
UNITS = {"least_flywheel_inertia": ("flywheel_inertia_kgm2", "kg m2", "flywheel inertia"),
         "least_motor_rms_torque": ("motor_rms_torque_N_m", "N m", "motor RMS torque"),
         "least_energy_per_stroke": ("energy_per_stroke_J", "J", "energy per stroke")}
# constraint block -> (the task's knob it is measured against, its unit, what the knob limits)
KNOBS = {"speed_fluctuation": ("max_speed_fluctuation", "", "speed fluctuation it can keep"),
         "belt_slip": ("belt_slip_torque_Nm", "N m", "belt torque it can keep"),
         "motor_breakdown": ("motor_safety_factor", "", "motor safety factor it can keep"),
         "single_stroke": ("single_stroke_energy_J", "J", "energy it can carry through a single stroke"),
         "mean_speed": ("nominal_speed_rad_s", "rad/s", "mean crank speed")}


@dataclass(frozen=True)
class _Block:
    """Constraints of one physical name: rows [start, stop) of g."""
    name: str
    start: int
    stop: int


@memoised(maxsize=8, per_thread=True)     # an nlpsol: one per thread (see BuildCache)
def _nlp(task: PressDesign, nodes: tuple, tol: float, samples: int, scales: tuple, elastic: bool, max_iter: int,
         near: bool = False, coarse: bool = False, warm: bool = False):
    """(nlpsol, blocks, (lbg, ubg), Function w -> figures, number of slacks). With `elastic`, the
    limits (not the motion's equations) get one slack each and the objective is their sum: the
    least violation, for an INFEASIBLE answer's best achievable. `near`: the start is close to the
    optimum (a small initial barrier parameter keeps IPOPT there). `coarse`: a first pass that only
    places the nodes (loose IPOPT tolerances, `COARSE_ITER` iterations). `warm`: the start is a coarse
    pass's optimum with its multipliers (IPOPT's warm start)."""
    ints = intervals(task, nodes, tol, samples)
    look = probe(task, samples)
    nd, K = len(task.variables), len(ints)
    m = len(task.state_names) - 1
    dsc, ysc, fsc = np.array(scales[0]), np.array(scales[1]), scales[2]
    fluct = task.max_speed_fluctuation is not None
    rows = []                                   # (name, expression, low, high, a limit the user set)

    # each interval's quadratures are variables too: no row then reaches every interval's integrator,
    # so the Jacobian's columns colour into few directions for CVODES' forward sensitivities
    w = ca.MX.sym("w", nd + K * m + 2 * fluct + K * len(QUADRATURES))
    d = w[:nd] * dsc
    Y = [w[nd + k * m:nd + (k + 1) * m] * ysc for k in range(K)]
    qsc = _quadrature_scales(task, scales)
    base = nd + K * m + 2 * fluct
    q = [w[base + k * len(qsc):base + (k + 1) * len(qsc)] * qsc for k in range(K)]
    totals = sum(q[1:], q[0])
    omega, belt, shaft = [], [], []
    for k, (integ, grid, u) in enumerate(ints):
        run = integ(x0=Y[k], p=ca.vertcat(u, d))
        xs = run["xf"]
        rows.append((f"periodicity[{k}]", (xs[:, -1] - Y[(k + 1) % K]) / ysc, 0, 0, False))
        rows.append((f"quadratures[{k}]", (run["qf"][:, -1] - q[k]) / qsc, 0, 0, False))
        out = look(xs, ca.DM(grid).T, u, d)
        omega.append(out[0, :].T)
        belt.append(out[1, :].T)
        shaft.append(out[2, :].T)
    period = totals[0]
    omega, belt, shaft = ca.vertcat(*omega), ca.vertcat(*belt), ca.vertcat(*shaft)
    design = dict(zip(task.variables, ca.vertsplit(d)))
    rms = ca.sqrt(totals[-1] / period)
    energy = task.motor_sync_speed_rad_s * totals[-2] if task.motor else 0 * period
    speed = task.nominal_speed_rad_s
    rows.append(("forward_motion", omega / (MIN_SPEED_SHARE * speed), 1, ca.inf, False))
    if "gear_ratio" in task.variables:      # the strokes per minute are the press's, whatever the ratio
        rows.append(("mean_speed", (TWO_PI / period - speed) / speed, 0, 0, False))
    if fluct:
        hi, lo = w[nd + K * m] * speed, w[nd + K * m + 1] * speed
        rows.append(("speed_samples", ca.vertcat(omega - hi, lo - omega) / speed, -ca.inf, 0, False))
        rows.append(("speed_fluctuation", (hi - lo) * period / TWO_PI / task.max_speed_fluctuation, -ca.inf, 1, True))
    if task.belt_slip_torque_Nm is not None:
        rows.append(("belt_slip", belt / task.belt_slip_torque_Nm, -1, 1, True))
    if task.motor_safety_factor is not None:
        allowed = design.get("motor_scale", 1.0) * task.motor_breakdown_torque_Nm / task.motor_safety_factor
        rows.append(("motor_breakdown", shaft / allowed, -1, 1, True))
    if task.single_stroke_speed_drop is not None and len(stage_angles(task)) == 4:      # a cut to carry
        a = stage_angles(task)[1]
        entry = Y[nodes.index(a)][task.state_names.index("omega_rad_s") - 1]
        margin = single_stroke_margin_J(task, design.get("flywheel_inertia_kgm2", task.flywheel_inertia_kgm2),
                                        entry, task.single_stroke_speed_drop, ca)
        rows.append(("single_stroke", margin / scales[3], 0, ca.inf, True))
    objective = {"least_flywheel_inertia": design.get("flywheel_inertia_kgm2", 0),
                 "least_motor_rms_torque": rms, "least_energy_per_stroke": energy}[task.objective] / fsc
    x, slacks = w, 0
    if elastic:                 # phase 1: least violation of the limits, one slack per limit
        soft = [r for r in rows if r[4]]
        slack = ca.MX.sym("slack", len(soft))
        x, slacks, objective = ca.vertcat(w, slack), len(soft), ca.sum1(slack)
        relaxed = [r for r in rows if not r[4]]
        for i, (name, e, low, high, _) in enumerate(soft):
            if np.isfinite(high):
                relaxed.append((name, e - slack[i], -ca.inf, high, True))
            if np.isfinite(low):
                relaxed.append((name, e + slack[i], low, ca.inf, True))
        rows = relaxed
    blocks, start = [], 0
    for name, e, _, _, _ in rows:
        blocks.append(_Block(name, start, start + e.numel()))
        start += e.numel()
    g = ca.vertcat(*[ca.vec(r[1]) for r in rows])
    lbg = np.concatenate([np.full(r[1].numel(), float(r[2])) for r in rows])
    ubg = np.concatenate([np.full(r[1].numel(), float(r[3])) for r in rows])
    # from a nearby start the barrier stays small (monotone): the adaptive rule can raise it from
    # 1e-6 to 1e3 on the first infeasible steps and wander back over ~50 quasi-Newton iterations
    # no wall-time limit: max_iter (a count) ends a solve, so a busy machine gives the same design
    solver = ca.nlpsol("design", "ipopt", {"x": x, "f": objective, "g": g},
                       {"ipopt.print_level": 0, "print_time": False, "ipopt.sb": "yes",
                        "ipopt.hessian_approximation": "limited-memory",
                        "ipopt.tol": 1e-5 if coarse else 1e-8, "ipopt.constr_viol_tol": 1e-7 if coarse else 1e-10,
                        "ipopt.mu_strategy": "monotone" if near else "adaptive", "ipopt.max_iter": min(max_iter, COARSE_ITER) if coarse else max_iter,
                        "ipopt.mu_init": 1e-6 if near else 0.1,
                        "error_on_fail": False} | (WARM_START if warm else {}))
    figures = ca.Function("figures", [x], [d, ca.vertcat(*Y), period, rms, energy, g, omega])
    return solver, tuple(blocks), (lbg, ubg), figures, slacks


def design(task: PressDesign, *, tol: Tolerance = 1e-10, samples: Samples = 16,
           max_iter: Annotated[int, Interval(ge=1, le=3000)] = 200, check_sensitivity: bool = False,
           start: Literal["rule_of_thumb", "press"] = "rule_of_thumb") -> Result:
    """The drive that minimises `task.objective` over `task.variables` subject to its limits, on
    the periodic steady motion (see the module doc and `models.press_design.PressDesign`).

    Parameters
    ----------
    tol : CVODES tolerance inside the NLP and (times 1e-2) in the event-located check.
    samples : outputs per shooting interval at which the limits are imposed (the speed extremes are
        interval boundaries, so the fluctuation is exact whatever this is).
    max_iter : IPOPT iterations.
    check_sensitivity : re-solve with the first active limit 0.1 % looser and tighter and compare the
        central difference with the multiplier's sensitivity (`sensitivity_fd_rel_error`).
    start : "rule_of_thumb" (the flywheel of `models.press.rule_of_thumb_flywheel_kgm2`, when the
        flywheel is free under a speed-fluctuation limit) or "press" (the press's own values) for
        the first try; the retries of the module doc follow when it does not certify.

    Returns a Result: SOLVED (IPOPT's Solve_Succeeded and the event-located check within
    `VERIFY_REL`); values: the design (`flywheel_inertia_kgm2`, ...), `speed_fluctuation`,
    `motor_rms_torque_N_m`, `energy_per_stroke_J`, the sensitivities `d_<objective>_d_<limit>` of
    each active limit and bound; INFEASIBLE with the best achievable (least violation) and the
    limits and bounds that conflict, or with the least motor when the motor cannot carry the cycle
    (stall); INACCURATE, LIMIT or FAILED otherwise, with the reason.

    >>> import mechopt
    >>> run = mechopt.solve("press/flywheel-design")
    >>> run.status.value, run.values["speed_fluctuation"] <= 0.01 + 1e-9
    ('SOLVED', True)
    """
    if not isinstance(task, PressDesign):
        raise ModelError(f"task={type(task).__name__}: expected a PressDesign", key="task")
    check_settings(design, tol=tol, samples=samples, max_iter=max_iter, check_sensitivity=check_sensitivity, start=start)
    task.require_drive("a design on the periodic motion")
    refuse_neutral_speed(task, "press.design")
    refuse_jumps(task, "press.design", "integrates each shooting stage across them (its stages end at the window's "
                 "ends and the speed's extremes only)")
    clock = Clock()
    first = task.start(rule_of_thumb=start == "rule_of_thumb")
    attempts, result = [], None
    for step in RETRIES:
        if step == "press_start":
            other = task.start(rule_of_thumb=start != "rule_of_thumb")
            if other == first:
                continue
            tried = _design(task, tol, samples, max_iter, check_sensitivity, None, other)
        elif step == "cut_continuation":
            if not task.cutting:
                continue
            tried = _continued(task, tol, samples, max_iter, check_sensitivity, first)
        else:
            tried = _design(task, tol, samples, max_iter, check_sensitivity, None, first)
        attempts.append({"step": step, "status": tried.status.value, "message": tried.message[:200]})
        result = tried if result is None or _rank(tried) < _rank(result) else result
        # a conflict, a stall or the rigid-belt limit is the problem's, not the start's: no retry changes it
        if tried.status in (Status.SOLVED, Status.INFEASIBLE) or "belt_mode" in tried.violated \
                or "model" in tried.diagnostics:
            break
    clock.build_s = result.timing.build_s          # the chosen try's construction; the other tries are solving
    timing = clock.timing()
    diagnostics = result.diagnostics | {"attempts": attempts}
    if result.status in (Status.SOLVED, Status.INFEASIBLE):
        message = result.message if len(attempts) == 1 else \
            f"{result.message} (after the retries {', '.join(a['step'] for a in attempts)})"
        return replace(result, timing=timing, diagnostics=diagnostics, message=message)
    hint = (f"not certified after the retries {', '.join(a['step'] for a in attempts)}; try: a looser or tighter "
            f"CVODES tolerance (tol=1e-8, or 1e-11; now {tol:g}), more IPOPT iterations (max_iter="
            f"{min(5 * max_iter, 3000)}; now {max_iter}), more samples per interval (samples={2 * samples}; "
            f"now {samples}), the other start (start={'press' if start == 'rule_of_thumb' else 'rule_of_thumb'}"
            f") with the press's flywheel_inertia_kgm2 near the answer, or wider bounds")
    return replace(result, timing=timing, diagnostics=diagnostics | {"hint": hint}, message=f"{result.message}; {hint}")


def _rank(result):
    """Which of two unfinished attempts to return: SOLVED, INFEASIBLE, INACCURATE, then the rest."""
    order = (Status.SOLVED, Status.INFEASIBLE, Status.INACCURATE)
    return order.index(result.status) if result.status in order else len(order)


def _continued(task, tol, samples, max_iter, check_sensitivity, start):
    """Retry `cut_continuation`: the design with the cut force at `CONTINUATION` of itself from
    `start`, then at the full force from its optimum (its nodes, design and orbit at phi = 0)."""
    keys = [k for k in (*FORCE_KEYS, "load_force_N", "load_torque_Nm", "load_energy_J") if getattr(task, k) is not None]
    softer = replace(task, **{k: CONTINUATION * getattr(task, k) for k in keys})
    first = _design(softer, tol, samples, max_iter, False, None, start)
    if first.status is not Status.SOLVED:
        return first
    nodes = tuple(np.radians(first.diagnostics["nodes_deg"]))
    design_ = {k: first.values[k] for k in task.variables}
    y0 = np.asarray(first.diagnostics["node_state"])
    return _design(task, tol, samples, max_iter, check_sensitivity, (nodes, design_, y0), design_)


def _design(task, tol, samples, max_iter, check_sensitivity, warm, start=None):
    """`design`'s one try from `start` (a design; the task's own start when None); `warm` =
    (nodes, design, states at phi = 0) of a nearby optimum to start from instead."""
    clock = Clock()
    stall = _stall(task)
    if stall is not None:
        return clock.result(Status.INFEASIBLE, stall[0], stall[1], ("stall",))
    start = task.start() if start is None else start
    too_fast = belt_too_fast_per_revolution(task.drive(start), STEPS_PER_REVOLUTION, "the design NLP")
    if too_fast:
        return _on_rigid_belt(task, too_fast, tol=tol, samples=samples, max_iter=max_iter, clock=clock)
    scales = _scales(task, start)
    if warm is None:        # the starting orbit only seeds the first pass and places its nodes: coarse
        orbit = steady_state(task.drive(start), tol=max(tol, COARSE_TOL))
        if orbit.status is not Status.SOLVED:
            return clock.result(orbit.status, dict(orbit.values),
                                f"no periodic motion at the starting design {start}: {orbit.message}", orbit.violated)
        y0 = np.asarray(orbit.diagnostics["initial_state"])         # the states other than phi at phi = 0
        nodes = _nodes(task, _extremes(task, tuple(stage_angles(task)), max(tol, COARSE_TOL), _vector(task, start), y0))
    else:
        nodes, start, y0 = warm[:3]
    origin = (dict(start), y0)
    # the speed extremes move with the design: make them nodes and re-solve from there (passes at a
    # coarse CVODES tolerance place them; the last pass, at `tol`, starts from the coarse optimum)
    coarse, near = warm is None and tol < COARSE_TOL, warm is not None
    passes, multipliers = [], {}
    for _ in range(MAX_PASSES):
        step_tol = COARSE_TOL if coarse else tol
        # after a coarse pass's optimum on as many nodes: IPOPT starts from its multipliers too
        refine = (bool(passes) and passes[-1]["tol"] > step_tol and passes[-1]["nodes"] == len(nodes)
                  and from_ipopt(passes[-1]["ipopt"]) is Status.SOLVED)
        lap = Clock()
        solver, blocks, (lbg, ubg), figures, _ = _nlp(task, nodes, step_tol, samples, scales, False, max_iter,
                                                      near, coarse, refine)
        clock.build_s += lap.elapsed()
        lbx, ubx = _box(task, nodes, scales, 0)
        guess = _guess(task, nodes, step_tol, samples, start, y0, scales)
        sol = solver(x0=guess, lbx=lbx, ubx=ubx, lbg=lbg, ubg=ubg, **(multipliers if refine else {}))
        multipliers = {"lam_x0": sol["lam_x"], "lam_g0": sol["lam_g"]}
        word = solver.stats()["return_status"]
        passes.append({"tol": step_tol, "nodes": len(nodes), "ipopt": word, "iterations": solver.stats()["iter_count"],
                       "warm_start": refine})
        if coarse and from_ipopt(word) is not Status.SOLVED:
            # the limits may conflict: the least violation says (phase 1); if it meets them all, its
            # design is where the fine pass starts
            phase1 = _phase1(task, nodes, tol, samples, scales, origin, max_iter)
            if from_ipopt(phase1[0]) is not Status.SOLVED or any(v > 1e-6 for v in phase1[-1].values()):
                return _not_solved(task, from_ipopt(word), word, nodes, tol, samples, scales, origin, clock,
                                   max_iter, phase1)
            start, y0 = dict(zip(task.variables, map(float, phase1[1]))), phase1[2][:len(task.state_names) - 1]
            coarse = False
            continue
        d, Y, period, rms, energy, g, omega = (np.asarray(v).ravel() for v in figures(sol["x"]))
        start, y0 = dict(zip(task.variables, map(float, d))), Y[:len(task.state_names) - 1]
        extremes = _extremes(task, nodes, step_tol, d, y0)
        (_, top), (_, bottom) = extremes
        missed = abs((top - bottom) - (omega.max() - omega.min())) / max(omega.max() - omega.min(), 1e-12)
        if from_ipopt(word) is not Status.SOLVED or (not coarse and missed < MISSED_SPREAD):
            break
        # the first pass's nodes were the starting design's extremes: dropped; later ones are kept
        nodes = _nodes(task, extremes, () if coarse and len(passes) == 1 else nodes)
        # coarse passes while their spread misses the dense one (a few at most), then the ones at `tol`
        coarse, near = coarse and missed > COARSE_MISSED and len(passes) < COARSE_PASSES, True
    status = from_ipopt(word)
    if status is not Status.SOLVED:
        return _not_solved(task, status, word, nodes, tol, samples, scales, origin, clock, max_iter)
    drive = task.drive(start)
    revolved, _ = revolution(structure(drive), tol, 60).trace(y0, dynamics_of(drive).p)
    values, diagnostics, arrays = summarise(drive, revolved,
                                            cut_angles=task.cut_window_rad())
    # the extremes are nodes, so the NLP's samples hold them: no parabola through coarse samples here
    values["speed_fluctuation"] = float((omega.max() - omega.min()) * period[0] / TWO_PI)
    values |= _sizing_values(task, start)
    if task.single_stroke_speed_drop is not None and len(stage_angles(task)) == 4:
        values["single_stroke_margin_J"] = float(single_stroke_margin_J(
            task, values["flywheel_inertia_kgm2"], Y[(len(task.state_names) - 1) * nodes.index(stage_angles(task)[1])
                                                     + task.state_names.index("omega_rad_s") - 1],
            task.single_stroke_speed_drop))
    if task.motor:
        values["motor_rms_torque_N_m"] = float(rms[0])
        values["energy_per_stroke_J"] = float(energy[0])
        values["peak_motor_shaft_torque_Nm"] = float(np.max(np.abs(arrays["motor_torque_Nm"])) / drive.gear_ratio)
    values["period_s"] = float(period[0])
    lam_g, lam_x = np.asarray(sol["lam_g"]).ravel(), np.asarray(sol["lam_x"]).ravel()
    active, said = _active(task, blocks, (lbg, ubg), g, lam_g, lam_x, scales, values)
    values |= active
    check = _verify(drive, np.r_[y0[:task.state_names.index("phi_rad")], 0.0,
                                 y0[task.state_names.index("phi_rad"):]], values, tol)
    values["verification_rel_error"] = check[0]
    diagnostics |= {"ipopt": word, "iterations": solver.stats()["iter_count"], "passes": passes,
                    "nodes_deg": np.degrees(nodes).tolist(), "node_state": y0.tolist(),
                    "verification": check[1], "active": said}
    status, message = Status.SOLVED, f"IPOPT {word} in {solver.stats()['iter_count']} iterations; " + "; ".join(said)
    if check[0] > VERIFY_REL and tol > 10 * TIGHTEST_TOL and not _is_retry(warm):
        # CVODES inside the NLP was not tight enough for this orbit (a sharp belt ripple at a speed
        # extreme): once more from here at a tenth of the tolerance
        again = _design(task, tol / 10, samples, max_iter, check_sensitivity, (nodes, start, y0, "retry"))
        return replace(again, message=f"re-solved at tol {tol / 10:g}: at tol {tol:g} the event-located check "
                                      f"missed by {check[0]:.3g}; " + again.message,
                       timing=clock.timing())
    if check[0] > VERIFY_REL:
        status = Status.INACCURATE
        message += (f"; the event-located simulation of the optimum differs by {check[0]:.3g} (relative) > "
                    f"{VERIFY_REL:g}: {check[1]}")
    else:
        message += f"; verified by the event-located simulation to {check[0]:.2g} relative"
    if check_sensitivity and status is Status.SOLVED:
        values |= _fd_check(task, values, tol, samples, max_iter, (nodes, start, y0))
    return clock.result(status, values, message, (), diagnostics, arrays)


def _is_retry(warm):
    """Whether this solve is already the one retry at a tighter tolerance."""
    return warm is not None and len(warm) > 3


def _fd_check(task, values, tol, samples, max_iter, warm):
    """The first active limit's sensitivity against the central difference of two re-solves with the
    limit 0.1 % looser and tighter: {`sensitivity_fd_rel_error`, `sensitivity_fd`}, or {} without one."""
    name = UNITS[task.objective][0]
    for block in ("speed_fluctuation", "belt_slip", "motor_breakdown"):
        knob = KNOBS[block][0]
        sens = values.get(f"d_{name}_d_{knob}")
        if sens:
            limit = getattr(task, knob)
            ends = [_design(replace(task, **{knob: limit * (1 + s)}), tol, samples, max_iter, False, warm)
                    for s in (1e-3, -1e-3)]
            # a start from the optimum's nodes may miss where the extremes move to: then from scratch
            ends = [end if end.status is Status.SOLVED else
                    _design(replace(task, **{knob: limit * (1 + s)}), tol, samples, max_iter, False, None)
                    for end, s in zip(ends, (1e-3, -1e-3))]
            if any(r.status is not Status.SOLVED for r in ends):
                return {}
            fd = (ends[0].values[name] - ends[1].values[name]) / (2e-3 * limit)
            return {"sensitivity_fd": fd, "sensitivity_fd_rel_error": abs(fd - sens) / max(abs(fd), abs(sens))}
    return {}


# --- the pieces ----------------------------------------------------------------------------------

def _scales(task, start):
    """(design variable scales, state scales, objective scale, energy scale): the NLP sees numbers near 1."""
    speed = task.nominal_speed_rad_s
    torque = max(required_mean_torque_Nm(task), 1.0)
    stiffness = start.get("belt_stiffness_Nm_rad", task.belt_stiffness_Nm_rad or 1.0)
    states = tuple(torque / stiffness if k == "twist_rad" else speed
                   for k in task.state_names if k != "phi_rad")
    gear = start.get("gear_ratio", task.gear_ratio)
    objective = {"least_flywheel_inertia": start.get("flywheel_inertia_kgm2", 1.0),
                 "least_motor_rms_torque": torque / gear, "least_energy_per_stroke": torque * TWO_PI}[task.objective]
    energy = max(required_mean_torque_Nm(task) * TWO_PI, 1.0)
    return tuple(abs(v) for v in start.values()), states, float(objective), energy


def _extremes(task, nodes, tol, d, y0):
    """[(angle, value)] of the crank speed's largest and smallest values over the revolution from y0 at
    design d: the largest of `DENSE` samples per interval, then, inside an interval (a smooth extreme),
    the angle where the crank's acceleration is 0, by secant steps on CVODES runs from the interval's
    start (`shooting.reach`); at a node (a kink, or an earlier pass's extreme) the node itself."""
    iw = task.state_names.index("omega_rad_s") - 1
    starts, speeds, y = [], [], y0
    for integ, _, u in intervals(task, nodes, tol, DENSE):
        starts.append(y)
        ys = np.asarray(integ(x0=y, p=np.r_[u, d])["xf"])
        speeds.append(ys[iw])
        y = ys[:, -1]
    phi, omega = _angles(nodes, DENSE), np.concatenate(speeds)
    go = reach(task, tol)

    def settle(k, guess):
        """(angle, speed) where the acceleration vanishes in interval k near angle `guess`, or None."""
        a, b = nodes[k], nodes[k + 1]
        u = cutting_on(task, a, b)

        def accel(span):
            end, alpha = go(starts[k], np.r_[u, d, a, span])
            return float(alpha), float(np.asarray(end).ravel()[iw])
        x0 = float(np.clip(guess - a, 1e-9, b - a))
        x1 = float(np.clip(x0 + 1e-4 * (1 if x0 < b - a - 1e-4 else -1), 0.0, b - a))
        g0, g1 = accel(x0)[0], accel(x1)[0]
        for _ in range(30):
            if g1 == g0 or abs(x1 - x0) < 1e-12:
                break
            x0, x1, g0 = x1, float(np.clip(x1 - g1 * (x1 - x0) / (g1 - g0), 0.0, b - a)), g1
            g1 = accel(x1)[0]
        return (a + x1, accel(x1)[1]) if 0.0 < x1 < b - a else None

    out = []
    spacing = max(np.diff(phi))
    for sign in (1, -1):
        # the few highest (lowest) local peaks of the samples: a belt ripple can make two nearly equal
        v = sign * omega
        peaks = [i for i in range(len(v)) if (i == 0 or v[i] >= v[i - 1]) and (i == len(v) - 1 or v[i] >= v[i + 1])]
        best = None
        for i in sorted(peaks, key=lambda i: -v[i])[:CANDIDATES]:
            here = (float(phi[i]), float(omega[i]))
            k = i // DENSE
            # inside an interval: there; at a node, the extreme may sit just either side of it
            tries = [(k, phi[i])] if i % DENSE != DENSE - 1 else [(k, phi[i] - 0.5 * spacing),
                                                                  (k + 1, phi[i] + 0.5 * spacing)]
            for j, guess in tries:
                found = settle(j, guess) if j < len(nodes) - 1 else None
                if found and abs(found[0] - phi[i]) < 2 * spacing and sign * (found[1] - here[1]) >= 0:
                    here = found
            if best is None or sign * (here[1] - best[1]) > 0:
                best = here
        out.append(best)
    return out


def _nodes(task, extremes, kept=()):
    """Stage boundaries, the angles of the crank speed's `extremes` away from them, and the `kept`
    nodes of earlier passes not within `NODE_MOVE_RAD` of these (two peaks of nearly one height take
    turns at being the largest: both stay nodes)."""
    stages = stage_angles(task)
    new = [at for at, _ in extremes if min(abs(at - s) for s in stages) > NODE_MOVE_RAD]
    old = [at for at in kept if min(abs(at - s) for s in [*stages, *new]) > NODE_MOVE_RAD]
    return tuple(sorted(set(stages) | set(new) | set(old)))


def _quadrature_scales(task, scales):
    """Scales of an interval's time [s], motor torque integral [N m s] and its square's [N2 m2 s]."""
    turn = TWO_PI / task.nominal_speed_rad_s
    torque = max(required_mean_torque_Nm(task), 1.0) / task.gear_ratio
    return np.array([turn, torque * turn, torque**2 * turn])


def _vector(task, design):
    return np.array([design[k] for k in task.variables])


def _angles(nodes, samples):
    """The angles of the NLP's samples: `samples` per interval, each interval's end included [rad]."""
    return np.concatenate([np.linspace(a, b, samples + 1)[1:] for a, b in pairwise(nodes)])


def _guess(task, nodes, tol, samples, start, y0, scales):
    """The NLP's starting point: the design `start`, and the states at the nodes from integrating
    the revolution from y0 (a periodic orbit's state at phi = 0)."""
    d = np.array([start[k] for k in task.variables])
    Y, Q, speeds, y = [], [], [], y0
    for integ, _, u in intervals(task, nodes, tol, samples):
        Y.append(y)
        run = integ(x0=y, p=np.r_[u, d])
        ys = np.asarray(run["xf"])
        Q.append(np.asarray(run["qf"])[:, -1] / _quadrature_scales(task, scales))
        speeds.append(ys[task.state_names.index("omega_rad_s") - 1])
        y = ys[:, -1]
    w = [d / np.array(scales[0])] + [y / np.array(scales[1]) for y in Y]
    if task.max_speed_fluctuation is not None:
        speeds = np.concatenate(speeds)
        w.append(np.array([speeds.max(), speeds.min()]) / task.nominal_speed_rad_s)
    return np.concatenate(w + Q)


def _box(task, nodes, scales, slacks):
    """Bounds of the NLP's variables: the design's box; the node states kept where the model holds
    (the crank and pulley turning forward, below four times the top speed; the belt twisted by less
    than ten times what the breakdown torque would twist it), so IPOPT never asks CVODES for a crank
    turning back; time forward; free torque integrals and speed bounds; nonnegative slacks."""
    low = [task.bounds(k)[0] / s for k, s in zip(task.variables, scales[0])]
    high = [task.bounds(k)[1] / s for k, s in zip(task.variables, scales[0])]
    most = {k: task.bounds(k)[1] for k in ("gear_ratio", "motor_scale") if k in task.variables}
    torque = 10 * max(breakdown_torque_at_crank_Nm(task.drive(most)) if task.motor else 0.0,
                      required_mean_torque_Nm(task), 1.0)
    stiffness = task.bounds("belt_stiffness_Nm_rad")[0] if "belt_stiffness_Nm_rad" in task.variables \
        else task.belt_stiffness_Nm_rad
    top = 4 * top_speed_rad_s(task.drive(most))
    state_low, state_high = [], []
    for k, sc in zip((k for k in task.state_names if k != "phi_rad"), scales[1]):
        span = (-torque / stiffness, torque / stiffness) if k == "twist_rad" else \
            (MIN_SPEED_SHARE * task.nominal_speed_rad_s, top)
        state_low.append(span[0] / sc)
        state_high.append(span[1] / sc)
    K = len(nodes) - 1
    fluct = 2 * (task.max_speed_fluctuation is not None)
    quad_low = np.tile([0.0, -np.inf, 0.0], K)
    return (np.r_[low, np.tile(state_low, K), np.full(fluct, -np.inf), quad_low, np.zeros(slacks)],
            np.r_[high, np.tile(state_high, K), np.full(fluct, np.inf), np.full(len(quad_low), np.inf),
                  np.full(slacks, np.inf)])


def _stall(task):
    """`models.press_energy.stall_check` at the biggest motor the bounds allow, with the least motor that could."""
    most = {k: task.bounds(k)[1] for k in ("gear_ratio", "motor_scale") if k in task.variables}
    drive = task.drive(most)
    stalled = stall_check(drive)
    if stalled is None:
        return None
    values, message = stalled
    least = values["required_mean_torque_Nm"] / drive.gear_ratio
    values |= {"min_motor_breakdown_torque_Nm": least, "min_motor_scale": least / task.motor_breakdown_torque_Nm}
    return values, (f"stall at every design within the bounds: {message}; the least motor that could has breakdown "
                    f"torque above {least:.4g} N m at its shaft (motor_scale > {values['min_motor_scale']:.4g}), "
                    f"necessary and approached as the flywheel grows (at exactly that the motor would sit at its "
                    f"breakdown slip)")


def _on_rigid_belt(task, why, *, tol, samples, max_iter, clock):
    """The design on the rigid-belt model, the stiff belt's limit, said so (no minutes of CVODES)."""
    if "belt_stiffness_Nm_rad" in task.variables:
        return clock.result(Status.LIMIT, {}, why + "; the belt stiffness cannot be a design variable there: bound it "
                            "below belt_stiffness_max_Nm_rad", ("belt_mode",))
    belt = ("belt_stiffness_Nm_rad", "belt_damping_Nms_rad", "belt_slip_torque_Nm")
    rigid = replace(task, effects=tuple(e for e in task.effects if e != "belt_elasticity"), **dict.fromkeys(belt))
    result = _design(rigid, tol, samples, max_iter, False, None)
    dropped = " (the belt slip limit is not checked: the rigid model has no belt)" if task.belt_slip_torque_Nm else ""
    hz, _ = belt_mode(task.drive(task.start()))
    ratio = hz / (task.nominal_speed_rad_s / TWO_PI)
    status, close = result.status, f"the belt mode is {ratio:.3g} times the revolution frequency"
    if ratio < RIGID_RATIO and status is Status.SOLVED:     # stiff, but not so stiff that the limit is exact
        status, close = Status.INACCURATE, close + f", less than {RIGID_RATIO}: the rigid belt only approximates it"
    return clock.result(status, result.values | {"belt_mode_Hz": hz},
                        f"rigid-belt limit: {why}; {close}; designed on that model{dropped}: {result.message}",
                        result.violated, result.diagnostics | {"model": "rigid belt (the stiff belt's limit)"},
                        result.arrays)


def _active(task, blocks, bounds, g, lam_g, lam_x, scales, values):
    """Sensitivities d objective / d limit of the active limits and bounds (values), and sentences in
    the user's terms."""
    name, unit, label = UNITS[task.objective]
    fsc = scales[2]
    out, said = {}, []
    for b in blocks:
        if b.name not in KNOBS:
            continue
        knob, knob_unit, limits = KNOBS[b.name]
        lam, gg = lam_g[b.start:b.stop], g[b.start:b.stop]
        at_bound = np.minimum(np.abs(gg - bounds[0][b.start:b.stop]), np.abs(gg - bounds[1][b.start:b.stop])) < 1e-6
        if not np.any(at_bound & (np.abs(lam) > 1e-8)):      # a limit with room left, or a degenerate zero multiplier
            continue
        setting = getattr(task, knob, None)
        if b.name == "single_stroke":       # d g / d (the knob) of each row: g = margin - extra energy, scaled
            dg = np.full(len(gg), -1 / scales[3])
        elif b.name == "mean_speed":        # g = (2 pi / T - omega) / omega
            dg = -(gg + 1) / setting
        else:                               # g = quantity / limit, or x safety factor for the motor
            dg = (gg if b.name == "motor_breakdown" else -gg) / setting
        sens = float(fsc * lam @ dg)
        out[f"d_{name}_d_{knob}"] = sens
        per = f" per {knob_unit}" if knob_unit else ""
        trade = ""
        if sens and b.name != "mean_speed":     # along the active limit: what one unit of the objective buys
            way = "lowers" if (sens < 0) == (b.name != "motor_breakdown") else "raises"
            trade = f": 1 {unit} more {label} {way} the {limits} by {abs(1 / sens):.4g} {knob_unit}".rstrip()
        said.append(f"{b.name} active (d {name} / d {knob} = {sens:.4g} {unit}{per}){trade}")
    for i, key in enumerate(task.variables):
        low, high = task.bounds(key)
        v = values[key]
        side = "lower" if abs(v - low) <= 1e-7 * max(abs(low), 1) else "upper" if abs(v - high) <= 1e-7 * abs(high) else None
        if side:
            bound = BOUNDS[key][0 if side == "lower" else 1]
            sens = float(-lam_x[i] * fsc / scales[0][i])
            out[f"d_{name}_d_{bound}"] = sens
            said.append(f"{key} is at its {side} bound {bound} = {v:.6g} (the bound is active: d {name} / d {bound} "
                        f"= {sens:.4g}): the optimum is the bound's")
    return out, said


def _sizing_values(task, design):
    """The drive's sizing at a design, every one of them (free or not), named with units."""
    drive = task.drive(design)
    out = {"flywheel_inertia_kgm2": drive.flywheel_inertia_kgm2, "gear_ratio": drive.gear_ratio}
    if task.belt:
        out["belt_stiffness_Nm_rad"] = drive.belt_stiffness_Nm_rad
    if task.motor:
        out |= {"motor_scale": design.get("motor_scale", 1.0), "motor_breakdown_torque_Nm": drive.motor_breakdown_torque_Nm,
                "motor_inertia_kgm2": drive.motor_inertia_kgm2}
    return {k: float(v) for k, v in out.items()}


def _located_extreme(drive, piece, trace, sign):
    """The largest (sign 1) or smallest (-1) crank speed of an event-located run: at the extreme sample,
    located where the acceleration changes sign between its neighbours (`event_driven.locate` on the
    piece's duration); the sample itself at a piece's end (a kink at an event)."""
    dyn = dynamics_of(drive)
    iw, alpha = drive.state_names.index("omega_rad_s"), Dynamics.OUTPUT_NAMES.index("alpha_rad_s2")
    c, j = max(((c, j) for c in range(len(trace.x)) for j in range(len(trace.x[c]))),
               key=lambda cj: sign * trace.x[cj[0]][cj[1], iw])
    value = float(trace.x[c][j, iw])
    if c == 0 or not 0 < j < len(trace.t[c]) - 1:
        return value
    start, mode = trace.t[c - 1][-1], trace.mode[c][0]

    def g(state):
        return float(dyn.outputs(state, mode)[alpha])
    lo, hi = trace.t[c][j - 1] - start, trace.t[c][j + 1] - start
    if g(trace.x[c][j - 1]) * g(trace.x[c][j + 1]) >= 0:
        return value
    _, state = locate(piece, trace.x[c - 1][-1], mode, lo, hi, g)
    return float(state[iw])


def _verify(drive, x0, values, tol):
    """(largest relative difference, per figure) between the NLP's figures and the event-located
    simulation of one period from the optimum's state at phi = 0."""
    period = values["period_s"]
    trace = Trace()
    piece = piece_by_time(drive, max(tol * 1e-2, 1e-13), 200)
    try:
        march(drive, piece, trace, np.r_[x0, np.zeros(4)], period * (1 + 1e-6), period / 32, 1000)
        got, _, arrays = summarise(drive, trace)
        top, bottom = (_located_extreme(drive, piece, trace, sign) for sign in (1, -1))
    except (RuntimeError, ArithmeticError) as exc:      # a failed check is a finding, reported, not a crash
        return float("inf"), {"error": str(exc)[:200]}
    if "omega_mean_rad_s" in got:
        got["speed_fluctuation"] = (top - bottom) / got["omega_mean_rad_s"]
    if drive.motor:
        t_rev = next((t for kind, t, _ in trace.events if kind == "revolution"), None)
        if t_rev is None:
            return float("inf"), {"error": f"the simulation did not complete the revolution in 1.000001 x {period:.9g} s"}
        shaft = arrays["motor_torque_Nm"] / drive.gear_ratio
        integrals = np.zeros(2)
        at = 0
        for k, chunk in enumerate(trace.t):
            if k and chunk[-1] <= t_rev * (1 + 1e-12):
                span = slice(at - 1, at + len(chunk))
                integrals += [simpson(shaft[span], x=arrays["t_s"][span]),
                              simpson(shaft[span] ** 2, x=arrays["t_s"][span])]
            at += len(chunk)
        got["motor_rms_torque_N_m"] = float(np.sqrt(integrals[1] / got["period_s"]))
        got["energy_per_stroke_J"] = float(drive.motor_sync_speed_rad_s * integrals[0])
    diffs = {k: abs(values[k] - got[k]) / max(abs(got[k]), 1e-12) for k in
             ("period_s", "omega_mean_rad_s", "speed_fluctuation", "motor_rms_torque_N_m", "energy_per_stroke_J")
             if k in values and k in got}
    return max(diffs.values()), diffs


def _phase1(task, nodes, tol, samples, scales, origin, max_iter):
    """The least violation of the limits (the elastic NLP) from the starting design's own orbit (a failed
    solve's last iterate can sit anywhere): (IPOPT's word, design, node states, period, RMS torque,
    energy, {limit: its least relative violation})."""
    solver, blocks, (lbg, ubg), figures, slacks = _nlp(task, nodes, tol, samples, scales, True, max_iter)
    lbx, ubx = _box(task, nodes, scales, slacks)
    guess = np.r_[_guess(task, nodes, tol, samples, *origin, scales), np.ones(slacks)]
    x = np.asarray(solver(x0=guess, lbx=lbx, ubx=ubx, lbg=lbg, ubg=ubg)["x"]).ravel()
    d, Y, period, rms, energy, _, _ = (np.asarray(v).ravel() for v in figures(x))
    slack = dict(zip(dict.fromkeys(b.name for b in blocks if b.name in KNOBS), x[len(x) - slacks:]))
    return solver.stats()["return_status"], d, Y, period, rms, energy, slack


def _not_solved(task, status, word, nodes, tol, samples, scales, origin, clock, max_iter, phase1=None):
    """IPOPT did not succeed: find the least violation of the limits (`_phase1`, unless given). Violated
    limits there conflict with each other, the motion and the bounds: INFEASIBLE with the best
    achievable. When none is violated, a feasible design exists and IPOPT's status stands."""
    phase1_word, d, _, period, rms, energy, slack = phase1 or _phase1(task, nodes, tol, samples, scales, origin,
                                                                       max_iter)
    values = _sizing_values(task, dict(zip(task.variables, map(float, d)))) | {"period_s": float(period[0])}
    if task.motor:
        values |= {"motor_rms_torque_N_m": float(rms[0]), "energy_per_stroke_J": float(energy[0])}
    broken = {k: v for k, v in slack.items() if v > 1e-6}
    if from_ipopt(phase1_word) is not Status.SOLVED or not broken:
        why = ("phase 1 (least violation) finds every limit can be met, so the design problem is feasible"
               if not broken else f"phase 1 (least violation) did not converge either ({phase1_word})")
        return clock.result(status if status is not Status.SOLVED else Status.FAILED, values,
                            f"IPOPT stopped with {word}: no optimum to trust; {why}", tuple(broken), {"ipopt": word})
    # the best achievable as the periodic motion of the least-violation design gives it (dense samples:
    # the NLP's samples were placed for another design's speed extremes)
    orbit = steady_state(task.drive(dict(zip(task.variables, map(float, d)))), tol=tol, samples=1000)
    limits = {"speed_fluctuation": ("max_speed_fluctuation", "speed_fluctuation"),
              "belt_slip": ("belt_slip_torque_Nm", "peak belt torque"),
              "motor_breakdown": ("motor_safety_factor", "motor torque / allowed"),
              "single_stroke": ("single_stroke_speed_drop", "single-stroke energy margin")}
    parts = []
    for name, over in broken.items():
        knob, what = limits[name]
        values[f"least_{name}_violation"] = float(over)
        if name == "speed_fluctuation":
            values["speed_fluctuation"] = orbit.values.get("speed_fluctuation", (1 + over) * task.max_speed_fluctuation)
            parts.append(f"speed_fluctuation >= {values['speed_fluctuation']:.4g} at best against the limit "
                         f"max_speed_fluctuation = {task.max_speed_fluctuation:g}")
        else:
            parts.append(f"{name} missed by {over:.3g} of its limit ({what}; {knob} = {getattr(task, knob):g})")
    bounds = []
    for key in task.variables:
        low, high = task.bounds(key)
        v = values[key]
        if abs(v - low) <= 1e-6 * max(abs(low), 1):
            bounds.append(f"{key} at its lower bound {BOUNDS[key][0]} = {low:g}")
        elif abs(v - high) <= 1e-6 * abs(high):
            bounds.append(f"{key} at its upper bound {BOUNDS[key][1]} = {high:g}")
    conflict = list(broken) + [b.split(" ")[0] for b in bounds]
    message = (f"INFEASIBLE: the limits conflict ({', '.join(conflict)}; IPOPT: {word}); the least violation: "
               + "; ".join(parts) + (" with " + ", ".join(bounds) if bounds else " (no bound active: the motion "
                                     "itself conflicts with them)"))
    return clock.result(Status.INFEASIBLE, values, message, tuple(conflict),
                        {"ipopt": word, "phase1": phase1_word, "least_violation": slack})
