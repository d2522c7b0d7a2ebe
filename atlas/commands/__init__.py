"""Commands beyond the sweep: one orbit, the essay's figures, the benchmarks."""
