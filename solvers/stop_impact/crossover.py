"""A grooved cam's roller crossing to the other wall (closure "groove", models/stop_impact.py):
where the contact force N changes sign, the flight across the backlash and the impact it ends in.

In a form-closed (grooved) cam the roller is driven by one wall while N = F + m x'' has that
wall's sign; where N changes sign the other wall must take over, and the roller first crosses
the groove's play (the backlash): an impact at the other wall, the "crossover shock" of
form-closed cams (Norton, *Cam Design and Manufacturing Handbook*, 2nd ed., Industrial Press
2009, ch. 10; Rothbart, *Cam Design Handbook*, ch. 11), not a lift-off.

The flight, a stated first-order model (the backlash small against the stroke): from the
crossover the walls go on along the in-contact path, the follower flies free of them, so it
drifts across the play under the force it now lacks: the relative acceleration towards the
other wall is -w N(t) / m (w = +1 leaving the driving wall, -1 leaving the other one; N the
in-contact force the chain computed, reduced mass m at C). From rest relative to the walls at the
crossover, the relative displacement d(t) = double integral of it; the roller lands on the other
wall where d reaches the backlash (its impact speed d'(t) there), or back on its own wall where
d returns to 0 first (the force turned back within the flight). N is taken piecewise linear
between the chain's samples (the flight spans tens of them), each cell integrated exactly, the
landing located in its cell by brentq. What this leaves out (the link's state during the flight,
the offset wall after it) is measured by the hybrid model of solvers/stop_impact/groove.py.
"""
import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

MAX_CROSSOVERS = 1000          # per rise: a count limit (a roller rattling in its groove), said when hit


@dataclass(frozen=True)
class Crossover:
    """One crossover: where N changes sign (xi, a fraction of the rise, > 1 in the dwell), the
    wall the roller leaves ("inner": the driving wall, N >= 0; "outer": the other one), where it
    lands and on which wall, and the impact speed there [m/s] (None: C met its plate, or the
    followed window ended, before the roller landed)."""
    xi: float
    leaves: str
    lands_xi: float | None
    lands_on: str | None
    impact_m_s: float | None

    def angle_deg(self, t_deg: float) -> float:
        """The cam angle of the crossover from the rise's start [deg]."""
        return self.xi * t_deg


WALL = {1: "inner", -1: "outer"}


def flight(xi, force_N, start, wall, *, mass_kg, T_s, backlash_m):
    """(landing xi, landing wall +1 / -1, impact speed [m/s]) of the flight from a crossover at
    `start` (xi) leaving wall `wall` (+1 inner, -1 outer), on the in-contact force `force_N`
    sampled at `xi` (piecewise linear, N(start) = 0 inserted); None where the samples end first."""
    after = xi > start
    x = np.r_[start, xi[after]]
    acc = -wall * np.r_[0.0, np.asarray(force_N, float)[after]] / mass_kg    # towards the other wall [m/s^2]
    if x.size < 2:
        return None
    h = np.diff(x) * T_s
    a0, a1 = acc[:-1], acc[1:]
    w = np.r_[0.0, np.cumsum(0.5 * h * (a0 + a1))]
    d = np.r_[0.0, np.cumsum(w[:-1] * h + h * h * (2 * a0 + a1) / 6)]
    past = np.flatnonzero((d[1:] >= backlash_m) | ((d[1:] <= 0.0) & (w[1:] < 0.0)))
    if not past.size:
        return None
    i = int(past[0])
    other = d[i + 1] >= backlash_m
    goal = backlash_m if other else 0.0

    def gap(tau):
        return d[i] + w[i] * tau + a0[i] * tau**2 / 2 + (a1[i] - a0[i]) * tau**3 / (6 * h[i]) - goal
    lo = 1e-300 if i == 0 else 0.0     # the flight's first instant sits at d = 0 itself
    tau = h[i] if gap(h[i]) == 0 else brentq(gap, lo, h[i], xtol=1e-15 * max(h[i], 1e-300))
    speed = abs(w[i] + a0[i] * tau + (a1[i] - a0[i]) * tau**2 / (2 * h[i]))
    return float(x[i] + tau / T_s), (-wall if other else wall), float(speed)


def crossovers(xi, force_N, locate, *, mass_kg, T_s, backlash_m):
    """The crossovers along one rise, in order: from the driving wall, each sign change of N the
    roller's wall cannot give starts a flight (`flight`); it lands, and the wall it lands on holds
    it until N leaves that wall's sign again. `locate(j)` is the xi where N changes sign between
    samples j - 1 and j (located by the chain). Returns (crossovers, whether MAX_CROSSOVERS was hit)."""
    force = np.asarray(force_N, float)
    out, wall, pos = [], 1, -math.inf
    while len(out) < MAX_CROSSOVERS:
        wrong = np.flatnonzero((xi > pos) & (wall * force < 0))
        if not wrong.size:
            return out, False
        j = int(wrong[0])
        held = wall * np.interp(pos, xi, force) >= 0 if math.isfinite(pos) else True
        start = max(locate(j), pos) if held else pos    # landed on a wall that cannot hold it: off at once
        landed = flight(xi, force, start, wall, mass_kg=mass_kg, T_s=T_s, backlash_m=backlash_m)
        if landed is None:
            out.append(Crossover(float(start), WALL[wall], None, None, None))
            return out, False
        pos, new, speed = landed
        out.append(Crossover(float(start), WALL[wall], pos, WALL[new], speed))
        if new == wall and pos <= start:        # no progress (cannot happen with d > 0 after the start)
            return out, False
        wall = new
    return out, True
