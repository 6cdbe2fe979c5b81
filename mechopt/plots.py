"""Pictures of a solved scene, for where a designer would rather look than read."""
from pathlib import Path

import numpy as np


def plot_run(run, out_dir) -> list[Path]:
    """Write the figures of a solved scene into out_dir; returns their paths."""
    import matplotlib
    matplotlib.use("Agg")
    plotter = _PLOTTERS.get(run.scene.task_class.__name__)
    if plotter is None or not {"H_mm", "L_mm"} <= run.result.values.keys():
        return []
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    return plotter(run, out_dir)


def _plot_linkage_fit(run, out_dir):
    import matplotlib.pyplot as plt

    from mechopt.models.cam_linkage import ideal_point, real_point
    from mechopt.solvers.path_deviation import path_distance

    task, _ = run.scene.build(run.overrides)
    H, L = run.result.values["H_mm"], run.result.values["L_mm"]
    t = np.linspace(0.0, task.t_finish_rad, 2000)
    ix, iy = ideal_point(t, task.a_mm, task.h_mm)
    rx, ry = real_point(np.linspace(0, 2 * np.pi, 4000), H, L)
    dist = path_distance(ix, iy, H, L)

    fig, (left, right) = plt.subplots(1, 2, figsize=(12, 5), gridspec_kw={"width_ratios": [1, 1.3]})
    left.plot(rx, ry, lw=1.0, color="tab:orange", label=f"real path: limaçon H={H:.3f}, L={L:.3f} mm")
    left.plot(ix, iy, lw=1.0, ls="--", color="tab:blue", label="ideal path (upper half) and its mirror")
    left.plot(ix, -iy, lw=1.0, ls="--", color="tab:blue")
    left.set_aspect("equal")
    left.set_xlabel("x [mm]")
    left.set_ylabel("y [mm]")
    left.legend(loc="upper left", fontsize=8)
    left.set_title(run.scene.id)

    right.plot(t, dist * 1000, color="tab:orange", label="distance ideal -> real path")
    right.axhline(task.err_width_mm * 1000, color="tab:red", ls=":", label=f"err_width_mm = {task.err_width_mm:g}")
    right.set_xlabel("ideal path parameter t [rad]")
    right.set_ylabel("deviation [µm]")
    right.set_title(f"max {run.result.values['max_deviation_mm'] * 1000:.2f} µm ({run.result.status.value})")
    right.legend(fontsize=8)
    fig.tight_layout()
    path = out_dir / f"{run.scene.id.replace('/', '_')}.png"
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return [path]


_PLOTTERS = {"LinkageFit": _plot_linkage_fit}
