"""The lift lever striking its stop (paper 004): frequencies, impact, rebound, amplitude law."""
from mechopt.solvers.stop_impact.lever import (impact_forces, linearise_amplitude,
                                                 natural_frequencies, operating_point, rebound)

__all__ = ["natural_frequencies", "impact_forces", "rebound", "linearise_amplitude", "operating_point"]
