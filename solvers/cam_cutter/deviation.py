"""How far the linkage's limaçon lies from the ideal torch path: two independent measures.

* `normal_deviation`: along each node's normal, the nearest crossing of the closed limaçon (the
  paper's criterion, Sec. IV). Substituting the normal line into the limaçon's implicit form gives
  the quartic the paper found "laborious"; its roots, for every node at once, are the eigenvalues
  of stacked 4x4 companion matrices. The minimax NLP and differential evolution use this measure.
* `path_distance` / `verified_deviation`: Euclidean distance to the closed limaçon (foot point),
  found by a KD-tree over a fine polyline and Newton on the foot condition, and maximised over the
  continuous path. It shares no code with the first and is the figure reported as
  `max_deviation_mm`. Both agree to second order in the angle between the two paths' normals.

Neither restricts crossings to the upper half-plane: the torch runs the whole closed limaçon and
the lower half cuts the mirror image, so a crossing just below the axis is a real cut point.
"""

import numpy as np
from scipy.spatial import cKDTree

from mechopt.kit.cache import memoised
from mechopt.models.cam_cutter import ideal_normal, ideal_point


def normal_quartic(px, py, nx, ny, H, L):
    """(c0, c1, c2, c3): F(P + d n) = d^4 + c3 d^3 + c2 d^2 + c1 d + c0, the limaçon's implicit
    form (`limacon_implicit`) along the unit normal n through P. Arrays broadcast."""
    u0 = px + L + H                       # node abscissa from the limaçon's pole
    r0 = u0 * u0 + py * py
    r1 = 2 * (u0 * nx + py * ny)
    g0 = r0 - H * u0
    g1 = r1 - H * nx
    # F(d) = (d^2 + g1 d + g0)^2 - L^2 (d^2 + r1 d + r0), monic because |n| = 1
    return g0 * g0 - L * L * r0, 2 * g0 * g1 - L * L * r1, g1 * g1 + 2 * g0 - L * L, 2 * g1


def normal_crossings(px, py, nx, ny, H, L):
    """Signed distances d [mm] at which P + d n meets the closed limaçon: the four roots of
    F(P + d n) = 0, complex where there is no crossing. Arrays broadcast; the result has a
    trailing axis of 4."""
    c0, c1, c2, c3 = np.broadcast_arrays(*normal_quartic(px, py, nx, ny, H, L))
    companion = np.zeros(c0.shape + (4, 4))
    companion[..., 1, 0] = companion[..., 2, 1] = companion[..., 3, 2] = 1.0
    companion[..., :, 3] = -np.stack([c0, c1, c2, c3], axis=-1)
    return np.linalg.eigvals(companion)


def normal_deviation(px, py, nx, ny, H, L):
    """Signed distance [mm] along the outward normal to the nearest crossing; +inf where the normal
    misses the limaçon. A crossing at the pole counts only when the pole is on the curve (L <= H:
    for L > H it is an isolated point of the implicit quartic, not a point the torch visits)."""
    roots = normal_crossings(px, py, nx, ny, H, L)
    scale = 1.0 + np.abs(roots.real)
    d = np.where(np.abs(roots.imag) <= 1e-7 * scale, roots.real, np.inf)
    H, L = np.asarray(H)[..., None], np.asarray(L)[..., None]
    finite = np.where(np.isfinite(d), d, 0.0)
    at_pole = np.hypot(px[..., None] + finite * nx[..., None] + L + H, py[..., None] + finite * ny[..., None])
    d = np.where((L > H) & (at_pole < 1e-6 * (L + H)), np.inf, d)
    nearest = np.argmin(np.abs(d), axis=-1)
    return np.take_along_axis(d, nearest[..., None], axis=-1)[..., 0]


def _limacon(c, n, H, L):
    """The point of eq. (10) where cos s = c and sin s = n [mm]: `real_point` with cos 2s and
    sin 2s expanded, so a Newton step costs one cos and one sin."""
    return L * (c - 1) + H * (c * c - 1), n * (L + H * c)


def _frozen(*arrays):
    for a in arrays:
        a.flags.writeable = False        # cached and shared between callers
    return arrays


@memoised(maxsize=4)
def _circle(vertices):
    s = np.linspace(0.0, 2 * np.pi, vertices, endpoint=False)
    return _frozen(s, np.cos(s), np.sin(s))


@memoised(maxsize=8)
def _vertices(H, L, vertices):
    """s and the points of eq. (10) on a polyline of the limaçon."""
    s, c, n = _circle(vertices)
    return (s, *_frozen(*_limacon(c, n, H, L)))


@memoised(maxsize=8)
def _tree(H, L, vertices):
    # an unbalanced tree (median-free splits) builds in 2/3 the time and queries as fast
    return cKDTree(np.column_stack(_vertices(H, L, vertices)[1:]), balanced_tree=False)


DIRECT_PAIRS = 2**16        # points x vertices up to which a direct search beats building a tree


def _nearest_vertex(px, py, H, L, vertices):
    """(distance, index) of each point's nearest polyline vertex: directly for a few points,
    else by a KD-tree (cached per linkage: the next call on it is a query)."""
    if px.size * vertices <= DIRECT_PAIRS:
        _, x, y = _vertices(H, L, vertices)
        squared = (x[None, :] - px[:, None]) ** 2 + (y[None, :] - py[:, None]) ** 2
        index = squared.argmin(axis=1)
        return np.sqrt(squared[np.arange(px.size), index]), index
    return _tree(H, L, vertices).query(np.column_stack([px, py]))


def path_distance(px, py, H, L, *, vertices=2**14, newton_steps=4):
    """Euclidean distance [mm] from points to the closed limaçon (H, L): nearest polyline vertex,
    then Newton on the foot condition (R - P).R' = 0, each step kept only if it brings R closer."""
    return foot_points(px, py, H, L, vertices=vertices, newton_steps=newton_steps)[0]


def foot_points(px, py, H, L, *, vertices=2**14, newton_steps=4):
    """(distance [mm], crank parameter s [rad]) of each point's nearest point on the limaçon."""
    H, L, px, py = float(H), float(L), np.ravel(px), np.ravel(py)
    best, index = _nearest_vertex(px, py, H, L, vertices)
    s = _circle(vertices)[0][index]
    spacing = 2 * np.pi / vertices
    c, n = np.cos(s), np.sin(s)
    for _ in range(newton_steps):
        # R, R', R'' of eq. (10) from cos s and sin s alone (cos 2s = 2c^2 - 1, sin 2s = 2nc)
        c2, n2 = 2 * c * c - 1, 2 * n * c
        x, y = _limacon(c, n, H, L)
        ex, ey = x - px, y - py
        vx, vy = -L * n - H * n2, L * c + H * c2
        ax, ay = -L * c - 2 * H * c2, -L * n - 2 * H * n2
        slope = vx * vx + vy * vy + ex * ax + ey * ay
        step = np.clip(-(ex * vx + ey * vy) / np.where(slope > 0, slope, np.inf), -spacing, spacing)
        trial = s + step
        tc, tn = np.cos(trial), np.sin(trial)
        tx, ty = _limacon(tc, tn, H, L)
        dist = np.hypot(tx - px, ty - py)
        closer = dist < best
        s, best = np.where(closer, trial, s), np.where(closer, dist, best)
        c, n = np.where(closer, tc, c), np.where(closer, tn, n)
        # a refused step would be refused again (same s, same step). After accepted steps below
        # 1e-6 rad Newton is within ~1e-11 rad (quadratic convergence): the distance, stationary
        # at a foot point, is then off by ~1e-18 mm at 0.06 mm from the curve, 1e-9 mm on it
        if not np.any(closer & (np.abs(step) > 1e-6)):
            break
    return best, s


def verified_deviation(a, h, H, L, t_end, *, samples=2048, peaks=6, levels=5, points=33):
    """Largest Euclidean distance [mm] from the ideal path (9) of the cardioid (a, h), t in
    [0, t_end], to the limaçon, and the t where it occurs (`verified_deviation_on` that path)."""
    return verified_deviation_on(lambda t: ideal_point(t, a, h), 0.0, t_end, H, L,
                                 samples=samples, peaks=peaks, levels=levels, points=points)


def verified_deviation_on(path, t_start, t_end, H, L, *, samples=2048, peaks=6, levels=5, points=33):
    """Largest Euclidean distance [mm] from a path (a function t -> (x, y) [mm], vectorised), t
    in [t_start, t_end], to the limaçon, and the t where it occurs: sampled, then the leading
    local maxima refined together by zooming,
    each level resampling +-1 spacing around every peak's best point (16x finer a level, so
    5 levels resolve t to ~1e-9 rad, enough for a maximum at a kink as well as a smooth one).
    The deviation's peaks are wide: 1024 samples find the same maximum as 16384 to 3e-14 mm
    at and around minimax optima of a = 20..30 mm, h = 0..3 mm; 2048 keep a margin."""
    t = np.linspace(t_start, t_end, samples)
    dist = path_distance(*path(t), H, L)
    padded = np.r_[-np.inf, dist, -np.inf]
    tops = np.flatnonzero((padded[1:-1] >= padded[:-2]) & (padded[1:-1] >= padded[2:]))
    centre = t[tops[np.argsort(dist[tops])[::-1][:peaks]]]
    half = (t_end - t_start) / (samples - 1)
    best_value, best_t = float(dist.max()), float(t[dist.argmax()])
    offsets = np.linspace(-1.0, 1.0, points)
    for _ in range(levels):
        grid = np.clip(centre[:, None] + half * offsets[None, :], t_start, t_end)
        near = path_distance(*path(grid.ravel()), H, L).reshape(grid.shape)
        pick = near.argmax(axis=1)
        centre = grid[np.arange(len(grid)), pick]
        k = int(near.max(axis=1).argmax())
        if near[k, pick[k]] > best_value:
            best_value, best_t = float(near[k, pick[k]]), float(centre[k])
        half *= 2.0 / (points - 1)
    return best_value, best_t


def deviation_arrays(task, H, L, *, samples=1000):
    """What a linkage (H, L) does along a task's path, one row per sample t [rad]: the path's
    point, its nearest point on the limaçon and the distance between them [mm] (`--csv`'s columns);
    and the whole limaçon (10) the linkage traces, as many points evenly over a crank turn
    (`turn_x_mm`, `turn_y_mm`, closed: the real path a figure draws, its inner loop too)."""
    t = np.linspace(task.t_start_rad, task.t_end_rad, samples)
    px, py = task.path_point(t)
    distance, s = foot_points(px, py, H, L)
    lx, ly = _limacon(np.cos(s), np.sin(s), float(H), float(L))
    turn = np.linspace(0.0, 2 * np.pi, samples)
    tx, ty = _limacon(np.cos(turn), np.sin(turn), float(H), float(L))
    return {"t_rad": t, "path_x_mm": px, "path_y_mm": py, "limacon_x_mm": lx, "limacon_y_mm": ly,
            "deviation_mm": distance, "turn_x_mm": tx, "turn_y_mm": ty}


def nodes_and_normals(t, a, h):
    """Ideal-path nodes and their outward normals at parameters t: (px, py, nx, ny)."""
    return (*ideal_point(t, a, h), *ideal_normal(t))
