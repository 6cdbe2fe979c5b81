"""Figures of a sweep table (`mechopt.sweep`): what a designer reads at a glance.

- one swept key: the output against it, a line through the solved variants;
- two grid keys: a map, one cell per variant, coloured by the output wherever the variant gave a
  value; any status but SOLVED (infeasible, inaccurate, ...) is hatched over, a cell with no value
  (invalid, failed) is grey with a red cross; the feasibility boundary (SOLVED | not) is a solid
  black line, with a few labelled isolines of the output;
- three grid keys, the third with at most 6 values: one such map per value of the third key on a
  shared colour scale, plus an overview of every value's boundary;
- more values or keys: at most 6 values of the third key, the others held at their middle value,
  and the title says so;
- random points (a ``--random`` axis): a scatter, coloured where SOLVED, red crosses elsewhere.

A not-solved variant is drawn at its value when the solver gave one and on the axis floor otherwise
(line plot), so a designer sees where the answer stops being an answer.
"""
import json
import re
import textwrap
from math import ceil
from pathlib import Path
from typing import NamedTuple

import numpy as np

from mechopt.figures.files import save_figure
from mechopt.figures.text import literal
from mechopt.sweep import META_KEY, check_unique
from mechopt.units import label as axis_label

__all__ = ["plot_sweep", "outputs_of", "grid_of", "boundary_of", "Grid"]

_NOT_OUTPUTS = {"variant", "status", "message", "warnings", "build_s", "solve_s"}
MAX_PANELS = 6          # small multiples beyond this stop being readable side by side


class Grid(NamedTuple):
    """One output of a sweep placed on the cells of two swept keys.

    xs, ys : sorted distinct values of the two keys.
    z : (len(ys), len(xs)) output values; NaN where no variant or no value.
    solved : (len(ys), len(xs)) True where the variant's status is SOLVED.
    status : (len(ys), len(xs)) status words (object array), None where no variant.
    """
    xs: np.ndarray
    ys: np.ndarray
    z: np.ndarray
    solved: np.ndarray
    status: np.ndarray


def outputs_of(table, scene=None) -> list[str]:
    """The outputs worth drawing: the scene's numeric expectations found in the table, else the first value."""
    keys = _swept(table)
    values = [c for c in table.column_names if c not in _NOT_OUTPUTS and c not in keys]
    wanted = [name for name in (scene.spec.expect if scene else ()) if name in values]
    return wanted or values[:1]


def grid_of(table, x_key, y_key, output, where=None) -> Grid:
    """Place `output` of the rows matching `where` on the (`x_key`, `y_key`) cells.

    Parameters
    ----------
    table : sweep table (pyarrow.Table).
    x_key, y_key : swept keys for the columns and rows of the grid.
    output : value column.
    where : {key: value} holding the other swept keys fixed (matched to 1e-9 relative).

    Raises
    ------
    ValueError : when two selected variants fall on one cell (another swept key is not fixed).
    """
    keep = np.ones(table.num_rows, dtype=bool)
    for key, value in (where or {}).items():
        keep &= np.isclose(_floats(table, key), value, rtol=1e-9, atol=0.0)
    x, y, z = _floats(table, x_key)[keep], _floats(table, y_key)[keep], _floats(table, output)[keep]
    status = np.array(table.column("status").to_pylist(), dtype=object)[keep]
    xs, ys = np.unique(x), np.unique(y)
    col, row = np.searchsorted(xs, x), np.searchsorted(ys, y)
    taken = np.zeros((len(ys), len(xs)), dtype=int)
    np.add.at(taken, (row, col), 1)
    if (taken > 1).any():
        r, c = np.argwhere(taken > 1)[0]
        raise ValueError(f"{taken[r, c]} variants fall on the cell {x_key} = {xs[c]:g}, {y_key} = {ys[r]:g}; "
                         f"fix the other swept keys with where={{key: value}}")
    Z = np.full(taken.shape, np.nan)
    S = np.full(taken.shape, None, dtype=object)
    Z[row, col], S[row, col] = z, status
    return Grid(xs, ys, Z, S == "SOLVED", S)


def boundary_of(grid: Grid) -> list[np.ndarray]:
    """The feasibility boundary: lines (arrays of (x, y) vertices) halfway between SOLVED cell
    centres and their not-solved neighbours; cells without a variant are left out. Empty when
    every cell is on one side or the grid is a single row or column."""
    import contourpy
    if len(grid.xs) < 2 or len(grid.ys) < 2:
        return []
    side = np.ma.masked_where(grid.status == None, grid.solved.astype(float))   # noqa: E711 -- elementwise
    if side.count() == 0 or side.min() == side.max():
        return []
    lines = contourpy.contour_generator(grid.xs, grid.ys, side).lines(0.5)
    return [np.asarray(line) for line in lines if len(line) > 1]


def plot_sweep(table, out_dir, *, scene=None, outputs=None) -> list[Path]:
    """Write one PNG per output into `out_dir` (see the module docstring for what is drawn).

    Parameters
    ----------
    table : pyarrow.Table from `mechopt.sweep.sweep` (or `read_table`).
    out_dir : folder, created if needed.
    scene : the swept scene; its expectations choose the default outputs, its id the title.
    outputs : value columns to draw (default `outputs_of(table, scene)`).

    Returns
    -------
    list of Path, one per output: ``sweep_<output>_vs_<key1>[_<key2>][_by_<key3>].png``.

    Raises
    ------
    SceneError : the table holds a variant more than once.
    """
    import matplotlib
    matplotlib.use("Agg")
    case = scene.id if scene else _meta(table).get("case", "sweep")
    check_unique(table, f"sweep table of {case}")     # a twice-written table would draw wrong maps
    title = literal(case)                             # a table from anywhere names its case
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    keys = _swept(table)
    regular = _regular(table, keys)
    paths = []
    for output in outputs or outputs_of(table, scene):
        if table.num_rows == 0:
            fig, name = _empty(title, output), f"sweep_{output}_vs_{'_'.join(keys[:2])}.png"
        elif len(keys) == 1:
            fig, name = _line(table, keys[0], output, title), f"sweep_{output}_vs_{keys[0]}.png"
        elif not regular:
            fig, name = _scatter(table, keys, output, title), f"sweep_{output}_vs_{keys[0]}_{keys[1]}.png"
        elif len(keys) == 2:
            fig, name = _panels(table, keys, output, title), f"sweep_{output}_vs_{keys[0]}_{keys[1]}.png"
        else:
            fig, name = _panels(table, keys, output, title), f"sweep_{output}_vs_{keys[0]}_{keys[1]}_by_{keys[2]}.png"
        paths.append(save_figure(fig, out_dir / _file_name(name)))
    return paths


def _file_name(name):
    """A figure's file name from swept keys and outputs, which a table from anywhere may name with
    '/', '..' or markup: only letters, digits and . = , - [ ] kept, the rest '_'."""
    return re.sub(r"[^\w.=,\[\]-]", "_", name).lstrip(".")[:200]


def _empty(case, output):
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6.4, 4.6))
    ax.set_axis_off()
    ax.set_title(f"{case}: {literal(output)}\nno variants in the table: nothing to draw", fontsize=10)
    return fig


# --- one key -------------------------------------------------------------------------------------

def _line(table, key, output, case):
    import matplotlib.pyplot as plt
    x, y, solved = _floats(table, key), _floats(table, output), _solved(table)
    fig, ax = plt.subplots(figsize=(6.4, 4.6))
    order = np.argsort(x, kind="stable")
    ax.plot(x[order][solved[order]], y[order][solved[order]], "o-", ms=4, label="SOLVED")
    floor = np.nanmin(y) if np.isfinite(y).any() else 0.0
    bad = ~solved
    if bad.any():
        ax.plot(x[bad], np.where(np.isnan(y[bad]), floor, y[bad]), "x", color="tab:red", ms=7,
                label=f"not solved: {_statuses(table, bad)} (no value: on the floor)")
    ax.set_xlabel(_axis(key))
    ax.set_ylabel(_axis(output))
    ax.set_title(f"{case}: {literal(output)}", fontsize=10)
    ax.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.14), ncol=2, frameon=False)
    ax.grid(alpha=0.3)
    return fig


# --- irregular points ----------------------------------------------------------------------------

def _scatter(table, keys, output, case):
    import matplotlib.pyplot as plt
    x, z, y, solved = _floats(table, keys[0]), _floats(table, keys[1]), _floats(table, output), _solved(table)
    fig, ax = plt.subplots(figsize=(6.4, 4.6))
    shown = solved & np.isfinite(y)
    dots = ax.scatter(x[shown], z[shown], c=y[shown], s=30, cmap="viridis", label="SOLVED")
    if shown.any():
        fig.colorbar(dots, ax=ax, label=_axis(output))
    if (~solved).any():
        ax.plot(x[~solved], z[~solved], "x", color="tab:red", ms=7, label=f"not solved: {_statuses(table, ~solved)}")
    ax.set_xlabel(_axis(keys[0]))
    ax.set_ylabel(_axis(keys[1]))
    more = f"; {literal(', '.join(keys[2:]))} overlaid" if len(keys) > 2 else ""
    ax.set_title(f"{case}: {literal(output)}\nrandom points, not a grid{more}", fontsize=10)
    ax.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.14), ncol=2, frameon=False)
    ax.grid(alpha=0.3)
    return fig


# --- maps over a regular grid --------------------------------------------------------------------

def _panels(table, keys, output, case):
    """A map per shown value of the third key (one map with two keys), the boundaries overlaid."""
    import matplotlib.pyplot as plt
    x_key, y_key = keys[:2]
    fixed, notes = {}, []
    for key in keys[3:]:                   # a fourth key and beyond: held at their middle value
        values = np.unique(_floats(table, key))
        fixed[key] = values[(len(values) - 1) // 2]
        notes.append(f"{literal(key)} held at {fixed[key]:g} (of {len(values)} values swept)")
    by = keys[2] if len(keys) > 2 else None
    shown = [None]
    if by:
        values = np.unique(_floats(table, by))
        shown = list(values[np.unique(np.linspace(0, len(values) - 1, MAX_PANELS).round().astype(int))])
        if len(shown) < len(values):
            notes.append(f"{len(shown)} of {len(values)} values of {literal(by)} shown")
    grids = [grid_of(table, x_key, y_key, output, fixed | ({by: v} if by else {})) for v in shown]
    lines = [boundary_of(g) for g in grids]
    overview = by is not None and len(shown) > 1 and any(lines)
    total = len(shown) + overview
    ncols = {1: 1, 2: 2, 4: 2}.get(total, 3)
    nrows = ceil(total / ncols)
    fig = plt.figure(figsize=(1.0 + 4.6 * ncols, 0.9 + 3.9 * nrows))
    spec = fig.add_gridspec(nrows, ncols + 1, width_ratios=[1] * ncols + [0.05])
    axes = [fig.add_subplot(spec[i // ncols, i % ncols]) for i in range(total)]
    coloured = np.concatenate([g.z[np.isfinite(g.z)] for g in grids])
    scale = (coloured.min(), coloured.max()) if coloured.size else (0.0, 1.0)
    levels = _levels(*scale)
    mesh = None
    for ax, grid, line, value in zip(axes, grids, lines, shown):
        mesh = _map(ax, grid, line, scale, levels, x_key, y_key)
        ax.set_title(f"{literal(by)} = {value:g}" if by else "", fontsize=9)
    if coloured.size:
        fig.colorbar(mesh, cax=fig.add_subplot(spec[:, -1]), label=_axis(output))
    if overview:
        _overview(axes[-1], grids, lines, by, shown, x_key, y_key)
    spare = nrows * ncols > total          # an empty slot holds the legend, else it goes under the first map
    _legend(fig.add_subplot(spec[-1, -2]) if spare else axes[0], grids, lines, levels, output, spare)
    what = literal(f"{output} over {x_key} × {y_key}" + (f", by {by}" if by else ""))
    chars = int(fig.get_figwidth() * 10)          # ~10 characters an inch at 11 pt: wrap, never clip
    fig.suptitle("\n".join(textwrap.wrap(f"{case}: {what}", chars) + textwrap.wrap("; ".join(notes), chars)),
                 fontsize=11)
    return fig


def _map(ax, grid, lines, scale, levels, x_key, y_key):
    """One heat map: every cell with a value coloured by it (an infeasible variant's value is its
    best achievable, worth seeing), the not-SOLVED ones hatched over, cells with no value grey with
    a red cross; the boundary black, isolines of the output thin and labelled."""
    from matplotlib.collections import PatchCollection
    from matplotlib.patches import Rectangle
    xe, ye = _edges(grid.xs), _edges(grid.ys)
    valued = np.isfinite(grid.z)
    mesh = ax.pcolormesh(xe, ye, np.ma.masked_where(~valued, grid.z), cmap="viridis", vmin=scale[0],
                         vmax=scale[1], shading="flat")
    present = grid.status != None                                    # noqa: E711 -- elementwise
    for mask, face in ((present & ~grid.solved & valued, (1.0, 1.0, 1.0, 0.35)), (present & ~valued, "0.85")):
        cells = [Rectangle((xe[c], ye[r]), xe[c + 1] - xe[c], ye[r + 1] - ye[r]) for r, c in np.argwhere(mask)]
        if cells:
            ax.add_collection(PatchCollection(cells, facecolor=face, edgecolor="0.45", hatch="///", linewidth=0.0))
    empty = np.argwhere(present & ~valued)
    if len(empty):
        size = float(np.clip(160 / max(len(grid.xs), len(grid.ys)), 3, 8))
        ax.plot(grid.xs[empty[:, 1]], grid.ys[empty[:, 0]], "x", color="tab:red", ms=size, mew=1.2)
    shown_z = np.ma.masked_invalid(grid.z)
    if len(levels) and min(len(grid.xs), len(grid.ys)) > 1 and shown_z.count() > 1:
        inside = [v for v in levels if shown_z.min() < v < shown_z.max()]
        if inside:
            iso = ax.contour(grid.xs, grid.ys, shown_z, levels=inside, colors="white", linewidths=0.8)
            iso.set(path_effects=_halo())
            for label in ax.clabel(iso, fmt="%g", fontsize=7):
                label.set_path_effects(_halo())
    for line in lines:
        ax.plot(line[:, 0], line[:, 1], color="black", lw=2.0)
    ax.set_xlim(xe[0], xe[-1])
    ax.set_ylim(ye[0], ye[-1])
    ax.set_xlabel(_axis(x_key))
    ax.set_ylabel(_axis(y_key))
    return mesh


def _overview(ax, grids, lines, by, shown, x_key, y_key):
    """Every shown value's boundary on one set of axes, one colour each; a value without a
    boundary says which side all its cells are on."""
    import matplotlib.pyplot as plt
    colours = plt.get_cmap("plasma")(np.linspace(0.0, 0.85, len(shown)))
    for colour, grid, line, value in zip(colours, grids, lines, shown):
        side = "" if line else ": all SOLVED" if grid.solved.all() else ": none SOLVED" if not grid.solved.any() else ""
        ax.plot(*(line[0].T if line else ([], [])), color=colour, lw=2.0, label=f"{literal(by)} = {value:g}{side}")
        for part in line[1:]:
            ax.plot(part[:, 0], part[:, 1], color=colour, lw=2.0)
    xe, ye = _edges(grids[0].xs), _edges(grids[0].ys)
    ax.set_xlim(xe[0], xe[-1])
    ax.set_ylim(ye[0], ye[-1])
    ax.set_xlabel(_axis(x_key))
    ax.set_ylabel(_axis(y_key))
    ax.grid(alpha=0.3)
    ax.set_title("feasibility boundaries", fontsize=9)
    ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.16), frameon=False)


def _legend(ax, grids, lines, levels, output, alone):
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch
    handles = []
    bad = [s for g in grids for s in g.status[(g.status != None) & ~g.solved]]    # noqa: E711
    if bad:
        words = ", ".join(f"{w} ×{bad.count(w)}" for w in sorted(set(bad)))
        handles.append((Patch(facecolor=(1.0, 1.0, 1.0, 0.35), edgecolor="0.45", hatch="///"),
                        f"not solved: {literal(words)} (coloured where the solver gave a value)"))
    if any((~np.isfinite(g.z) & (g.status != None)).any() for g in grids):      # noqa: E711
        handles.append(((Patch(facecolor="0.85", edgecolor="0.45", hatch="///"),
                         Line2D([], [], ls="", marker="x", color="tab:red")), "no value"))
    if any(lines):
        handles.append((Line2D([], [], color="black", lw=2.0), "feasibility boundary (SOLVED | not)"))
    if len(levels):
        handles.append((Line2D([], [], color="white", lw=0.8, path_effects=_halo()), f"isolines of {literal(output)}"))
    if alone:
        ax.set_axis_off()
    if handles:
        ax.legend(*zip(*handles), fontsize=8 if alone else 7, loc="center" if alone else "upper center",
                  bbox_to_anchor=None if alone else (0.5, -0.16), frameon=False)


# --- helpers -------------------------------------------------------------------------------------

def _levels(low, high):
    """A few round isoline values strictly inside (low, high)."""
    from matplotlib.ticker import MaxNLocator
    if not high > low:
        return np.array([])
    ticks = MaxNLocator(5).tick_values(low, high)
    return ticks[(ticks > low) & (ticks < high)]


def _halo():
    """A dark rim that keeps a white isoline readable on the light end of the colour map."""
    from matplotlib.patheffects import withStroke
    return [withStroke(linewidth=2.0, foreground="0.25")]


def _edges(values):
    """Cell edges halfway between grid values; a single value gets a cell of its own size."""
    if len(values) == 1:
        half = 0.5 * abs(values[0]) or 0.5
        return np.array([values[0] - half, values[0] + half])
    mid = 0.5 * (values[1:] + values[:-1])
    return np.concatenate([[2 * values[0] - mid[0]], mid, [2 * values[-1] - mid[-1]]])


def _regular(table, keys):
    """True when the swept keys are a grid: no random axis, and no two variants on one point."""
    spec = _meta(table).get("spec")
    if spec is not None and spec.get("random"):
        return False
    points = {tuple(row[k] for k in keys) for row in table.select(keys).to_pylist()}
    return len(points) == table.num_rows


def _axis(name):
    """A swept key or output as an axis label, drawn as written."""
    return literal(axis_label(name))


def _meta(table):
    raw = (table.schema.metadata or {}).get(META_KEY)
    return json.loads(raw) if raw else {}


def _solved(table):
    return np.array([s == "SOLVED" for s in table.column("status").to_pylist()])


def _statuses(table, mask):
    words = np.array(table.column("status").to_pylist(), dtype=object)[mask]
    return literal(", ".join(f"{w} ×{int((words == w).sum())}" for w in sorted(set(words))))


def _swept(table):
    """Swept keys: the columns before `variant` (the sweep writes them first)."""
    names = table.column_names
    return names[:names.index("variant")]


def _floats(table, name):
    return np.array([np.nan if v is None else float(v) for v in table.column(name).to_pylist()])
