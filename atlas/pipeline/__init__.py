"""From a config to a file: config, run identity, per-point preparation, tiles, the sweep."""
