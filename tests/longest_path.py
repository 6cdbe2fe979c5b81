"""An independent longest path of a cyclogram's network, for tests that check the solvers' span."""
import numpy as np


def longest_path(task, lb=None):
    """Longest path first -> last over the task's arcs with bounds lb (by default its lower bounds
    [deg]), by relaxing the arcs in repeated passes (no networkx, no levels)."""
    lb = task.lower_bounds_deg()[0] if lb is None else lb
    dist = {task.first_event: 0.0}
    for _ in range(len(task.arcs)):                  # Bellman-Ford style: enough passes for any DAG
        changed = False
        for (x, y), w in zip(task.arcs, lb):
            if x in dist and dist[x] + w > dist.get(y, -np.inf):
                dist[y], changed = dist[x] + w, True
        if not changed:
            break
    return dist[task.last_event]
