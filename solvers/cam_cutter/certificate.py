"""Is a linkage the global minimax over its box? A lower bound on the deviation over every (H, L)
of the box, by branch and bound on a Lipschitz bound, and the starts a multistart takes from it.

Lipschitz bound (from eq. (10)): moving the links by (dH, dL) moves the limaçon's point at crank
parameter s by dL (cos s - 1, sin s) + dH/2 (cos 2s - 1, sin 2s), whose largest length over a
cell is `lipschitz_radius`. Every point of the curve moves that far at most, so a node's
distance to the closed curve changes no more. Over a cell of half-widths
(hH, hL) the largest node distance is then at least its value at the centre less that radius;
and the largest over any set of the path's points bounds the largest over the whole path.

The distance at a centre is `foot_points`' (nearest of ROUND_VERTICES polyline vertices, refined
by Newton): the bound takes it as exact (tests check it against 2^16 vertices).
"""
import heapq
import math

import numpy as np

from mechopt.solvers.cam_cutter.deviation import foot_points
from mechopt.solvers.cam_cutter.problem import ROUND_VERTICES

__all__ = ["lipschitz_radius", "largest_distance", "grid_starts", "box_lower_bound"]


def lipschitz_radius(hH, hL):
    """The farthest any point of the limaçon (10) moves when H and L move by at most hH and hL [mm].
    With u = s/2 the move dL (cos s - 1, sin s) + dH/2 (cos 2s - 1, sin 2s) has squared length
    4 sin^2 u (dL^2 + (dH^2 + 2 dL dH) cos^2 u), largest at dL dH >= 0; as a function of
    x = cos^2 u it is a parabola whose top is at x = (k - hL^2) / 2k, k = hH^2 + 2 hL hH."""
    k = hH * hH + 2.0 * hL * hH
    x = min(max((k - hL * hL) / (2.0 * k), 0.0), 1.0) if k > 0 else 0.0
    return 2.0 * math.sqrt((1.0 - x) * (hL * hL + k * x))


def largest_distance(px, py, H, L):
    """The largest distance [mm] from the points (px, py) to the limaçon (H, L)."""
    return float(foot_points(px, py, H, L, vertices=ROUND_VERTICES)[0].max())


def _grid(box, grid):
    """Centres (H, L) of a grid x grid cells over the box, and the cells' half-widths."""
    (H_lo, H_hi, L_lo, L_hi), (nH, nL) = box, grid
    hH, hL = (H_hi - H_lo) / (2 * nH), (L_hi - L_lo) / (2 * nL)
    H = np.linspace(H_lo + hH, H_hi - hH, nH)
    L = np.linspace(L_lo + hL, L_hi - hL, nL)
    return H, L, hH, hL


def grid_starts(px, py, box, *, grid=(16, 8), count=4):
    """Up to `count` starts (H, L) [mm] for a multistart: the grid cells' centres whose largest node
    distance is below their eight neighbours', best first."""
    H, L, _, _ = _grid(box, grid)
    value = np.array([[largest_distance(px, py, h, l) for l in L] for h in H])
    padded = np.pad(value, 1, constant_values=np.inf)
    lowest = np.ones(value.shape, dtype=bool)
    for di in (-1, 0, 1):
        for dj in (-1, 0, 1):
            if di or dj:
                lowest &= value <= padded[1 + di:1 + di + value.shape[0], 1 + dj:1 + dj + value.shape[1]]
    i, j = np.nonzero(lowest)
    order = np.argsort(value[i, j])[:count]
    return [(float(H[a]), float(L[b])) for a, b in zip(i[order], j[order])]


def box_lower_bound(px, py, box, upper, *, gap, max_cells=20_000, grid=(16, 8)):
    """A lower bound [mm] on the largest distance from the points (px, py) to the limaçon, over
    every (H, L) in box = (H_lo, H_hi, L_lo, L_hi): cells of a grid split in four (best bound
    first) until every cell's bound is within `gap` of `upper` (an achieved deviation) or
    `max_cells` centres have been measured. Returns (lower bound, cells measured, complete)."""
    H, L, hH, hL = _grid(box, grid)
    radius = lipschitz_radius(hH, hL)
    cells = [(largest_distance(px, py, h, l) - radius, float(h), float(l), hH, hL) for h in H for l in L]
    heapq.heapify(cells)
    measured = len(cells)
    while cells[0][0] < upper - gap and measured < max_cells:
        bound, h, l, hH, hL = heapq.heappop(cells)
        radius = lipschitz_radius(hH / 2, hL / 2)
        for dh in (-hH / 2, hH / 2):
            for dl in (-hL / 2, hL / 2):
                child = max(bound, largest_distance(px, py, h + dh, l + dl) - radius)
                heapq.heappush(cells, (child, h + dh, l + dl, hH / 2, hL / 2))
        measured += 4
    return float(cells[0][0]), measured, bool(cells[0][0] >= upper - gap)
