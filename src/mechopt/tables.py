"""CSV tables as testing machines and CAD systems export them: a comma or a semicolon between
columns (then often a decimal comma), UTF-8 with or without a byte-order mark, blank lines
anywhere. The one reader of the force fit's load-travel records and of scenes' point tables;
every error names the file (and the line)."""
import csv
from pathlib import Path

from mechopt.models.errors import ModelError

MAX_BYTES = 100_000_000      # read whole into memory: refuse what is plainly not a table of readings


def read_rows(path, *, what, example, max_bytes=MAX_BYTES):
    """(header, [(line number, cells)], delimiter) of the CSV file `path`; `what` names the record
    in a size error ("a load-travel record"), `example` the header it should have."""
    path = Path(path)
    try:
        size = path.stat().st_size
        if size > max_bytes:
            raise ModelError(f"{path}: {size / 1e6:.3g} MB; {what} is at most {max_bytes / 1e6:g} MB "
                             f"(millions of readings)", key="path")
        raw = path.read_bytes()
    except OSError as exc:
        raise ModelError(f"{path}: cannot read: {exc.strerror}", key="path") from None
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise ModelError(f"{path}: not UTF-8 text (byte 0x{raw[exc.start]:02x} at offset {exc.start}); "
                         f"save it as UTF-8 CSV with a header such as {example}", key="path") from None
    lines = text.splitlines()
    if not any(line.strip() for line in lines):
        raise ModelError(f"{path}: empty file; expected a header such as {example}", key="path")
    first = next(line for line in lines if line.strip())
    delimiter = ";" if first.count(";") > first.count(",") else ","
    rows = [(number, row) for number, row in enumerate(csv.reader(lines, delimiter=delimiter), start=1)
            if any(c.strip() for c in row)]
    header = [h.strip() for h in rows[0][1]]
    return header, rows[1:], delimiter


def number(cell, delimiter) -> float:
    """A cell as a float; a decimal comma is read when ';' separates the columns."""
    cell = cell.strip()
    return float(cell.replace(",", ".") if delimiter == ";" else cell)
