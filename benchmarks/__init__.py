"""Development code: benchmarks (`make bench`), evaluation helpers and figure scripts (not installed)."""
