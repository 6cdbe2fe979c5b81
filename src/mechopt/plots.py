"""Pictures of a solved scene, for where a designer would rather look than read.

The figures of a task from `models/<module>.py` live in `mechopt/figures/<module>.py`, as
`plot(run, out_dir) -> list[Path]`; a model without such a module has no figures yet.
"""
import importlib
from pathlib import Path


def plot_run(run, out_dir) -> list[Path]:
    """Write the figures of a solved scene into out_dir; returns their paths."""
    import matplotlib
    matplotlib.use("Agg")
    module = run.scene.task_class.__module__.rpartition(".")[2]
    try:
        figures = importlib.import_module(f"mechopt.figures.{module}")
    except ModuleNotFoundError:
        return []
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    return figures.plot(run, out_dir)


def save_figure(fig, path, *, dpi=110) -> Path:
    """Lay out, write and close a matplotlib figure (closing frees it: sweeps draw many)."""
    import matplotlib.pyplot as plt
    fig.tight_layout()
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
    return Path(path)
