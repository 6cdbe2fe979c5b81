"""Old path of the cyclogram's plan (mechopt.solvers.cyclogram.plan and the modules it was split
into), kept for one release: its names, re-exported. Gone: dag_times, schedule_floats and
longest_distances (the longest paths are graph.Levels' passes: schedule.float_array, graph_floats)."""
from mechopt.solvers.cyclogram.certify import ONE_SIDED_STEP, SENS_LIMITS, certified, certify, one_sided_sensitivity
from mechopt.solvers.cyclogram.conflicts import MAX_CONFLICTS, conflict_chain, constraint_arcs, positive_cycle
from mechopt.solvers.cyclogram.graph_method import RANGING_MAX_OPS, RANGING_MAX_TABLE
from mechopt.solvers.cyclogram.lp_method import LP_BUILDS, set_parameters
from mechopt.solvers.cyclogram.net import PER_NAME_MAX_OPS, Net, back_arcs, per_name, plan_arrays
from mechopt.solvers.cyclogram.plan import plan_cyclogram
from mechopt.solvers.cyclogram.schedule import (
    SENSITIVITY_CONVENTION,
    float_array,
    graph_floats,
    limit_diagnostics,
    schedule_values,
)

__all__ = ["LP_BUILDS", "MAX_CONFLICTS", "ONE_SIDED_STEP", "PER_NAME_MAX_OPS", "RANGING_MAX_OPS", "RANGING_MAX_TABLE",
           "SENSITIVITY_CONVENTION", "SENS_LIMITS", "Net", "back_arcs", "certified", "certify", "conflict_chain",
           "constraint_arcs", "float_array", "graph_floats", "limit_diagnostics", "one_sided_sensitivity", "per_name",
           "plan_arrays", "plan_cyclogram", "positive_cycle", "schedule_values", "set_parameters"]
