"""Figures for the lift lever striking its plate (models/stop_impact.py, paper 004).

Rebound scenes: the time histories of eq. (2) at each speed (as the paper's Fig. 8) and the
first-rebound amplitude against speed, with the source's points taken from the scene's own
expectations. The amplitude-law scene: the exact a(t) beside its tangent and the limit. The
operating-point scene: the history at its speed and phase angle against the limit.
"""
import numpy as np

from mechopt.figures.registry import new_figure, register
from mechopt.models.stop_impact import LeverStop
from mechopt.solvers.stop_impact.law import impact_at, rebound_amplitude_mm
from mechopt.solvers.stop_impact.response import closed_form_response


@register(LeverStop)
def rebound_figures(run):
    """This scene's figures by name ({} for scenes without any: frequencies, impact forces)."""
    solver = run.scene.solver.__name__
    if solver == "rebound" and any(k.startswith("rebound_mm_") for k in run.result.values):
        return {"histories": _histories(run), "amplitude": _amplitude_vs_speed(run)}
    if solver == "linearise_amplitude" and "slope_mm_per_deg" in run.result.values:
        return {"law": _law(run)}
    if solver == "operating_point" and "rebound_mm" in run.result.values:
        return {"histories": _histories(run, [run.task.speed_nominal_rpm], run.task.amplitude_limit_mm)}
    return {}


def _histories(run, speeds=None, limit_mm=None):
    """q(t) after contact at each speed (the scene's `speeds_rpm` by default), with the
    amplitude limit when one is given."""
    task = run.task
    fig = new_figure(figsize=(8, 4.5))
    ax = fig.subplots()
    for n in task.speeds_rpm if speeds is None else speeds:
        imp = impact_at(task, n)
        t = np.linspace(0.0, 3 * imp.window_s, 1500)
        ax.plot(t * 1e3, closed_form_response(imp, t)[0] * 1e3, lw=1.2, label=f"n = {n:g} rpm, t = {task.t_deg:g} deg")
    if limit_mm is not None:
        ax.axhline(limit_mm, color="tab:red", ls=":", label=f"amplitude limit {limit_mm:g} mm")
    ax.axvspan(0, 2 * task.contact_time_s * 1e3, color="0.9", label="impact pulse (2 tau)")
    ax.axhline(0, color="k", lw=0.6)
    ax.set(xlabel="time after contact [ms]", ylabel="q: C off the plate [mm]",
           title=f"{run.scene.id}: rebound after contact, eq. (2) (cf. paper's Fig. 8)")
    ax.legend(fontsize=8)
    return fig


def _amplitude_vs_speed(run):
    task = run.task
    speeds = np.linspace(0.5 * min(task.speeds_rpm), 1.2 * max(task.speeds_rpm), 200)
    fig = new_figure(figsize=(7, 4.5))
    ax = fig.subplots()
    ax.plot(speeds, rebound_amplitude_mm(task, speeds, task.t_deg), label=f"eq. (2), t = {task.t_deg:g} deg")
    got = {k: v for k, v in run.result.values.items() if k.startswith("rebound_mm_")}
    ax.plot([task.speeds_rpm[i] for i in range(len(got))], list(got.values()), "o", mfc="none", label="computed")
    published = [(name, e.value) for name, e in run.scene.spec.expect.items()
                 if name.startswith("rebound_mm_") and isinstance(e.value, (int, float))]
    if published:
        speed_of = {f"rebound_mm_{n:g}".replace(".", "p"): n for n in task.speeds_rpm}
        ax.plot([speed_of[k] for k, _ in published], [v for _, v in published], "kx", ms=8,
                label=f"source ({run.scene.spec.expect[published[0][0]].kind})")
    events = {k: v for k, v in run.result.values.items() if k.startswith("rebound_event_mm_")}
    if events:
        ax.plot(task.speeds_rpm[:len(events)], list(events.values()), "s", ms=4,
                label="event-driven contact (stiffness switch)")
    ax.set(xlabel="main shaft speed n [rpm]", ylabel="first rebound [mm]", title=f"{run.scene.id}")
    ax.legend(fontsize=8)
    return fig


def _law(run):
    task = run.task
    v = run.result.values
    t = np.linspace(0.5 * task.t_deg, 2.0 * task.t_deg, 300)
    fig = new_figure(figsize=(7, 4.5))
    ax = fig.subplots()
    ax.plot(t, rebound_amplitude_mm(task, task.speed_nominal_rpm, t), label="exact a(t), eq. (2)")
    ax.plot(t, v["slope_mm_per_deg"] * t + v["intercept_mm"], "--",
            label=f"tangent: {v['slope_mm_per_deg']:.4f} t + {v['intercept_mm']:.4f}")
    ax.axhline(task.amplitude_limit_mm, color="tab:red", ls=":", label=f"limit {task.amplitude_limit_mm:g} mm")
    ax.axvline(v["t_3_7_min_deg"], color="0.5", lw=0.8)
    ax.set(xlabel="phase angle t(3,7) [deg]", ylabel="first rebound a [mm]",
           title=f"{run.scene.id}: n = {task.speed_nominal_rpm:g} rpm")
    ax.legend(fontsize=8)
    return fig
