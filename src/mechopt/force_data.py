"""Load-travel data of a testing machine, read from CSV (the only file-reading of the force fit)."""
import csv
from pathlib import Path

import numpy as np

from mechopt.models.errors import ModelError

TRAVEL_UNITS_MM = {"mm": 1.0, "m": 1000.0, "um": 1e-3}
LOAD_UNITS_N = {"N": 1.0, "kN": 1000.0}


def read_force_csv(path):
    """(travel [mm], load [N]) from a CSV file whose header names the columns and their units,
    e.g. ``travel_mm,load_N`` (travel in mm, m or um; load in N or kN), one row per reading."""
    path = Path(path)
    try:
        with path.open(newline="", encoding="utf-8") as handle:
            rows = list(csv.reader(handle))
    except OSError as exc:
        raise ModelError(f"{path}: cannot read: {exc.strerror}", key="path") from None
    if not rows:
        raise ModelError(f"{path}: empty file; expected a header such as travel_mm,load_N", key="path")
    header = [h.strip() for h in rows[0]]
    travel_col = _column(path, header, "travel", TRAVEL_UNITS_MM)
    load_col = _column(path, header, "load", LOAD_UNITS_N)
    x, f = [], []
    for line, row in enumerate(rows[1:], start=2):
        if not row or all(not c.strip() for c in row):
            continue
        try:
            x.append(float(row[travel_col[0]]) * travel_col[1])
            f.append(float(row[load_col[0]]) * load_col[1])
        except (ValueError, IndexError):
            raise ModelError(f"{path}: line {line}: {row!r} is not a number in every column", key="path") from None
    return np.array(x), np.array(f)


def _column(path, header, name, units):
    """(index, factor to mm or N) of the column `<name>_<unit>`; errors name what is allowed."""
    for i, h in enumerate(header):
        stem, _, unit = h.partition("_")
        if stem == name:
            if unit not in units:
                raise ModelError(f"{path}: column {h!r}: unit {unit!r} unknown; allowed "
                                 + ", ".join(f"{name}_{u}" for u in units), key=name)
            return i, units[unit]
    raise ModelError(f"{path}: no '{name}_<unit>' column in header {header}; expected e.g. travel_mm,load_N", key=name)
