"""Benchmarks (JSON + Markdown in bench/results/); not tests."""
