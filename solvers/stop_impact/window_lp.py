"""The synthesis' linear model and its window LP (solvers/stop_impact/synthesis.py).

The law is a spline in xi (models/cam_law.py): S = s0 + B c. At a fixed speed n and phase angle t
the elastic lever's relative error e is linear in c (superposition), so are X = S + e, its
velocity X' and acceleration X'' (what the roller must push), and the kinematic analogues.
What is not linear is *where* C meets its plate (X = 1 - preload / H). It is made linear by an
arrival window: C stays below the plate before xi_a (X <= target), and from xi_a to the end of the
grid its velocity stays below u_k, with X >= target at the end so that it does arrive. Then the
approach velocity is at most u_k H / T_k whatever the exact contact, and the rebound of eq. (2),
max_s (v0 g(s) + p(s)) (v0 and the pulse scale together, the preload does not), is a convex
piecewise-linear function of v0: r >= g_j v0 + p_j, one row per line of its upper envelope.

Each LP is assembled once per phase angle and sample set as sparse rows, scaled and held in HiGHS
(solvers/stop_impact/window_rows.py); a window changes only the bounds of the rows it masks, and
each window is solved from scratch by the dual simplex (the interior point where it does not
settle, iteration limits both); the lever enters as a dense response matrix for few coefficients and as
state variables tied by the exact step for many (`elastic_states`); the rows are sampled on the
grid (every 0.015 in xi early in the rise, 0.004 near the plate), the roller's force kept 5 % above
zero there (a force closure: no lift-off; a groove: no crossover, whose flight across the backlash the
linear model does not hold). `predicted_rebounds_mm` is the linear model on the full grid: what the
dense check and the chain judge.

A t whose kinematic bounds alone conflict (below the kinematic minimum) is refused by one small
LP before any window is tried, naming the bounds that bind (`kinematic_conflict`).
"""
import math
from dataclasses import dataclass

import numpy as np
from scipy import sparse
from scipy.optimize import brentq

from mechopt.kit.cache import BuildCache, memoised
from mechopt.kit.errors import ModelError
from mechopt.kit.result import Status
from mechopt.models.cam_follower import law_values
from mechopt.models.cam_law import (
    SplineBasis,
    SplineLaw,
    elastic_response,
    elastic_responses,
    intervals_for,
    step_matrices,
)
from mechopt.models.stop_impact import LeverStop
from mechopt.solvers.stop_impact.cam_follower import follower_data
from mechopt.solvers.stop_impact.law import envelope_amplitude_m
from mechopt.solvers.stop_impact.response import closed_form_amplitude_m, response_parts
from mechopt.solvers.stop_impact.window_rows import INF, HeldLP, Rows

__all__ = ["BASES", "LinearLever", "SpeedResponse", "WindowLP", "band_speeds", "elastic_states", "kinematic_conflict",
           "kinematic_rows", "lever_lines", "linear_lever", "predicted_rebounds_mm", "rebound_envelope",
           "rebound_of_v0_mm", "speed_response", "v0_limit_m_s"]

DWELL_XI = 0.3                  # the grid runs this far past the rise: C may reach its plate in the dwell
RISE_NODES = 600                # at least this many grid nodes over the rise (a multiple of the knots)
ROW_SPACING_XI = (0.015, 0.004)  # LP rows this far apart before / after ARRIVAL_FROM_XI (the full grid is checked after)
ARRIVAL_FROM_XI = 0.55          # where the plate comes near: rows close enough that X' cannot peak between them
CONTACT_MARGIN = 0.05           # the roller's force kept above 5 % of the closure at the rows (it peaks between them)
STATE_FORM_FROM = 200           # coefficients from which the LP carries the lever's states (elastic_states)
ENVELOPE_POINTS = 2049          # time samples of eq. (2)'s window for the envelope's lines
BASES = BuildCache("stop_impact.synthesis_bases", maxsize=8)


@dataclass(frozen=True)
class LinearLever:
    """The spline space on its grid: the matrices of S, S', S'', S''' at the nodes (affine in the
    free coefficients: value = offset + matrix @ c), built once per (coefficients, continuity)."""
    basis: SplineBasis
    xi: np.ndarray                      # nodes over [0, 1 + DWELL_XI], knots among them
    step: float
    rise: np.ndarray                    # mask of the nodes in [0, 1]
    kin: tuple                          # ((s0, B), (d0, D), (a0, A), (j0, J)) at the nodes
    bound_kin: tuple                    # the same at the knots and quarter points: where the bounds hold

    def response(self, lam: float, zeta: float):
        """((X0, XB), (dX0, dXB), (ddX0, ddXB)) of the elastic lever at lambda: affine in c, the
        matrices dense (superposition of every basis function's response; a derivative-free
        peer's objective, not the LP's: `elastic_states` keeps the LP sparse)."""
        (s0, B), (d0, D), (a0, A), _ = self.kin
        inputs = np.column_stack([a0, A.toarray()])
        e, de = elastic_response(inputs, lam, zeta, self.step)
        dde = -inputs - 2 * zeta * lam * de - lam * lam * e
        X = (s0 + e[:, 0], B.toarray() + e[:, 1:])
        dX = (d0 + de[:, 0], D.toarray() + de[:, 1:])
        ddX = (a0 + dde[:, 0], inputs[:, 1:] + dde[:, 1:])
        return X, dX, ddX


def linear_lever(coefficients: int, continuity: int) -> LinearLever:
    """The grid and kinematic matrices for `coefficients` free spline coefficients (cached)."""
    key = (coefficients, continuity)
    return BASES.get(key, lambda: _build_lever(coefficients, continuity))[0]


def _build_lever(coefficients, continuity):
    basis = SplineBasis(intervals_for(coefficients, continuity), continuity)
    per = max(1, math.ceil(RISE_NODES / basis.intervals))
    step = 1.0 / (basis.intervals * per)
    xi = np.arange(0, round((1 + DWELL_XI) / step) + 1) * step
    rise = xi <= 1.0 + 1e-12
    mats = basis.matrices(xi[rise], order=3)
    dwell = (~rise).sum()
    kin = []
    for d, (off, mat) in enumerate(mats):
        off = np.concatenate([off, np.full(dwell, 1.0 if d == 0 else 0.0)])
        kin.append((off, sparse.vstack([mat, sparse.csr_matrix((dwell, mat.shape[1]))], format="csr")))
    breaks = np.unique(basis.knots)
    quarters = np.unique(np.concatenate([breaks[:-1] + f * np.diff(breaks) for f in (0.0, 0.25, 0.5, 0.75)]
                                        + [[1.0]]))
    # a cubic's acceleration is linear between knots (its peak at one) and its jerk constant: these
    # points hold those bounds exactly, the velocity's and a quartic's to O(h^2)
    bounds = tuple(basis.matrices(quarters, order=3))       # banded
    return LinearLever(basis, xi, step, rise, tuple(kin), bounds)


# ---------------------------------------------------------------- rebound as a function of v0

def rebound_of_v0_mm(task: LeverStop, v0_m_s: float) -> float:
    """The first rebound of eq. (2) [mm] for an approach velocity v0 (closed form)."""
    return closed_form_amplitude_m(task.impact(0.0, v0_m_s=float(v0_m_s)))[0] * 1e3


def rebound_envelope(task, v_top):
    """Lines (g [mm per m/s], p [mm]) whose maximum is the rebound for v0 in [0, v_top]: the
    grid lines that are the largest at one of 400 speeds there (a <= max(0, max_j g_j v0 + p_j)).
    Sampled, not the exact envelope (law.upper_envelope): on the lift it keeps 132 of the exact
    265 lines and under-reads the envelope by at most 6.5e-6 mm, while the LP runs ~3x faster;
    the chain's check of every law covers the gap."""
    unit = task.impact(0.0, v0_m_s=1.0)
    s = np.linspace(0.0, unit.window_s, ENVELOPE_POINTS)
    moving, pressed = response_parts(unit, s)
    g, p = moving[0] * 1e3, pressed[0] * 1e3
    v = np.linspace(0.0, v_top, 400)
    keep = np.unique(np.argmax(np.outer(v, g) + p, axis=1))
    return g[keep], p[keep]


@memoised(maxsize=64)      # a lever's, whatever the phase angle: the search asks at every step
def lever_lines(task, limit_mm):
    """The rebound's lines (`rebound_envelope`) of a lever over v0 up to 4x the v0 that keeps
    `limit_mm` (at least 1e-3 m/s): what its LP rows hold."""
    lines = rebound_envelope(task, 4 * max(v0_limit_m_s(task, limit_mm), 1e-3))
    for each in lines:
        each.flags.writeable = False        # shared by every LP of the lever
    return lines


def v0_limit_m_s(task, limit_mm):
    """The largest v0 whose rebound keeps `limit_mm` (the rebound grows with v0) [m/s]."""
    f = lambda v: rebound_of_v0_mm(task, v) - limit_mm
    if f(0.0) > 0:
        raise ModelError(f"amplitude_limit_mm={limit_mm}: the preload alone throws C further; no approach keeps it",
                         key="amplitude_limit_mm")
    hi = 0.1
    while f(hi) < 0:
        hi *= 2
    return brentq(f, 0.0, hi, xtol=1e-14)


# ---------------------------------------------------------------- one LP

@dataclass
class SpeedResponse:
    """The lever at one speed: lambda = omega t / Omega, its damping ratio, the rise's time T [s],
    and the dense response (`LinearLever.response`) when the LP takes that form (else None)."""
    rpm: float
    lam: float
    zeta: float
    T: float
    resp: tuple | None = None
    lines: tuple | None = None          # its lever's rebound envelope (`rebound_envelope`) when not the LP's


def speed_response(task, lever, rpm, t_deg, lines=None):
    """The lever at `rpm`; its dense response computed here, once, below STATE_FORM_FROM coefficients
    (the form `elastic_states` then takes). `lines`: the envelope of this lever's rebound (a lever
    of the box, whose plate rings at its own frequency and damping)."""
    lam, zeta, H, target, T = follower_data(task, rpm, t_deg)
    dense = lever.basis.size < STATE_FORM_FROM
    return SpeedResponse(rpm, lam, zeta, T, lever.response(lam, zeta) if dense else None, lines)


def elastic_states(rows, lever, speed, k, at):
    """(X at the nodes `at`, X at the grid's end, X' and X'' at `at`), each (terms, offset): the
    elastic lever at speed number k as affine maps of the Rows' columns. Two forms of one map, chosen
    by size (measured, one LP at 420 rpm): below STATE_FORM_FROM coefficients the superposition's
    dense response matrix on the coefficients c (few columns; 24 coefficients x 5 speeds: ~8x faster
    than the states); from it on, e and e' as columns `e<k>`, `de<k>` at every node (at rest at node
    0), tied to c by the exact first-order-hold step (models/cam_law.py `step_matrices`): each row
    holds a few coefficients (10^3 coefficients: 0.75 s presolved against 6.4 s dense)."""
    last = [lever.xi.size - 1]
    if speed.resp is not None:
        (X0, XB), (dX0, dXB), (ddX0, ddXB) = speed.resp
        return tuple(([("c", mat[i])], off[i]) for (off, mat), i in
                     (((X0, XB), at), ((X0, XB), last), ((dX0, dXB), at), ((ddX0, ddXB), at)))
    (s0, B), (d0, D), (a0, A), _ = lever.kin
    Phi, Ga, Gb = step_matrices(speed.lam, speed.zeta, lever.step)
    n, h = lever.xi.size, lever.step
    e, de = f"e{k}", f"de{k}"
    at_rest = (np.r_[0.0, np.full(n - 1, -INF)], np.r_[0.0, np.full(n - 1, INF)])
    rows.column(e, n, *at_rest)
    rows.column(de, n, *at_rest)
    up, down = sparse.eye(n - 1, n, k=1, format="csr"), sparse.eye(n - 1, n, format="csr")
    drive = lambda j: Ga[j] * A[:-1] + (Gb[j] / h) * (A[1:] - A[:-1])     # S'' linear over each step
    for j, own in ((0, e), (1, de)):
        shift = {e: -Phi[j, 0] * down, de: -Phi[j, 1] * down}
        shift[own] = shift[own] + up
        rows.tie([(e, shift[e]), (de, shift[de]), ("c", -drive(j))], Ga[j] * a0[:-1] + Gb[j] * np.diff(a0) / h)
    pick = sparse.eye(n, format="csr")
    X = ([("c", B[at]), (e, pick[at])], s0[at])
    ddX = ([(de, -2 * speed.zeta * speed.lam * pick[at]), (e, -speed.lam ** 2 * pick[at])], np.zeros(len(at)))
    return X, ([("c", B[last]), (e, pick[last])], s0[last]), ([("c", D[at]), (de, pick[at])], d0[at]), ddX


def _negated(terms):
    return [(name, -coef) for name, coef in terms]


def kinematic_rows(rows, lever, t_deg, stroke_mm, bounds):
    """The kinematic bounds given (velocity, acceleration, jerk of C's travel against the cam angle)
    as rows of the coefficients c, a family each, held at the knots and quarter points (`bound_kin`)."""
    t_rad = math.radians(t_deg)
    _, (d0, D), (a0, A), (j0, J) = lever.bound_kin
    for name, (off, mat), power, key in (("velocity", (d0, D), 1, "max_velocity_mm_per_rad"),
                                         ("acceleration", (a0, A), 2, "max_acceleration_mm_per_rad2"),
                                         ("jerk", (j0, J), 3, "max_jerk_mm_per_rad3")):
        if bounds.get(key):
            lim = bounds[key] * t_rad**power / stroke_mm      # the bound on the analogue of S
            rows.le(name, [("c", mat)], lim - off)
            rows.le(name, [("c", -mat)], lim + off)


def kinematic_conflict(lever, t_deg, stroke_mm, bounds):
    """The kinematic bounds that no rest-to-rest law of the space keeps at `t_deg` (a tuple, empty
    when some law keeps them all): one small LP with a slack per bound, the lever left out. Any
    window's LP holds these rows too, so a conflict here is infeasibility for every window, found
    without them (below the kinematic minimum they took HiGHS 1-16 s each)."""
    rows = Rows()
    rows.column("c", lever.basis.size)
    kinematic_rows(rows, lever, t_deg, stroke_mm, bounds)
    if not rows.rows:
        return ()
    names = rows.slacken()
    held = HeldLP(rows, movable=[])
    status, x, _ = held.solve([])
    if status is not Status.SOLVED:
        return ()                                   # no verdict here: the windows' LPs decide
    return tuple(name for name in names if held.block(x, f"slack:{name}")[0] > 1e-9)


def _rows(lever):
    """The grid nodes the LP holds its dynamic limits at: sparse early in the rise, dense where C
    approaches its plate, and the grid's last node."""
    coarse, fine = (max(1, round(h / lever.step)) for h in ROW_SPACING_XI)
    index = np.arange(lever.xi.size)
    rows = np.where(lever.xi < ARRIVAL_FROM_XI, index % coarse == 0, index % fine == 0)
    rows[-1] = True
    return rows


class WindowLP:
    """The LP at one phase angle and set of speeds, assembled once as sparse rows and held in HiGHS
    (solvers/stop_impact/window_rows.py); the arrival window's start xi_a decides which rows hold
    (their upper bound, or +inf), so each candidate window changes bounds in place and re-solves.
    `slack`: each family of limits gets a slack and the sum is minimised (which limits bind when
    nothing is feasible)."""

    def __init__(self, task, lever, speeds, t_deg, *, objective, limit_mm, bounds, lines, slack=False, extra=None):
        H = task.stroke_mm * 1e-3
        self.target = 1.0 - (task.preload_mm * 1e-3 / H if "preload" in task.effects else 0.0)
        at = np.flatnonzero(_rows(lever))
        self.xi = lever.xi[at]
        rows = Rows()
        rows.column("c", lever.basis.size)
        goal = "peak" if objective == "least_acceleration" else "r"
        rows.column(goal, cost=0.0 if slack else 1.0)
        kinematic_rows(rows, lever, t_deg, task.stroke_mm, bounds)
        if extra is not None:           # the cam's geometry linearised at a law, its trust region (geometry_steps)
            extra(rows)
        if goal == "peak":
            _, _, (a0, A), _ = lever.bound_kin
            rows.le("objective", [("c", A), ("peak", -np.ones(A.shape[0]))], -a0)
            rows.le("objective", [("c", -A), ("peak", -np.ones(A.shape[0]))], a0)
        # the roller kept on its driving wall (rows below): under a force closure against lift-off; in a
        # groove against a crossover, whose flight across the backlash moves C's approach off this
        # linear model (solvers/stop_impact/groove.py: 0.33 of the limit on loom/machine-speed-codesign's law)
        closure = task.closure_force_N if "cam_drive" in task.effects and task.closure_force_N is not None else None
        held = "cam_contact" if task.closure == "force" else "no_crossover"
        before, after = [], []
        for k, sp in enumerate(speeds):
            (X, X0), (X_end, X0_end), (dX, dX0), (ddX, ddX0) = elastic_states(rows, lever, sp, k, at)
            scale = H / sp.T                                            # X' -> m/s
            u = f"u{k}"
            rows.column(u)
            before.append(rows.le("arrival", X, self.target - X0))     # below the plate before xi_a
            rows.le("arrival", _negated(X_end), X0_end - self.target)   # on it by the grid's end
            after.append(rows.le("approach", dX + [(u, -np.ones(at.size))], -dX0))
            g, p = lines if sp.lines is None else sp.lines
            if goal == "r":
                rows.le("rebound", [(u, g * scale), ("r", -np.ones(g.size))], -p)
            else:
                rows.le("rebound", [(u, g * scale)], limit_mm - p)
            if closure is not None:      # the roller stays on its cam: N = F + m H X'' / T^2 >= 0
                rows.le(held, _negated(ddX), ddX0 + (1 - CONTACT_MARGIN) * closure * sp.T**2
                        / (task.mass_kg * H))
        self.slacks = rows.slacken() if slack else []
        self.masks = len(before), len(after)
        movable = np.concatenate(before + after)
        self.rows, self.held = rows, HeldLP(rows, movable)
        self.upper = rows.bounds()[1][movable]                         # where each movable row holds
        self.given_up = 0

    def upper_at(self, window_xi):
        """The movable rows' upper bounds with the window at xi_a = window_xi: the arrival rows hold
        before it, the approach rows from it on (+inf where a row does not hold)."""
        # the velocity rows start a row early: C may cross between the last row below and the window
        holds = np.concatenate([self.xi < window_xi] * self.masks[0]
                               + [self.xi >= window_xi - 1.01 * ROW_SPACING_XI[1]] * self.masks[1])
        return np.where(holds, self.upper, INF)

    def solve(self, window_xi):
        """(status, c, value, slacks) with the arrival window starting at xi_a = window_xi. Each
        window is solved from scratch (HeldLP.solve: the answer does not depend on the windows
        solved before it, nor on the machine's speed or load); one that HiGHS does not settle within
        its iteration limits is given up: LIMIT, counted in `given_up`, no proof of infeasibility."""
        status, x, value = self.held.solve(self.upper_at(window_xi))
        if status is Status.LIMIT:
            self.given_up += 1
        if status is not Status.SOLVED:
            return status, None, math.inf, {}
        return (status, self.held.block(x, "c"), value,
                {name: float(self.held.block(x, f"slack:{name}")[0]) for name in self.slacks})


# ---------------------------------------------------------------- predictions on the full grid

def predicted_rebounds_mm(task: LeverStop, law: SplineLaw | str, t_deg: float, speeds_rpm, *, lever=None):
    """The linear model's rebound [mm], contact xi and approach velocity [m/s] at each speed
    (the crossing X = target on the grid, X' interpolated there): what the synthesis predicts,
    for the chain to confirm. A library law's name works too (its S'' sampled on the grid)."""
    lever = lever or linear_lever(100, 2)
    H = task.stroke_mm * 1e-3
    S, dS, ddS = law_values(law, lever.xi)
    speeds = [float(n) for n in np.atleast_1d(speeds_rpm)]
    data = [follower_data(task, n, t_deg) for n in speeds]
    e, de = elastic_responses(ddS, [d[0] for d in data], data[0][1], lever.step)
    out = []
    for k, (lam, zeta, _, target, T) in enumerate(data):
        X, dX = S + e[k], dS + de[k]
        hit = np.flatnonzero((X[:-1] < target) & (X[1:] >= target))
        if not hit.size:
            out.append((0.0, math.nan, 0.0))
            continue
        j = int(hit[0])
        w = (target - X[j]) / (X[j + 1] - X[j])
        v0 = (dX[j] + w * (dX[j + 1] - dX[j])) * H / T
        out.append((math.nan, float(lever.xi[j] + w * lever.step), float(v0)))
    # eq. (2) for every speed's v0 at once: v0 and the pulse scale together, the preload does not
    # (law.envelope_amplitude_m: within 1e-13 of `rebound_of_v0_mm`'s per-point Newton, ~70x faster)
    hit = [k for k, p in enumerate(out) if not math.isnan(p[1])]
    if hit:
        rebounds = envelope_amplitude_m([out[k][2] for k in hit], task.impact(1.0, 1.0, v0_m_s=1.0)) * 1e3
        for k, mm in zip(hit, rebounds):
            out[k] = (float(mm),) + out[k][1:]
    return out


def band_speeds(band_rpm, step_rpm):
    """The dense check's speeds: every `step_rpm` across the band, both ends included [rpm]."""
    lo, hi = band_rpm
    return np.unique(np.concatenate([np.arange(lo, hi, step_rpm), [hi]])).astype(float)
