"""CSV tables as testing machines and CAD systems export them: a comma or a semicolon between
columns (then often a decimal comma), UTF-8 with or without a byte-order mark, blank lines
anywhere. The one reader of the force fit's load-travel records and of scenes' point tables;
every error names the file (and the line)."""
import csv
import io
import re
from collections import Counter
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from mechopt.files import read_regular
from mechopt.kit.errors import ModelError, quote, some_of

MAX_BYTES = 100_000_000      # read whole into memory: refuse what is plainly not a table of readings
MAX_ROWS = 1_000_000         # counted before parsing: a table of more readings takes minutes to refuse
MAX_COLUMNS = 100            # a table of readings or operations has a few; its header checks grow with the count
_BLANK_LINE = re.compile(rb"^[ \t\r]*$", re.MULTILINE)
_COLUMN_NAME = re.compile(r"[^\W\d]\w{0,63}")     # a header's cell: a name (x_mm, Travel_kN, min_deg), not text
_PLAIN_NUMBER = "0123456789.+-eE"                  # what a decimal literal is made of (float() takes more)


def read_rows(path, *, what, example, max_bytes=MAX_BYTES, max_rows=MAX_ROWS, max_columns=MAX_COLUMNS):
    """(header, [(line number, cells)], delimiter) of the CSV file `path`, a regular file of at most
    `max_bytes` bytes, `max_rows` rows below its header and `max_columns` columns; `what` names the
    record in a size error ("a load-travel record"), `example` the header it should have. A cell
    holding a line break or a NUL character is refused (a name is one line of text)."""
    path = Path(path)
    raw = _read_bytes(path, what, max_bytes, max_rows)
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise ModelError(f"{path}: not UTF-8 text (byte 0x{raw[exc.start]:02x} at offset {exc.start}); "
                         f"save it as UTF-8 CSV with a header such as {example}", key="path") from None
    first = re.search(r"\S[^\r\n]*", text)
    if first is None:
        raise ModelError(f"{path}: empty file; expected a header such as {example}", key="path")
    delimiter = ";" if first[0].count(";") > first[0].count(",") else ","
    rows = _parse(path, text, delimiter, what, max_columns)
    _refuse_nul(path, text, rows)
    header = [h.strip() for h in rows[0][1]]
    return header, rows[1:], delimiter


def _read_bytes(path, what, max_bytes, max_rows) -> bytes:
    """The file's bytes, refused (naming it) unless a regular file within max_bytes and max_rows."""
    try:
        raw = read_regular(path, max_bytes=max_bytes, what=what)
    except OSError as exc:
        raise ModelError(f"{path}: cannot read: {exc.strerror}", key="path") from None
    except ValueError as exc:
        raise ModelError(str(exc), key="path") from None
    rows = _rows_below_header(raw, max_rows)
    if rows > max_rows:
        raise ModelError(f"{path}: {rows:,} rows; {what} has at most {max_rows:,} rows", key="path")
    return raw


def _rows_below_header(raw: bytes, max_rows: int) -> int:
    """Rows under the header, counted on the bytes before any parsing: lines holding more than
    spaces, less one (a last line break ends the last row, it starts none). A lone CR ends a line
    too, as csv reads it (old Mac files). The lines alone when they are no more than max_rows + 1
    (the blank ones only lower the count; finding them costs more than the rest of a plain read)."""
    lines = raw.count(b"\n") + 1
    if b"\r" in raw:
        lines += raw.count(b"\r") - raw.count(b"\r\n")
    if lines - 1 <= max_rows:
        return lines - 1
    return max(lines - len(_BLANK_LINE.findall(raw)) - 1, 0)


def _parse(path, text, delimiter, what, max_columns):
    """[(line number, cells)] of the non-blank rows; a quoted cell running over a line break, a
    header of more than `max_columns` cells and what the csv module cannot read are refused by line."""
    reader = csv.reader(io.StringIO(text, newline=""), delimiter=delimiter)
    rows, line = [], 0
    try:
        for cells in reader:
            start, line = line + 1, reader.line_num
            if line != start:
                raise ModelError(f"{path}: line {start}: a line break inside a quoted cell; every cell of {what} "
                                 "is one line", key="path")
            if "".join(cells).strip():       # a blank row: every cell empty or spaces (one join, not a loop)
                if not rows and len(cells) > max_columns:
                    raise ModelError(f"{path}: line {start}: a header of {len(cells):,} columns; {what} has at most "
                                     f"{max_columns}", key="path")
                rows.append((start, cells))
    except csv.Error as exc:
        limit = csv.field_size_limit()
        why = (f"a cell longer than {limit:,} characters, the most a cell may hold" if "field limit" in str(exc)
               else f"not CSV ({exc})")
        raise ModelError(f"{path}: line {reader.line_num}: {why}", key="path") from None
    return rows


def _refuse_nul(path, text, rows):
    """A NUL character anywhere is refused, naming its line and column (a binary file, or a cell
    a program would cut short there): by the header's name when that is a name, else by number."""
    if "\x00" not in text:
        return
    header = [h.strip() for h in rows[0][1]]
    line, column = next((line, i) for line, cells in rows for i, cell in enumerate(cells) if "\x00" in cell)
    named = line != rows[0][0] and column < len(header) and _COLUMN_NAME.fullmatch(header[column])
    raise ModelError(f"{path}: line {line}, column {header[column] if named else column + 1}: a NUL character; "
                     "a CSV table is text", key="path")


def check_header(path, header, known, example):
    """Refuse a first line that is no header of this table (`known`: the column names it takes,
    or a test of one), quoting nothing of it: a header of names (x_mm, min_deg), at least two of
    them or one the table takes, is named in later errors; any other file (a key, /etc/passwd)
    is only said not to be such a table."""
    takes = known if callable(known) else set(known).__contains__
    names = all(_COLUMN_NAME.fullmatch(h) for h in header)
    if not (names and (len(header) >= 2 or any(takes(h) for h in header))):
        raise ModelError(f"{path}: not a CSV table with columns {example} (its first line is no header of "
                         "column names)", key="path")


def number(cell, delimiter) -> float:
    """A cell as a float: a plain decimal literal (12, -0.5, 3e-4), with a decimal comma when ';'
    separates the columns. ValueError for what float() takes besides (1_0, inf, nan, other digits)."""
    cell = cell.strip()
    if delimiter == ";":
        cell = cell.replace(",", ".")
    if cell.strip(_PLAIN_NUMBER):        # a character outside the literal's (strip leaves it, wherever it is)
        raise ValueError(f"not a plain decimal number: {cell!r}")
    return float(cell)


MAX_TEXT = 200               # a name cell in a timing table: an event or an operation, not a paragraph
MAX_NUMBER = 40              # read_columns' widest number cell (a longer one: read row by row)


def _check_columns(path, header, columns, kinds, example, delimiter):
    """A records table's header: every name of `columns` in it, none outside `kinds`, none twice."""
    check_header(path, header, kinds, example)
    counts = Counter(header)                 # one pass: header.count per name was quadratic
    problems = [f"lacks {c}" for c in columns if c not in counts]
    problems += [f"unknown column {quote(c)}" for c in counts if c not in kinds][:3]
    problems += [f"{quote(c)} given twice" for c, n in counts.items() if n > 1][:3]
    if problems:
        raise ModelError(f"{path}: header {some_of(header, 12, delimiter)}: {'; '.join(problems)} "
                         f"(allowed columns: {', '.join(kinds)})", key="path")


def read_records(path, columns, kinds, *, required=(), what, example, max_rows=MAX_ROWS):
    """[(line number, {column: value})] of the CSV file `path`, whose header must hold every name
    in `columns` and no name outside `kinds` ({column: str or float}, which types the cells: text
    stripped and at most MAX_TEXT characters, numbers as `number` reads them). An empty cell is
    left out of its row (an optional value not given), unless its column is in `required`.
    Errors name the file, the line and the column, and quote a cell short."""
    header, rows, delimiter = read_rows(path, what=what, example=example, max_rows=max_rows)
    _check_columns(path, header, columns, kinds, example, delimiter)
    out = []
    typed = [(column, kinds[column] is not str) for column in header]
    read = lambda cell: number(cell, delimiter)        # noqa: E731
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


_SPACE = np.array([chr(b).isspace() for b in range(256)])         # what str.strip() takes off a cell's ends
_NUMBER_BYTE = np.zeros(256, dtype=bool)
_NUMBER_BYTE[np.frombuffer(_PLAIN_NUMBER.encode(), np.uint8)] = True
_NUMBER_BYTE[0] = True                                            # a narrower cell's padding
_CUTS = {d: bytes(int(b in (ord(d), ord("\n"))) for b in range(256)) for d in ",;"}    # bytes.translate tables


class Columns(Sequence):
    """A CSV table held as whole columns, {column: array} in the header's order: text cells as an
    ASCII bytes array (b"" where empty), numbers as a float array (NaN where empty: a cell that
    says nan is no plain number, so NaN only ever means not given). Read as a sequence it is
    `read_records`' rows ({column: value}, an empty cell left out), built on first use, for a
    reader that needs rows; a reader of whole columns takes `columns`."""

    def __init__(self, columns: dict[str, np.ndarray]):
        self.columns = columns
        self._rows = None

    def __len__(self):
        return len(next(iter(self.columns.values()), ()))

    def __getitem__(self, k):
        return self.rows()[k]

    def rows(self) -> list[dict]:
        """The table row by row, as read_records reads it."""
        if self._rows is None:
            text = [name for name, a in self.columns.items() if a.dtype.kind == "S"]
            cells = [[(name, v.decode()) if v else None for v in self.columns[name].tolist()] if name in text
                     else [(name, v) if v == v else None for v in self.columns[name].tolist()]
                     for name in self.columns]
            self._rows = [dict(c for c in row if c is not None) for row in zip(*cells)]
        return self._rows

    def __eq__(self, other):
        if isinstance(other, Columns):
            return list(self.columns) == list(other.columns) and all(
                np.array_equal(a, other.columns[k], equal_nan=a.dtype.kind == "f") for k, a in self.columns.items())
        return self.rows() == other if isinstance(other, list) else NotImplemented

    __hash__ = None

    def __repr__(self):
        return f"<{len(self):,} rows of {', '.join(self.columns)} read from a CSV file>"


def read_columns(path, columns, kinds, *, required=(), what, example, max_rows=MAX_ROWS,
                 only=None) -> Columns | None:
    """`read_records`' table as whole columns (`Columns`), read with no Python object per row,
    when the file is plain: ASCII, no quoted cell, no blank line, every row as many cells as the
    header, no cell with spaces around it, every number a plain literal and every required cell
    given, no column beyond `only` (where given); None otherwise (then read_records reads it row
    by row and names any fault). The size and the header are refused here as there."""
    path = Path(path)
    raw = _read_bytes(path, what, MAX_BYTES, max_rows).removeprefix(b"\xef\xbb\xbf")
    if b'"' in raw or b"\x00" in raw or (b"\r" in raw and raw.count(b"\r") != raw.count(b"\r\n")):
        return None
    if b"\r" in raw:
        raw = raw.replace(b"\r\n", b"\n")
    if not raw.endswith(b"\n"):
        raw += b"\n"
    buf = np.frombuffer(raw, np.uint8)
    if buf.max() >= 0x80:                   # text beyond ASCII: strip and widths count characters
        return None
    line = raw[:raw.index(b"\n")].decode("ascii")
    delimiter = ";" if line.count(";") > line.count(",") else ","
    header = [h.strip() for h in line.split(delimiter)]
    if not "".join(header) or len(header) > MAX_COLUMNS:
        return None
    _check_columns(path, header, columns, kinds, example, delimiter)
    if only is not None and not set(header) <= only:
        return None
    body = buf[len(line) + 1:]
    cuts = np.frombuffer(raw.translate(_CUTS[delimiter]), np.uint8)[len(line) + 1:]    # 1 at a cell's end
    ends = np.flatnonzero(cuts).astype(np.int32)          # positions in a file of at most MAX_BYTES
    del cuts
    if not ends.size or ends.size % len(header):
        return None
    ends = ends.reshape(-1, len(header))
    if (body[ends[:, -1]] != ord("\n")).any() or (body[ends[:, :-1]] == ord("\n")).any():
        return None                          # a row of more or fewer cells than the header
    starts = np.empty_like(ends)
    starts[0, 0], starts[1:, 0], starts[:, 1:] = 0, ends[:-1, -1] + 1, ends[:, :-1] + 1
    size = ends - starts
    filled = size > 0
    if not filled.any(axis=1).all() or _SPACE[body[starts[filled]]].any() or _SPACE[body[ends[filled] - 1]].any():
        return None                          # a blank row, or a cell with spaces around it
    out, padded = {}, None
    for j, name in enumerate(header):
        width = int(size[:, j].max())
        if (name in required and not filled[:, j].all()) or width > (MAX_TEXT if kinds[name] is str else MAX_NUMBER) \
                or width * len(size) > 2 * len(body) + 2**20:   # a few wide cells: the rows hold them in less memory
            return None
        if padded is None:                   # the body and room for its last cell's window
            padded = np.zeros(len(body) + int(size.max()), np.uint8)
            padded[:len(body)] = body
        cells = _cells(padded, starts[:, j], size[:, j])
        if kinds[name] is str:
            out[name] = cells
        else:
            out[name] = _numbers(cells, filled[:, j], delimiter)
            if out[name] is None:
                return None
    return Columns(out)


def _cells(padded, starts, size) -> np.ndarray:
    """The cells at `starts` of `size` bytes as one fixed-width bytes array (b"" where empty): the
    window of the widest cell's width at each start (a view of the body, `padded` past its end by
    that width), its bytes past the cell's end set to 0."""
    width = max(int(size.max(initial=0)), 1)
    grid = np.lib.stride_tricks.sliding_window_view(padded, width)[starts]
    grid[np.arange(width) >= size[:, None]] = 0
    return grid.view(f"S{width}").ravel()


def _numbers(cells, filled, delimiter) -> np.ndarray | None:
    """The cells as `number` reads them (NaN where empty), or None where one is no plain number."""
    grid = cells.view(np.uint8).reshape(len(cells), -1)
    if delimiter == ";":                     # a decimal comma
        grid = np.where(grid == ord(","), np.uint8(ord(".")), grid)
    if not _NUMBER_BYTE[grid].all():
        return None
    values = np.full(len(cells), np.nan)
    fast = _short_decimals(grid, values) & filled
    rest = filled & ~fast
    try:
        values[rest] = grid[rest].view(cells.dtype).ravel().astype(float)
    except ValueError:                       # "1.2.3", "+-1", "e": float() refuses them too
        return None
    return values


def _short_decimals(grid, values) -> np.ndarray:
    """Cells [+-]digits[.digits] of at most 15 digits read into `values` exactly as float() reads
    them: m / 10^k with the integer m < 2^53 and 10^k (k <= 15) both exact floats, one correctly
    rounded division (Clinger's fast path, as strtod's); per cell whether it was one such."""
    by_place = np.ascontiguousarray(grid.T)         # a byte position a row: the sums below run along rows
    digit = (by_place >= ord("0")) & (by_place <= ord("9"))
    dot, sign = by_place == ord("."), (grid[:, 0] == ord("+")) | (grid[:, 0] == ord("-"))
    count = digit.sum(axis=0, dtype=np.int32)
    ok = (dot.sum(axis=0, dtype=np.int32) <= 1) & (count >= 1) & (count <= 15)
    ok &= (digit | dot | (by_place == 0)).sum(axis=0, dtype=np.int32) + sign == len(by_place)   # nothing else
    scale = np.where(digit, np.uint8(10), np.uint8(1))
    value = np.where(digit, by_place - np.uint8(ord("0")), np.uint8(0))
    mantissa, places, after = np.zeros(len(grid), np.int64), np.zeros(len(grid), np.int32), np.zeros(len(grid), bool)
    for j in range(len(by_place)):          # m = 10 m + digit, and the digits after the dot, a byte position at a time
        mantissa *= scale[j]
        mantissa += value[j]
        after |= dot[j]
        places += digit[j] & after
    got = mantissa[ok] / 10.0 ** places[ok]
    values[ok] = np.where(grid[ok, 0] == ord("-"), -got, got)
    return ok
