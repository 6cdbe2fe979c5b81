"""Pictures of a solved scene, for where a designer would rather look than read: drawn by the
functions registered in `mechopt.figures`, saved here."""
from pathlib import Path

from mechopt.figures.registry import figures_of


def figures(run) -> dict:
    """The figures of a solved scene as matplotlib Figures, by name (for a notebook: no files)."""
    return figures_of(run)


def plot_run(run, out_dir) -> list[Path]:
    """Write the figures of a solved scene into out_dir as `<scene>_<name>.png`; their paths."""
    from mechopt.files import make_folder
    out_dir = make_folder(out_dir)
    stem = run.scene.id.replace("/", "_")
    return [save_figure(fig, out_dir / f"{stem}_{name}.png") for name, fig in figures(run).items()]


def save_figure(fig, path, *, dpi=110) -> Path:
    """Lay out, write (whole or not at all: drawn in memory, then renamed into place, so Ctrl-C
    or a full disk leaves no truncated PNG) and release a matplotlib figure (sweeps draw many)."""
    import io

    from mechopt.files import write_bytes_atomic
    try:
        fig.tight_layout()
        image = io.BytesIO()
        fig.savefig(image, dpi=dpi, format=Path(path).suffix.lstrip(".") or "png")
        write_bytes_atomic(path, image.getvalue())
    finally:
        if fig.canvas.manager is not None:      # a pyplot figure: pyplot keeps it until closed
            import matplotlib.pyplot as plt
            plt.close(fig)
    return Path(path)
