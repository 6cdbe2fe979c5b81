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
"""
from dataclasses import dataclass

import numpy as np

from mechopt.kit.errors import ModelError, require

LOAD_KEYS = ("load_from_mm", "load_to_mm", "load_from_deg", "load_to_deg", "load_force_N", "load_torque_Nm",
             "load_energy_J")


@dataclass(frozen=True)
class Load:
    """A resolved `constant_load`: its crank-angle window [rad] and what acts inside it."""
    start_rad: float
    end_rad: float
    force_N: float           # along the stroke, against the slide moving down
    torque_Nm: float         # at the crank, against its turning

    def work_J(self, travel) -> float:
        """The work of one stroke [J]: F times the travel inside the window plus M times its angle;
        `travel(phi)` gives X [m]."""
        return self.force_N * float(travel(self.end_rad) - travel(self.start_rad)) \
            + self.torque_Nm * (self.end_rad - self.start_rad)

    def work_so_far_J(self, phi, travel):
        """The work done from the revolution's start to each crank angle phi in [0, 2 pi] [J]."""
        inside = np.clip(phi, self.start_rad, self.end_rad)
        return self.force_N * (travel(inside) - travel(self.start_rad)) + self.torque_Nm * (inside - self.start_rad)


def resolve_load(task, angle_at_travel) -> Load:
    """The `Load` of a task with effect `constant_load`: one interval (mm or deg, both ends), one of
    force, torque or energy (with `load_shape`), each checked with a message naming the key.
    `angle_at_travel(x_m)`: the crank angle in [0, pi] at which the tool has travelled x_m."""
    by_mm = task.load_from_mm is not None or task.load_to_mm is not None
    by_deg = task.load_from_deg is not None or task.load_to_deg is not None
    require(by_mm != by_deg, "give the load's interval once: load_from_mm and load_to_mm (travel from top dead "
            "centre) or load_from_deg and load_to_deg (crank angle)", key="load_from_mm")
    low, high = ("load_from_mm", "load_to_mm") if by_mm else ("load_from_deg", "load_to_deg")
    a, b = getattr(task, low), getattr(task, high)
    require(a is not None and b is not None, f"{low} and {high}: give both ends of the load's interval", key=low)
    require(a < b, f"{high}={b:g}: allowed > {low}={a:g}", key=high)
    given = [k for k in ("load_force_N", "load_torque_Nm", "load_energy_J") if getattr(task, k) is not None]
    require(len(given) == 1, f"constant_load: give one of load_force_N, load_torque_Nm, load_energy_J (given: "
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
