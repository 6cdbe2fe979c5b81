"""The lift lever striking its stop (paper 004, eq. (2)).

* `response`      the first rebound three independent ways: closed form, quadrature, CVODES.
* `law`           the exact amplitude law a(t, n), vectorised, and its tangent for the LP.
* `contact`       an event-driven check with the stiffness switching at the plate.
* `entry_points`  what scenes name: `natural_frequencies`, `impact_forces`, `rebound`
                  (method="closed_form" | "quadrature" | "ode"), `linearise_amplitude`,
                  `operating_point`, `cam_dynamics`.
* `fit`           every root of the chain's calibration (stroke, t) on the published law, and the
                  spread of its predictions over the roots and the damping: `fit_roots`.
* `synthesis`     the lift cam's law synthesised as a spline under the rebound limit over a speed
                  band (LPs in cvxpy), checked by the chain: `synthesise_law`.
* `cam_follower`  the lift cam's rise with the elastic lever (Fig. 4): contact with the plate,
                  approach velocity, dynamic errors, the roller's contact force.
* `cam_shape`     the lift cam for the shop: pitch curve, profile, pressure angle, radius of
                  curvature, undercut, point tables with their chordal error: `cam_profile`
                  (`shape_cam` with any law, e.g. a synthesised one: `law_of(result)`).
"""
from typing import TYPE_CHECKING

from mechopt.kit.lazy import lazy_names

if TYPE_CHECKING:       # for readers and the docs; at run time each name imports its module when used
    from mechopt.solvers.stop_impact.cam_shape import cam_profile, shape_cam
    from mechopt.solvers.stop_impact.entry_points import (
                                                          cam_dynamics,
                                                          impact_forces,
                                                          linearise_amplitude,
                                                          natural_frequencies,
                                                          operating_point,
                                                          rebound,
    )
    from mechopt.solvers.stop_impact.fit import fit_roots
    from mechopt.solvers.stop_impact.synthesis import law_of, synthesise_law

__getattr__, __dir__ = lazy_names(__name__, {
    "cam_shape": ["SHOP_PREFIX", "cam_profile", "shape_cam"], "fit": ["fit_roots"], "synthesis": ["law_of", "synthesise_law"],
    "entry_points": ["cam_dynamics", "impact_forces", "linearise_amplitude", "natural_frequencies",
                     "operating_point", "rebound"]})

__all__ = ["cam_dynamics", "cam_profile", "fit_roots", "impact_forces", "law_of", "linearise_amplitude",
           "natural_frequencies", "operating_point", "rebound", "shape_cam", "synthesise_law"]
