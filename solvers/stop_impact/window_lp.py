"""The lift cam's motion law synthesised under the lever's dynamic limits, and
checked by the chain that did not design it.

The law is a spline in xi (models/cam_law.py): S = s0 + B c. At a fixed speed n and phase angle t
the elastic lever's relative error e is linear in c (superposition), so are X = S + e, its
velocity X' and acceleration X'' (what the roller must push), and the kinematic analogues.
What is not linear is *where* C meets its plate (X = 1 - preload / H). It is made linear by an
arrival window: C stays below the plate before xi_a (X <= target), and from xi_a to the end of the
grid its velocity stays below u_k, with X >= target at the end so that it does arrive. Then the
approach velocity is at most u_k H / T_k whatever the exact contact, and the rebound of eq. (2),
max_s (v0 g(s) + p(s)) (v0 and the pulse scale together, the preload does not), is a convex
piecewise-linear function of v0: r >= g_j v0 + p_j, one row per line of its upper envelope. xi_a
is scanned (a few candidates, then the neighbours of the best): each candidate is one LP solve
(HiGHS), status checked.

Objectives (`objective`):
* "least_rebound"      min over c of the largest rebound at the sampled speeds, at t = t_deg;
* "least_acceleration" min of the peak |S''| with the rebound <= amplitude_limit_mm, at t_deg;
* "least_phase"        the least t with the least rebound <= amplitude_limit_mm over the band:
                       regula falsi (Illinois) on r*(t) - limit in [phase_from_deg, phase_to_deg]
                       to `phase_tol_deg` or r* within 1e-4 of the limit, r*(t) the least-rebound
                       LP's value, assumed to fall as t grows (more time, slower arrival: stated,
                       not proven); a t below the kinematic minimum is a bisection step.

Each LP is assembled once per phase angle and sample set as sparse rows, scaled and held in HiGHS
(solvers/stop_impact/window_rows.py); a window changes only the bounds of the rows it masks, and
each window is solved from scratch by the dual simplex (the interior point where it does not
settle, iteration limits both); the lever enters as a dense response matrix for few coefficients and as
state variables tied by the exact step for many (`elastic_states`); the rows are sampled on the
grid (every 0.015 in xi early in the rise, 0.004 near the plate), the roller's force kept 5 % above
zero there (a force closure: no lift-off; a groove: no crossover, whose flight across the backlash the
linear model does not hold), and the full grid (the dense check) and the chain judge the result. Not modelled: the
Hertz stress of the law; the cam's pressure angle and radius of curvature only when `geometry`
(sequential LPs, solvers/stop_impact/cam_rows.py).

A t whose kinematic bounds alone conflict (below the kinematic minimum) is refused by one small
LP before any window is tried, naming the bounds that bind (`kinematic_conflict`).

Robust over the speed band [band_low_rpm, band_high_rpm]: constraints at `sample_speeds` speeds,
then the linear model is checked densely (every `dense_step_rpm`) between them; a speed that
breaks the limit (or the LP's bound) is added to the samples and the LP solved again.

Verification: the law found runs through follow_cam (CVODES, the contact located) and the closed
form of eq. (2) at every sampled speed and at the dense check's worst; the linear prediction must
agree within `agreement_rel` (else INACCURATE). The four library laws are run at the same t and
speeds beside it: rebound, dynamic error, peak acceleration.
"""
import dataclasses
import math
from dataclasses import dataclass
from typing import Literal

import numpy as np
from scipy import sparse
from scipy.optimize import brentq

from mechopt.kit.cache import BuildCache, memoised
from mechopt.kit.errors import ModelError, SettingError
from mechopt.kit.result import Clock, Result, Status
from mechopt.kit.settings import Annotated, Interval, NonNegative
from mechopt.models.cam_follower import LAWS, law_values
from mechopt.models.cam_law import (
    SplineBasis,
    SplineLaw,
    elastic_response,
    elastic_responses,
    intervals_for,
    step_matrices,
)
from mechopt.models.cam_shape import CamShape
from mechopt.models.stop_impact import LeverStop, speed_tag
from mechopt.solvers.stop_impact.cam_follower import follow_cam, follower_data
from mechopt.solvers.stop_impact.cam_rows import TRUST, CamGeometry, GeometryCheck, least_pressure_angle
from mechopt.solvers.stop_impact.cam_shape import law_cam
from mechopt.solvers.stop_impact.law import RollerLeftCam, envelope_amplitude_m, rebound_amplitude_mm
from mechopt.solvers.stop_impact.lever_box import LeverBox, takes_box
from mechopt.solvers.stop_impact.response import closed_form_amplitude_m, response_parts
from mechopt.solvers.stop_impact.window_rows import INF, HeldLP, Rows

__all__ = ["BASES", "LinearLever", "box_values", "SpeedResponse", "WindowLP", "band_speeds", "design_law", "law_of", "linear_lever",
           "predicted_rebounds_mm", "rebound_envelope", "speed_response", "v0_limit_m_s",
           "rebound_of_v0_mm", "synthesise_law"]

def law_of(result: Result) -> SplineLaw:
    """The synthesised law of a `synthesise_law` Result (its diagnostics law_knots, law_coefficients):
    `law_of(run.result).values(xi)` gives S and its first three derivatives on any xi grid (the shop's input)."""
    knots, coeffs = np.asarray(result.diagnostics["law_knots"]), np.asarray(result.diagnostics["law_coefficients"])
    return SplineLaw(tuple(map(float, knots)), tuple(map(float, coeffs)), knots.size - coeffs.size - 1)

DWELL_XI = 0.3                  # the grid runs this far past the rise: C may reach its plate in the dwell
RISE_NODES = 600                # at least this many grid nodes over the rise (a multiple of the knots)
ROW_SPACING_XI = (0.015, 0.004)  # LP rows this far apart before / after ARRIVAL_FROM_XI (the full grid is checked after)
ARRIVAL_FROM_XI = 0.55          # where the plate comes near: rows close enough that X' cannot peak between them
CONTACT_MARGIN = 0.05           # the roller's force kept above 5 % of the closure at the rows (it peaks between them)
STATE_FORM_FROM = 200           # coefficients from which the LP carries the lever's states (elastic_states)
WINDOW_CANDIDATES = (0.7, 0.8, 0.9)            # xi_a scanned first, then halved steps around the best
WINDOW_REFINE = 1               # halvings of the scan step around the best window
BOUND_MARGIN = 1e-6             # a window's lower bound rules it out only this far (relative) above a value found
ENVELOPE_POINTS = 2049          # time samples of eq. (2)'s window for the envelope's lines
ROOT_FTOL = 1e-4                # the least phase: r*(t) within this of the limit (relative) ends the search
MAX_PHASE_STEPS = 40
ROBUST_ROUNDS = 8               # rounds of the dense check over the box's grid for one LP (each adds every
                                # lever's worst point that fails: a count)
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
        if extra is not None:           # the cam's geometry linearised at a law, its trust region (_geometry_steps)
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


# ---------------------------------------------------------------- the search

@dataclass
class _Design:
    status: Status
    law: SplineLaw | None
    value: float
    window_xi: float
    speeds: list
    lps: int
    message: str = ""
    violated: tuple = ()
    given_up: int = 0               # windows HiGHS did not settle within its iteration limits (WindowLP.solve)
    retried: int = 0                # windows the dual simplex did not settle, retried by the interior point
    c: np.ndarray | None = None     # the law's free coefficients
    geometry: GeometryCheck | None = None   # its cam's exact geometry (with a CamGeometry)
    geometry_steps: int = 0         # the sequential geometry LPs taken


def design_law(task: LeverStop, t_deg: float, band_rpm: tuple, *, geometry: CamGeometry | None = None,
               **settings) -> _Design:
    """The best law at phase angle `t_deg` (`_design`: its settings); with `geometry`, its cam's
    pressure angle and radius of curvature held too, by sequential LPs (`_geometry_steps`)."""
    if geometry is None:
        return _design(task, t_deg, band_rpm, **settings)
    return _geometry_steps(task, t_deg, band_rpm, geometry, settings)


def _geometry_steps(task, t_deg, band_rpm, geometry, settings):
    """The law without the cam's geometry, then while its exact geometry (`CamGeometry.check`)
    breaks a limit: the window LP again with the geometry rows linearised at the last law, its
    coefficients within TRUST of it, each family's limit lowered by the exact excess of the laws
    the linearised rows gave so far (their error; solvers/stop_impact/cam_rows.py); the speeds and
    window of the last law carried. SOLVED when the exact geometry holds; the LP's own status when
    a step has no law; LIMIT after `geometry.steps` steps."""
    lever = linear_lever(settings.get("coefficients", 100), settings.get("continuity", 2))
    d, backoff, check = _design(task, t_deg, band_rpm, **settings), {"pressure_angle": 0.0, "curvature_kappa": 0.0}, None
    for step in range(geometry.steps + 1):
        if d.status is not Status.SOLVED:
            said = f" (geometry step {step}: the rows linearised at the last law, its coefficients within {TRUST:g})"
            return dataclasses.replace(d, geometry_steps=step, message=d.message + (said if step else ""))
        check = geometry.check(d.law, t_deg)
        if check.holds():
            return dataclasses.replace(d, geometry=check, geometry_steps=step)
        if step == geometry.steps:
            break
        if step:        # a law of the linearised rows that breaks the exact limit: the rows' error, backed off
            backoff["pressure_angle"] += max(check.excess["pressure_angle"], 0.0)
            least = geometry.least_radius_mm
            if check.excess["curvature"] > 0:           # rho short by v: kappa over 1 / least by this
                backoff["curvature_kappa"] += 1.0 / max(least - check.excess["curvature"], 1e-3 * least) - 1.0 / least
        rows, c_k = geometry.linearised(lever, d.c, t_deg, backoff), d.c

        def extra(lp_rows, rows=rows, c_k=c_k):
            lp_rows.bound("c", c_k - TRUST, c_k + TRUST)
            for family, G, upper in rows:
                lp_rows.le(family, [("c", G)], upper)
        d = _design(task, t_deg, band_rpm, **settings | {"samples": d.speeds, "around": d.window_xi, "extra": extra})
    return dataclasses.replace(
        d, status=Status.LIMIT, geometry=check, geometry_steps=geometry.steps,
        message=f"the cam's geometry at t = {t_deg:.6g} deg still breaks its limits after {geometry.steps} "
                f"sequential LPs (geometry_steps): pressure angle {check.pressure_deg:.4g} deg "
                f"(max_pressure_angle_deg={geometry.max_pressure_angle_deg:g}), least radius of curvature "
                f"{min(check.convex_mm, check.concave_mm):.4g} mm (bound {geometry.least_radius_mm:g} mm)")


def _design(task: LeverStop, t_deg: float, band_rpm: tuple, *, objective="least_rebound", coefficients=100,
            continuity=2, sample_speeds=5, dense_step_rpm=5.0, bounds=None, rounds=4, samples=None,
            around=None, dense_bar_mm=None, explain=True, box: LeverBox | None = None, extra=None) -> _Design:
    """The best law at phase angle `t_deg` over the speed band: the LP over the arrival window
    (`_scan`), the dense check between the sampled speeds, a failing speed added and the LP solved
    again (at most `rounds` times). The dense check holds the law to the LP's own value (least
    rebound) or to the limit (`dense_bar_mm`, the least phase's question: is the limit kept?).
    `explain`: when no window is feasible, a slack LP names the limits that bind (the least
    phase's search skips it).

    `box` (solvers/stop_impact/lever_box.py): the LP holds the box's nominal and corner levers at
    the sampled speeds of the band raised by its margin, the dense check runs over its grid of
    levers, and a failing (lever, speed) is added as a failing speed is. The samples are points
    (frequency factor, zeta, rpm); `rounds` counts the rounds of additions (each adds every lever's failing worst)."""
    bounds = bounds or {}
    box = box or LeverBox()
    lever = linear_lever(coefficients, continuity)
    limit = task.amplitude_limit_mm
    lo, hi = box.band(band_rpm)
    if samples is None:
        speeds0 = list(np.linspace(lo, hi, sample_speeds)) if sample_speeds > 1 else [hi]
        samples = [key + (float(n),) for key in box.corners(task) for n in speeds0]
    samples = sorted(tuple(map(float, point)) for point in samples)
    dense = band_speeds((lo, hi), dense_step_rpm)
    conflict = kinematic_conflict(lever, t_deg, task.stroke_mm, bounds)
    if conflict:
        return _Design(Status.INFEASIBLE, None, math.inf, math.nan, samples, 1,
                       f"no law at t = {t_deg:.6g} deg keeps the kinematic bounds: binding: {', '.join(conflict)}",
                       conflict)
    levers = {key: LeverBox.lever(task, key) for key in box.grid_keys(task) + box.corners(task)}
    lines = {key: lever_lines(each, limit) for key, each in levers.items()}
    lps, counts, floors, responses = 0, {"given_up": 0, "retried": 0}, None, {}
    for _ in range(rounds):
        levers |= {p[:2]: LeverBox.lever(task, p[:2]) for p in samples if p[:2] not in levers}
        lines |= {key: lever_lines(each, limit) for key, each in levers.items() if key not in lines}
        responses |= {p: speed_response(levers[p[:2]], lever, p[2], t_deg, lines[p[:2]])
                      for p in samples if p not in responses}       # a round's samples are the last's and more
        speeds = [responses[p] for p in samples]
        nominal = lines[box.nominal(task)]
        lp = WindowLP(task, lever, speeds, t_deg, objective=objective, limit_mm=limit, bounds=bounds, lines=nominal,
                      extra=extra)
        (status, c, value, xa), count, floors = _scan(lp, around, floors)   # next round: these bound its windows
        lps = lps + count
        counts = {"given_up": counts["given_up"] + lp.given_up, "retried": counts["retried"] + lp.held.retried}
        if status is Status.INFEASIBLE and not explain:
            return _Design(Status.INFEASIBLE, None, math.inf, xa, samples, lps,
                           f"no law at t = {t_deg:.6g} deg keeps every limit", **counts)
        if status is Status.INFEASIBLE:
            slack = WindowLP(task, lever, speeds, t_deg, objective=objective, limit_mm=limit, bounds=bounds,
                              lines=nominal, slack=True, extra=extra)
            (_, _, _, xa), count, _ = _scan(slack)
            sl = slack.solve(xa)[3]
            binding = tuple(k for k, v in sl.items() if v > 1e-9)
            return _Design(Status.INFEASIBLE, None, math.inf, xa, samples, lps + count,
                           f"no law at t = {t_deg:.6g} deg keeps every limit at {_points_text(samples)}; "
                           f"binding: {', '.join(binding) or 'none found'}", binding, **counts)
        if status is not Status.SOLVED:
            return _Design(status, None, math.inf, xa, samples, lps, f"HiGHS: {status.value} at xi_a = {xa:g}",
                           **counts)
        law = lever.basis.law(c)
        bar = dense_bar_mm if dense_bar_mm is not None else value if objective == "least_rebound" else limit
        failing = [(mm, point) for key in box.grid_keys(task)
                   for mm, point in [_dense_worst(levers, [key], law, t_deg, dense, lever)]
                   if mm > bar * (1 + 1e-3) + 1e-4 * limit and point not in samples]
        if not failing:
            return _Design(Status.SOLVED, law, value, xa, samples, lps, **counts, c=c)
        worst = max(failing)[1]
        samples = sorted(samples + [point for _, point in failing])   # broken between samples: sample them too
    return _Design(Status.LIMIT, law, value, xa, samples, lps,
                   f"the dense check still fails at {_points_text([worst])} after {rounds} rounds", **counts, c=c)


def _dense_worst(levers, keys, law, t_deg, dense, lever):
    """(the linear model's largest rebound [mm], its point (frequency factor, zeta, rpm)) over the
    levers `keys` at every speed of `dense`."""
    best = (-math.inf, None)
    for key in keys:
        pred = [p[0] for p in predicted_rebounds_mm(levers[key], law, t_deg, dense, lever=lever)]
        j = int(np.argmax(pred))
        if pred[j] > best[0]:
            best = (pred[j], key + (float(dense[j]),))
    return best


def _points_text(points):
    """Sampled points for a message: the speeds alone when every point is one lever."""
    if len({p[:2] for p in points}) == 1:
        return f"{', '.join(f'{p[2]:g}' for p in points)} rpm"
    return ", ".join(f"(f x{p[0]:g}, zeta {p[1]:g}, {p[2]:g} rpm)" for p in points)


def band_speeds(band_rpm, step_rpm):
    """The dense check's speeds: every `step_rpm` across the band, both ends included [rpm]."""
    lo, hi = band_rpm
    return np.unique(np.concatenate([np.arange(lo, hi, step_rpm), [hi]])).astype(float)


def _scan(lp, around=None, floors=None):
    """((status, c, value, xi_a) of the best window, LPs solved, {xi_a: (status, value or its
    lower bound)} of the windows tried): WINDOW_CANDIDATES (or, `around` a window that was best at
    a neighbouring t, it and its neighbours), then steps halved around the best (the value is not
    convex in xi_a: a scan, stated, not a proof).

    `floors`: the windows tried of the same LP with fewer rows (the dense check's round before: a
    sample more is rows more, so its values are lower bounds here and its infeasible windows stay
    infeasible). Each stage's windows are solved lowest bound first; a window proven infeasible
    there, or whose bound exceeds by BOUND_MARGIN a value already solved here, is not solved: it
    cannot be the best, so the scan takes the same steps to the same best window and law."""
    floors, tried, bounded = floors or {}, {}, set()
    step = WINDOW_CANDIDATES[1] - WINDOW_CANDIDATES[0]
    first = WINDOW_CANDIDATES if around is None else (around - step / 2, around, around + step / 2)

    def stage(windows):
        todo = [xa for xa in dict.fromkeys(round(float(w), 12) for w in windows)
                if xa not in tried and 0.0 < xa <= 1.0 + DWELL_XI]
        got = {}
        for xa in sorted(todo, key=lambda w: floors.get(w, (None, -math.inf))[1]):     # stable: no floors, in order
            found = [v[2] for k, v in (tried | got).items() if k not in bounded]
            got[xa] = _floor_rules_out(floors.get(xa), found)
            if got[xa] is None:
                got[xa] = lp.solve(xa)
            else:
                bounded.add(xa)
        tried.update((xa, got[xa]) for xa in todo)          # in the scan's order: min() breaks ties as before
    stage(first)
    if around is not None:
        step /= 2
        if not any(math.isfinite(v[2]) for v in tried.values()):      # lost it: the full scan
            best, count, seen = _scan(lp, floors=floors)
            return best, count + len(tried) - len(bounded), seen
    for _ in range(WINDOW_REFINE):
        best = min(tried, key=lambda k: tried[k][2])
        if not math.isfinite(tried[best][2]):
            break
        step /= 2
        stage((best - step, best + step))
    best = min(tried, key=lambda k: tried[k][2])
    solved = {k: v for k, v in tried.items() if k not in bounded}
    seen = {k: (v[0], v[2]) for k, v in tried.items()}     # a lower bound stays one with more rows
    status, c, value, _ = tried[best]
    if status is Status.INFEASIBLE:         # a window HiGHS failed on is no proof of infeasibility
        failed = [k for k, v in solved.items() if v[0] not in (Status.SOLVED, Status.INFEASIBLE)]
        if failed:
            return (tried[failed[0]][0], None, math.inf, failed[0]), len(solved), seen
    return (status, c, value, best), len(solved), seen


def _floor_rules_out(floor, found):
    """A window's (status, None, value, {}) standing for its LP when its floor (`_scan`) rules it
    out: infeasible there, or a bound above the least value `found` so far; else None."""
    if floor is None:
        return None
    status, value = floor
    if status is Status.INFEASIBLE:
        return Status.INFEASIBLE, None, math.inf, {}
    least = min((v for v in found if math.isfinite(v)), default=math.inf)
    if status is Status.SOLVED and math.isfinite(least) and value > least + BOUND_MARGIN * abs(least):
        return Status.SOLVED, None, value, {}
    return None


# ---------------------------------------------------------------- the solver a scene names

@takes_box
def synthesise_law(task: LeverStop, *, objective: Literal["least_phase", "least_rebound", "least_acceleration"]
                   = "least_phase",
                   coefficients: Annotated[int, Interval(ge=2, le=2000)] = 100,
                   continuity: Literal[2, 3] = 2,
                   band_low_rpm: Annotated[float, Interval(gt=0, le=1e5)] = 280.0,
                   band_high_rpm: Annotated[float, Interval(gt=0, le=1e5)] = 420.0,
                   sample_speeds: Annotated[int, Interval(ge=1, le=50)] = 5,
                   dense_step_rpm: Annotated[float, Interval(gt=0, le=1e4)] = 5.0,
                   max_velocity_mm_per_rad: NonNegative = 0.0,
                   max_acceleration_mm_per_rad2: NonNegative = 0.0,
                   max_jerk_mm_per_rad3: NonNegative = 0.0,
                   phase_from_deg: Annotated[float, Interval(gt=0, lt=360)] = 10.0,
                   phase_to_deg: Annotated[float, Interval(gt=0, lt=360)] = 60.0,
                   phase_tol_deg: Annotated[float, Interval(gt=0, le=1)] = 0.01,
                   verify: bool = True,
                   agreement_rel: Annotated[float, Interval(gt=0, le=0.5)] = 2e-3,
                   compare: bool = True,
                   box: LeverBox | None = None,
                   robust: bool = False,
                   geometry: bool = False,
                   max_pressure_angle_deg: Annotated[float, Interval(gt=0, lt=90)] = 45.0,
                   min_curvature_margin_mm: NonNegative = 0.0,
                   cam_base_radius_mm: Annotated[float, Interval(gt=0, le=1e4)] = 60.0,
                   cam_roller_radius_mm: Annotated[float, Interval(gt=0, le=1e4)] = 15.0,
                   cam_centre_distance_mm: Annotated[float, Interval(gt=0, le=1e4)] = 120.0,
                   cam_dwell_deg: Annotated[float, Interval(ge=0, lt=360)] = 60.0,
                   geometry_steps: Annotated[int, Interval(ge=1, le=50)] = 8) -> Result:
    """Synthesise the lift cam's law (module docstring) and check it by the chain.

    Parameters
    ----------
    task : the lever (effects cam_drive and the impact's), `stroke_mm`, `amplitude_limit_mm` the
        rebound limit [mm], `t_deg` the phase angle for the fixed-angle objectives [deg].
    objective : "least_phase" | "least_rebound" | "least_acceleration".
    coefficients, continuity : free spline coefficients; C2 (cubic) or C3 (quartic) at the dwells.
    band_low_rpm, band_high_rpm, sample_speeds, dense_step_rpm : the speed band, the speeds the LP
        holds and the step of the dense check between them [rpm].
    max_velocity_mm_per_rad, max_acceleration_mm_per_rad2, max_jerk_mm_per_rad3 : kinematic bounds
        on the analogues of C's travel (0: none).
    phase_from_deg, phase_to_deg, phase_tol_deg : the search's bracket and tolerance on t [deg].
    verify, agreement_rel : run the law through follow_cam (CVODES) and eq. (2) and require the
        linear prediction to agree within agreement_rel (else INACCURATE).
    compare : the four library laws at the same t and speeds (values `<law>_rebound_mm_<rpm>` ...), and
        with least_phase the cycloid's least angle (`t_min_cycloidal_deg`, `phase_gain_percent`).
    box : the lever's uncertain inputs on a box (solvers/stop_impact/lever_box.py; a scene's settings
        box_frequency_low, box_frequency_high, box_zeta_low, box_zeta_high, box_speed_margin,
        box_grid: `takes_box`): a factor on both natural frequencies, the damping ratio (both 0: the
        task's own), the band's top raised by a fraction, the dense check's points per axis. Given,
        the result reports the chain's worst rebound over the box (`rebound_worst_box_mm`, its lever
        and speed in diagnostics).
    robust : the law must keep the limit on the whole box: its corners and nominal are LP rows, its
        grid the dense check, a failing point added (`design_law`); with compare, the nominal law's
        and the cycloid's (at its least angle) worst over the same box beside it.
    geometry : hold the lift cam's geometry too (solvers/stop_impact/cam_rows.py; off: nothing
        changes): the cam an oscillating roller follower in a groove, turning counter-clockwise, its
        lever arms and stroke the task's (a_mm, b_mm, stroke_mm), the rise and the mirrored return
        over t; `cam_base_radius_mm`, `cam_roller_radius_mm`, `cam_centre_distance_mm` (cam centre
        to the lever's pivot), `cam_dwell_deg` (upper dwell) [mm, deg]; the limits
        `max_pressure_angle_deg` (rise and return) and the pitch curve's radius of curvature >=
        roller radius + `min_curvature_margin_mm` on both walls of the groove; at most
        `geometry_steps` sequential LPs per phase angle (LIMIT naming them when the exact geometry
        still breaks a limit). Values: max_pressure_angle_{rise,return}_deg, min_radius_of_curvature_mm,
        min_concave_radius_mm, pressure_angle_binds, curvature_binds (1: within BINDS_WITHIN of its limit).

    Whatever `geometry`, the law's cam for the shop (`cam_shape.law_cam`: the lift cam of the cam_*
    settings, the lever's arms and stroke, rise and return over t): arrays `cam_pitch_x_mm` ...,
    diagnostics `cam` (its status, chordal errors, rise-start direction, geometry); the DXF writer
    draws from them.
    """
    task.need("stroke_mm", "amplitude_limit_mm")
    task.need_effect("cam_drive")
    if band_low_rpm > band_high_rpm:
        raise SettingError(f"band_low_rpm={band_low_rpm} > band_high_rpm={band_high_rpm}: the band is empty",
                           key="band_low_rpm")
    if phase_from_deg >= phase_to_deg:
        raise SettingError(f"phase_from_deg={phase_from_deg} >= phase_to_deg={phase_to_deg}: empty bracket",
                           key="phase_from_deg")
    box = box or LeverBox()
    clock = Clock()
    bounds = {"max_velocity_mm_per_rad": max_velocity_mm_per_rad,
              "max_acceleration_mm_per_rad2": max_acceleration_mm_per_rad2, "max_jerk_mm_per_rad3": max_jerk_mm_per_rad3}
    band = (band_low_rpm, band_high_rpm)
    common = dict(coefficients=coefficients, continuity=continuity, sample_speeds=sample_speeds,
                  dense_step_rpm=dense_step_rpm, bounds=bounds)
    if robust and not box.trivial:
        common |= {"box": box, "rounds": ROBUST_ROUNDS}
    cam = None
    if geometry:
        try:        # the lever's arms and stroke, the rise and return over the bracket's top
            shape = CamShape(base_radius_mm=cam_base_radius_mm, roller_radius_mm=cam_roller_radius_mm,
                             stroke_mm=task.stroke_mm, rise_deg=phase_to_deg, return_deg=phase_to_deg,
                             dwell_deg=cam_dwell_deg, centre_distance_mm=cam_centre_distance_mm, a_mm=task.a_mm,
                             b_mm=task.b_mm, follower="oscillating", closure="groove")
        except ModelError as exc:       # named as the setting (or the task's parameter) at fault
            key = f"cam_{exc.key}" if exc.key in ("base_radius_mm", "roller_radius_mm", "centre_distance_mm",
                                                  "dwell_deg") else "phase_to_deg" if exc.key == "rise_deg" else exc.key
            raise SettingError(f"geometry: the lift cam cannot be made ({key}): {exc}", key=key) from None
        cam = CamGeometry(shape, max_pressure_angle_deg, min_curvature_margin_mm, geometry_steps)
        common["geometry"] = cam
    limit = task.amplitude_limit_mm
    build = Clock()
    linear_lever(coefficients, continuity)
    clock.build_s = build.elapsed()
    values, diagnostics = {}, {}
    if objective == "least_phase":
        design, t_deg, search = _least_phase(task, band, phase_from_deg, phase_to_deg, phase_tol_deg, common)
        diagnostics |= {"bisection_steps": search["steps"], "windows_given_up": search["given_up"],
                        "windows_retried": search["retried"]}
        if design.status is not Status.SOLVED:
            if cam is not None and design.status is Status.INFEASIBLE:
                design = _least_angle(design, cam, task, t_deg, bounds, coefficients, continuity, values)
            return _unsolved(design, values, diagnostics, clock, t_deg, limit, task, band, dense_step_rpm)
    else:
        task.need("t_deg")
        t_deg = task.t_deg
        design = design_law(task, t_deg, band, objective=objective, **common)
        diagnostics |= {"windows_given_up": design.given_up, "windows_retried": design.retried}
        if design.status is not Status.SOLVED:
            return _unsolved(design, values, diagnostics, clock, t_deg, limit, task, band, dense_step_rpm)
    law = design.law
    lever = linear_lever(coefficients, continuity)
    values |= {"t_deg": t_deg, "lp_value": design.value, "window_xi": design.window_xi, "lps": float(design.lps)}
    if cam is not None:
        values |= _geometry_values(cam, design)
        diagnostics["geometry_binds"] = [k for k in ("pressure_angle", "curvature") if values[f"{k}_binds"]]
    if objective == "least_phase":
        values["t_min_synthesized_deg"] = t_deg
        if robust and not box.trivial:
            values["t_min_robust_deg"] = t_deg
        t_cyc = _library_least_phase(task, "cycloidal", band, phase_from_deg, phase_to_deg, phase_tol_deg,
                                     dense_step_rpm) if compare else None
        if t_cyc is not None:
            values["t_min_cycloidal_deg"] = t_cyc
            values["phase_gain_percent"] = 100.0 * (1.0 - t_deg / t_cyc)
    dense = band_speeds(band, dense_step_rpm)
    pred = predicted_rebounds_mm(task, law, t_deg, dense, lever=lever)
    worst = int(np.argmax([p[0] for p in pred]))
    values |= {"rebound_max_predicted_mm": pred[worst][0], "rebound_max_speed_rpm": float(dense[worst])}
    xi = np.linspace(0, 1, 2001)
    S, dS, ddS, dddS = law.values(xi)
    t_rad = math.radians(t_deg)
    H_mm = task.stroke_mm
    values |= {"peak_velocity_mm_per_rad": float(np.abs(dS).max()) * H_mm / t_rad,
               "peak_acceleration_mm_per_rad2": float(np.abs(ddS).max()) * H_mm / t_rad**2,
               "peak_jerk_mm_per_rad3": float(np.abs(dddS).max()) * H_mm / t_rad**3}
    arrays = _analogues(law, xi, H_mm, t_rad, "") | {"speed_rpm": dense.astype(float),
                                                     "rebound_predicted_mm": np.array([p[0] for p in pred])}
    if compare:          # the library laws' analogues at the same t, and the cycloid's rebound against speed
        for name in LAWS:
            arrays |= _analogues(name, xi, H_mm, t_rad, f"{name}_")
        arrays["rebound_cycloidal_predicted_mm"] = np.array(
            [p[0] for p in predicted_rebounds_mm(task, "cycloidal", t_deg, dense, lever=lever)])
    status, message, warnings = Status.SOLVED, f"{objective}: {law} at t = {t_deg:.6g} deg", ()
    if verify:
        nominal = box.nominal(task)
        check_points = sorted(set(design.speeds) | {nominal + (float(dense[worst]),)})
        if robust and not box.trivial:      # and the box's worst (the robust LP's dense check was over it)
            check_points = sorted(set(check_points) | {box_worst_point(task, law, t_deg, band, box, dense_step_rpm,
                                                                       lever)[1]})
        worst_gap, chains = 0.0, []
        for point in check_points:
            n, each = point[2], dataclasses.replace(LeverBox.lever(task, point[:2]), law=law)
            try:
                chain = float(rebound_amplitude_mm(each, n, t_deg))
            except RollerLeftCam as exc:
                return clock.result(Status.INACCURATE, values, message=f"the chain at {_points_text([point])}: {exc}",
                                    arrays=arrays, diagnostics=diagnostics)
            own = predicted_rebounds_mm(LeverBox.lever(task, point[:2]), law, t_deg, [n], lever=lever)[0][0]
            worst_gap = max(worst_gap, abs(chain - own) / max(limit, 1e-300))
            chains.append(chain)
            if point[:2] == nominal:
                values[f"rebound_chain_mm_{speed_tag(n)}"] = chain
                values[f"rebound_predicted_mm_{speed_tag(n)}"] = own
        values["chain_rel_diff"] = worst_gap
        values["rebound_max_chain_mm"] = max(chains)
        diagnostics["chain_points"] = [list(p) + [c] for p, c in zip(check_points, chains)]
        if worst_gap > agreement_rel:
            status = Status.INACCURATE
        over = values["rebound_max_chain_mm"] - limit
        if objective != "least_rebound" and over > agreement_rel * limit:
            status = Status.INACCURATE
            message += f"; the chain's rebound exceeds amplitude_limit_mm by {over:.3g} mm"
        message += (f"; the chain (CVODES + eq. (2)) agrees with the linear prediction to {worst_gap:.1e} of the "
                    f"limit at {len(check_points)} points (tolerance {agreement_rel:g})")
    if not box.trivial:
        diagnostics |= box_values(task, law, t_deg, band, box, dense_step_rpm, lever, values, "")
        if robust and compare and objective == "least_phase":
            _beside(task, band, phase_from_deg, phase_to_deg, phase_tol_deg, common, box, values, diagnostics)
    if compare:
        _compare(task, law, t_deg, sorted({p[2] for p in design.speeds if p[:2] == box.nominal(task)}), values)
    sampled = [p[2] if box.trivial else list(p) for p in design.speeds]
    shop, said = law_cam(task, law, t_deg, {"base_radius_mm": cam_base_radius_mm, "roller_radius_mm": cam_roller_radius_mm,
                                            "centre_distance_mm": cam_centre_distance_mm, "dwell_deg": cam_dwell_deg})
    return clock.result(status, values, message=message,
                        arrays=arrays | shop, diagnostics=diagnostics | said | {"sampled_speeds_rpm": sampled,
                                                                  "law_knots": list(law.knots),
                                                                  "law_coefficients": list(law.coefficients)},
                        warnings=warnings)


BINDS_WITHIN = (0.1, 0.1)       # a geometry limit binds when the exact value is this near it [deg, mm]


def _geometry_values(cam, design):
    """The synthesised law's cam: pressure angles, least radii, which geometry limit binds."""
    check = design.geometry
    return {"max_pressure_angle_rise_deg": check.pressure_rise_deg,
            "max_pressure_angle_return_deg": check.pressure_return_deg,
            "min_radius_of_curvature_mm": check.convex_mm, "min_concave_radius_mm": check.concave_mm,
            "pressure_angle_binds": float(check.excess["pressure_angle"] >= -BINDS_WITHIN[0]),
            "curvature_binds": float(check.excess["curvature"] >= -BINDS_WITHIN[1]),
            "geometry_steps_taken": float(design.geometry_steps)}


def _least_angle(design, cam, task, t_deg, bounds, coefficients, continuity, values):
    """No law at the bracket's top: the least largest pressure angle the sequential steps reach
    there, the lever left out (`cam_rows.least_pressure_angle`, from the cycloid's fit), named in
    the message and `least_pressure_angle_deg`."""
    lever = linear_lever(coefficients, continuity)
    (s0, B), *_ = lever.kin
    rise = lever.rise
    c0 = np.linalg.lstsq(B[np.flatnonzero(rise)].toarray(), law_values("cycloidal", lever.xi[rise])[0] - s0[rise], rcond=None)[0]
    least, steps = least_pressure_angle(cam, lever, t_deg, c0,
                                        lambda rows: kinematic_rows(rows, lever, t_deg, task.stroke_mm, bounds))
    values["least_pressure_angle_deg"] = least
    if least <= cam.max_pressure_angle_deg:
        return design
    return dataclasses.replace(
        design, violated=tuple(dict.fromkeys(design.violated + ("pressure_angle",))),
        message=design.message + f"; the least largest pressure angle a law of the space reaches at t = {t_deg:g} deg "
                                 f"(the lever left out, {steps} sequential LPs) is {least:.4g} deg > "
                                 f"max_pressure_angle_deg={cam.max_pressure_angle_deg:g}")


def _least_phase(task, band, lo, hi, tol, common):
    """The least t with the least rebound over the band <= limit: regula falsi (Illinois) on
    r*(t) - limit, r*(t) the least-rebound LP's value, assumed to fall as t grows (stated, not
    proven); a t with no law at all (below the kinematic minimum, or every window given up by
    HiGHS: counted, the search moves up) is a bisection step. The speeds the dense check added and
    the best window are carried to the next t."""
    limit = task.amplitude_limit_mm
    state = {"samples": None, "around": None, "steps": 0, "given_up": 0, "retried": 0}

    def excess(t):
        d = design_law(task, t, band, objective="least_rebound", samples=state["samples"], around=state["around"],
                       dense_bar_mm=limit, explain=False, **common)
        state["steps"] += 1
        state["given_up"] += d.given_up
        state["retried"] += d.retried
        if d.status is Status.SOLVED:
            state["samples"], state["around"] = d.speeds, d.window_xi
            return d.value - limit, d
        # no window solved, some given up (LIMIT): no law found here, the search moves up (counted)
        return (math.inf if d.status in (Status.INFEASIBLE, Status.LIMIT) and d.law is None else math.nan), d
    f_hi, best = excess(hi)
    if not f_hi <= 0:
        if best.status is Status.INFEASIBLE:         # no law even at the bracket's top: name what binds
            best = design_law(task, hi, band, objective="least_rebound", dense_bar_mm=limit, **common)
        if best.status is Status.SOLVED:
            best = dataclasses.replace(best, status=Status.INFEASIBLE, violated=("amplitude",),
                                       message=f"no law keeps amplitude_limit_mm={limit:g} over {band[0]:g}-{band[1]:g} "
                                               f"rpm even at t = {hi:g} deg: the best is {best.value:.4g} mm")
        return best, hi, state
    f_lo, low = excess(lo)
    if f_lo <= 0:                                   # the bracket's bottom already keeps it
        return low, lo, state
    side = 0
    while hi - lo > tol:
        if math.isfinite(f_lo):
            mid = hi - f_hi * (hi - lo) / (f_hi - f_lo)
            mid = min(max(mid, lo + 0.1 * tol), hi - 0.1 * tol)
        else:
            mid = 0.5 * (lo + hi)
        f_mid, d = excess(mid)
        if math.isnan(f_mid):
            return d, mid, state
        if f_mid <= 0:
            hi, f_hi, best = mid, f_mid, d
            if side == -1 and math.isfinite(f_lo):
                f_lo /= 2                           # Illinois: the stale end's weight halved
            side = -1
        else:
            lo, f_lo = mid, f_mid
            if side == 1:
                f_hi /= 2
            side = 1
        if -f_hi <= ROOT_FTOL * limit or state["steps"] >= MAX_PHASE_STEPS:   # r*(hi) is the limit to the LP's digits
            break
    return best, hi, state


def box_worst_point(task, law, t_deg, band, box, step, lever):
    """(the linear model's largest rebound [mm], its point (frequency factor, zeta, rpm)) of `law`
    at `t_deg` over the box's grid of levers and its band (the margin added), every `step` rpm."""
    keys = box.grid_keys(task)
    levers = {key: LeverBox.lever(task, key) for key in keys}
    return _dense_worst(levers, keys, law, t_deg, band_speeds(box.band(band), step), lever)


def box_values(task, law, t_deg, band, box, step, lever, values, suffix):
    """The chain's worst rebound of `law` at `t_deg` over the box: at every lever of its grid, the
    chain (CVODES rise, eq. (2)) at the speed where the linear model's rebound is largest (the two
    agree within the synthesis' agreement_rel: the status criterion). Sets
    `rebound_worst_box<suffix>_mm` and `box_roller_left<suffix>` (levers of the grid on which the
    roller leaves its cam there: no rebound, a failure of its own, counted, not in the worst);
    returns the diagnostics naming where they are."""
    dense = band_speeds(box.band(band), step)
    worst, where, left = -math.inf, None, []
    for key in box.grid_keys(task):
        each = LeverBox.lever(task, key)
        pred = [p[0] for p in predicted_rebounds_mm(each, law, t_deg, dense, lever=lever)]
        n = float(dense[int(np.argmax(pred))])
        chain = float(rebound_amplitude_mm(dataclasses.replace(each, law=law), n, t_deg, lost=math.nan))
        if math.isnan(chain):
            left.append(list(key) + [n])
        elif chain > worst:
            worst, where = chain, key + (n,)
    values |= {f"rebound_worst_box{suffix}_mm": worst, f"box_roller_left{suffix}": float(len(left))}
    return {f"rebound_worst_box{suffix}_at": where and {"frequency_factor": where[0], "zeta": where[1],
                                                        "speed_rpm": where[2]},
            f"box_roller_left{suffix}_at": left,
            "box": {"frequency_factor": list(box.frequency), "zeta": list(box.zeta or box._zetas(task)),
                    "band_rpm": list(box.band(band)), "grid": box.grid}}


def _beside(task, band, lo, hi, tol, common, box, values, diagnostics):
    """The nominal law (synthesised without the box) and the cycloid at its least angle, each with
    its worst rebound over the same box (`rebound_worst_box_nominal_mm`, `..._cycloidal_mm`)."""
    lever = linear_lever(common["coefficients"], common["continuity"])
    nominal = {k: v for k, v in common.items() if k not in ("box", "rounds")}
    design, t_nom, _ = _least_phase(task, band, lo, hi, tol, nominal)
    if design.status is Status.SOLVED:
        values["t_min_nominal_deg"] = t_nom
        diagnostics |= box_values(task, design.law, t_nom, band, box, common["dense_step_rpm"], lever, values,
                                   "_nominal")
    if "t_min_cycloidal_deg" in values:
        diagnostics |= box_values(task, "cycloidal", values["t_min_cycloidal_deg"], band, box,
                                   common["dense_step_rpm"], lever, values, "_cycloidal")


def _library_least_phase(task, law, band, lo, hi, tol, step):
    """The least t in [lo, hi] at which the library `law` keeps the limit over the band (the linear
    model's rebound at every `step` rpm; bisection, as for the synthesised law); None if not at hi."""
    dense = band_speeds(band, step)
    limit = task.amplitude_limit_mm

    def ok(t):
        return max(p[0] for p in predicted_rebounds_mm(task, law, t, dense)) <= limit
    if not ok(hi):
        return None
    while hi - lo > tol:
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if ok(mid) else (mid, hi)
    return hi


def _unsolved(design, values, diagnostics, clock, t_deg, limit, task=None, band=None, step=5.0):
    """No law: the status and what binds; with a best law (the limit missed), the best achievable
    rebound over the band and the speed where it is set."""
    values = values | {"t_deg": t_deg}
    if design.law is not None and task is not None:
        dense = band_speeds(band, step)
        pred = [p[0] for p in predicted_rebounds_mm(task, design.law, t_deg, dense)]
        worst = int(np.argmax(pred))
        values |= {"rebound_best_mm": pred[worst], "rebound_best_speed_rpm": float(dense[worst])}
    return clock.result(design.status, values, message=design.message, violated=design.violated,
                        diagnostics=diagnostics)


def _compare(task, law, t_deg, speeds, values):
    """The synthesised law beside the four library laws at the same t and speeds (the chain)."""
    for name, each in [("synthesized", law)] + [(k, k) for k in LAWS]:
        other = dataclasses.replace(task, law=each)
        for n in speeds:
            rise = follow_cam(other, n, t_deg)
            tag = f"{name}_{{}}_{speed_tag(n)}"
            if rise.status is Status.SOLVED:
                values[tag.format("rebound_mm")] = float(rebound_amplitude_mm(other, n, t_deg))
            values[tag.format("dynamic_error_mm")] = rise.dynamic_error_mm
        ddS = law_values(each, np.linspace(0, 1, 2001))[2]
        values[f"{name}_peak_acceleration_mm_per_rad2"] = float(np.abs(ddS).max()) * task.stroke_mm / math.radians(
            t_deg)**2


def _analogues(law, xi, H_mm, t_rad, prefix):
    """The law's travel of C and its analogues against the cam angle over the rise [mm, mm/rad^k]."""
    S, dS, ddS = law_values(law, xi)[:3]
    return {f"{prefix}phi_deg": xi * math.degrees(t_rad), f"{prefix}s_mm": S * H_mm,
            f"{prefix}ds_dphi_mm_per_rad": dS * H_mm / t_rad, f"{prefix}d2s_dphi2_mm_per_rad2": ddS * H_mm / t_rad**2}


