"""The extremes of a quantity over the cam's turn: the largest sample, polished by a bounded
scalar search between its neighbours (the extreme of a smooth curve lies between samples)."""
import math

import numpy as np

POLISH_XTOL_RAD = 1e-10


def polished_min(fun, theta, values, where=None) -> tuple[float, float]:
    """(least value, its cam angle [rad]) of `fun(theta_array) -> values` over the samples
    `theta` (restricted to `where`), polished between the neighbours of the least sample;
    (inf, nan) when no sample is allowed."""
    from scipy.optimize import minimize_scalar

    allowed = np.ones(theta.size, bool) if where is None else np.asarray(where, bool)
    masked = np.where(allowed, values, np.inf)
    if not np.isfinite(masked).any():
        return math.inf, math.nan
    i = int(np.argmin(masked))
    lo, hi = theta[max(i - 1, 0)], theta[min(i + 1, theta.size - 1)] if i + 1 < theta.size else 2 * math.pi
    cap = masked[i] + abs(masked[i]) + 1.0      # a finite stand-in where `fun` is masked (inf): Brent's fit stays finite
    best = minimize_scalar(lambda t: min(float(fun(np.array([t]))[0]), cap), bounds=(lo, hi), method="bounded",
                           options={"xatol": POLISH_XTOL_RAD})
    if best.success and best.fun < masked[i]:
        return float(best.fun), float(best.x) % (2 * math.pi)
    return float(masked[i]), float(theta[i])
