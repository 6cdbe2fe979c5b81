"""Figures of a sweep table (`mechopt.sweep`): an output against one swept key, or a map over two.

Solved variants are drawn filled; any other status (infeasible, inaccurate, invalid, ...) is
marked with a red cross, at its value when the solver gave one and on the axis floor otherwise,
so a designer sees where the answer stops being an answer.
"""
from pathlib import Path

import numpy as np

from mechopt.plots import save_figure

__all__ = ["plot_sweep", "outputs_of"]

_NOT_OUTPUTS = {"variant", "status", "message", "build_s", "solve_s"}


def outputs_of(table, scene=None) -> list[str]:
    """The outputs worth drawing: the scene's numeric expectations found in the table, else the first value."""
    keys = _swept(table)
    values = [c for c in table.column_names if c not in _NOT_OUTPUTS and c not in keys]
    wanted = [name for name in (scene.spec.expect if scene else ()) if name in values]
    return wanted or values[:1]


def plot_sweep(table, out_dir, *, scene=None, outputs=None) -> list[Path]:
    """Write one PNG per output into `out_dir`: a line against the swept key (one key) or a map
    over the first two swept keys (colour = output). Returns the paths.

    Parameters
    ----------
    table : pyarrow.Table from `mechopt.sweep.sweep` (or `read_table`).
    out_dir : folder, created if needed.
    scene : the swept scene; its expectations choose the default outputs.
    outputs : value columns to draw (default `outputs_of(table, scene)`).
    """
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    keys = _swept(table)
    solved = np.array([s == "SOLVED" for s in table.column("status").to_pylist()])
    paths = []
    for output in outputs or outputs_of(table, scene):
        y = _floats(table, output)
        fig, ax = plt.subplots(figsize=(6.4, 4.6))
        if len(keys) == 1:
            x = _floats(table, keys[0])
            order = np.argsort(x, kind="stable")
            ax.plot(x[order][solved[order]], y[order][solved[order]], "o-", ms=4, label="SOLVED")
            floor = np.nanmin(y) if np.isfinite(y).any() else 0.0
            bad = ~solved
            if bad.any():
                    ax.plot(x[bad], np.where(np.isnan(y[bad]), floor, y[bad]), "x", color="tab:red", ms=7,
                        label="not solved (no value: on the floor)")
            ax.set_xlabel(keys[0])
            ax.set_ylabel(output)
        else:
            x, z = _floats(table, keys[0]), _floats(table, keys[1])
            shown = solved & np.isfinite(y)
            dots = ax.scatter(x[shown], z[shown], c=y[shown], s=60, marker="s", cmap="viridis", label="SOLVED")
            if shown.any():
                fig.colorbar(dots, ax=ax, label=output)
            if (~solved).any():
                ax.plot(x[~solved], z[~solved], "x", color="tab:red", ms=8, label="not solved")
            ax.set_xlabel(keys[0])
            ax.set_ylabel(keys[1])
            more = f" (other swept keys {', '.join(keys[2:])} overlaid)" if len(keys) > 2 else ""
            ax.set_title(f"{output}{more}", fontsize=9)
        ax.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.14), ncol=2, frameon=False)
        ax.grid(alpha=0.3)
        name = f"sweep_{output}_vs_{'_'.join(keys[:2])}.png"
        paths.append(save_figure(fig, out_dir / name))
    return paths


def _swept(table):
    """Swept keys: the columns before `variant` (the sweep writes them first)."""
    names = table.column_names
    return names[:names.index("variant")]


def _floats(table, name):
    return np.array([np.nan if v is None else float(v) for v in table.column(name).to_pylist()])
