"""Load-travel data of a testing machine, read from CSV (the only file-reading of the force fit).

Testing machines export with a comma or a semicolon between columns (then often with a decimal
comma) and spell the header in any case; all of these are read. Every error is one line that
names the file (and the line, or the expected header)."""
import csv
import math
from pathlib import Path

import numpy as np

from mechopt.models.errors import ModelError

TRAVEL_UNITS_MM = {"mm": 1.0, "m": 1000.0, "um": 1e-3}
LOAD_UNITS_N = {"N": 1.0, "kN": 1000.0}
EXPECTED_HEADER = "travel_<mm|m|um>,load_<N|kN> (or ';' between columns; any order, any case)"
# readings beyond these cannot come from a press's testing machine, and a degree-6 fit of them
# overflows (X^6 of 1e60 is inf): refused rather than fitted
MAX_TRAVEL_MM = 1e6
MAX_LOAD_N = 1e12
MAX_BYTES = 100_000_000      # read whole into memory: refuse what is plainly not a testing machine's record


def read_force_csv(path):
    """(travel [mm], load [N]) from a CSV file whose header names the columns and their units,
    e.g. ``travel_mm,load_N`` or ``Travel_mm;Load_kN`` (travel in mm, m or um; load in N or kN),
    one row per reading."""
    path = Path(path)
    try:
        size = path.stat().st_size
        if size > MAX_BYTES:
            raise ModelError(f"{path}: {size / 1e6:.3g} MB; a load-travel record is at most {MAX_BYTES / 1e6:g} MB "
                             f"(millions of readings)", key="path")
        raw = path.read_bytes()
    except OSError as exc:
        raise ModelError(f"{path}: cannot read: {exc.strerror}", key="path") from None
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise ModelError(f"{path}: not UTF-8 text (byte 0x{raw[exc.start]:02x} at offset {exc.start}); "
                         f"save it as UTF-8 CSV with the header {EXPECTED_HEADER}", key="path") from None
    lines = text.splitlines()
    if not any(line.strip() for line in lines):
        raise ModelError(f"{path}: empty file; expected a header such as travel_mm,load_N", key="path")
    first = next(line for line in lines if line.strip())
    delimiter = ";" if first.count(";") > first.count(",") else ","
    rows = list(csv.reader(lines, delimiter=delimiter))
    start = next(i for i, row in enumerate(rows) if any(c.strip() for c in row))
    header = [h.strip() for h in rows[start]]
    travel_col = _column(path, header, "travel", TRAVEL_UNITS_MM)
    load_col = _column(path, header, "load", LOAD_UNITS_N)
    x, f = [], []
    for line, row in enumerate(rows[start + 1:], start=start + 2):
        if not row or all(not c.strip() for c in row):
            continue
        try:
            x.append(_number(path, line, row, travel_col, MAX_TRAVEL_MM, "mm", delimiter))
            f.append(_number(path, line, row, load_col, MAX_LOAD_N, "N", delimiter))
        except ModelError:
            raise
        except (ValueError, IndexError):
            raise ModelError(f"{path}: line {line}: {row!r} is not a number in every column", key="path") from None
    return np.array(x), np.array(f)


def _number(path, line, row, column, limit, unit, delimiter):
    """One reading in mm or N; a decimal comma is read when ';' separates the columns."""
    (index, factor), cell = column, row[column[0]].strip()
    value = float(cell.replace(",", ".") if delimiter == ";" else cell) * factor
    if not (math.isfinite(value) and abs(value) <= limit):
        raise ModelError(f"{path}: line {line}: {cell!r} in column {index + 1} is {value:g} {unit}, outside "
                         f"[-{limit:g}, {limit:g}] {unit}", key="path")
    return value


def _column(path, header, name, units):
    """(index, factor to mm or N) of the column `<name>_<unit>` (any case); errors name what is allowed."""
    for i, h in enumerate(header):
        stem, _, unit = h.partition("_")
        if stem.lower() == name:
            known = {u.lower(): factor for u, factor in units.items()}
            if unit.lower() not in known:
                raise ModelError(f"{path}: column {h!r}: unit {unit!r} unknown; allowed "
                                 + ", ".join(f"{name}_{u}" for u in units), key=name)
            return i, known[unit.lower()]
    raise ModelError(f"{path}: no '{name}_<unit>' column in header {header}; expected {EXPECTED_HEADER}, "
                     f"e.g. travel_mm,load_N", key=name)
