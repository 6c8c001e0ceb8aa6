"""The condensed Newton solve (kinematic rows eliminated: v by phi' = v, p by
p' = 1/2 p*(0, Omega)) equals the solve with the full band LU, on the rod's own iteration
matrices J = dF/dy + cj dF/dy' at random states, for several ends, a Maxwell rod and a
range of cj; and it is smaller. The rod's condensed matrix is block tridiagonal in its
cells and takes the block LU path (for every end and material); hand-made systems that
are not block tridiagonal take the band path; singular matrices are reported."""

from __future__ import annotations

import ctypes
import re

import numpy as np
import pytest

from runtime.solvers.native.band import band_solve
from runtime.solvers.native.condensed import CondensedNewton
from runtime.solvers.native.loader import load
from runtime.solvers.native.relaxation import RelaxationBlock
from tests.rods import MAXWELL, random_state, rod_model, with_internal_strains

pytestmark = pytest.mark.skipif(load() is None, reason="no C compiler")

ENDS = [dict(), dict(end="clamped"), dict(start="pinned", end="pinned"),
        dict(start="free", end="clamped"), dict(start="free", end="free")]


def _rod_system_at(kw, cj, seed=2, N=9):
    """A rod model, its J at cj and a random state (band), the generator, the state."""
    rng = np.random.default_rng(seed)
    m = rod_model(N, **kw)
    y = random_state(m, rng)
    if m.branches:
        y = with_internal_strains(m, y, rng)
    yp = rng.standard_normal(m.n)
    ab = np.zeros((m.ldab, m.n), order="F")
    m.jacobian_band(0.0, y, yp, cj, ab)
    return m, ab, rng, y, yp


def _rod_system(kw, cj, seed=2, N=9):
    return _rod_system_at(kw, cj, seed, N)[:3]


def _dense(ab, kl, ku):
    """The matrix of band storage ``ab`` (rows kl .. 2 kl + ku)."""
    n = ab.shape[1]
    A = np.zeros((n, n))
    for j in range(n):
        for i in range(max(0, j - ku), min(n, j + kl + 1)):
            A[i, j] = ab[kl + ku + i - j, j]
    return A


def _fused_update_reference(A, qrows, b, scale, dcj):
    """The correction the fused Newton update applies, written out densely: the kept
    and kinematic unknowns x from the Schur complement of the factorised A (its
    relaxation diagonal D) with the right-hand side at the current cj's diagonal
    D + dcj, the relaxation unknowns q from their own rows at that diagonal for the
    applied (scaled) dx: ``d_q = (b_q - A[q, x] d_x) / (D + dcj)``."""
    n = A.shape[0]
    Q = np.asarray(qrows)
    X = np.setdiff1d(np.arange(n), Q)
    D = np.diag(A)[Q]
    Dc = D + dcj
    S = A[np.ix_(X, X)] - A[np.ix_(X, Q)] @ (A[np.ix_(Q, X)] / D[:, None])
    dx = scale * np.linalg.solve(S, b[X] - A[np.ix_(X, Q)] @ (b[Q] / Dc))
    d = np.empty(n)
    d[X] = dx
    d[Q] = (b[Q] - A[np.ix_(Q, X)] @ dx) / Dc
    return d


@pytest.mark.parametrize("kw", ENDS + [dict(tau=None, **MAXWELL)])
def test_condensed_solve_equals_the_full_solve(kw):
    rng = np.random.default_rng(2)
    m = rod_model(9, **kw)
    cond = CondensedNewton.build(m, m.n, m.kl, m.ku, m.ldab)
    # v and p eliminated by the kinematic rows, a Maxwell rod's internal strains by their
    # relaxation rows: phi and Omega are kept, as for a Kelvin-Voigt rod
    assert cond is not None and cond.nc == 3 * (m.N + 1) + 3 * m.N
    assert cond.relaxation_eliminated == (2 * m.N + 1 if m.branches else 0)
    assert 2 * cond.klc + cond.kuc + 1 < m.ldab
    for cj in (1e1, 3e3, 1e6):
        y = random_state(m, rng)
        if m.branches:
            y = with_internal_strains(m, y, rng)
        yp = rng.standard_normal(m.n)
        ab = np.zeros((m.ldab, m.n), order="F")
        m.jacobian_band(0.0, y, yp, cj, ab)
        b = rng.standard_normal(m.n)
        full, info = band_solve(ab.copy(order="F"), m.kl, m.ku, b)
        ab[:m.kl] = np.nan          # the LU's fill-in room: not part of J, never read
        assert cond.factor(ab) == 0
        x = cond.solve(ab, b)
        assert info == 0
        np.testing.assert_allclose(x, full, rtol=1e-9, atol=1e-11 * np.abs(full).max())


@pytest.mark.parametrize("kw", ENDS + [dict(tau=None, **MAXWELL),
                                       dict(tau=None, start="pinned", end="clamped", **MAXWELL)])
@pytest.mark.parametrize("N", [1, 2, 9])
def test_rods_take_the_block_path(kw, N):
    m = rod_model(N, **kw)
    cond = CondensedNewton.build(m, m.n, m.kl, m.ku, m.ldab)
    assert cond.block_tridiagonal, cond.band_reason
    assert cond.band_reason is None
    kv6 = cond._keep["kv6"]
    assert kv6.size == N + 1
    # the fixed-size kernels serve the interior cells (not the ends, whose neighbours
    # differ), of a Maxwell rod too: its internal strains are eliminated first
    assert kv6[2:-1].sum() == (N - 2 if N > 2 else 0)
    assert cond.relaxation_reason is None
    assert cond.relaxation_eliminated == (2 * N + 1 if m.branches else 0)
    assert not kv6[[0, 1, -1]].any()
    # the kinematic blocks phi' = v are recognised as diagonal
    assert CondensedNewton(cond._lib, m.n, m.kl, m.ku, m.ldab,
                                  m.condensation_blocks()).block_tridiagonal is False
    diag = cond._keep["diag"]
    assert diag.sum() == N + 1 and diag[::2].all()    # v blocks (sorted: v0, p1, v1, ...)


@pytest.mark.parametrize("kw", [dict(), dict(tau=None, **MAXWELL)])
def test_block_and_band_paths_agree_at_length(kw):
    """N = 40: many interior (fixed-size) cells; both paths against the full band LU."""
    m, ab, rng = _rod_system(kw, 1e2, seed=5, N=40)
    block = CondensedNewton.build(m, m.n, m.kl, m.ku, m.ldab)
    band = CondensedNewton(block._lib, m.n, m.kl, m.ku, m.ldab, m.condensation_blocks())
    assert block.block_tridiagonal and not band.block_tridiagonal
    b = rng.standard_normal(m.n)
    full, info = band_solve(ab.copy(order="F"), m.kl, m.ku, b)
    assert info == 0
    for cond in (block, band):
        assert cond.factor(ab) == 0
        np.testing.assert_allclose(cond.solve(ab, b), full, rtol=1e-9,
                                   atol=1e-11 * np.abs(full).max())


def test_fused_newton_update_matches_solve_then_update():
    """kv_cond_newton (solve, scaling, weighted norm and updates fused per cell) equals
    the solve followed by the update in NumPy."""
    m, ab, rng = _rod_system({}, 3e2, seed=7, N=12)
    cond = CondensedNewton.build(m, m.n, m.kl, m.ku, m.ldab)
    assert cond.factor(ab) == 0
    res = rng.standard_normal(m.n)
    ewt = rng.uniform(0.5, 2.0, m.n)
    ee, yy, ypw = (rng.standard_normal(m.n) for _ in range(3))
    scale, cj = 0.7, 3e2
    d = scale * cond.solve(ab, res)
    want = (np.sqrt(np.mean((d * ewt) ** 2)), d, ee - d, yy - d, ypw - cj * d)
    r, e, y_, yp_ = res.copy(), ee.copy(), yy.copy(), ypw.copy()
    P = lambda a: a.ctypes.data  # noqa: E731
    nrm = cond._lib.kv_cond_newton(cond.ptr, P(ab), P(r), scale, P(ewt), P(e), P(y_),
                                   P(yp_), cj)
    np.testing.assert_allclose(nrm, want[0], rtol=1e-12)
    for got, ref in zip((r, e, y_, yp_), want[1:], strict=True):
        np.testing.assert_allclose(got, ref, rtol=1e-12, atol=1e-14 * np.abs(ref).max())


def test_raw_entry_points_for_an_including_step_loop():
    """cond_factor_raw / cond_solve_raw (no floating-point mode change) are exported and
    give what kv_cond_factor / kv_cond_solve give."""
    m, ab, rng = _rod_system({}, 1e3)
    cond = CondensedNewton.build(m, m.n, m.kl, m.ku, m.ldab)
    lib = cond._lib
    raw_f, raw_s = lib.cond_factor_raw, lib.cond_solve_raw
    raw_f.argtypes, raw_f.restype = [ctypes.c_void_p, ctypes.c_void_p], ctypes.c_int
    raw_s.argtypes, raw_s.restype = [ctypes.c_void_p] * 3, None
    b = rng.standard_normal(m.n)
    assert raw_f(cond.ptr, ab.ctypes.data) == 0
    x = b.copy()
    raw_s(cond.ptr, ab.ctypes.data, x.ctypes.data)
    assert cond.factor(ab) == 0
    np.testing.assert_array_equal(x, cond.solve(ab, b))


# ---- hand-made systems ---------------------------------------------------------------

def _cell_system(sizes, rng, far=False):
    """A random system on cells of the given sizes, each starting with a kinematic block:
    rows 0..e-1 of a cell involve only its columns 0..e-1 (eliminated) and e..2e-1
    (kept), e = 2 or 3; every other row couples to the cells next to it (and, with far,
    one row also to the cell after next). The kept part of each cell's diagonal block is
    a scaled cyclic permutation (zero diagonal) plus small noise, and that of cell 4 has
    neither noise nor couplings (its diagonal block in the condensed matrix is the
    permutation itself): their elimination has to pivot. Returns the dense matrix, its
    band storage (NaN in the fill-in room, which is not part of the matrix), kl, ku, the
    blocks, the cells and the pattern."""
    starts = np.concatenate(([0], np.cumsum(sizes)[:-1]))
    n = int(np.sum(sizes))
    A = np.zeros((n, n))
    blocks = []
    for c, (s, z) in enumerate(zip(starts, sizes, strict=True)):
        e = 2 + c % 2
        lo, hi = starts[max(c - 1, 0)], starts[c + 2] if c + 2 < len(sizes) else n
        if c != 4:
            A[s + e:s + z, lo:hi] = 1e-3 * rng.standard_normal((z - e, hi - lo))
        P = np.roll(np.eye(z - e), 1, axis=1)
        A[s + e:s + z, s + e:s + z] += 4.0 * P
        A[s:s + e, s:s + e] = 2.0 * np.eye(e) + 0.3 * rng.standard_normal((e, e))
        A[s:s + e, s + e:s + 2 * e] = rng.standard_normal((e, e))
        blocks.append((int(s), e, int(s), int(s + e), e))
    if far:
        c = len(sizes) // 2
        A[starts[c] + sizes[c] - 1, starts[c + 2] + sizes[c + 2] - 1] = 0.5
    rows, cols = np.nonzero(A)
    kl, ku = int((rows - cols).max()), int((cols - rows).max())
    ab = np.zeros((2 * kl + ku + 1, n), order="F")
    ab[kl + ku + rows - cols, cols] = A[rows, cols]
    pattern = ab != 0
    ab[:kl] = np.nan
    return A, ab, kl, ku, blocks, [int(s) for s in starts], pattern


SIZES = [5, 7, 6, 8, 7, 7, 5, 9, 6]


@pytest.mark.parametrize("sizes", [SIZES, [8, 9] * 4])
def test_hand_made_block_tridiagonal_system_takes_the_block_path(sizes):
    """Cells of various sizes (the generic kernels) with pivoting inside the blocks; and
    cells of 6 kept unknowns each that are not the rod's (other blocks)."""
    rng = np.random.default_rng(11)
    A, ab, kl, ku, blocks, cells, pattern = _cell_system(sizes, rng)
    lib = load()
    cond = CondensedNewton(lib, A.shape[0], kl, ku, ab.shape[0], blocks, cells=cells,
                                  pattern=pattern)
    assert cond.block_tridiagonal, cond.band_reason
    assert not cond._keep["kv6"].any()
    b = rng.standard_normal(A.shape[0])
    assert cond.factor(ab) == 0
    np.testing.assert_allclose(cond.solve(ab, b), np.linalg.solve(A, b), rtol=1e-10,
                               atol=1e-12)


@pytest.mark.parametrize("case", ["no cells", "far coupling", "no pattern", "cell splits a block"])
def test_systems_that_are_not_block_tridiagonal_take_the_band_path(case):
    rng = np.random.default_rng(12)
    A, ab, kl, ku, blocks, cells, pattern = _cell_system(SIZES, rng, far=case == "far coupling")
    kw = dict(cells=cells, pattern=pattern)
    if case == "no cells":
        kw = dict(pattern=pattern)
    elif case == "no pattern":            # the band alone spans more than a cell each way
        kw = dict(cells=cells)
    elif case == "cell splits a block":
        kw = dict(cells=[0] + [c + 1 for c in cells[1:]], pattern=pattern)
    cond = CondensedNewton(load(), A.shape[0], kl, ku, ab.shape[0], blocks, **kw)
    assert not cond.block_tridiagonal
    assert cond.band_reason
    b = rng.standard_normal(A.shape[0])
    assert cond.factor(ab) == 0
    np.testing.assert_allclose(cond.solve(ab, b), np.linalg.solve(A, b), rtol=1e-10,
                               atol=1e-12)


def test_a_pattern_contradicting_the_blocks_is_refused():
    rng = np.random.default_rng(13)
    A, ab, kl, ku, blocks, cells, pattern = _cell_system(SIZES, rng)
    pattern[kl + ku + 0 - 6, 6] = True           # row 0 (a kinematic row) and column 6
    with pytest.raises(ValueError, match="outside the block"):
        CondensedNewton(load(), A.shape[0], kl, ku, ab.shape[0], blocks,
                               cells=cells, pattern=pattern)


# ---- singular matrices ---------------------------------------------------------------

@pytest.mark.parametrize("kw", [dict(), dict(tau=None, **MAXWELL)])
def test_singular_matrices_are_reported(kw):
    m, ab, _ = _rod_system(kw, 1e3)
    cond = CondensedNewton.build(m, m.n, m.kl, m.ku, m.ldab)
    assert cond.block_tridiagonal
    cs = cond._keep["cs"]
    kv = m.kl + m.ku
    # a kept row of cell 4 (Omega's first row: a momentum balance) vanishes: D_4 singular
    i = int(m.omega_index[3][0])
    j = np.arange(max(0, i - m.kl), min(m.n, i + m.ku + 1))
    bad = ab.copy(order="F")
    bad[kv + i - j, j] = 0.0
    info = cond.factor(bad)
    assert cs[4] < info <= cs[5]
    # a non-finite entry
    bad = ab.copy(order="F")
    bad[kv, int(m.phi_index[5][1])] = np.nan
    assert cond.factor(bad) != 0
    # a singular kinematic block: the rows phi' = v lose v
    bad = ab.copy(order="F")
    v0 = int(m.v_index[6][0])
    r0 = int(m.phi_index[6][0])
    for q in range(3):
        bad[kv + r0 + np.arange(3) - (v0 + q), v0 + q] = 0.0
    assert cond.factor(bad) == -1
    # and a good matrix factorises again afterwards
    assert cond.factor(ab) == 0


def test_singular_hand_made_system_is_reported_on_the_block_path():
    rng = np.random.default_rng(14)
    A, ab, kl, ku, blocks, cells, pattern = _cell_system(SIZES, rng)
    cond = CondensedNewton(load(), A.shape[0], kl, ku, ab.shape[0], blocks,
                                  cells=cells, pattern=pattern)
    assert cond.block_tridiagonal
    # a kept row of cell 3 vanishes (and so does its row of the condensed matrix): D_3
    # is exactly singular (as with LAPACK, only an exactly zero pivot is reported)
    r = cells[3] + 5
    bad = ab.copy(order="F")
    j = np.arange(max(0, r - ku), min(A.shape[0], r + kl + 1))
    bad[kl + ku + r - j, j] = 0.0
    cs = cond._keep["cs"]
    info = cond.factor(bad)
    assert cs[3] < info <= cs[4]
    _, band_info = band_solve(bad.copy(order="F"), kl, ku, np.ones(A.shape[0]))
    assert band_info > 0


# ---- relaxation blocks (the second stage) ------------------------------------------------

def _relaxation_system(ncell, rng, channels=3, terms=1, bad=None):
    """A random system of ``ncell`` cells, each: a kinematic block (rows 0..2 involve
    columns 0..2, eliminated, and 3..5, kept), 3 more kept unknowns (6..8) and two
    relaxation blocks of ``terms`` x ``channels`` unknowns (rows diagonal in them) with
    the structure of RelaxationBlock (the rows of a strain are multiples of one row by
    the terms' rates, its columns multiples of one column by the terms' moduli; strain 1
    of every second block has no moduli, so its columns are zero): a "segment" block
    whose rows involve the kept columns 3..5 of the cell and of the cell before and the
    eliminated column 0 of the cell, involved by the kept rows of both cells; and a
    "joint" block whose rows involve the eliminated columns of the cell and the next,
    involved by the kept rows of both (the rod's pattern). ``bad``: "offdiagonal" (a
    relaxation row involves another unknown of its block), "far" (a relaxation row
    involves a column two cells away). Returns as _cell_system, and the relaxation
    blocks."""
    q_size = channels * terms
    z = 9 + 2 * q_size
    n = ncell * z
    A = np.zeros((n, n))
    blocks, relax = [], []
    for c in range(ncell):                       # kept rows: nearest-neighbour couplings
        s = c * z
        kept = np.r_[s + 3:s + 9]
        A[s:s + 3, s:s + 3] = 2.0 * np.eye(3) + 0.3 * rng.standard_normal((3, 3))
        A[s:s + 3, s + 3:s + 6] = rng.standard_normal((3, 3))
        blocks.append((s, 3, s, s + 3, 3))
        lo, hi = max(c - 1, 0) * z, min(c + 2, ncell) * z
        A[kept[:, None], np.arange(lo, hi)] = 1e-2 * rng.standard_normal((6, hi - lo))
        A[kept, kept] += 4.0
    for c in range(ncell):                       # relaxation rows and columns: D dq + ...
        s = c * z
        kept = np.r_[s + 3:s + 9]
        qs, qj = s + 9, s + 9 + q_size
        src_s = [s + 3, s + 4, s + 5, s] + ([s - z + 3, s - z + 4, s - z + 5] if c else [])
        rows_s = np.r_[kept, kept - z] if c else kept
        src_j = [s, s + 1, s + 2] + ([s + z, s + z + 1, s + z + 2] if c + 1 < ncell else [])
        rows_j = np.r_[kept, kept + z] if c + 1 < ncell else kept
        for q0, src, rows in ((qs, src_s, rows_s), (qj, src_j, rows_j)):
            A[q0:q0 + q_size, :] = 0.0
            A[:, q0:q0 + q_size] = 0.0
            u = np.arange(q0, q0 + q_size)
            A[u, u] = rng.uniform(1.0, 3.0, q_size)
            rates = np.repeat(rng.uniform(0.5, 2.0, terms), channels)
            moduli = rng.uniform(-2.0, 2.0, (terms, channels))
            if channels > 1 and len(relax) % 2:
                moduli[:, 1] = 0.0
            E = rng.standard_normal((channels, len(src)))         # -dstrain/dx
            G = rng.standard_normal((rows.size, channels))
            A[q0:q0 + q_size, src] = rates[:, None] * np.tile(E, (terms, 1))
            A[rows[:, None], u] = np.tile(G, (1, terms)) * moduli.ravel()
            relax.append(RelaxationBlock(q0, channels, rates, moduli.ravel()))
    if bad == "offdiagonal":
        q0 = relax[3].offset
        A[q0, q0 + 1] = 0.5
    elif bad == "far":
        q0 = relax[2].offset
        A[q0, 3 * z + 4] = 0.5
    rows, cols = np.nonzero(A)
    kl, ku = int((rows - cols).max()), int((cols - rows).max())
    ab = np.zeros((2 * kl + ku + 1, n), order="F")
    ab[kl + ku + rows - cols, cols] = A[rows, cols]
    pattern = ab != 0
    ab[:kl] = np.nan
    return A, ab, kl, ku, blocks, [c * z for c in range(ncell)], pattern, relax


@pytest.mark.parametrize("channels,terms", [(3, 1), (2, 2), (3, 3), (4, 2)])
def test_relaxation_blocks_are_eliminated_on_a_hand_made_system(channels, terms):
    """Relaxation blocks of several shapes (the literal 3 strains and the generic
    kernels), their sources kept and eliminated unknowns in two cells: the condensed
    system keeps 6 unknowns per cell, and its solve, the fused Newton update and the
    dense solve of the full matrix agree."""
    rng = np.random.default_rng(21)
    A, ab, kl, ku, blocks, cells, pattern, relax = _relaxation_system(7, rng, channels,
                                                                      terms)
    cond = CondensedNewton(load(), A.shape[0], kl, ku, ab.shape[0], blocks, cells=cells,
                           pattern=pattern, relaxation_blocks=relax)
    assert cond.block_tridiagonal and cond.relaxation_reason is None
    assert cond.relaxation_eliminated == len(relax) and cond.nc == 6 * 7
    cjf = 5.0                                   # the cj the matrix stands for
    assert cond.factor(ab, cjf) == 0
    b = rng.standard_normal(A.shape[0])
    want = np.linalg.solve(A, b)
    np.testing.assert_allclose(cond.solve(ab, b), want, rtol=1e-10, atol=1e-12)
    qrows = np.concatenate([np.arange(r.offset, r.offset + r.size) for r in relax])
    P = lambda a: a.ctypes.data  # noqa: E731
    # at the factorised cj with scale 1: the Newton correction J^-1 b; at another cj
    # (IDA's scale 2 / (1 + cj / cj_f)): the relaxation rows hold at the current cj
    for cj, scale in ((cjf, 1.0), (4.0, 2.0 / (1.0 + 4.0 / cjf)), (6.5, 0.7)):
        ewt = rng.uniform(0.5, 2.0, A.shape[0])
        ee, yy, ypw = (rng.standard_normal(A.shape[0]) for _ in range(3))
        r, e, y_, yp_ = b.copy(), ee.copy(), yy.copy(), ypw.copy()
        nrm = cond._lib.kv_cond_newton(cond.ptr, P(ab), P(r), scale, P(ewt), P(e), P(y_),
                                       P(yp_), cj)
        d = _fused_update_reference(A, qrows, b, scale, cj - cjf)
        if cj == cjf:
            np.testing.assert_allclose(d, want, rtol=1e-10, atol=1e-12)
        A_now = A.copy()
        A_now[qrows, qrows] += cj - cjf
        np.testing.assert_allclose((A_now @ r)[qrows], b[qrows], rtol=1e-10, atol=1e-12)
        np.testing.assert_allclose(nrm, np.sqrt(np.mean((d * ewt) ** 2)), rtol=1e-10)
        for got, ref in zip((r, e, y_, yp_), (d, ee - d, yy - d, ypw - cj * d),
                            strict=True):
            np.testing.assert_allclose(got, ref, rtol=1e-10, atol=1e-12)


@pytest.mark.parametrize("bad,why", [("offdiagonal", "not diagonal"),
                                     ("far", "not neighbours|beyond|window")])
def test_relaxation_blocks_that_do_not_qualify_stay_kept(bad, why):
    """A relaxation row that is not diagonal in its block, or whose fill would reach two
    cells away: the blocks stay kept unknowns (said why), and the solve is still right."""
    rng = np.random.default_rng(22)
    A, ab, kl, ku, blocks, cells, pattern, relax = _relaxation_system(6, rng, bad=bad)
    cond = CondensedNewton(load(), A.shape[0], kl, ku, ab.shape[0], blocks, cells=cells,
                           pattern=pattern, relaxation_blocks=relax)
    assert cond.relaxation_eliminated == 0
    assert re.search(why, cond.relaxation_reason), cond.relaxation_reason
    assert cond.factor(ab) == 0
    b = rng.standard_normal(A.shape[0])
    np.testing.assert_allclose(cond.solve(ab, b), np.linalg.solve(A, b), rtol=1e-9,
                               atol=1e-11)


def test_a_singular_relaxation_block_is_reported():
    rng = np.random.default_rng(23)
    A, ab, kl, ku, blocks, cells, pattern, relax = _relaxation_system(5, rng)
    cond = CondensedNewton(load(), A.shape[0], kl, ku, ab.shape[0], blocks, cells=cells,
                           pattern=pattern, relaxation_blocks=relax)
    assert cond.relaxation_eliminated == len(relax)
    q0 = relax[4].offset + 1
    bad = ab.copy(order="F")
    bad[kl + ku, q0] = 0.0                         # its diagonal entry
    assert cond.factor(bad) == -1
    assert cond.factor(ab) == 0


def test_maxwell_rod_with_and_without_relaxation_blocks():
    """The Maxwell rod's internal strains eliminated (6 kept unknowns per cell, the
    fixed-size path) or kept (the path before: 6 + 6B per cell) give the same Newton
    corrections, to rounding; its fused update at a later cj solves the relaxation rows
    at that cj (a dense reference of the update, and J formed there)."""
    m, ab, rng, y, yp = _rod_system_at(dict(tau=None, **MAXWELL), 3e2, seed=9, N=12)
    with_q = CondensedNewton.build(m, m.n, m.kl, m.ku, m.ldab)
    kept = CondensedNewton(with_q._lib, m.n, m.kl, m.ku, m.ldab, m.condensation_blocks(),
                           cells=m.condensation_cells(), pattern=m.band_pattern())
    assert with_q.relaxation_eliminated == 2 * m.N + 1 and kept.relaxation_eliminated == 0
    assert with_q.nc == 6 * m.N + 3 and kept.nc == (6 + 6 * m.branches) * m.N + 3 + 3 * m.branches
    assert with_q._keep["kv6"].sum() == m.N - 2 and not kept._keep["kv6"].any()
    b = rng.standard_normal(m.n)
    assert with_q.factor(ab, 3e2) == 0 and kept.factor(ab, 3e2) == 0
    x, x0 = with_q.solve(ab, b), kept.solve(ab, b)
    np.testing.assert_allclose(x, x0, rtol=1e-9, atol=1e-11 * np.abs(x0).max())
    ewt = rng.uniform(0.5, 2.0, m.n)
    ee, yy, ypw = (rng.standard_normal(m.n) for _ in range(3))
    r, e, y_, yp_ = b.copy(), ee.copy(), yy.copy(), ypw.copy()
    P = lambda a: a.ctypes.data  # noqa: E731
    # a later cj (2.4e2 against the factorised 3e2) and IDA's scale for it: the
    # relaxation rows are solved at the current cj (the dense reference, J rebuilt
    # there for the check that they hold)
    cj = 2.4e2
    scale = 2.0 / (1.0 + cj / 3e2)
    nrm = with_q._lib.kv_cond_newton(with_q.ptr, P(ab), P(r), scale, P(ewt), P(e), P(y_),
                                     P(yp_), cj)
    qrows = np.concatenate([np.arange(r.offset, r.offset + r.size)
                            for r in m.condensation_relaxation_blocks()])
    d = _fused_update_reference(_dense(ab, m.kl, m.ku), qrows, b, scale, cj - 3e2)
    ab_now = np.zeros_like(ab)
    m.jacobian_band(0.0, y, yp, cj, ab_now)
    np.testing.assert_allclose((_dense(ab_now, m.kl, m.ku) @ r)[qrows], b[qrows],
                               rtol=1e-9, atol=1e-10 * np.abs(b).max())
    np.testing.assert_allclose(nrm, np.sqrt(np.mean((d * ewt) ** 2)), rtol=1e-9)
    for got, ref in zip((r, e, y_, yp_), (d, ee - d, yy - d, ypw - cj * d), strict=True):
        np.testing.assert_allclose(got, ref, rtol=1e-9, atol=1e-11 * np.abs(ref).max())


@pytest.mark.parametrize("kw", [dict(tau=None, **MAXWELL),
                                dict(tau=None, end="clamped", **MAXWELL)])
def test_the_rod_has_the_structure_of_its_relaxation_blocks(kw):
    """The elimination relies on RelaxationBlock's structure; the rod's Jacobian at a
    random state has it: the rows of a strain are the first term's times rate_b/rate_0,
    its columns (outside the block) the reference term's times the moduli's ratio."""
    m, ab, rng, y, yp = _rod_system_at(kw, 7e2, seed=31, N=6)
    J = _dense(ab, m.kl, m.ku)
    coupled = 0
    for r in m.condensation_relaxation_blocks():
        c, u = r.channels, np.arange(r.offset, r.offset + r.size)
        rows = J[u].copy()
        rows[:, u] = 0.0
        cols = J[:, u].copy()
        cols[u, :] = 0.0
        R, M = r.rates.reshape(-1, c), r.moduli.reshape(-1, c)
        assert rows.any() == cols.any()     # none: a clamp's joint (its terms only decay)
        coupled += rows.any()
        for b in range(R.shape[0]):
            for k in range(c):
                np.testing.assert_allclose(rows[b * c + k], R[b, k] / R[0, k] * rows[k],
                                           rtol=1e-14, atol=1e-300)
                ref = int(np.argmax(np.abs(M[:, k])))
                np.testing.assert_allclose(cols[:, b * c + k],
                                           M[b, k] / M[ref, k] * cols[:, ref * c + k],
                                           rtol=1e-14, atol=1e-300)
    assert coupled >= 2 * m.N - 1


@pytest.mark.parametrize("rates,moduli,why", [
    ([1.0, -1.0, 1.0], [1.0, 1.0, 1.0], "positive"),
    ([1.0, 1.0, 1.0, 1.0], [1.0, 1.0, 1.0, 1.0], "B x strains"),
    ([1.0, 1.0, 1.0], [1.0, np.nan, 1.0], "finite")])
def test_relaxation_blocks_without_the_structure_stay_kept(rates, moduli, why):
    """Blocks whose rates or moduli cannot carry the structure are not eliminated, said
    why, and the solve is still J^-1."""
    rng = np.random.default_rng(24)
    A, ab, kl, ku, blocks, cells, pattern, relax = _relaxation_system(4, rng)
    relax[1] = RelaxationBlock(relax[1].offset, 3, np.array(rates, float),
                               np.array(moduli, float))
    cond = CondensedNewton(load(), A.shape[0], kl, ku, ab.shape[0], blocks, cells=cells,
                           pattern=pattern, relaxation_blocks=relax)
    assert cond.relaxation_eliminated == 0
    assert why in cond.relaxation_reason, cond.relaxation_reason
    assert cond.factor(ab) == 0
    b = rng.standard_normal(A.shape[0])
    np.testing.assert_allclose(cond.solve(ab, b), np.linalg.solve(A, b), rtol=1e-9,
                               atol=1e-11)


@pytest.mark.parametrize("kw", [dict(tau=None, **MAXWELL),
                                dict(tau=None, end="clamped", **MAXWELL)])
def test_the_relaxed_jacobian_forms_what_the_factorisation_reads(kw):
    """kvrod_jacobian_band_cells_relaxed (the step loop's Jacobian of a Maxwell rod)
    forms, of the internal strains' rows and columns, the diagonal, the first term's rows
    and the reference columns that CondensedNewton.relaxation_need marks, each entry bit
    for bit as the full Jacobian; the rest of those columns it leaves as it found it
    (NaN here). Factorised from it, every Newton solve equals the full Jacobian's bit
    for bit: a read of an entry it did not form would be NaN."""
    m, ab, rng, y, yp = _rod_system_at(kw, 4e2, seed=5, N=11)
    cond = CondensedNewton.build(m, m.n, m.kl, m.ku, m.ldab)
    need = cond.relaxation_need()
    q = np.zeros(m.n, bool)
    for r in m.condensation_relaxation_blocks():
        q[r.offset:r.offset + r.size] = True
        first = np.arange(r.offset, r.offset + r.channels)
        assert np.all(need[first] & 2) and not np.any(need[r.offset + r.channels:
                                                          r.offset + r.size] & 2)
    assert np.all(need[~q] == 3)
    B = m.branches
    assert 0 < np.count_nonzero(need[q] & 1) <= q.sum() // B     # one term per strain
    assert np.count_nonzero(need[q] & 2) == q.sum() // B
    kern = m.c_kernels()
    fn, set_need = kern.jacobian_cells_relaxed
    set_need(need)
    relaxed = np.full_like(ab, np.nan)
    P = lambda a: a.ctypes.data  # noqa: E731
    proto = ctypes.CFUNCTYPE(ctypes.c_int, ctypes.c_void_p, ctypes.c_double, ctypes.c_void_p,
                             ctypes.c_void_p, ctypes.c_double, ctypes.c_double, ctypes.c_int,
                             ctypes.c_void_p, ctypes.c_int, ctypes.c_int, ctypes.c_int)
    assert proto(fn)(kern.ctx, 0.0, P(y), P(yp), 1.0, 4e2, m.ldab, P(relaxed), 0, 0, m.N) == 0
    full, got = _dense(ab, m.kl, m.ku), _dense(np.where(np.isnan(relaxed), 7.0, relaxed),
                                                m.kl, m.ku)
    band = np.abs(np.subtract.outer(np.arange(m.n), np.arange(m.n)))
    inband = (np.subtract.outer(np.arange(m.n), np.arange(m.n)) <= m.kl) & (
        np.subtract.outer(np.arange(m.n), np.arange(m.n)) >= -m.ku)
    col_full = (need & 1).astype(bool)
    row_full = (need & 2).astype(bool)
    diag = band == 0
    formed = inband & ((col_full[None, :] & row_full[:, None]) | diag)
    assert np.array_equal(got[formed], full[formed])                   # bit for bit
    # rows not needed: zero in the columns that are (cleared, not formed)
    assert not got[inband & col_full[None, :] & ~row_full[:, None] & ~diag].any()
    # columns not needed: untouched off the diagonal
    untouched = inband & ~col_full[None, :] & ~diag
    assert untouched.any() and np.all(got[untouched] == 7.0)
    c_full = CondensedNewton.build(m, m.n, m.kl, m.ku, m.ldab)
    assert c_full.factor(ab, 4e2) == 0 and cond.factor(relaxed, 4e2) == 0
    b = rng.standard_normal(m.n)
    assert np.array_equal(cond.solve(relaxed, b), c_full.solve(ab, b))
    ewt = rng.uniform(0.5, 2.0, m.n)
    outs = []
    for c, a in ((c_full, ab), (cond, relaxed)):
        r, e, yy_, yp_ = b.copy(), *(np.linspace(-1.0, 1.0, m.n) for _ in range(3))
        nrm = c._lib.kv_cond_newton(c.ptr, P(a), P(r), 0.8, P(ewt), P(e), P(yy_), P(yp_),
                                    3.3e2)
        outs.append((nrm, r, e, yy_, yp_))
    assert outs[0][0] == outs[1][0]
    for u, v in zip(outs[0][1:], outs[1][1:], strict=True):
        assert np.array_equal(u, v)
    assert np.isfinite(outs[1][1]).all()
