"""Warm starts between the variants of a sweep: inside `session()` a solver may keep what one
answer learnt for the next (`store()`, a dict per session, keyed by the solver); outside it
`store()` is None, so a single run never depends on what ran before it."""
import contextlib
import contextvars

__all__ = ["session", "store"]

_STORE: contextvars.ContextVar[dict | None] = contextvars.ContextVar("mechopt_warm_store", default=None)


@contextlib.contextmanager
def session():
    """A fresh store for the variants solved inside (`sweep` opens one per chunk)."""
    token = _STORE.set({})
    try:
        yield
    finally:
        _STORE.reset(token)


def store() -> dict | None:
    """The current session's store, or None outside a session."""
    return _STORE.get()
