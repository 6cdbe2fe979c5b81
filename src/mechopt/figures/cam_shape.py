"""Figures of a cam for the shop (models/cam_shape.py): the profile as drawn (pitch curve and the
flanks), and the pitch curve's curvature and pressure
angle against the cam angle. They read the Result's arrays only."""
import numpy as np

from mechopt.dxf import ShopCurve, shop_drawing
from mechopt.figures.registry import figure, new_figure
from mechopt.figures.text import literal
from mechopt.solvers.stop_impact import cam_profile

# the cam's curves in the shop's drawing: the solver's point tables, each on its layer (DXF colour index)
CAM_LAYERS = {"profile": ("CAM_PROFILE", 7), "groove_outer": ("CAM_GROOVE_OUTER", 5), "pitch": ("PITCH_CURVE", 1)}
CURVES = {"pitch": ("pitch curve", "tab:red", "--"), "profile": ("cam profile", "black", "-"),
          "groove_outer": ("groove, outer wall", "tab:blue", "-")}


@figure(cam_profile)
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
def cam_shop_curves(run) -> list[ShopCurve]:
    """The cam for the shop: each point table the solver returned, with its measured chordal error."""
    arrays, errors = run.arrays, run.result.diagnostics["chord_error_mm"]
    return [ShopCurve(layer, np.column_stack([arrays[f"{name}_x_mm"], arrays[f"{name}_y_mm"]]), errors[name], name,
                      colour=colour)
            for name, (layer, colour) in CAM_LAYERS.items() if f"{name}_x_mm" in arrays]
