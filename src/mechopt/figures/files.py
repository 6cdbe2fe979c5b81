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
    import warnings

    from mechopt.files import write_bytes_atomic
    try:
        with warnings.catch_warnings():     # margins too narrow for a long label: "tight" below holds it
            warnings.filterwarnings("ignore", "Tight layout not applied", UserWarning)
            fig.tight_layout()
        image = io.BytesIO()
        # "tight": the image grows to hold every text (a long operation name is never cut at the edge)
        fig.savefig(image, dpi=dpi, format=Path(path).suffix.lstrip(".") or "png", bbox_inches="tight",
                    pad_inches=0.05)
        write_bytes_atomic(path, image.getvalue())
    finally:
        if fig.canvas.manager is not None:      # a pyplot figure: pyplot keeps it until closed
            import matplotlib.pyplot as plt
            plt.close(fig)
    return Path(path)
