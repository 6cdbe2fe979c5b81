"""How much each assumed parameter moves the press's periodic motion: d(output)/d(parameter) by
CasADi AD through the periodic solution (the implicit function theorem of CasADi's rootfinder).

The unknowns are the periodic orbit's states at phi = 0 and the crank angles of the extremes
(slowest and fastest crank speed, peak belt torque); the residuals are periodicity over the
revolution (three CVODES pieces in the crank angle, as `steady_state` has them) and d(g)/d(phi) = 0
at each extreme. The rootfinder's derivatives with respect to the parameters are then exact to
the integration tolerance: the speed fluctuation (omega_max - omega_min) / omega_mean, the angle
of the slowest speed, the peak belt torque, the mean crank speed and the works of a revolution.
"""

import casadi as ca
import numpy as np

from mechopt.kit.errors import MechoptError, ModelError
from mechopt.kit.result import Clock, Result, Status, from_rootfinder
from mechopt.kit.settings import Annotated, Interval, Tolerance
from mechopt.models.press import PressDrive
from mechopt.models.press_equations import WORK_NAMES, Equations, equations, parameters, structure
from mechopt.solvers.press.periodic import steady_state
from mechopt.solvers.press.problem import TWO_PI, casadi_failure, check_task, refuse_jumps, refuse_neutral_speed

MAX_STEPS = 100_000                 # CVODES steps per piece of the revolution (its max_num_steps)
ROD_SIGN = "rod_weight_sign"        # +1: the rod's weight helps on the way down (the model's reading); -1: the table's
OUTPUTS = ("speed_fluctuation", "omega_min_deg", "peak_belt_torque_Nm", "omega_mean_rad_s", "cut_work_J",
           "motor_work_J")
_BY_EFFECT = {"belt_elasticity": ("belt_stiffness_Nm_rad", "belt_damping_Nms_rad"),
              "friction": ("friction_torque_Nm",),
              "motor_characteristic": ("motor_breakdown_torque_Nm", "motor_breakdown_slip", "motor_sync_speed_rad_s")}
_ALWAYS = ("flywheel_inertia_kgm2", "tool_mass_kg", "rod_mass_kg", "crank_mass_kg", "motor_inertia_kgm2",
           "gear_ratio")


def assumed_parameters(task: PressDrive) -> tuple[str, ...]:
    """The parameters the paper does not give that the task's effects use (and the calibrated gear ratio)."""
    names = list(_ALWAYS)
    for effect, keys in _BY_EFFECT.items():
        if effect in task.effects:
            names += keys
    return tuple(names)


def _orbit_rhs(task: PressDrive, names):
    """The model's eqs. (2) for forward motion (friction sign +1, not stuck) with `names` and the
    rod-weight reading as the input p: f(x, U, p) -> (dx/dt, belt torque), x = the task's states then
    the work integrals (`WORK_NAMES`). The structure's own Functions (`models.press_equations.equations`), the
    other numbers the task's."""
    p = ca.SX.sym("p", len(names) + 1)
    given = dict(zip(names, ca.vertsplit(p)))
    P = ca.vertcat(*parameters(task, rod_weight_sign=p[-1], **given))
    eq = equations(structure(task))
    x = ca.SX.sym("x", eq.rhs.size1_in(0))
    U = ca.SX.sym("U")
    mode = ca.vertcat(U, 1, 0)
    belt = eq.outputs(x, mode, P)[Equations.OUTPUT_NAMES.index("belt_torque_Nm")]
    return ca.Function("rhs_p", [x, U, p], [eq.rhs(x, mode, P), belt]), p.numel()


class _Orbit:
    """The periodic orbit and its extremes as a rootfinder in (orbit unknowns z; parameters p)."""

    def __init__(self, task, names, tol, guess_arrays):
        rhs, n_p = _orbit_rhs(task, names)
        works = len(WORK_NAMES)
        n = len(task.state_names)
        self.iphi, self.iw = task.state_names.index("phi_rad"), task.state_names.index("omega_rad_s")
        keep = [i for i in range(n) if i != self.iphi]
        self.m = len(keep)
        # one CVODES piece in s in [0, 1] over crank angles a..b: d/ds = (b - a) d/dphi = (b - a) (d/dt) / omega
        y = ca.SX.sym("y", self.m + 1 + works)         # other states, time, works (motor, cut, ...)
        s, q = ca.SX.sym("s"), ca.SX.sym("q", 3 + n_p)  # q = (a, b, U, p)
        a, b, U, p = q[0], q[1], q[2], q[3:]
        phi = a + s * (b - a)
        x = ca.vertcat(*[y[keep.index(i)] if i != self.iphi else phi for i in range(n)], y[self.m + 1:])
        xdot, _ = rhs(x, U, p)
        dy = ca.vertcat(*[xdot[i] for i in keep], 1, xdot[n:]) / x[self.iw]
        self.piece = ca.integrator("piece", "cvodes", {"x": y, "t": s, "p": q, "ode": (b - a) * dy}, 0.0, 1.0,
                                   {"abstol": tol, "reltol": tol, "max_num_steps": MAX_STEPS})
        # d(g)/d(phi) along the motion for g = crank speed and belt torque (x_full with its derivative)
        xf, pf, Uf = ca.SX.sym("xf", n + works), ca.SX.sym("pf", n_p), ca.SX.sym("Uf")
        xdot, belt = rhs(xf, Uf, pf)
        self.g = ca.Function("g", [xf, Uf, pf], [ca.vertcat(xf[self.iw], belt),
                                                 ca.jtimes(ca.vertcat(xf[self.iw], belt), xf, xdot)])
        self.keep, self.n = keep, n
        window = task.cut_window_rad()
        self.bounds = [0.0, *window, TWO_PI] if window is not None and window[0] < window[1] else [0.0, TWO_PI]
        self.extremes = self._classify(guess_arrays)

    def _classify(self, arrays):
        """(name, sign, piece, fixed angle or None, guess) of each extreme from the sampled orbit."""
        phi = np.asarray(arrays["phi_rad"]) % TWO_PI
        phi[-1] = TWO_PI if phi[-1] < 1e-9 else phi[-1]
        out = []
        for name, series, sign in (("omega_min", arrays["omega_rad_s"], -1.0), ("omega_max", arrays["omega_rad_s"], 1.0),
                                   ("belt_peak", arrays["belt_torque_Nm"], None)):
            series = np.asarray(series)
            sign = sign if sign is not None else (1.0 if abs(series.max()) >= abs(series.min()) else -1.0)
            k = int(np.argmax(sign * series))
            angle = float(phi[k])
            on_bound = [bd for bd in self.bounds if abs(angle - bd) < 1e-9]
            piece = max(j for j in range(len(self.bounds) - 1) if self.bounds[j] <= angle + 1e-12)
            piece = min(piece, len(self.bounds) - 2)
            out.append((name, sign, piece, on_bound[0] if on_bound else None, angle))
        return out

    def residual_and_outputs(self, z, p):
        """(residual, outputs) as MX of the unknowns z = (orbit states at phi = 0, extreme angles) and p."""
        y0 = z[:self.m]
        y = ca.vertcat(y0, ca.MX.zeros(1 + len(WORK_NAMES)))
        starts = []
        for j, (a, b) in enumerate(zip(self.bounds[:-1], self.bounds[1:])):
            starts.append(y)
            u = float(len(self.bounds) == 4 and j == 1)
            y = self.piece(x0=y, p=ca.vertcat(a, b, u, p))["xf"]
        residual = [y[:self.m] - y0]
        values = {}
        for k, (name, sign, piece, fixed, _) in enumerate(self.extremes):
            angle = z[self.m + k]
            a = self.bounds[piece]
            u = float(len(self.bounds) == 4 and piece == 1)
            ya = self.piece(x0=starts[piece], p=ca.vertcat(a, angle, u, p))["xf"]
            x = ca.vertcat(*[ya[self.keep.index(i)] if i != self.iphi else angle for i in range(self.n)],
                           ya[self.m + 1:])
            g, dg = self.g(x, u, p)
            which = 0 if name.startswith("omega") else 1
            # d(g)/d(phi) relative to g: the angle rows weigh like the periodicity rows
            residual.append(angle - fixed if fixed is not None else dg[which] / (x[self.iw] * g[which]))
            values[name] = sign * g[which] if name == "belt_peak" else g[which]
            values[name + "_angle"] = angle
        period = y[self.m]
        mean = TWO_PI / period
        outputs = ca.vertcat((values["omega_max"] - values["omega_min"]) / mean, values["omega_min_angle"] * 180 / np.pi,
                             values["belt_peak"], mean, y[self.m + 2], y[self.m + 1])
        return ca.vertcat(*residual), outputs


def sensitivity(task: PressDrive, *, tol: Tolerance = 1e-10, max_iter: Annotated[int, Interval(ge=1, le=100)] = 30,
                verify_step: Annotated[float, Interval(ge=0, le=0.1)] = 0.0) -> Result:
    """d(output)/d(parameter) of the periodic steady motion, by CasADi AD (implicit function theorem
    through the rootfinder), for every assumed parameter (`assumed_parameters`) and the rod-weight
    sign reading.

    Outputs (`OUTPUTS`): speed fluctuation (omega_max - omega_min) / omega_mean, crank angle of the
    slowest speed [deg], peak belt torque [N m] (the reduced motor torque without a belt), mean crank
    speed [rad/s], cut work and motor work of a revolution [J]. `arrays` hold the table, one row per
    parameter (`diagnostics["parameters"]` names them): `d_<output>` and `elasticity_<output>`
    (p/y dy/dp: 0.1 means 1 % more of the parameter gives 0.1 % more output). `values` hold the
    outputs, the speed fluctuation's elasticities, the fluctuation under the other rod-weight reading
    and the slide's weight swing m_tool g H. With `verify_step` > 0 every derivative is also taken by
    central differences of re-solves at p (1 +- verify_step): `ad_fd_mismatch` is the largest
    gap between the two elasticities (arrays `fd_elasticity_<output>`).

    Parameters
    ----------
    tol : CVODES tolerance (the orbit's periodicity to 100 tol).  max_iter : Newton iterations.
    verify_step : relative step of the finite-difference check (0: none).
    """
    check_task(task, sensitivity, tol=tol, max_iter=max_iter, verify_step=verify_step)
    refuse_neutral_speed(task, "press.sensitivity")
    refuse_jumps(task, "press.sensitivity", "integrates the window as one piece")
    if not task.motor:
        raise ModelError("effects lack 'motor_characteristic': without the motor the crank's mean speed is "
                         "not set by the drive; add the effect", key="effects")
    clock = Clock()
    base = steady_state(task, tol=tol, samples=200)
    if base.status is not Status.SOLVED:
        return clock.result(base.status, base.values, f"no periodic orbit to differentiate: {base.message}",
                            base.violated, base.diagnostics)
    try:
        return _differentiate(task, base, tol, max_iter, verify_step, clock)
    except RuntimeError as exc:          # CasADi raises where CVODES stops (too many steps): a status, not a crash
        if isinstance(exc, MechoptError):
            raise
        status, message, failure = casadi_failure(exc, "differentiating the periodic orbit: no derivatives")
        return clock.result(status, {}, message, (), base.diagnostics | failure)


def _differentiate(task, base, tol, max_iter, verify_step, clock) -> Result:
    """`sensitivity`'s answer from the steady orbit `base`: the rootfinder through it and its derivatives."""
    names = assumed_parameters(task)
    orbit = _Orbit(task, names, tol, base.arrays)
    n_p = len(names) + 1
    z, p = ca.MX.sym("z", orbit.m + 3), ca.MX.sym("p", n_p)
    residual, outputs = orbit.residual_and_outputs(z, p)
    rf = ca.rootfinder("orbit", "newton", ca.Function("G", [z, p], [residual]),
                       {"max_iter": max_iter, "error_on_fail": False, "abstol": 100 * tol})
    z0, p0 = ca.MX.sym("z0", orbit.m + 3), ca.MX.sym("p0", n_p)
    zs = rf(z0, p0)
    out = ca.Function("out", [z, p], [outputs])(zs, p0)
    solve = ca.Function("solve", [z0, p0], [out, zs])
    derivative = ca.Function("derivative", [z0, p0], [out, ca.jacobian(out, p0)])
    guess = np.r_[base.diagnostics["initial_state"], [e[3] if e[3] is not None else e[4] for e in orbit.extremes]]
    values0 = np.r_[[getattr(task, k) for k in names], 1.0]
    clock.built()
    orbit_z = np.asarray(rf(guess, values0)).ravel()
    status, iterations = from_rootfinder(rf.stats()["return_status"]), rf.stats()["iter_count"]
    periodic = ca.Function("G", [z, p], [residual])
    miss = float(np.max(np.abs(np.asarray(periodic(orbit_z, values0)))))
    guess = orbit_z             # the derivatives and re-solves start on the orbit
    y, D = (np.asarray(v) for v in derivative(guess, values0))
    y = y.ravel()
    if status is Status.SOLVED and miss > 1e3 * tol:
        status = Status.INACCURATE
    strayed = [e[0] for k, e in enumerate(orbit.extremes) if e[3] is None
               and not orbit.bounds[e[2]] <= orbit_z[orbit.m + k] <= orbit.bounds[e[2] + 1]]
    if status is Status.SOLVED and strayed:     # its condition was solved on the wrong piece's equations
        status = Status.INACCURATE
    elasticity = D * values0[None, :] / np.where(y == 0, np.inf, y)[:, None]
    rows = [*names, ROD_SIGN]
    values = dict(zip(OUTPUTS, map(float, y)))
    values |= {f"speed_fluctuation_elasticity_{k}": float(elasticity[0, i]) for i, k in enumerate(rows)}
    opposing, z_opposing = (np.asarray(v).ravel() for v in solve(guess, np.r_[values0[:-1], -1.0]))
    if np.max(np.abs(np.asarray(periodic(z_opposing, np.r_[values0[:-1], -1.0])))) <= 1e3 * tol:
        values["speed_fluctuation_rod_weight_opposing"] = float(opposing[0])    # else left out: no orbit found
        values["rod_weight_reading_spread"] = float(opposing[0] / y[0] - 1)
    g = task.gravity_m_s2 if "gravity" in task.effects else 0.0
    values["slide_weight_swing_J"] = float(task.tool_mass_kg * g * (task.travel(np.pi) - task.travel(0.0)))
    values["periodicity_residual"] = miss
    diagnostics = {"parameters": rows, "parameter_values": values0.tolist(), "outputs": list(OUTPUTS),
                   "extremes": {e[0]: ("kink at an event" if e[3] is not None else "smooth") for e in orbit.extremes},
                   "newton_iterations": iterations}
    arrays = {"parameter": rows, "parameter_value": values0}       # one row per parameter, named
    for j, name in enumerate(OUTPUTS):
        arrays[f"d_{name}"] = D[j]
        arrays[f"elasticity_{name}"] = elasticity[j]
    if verify_step > 0:
        fd = np.empty_like(D)
        for i in range(n_p):
            step = verify_step * (values0[i] if values0[i] != 0 else 1.0)
            up, down = values0.copy(), values0.copy()
            up[i] += step
            down[i] -= step
            fd[:, i] = (np.asarray(solve(guess, up)[0]).ravel() - np.asarray(solve(guess, down)[0]).ravel()) / (2 * step)
        fd_elasticity = fd * values0[None, :] / np.where(y == 0, np.inf, y)[:, None]
        values["ad_fd_mismatch"] = float(np.max(np.abs(fd_elasticity - elasticity)))
        arrays |= {f"fd_elasticity_{name}": fd_elasticity[j] for j, name in enumerate(OUTPUTS)}
    message = (f"d(output)/d(parameter) through the periodic orbit ({diagnostics['newton_iterations']} Newton "
               f"iterations, residual {miss:.3g}); largest |elasticity| of the speed fluctuation: "
               f"{rows[int(np.argmax(np.abs(elasticity[0])))]} ({np.max(np.abs(elasticity[0])):.3g})")
    if strayed:
        message = (f"the extremes {', '.join(strayed)} left the piece of the revolution they were sampled on: "
                   "their derivatives are not to trust")
    if status is not Status.SOLVED and not strayed:
        message = f"the orbit's rootfinder stopped after {iterations} iterations (residual {miss:.3g}): not to trust"
    return clock.result(status, values, message, (), diagnostics, arrays)
