"""The lift cam's geometry as rows of the synthesis' window LP: pressure angle and radius of
curvature, linearised around the current law and solved in a short sequence of LPs.

The cam is a `models.cam_shape.CamShape` (an oscillating roller follower in a groove, turning
counter-clockwise: the pitch curve takes the sense of rotation in), cut to the law over
the rise and, mirrored, over the return (1 - S over the same angle, as the shop's drawing of a
synthesised law reads the lift cam's return). At a node xi the pressure angle phi and the pitch
curve's signed curvature kappa = 1 / rho (> 0 convex) are smooth functions of (S, S', S'') there
alone (Norton, *Design of Machinery*, ch. 8: pressure angle, radius of curvature, undercutting);
the law being S = s0 + B c, each is linearised around the current coefficients c_k:

    q(c) ~ q_k + (g_S B + g_D D + g_A A)(c - c_k),

g the partial derivatives (central differences in S, S', S'', step DIFF_STEP, of the general
roller cam `models.cam_geometry.roller_cam`, pointwise in them, whose pressure angle is signed:
smooth where |phi| has a corner at 0). The rows: |phi| <= max_pressure_angle_deg at the rise's and
the return's nodes (every NODE_SPACING_XI); kappa <= 1 / (roller radius + min_curvature_margin_mm) (the inner wall not undercut, with
the margin) and, for a groove, -kappa <= the same (its outer wall, on the concave parts). Curvature
is held rather than rho, which is infinite at every inflection.

Sequential convex steps (a trust-region SLP: Nocedal & Wright, *Numerical Optimization*, 2nd ed.,
Sec. 18.5 on trust regions for SQP/SLP): the law without these rows first; while its exact check
breaks a limit, each step solves the window LP with the rows linearised
at c_k and |c - c_k| <= TRUST (each coefficient) and checks its law exactly on the whole cam
(`models.cam_shape.summarise`, 7200 cam angles, extremes polished; the independent check is the polygon test's); the
exact excess over its limit of a law the linearised rows gave (their error, and the nodes'
spacing) is added to that family's back-off for the next step. It stops when the exact
geometry holds within GEOMETRY_TOL_DEG / GEOMETRY_TOL_MM (SOLVED), when a step's LP has no law
(INFEASIBLE: none within the trust region around c_k meets the linearised rows, which a
non-convex set does not prove for the whole space: said so), or after `steps` steps (LIMIT naming
the count). Nothing here asserts a global optimum.
"""
import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from mechopt.kit.result import Status
from mechopt.models.cam_geometry import roller_cam
from mechopt.models.cam_shape import CamShape, pitch, roller_centre, summarise
from mechopt.solvers.stop_impact.window_rows import HeldLP, Rows

__all__ = ["CamGeometry", "GeometryCheck", "TRUST", "least_pressure_angle"]

DIFF_STEP = 1e-6            # central-difference step in S, S', S'' (each O(1) over the rise)
NODE_SPACING_XI = 0.01      # the rows' nodes over the rise and the return
DROP_REL = 1e-8             # a row's entries below this share of its largest are dropped (rounding noise)
TRUST = 0.05                # |c - c_k| per coefficient in one step (S in [0, 1])
GEOMETRY_TOL_DEG = 0.02     # the exact pressure angle may exceed its limit by this and hold
GEOMETRY_TOL_MM = 0.02      # the exact radius of curvature may fall short of its bound by this
SENSE = 1                   # the lift cam turns counter-clockwise (cam_shape.ORIENTATION = -SENSE)
CHECK_SAMPLES = 7200        # cam angles of the exact check (summarise)


@dataclass(frozen=True)
class GeometryCheck:
    """The exact geometry of one law on its cam: largest pressure angle on the rise and the
    return [deg], least convex and concave pitch radius of curvature [mm], and each family's
    excess over its limit (pressure angle [deg], curvature [mm short of the bound]; <= 0 holds)."""
    pressure_deg: float
    pressure_rise_deg: float
    pressure_return_deg: float
    convex_mm: float
    concave_mm: float
    excess: dict

    def holds(self) -> bool:
        return (self.excess["pressure_angle"] <= GEOMETRY_TOL_DEG
                and self.excess["curvature"] <= GEOMETRY_TOL_MM)


@dataclass(frozen=True)
class CamGeometry:
    """The lift cam a synthesised law is cut to (its `CamShape` with the rise and return at the
    phase angle set per t by `at`), the limits, and the step limit of the sequential LPs."""
    shape: CamShape
    max_pressure_angle_deg: float
    min_curvature_margin_mm: float
    steps: int

    def at(self, t_deg: float) -> CamShape:
        """The cam with its rise and (mirrored) return over `t_deg`."""
        return dataclasses.replace(self.shape, rise_deg=t_deg, return_deg=t_deg,
                                   max_pressure_angle_deg=self.max_pressure_angle_deg)

    @property
    def least_radius_mm(self) -> float:
        return self.shape.roller_radius_mm + self.min_curvature_margin_mm

    def check(self, law, t_deg: float) -> GeometryCheck:
        """The law's exact geometry on its cam (`summarise`) and each family's excess."""
        shape = self.at(t_deg)
        fn = _callable(law)
        s = summarise(shape, fn, samples=CHECK_SAMPLES)
        rise = self._phase_pressure(shape, fn, "rise")
        back = self._phase_pressure(shape, fn, "return")
        concave = s.min_concave_radius_mm if shape.closure == "groove" else math.inf
        short = max(self.least_radius_mm - s.min_convex_radius_mm, self.least_radius_mm - concave)
        return GeometryCheck(s.max_pressure_angle_deg, rise, back, s.min_convex_radius_mm, s.min_concave_radius_mm,
                             {"pressure_angle": s.max_pressure_angle_deg - self.max_pressure_angle_deg,
                              "curvature": short})

    @staticmethod
    def _phase_pressure(shape, fn, phase):
        """The largest pressure angle over one phase on a fine grid [deg] (which phase sets it)."""
        theta = _angles(shape, np.linspace(0.0, 1.0, 4001)[1:-1], phase)
        return float(np.degrees(pitch(shape, theta, fn).pressure_rad.max()))

    def linearised(self, lever, c_k, t_deg, backoff):
        """[(family, G, upper)]: rows G c <= upper of the pressure angle (rad) and the scaled
        curvature ((r + margin) kappa <= 1) at the nodes, linearised at the free coefficients c_k,
        each family's limit lowered by its `backoff` (the excess the exact check found)."""
        shape = self.at(t_deg)
        xi_all = lever.xi
        nodes = np.flatnonzero((xi_all > 0) & (xi_all < 1))
        nodes = nodes[::max(1, round(NODE_SPACING_XI / lever.step))]
        (s0, B), (d0, D), (a0, A), _ = lever.kin
        B, D, A = (np.asarray(M[nodes].todense()) for M in (B, D, A))
        S, dS, ddS = s0[nodes] + B @ c_k, d0[nodes] + D @ c_k, a0[nodes] + A @ c_k
        xi = xi_all[nodes]
        rows = []
        scale = self.least_radius_mm
        for phase in ("rise", "return"):
            theta = _angles(shape, xi, phase)
            (phi, kappa), grads = _quantities(shape, theta, S, dS, ddS)
            G = {name: sum(grads[name][j][:, None] * M for j, M in enumerate((B, D, A))) for name in ("phi", "kappa")}
            for M in G.values():        # entries HiGHS would drop after scaling: dropped here, said
                M[np.abs(M) < DROP_REL * np.abs(M).max(axis=1, keepdims=True)] = 0.0
            lim_phi = math.radians(self.max_pressure_angle_deg) - math.radians(backoff.get("pressure_angle", 0.0))
            for sign in (1.0, -1.0):          # |phi| <= limit, phi signed
                rows.append(("pressure_angle", sign * G["phi"], lim_phi - sign * (phi - G["phi"] @ c_k)))
            lim_k = 1.0 - scale * backoff.get("curvature_kappa", 0.0)
            rows.append(("curvature", scale * G["kappa"], lim_k - scale * kappa + scale * G["kappa"] @ c_k))
            if shape.closure == "groove":
                rows.append(("curvature", -scale * G["kappa"], lim_k + scale * kappa - scale * G["kappa"] @ c_k))
        return rows


def _callable(law):
    """A law as `summarise` takes it: xi -> (S, S', S'')."""
    return lambda x: tuple(law.values(x)[:3])


def _angles(shape, xi, phase):
    """Cam angles [rad] of the rise's fraction xi on the rise, or on the (mirrored) return."""
    b1, dw = math.radians(shape.rise_deg), math.radians(shape.dwell_deg)
    return xi * b1 if phase == "rise" else b1 + dw + xi * math.radians(shape.return_deg)


def _quantities(shape, theta, S, dS, ddS):
    """((phi [rad], signed; kappa [1/mm]) at the angles, given S, S', S'' at them; and their
    central differences in S, S', S'': {"phi": (g_S, g_D, g_A), "kappa": ...}). From the general
    roller cam (models/cam_geometry.roller_cam, counter-clockwise: SENSE), whose signed pressure
    angle is smooth where |phi| (cam_shape.pitch's) has a corner at 0."""
    def at(S_, dS_, ddS_):
        R, dR, ddR, moving = roller_centre(shape, theta, lambda x: (S_, dS_, ddS_))
        cam = roller_cam(theta, R, dR, ddR, moving, shape.roller_radius_mm, SENSE)
        return cam.pressure_rad, 1.0 / cam.pitch_radius_mm
    base = at(S, dS, ddS)
    grads = {"phi": [], "kappa": []}
    for j in range(3):
        up, down = [S, dS, ddS], [S, dS, ddS]
        up[j], down[j] = up[j] + DIFF_STEP, down[j] - DIFF_STEP
        hi, lo = at(*up), at(*down)
        grads["phi"].append((hi[0] - lo[0]) / (2 * DIFF_STEP))
        grads["kappa"].append((hi[1] - lo[1]) / (2 * DIFF_STEP))
    return base, grads


def least_pressure_angle(geometry: CamGeometry, lever, t_deg, c_start, kinematic):
    """(the least largest pressure angle [deg] these steps find for a law of the space at `t_deg`,
    steps taken): the lever left out, the kinematic rows `kinematic(rows)` kept, min p over
    phi <= p at the nodes by the same trust-region steps from `c_start`, each law checked exactly.
    A local search on a non-convex set: what the steps reach, not a proven least."""
    c, best, step = np.asarray(c_start, float), math.inf, 0
    for step in range(1, geometry.steps + 1):
        rows = Rows()
        rows.column("c", c.size, c - TRUST, c + TRUST)
        rows.column("p", cost=1.0)
        kinematic(rows)
        lim = math.radians(geometry.max_pressure_angle_deg)
        for family, G, upper in geometry.linearised(lever, c, t_deg, {}):
            if family == "pressure_angle":           # the same rows with p in place of the limit
                rows.le(family, [("c", G), ("p", -np.ones(G.shape[0]))], upper - lim)
        held = HeldLP(rows, movable=[])
        status, x, _ = held.solve([])
        if status is not Status.SOLVED:
            break
        got = geometry.check(lever.basis.law(held.block(x, "c")), t_deg).pressure_deg
        if got >= best - 1e-3:
            best = min(best, got)
            break
        best, c = got, held.block(x, "c")
    return best, step
