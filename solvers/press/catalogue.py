"""A motor and a belt ratio from a catalogue: enumeration over the rows, ratios
tried in each, with the continuous design NLP (`design`) inside; the cheapest feasible row wins.

Rows go cheapest first (least rated power, then least breakdown torque), so the search stops at the
first row with a feasible ratio: the rows before it are each shown infeasible, with the reason. A
ratio is screened before any NLP when the motor's idle speed reduced by it (the fastest the crank
can turn) is already below the speed band, when the motor cannot carry the cycle's mean load
(`models.press_energy.stall_check`), or when the steady motion at the starting flywheel turns the crank clearly
off the band (one warm-started `steady_state`)."""

import numpy as np

from mechopt.kit.errors import ModelError
from mechopt.kit.result import Clock, Result, Status
from mechopt.kit.settings import Annotated, Interval, Tolerance
from mechopt.models.press_design import PressCatalogue
from mechopt.models.press_energy import stall_check
from mechopt.solvers.press.design import design
from mechopt.solvers.press.periodic import steady_state
from mechopt.solvers.press.problem import Samples

BAND_SLACK = 0.01       # a ratio whose steady speed misses the band by more is not designed


def catalogue(task: PressCatalogue, *, tol: Tolerance = 1e-10, samples: Samples = 16,
              max_iter: Annotated[int, Interval(ge=1, le=3000)] = 200) -> Result:
    """The cheapest catalogue row (`task.motors`) with a ratio (`task.ratios`) whose designed drive
    keeps every limit and the mean crank speed within `max_speed_deviation` of the nominal one.

    Returns a Result: SOLVED with the row (`motor_row`, its index; `rated_power_kW`,
    `motor_breakdown_torque_Nm`, `motor_inertia_kgm2`), the ratio, the designed variables, and the
    motor's torque margin (`motor_torque_margin`: M_k over the peak motor shaft torque of the steady
    revolution); `arrays` hold every (row, ratio) tried: row, ratio, a status code (0 feasible,
    1 screened out, 2 design not SOLVED, 3 off the speed band) and the designed flywheel (NaN when
    none); INFEASIBLE when no row has a feasible ratio, with each row's reason in the message.
    """
    if not isinstance(task, PressCatalogue):
        raise ModelError(f"task={type(task).__name__}: expected a PressCatalogue", key="task")
    clock = Clock()
    low, high = (task.nominal_speed_rad_s * (1 + s * task.max_speed_deviation) for s in (-1, 1))
    order = sorted(range(len(task.motors)), key=lambda k: (task.motors[k][1], task.motors[k][2]))
    tried, reasons = [], []
    for k in order:
        row = task.motors[k]
        found = []
        for ratio in task.ratios:
            drive = task.candidate(row, ratio)
            if task.motor_sync_speed_rad_s / ratio < low:
                tried.append((k, ratio, 1, np.nan))
                continue
            if stall_check(drive) is not None:
                tried.append((k, ratio, 1, np.nan))
                continue
            if _off_the_band(drive, low, high):
                tried.append((k, ratio, 1, np.nan))
                continue
            result = design(drive, tol=tol, samples=samples, max_iter=max_iter)
            if result.status is not Status.SOLVED:
                tried.append((k, ratio, 2, np.nan))
                continue
            speed = result.values["omega_mean_rad_s"]
            ok = low <= speed <= high
            tried.append((k, ratio, 0 if ok else 3, result.values["flywheel_inertia_kgm2"]))
            if ok:
                found.append((result.values[_objective_key(task)], ratio, result, drive))
        if found:
            _, ratio, result, drive = min(found, key=lambda f: f[0])
            return _chosen(task, k, ratio, result, drive, tried, reasons, clock)
        reasons.append(f"{row[0]}: " + _why_not(task, k, tried, low, high))
    return clock.result(Status.INFEASIBLE, {}, "no catalogue row has a feasible ratio: " + "; ".join(reasons),
                        ("catalogue",), {}, _table(tried))


def _off_the_band(drive, low, high):
    """True when the steady motion at the starting design (a warm-started `steady_state`, ~10 ms)
    turns the crank off the speed band by more than `BAND_SLACK` of it: the mean speed hardly
    depends on the flywheel the NLP then chooses (the NLP's own check decides the rest)."""
    run = steady_state(drive.drive(drive.start()))
    speed = run.values.get("omega_mean_rad_s")
    return run.status is Status.SOLVED and not low * (1 - BAND_SLACK) <= speed <= high * (1 + BAND_SLACK)


def _objective_key(task):
    return {"least_flywheel_inertia": "flywheel_inertia_kgm2", "least_motor_rms_torque": "motor_rms_torque_N_m",
            "least_energy_per_stroke": "energy_per_stroke_J"}[task.objective]


def _why_not(task, k, tried, low, high):
    codes = {r[1]: r[2] for r in tried if r[0] == k}
    words = {1: "screened out (speed off the band at the starting flywheel, or the motor cannot carry the mean "
                "load)",
             2: "the design is not SOLVED (a limit cannot be kept)", 3: f"mean speed off [{low:.4g}, {high:.4g}] rad/s"}
    return ", ".join(f"i = {ratio:g} {words[code]}" for ratio, code in codes.items())


def _table(tried):
    rows = np.array([(k, ratio, code, J) for k, ratio, code, J in tried], dtype=float).reshape(-1, 4)
    return {"row": rows[:, 0], "ratio": rows[:, 1], "code": rows[:, 2], "flywheel_inertia_kgm2": rows[:, 3]}


def _chosen(task, k, ratio, result, drive, tried, reasons, clock):
    row = task.motors[k]
    steady = steady_state(drive.drive({v: result.values[v] for v in task.variables}))
    peak = float(np.max(np.abs(steady.arrays["motor_torque_Nm"]))) / ratio
    values = dict(result.values) | {"motor_row": float(k), "rated_power_kW": float(row[1]),
                                    "motor_breakdown_torque_Nm": float(row[2]), "motor_inertia_kgm2": float(row[3]),
                                    "gear_ratio": float(ratio), "peak_motor_shaft_torque_Nm": peak,
                                    "motor_torque_margin": float(row[2]) / peak,
                                    "designs_solved": float(sum(1 for r in tried if r[2] in (0, 3)))}
    cheaper = ("; cheaper rows: " + "; ".join(reasons)) if reasons else "; it is the cheapest row"
    key = _objective_key(task)
    message = (f"{row[0]} ({row[1]:g} kW) with i = {ratio:g}: {key} {values[key]:.5g}, "
               f"mean speed {values['omega_mean_rad_s']:.4g} rad/s, torque margin {values['motor_torque_margin']:.3g} "
               f"(M_k / peak shaft torque){cheaper}")
    return clock.result(Status.SOLVED, values, message, (), result.diagnostics | {"tried": len(tried)},
                        result.arrays | _table(tried))
