"""The least base radius of a cam: the classic design question. A roller follower's largest
pressure angle must stay within `max_pressure_angle_deg`; a flat face's profile must keep its
radius of curvature above `min_profile_radius_mm` (no cusp: rho = Rb + s + s'' > 0 for a
translating face, Norton, *Design of Machinery*, 5th ed., sec. 8.9). The search: a grid over
the scene's bounds [base_radius_min_mm, base_radius_max_mm] finds the least feasible grid point
(whether or not feasibility is monotone in the base radius), then bisection between it and the
grid point below narrows the answer to `tol_mm`; each step is counted. The answer is the
feasible end of the last bracket, certified by evaluating the criterion there again on other,
denser samples."""
import math

import numpy as np

from mechopt.kit.errors import ModelError, require
from mechopt.kit.result import Clock, Result, Status
from mechopt.kit.settings import Annotated, Interval
from mechopt.models.cam_followers import CamFollower
from mechopt.solvers.cam.sizing import Samples, convex_min, pressure_peaks

__all__ = ["least_base_radius"]

CERTIFY = 4         # the answer is checked again on this many times the search's samples


def least_base_radius(task: CamFollower, *, samples: Samples = 3600,
                      grid: Annotated[int, Interval(ge=2, le=10_000)] = 41,
                      tol_mm: Annotated[float, Interval(gt=0, le=10)] = 1e-4,
                      iterations: Annotated[int, Interval(ge=1, le=200)] = 60) -> Result:
    """The least base radius [mm] within the task's bounds meeting its criterion (module
    docstring), with the criterion's value there (`pressure_angle_at_answer_deg` or
    `profile_radius_at_answer_mm`), the bracket's width and the evaluations counted.

    INFEASIBLE when no grid point meets the criterion, naming the least achievable pressure
    angle (or the largest profile radius) and its base radius; LIMIT when `iterations` bisection
    steps leave the bracket wider than `tol_mm` (the feasible end is still returned).
    """
    clock = Clock()
    lo, hi = task.base_radius_min_mm, task.base_radius_max_mm
    require(hi > 0, "least_base_radius needs base_radius_min_mm and base_radius_max_mm (0 < min < max)",
            key="base_radius_max_mm")
    theta = np.linspace(0.0, 2 * math.pi, samples, endpoint=False)
    lift = task.lift(theta)
    flat = task.face == "flat"
    name, limit = (("profile_radius_at_answer_mm", task.min_profile_radius_mm) if flat
                   else ("pressure_angle_at_answer_deg", task.max_pressure_angle_deg))
    count = [0]

    def measure(base, theta=theta, lift=lift):
        """The criterion's value at `base` (the profile's least radius, or the largest pressure
        angle; a layout the follower cannot reach: nan)."""
        count[0] += 1
        try:
            c = task.curves(theta, base, lift=lift)
            if flat:
                return convex_min(task, theta, c.profile_radius_mm, "profile", base)[0]
            peaks = pressure_peaks(task, theta, c, lift[1], base)
            return max(v for k, v in peaks.items() if k.startswith("max_pressure_angle"))
        except ModelError:
            return math.nan

    def ok(value):
        return (value > limit) if flat else (value <= limit)

    def values_of(good, certified, bad, steps, evaluations):
        return {"least_base_radius_mm": good, name: certified, "bracket_mm": (good - bad) if bad is not None else 0.0,
                "evaluations": float(evaluations), "bisection_steps": float(steps)}

    bases = np.linspace(lo, hi, grid)
    found = [measure(b) for b in bases]
    arrays = {"grid_base_radius_mm": bases, ("grid_profile_radius_mm" if flat else "grid_pressure_angle_deg"):
              np.array(found)}     # nan: a layout the follower cannot reach
    feasible = [i for i, v in enumerate(found) if math.isfinite(v) and ok(v)]
    if not feasible:
        reached = [(v, b) for v, b in zip(found, bases) if math.isfinite(v)]
        best = (max if flat else min)(reached, default=(math.nan, hi))
        what = (f"the profile's radius of curvature stays at or below min_profile_radius_mm={limit:g} (largest "
                f"{best[0]:.4g} mm, at base radius {best[1]:.4g} mm)" if flat else
                f"no base radius keeps the pressure angle within max_pressure_angle_deg={limit:g}: the least "
                f"achievable is {best[0]:.4f} deg, at base radius {best[1]:.4g} mm")
        values = {"evaluations": float(count[0])} | (
            {"least_achievable_" + ("profile_radius_mm" if flat else "pressure_angle_deg"): best[0],
             "at_base_radius_mm": float(best[1])} if math.isfinite(best[0]) else {})
        return clock.result(Status.INFEASIBLE, values, violated=("base_radius",), arrays=arrays,
                            message=f"within base_radius_min_mm={lo:g} ... base_radius_max_mm={hi:g}: {what}")
    first = feasible[0]
    good = float(bases[first])
    bad = float(bases[first - 1]) if first > 0 else None
    steps = 0
    while bad is not None and good - bad > tol_mm and steps < iterations:
        mid = 0.5 * (good + bad)
        v = measure(mid)
        steps += 1
        if math.isfinite(v) and ok(v):
            good = mid
        else:
            bad = mid
    dense = np.linspace(0.0, 2 * math.pi, CERTIFY * samples, endpoint=False)     # other samples than the search's
    certified = measure(good, dense, task.lift(dense))
    if not ok(certified):
        return clock.result(Status.INACCURATE, values_of(good, certified, bad, steps, count[0]), arrays=arrays,
                            message=f"base radius {good:.6g} mm met the limit on {samples} samples but not on "
                            f"{CERTIFY * samples} ({certified:.6g}): more samples")
    values = values_of(good, certified, bad, steps, count[0])
    if bad is None:
        return clock.result(Status.SOLVED, values, arrays=arrays, message=f"the least bound base_radius_min_mm={lo:g} already meets "
                            f"the limit ({certified:.4f}); the least base radius may be smaller")
    if good - bad > tol_mm:
        return clock.result(Status.LIMIT, values, arrays=arrays, message=f"{iterations} bisection steps left the bracket "
                            f"{good - bad:.3g} mm > tol_mm={tol_mm:g}; the feasible end is returned")
    return clock.result(Status.SOLVED, values, arrays=arrays, message=f"least base radius {good:.4f} mm (within {good - bad:.2g} "
                        f"mm), {count[0]} evaluations")
