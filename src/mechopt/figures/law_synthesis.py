"""Figures of a synthesised cam law: the law's travel and analogues beside the library
laws at the same phase angle, its predicted rebound against speed with the limit, and for the
co-designed machine the re-planned timing diagram. They read the Result's arrays only.

The shop's drawing of a synthesised law (`--dxf`) is the lift cam cut to it: the law enters the
lift cam's geometry (stop-impact/lift-cam-profile) and `shape_cam` makes its point tables."""
import dataclasses

import numpy as np

from mechopt.cam_sheet import Phase
from mechopt.dxf import NothingToExport, shop_drawing
from mechopt.figures.cam_shape import cam_drawing, stated_phase
from mechopt.figures.loom import gantt
from mechopt.figures.registry import figure, new_figure
from mechopt.figures.text import literal
from mechopt.kit.result import Status
from mechopt.models.cam_follower import LAWS
from mechopt.solvers.loom import codesign_machine_speed
from mechopt.solvers.stop_impact import law_of, shape_cam, synthesise_law

# The lift cam whose law is synthesised: its scene states the cam's geometry (base and roller
# radii, centre distance, upper dwell, bore) and its phase on the shaft (from the loom's cyclogram)
LIFT_CAM = "stop-impact/lift-cam-profile"
LIFT_START = "3"            # the loom's event where the lift's rise begins: operation (3,7), as the co-design names it

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


@shop_drawing(synthesise_law)
def synthesised_cam(run) -> list:
    """The lift cam cut to the synthesised law at its phase angle t_deg, placed on its shaft as
    stop-impact/lift-cam-profile places it (its phase derived from the loom's cyclogram)."""
    from mechopt import registry  # the spine's scene look-up, at call time (it imports the figures)
    lift = registry.run(LIFT_CAM)          # its task as posed: the phase derived from the cyclogram
    return _lift_cam(run, lift, run.task, run.values["t_deg"], stated_phase(lift))


@shop_drawing(codesign_machine_speed)
def codesigned_cam(run) -> list:
    """The lift cam cut to the co-designed law at the re-planned t(3,7), placed on its shaft by the
    re-planned cyclogram itself: the rise begins at event 3 (`p_3_deg`, the start of operation (3,7))."""
    from mechopt import registry
    lift = registry.run(LIFT_CAM)
    event = run.task.events.get(LIFT_START, {}).get("what", "the start of operation (3,7)")
    phase = Phase(run.values[f"p_{LIFT_START}_deg"], f"{run.scene.id}'s re-planned cyclogram, event {LIFT_START}: {event}")
    return _lift_cam(run, lift, run.task.lever_model, run.values["t_3_7_deg"], phase)


def _lift_cam(run, lift, lever, t_deg, phase) -> list:
    """The lift cam cut to `run`'s synthesised law: the geometry and bore of stop-impact/lift-cam-profile
    (`lift`, its Run); the lever's arms and stroke of `lever`; the rise over `t_deg` and the return
    with the same law over the same angle (as the lift cam's scene reads its return). The drawing's
    notes say where each comes from."""
    law = law_of(run.result)
    shape = dataclasses.replace(lift.task, stroke_mm=lever.stroke_mm, a_mm=lever.a_mm, b_mm=lever.b_mm,
                                rise_deg=t_deg, return_deg=t_deg)
    cam = shape_cam(shape, lambda xi: tuple(law.values(xi)[:3]), **lift.settings)      # its samples
    if cam.status is not Status.SOLVED:
        raise NothingToExport(f"{run.scene.id}: the lift cam cut to the synthesised law is {cam.status.value}, "
                              f"nothing exported as DXF ({cam.message})")
    notes = [f"LAW: {law} of {run.scene.id}; rise and return over t = {t_deg:.6g} deg",
             f"CAM: {LIFT_CAM}'s base, roller, centre distance, dwell and bore; lever arms and stroke of {run.scene.id}",
             f"MAX PRESSURE ANGLE {cam.values['max_pressure_angle_deg']:.4g} deg, least pitch radius of curvature "
             f"{cam.values['min_radius_of_curvature_mm']:.4g} mm"]
    return cam_drawing(shape, cam, phase, notes)
