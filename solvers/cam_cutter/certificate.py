"""Is a linkage the global minimax over its box? A lower bound on the largest node distance over
every (H, L) of the box, by branch and bound on cells of (H, L), and the starts a multistart takes.

A cell's bound is the largest of these lower bounds on max_i distance(P_i, limaçon(H, L)) over
the cell, each from `bound.cell_bounds` (one call for every (cell, node) pair of a level):

* a node's constant bound (zero order; or its first-order bound at its worst corner);
* a mixed one, the dual of a small linear program: for weights w >= 0 summing to 1,
  max_i d_i >= sum_i w_i d_i >= sum_i w_i lb_i, with lb_i a node's first-order bound (the least
  of its runs' affine bounds d0 + g . (dH, dL) - E: concave), so the sum is concave in (dH, dL)
  and least at one of the cell's corners. The weights tried (`_dual`) are the vertices of the
  dual's simplex over KEEP + REACH nodes: KEEP of different gradient directions, each the highest
  at the cell's centre in its direction (`_diverse`), and the REACH highest at a corner: each node
  alone, pairs that cancel one gradient component, triples that cancel both. On the scenes' cells
  about their optima this is the linear program's optimum over every node (the test compares).
  Near the answer, whose active nodes' gradients cancel, it loses only second-order terms.

The costly bounds are taken only where they can close a cell: the first-order bound in cells the
zero-order one left open, the tangent-segment bound in those a node's worst corner leaves open too
(`_measure`, `bound.cell_bounds`). The first grid is measured on every
SCREEN-th node and split without a recheck (a coarse cell seldom closes on the rest); a cell's
children are measured on its KEEP + REACH nodes first, and those still below the target on every
node: any subset of the nodes gives a lower bound, and a child's bound is at least its parent's.
A level of few children (DIRECT_PAIRS) is measured on every node at once: a measuring call costs
a fixed ~1 ms of numpy calls, as much as some 300 (cell, node) pairs. Cells are split level by
level (all of a level in one call) until every cell's bound is within `gap` of `upper` (an
achieved deviation: the early stop) or `max_cells` cells have been measured.

Every node can bind: a node's distance varies over a cell by up to its first-order move
|gH| hH + |gL| hL, which at the certificate's finest cells (~0.05 mm about the cardioid's optimum)
is of the order of the deviation itself, so an upper bound d0 + that move is below the cell's
lower bound for only 4-6 of 27 nodes even at the last level (and d0 + r for none): a node set
pruned per cell would save little.

Warm start (`box_lower_bound(start=...)`, `warm_cells`): the leaves of an earlier certificate
meeting this box (and grid cells for any part of the box they miss), each bound lowered by how far
the nodes moved. That is a bound: the distance to a curve is 1-Lipschitz in the point, so if every
earlier node P_j has a node P_i' of this set within m, then for every linkage
max_i d(P_i') >= max_j d(P_j) - m (`moved_bound`). Only leaves below the target are measured again;
leaves finer than the move give way to unmeasured cells as wide (`warm_cells(finest=...)`).
"""
import functools
from dataclasses import dataclass

import numpy as np

from mechopt.solvers.cam_cutter.bound import cell_bounds, lipschitz_radius
from mechopt.solvers.cam_cutter.deviation import foot_points
from mechopt.solvers.cam_cutter.problem import ROUND_VERTICES

__all__ = ["lipschitz_radius", "largest_distance", "grid_starts", "box_lower_bound", "Cells",
           "Bound", "moved_bound", "warm_cells"]

KEEP = 5                # nodes a cell's bound mixes, and its children are first measured on
SECTORS = 8             # gradient directions `_diverse` picks nodes from (SECTORS + 1 >= KEEP)
REACH = 3               # and the nodes highest at a corner (the dual mixes both)
SCREEN = 4              # the first cells are screened on every SCREEN-th node
GRID = (20, 20)         # the first cells over (H, L): 20 x 10 took as long on the cardioid scene, 1.3-1.4x on the others
DIRECT_PAIRS = 500      # children x nodes up to which a level is measured on every node in one call


@dataclass(frozen=True)
class Cells:
    """Cells of (H, L) [mm]: centres, half-widths and lower bounds [mm], one entry a cell."""
    H: np.ndarray
    L: np.ndarray
    hH: np.ndarray
    hL: np.ndarray
    bound: np.ndarray

    def take(self, which) -> "Cells":
        return Cells(*(v[which] for v in (self.H, self.L, self.hH, self.hL, self.bound)))


@dataclass(frozen=True)
class Bound:
    """`box_lower_bound`'s answer: the lower bound [mm], cells measured, whether every cell reached
    the target, whether it started from an earlier certificate's leaves, and the leaves."""
    lower: float
    cells: int
    complete: bool
    warm_started: bool
    leaves: Cells


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


def moved_bound(cells: Cells, moved) -> Cells:
    """Cells whose bounds hold for nodes moved by at most `moved` [mm]: each bound less `moved`."""
    return Cells(cells.H, cells.L, cells.hH, cells.hL, cells.bound - moved)


@functools.cache
def _pairings(k):
    """Index arrays of the node pairs and triples of k nodes."""
    pairs = np.array([(i, j) for i in range(k) for j in range(i + 1, k)], dtype=int).reshape(-1, 2)
    triples = np.array([(i, j, l) for i in range(k) for j in range(i + 1, k) for l in range(j + 1, k)],
                       dtype=int).reshape(-1, 3)
    return pairs, triples


def _dual(gH, gL, corner):
    """The best of the dual's mixtures w (on the simplex over each cell's K nodes) at which
    min over the cell of max_i (a_i + g_i . d) can be largest: each node alone, each pair mixed to
    cancel one gradient component, each triple mixed to cancel both; each valued at its least
    corner, min_k sum_i w_i corner[i, k] (`corner`: cell, node, corner [mm]). Per cell [mm]."""
    count, k = gH.shape
    pairs, triples = _pairings(k)
    best = corner.min(axis=-1).max(axis=1)                       # each node alone
    ci, cj = corner[:, pairs[:, 0]], corner[:, pairs[:, 1]]
    for g in (gH, gL):                    # pairs: t g_i + (1 - t) g_j = 0 in one component
        gi, gj = g[:, pairs[:, 0]], g[:, pairs[:, 1]]
        t = np.clip(np.divide(gj, gj - gi, out=np.zeros_like(gi), where=np.abs(gj - gi) > 1e-300), 0.0, 1.0)
        best = np.maximum(best, (t[..., None] * ci + (1.0 - t[..., None]) * cj).min(axis=-1).max(axis=1))
    if len(triples):                      # triples: sum w = 1, sum w gH = 0, sum w gL = 0 (Cramer)
        hi, hj, hl = (gH[:, triples[:, m]] for m in range(3))
        li, lj, ll = (gL[:, triples[:, m]] for m in range(3))
        w = np.stack([hj * ll - hl * lj, hl * li - hi * ll, hi * lj - hj * li], axis=-1)
        total = w.sum(axis=-1)
        ok = np.abs(total) > 1e-12 * (np.abs(w).sum(axis=-1) + 1e-300)
        w = np.clip(w / np.where(ok, total, 1.0)[..., None], 0.0, None)
        w = np.where(ok[..., None], w, 1.0)
        w /= w.sum(axis=-1, keepdims=True)             # on the simplex whatever the rounding: a bound
        mixed = sum(w[..., m, None] * corner[:, triples[:, m]] for m in range(3))
        best = np.maximum(best, mixed.min(axis=-1).max(axis=1))
    return best


CORNERS = np.array([(-1, -1), (-1, 1), (1, -1), (1, 1)], dtype=float)


def warm_cells(leaves: Cells, moved, box, grid=GRID, finest=0.0) -> Cells:
    """The start of a warm certificate over `box`: the earlier `leaves` that meet the box, each
    bound less `moved` [mm] (`moved_bound`), and the grid cells of the box that the leaves' box does
    not hold, unmeasured. Leaves narrower than `finest` [mm] (the fine ones about the earlier
    answer, which a move of the path makes stale) give way to the unmeasured cells `finest` wide
    of a lattice that meet them, so the partition is reused down to the scale the move leaves valid.
    Together they cover the box (cells may overlap: a point's bound is the least of its cells'
    either way)."""
    H_lo, H_hi, L_lo, L_hi = box
    meet = ((leaves.H + leaves.hH > H_lo) & (leaves.H - leaves.hH < H_hi)
            & (leaves.L + leaves.hL > L_lo) & (leaves.L - leaves.hL < L_hi))
    old = ((leaves.H - leaves.hH).min(), (leaves.H + leaves.hH).max(), (leaves.L - leaves.hL).min(),
           (leaves.L + leaves.hL).max())
    H, L, hH, hL = _grid(box, grid)
    HH, LL = np.meshgrid(H, L, indexing="ij")
    outside = ((HH - hH < old[0]) | (HH + hH > old[1]) | (LL - hL < old[2]) | (LL + hL > old[3])).ravel()
    fresh = Cells(HH.ravel()[outside], LL.ravel()[outside], np.full(outside.sum(), hH), np.full(outside.sum(), hL),
                  np.full(outside.sum(), -np.inf))
    kept = leaves.take(meet)
    small = np.maximum(kept.hH, kept.hL) < finest
    if small.any():
        fine = kept.take(small)
        # a lattice of cells `finest` wide (the leaves' aspect), those meeting a fine leaf: every
        # lattice index from a leaf's lowest to its highest, a side, so they cover every fine leaf
        aspect = np.array([fine.hH[0], fine.hL[0]]) / max(fine.hH[0], fine.hL[0])
        width = 2 * finest * aspect
        origin = np.array([(fine.H - fine.hH).min(), (fine.L - fine.hL).min()])
        index = [np.floor((np.stack([c - h, c + h]) - o) / w).astype(int)            # (lo, hi) a leaf
                 for c, h, o, w in ((fine.H, fine.hH, origin[0], width[0]), (fine.L, fine.hL, origin[1], width[1]))]
        steps = [range(int((i[1] - i[0]).max()) + 1) for i in index]
        ij = np.unique(np.concatenate([np.column_stack([np.minimum(index[0][0] + a, index[0][1]),
                                                        np.minimum(index[1][0] + b, index[1][1])])
                                       for a in steps[0] for b in steps[1]]), axis=0)
        centre = origin + (ij + 0.5) * width
        fresh = _joined(fresh, Cells(centre[:, 0], centre[:, 1], np.full(len(ij), width[0] / 2),
                                     np.full(len(ij), width[1] / 2), np.full(len(ij), -np.inf)))
        kept = kept.take(~small)
    return _joined(moved_bound(kept, moved), fresh)


def _diverse(value, gH, gL):
    """Per row, KEEP node columns: the highest `value` of each of SECTORS gradient directions (and
    of the nodes with no gradient), highest first, then the highest of the rest by value (repeats
    harmless). The mixed bound needs nodes whose gradients can cancel: the highest alone often
    crowd one peak of the path."""
    sector = np.where((gH == 0) & (gL == 0), SECTORS,
                      ((np.arctan2(gL, gH) + np.pi) * (SECTORS / (2 * np.pi))).astype(int) % SECTORS)
    best = np.where(sector[..., None] == np.arange(SECTORS + 1), value[..., None], -np.inf).argmax(axis=1)
    filled = np.take_along_axis(sector, best, axis=1) == np.arange(SECTORS + 1)     # the sector has a node
    best_value = np.where(filled, np.take_along_axis(value, best, axis=1), -np.inf)
    chosen = np.take_along_axis(best, np.argsort(best_value, axis=1)[:, ::-1], axis=1)[:, :KEEP]
    by_value = np.argsort(value, axis=1)[:, ::-1]
    by_value = by_value[:, np.arange(KEEP) % by_value.shape[1]]          # fewer nodes than KEEP: repeats
    return np.where(np.arange(KEEP) < filled.sum(axis=1)[:, None], chosen, by_value)


def _measure(px, py, cells: Cells, nodes, target=np.inf):
    """Bounds [mm] of `cells` measured on the node indices `nodes` (a row a cell), and each cell's
    most promising nodes (`_diverse`). The bound: for any weights w on the simplex,
    max_i d_i >= sum_i w_i d_i >= sum_i w_i lb_i, lb_i a node's first-order bound (the least of its
    runs' affine bounds: concave in (dH, dL)), so the sum is concave and least at a corner; the
    largest over `_dual` of that least corner (the linear program's dual). The costlier bounds
    (first order; the tangent-segment bound of the pairs with no first-order one) are taken only in
    the cells the cheaper ones leave below `target` (any bound of a node is a bound)."""
    count, width = nodes.shape
    pairs = (px[nodes.ravel()], py[nodes.ravel()], *(np.repeat(v, width) for v in (cells.H, cells.L, cells.hH, cells.hL)))
    zero, d0, gH, gL, E, first = cell_bounds(*pairs, width=width, target=target)
    bound = np.maximum(cells.bound, zero.reshape(count, width).max(axis=1))
    pick = np.zeros((count, KEEP + REACH), dtype=int)               # a closed cell's: never used
    rows = np.flatnonzero(bound < target)
    if rows.size:
        part = (rows[:, None] * width + np.arange(width)).ravel()
        bound[rows], pick[rows] = _combined(cells.take(rows), *(v[part] for v in (zero, d0, gH, gL, E, first)), width)
    return Cells(cells.H, cells.L, cells.hH, cells.hL, bound), np.take_along_axis(nodes, pick, axis=1)


def _combined(cells: Cells, zero, d0, gH, gL, E, first, width):
    """`_measure`'s bound of each cell from its pairs' bounds (`bound.cell_bounds`, `width` pairs a
    cell), and the columns of the nodes its children are screened on: the dual's (`_diverse` by
    the bound at the centre, the corners' mean, and the REACH highest at a corner)."""
    count = cells.H.size
    dH, dL = CORNERS[:, 0] * np.repeat(cells.hH, width)[:, None], CORNERS[:, 1] * np.repeat(cells.hL, width)[:, None]
    corner = ((d0 - E)[:, None, :] + gH[:, None, :] * dH[..., None] + gL[:, None, :] * dL[..., None]).min(axis=-1)
    corner = np.where(first[:, None], np.maximum(corner, zero[:, None]), zero[:, None]).reshape(count, width, 4)
    gH, gL = (np.where(first, g[:, 0], 0.0).reshape(count, width) for g in (gH, gL))
    pick = np.hstack([_diverse(corner.mean(axis=-1), gH, gL), np.argsort(corner.max(axis=-1), axis=1)[:, np.arange(-REACH, 0) % width]])
    dual = _dual(*(np.take_along_axis(g, pick, axis=1) for g in (gH, gL)), np.take_along_axis(corner, pick[..., None], axis=1))
    return np.maximum(np.maximum(cells.bound, zero.reshape(count, width).max(axis=1)), dual), pick


def _screened(px, py, cells: Cells, nodes, target, *, recheck=True):
    """`_measure` on the node indices `nodes` (a row a cell), then (with `recheck`) the cells still
    below the target on every node: a few nodes close most cells."""
    cells, top = _measure(px, py, cells, nodes, target)
    still = cells.bound < target
    if recheck and still.any():
        again, top[still] = _measure(px, py, cells.take(still), np.tile(np.arange(px.size), (int(still.sum()), 1)),
                                     target)
        cells.bound[still] = again.bound
    return cells, top


def _joined(a: Cells, b: Cells) -> Cells:
    return Cells(*(np.concatenate([u, v]) for u, v in zip(
        (a.H, a.L, a.hH, a.hL, a.bound), (b.H, b.L, b.hH, b.hL, b.bound))))


def _split(cells: Cells) -> Cells:
    """Each cell's four children, in order (the first cell's four first), bound the parent's."""
    hH, hL = cells.hH / 2, cells.hL / 2
    sign = np.array([(-1, -1), (-1, 1), (1, -1), (1, 1)])
    return Cells((cells.H[:, None] + sign[:, 0] * hH[:, None]).ravel(),
                 (cells.L[:, None] + sign[:, 1] * hL[:, None]).ravel(),
                 np.repeat(hH, 4), np.repeat(hL, 4), np.repeat(cells.bound, 4))


def box_lower_bound(px, py, box, upper, *, gap, max_cells=20_000, grid=GRID, start: Cells | None = None) -> Bound:
    """A lower bound [mm] on the largest distance from the points (px, py) to the limaçon, over
    every (H, L) in box = (H_lo, H_hi, L_lo, L_hi): the cells of a grid (or `start`, an earlier
    certificate's leaves covering the box, `moved_bound`), split in four level by level until every
    cell's bound is within `gap` of `upper` (an achieved deviation) or `max_cells` cells have been
    measured (the lowest split first when the room is short)."""
    px, py = np.ravel(px).astype(float), np.ravel(py).astype(float)
    target, warm = upper - gap, start is not None
    if start is None:
        H, L, hH, hL = _grid(box, grid)
        HH, LL = np.meshgrid(H, L, indexing="ij")
        start = Cells(HH.ravel(), LL.ravel(), np.full(HH.size, hH), np.full(HH.size, hL), np.full(HH.size, -np.inf))
    low = start.bound < target               # the first cells (a grid, or earlier leaves below the target)
    # the first grid on every SCREEN-th node, split without a recheck: a coarse cell seldom closes
    # on the rest, and its children are screened on its best nodes, then rechecked
    fresh, top = _screened(px, py, start.take(low), np.tile(np.arange(0, px.size, SCREEN), (int(low.sum()), 1)),
                           target, recheck=warm)
    cells = _joined(start.take(~low), fresh)
    top = np.vstack([np.zeros((int((~low).sum()), KEEP + REACH), dtype=int), top])     # closed cells: never split
    measured = int(low.sum())
    while True:
        open_ = np.flatnonzero(cells.bound < target)
        room = (max_cells - measured) // 4
        if open_.size == 0 or room <= 0:      # the first grid alone may exceed max_cells
            break
        open_ = open_[np.argsort(cells.bound[open_], kind="stable")[:room]]   # the lowest first when short
        children = _split(cells.take(open_))
        if children.H.size * px.size <= DIRECT_PAIRS:      # few: every node at once, one call
            children, child_top = _measure(px, py, children, np.tile(np.arange(px.size), (children.H.size, 1)), target)
        else:
            children, child_top = _screened(px, py, children, np.repeat(top[open_], 4, axis=0), target)
        keep = np.ones(cells.H.size, dtype=bool)
        keep[open_] = False
        cells, top = _joined(cells.take(keep), children), np.vstack([top[keep], child_top])
        measured += children.H.size
    lower = float(cells.bound.min())
    return Bound(lower, measured, bool(lower >= target), warm, cells)
