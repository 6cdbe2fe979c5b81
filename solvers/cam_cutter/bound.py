"""Lower bounds on a node's distance to the limaçon (10) over a cell of link lengths (H, L) [mm],
for many (cell, node) pairs at once: the certificate's bound (`certificate.box_lower_bound`).

Eq. (10) is linear in the links: R(s; H, L) = L a(s) + H b(s), a = (cos s - 1, sin s),
b = (cos 2s - 1, sin 2s) / 2, with |a'| = |b'| = |a''| = |a'''| = 1, |b''| = 2, |b'''| = 4. On a
cell of centre (H, L) and half-widths (hH, hL), with Q(s) = R(s; H, L) and the move
m(s) = dL a(s) + dH b(s) to R(s; H + dH, L + dL), |dH| <= hH, |dL| <= hL:

    |Q'| <= |L| + |H| =: V,  |Q''| <= |L| + 2|H| =: M,  |Q'''| <= |L| + 4|H| =: M3,
    |m| <= r (`lipschitz_radius`),  |m'| <= hL + hH,  |m''| <= hL + 2 hH.

Zero order (a polyline of N vertices s_j = 2 pi j / N). Every s is within pi/N of a vertex, so
|P - Q(s)| >= |P - Q_j| - V pi / N =: lb_j, and |P - R(s; cell point)| >= min_j lb_j - r.

First order (Cauchy-Schwarz |X| >= |e . X| for a unit e, and Taylor in s with its remainder).
Take any s0 (the vertex nearest P, refined by Newton on the foot condition; any s0 gives a bound,
a good one a tight bound), d0 = |P - Q(s0)|, the unit vectors u = (P - Q(s0)) / d0 and n, u turned
a right angle, eps_u = |u . Q'(s0)| (~0 at a foot point), v = |n . Q'(s0)| = sqrt(|Q'(s0)|^2 - eps_u^2),
the signed bend q = u . Q''(s0) (negative where the curve bends away from P), and the move's own
parts at s0, k = |u . a'(s0)| hL + |u . b'(s0)| hH >= |u . m'(s0)| and
rt = |n . a(s0)| hL + |n . b(s0)| hH >= |n . m(s0)|. For X(s) = P - Q(s) - m(s), t = s - s0
(n . (P - Q(s0)) = 0; a rounding residue eps_t is allowed for):
u . (Q(s) - Q(s0)) <= eps_u |t| + q t^2/2 + M3 |t|^3/6, u . (m(s) - m(s0)) <= k |t| + (hL + 2 hH) t^2/2,
|n . (Q(s) - Q(s0))| >= v |t| - M t^2/2 and |n . m(s)| <= rt + (hL + hH) |t|:

    A:  u . X >= D - (eps_u + k) |t| - (q + hL + 2 hH) t^2/2 - M3 |t|^3/6,
        D = d0 + g . (dH, dL), g = -(u . b(s0), u . a(s0)) (u . m(s0) = -g . (dH, dL));
    B:  |n . X| >= (v - hL - hH) |t| - M t^2/2 - eps_t - rt   (concave in |t|);
    C:  |X| >= lb_j - r on the arc of every vertex j.

D is at most top = d0 + |gH| hH + |gL| hL <= d0 + r. Let t0 be the least t with B(t) = top, and
sigma the farthest (plus pi/N) that a vertex with lb_j < high + 2 r (high >= the nearest vertex's
distance >= d0) lies from s0. If t0 exists and B(sigma) >= top (B concave: B >= top on [t0, sigma]),
then for |t| <= t1 = min(t0, sigma) |X| = sqrt((u . X)^2 + (n . X)^2) >= sqrt(A+^2 + B+^2),
for t1 <= |t| <= sigma B gives |X| >= top >= D, beyond sigma C gives |X| >= high + r >= top, so

    distance(P, limaçon(H + dH, L + dL)) >= d0 + g . (dH, dL) - E,

E the largest over a partition of [0, t1] of D - sqrt(A+^2 + B+^2) with A and B bounded on each
piece (`_loss`). E is second order in the cell: where the curve bends away from P (q < 0) A's loss
is at most (eps_u + k)^2 / (2 |q|); elsewhere B leaves A only |t| <~ rt / v, a loss
~ k rt / v + q rt^2 / (2 v^2), both products of the move; the zero-order bound loses r.
Where the conditions fail (two branches of the curve near P, as at the double point) the pair
keeps the zero-order bound, raised by the tangent-segment one (`tangent_bound`). Each bound is
checked against brute force over cells near and far from the optima
(tests/cam_cutter/test_cam_cutter_global.py).
"""
import numpy as np

__all__ = ["lipschitz_radius", "cell_bounds", "tangent_bound", "POLYLINE"]

POLYLINE = 128          # N: the zero-order polyline; its error V pi / N only widens the window
NEAR_ARCS = 32          # polyline arcs near a node that `_tangents` cuts finely
SUBARCS = 16            # sub-arcs an arc: M (pi / (POLYLINE SUBARCS))^2 / 2 ~ 2e-4 mm on the paper's cam
NEWTON_STEPS = 4
INTERVALS = 8           # geometric points of the partition of the first-order window (`_loss`)
UNIFORM = 16            # and uniform ones
ROUNDING = 1e-12        # relative: a margin for floating-point rounding in the bounds


def lipschitz_radius(hH, hL):
    """The farthest any point of the limaçon (10) moves when H and L move by at most hH and hL [mm]
    (arrays broadcast). With u = s/2 the move dL (cos s - 1, sin s) + dH/2 (cos 2s - 1, sin 2s) has
    squared length 4 sin^2 u (dL^2 + (dH^2 + 2 dL dH) cos^2 u), largest at dL dH >= 0; as a function
    of x = cos^2 u it is a parabola whose top is at x = (k - hL^2) / 2k, k = hH^2 + 2 hL hH."""
    hH, hL = np.asarray(hH, dtype=float), np.asarray(hL, dtype=float)
    k = hH * hH + 2.0 * hL * hH
    x = np.clip((k - hL * hL) / (2.0 * np.where(k > 0, k, 1.0)), 0.0, 1.0) * (k > 0)
    r = 2.0 * np.sqrt((1.0 - x) * (hL * hL + k * x))
    return float(r) if r.ndim == 0 else r


def _curve(s, H, L):
    """Q(s), Q'(s), Q''(s) of eq. (10) and the vectors a(s), b(s): each an (x, y) pair of arrays."""
    c, n = np.cos(s), np.sin(s)
    c2, n2 = 2 * c * c - 1, 2 * n * c
    a, b = (c - 1, n), ((c2 - 1) / 2, n2 / 2)
    q = (L * a[0] + H * b[0], L * a[1] + H * b[1])
    q1 = (-L * n - H * n2, L * c + H * c2)
    q2 = (-L * c - 2 * H * c2, -L * n - 2 * H * n2)
    return q, q1, q2, a, b


_GRID = np.linspace(0.0, 2 * np.pi, POLYLINE, endpoint=False)
_A = (np.cos(_GRID) - 1, np.sin(_GRID))
_B = ((np.cos(2 * _GRID) - 1) / 2, np.sin(2 * _GRID) / 2)
# |P - L a_j - H b_j|^2 = |P|^2 + features(P, H, L) @ _TERMS: one matrix product for every vertex
_TERMS = np.array([-2 * _A[0], -2 * _A[1], -2 * _B[0], -2 * _B[1],
                   _A[0] ** 2 + _A[1] ** 2, 2 * (_A[0] * _B[0] + _A[1] * _B[1]), _B[0] ** 2 + _B[1] ** 2])
CHUNK = 256             # pairs a block: m n k below OpenBLAS's 4 x 65536 keeps its product on one thread


def _squared(px, py, H, L):
    """|P - Q_j|^2 [mm^2] to the POLYLINE vertices, a row a pair, and its rounding allowance."""
    features = np.column_stack([L * px, L * py, H * px, H * py, L * L, L * H, H * H])
    size = px * px + py * py
    return size[:, None] + features @ _TERMS, 1e-13 * (size + 4 * (np.abs(L) + np.abs(H)) ** 2)


# vertex k's offset from vertex j on the circle, -N/2 .. N/2 - 1 (a row a j), and the offsets after
# and before j, N where on the other side (tables: one gather a call where the arithmetic took five)
_OFFSET = ((np.arange(POLYLINE) - np.arange(POLYLINE)[:, None] + POLYLINE // 2) % POLYLINE - POLYLINE // 2).astype(np.int16)
_FAR = np.int16(POLYLINE)
_AFTER, _BEFORE = np.where(_OFFSET > 0, _OFFSET, _FAR), np.where(_OFFSET <= 0, -_OFFSET, _FAR)
for _table in (_OFFSET, _AFTER, _BEFORE):
    _table.flags.writeable = False       # shared by every call and thread: read only


def _run(near, j):
    """The run of `near` vertices (a row a pair, circular) around vertex j: the mask of its members
    and sigma [rad], the farthest a member lies from j plus half a spacing; the run is the whole
    circle (sigma = inf) where every vertex is near."""
    offset = _OFFSET[j]
    right = np.where(near, _FAR, _AFTER[j]).min(axis=1)      # the first vertex not near, either side
    left = np.where(near, _FAR, _BEFORE[j]).min(axis=1)
    whole = near.all(axis=1)
    member = ((offset > -left[:, None]) & (offset < right[:, None])) | whole[:, None]
    sigma = np.where(whole, np.inf, (np.maximum(left, right) - 0.5) * (2 * np.pi / POLYLINE))
    return member, sigma


def _nearest(px, py, H, L):
    """Lower and upper bounds [mm] on each pair's distance to its nearest POLYLINE vertex
    (rounding allowed for), and the squared distances to every vertex with their rounding
    allowance (`_squared`, a row a pair)."""
    squared, tol = np.empty((px.size, POLYLINE)), np.empty(px.size)
    for k in range(0, px.size, CHUNK):
        part = slice(k, k + CHUNK)
        squared[part], tol[part] = _squared(px[part], py[part], H[part], L[part])
    least = squared.min(axis=1)
    return np.sqrt(np.maximum(least - tol, 0.0)), np.sqrt(least + tol), squared, tol


def _scan(squared, tol, high, slack):
    """The vertices nearer P than `high` (`_nearest`) plus `slack` [mm] ("near") in runs: the
    nearest's run (its vertex's s [rad] and sigma [rad], `_run`) and the nearest vertex's run of the
    rest (where there is one, else the first again); and whether the two runs hold every near vertex."""
    j = squared.argmin(axis=1)
    near = squared < ((high + slack) ** 2 + tol)[:, None]
    first, sigma1 = _run(near, j)
    rest = near & ~first
    two = rest.any(axis=1)
    j2, sigma2, covered = j.copy(), sigma1.copy(), np.ones(j.size, dtype=bool)
    if two.any():                       # near vertices outside the first run: the second run
        j2[two] = np.where(rest[two], squared[two], np.inf).argmin(axis=1)
        second, sigma2[two] = _run(near[two], j2[two])
        covered[two] = ~(rest[two] & ~second).any(axis=1)
    return (_GRID[j], sigma1), (_GRID[j2], sigma2), covered


def _tangents(px, py, H, L, reach, spacing, squared, tol):
    """A lower bound [mm] on the distance from P to the limaçon where the first-order bound does
    not apply (several branches near P): every polyline vertex farther than `reach` [mm] bounds its
    arc's points at reach less the spacing error V pi / N [mm]; the arcs of the
    nearer ones (at most NEAR_ARCS, else the bound is -inf) are cut in SUBARCS, and the distance to
    each sub-arc is at least that to its centre's tangent segment Q_k + Q'_k t, |t| <= pi/(N SUBARCS),
    less M (pi/(N SUBARCS))^2 / 2, the farthest the arc strays from it (Taylor: |Q''| <= M).
    `squared`, `tol`: the squared distances to the vertices and their allowance (`_nearest`)."""
    half = np.pi / (POLYLINE * SUBARCS)
    near = squared < (reach * reach + tol)[:, None]
    count = near.sum(axis=1)
    near &= (count <= NEAR_ARCS)[:, None]                 # more near arcs: no bound (-inf)
    out = np.where(count == 0, reach - spacing, -np.inf)
    pair, vertex = np.nonzero(near)                      # the near arcs, pair by pair
    if pair.size == 0:
        return out
    # cos and sin of s_j + offset by the sum formulas: a product where np.cos would cost 20x
    cj, nj = _COS[vertex][:, None], _SIN[vertex][:, None]
    c, n = cj * _SUB_COS - nj * _SUB_SIN, nj * _SUB_COS + cj * _SUB_SIN
    Hp, Lp = H[pair, None], L[pair, None]
    c2, n2 = 2 * c * c - 1, 2 * n * c
    x, y = Lp * (c - 1) + Hp * (c2 - 1) / 2, n * (Lp + Hp * c)
    vx, vy = -Lp * n - Hp * n2, Lp * c + Hp * c2
    wx, wy = px[pair, None] - x, py[pair, None] - y
    t = np.clip((wx * vx + wy * vy) / np.maximum(vx * vx + vy * vy, 1e-300), -half, half)
    gap = (np.hypot(wx - t * vx, wy - t * vy) - (np.abs(L[pair]) + 2 * np.abs(H[pair]))[:, None] * half * half / 2).min(axis=1)
    first = np.flatnonzero(np.r_[True, pair[1:] != pair[:-1]])      # each pair's first arc
    has = pair[first]
    out[has] = np.minimum(np.minimum.reduceat(gap, first), reach[has] - spacing[has])
    return out


_SUB_OFFSET = (2 * np.arange(SUBARCS) + 1 - SUBARCS) * np.pi / (POLYLINE * SUBARCS)   # sub-arc centres from s_j
_SUB_COS, _SUB_SIN = np.cos(_SUB_OFFSET), np.sin(_SUB_OFFSET)
_COS, _SIN = np.cos(_GRID), np.sin(_GRID)
for _table in (_SUB_COS, _SUB_SIN, _COS, _SIN):
    _table.flags.writeable = False


def _foot(px, py, H, L, s):
    """Newton on the foot condition (Q - P) . Q' = 0 from s, each step at most 2 pi / POLYLINE."""
    step_max = 2 * np.pi / POLYLINE
    for _ in range(NEWTON_STEPS):
        (x, y), (vx, vy), (ax, ay), _, _ = _curve(s, H, L)
        ex, ey = x - px, y - py
        slope = vx * vx + vy * vy + ex * ax + ey * ay
        s = s + np.clip(-(ex * vx + ey * vy) / np.where(slope > 0, slope, np.inf), -step_max, step_max)
    return s


def _loss(top, slope, quad, M3, speed, M, offset, t1):
    """E [mm]: over |t| <= t1, |X| >= sqrt(A+^2 + B+^2) >= D - E for every D = d0 + g . (dH, dL) <= top,
    with A = D - l(t), l(t) = slope |t| + quad t^2/2 + M3 |t|^3/6 (quad signed: a curve bending
    away from P gains), and B = speed |t| - M t^2/2 - offset (concave). On [t_k, t_k+1] of a
    partition of [0, t1] (0, geometric points t1 2^-k down from t1/2, and t1 j/UNIFORM)
    A >= D - alpha, alpha = slope t_k+1 + max(quad t_k^2, quad t_k+1^2)/2 + M3 t_k+1^3/6 (each term
    bounded on its own), and B >= beta, the lesser of B at the ends (concave), so
    |X| >= D - alpha + sqrt((D - alpha)^2 + beta^2) - (D - alpha), a gain that falls as D rises:
    it is taken at D = top (or |X| >= beta where D < alpha). The first interval starts at 0, where
    beta = 0 and alpha >= 0: E >= 0."""
    t = t1[:, None] * _FRACTIONS
    lo, hi = t[:, :-1], t[:, 1:]
    hi2 = hi * hi
    alpha = hi * (slope[:, None] + M3[:, None] * hi2 / 6) + np.maximum(quad[:, None] * (lo * lo), quad[:, None] * hi2) / 2
    B = t * (speed[:, None] - M[:, None] * t / 2) - offset[:, None]
    beta = np.maximum(np.minimum(B[:, :-1], B[:, 1:]), 0.0)
    x = np.maximum(top[:, None] - alpha, 0.0)
    return (alpha + x - np.sqrt(x * x + beta * beta)).max(axis=1)


_FRACTIONS = np.unique(np.r_[0.0, 2.0 ** -np.arange(INTERVALS, 0, -1), np.linspace(0.0, 1.0, UNIFORM + 1)])


def cell_bounds(px, py, H, L, hH, hL, *, fine=True, width=None, target=np.inf):
    """Bounds on the distance [mm] from nodes (px, py) to the limaçon over cells of centre (H, L)
    and half-widths (hH, hL), one (cell, node) pair an element (arrays of one shape; see the module
    docstring). Returns (zero, d0, gH, gL, E, first): `zero` a constant bound over the cell; where
    `first`, the distance at (H + dH, L + dL) is at least min_b (d0 + gH dH + gL dL - E)[b] over the
    two runs b of arcs near the node (the last axis; one run is given twice). `zero` is at least
    that bound's worst corner and, with `fine`, where not `first`, `tangent_bound` (computed here
    from the same squared vertex distances). Given `width` (the pairs come `width` a cell, cell by
    cell), a cell whose zero-order bound on one of its nodes reaches `target` [mm] is closed: its
    pairs keep that bound alone (`first` False, no tangent-segment bound); and one that a node's
    worst corner closes takes no tangent-segment bound."""
    px, py, H, L, hH, hL = (np.ravel(v).astype(float) for v in np.broadcast_arrays(px, py, H, L, hH, hL))
    r = lipschitz_radius(hH, hL)
    V, M = np.abs(L) + np.abs(H), np.abs(L) + 2 * np.abs(H)
    margin = ROUNDING * (1.0 + V)
    spacing = V * np.pi / POLYLINE
    low, high, squared, tol = _nearest(px, py, H, L)
    zero = low - spacing - r - margin
    d0, gH, gL, E = (np.zeros((px.size, 2)) for _ in range(4))
    ok, covered = np.zeros((px.size, 2), dtype=bool), np.zeros(px.size, dtype=bool)
    wanted = np.ones(px.size, dtype=bool) if width is None else \
        np.repeat(zero.reshape(-1, width).max(axis=1) < target, width)      # cells still open
    one = np.flatnonzero(wanted)
    if one.size == 0:                     # every cell closed by the zero-order bound
        return zero, d0, gH, gL, E, covered
    runs = _scan(squared[one], tol[one], high[one], (2 * r + spacing)[one])
    covered[one] = runs[2]
    # both runs' branches in one call: the first run of every wanted pair, the second where there
    # is one (else the first stands for both)
    two = runs[1][0] != runs[0][0]
    rows = np.r_[one, one[two]]
    got = _branch(*(v[rows] for v in (px, py, H, L, hH, hL, r, M)), np.r_[runs[0][0], runs[1][0][two]],
                  np.r_[runs[0][1], runs[1][1][two]], margin[rows])
    for whole, part in zip((d0, gH, gL, E, ok), got):
        whole[one, :] = part[:one.size, None]
        whole[one[two], 1] = part[one.size:]
    first = covered & ok.all(axis=1) & (d0[:, 0] <= high)   # beyond both runs every point is farther than high + r
    worst = (d0 - np.abs(gH) * hH[:, None] - np.abs(gL) * hL[:, None] - E).min(axis=1)
    zero = np.where(first, np.maximum(zero, worst), zero)
    other = one[~first[one]] if fine else one[:0]
    if width is not None and other.size:  # not in cells a node's worst corner has closed
        other = other[np.repeat(zero.reshape(-1, width).max(axis=1) < target, width)[other]]
    if other.size:                        # more branches near the node: the tangent-segment bound
        zero[other] = np.maximum(zero[other], _tangents(px[other], py[other], H[other], L[other],
                                                        (high + 2 * r + spacing)[other], spacing[other],
                                                        squared[other], tol[other]) - r[other] - margin[other])
    return zero, d0, gH, gL, E, first


def tangent_bound(px, py, H, L, hH, hL):
    """A constant bound [mm] on the distance from nodes (px, py) to the limaçon over cells of centre
    (H, L) and half-widths (hH, hL), one pair an element, where several branches pass near the
    node: `_tangents` at the cell's centre, less the move r (`lipschitz_radius`)."""
    px, py, H, L, hH, hL = (np.ravel(v).astype(float) for v in np.broadcast_arrays(px, py, H, L, hH, hL))
    r = lipschitz_radius(hH, hL)
    V = np.abs(L) + np.abs(H)
    spacing = V * np.pi / POLYLINE
    _, high, squared, tol = _nearest(px, py, H, L)
    return _tangents(px, py, H, L, high + 2 * r + spacing, spacing, squared, tol) - r - ROUNDING * (1.0 + V)


def _branch(px, py, H, L, hH, hL, r, M, sj, sigma, margin):
    """The first-order bound of one run of near arcs (module docstring): from the run's vertex sj
    [rad] Newton's s0, then d0, gH, gL and E [mm]; `ok` where its conditions hold over the run,
    whose farthest arc ends sigma [rad] from sj."""
    s0 = _foot(px, py, H, L, sj)
    (x, y), (vx, vy), (ax, ay), a, b = _curve(s0, H, L)
    wx, wy = px - x, py - y
    d0, speed = np.hypot(wx, wy), np.hypot(vx, vy)
    ux, uy = wx / np.where(d0 > 0, d0, 1.0), wy / np.where(d0 > 0, d0, 1.0)
    tx, ty = -uy, ux                                     # the unit normal to u: exactly orthogonal
    eps_u = np.abs(ux * vx + uy * vy)
    eps_t = np.abs(wx * tx + wy * ty)                     # ~0 (w is along u): rounding only
    gH, gL = -(ux * b[0] + uy * b[1]), -(ux * a[0] + uy * a[1])
    # k >= |u . m'(s0)| and rt >= |n . m(s0)|: a' = (-a_y, a_x + 1), b' = (-2 b_y, 2 b_x + 1)
    k = np.abs(uy * (a[0] + 1) - ux * a[1]) * hL + np.abs(uy * (2 * b[0] + 1) - 2 * ux * b[1]) * hH
    rt = np.abs(tx * a[0] + ty * a[1]) * hL + np.abs(tx * b[0] + ty * b[1]) * hH
    quad = ux * ax + uy * ay + hL + 2 * hH              # u . Q''(s0) + max |m''|
    M3 = np.abs(L) + 4 * np.abs(H)                      # max |Q'''| (|a'''| = 1, |b'''| = 4)
    top = d0 + np.abs(gH) * hH + np.abs(gL) * hL         # the largest D over the cell
    sigma = np.minimum(sigma + np.abs((s0 - sj + np.pi) % (2 * np.pi) - np.pi), 2 * np.pi)  # from s0; > pi: not ok
    pace = np.sqrt(np.maximum(speed * speed - eps_u * eps_u, 0.0)) - hL - hH   # |n . Q'(s0)| less |m'|
    offset = eps_t + rt                                  # B(t) = pace |t| - M t^2/2 - offset
    disc = pace * pace - 2 * M * (top + offset)          # B(t0) = top
    t0 = (pace - np.sqrt(np.maximum(disc, 0.0))) / M
    B_sigma = pace * sigma - M * sigma * sigma / 2 - offset
    ok = (d0 > 0) & (pace > 0) & (disc >= 0) & (sigma < np.pi) & ((sigma <= t0) | (B_sigma >= top))
    t1 = np.where(ok, np.minimum(t0, sigma), 0.0)
    E = _loss(top, eps_u + k, quad, M3, pace, M, offset, t1) + margin
    return d0, gH, gL, E, ok
