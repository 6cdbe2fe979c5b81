"""Curves for the shop as DXF: a solved scene's curves (a cam profile, a pitch curve, a torch
path) as closed LWPOLYLINEs (open where a curve ends) on named layers, units mm, each from a point
table whose chordal error is measured (`models/cam_shape.point_table`) and written into the drawing.
Beside the curves a drawing may carry exact marks: circles (a bore), arcs, lines (a centre mark, a
reference mark) and text notes (`ShopCircle`, `ShopArc`, `ShopLine`, `ShopText`; a cam's are made
by `mechopt.cam_sheet`).

Which curves a scene has is decided by its solver, as its figures are: a mechanism's output module
registers a writer `@shop_drawing(solver, ...)` (a `Run` -> its `ShopCurve`s); this module knows
no mechanism. A scene whose solver has no writer says so (`NothingToExport`), never writes an
empty file; a writer's rule knowable from the posed task (a cam's bore: `drawable_if`) is asked
before the solve.

A file is written whole or not at all (`mechopt.files.write_bytes_atomic`), and by one writer at
a time: `<file>.lock` beside it is held while it is written, and a second writer is refused.
"""
import io
import os
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from mechopt.files import holds, make_folder, take_lock, write_bytes_atomic
from mechopt.kit.errors import MechoptError, SceneError
from mechopt.kit.registrar import by_solver

INSUNITS_MM = 4                 # DXF $INSUNITS code of millimetres
WHITE = 7                       # DXF colour index of a layer that names none (white on black, black on white)
BYLAYER = 256                   # DXF colour index "as its layer" (an entity that names no colour of its own)


class NothingToExport(MechoptError):
    """A solved scene that has no curve for the shop (a loom plan, a press run, an infeasible cam)."""


@dataclass(frozen=True)
class ShopCurve:
    """One curve for the drawing: its layer (and the layer's DXF colour index), points (n x 2)
    [mm], measured chordal error, and whether it closes (a cam, a torch path) or ends (an ideal
    path that its mirror does not close)."""
    layer: str
    xy: np.ndarray
    chord_error_mm: float
    what: str
    closed: bool = True
    colour: int = WHITE


@dataclass(frozen=True)
class ShopCircle:
    """A full circle (a bore): centre (x, y) [mm], radius [mm]."""
    layer: str
    centre: tuple[float, float]
    radius_mm: float
    what: str
    colour: int = BYLAYER

    def add_to(self, msp, attribs):
        msp.add_circle(self.centre, self.radius_mm, dxfattribs=attribs)


@dataclass(frozen=True)
class ShopArc:
    """An arc counter-clockwise from `start_deg` to `end_deg` (DXF's sense), centre [mm], radius [mm]."""
    layer: str
    centre: tuple[float, float]
    radius_mm: float
    start_deg: float
    end_deg: float
    what: str
    colour: int = BYLAYER

    def add_to(self, msp, attribs):
        msp.add_arc(self.centre, self.radius_mm, self.start_deg, self.end_deg, dxfattribs=attribs)


@dataclass(frozen=True)
class ShopLine:
    """A straight line from `start` to `end` (x, y) [mm]."""
    layer: str
    start: tuple[float, float]
    end: tuple[float, float]
    what: str
    colour: int = BYLAYER

    def add_to(self, msp, attribs):
        msp.add_line(self.start, self.end, dxfattribs=attribs)


@dataclass(frozen=True)
class ShopText:
    """A one-line note at `at` (x, y) [mm], `height_mm` tall (DXF TEXT)."""
    layer: str
    text: str
    at: tuple[float, float]
    height_mm: float
    what: str = "note"
    colour: int = BYLAYER

    def add_to(self, msp, attribs):
        msp.add_text(self.text, height=self.height_mm, dxfattribs=attribs | {"insert": self.at})


SHOP_MARKS = (ShopCircle, ShopArc, ShopLine, ShopText)
SHOP_DRAWINGS: dict[Callable, Callable] = {}


# `@shop_drawing(solver, ...)` registers a DXF writer, `writer(run) -> list[ShopCurve]`, for these
# solver functions (one writer per solver), beside the mechanism's figures
shop_drawing = by_solver(SHOP_DRAWINGS, "shop_drawing", "draws for the shop")


def writer_of(scene) -> Callable:
    """The DXF writer of a scene's solver, looked up from the scene alone (before any solve);
    NothingToExport naming the solvers that have one when it has none."""
    from mechopt.figures.registry import import_rows
    import_rows()           # each mechanism's output modules register their writers (a row added late too)
    writer = SHOP_DRAWINGS.get(scene.solver)
    if writer is None:
        solvers = sorted({s.__name__ for s in SHOP_DRAWINGS})
        raise NothingToExport(f"{scene.id}: nothing to export as DXF (task {scene.task_class.__name__}); its solver "
                              f"{scene.solver.__name__} has no DXF writer; --dxf draws the results of: "
                              f"{', '.join(solvers)}")
    return writer


def drawable_if(check: Callable) -> Callable:
    """A DXF writer's rule on the task as posed, knowable before any solve: `check(task)` returns
    why the scene cannot be drawn (a str) or None. Put under `@shop_drawing(...)`; the command
    line asks it before solving (`refuse_before_solve`), `shop_curves` again on the solved task."""
    def mark(writer):
        writer.drawable_if = check
        return writer
    return mark


def _undrawable(scene, task) -> None:
    why = getattr(writer_of(scene), "drawable_if", lambda task: None)(task)
    if why:
        raise NothingToExport(f"{scene.id}: {why}")


def refuse_before_solve(scene, pose: Callable) -> None:
    """NothingToExport, before any solve, when the scene cannot be drawn: its solver has no writer
    (`writer_of`), or its writer's rule (`drawable_if`) refuses the task `pose()` returns (the
    task as posed: the file, its derived values, the overrides; asked only where there is a rule)."""
    writer = writer_of(scene)
    if hasattr(writer, "drawable_if"):
        _undrawable(scene, pose())


def shop_curves(run) -> list:
    """The curves (and marks) of a solved scene (a `registry.Run`); NothingToExport when it has none."""
    writer = writer_of(run.scene)
    _undrawable(run.scene, run.task)
    if not run.success:
        raise NothingToExport(f"{run.scene.id}: status {run.status.value}, nothing exported as DXF "
                              f"({run.result.message})")
    return writer(run)


def ezdxf_module():
    """The ezdxf package, or a MechoptError naming the extra that installs it."""
    try:
        import ezdxf
    except ImportError:
        raise MechoptError("writing DXF needs ezdxf: pip install 'mechopt[dxf]'") from None
    return ezdxf


def dxf_bytes(curves, *, title: str = "") -> bytes:
    """A DXF drawing (R2010, units mm): each `ShopCurve` an LWPOLYLINE, each mark its entity, on
    its layer (made with the colour of the first item that names it)."""
    ezdxf = ezdxf_module()
    doc = ezdxf.new("R2010", setup=False)
    doc.header["$INSUNITS"] = INSUNITS_MM
    doc.header["$MEASUREMENT"] = 1                  # metric
    msp = doc.modelspace()
    for item in curves:
        if item.layer not in doc.layers:
            doc.layers.add(item.layer, color=WHITE if item.colour == BYLAYER else item.colour)
        attribs = {"layer": item.layer} | ({} if item.colour == BYLAYER else {"color": item.colour})
        if isinstance(item, ShopCurve):
            msp.add_lwpolyline([tuple(map(float, p)) for p in item.xy], close=item.closed,
                               dxfattribs={"layer": item.layer})
        else:
            item.add_to(msp, attribs)
    if title:
        doc.header["$PROJECTNAME"] = title[:250]
    stream = io.StringIO()
    doc.write(stream)
    return stream.getvalue().encode(doc.output_encoding)


def write_dxf(curves, path) -> Path:
    """Write `curves` to `path` whole or not at all, one writer at a time (SceneError when
    another process is writing it); returns the path."""
    path = Path(path)
    make_folder(path.parent)
    lock = path.with_name(f"{path.name}.lock")
    try:
        fd = take_lock(lock)
    except ValueError as exc:
        raise SceneError(f"--dxf: {exc}; nothing was written") from None
    if fd is None:
        raise SceneError(f"--dxf: {path} is being written by another process; wait for it or choose another folder")
    try:
        return write_bytes_atomic(path, dxf_bytes(curves, title=path.stem))
    finally:
        if holds(fd, lock):              # still ours (not removed and replaced by another writer's)
            lock.unlink(missing_ok=True)
        os.close(fd)


def export_run(run, out_dir) -> list[tuple[Path, ShopCurve]]:
    """Write a solved scene's curves (and marks) as `<scene>.dxf` in `out_dir` (all layers in one
    drawing); (path, item) per item written. NothingToExport when the scene has none."""
    curves = shop_curves(run)
    path = dxf_path(run.scene, out_dir)
    write_dxf(curves, path)
    return [(path, c) for c in curves]


def dxf_path(scene, out_dir) -> Path:
    """Where `export_run` writes a scene's drawing: `<out_dir>/<scene id, / as _>.dxf`."""
    return Path(out_dir) / f"{scene.id.replace('/', '_')}.dxf"


def read_polylines(path) -> dict[str, np.ndarray]:
    """The polylines of a DXF file by layer (n x 2) [mm], as ezdxf reads them back."""
    doc = ezdxf_module().readfile(str(path))
    return {e.dxf.layer: np.array([(x, y) for x, y, *_ in e.get_points()]) for e in doc.modelspace()
            if e.dxftype() == "LWPOLYLINE"}


def chord_note(curve: ShopCurve) -> str:
    """One line for the terminal: layer, points, chordal error."""
    return (f"{curve.layer}: {len(curve.xy)} points, chordal error {curve.chord_error_mm:.4g} mm "
            f"({curve.what}; length {_length(curve):.6g} mm)")


def notes(items) -> list[str]:
    """Lines for the terminal: one per curve (`chord_note`), one per layer of marks (what they are;
    text notes are in the drawing, not repeated)."""
    marks: dict[str, list[str]] = {}
    for item in items:
        if not isinstance(item, (ShopCurve, ShopText)):
            marks.setdefault(item.layer, []).append(item.what)
    return ([chord_note(c) for c in items if isinstance(c, ShopCurve)]
            + [f"{layer}: {'; '.join(dict.fromkeys(whats))}" for layer, whats in marks.items()])


def _length(curve):
    xy = np.vstack([curve.xy, curve.xy[:1]]) if curve.closed else curve.xy
    return float(np.sum(np.hypot(*np.diff(xy, axis=0).T)))


__all__ = ["SHOP_DRAWINGS", "SHOP_MARKS", "NothingToExport", "ShopArc", "ShopCircle", "ShopCurve", "ShopLine", "ShopText",
           "chord_note", "drawable_if", "dxf_bytes", "dxf_path", "export_run", "ezdxf_module", "notes", "read_polylines",
           "refuse_before_solve", "shop_curves", "shop_drawing", "write_dxf", "writer_of"]
