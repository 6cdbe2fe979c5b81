"""A lever's preparation for the highest speed kept on disk, shared by fresh processes.

The rebound's exact bound (the walk, `loom.repair.cached_amplitude_bound`) and the n / t probe
(`cyclogram.speed_laws.n_over_t_probe`) are properties of the lever, its limit and the walk's grid
alone, and cost most of a fresh highest-speed solve (loom/machine-speed: ~30 of ~50 ms CPU, where
the re-solve, with them kept in the process's build caches, takes ~8 ms). A build cache is gone
with its process (and with `kit.cache.clear`); this store keeps them in a folder, one small JSON
file per key, so a second process (or a solve after the caches were cleared) reads them.

Off unless the variable MECHOPT_CACHE_DIR names a folder (created when missing). An entry is found
by a SHA-256 of its key's repr and of the code that computes it (`code_fingerprint`: the sources of
mechopt.models, mechopt.solvers.stop_impact, mechopt.solvers.loom and the probe's module speed_laws, and
the numpy and scipy versions): edited code misses every old entry, never reads it. A key whose repr
may stand for another key's (an object's address, a numpy array: `_UNSTABLE`) is not stored. A file that cannot be read is named
(StoreWarning), computed anew and written over; files are written whole (a temporary file renamed), so readers in other
processes see an entry complete or not at all.
"""
import functools
import hashlib
import json
import os
import tempfile
import warnings
from collections.abc import Callable
from pathlib import Path

ENV = "MECHOPT_CACHE_DIR"


class StoreWarning(UserWarning):
    """A stored entry could not be read (damaged): named, recomputed and written over."""


_PACKAGES = ("mechopt.models", "mechopt.solvers.stop_impact", "mechopt.solvers.loom")
_MODULES = ("mechopt.solvers.cyclogram.speed_laws",)        # the probe
# a key's repr that may stand for more than one key: an object's address, a numpy array (its repr
# rounds to 8 digits and elides long ones)
_UNSTABLE = (" at 0x", "array(", "...")


@functools.cache            # the installed code's identity, not a build: kept through kit.cache.clear
def code_fingerprint() -> str:
    """SHA-256 of the sources the stored results depend on, and of numpy's and scipy's versions."""
    import importlib
    import importlib.util

    import numpy
    import scipy
    digest = hashlib.sha256(f"numpy {numpy.__version__} scipy {scipy.__version__}".encode())
    files = []
    for name in _PACKAGES:
        files += sorted(Path(p) for folder in importlib.import_module(name).__path__ for p in Path(folder).glob("*.py"))
    files += [Path(importlib.util.find_spec(name).origin) for name in _MODULES]
    for path in files:
        digest.update(path.name.encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()


def folder() -> Path | None:
    """The store's folder (MECHOPT_CACHE_DIR), None when the store is off."""
    where = os.environ.get(ENV)
    return Path(where) if where else None


def stored(kind: str, key, compute: Callable[[], object], encode: Callable[[object], object],
           decode: Callable[[object], object], *, enabled: bool = True):
    """compute(), or its stored value for (kind, key) when the store is on and holds it (then
    decode(the JSON of encode(value)) must equal the value: floats are written by repr, exact).
    `enabled` False (a test's law in place of the chain's, say): compute() alone."""
    where = folder()
    text = repr(key)
    if where is None or not enabled or any(part in text for part in _UNSTABLE):
        return compute()
    name = hashlib.sha256(f"{kind}\n{text}\n{code_fingerprint()}".encode()).hexdigest()[:40]
    path = where / f"{kind}-{name}.json"
    try:
        return decode(json.loads(path.read_text(encoding="utf-8")))
    except FileNotFoundError:
        pass
    except (OSError, ValueError, TypeError, KeyError) as exc:      # damaged: named, computed anew
        warnings.warn(f"{path}: unreadable stored {kind} ({type(exc).__name__}: {exc}); recomputed and "
                      "written over", StoreWarning, stacklevel=2)
    value = compute()
    where.mkdir(parents=True, exist_ok=True)
    with tempfile.NamedTemporaryFile("w", dir=where, suffix=".tmp", delete=False, encoding="utf-8") as f:
        json.dump(encode(value), f)
    os.replace(f.name, path)
    return value
