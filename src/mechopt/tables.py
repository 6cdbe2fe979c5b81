"""CSV tables as testing machines and CAD systems export them: a comma or a semicolon between
columns (then often a decimal comma), UTF-8 with or without a byte-order mark, blank lines
anywhere. The one reader of the force fit's load-travel records and of scenes' point tables;
every error names the file (and the line)."""
import csv
from pathlib import Path

from mechopt.files import read_regular
from mechopt.models.errors import ModelError

MAX_BYTES = 100_000_000      # read whole into memory: refuse what is plainly not a table of readings
MAX_ROWS = 1_000_000         # counted before parsing: a table of more readings takes minutes to refuse


def read_rows(path, *, what, example, max_bytes=MAX_BYTES, max_rows=MAX_ROWS):
    """(header, [(line number, cells)], delimiter) of the CSV file `path`, a regular file of at most
    `max_bytes` bytes and `max_rows` lines; `what` names the record in a size error ("a load-travel
    record"), `example` the header it should have."""
    path = Path(path)
    try:
        raw = read_regular(path, max_bytes=max_bytes, what=what)
    except OSError as exc:
        raise ModelError(f"{path}: cannot read: {exc.strerror}", key="path") from None
    except ValueError as exc:
        raise ModelError(str(exc), key="path") from None
    lines = raw.count(b"\n") + 1
    if lines > max_rows + 1:
        raise ModelError(f"{path}: {lines:,} lines; {what} has at most {max_rows:,} rows", key="path")
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
