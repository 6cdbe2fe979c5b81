"""The kit: what every layer (models, solvers, the spine) may import, and which imports nothing of
mechopt outside this folder: errors, the build cache, the solver Result, settings' ranges, Ctrl-C
inside a solve, HiGHS's quiet construction (tests/spine/test_layout.py holds the rule)."""
