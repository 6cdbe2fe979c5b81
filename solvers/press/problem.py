"""The press problem, public to every press method: fixed_step, event_driven, periodic and scipy_peer
are siblings over it (as scipy's rk, radau and bdf over its base); design, loads and sensitivity
stand above. Here: the assembled equations per task, the initial state, the trace of a run and its
summary, the switching logic (U, the next angle event, the mode), and the pieces every method
integrates (CVODES by time between located events, by crank angle over a revolution)."""
import re
from dataclasses import dataclass, field
from typing import Annotated, Literal

import casadi as ca
import numpy as np
from annotated_types import Interval

from mechopt.kit.cache import memoised
from mechopt.kit.errors import MechoptError, ModelError, SettingError
from mechopt.kit.result import Status, from_casadi_integrator
from mechopt.kit.settings import check_settings
from mechopt.models.press import PressDrive
from mechopt.models.press_energy import (
    belt_mode_rad_s,
    cut_work_J,
    energy_swing_J,
    inertia_at_crank_kgm2,
    rule_of_thumb_flywheel_kgm2,
)
from mechopt.models.press_equations import PARAMETERS, WORK_NAMES, Dynamics, dynamics, equations, structure
from mechopt.models.press_loads import Load

TWO_PI = 2 * np.pi
ANGLE_TOL_RAD = 1e-12          # events are located to this in crank angle (omega ~ 25: 4e-14 s) near phi = 0
ANGLE_ULPS = 64                # and to this many units in the last place of the angle far from it


def angle_tol(phi) -> float:
    """How close an event is located to the angle phi [rad]: `ANGLE_TOL_RAD`, or relative to phi once
    a double's spacing there makes that absolute figure unreachable (1445 rad after a minute: 2.3e-13)."""
    return max(ANGLE_TOL_RAD, ANGLE_ULPS * float(np.spacing(abs(phi))))
Start = Literal["nominal", "rest"]
Duration = Annotated[float, Interval(gt=0, le=3600)]          # simulated time [s]
Samples = Annotated[int, Interval(ge=1, le=10_000)]           # outputs per integrated piece


@memoised(maxsize=32)
def dynamics_of(task: PressDrive) -> Dynamics:
    """The task's equations (its structure's, built once) with its numbers bound; refused for a press
    without a drive (`PressDrive.require_drive`)."""
    task.require_drive()
    return dynamics(task)


def initial_state(task: PressDrive, start: str) -> np.ndarray:
    """Physical states plus zero work integrals: at rest, or turning at the nominal speed with
    the pulley at the speed that feeds it (omega i = motor speed) and the belt untwisted."""
    w = 0.0 if start == "rest" else task.nominal_speed_rad_s
    values = {"twist_rad": 0.0, "omega_p_rad_s": w, "phi_rad": 0.0, "omega_rad_s": w}
    return np.r_[[values[k] for k in task.state_names], np.zeros(len(WORK_NAMES))]


@dataclass
class Trace:
    """What a run produced: samples (time, states, mode) and the events located."""
    t: list = field(default_factory=list)
    x: list = field(default_factory=list)
    mode: list = field(default_factory=list)
    events: list = field(default_factory=list)       # (kind, t_s, phi_rad)

    def add(self, t, x, mode):
        self.t.append(np.atleast_1d(t))
        self.x.append(np.atleast_2d(x).reshape(len(np.atleast_1d(t)), -1))
        self.mode.append(np.tile(mode, (len(np.atleast_1d(t)), 1)))

    def arrays(self):
        return np.concatenate(self.t), np.concatenate(self.x), np.concatenate(self.mode)


def casadi_failure(exc: BaseException, doing: str) -> tuple[Status, str, dict]:
    """A CasADi integrator's exception as (status, one-line message in the user's terms, diagnostics
    keeping the raw text): the call stack CasADi puts in its message never reaches `message`."""
    raw = str(exc)
    flags = re.findall(r"CV_[A-Z_]+", raw)
    what = flags[-1] if flags else "an integrator error"
    hint = {"CV_TOO_MUCH_WORK": "more steps than allowed: the crank nearly stops (omega -> 0) or a mode is "
                                "too fast for the step",
            "CV_CONV_FAILURE": "the corrector did not converge", "CV_ERR_FAILURE": "the error test kept failing"}
    return (from_casadi_integrator(raw), f"CVODES gave up ({what}: {hint.get(what, 'see diagnostics')}) {doing}",
            {"casadi_error": raw})


# --- the belt mode against what a method can afford ------------------------------------------

RIGID_LIMIT = "the rigid-belt model (drop effect `belt_elasticity`) is its limit"
_RK4_TABLEAU = (np.array([[0, 0, 0, 0], [0.5, 0, 0, 0], [0, 0.5, 0, 0], [0, 0, 1, 0]]), np.array([1, 2, 2, 1]) / 6)


def belt_mode(task: PressDrive) -> tuple[float, complex]:
    """(frequency [Hz], fastest eigenvalue [1/s]) of the linearised belt mode: the twist between
    the two inertias, J_eff s^2 + h_p s + C_p = 0 with 1/J_eff = 1/J_p + 1/J_k (see `belt_mode_rad_s`)."""
    omega = belt_mode_rad_s(task)
    if omega == 0:
        return 0.0, 0j
    j_eff = task.belt_stiffness_Nm_rad / omega**2
    roots = np.roots([j_eff, task.belt_damping_Nms_rad, task.belt_stiffness_Nm_rad])
    return omega / TWO_PI, complex(roots[np.argmax(np.abs(roots))])


def stable_step_s(eigenvalue: complex, tableau=_RK4_TABLEAU) -> float:
    """The largest step h of an explicit Runge-Kutta method (Butcher A, b) with |R(h lambda)| <= 1
    for this eigenvalue: R(z) = 1 + z b (I - z A)^-1 1, bisected along the eigenvalue's ray."""
    A, b = (np.asarray(a, dtype=float) for a in tableau)
    A = np.pad(A[:len(b), :len(b)], ((0, 0), (0, len(b) - min(A.shape[1], len(b)))))   # scipy stores A narrower
    if eigenvalue == 0:
        return float("inf")

    def stable(h):
        z = h * eigenvalue
        return abs(1 + z * b @ np.linalg.solve(np.eye(len(b)) - z * A, np.ones(len(b)))) <= 1 + 1e-12

    lo, hi = 0.0, 10.0 / abs(eigenvalue)
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if stable(mid) else (lo, mid)
    return lo


def belt_too_fast(task: PressDrive, step_s: float, steps: float, most: float, method: str, *,
                  why: str = "", over: str = "") -> str | None:
    """The message when `method` needs `steps` steps below `step_s` each (`over` a span) and can
    afford `most`, or its step is above the limit (steps = inf); None when it can."""
    if steps <= most:
        return None
    hz, _ = belt_mode(task)
    return (f"the belt mode at {hz:.4g} Hz needs steps below {step_s:.3g} s{why}: "
            + (f"{steps:.3g} of them{over}, more than the {most:g} {method} can afford"
               if np.isfinite(steps) else f"{method} would diverge (beyond its stability limit)")
            + f"; {RIGID_LIMIT} (belt_stiffness_Nm_rad = {task.belt_stiffness_Nm_rad:g})")


def belt_too_fast_per_revolution(task: PressDrive, most: float, method: str) -> str | None:
    """`belt_too_fast` for a method that follows the belt mode at a tenth of its period over one
    revolution and can afford `most` such steps (steady_state's Newton, the design NLP); None
    without an elastic belt or when it can."""
    hz, _ = belt_mode(task)
    if hz == 0:
        return None
    step = 0.1 / hz
    return belt_too_fast(task, step, TWO_PI / task.nominal_speed_rad_s / step, most, method,
                         why=" (a tenth of its period)", over=" per revolution")


def nominal_speed_note(task: PressDrive) -> str:
    """'' or, with a motor whose working range at the crank (breakdown to idle speed, reduced by i)
    misses `nominal_speed_rad_s`, the words saying it is a start speed and guess only."""
    if not task.motor:
        return ""
    idle = task.motor_sync_speed_rad_s / task.gear_ratio
    if idle * (1 - task.motor_breakdown_slip) <= task.nominal_speed_rad_s <= idle:
        return ""
    return (f"; nominal_speed_rad_s={task.nominal_speed_rad_s:g} is a start speed and guess only: the motor sets "
            f"the speed (its working range at the crank: {idle * (1 - task.motor_breakdown_slip):.4g} to "
            f"{idle:.4g} rad/s, motor_sync_speed_rad_s / gear_ratio at breakdown slip and idle)")


def top_speed_rad_s(task: PressDrive) -> float:
    """The fastest the crank turns for long: the motor's synchronous speed reduced by i, or the
    nominal speed of an ideal drive (and never below it) [rad/s]."""
    sync = task.motor_sync_speed_rad_s / task.gear_ratio if task.motor else 0.0
    return max(sync, task.nominal_speed_rad_s)


def refuse_work(key: str, value, amount: float, most: float, what: str, bound: str, *,
                kind: type[MechoptError] = SettingError):
    """Refuse before any work a request whose size estimate `amount` exceeds `most`: one line naming
    the key, what the value implies, and the range that is allowed. `key` is a solver setting
    (SettingError) unless `kind` says otherwise (a model parameter: ModelError)."""
    if amount > most:
        raise kind(f"{key}={value} means about {amount:.3g} {what}, more than the {most:g} allowed "
                   f"({bound})", key=key)


def check_task(task, solver, **settings):
    """Refuse a task that is no PressDrive, then settings outside the ranges `solver`'s signature
    declares (SettingError, as a scene's are refused), before any work."""
    if not isinstance(task, PressDrive):
        raise ModelError(f"task={type(task).__name__}: expected a PressDrive", key="task")
    check_settings(solver, **settings)


def refuse_jumps(task: PressDrive, method: str, why: str):
    """Refuse `method` for a measured load with jumps inside its window (`why`: what it cannot do),
    naming the methods that stop at them."""
    if task.load is not None and task.load.jumps_rad:
        raise ModelError(f"load_table jumps at {', '.join(f'{a:.6g}' for a in np.degrees(task.load.jumps_rad))} deg "
                         f"and {method} {why}; events, ivp (locate_events), rk4 (the paper's fixed steps) and steady_state stop "
                         "at each jump", key="load_table")


def refuse_neutral_speed(task: PressDrive, method: str):
    """A constant-torque motor fixes no speed level: with its torque equal to the mean load every
    speed repeats (the periodic motions form a family, Newton's Jacobian is singular), with any other
    torque none repeats. Refuse a method that needs one periodic motion, naming the ones that work."""
    if task.torque_motor:
        raise ModelError(f"effect 'constant_torque_motor' with {method}: a constant torque sets no speed level, so "
                         "there is no single periodic motion (with the mean load's torque every speed repeats); "
                         "run press.simulate with method events, rk4 or ivp from nominal_speed_rad_s", key="effects")


def summarise(task: PressDrive, trace: Trace, *, cut_angles=None) -> tuple[dict, dict, dict]:
    """`values`, `diagnostics` and `arrays` of a run from its samples and events (see the package doc).

    The arrays are what figures and notebooks read: time `t_s`, every state by name, `cutting`
    (U, 0 or 1), the work integrals (`WORK_NAMES`) and the outputs of `Dynamics.OUTPUT_NAMES`."""
    dyn = dynamics_of(task)
    t, x, mode = trace.arrays()
    out = np.asarray(dyn.outputs.map(len(t))(x.T, mode.T))
    names = dict(zip(Dynamics.OUTPUT_NAMES, out))
    n = dyn.n_states
    iphi, iw = task.state_names.index("phi_rad"), task.state_names.index("omega_rad_s")
    phi, w = x[:, iphi], x[:, iw]
    works = x[-1, n:] - x[0, n:]
    energy = (names["kinetic_J"][-1] + names["potential_J"][-1]) - (names["kinetic_J"][0] + names["potential_J"][0])
    work = dict(zip(WORK_NAMES, map(float, works)))
    motor, cut, fric, damp = (work[k] for k in ("motor_work_J", "cut_work_J", "friction_work_J", "damping_work_J"))
    scale = max(abs(motor), abs(cut) + abs(fric) + abs(damp) + abs(energy), 1e-300)
    residual = abs(motor - cut - fric - damp - energy) / scale
    values = {"duration_s": float(t[-1] - t[0]), "energy_residual": float(residual), **work,
              "energy_change_J": float(energy),
              "peak_force_N": float(np.max(names["force_N"])), "peak_Q_N": float(np.max(np.abs(names["Q_N"]))),
              "peak_belt_torque_Nm": float(np.max(np.abs(names["belt_torque_Nm"]))),
              "final_phi_rad": float(phi[-1]), "final_omega_rad_s": float(w[-1]),
              "revolutions": float(np.floor(phi[-1] / TWO_PI + 1e-9) - np.floor(phi[0] / TWO_PI + 1e-9))}
    # the last full revolution: mean speed and fluctuation coefficient (omega_max - omega_min) / omega_mean
    marks = np.arange(np.ceil(phi[0] / TWO_PI - 1e-9), np.floor(phi[-1] / TWO_PI + 1e-9) + 1) * TWO_PI
    if len(marks) >= 2 and np.all(np.diff(phi) >= -1e-12):
        t0, t1 = (np.interp(m, phi, t) for m in marks[-2:])
        inside = (t >= t0 - 1e-12) & (t <= t1 + 1e-12)
        mean = TWO_PI / (t1 - t0)
        top, low = (_extreme(t[inside], w[inside], pick, mode[inside, 0]) for pick in (max, min))
        values |= {"omega_mean_rad_s": float(mean), "speed_fluctuation": float((top - low) / mean),
                   "period_s": float(t1 - t0)}
        values |= revolution_extras(task, t, x[:, n + WORK_NAMES.index("motor_work_J")], (t0, t1), top, low)
        if task.at_deg:
            values |= values_at_deg(task, phi[inside] - marks[-2], w[inside], names, inside)
        if values["speed_fluctuation"] > 0:     # the textbook flywheel for the fluctuation this run shows
            values |= {"energy_swing_J": energy_swing_J(task),
                       "flywheel_rule_of_thumb_kgm2": rule_of_thumb_flywheel_kgm2(task, values["speed_fluctuation"]),
                       # the same rule over everything turning with the crank, at the run's own mean speed
                       "inertia_rule_of_thumb_at_crank_kgm2": energy_swing_J(task) / (
                           values["speed_fluctuation"] * values["omega_mean_rad_s"] ** 2),
                       "inertia_at_crank_kgm2": inertia_at_crank_kgm2(task)}
    cuts_on = [e for e in trace.events if e[0] == "cut_start"]
    cuts_off = [e for e in trace.events if e[0] == "cut_end"]
    if cut_angles is not None:
        values |= {"cut_start_deg": float(np.degrees(cut_angles[0])), "cut_end_deg": float(np.degrees(cut_angles[1]))}
    elif cuts_on and cuts_off:
        values |= {"cut_start_deg": float(np.degrees(cuts_on[-1][2] % TWO_PI)),
                   "cut_end_deg": float(np.degrees(cuts_off[-1][2] % TWO_PI))}
    diagnostics_cut = None
    if task.cutting:
        per_cut_J = cut_work_J(task)
        values["cuts"] = float(cut / per_cut_J) if per_cut_J > 0 else 0.0
        window = cut_angles if cut_angles is not None else task.cut_window_rad()
        turns = np.arange(np.floor(phi[0] / TWO_PI) - 1, np.floor(phi[-1] / TWO_PI) + 2) * TWO_PI
        whole = int(np.sum((turns + window[0] >= phi[0] - 1e-9) & (turns + window[1] <= phi[-1] + 1e-9)))
        partial = int(np.sum((turns + window[0] < phi[-1]) & (turns + window[1] > phi[-1] + 1e-9)))
        values["cut_windows"] = float(whole)
        if per_cut_J > 0 and not whole - 1e-3 <= values["cuts"] <= whole + partial + 1e-3:
            diagnostics_cut = (f"the cutting work is {values['cuts']:.4g} cuts' worth over {whole} cut windows "
                               f"crossed: a cut was missed or mis-integrated")
    diagnostics = {"events": [(k, float(tt), float(np.degrees(p))) for k, tt, p in trace.events],
                   "event_count": len(trace.events), "samples": int(len(t)),
                   "min_omega_rad_s": float(w.min()), "states": list(task.state_names),
                   "cut_work_mismatch": diagnostics_cut}
    arrays = {"t_s": t, **{k: x[:, i] for i, k in enumerate(task.state_names)}, "cutting": mode[:, 0],
              **{k: x[:, n + i] - x[0, n + i] for i, k in enumerate(WORK_NAMES)}, **names}
    return values, diagnostics, arrays


def revolution_extras(task: PressDrive, t, motor_work, span, top, low) -> dict:
    """What the last full revolution (times `span`) adds for a drive's designer: the crank's extreme
    speeds (`top`, `low`) [rad/s], the motor's mean power over it [W], and with a flywheel on an
    intermediate shaft that shaft's extreme speeds (the crank's times `intermediate_ratio`) [rad/s]."""
    t0, t1 = span
    work = float(np.interp(t1, t, motor_work) - np.interp(t0, t, motor_work))
    out = {"omega_max_rad_s": float(top), "omega_min_rad_s": float(low), "motor_mean_power_W": work / (t1 - t0)}
    if task.intermediate_inertia_kgm2 > 0:
        out |= {"intermediate_omega_max_rad_s": float(top * task.intermediate_ratio),
                "intermediate_omega_min_rad_s": float(low * task.intermediate_ratio)}
    return out


AT_OUTPUTS = ("travel_mm", "force_N", "Q_N", "rod_force_N", "crank_torque_Nm", "motor_torque_Nm", "belt_torque_Nm",
              "main_bearing_load_N", "guide_force_N")


def values_at_deg(task: PressDrive, turn, w, outputs, inside) -> dict:
    """`<name>_<deg>` (`kinematics.at_name`) at the task's `at_deg` over the last revolution (`turn`: its crank angles from
    0 [rad], `w` the crank speed there): the crank speed and acceleration and the outputs `AT_OUTPUTS`
    interpolated linearly between the run's samples (at a switching angle: the value on one side), the
    slider's and rod's rates from the crank-slider's closed forms at that angle with that speed and
    acceleration (X' omega, X'' omega^2 + X' alpha; beta likewise)."""
    from mechopt.solvers.press.kinematics import at_name, slider_crank_rates
    angles = np.radians(task.at_deg)
    omega = np.interp(angles, turn, w)
    alpha = np.interp(angles, turn, outputs["alpha_rad_s2"][inside])
    _, dX, ddX, beta, db, ddb = slider_crank_rates(angles, task.r_m, task.rod_ratio, task.kinematics)
    found = {"omega_rad_s": omega, "alpha_rad_s2": alpha, "slider_velocity_m_s": dX * omega,
             "slider_acceleration_m_s2": ddX * omega**2 + dX * alpha, "rod_angle_deg": np.degrees(beta),
             "rod_angular_velocity_rad_s": db * omega, "rod_angular_acceleration_rad_s2": ddb * omega**2 + db * alpha,
             **{k: np.interp(angles, turn, outputs[k][inside]) for k in AT_OUTPUTS}}
    return {at_name(name, deg): float(series[k]) for k, deg in enumerate(task.at_deg)
            for name, series in found.items()}


def _extreme(t, w, pick, cutting):
    """The largest (pick=max) or smallest sample of w, refined by a parabola through it and its
    neighbours when all three lie in one mode of U (a smooth extremum: at the cut's start or end
    omega has a kink, and a parabola across it overshoots by ~1e-3 relative)."""
    i = int(np.argmax(w) if pick is max else np.argmin(w))
    if 0 < i < len(w) - 1 and t[i - 1] < t[i] < t[i + 1] and cutting[i - 1] == cutting[i] == cutting[i + 1]:
        c = np.polyfit(t[i - 1:i + 2] - t[i], w[i - 1:i + 2], 2)
        if c[0] != 0:
            vertex = -c[1] / (2 * c[0])
            if t[i - 1] - t[i] < vertex < t[i + 1] - t[i]:
                return pick(w[i], float(np.polyval(c, vertex)))
    return float(w[i])


def checked(status, message, violated, diagnostics):
    """A run whose cutting work disagrees with the cut windows it crossed says so, and is at best
    INACCURATE."""
    if diagnostics.get("cut_work_mismatch"):
        return (Status.INACCURATE if status is Status.SOLVED else status,
                f"{message}; {diagnostics['cut_work_mismatch']}", violated + ("cut_work",))
    return status, message, violated

def paper_U(task, xs):
    if not task.cutting:
        return np.zeros(len(xs))
    phi = xs[:, task.state_names.index("phi_rad")]
    w = xs[:, task.state_names.index("omega_rad_s")]
    if task.load is not None:           # a constant load: its crank-angle window, turning forward
        a, b = task.cut_window_rad()
        turn = np.mod(phi, TWO_PI)
        return ((turn >= a) & (turn <= b) & (w > 0)).astype(float)
    pen = task.travel(phi) * 1000 - (task.stroke_mm - task.blank_thickness_mm - task.shortfall_mm)
    down = w * np.sin(phi) > 0          # dX/dphi = r sin(phi) (1 + lambda cos(phi) ...) has the sign of sin(phi)
    return ((pen >= 0) & (pen <= task.blank_thickness_mm) & down).astype(float)


def angle_events(task, phi):
    """The next angle event strictly after phi: (angle, kind)."""
    base = np.floor(phi / TWO_PI) * TWO_PI
    marks = [(0.0, "revolution")]
    window = task.cut_window_rad()
    if window is not None and window[0] < window[1]:
        marks += [(window[0], "cut_start"), (window[1], "cut_end")]
        marks += [(a, "load_jump") for a in (task.load.jumps_rad if task.load is not None else ())]
    for turn in (0, 1):
        for angle, kind in sorted(marks):
            a = base + turn * TWO_PI + angle
            if a > phi + angle_tol(a):
                return a, kind
    raise AssertionError("unreachable")


def mode_at(task, dyn, x, moving_sign):
    """[U, friction sign, stuck] for a state: U from the crank angle (half-open window)."""
    phi = x[task.state_names.index("phi_rad")]
    window = task.cut_window_rad()
    u = 0.0
    if window is not None and moving_sign > 0:
        a = phi % TWO_PI
        u = float(window[0] - ANGLE_TOL_RAD <= a < window[1] - ANGLE_TOL_RAD)
    return np.array([u, float(moving_sign), 0.0])


def drive_torque(dyn, x, mode):
    """The torque turning the crank before friction, at a state in a mode [N m]."""
    return float(dyn.outputs(x, mode)[Dynamics.OUTPUT_NAMES.index("drive_torque_Nm")])


# --- the pieces every method integrates: CVODES by time (events) and by crank angle (periodic) ---

class Piece:
    """A structure's CVODES piece (`time_piece`) with a task's p bound: called as the integrator is."""

    def __init__(self, integrator: ca.Function, p: np.ndarray):
        self.integrator, self.p = integrator, p

    def __call__(self, *, x0, p):
        return self.integrator(x0=x0, p=np.r_[p, self.p])


@memoised(maxsize=32, per_thread=True)    # a CVODES integrator: one per thread (see BuildCache)
def time_piece(key: tuple, tol: float, samples: int) -> ca.Function:
    """CVODES over a piece of duration p[0] in mode p[1:4] with the press's p (`PARAMETERS`) after
    them (time scaled to [0, 1]): the states at `samples` equally spaced times, the last being the
    end of the piece. Built once per structure (`models.press_equations.structure`)."""
    eq = equations(key)
    x = ca.SX.sym("x", eq.rhs.size1_in(0))
    p = ca.SX.sym("p", 4 + len(PARAMETERS))
    grid = np.linspace(0, 1, samples + 1)[1:]
    return ca.integrator("piece", "cvodes", {"x": x, "p": p, "ode": p[0] * eq.rhs(x, p[1:4], p[4:])}, 0.0, grid,
                         {"abstol": tol, "reltol": tol, "max_num_steps": 100000})


def piece_by_time(task: PressDrive, tol: float, samples: int) -> Piece:
    """`time_piece` of the task's structure with its p bound."""
    return Piece(time_piece(structure(task), tol, samples), dynamics_of(task).p)


class Stall(Exception):
    pass


class Limit(Exception):
    pass


def march(task, piece, trace, x, duration_s, max_step_s, max_events):
    dyn = dynamics_of(task)
    iphi, iw = task.state_names.index("phi_rad"), task.state_names.index("omega_rad_s")
    friction = task.friction_torque_Nm if task.friction else 0.0
    t = 0.0
    mode = start_mode(task, dyn, x, friction)
    trace.add(t, x, mode)
    while t < duration_s * (1 - 1e-14):
        if len(trace.events) > max_events:
            raise Limit(f"more than max_events={max_events} events by t = {t:.6g} s")
        stuck = mode[2] > 0
        T = min(max_step_s, duration_s - t)
        target = kind = None
        if not stuck and mode[1] > 0:
            target, kind = angle_events(task, x[iphi])
            if x[iw] > 0:
                T = min(T, (target - x[iphi]) / x[iw])
        xs = run_piece(piece, x, T, mode)
        end = xs[-1]
        # friction events: omega crossing zero while moving, breakaway while stuck
        if stuck:
            g = lambda s: abs(drive_torque(dyn, s, mode)) - friction
            gs = [g(s) for s in xs]
            hit = next((i for i, v in enumerate(gs) if v > 0), None)
            if hit is not None:
                T_ev, xe = locate(piece, x, mode, T * hit / len(xs), T * (hit + 1) / len(xs), g)
                xs = run_piece(piece, x, T_ev, mode)
                t = commit(trace, t, T_ev, xs, mode)
                x = xs[-1]
                sign = np.sign(drive_torque(dyn, x, mode))
                mode = mode_at(task, dyn, x, sign)
                trace.events.append(("slip", t, float(x[iphi])))
                continue
        elif mode[1] != 0:
            ws = xs[:, iw] * mode[1]
            hit = next((i for i, v in enumerate(ws) if v <= 0), None)
            if hit is not None:
                lo = T * hit / len(xs)
                T_ev, xe = locate(piece, x, mode, lo, T * (hit + 1) / len(xs), lambda s: s[iw] * mode[1])
                xs = run_piece(piece, x, T_ev, mode)
                t = commit(trace, t, T_ev, xs, mode)
                x = xs[-1].copy()
                x[iw] = 0.0            # exactly at rest: the event's definition
                trace.events.append(("stop", t, float(x[iphi])))
                if mode[0] > 0:
                    raise Stall(f"the press stalls in the cut at crank angle {np.degrees(x[iphi] % TWO_PI):.3f} deg, "
                                 f"t = {t:.6g} s: the flywheel and motor cannot supply the cutting work")
                mode = start_mode(task, dyn, x, friction)
                if mode[2] > 0:
                    trace.events.append(("stick", t, float(x[iphi])))
                continue
        if target is not None and end[iphi] >= target - angle_tol(target):
            if abs(end[iphi] - target) > angle_tol(target):
                T, xs = newton_angle(piece, x, mode, T, target, iphi, iw)
            t = commit(trace, t, T, xs, mode)
            x = xs[-1]
            trace.events.append((kind, t, float(target)))
            x = x.copy()
            x[iphi] = target               # remove the last 1e-12 rad so the next window is clean
            mode = mode_at(task, dyn, x, 1.0)
            continue
        t = commit(trace, t, T, xs, mode)
        x = end


def start_mode(task, dyn, x, friction):
    """Mode for a state at rest or moving: stuck if static friction holds it."""
    w = x[task.state_names.index("omega_rad_s")]
    if w != 0:
        return mode_at(task, dyn, x, np.sign(w))
    rest = np.array([0.0, 0.0, 1.0])
    drive = drive_torque(dyn, x, rest)
    if abs(drive) <= friction:
        return rest
    return mode_at(task, dyn, x, np.sign(drive))


def run_piece(piece, x, T, mode):
    out = piece(x0=x, p=np.r_[T, mode])["xf"]
    return np.asarray(out).T


def commit(trace, t, T, xs, mode):
    n = len(xs)
    trace.add(t + T * np.arange(1, n + 1) / n, xs, mode)
    return t + T


def newton_angle(piece, x, mode, T, target, iphi, iw):
    """Duration T at which phi reaches `target` (Newton: d phi / dT = omega)."""
    for _ in range(50):
        xs = run_piece(piece, x, T, mode)
        miss = xs[-1, iphi] - target
        if abs(miss) <= angle_tol(target):
            return T, xs
        T -= miss / xs[-1, iw]
    raise Limit(f"event at crank angle {target:.12g} rad not located to {angle_tol(target):.3g} rad in 50 Newton "
                "steps")


def locate(piece, x, mode, lo, hi, g):
    """Duration in [lo, hi] where g(state) changes sign (Illinois false position)."""
    g_lo = g(run_piece(piece, x, lo, mode)[-1]) if lo > 0 else g(x)
    g_hi = g(run_piece(piece, x, hi, mode)[-1])
    side = 0
    for _ in range(200):
        mid = hi - g_hi * (hi - lo) / (g_hi - g_lo) if g_hi != g_lo else 0.5 * (lo + hi)
        state = run_piece(piece, x, mid, mode)[-1]
        g_mid = g(state)
        if abs(hi - lo) < 1e-14 or g_mid == 0:
            return mid, state
        if (g_mid > 0) == (g_hi > 0):
            hi, g_hi = mid, g_mid
            if side == 1:
                g_lo /= 2
            side = 1
        else:
            lo, g_lo = mid, g_mid
            if side == -1:
                g_hi /= 2
            side = -1
        if abs(g_mid) < 1e-12:
            return mid, state
    raise Limit(f"an event was not located to 1e-12 in 200 false-position steps (bracket {hi - lo:.3g} s, "
                 f"g = {g_mid:.3g})")



CUT_START, CUT_END = PARAMETERS.index("cut_start_rad"), PARAMETERS.index("cut_end_rad")


@dataclass(frozen=True)
class Revolution:
    """One revolution of a structure in the crank angle (d/dphi = (d/dt) / omega), as CVODES pieces
    over [0, cut start], [cut start, cut end], [cut end, 2 pi] (one piece without a cut); the state y:
    the states other than phi, then time, then the work integrals. Every number is an input (p,
    `PARAMETERS`: the cut's angles are two of them), so a what-if re-solves on the same build.

    * ``piece(x0=y, p=[a, b, U, p])``: CVODES from angle a to b (scaled to s in [0, 1]) with U fixed,
      the states at `samples` equally spaced angles, the last at b.
    * ``variational(x0=[y, Y], p=[a, b, U, p])``: the same piece with the variational equations
      beside it (Y = dy/dy0, column-major), for the monodromy (`residual`).
    """
    state_names: tuple[str, ...]
    cutting: bool
    piece: ca.Function
    variational: ca.Function
    grid: np.ndarray
    jumps: tuple = ()               # a measured load's jumps inside the window [rad]: piece boundaries too

    def __post_init__(self):
        object.__setattr__(self, "n", len(self.state_names))     # states, set once (read per Newton step)

    def spans(self, p, numbers=False) -> list[tuple]:
        """(a, b, U) of each piece for p (numbers or symbols; with numbers, an empty cut is no piece)."""
        if not self.cutting or (numbers and not p[CUT_START] < p[CUT_END]):
            return [(0.0, TWO_PI, 0.0)]
        inside = [p[CUT_START], *self.jumps, p[CUT_END]]
        return [(0.0, p[CUT_START], 0.0), *((a, b, 1.0) for a, b in zip(inside[:-1], inside[1:])),
                (p[CUT_END], TWO_PI, 0.0)]

    def residual(self, y0, p) -> tuple[np.ndarray, np.ndarray]:
        """(y(2 pi) - y0 over the states other than phi, the monodromy minus the identity): the
        periodicity residual and its Jacobian, for Newton shooting."""
        m = self.n - 1
        y = np.r_[y0, np.zeros(1 + len(WORK_NAMES))]
        Y = np.eye(len(y), m)
        for a, b, u in self.spans(p, numbers=True):
            z = np.asarray(self.variational(x0=np.r_[y, Y.ravel(order="F")], p=np.r_[a, b, u, p])["xf"]).ravel()
            y, Y = z[:len(y)], z[len(y):].reshape((len(y), m), order="F")
        return y[:m] - y0, Y[:m] - np.eye(m)

    def trace(self, y0, p) -> tuple["Trace", np.ndarray]:
        """Samples over the revolution from the states y0 (other than phi) [as a Trace], and y at 2 pi."""
        n, iphi = self.n, self.state_names.index("phi_rad")
        trace = Trace()
        y = np.r_[y0, np.zeros(1 + len(WORK_NAMES))]

        def full(rows, angles):
            return np.column_stack([rows[:, :iphi], angles, rows[:, iphi:n - 1], rows[:, n:]]), rows[:, n - 1]

        trace.add(0.0, full(y[None, :], np.zeros(1))[0], np.array([0.0, 1.0, 0.0]))
        for a, b, u in self.spans(p, numbers=True):
            ys = np.asarray(self.piece(x0=y, p=np.r_[a, b, u, p])["xf"]).T
            x, t = full(ys, a + (b - a) * self.grid)
            trace.add(t, x, np.array([u, 1.0, 0.0]))
            kind = ("load_jump" if b in self.jumps else "cut_start" if u == 0 and b < TWO_PI
                    else "cut_end" if u == 1 else "revolution")
            trace.events.append((kind, float(t[-1]), float(b)))
            y = ys[-1]
        return trace, y[:n - 1]


@memoised(maxsize=16, per_thread=True)    # CVODES integrators: one per thread (see BuildCache)
def revolution(key: tuple, tol: float, samples: int) -> Revolution:
    """The `Revolution` of a structure (`models.press_equations.structure`), built once per (structure, tol, samples)."""
    eq = equations(key)
    names = eq.state_names
    n, iphi, iw = len(names), names.index("phi_rad"), names.index("omega_rad_s")
    y = ca.SX.sym("y", n - 1 + 1 + len(WORK_NAMES))      # other states, time, works
    s = ca.SX.sym("s")
    q = ca.SX.sym("q", 3 + len(PARAMETERS))              # a, b, U, p
    a, b, u, p = q[0], q[1], q[2], q[3:]
    phi = a + s * (b - a)
    states = ca.vertcat(y[:iphi], phi, y[iphi:n - 1])
    xdot = eq.rhs(ca.vertcat(states, y[n:]), ca.vertcat(u, 1, 0), p)
    dy = ca.vertcat(xdot[:iphi], xdot[iphi + 1:n], 1, xdot[n:]) / states[iw]
    grid = np.linspace(0, 1, samples + 1)[1:]
    piece = ca.integrator("revolution", "cvodes", {"x": y, "t": s, "p": q, "ode": (b - a) * dy}, 0.0, grid,
                          {"abstol": tol, "reltol": tol, "max_num_steps": 100000})
    Y = ca.SX.sym("Y", y.numel(), n - 1)        # dy/dy0: the variational equations ride along
    ode = (b - a) * dy
    variational = ca.integrator("variational", "cvodes",
                                {"x": ca.vertcat(y, ca.vec(Y)), "t": s, "p": q,
                                 "ode": ca.vertcat(ode, ca.vec(ca.jacobian(ode, y) @ Y))}, 0.0, 1.0,
                                {"abstol": tol, "reltol": tol, "max_num_steps": 100000})
    jumps = Load(0.0, 0.0, 0.0, 0.0, key[2][2], key[2][1]).jumps_rad if len(key) > 2 else ()
    return Revolution(names, bool({"cutting_force", "constant_load"} & set(key[0])), piece, variational, grid,
                      tuple(jumps))
