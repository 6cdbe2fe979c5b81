"""Motion of the crank press (paper 001, eqs. (1)-(2)): the paper's RK4, ours, and the peer.

* `rk4` (fixed_step.py):       fixed-step classical Runge-Kutta on the switched equations, the
                               paper's method with its step refinement; the baseline.
* `events` (event_driven.py):  CVODES on each smooth piece, restarted at located events.
* `steady_state` (periodic.py): the periodic steady motion over one revolution, solved directly.
* `ivp` (scipy_peer.py):       scipy's solve_ivp, the peer a user would reach for.
* `simulate(task, method=...)`: one door to all four (`METHODS`), as `scipy.integrate.solve_ivp` has.

The four are siblings over `problem.py` (the press problem: its equations per structure, the
pieces they integrate, the switching logic, the summary of a run); none imports another.

Every result reports the energy balance over the run (motor work = cutting + friction + belt
damping work + change of kinetic and potential energy; `energy_residual`, relative), the events
located, the speed fluctuation coefficient and the peaks of force, Q and belt torque, and carries
the run's samples in `Result.arrays` (`t_s`, the states, `cutting`, the outputs).
`kinematics` (kinematics.py): the crank-slider at constant crank speed, no dynamics.
`loads` (loads.py) adds the peaks of the loads a designer sizes parts with (Figs. 9-10).
`force_fit.fit_force` fits the force law (1) to load-travel data.
`sensitivity` (sensitivity.py): d(output)/d(assumed parameter) through the periodic orbit by AD.
`design` (design.py) chooses the drive by optimisation over the periodic steady motion;
`flywheel` (flywheel.py): the least flywheel alone by a safeguarded Newton on the orbit's sensitivity;
`catalogue` (catalogue.py) picks a motor row and a belt ratio from a catalogue with `design` inside.
"""
from typing import Literal

from mechopt.solvers.press.catalogue import catalogue
from mechopt.solvers.press.design import design
from mechopt.solvers.press.event_driven import events
from mechopt.solvers.press.fixed_step import rk4
from mechopt.solvers.press.flywheel import flywheel
from mechopt.solvers.press.kinematics import kinematics
from mechopt.solvers.press.loads import loads
from mechopt.solvers.press.periodic import steady_state
from mechopt.solvers.press.scipy_peer import ivp
from mechopt.solvers.press.sensitivity import sensitivity

__all__ = ["METHODS", "Method", "catalogue", "design", "events", "flywheel", "ivp", "kinematics", "loads", "rk4", "sensitivity", "simulate",
           "steady_state"]

METHODS = {"rk4": rk4, "events": events, "steady_state": steady_state, "ivp": ivp}
Method = Literal["rk4", "events", "steady_state", "ivp"]


def simulate(task, *, method: Method = "events", **options):
    """Motion of the press by one of `METHODS` ("rk4", "events", "steady_state", "ivp"), with
    that method's keyword options; returns its Result (values, status, `arrays` of the samples).
    A scene reaches it as `solver = "press.simulate"` with `method` in its solver settings (the
    method's own settings through its own solver name, e.g. `press.events`).

    >>> from mechopt import load
    >>> task, _ = load("press/kd2322").build()
    >>> simulate(task, method="steady_state").status.value
    'SOLVED'
    """
    from mechopt.kit.settings import check_settings
    check_settings(simulate, method=method)          # SettingError: method='x': allowed rk4, events, ...
    return METHODS[method](task, **options)
