"""Old path of the cyclogram's model (mechopt.models.cyclogram and its parts) and of the loom's own
limits (mechopt.models.loom_limits), kept for one release: its names, re-exported (a scene's
`task = "loom.Cyclogram"` finds its one task class here)."""
from mechopt.models.cyclogram import Cyclogram as Cyclogram
from mechopt.models.cyclogram_bounds import time_floor_deg as time_floor_deg
from mechopt.models.cyclogram_motions import LEAST_ANGLE as LEAST_ANGLE
from mechopt.models.cyclogram_tables import (
    MAX_CYCLES as MAX_CYCLES,
)
from mechopt.models.cyclogram_tables import (
    MAX_DEG as MAX_DEG,
)
from mechopt.models.cyclogram_tables import (
    MAX_MPA as MAX_MPA,
)
from mechopt.models.cyclogram_tables import (
    MAX_MS as MAX_MS,
)
from mechopt.models.cyclogram_tables import (
    MAX_RPM as MAX_RPM,
)
from mechopt.models.cyclogram_tables import (
    OPERATION_COLUMNS as OPERATION_COLUMNS,
)
from mechopt.models.cyclogram_tables import (
    SYNC_COLUMNS as SYNC_COLUMNS,
)
from mechopt.models.cyclogram_tables import (
    TASK_COLUMNS as TASK_COLUMNS,
)
from mechopt.models.cyclogram_tables import (
    WINDOW_COLUMNS as WINDOW_COLUMNS,
)
from mechopt.models.cyclogram_tables import (
    task_operations as task_operations,
)
from mechopt.models.loom_limits import (
    AMPLITUDE_LAWS as AMPLITUDE_LAWS,
)
from mechopt.models.loom_limits import (
    STRESS_FORMS as STRESS_FORMS,
)
from mechopt.models.loom_limits import (
    amplitude_bound_deg as amplitude_bound_deg,
)
from mechopt.models.loom_limits import (
    amplitude_mm as amplitude_mm,
)
from mechopt.models.loom_limits import (
    lever_stop as lever_stop,
)
from mechopt.models.loom_limits import (
    stress_bound_deg as stress_bound_deg,
)
from mechopt.models.loom_limits import (
    stress_MPa as stress_MPa,
)

__all__ = ["Cyclogram"]            # the task a scene may name (`loom.Cyclogram`)
