"""Accuracy costs time: the lever's first rebound (paper 004, eq. (2)) three ways, and the law
a(t, n) swept over a million points.

Per evaluation (one first-rebound amplitude, the scenes' 280 rpm and 177 rpm-with-preload cases):

* ``closed form``         `closed_form_amplitude_m`: the Duhamel integral in closed form (baseline);
* ``quadrature epsrel=…`` `quadrature_amplitude_m`: QUADPACK on the Duhamel integrals;
* ``ODE reltol=…``        `ode_amplitude_m`: CasADi/CVODES, phase by phase (build cached, as in a session).

Error is measured against the closed form, which the tight quadrature and ODE confirm to 1e-12
(tests pin 1e-8). Then the sweep: `rebound_amplitude_mm` over 10^6 random (n, t) points, beside
the same points one by one through the scalar closed form (timed on a sample, scaled up).
Timings are measured here and only here; tests never assert them.
"""
import statistics
import time

import numpy as np

from mechopt import registry
from mechopt.plots import save_figure
from mechopt.solvers.stop_impact.entry_points import AGREEMENT_REL
from mechopt.solvers.stop_impact.law import rebound_amplitude_mm
from mechopt.solvers.stop_impact.response import closed_form_amplitude_m, ode_amplitude_m, quadrature_amplitude_m

__all__ = ["cli", "evaluations", "sweep", "table", "sweep_table", "plot", "SCENES", "SWEEP_TARGET_S"]

SCENES = {"280 rpm": ("stop-impact/rebound-280-420", 280.0), "177 rpm + preload": ("stop-impact/rebound-177rpm", 177.0)}
QUAD_EPSREL = (1e-4, 1e-7, 1e-10, 1e-13)
ODE_RELTOL = (1e-4, 1e-7, 1e-10, 1e-13)
SWEEP_POINTS = 1_000_000
SWEEP_TARGET_S = 1.0


def _median_time(call, repeats):
    walls, out = [], None
    for _ in range(repeats):
        start = time.perf_counter()
        out = call()
        walls.append(time.perf_counter() - start)
    return statistics.median(walls), out


def evaluations(repeats=5, progress=None):
    """One row per (case, method, accuracy knob): median wall seconds per amplitude, the amplitude,
    its relative error against the closed form, and the ratio of its time to the closed form's."""
    rows = []
    for case, (scene_id, speed) in SCENES.items():
        task, _ = registry.find(scene_id).build()
        imp = task.impact(speed)
        ode_amplitude_m(imp)                        # build the CVODES functions outside the timing
        base_s, (ref, _) = _median_time(lambda: closed_form_amplitude_m(imp), repeats)
        methods = [("closed form", "-", lambda: closed_form_amplitude_m(imp)[0])]
        methods += [("quadrature", f"epsrel={e:g}", lambda e=e: quadrature_amplitude_m(imp, epsrel=e)[0])
                    for e in QUAD_EPSREL]
        for r in ODE_RELTOL:
            ode_amplitude_m(imp, reltol=r)          # cached build
            methods.append(("ODE (CVODES)", f"reltol={r:g}", lambda r=r: ode_amplitude_m(imp, reltol=r)[0]))
        for method, knob, call in methods:
            wall, amp = _median_time(call, repeats)
            rows.append({"case": case, "method": method, "knob": knob, "wall_s": wall, "amplitude_mm": amp * 1e3,
                         "rel_error": abs(amp - ref) / ref, "over_closed_form": wall / base_s})
            if progress:
                progress(f"{case:<18} {method:<13} {knob:<14} {wall * 1e3:9.3f} ms")
    return rows


def sweep(repeats=3, progress=None, points=SWEEP_POINTS, sample=2000):
    """Median seconds of `rebound_amplitude_mm` over `points` random (n in 150..450 rpm, t in
    20..60 deg) for each case, the scalar loop's seconds scaled from `sample` points, and the
    largest relative difference between the two on that sample."""
    rng = np.random.default_rng(7)
    n, t = rng.uniform(150, 450, points), rng.uniform(20, 60, points)
    rows = []
    for case, (scene_id, _) in SCENES.items():
        task, _ = registry.find(scene_id).build()
        wall, swept = _median_time(lambda: rebound_amplitude_mm(task, n, t), repeats)
        idx = rng.choice(points, sample, replace=False)
        start = time.perf_counter()
        one = np.array([closed_form_amplitude_m(task.impact(n[i], t[i]))[0] * 1e3 for i in idx])
        loop_s = (time.perf_counter() - start) * points / sample
        rows.append({"case": case, "points": points, "wall_s": wall, "loop_s_estimated": loop_s,
                     "speedup": loop_s / wall, "max_rel_diff": float(np.max(np.abs(swept[idx] - one) / one)),
                     "target_s": SWEEP_TARGET_S})
        if progress:
            progress(f"sweep {case:<18} {wall:.3f} s for {points} points")
    return rows


def table(rows):
    head = (f"{'case':<19}{'method':<14}{'knob':<15}{'time/eval ms':>13}{'x closed form':>15}{'rel error':>12}"
            "  amplitude mm")
    lines = [head, "-" * len(head)]
    for r in rows:
        lines.append(f"{r['case']:<19}{r['method']:<14}{r['knob']:<15}{r['wall_s'] * 1e3:>13.3f}"
                     f"{r['over_closed_form']:>15.1f}{r['rel_error']:>12.1e}  {r['amplitude_mm']:.9f}")
    return "\n".join(lines)


def sweep_table(rows):
    head = (f"{'sweep case':<19}{'points':>9}{'median s':>10}{'target s':>10}{'loop s (est.)':>15}{'speedup':>9}"
            f"{'max rel diff':>14}  verdict")
    lines = [head, "-" * len(head)]
    for r in rows:
        lines.append(f"{r['case']:<19}{r['points']:>9}{r['wall_s']:>10.3f}{'< ' + format(r['target_s'], 'g'):>10}"
                     f"{r['loop_s_estimated']:>15.1f}{r['speedup']:>9.0f}{r['max_rel_diff']:>14.1e}  "
                     f"{'met' if r['wall_s'] < r['target_s'] else 'MISSED'}")
    return "\n".join(lines)


def plot(rows, out_dir):
    """Write "rebound_work_precision.png": relative error against time per evaluation."""
    import pathlib

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out = pathlib.Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    fig, axes = plt.subplots(1, len(SCENES), figsize=(12, 4.8), sharey=True)
    for ax, case in zip(np.atleast_1d(axes), SCENES):
        for method, marker in (("closed form", "*"), ("quadrature", "o"), ("ODE (CVODES)", "s")):
            mine = [r for r in rows if r["case"] == case and r["method"] == method]
            ax.plot([r["wall_s"] for r in mine], [max(r["rel_error"], 1e-17) for r in mine], marker=marker,
                    label=method)
            for r in mine:
                if r["knob"] != "-":
                    ax.annotate(r["knob"].split("=")[1], (r["wall_s"], max(r["rel_error"], 1e-17)),
                                textcoords="offset points", xytext=(4, 3), fontsize=7)
        ax.axhline(AGREEMENT_REL, color="tab:red", ls=":", label="agreement required (1e-8)")
        ax.set(xscale="log", yscale="log", xlabel="time per amplitude, median [s]", title=case)
        ax.grid(True, which="both", alpha=0.3)
    np.atleast_1d(axes)[0].set_ylabel("relative error vs closed form (floor 1e-17)")
    np.atleast_1d(axes)[0].legend(fontsize=8)
    fig.suptitle("Lever rebound (paper 004, eq. (2)): closed form, quadrature, ODE")
    path = out / "rebound_work_precision.png"
    save_figure(fig, path, dpi=120)
    return [str(path)]


def cli(repeats, out_dir, progress=None) -> str:
    """What `mechopt bench stop-impact` prints: per-evaluation table, the 10^6-point sweep, the plot."""
    rows = evaluations(repeats=repeats, progress=progress)
    swept = sweep(repeats=max(1, min(repeats, 3)), progress=progress)
    return "\n".join([table(rows), "", sweep_table(swept), *(f"plot: {p}" for p in plot(rows, out_dir))])
