"""``np.unique`` and ``np.union1d`` of 1-D arrays without ``numpy.ma``.

NumPy 2's ``np.unique`` (and so ``union1d``, ``setdiff1d``, ``intersect1d``) imports
``numpy.ma`` on first use, 15-25 ms: a tenth of a short ``kvrod simulate`` process of a
generalized Maxwell rod, where one ``union1d`` of three relaxation times paid it.
"""

from __future__ import annotations

import numpy as np


def sorted_unique(a: np.ndarray) -> np.ndarray:
    """The sorted distinct values of the 1-D array ``a`` (``np.unique(a)``)."""
    a = np.sort(np.asarray(a).ravel())
    keep = np.ones(a.size, bool)
    np.not_equal(a[1:], a[:-1], out=keep[1:])
    return a[keep]


def sorted_union(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The sorted distinct values of two 1-D arrays (``np.union1d(a, b)``)."""
    return sorted_unique(np.concatenate((np.ravel(a), np.ravel(b))))
