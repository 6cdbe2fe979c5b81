"""The lift's rise in a grooved cam with its backlash, as a hybrid model: what the crossovers do
to the approach of C to its plate (the input of eq. (2)), which the chain (follow_cam, the walls
taken without backlash) leaves out.

Three phases, C's state (x, x') carried across each switch, in the rise's own time xi with X = x / H
(models/cam_follower.py), phi = F T^2 / (m H) the closure force F in those units:

* on the inner (driving) wall: the roller's centre on the pitch path S, C through the link:
  X'' = -2 zeta lambda (X' - S') - lambda^2 (X - S); held while N = F + m x'' >= 0;
* on the outer wall: the same with the path S + delta / H (the backlash delta, reduced to C);
  held while N <= 0;
* in flight: the roller (massless) touches neither wall: the link carries the closure alone,
  so m x'' = -F, X'' = -phi, and the roller R follows C through the link's damper,
  lambda^2 (R - X) + 2 zeta lambda (R' - X') = -phi (its relaxation, time 2 zeta / lambda);
  it lands where R reaches the other wall (S + delta / H leaving the inner one, S leaving the
  outer) or its own again. The impact speed is |R' - S'| H / T there; the landing is inelastic
  for the massless roller (it takes the wall's motion), C's state unchanged. A landing on a wall
  that cannot hold N is a flight again at once.

C meets its plate where X = 1 - preload / H: the approach velocity v0 with the backlash. scipy's
DOP853 with its event location, restarted at each switch (a count limit, said when hit).
The damping ratio must be > 0 (with none the massless roller has no motion of its own in flight).
"""
import math
from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp

from mechopt.kit.errors import ModelError
from mechopt.kit.result import Status, from_ivp
from mechopt.models.stop_impact import LeverStop
from mechopt.solvers.stop_impact.cam_follower import dwell_length, follower_data
from mechopt.solvers.stop_impact.crossover import law_path
from mechopt.solvers.stop_impact.response import closed_form_amplitude_m

MAX_SWITCHES = 200          # phase changes followed in one rise (a count)


@dataclass(frozen=True)
class GrooveRise:
    """One rise with the backlash: the contact with the plate (xi, None if none) and v0 [m/s],
    the flights ((leave xi, land xi, wall left, wall landed on, impact speed m/s), ...), status."""
    contact_xi: float | None
    approach_velocity_m_s: float
    flights: tuple
    status: Status
    message: str


def follow_groove(task: LeverStop, speed_rpm, t_deg=None, *, rtol: float = 1e-11) -> GrooveRise:
    """The rise of `task` (closure "groove") at `speed_rpm` and `t_deg` with its backlash (module
    docstring)."""
    if task.closure != "groove":
        raise ModelError(f"closure={task.closure!r}: the hybrid groove model needs closure='groove'", key="closure")
    if "damping" not in task.effects or not task.damping_ratio:
        raise ModelError("the hybrid groove model needs the effect 'damping' with damping_ratio > 0 (the link's "
                         "damper moves the massless roller in flight)", key="damping_ratio")
    t_deg = task.t_deg if t_deg is None else t_deg
    lam, zeta, H, target, T = follower_data(task, speed_rpm, t_deg)
    phi = task.closure_force_N * T**2 / (task.mass_kg * H)
    gap = task.backlash_mm * 1e-3 / H
    end = 1.0 + dwell_length(lam, t_deg)[0]

    law = law_path(task.law)

    def path(xi):
        S, dS, ddS = (float(v[0]) for v in law(xi))
        return (S, dS, ddS) if xi <= 1.0 else (1.0, 0.0, 0.0)

    def driven(offset):
        def f(xi, y):
            S, dS, _ = path(xi)
            return [y[1], -2 * zeta * lam * (y[1] - dS) - lam * lam * (y[0] - S - offset)]
        return f

    def force(xi, y, offset):        # N / (m H / T^2) on a wall
        return driven(offset)(xi, y)[1] + phi

    def free(xi, y):                 # X, X', R: C under the closure alone, the roller through the link
        return [y[1], -phi, y[1] - (lam * lam * (y[2] - y[0]) + phi) / (2 * zeta * lam)]

    def plate(xi, y):
        return y[0] - target
    plate.terminal, plate.direction = True, 1

    xi, y, wall, flights = 0.0, np.zeros(2), 1, []
    for _ in range(MAX_SWITCHES):
        offset = 0.0 if wall == 1 else gap
        if wall * force(xi, y, offset) >= 0:           # the wall holds it: driven
            def off(u, z, o=offset):
                return force(u, z, o)
            off.terminal, off.direction = True, -wall
            run, hit = _run(driven(offset), xi, y, end, (plate, off), rtol)
            if run is None or hit is None:
                return _ended(run, flights)
            xi, y = hit[1], hit[2]
            if hit[0] == 0:
                return GrooveRise(xi, float(y[1]) * H / T, tuple(flights), Status.SOLVED, "C meets its plate")
        S = path(xi)[0]
        z0 = np.r_[y, S + offset]                       # the roller leaves its wall from the wall

        def other(u, z, o=gap if wall == 1 else 0.0):
            return z[2] - path(u)[0] - o

        def back(u, z, o=offset):
            return z[2] - path(u)[0] - o
        other.terminal, other.direction = True, wall
        back.terminal, back.direction = True, -wall
        start = xi
        run, hit = _run(free, xi, z0, end, (plate, other, back), rtol)
        if run is None or hit is None:
            return _ended(run, flights)
        xi, z = hit[1], hit[2]
        if hit[0] == 0:
            return GrooveRise(xi, float(z[1]) * H / T, tuple(flights), Status.SOLVED, "C meets its plate in flight")
        landed = -wall if hit[0] == 1 else wall
        speed = abs(free(xi, z)[2] - path(xi)[1]) * H / T
        flights.append((start, xi, wall, landed, speed))
        y, wall = z[:2], landed
    return GrooveRise(None, 0.0, tuple(flights), Status.LIMIT, f"stopped after {MAX_SWITCHES} switches (a count)")


def _run(rhs, xi0, y0, end, events, rtol):
    """(solve_ivp run, (event index, xi, state) of the first terminal event or None), split at
    xi = 1 where the path's acceleration may jump; run None when the integrator failed."""
    xi, y = xi0, np.asarray(y0, float)
    for stop in ([1.0, end] if xi0 < 1.0 else [end]):
        run = solve_ivp(rhs, (xi, stop), y, method="DOP853", rtol=rtol, atol=rtol * 1e-3, events=events)
        if from_ivp(run.status) is not Status.SOLVED:
            return None, None
        hits = [(float(ts[0]), k, np.asarray(ys[0])) for k, (ts, ys) in enumerate(zip(run.t_events, run.y_events))
                if len(ts)]
        if hits:
            when, k, state = min(hits, key=lambda h: h[0])
            return run, (k, when, state)
        xi, y = stop, run.y[:, -1]
    return run, None


def _ended(run, flights):
    if run is None:
        return GrooveRise(None, 0.0, tuple(flights), Status.FAILED, "DOP853 failed")
    return GrooveRise(None, 0.0, tuple(flights), Status.SOLVED, "C does not reach its plate in the followed window")


def rebound_with_backlash_mm(task: LeverStop, speed_rpm, t_deg=None):
    """(first rebound [mm] from the hybrid's v0, the hybrid's GrooveRise): eq. (2) on the approach
    the backlash gives (closed form, solvers/stop_impact/response.py), whether or not a crossover
    comes before the plate (the chain, solvers/stop_impact/law.py, takes it only then)."""
    rise = follow_groove(task, speed_rpm, t_deg)
    if rise.status is not Status.SOLVED or rise.contact_xi is None:
        return math.nan, rise
    return closed_form_amplitude_m(task.impact(speed_rpm, t_deg, v0_m_s=rise.approach_velocity_m_s))[0] * 1e3, rise
