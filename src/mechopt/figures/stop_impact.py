"""Figures for the lift lever striking its plate (models/stop_impact.py, paper 004).

Rebound scenes: the time histories of eq. (2) at each speed (as the paper's Fig. 8) and the
first-rebound amplitude against speed, with the source's points taken from the scene's own
expectations. The amplitude-law scene: the exact a(t) beside its tangent and the limit. The
operating-point scene: the history at its speed and phase angle against the limit. The
cam-dynamics scene: the rise's analogues and their dynamic errors at each speed (Fig. 4).
"""
import numpy as np

from mechopt.figures.registry import new_figure, register
from mechopt.models.cam_follower import law_values
from mechopt.models.stop_impact import LeverStop
from mechopt.solvers.stop_impact.cam_follower import follow_cam
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
    if solver == "cam_dynamics" and "approach_velocity_m_s" in run.result.values:
        analogues, errors = _cam_rises(run)
        return {"analogues": analogues, "dynamic_errors": errors}
    return {}


def _cam_rises(run):
    """Fig. 4: the displacement, velocity and acceleration analogues of C over the rise (against
    the cam angle, up to the contact with the plate) at each speed, beside the law's own; and
    their dynamic errors (elastic minus kinematic)."""
    task = run.task
    speeds = sorted({*task.speeds_rpm, task.speed_nominal_rpm})
    rad = np.radians(task.t_deg)
    scales = (task.stroke_mm, task.stroke_mm / rad, task.stroke_mm / rad**2)
    labels = ("displacement x [mm]", "velocity analogue\ndx/dphi [mm/rad]", "acceleration analogue\nd2x/dphi2 [mm/rad^2]")
    figs = [new_figure(figsize=(8, 9)) for _ in range(2)]
    axes = [fig.subplots(3, 1, sharex=True) for fig in figs]
    xi = np.linspace(0.0, 1.0, 400)
    for ax, scale, kin in zip(axes[0], scales, law_values(task.law, xi)):
        ax.plot(xi * task.t_deg, kin * scale, "k--", lw=1, label=f"{task.law} law (rigid lever)")
    for n in speeds:
        rise = follow_cam(task, n)
        kinematic = law_values(task.law, rise.xi)
        for row, (got, kin, scale) in enumerate(zip((rise.X, rise.dX, rise.ddX), kinematic, scales)):
            axes[0][row].plot(rise.xi * task.t_deg, got * scale, lw=1.1, label=f"n = {n:g} rpm")
            axes[1][row].plot(rise.xi * task.t_deg, (got - kin) * scale, lw=1.1, label=f"n = {n:g} rpm")
        if rise.contact_xi is not None:
            axes[0][0].plot(rise.contact_xi * task.t_deg, rise.X[-1] * task.stroke_mm, "o", ms=4, color="0.3")
    for which, (fig, rows) in enumerate(zip(figs, axes)):
        for ax, label in zip(rows, labels):
            ax.set_ylabel(("error of the " if which else "") + label, fontsize=8)
            ax.grid(alpha=0.3)
        rows[-1].set_xlabel("cam angle into the rise phi [deg] (to the contact with the plate)")
        rows[0].legend(fontsize=7)
        fig.suptitle(f"{run.scene.id}: " + ("dynamic errors of the motion law" if which else
                                            "analogues with the elastic lever (cf. paper's Fig. 4)"))
    return figs[0], figs[1]


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
    amplitude = rebound_amplitude_mm(task, speeds, task.t_deg, lost=np.nan)
    ax.plot(speeds, amplitude, label=f"eq. (2), t = {task.t_deg:g} deg")
    _mark_lost(ax, speeds, amplitude)
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
    amplitude = rebound_amplitude_mm(task, task.speed_nominal_rpm, t, lost=np.nan)
    ax.plot(t, amplitude, label="exact a(t), eq. (2)")
    _mark_lost(ax, t, amplitude)
    ax.plot(t, v["slope_mm_per_deg"] * t + v["intercept_mm"], "--",
            label=f"tangent: {v['slope_mm_per_deg']:.4f} t + {v['intercept_mm']:.4f}")
    ax.axhline(task.amplitude_limit_mm, color="tab:red", ls=":", label=f"limit {task.amplitude_limit_mm:g} mm")
    ax.axvline(v["t_3_7_min_deg"], color="0.5", lw=0.8)
    ax.set(xlabel="phase angle t(3,7) [deg]", ylabel="first rebound a [mm]",
           title=f"{run.scene.id}: n = {task.speed_nominal_rpm:g} rpm")
    ax.legend(fontsize=8)
    return fig


def _mark_lost(ax, x, amplitude):
    """Shade where the roller leaves its cam (no rebound is defined there), and say so."""
    lost = np.isnan(amplitude)
    if lost.any():
        ax.fill_between(x, 0, 1, where=lost, transform=ax.get_xaxis_transform(), color="0.85",
                        label="roller leaves its cam: no rebound")
