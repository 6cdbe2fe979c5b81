"""The least flywheel for a speed-fluctuation limit, one variable: a safeguarded secant iteration on
the periodic solution, not an NLP.

The speed fluctuation C(J) = (omega_max - omega_min) / omega_mean of the periodic motion falls as the
flywheel J grows, nearly as 1 / J_total (the swing's energy is set by the load: Delta E = C J_total
omega^2, J_total everything turning with the crank, `models.press.inertia_at_crank_kgm2`). The least J
with C(J) <= C_max is the root of g(u) = log C(e^u) - log C_max, u = log J, nearly linear in u. The
first step's slope is that law's, dg/du = -J / J_total; each later one the secant through the last two
periodic solutions (the sensitivity dC/dJ by difference of orbits); a step that leaves the bracket
known so far is replaced by the bisection of the bracket in u (the safeguard). Each C(J) is one
periodic solve (`steady_state`: Newton shooting, warm from the last orbit), its extremes refined
between samples. At the lower bound C(J_min) <= C_max makes J_min the answer; C(J_max) > C_max is
INFEASIBLE. The single-stroke limit (`models.press_design.single_stroke_margin_J`, linear in J at a given
entry speed into the cut) then raises J when it needs more, by a fixed point on the entry speed.

Counted and reported: the periodic solves. press/flywheel-design's NLP (`design`) answers the same
question with every limit; this is its one-variable shortcut (`mechopt bench press` times both and
Nelder-Mead).
"""
import numpy as np

from mechopt.kit.errors import ModelError
from mechopt.kit.result import Clock, Result, Status
from mechopt.kit.settings import Annotated, Interval, Tolerance, check_settings
from mechopt.models.press_design import PressDesign, single_stroke_margin_J
from mechopt.models.press_energy import energy_swing_J, inertia_at_crank_kgm2, rule_of_thumb_flywheel_kgm2
from mechopt.solvers.press.periodic import steady_state
from mechopt.solvers.press.problem import refuse_neutral_speed

ROOT_REL = 1e-9          # |C / C_max - 1| at which the root is taken (the sampled extremes hold ~1e-7)
STEP_REL = 1e-10         # or a step in log J this small
SAMPLES = 200            # steady_state's samples per piece (the extremes by parabola between them)
NAMES = ("flywheel_inertia_kgm2",)
UNSUPPORTED = ("belt_slip_torque_Nm", "motor_safety_factor")


def _check(task):
    if not isinstance(task, PressDesign):
        raise ModelError(f"task={type(task).__name__}: expected a PressDesign", key="task")
    if task.objective != "least_flywheel_inertia" or task.variables != NAMES:
        raise ModelError(f"objective={task.objective!r}, variables={list(task.variables)}: press.flywheel designs "
                         "the least flywheel alone (objective 'least_flywheel_inertia', variables "
                         "['flywheel_inertia_kgm2']); press.design takes the others", key="variables")
    if task.max_speed_fluctuation is None:
        raise ModelError("max_speed_fluctuation missing: press.flywheel finds the least flywheel that keeps it",
                         key="max_speed_fluctuation")
    other = [k for k in UNSUPPORTED if getattr(task, k) is not None]
    if other:
        raise ModelError(f"{other[0]}={getattr(task, other[0])}: press.flywheel keeps the speed fluctuation and the "
                         "single stroke only; press.design takes this limit", key=other[0])
    task.require_drive("a flywheel design")
    refuse_neutral_speed(task, "press.flywheel")


def flywheel(task: PressDesign, *, tol: Tolerance = 1e-10,
             max_solves: Annotated[int, Interval(ge=3, le=100)] = 30) -> Result:
    """The least flywheel J within its bounds that keeps `max_speed_fluctuation` (and, when given,
    `single_stroke_speed_drop`) on the periodic steady motion (see the module doc).

    Parameters
    ----------
    tol : CVODES tolerance of each periodic solve.
    max_solves : periodic solves allowed in all (LIMIT when reached, with the bracket).

    Returns a Result: SOLVED (the root to `ROOT_REL`, or a bound); values `flywheel_inertia_kgm2`,
    `speed_fluctuation`, `periodic_solves`, `secant_steps`, `single_stroke_margin_J`, the textbook's
    `flywheel_rule_of_thumb_kgm2` for the same limit (with the load diagram's `energy_swing_J`), the
    answer's `omega_mean_rad_s` and `energy_residual`, and its revolution's `arrays` (steady_state's);
    INFEASIBLE when the largest flywheel allowed cannot keep the limit; LIMIT after `max_solves`.
    """
    _check(task)
    check_settings(flywheel, tol=tol, max_solves=max_solves)
    clock = Clock()
    low_bound, high_bound = (np.log(b) for b in task.bounds("flywheel_inertia_kgm2"))
    limit = task.max_speed_fluctuation
    solves, steps, seen = 0, 0, []          # seen: (u, g, run) of each periodic solve
    lo = hi = None                          # u with g > 0 (too little flywheel), g <= 0 (enough)

    def evaluate(u):
        nonlocal solves
        run = steady_state(task.drive({"flywheel_inertia_kgm2": float(np.exp(u))}), tol=tol, samples=SAMPLES)
        solves += 1
        if run.status is not Status.SOLVED:
            raise _Stop(run)
        return np.log(run.values["speed_fluctuation"] / limit), run

    u = float(np.clip(np.log(task.start()["flywheel_inertia_kgm2"]), low_bound, high_bound))
    try:
        while True:
            if solves >= max_solves:
                return clock.result(Status.LIMIT, {"flywheel_inertia_kgm2": float(np.exp(u)), "periodic_solves": solves},
                                    f"max_solves={max_solves} periodic solves reached before the root (bracket "
                                    f"{np.exp(lo) if lo is not None else '-'} .. {np.exp(hi) if hi is not None else '-'}"
                                    " kg m2)")
            g, run = evaluate(u)
            seen.append((u, g, run))
            if g > 0:
                lo = u if lo is None else max(lo, u)
            else:
                hi = u if hi is None else min(hi, u)
            if abs(np.expm1(g)) <= ROOT_REL or (g <= 0 and u <= low_bound):
                break
            if g > 0 and u >= high_bound:
                return clock.result(Status.INFEASIBLE, {"flywheel_inertia_kgm2": float(np.exp(u)),
                                                        "speed_fluctuation": run.values["speed_fluctuation"],
                                                        "periodic_solves": solves},
                                    f"the largest flywheel allowed ({np.exp(high_bound):g} kg m2) keeps the speed "
                                    f"fluctuation at {run.values['speed_fluctuation']:.6g}, above "
                                    f"max_speed_fluctuation={limit:g}", ("speed_fluctuation",))
            if len(seen) == 1:          # C ~ 1 / J_total: d log C / d log J = -J / J_total
                drive = task.drive({"flywheel_inertia_kgm2": float(np.exp(u))})
                slope = -float(np.exp(u)) / inertia_at_crank_kgm2(drive)
            else:
                (u0, g0, _), (u1, g1, _) = seen[-2], seen[-1]
                slope = (g1 - g0) / (u1 - u0) if u1 != u0 else np.nan
            step = -g / slope if slope < 0 else np.nan
            left = lo if lo is not None else low_bound
            right = hi if hi is not None else high_bound
            new = u + step
            if not (np.isfinite(new) and left <= new <= right):      # the safeguard
                new = 0.5 * (left + right) if lo is not None and hi is not None else \
                    float(np.clip(new, left, right)) if np.isfinite(new) else (right if g > 0 else left)
            steps += 1
            if abs(new - u) <= STEP_REL:
                break
            u = new
        active = "flywheel_inertia_min_kgm2" if u <= low_bound and g < 0 else "speed_fluctuation"
        margin = None
        if task.single_stroke_speed_drop is not None and task.cutting:
            while solves < max_solves:          # a fixed point on the entry speed into the cut
                entry = float(np.interp(task.cut_window_rad()[0], run.arrays["phi_rad"], run.arrays["omega_rad_s"]))
                J = float(np.exp(u))
                margin = float(single_stroke_margin_J(task, J, entry, task.single_stroke_speed_drop))
                if margin >= -1e-9 * J:
                    break
                per_J = float(single_stroke_margin_J(task, J + 1.0, entry, task.single_stroke_speed_drop)) - margin
                u = float(min(np.log(J - margin / per_J), high_bound))
                active = "single_stroke"
                _, run = evaluate(u)
    except _Stop as stop:
        return clock.result(stop.run.status, {"periodic_solves": solves},
                            f"no periodic orbit at J = {np.exp(u):.6g} kg m2: {stop.run.message}")
    J = float(np.exp(u))
    values = {"flywheel_inertia_kgm2": J, "speed_fluctuation": run.values["speed_fluctuation"],
              "periodic_solves": solves, "secant_steps": steps, "omega_mean_rad_s": run.values["omega_mean_rad_s"],
              "energy_residual": run.values["energy_residual"]}
    if margin is not None:
        values["single_stroke_margin_J"] = margin
    # the textbook's flywheel for the same limit beside the designed one (the load diagram's Delta E)
    values |= {"energy_swing_J": energy_swing_J(task), "flywheel_rule_of_thumb_kgm2":
               rule_of_thumb_flywheel_kgm2(task, limit)}
    return clock.result(Status.SOLVED, values,
                        f"least flywheel {J:.8g} kg m2 ({active} active) by {steps} safeguarded secant steps, "
                        f"{solves} periodic solves (steady_state) in all", diagnostics={"active": active},
                        arrays=run.arrays)


class _Stop(Exception):
    def __init__(self, run):
        super().__init__(run.message)
        self.run = run
