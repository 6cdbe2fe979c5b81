"""The torch-guiding linkage (paper 000): fit H, L to the ideal path, check a given linkage.

`fit` holds the solvers a scene names (`cam_cutter.minimax`, ...); `deviation` measures how far
a limaçon is from the ideal path; `kinetostatics.joint_loads` the reactions and driving torque
over the cycle (Sec. V re-derived); `family.readjustable` one H for a family of cams (Sec. VII).
`minimax` also takes a cam of any shape (`models.cam_profile.ProfileFit`), globally over its box
(`certificate`: the multistart's starts and the lower bound); `problem` is the minimax problem
`fit` and `family` share. `fit_linkage(task, method=...)` is the one door to the four
ways of finding the linkage, as `scipy.integrate.solve_ivp` has one for its methods.
"""
from typing import Literal

from mechopt.solvers.cam_cutter.family import evolve_family, readjustable
from mechopt.solvers.cam_cutter.fit import check, evolve, grid_scan, minimax, robust
from mechopt.solvers.cam_cutter.kinetostatics import joint_loads

__all__ = ["grid_scan", "minimax", "robust", "evolve", "check", "joint_loads", "readjustable", "evolve_family",
           "fit_linkage", "METHODS"]

METHODS = {"grid_scan": grid_scan, "minimax": minimax, "robust": robust, "evolve": evolve}
Method = Literal["grid_scan", "minimax", "robust", "evolve"]


def fit_linkage(task, *, method: Method = "minimax", **options):
    """Link lengths H, L [mm] that keep the limaçon within the band of the offset cardioid, by one
    of `METHODS`: "grid_scan" (the paper's), "minimax" (exact NLP), "robust" (the lattice point
    whose neighbours stay best), "evolve" (scipy's differential evolution, the peer); with that
    method's keyword options. Returns its Result."""
    from mechopt.kit.settings import check_settings
    check_settings(fit_linkage, method=method)       # SettingError: method='x': allowed grid_scan, ...
    return METHODS[method](task, **options)
