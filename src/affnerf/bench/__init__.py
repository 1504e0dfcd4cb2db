"""Benchmarks: each measures medians over repeats on the current machine and writes tagged JSON results."""
