"""Load-travel data of a testing machine, read from CSV (the only file-reading of the force fit;
the CSV dialects are `mechopt.tables`'). The header names each column with its unit, in any case;
every error is one line that names the file (and the line, or the expected header)."""
import math
from pathlib import Path

import numpy as np

from mechopt.kit.errors import ModelError, quote
from mechopt.tables import MAX_BYTES, check_header, number, read_rows

TRAVEL_UNITS_MM = {"mm": 1.0, "m": 1000.0, "um": 1e-3}
LOAD_UNITS_N = {"N": 1.0, "kN": 1000.0}
EXPECTED_HEADER = "travel_<mm|m|um>,load_<N|kN> (or ';' between columns; any order, any case)"
# readings beyond these cannot come from a press's testing machine, and a degree-6 fit of them
# overflows (X^6 of 1e60 is inf): refused rather than fitted
MAX_TRAVEL_MM = 1e6
MAX_LOAD_N = 1e12


def read_force_csv(path):
    """(travel [mm], load [N]) from a CSV file whose header names the columns and their units,
    e.g. ``travel_mm,load_N`` or ``Travel_mm;Load_kN`` (travel in mm, m or um; load in N or kN),
    one row per reading."""
    path = Path(path)
    header, rows, delimiter = read_rows(path, what="a load-travel record", example="travel_mm,load_N",
                                        max_bytes=MAX_BYTES)
    check_header(path, header, lambda name: name.partition("_")[0].lower() in ("travel", "load"), EXPECTED_HEADER)
    travel_col = _column(path, header, "travel", TRAVEL_UNITS_MM)
    load_col = _column(path, header, "load", LOAD_UNITS_N)
    x, f = [], []
    for line, row in rows:
        try:
            x.append(_reading(path, line, row, travel_col, MAX_TRAVEL_MM, "mm", delimiter))
            f.append(_reading(path, line, row, load_col, MAX_LOAD_N, "N", delimiter))
        except ModelError:
            raise
        except (ValueError, IndexError):
            raise ModelError(f"{path}: line {line}: {quote(row)} is not a number in every column",
                             key="path") from None
    return np.array(x), np.array(f)


def _reading(path, line, row, column, limit, unit, delimiter):
    """One reading in mm or N."""
    (index, factor), cell = column, row[column[0]].strip()
    value = number(cell, delimiter) * factor
    if not (math.isfinite(value) and abs(value) <= limit):
        raise ModelError(f"{path}: line {line}: {quote(cell)} in column {index + 1} is {value:g} {unit}, outside "
                         f"[-{limit:g}, {limit:g}] {unit}", key="path")
    return value


def _column(path, header, name, units):
    """(index, factor to mm or N) of the column `<name>_<unit>` (any case); errors name what is allowed."""
    for i, h in enumerate(header):
        stem, _, unit = h.partition("_")
        if stem.lower() == name:
            known = {u.lower(): factor for u, factor in units.items()}
            if unit.lower() not in known:
                raise ModelError(f"{path}: column {quote(h)}: unit {quote(unit)} unknown; allowed "
                                 + ", ".join(f"{name}_{u}" for u in units), key=name)
            return i, known[unit.lower()]
    raise ModelError(f"{path}: no '{name}_<unit>' column in header {quote(header)}; expected {EXPECTED_HEADER}, "
                     f"e.g. travel_mm,load_N", key=name)
