"""The lift lever's uncertain inputs on a box, for a law that must hold on every lever of it.

Three inputs the model takes from assumptions or calibrations: the natural frequencies (both modes
together: E_GPa scaled by the factor's square, so the moving lever's and the plate's frequency move
by the factor and the preload's force with the stiffness; the mass, hence the roller's closure per
unit mass, stays), the damping ratio zeta (of the link and of the plate, as the model has one), and a
speed margin above the band's top (the machine run faster than planned). A lever of the box is a
key (frequency factor, zeta); the speed is the band's own axis. The synthesis holds the box's
corners and its nominal in the LP and checks a grid of it (solvers/stop_impact/synthesis_search.py,
synthesis_box.py).
"""
import dataclasses
import functools
import inspect
from dataclasses import dataclass

import numpy as np

from mechopt.kit.errors import SettingError
from mechopt.kit.settings import Annotated, Interval, range_fault
from mechopt.models.stop_impact import LeverStop

__all__ = ["BOX_SETTINGS", "LeverBox", "box_of", "takes_box"]


@dataclass(frozen=True)
class LeverBox:
    """frequency: (low, high) factor on both natural frequencies; zeta: (low, high) damping ratio,
    None for the task's own; speed_margin: the band's top raised by this fraction; grid: points
    per axis of the dense check (both ends included)."""
    frequency: tuple = (1.0, 1.0)
    zeta: tuple | None = None
    speed_margin: float = 0.0
    grid: int = 3

    def __post_init__(self):
        lo, hi = self.frequency
        for key, value in (("box_frequency_low", lo), ("box_frequency_high", hi)):
            if not value > 0:
                raise SettingError(range_fault(key, value, "allowed > 0 (a factor on the natural frequencies)"),
                                   key=key)
        if lo > hi:
            raise SettingError(f"box_frequency_low={lo} > box_frequency_high={hi}: the box is empty",
                               key="box_frequency_low")
        if self.zeta is not None:
            zlo, zhi = self.zeta
            for key, value in (("box_zeta_low", zlo), ("box_zeta_high", zhi)):
                if not 0 <= value <= 1:
                    raise SettingError(range_fault(key, value, "allowed 0 ... 1 (a damping ratio)"), key=key)
            if zlo > zhi:
                raise SettingError(f"box_zeta_low={zlo} > box_zeta_high={zhi}: the box is empty", key="box_zeta_low")
        if not 0 <= self.speed_margin <= 1:
            raise SettingError(range_fault("box_speed_margin", self.speed_margin, "allowed 0 ... 1"),
                               key="box_speed_margin")

    @property
    def trivial(self) -> bool:
        """One lever and no margin: the nominal synthesis."""
        return self.frequency == (1.0, 1.0) and self.zeta is None and self.speed_margin == 0.0

    def nominal(self, task: LeverStop) -> tuple:
        return 1.0, float(task.damping_ratio or 0.0)

    def _zetas(self, task):
        return self.zeta if self.zeta is not None else (self.nominal(task)[1],) * 2

    def corners(self, task: LeverStop) -> list:
        """The nominal key, then the box's corners (each once)."""
        keys = [self.nominal(task)]
        for f in self.frequency:
            for z in self._zetas(task):
                if (float(f), float(z)) not in keys:
                    keys.append((float(f), float(z)))
        return keys

    def grid_keys(self, task: LeverStop, points: int | None = None) -> list:
        """The nominal key and a `points` x `points` grid of the box (corners included)."""
        points = points or self.grid
        keys = [self.nominal(task)]
        for f in np.linspace(*self.frequency, points):
            for z in np.linspace(*self._zetas(task), points):
                if (float(f), float(z)) not in keys:
                    keys.append((float(f), float(z)))
        return keys

    def band(self, band_rpm) -> tuple:
        """The speed band with the margin above its top [rpm]."""
        return float(band_rpm[0]), float(band_rpm[1]) * (1.0 + self.speed_margin)

    @staticmethod
    def lever(task: LeverStop, key) -> LeverStop:
        """The lever at (frequency factor, zeta): E_GPa times the factor's square (module docstring)."""
        f, z = key
        if key == (1.0, float(task.damping_ratio or 0.0)):
            return task
        return dataclasses.replace(task, E_GPa=task.E_GPa * f * f, damping_ratio=z)


# The box as a scene's solver settings, declared once for every solver that takes a box (`takes_box`)
BOX_SETTINGS = tuple(inspect.Parameter(name, inspect.Parameter.KEYWORD_ONLY, default=default, annotation=annotation)
                     for name, default, annotation in (
                         ("box_frequency_low", 1.0, Annotated[float, Interval(gt=0, le=10)]),
                         ("box_frequency_high", 1.0, Annotated[float, Interval(gt=0, le=10)]),
                         ("box_zeta_low", 0.0, Annotated[float, Interval(ge=0, le=1)]),
                         ("box_zeta_high", 0.0, Annotated[float, Interval(ge=0, le=1)]),
                         ("box_speed_margin", 0.0, Annotated[float, Interval(ge=0, le=1)]),
                         ("box_grid", 3, Annotated[int, Interval(ge=2, le=50)])))


def box_of(box_frequency_low=1.0, box_frequency_high=1.0, box_zeta_low=0.0, box_zeta_high=0.0,
           box_speed_margin=0.0, box_grid=3) -> LeverBox:
    """The LeverBox of the flat settings (both zeta bounds 0: the task's own damping ratio);
    out-of-range or reversed bounds are a SettingError naming the key."""
    zeta = None if box_zeta_low == box_zeta_high == 0.0 else (box_zeta_low, box_zeta_high)
    return LeverBox((box_frequency_low, box_frequency_high), zeta, box_speed_margin, box_grid)


def takes_box(solver):
    """`solver(task, *, ..., box: LeverBox | None = None)` as a solver a scene names: its signature
    shows the box's flat settings (BOX_SETTINGS: box_frequency_low ... box_grid, checked by the
    scene loader and listed by `mechopt describe`) in place of `box`; a Python caller gives either
    those or `box=`, and bad box input is refused before any work."""
    signature = inspect.signature(solver)
    kept = [p for p in signature.parameters.values() if p.name != "box"]

    @functools.wraps(solver)
    def with_box(task, *args, box=None, **settings):
        flat = {p.name: settings.pop(p.name) for p in BOX_SETTINGS if p.name in settings}
        if box is not None and flat:
            key = next(iter(flat))
            raise SettingError(f"{key}={flat[key]!r} with box=...: give the box or its settings", key=key)
        return solver(task, *args, box=box_of(**flat) if box is None else box, **settings)
    with_box.__signature__ = signature.replace(parameters=kept + list(BOX_SETTINGS))
    return with_box
