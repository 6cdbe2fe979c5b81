"""The lift lever striking its stop (paper 004, eq. (2)).

* `response`      the first rebound three independent ways: closed form, quadrature, CVODES.
* `law`           the exact amplitude law a(t, n), vectorised, and its tangent for the LP.
* `contact`       an event-driven check with the stiffness switching at the plate.
* `entry_points`  what scenes name: `natural_frequencies`, `impact_forces`, `rebound`
                  (method="closed_form" | "quadrature" | "ode"), `linearise_amplitude`,
                  `operating_point`, `cam_dynamics`.
* `cam_follower`  the lift cam's rise with the elastic lever (Fig. 4): contact with the plate,
                  approach velocity, dynamic errors, the roller's contact force.
"""
from mechopt.solvers.stop_impact.entry_points import (
                                                      cam_dynamics,
                                                      impact_forces,
                                                      linearise_amplitude,
                                                      natural_frequencies,
                                                      operating_point,
                                                      rebound,
)

__all__ = ["cam_dynamics", "impact_forces", "linearise_amplitude", "natural_frequencies", "operating_point", "rebound"]
