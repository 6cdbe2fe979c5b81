"""What a model's effect is: a named piece of physics a scene switches on, with its own parameters."""
from dataclasses import dataclass


@dataclass(frozen=True)
class Effect:
    adds: str                      # what the effect puts into the model, in words
    equation: str                  # where it comes from in the paper
    params: tuple[str, ...] = ()   # parameters that exist only when the effect is on


def check_effects(task) -> None:
    """The one rule of effects, for every task with an `EFFECTS` table: each listed effect is
    known, and an effect's own parameters are given exactly when the effect is listed (None
    otherwise): an effect that is not listed adds no parameter, state or term."""
    from mechopt.kit.errors import ModelError
    known = type(task).EFFECTS
    unknown = [e for e in task.effects if e not in known]
    if unknown:
        raise ModelError(f"effects={list(task.effects)}: unknown {unknown}; known: "
                         f"{', '.join(known) or 'none'} ({type(task).__name__})", key="effects")
    for name, effect in known.items():
        for key in effect.params:
            given = getattr(task, key, None) is not None
            if given and name not in task.effects:
                raise ModelError(f"{key}={getattr(task, key)} belongs to effect '{name}', which is not listed in "
                                 f"effects; add it to effects or drop the parameter", key=key)
            if not given and name in task.effects:
                raise ModelError(f"{key} missing: effect '{name}' needs it", key=key)
