"""The press's working load when it is not eq. (1): a constant force or torque over a stated part
of the stroke, or a stated energy per stroke with a stated shape (effect ``constant_load``).

The textbook punching press (e.g. Sarkar, Theory of Machines, ch. 6; Khurmi and Gupta, Theory of
Machines, ch. 16 "Turning moment diagrams and flywheel") gives the load one of two ways:

* a force that acts while the slide travels through the plate: a constant force F [N] along the
  stroke over a travel interval [from, to] mm from top dead centre (the work F (to - from));
* the energy of one punch [J] drawn "during 1/n of the revolution": a constant torque M [N m] at
  the crank over a crank-angle interval [from, to] deg (the work M (to - from) in rad).

An energy per stroke with ``load_shape = "constant_force"`` is read as the first (F = E / travel),
with ``"constant_torque"`` as the second (M = E / angle). Either interval may be given in travel
(mm, on the way down: the crank angles where X reaches them) or in crank angle (deg); the load acts
only while the crank turns forward. The interval's ends are switching events, located as eq. (1)'s
cut window is (the same `cut_start` / `cut_end` events and revolution pieces).

A measured load is a table (`load_table`, rows [x, F_N], e.g. from a CSV): the force along the
stroke against the crank angle [deg] or the travel [mm] (`load_table_axis`), linear between rows
(in that variable), on the way down, zero outside the table's span (the window). Two rows at the same
x are a jump: its crank angle is an event of its own (`load_jump`), the integrators stop and restart
there as at the window's ends, so no step crosses it.
"""
from dataclasses import dataclass
from itertools import pairwise

import casadi as ca
import numpy as np
from scipy.integrate import quad

from mechopt.kit.errors import ModelError, require

LOAD_KEYS = ("load_from_mm", "load_to_mm", "load_from_deg", "load_to_deg", "load_force_N", "load_torque_Nm",
             "load_energy_J")
MAX_TABLE_ROWS = 2000


@dataclass(frozen=True)
class Load:
    """A resolved `constant_load`: its crank-angle window [rad] and what acts inside it."""
    start_rad: float
    end_rad: float
    force_N: float           # along the stroke, against the slide moving down
    torque_Nm: float         # at the crank, against its turning
    table: tuple = ()        # rows (crank angle [rad], x as given [deg or mm], F [N]) of a measured load
    axis: str = ""           # what the table's x is: "crank_deg" or "travel_mm"

    @property
    def jumps_rad(self) -> tuple[float, ...]:
        """The crank angles inside the window where the table jumps (two rows at one x)."""
        return tuple(a0 for (a0, _, _), (a1, _, _) in pairwise(self.table)
                     if a1 == a0 and self.start_rad < a0 < self.end_rad)

    def key(self) -> tuple:
        """What a build of the equations depends on besides p: the table (its rows are not in p)."""
        return ("table", self.axis, self.table) if self.table else ()

    def table_force_N(self, turn, x_mm, m=np):
        """The table's force at crank angles `turn` in [0, 2 pi) with travel `x_mm` there [N]: linear
        in the table's x between rows, 0 outside its span (numbers, or CasADi with m=ca)."""
        pick = (lambda c, v: ca.if_else(c, v, 0)) if m is ca else (lambda c, v: np.where(c, v, 0.0))
        both = ca.logic_and if m is ca else np.logical_and
        total = 0.0 * turn
        last = len(self.table) - 2
        for k, ((a0, s0, f0), (a1, s1, f1)) in enumerate(pairwise(self.table)):
            if a1 <= a0:
                continue                    # a jump: no segment, the next row starts the next one
            s = x_mm if self.axis == "travel_mm" else turn * 180 / np.pi
            upper = turn <= a1 if k == last else turn < a1
            total = total + pick(both(turn >= a0, upper), f0 + (f1 - f0) * (s - s0) / (s1 - s0))
        return total

    def work_J(self, travel) -> float:
        """The work of one stroke [J]: F times the travel inside the window plus M times its angle;
        a table's: the integral of F dX, exact on each row's segment (linear in X: the trapezoid; linear
        in the crank angle: by parts, F X minus the integral of X dF, that one by quadrature).
        `travel(phi)` gives X [m]."""
        if self.table:
            return float(self.work_so_far_J(np.array([self.end_rad]), travel)[0])
        return self.force_N * float(travel(self.end_rad) - travel(self.start_rad)) \
            + self.torque_Nm * (self.end_rad - self.start_rad)

    def work_so_far_J(self, phi, travel):
        """The work done from the revolution's start to each crank angle phi in [0, 2 pi] [J]."""
        if self.table:
            return np.array([self._table_work_J(min(max(float(p), self.start_rad), self.end_rad), travel)
                             for p in np.atleast_1d(phi)])
        inside = np.clip(phi, self.start_rad, self.end_rad)
        return self.force_N * (travel(inside) - travel(self.start_rad)) + self.torque_Nm * (inside - self.start_rad)

    def _table_work_J(self, upto, travel) -> float:
        work = 0.0
        for (a0, s0, f0), (a1, s1, f1) in pairwise(self.table):
            if a1 <= a0 or upto <= a0:
                continue
            b = min(upto, a1)
            X0, Xb = float(travel(a0)), float(travel(b))
            if self.axis == "travel_mm":            # F linear in X: the trapezoid is exact
                fb = f0 + (f1 - f0) * (Xb * 1000 - s0) / (s1 - s0)
                work += 0.5 * (f0 + fb) * (Xb - X0)
            else:                                   # F linear in phi: F X - integral of X dF
                slope = (f1 - f0) / (a1 - a0)
                fb = f0 + slope * (b - a0)
                area = quad(lambda p: float(travel(p)), a0, b, epsabs=0, epsrel=1e-13)[0]
                work += fb * Xb - f0 * X0 - slope * area
        return work


def resolve_load(task, angle_at_travel) -> Load:
    """The `Load` of a task with effect `constant_load`: one interval (mm or deg, both ends), one of
    force, torque or energy (with `load_shape`), each checked with a message naming the key.
    `angle_at_travel(x_m)`: the crank angle in [0, pi] at which the tool has travelled x_m."""
    if task.load_table:
        return _table_load(task, angle_at_travel)
    by_mm = task.load_from_mm is not None or task.load_to_mm is not None
    by_deg = task.load_from_deg is not None or task.load_to_deg is not None
    require(by_mm != by_deg, "give the load's interval once: load_from_mm and load_to_mm (travel from top dead "
            "centre) or load_from_deg and load_to_deg (crank angle)", key="load_from_mm")
    low, high = ("load_from_mm", "load_to_mm") if by_mm else ("load_from_deg", "load_to_deg")
    a, b = getattr(task, low), getattr(task, high)
    require(a is not None and b is not None, f"{low} and {high}: give both ends of the load's interval", key=low)
    require(a < b, f"{high}={b:g}: allowed > {low}={a:g}", key=high)
    given = [k for k in ("load_force_N", "load_torque_Nm", "load_energy_J") if getattr(task, k) is not None]
    require(len(given) == 1, f"constant_load: give one of load_force_N, load_torque_Nm, load_energy_J, load_table (given: "
            f"{', '.join(given) or 'none'})", key=given[1] if len(given) > 1 else "load_force_N")
    if by_mm:
        stroke = task.stroke_mm
        require(b <= stroke, f"load_to_mm={b:g}: allowed <= the stroke 2 crank_radius_mm = {stroke:g} mm", key=high)
        start, end = (angle_at_travel(x / 1000) for x in (a, b))
    else:
        start, end = np.radians(a), np.radians(b)
        pushes = task.load_force_N is not None or (task.load_energy_J is not None
                                                   and task.load_shape == "constant_force")
        if pushes:      # a force along the stroke over a crank interval: the slide must move one way inside it
            require(b <= 180, f"load_to_deg={b:g}: allowed <= 180 for a force along the stroke (the way down, "
                    "where the slide moves one way)", key=high)
    start, end = float(start), float(end)
    force = torque = 0.0
    if task.load_force_N is not None:
        force = task.load_force_N
    elif task.load_torque_Nm is not None:
        torque = task.load_torque_Nm
    elif task.load_shape == "constant_force":
        span_m = float(task.travel(end) - task.travel(start))
        if span_m <= 0:
            raise ModelError("load_energy_J with load_shape='constant_force' needs a travel inside the interval",
                             key="load_energy_J")
        force = task.load_energy_J / span_m
    else:
        torque = task.load_energy_J / (end - start)
    return Load(start, end, float(force), float(torque))


def _table_load(task, angle_at_travel) -> Load:
    """The `Load` of a `load_table`: its rows checked (two numbers each, x non-decreasing with at most
    two rows at one x, F >= 0, x on the way down), x turned into crank angles."""
    stray = [k for k in LOAD_KEYS if getattr(task, k) is not None]
    require(not stray, f"{stray[0] if stray else ''}: a load_table sets the load and its interval alone; drop it",
            key=stray[0] if stray else "load_table")
    rows = task.load_table
    ok = 2 <= len(rows) <= MAX_TABLE_ROWS and all(
        isinstance(r, tuple) and len(r) == 2
        and all(isinstance(v, int | float) and not isinstance(v, bool) and np.isfinite(v) for v in r) for r in rows)
    require(ok, f"load_table: expected 2 to {MAX_TABLE_ROWS} rows [x, F_N] of finite numbers", key="load_table")
    xs = [float(r[0]) for r in rows]
    top = 180.0 if task.load_table_axis == "crank_deg" else task.stroke_mm
    unit = "deg" if task.load_table_axis == "crank_deg" else "mm"
    for k, (x, f) in enumerate(rows):
        require(0 <= x <= top, f"load_table[{k}]: x = {x:g} {unit}: allowed 0 ... {top:g} (the way down)",
                key="load_table")
        require(f >= 0, f"load_table[{k}]: F = {f:g} N: allowed >= 0 (against the slide moving down)", key="load_table")
    for k in range(1, len(xs)):
        require(xs[k] >= xs[k - 1], f"load_table[{k}]: x = {xs[k]:g} {unit} after {xs[k - 1]:g}: allowed "
                "non-decreasing", key="load_table")
        require(k < 2 or not xs[k] == xs[k - 1] == xs[k - 2], f"load_table[{k}]: three rows at x = {xs[k]:g} "
                f"{unit}: a jump is two rows", key="load_table")
    require(xs[-1] > xs[0], "load_table: its x spans nothing", key="load_table")
    angles = [float(np.radians(x)) if task.load_table_axis == "crank_deg" else float(angle_at_travel(x / 1000))
              for x in xs]
    table = tuple((a, x, float(r[1])) for a, x, r in zip(angles, xs, rows))
    return Load(angles[0], angles[-1], 0.0, 0.0, table, task.load_table_axis)
