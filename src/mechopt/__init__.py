"""mechopt: formal optimisation models for machine mechanisms, from published studies."""
