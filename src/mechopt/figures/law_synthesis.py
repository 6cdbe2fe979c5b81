"""Figures of a synthesised cam law: the law's travel and analogues beside the library
laws at the same phase angle, its predicted rebound against speed with the limit, and for the
co-designed machine the re-planned timing diagram. They read the Result's arrays only."""
import numpy as np

from mechopt.figures.loom import gantt
from mechopt.figures.registry import figure, new_figure
from mechopt.figures.text import literal
from mechopt.models.cam_follower import LAWS
from mechopt.solvers.loom import codesign_machine_speed
from mechopt.solvers.stop_impact import synthesise_law

ROWS = (("s_mm", "s [mm]"), ("ds_dphi_mm_per_rad", "ds/dphi [mm/rad]"),
        ("d2s_dphi2_mm_per_rad2", "d2s/dphi2 [mm/rad^2]"))


@figure(synthesise_law)
def synthesised(run) -> dict:
    a = run.result.arrays
    if "phi_deg" not in a:
        return {}
    return {"laws": _laws(run), **({"rebound_vs_speed": _rebound(run)} if "rebound_predicted_mm" in a else {})}


@figure(codesign_machine_speed)
def codesigned(run) -> dict:
    speed = run.result.values.get("speed_rpm")
    out = gantt(run, headline=None if speed is None else f"co-designed, {speed:.2f} rpm")
    return out | ({"laws": _laws(run)} if "phi_deg" in run.result.arrays else {})


def _laws(run):
    a = run.result.arrays
    fig = new_figure(figsize=(7, 7))
    axes = fig.subplots(len(ROWS), 1, sharex=True)
    for ax, (key, label) in zip(axes, ROWS):
        for name in LAWS:
            if f"{name}_{key}" in a:
                ax.plot(a[f"{name}_phi_deg"], a[f"{name}_{key}"], lw=0.8, alpha=0.7, label=name)
        ax.plot(a["phi_deg"], a[key], "k", lw=1.6, label="synthesised")
        ax.set_ylabel(label, fontsize=8)
        ax.grid(True, alpha=0.3)
    axes[0].legend(fontsize=7)
    axes[-1].set_xlabel("cam angle over the rise [deg]")
    t_deg = run.result.values.get('t_deg', float('nan'))
    axes[0].set_title(f"{literal(run.scene.id)}: the laws at t = {t_deg:.4g} deg", fontsize=9)
    return fig


def _rebound(run):
    a = run.result.arrays
    fig = new_figure(figsize=(7, 4))
    ax = fig.add_subplot()
    ax.plot(a["speed_rpm"], a["rebound_predicted_mm"], "k.-", label="synthesised (linear prediction)")
    if "rebound_cycloidal_predicted_mm" in a:
        ax.plot(a["speed_rpm"], a["rebound_cycloidal_predicted_mm"], ".-", label="cycloidal, same t")
    limit = getattr(run.task, "amplitude_limit_mm", None)
    if limit:
        ax.axhline(limit, color="tab:red", ls=":", label=f"limit {limit:g} mm")
    ax.set_xlabel("shaft speed [rpm]")
    ax.set_ylabel("rebound at the stop [mm]")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_ylim(bottom=0.0 if np.all(a["rebound_predicted_mm"] >= 0) else None)
    return fig
