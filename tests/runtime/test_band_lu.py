"""kvrod's band LU (runtime/solvers/bdf_helpers.c, LAPACK's dgbtf2 written out) against
SciPy's LAPACK dgbtrf/dgbtrs and a dense solve, on random band matrices whose pivoting
moves rows (small diagonals), on singular ones, and with the widths of the rod."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.linalg.lapack import dgbtrf

from runtime.solvers.native.band import band_solve
from runtime.solvers.native.loader import load
from runtime.solvers.protocols import band_storage

pytestmark = pytest.mark.skipif(load() is None, reason="no C compiler")


def _band(n: int, kl: int, ku: int, rng, diag: float = 0.01) -> tuple[np.ndarray, np.ndarray]:
    A = np.zeros((n, n))
    for i in range(n):
        for j in range(max(0, i - kl), min(n, i + ku + 1)):
            A[i, j] = rng.standard_normal()
        # small pivots make row interchanges happen; without subdiagonals (no pivoting
        # possible, or a triangular matrix) a dominant diagonal keeps it well conditioned
        A[i, i] = A[i, i] * diag if kl > 0 and ku > 0 else 3.0 + abs(A[i, i])
    ab = band_storage(n, kl, ku)
    for j in range(n):
        for i in range(max(0, j - ku), min(n, j + kl + 1)):
            ab[kl + ku + i - j, j] = A[i, j]
    return A, ab


@pytest.mark.parametrize(("n", "kl", "ku"), [(1, 0, 0), (7, 2, 1), (40, 5, 9), (120, 25, 21),
                                             (30, 0, 3), (30, 4, 0)])
def test_band_lu_matches_lapack_and_solves(n, kl, ku):
    rng = np.random.default_rng(n + kl + ku)
    A, ab = _band(n, kl, ku, rng)
    b = rng.standard_normal(n)
    lapack, piv_l, info_l = dgbtrf(ab.copy(order="F"), kl, ku)
    ours = ab.copy(order="F")
    x, info = band_solve(ours, kl, ku, b)
    assert info == info_l == 0
    np.testing.assert_allclose(ours, lapack, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(A @ x, b, rtol=1e-9, atol=1e-9)
    lib = load()
    ipiv = np.zeros(n, dtype=np.int32)
    prof = np.zeros(2 * n, dtype=np.int32)
    lib.kv_gbtrf(n, kl, ku, ab.ctypes.data, ab.shape[0], ipiv.ctypes.data, prof.ctypes.data)
    np.testing.assert_array_equal(ipiv, piv_l + 1)          # LAPACK's 1-based pivots


def test_singular_band_matrix_reports_the_zero_pivot():
    rng = np.random.default_rng(3)
    A, ab = _band(12, 2, 2, rng)
    ab[:, 5] = 0.0                   # column 6 (1-based) vanishes
    _, info = band_solve(ab, 2, 2, np.ones(12))
    _, _, info_l = dgbtrf(_band(12, 2, 2, np.random.default_rng(3))[1] * (
        np.arange(12) != 5), 2, 2)
    assert info == 6 == info_l
