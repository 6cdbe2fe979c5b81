"""The lift cam driving the lever through an elastic link (paper 004, Fig. 4; Dresig and Vulfson's
one-mass model of a cam mechanism with an elastic follower).

The cam's motion law moves the lever's end C kinematically by s(phi) = H S(xi), xi = phi / t the
fraction of the rise (t the phase angle of operation (3,7), H the stroke at C). The lever bends
between its roller and C with the stiffness c of Fig. 5, so C (reduced mass m) follows

    m x'' + b (x' - s') + c (x - s) = 0,        b = 2 zeta sqrt(c m),

which in the rise's own time xi = Omega tt / t (Omega the shaft speed, tt the time) reads, with
X = x / H, the relative (dynamic) error e = X - S and lambda = omega T, T = t / Omega the rise's
duration, omega = sqrt(c / m):

    e'' = -S''(xi) - 2 zeta lambda e' - lambda^2 e                      ( ' = d/dxi )

After the rise the cam dwells (S = 1). The plate stands `preload_mm` below the cam's end
position: C meets it where X = 1 - preload / H. The roller stays on its cam while the contact
force N = F_closure + m x'' stays >= 0 (the closing spring's force, reacted by the cam).

Laws: the library's (models/cam_laws.py, `mechopt.laws`), each S(xi) written there once; here
its S as a CasADi expression, derivatives by CasADi's AD (the integrators' path, unchanged since
the four laws below lived here). `LAWS` are the four the lift's scenes compare:

================  =======================================  ===========================
law               S(xi)                                    continuity at the ends
================  =======================================  ===========================
cycloidal         xi - sin(2 pi xi) / (2 pi)               acceleration 0, jerk jumps
modified_sine     Kloomok-Muffley, 3 pieces (1/8, 7/8)     acceleration 0, jerk jumps
polynomial_345    10 xi^3 - 15 xi^4 + 6 xi^5               acceleration 0, jerk jumps
harmonic          (1 - cos(pi xi)) / 2                     acceleration jumps (pi^2 / 2)
================  =======================================  ===========================
"""
import math

import numpy as np

from mechopt.kit.cache import memoised
from mechopt.kit.errors import ModelError
from mechopt.models.cam_law import SplineLaw
from mechopt.models.cam_laws import law as library_law

LAWS = ("cycloidal", "modified_sine", "polynomial_345", "harmonic")      # the lift's scenes compare these


def law_displacement(law: str, xi):
    """S(xi), the normalised displacement of the library's motion law `law` over the rise xi in
    [0, 1] (a CasADi expression of the CasADi symbol `xi`)."""
    if isinstance(law, SplineLaw):
        raise ModelError(f"law={law}: a spline law gives S'' (casadi_ddS) and numbers (values), not S as "
                         "an expression", key="law")
    return library_law(law).expression(xi)[0]


@memoised(maxsize=16)
def law_function(law: str) -> "ca.Function":        # noqa: F821  (CasADi imported where used)
    """CasADi function xi -> (S, S', S'') of the law during the rise (derivatives by AD). A
    synthesised `SplineLaw` (models/cam_law.py) gives S'' alone: S and S' come out as 0 (the
    integrators read S'' only; numbers come from `law_values`)."""
    import casadi as ca
    xi = ca.SX.sym("xi")
    if isinstance(law, SplineLaw):
        zero = ca.SX(0)
        return ca.Function("law_spline", [xi], [zero, zero, law.casadi_ddS(xi)], ["xi"], ["S", "dS", "ddS"])
    s = law_displacement(law, xi)
    ds = ca.gradient(s, xi)
    name = f"law_{law}" if isinstance(law, str) and law.isidentifier() else "law_member"   # "scca(0.2, 0.6)"
    return ca.Function(name, [xi], [s, ds, ca.gradient(ds, xi)], ["xi"], ["S", "dS", "ddS"])


def law_values(law: str, xi):
    """(S, S', S'') at the phases `xi` (array), the dwell (S = 1, S' = S'' = 0) past xi = 1 and
    rest (S = 0) before 0: numbers for plots and the scipy reference."""
    xi = np.atleast_1d(np.asarray(xi, dtype=float))
    if isinstance(law, SplineLaw):
        return law.values(xi)[:3]
    inside = np.clip(xi, 0.0, 1.0)
    out = law_function(law).map(xi.size)(inside[None, :])
    s, ds, dds = (np.asarray(v, dtype=float).ravel() for v in out)
    after, before = xi > 1.0, xi < 0.0
    s = np.where(after, 1.0, np.where(before, 0.0, s))
    ds, dds = (np.where(after | before, 0.0, v) for v in (ds, dds))
    return s, ds, dds


def rise_duration_s(speed_rpm, t_deg):
    """T = t / Omega: how long the rise over the phase angle t [deg] lasts at n [rpm] [s]."""
    return (np.asarray(t_deg, float) * math.pi / 180.0) / (2 * math.pi * np.asarray(speed_rpm, float) / 60.0)


def relative_acceleration(law_s2, e, de, lam, zeta):
    """e'' of the elastic follower in the rise's own time (module docstring); works for numbers
    and CasADi symbols alike."""
    return -law_s2 - 2 * zeta * lam * de - lam * lam * e
