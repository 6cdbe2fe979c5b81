"""Figures for the lift lever striking its plate (models/stop_impact.py, paper 004), drawn from
the solvers' arrays.

Rebound scenes: the time histories of eq. (2) at each speed over the first rebound's window (as
the paper's Fig. 8) and the first-rebound amplitude against speed, the computed points beside the
source's, taken from the scene's own expectations. The amplitude-law scene: the exact a(t) where
the bound's search evaluated it, beside its tangent and the limit. The operating-point scene: the
history at its speed and phase angle against the limit. The cam-dynamics scene: the rise's
analogues and their dynamic errors at each speed (Fig. 4).
"""

from mechopt.figures.registry import figure, new_figure
from mechopt.figures.text import literal
from mechopt.models.stop_impact import speed_tag
from mechopt.solvers.stop_impact import (
    cam_dynamics,
    fit_roots,
    impact_forces,
    linearise_amplitude,
    natural_frequencies,
    operating_point,
    rebound,
)


@figure(natural_frequencies, impact_forces, fit_roots)
def no_figures(run):
    """Scalars (frequencies, impact forces, a calibration's roots): a table, no picture."""
    return {}


@figure(rebound)
def rebound_figures(run):
    """The rebound histories and the amplitude against speed ({} when the cam lost its roller)."""
    if not len(run.result.arrays.get("t_s", ())):
        return {}
    return {"histories": _histories(run), "amplitude": _amplitude_vs_speed(run)}


@figure(linearise_amplitude)
def amplitude_law(run):
    """The exact law and its tangent ({} when the roller leaves its cam: no law)."""
    return {"law": _law(run)} if len(run.result.arrays.get("t_deg", ())) else {}


@figure(operating_point)
def operating_history(run):
    """The history at the operating point against the amplitude limit."""
    if not len(run.result.arrays.get("t_s", ())):
        return {}
    return {"histories": _histories(run, [run.task.speed_nominal_rpm], run.task.amplitude_limit_mm)}


@figure(cam_dynamics)
def cam_rises(run):
    """The rise's analogues at each speed and their dynamic errors ({} when no rise was followed)."""
    if not len(run.result.arrays.get("phi_deg", ())):
        return {}
    analogues, errors = _cam_rises(run)
    return {"analogues": analogues, "dynamic_errors": errors}


def _cam_rises(run):
    """Fig. 4: the displacement, velocity and acceleration analogues of C over the rise (against
    the cam angle, up to the nominal speed's contact with the plate) at each speed, beside the
    law's own; and their dynamic errors (elastic minus kinematic)."""
    task, a, values = run.task, run.result.arrays, run.result.values
    speeds = sorted({*task.speeds_rpm, task.speed_nominal_rpm})
    phi = a["phi_deg"]
    names = ("x_mm", "dx_dphi_mm_per_rad", "d2x_dphi2_mm_per_rad2")
    kinematic = [a[k] for k in ("s_mm", "ds_dphi_mm_per_rad", "d2s_dphi2_mm_per_rad2")]
    labels = ("displacement x [mm]", "velocity analogue\ndx/dphi [mm/rad]", "acceleration analogue\nd2x/dphi2 [mm/rad^2]")
    figs = [new_figure(figsize=(8, 9)) for _ in range(2)]
    axes = [fig.subplots(3, 1, sharex=True) for fig in figs]
    for ax, kin in zip(axes[0], kinematic):
        ax.plot(phi, kin, "k--", lw=1, label=f"{literal(task.law)} law (rigid lever)")
    plate_mm = a["x_mm"][-1]            # the nominal rise ends where C meets the plate: every contact is there
    for n in speeds:
        suffix = "" if n == task.speed_nominal_rpm else f"_{speed_tag(n)}"
        for row, (name, kin) in enumerate(zip(names, kinematic)):
            got = a[name + suffix]
            axes[0][row].plot(phi, got, lw=1.1, label=f"n = {n:g} rpm")
            axes[1][row].plot(phi, got - kin, lw=1.1, label=f"n = {n:g} rpm")
        if f"contact_angle_deg{suffix}" in values:
            axes[0][0].plot(values[f"contact_angle_deg{suffix}"], plate_mm, "o", ms=4, color="0.3")
    for which, (fig, rows) in enumerate(zip(figs, axes)):
        for ax, label in zip(rows, labels):
            ax.set_ylabel(("error of the " if which else "") + label, fontsize=8)
            ax.grid(alpha=0.3)
        rows[-1].set_xlabel("cam angle into the rise phi [deg] (to the contact with the plate)")
        rows[0].legend(fontsize=7)
        fig.suptitle(f"{literal(run.scene.id)}: " + ("dynamic errors of the motion law" if which else
                                            "analogues with the elastic lever (cf. paper's Fig. 4)"))
    return figs[0], figs[1]


def _histories(run, speeds=None, limit_mm=None):
    """q(t) after contact over the first rebound's window at each speed (the scene's `speeds_rpm`
    by default; one speed's array is `q_mm`), with the amplitude limit when one is given."""
    task, a = run.task, run.result.arrays
    fig = new_figure(figsize=(8, 4.5))
    ax = fig.subplots()
    for n in task.speeds_rpm if speeds is None else speeds:
        q = a["q_mm"] if speeds is not None else a[f"q_mm_{speed_tag(n)}"]
        ax.plot(a["t_s"] * 1e3, q, lw=1.2, label=f"n = {n:g} rpm, t = {task.t_deg:g} deg")
    if limit_mm is not None:
        ax.axhline(limit_mm, color="tab:red", ls=":", label=f"amplitude limit {limit_mm:g} mm")
    ax.axvspan(0, 2 * task.contact_time_s * 1e3, color="0.9", label="impact pulse (2 tau)")
    ax.axhline(0, color="k", lw=0.6)
    ax.set(xlabel="time after contact [ms]", ylabel="q: C off the plate [mm]",
           title=f"{literal(run.scene.id)}: rebound after contact, eq. (2) (cf. paper's Fig. 8)")
    ax.legend(fontsize=8)
    return fig


def _amplitude_vs_speed(run):
    """The computed first rebounds against speed (joined), the event-driven contact's beside them
    and the source's points."""
    task, values = run.task, run.result.values
    speeds = [n for n in task.speeds_rpm if f"rebound_mm_{speed_tag(n)}" in values]
    fig = new_figure(figsize=(7, 4.5))
    ax = fig.subplots()
    ax.plot(speeds, [values[f"rebound_mm_{speed_tag(n)}"] for n in speeds], "o-", mfc="none",
            label=f"computed, eq. (2), t = {task.t_deg:g} deg")
    published = [(name, e.value) for name, e in run.scene.spec.expect.items()
                 if name.startswith("rebound_mm_") and isinstance(e.value, (int, float))]
    if published:
        speed_of = {f"rebound_mm_{speed_tag(n)}": n for n in task.speeds_rpm}
        ax.plot([speed_of[k] for k, _ in published], [v for _, v in published], "kx", ms=8,
                label=f"source ({run.scene.spec.expect[published[0][0]].kind})")
    events = [n for n in speeds if f"rebound_event_mm_{speed_tag(n)}" in values]
    if events:
        ax.plot(events, [values[f"rebound_event_mm_{speed_tag(n)}"] for n in events], "s", ms=4,
                label="event-driven contact (stiffness switch)")
    ax.set(xlabel="main shaft speed n [rpm]", ylabel="first rebound [mm]", title=f"{literal(run.scene.id)}")
    ax.legend(fontsize=8)
    return fig


def _law(run):
    """The exact a(t) at the phase angles the bound's search evaluated, its tangent there, the
    limit and the tangent's bound."""
    task, v, a = run.task, run.result.values, run.result.arrays
    fig = new_figure(figsize=(7, 4.5))
    ax = fig.subplots()
    ax.plot(a["t_deg"], a["amplitude_mm"], ".-", label="exact a(t), eq. (2)")
    ax.plot(a["t_deg"], a["tangent_mm"], "--",
            label=f"tangent: {v['slope_mm_per_deg']:.4f} t + {v['intercept_mm']:.4f}")
    ax.axhline(task.amplitude_limit_mm, color="tab:red", ls=":", label=f"limit {task.amplitude_limit_mm:g} mm")
    ax.axvline(v["t_3_7_min_deg"], color="0.5", lw=0.8)
    ax.set(xlabel="phase angle t(3,7) [deg]", ylabel="first rebound a [mm]",
           title=f"{literal(run.scene.id)}: n = {task.speed_nominal_rpm:g} rpm")
    ax.legend(fontsize=8)
    return fig
