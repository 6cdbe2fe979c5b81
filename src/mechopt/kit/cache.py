"""The one build cache of the package: compiled CasADi functions, cvxpy problems, KD-trees and
other pure results kept per process, so a sweep re-solves instead of rebuilding.

Every cache is a `BuildCache` registered here; `clear()` empties them all (`mechopt.clear_caches()`).
`memoised` is the decorator form for a pure function of hashable arguments.
"""
import contextlib
import functools
import threading
import time
from collections import OrderedDict
from collections.abc import Callable, Hashable
from typing import Any

_CACHES: list["BuildCache"] = []


class _Kept:
    """A build and the lock of its users (see `BuildCache.held`)."""
    __slots__ = ("value", "lock")

    def __init__(self, value):
        self.value, self.lock = value, threading.RLock()


class BuildCache:
    """The newest `maxsize` builds, by key; the oldest is dropped first (a 10^5-event LP holds ~100 MB).

    Safe under threads (Dask workers run several tasks at once in one process): the table has its
    lock, each key is built once however many threads ask for it together, and `held` lends a
    build to one thread at a time, for a solver object whose state is set and then solved.
    `per_thread` keeps one build per thread instead: for CasADi's integrators, nlpsols and
    rootfinders, whose calls from two threads at once crash the process (their memory is one per
    object) and whose `stats()` tell the last call's, whichever thread made it. `maxsize` counts
    every thread's builds."""

    def __init__(self, name: str, maxsize: int, *, per_thread: bool = False):
        self.name, self.maxsize, self.per_thread = name, maxsize, per_thread
        self._items: OrderedDict[Hashable, _Kept] = OrderedDict()
        self._lock = threading.Lock()                      # the table
        self._building: dict[Hashable, threading.Lock] = {}   # a key being built: the others wait for it
        _CACHES.append(self)

    def get(self, key: Hashable, build: Callable[[], Any]) -> tuple[Any, float]:
        """The build for `key` and the seconds this call spent building it (0 when it was kept)."""
        kept, seconds = self._kept(key, build)
        return kept.value, seconds

    @contextlib.contextmanager
    def held(self, key: Hashable, build: Callable[[], Any]):
        """`with cache.held(key, build) as (value, seconds):` the build for `key`, used by this thread
        alone inside the block. A cvxpy Problem re-solved with new Parameter values is one state:
        two threads setting its parameters at once would solve one's numbers and read the other's
        duals (SOLVED with wrong sensitivities), so set-parameters-solve-read is held as one."""
        kept, seconds = self._kept(key, build)
        with kept.lock:
            yield kept.value, seconds

    def _key(self, key):
        return (threading.get_ident(), key) if self.per_thread else key

    def _kept(self, key, build) -> tuple[_Kept, float]:
        key = self._key(key)
        with self._lock:
            if key in self._items:
                self._items.move_to_end(key)
                return self._items[key], 0.0
            building = self._building.setdefault(key, threading.Lock())
        with building:
            with self._lock:           # built by another thread while this one waited
                if key in self._items:
                    self._items.move_to_end(key)
                    return self._items[key], 0.0
            try:
                start = time.perf_counter()
                kept = _Kept(build())
                seconds = time.perf_counter() - start
                with self._lock:
                    self._items[key] = kept
                    while len(self._items) > self.maxsize:
                        self._items.popitem(last=False)
            finally:
                with self._lock:
                    self._building.pop(key, None)
        return kept, seconds

    def values(self) -> list:
        with self._lock:
            return [kept.value for kept in self._items.values()]

    def clear(self) -> None:
        with self._lock:
            self._items.clear()

    def __len__(self) -> int:
        return len(self._items)

    def __contains__(self, key: Hashable) -> bool:
        return self._key(key) in self._items


def memoised(maxsize: int, *, per_thread: bool = False) -> Callable:
    """Cache a pure function of hashable arguments in a registered `BuildCache` (`fn.cache`);
    `per_thread` as there (for builds holding CasADi solvers)."""
    def wrap(fn):
        cache = BuildCache(f"{fn.__module__}.{fn.__qualname__}", maxsize, per_thread=per_thread)

        @functools.wraps(fn)
        def cached(*args):
            return cache.get(args, lambda: fn(*args))[0]
        cached.cache = cache
        return cached
    return wrap


def clear() -> None:
    """Empty every build cache (the next call of each solver builds afresh)."""
    for cache in _CACHES:
        cache.clear()


def caches() -> tuple[BuildCache, ...]:
    """Every registered cache, for inspection (`name`, `len`)."""
    return tuple(_CACHES)
