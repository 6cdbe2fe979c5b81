"""Results kept on disk, shared by fresh processes: one small JSON file per key in a folder.

Used for what a solve prepares once per lever and reuses (the highest speed's walk of the
rebound's exact bound and its n / t probe: ~30 of ~50 ms CPU of a fresh loom/machine-speed, where
the re-solve, with them in the process's build caches, takes ~8 ms). A build cache is gone with
its process (and with `kit.cache.clear`); this store keeps its entries for the next process.

Off unless the variable MECHOPT_CACHE_DIR names a folder (created when missing). An entry is found
by a SHA-256 of its key's repr and of the code that computes it (`code_fingerprint(sources)`: the
sources of the packages and modules the caller names, and the numpy and scipy versions): edited
code misses every old entry, never reads it. A key whose repr may stand for another key's (an
object's address, a numpy array: `_UNSTABLE`) is not stored. A file that cannot be read is named
(StoreWarning), computed anew and written over; files are written whole (a temporary file
renamed), so readers in other processes see an entry complete or not at all.
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
LIBRARIES = ("numpy", "scipy", "casadi")      # what a stored result's numbers also depend on (CVODES: casadi)


class StoreWarning(UserWarning):
    """A stored entry could not be read (damaged): named, recomputed and written over."""


# a key's repr that may stand for more than one key: an object's address, a numpy array (its repr
# rounds to 8 digits and elides long ones)
_UNSTABLE = (" at 0x", "array(", "...")


@functools.cache            # the installed code's identity, not a build: kept through kit.cache.clear
def code_fingerprint(sources: tuple[str, ...]) -> str:
    """SHA-256 of the sources the stored results depend on (`sources`: packages, every .py file in
    them, or modules, by import name), and of the numeric libraries' versions (`LIBRARIES`)."""
    import importlib.metadata
    import importlib.util

    digest = hashlib.sha256(" ".join(f"{lib} {importlib.metadata.version(lib)}" for lib in LIBRARIES).encode())
    files = []
    for name in sources:
        spec = importlib.util.find_spec(name)
        if spec.submodule_search_locations:             # a package: all its modules
            files += sorted(p for folder in spec.submodule_search_locations for p in Path(folder).glob("*.py"))
        else:
            files.append(Path(spec.origin))
    for path in files:
        digest.update(path.name.encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()


def folder() -> Path | None:
    """The store's folder (MECHOPT_CACHE_DIR), None when the store is off."""
    where = os.environ.get(ENV)
    return Path(where) if where else None


def stored(kind: str, key, compute: Callable[[], object], encode: Callable[[object], object],
           decode: Callable[[object], object], *, sources: tuple[str, ...], enabled: bool = True):
    """compute(), or its stored value for (kind, key) when the store is on and holds it (then
    decode(the JSON of encode(value)) must equal the value: floats are written by repr, exact);
    `sources` name the code that computes it (`code_fingerprint`).
    `enabled` False (a test's law in place of the chain's, say): compute() alone."""
    where = folder()
    text = repr(key)
    if where is None or not enabled or any(part in text for part in _UNSTABLE):
        return compute()
    name = hashlib.sha256(f"{kind}\n{text}\n{code_fingerprint(tuple(sources))}".encode()).hexdigest()[:40]
    path = where / f"{kind}-{name}.json"
    try:
        return decode(json.loads(path.read_text(encoding="utf-8")))
    except FileNotFoundError:
        pass
    except Exception as exc:        # damaged (unreadable, not JSON, or not the shape decode takes): named
        warnings.warn(f"{path}: unreadable stored {kind} ({type(exc).__name__}: {exc}); recomputed and "
                      "written over", StoreWarning, stacklevel=2)
    value = compute()
    _write(path, encode(value))
    return value


def _write(path: Path, data) -> None:
    """`data` as JSON at `path`, whole or not at all (a temporary file renamed); a store that cannot
    be written (full, read-only, data JSON cannot hold) is named in a warning, the answer unchanged."""
    tmp = None
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        with tempfile.NamedTemporaryFile("w", dir=path.parent, suffix=".tmp", delete=False, encoding="utf-8") as f:
            tmp = f.name
            json.dump(data, f)
        os.replace(tmp, path)
    except (OSError, TypeError, ValueError) as exc:
        if tmp is not None:
            Path(tmp).unlink(missing_ok=True)
        warnings.warn(f"{path}: not stored ({type(exc).__name__}: {exc})", StoreWarning, stacklevel=3)
