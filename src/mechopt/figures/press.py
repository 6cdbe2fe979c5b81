"""Figures for the crank press scenes (models/press.py), after the paper's Figs. 8-10."""
import numpy as np

from mechopt.figures.registry import figure, new_figure
from mechopt.figures.text import literal
from mechopt.solvers.press import (
    catalogue,
    design,
    events,
    flywheel,
    ivp,
    kinematics,
    loads,
    rk4,
    sensitivity,
    simulate,
    steady_state,
)


@figure(events, steady_state, rk4, ivp, simulate, flywheel)
def cycle(run):
    """Force F and load Q against tool travel and crank angle (Figs. 8-10), crank speed and belt
    torque against time; one PNG per scene."""
    arrays = run.result.arrays
    if not len(arrays.get("t_s", ())):
        return {}
    t, w, out = arrays["t_s"], arrays["omega_rad_s"], arrays
    phi_deg = np.degrees(arrays["phi_rad"]) % 360
    cutting = arrays["cutting"] > 0
    task = run.task

    fig = new_figure(figsize=(12, 8))
    ax = fig.subplots(2, 2)
    if cutting.any():
        pen = out["penetration_mm"]
        ax[0, 0].plot(pen[cutting], out["force_N"][cutting], ".", ms=3, label="F, eq. (1) (Fig. 8)")
        ax[0, 0].plot(pen[cutting], out["Q_N"][cutting], ".", ms=3, label="Q = F + m (X'' - g) (Fig. 9)")
        ax[0, 0].set_xlabel("tool penetration X - (H - Z - delta) [mm]")
        ax[0, 0].legend(fontsize=8)
        ax[0, 1].plot(phi_deg[cutting], out["force_N"][cutting], ".", ms=3, label="F")
        ax[0, 1].plot(phi_deg[cutting], out["Q_N"][cutting], ".", ms=3, label="Q (Fig. 10)")
        ax[0, 1].set_xlabel("crank angle [deg]")
        ax[0, 1].legend(fontsize=8)
    ax[0, 0].set_ylabel("force [N]")
    ax[0, 0].set_title("cutting force and load against tool travel")
    ax[0, 1].set_title("against crank angle, during the cut")
    ax[1, 0].plot(t, w, lw=1)
    ax[1, 0].set_xlabel("t [s]")
    ax[1, 0].set_ylabel("crank speed omega_k [rad/s]")
    ax[1, 1].plot(t, out["belt_torque_Nm"], lw=1)
    ax[1, 1].set_xlabel("t [s]")
    ax[1, 1].set_ylabel("belt torque [N m]" if task.belt else "motor torque, reduced [N m]")
    for a in ax.ravel():
        a.grid(alpha=0.3)
    fig.suptitle(f"{literal(run.scene.id)}: {run.result.status.value}", fontsize=10)
    return {"cycle": fig}


@figure(kinematics)
def rates(run):
    """The slider's travel, velocity and acceleration and the rod's angle and rates over a turn."""
    a = run.result.arrays
    fig = new_figure(figsize=(12, 7))
    ax = fig.subplots(2, 3, sharex=True)
    for axis, (name, label) in zip(ax.ravel(), [
            ("travel_mm", "slider travel X [mm]"), ("slider_velocity_m_s", "slider velocity [m/s]"),
            ("slider_acceleration_m_s2", "slider acceleration [m/s²]"), ("rod_angle_deg", "rod angle β [deg]"),
            ("rod_angular_velocity_rad_s", "rod angular velocity [rad/s]"),
            ("rod_angular_acceleration_rad_s2", "rod angular acceleration [rad/s²]")]):
        axis.plot(a["crank_angle_deg"], a[name], lw=1.2)
        axis.set_ylabel(label)
        axis.grid(alpha=0.3)
    for axis in ax[1]:
        axis.set_xlabel("crank angle from top dead centre [deg]")
    fig.suptitle(f"{literal(run.scene.id)}: {literal(run.result.message)}", fontsize=9)
    return {"rates": fig}


@figure(loads)
def cycle_and_loads(run):
    """The cycle figure and the loads of one steady revolution."""
    figures = cycle(run)
    if figures:
        figures["loads"] = _loads(run, np.degrees(run.result.arrays["phi_rad"]))     # 0 to 360, not wrapped
    return figures


def _loads(run, phi_deg):
    """Forces and torques against crank angle over the revolution and against tool travel (down and
    up strokes apart), the cut's Q readings as in Figs. 9-10; the peaks marked."""
    a, v = run.result.arrays, run.result.values
    X = a["travel_mm"]
    down = np.gradient(X) >= 0
    forces = [("rod_force_N", "rod force, tool end"), ("main_bearing_load_N", "main-bearing load |pin force|"),
              ("Q_N", "Q = F + m (X'' - g), our reading of Figs. 9-10"), ("force_N", "F, eq. (1)")]
    torques = [("crank_torque_Nm", "crank torque (shaft to linkage)"), ("belt_torque_Nm", "belt torque"),
               ("motor_torque_Nm", "motor torque, reduced to the crank")]
    fig = new_figure(figsize=(12, 8))
    ax = fig.subplots(2, 2)
    for key, label in forces:
        ax[0, 0].plot(phi_deg, a[key], lw=1, label=label)
        ax[1, 0].plot(np.where(down, X, np.nan), a[key], lw=1, label=f"{label} (down)")
    for key, label in torques:
        ax[0, 1].plot(phi_deg, a[key], lw=1, label=label)
        ax[1, 1].plot(np.where(down, X, np.nan), a[key], lw=1, label=f"{label} (down)")
        ax[1, 1].plot(np.where(down, np.nan, X), a[key], lw=1, ls="--", label=f"{label} (up)")
    ax[0, 0].plot(v["peak_rod_force_at_deg"], v["peak_rod_force_N"], "kv", label="peak rod force")
    ax[0, 1].plot(v["peak_crank_torque_at_deg"], v["peak_crank_torque_Nm"], "kv", label="peak crank torque")
    ax[1, 0].plot(v["peak_rod_force_at_mm"], v["peak_rod_force_N"], "kv", label="peak rod force")
    for row in ax:
        row[0].set_ylabel("force [N]")
        row[1].set_ylabel("torque [N m]")
    for a_ in ax[0]:
        a_.set_xlabel("crank angle from top dead centre [deg]")
    for a_ in ax[1]:
        a_.set_xlabel("tool travel X [mm]")
    ax[0, 0].set_title("forces over the revolution")
    ax[0, 1].set_title("torques over the revolution")
    ax[1, 0].set_title("forces against tool travel, down stroke (Figs. 9-10)")
    ax[1, 1].set_title("torques against tool travel")
    for a_ in ax.ravel():
        a_.grid(alpha=0.3)
        a_.legend(fontsize=7)
    fig.suptitle(f"{literal(run.scene.id)}: loads over one steady revolution ({run.result.status.value})", fontsize=10)
    return fig


@figure(sensitivity)
def elasticities(run):
    """Bar chart of the elasticities (p / y) dy/dp of press.sensitivity: one panel per output, one bar
    per assumed parameter, longest first in the speed fluctuation's panel."""
    a, rows = run.result.arrays, run.result.diagnostics.get("parameters", [])
    outputs = [k.removeprefix("elasticity_") for k in a if k.startswith("elasticity_")
               and np.any(a[k] != 0)]                          # an output no parameter moves has no panel
    if not rows or not outputs:
        return {}
    order = np.argsort(np.abs(a["elasticity_speed_fluctuation"]))
    ncols = min(3, len(outputs))            # at most three panels a row: a page shows it near full size
    nrows = -(-len(outputs) // ncols)
    fig = new_figure(figsize=(4 * ncols + 1.5, 0.25 * len(rows) * nrows + 1.2 * nrows + 0.8))
    axes = fig.subplots(nrows, ncols, sharey=True, squeeze=False).ravel()
    for ax, name in zip(axes, outputs):
        ax.barh(np.arange(len(rows)), a[f"elasticity_{name}"][order])
        ax.set_title(literal(name), fontsize=9)
        ax.axvline(0, color="k", lw=0.5)
        ax.grid(alpha=0.3, axis="x")
        ax.tick_params(axis="y", labelsize=8)
    for ax in axes[len(outputs):]:
        ax.remove()                          # the grid's empty places: no panel
    axes[0].set_yticks(np.arange(len(rows)), [literal(rows[i]) for i in order], fontsize=8)
    fig.supxlabel("elasticity: % change of the output per % change of the parameter")
    fig.suptitle(f"{literal(run.scene.id)}: what the periodic motion owes to each assumed value "
                 f"({run.result.status.value})", fontsize=10)
    return {"elasticities": fig}


@figure(design, catalogue)
def designed(run):
    """The designed drive's steady revolution (the cycle figure) and its limits: crank speed against
    crank angle with the fluctuation band the design keeps, belt and motor torque with their limits."""
    figures = cycle(run)
    arrays, task, values = run.result.arrays, run.task, run.result.values
    if not figures:
        return figures
    phi_deg = np.degrees(arrays["phi_rad"])
    fig = new_figure(figsize=(12, 5))
    ax = fig.subplots(1, 2)
    w = arrays["omega_rad_s"]
    ax[0].plot(phi_deg, w, lw=1, label="crank speed at the optimum")
    if task.max_speed_fluctuation is not None:
        mean = values["omega_mean_rad_s"]
        top = w.max()
        ax[0].axhspan(top - task.max_speed_fluctuation * mean, top, color="C2", alpha=0.15,
                      label=f"allowed band: max_speed_fluctuation = {task.max_speed_fluctuation:g}")
    ax[0].set_xlabel("crank angle [deg]")
    ax[0].set_ylabel("omega_k [rad/s]")
    ax[0].set_title("speed over the steady revolution")
    ax[1].plot(phi_deg, arrays["belt_torque_Nm"], lw=1, label="belt torque at the crank shaft")
    if task.belt_slip_torque_Nm is not None:
        ax[1].axhline(task.belt_slip_torque_Nm, color="C0", ls="--", lw=1, label="belt slip limit")
    if task.motor:
        shaft = arrays["motor_torque_Nm"] / values["gear_ratio"]
        ax[1].plot(phi_deg, shaft, lw=1, label="motor shaft torque")
        ax[1].axhline(values["motor_rms_torque_N_m"], color="C1", ls=":", lw=1, label="motor RMS torque")
        if task.motor_safety_factor is not None:
            ax[1].axhline(values["motor_breakdown_torque_Nm"] / task.motor_safety_factor, color="C1", ls="--", lw=1,
                          label="breakdown torque / safety factor")
    ax[1].set_xlabel("crank angle [deg]")
    ax[1].set_ylabel("torque [N m]")
    ax[1].set_title("torques and their limits")
    for a in ax:
        a.grid(alpha=0.3)
        a.legend(fontsize=7)
    design = ", ".join(f"{k} = {values[k]:.4g}" for k in task.variables)
    fig.suptitle(f"{literal(run.scene.id)}: {literal(task.objective)} -> {literal(design)} "
                 f"({run.result.status.value})", fontsize=10)
    return figures | {"design": fig}
