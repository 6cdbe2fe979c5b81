"""The cyclogram wing's solvers: event times of a cyclic machine's network (paper 004, problem (1);
the STB loom is its case), a linear program solved on its graph.

    minimise p(N) - p(1)   subject to   p(y) - p(x) >= [phi(x, y)]                 every operation
                                        p(y) - p(x) >= sigma-bound(x, y; [sigma_H])  cam pairs
                                        slope (p(7) - p(3)) + intercept <= a_lim    amplitude law
                                        p(y) - p(x) <= w,  p(a) = p(b)             windows, syncs
                                        p(1) = 0                                     anchor

* `plan.plan_cyclogram`: this LP solved on the graph (`graph_method`: its dual, longest paths on
  `graph.Levels`, the default) or in cvxpy (`lp_method`), each checked against the other on demand
  (check=True, `certify`); `net` (the task as index arrays), `schedule` (values, floats, the
  critical chain), `conflicts` (an infeasible network's positive cycles, named);
* `speed.max_machine_speed`: the whole machine's largest speed, an LP in (p, n) or bisection on n
  (part 5);
* `motions.plan_motions`: the LP with clearances between motions and the least of several
  motions' angles maximised (rows that are not difference constraints);
* `cycle_time.least_cycle_time`: a recurrent machine's least cycle time, the maximum cycle ratio
  of its constraints, and the circuit that sets it (the LP in (p, T) as certificate);
* `event_time`: the LP's matrices, and `HeldLP`, the LP held in HiGHS for many bound changes.

The STB loom's own solvers (the exact rebound's repair, the lift law's co-design) are mechopt.solvers.loom's.
"""
from typing import TYPE_CHECKING

from mechopt.kit.lazy import lazy_names

if TYPE_CHECKING:       # for readers and the docs; at run time each name imports its module when used
    from mechopt.solvers.cyclogram.conflicts import conflict_chain, positive_cycle
    from mechopt.solvers.cyclogram.cycle_time import least_cycle_time
    from mechopt.solvers.cyclogram.event_time import HeldLP, build_event_time_lp, incidence
    from mechopt.solvers.cyclogram.motions import plan_motions
    from mechopt.solvers.cyclogram.plan import plan_cyclogram
    from mechopt.solvers.cyclogram.speed import max_machine_speed

# a plan needs neither the speed LP nor cvxpy's LP: each imports when used
__getattr__, __dir__ = lazy_names(__name__, {
    "cycle_time": ["least_cycle_time"], "event_time": ["HeldLP", "build_event_time_lp", "incidence"],
    "motions": ["plan_motions"], "plan": ["plan_cyclogram"], "conflicts": ["conflict_chain", "positive_cycle"],
    "speed": ["max_machine_speed"]})

__all__ = ["HeldLP", "build_event_time_lp", "conflict_chain", "incidence", "least_cycle_time", "max_machine_speed",
           "plan_cyclogram", "plan_motions", "positive_cycle"]
