"""The one build cache of the package: compiled CasADi functions, cvxpy problems, KD-trees and
other pure results kept per process, so a sweep re-solves instead of rebuilding.

Every cache is a `BuildCache` registered here; `clear()` empties them all (`mechopt.clear_caches()`).
`memoised` is the decorator form for a pure function of hashable arguments.
"""
import functools
import time
from collections import OrderedDict
from collections.abc import Callable, Hashable
from typing import Any

_CACHES: list["BuildCache"] = []


class BuildCache:
    """The newest `maxsize` builds, by key; the oldest is dropped first (a 10^5-event LP holds ~100 MB)."""

    def __init__(self, name: str, maxsize: int):
        self.name, self.maxsize = name, maxsize
        self._items: OrderedDict[Hashable, Any] = OrderedDict()
        _CACHES.append(self)

    def get(self, key: Hashable, build: Callable[[], Any]) -> tuple[Any, float]:
        """The build for `key` and the seconds this call spent building it (0 when it was kept)."""
        if key in self._items:
            self._items.move_to_end(key)
            return self._items[key], 0.0
        start = time.perf_counter()
        value = build()
        self._items[key] = value
        while len(self._items) > self.maxsize:
            self._items.popitem(last=False)
        return value, time.perf_counter() - start

    def values(self) -> list:
        return list(self._items.values())

    def clear(self) -> None:
        self._items.clear()

    def __len__(self) -> int:
        return len(self._items)

    def __contains__(self, key: Hashable) -> bool:
        return key in self._items


def memoised(maxsize: int) -> Callable:
    """Cache a pure function of hashable arguments in a registered `BuildCache` (`fn.cache`)."""
    def wrap(fn):
        cache = BuildCache(f"{fn.__module__}.{fn.__qualname__}", maxsize)

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
