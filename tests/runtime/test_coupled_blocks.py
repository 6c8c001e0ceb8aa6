"""Newton systems of coupled band blocks (runtime/solvers/native/blocks.c): the Woodbury
solve over the blocks' own factorisations against a dense solve of the same matrix."""

from __future__ import annotations

import numpy as np
import pytest

from runtime.solvers.native.loader import load
from runtime.solvers.protocols import dense_to_band

pytestmark = pytest.mark.skipif(load() is None, reason="needs a C compiler")


def _random_band(rng, n: int, kl: int, ku: int) -> np.ndarray:
    A = np.zeros((n, n))
    for d in range(-kl, ku + 1):
        idx = np.arange(max(0, -d), min(n, n - d))
        A[idx, idx + d] = rng.normal(size=idx.size)
    A += np.diag(4.0 + rng.random(n)) * np.sign(rng.normal(size=n))
    return A


@pytest.mark.parametrize("seed", range(12))
def test_woodbury_solve_matches_a_dense_solve(seed):
    from runtime.solvers.native.blocks import Block, CoupledBlocks

    rng = np.random.default_rng(seed)
    sizes = rng.integers(5, 30, size=rng.integers(1, 5))
    blocks, off = [], 0
    for n in sizes:
        kl, ku = int(rng.integers(0, 4)), int(rng.integers(0, 4))
        blocks.append(Block(off, int(n), kl, ku))
        off += int(n)
    N = off
    m = int(rng.integers(0, 24))
    rows = rng.choice(N, size=min(m, N), replace=False)
    coupling = {int(r): rng.choice(N, size=int(rng.integers(1, 6)), replace=False).tolist()
                for r in rows}
    cb = CoupledBlocks(blocks, coupling)
    J = np.zeros((N, N))
    for b, ab in zip(blocks, cb.ab, strict=True):
        A = _random_band(rng, b.n, b.kl, b.ku)
        dense_to_band(A, b.kl, b.ku, ab)
        J[b.offset:b.offset + b.n, b.offset:b.offset + b.n] = A
    for k, (r, c) in enumerate(cb.entries):
        cb.ev[k] = 30.0 * rng.normal()       # large: the capacitance needs pivoting
        J[r, c] += cb.ev[k]
    assert np.allclose(cb.dense(), J)
    assert cb.factor() == 0
    b = rng.normal(size=N)
    x = cb.solve(b.copy())
    assert np.allclose(J @ x, b, rtol=0, atol=1e-9 * np.abs(b).max() * np.linalg.cond(J))


def test_a_singular_coupled_matrix_is_reported():
    """Two 1 x 1 blocks [1] and [1] coupled to [[1, 1], [1, 1]]: singular only through the
    couplings, which the capacitance sees."""
    from runtime.solvers.native.blocks import Block, CoupledBlocks

    cb = CoupledBlocks([Block(0, 1, 0, 0), Block(1, 1, 0, 0)], {0: [1], 1: [0]})
    cb.ab[0][0, 0] = cb.ab[1][0, 0] = 1.0
    cb.ev[:] = 1.0
    assert cb.factor() > 0


@pytest.mark.parametrize("seed", range(6))
def test_dynamic_couplings_add_to_the_fixed_ones(seed):
    """Rows that change from one factorisation to the next (contact pairs), some repeating
    a fixed coupling row: the solve against the dense matrix, twice with other rows."""
    from runtime.solvers.native.blocks import Block, CoupledBlocks

    rng = np.random.default_rng(100 + seed)
    blocks = [Block(0, 20, 2, 3), Block(20, 15, 1, 1), Block(35, 12, 3, 2)]
    N = 47
    coupling = {3: [30, 40], 25: [1, 44]}
    cb = CoupledBlocks(blocks, coupling, dynamic_rows=12, dynamic_entries=60)
    base = np.zeros((N, N))
    for b in blocks:
        A = _random_band(rng, b.n, b.kl, b.ku)
        base[b.offset:b.offset + b.n, b.offset:b.offset + b.n] = A
    for _ in range(2):
        J = base.copy()
        for b, ab in zip(blocks, cb.ab, strict=True):
            dense_to_band(base[b.offset:b.offset + b.n, b.offset:b.offset + b.n], b.kl,
                          b.ku, ab)
        for k, (r, c) in enumerate(cb.entries):
            cb.ev[k] = 30.0 * rng.normal()
            J[r, c] += cb.ev[k]
        rows = [3] + rng.choice(N, size=int(rng.integers(1, 10)), replace=False).tolist()
        entries = []
        for r in rows:
            cols = rng.choice(N, size=int(rng.integers(1, 5)), replace=False)
            row = [(int(c), float(20.0 * rng.normal())) for c in cols]
            for c, v in row:
                J[r, c] += v
            entries.append(row)
        cb.set_dynamic(rows, entries)
        assert np.allclose(cb.dense(), J)
        assert cb.factor() == 0
        b = rng.normal(size=N)
        x = cb.solve(b.copy())
        assert np.allclose(J @ x, b, rtol=0, atol=1e-9 * np.abs(b).max() * np.linalg.cond(J))
