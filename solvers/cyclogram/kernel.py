"""Compiled longest-path passes for large networks: numba, optional.

A pass over a DAG's arcs in topological order of their heads is one loop of a few instructions
per arc; numpy does it level by level (graph.Levels), paying ~10 us of Python per level and
numpy call. On the layered 10^5-event network (1000 levels, 3 x 10^5 arcs) that overhead is the
whole pass (~9 ms, best of 15); the compiled loop takes ~2 ms (its reads of dist follow the
arcs, not memory order). So `graph.Levels` hands its passes to these kernels for networks of
at least COMPILED_MIN_ARCS arcs when numba imports, and keeps the numpy levels otherwise: numba
is an optional dependency (`pip install mechopt[fast]`), its import (~0.5 s) is paid only by a
process that solves a large network, and its compiled code is cached on disk (the first
compile, ~2 s, happens once per installation), and a process imports it only once its numpy
passes would have cost as much (COMPILED_AFTER_LEVEL_CALLS). Small networks, every scene of the package
among them, never import it.

Set MECHOPT_NO_NUMBA=1 to keep the numpy passes (the fallback, and the reference the tests
compare against).
"""
import os
import warnings

COMPILED_MIN_ARCS = 20_000      # below: the numpy levels are as fast (few levels) and need no import
# numba's import and cache load cost ~0.5-0.9 s and ~60 MB in a fresh process (a second process
# loads the cached code, it does not compile: tests/cyclogram/test_cli_speed.py), about 50,000 numpy
# level steps at ~10 us: a process takes the compiled passes once its numpy passes have stepped
# through that many levels (graph.Levels), so a one-off solve of a shallow network never pays it
COMPILED_AFTER_LEVEL_CALLS = 50_000

_KERNELS = None                 # (forward, backward) once imported; False when numba is missing


def kernels():
    """(forward, backward) compiled passes, or None when numba is not installed or switched off."""
    global _KERNELS
    if _KERNELS is None:
        _KERNELS = False
        if not os.environ.get("MECHOPT_NO_NUMBA"):
            try:
                with warnings.catch_warnings():     # a cache folder it cannot write: slower, not wrong
                    warnings.simplefilter("ignore")
                    _KERNELS = _compile()
            except Exception:       # noqa: BLE001 - numba missing or unable to compile here: the numpy passes
                _KERNELS = False
    return _KERNELS or None


def _compile():
    """The two passes, compiled (or loaded from numba's cache) now, on a two-event network."""
    import numpy as np
    from numba import njit

    @njit(cache=True, nogil=True)
    def forward(dist, order, tails, heads, w):          # pragma: no cover - compiled
        """dist[h] = max(dist[h], dist[t] + w[order]) along tails, heads (the arcs sorted by their
        head's level; `order` their indices in w)."""
        for i in range(order.size):
            c = dist[tails[i]] + w[order[i]]
            if c > dist[heads[i]]:
                dist[heads[i]] = c

    @njit(cache=True, nogil=True)
    def backward(dist, order, tails, heads, w):         # pragma: no cover - compiled
        """dist[t] = max(dist[t], w[order] + dist[h]) along tails, heads (sorted by their tail's
        level, the last level first)."""
        for i in range(order.size):
            c = dist[heads[i]] + w[order[i]]
            if c > dist[tails[i]]:
                dist[tails[i]] = c

    one, order = np.zeros(1), np.zeros(1, dtype=np.int64)
    for kernel in (forward, backward):
        kernel(np.zeros(2), order, order, order + 1, one)
    return forward, backward
