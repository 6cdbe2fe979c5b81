"""Shared test settings: property tests draw the same examples on every run, so CI cannot flake."""
from hypothesis import settings

settings.register_profile("mechopt", derandomize=True, database=None, deadline=None)
settings.load_profile("mechopt")
