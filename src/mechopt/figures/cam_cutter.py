"""Figures for the cam-cutting linkage scenes (models/cam_cutter.py): drawn from the solvers'
arrays (the path, its deviation, the whole limaçon of the linkage found)."""
import numpy as np

from mechopt.dxf import NothingToExport, ShopCurve, shop_drawing
from mechopt.figures.registry import figure, new_figure
from mechopt.figures.text import literal
from mechopt.models.cam_cutter import ideal_point, real_point
from mechopt.models.cam_profile import ProfileFit
from mechopt.models.cam_shape import mirrored, point_table
from mechopt.solvers.cam_cutter import (
    check,
    evolve,
    evolve_family,
    fit_linkage,
    grid_scan,
    joint_loads,
    minimax,
    readjustable,
    robust,
)

TORCH_TOL_MM = 0.001            # the torch path's chordal error in the shop's drawing: a tenth of the paper's H, L precision
AXIS_REL = 1e-7                 # an end this close to the x axis (relative to the cam) closes by its mirror
TORCH_COLOUR, IDEAL_COLOUR = 3, 8         # DXF colour indices of the two layers


@figure(grid_scan, robust, evolve, check)
def paths_and_deviation(run):
    """The two paths and the deviation along the ideal path, with the band."""
    task = run.task
    # the linkage a solver found, or the one a check was given
    H = run.result.values.get("H_mm", getattr(task, "H_mm", None))
    L = run.result.values.get("L_mm", getattr(task, "L_mm", None))
    a = run.result.arrays
    if H is None or L is None or not len(a.get("t_rad", ())):
        return {}             # no linkage found (an infeasible grid scan): nothing to draw

    t, ix, iy, dist = a["t_rad"], a["path_x_mm"], a["path_y_mm"], a["deviation_mm"]
    rx, ry = a["turn_x_mm"], a["turn_y_mm"]      # the real path: the whole limaçon

    fig = new_figure(figsize=(12, 5))
    left, right = fig.subplots(1, 2, gridspec_kw={"width_ratios": [1, 1.3]})
    left.plot(rx, ry, lw=1.0, color="tab:orange", label=f"real path: limaçon H={H:.3f}, L={L:.3f} mm")
    left.plot(ix, iy, lw=1.0, ls="--", color="tab:blue", label="ideal path (upper half) and its mirror")
    left.plot(ix, -iy, lw=1.0, ls="--", color="tab:blue")
    # the double point, where the paper's test is ill-posed, is invisible at full scale: zoom on it
    zoom = left.inset_axes([0.55, 0.06, 0.42, 0.42])
    zoom.plot(rx, ry, lw=1.0, color="tab:orange")
    zoom.plot(ix, iy, lw=1.0, ls="--", color="tab:blue")
    zoom.plot(ix, -iy, lw=1.0, ls="--", color="tab:blue")
    cx, span = -(H + L), 0.6
    zoom.set_xlim(cx - span, cx + span)
    zoom.set_ylim(-span, span)
    zoom.set_title("double point ±0.6 mm", fontsize=7)
    zoom.tick_params(labelsize=6)
    zoom.locator_params(nbins=3)
    left.indicate_inset_zoom(zoom, edgecolor="grey")
    left.set_aspect("equal")
    left.set_xlabel("x [mm]")
    left.set_ylabel("y [mm]")
    left.legend(loc="upper left", fontsize=8)
    left.set_title(literal(run.scene.id))

    right.plot(t, dist * 1000, color="tab:orange", label="distance ideal -> real path")
    right.axhline(task.err_width_mm * 1000, color="tab:red", ls=":", label=f"band: err_width = {task.err_width_mm * 1000:g} µm")
    right.set_xlabel("ideal path parameter t [rad]")
    right.set_ylabel("deviation [µm]")
    right.set_title(f"max {run.result.values['max_deviation_mm'] * 1000:.2f} µm ({run.result.status.value})")
    right.legend(fontsize=8)
    return {"paths": fig}


@figure(minimax, fit_linkage)
def fitted_paths(run):
    """The paths of a fitted linkage: a cam of any shape (`ProfileFit`) drawn as its torch path,
    the paper's cardioid as the ideal path (the task says which question was asked)."""
    return profile_path_and_band(run) if isinstance(run.task, ProfileFit) else paths_and_deviation(run)


@figure(joint_loads)
def reactions_and_torque(run):
    """Reactions in the pairs and the driving torque over the cycle, with the condition number."""
    arrays = run.result.arrays
    if not arrays.get("phi_rad", np.empty(0)).size:
        return {}             # no regular angle: nothing to draw
    phi = np.degrees(arrays["phi_rad"])
    fig = new_figure(figsize=(12, 7))
    top, middle, bottom = fig.subplots(3, 1, sharex=True, gridspec_kw={"height_ratios": [2, 1, 1]})
    for pair, label in (("O1", "crank bearing O1"), ("P", "crank pin P"), ("O", "block pivot O"),
                        ("O_slide", "block on link (normal force)")):
        top.semilogy(phi, arrays[f"R_{pair}_N"], lw=1.0, label=label)
    top.set_ylabel("reaction [N]")
    top.set_title(f"{literal(run.scene.id)}: reactions grow as 1/|cos(phi/2)| where the crank pin crosses O "
                  f"({run.result.status.value})", fontsize=9)
    top.legend(fontsize=8, ncol=2)
    middle.plot(phi, arrays["M_N_m"], color="black", lw=1.0)
    middle.set_ylabel("driving torque [N m]")
    bottom.semilogy(phi, arrays["condition_number"], color="tab:red", lw=1.0)
    bottom.set_ylabel("cond A")
    bottom.set_xlabel("crank angle phi [deg] (the link turns once in two crank turns)")
    for ax in (top, middle, bottom):
        for singular in (180, 540):
            ax.axvline(singular, color="grey", ls=":", lw=0.8)
    return {"loads": fig}


def profile_path_and_band(run):
    """A cam of any shape: its torch path (and mirror), the limaçon, the deviation with the band
    and the point that sets it."""
    task, values, a = run.task, run.result.values, run.result.arrays
    if "H_mm" not in values or not len(a.get("t_rad", ())):
        return {}             # the NLP failed: no linkage to draw
    H, L = values["H_mm"], values["L_mm"]
    t, ix, iy, dist = a["t_rad"], a["path_x_mm"], a["path_y_mm"], a["deviation_mm"]
    rx, ry = a["turn_x_mm"], a["turn_y_mm"]      # the real path: the whole limaçon
    fig = new_figure(figsize=(12, 5))
    left, right = fig.subplots(1, 2, gridspec_kw={"width_ratios": [1, 1.3]})
    left.plot(rx, ry, lw=1.0, color="tab:orange", label=f"limaçon H={H:.3f}, L={L:.3f} mm")
    left.plot(ix, iy, lw=1.0, ls="--", color="tab:blue", label=f"torch path (kerf h = {task.h_mm:g} mm) and mirror")
    left.plot(ix, -iy, lw=1.0, ls="--", color="tab:blue")
    where = run.result.diagnostics.get("max_deviation_at_mm")
    if where:
        left.plot(*where, "x", color="tab:red", ms=9, label="largest deviation")
    left.set_aspect("equal")
    left.set(xlabel="x [mm]", ylabel="y [mm]", title=literal(run.scene.id))
    left.legend(loc="upper left", fontsize=8)
    right.plot(t, dist * 1000, color="tab:orange", label="distance path -> limaçon")
    right.axhline(task.err_width_mm * 1000, color="tab:red", ls=":", label=f"band {task.err_width_mm * 1000:g} µm")
    right.set(xlabel="curve parameter t", ylabel="deviation [µm]",
              title=f"max {values['max_deviation_mm'] * 1000:.2f} µm ({run.result.status.value})")
    right.legend(fontsize=8)
    return {"paths": fig}


@figure(readjustable, evolve_family)
def family_settings(run):
    """The readjustable tool: the wing length L(a) per nozzle h at the one H, and each cam's
    deviation against the band."""
    arrays, values = run.result.arrays, run.result.values
    if "H_mm" not in values or not len(arrays.get("a_mm", ())):
        return {}
    a, h, L, dev = (np.asarray(arrays[k]) for k in ("a_mm", "h_mm", "L_mm", "deviation_mm"))
    fig = new_figure(figsize=(12, 5))
    left, right = fig.subplots(1, 2)
    for nozzle in dict.fromkeys(h):
        mine = h == nozzle
        left.plot(a[mine], L[mine], "o-", label=f"h = {nozzle:g} mm")
        right.plot(a[mine], dev[mine] * 1000, "o-", label=f"h = {nozzle:g} mm")
    left.set(xlabel="cam size a [mm]", ylabel="wing length L [mm]",
             title=f"{literal(run.scene.id)}: settings at one H = {values['H_mm']:.4f} mm")
    right.axhline(run.task.err_width_mm * 1000, color="tab:red", ls=":", label="band")
    served = [values.get(k) for k in ("a_served_min_mm", "a_served_max_mm")]
    if None not in served:
        right.axvspan(*served, color="tab:green", alpha=0.1, label=f"a served: {served[0]:.3f} .. {served[1]:.3f} mm")
    right.set(xlabel="cam size a [mm]", ylabel="deviation [µm]",
              title=f"family worst {values['worst_deviation_mm'] * 1000:.1f} µm ({run.result.status.value})")
    for ax in (left, right):
        ax.legend(fontsize=8)
        ax.grid(alpha=0.3)
    return {"settings": fig}


@shop_drawing(grid_scan, robust, evolve, check, minimax, fit_linkage, joint_loads)
def torch_shop_curves(run) -> list[ShopCurve]:
    """The torch path over the range that is cut, and the ideal path (its upper half closed by
    its mirror, corner at t_FINISH) on another layer.

    The cut is the limaçon (10) of the solved (or given) links from the origin (s = 0) to where it
    first meets the x axis again, closed by its mirror: its double point where |H| > L (the inner
    loop beyond it is not cut: a contour inside the cam's body, the torch would gouge it), else
    s = pi. An ideal path that its mirror does not close is cut open, between the limaçon's
    points nearest its start and its end (the solver's foot points)."""
    task, values = run.task, run.values
    H, L = (values.get(k, getattr(task, k, None)) for k in ("H_mm", "L_mm"))
    if H is None or L is None:
        raise NothingToExport(f"{run.scene.id}: no linkage (H_mm, L_mm) in this result: no torch path to export")
    torch = lambda s: np.array(real_point(s, H, L))             # noqa: E731
    what = f"limacon H={H:.6g} L={L:.6g} mm"
    if not hasattr(task, "t_end_rad"):          # the loads' task knows its links, not the path they follow
        return [_closed_cut(torch, cut_end_rad(H, L), what)]
    if isinstance(task, ProfileFit):
        upper = lambda t: np.array(task.path_point(t))              # noqa: E731
    else:
        upper = lambda t: np.array(ideal_point(t, task.a_mm, task.h_mm))  # noqa: E731
    t0, t1 = task.t_start_rad, task.t_end_rad
    ends = upper(np.array([t0, t1]))
    if np.all(np.abs(ends[1]) <= AXIS_REL * task.size_mm):      # both ends on the axis: the mirror closes it
        ideal = point_table(mirrored(upper, t0, t1), TORCH_TOL_MM, period=2 * (t1 - t0), breaks=(t1 - t0,))
        return [_closed_cut(torch, cut_end_rad(H, L), what),
                ShopCurve("IDEAL_PATH", ideal.xy, ideal.chord_error_mm, "ideal path and its mirror", colour=IDEAL_COLOUR)]
    # drawn as given, from its start to its end; the torch between its foot points
    ideal = point_table(lambda t: upper(t0 + t), TORCH_TOL_MM, period=t1 - t0, closed=False)
    a = run.result.arrays
    s0, s1 = (limacon_parameter(a["limacon_x_mm"][i], a["limacon_y_mm"][i], H, L) for i in (0, -1))
    s1 += 2 * np.pi * (s1 <= s0)
    cut = point_table(lambda s: torch(s0 + s), TORCH_TOL_MM, period=s1 - s0, closed=False)
    return [ShopCurve("TORCH_PATH", cut.xy, cut.chord_error_mm, f"{what}, cut open between the path's ends",
                      closed=False, colour=TORCH_COLOUR),
            ShopCurve("IDEAL_PATH", ideal.xy, ideal.chord_error_mm, "ideal path, open", closed=False,
                      colour=IDEAL_COLOUR)]


def cut_end_rad(H, L) -> float:
    """The crank parameter s in (0, pi] where the limaçon (10) first meets the x axis after the
    origin: y = sin s (L + H cos s) = 0 at its double point s = arccos(-L / H) where |H| > L, else at pi."""
    return float(np.arccos(-L / H)) if abs(H) > abs(L) else float(np.pi)


def limacon_parameter(x, y, H, L) -> float:
    """The crank parameter s of a point on the limaçon (10): about its pole (-(L + H), 0) the point
    is (L + H cos s) (cos s, sin s), so s is the point's polar angle there, or that plus pi where
    L + H cos s < 0 (the inner loop) [rad, in [0, 2 pi)]."""
    polar = float(np.arctan2(y, x + L + H))
    return min((s % (2 * np.pi) for s in (polar, polar + np.pi)),
               key=lambda s: np.hypot(*(np.array(real_point(s, H, L)) - (x, y))))


def _closed_cut(torch, end, what) -> ShopCurve:
    table = point_table(mirrored(torch, 0.0, end), TORCH_TOL_MM, period=2 * end, breaks=(end,))
    return ShopCurve("TORCH_PATH", table.xy, table.chord_error_mm, f"{what}, cut to s = {end:.6g} rad and its mirror",
                     colour=TORCH_COLOUR)
