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

C meets its plate where X = 1 - preload / H: the approach velocity v0 with the backlash. Each
phase is linear, so `follow_groove` takes each by its exact solution (`follow_groove_exact`):
on a wall the follower's error e = X - S - offset by Duhamel's integral from the phase's own start (the batch path's
integral I, solvers/stop_impact/rise_batch.py: e = -Im(e^{mu xi} (I(xi) - K)) / w, the constant
K set by C's state at the phase's start), in flight the closed form of
solvers/stop_impact/crossover.py; each event (N's sign change, the plate, a landing) bracketed
on the rise's 1001 samples and the dwell's, polished by brentq (xtol 1e-15). Where that path
does not apply (the batch path's limits: zeta >= 1, a law of unknown joins, zeta lambda past
EXP_LIMIT) and as the independent reference in the tests: `follow_groove_ivp`, scipy's DOP853
with its event location, restarted at each switch. Both follow at most MAX_SWITCHES phases (a
count limit, said when hit). The damping ratio must be > 0 (with none the massless roller has
no motion of its own in flight).
"""
import math
from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from mechopt.kit.errors import ModelError
from mechopt.kit.result import Status, from_ivp
from mechopt.models.stop_impact import LeverStop
from mechopt.solvers.stop_impact.cam_follower import dwell_length, follower_data, groove_of
from mechopt.solvers.stop_impact.crossover import law_path
from mechopt.solvers.stop_impact.response import closed_form_amplitude_m
from mechopt.solvers.stop_impact.rise_batch import (
    EXP_LIMIT,
    POINTS,
    interval_integrals,
    law_joins,
    law_parts,
    rise_integrals,
)

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


def _check(task: LeverStop):
    if task.closure != "groove":
        raise ModelError(f"closure={task.closure!r}: the hybrid groove model needs closure='groove'", key="closure")
    if "damping" not in task.effects or not task.damping_ratio:
        raise ModelError("the hybrid groove model needs the effect 'damping' with damping_ratio > 0 (the link's "
                         "damper moves the massless roller in flight)", key="damping_ratio")


def follow_groove(task: LeverStop, speed_rpm, t_deg=None) -> GrooveRise:
    """The rise of `task` (closure "groove") at `speed_rpm` and `t_deg` with its backlash, each
    phase by its exact solution (module docstring); `follow_groove_ivp` where that path does not
    apply."""
    exact = follow_groove_exact(task, speed_rpm, t_deg)
    return follow_groove_ivp(task, speed_rpm, t_deg) if exact is None else exact


def follow_groove_exact(task: LeverStop, speed_rpm, t_deg=None) -> GrooveRise | None:
    """`follow_groove` by the exact phases alone: None where they do not apply (module docstring)."""
    _check(task)
    t_deg = task.t_deg if t_deg is None else t_deg
    lam, zeta, H, target, T = follower_data(task, speed_rpm, t_deg)
    walls = ExactWalls.of(task, lam, zeta, H, T, dwell_length(lam, t_deg)[0])
    if walls is None:
        return None
    flights_of = groove_of(task, lam, zeta, H, T)
    xi, X, dX, wall, flights = 0.0, 0.0, 0.0, 1, []
    for _ in range(MAX_SWITCHES):
        if wall * walls.force(xi, X, dX, wall) >= 0:          # the wall holds it: driven
            hit = walls.ride(xi, X, dX, wall, target)
            if hit is None:
                return _ended(False, flights)
            k, xi, X, dX = hit
            if k == 0:
                return GrooveRise(xi, dX * H / T, tuple(flights), Status.SOLVED, "C meets its plate")
        landed = flights_of.flight(xi, X, dX, wall, walls.nodes)
        reach = xi + _plate_in_flight(X, dX, flights_of.phi, target)
        if reach <= (walls.nodes[-1] if landed is None else landed[0]):
            return GrooveRise(reach, (dX - flights_of.phi * (reach - xi)) * H / T, tuple(flights), Status.SOLVED,
                              "C meets its plate in flight")
        if landed is None:
            return _ended(False, flights)
        land, new, speed, X, dX = landed
        flights.append((xi, land, wall, new, speed))
        xi, wall = land, new
    return GrooveRise(None, 0.0, tuple(flights), Status.LIMIT, f"stopped after {MAX_SWITCHES} switches (a count)")


def _plate_in_flight(X0, dX0, phi, target) -> float:
    """How long after leaving its wall C, flying under the closure alone (X'' = -phi), meets its
    plate rising (inf: it does not): the smaller root of X0 + X0' s - phi s^2 / 2 = target."""
    rest, disc = target - X0, dX0 * dX0 - 2.0 * phi * (target - X0)
    if rest <= 0 or dX0 <= 0 or disc < 0:
        return math.inf
    return 2.0 * rest / (dX0 + math.sqrt(disc))


class ExactWalls:
    """C driven by one wall of one rise, exactly (module docstring): the rise's samples and the
    dwell's (`nodes`), Duhamel's integral I at each of them, and the events of a wall phase."""

    def __init__(self, law, joins, lam, zeta, phi, gap, dwell):
        self.law, self.joins, self.lam, self.zeta, self.phi, self.gap = law, joins, lam, zeta, phi, gap
        self.mu = np.array([complex(-zeta * lam, lam * math.sqrt(1.0 - zeta * zeta))])
        self.grid, I_rise = rise_integrals(law, joins, self.mu)
        I_rise = I_rise[0]
        tail = 1.0 + dwell * self.grid[1:]
        self.nodes = np.r_[self.grid, tail]
        self.I_nodes = np.r_[I_rise, np.full(tail.size, I_rise[-1])]
        self.S_nodes, self.dS_nodes = law_parts(law, self.nodes)[:2]

    @classmethod
    def of(cls, task, lam, zeta, H, T, dwell):
        """The exact walls of one rise, None where the batch path's limits exclude it."""
        joins = law_joins(task.law)
        if (joins is None or np.any(np.diff(joins) <= 1.0 / (POINTS - 1)) or not 0.0 < zeta < 1.0
                or zeta * lam >= EXP_LIMIT):
            return None
        phi = task.closure_force_N * T**2 / (task.mass_kg * H)
        return cls(task.law, joins, lam, zeta, phi, task.backlash_mm * 1e-3 / H, dwell)

    def integral(self, xi: float) -> complex:
        """I(xi) = integral_0^xi e^{-mu s} S''(s) ds: a sample's, and the rest of its cell."""
        if xi >= 1.0:
            return complex(self.I_nodes[POINTS - 1])
        k = min(int(np.searchsorted(self.grid, xi, side="right")) - 1, POINTS - 2)
        rest = interval_integrals(self.law, self.joins, self.mu, self.grid[k:k + 1], np.array([xi]))
        return complex(self.I_nodes[k] + rest[0])

    def _parts(self, xi: float):
        S, dS = (float(v[0]) for v in law_parts(self.law, np.array([xi]))[:2])
        return S, dS

    def force(self, xi, X, dX, wall) -> float:
        """N / (m H / T^2) on `wall` (+1 inner: S; -1 outer: S + gap) for C at (X, X')."""
        S, dS = self._parts(xi)
        offset = 0.0 if wall == 1 else self.gap
        return -2 * self.zeta * self.lam * (dX - dS) - self.lam**2 * (X - S - offset) + self.phi

    def ride(self, xi0, X0, dX0, wall, target):
        """(0 the plate / 1 N leaving the wall's sign, xi, X, X') of the first event on `wall` from
        C at (X0, X0') at xi0; None where the followed window ends first."""
        mu, w = self.mu[0], self.mu[0].imag
        offset = 0.0 if wall == 1 else self.gap
        S0, dS0 = self._parts(xi0)
        e0, de0 = X0 - S0 - offset, dX0 - dS0
        K = self.integral(xi0) - ((mu.real * e0 - de0) - 1j * w * e0) * np.exp(-mu * xi0)

        def state(xi, I, S, dS):                  # X - target, N wall's sign, X, X'
            turn = np.exp(mu * xi) * (I - K)
            e, de = -turn.imag / w, -(mu * turn).imag / w
            return (S + offset + e - target, wall * (-2 * self.zeta * self.lam * de - self.lam**2 * e + self.phi),
                    S + offset + e, dS + de)

        def at(xi):
            return state(xi, self.integral(xi), *self._parts(xi))
        later = self.nodes > xi0
        x = np.r_[xi0, self.nodes[later]]
        plate, held = state(x, np.r_[self.integral(xi0), self.I_nodes[later]], np.r_[S0, self.S_nodes[later]],
                            np.r_[dS0, self.dS_nodes[later]])[:2]
        cells = [(int(np.argmax(h)), k) for k, h in enumerate(((plate[:-1] <= 0) & (plate[1:] >= 0),
                                                             (held[:-1] >= 0) & (held[1:] <= 0))) if h.any()]
        if not cells:
            return None
        found = []
        for i, k in cells:
            if i == min(cells)[0]:          # an event in a later cell comes after it: not located
                g = (lambda u, k=k: at(u)[k])     # noqa: E731
                found.append((x[i + 1] if g(x[i + 1]) == 0 or g(x[i]) * g(x[i + 1]) > 0
                               else brentq(g, x[i], x[i + 1], xtol=1e-15), k))
        xi, k = min(found)
        _, _, X, dX = at(xi)
        return k, xi, float(X), float(dX)


def follow_groove_ivp(task: LeverStop, speed_rpm, t_deg=None, *, rtol: float = 1e-11) -> GrooveRise:
    """The rise of `task` (closure "groove") at `speed_rpm` and `t_deg` with its backlash by
    DOP853 (module docstring): the exact path's reference, and its stand-in outside its limits."""
    _check(task)
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
                return _ended(run is None, flights)
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
            return _ended(run is None, flights)
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


def _ended(failed, flights):
    """The rise without a contact: the integrator failed (DOP853 only), or the window ended."""
    if failed:
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
