"""Index tables of the state layout for all elements at once.

``generated/rod_layout.py`` (the one source of the layout) answers per element: the
index of node i's position, segment i's quaternion, ... A model build asks it for every
node and segment of six tables, and statics for two more: ~400 Python calls at N = 50
(~0.5 ms of every `kvrod simulate`). The layout is affine in the cell index past cell 0
(``cell_start(i) = c0 + c (i - 1)`` for i >= 1, the same field offsets in every such
cell), so three calls give a whole table; :func:`layout_table` is that, and the tests
compare it with the per-element calls (tests/runtime/test_layout_tables.py).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np


def layout_table(at: Callable[[int], int], first: int, last: int) -> np.ndarray:
    """``[at(i) for i in range(first, last + 1)]`` (int array) from at most three calls:
    ``at(0)`` where the range starts at cell 0, ``at(1)`` and ``at(2)``, which fix the
    affine layout of the cells i >= 1 (``at`` e.g. ``lambda i: L.node_phi(i, B)``)."""
    if last < first:
        return np.zeros(0, dtype=int)
    if first < 0:
        raise ValueError(f"layout_table: first = {first} must be >= 0")
    i = np.arange(first, last + 1)
    out = np.empty(i.size, dtype=int)
    later = i >= 1
    if later.any():
        a1 = at(1)
        out[later] = a1 + (at(2) - a1) * (i[later] - 1)
    if not later.all():
        out[~later] = at(0)
    return out


def layout_blocks(at: Callable[[int], int], first: int, last: int, width: int
                  ) -> np.ndarray:
    """(last - first + 1, width) indices: :func:`layout_table` plus ``0 .. width - 1``
    along each row (a node's 3 position components, a segment's 4 quaternion ones)."""
    return layout_table(at, first, last)[:, None] + np.arange(width)
