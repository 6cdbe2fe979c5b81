"""A plain timing table (names, angles and notes: no time, law, window, cycles or mark) read as
whole columns (`mechopt.tables.Columns`) and turned into the cyclogram's network as index arrays
with no Python object per operation: events numbered by numpy (np.unique over the names), in the
order the row-by-row build gives them (first mention), operations in its arc order (by tail, in
the table's order), each event's group as `events_of` agrees it. `PlainNetwork.of` checks what the
row-by-row build checks (distinct ends, one operation per pair, no precedence cycle, one first and
one last event) and answers None where a row breaks a rule: the rows are then built one by one and
the error names the row. The networkx graph is built from the arrays only when asked (`graph`)."""
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from mechopt.models.cyclogram_tables import MAX_DEG

# columns of a plain table: each one the row-by-row build reads as given (models/cyclogram_network.py,
# PLAIN_OPERATION_KEYS: the CSV's columns among them)
PLAIN_COLUMNS = frozenset({"from", "to", "min_deg", "name", "group", "mechanism", "why"})


@dataclass(frozen=True, eq=False)
class PlainNetwork:
    """Events and operations as arrays: `names` the events (str array, graph order), `tails`,
    `heads` (int64, arc order), `min_deg` [deg] and, per operation, its `arc_name` and `arc_group`
    (ASCII bytes, b"" where none: read as text where asked, a graph's or a message's); per event
    its `event_group` and `event_mechanism` (str, "" where none). Read-only."""
    names: np.ndarray
    tails: np.ndarray
    heads: np.ndarray
    min_deg: np.ndarray
    arc_name: np.ndarray
    arc_group: np.ndarray
    event_group: np.ndarray
    event_mechanism: np.ndarray

    @classmethod
    def of(cls, table) -> "PlainNetwork | None":
        """The network of a `Columns` table, or None where the table is not plain or a row breaks
        a rule (the row-by-row build then names it)."""
        cols = table.columns
        if not (cols.keys() <= PLAIN_COLUMNS and {"from", "to", "min_deg"} <= cols.keys()) or not len(table):
            return None
        phi = cols["min_deg"]
        with np.errstate(invalid="ignore"):
            if not bool(np.all((phi >= 0) & (phi <= MAX_DEG))):        # an empty cell (NaN) fails too
                return None
        ends = np.empty(2 * len(table), dtype=np.result_type(cols["from"], cols["to"]))
        ends[0::2], ends[1::2] = cols["from"], cols["to"]              # first mention: from, to, from, to, ...
        if not _filled(ends).all():                                    # an empty name
            return None
        unique, first, inverse = np.unique(_keys(ends), return_index=True, return_inverse=True)
        unique = ends[first]
        order = np.argsort(first, kind="stable")
        rank = np.empty_like(order)
        rank[order] = np.arange(len(order))
        ids = rank[inverse]
        t, h, n = ids[0::2], ids[1::2], len(unique)
        pairs = np.sort(t * n + h)
        if (t == h).any() or (pairs[1:] == pairs[:-1]).any():         # an event joined to itself; a pair twice
            return None
        if not (t < h).all() and not _acyclic(n, t, h):   # numbered by first mention, a table in
            return None                                     # precedence order has every arc forward
        indeg, outdeg = np.bincount(h, minlength=n), np.bincount(t, minlength=n)
        if (indeg == 0).sum() != 1 or (outdeg == 0).sum() != 1:
            return None
        # networkx's edge order: by tail, each tail's in row order (a table in tail order already is)
        arcs = np.arange(len(t)) if (t[1:] >= t[:-1]).all() else np.argsort(t, kind="stable")
        blank = np.zeros(len(table), dtype="S1")
        group, mechanism = cols.get("group", blank), cols.get("mechanism", blank)
        out = cls(names=ascii_text(unique[order]), tails=t[arcs], heads=h[arcs], min_deg=phi[arcs],
                  arc_name=cols.get("name", blank)[arcs], arc_group=group[arcs],
                  event_group=_agreed(group, t, h, n), event_mechanism=_agreed(mechanism, t, h, n))
        for a in vars(out).values():
            a.flags.writeable = False
        return out


def _acyclic(n, tails, heads) -> bool:
    """Whether the arcs hold no cycle (Kahn's levels, the solvers' passes' order too)."""
    try:
        topological_levels(n, tails, heads)
    except ValueError:
        return False
    return True


def topological_levels(n: int, tails: np.ndarray, heads: np.ndarray) -> np.ndarray:
    """Each event's level: 0 without predecessors, else 1 + the largest level of one (Kahn's
    algorithm a whole level at a time). ValueError when the arcs hold a cycle."""
    by_tail = np.argsort(tails, kind="stable")
    start = np.r_[0, np.cumsum(np.bincount(tails, minlength=n))]
    succ = heads[by_tail]
    indeg = np.bincount(heads, minlength=n)
    level = np.full(n, -1, dtype=np.int64)
    frontier, depth = np.flatnonzero(indeg == 0), 0
    while frontier.size:
        level[frontier] = depth
        counts = start[frontier + 1] - start[frontier]
        total = int(counts.sum())
        if not total:
            break
        offsets = np.repeat(start[frontier] - np.r_[0, np.cumsum(counts)[:-1]], counts) + np.arange(total)
        reached = succ[offsets]
        np.subtract.at(indeg, reached, 1)
        # the events freed, sorted, once each (np.unique's hash costs ~0.1 ms a level, and imports numpy.ma)
        reached = np.sort(reached[indeg[reached] == 0])
        first = np.ones(reached.size, dtype=bool)
        first[1:] = reached[1:] != reached[:-1]
        frontier, depth = reached[first], depth + 1
    if (level < 0).any():
        raise ValueError("the operations hold a precedence cycle")
    return level


def _keys(names) -> np.ndarray:
    """Names as sort keys: names of up to 8 bytes as one integer each (a sort of integers, not of
    strings: only equality matters, the events are then put in order of first mention)."""
    return names.astype("S8").view(np.uint64) if names.dtype.itemsize <= 8 else names


def _filled(cells) -> np.ndarray:
    """Per bytes cell whether it holds text (its first byte: no cell holds a NUL)."""
    return cells.view(np.uint8).reshape(len(cells), -1)[:, 0] != 0


def ascii_text(cells) -> np.ndarray:
    """ASCII bytes cells as a str array: each byte widened to its code point (numpy's astype(str)
    decodes a cell at a time, ~20x slower)."""
    cells = np.ascontiguousarray(cells)
    return cells.view(np.uint8).astype(np.uint32).view(f"U{cells.dtype.itemsize}").reshape(cells.shape)


def _agreed(values, tails, heads, n) -> np.ndarray:
    """Per event the value (bytes cells) on which every operation ending at it agrees, or, with
    none ending at it, every one starting at it; "" where they differ (`cyclogram_tables.events_of`,
    per column); a str array."""
    if not _filled(values).any():               # no such column: "" everywhere
        return np.full(n, "")
    _, first, code = np.unique(_keys(values), return_index=True, return_inverse=True)
    kinds = ascii_text(values[first])
    into, out = _agree(code, heads, n), _agree(code, tails, n)
    pick = np.where(np.bincount(heads, minlength=n) > 0, into, out)
    return np.append(kinds, "")[pick]           # -1: the "" appended


def _agree(code, at, n) -> np.ndarray:
    """Per event the code of the operations `at` it when they all have the same, else -1."""
    low, high = np.full(n, len(code) + 1), np.full(n, -1)
    np.minimum.at(low, at, code)
    np.maximum.at(high, at, code)
    return np.where(low == high, low, -1)


class Arcs(Sequence):
    """The operations as (from, to) pairs, in arc order, read off the index arrays when asked
    (a list of 10^5 tuples costs more than the solve)."""

    def __init__(self, names: list[str], tails: np.ndarray, heads: np.ndarray):
        self._names, self._tails, self._heads = names, tails, heads

    def __len__(self):
        return len(self._tails)

    def __getitem__(self, k):
        if isinstance(k, slice):
            return [self[i] for i in range(*k.indices(len(self)))]
        return self._names[self._tails[k]], self._names[self._heads[k]]

    def __eq__(self, other):
        return list(self) == list(other) if isinstance(other, Sequence) else NotImplemented

    __hash__ = None
