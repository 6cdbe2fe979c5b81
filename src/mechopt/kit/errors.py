"""The errors mechopt raises, by kind (cvxpy's `error.py` is the model). Each names the offending
input (`key`) when there is one, and each is also the builtin it is a kind of (a bad number is a
ValueError, a crashed back end a RuntimeError), so a caller may catch either.

Part of the kit (`mechopt.kit`): importable from models, solvers and the spine alike,
and importing nothing from mechopt themselves (tests/spine/test_layout.py).
"""


class MechoptError(Exception):
    """Base of every mechopt error; `key` is the parameter or setting at fault, if any."""

    def __init__(self, message: str, *, key: str | None = None):
        super().__init__(message)
        self.key = key


class ModelError(MechoptError, ValueError):
    """The numbers describe a mechanism that cannot exist (negative length, no assembly)."""


class SceneError(MechoptError, ValueError):
    """A scene file or an override is malformed; the message names file, key and what is allowed."""


class SettingError(SceneError):
    """A solver setting is unknown or out of the range its signature declares (in a scene or a direct call)."""


class SolverError(MechoptError, RuntimeError):
    """A numerical back end crashed or returned something unusable (not: infeasible, which is a status)."""


NAMED = 20         # items of a list a message names (a conflicting chain's constraints); the rest are counted


def some_of(items, limit: int = NAMED, sep: str = "; ") -> str:
    """The first `limit` items joined by `sep`, and how many more there are ("a; b ... and 999,998
    more"): a message stays a line whatever the size of the problem it speaks of."""
    items = list(items)
    shown = sep.join(map(str, items[:limit]))
    return shown if len(items) <= limit else f"{shown} ... and {len(items) - limit:,} more"


def require(ok: bool, message: str, *, key: str | None = None, kind: type[MechoptError] = ModelError) -> None:
    """Raise `kind(message, key=key)` unless `ok`: a rule relating inputs (a < b, the stroke against
    the blank); one input's own range is declared on its field instead (kit.settings.check_fields)."""
    if not ok:
        raise kind(message, key=key)


def quote(value, limit: int = 40) -> str:
    """A short, escaped prefix of a value read from a file: an error names the file and line but
    echoes no more of its content (a reference may name a key file or /etc/passwd)."""
    try:
        text = repr(value)
    except RecursionError:
        return "(a value nested too deeply to show)"
    return text if len(text) <= limit else f"{text[:limit]}... ({len(text)} characters)"
