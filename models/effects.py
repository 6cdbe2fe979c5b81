"""What a model's effect is: a named piece of physics a scene switches on, with its own parameters."""
from dataclasses import dataclass


@dataclass(frozen=True)
class Effect:
    adds: str                      # what the effect puts into the model, in words
    equation: str                  # where it comes from in the paper
    params: tuple[str, ...] = ()   # parameters that exist only when the effect is on
