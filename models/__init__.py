"""Physics and geometry of the mechanisms: frozen parameter sets and pure functions.

Nothing here calls an optimiser or touches the disk; `solvers` builds problems from these.
"""

if __name__ != "mechopt.models":      # `import models` from the repository root: a second, different copy
    raise ImportError(f"{__name__}: this folder is the package mechopt.models; import mechopt.models "
                      "(installed by `pip install -e .`), not models from the repository root")
