"""The speed-dependent limits of the highest speed, each as t >= g n: their coefficients g
[deg/rpm] (the time floor, the contact stress, the rebound's exact bound through r* = n_ref / T),
the probe that the rebound is a function of n / t, and every arc's bound at a given speed (the
LP's max([phi], g n), or the exact laws at n for bisection)."""
import math

import numpy as np

from mechopt.kit import store
from mechopt.kit.cache import BuildCache
from mechopt.kit.errors import ModelError
from mechopt.models.cyclogram import Cyclogram
from mechopt.solvers.loom import repair
from mechopt.solvers.loom.repair import box_amplitude_bound, exact_amplitude_mm
from mechopt.solvers.stop_impact.law import chain_rebounds_mm
from mechopt.solvers.stop_impact.lever_box import LeverBox


def angle_floors_deg(task: Cyclogram) -> np.ndarray:
    """Each arc's [phi] as given, without the time floor of `min_ms` (that one grows with n) [deg]."""
    return np.fromiter((phi for _, _, phi in task.graph.edges(data="min_deg")), dtype=float, count=len(task.arcs))


N_OVER_T_RTOL = 1e-9             # the probe: a(c t, c n) = a(t, n) to this (the chain meets it to 1e-16)
N_OVER_T_FACTORS = (0.5, 2.0)
def n_over_t_probe(task: Cyclogram, scan_to_deg: float) -> tuple[bool, float]:
    """Whether every speed-dependent law is a function of n / t alone, and the largest relative
    change seen. The time floor (0.006 n T) and the stress (sigma_ref t_ref n / (t n_ref)) are by
    their form; the rebound is probed: a(c t, c n) against a(t, n) for c = 0.5, 2 at t =
    scan_to_deg and 3/4 of it, n the task's speed. (The chain passes: its rise in its own time
    depends on lambda = omega t / Omega only, and the impact on v0 only; see models/loom_limits.py, the STB loom's laws.)"""
    if not task.amplitude_arcs():
        return True, 0.0
    key = (task.lever_model, float(reference_rpm(task)), float(scan_to_deg))    # a property of the law alone
    return _PROBES.get(key, lambda: store.stored(                                # on disk too, when on
        "n_over_t_probe", key, lambda: n_over_t_probe_at(task, scan_to_deg), list, lambda d: (bool(d[0]), float(d[1])),
        sources=repair.WALK_SOURCES, enabled=repair.rebound_amplitude_mm is chain_rebounds_mm))[0]


_PROBES = BuildCache("cyclogram.n_over_t_probe", maxsize=16)


def n_over_t_probe_at(task, scan_to_deg):
    """Every point of the probe in one call of the law (the chain's batch path: each point's value
    is the one it has alone, a call's overhead paid once instead of six times)."""
    n, worst = reference_rpm(task), 0.0
    tops = (scan_to_deg, 0.75 * scan_to_deg)
    t = np.array([[top, *(c * top for c in N_OVER_T_FACTORS)] for top in tops])
    speed = np.array([[n, *(c * n for c in N_OVER_T_FACTORS)] for _ in tops])
    for base, *others in np.asarray(exact_amplitude_mm(task, t, speed, lost=np.nan), dtype=float).tolist():
        for other in others:
            if np.isnan(base) and np.isnan(other):
                continue
            worst = max(worst, abs(other - base) / max(abs(base), 1e-300) if np.isfinite(other - base) else math.inf)
    return worst <= N_OVER_T_RTOL, worst


def reference_rpm(task):
    if task.speed_rpm is None:
        raise ModelError("speed_rpm: the rebound's exact bound is found at a reference speed; give speed_rpm",
                         key="speed_rpm")
    return task.speed_rpm


def time_law(task, k) -> str:
    """What sets arc k's time floor: a motion's limit ("max_accel", "max_velocity") or its min_ms."""
    return task.arc_data(k)["motion_limit"] or "min_time"


def speed_coeffs_deg_per_rpm(task: Cyclogram, scan_to_deg: float = 60.0, scan_step_deg: float = 0.25,
                             box: LeverBox | None = None) -> tuple[np.ndarray, list[str], dict]:
    """Per arc, the angle every rpm of speed asks for [deg/rpm], which law sets it ("min_time",
    "contact_stress", "amplitude" or "" for none), and per amplitude arc its exact bound at the
    task's speed. Each law is f(n / t) <= limit, so it is t >= n / r*: a bound proportional to n.
    For the wavy rebound r* = n_ref / T, T the exact bound at n_ref on [phi, scan_to_deg]
    (`exact_amplitude_bound`): a <= limit for every n / t in [n_ref / scan_to_deg, r*]. With a
    box, T is the largest over its levers at n_ref (1 + margin) (`box_amplitude_bound`)."""
    g = task.time_coeffs_deg_per_rpm()
    why = [time_law(task, k) if c > 0 else "" for k, c in enumerate(g)]
    for k in task.stress_arcs():
        c = task.stress_coeff_deg_per_rpm(k)
        if c > g[k]:
            g[k], why[k] = c, "contact_stress"
    bounds, phi = {}, angle_floors_deg(task)
    for k in task.amplitude_arcs():
        n_ref = reference_rpm(task)
        bounds[k] = box_amplitude_bound(task, box, n_ref, float(phi[k]), scan_to_deg, scan_step_deg)
        c = math.inf if bounds[k].from_deg is None else bounds[k].from_deg / n_ref
        if c > g[k]:
            g[k], why[k] = c, "amplitude"
    return g, why, bounds


def lp_bounds_at(phi, g, why, n_rpm):
    """The LP's bounds at speed n: max([phi], g n) [deg], and which law sets each ("" for [phi])."""
    lb = np.maximum(phi, g * n_rpm)
    return lb, [w if g[k] * n_rpm >= phi[k] else "" for k, w in enumerate(why)]


def exact_amplitude_bounds(task, box, phi, scan_to_deg, scan_step_deg, n_rpm):
    """Per amplitude arc, the rebound's exact bound at speed n on [phi, scan_to_deg] (over the box)."""
    return {k: box_amplitude_bound(task, box, n_rpm, float(phi[k]), scan_to_deg, scan_step_deg)
            for k in task.amplitude_arcs()}


def exact_bounds_at(task, box, phi, scan_to_deg, scan_step_deg, n_rpm):
    """Each arc's smallest angle at speed n from the exact laws directly [deg], and which law sets
    it: the time floor, the stress bound sigma_ref t_ref n / ([sigma_H] n_ref), the rebound's
    exact bound on [phi, scan_to_deg] (inf where none holds there). At n = 0: [phi]."""
    lb = np.maximum(phi, task.time_coeffs_deg_per_rpm() * n_rpm)
    why = [time_law(task, k) if b > p else "" for k, (b, p) in enumerate(zip(lb, phi))]
    for k in task.stress_arcs():
        bound = task.stress_coeff_deg_per_rpm(k) * n_rpm
        if bound > lb[k]:
            lb[k], why[k] = bound, "contact_stress"
    if n_rpm > 0:
        for k, b in exact_amplitude_bounds(task, box, phi, scan_to_deg, scan_step_deg, n_rpm).items():
            bound = math.inf if b.from_deg is None else b.from_deg
            if bound > lb[k]:
                lb[k], why[k] = bound, "amplitude"
    return lb, why
