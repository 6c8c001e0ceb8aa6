"""Benchmarks (JSON + Markdown in bench/results/); not tests.

``run_all(quick=False, out_dir=Path("bench/results"))`` runs everything (``python -m bench``).
"""

from __future__ import annotations

from pathlib import Path


def run_all(quick: bool = False, out_dir: Path = Path("bench/results"),
            only: tuple[str, ...] | None = None) -> dict:
    """Run the benchmarks (all, or the sections in ``only``); see :mod:`bench.__main__`."""
    from bench.__main__ import run_all as _run_all

    return _run_all(quick=quick, out_dir=out_dir, only=only)
