"""The cyclogram's tables as a scene gives them: the columns a CSV may carry (operations, windows,
syncs, task tables), the keys each entry allows, the stated ranges of the inputs, the checks of one
entry, and a task table (activity on node) turned into the event network it stands for."""
import math

from mechopt.kit.errors import ModelError, some_of
from mechopt.models.cyclogram_motions import MOTION_KEYS
from mechopt.models.provenance import provenance_problem

# stated limits of the inputs: past 1e6 deg (a thousand turns) the LP's feasibility tolerance
# (1e-7 relative) is coarser than the 1e-6 deg its answer is certified to; stresses past 1e6 MPa
# are no material's (and square past the float range in the sensitivities)
MAX_DEG = 1e6
MAX_MPA = 1e6
MAX_RPM = 1e6           # the lever model's stated range (models/stop_impact.py)
MAX_MS = 1e6
MAX_CYCLES = 1_000_000  # cycles a recurrent operation may span (a whole number)
NOTE_KEYS = {"mark", "why", "where", "what"}         # provenance and description, not physics
EVENT_KEYS = {"mechanism", "group"} | NOTE_KEYS
OPERATION_KEYS = {"from", "to", "min_deg", "min_ms", "max_deg", "stress", "amplitude", "name", "group",
            "mechanism", "cycles"} | set(MOTION_KEYS) | NOTE_KEYS
# an operations table read from a designer's CSV (scene: `operations = { csv = "ops.csv", columns =
# [...] }`): its columns and their kinds; event names are text ("3", "10.1", "feed.start")
OPERATION_COLUMNS = {"from": str, "to": str, "name": str, "group": str, "mechanism": str, "min_deg": float,
                     "min_ms": float, "max_deg": float, "stress": str, "amplitude": str, "mark": str, "why": str,
                     "cycles": float, "law": str, "stroke_mm": float, "max_accel_m_s2": float,
                     "max_velocity_m_s": float, "direction": str, "stroke_deg": float, "max_accel_rad_s2": float,
                     "max_velocity_rad_s": float}
WINDOW_COLUMNS = {"from": str, "to": str, "max_deg": float, "max_ms": float} | {k: str for k in sorted(NOTE_KEYS)}
SYNC_COLUMNS = {"events": str} | {k: str for k in sorted(NOTE_KEYS)}   # events "a;b;c": one sync per row
STRESS_KEYS = {"sigma_ref_MPa", "t_ref_deg"} | NOTE_KEYS
WINDOW_KEYS = {"from", "to", "max_deg", "max_ms"} | NOTE_KEYS
SYNC_KEYS = {"events"} | NOTE_KEYS
# a task table (activity on node): each task a duration and the tasks it waits for, "a;b", one k
# cycles before written "b@k"; turned into the event network by `task_operations`
TASK_COLUMNS = {"task": str, "min_ms": float, "min_deg": float, "after": str, "name": str, "group": str,
                "mechanism": str, "mark": str, "why": str}
TASK_KEYS = set(TASK_COLUMNS) | NOTE_KEYS


def events_of(operations) -> dict:
    """{event: {group, mechanism}} from the operations naming them, in order of first mention: an
    event takes the group (and mechanism) on which every operation ending at it agrees (the motion
    that brings it about), or, with none ending at it (the first event), every one starting at it;
    where they differ (a junction of groups, the last event) it takes none."""
    into, out = {}, {}                  # event -> (group, mechanism) agreed so far ("" when none)
    rows = [op for op in operations if isinstance(op, dict) and "from" in op and "to" in op]   # others: the checks'
    for op in rows:
        about = (str(op.get("group", "")), str(op.get("mechanism", "")))
        for side, name in ((out, str(op["from"])), (into, str(op["to"]))):
            seen = side.setdefault(name, about)
            if seen is not about and seen != about:
                side[name] = tuple(s if s == a else "" for s, a in zip(seen, about))
    names = dict.fromkeys(name for op in rows for name in (str(op["from"]), str(op["to"])))
    return {name: {k: v for k, v in zip(("group", "mechanism"), into.get(name) or out[name]) if v} for name in names}


def task_operations(tasks) -> list[dict]:
    """A task table (activity on node: rows {task, min_ms or min_deg, after}) as the operations of
    its event network: each task t an operation t.start -> t.end of its duration; each task b it
    waits for an operation b.end -> t.start of 0 (cycles = k for "b@k", b of k cycles before);
    a task waiting for none of this cycle starts after the event `start`, one none waits for ends
    before `end`. Errors name the task's row."""
    check_table(tasks, "tasks", list)
    rows = {}
    for j, row in enumerate(tasks):
        check_entry(row, f"tasks[{j}]", TASK_KEYS, required=("task",))
        name = str(row["task"]).strip()
        if not name or name in rows or name in ("start", "end"):
            why = "given twice" if name in rows else "a task needs a name other than start and end"
            raise ModelError(f"tasks[{j}].task={row['task']!r}: {why}", key=f"tasks[{j}].task")
        if "min_ms" not in row and "min_deg" not in row:
            raise ModelError(f"tasks[{name}]: give its duration, min_ms or min_deg", key=f"tasks[{name}]")
        rows[name] = row
    ops, waits, awaited = [], set(), set()
    for name, row in rows.items():
        ops.append({"from": f"{name}.start", "to": f"{name}.end", "name": str(row.get("name", name))}
                   | {k: row[k] for k in ("min_ms", "min_deg", "group", "mechanism", "mark", "why") if k in row})
        for before, k in _predecessors(row.get("after", ""), f"tasks[{name}].after", rows):
            ops.append({"from": f"{before}.end", "to": f"{name}.start", "min_deg": 0.0} | ({"cycles": k} if k else {}))
            if not k:
                waits.add(name)
                awaited.add(before)
    ops += [{"from": "start", "to": f"{t}.start", "min_deg": 0.0} for t in rows if t not in waits]
    ops += [{"from": f"{t}.end", "to": "end", "min_deg": 0.0} for t in rows if t not in awaited]
    return ops


def _predecessors(after, key, rows) -> list[tuple[str, int]]:
    """(task, cycles) of an `after` cell "a;b@1" (a list of such names too), each a task of the table."""
    if not isinstance(after, (str, list)) or (isinstance(after, list) and not all(isinstance(a, str) for a in after)):
        raise ModelError(f"{key}={after!r}: expected the tasks waited for, as 'a;b' (or 'b@k': k cycles before)",
                         key=key)
    out = []
    for item in (after.split(";") if isinstance(after, str) else after):
        name, _, k = item.strip().partition("@")
        name = name.strip()
        if not name:
            continue
        if name not in rows:
            raise ModelError(f"{key}: unknown task {name!r}; tasks: {some_of(rows, sep=', ')}", key=key)
        if k and not (k.strip().isdigit() and int(k) <= MAX_CYCLES):
            raise ModelError(f"{key}: {item.strip()!r}: the cycles after '@' must be a whole number in "
                             f"[0, {MAX_CYCLES}]", key=key)
        out.append((name, int(k) if k else 0))
    return out


def split_windows(operations) -> tuple[list, list]:
    """(operations, windows): an operation's `max_deg` (its window, p(to) - p(from) <= max_deg)
    taken out as a window of its own, so the solvers see one kind of window."""
    ops, windows = [], []
    for op in operations:
        if isinstance(op, dict) and "max_deg" in op:
            op = dict(op)
            window = {"from": op.get("from"), "to": op.get("to"), "max_deg": op.pop("max_deg")}
            if op.get("mark", "given") != "given":
                window |= {"mark": op["mark"], "why": op.get("why", "")}
            windows.append(window)
        ops.append(op)
    return ops, windows


def cycles_of(op, key) -> int:
    """An operation's `cycles` (0 when not given), checked: a whole number in [0, MAX_CYCLES]."""
    k = op.get("cycles", 0)
    if isinstance(k, bool) or not isinstance(k, (int, float)) or not float(k).is_integer() \
            or not 0 <= k <= MAX_CYCLES:
        raise ModelError(f"{key}.cycles={k!r}: a count of cycles must be a whole number in [0, {MAX_CYCLES}]",
                         key=f"{key}.cycles")
    return int(k)


def floors_of(op, key) -> tuple[float, float | None]:
    """(min_deg, min_ms or None) of an operation row, checked (a timed operation may leave out min_deg)."""
    phi = finite_number(op.get("min_deg", 0.0), f"{key}.min_deg")
    if phi < 0:
        raise ModelError(f"{key}.min_deg={phi}: a minimum phase angle must be >= 0", key=f"{key}.min_deg")
    if phi > MAX_DEG:
        raise ModelError(f"{key}.min_deg={phi}: a minimum phase angle must be <= {MAX_DEG:g} deg",
                         key=f"{key}.min_deg")
    min_ms = op.get("min_ms")
    if min_ms is not None and not 0 <= finite_number(min_ms, f"{key}.min_ms") <= MAX_MS:
        raise ModelError(f"{key}.min_ms={min_ms}: a minimum duration must be in [0, {MAX_MS:g}] ms",
                         key=f"{key}.min_ms")
    return phi, None if min_ms is None else float(min_ms)


def check_table(value, key, kind):
    if not isinstance(value, kind):
        raise ModelError(f"{key}: expected a {'table' if kind is dict else 'list of tables'}, got {value!r}", key=key)


def check_entry(entry, key, allowed, required):
    if not isinstance(entry, dict):
        raise ModelError(f"{key}: expected a table, got {entry!r}", key=key)
    if entry.keys() <= allowed and all(k in entry for k in required) and "mark" not in entry:
        return                  # the common case, checked fast: 10^5-event networks pass through here
    unknown = sorted(set(entry) - allowed)
    if unknown:
        raise ModelError(f"{key}: unknown {', '.join(unknown)}; allowed: {', '.join(sorted(allowed))}", key=key)
    missing = [k for k in required if k not in entry]
    if missing:
        raise ModelError(f"{key}: missing {', '.join(missing)}", key=key)
    problem = provenance_problem(entry.get("mark", "given"), entry.get("why", ""))
    if problem:
        raise ModelError(f"{key}{'.' if problem.startswith('mark=') else ': '}{problem}", key=key)


def check_known_event(g, name, key):
    if name not in g:
        raise ModelError(f"{key}: unknown event {name!r}; events: {some_of(g.nodes, sep=', ')}", key=key)


def check_linked_event(g, name, key, also=frozenset()):
    check_known_event(g, name, key)
    if g.degree(name) == 0 and name not in also:
        raise ModelError(f"{key}: event {name!r} has no operation; a window or sync needs events of the network",
                         key=key)


def finite_number(value, key):
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ModelError(f"{key}={value!r}: expected a finite number", key=key)
    return float(value)
