"""The six-node (quadratic) triangle of the section's mesh: its shape functions and their
derivatives in area coordinates (used by the mesh for its node placement checks and by
the finite-element assembly)."""

from __future__ import annotations

import numpy as np


def shape_functions(L: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Six-node triangle: N (nq, 6) and dN/d(xi, eta) (nq, 6, 2) at area coordinates L
    (nq, 3), with xi = L2, eta = L3; nodes: corners, then midsides 0-1, 1-2, 2-0."""
    l1, l2, l3 = L[:, 0], L[:, 1], L[:, 2]
    N = np.column_stack([l1 * (2 * l1 - 1), l2 * (2 * l2 - 1), l3 * (2 * l3 - 1),
                         4 * l1 * l2, 4 * l2 * l3, 4 * l3 * l1])
    dl = np.array([[-1.0, -1.0], [1.0, 0.0], [0.0, 1.0]])     # dL_k / d(xi, eta)
    dN_dl = np.stack([
        np.column_stack([4 * l1 - 1, 0 * l1, 0 * l1]),
        np.column_stack([0 * l1, 4 * l2 - 1, 0 * l1]),
        np.column_stack([0 * l1, 0 * l1, 4 * l3 - 1]),
        np.column_stack([4 * l2, 4 * l1, 0 * l1]),
        np.column_stack([0 * l1, 4 * l3, 4 * l2]),
        np.column_stack([4 * l3, 0 * l1, 4 * l1])], axis=1)     # (nq, 6, 3)
    return N, dN_dl @ dl
