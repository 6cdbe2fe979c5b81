"""A polynomial force law from load-travel data of a testing machine (paper 001, eq. (1)).

The paper fits the Instron diagram of an expanded-graphite sheet by least squares over 60
points: a quartic through the origin, eq. (1), with the largest relative errors 8.6 % and 4.5 %
on its two segments (Fig. 6); a combination of straight lines and parabolas erred by up to 38 %.
`fit_force` does the same fit for any degree 1-6 and reports the largest relative error on each
segment of the travel. Reading a testing machine's CSV is `mechopt.force_data`'s job (a solver
never reads a file).
"""

import numpy as np

from mechopt.kit.errors import ModelError, SettingError
from mechopt.kit.result import Clock, Result, Status

__all__ = ["fit_force"]

SMALL_LOAD = 0.05          # relative errors are taken where |load| >= 5 % of the largest load


def fit_force(travel_mm, load_N, degree: int, *, segments: int = 2, through_origin: bool = True) -> Result:
    """Least-squares polynomial F(X) = sum_k c_k X^k, k = 1..degree (k = 0 too unless
    `through_origin`), and its largest relative error on each of `segments` equal spans of X.

    Parameters
    ----------
    travel_mm : tool travel X [mm].  load_N : measured force [N].
    degree : 1 to 6.  segments : spans of the travel on which errors are reported (the paper: 2).
    through_origin : no constant term (no force before contact), as eq. (1).

    Returns
    -------
    Result with values ``c<k>_N_per_mm<k>`` (coefficients), ``max_rel_error_seg<j>`` (largest
    |fit - load| / |load| on segment j, over points whose load is at least 5 % of the largest, so
    that the first touch does not divide by ~0), ``max_rel_error`` and ``rms_N``. INACCURATE when
    the normal equations are rank-deficient (too few distinct travels for the degree).

    Example: ``fit_force(x, f, 4).values["c4_N_per_mm4"]`` recovers eq. (1)'s X^4 coefficient from its data.
    """
    x = np.asarray(travel_mm, dtype=float).ravel()
    f = np.asarray(load_N, dtype=float).ravel()
    if isinstance(degree, bool) or not isinstance(degree, (int, np.integer)) or not 1 <= degree <= 6:
        raise SettingError(f"degree={degree!r}: allowed 1, 2, 3, 4, 5 or 6", key="degree")
    if isinstance(segments, bool) or not isinstance(segments, (int, np.integer)) or segments < 1:
        raise SettingError(f"segments={segments!r}: must be an integer >= 1", key="segments")
    if x.shape != f.shape:
        raise ModelError(f"travel_mm has {x.size} values but load_N has {f.size}; give one load per travel",
                         key="load_N")
    if not (np.all(np.isfinite(x)) and np.all(np.isfinite(f))):
        raise ModelError("travel_mm and load_N must be finite numbers (found NaN or inf)", key="load_N")
    if not np.any(f):
        raise ModelError("load_N is zero everywhere: there is no force law to fit", key="load_N")
    powers = np.arange(1 if through_origin else 0, degree + 1)
    if x.size < powers.size:
        raise ModelError(f"{x.size} points cannot fix {powers.size} coefficients of degree {degree}; "
                         f"give at least {powers.size}", key="travel_mm")
    clock = Clock()
    A = x[:, None] ** powers[None, :]
    coeffs, _, rank, _ = np.linalg.lstsq(A, f, rcond=None)
    fitted = A @ coeffs
    values = {f"c{k}_N_per_mm{k}" if k else "c0_N": float(c) for k, c in zip(powers, coeffs)}
    values["rms_N"] = float(np.sqrt(np.mean((fitted - f) ** 2)))
    edges = np.linspace(x.min(), x.max(), segments + 1)
    relevant = np.abs(f) >= SMALL_LOAD * np.abs(f).max()
    worst = []
    for j in range(segments):
        inside = (x >= edges[j]) & ((x < edges[j + 1]) if j < segments - 1 else (x <= edges[j + 1])) & relevant
        if inside.any():
            values[f"max_rel_error_seg{j + 1}"] = float(np.max(np.abs(fitted[inside] - f[inside]) / np.abs(f[inside])))
            worst.append(values[f"max_rel_error_seg{j + 1}"])
    if worst:
        values["max_rel_error"] = max(worst)
    status = Status.SOLVED if rank == powers.size else Status.INACCURATE
    message = (f"least squares, degree {degree}, {x.size} points" if status is Status.SOLVED else
               f"rank {rank} < {powers.size} coefficients: too few distinct travels for degree {degree}")
    return clock.result(status, values, message,
                        diagnostics={"segment_edges_mm": edges.tolist(), "points": int(x.size)})
