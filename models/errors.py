"""The errors mechopt raises. Each names the offending input (`key`) when there is one."""


class MechoptError(Exception):
    """Base of every mechopt error; `key` is the parameter or setting at fault, if any."""

    def __init__(self, message: str, *, key: str | None = None):
        super().__init__(message)
        self.key = key


class ModelError(MechoptError, ValueError):
    """The numbers describe a mechanism that cannot exist (negative length, no assembly)."""


class SceneError(MechoptError, ValueError):
    """A scene file or an override is malformed; the message names file, key and what is allowed."""


class SolverError(MechoptError, RuntimeError):
    """A numerical back end crashed or returned something unusable (not: infeasible, which is a status)."""
