"""Figures of a cam with any follower (solvers/cam): the cam as drawn (pitch curve, profile, a
groove's other wall), its pressure angle and radii against the cam angle, its forces and contact
stress; and the least base radius search's criterion against the base radius. They read the
Result's arrays only. `size_cam`'s drawing for the shop is `mechopt.cam_sheet`'s."""
import numpy as np

from mechopt.cam_sheet import bore_stated, sheet_of
from mechopt.dxf import drawable_if, shop_drawing
from mechopt.figures.cam_shape import stated_phase
from mechopt.figures.registry import figure, new_figure
from mechopt.figures.text import literal
from mechopt.solvers.cam import least_base_radius, size_cam

CURVES = {"pitch": ("pitch curve", "tab:red", "--"), "profile": ("cam profile", "black", "-"),
          "groove_outer": ("groove, other wall", "tab:blue", "-")}


@figure(size_cam)
def cam_figures(run) -> dict:
    a = run.arrays
    fig = new_figure(figsize=(6, 6))
    ax = fig.add_subplot()
    for name, (label, colour, style) in CURVES.items():
        if f"{name}_x_mm" in a and (name != "pitch" or run.task.face == "roller"):     # a flat face's pitch is its profile
            ax.plot(np.r_[a[f"{name}_x_mm"], a[f"{name}_x_mm"][:1]], np.r_[a[f"{name}_y_mm"], a[f"{name}_y_mm"][:1]],
                    style, color=colour, lw=1, label=label)
    ax.plot([0], [0], "k+")
    ax.set(aspect="equal", xlabel="x [mm] (cam frame, cam angle 0)", ylabel="y [mm]",
           title=f"{literal(run.scene.id)}: {run.task.follower} {run.task.face} follower, {run.task.sense} cam")
    ax.legend(fontsize=8, loc="upper right")
    out = {"profile": fig}
    fig2 = new_figure(figsize=(7, 7))
    rows = fig2.subplots(3, 1, sharex=True)
    rows[0].plot(a["cam_angle_deg"], a["s_mm"], lw=1)
    rows[0].set_ylabel("follower s [mm]")
    rows[1].plot(a["cam_angle_deg"], a["pressure_angle_deg"], lw=1)
    rows[1].axhline(run.task.max_pressure_angle_deg, color="tab:red", lw=0.8, ls=":")
    rows[1].axhline(-run.task.max_pressure_angle_deg, color="tab:red", lw=0.8, ls=":")
    rows[1].set_ylabel("pressure angle [deg]\n(signed)")
    rows[2].plot(a["cam_angle_deg"], 1.0 / np.asarray(a["profile_radius_mm"]), lw=1)
    rows[2].axhline(0, color="grey", lw=0.5)
    rows[2].set(ylabel="profile curvature [1/mm]\n(> 0 convex)", xlabel="cam angle [deg]")
    out["kinematics"] = fig2
    if "follower_force_N" in a:
        fig3 = new_figure(figsize=(7, 5))
        top, bottom = fig3.subplots(2, 1, sharex=True)
        top.plot(a["cam_angle_deg"], a["follower_force_N"], lw=1, label="follower force Q")
        top.plot(a["cam_angle_deg"], a["contact_force_N"], lw=1, label="contact force N")
        top.axhline(0, color="grey", lw=0.5)
        top.set_ylabel("force [N]")
        top.legend(fontsize=8)
        if "contact_stress_MPa" in a:
            bottom.plot(a["cam_angle_deg"], a["contact_stress_MPa"], lw=1)
        bottom.set(ylabel="Hertz stress [MPa]", xlabel="cam angle [deg]")
        out["forces"] = fig3
    return out


@figure(least_base_radius)
def base_radius_figures(run) -> dict:
    a = run.arrays
    if "grid_base_radius_mm" not in a:
        return {}
    fig = new_figure(figsize=(6, 4))
    ax = fig.add_subplot()
    name = "grid_profile_radius_mm" if "grid_profile_radius_mm" in a else "grid_pressure_angle_deg"
    ax.plot(a["grid_base_radius_mm"], a[name], "o-", ms=3, lw=1)
    if "least_base_radius_mm" in run.values:
        ax.axvline(run.values["least_base_radius_mm"], color="tab:red", lw=0.8, ls=":", label="least base radius")
        ax.legend(fontsize=8)
    ax.set(xlabel="base radius [mm]", ylabel=("least profile radius [mm]" if "profile" in name
                                              else "largest pressure angle [deg]"), title=literal(run.scene.id))
    return {"criterion": fig}


@shop_drawing(size_cam)
@drawable_if(bore_stated)
def cam_shop_drawing(run) -> list:
    """The cam for the shop (`mechopt.cam_sheet.sheet_of`): the solver's point tables with their
    measured chordal errors, the centre and bore, the rise-start mark, the sense of rotation and the
    phase on the shaft where the scene states `rise_start_shaft_deg`. A task without a bore is
    refused before the solve (`bore_stated`)."""
    task, diagnostics = run.task, run.result.diagnostics
    notes = (f"{task.follower} {task.face} follower; the cam as it stands at cam angle 0",)
    if task.face == "flat":
        notes += ("flat face: PITCH_CURVE is the profile itself",)
    return sheet_of(run.arrays, diagnostics["chord_error_mm"], rise_start_deg=diagnostics["rise_start_deg"],
                    bore_diameter_mm=task.bore_diameter_mm, sense=task.sense, phase=stated_phase(run), notes=notes)
