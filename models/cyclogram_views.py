"""Views of a cyclogram's network the solvers read: events and operations as index arrays, labels,
groups, windows and syncs as pairs, each operation's attributes and motion (cached: the task is
frozen, and a walk over 10^5 events costs ~0.1 s)."""
from functools import cached_property
from typing import TYPE_CHECKING

import numpy as np

from mechopt.kit.errors import ModelError
from mechopt.models.cyclogram_bounds import time_floor_deg
from mechopt.models.cyclogram_columns import Arcs, ascii_text

if TYPE_CHECKING:
    import networkx as nx


class Views:
    """The views of a Cyclogram's `graph` (a part of it: the dataclass's fields are the task's)."""

    @property
    def event_names(self) -> list[str]:
        return list(self._event_names) if self._columnar is not None else list(self.graph.nodes)

    @cached_property
    def _event_names(self) -> tuple[str, ...]:
        return tuple(self._columnar.names.tolist())

    @cached_property
    def arcs(self) -> list[tuple[str, str]]:
        """Operations as (from, to), in the order every per-arc array uses (a plain table's: a
        sequence read off its index arrays)."""
        plain = self._columnar
        return list(self.graph.edges) if plain is None else Arcs(self._event_names, plain.tails, plain.heads)

    # the views below are cached (the task is frozen): a solve asks for them several times, and a
    # walk over the graph's nodes or edges costs ~0.1 s at 10^5 events

    @cached_property
    def index_arrays(self) -> tuple[tuple[str, ...], np.ndarray, np.ndarray]:
        """(events in graph order without the isolated ones, tails, heads): the operations as
        index arrays into those events, in `arcs` order (read-only; the solvers' view)."""
        plain = self._columnar
        if plain is not None:                   # every event has an operation: none isolated
            return self._event_names, plain.tails, plain.heads
        names, index = tuple(self.event_index), self.event_index
        tails = np.fromiter((index[x] for x, _ in self.arcs), dtype=np.int64, count=len(self.arcs))
        heads = np.fromiter((index[y] for _, y in self.arcs), dtype=np.int64, count=len(self.arcs))
        tails.flags.writeable = heads.flags.writeable = False
        return names, tails, heads

    @cached_property
    def event_index(self) -> dict[str, int]:
        """Event -> its index in `index_arrays` (graph order, isolated events left out); not to be changed."""
        if self._columnar is not None:
            return {v: i for i, v in enumerate(self._event_names)}
        isolated = set(self._isolated)
        return {v: i for i, v in enumerate(v for v in self.graph if v not in isolated)}

    @cached_property
    def group_indices(self) -> dict[str, np.ndarray]:
        """Group -> the indices (as `event_index`) of its events that have an operation."""
        plain = self._columnar
        if plain is not None:
            return {group: np.flatnonzero(plain.event_group == group) for group in self._group_order}
        index = self.event_index
        return {group: np.array([index[v] for v in events if v in index], dtype=np.int64)
                for group, events in self._groups.items()}

    @cached_property
    def _group_order(self) -> list[str]:
        """A plain table's groups in order of their first event."""
        kinds, first = np.unique(self._columnar.event_group, return_index=True)
        return [str(kinds[j]) for j in np.argsort(first) if kinds[j]]

    @cached_property
    def operation_labels(self) -> np.ndarray:
        """Each operation as "from->to", in `arcs` order (read-only)."""
        plain = self._columnar
        if plain is None:
            labels = np.array([f"{x}->{y}" for x, y in self.arcs], dtype=str)
        else:                   # joined as ASCII bytes (a plain table's names are), a quarter of str's memory
            names = plain.names.astype("S")
            labels = ascii_text(np.char.add(np.char.add(names[plain.tails], b"->"), names[plain.heads]))  # numpy 1.26 too
        labels.flags.writeable = False
        return labels

    @cached_property
    def end_indices(self) -> tuple[int, int]:
        """(first, last): the indices (as `event_index`) of the first and the last event."""
        plain = self._columnar
        if plain is None:
            return self.event_index[self.first_event], self.event_index[self.last_event]
        n = len(plain.names)
        return tuple(int(np.flatnonzero(np.bincount(ends, minlength=n) == 0)[0]) for ends in (plain.heads, plain.tails))

    @cached_property
    def first_event(self) -> str:
        if self._columnar is not None:
            return str(self._columnar.names[self.end_indices[0]])
        return next(v for v in self.graph if self.graph.in_degree(v) == 0 and self.graph.out_degree(v) > 0)

    @cached_property
    def last_event(self) -> str:
        if self._columnar is not None:
            return str(self._columnar.names[self.end_indices[1]])
        return next(v for v in self.graph if self.graph.out_degree(v) == 0 and self.graph.in_degree(v) > 0)

    @property
    def isolated_events(self) -> list[str]:
        return list(self._isolated)

    @cached_property
    def _isolated(self) -> tuple[str, ...]:
        if self._columnar is not None:
            return ()
        return tuple(v for v, d in self.graph.degree if d == 0)

    @property
    def groups(self) -> dict[str, list[str]]:
        """Group name -> its events (events without a group are left out)."""
        return {group: list(events) for group, events in self._groups.items()}

    @cached_property
    def _groups(self) -> dict[str, tuple[str, ...]]:
        out: dict[str, list[str]] = {}
        plain = self._columnar
        for v, group in (self.graph.nodes(data="group") if plain is None
                         else zip(self._event_names, plain.event_group.tolist())):
            if group:
                out.setdefault(group, []).append(v)
        return {group: tuple(events) for group, events in out.items()}

    def group_graph(self, group: str) -> "nx.DiGraph":
        """The subgraph of one group's events and the operations between them."""
        if group not in self.groups:
            raise ModelError(f"group={group!r}: no such group; known: {', '.join(self.groups) or 'none'}", key="group")
        return self.graph.subgraph(self.groups[group])

    def sync_pairs(self) -> list[tuple[str, str]]:
        """Each synchronisation as consecutive equal pairs (a, b): p(a) = p(b)."""
        return [(str(s["events"][i]), str(s["events"][i + 1])) for s in self.syncs for i in range(len(s["events"]) - 1)]

    def window_arcs(self) -> list[tuple[str, str, float]]:
        """(from, to, max_deg) of every window: p(to) - p(from) <= max_deg; a window in time (max_ms)
        as the angle the shaft turns in it at speed_rpm (a time becomes an angle at a speed)."""
        out = []
        for k, w in enumerate(self.windows):
            if "max_deg" in w:
                out.append((str(w["from"]), str(w["to"]), float(w["max_deg"])))
                continue
            if self.speed_rpm is None:
                raise ModelError(f"windows[{k}].max_ms needs speed_rpm (a time becomes an angle at a speed)",
                                 key="speed_rpm")
            out.append((str(w["from"]), str(w["to"]), time_floor_deg(float(w["max_ms"]), self.speed_rpm)))
        return out

    def time_windows(self) -> list[int]:
        """Indices of the windows given in time (max_ms): their angle grows with the speed."""
        return [k for k, w in enumerate(self.windows) if "max_ms" in w]

    @cached_property
    def _arc_data(self) -> tuple[dict, ...]:
        """Each arc's attributes, in `arcs` order: one walk of the graph's edges for the views
        above (a walk through networkx's views per attribute cost ~0.3 s each at 3 x 10^5 arcs)."""
        return tuple(d for _, _, d in self.graph.edges(data=True))

    @cached_property
    def operation_names(self) -> dict[tuple[str, str], str]:
        """(from, to) -> ' "name"' for the operations the table names (the conflict messages' words)."""
        plain = self._columnar
        if plain is not None:
            named = np.flatnonzero(plain.arc_name != b"")
            return {self.arcs[k]: f' "{name}"' for k, name in zip(named.tolist(),
                                                                  ascii_text(plain.arc_name[named]).tolist())}
        return {(x, y): f' "{name}"' for x, y, name in self.graph.edges(data="name") if name}

    @cached_property
    def motion_arcs(self) -> dict:
        """Arc index (in `arcs` order) -> its Motion (models/cyclogram_motions.py), for the operations with a law."""
        if self._columnar is not None:
            return {}               # a plain table has no law column
        return {k: d["motion"] for k, d in enumerate(self._arc_data) if d["motion"] is not None}

    def motion_values(self, t_deg, speed_rpm) -> dict:
        """Peak acceleration and velocity of every motion with a stroke, its angle t (per arc,
        `arcs` order) at speed n: accel_<x>_<y>_m_s2, velocity_<x>_<y>_m_s (stroke_mm) or
        accel_<x>_<y>_rad_s2, velocity_<x>_<y>_rad_s (stroke_deg, an oscillating output)."""
        out = {}
        for k, motion in self.motion_arcs.items() if speed_rpm else ():
            if motion.stroke is not None and t_deg[k] > 0:
                (x, y), (_, accel, velocity) = self.arcs[k], motion.units
                out[f"accel_{x}_{y}_{accel}"] = motion.peak_accel(float(t_deg[k]), speed_rpm)
                out[f"velocity_{x}_{y}_{velocity}"] = motion.peak_velocity(float(t_deg[k]), speed_rpm)
        return out

    def arc_data(self, k: int) -> dict:
        x, y = self.arcs[k]
        return self.graph.edges[x, y]
