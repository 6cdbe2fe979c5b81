"""An event-driven check of eq. (2): the lever's contact with the plate and its separation, with
the stiffness switching between on the plate and off it (eq. (2) keeps one stiffness)."""
import math

from scipy.integrate import solve_ivp

from mechopt.kit.result import Status, from_ivp
from mechopt.models.stop_impact import LeverStop


def simulate_contact(task: LeverStop, speed_rpm, *, v0_m_s: float | None = None, rtol: float = 1e-11):
    """The lever's contact with the plate and its separation as a piecewise-linear event-driven
    simulation: C arrives at the plate (x = 0) with the approach velocity; on the plate the
    stiffness is c_stop (Fig. 6), off it c_free (Fig. 5) about the cam's position -preload; the
    plate only pushes. Located events: separation (x rises through 0), first rebound peak
    (x' = 0 off the plate). Damping zeta of each configuration's own frequency.

    `v0_m_s` the approach velocity when the cam computed it (effect cam_drive).
    Returns (rebound_mm, contact_s, status, message): 0 mm when C never leaves the plate.
    """
    m, cf, cs = task.mass_kg, task.c_free_N_per_m, task.c_stop_N_per_m
    zeta = task.damping_ratio if "damping" in task.effects else 0.0
    delta = task.preload_mm * 1e-3 if "preload" in task.effects else 0.0
    v0 = float(task.approach_velocity_m_s(speed_rpm)) if v0_m_s is None else float(v0_m_s)

    def on_plate(t, y):
        return [y[1], (-cf * (y[0] + delta) - (cs - cf) * y[0] - 2 * zeta * math.sqrt(cs * m) * y[1]) / m]

    def off_plate(t, y):
        return [y[1], (-cf * (y[0] + delta) - 2 * zeta * math.sqrt(cf * m) * y[1]) / m]

    def separation(t, y):
        return y[0]
    separation.terminal, separation.direction = True, 1

    def peak(t, y):
        return y[1]
    peak.terminal, peak.direction = True, -1

    scale = abs(v0) / task.omega_stop_rad_s + delta        # what moves C: its approach, the preload
    if scale == 0.0:
        return 0.0, 0.0, Status.SOLVED, "nothing moves C: no approach velocity, no preload"
    horizon = 4 * math.pi / task.omega_stop_rad_s
    # start a hair inside the plate so the separation event is not the start point
    contact = solve_ivp(on_plate, (0.0, horizon), [-1e-15 * v0, -v0], method="DOP853", rtol=rtol,
                        atol=1e-14 * scale, events=separation)
    status = from_ivp(contact.status)
    if status is not Status.SOLVED:
        return 0.0, 0.0, status, f"contact phase: {contact.message}"
    if not contact.t_events[0].size:
        return 0.0, horizon, Status.SOLVED, "C stays on the plate (the preload holds it)"
    t_sep, y_sep = contact.t_events[0][0], contact.y_events[0][0]
    free = solve_ivp(off_plate, (t_sep, t_sep + 2 * math.pi / task.omega_free_rad_s), [0.0, y_sep[1]],
                     method="DOP853", rtol=rtol, atol=1e-14 * scale, events=peak)
    status = from_ivp(free.status)
    if status is not Status.SOLVED or not free.t_events[0].size:
        return 0.0, t_sep, Status.FAILED if status is Status.SOLVED else status, f"free phase: {free.message}"
    return float(free.y_events[0][0][0]) * 1e3, float(t_sep), Status.SOLVED, "separated and peaked"
