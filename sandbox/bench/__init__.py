"""Benchmarks behind ``python -m sandbox bench`` (medians of repeated runs, in one process)."""
