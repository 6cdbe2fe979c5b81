"""Scene files (TOML), one per published setting: data only, read by `mechopt.scene`."""
