"""Numerics: turn a model's question into a formal problem, solve it, return a `Result`."""

if __name__ != "mechopt.solvers":      # `import solvers` from the repository root: a second, different copy
    raise ImportError(f"{__name__}: this folder is the package mechopt.solvers; import mechopt.solvers "
                      "(installed by `pip install -e .`), not solvers from the repository root")
