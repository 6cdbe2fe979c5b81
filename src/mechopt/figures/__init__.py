"""One module per model module (`mechopt.figures.<model module>`), each with `plot(run, out_dir) -> [paths]`."""
