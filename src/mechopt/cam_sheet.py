"""A cam's drawing for the shop, from any cam (any follower, any law): its curves, and the marks
that put it on its shaft. `cam_sheet(...)` returns the items `mechopt.dxf` writes; `sheet_of(...)`
makes them from a solved cam's Result arrays (every cam writer's one path).

The drawing is in the cam's own frame as it stands when the rise begins, units mm. Its layers
(the interface a check outside the package may rely on):

* `PITCH_CURVE`       the roller centre's path (closed LWPOLYLINE);
* `CAM_PROFILE`       the cam's working surface (a groove: its inner wall);
* `CAM_GROOVE_OUTER`  a grooved (form-closed) cam's outer wall, where there is one;
* `CENTRE`            the centre mark (two LINEs crossing at the centre) and the bore (CIRCLE);
* `REFERENCE`         the rise-start mark (a radial LINE, colour 1, from the bore out past the
                      profile, along the direction from the centre to the roller centre as the
                      rise begins); where the cam's phase on its shaft is stated, the shaft-zero
                      mark (a radial LINE, colour 5: the cam's line that faces the follower's rest
                      position when the machine's shaft is at 0, i.e. the rise-start mark turned
                      back by the shaft angle at which the rise begins); the sense of rotation (an
                      ARC with a two-LINE arrowhead, colour 3); and TEXT notes: units, sense, each
                      mark's angle to 1e-6 deg, the bore, where the phase comes from.

Angles are counter-clockwise from the drawing's +x axis about the cam's centre [deg].
"""
import math
from dataclasses import dataclass
from typing import Literal, NamedTuple

import numpy as np

from mechopt.dxf import ShopArc, ShopCircle, ShopCurve, ShopLine, ShopText
from mechopt.kit.errors import require

SENSES = {"ccw": 1.0, "cw": -1.0}       # the sign of the cam's turn (counter-clockwise positive)
SENSE_WORDS = {"ccw": "COUNTER-CLOCKWISE (ccw)", "cw": "CLOCKWISE (cw)"}
RISE_COLOUR, SHAFT_ZERO_COLOUR, SENSE_COLOUR = 1, 5, 3      # DXF colour indices on REFERENCE (red, blue, green)
LAYER_COLOURS = {"PITCH_CURVE": 1, "CAM_PROFILE": 7, "CAM_GROOVE_OUTER": 5}     # the curves' layers
MARK_REACH = 1.10           # the radial marks run out to this many times the cam's largest radius
ARC_RADIUS, ARC_SPAN_DEG = 1.05, 40.0      # the sense arc: radius (of the largest), span, opposite the rise mark
ARROW, TEXT = 0.05, 0.035   # arrowhead length, text height: shares of the largest radius


class Table(NamedTuple):
    """A curve's point table: points (n x 2) [mm] and its measured chordal error [mm]
    (`models.cam_shape.PointTable` has both attributes too)."""
    xy: np.ndarray
    chord_error_mm: float


@dataclass(frozen=True)
class Phase:
    """The cam's phase on its shaft: the machine's shaft angle at which the rise begins [deg]
    (a cyclogram's event), and where that angle comes from (said in the drawing)."""
    shaft_deg: float
    source: str


def cam_sheet(pitch, profile, groove_outer=None, *, bore_diameter_mm: float, rise_start_deg: float,
              sense: Literal["ccw", "cw"], centre_mm=(0.0, 0.0), phase: Phase | None = None,
              notes=()) -> list:
    """The drawing of a cam: `pitch`, `profile` and optionally `groove_outer` (each a `Table` or
    `PointTable`: xy n x 2 [mm] in the cam's frame, chord_error_mm), its centre `centre_mm` (x, y)
    [mm], the bore's diameter [mm], `rise_start_deg` the direction of the roller centre from the
    centre as the rise begins [deg], the sense in which the cam turns seen on the drawing, the
    phase on the shaft when the cam belongs to a machine, and further one-line `notes` (where the
    geometry comes from). Returns `ShopCurve`s and marks (module docstring: the layers).

    Refused (ModelError naming the key): an unknown sense, a non-finite angle, a bore that does
    not fit inside the profile, a table that is not n x 2 finite points."""
    require(sense in SENSES, f"sense={sense!r}: allowed: {', '.join(SENSES)}", key="sense")
    require(math.isfinite(rise_start_deg), f"rise_start_deg={rise_start_deg}: allowed: a finite angle [deg]",
            key="rise_start_deg")
    centre = np.array([float(c) for c in centre_mm])
    require(centre.shape == (2,) and bool(np.all(np.isfinite(centre))),
            f"centre_mm={centre_mm!r}: allowed: two finite numbers (x, y) [mm]", key="centre_mm")
    tables = {"PITCH_CURVE": pitch, "CAM_PROFILE": profile}
    if groove_outer is not None:
        tables["CAM_GROOVE_OUTER"] = groove_outer
    for layer, table in tables.items():
        xy = np.asarray(table.xy, dtype=float)
        require(xy.ndim == 2 and xy.shape[1] == 2 and xy.shape[0] >= 3 and bool(np.all(np.isfinite(xy))),
                f"{layer}: allowed: >= 3 finite points (n x 2) [mm]; got shape {xy.shape}", key=layer)
    radii = {layer: np.hypot(*(np.asarray(t.xy, dtype=float) - centre).T) for layer, t in tables.items()}
    inner, outer = min(r.min() for r in radii.values()), max(r.max() for r in radii.values())
    bore = bore_diameter_mm / 2
    require(math.isfinite(bore_diameter_mm) and 0 < bore < inner,
            f"bore_diameter_mm={bore_diameter_mm:g}: allowed: 0 < d < {2 * inner:.6g} (the profile's least "
            "diameter about the centre)", key="bore_diameter_mm")
    items = [ShopCurve(layer, np.asarray(t.xy, dtype=float), float(t.chord_error_mm), layer.lower().replace("_", " "),
                       colour=LAYER_COLOURS[layer]) for layer, t in tables.items()]
    items += _centre(centre, bore)
    items += _reference(centre, bore, outer, rise_start_deg, sense, phase)
    items += _notes(centre, outer, bore_diameter_mm, rise_start_deg, sense, phase, notes)
    return items


SHEET_TABLES = ("pitch", "profile", "groove_outer")     # a solver's point tables, as cam_sheet's arguments


def sheet_of(arrays, chord_error_mm: dict, *, prefix: str = "", rise_start_deg: float | None = None, **sheet) -> list:
    """The drawing of a solved cam from its Result alone (one path for every cam solver): the
    point tables `<prefix><table>_x_mm`, `_y_mm` of `arrays` (pitch, profile, groove_outer: those
    there are) with their measured chordal errors `chord_error_mm[table]`, and `cam_sheet`'s other
    arguments (`sheet`: bore, sense, phase, notes). `rise_start_deg` None: the direction of the
    pitch table's first vertex (a table that starts where the rise does)."""
    tables = {name: Table(np.column_stack([arrays[f"{prefix}{name}_x_mm"], arrays[f"{prefix}{name}_y_mm"]]),
                          float(chord_error_mm[name]))
              for name in SHEET_TABLES if f"{prefix}{name}_x_mm" in arrays}
    require("pitch" in tables and "profile" in tables, f"no point tables {prefix}pitch_x_mm and {prefix}profile_x_mm "
            f"among the arrays ({', '.join(sorted(arrays)) or 'none'})", key="arrays")
    if rise_start_deg is None:
        rise_start_deg = math.degrees(math.atan2(tables["pitch"].xy[0, 1], tables["pitch"].xy[0, 0]))
    return cam_sheet(**tables, rise_start_deg=rise_start_deg, **sheet)


def bore_stated(task) -> str | None:
    """Why a cam task cannot be drawn, knowable before it is solved: its bore not stated (0); None
    where it is (`mechopt.dxf.drawable_if`)."""
    if task.bore_diameter_mm > 0:
        return None
    return ("bore_diameter_mm not stated (0): the drawing's bore needs it (--set bore_diameter_mm=D, D [mm] below "
            "the cam's least diameter)")


def _radial(centre, angle_deg, r0, r1):
    a = math.radians(angle_deg)
    u = np.array([math.cos(a), math.sin(a)])
    return tuple(map(float, centre + r0 * u)), tuple(map(float, centre + r1 * u))


def _centre(centre, bore):
    """The centre mark (crossing lines a quarter past the bore) and the bore."""
    reach = 1.25 * bore
    x, y = map(float, centre)
    return [ShopLine("CENTRE", (x - reach, y), (x + reach, y), "centre mark"),
            ShopLine("CENTRE", (x, y - reach), (x, y + reach), "centre mark"),
            ShopCircle("CENTRE", (x, y), bore, f"bore d = {2 * bore:g} mm")]


def shaft_zero_deg(rise_start_deg: float, sense: str, phase: Phase) -> float:
    """The shaft-zero mark's angle: the rise-start mark turned back by the shaft angle at which the
    rise begins (a cam turning ccw brings a line at larger angle to the follower earlier) [deg]."""
    return rise_start_deg + SENSES[sense] * phase.shaft_deg


def _reference(centre, bore, outer, rise_start_deg, sense, phase):
    reach = MARK_REACH * outer
    items = [ShopLine("REFERENCE", *_radial(centre, rise_start_deg, bore, reach),
                      f"rise-start mark at {rise_start_deg:.6f} deg", colour=RISE_COLOUR)]
    if phase is not None:
        zero = shaft_zero_deg(rise_start_deg, sense, phase)
        items.append(ShopLine("REFERENCE", *_radial(centre, zero, bore, reach),
                              f"shaft-zero mark at {zero:.6f} deg", colour=SHAFT_ZERO_COLOUR))
    # the sense: an arc opposite the rise mark, its arrowhead at the end the cam turns towards
    r, mid = ARC_RADIUS * outer, rise_start_deg + 180.0
    start, end = mid - ARC_SPAN_DEG / 2, mid + ARC_SPAN_DEG / 2
    items.append(ShopArc("REFERENCE", tuple(map(float, centre)), r, start, end, f"turns {sense}", colour=SENSE_COLOUR))
    tip_deg = end if sense == "ccw" else start
    a = math.radians(tip_deg)
    tip = centre + r * np.array([math.cos(a), math.sin(a)])
    along = SENSES[sense] * np.array([-math.sin(a), math.cos(a)])           # the way the cam's rim moves there
    radial = np.array([math.cos(a), math.sin(a)])
    size = ARROW * outer
    for side in (1.0, -1.0):
        barb = tip - size * along + side * 0.4 * size * radial
        items.append(ShopLine("REFERENCE", tuple(map(float, tip)), tuple(map(float, barb)), f"turns {sense}",
                              colour=SENSE_COLOUR))
    return items


def _notes(centre, outer, bore_diameter_mm, rise_start_deg, sense, phase, extra):
    lines = ["UNITS: mm",
             f"TURNS {SENSE_WORDS[sense]} SEEN ON THIS DRAWING",
             f"RISE START MARK at {rise_start_deg:.6f} deg: the roller centre's direction as the rise begins",
             f"BORE d = {bore_diameter_mm:g} mm, centred on the centre mark"]
    if phase is None:
        lines.append("PHASE ON THE SHAFT: not stated for this cam; key it to its shaft by the RISE START mark")
    else:
        lines.append(f"SHAFT ZERO MARK at {shaft_zero_deg(rise_start_deg, sense, phase):.6f} deg: the rise begins at "
                     f"shaft angle {phase.shaft_deg:.6g} deg ({phase.source})")
    height = TEXT * outer
    x0, y0 = float(centre[0]) - outer, float(centre[1]) - 1.25 * outer
    return [ShopText("REFERENCE", line, (x0, y0 - 1.6 * height * k), height)
            for k, line in enumerate([*lines, *extra])]


__all__ = ["LAYER_COLOURS", "Phase", "SENSES", "SHEET_TABLES", "Table", "bore_stated", "cam_sheet", "shaft_zero_deg",
           "sheet_of"]
