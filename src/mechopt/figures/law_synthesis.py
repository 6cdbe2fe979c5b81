"""Figures of a synthesised cam law: the law's travel and analogues beside the library
laws at the same phase angle, its predicted rebound against speed with the limit, and for the
co-designed machine the re-planned timing diagram. They read the Result's arrays only.

The shop's drawing of a synthesised law (`--dxf`) is the lift cam cut to it, as its solver
returned it (arrays `cam_...`: solvers/stop_impact/cam_shape.py `law_cam`), drawn by
`mechopt.cam_sheet.sheet_of`."""
import numpy as np

from mechopt.cam_sheet import Phase, sheet_of
from mechopt.dxf import NothingToExport, shop_drawing
from mechopt.figures.cam_shape import phase_stated
from mechopt.figures.cyclogram import gantt
from mechopt.figures.registry import figure, new_figure
from mechopt.figures.text import literal
from mechopt.kit.result import Status
from mechopt.models.cam_follower import LAWS
from mechopt.solvers.loom import codesign_machine_speed
from mechopt.solvers.stop_impact import SHOP_PREFIX, law_of, synthesise_law

# The lift cam whose law is synthesised: its scene states the cam's bore and its phase on the shaft
# (from the loom's cyclogram); the cam's geometry is the solver's (its cam_* settings)
LIFT_CAM = "stop-impact/lift-cam-profile"

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
    """The lift cam cut to the synthesised law at its phase angle t_deg, as the solver returned it
    (arrays `cam_...`, diagnostics `cam`: solvers/stop_impact/cam_shape.py `law_cam`), its bore and
    phase on the shaft as stop-impact/lift-cam-profile states them (the phase derived from the loom's
    cyclogram: that scene posed, not solved)."""
    from mechopt import registry  # the spine's scene look-up, at call time (it imports the figures)
    lift, _ = registry.pose(LIFT_CAM)
    return _lift_cam(run, lift.bore_diameter_mm, phase_stated(registry.find(LIFT_CAM), lift, {}))


@shop_drawing(codesign_machine_speed)
def codesigned_cam(run) -> list:
    """The lift cam cut to the co-designed law at the re-planned t(3,7), as the solver returned it,
    placed on its shaft by the re-planned cyclogram itself: the rise begins at the event the solver
    names (event 3, `p_3_deg`, the start of operation (3,7)); the bore stop-impact/lift-cam-profile's."""
    from mechopt import registry
    cam = run.result.diagnostics.get("cam", {})
    phase = None if "rise_start_shaft_deg" not in cam else Phase(
        cam["rise_start_shaft_deg"], f"{run.scene.id}'s re-planned cyclogram, event {cam['phase_event']}: "
                                     f"{cam['phase_event_what']}")
    return _lift_cam(run, registry.find(LIFT_CAM).build()[0].bore_diameter_mm, phase)


def _lift_cam(run, bore_diameter_mm, phase) -> list:
    """The drawing of the cam `run`'s solver cut to its law (`mechopt.cam_sheet.sheet_of` on its
    arrays `cam_...`); the notes say where the law, the cam and the bore come from."""
    cam = run.result.diagnostics.get("cam", {})
    if cam.get("status") != Status.SOLVED.value:
        raise NothingToExport(f"{run.scene.id}: the lift cam cut to the synthesised law is "
                              f"{cam.get('status', 'not made')}, nothing exported as DXF ({cam.get('message', '')})")
    g = cam["geometry"]
    notes = [f"LAW: {law_of(run.result)} of {run.scene.id}; rise and return over t = {cam['t_deg']:.6g} deg",
             f"CAM: base {g['base_radius_mm']:g} mm, roller {g['roller_radius_mm']:g} mm, centre distance "
             f"{g['centre_distance_mm']:g} mm, dwell {g['dwell_deg']:g} deg, lever arms and stroke of {run.scene.id}; "
             f"bore of {LIFT_CAM}",
             f"MAX PRESSURE ANGLE {cam['max_pressure_angle_deg']:.4g} deg, least pitch radius of curvature "
             f"{cam['min_radius_of_curvature_mm']:.4g} mm"]
    return sheet_of(run.arrays, cam["chord_error_mm"], prefix=SHOP_PREFIX, rise_start_deg=cam["rise_start_deg"],
                    bore_diameter_mm=bore_diameter_mm, sense=cam["sense"], phase=phase, notes=notes)
