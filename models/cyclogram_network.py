"""The cyclogram's network built from its tables and checked: events and operations as a graph
(precedence without a cycle, one first and one last event), windows, syncs, the limiting
operation, the recurrent operations (those ending k cycles later) and the laws an operation names."""
from functools import cached_property
from typing import TYPE_CHECKING

import numpy as np

from mechopt.kit.errors import ModelError, some_of
from mechopt.models.cyclogram_columns import PlainNetwork, ascii_text
from mechopt.models.cyclogram_motions import MOTION_KEYS, motion_of
from mechopt.models.cyclogram_tables import (
    EVENT_KEYS,
    MAX_DEG,
    MAX_MPA,
    MAX_MS,
    OPERATION_KEYS,
    STRESS_KEYS,
    SYNC_KEYS,
    WINDOW_KEYS,
    check_entry,
    check_known_event,
    check_linked_event,
    check_table,
    cycles_of,
    finite_number,
    floors_of,
)
from mechopt.models.loom_limits import AMPLITUDE_LAWS

if TYPE_CHECKING:       # imported where the graph is built: a plain table's run never builds it
    import networkx as nx

# an operation row solved as given, no law to evaluate (no stress, amplitude, motion, time, cycles, mark)
PLAIN_OPERATION_KEYS = frozenset({"from", "to", "min_deg", "name", "group", "mechanism", "why", "where", "what"})


class Network:
    """The `graph` of a Cyclogram (a part of it: the dataclass's fields are the task's) and its checks."""

    # the network as arrays when the operations came as a plain CSV table (models/cyclogram_columns.py);
    # then the views read the arrays and `graph` is built from them only when asked
    _columnar: PlainNetwork | None = None

    def _take_columns(self):
        """A plain table's network from its columns (`_columnar`); any other table as its rows."""
        if not isinstance(getattr(self.operations, "columns", None), dict):     # not a Columns table
            return
        plain = None if self.tasks or self.events else PlainNetwork.of(self.operations)
        if plain is None:
            object.__setattr__(self, "operations", list(self.operations.rows()))
        else:
            object.__setattr__(self, "_columnar", plain)

    def _check_network(self):
        """The network built and checked: the rows' graph; or the plain table's arrays, checked as
        they were built, and the graph too where windows, syncs or a limiting operation name events."""
        if self._columnar is None or self.windows or self.syncs or self.limiting_op is not None:
            _ = self.graph

    @cached_property
    def graph(self) -> "nx.DiGraph":
        """Events as nodes (mechanism, group), operations as arcs (min_deg, stress, amplitude)."""
        import networkx as nx
        g = nx.DiGraph()
        plain = self._columnar
        if plain is not None:
            g.add_nodes_from((v, {"mechanism": m, "group": group}) for v, m, group in
                             zip(plain.names.tolist(), plain.event_mechanism.tolist(), plain.event_group.tolist()))
            g.add_edges_from((x, y, arc_attributes(a, {"name": name, "group": group})) for x, y, a, name, group in
                             zip(*(plain.names[ends].tolist() for ends in (plain.tails, plain.heads)),
                                 plain.min_deg.tolist(), *(ascii_text(text).tolist() for text in
                                                           (plain.arc_name, plain.arc_group))))
        else:
            check_table(self.events, "events", dict)
            for name, attrs in self.events.items():
                check_entry(attrs, f"events.{name}", EVENT_KEYS, required=())
                g.add_node(str(name), mechanism=str(attrs.get("mechanism", "")), group=str(attrs.get("group", "")))
            check_table(self.operations, "operations", list)
            if not self._add_plain_operations(g):
                self._add_operations(g)
        if not nx.is_directed_acyclic_graph(g):
            cycle = nx.find_cycle(g)
            chain = some_of([cycle[0][0]] + [v for _, v in cycle], sep=" -> ")
            raise ModelError(f"operations: precedence cycle {chain}: an event cannot precede itself", key="operations")
        self._check_ends(g)
        return g

    def _add_plain_operations(self, g) -> bool:
        """The operations as arcs of g at once, checked over whole columns, when every row is plain
        (an angle, names and notes: PLAIN_OPERATION_KEYS) and passes; False, g unchanged, when one
        is not (then `_add_operations`, row by row, builds them or names the first bad row). The
        arcs and their attributes are `_add_operations`' (a 10^5-row timing table: ~1.5 s -> 0.3 s)."""
        ops = self.operations
        if not all(type(op) is dict and op.keys() <= PLAIN_OPERATION_KEYS and "min_deg" in op
                   and "from" in op and "to" in op for op in ops):
            return False
        phi = [op["min_deg"] for op in ops]
        if not all(type(v) is float or type(v) is int for v in phi):        # bool is neither
            return False
        with np.errstate(invalid="ignore"):
            phi = np.array(phi, dtype=float)
            if not bool(np.all((phi >= 0) & (phi <= MAX_DEG))):       # NaN fails too; inf past MAX_DEG
                return False
        xs, ys = [str(op["from"]) for op in ops], [str(op["to"]) for op in ops]
        pairs = set(zip(xs, ys))
        if (len(pairs) != len(ops) or not all(map(g.__contains__, set(xs) | set(ys)))
                or any(map(str.__eq__, xs, ys))):
            return False
        g.add_edges_from((x, y, arc_attributes(a, op)) for x, y, a, op in zip(xs, ys, phi.tolist(), ops))
        return True

    def _add_operations(self, g):
        """The operations as arcs of g, row by row, each checked (errors name the row)."""
        for k, op in enumerate(self.operations):
            key = f"operations[{k}]"
            check_entry(op, key, OPERATION_KEYS, required=("from", "to") if "min_ms" in op else ("from", "to", "min_deg"))
            x, y = str(op["from"]), str(op["to"])
            key = f"operations[{x}->{y}]"
            if cycles_of(op, key):
                continue        # a recurrent operation: not an arc of the cycle's network (`recurrences`)
            for end in (x, y):
                check_known_event(g, end, key)
            if x == y:
                raise ModelError(f"{key}: an operation must join two different events", key=key)
            if g.has_edge(x, y):
                raise ModelError(f"{key}: given twice; one operation per pair of events", key=key)
            phi, min_ms = floors_of(op, key)
            motion = motion_of(op, key)
            motion_ms, motion_limit = motion.least_ms() if motion else (0.0, "")
            if motion_ms > (min_ms or 0.0):      # the motion's limits as a least duration (models/cyclogram_motions.py)
                min_ms = motion_ms
            stress, amplitude = op.get("stress"), op.get("amplitude")
            if stress is not None:
                self._check_stress_ref(stress, key)
            if amplitude is not None:
                self._check_amplitude_ref(amplitude, key)
            g.add_edge(x, y, **arc_attributes(phi, op, min_ms=min_ms, stress=stress, motion=motion, amplitude=amplitude,
                                              motion_limit=motion_limit if motion_ms and motion_ms == min_ms else ""))

    def _check_stress_ref(self, name, key):
        check_table(self.stress_models, "stress_models", dict)
        if name not in self.stress_models:
            raise ModelError(f"{key}.stress={name!r}: no such stress model; defined: "
                             f"{', '.join(self.stress_models) or 'none'}", key=f"{key}.stress")
        if self.sigma_H_limit_MPa is None:
            raise ModelError(f"{key}.stress={name!r} needs sigma_H_limit_MPa (effect contact_stress)",
                             key="sigma_H_limit_MPa")
        model = self.stress_models[name]
        check_entry(model, f"stress_models.{name}", STRESS_KEYS, required=("sigma_ref_MPa", "t_ref_deg"))
        for k, top in (("sigma_ref_MPa", MAX_MPA), ("t_ref_deg", MAX_DEG)):
            if not 0 < finite_number(model[k], f"stress_models.{name}.{k}") <= top:
                raise ModelError(f"stress_models.{name}.{k}={model[k]} must be in (0, {top:g}]",
                                 key=f"stress_models.{name}.{k}")

    def _check_amplitude_ref(self, law, key):
        if law not in AMPLITUDE_LAWS:
            raise ModelError(f"{key}.amplitude={law!r}: no such amplitude model; known: "
                             f"{', '.join(AMPLITUDE_LAWS)}", key=f"{key}.amplitude")
        missing = [k for k in ("amplitude_slope_mm_per_deg", "amplitude_intercept_mm") if getattr(self, k) is None]
        if len(missing) == 2 and self.lever is not None:
            missing = []                # the lever's exact law stands in for the linear one
        missing += ["amplitude_limit_mm"] if self.amplitude_limit_mm is None else []
        if missing:
            raise ModelError(f"{key}.amplitude={law!r} needs {', '.join(missing)} (effect stop_vibration)"
                             + (" (or, for slope and intercept, the exact law's table `lever`)"
                                if len(missing) > 1 else ""), key=missing[0])

    def _check_ends(self, g):
        linked = [v for v in g if g.degree(v) > 0]
        starts = [v for v in linked if g.in_degree(v) == 0]
        ends = [v for v in linked if g.out_degree(v) == 0]
        # a recurrent network is a circuit of cycles, not one cycle's chain from a first to a last event
        if (len(starts) != 1 or len(ends) != 1) and not self.recurrences:
            listed = [f"[{some_of(map(repr, events), sep=', ')}]" for events in (starts, ends)]
            raise ModelError(f"operations: a cyclogram needs one first and one last event; found first {listed[0]} "
                             f"and last {listed[1]} (join them with zero-angle operations)", key="operations")
        check_table(self.windows, "windows", list)
        for k, w in enumerate(self.windows):
            key = f"windows[{k}]"
            check_entry(w, key, WINDOW_KEYS, required=("from", "to"))
            for end in (w["from"], w["to"]):
                check_linked_event(g, str(end), key, self._recurrent_events)
            given = [unit for unit in ("max_deg", "max_ms") if unit in w]
            if len(given) != 1:
                raise ModelError(f"{key}: give max_deg (an angle) or max_ms (a time), one of them; got "
                                 f"{' and '.join(given) or 'neither'}", key=key)
            limit, top = (MAX_DEG, "deg") if given[0] == "max_deg" else (MAX_MS, "ms")
            if not abs(finite_number(w[given[0]], f"{key}.{given[0]}")) <= limit:
                raise ModelError(f"{key}.{given[0]}={w[given[0]]}: allowed within +-{limit:g} {top}",
                                 key=f"{key}.{given[0]}")
        check_table(self.syncs, "syncs", list)
        for k, s in enumerate(self.syncs):
            key = f"syncs[{k}]"
            check_entry(s, key, SYNC_KEYS, required=("events",))
            if not isinstance(s["events"], list) or len(s["events"]) < 2:
                raise ModelError(f"{key}.events={s['events']!r}: give a list of two or more events", key=key)
            for end in s["events"]:
                check_linked_event(g, str(end), key, self._recurrent_events)
        if self.limiting_op is not None:
            if not isinstance(self.limiting_op, list) or len(self.limiting_op) != 2 \
                    or not g.has_edge(str(self.limiting_op[0]), str(self.limiting_op[1])):
                raise ModelError(f"limiting_op={self.limiting_op!r}: must name an operation [from, to]",
                                 key="limiting_op")

    @cached_property
    def recurrences(self) -> tuple[dict, ...]:
        """The recurrent operations, rows with `cycles` = k > 0: p(to) + k T >= p(from) + d, the
        event `to` of k cycles later after `from` of this one (T the cycle; d its min_deg, or min_ms
        in a time-based network). `from` may equal `to` (a station busy for d before it starts
        again). They carry a floor only (min_deg or min_ms): no window, stress or amplitude. The
        least cycle time over them is `cyclogram.least_cycle_time`; a one-cycle solver refuses them
        (`check_one_cycle`). Rows with cycles = 0 are ordinary operations."""
        if self._columnar is not None:
            return ()               # a plain table has no cycles column
        check_table(self.operations, "operations", list)
        out, seen = [], set()
        for op in self.operations:
            if not isinstance(op, dict) or "cycles" not in op or "from" not in op or "to" not in op:
                continue                # an ordinary row, or one the network's checks report
            x, y = str(op["from"]), str(op["to"])
            key = f"operations[{x}->{y}]"
            k = cycles_of(op, key)
            if not k:
                continue
            check_entry(op, key, OPERATION_KEYS, required=("from", "to") if "min_ms" in op else ("from", "to", "min_deg"))
            for end in (x, y):
                if end not in self.events:
                    raise ModelError(f"{key}: unknown event {end!r}; events: {some_of(self.events, sep=', ')}",
                                     key=key)
            extra = sorted(({"max_deg", "stress", "amplitude"} | set(MOTION_KEYS)) & op.keys())
            if extra:
                raise ModelError(f"{key}.cycles={k}: a recurrent operation carries min_deg or min_ms only, not "
                                 f"{', '.join(extra)}", key=f"{key}.{extra[0]}")
            if (x, y, k) in seen:
                raise ModelError(f"{key}.cycles={k}: given twice; one operation per pair of events and cycles",
                                 key=key)
            seen.add((x, y, k))
            phi, min_ms = floors_of(op, key)
            out.append({"from": x, "to": y, "cycles": k, "min_deg": phi, "min_ms": min_ms,
                        "name": str(op.get("name", ""))})
        return tuple(out)

    @cached_property
    def _recurrent_events(self) -> frozenset:
        return frozenset(e for op in self.recurrences for e in (op["from"], op["to"]))

    def check_one_cycle(self, solver: str) -> None:
        """ModelError when the network has recurrent operations: `solver` schedules one cycle."""
        if self.recurrences:
            op = self.recurrences[0]
            key = f"operations[{op['from']}->{op['to']}].cycles"
            raise ModelError(f"{key}={op['cycles']}: {solver} schedules one cycle and takes no recurrent "
                             f"operation; the least cycle time of a recurrent network is cyclogram.least_cycle_time",
                             key=key)


def arc_attributes(min_deg, op, *, min_ms=None, stress=None, motion=None, motion_limit="", amplitude=None) -> dict:
    """An operation's arc attributes, one list for the row-by-row build and the plain table's at once."""
    return {"min_deg": min_deg, "min_ms": min_ms, "stress": stress, "motion": motion, "motion_limit": motion_limit,
            "amplitude": amplitude, "name": str(op.get("name", "")), "group": str(op.get("group", ""))}
