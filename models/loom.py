"""Old path of the cyclogram's model (mechopt.models.cyclogram and its parts) and of the loom's own
limits (mechopt.models.loom_limits), kept for one release: its names, re-exported."""
from mechopt.models.cyclogram import Cyclogram
from mechopt.models.cyclogram_bounds import time_floor_deg
from mechopt.models.cyclogram_motions import LEAST_ANGLE
from mechopt.models.cyclogram_tables import (
    MAX_CYCLES,
    MAX_DEG,
    MAX_MPA,
    MAX_MS,
    MAX_RPM,
    OPERATION_COLUMNS,
    SYNC_COLUMNS,
    TASK_COLUMNS,
    WINDOW_COLUMNS,
    task_operations,
)
from mechopt.models.loom_limits import (
    AMPLITUDE_LAWS,
    STRESS_FORMS,
    amplitude_bound_deg,
    amplitude_mm,
    lever_stop,
    stress_bound_deg,
    stress_MPa,
)

__all__ = ["AMPLITUDE_LAWS", "LEAST_ANGLE", "MAX_CYCLES", "MAX_DEG", "MAX_MPA", "MAX_MS", "MAX_RPM", "OPERATION_COLUMNS",
           "STRESS_FORMS", "SYNC_COLUMNS", "TASK_COLUMNS", "WINDOW_COLUMNS", "Cyclogram", "amplitude_bound_deg",
           "amplitude_mm", "lever_stop", "stress_MPa", "stress_bound_deg", "task_operations", "time_floor_deg"]
