"""The torch-guiding linkage (paper 000): fit H, L to the ideal path, check a given linkage.

`fit` holds the solvers a scene names (`cam_cutter.minimax`, ...); `deviation` measures how far
a limaçon is from the ideal path.
"""
from mechopt.solvers.cam_cutter.fit import check, evolve, grid_scan, minimax, robust

__all__ = ["grid_scan", "minimax", "robust", "evolve", "check"]
