"""Scene files (TOML), one per published setting: data only, read by `mechopt.scene`."""

if __name__ != "mechopt.cases":      # `import cases` from the repository root: a second, different copy
    raise ImportError(f"{__name__}: this folder is the package mechopt.cases; import mechopt.cases "
                      "(installed by `pip install -e .`), not cases from the repository root")
