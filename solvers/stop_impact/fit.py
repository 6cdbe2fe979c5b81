"""Every root of the chain's calibration: the stroke H and phase angle t at which
the chain's a(t) at the nominal speed has the published law a = slope t + intercept as its
tangent; what each root predicts, the spread over the roots and over the assumed damping, and
the root that a rule looking at the law alone picks.

The two conditions are a(t; H) = intercept + slope t (C's rebound on the law's line) and
da/dt(t; H) = slope. For each t of a grid the first fixes H (secant from the nearest t's H: a
grows with H, the approach velocity scaling with the stroke); the second's residual is then scanned over t, and each sign change is polished by brentq. Points
where the roller leaves its cam carry no rise and are gaps of the scan (reported).
"""
import dataclasses
import math

import numpy as np
from scipy.optimize import brentq

from mechopt.kit.errors import SettingError
from mechopt.kit.result import Clock, Result, Status
from mechopt.kit.settings import Annotated, Interval, NonNegative, Positive, Tolerance
from mechopt.models.stop_impact import LeverStop, speed_tag
from mechopt.solvers.stop_impact.law import RollerLeftCam, amplitude_law, approach_velocity_m_s, rebound_amplitude_mm

ROOT_AGREEMENT_REL = 1e-7       # the polished root's tangent against the law, relative


def fit_roots(task: LeverStop, *, t_min_deg: Annotated[float, Interval(gt=0, lt=360)] = 25.0,
              t_max_deg: Annotated[float, Interval(gt=0, lt=360)] = 50.0,
              t_step_deg: Annotated[float, Interval(gt=0, le=5)] = 0.5,
              stroke_min_mm: Positive = 5.0, stroke_max_mm: Positive = 80.0,
              damping_low: NonNegative = 0.02, damping_high: NonNegative = 0.10,
              xtol_deg: Tolerance = 1e-7) -> Result:
    """Every (stroke_mm, t_deg) in the box [stroke_min_mm, stroke_max_mm] x [t_min_deg, t_max_deg]
    at which the chain's tangent at `speed_nominal_rpm` is the law (`law_slope_mm_per_deg`,
    `law_intercept_mm`), and the rebounds (`rebound_mm_<rpm>`) and impact forces at `speeds_rpm`
    under each: at the chosen root, their least and largest over the roots (`rebound_roots_min_mm_370`,
    `..._roots_max_...`) and, at the chosen root, over the damping ratios `damping_low` ...
    `damping_high` (`_damping_min`, `_damping_max`).

    The rule that picks the root looks at the law only, never at a rebound: the root whose t is
    nearest t0 = intercept / (2 |slope|), the tangent point the law has if the rebound is
    proportional to n / t (stop-impact/law-paper-reading). SOLVED when every root's own tangent
    (amplitude_law) meets the law within 1e-7; a root at a scan gap's edge is reported in the
    message (a root may hide in a gap: there the roller leaves its cam).
    """
    task.need("law_slope_mm_per_deg", "law_intercept_mm", "speed_nominal_rpm")
    task.need_effect("cam_drive")
    if not (t_min_deg < t_max_deg and stroke_min_mm < stroke_max_mm):
        raise SettingError(f"empty box: t_min_deg={t_min_deg:g} must be below t_max_deg={t_max_deg:g} and "
                           f"stroke_min_mm={stroke_min_mm:g} below stroke_max_mm={stroke_max_mm:g}", key="t_min_deg")
    clock = Clock()
    fit = _Fit(task, stroke_min_mm, stroke_max_mm)
    grid = np.arange(t_min_deg, t_max_deg + 0.5 * t_step_deg, t_step_deg)
    scan = [fit.residual_or_gap(t) for t in grid]
    gaps = [float(t) for t, r in zip(grid, scan) if r is None]
    roots = []
    for i in range(len(grid) - 1):
        lo, hi = scan[i], scan[i + 1]
        if lo is None or hi is None or lo * hi > 0 or (lo == 0 and i > 0):
            continue
        t = brentq(fit.residual, grid[i], grid[i + 1], xtol=xtol_deg, rtol=1e-14)
        roots.append((t, fit.stroke_for(t)))
    values = {"roots": float(len(roots)), "t0_deg": task.law_intercept_mm / (2 * abs(task.law_slope_mm_per_deg))}
    if not roots:
        return clock.result(Status.INFEASIBLE, values, violated=("law_tangent",),
                            message=f"no root in the box (gaps where the roller leaves its cam: {_span(gaps)})")
    worst = 0.0
    for k, (t, H) in enumerate(roots, 1):
        slope, intercept = amplitude_law(fit.at(H, t))
        worst = max(worst, abs(slope / task.law_slope_mm_per_deg - 1), abs(intercept / task.law_intercept_mm - 1))
        values |= {f"root_t_deg_{k}": t, f"root_stroke_mm_{k}": H}
    chosen = min(range(len(roots)), key=lambda k: abs(roots[k][0] - values["t0_deg"]))
    values |= {"chosen_root": float(chosen + 1), "max_tangent_residual_rel": worst}
    table = [fit.predictions(H, t) for t, H in roots]
    swings = [fit.predictions(*roots[chosen][::-1], damping_ratio=z) for z in (damping_low, damping_high)]
    for name in table[0]:
        over_roots = [row[name] for row in table]
        over_damping = [table[chosen][name]] + [row[name] for row in swings]
        values |= {name: table[chosen][name], _spread(name, "roots_min"): np.nanmin(over_roots),
                   _spread(name, "roots_max"): np.nanmax(over_roots), _spread(name, "damping_min"): np.nanmin(over_damping),
                   _spread(name, "damping_max"): np.nanmax(over_damping)}
    edge = [t for t, _ in roots if any(abs(t - g) <= t_step_deg for g in gaps)]
    status = Status.SOLVED if worst <= ROOT_AGREEMENT_REL else Status.INACCURATE
    message = (f"{len(roots)} roots in t [{t_min_deg:g}, {t_max_deg:g}] deg x stroke [{stroke_min_mm:g}, "
               f"{stroke_max_mm:g}] mm; chosen {chosen + 1} (t nearest t0 = {values['t0_deg']:.4g} deg); tangents "
               f"meet the law to {worst:.1e}" + (f"; the roller leaves its cam at t in {_span(gaps)}" if gaps else "")
               + (f"; roots next to that gap: {', '.join(f'{t:.3f}' for t in edge)} deg" if edge else ""))
    diagnostics = {"roots": [{"t_deg": t, "stroke_mm": H} | row for (t, H), row in zip(roots, table)], "gaps_deg": gaps}
    arrays = {"t_deg": [t for t, _ in roots], "stroke_mm": [H for _, H in roots]}     # one row per root
    arrays |= {name: [row[name] for row in table] for name in table[0]}
    return clock.result(status, values, message=message, diagnostics=diagnostics, arrays=arrays)


class _Fit:
    """The two fit conditions for one task, the stroke box and the scan's last stroke (a warm start)."""

    def __init__(self, task, stroke_min_mm, stroke_max_mm):
        self.task, self.box, self.speed = task, (stroke_min_mm, stroke_max_mm), task.speed_nominal_rpm
        self.known = {}                 # t -> H found: the nearest is the next search's start

    def at(self, stroke_mm, t_deg):
        return dataclasses.replace(self.task, stroke_mm=float(stroke_mm), t_deg=float(t_deg))

    def amplitude(self, stroke_mm, t_deg):
        return float(rebound_amplitude_mm(self.at(stroke_mm, t_deg), self.speed, t_deg))

    def stroke_for(self, t_deg):
        """H with a(t; H) on the law's line: secant (the first step as if a were proportional to H)
        from the H found at the nearest t, each step at most doubling or halving H and halved
        again while the roller would leave its cam (a larger stroke drives it harder)."""
        target = self.task.law_intercept_mm + self.task.law_slope_mm_per_deg * t_deg
        near = min(self.known, key=lambda t: abs(t - t_deg), default=None)
        h = self.known[near] if near is not None else self.task.stroke_mm
        fh, previous = self.amplitude(h, t_deg) - target, None
        for _ in range(40):
            if abs(fh) <= 1e-14 * abs(target):
                break
            if previous is not None and previous[1] != fh:
                step = -fh * (h - previous[0]) / (fh - previous[1])
            else:
                step = h * (target / (fh + target) - 1)
            step = min(max(step, -0.5 * h), h)
            for _ in range(30):
                try:
                    f_new = self.amplitude(h + step, t_deg) - target
                    break
                except RollerLeftCam as exc:
                    if exc.status is not Status.INFEASIBLE:
                        raise
                    step /= 2
            else:
                raise ValueError(f"t = {t_deg:g} deg: the roller leaves its cam at every stroke tried")
            previous, h, fh = (h, fh), h + step, f_new
        if not (self.box[0] <= h <= self.box[1]) or abs(fh) > 1e-12 * abs(target):
            raise ValueError(f"t = {t_deg:g} deg: no stroke in the box puts the rebound on the law's line")
        self.known[float(t_deg)] = h
        return h

    def residual(self, t_deg):
        """The chain's tangent slope at (t, H(t)) less the law's [mm/deg]."""
        return amplitude_law(self.at(self.stroke_for(t_deg), t_deg))[0] - self.task.law_slope_mm_per_deg

    def residual_or_gap(self, t_deg):
        try:
            return self.residual(t_deg)
        except RollerLeftCam as exc:
            if exc.status is not Status.INFEASIBLE:
                raise
        except ValueError:              # no stroke in the box puts C's rebound on the law's line
            pass
        return None

    def predictions(self, stroke_mm, t_deg, damping_ratio=None):
        """Rebound [mm] and impact force [N] at every speed of `speeds_rpm` under one root."""
        task = self.at(stroke_mm, t_deg)
        if damping_ratio is not None:
            task = dataclasses.replace(task, damping_ratio=damping_ratio)
        out = {}
        for n in task.speeds_rpm:
            tag = speed_tag(n)
            try:                        # where the roller leaves its cam: no prediction (NaN, left out of spreads)
                v0 = approach_velocity_m_s(task, n, t_deg)
            except RollerLeftCam as exc:
                if exc.status is not Status.INFEASIBLE:
                    raise
                out |= {f"rebound_mm_{tag}": math.nan, f"impact_force_N_{tag}": math.nan}
                continue
            out[f"rebound_mm_{tag}"] = float(rebound_amplitude_mm(task, n, t_deg))
            out[f"impact_force_N_{tag}"] = float(task.impact_force_N(v0))
        return out


def _span(points):
    return f"[{min(points):g}, {max(points):g}] deg ({len(points)} grid points)" if points else "none"


def _spread(name: str, which: str) -> str:
    """`rebound_mm_370` -> `rebound_roots_min_mm_370`: the unit and the speed stay at the end of the name."""
    quantity, unit, speed = name.rsplit("_", 2)
    return f"{quantity}_{which}_{unit}_{speed}"
