"""The STB loom's own solvers, on the cyclogram wing's engine (mechopt.solvers.cyclogram):

* `repair.repair_cyclogram`: the cyclogram's optimum checked on the loom's exact rebound and
  contact stress, re-cut and re-solved until they hold;
* `codesign.codesign_machine_speed`: the machine's highest speed co-designed with the lift cam's law.

The engine's names (`plan_cyclogram`, `max_machine_speed`, `least_cycle_time`, `plan_motions`, ...)
and its modules (`mechopt.solvers.loom.plan`, `.graph`, ...) answer here too, for one release:
the same functions and modules as mechopt.solvers.cyclogram's (scenes saying `loom.plan_cyclogram`
run as before).
"""
from typing import TYPE_CHECKING

from mechopt.kit.lazy import lazy_names

if TYPE_CHECKING:       # for readers and the docs; at run time each name imports its module when used
    from mechopt.solvers.cyclogram import (
        HeldLP,
        build_event_time_lp,
        conflict_chain,
        incidence,
        least_cycle_time,
        max_machine_speed,
        plan_cyclogram,
        plan_motions,
        positive_cycle,
    )
    from mechopt.solvers.loom.codesign import codesign_machine_speed
    from mechopt.solvers.loom.repair import exact_amplitude_bound, repair_cyclogram

# the loom's own solvers, then the engine's names by their old modules (aliases of the cyclogram's)
__getattr__, __dir__ = lazy_names(__name__, {
    "codesign": ["codesign_machine_speed"], "repair": ["exact_amplitude_bound", "repair_cyclogram"],
    "cycle_time": ["least_cycle_time"], "event_time": ["HeldLP", "build_event_time_lp", "incidence"],
    "motions": ["plan_motions"], "plan": ["conflict_chain", "plan_cyclogram", "positive_cycle"],
    "speed": ["max_machine_speed"]})

__all__ = ["HeldLP", "build_event_time_lp", "codesign_machine_speed", "conflict_chain", "exact_amplitude_bound", "incidence",
           "least_cycle_time", "max_machine_speed", "plan_cyclogram", "plan_motions", "positive_cycle", "repair_cyclogram"]
