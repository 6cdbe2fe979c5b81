"""One steady revolution of the press as multiple shooting in the crank angle, with the design
variables as symbols: the pieces of the design NLP (design.py).

In the crank angle the cut starts and ends at fixed angles (they depend on the geometry only, not
on the drive being designed), so they are interval boundaries and U is a constant on each
interval: the switched force is kept exactly, never smoothed. Each interval is one CVODES
integrator of the same equations `steady_state` uses (`models.press_equations.dynamics`, here with the
design variables left free), with three quadratures beside the states (`QUADRATURES`): time, and
the integrals of the motor shaft torque and of its square (energy and RMS torque).
"""
from itertools import pairwise

import casadi as ca
import numpy as np

from mechopt.kit.cache import memoised
from mechopt.models.press_design import PressDesign, design_parameters, sizing
from mechopt.models.press_equations import WORK_NAMES, Dynamics, equations, structure
from mechopt.solvers.press.problem import TWO_PI

QUADRATURES = ("time_s", "motor_torque_integral_Nms", "motor_torque_sq_integral_N2m2s")


def stage_angles(task: PressDesign) -> list[float]:
    """0, the cut's start and end (when there is a cut of nonzero length), 2 pi [rad]."""
    window = task.cut_window_rad()
    if window is not None and window[0] < window[1]:
        return [0.0, window[0], window[1], TWO_PI]
    return [0.0, TWO_PI]


def cutting_on(task: PressDesign, a: float, b: float) -> float:
    """U on the interval [a, b] (inside one stage): 1 inside the cut window, else 0."""
    window = task.cut_window_rad()
    return float(window is not None and window[0] <= a and b <= window[1] and window[0] < window[1])


def _symbols(task: PressDesign):
    """The shooting state y (the states other than phi), phi, U, design p; the model's state x (zero
    work integrals) and mode; the press's equations with the design variables as symbols in their
    p (the very Functions the simulators call), and the gear ratio (a symbol when free)."""
    iphi = task.state_names.index("phi_rad")
    phi, u = ca.SX.sym("phi"), ca.SX.sym("u")
    p = ca.SX.sym("p", len(task.variables))
    dyn = Dynamics(task, equations(structure(task)),
                   ca.vertcat(*design_parameters(task, dict(zip(task.variables, ca.vertsplit(p))))))
    y = ca.SX.sym("y", dyn.n_states - 1)
    others = ca.vertsplit(y)                    # (slicing y[:0] gives a 1-by-0 that vertcat miscounts)
    x = ca.vertcat(*others[:iphi], phi, *others[iphi:], ca.DM.zeros(len(WORK_NAMES)))
    gear = sizing(task, dict(zip(task.variables, ca.vertsplit(p))))["gear_ratio"]
    return y, phi, u, p, x, ca.vertcat(u, 1, 0), dyn, gear


@memoised(maxsize=8, per_thread=True)     # CVODES integrators: one per thread (see BuildCache)
def intervals(task: PressDesign, nodes: tuple[float, ...], tol: float, samples: int):
    """[(CVODES integrator, its output angles, U)] for the intervals between `nodes` [rad]. The
    integrator's state: the states other than phi; its quadratures `QUADRATURES` (cumulative at each
    output); its parameter: U, then the design variables in `task.variables` order."""
    y, phi, u, p, x, mode, dyn, gear = _symbols(task)
    n = dyn.n_states
    iphi = task.state_names.index("phi_rad")
    xdot = dyn.rhs(x, mode)
    shaft = dyn.outputs(x, mode)[1] / gear if task.motor else 0 * phi       # motor torque at its shaft
    w = x[task.state_names.index("omega_rad_s")]
    ode = ca.vertcat(*[xdot[i] for i in range(n) if i != iphi]) / w
    quad = ca.vertcat(1, shaft, shaft**2) / w
    out = []
    # Adams, not BDF: the belt mode is at most ~30 times the revolution (design.STEPS_PER_REVOLUTION; faster
    # ones go to the rigid-belt model), so at 1e-10 accuracy, not stability, sets the step, and
    # Adams' orders up to 12 take fewer of them (the Jacobian with its sensitivities costs ~40 % of BDF's)
    for k, (a, b) in enumerate(pairwise(nodes)):
        grid = np.linspace(a, b, samples + 1)[1:]
        integ = ca.integrator(f"shoot{k}", "cvodes", {"x": y, "t": phi, "p": ca.vertcat(u, p), "ode": ode,
                                                     "quad": quad}, a, grid,
                              {"abstol": tol, "reltol": tol, "max_num_steps": 100000, "quad_err_con": True,
                               "linear_multistep_method": "adams"})
        out.append((integ, grid, cutting_on(task, a, b)))
    return out


@memoised(maxsize=8)
def probe(task: PressDesign, samples: int) -> ca.Function:
    """(states other than phi (columns), their angles, U, design p) -> rows omega [rad/s], belt torque
    at the crank shaft [N m], motor shaft torque [N m], at each sample."""
    y, phi, u, p, x, mode, dyn, gear = _symbols(task)
    out = dyn.outputs(x, mode)
    w = x[task.state_names.index("omega_rad_s")]
    one = ca.Function("probe", [y, phi, u, p], [ca.vertcat(w, out[0], out[1] / gear if task.motor else 0 * phi)])
    return one.map(samples)


@memoised(maxsize=8, per_thread=True)     # a CVODES integrator: one per thread (see BuildCache)
def reach(task: PressDesign, tol: float) -> ca.Function:
    """(states other than phi at angle a, U, design p, a, angle L further) -> (those states at a + L,
    the crank's angular acceleration there [rad/s2]): CVODES over s in [0, 1] with phi = a + s L, to
    place a speed extreme (acceleration 0) to the integrator's accuracy."""
    y, phi, u, p, x, mode, dyn, _ = _symbols(task)
    n = dyn.n_states
    iphi = task.state_names.index("phi_rad")
    a, span, s = ca.SX.sym("a"), ca.SX.sym("span"), ca.SX.sym("s")
    xdot = dyn.rhs(x, mode)
    ode = ca.vertcat(*[xdot[i] for i in range(n) if i != iphi]) / x[task.state_names.index("omega_rad_s")]
    ode = ca.substitute(ode, phi, a + s * span) * span
    integ = ca.integrator("reach", "cvodes", {"x": y, "t": s, "p": ca.vertcat(u, p, a, span), "ode": ode}, 0.0, 1.0,
                          {"abstol": tol, "reltol": tol, "max_num_steps": 100000})
    y0, p_all = ca.MX.sym("y0", y.numel()), ca.MX.sym("p", 1 + p.numel() + 2)
    end = integ(x0=y0, p=p_all)["xf"]
    alpha = dyn.OUTPUT_NAMES.index("alpha_rad_s2")
    accel = ca.Function("accel", [y, phi, u, p], [dyn.outputs(x, mode)[alpha]])
    return ca.Function("reach", [y0, p_all], [end, accel(end, p_all[-2] + p_all[-1], p_all[0], p_all[1:-2])])
