"""The synthesised law beside the library laws (solvers/stop_impact/synthesis.py, `compare`): the
chain's rebound and dynamic error at the same t and speeds, the analogues, and a library law's
least phase angle by the same linear model."""
import dataclasses
import math

import numpy as np

from mechopt.kit.result import Status
from mechopt.models.cam_follower import LAWS, law_values
from mechopt.models.stop_impact import speed_tag
from mechopt.solvers.stop_impact.cam_follower import follow_cam
from mechopt.solvers.stop_impact.law import rebound_amplitude_mm
from mechopt.solvers.stop_impact.window_lp import band_speeds, predicted_rebounds_mm

__all__ = ["analogues", "compare_laws", "library_least_phase"]


def library_least_phase(task, law, band, lo, hi, tol, step):
    """The least t in [lo, hi] at which the library `law` keeps the limit over the band (the linear
    model's rebound at every `step` rpm; bisection, as for the synthesised law); None if not at hi."""
    dense = band_speeds(band, step)
    limit = task.amplitude_limit_mm

    def ok(t):
        return max(p[0] for p in predicted_rebounds_mm(task, law, t, dense)) <= limit
    if not ok(hi):
        return None
    while hi - lo > tol:
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if ok(mid) else (mid, hi)
    return hi


def compare_laws(task, law, t_deg, speeds, values):
    """The synthesised law beside the four library laws at the same t and speeds (the chain)."""
    for name, each in [("synthesized", law)] + [(k, k) for k in LAWS]:
        other = dataclasses.replace(task, law=each)
        for n in speeds:
            rise = follow_cam(other, n, t_deg)
            tag = f"{name}_{{}}_{speed_tag(n)}"
            if rise.status is Status.SOLVED:
                values[tag.format("rebound_mm")] = float(rebound_amplitude_mm(other, n, t_deg))
            values[tag.format("dynamic_error_mm")] = rise.dynamic_error_mm
        ddS = law_values(each, np.linspace(0, 1, 2001))[2]
        values[f"{name}_peak_acceleration_mm_per_rad2"] = float(np.abs(ddS).max()) * task.stroke_mm / math.radians(
            t_deg)**2


def analogues(law, xi, H_mm, t_rad, prefix):
    """The law's travel of C and its analogues against the cam angle over the rise [mm, mm/rad^k]."""
    S, dS, ddS = law_values(law, xi)[:3]
    return {f"{prefix}phi_deg": xi * math.degrees(t_rad), f"{prefix}s_mm": S * H_mm,
            f"{prefix}ds_dphi_mm_per_rad": dS * H_mm / t_rad, f"{prefix}d2s_dphi2_mm_per_rad2": ddS * H_mm / t_rad**2}
