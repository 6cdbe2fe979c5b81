"""CSV tables as testing machines and CAD systems export them: a comma or a semicolon between
columns (then often a decimal comma), UTF-8 with or without a byte-order mark, blank lines
anywhere. The one reader of the force fit's load-travel records and of scenes' point tables;
every error names the file (and the line)."""
import csv
from pathlib import Path

from mechopt.errors import ModelError
from mechopt.files import quote, read_regular

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
            if "".join(row).strip()]            # a blank row: every cell empty or spaces (one join, not a loop)
    header = [h.strip() for h in rows[0][1]]
    return header, rows[1:], delimiter


def number(cell, delimiter) -> float:
    """A cell as a float; a decimal comma is read when ';' separates the columns."""
    cell = cell.strip()
    return float(cell.replace(",", ".") if delimiter == ";" else cell)


MAX_TEXT = 200               # a name cell in a timing table: an event or an operation, not a paragraph


def read_records(path, columns, kinds, *, required=(), what, example, max_rows=MAX_ROWS):
    """[(line number, {column: value})] of the CSV file `path`, whose header must hold every name
    in `columns` and no name outside `kinds` ({column: str or float}, which types the cells: text
    stripped and at most MAX_TEXT characters, numbers as `number` reads them). An empty cell is
    left out of its row (an optional value not given), unless its column is in `required`.
    Errors name the file, the line and the column, and quote a cell short."""
    header, rows, delimiter = read_rows(path, what=what, example=example, max_rows=max_rows)
    problems = [f"lacks {c}" for c in columns if c not in header]
    problems += [f"unknown column {quote(c)}" for c in header if c not in kinds][:3]
    problems += [f"{quote(c)} given twice" for c in sorted(set(header)) if header.count(c) > 1][:3]
    if problems:
        raise ModelError(f"{path}: header {quote(delimiter.join(header), 80)}: {'; '.join(problems)} "
                         f"(allowed columns: {', '.join(kinds)})", key="path")
    out = []
    typed = [(column, kinds[column] is not str) for column in header]
    # a comma between columns: a number cell is what float() reads (number() without its decimal comma)
    read = float if delimiter == "," else (lambda cell: number(cell, delimiter))
    for line, cells in rows:
        if len(cells) > len(header):
            raise ModelError(f"{path}: line {line}: {len(cells)} cells, the header names {len(header)}", key="path")
        row = {}
        for (column, numeric), cell in zip(typed, cells):
            cell = cell.strip()
            if not cell:
                continue
            if numeric:
                try:
                    row[column] = read(cell)
                except ValueError:
                    raise ModelError(f"{path}: line {line}, column {column}: expected a number, got {quote(cell)}",
                                     key="path") from None
            elif len(cell) > MAX_TEXT:
                raise ModelError(f"{path}: line {line}, column {column}: {quote(cell)} is longer than "
                                 f"{MAX_TEXT} characters", key="path")
            else:
                row[column] = cell
        absent = [c for c in required if c not in row]
        if absent:
            raise ModelError(f"{path}: line {line}: empty {', '.join(absent)} (required)", key="path")
        out.append((line, row))
    return out
