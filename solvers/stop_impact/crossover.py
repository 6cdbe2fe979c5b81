"""A grooved cam's roller crossing to the other wall (closure "groove", models/stop_impact.py):
where the contact force N changes sign, the flight across the backlash and the impact it ends in.

In a form-closed (grooved) cam the roller is driven by one wall while N = F + m x'' has that
wall's sign; where N changes sign the other wall must take over, and the roller first crosses
the groove's play (the backlash): an impact at the other wall, the "crossover shock" of
form-closed cams (Norton, *Cam Design and Manufacturing Handbook*, 2nd ed., Industrial Press
2009, ch. 10; Rothbart, *Cam Design Handbook*, ch. 11), not a lift-off.

The flight (stated model; in the rise's own time xi, X = x / H, lambda, zeta as in
models/cam_follower.py, phi = F T^2 / (m H) the closure force F in those units): the roller is
massless, so while it touches neither wall the link carries the closure force alone: C flies
under it, X'' = -phi, and the roller R follows C through the link's damper,
lambda^2 (R - X) + 2 zeta lambda (R' - X') = -phi, in closed form:

    X(s) = X0 + X0' s - phi s^2 / 2,   R - X = -phi / lambda^2 + (R0 - X0 + phi / lambda^2) exp(-lambda s / (2 zeta))

(s = xi - xi_c; R0 on the wall it leaves). It lands where R meets the other wall (the pitch path
S shifted by the backlash delta / H, delta reduced to C's travel) or its own again; the impact
speed is |R' - S'| H / T there. The landing is inelastic for the massless roller (it takes the
wall's motion) and leaves C's state as it is; a wall that cannot hold N with that state sends
the roller off again at once. Each flight starts from the chain's state at its crossover (the
walls taken without backlash before it): the first crossover's flight is this model's exact
one, later ones start from the backlash-free path. solvers/stop_impact/groove.py follows the
whole rise with the backlash (and checks the first flight by DOP853).
"""
import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq


def law_path(law):
    """xi (array) -> (S, S', S'') of the law over the rise, the dwell's (1, 0, 0) past it: a
    synthesised spline's B-spline and its two derivatives built once (its `values` builds them on
    every call, 2 ms: the hybrid's integrator calls it thousands of times), a library law's
    CasADi function as the chain has it."""
    from mechopt.models.cam_follower import law_values
    from mechopt.models.cam_law import SplineLaw
    if not isinstance(law, SplineLaw):
        return lambda xi: law_values(law, xi)
    from scipy.interpolate import BSpline
    spline = BSpline(np.asarray(law.knots), np.asarray(law.coefficients), law.degree, extrapolate=False)
    parts = (spline, spline.derivative(1), spline.derivative(2))

    def path(xi):
        xi = np.atleast_1d(np.asarray(xi, float))
        inside, after = np.clip(xi, 0.0, 1.0), xi > 1.0
        S, dS, ddS = (np.nan_to_num(p(inside)) for p in parts)
        return np.where(after, 1.0, S), np.where(after, 0.0, dS), np.where(after, 0.0, ddS)
    return path


MAX_CROSSOVERS = 1000          # per rise: a count limit (a roller rattling in its groove), said when hit
WALL = {1: "inner", -1: "outer"}


@dataclass(frozen=True)
class Crossover:
    """One crossover: where N changes sign (xi, a fraction of the rise, > 1 in the dwell), the
    wall the roller leaves ("inner": the driving wall, N >= 0; "outer": the other one), where it
    lands and on which wall, and the impact speed there [m/s] (None: the followed window ended
    before the roller landed)."""
    xi: float
    leaves: str
    lands_xi: float | None
    lands_on: str | None
    impact_m_s: float | None

    def angle_deg(self, t_deg: float) -> float:
        """The cam angle of the crossover from the rise's start [deg]."""
        return self.xi * t_deg


@dataclass(frozen=True)
class Groove:
    """One rise's data for its flights: lambda, zeta, phi (closure), gap = delta / H, the rise's
    time T [s] and stroke H [m], and `path(xi)` -> (S, S') of the walls' pitch path (arrays)."""
    lam: float
    zeta: float
    phi: float
    gap: float
    T: float
    H: float
    path: object

    def force(self, xi, X, dX, wall):
        """N / (m H / T^2) on wall `wall` (+1 inner: path S; -1 outer: S + gap) for C at (X, X')."""
        S, dS = self.path(np.atleast_1d(xi))
        offset = 0.0 if wall == 1 else self.gap
        return float(-2 * self.zeta * self.lam * (dX - dS[0]) - self.lam**2 * (X - S[0] - offset) + self.phi)

    def flight(self, xi0, X0, dX0, wall, grid):
        """(landing xi, wall landed on, impact speed [m/s], X, X' there) of the flight from the
        crossover at xi0 leaving `wall` with C at (X0, X0') (module docstring); the landing
        bracketed on `grid` (xi, increasing), polished by brentq; None where the grid ends first."""
        lam, zeta, phi = self.lam, self.zeta, self.phi
        here = 0.0 if wall == 1 else self.gap
        there = self.gap if wall == 1 else 0.0
        u0 = float(self.path(np.atleast_1d(xi0))[0][0]) + here - X0 + phi / lam**2
        rate = lam / (2 * zeta)

        def state(xi):          # X, X', R, R'
            s = np.asarray(xi, float) - xi0
            X, dX = X0 + dX0 * s - phi * s * s / 2, dX0 - phi * s
            decay = np.exp(-rate * s)
            return X, dX, X - phi / lam**2 + u0 * decay, dX - rate * u0 * decay

        def gaps(xi):           # towards the other wall (> 0 before it) and off its own (> 0 while away)
            S = self.path(np.atleast_1d(xi))[0]
            R = state(xi)[2]
            return wall * (S + there - R), wall * (R - S - here)
        x = np.r_[xi0, grid[grid > xi0 + 1e-9]]       # a sample at the start itself: its own wall
        if x.size < 2:
            return None
        to_other, off_own = gaps(x)
        off_own[0] = 1.0                        # it starts on its own wall
        bad = np.flatnonzero((to_other[1:] <= 0) | (off_own[1:] <= 0))
        if not bad.size:
            return None
        i = int(bad[0])
        other = to_other[i + 1] <= 0 and (off_own[i + 1] > 0 or to_other[i + 1] <= off_own[i + 1])
        k = 0 if other else 1
        f = lambda xi: gaps(np.array([xi]))[k][0]       # noqa: E731
        lo = x[i] if f(x[i]) > 0 else x[i] + 1e-15 * max(1.0, x[i])
        land = x[i + 1] if f(x[i + 1]) == 0 else brentq(f, lo, x[i + 1], xtol=1e-15)
        X, dX, _, dR = (float(v) for v in state(land))
        dS = float(self.path(np.atleast_1d(land))[1][0])
        return land, (-wall if other else wall), abs(dR - dS) * self.H / self.T, X, dX


def crossovers(xi, force_N, locate, groove: Groove):
    """The crossovers along one rise, in order. From the driving wall, each sign change of N on
    the chain's samples that the roller's wall cannot give starts a flight (`Groove.flight`),
    `locate(j)` -> (xi, X, X') of the chain where N changes sign between samples j - 1 and j.
    The wall it lands on holds it (C's state at the landing: else a flight again at once) until N
    on the samples leaves that wall's sign. Returns (crossovers, whether MAX_CROSSOVERS was hit)."""
    force = np.asarray(force_N, float)
    out, wall, pos, start, last = [], 1, -math.inf, None, None
    while len(out) < MAX_CROSSOVERS:
        if start is None:
            wrong = np.flatnonzero((xi > pos) & (wall * force < 0))
            if not wrong.size:
                return out, False
            start = locate(int(wrong[0]))
            if start[0] < pos:              # the path's sign changed within the last flight: off at its landing
                start = last
        x0, X0, dX0 = start
        landed = groove.flight(x0, X0, dX0, wall, xi)
        if landed is None:
            out.append(Crossover(float(x0), WALL[wall], None, None, None))
            return out, False
        pos, new, speed, X, dX = landed
        out.append(Crossover(float(x0), WALL[wall], pos, WALL[new], speed))
        wall, last = new, (pos, X, dX)
        start = last if wall * groove.force(pos, X, dX, wall) < 0 else None
    return out, True
