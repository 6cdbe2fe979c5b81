"""Accuracy costs time: the lift's cam rise with the elastic lever (Fig. 4) and the lever's first
rebound (eq. (2)), each against a tight reference; and what one point of the chain's law costs.

The cam rise (`stop-impact/cam-dynamics`, 280 and 420 rpm), the approach velocity at the located
contact with the plate:

* ``CVODES reltol=…``   `follow_cam` (CasADi, phase by phase, contact by Newton; build cached);
* ``DOP853 rtol=…``     `follow_cam_reference` (scipy, its own event location);

error against DOP853 at rtol 1e-13 (tests pin CVODES against an independent Radau to 1e-7).

The first rebound per evaluation (the scenes' 280 rpm and 177 rpm-with-preload cases, v0 from the
cam): closed form (baseline), QUADPACK on the Duhamel integrals, CVODES on eq. (2); error against
the closed form. Then the chain's law `rebound_amplitude_mm`: each (n, t) is its own rise, so its
cost per point is measured on a sample (the earlier fitted law, proportional to n / t, swept 10^6
points in 0.1 s; the chain cannot be tabulated that way). Timings are measured here and only here.
"""
import statistics
import time

import numpy as np

from mechopt import registry
from mechopt.benchmarks import synthesis
from mechopt.figures import save_figure
from mechopt.solvers.stop_impact.cam_follower import follow_cam, follow_cam_reference
from mechopt.solvers.stop_impact.entry_points import AGREEMENT_REL
from mechopt.solvers.stop_impact.law import impact_at, rebound_amplitude_mm
from mechopt.solvers.stop_impact.response import closed_form_amplitude_m, ode_amplitude_m, quadrature_amplitude_m

__all__ = ["SCENES", "cam_rows", "cam_table", "cli", "evaluations", "law_cost", "plot", "synthesis_rows",
           "synthesis_table", "table"]

SCENES = {"280 rpm": ("stop-impact/rebound-280-420", 280.0), "177 rpm + preload": ("stop-impact/rebound-177rpm", 177.0)}
CAM_SCENE, CAM_SPEEDS = "stop-impact/cam-dynamics", (280.0, 420.0)
CAM_RELTOL = (1e-4, 1e-6, 1e-8, 1e-10, 1e-12)
DOP_RTOL = (1e-4, 1e-6, 1e-8, 1e-10)
REFERENCE_RTOL = 1e-13
QUAD_EPSREL = (1e-4, 1e-7, 1e-10, 1e-13)
ODE_RELTOL = (1e-4, 1e-7, 1e-10, 1e-13)
LAW_SAMPLE = 200


def _median_time(call, repeats):
    walls, out = [], None
    for _ in range(repeats):
        start = time.perf_counter()
        out = call()
        walls.append(time.perf_counter() - start)
    return statistics.median(walls), out


def evaluations(repeats=5, progress=None, quick=False):
    """One row per (case, method, accuracy knob): median wall seconds per amplitude, the amplitude,
    its relative error against the closed form, and the ratio of its time to the closed form's."""
    rows = []
    for case, (scene_id, speed) in list(SCENES.items())[:1 if quick else None]:
        task, _ = registry.find(scene_id).build()
        imp = impact_at(task, speed)
        ode_amplitude_m(imp)                        # build the CVODES functions outside the timing
        base_s, (ref, _) = _median_time(lambda imp=imp: closed_form_amplitude_m(imp), repeats)
        methods = [("closed form", "-", lambda imp=imp: closed_form_amplitude_m(imp)[0])]
        methods += [("quadrature", f"epsrel={e:g}", lambda e=e, imp=imp: quadrature_amplitude_m(imp, epsrel=e)[0])
                    for e in QUAD_EPSREL[1::2 if quick else 1]]
        for r in ODE_RELTOL[1::2 if quick else 1]:
            ode_amplitude_m(imp, reltol=r)          # cached build
            methods.append(("ODE (CVODES)", f"reltol={r:g}", lambda r=r, imp=imp: ode_amplitude_m(imp, reltol=r)[0]))
        for method, knob, call in methods:
            wall, amp = _median_time(call, repeats)
            rows.append({"case": case, "method": method, "knob": knob, "wall_s": wall, "amplitude_mm": amp * 1e3,
                         "rel_error": abs(amp - ref) / ref, "over_closed_form": wall / base_s})
            if progress:
                progress(f"{case:<18} {method:<13} {knob:<14} {wall * 1e3:9.3f} ms")
    return rows


def cam_rows(repeats=5, progress=None, quick=False):
    """One row per (speed, integrator, tolerance): median wall seconds of one rise, the approach
    velocity and its relative error against DOP853 at rtol 1e-13, and the time over CVODES at 1e-10's."""
    task, _ = registry.find(CAM_SCENE).build()
    cvodes = CAM_RELTOL[1::2] if quick else CAM_RELTOL
    dop = DOP_RTOL[1::2] if quick else DOP_RTOL
    rows = []
    for speed in CAM_SPEEDS[-1:] if quick else CAM_SPEEDS:
        ref = follow_cam_reference(task, speed, rtol=REFERENCE_RTOL)[1]
        for r in cvodes:
            follow_cam(task, speed, reltol=r)             # build the CVODES functions outside the timing
        base_s, _ = _median_time(lambda speed=speed: follow_cam(task, speed, reltol=1e-10), repeats)
        runs = [("CVODES", f"reltol={r:g}",
                 lambda r=r, speed=speed: follow_cam(task, speed, reltol=r).approach_velocity_m_s) for r in cvodes]
        runs += [("DOP853", f"rtol={r:g}", lambda r=r, speed=speed: follow_cam_reference(task, speed, rtol=r)[1])
                 for r in dop]
        for method, knob, call in runs:
            wall, v0 = _median_time(call, repeats)
            rows.append({"case": f"rise {speed:g} rpm", "method": method, "knob": knob, "wall_s": wall,
                         "approach_velocity_m_s": v0, "rel_error": abs(v0 - ref) / ref, "over_cvodes": wall / base_s})
            if progress:
                progress(f"rise {speed:g} rpm {method:<7} {knob:<14} {wall * 1e3:9.3f} ms")
    return rows


def law_cost(repeats=3, progress=None, points=LAW_SAMPLE):
    """Median seconds per point of the chain's `rebound_amplitude_mm` over `points` random (n in
    150..420 rpm, t in 30..60 deg): one cam rise and one closed-form rebound each."""
    rng = np.random.default_rng(7)
    n, t = rng.uniform(150, 420, points), rng.uniform(30, 60, points)
    task, _ = registry.find(SCENES["280 rpm"][0]).build()
    wall, _ = _median_time(lambda: rebound_amplitude_mm(task, n, t), repeats)
    if progress:
        progress(f"chain law: {wall:.3f} s for {points} points")
    return {"points": points, "wall_s": wall, "per_point_ms": wall / points * 1e3}


def table(rows):
    head = (f"{'case':<19}{'method':<14}{'knob':<15}{'time/eval ms':>13}{'x closed form':>15}{'rel error':>12}"
            "  amplitude mm")
    lines = [head, "-" * len(head)]
    for r in rows:
        lines.append(f"{r['case']:<19}{r['method']:<14}{r['knob']:<15}{r['wall_s'] * 1e3:>13.3f}"
                     f"{r['over_closed_form']:>15.1f}{r['rel_error']:>12.1e}  {r['amplitude_mm']:.9f}")
    return "\n".join(lines)


def cam_table(rows, cost):
    head = (f"{'case':<14}{'method':<9}{'knob':<15}{'time/rise ms':>13}{'x CVODES 1e-10':>16}{'rel error':>12}"
            "  approach velocity m/s")
    lines = [head, "-" * len(head)]
    for r in rows:
        lines.append(f"{r['case']:<14}{r['method']:<9}{r['knob']:<15}{r['wall_s'] * 1e3:>13.3f}"
                     f"{r['over_cvodes']:>16.1f}{r['rel_error']:>12.1e}  {r['approach_velocity_m_s']:.10f}")
    lines.append(f"chain law a(t, n): {cost['per_point_ms']:.2f} ms per point (median over {cost['points']} points)")
    return "\n".join(lines)


def plot(rows, cam, out_dir):
    """Write "stop_impact_work_precision.png": relative error against time, the rebound per
    evaluation (two cases) and the cam rise (each speed)."""
    import pathlib

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out = pathlib.Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    cases = [(c, rows, "relative error of the amplitude vs closed form") for c in dict.fromkeys(r["case"] for r in rows)]
    cases += [(c, cam, "relative error of v0 vs DOP853 at 1e-13") for c in dict.fromkeys(r["case"] for r in cam)]
    fig, axes = plt.subplots(1, len(cases), figsize=(4.5 * len(cases), 4.8), squeeze=False)
    markers = {"closed form": "*", "quadrature": "o", "ODE (CVODES)": "s", "CVODES": "s", "DOP853": "^"}
    for ax, (case, table_rows, ylabel) in zip(axes[0], cases):
        for method in dict.fromkeys(r["method"] for r in table_rows if r["case"] == case):
            mine = [r for r in table_rows if r["case"] == case and r["method"] == method]
            ax.plot([r["wall_s"] for r in mine], [max(r["rel_error"], 1e-17) for r in mine],
                    marker=markers.get(method, "."), label=method)
            for r in mine:
                if r["knob"] != "-":
                    ax.annotate(r["knob"].split("=")[1], (r["wall_s"], max(r["rel_error"], 1e-17)),
                                textcoords="offset points", xytext=(4, 3), fontsize=7)
        if table_rows is rows:
            ax.axhline(AGREEMENT_REL, color="tab:red", ls=":", label="agreement required (1e-8)")
        ax.set(xscale="log", yscale="log", xlabel="time per evaluation, median [s]", ylabel=ylabel, title=case)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    fig.suptitle("Lift lever (paper 004): eq. (2) three ways; the cam rise with the elastic lever two ways")
    path = out / "stop_impact_work_precision.png"
    save_figure(fig, path, dpi=120)
    return [str(path)]


def cli(repeats, out_dir, progress=None, quick=False) -> str:
    """What `mechopt bench stop-impact` prints: the rebound per evaluation, the cam rise's
    work-precision, the chain law's cost per point, the plot. `quick`: one case and speed, every
    other tolerance, one run each (a few seconds)."""
    repeats = 1 if quick else repeats
    rows = evaluations(repeats=repeats, progress=progress, quick=quick)
    cam = cam_rows(repeats=repeats, progress=progress, quick=quick)
    cost = law_cost(repeats=1 if quick else min(repeats, 3), progress=progress, points=20 if quick else LAW_SAMPLE)
    synth = synthesis_table(synthesis_rows(repeats=1 if quick else min(repeats, 3), progress=progress, quick=quick))
    window = synthesis.cli(repeats, out_dir, progress=progress, quick=quick)
    return "\n".join([table(rows), "", cam_table(cam, cost), "", synth, "", window,
                      *(f"plot: {p}" for p in plot(rows, cam, out_dir))])


# ---------------------------------------------------------------- law synthesis

SYNTH_COEFFICIENTS = (100, 300, 1000)
DE_SECONDS = 60.0                       # differential evolution's budget (it does not reach the LP's optimum)


def synthesis_rows(repeats=3, progress=None, quick=False):
    """The least-rebound law at the chain's t and 420 rpm (one speed, one arrival window xi_a =
    0.85: one LP), cold (the spline space built afresh) for 10^2 ... 10^3 coefficients; against
    scipy's differential_evolution over the same spline (its coefficients boxed to [-0.5, 1.5],
    the same rebound as objective through the same linear lever, the LP's limits as a penalty)
    given DE_SECONDS, one run: its best rebound and time beside the LP's."""
    from scipy.optimize import differential_evolution

    from mechopt.solvers.stop_impact import window_lp
    task = registry.find("stop-impact/amplitude-law").build()[0]
    rows = []
    for k in SYNTH_COEFFICIENTS[:1] if quick else SYNTH_COEFFICIENTS:
        def cold():
            window_lp.BASES.clear()
            lever = window_lp.linear_lever(k, 2)
            speed = window_lp.speed_response(task, lever, 420.0, task.t_deg)
            lines = window_lp.rebound_envelope(task, 4 * window_lp.v0_limit_m_s(task, task.amplitude_limit_mm))
            lp = window_lp.WindowLP(task, lever, [speed], task.t_deg, objective="least_rebound",
                              limit_mm=task.amplitude_limit_mm, bounds={"max_acceleration_mm_per_rad2": 570.0},
                              lines=lines)
            return lp.solve(0.85)
        seconds, out = _median_time(cold, repeats)
        rows.append({"method": f"LP (sparse rows, HiGHS), {k} coefficients", "seconds": seconds, "rebound_mm": out[2]})
        if progress:
            progress(f"LP {k}: {seconds:.3g} s")
    k = SYNTH_COEFFICIENTS[0]
    lever = window_lp.linear_lever(k, 2)
    speed = window_lp.speed_response(task, lever, 420.0, task.t_deg)
    (X0, XB), (dX0, dXB), _ = lever.response(speed.lam, speed.zeta)
    H = task.stroke_mm * 1e-3
    target = 1.0 - task.preload_mm / task.stroke_mm
    _, (_, _), (a0, A), _ = lever.bound_kin
    acc = 570.0 * np.radians(task.t_deg)**2 / task.stroke_mm
    window = lever.xi >= 0.85

    def objective(c):      # the LP's problem as a penalty: the rebound of the window's peak X'
        X, dX = X0 + XB @ c, dX0 + dXB @ c
        over = max(0.0, (X[~window] - target).max()) + max(0.0, target - X[-1]) + max(0.0, np.abs(a0 + A @ c).max() - acc)
        return window_lp.rebound_of_v0_mm(task, max(dX[window].max(), 0.0) * H / speed.T) + 1e3 * over
    start = time.perf_counter()
    de = differential_evolution(objective, [(-0.5, 1.5)] * k, maxiter=100000, tol=0, seed=1, polish=False,
                                callback=lambda *a, **kw: time.perf_counter() - start > (5.0 if quick else DE_SECONDS))
    rows.append({"method": f"scipy differential_evolution, {k} coefficients", "seconds": time.perf_counter() - start,
                 "rebound_mm": float(de.fun)})
    return rows


DE_OVER_LP_TARGET = 50.0                # the target: the LP at least 50x faster than the derivative-free peer


def synthesis_table(rows):
    """The rows, and the target's verdict: differential evolution's time over the LP's at the same
    coefficients, in the same run (a peer stopped by its budget before the LP's optimum makes the
    ratio a lower bound: said)."""
    base = rows[0]
    lines = ["law synthesis, least rebound at t = 35.59 deg, 420 rpm (cold; medians)",
             f"{'method':48s} {'seconds':>9s} {'rebound mm':>11s} {'time / LP(100)':>15s}"]
    for r in rows:
        lines.append(f"{r['method']:48s} {r['seconds']:9.3g} {r['rebound_mm']:11.4g} {r['seconds'] / base['seconds']:15.3g}")
    de = rows[-1]
    ratio = de["seconds"] / base["seconds"]
    short = de["rebound_mm"] > base["rebound_mm"] * (1 + 1e-3)
    verdict = ("met" if ratio >= DE_OVER_LP_TARGET else
               "undecided: DE's budget ended first" if short else "MISSED")
    lines.append(f"differential evolution / LP at {SYNTH_COEFFICIENTS[0]} coefficients: {ratio:.3g}"
                 f"{' or more (DE stopped by its budget above the LP optimum)' if short else ''} "
                 f"(>= {DE_OVER_LP_TARGET:g}: {verdict})")
    return "\n".join(lines)
