"""Physics and geometry of the mechanisms: frozen parameter sets and pure functions.

Nothing here calls an optimiser or touches the disk; `solvers` builds problems from these.
"""
