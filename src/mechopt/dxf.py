"""Curves for the shop as DXF: a solved scene's cam profile, pitch curve or
torch path as closed LWPOLYLINEs (open where a curve ends) on named layers, units mm, each from a point table whose
chordal error is measured (`models/cam_shape.point_table`) and written into the drawing.

Which curves a scene has is decided by its task class (`EXPORTS`): the lift cam
(`cam_shape.CamShape`) takes its tables from the solver's arrays; the cam-cutting linkage
(paper 000) has its designed torch path, the limaçon of the solved H, L (eq. 10), and the ideal
path it follows (the offset cardioid, eq. 9, or the user's curve) on another layer. A scene
with nothing to export says so (`NothingToExport`), never writes an empty file.

A file is written whole or not at all (`mechopt.files.write_bytes_atomic`), and by one writer at
a time: `<file>.lock` beside it is held while it is written, and a second writer is refused.
"""
import io
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from mechopt.files import holds, make_folder, take_lock, write_bytes_atomic
from mechopt.kit.errors import MechoptError, SceneError
from mechopt.models.cam_cutter import LinkageCheck, LinkageFit, LinkageLoads, ideal_point, real_point
from mechopt.models.cam_profile import ProfileFit
from mechopt.models.cam_shape import CamShape, mirrored, point_table

INSUNITS_MM = 4                 # DXF $INSUNITS code of millimetres
LAYER_COLOURS = {"CAM_PROFILE": 7, "CAM_GROOVE_OUTER": 5, "PITCH_CURVE": 1, "TORCH_PATH": 3, "IDEAL_PATH": 8}
CAM_LAYERS = {"profile": "CAM_PROFILE", "groove_outer": "CAM_GROOVE_OUTER", "pitch": "PITCH_CURVE"}
TORCH_TOL_MM = 0.001            # the torch path's chordal error: a tenth of the paper's H, L precision
AXIS_REL = 1e-7                 # an end this close to the x axis (relative to the cam) closes by its mirror


class NothingToExport(MechoptError):
    """A solved scene that has no curve for the shop (a loom plan, a press run, an infeasible cam)."""


@dataclass(frozen=True)
class ShopCurve:
    """One curve for the drawing: its layer, points (n x 2) [mm], measured chordal error, and
    whether it closes (a cam, a torch path) or ends (an ideal path that its mirror does not close)."""
    layer: str
    xy: np.ndarray
    chord_error_mm: float
    what: str
    closed: bool = True


def shop_curves(run) -> list[ShopCurve]:
    """The curves of a solved scene (a `registry.Run`); NothingToExport when it has none."""
    export = next((f for cls, f in EXPORTS.items() if isinstance(run.task, cls)), None)
    if export is None:
        raise NothingToExport(f"{run.scene.id}: nothing to export as DXF (task {type(run.task).__name__}); "
                              f"--dxf draws cams and torch paths: {', '.join(c.__name__ for c in EXPORTS)}")
    if not run.success:
        raise NothingToExport(f"{run.scene.id}: status {run.status.value}, nothing exported as DXF "
                              f"({run.result.message})")
    return export(run)


def _cam_curves(run):
    arrays, errors = run.arrays, run.result.diagnostics["chord_error_mm"]
    return [ShopCurve(layer, np.column_stack([arrays[f"{name}_x_mm"], arrays[f"{name}_y_mm"]]), errors[name], name)
            for name, layer in CAM_LAYERS.items() if f"{name}_x_mm" in arrays]


def _torch_curves(run):
    """The limaçon (10) of the solved (or given) links over a whole crank turn (its inner loop
    too, where H > L: the torch runs it), and the ideal path (its upper half closed by its
    mirror, corner at t_FINISH) on another layer."""
    task, values = run.task, run.values
    H, L = (values.get(k, getattr(task, k, None)) for k in ("H_mm", "L_mm"))
    if H is None or L is None:
        raise NothingToExport(f"{run.scene.id}: no linkage (H_mm, L_mm) in this result: no torch path to export")
    limacon = point_table(lambda s: np.array(real_point(s, H, L)), TORCH_TOL_MM)
    curves = [ShopCurve("TORCH_PATH", limacon.xy, limacon.chord_error_mm, f"limacon H={H:.6g} L={L:.6g} mm")]
    if not hasattr(task, "t_end_rad"):          # the loads' task knows its links, not the path they follow
        return curves
    if isinstance(task, ProfileFit):
        upper = lambda t: np.array(task.path_point(t))              # noqa: E731
    else:
        upper = lambda t: np.array(ideal_point(t, task.a_mm, task.h_mm))  # noqa: E731
    t0, t1 = task.t_start_rad, task.t_end_rad
    ends = upper(np.array([t0, t1]))
    if np.all(np.abs(ends[1]) <= AXIS_REL * task.size_mm):      # both ends on the axis: the mirror closes it
        ideal = point_table(mirrored(upper, t0, t1), TORCH_TOL_MM, period=2 * (t1 - t0), breaks=(t1 - t0,))
        curves.append(ShopCurve("IDEAL_PATH", ideal.xy, ideal.chord_error_mm, "ideal path and its mirror"))
    else:                                                       # drawn as given, from its start to its end
        ideal = point_table(lambda t: upper(t0 + t), TORCH_TOL_MM, period=t1 - t0, closed=False)
        curves.append(ShopCurve("IDEAL_PATH", ideal.xy, ideal.chord_error_mm, "ideal path, open", closed=False))
    return curves


EXPORTS = {CamShape: _cam_curves, LinkageFit: _torch_curves, LinkageCheck: _torch_curves,
           LinkageLoads: _torch_curves, ProfileFit: _torch_curves}


def ezdxf_module():
    """The ezdxf package, or a MechoptError naming the extra that installs it."""
    try:
        import ezdxf
    except ImportError:
        raise MechoptError("writing DXF needs ezdxf: pip install 'mechopt[dxf]'") from None
    return ezdxf


def dxf_bytes(curves, *, title: str = "") -> bytes:
    """A DXF drawing (R2010, units mm) of LWPOLYLINEs, one layer per curve."""
    ezdxf = ezdxf_module()
    doc = ezdxf.new("R2010", setup=False)
    doc.header["$INSUNITS"] = INSUNITS_MM
    doc.header["$MEASUREMENT"] = 1                  # metric
    msp = doc.modelspace()
    for curve in curves:
        if curve.layer not in doc.layers:
            doc.layers.add(curve.layer, color=LAYER_COLOURS.get(curve.layer, 7))
        msp.add_lwpolyline([tuple(map(float, p)) for p in curve.xy], close=curve.closed,
                           dxfattribs={"layer": curve.layer})
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
    """Write a solved scene's curves as `<scene>.dxf` in `out_dir` (all layers in one drawing);
    (path, curve) per curve written. NothingToExport when the scene has none."""
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


def _length(curve):
    xy = np.vstack([curve.xy, curve.xy[:1]]) if curve.closed else curve.xy
    return float(np.sum(np.hypot(*np.diff(xy, axis=0).T)))


__all__ = ["EXPORTS", "NothingToExport", "ShopCurve", "chord_note", "dxf_bytes", "dxf_path", "export_run",
           "ezdxf_module", "read_polylines", "shop_curves", "write_dxf"]
