"""Figures of a cam for the shop (models/cam_shape.py): the profile as drawn (pitch curve and the
flanks), and the pitch curve's curvature and pressure
angle against the cam angle. They read the Result's arrays only. The shop's drawing
(`mechopt.cam_sheet`) adds the centre, bore, rise-start mark, sense and the phase on the shaft."""

import numpy as np

from mechopt.cam_sheet import Phase, bore_stated, sheet_of
from mechopt.dxf import drawable_if, shop_drawing
from mechopt.figures.registry import figure, new_figure
from mechopt.figures.text import literal
from mechopt.models.cam_shape import ORIENTATION
from mechopt.solvers.stop_impact import cam_profile, shape_cam

# the model's convention: its pitch curve runs clockwise as the cam angle grows, the cam turns ccw
SENSE = "ccw" if ORIENTATION == -1 else "cw"
PHASE_KEY = "rise_start_shaft_deg"
CURVES = {"pitch": ("pitch curve", "tab:red", "--"), "profile": ("cam profile", "black", "-"),
          "groove_outer": ("groove, outer wall", "tab:blue", "-")}


@figure(cam_profile, shape_cam)
def cam_shape_figures(run) -> dict:
    arrays, values = run.arrays, run.values
    if "pitch_x_mm" not in arrays:
        return {}
    fig = new_figure(figsize=(6, 6))
    ax = fig.add_subplot()
    for name, (label, colour, style) in CURVES.items():
        if f"{name}_x_mm" in arrays:
            x, y = np.r_[arrays[f"{name}_x_mm"], arrays[f"{name}_x_mm"][:1]], np.r_[arrays[f"{name}_y_mm"],
                                                                                     arrays[f"{name}_y_mm"][:1]]
            ax.plot(x, y, style, color=colour, lw=1, label=f"{label} ({len(x) - 1} points)")
    ax.plot([0], [0], "k+")
    ax.set_aspect("equal")
    ax.set_xlabel("x [mm] (cam frame)")
    ax.set_ylabel("y [mm]")
    ax.set_title(f"{literal(run.scene.id)}: chordal error {values.get('chord_error_mm', float('nan')):.3g} mm")
    ax.legend(fontsize=8, loc="upper right")
    out = {"profile": fig}
    fig2 = new_figure(figsize=(7, 5))
    top, bottom = fig2.subplots(2, 1, sharex=True)
    rho = np.asarray(arrays["radius_of_curvature_mm"])
    top.plot(arrays["cam_angle_deg"], 1.0 / rho, lw=1)        # curvature: no blow-up where rho passes infinity
    top.axhline(0, color="grey", lw=0.5)
    roller = run.result.diagnostics.get("roller_radius_mm")
    if roller:
        top.axhline(1.0 / roller, color="tab:red", lw=0.8, ls=":", label="1 / roller radius: the inner flank undercut above")
        top.legend(fontsize=8)
    top.set_ylabel("pitch curvature [1/mm]\n(> 0 convex)")
    bottom.plot(arrays["cam_angle_deg"], arrays["pressure_angle_deg"], lw=1)
    bottom.set_ylabel("pressure angle [deg]")
    bottom.set_xlabel("cam angle [deg]")
    out["curvature"] = fig2
    return out


@shop_drawing(cam_profile)
@drawable_if(bore_stated)
def cam_shop_curves(run) -> list:
    """The cam for the shop (`mechopt.cam_sheet.sheet_of`): each point table the solver returned
    (its measured chordal error), the centre and bore, the rise-start mark along the pitch curve's
    first vertex (the roller centre at cam angle 0, where the rise begins), the sense, the phase on
    the shaft as the scene states it. A task without a bore is refused before the solve."""
    return sheet_of(run.arrays, run.result.diagnostics["chord_error_mm"], bore_diameter_mm=run.task.bore_diameter_mm,
                    sense=SENSE, phase=stated_phase(run))


def stated_phase(run) -> Phase | None:
    """The cam's phase on its shaft where the scene states it (a --set, a derived value, a
    parameter), with where it comes from; None where it does not."""
    return phase_stated(run.scene, run.task, run.overrides)


def phase_stated(scene, task, overrides) -> Phase | None:
    """`stated_phase` of a scene's task as posed (`registry.pose`), with the overrides it was posed with."""
    spec, value = scene.spec, getattr(task, PHASE_KEY)
    if PHASE_KEY in overrides:
        return Phase(value, f"set by --set {PHASE_KEY}")
    if PHASE_KEY in spec.derive:
        return Phase(value, f"{scene.id} derives it from {spec.derive[PHASE_KEY]}, the cyclogram's event")
    if PHASE_KEY in spec.params:
        p = spec.params[PHASE_KEY]
        return Phase(value, f"{p.mark}: {p.where or p.why or p.on}")
    return None
