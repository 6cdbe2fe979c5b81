"""Many rises of the lift cam at once (the chain's batch path): the approach velocity v0 at many
(n, t) in one pass, by the exact solution of the follower's linear equation rather than one
CVODES run per point (`cam_follower.follow_cam`, whose rules this follows step by step).

The relative error obeys e'' + 2 zeta lambda e' + lambda^2 e = -S''(xi) from rest
(models/cam_follower.py), a linear equation with constant coefficients. With mu = -zeta lambda
+ i w, w = lambda sqrt(1 - zeta^2) (zeta < 1), its impulse response is Im(e^{mu u}) / w, so by
Duhamel's integral (Meirovitch, Elements of Vibration Analysis, 2nd ed. 1986, sec. 4.8)

    e(xi)  = -Im(e^{mu xi} I(xi)) / w,   e'(xi) = -Im(mu e^{mu xi} I(xi)) / w,
    I(xi)  = integral_0^xi e^{-mu s} S''(s) ds,

I constant past the rise (S'' = 0 in the dwell). I is summed over the cells of follow_cam's own
sample grid (1001 points), each cell split at the law's joins (its knots or piece breaks, where
S''' jumps) and integrated by Gauss-Legendre with GAUSS_NODES nodes: |mu| dxi < 0.2 on the
scenes' ranges, so the rule's error is below rounding. S'' is sampled once for every lambda.
From there follow_cam's rules: the first sample where X = S + e reaches the plate's X (rise,
then the dwell's samples), the contact by the same safeguarded Newton, v0 = X' H / T there, and
the roller leaves its cam where N = F_closure + m H X'' / T^2 < 0 on a sample before the contact
(X'' = -2 zeta lambda e' - lambda^2 e, the law's S'' cancelling). CVODES at the chain's reltol
1e-12 differs from this by its own error (~1e-10 relative in v0; tests/loom/test_walk.py).

Points this path does not take (zeta >= 1, a law of unknown joins or of two joins in one cell,
no contact within the window, a dwell the cycle cuts, a growth e^{zeta lambda} past EXP_LIMIT)
are marked for the per-point chain."""
import numpy as np

from mechopt.kit.cache import memoised
from mechopt.kit.errors import ModelError
from mechopt.models.cam_law import SplineLaw
from mechopt.models.cam_laws import law as library_law
from mechopt.models.stop_impact import LeverStop
from mechopt.solvers.stop_impact.cam_follower import dwell_length, follower_data

GAUSS_NODES = 8
POINTS = 1001                 # follow_cam's samples per phase
NEWTON_ITERATIONS = 60        # follow_cam's contact search
EXP_LIMIT = 600.0             # zeta lambda above it: e^{zeta lambda xi} would overflow

ROLLER_LEFT, TAKEN, NOT_TAKEN = 1, 0, -1      # `rise_batch` outcome per point
_X, _W = np.polynomial.legendre.leggauss(GAUSS_NODES)


def law_joins(law) -> np.ndarray | None:
    """The xi in (0, 1) where the law's pieces join (S''' may jump there), None when unknown."""
    if isinstance(law, SplineLaw):
        knots = np.unique(np.asarray(law.knots, float))
    else:
        try:
            knots = np.asarray(library_law(law).breaks, float)
        except ModelError:      # a law the library does not name: the per-point chain
            return None
    return knots[(knots > 0.0) & (knots < 1.0)]


def _cuts(left, right, joins):
    """Where each interval [left, right] is cut: at the join inside it (at most one: the joins lie
    further apart than a cell), else at left (an empty first piece)."""
    inside = np.append(joins, np.inf)[np.searchsorted(joins, left, side="right")]
    return np.where(inside < right, inside, left)


def law_parts(law, xi):
    """(S, S', S'') at xi (any shape): the rise on [0, 1], rest before, the dwell after (as
    `law_values`, from the library's numpy forms)."""
    xi = np.asarray(xi, float)
    flat = xi.ravel()
    inside = np.clip(flat, 0.0, 1.0)
    if isinstance(law, SplineLaw):
        parts = [np.nan_to_num(part(inside)) for part in _spline_parts(law)]
    else:
        parts = list(library_law(law).values(inside)[:3])
    if np.any(inside != flat):                  # past the rise (or before it)
        after, before = flat > 1.0, flat < 0.0
        parts = [np.where(after, 1.0, np.where(before, 0.0, parts[0])),
                 *(np.where(after | before, 0.0, v) for v in parts[1:])]
    return tuple(np.reshape(v, xi.shape) for v in parts)


@memoised(maxsize=16)
def _spline_parts(law: SplineLaw):
    """S, S', S'' of a synthesised law as B-splines, built once (SplineLaw.values builds them per call)."""
    from scipy.interpolate import BSpline
    spline = BSpline(np.asarray(law.knots, float), np.asarray(law.coefficients, float), law.degree, extrapolate=False)
    return spline, spline.derivative(1), spline.derivative(2)


def interval_integrals(law, joins, mu, left, right):
    """integral_left^right e^{-mu s} S''(s) ds per point (mu, left, right: (N,)), by Gauss-Legendre
    on the two pieces either side of a join inside (the first empty without one)."""
    cut = _cuts(left, right, joins)
    starts, ends = np.stack([left, cut], -1), np.stack([cut, right], -1)
    half = 0.5 * (ends - starts)
    nodes = (0.5 * (ends + starts))[..., None] + half[..., None] * _X
    drive = law_parts(law, nodes)[2] * _W * half[..., None]
    return (np.exp(-mu[:, None, None] * nodes) * drive).sum(axis=(-2, -1))


@memoised(maxsize=16)
def _grid_drive(law, joins: tuple):
    """The rise's sample grid, S on it, and per cell without a join S'' w_j h at its Gauss nodes
    (cell start + h (x_j + 1), h half the step: the same offsets in every cell); the cells that
    hold a join (their integrals piece by piece)."""
    grid = np.linspace(0.0, 1.0, POINTS)
    h = 0.5 * (grid[1] - grid[0])
    offsets = h * (_X + 1.0)
    drive = law_parts(law, grid[:-1, None] + offsets)[2] * _W * h
    split = np.unique(np.searchsorted(grid, np.asarray(joins), side="right") - 1)
    split = split[(split >= 0) & (split < POINTS - 1)]
    drive[split] = 0.0
    return grid, law_parts(law, grid)[0], offsets, drive, split


def _grid_integrals(law, joins, mu):
    """I at every node of the rise's grid for each mu (N, POINTS): per cell e^{-mu x_k} times the
    cell's Gauss sum at the shared offsets (one matrix product), the join cells piece by piece."""
    grid, _, offsets, drive, split = _grid_drive(law, tuple(joins))
    shift = np.exp(-mu[:, None] * offsets[None, :])
    sums = shift.real @ drive.T + 1j * (shift.imag @ drive.T)     # (real products: BLAS)
    cells = np.exp(-mu[:, None] * grid[None, :-1]) * sums
    if split.size:              # every (mu, join cell) pair in one call
        pairs = interval_integrals(law, joins, np.repeat(mu, split.size), np.tile(grid[split], mu.size),
                                    np.tile(grid[split + 1], mu.size))
        cells[:, split] = pairs.reshape(mu.size, split.size)
    return np.concatenate([np.zeros((mu.size, 1), complex), np.cumsum(cells, axis=1)], axis=1)


def rise_integrals(law, joins, mu):
    """(the rise's sample grid (POINTS,), I at each of its nodes for each mu (N, POINTS)): the
    exact groove's walls (solvers/stop_impact/groove.py) start from these too."""
    return _grid_drive(law, tuple(joins))[0], _grid_integrals(law, joins, mu)


def _state(mu, w, xi, I):
    """(e, e') at xi from I(xi): mu, w, I of shape (N,), xi broadcast."""
    turn = np.exp(mu * xi) * I
    return -turn.imag / w, -(mu * turn).imag / w


def rise_batch(task: LeverStop, speed_rpm, t_deg):
    """v0 [m/s] at each (n, t) (1-d arrays of one length) and the outcome per point: TAKEN (v0
    as follow_cam would give it, status SOLVED), ROLLER_LEFT (follow_cam's INFEASIBLE: the
    contact force falls below 0 before C meets its plate, force closure) or NOT_TAKEN (the
    per-point chain's: among them a groove's crossover)."""
    n_rpm, t = (np.asarray(a, float).ravel() for a in (speed_rpm, t_deg))
    size = n_rpm.size
    v0, outcome = np.zeros(size), np.full(size, NOT_TAKEN)
    joins = law_joins(task.law) if "cam_drive" in task.effects else None
    if joins is None or size == 0 or np.any(np.diff(joins) <= 1.0 / (POINTS - 1)):     # one join a cell at most
        return v0, outcome
    data = [follower_data(task, n, tt) for n, tt in zip(n_rpm, t)]
    lam, zeta, H, target, T = (np.array([d[i] for d in data]) for i in range(5))
    dwell = np.array([dwell_length(la, tt) for la, tt in zip(lam, t)])
    ok = (zeta < 1.0) & (zeta * lam < EXP_LIMIT) & (dwell[:, 1] == 0)
    if not ok.any():
        return v0, outcome
    pick = np.flatnonzero(ok)
    lam, zeta, H, target, T, dwell = lam[pick], zeta[pick], H[pick], target[pick], T[pick], dwell[pick, 0]
    mu = -zeta * lam + 1j * lam * np.sqrt(1.0 - zeta * zeta)
    w = mu.imag
    # the rise's samples: I at every node, cumulative over the cells
    grid, S_grid = _grid_drive(task.law, tuple(joins))[:2]
    I_nodes = _grid_integrals(task.law, joins, mu)
    e, de = _state(mu[:, None], w[:, None], grid[None, :], I_nodes)
    X = S_grid[None, :] + e
    hit = (X[:, :-1] < target[:, None]) & (X[:, 1:] >= target[:, None])
    in_rise, j_rise = hit.any(axis=1), np.argmax(hit, axis=1)
    rows, k = np.arange(mu.size), np.arange(POINTS)[None, :]
    damp, stiff = 2.0 * zeta * lam, lam * lam
    lo, hi, I_lo = grid[j_rise], grid[np.minimum(j_rise + 1, POINTS - 1)], I_nodes[rows, j_rise]
    rise_seen = np.where(in_rise[:, None], k <= j_rise[:, None], True)
    least = np.where(rise_seen, -damp[:, None] * de - stiff[:, None] * e, np.inf).min(axis=1)
    found = in_rise.copy()
    late = np.flatnonzero(~in_rise)
    if late.size:               # the dwell's samples (I fixed at I(1)) where the rise does not meet the plate
        xi_d = 1.0 + dwell[late, None] * grid[None, :]
        e_d, de_d = _state(mu[late, None], w[late, None], xi_d, I_nodes[late, -1:])
        hit_d = (1.0 + e_d[:, :-1] < target[late, None]) & (1.0 + e_d[:, 1:] >= target[late, None])
        j_d, at = np.argmax(hit_d, axis=1), np.arange(late.size)
        found[late] = hit_d.any(axis=1)
        lo[late], hi[late] = xi_d[at, j_d], xi_d[at, np.minimum(j_d + 1, POINTS - 1)]
        I_lo[late] = I_nodes[late, -1]
        ddX_d = -damp[late, None] * de_d - stiff[late, None] * e_d
        least[late] = np.minimum(least[late], np.where(k <= j_d[:, None], ddX_d, np.inf).min(axis=1))
    xi_c, e_c, de_c = _locate(task.law, mu, w, joins, lo, hi, I_lo, target)
    # the roller's force N = F_closure + m H X'' / T^2 on the samples up to the contact and at it
    least = np.minimum(least, -damp * de_c - stiff * e_c)
    closure = task.closure_force_N if "cam_drive" in task.effects else 0.0
    left = closure + task.mass_kg * H / T**2 * least < 0
    dS_c = law_parts(task.law, xi_c)[1]
    speed = (dS_c + de_c) * H / T
    good = found & np.isfinite(speed)
    # in a groove N < 0 is a crossover, not a lift-off: its flight across the backlash is the
    # per-point chain's (solvers/stop_impact/groove.py)
    lifted = ROLLER_LEFT if task.closure == "force" else NOT_TAKEN
    outcome[pick] = np.where(good, np.where(left, lifted, TAKEN), NOT_TAKEN)
    v0[pick] = np.where(good & ~left, speed, 0.0)
    return v0, outcome


def _locate(law, mu, w, joins, lo, hi, I_lo, target):
    """follow_cam's `_locate` for every point at once: where X = S + e reaches `target` in
    [lo, hi], safeguarded Newton from the cell's middle, each iterate's state from I at lo."""
    def at(xi):
        return _state(mu, w, xi, I_lo + interval_integrals(law, joins, mu, lo, xi))
    a, b, xi = lo.copy(), hi.copy(), 0.5 * (lo + hi)
    e, de = at(xi)
    done = np.zeros(lo.size, bool)
    for _ in range(NEWTON_ITERATIONS):
        S, dS = law_parts(law, xi)[:2]
        gap, slope = S + e - target, dS + de
        a, b = np.where(gap < 0, xi, a), np.where(gap < 0, b, xi)
        with np.errstate(divide="ignore", invalid="ignore"):
            step = np.where(slope > 0, xi - gap / slope, 0.5 * (a + b))
        nxt = np.where((a < step) & (step < b), step, 0.5 * (a + b))
        # follow_cam stops where the next iterate is within 1e-15; here also where Newton's own
        # step is (at the root the bracket may reject it and restart bisection for ~1e-15 more)
        done |= (np.abs(nxt - xi) <= 1e-15) | (np.abs(step - xi) <= 1e-15)
        if done.all():
            break
        xi = np.where(done, xi, nxt)
        e_new, de_new = at(xi)
        e, de = np.where(done, e, e_new), np.where(done, de, de_new)
    return xi, e, de


__all__ = ["NOT_TAKEN", "ROLLER_LEFT", "TAKEN", "interval_integrals", "law_joins", "law_parts", "rise_batch",
           "rise_integrals"]
