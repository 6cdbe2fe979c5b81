"""Figures for the crank press scenes (models/press.py), after the paper's Figs. 8-10."""
import numpy as np

from mechopt.figures.registry import new_figure, register
from mechopt.models.press import PressDrive


@register(PressDrive)
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
    fig.suptitle(f"{run.scene.id}: {run.result.status.value}", fontsize=10)
    return {"cycle": fig}
