"""The Newton systems of a BDF step condensed by the kinematic rows and, on the block
path, by the relaxation rows (``kv_cond`` in condensed.c; relaxation.py): block
tridiagonal in the rod's cells, else a band LU of the condensed matrix."""

from __future__ import annotations

import ctypes
import math

import numpy as np

from runtime.sorted_sets import sorted_unique

from .loader import load
from .relaxation import _ranges

#: the relaxation blocks' tables (relaxation.py), in the order of ``kv_cond``
_Q_FIELDS = ("q_off", "q_sz", "q_nch", "q_eo", "q_co", "q_so", "q_src", "q_tgt", "q_ao",
             "q_nu", "q_mu", "q_A", "q_dinv", "q_kap", "q_g", "q_dc", "q_kc", "q_gh", "q_cb",
             "q_fk", "q_fl", "q_kb", "q_kco", "q_kcol", "q_kwo", "q_W", "q_bk", "q_bl",
             "q_ucell", "q_ustep")
#: its real-valued ones (the rest int32, q_kwo int64)
_Q_REAL = ("q_nu", "q_mu", "q_A", "q_dinv", "q_kap", "q_g", "q_dc", "q_kc", "q_gh", "q_W")


class _CondStruct(ctypes.Structure):
    """Mirror of ``kv_cond`` in condensed.c."""

    _fields_ = [(name, ctypes.c_int) for name in
                ("n", "kl", "ku", "ldab", "nc", "klc", "kuc", "ldc", "nb")] + [
        (name, ctypes.c_void_p) for name in
        ("e_off", "e_sz", "r_off", "k_off", "k_sz", "keep_row", "keep_col", "row2c",
         "col2c", "G", "Minv", "g", "abc", "ipiv", "prof", "rc", "w_off", "w_r0", "w_nr",
         "W")] + [(name, ctypes.c_int) for name in ("bt", "ncell", "mmax")] + [
        (name, ctypes.c_void_p) for name in
        ("cf", "cs", "cb", "ce", "eo", "fo", "xo", "F", "X", "ge", "T", "rp", "run", "ecol",
         "kv6", "diag")] + [("col0", ctypes.c_int), ("nq", ctypes.c_int)] + [
        (name, ctypes.c_void_p) for name in _Q_FIELDS] + [
        (name, ctypes.c_double) for name in ("q_cjf", "q_rdcj")]


class CondensedNewton:
    """The Newton systems of a BDF step, condensed by eliminating kinematic blocks (see
    ``kv_cond`` in condensed.c): ``factor(ab)`` condenses and factorises the full band
    J (which it leaves intact), ``kv_cond_newton(ptr, ...)`` is ``kv_newton`` through
    those factors.

    ``blocks`` are ``(e_off, e_size, r_off, k_off, k_size)``: rows r_off..+e_size involve
    only the columns e_off..+e_size (eliminated) and k_off..+k_size (kept), e_size <= 4,
    k_size <= 4. Every other row and column is kept; kept rows pair with kept columns in
    index order. Built once per solver; None from :meth:`build` without the C helpers.

    ``cells`` (optional): the first state index of each cell of a partition of the state
    into contiguous ranges, and ``pattern`` (optional): J's structural nonzeros in band
    storage (ldab, n) (default: every position of the band). When every block lies in
    one cell and every kept row of cell k has its structural nonzeros in cells k-1..k+1,
    the condensed matrix is block tridiagonal in the cells and is factorised by a block
    LU over them (``block_tridiagonal`` True; the rod's nearest-neighbour coupling);
    otherwise, or without cells, by the band LU of the condensed band
    (``block_tridiagonal`` False, ``band_reason`` says why).

    ``relaxation_blocks`` (optional, the block path with a pattern only):
    :class:`~runtime.solvers.native.relaxation.RelaxationBlock` ranges of unknowns whose
    rows (the same range) are diagonal in them and otherwise involve only the unknowns of
    the kinematic stage, with the structure of a Maxwell rod's internal strains
    (``relaxation.py``). They are eliminated first, into the rows that involve
    them, when J's pattern shows that their fill stays between neighbouring cells
    (``relaxation_eliminated`` blocks); otherwise they stay kept unknowns
    (``relaxation_reason`` says why).
    """

    def __init__(self, lib, n: int, kl: int, ku: int, ldab: int,
                 blocks: list[tuple[int, int, int, int, int]], cells=None,
                 pattern=None, relaxation_blocks=None) -> None:
        import numpy as np

        self.n = n
        b = np.asarray(blocks, dtype=np.int32).reshape(-1, 5)
        # by position: the blocks of a cell are then consecutive (the block path)
        b = b[np.argsort(b[:, 0], kind="stable")]
        if b.size and (b[:, 1].max() > 4 or b[:, 4].max() > 4):
            raise ValueError("CondensedNewton: blocks of at most 4 unknowns")
        if pattern is not None:
            pattern = np.asarray(pattern)
            if pattern.shape != (ldab, n):
                raise ValueError(f"CondensedNewton: pattern of shape {pattern.shape}, "
                                 f"expected {(ldab, n)}")
        # (i, j): J's structural nonzeros (every band position without a pattern)
        entries = (_band_entries(kl, ku, n, pattern)
                   if pattern is not None or cells is not None else None)
        if pattern is not None:
            _check_block_rows(pattern, kl, ku, b, entries)
        diag = _diagonal_blocks(pattern, kl, ku, b)
        rblocks = sorted(relaxation_blocks or [], key=lambda r: r.offset)
        rq = np.array([(r.offset, r.rates.size) for r in rblocks],
                      dtype=np.int64).reshape(-1, 2)
        self.relaxation_reason: str | None = None
        qt = None
        if len(rq) and (cells is None or pattern is None):
            self.relaxation_reason = "relaxation blocks need the cells and the pattern"
            rq, rblocks = rq[:0], []
        while True:
            keep_row, keep_col, row2c, col2c = _kept(n, b, rq)
            bt, self.band_reason = _cell_tables(n, kl, ku, b, keep_row, keep_col, col2c, cells,
                                                pattern, diag, rq, entries)
            if len(rq) and bt is not None:
                qt, self.relaxation_reason = _relaxation(n, b, rblocks, bt, keep_row,
                                                         col2c, entries)
            elif len(rq):
                self.relaxation_reason = "the condensed matrix is not block tridiagonal"
            if not len(rq) or qt is not None:
                break
            rq, rblocks = rq[:0], []     # the relaxation blocks stay kept unknowns
        nc = keep_row.size
        #: relaxation blocks eliminated (the second stage: relaxation.py)
        self.relaxation_eliminated = len(rq)
        band = bt is None
        self.block_tridiagonal = not band
        # the kept rows in the band of each block's eliminated columns: a contiguous
        # range of condensed rows (kept rows keep their order)
        first = np.searchsorted(keep_row, np.maximum(b[:, 0] - ku, 0))
        last = np.searchsorted(keep_row, np.minimum(b[:, 0] + b[:, 1] + kl, n)) - 1
        w_nr = np.where(last >= first, last - first + 1, 0).astype(np.int32)
        w_r0 = np.where(w_nr > 0, first, 0).astype(np.int32)
        # condensed bandwidths from the structure (conservative: every stored position)
        # of J[kept, kept] ...
        rows = keep_col[:, None] + np.arange(-ku, kl + 1)
        ok = (rows >= 0) & (rows < n)
        rc = row2c[np.where(ok, rows, 0)]
        ok &= rc >= 0
        d = (rc - np.arange(nc)[:, None])[ok]
        lo, hi = (int(d.max()), int(-d.min())) if d.size else (0, 0)
        # ... and of the fill J[kept, e_b] G_b on the columns k_b
        for k, (_e0, _es, _r, k0, ks) in enumerate(b):
            if w_nr[k]:
                tc = col2c[k0:k0 + ks]
                lo = max(lo, int(w_r0[k] + w_nr[k] - 1 - tc.min()))
                hi = max(hi, int(tc.max() - w_r0[k]))
        lo, hi = max(lo, 0), max(hi, 0)
        self.nc, self.klc, self.kuc = nc, lo, hi
        ldc = 2 * lo + hi + 1
        w_off = np.zeros(len(b), np.int32)
        if len(b):
            w_off[1:] = np.cumsum(w_nr[:-1] * b[:-1, 1])
        self._keep = dict(                    # (the band path's arrays are 1-element
                                              # placeholders on the block path)
            e_off=np.ascontiguousarray(b[:, 0]), e_sz=np.ascontiguousarray(b[:, 1]),
            r_off=np.ascontiguousarray(b[:, 2]), k_off=np.ascontiguousarray(b[:, 3]),
            k_sz=np.ascontiguousarray(b[:, 4]), keep_row=keep_row, keep_col=keep_col,
            row2c=row2c, col2c=col2c, G=np.zeros(16 * max(len(b), 1)),
            Minv=np.zeros(16 * max(len(b), 1)), g=np.zeros(4 * max(len(b), 1)),
            abc=np.zeros((ldc, max(nc, 1)) if band else (1, 1), order="F"),
            ipiv=np.zeros(max(nc, 1) if band else 1, np.int32),
            prof=np.zeros(2 * max(nc, 1) if band else 1, np.int32),
            rc=np.zeros(max(nc, 1)), w_off=w_off, w_r0=w_r0, w_nr=w_nr,
            W=np.zeros(max(int((w_nr * b[:, 1]).sum()) if len(b) and band else 0, 1)))
        if bt is None:
            bt = dict(ncell=0, mmax=0, **{k: np.zeros(1, np.int32) for k in (
                "cf", "cs", "cb", "ce", "eo", "rp", "run", "ecol", "kv6")},
                fo=np.zeros(1, np.int64), xo=np.zeros(1, np.int64), F=np.zeros(1),
                X=np.zeros(1), ge=np.zeros(1), T=np.zeros(1))
        self._keep.update({k: v for k, v in bt.items() if k not in ("ncell", "mmax")})
        self._keep["diag"] = diag
        if qt is None:
            qt = {k: np.zeros(1, np.int64 if k == "q_kwo" else
                              np.float64 if k in _Q_REAL else np.int32)
                  for k in _Q_FIELDS}
        self._keep.update({k: qt[k] for k in _Q_FIELDS})
        ptrs = (self._keep[k].ctypes.data for k in (
            "e_off", "e_sz", "r_off", "k_off", "k_sz", "keep_row", "keep_col", "row2c",
            "col2c", "G", "Minv", "g", "abc", "ipiv", "prof", "rc", "w_off", "w_r0", "w_nr",
            "W"))
        bt_ptrs = (self._keep[k].ctypes.data for k in (
            "cf", "cs", "cb", "ce", "eo", "fo", "xo", "F", "X", "ge", "T", "rp", "run", "ecol",
            "kv6", "diag"))
        s = _CondStruct(n, kl, ku, ldab, nc, lo, hi, ldc, len(b), *ptrs,
                        int(self.block_tridiagonal), bt["ncell"], bt["mmax"], *bt_ptrs, 0,
                        len(rq), *(self._keep[k].ctypes.data for k in _Q_FIELDS))
        self._struct = s
        self.ptr = ctypes.addressof(s)
        self._lib = lib

    def relaxation_need(self):
        """What the factorisation reads of the eliminated relaxation blocks' rows and
        columns, per state index (uint8, n): bit 0 the column, bit 1 the row in full, else
        only its diagonal entry (the D of the block). It reads the first term's rows
        (E, ``q_elim_cell``) and the reference columns at kept rows (``q_fill_cell``);
        every other unknown is read in full. None when no relaxation block is
        eliminated. (``kvrod_jacobian_band_cells_relaxed`` forms no more than this.)"""
        import numpy as np

        if not self.relaxation_eliminated:
            return None
        k = self._keep
        need = np.full(self.n, 3, np.uint8)
        for o, sz, nch in zip(k["q_off"], k["q_sz"], k["q_nch"], strict=True):
            need[o:o + sz] = 0
            need[o:o + nch] = 2
        need[k["q_kcol"][:k["q_kco"][-1]]] |= 1
        return need

    @property
    def cell_starts(self) -> np.ndarray | None:
        """First state index of each cell and the end (ncell + 1, int32) on the block
        tridiagonal path; None on the band path."""
        return self._keep["cf"] if self.block_tridiagonal else None

    @classmethod
    def build(cls, problem, n: int, kl: int, ku: int, ldab: int):
        """For a problem that describes its kinematic blocks (``condensation_blocks()``),
        with the C helpers available; else None. The block tridiagonal path needs the
        problem's ``condensation_cells()`` and, to prove the structure,
        ``band_pattern()`` (J's structural nonzeros in band storage); there, the
        problem's ``condensation_relaxation_blocks()`` (if it has them) are eliminated
        too."""
        lib = load()
        get = getattr(problem, "condensation_blocks", None)
        if lib is None or get is None:
            return None
        blocks = get()
        if not blocks:
            return None
        cells = getattr(problem, "condensation_cells", None)
        pattern = getattr(problem, "band_pattern", None)
        relax = getattr(problem, "condensation_relaxation_blocks", None)
        return cls(lib, n, kl, ku, ldab, blocks, cells=cells() if cells else None,
                   pattern=pattern() if pattern else None,
                   relaxation_blocks=relax() if relax else None)

    def factor(self, ab, cj: float = math.nan) -> int:
        """Condense J (band ``ab``, unchanged) and factorise: LAPACK's info (-1: a
        kinematic block is singular).

        ``cj``: the cj J was formed with (1/s). The fused Newton update
        (``kv_cond_newton``) solves the relaxation rows at its own cj from it (see
        ``kv_cond.q_cjf``); without it (NaN) that update of a system with relaxation blocks
        is NaN, and the integrator stops on it. Plain solves do not read it."""
        return int(self._lib.kv_cond_factor(self.ptr, ab.ctypes.data, cj))

    def solve(self, ab, b):
        """``J^-1 b`` (a new array) through the condensed factors."""
        import numpy as np

        x = np.array(b, dtype=float)
        self._lib.kv_cond_solve(self.ptr, ab.ctypes.data, x.ctypes.data)
        return x


def _kept(n: int, b, rq):
    """keep_row, keep_col (condensed -> full) and row2c, col2c (full -> condensed, -1:
    eliminated) with the kinematic blocks ``b`` and the relaxation blocks ``rq``
    ((offset, size): rows = columns) eliminated."""
    import numpy as np

    elim_rows = np.zeros(n, bool)
    elim_cols = np.zeros(n, bool)
    if len(b):
        elim_cols[_ranges(b[:, 0], b[:, 1])] = True
        elim_rows[_ranges(b[:, 2], b[:, 1])] = True
    if len(rq):
        q = _ranges(rq[:, 0], rq[:, 1])
        elim_cols[q] = True
        elim_rows[q] = True
    keep_row = np.flatnonzero(~elim_rows).astype(np.int32)
    keep_col = np.flatnonzero(~elim_cols).astype(np.int32)
    if keep_row.size != keep_col.size:
        raise ValueError("CondensedNewton: eliminated rows and columns differ in number")
    row2c = np.full(n, -1, np.int32)
    row2c[keep_row] = np.arange(keep_row.size, dtype=np.int32)
    col2c = np.full(n, -1, np.int32)
    col2c[keep_col] = np.arange(keep_col.size, dtype=np.int32)
    return keep_row, keep_col, row2c, col2c


def _relaxation(n: int, b, rblocks, bt, keep_row, col2c, entries):
    """relaxation.relaxation_tables on the block path's cells."""
    import numpy as np

    from .relaxation import relaxation_tables

    ecol_pos = np.full(n, -1, np.int64)
    if len(b):
        ecol = _ranges(b[:, 0], b[:, 1])
        ecol_pos[ecol] = np.arange(ecol.size)
    i, j = entries
    return relaxation_tables(n, rblocks, bt["cf"].astype(np.int64), keep_row,
                             col2c.astype(np.int64), ecol_pos, i, j)


def _band_entries(kl: int, ku: int, n: int, pattern):
    """(i, j) of J's structural nonzeros: those of ``pattern`` (band storage), or every
    position of the band."""
    import numpy as np

    kv = kl + ku
    nz = (pattern[kl:kl + kv + 1] != 0) if pattern is not None else np.ones((kv + 1, n), bool)
    d, j = np.nonzero(nz)
    i = j + d - ku
    ok = (i >= 0) & (i < n)
    return i[ok], j[ok]


def _check_block_rows(pattern, kl: int, ku: int, b, entries=None) -> None:
    """The condensation's premise, on J's structural pattern: the rows of a block involve
    only its own eliminated and kept columns."""
    import numpy as np

    n = pattern.shape[1]
    i, j = entries if entries is not None else _band_entries(kl, ku, n, pattern)
    block_of_row = np.full(n, -1)
    for k, (_e0, es, r0, _k0, _ks) in enumerate(b):
        block_of_row[r0:r0 + es] = k
    bi = block_of_row[i]
    sel = bi >= 0
    i, j, bi = i[sel], j[sel], bi[sel]
    e0, es, k0, ks = (b[bi, c].astype(np.int64) for c in (0, 1, 3, 4))
    bad = ~(((j >= e0) & (j < e0 + es)) | ((j >= k0) & (j < k0 + ks)))
    if bad.any():
        raise ValueError(f"CondensedNewton: row {int(i[bad][0])} of a kinematic block "
                         f"involves column {int(j[bad][0])}, outside the block")


def _diagonal_blocks(pattern, kl: int, ku: int, b):
    """Per block, 1 when M_b and K_b are structurally diagonal in ``pattern`` (e = k)."""
    import numpy as np

    out = np.zeros(max(len(b), 1), np.int32)
    if pattern is None:
        return out
    kv = kl + ku
    for size in sorted_unique(b[:, 1]):
        sel = np.flatnonzero((b[:, 1] == size) & (b[:, 4] == size))
        if not sel.size:
            continue
        i, q = np.nonzero(~np.eye(size, dtype=bool))          # off-diagonal (row, column)
        rows = b[sel, 2][:, None] + i
        nz = np.zeros(rows.shape, bool)
        for c0 in (b[sel, 0], b[sel, 3]):
            cols = c0[:, None] + q
            d = kv + rows - cols
            ok = (d >= kl) & (d <= kl + kv)
            nz[ok] |= pattern[d[ok], cols[ok]] != 0
        out[sel] = ~nz.any(axis=1)
    return out


def _cell_tables(n: int, kl: int, ku: int, b, keep_row, keep_col, col2c, cells, pattern,
                 diag, rq=(), entries=None):
    """The per-cell tables of the block tridiagonal path (see ``kv_cond`` in
    condensed.c) and None, or None and why the condensed matrix is not block
    tridiagonal in ``cells``. ``diag``: per block, structurally diagonal; ``rq``: the
    relaxation blocks eliminated too ((offset, size))."""
    import numpy as np

    if cells is None:
        return None, "no cells given"
    cf = np.asarray(cells, dtype=np.int64).ravel()
    if cf.size == 0 or cf[0] != 0 or np.any(np.diff(cf) <= 0) or cf[-1] >= n:
        return None, "cells are not increasing first indices from 0"
    ncell = cf.size
    cf = np.append(cf, n)
    cell = np.repeat(np.arange(ncell), np.diff(cf))           # of every state index
    e0, es, r0, k0, ks = (b[:, c].astype(np.int64) for c in range(5))
    cell_b = cell[e0]
    for first, size in ((e0, es), (r0, es), (k0, ks)):
        if np.any(cell[first] != cell_b) or np.any(cell[first + size - 1] != cell_b):
            return None, "a block spans two cells"
    for q in range(1, 4):          # k_b: kept, consecutive condensed columns
        has = q < ks
        if np.any(col2c[(k0 + q)[has]] != col2c[k0[has]] + q):
            return None, "a block's kept columns are not consecutive condensed columns"
    if len(b) and np.any(col2c[k0] < 0):
        return None, "a block's kept columns are eliminated"
    cs = np.searchsorted(keep_col, cf)
    if not np.array_equal(cs, np.searchsorted(keep_row, cf)):
        return None, "a cell keeps different numbers of rows and columns"
    m = np.diff(cs)
    if np.any(m == 0):
        return None, "a cell keeps no unknowns"
    kept = np.zeros(n, bool)
    kept[keep_row] = True
    i, j = entries if entries is not None else _band_entries(kl, ku, n, pattern)
    far = kept[i] & (np.abs(cell[i] - cell[j]) > 1)
    if far.any():
        i, j = int(i[far][0]), int(j[far][0])
        return None, (f"row {i} (cell {cell[i]}) couples to column {j} (cell {cell[j]})"
                      + ("" if pattern is not None else " in the band (no pattern given)"))
    cb = np.searchsorted(cell_b, np.arange(ncell + 1))
    eo = np.zeros(len(b) + 1, np.int64)
    eo[1:] = np.cumsum(es)
    ce = eo[cb]
    mp = np.concatenate(([0], m[:-1]))
    mn = np.concatenate((m[1:], [0]))
    ne3 = ce[np.minimum(np.arange(ncell) + 2, ncell)] - ce[np.maximum(np.arange(ncell) - 1, 0)]
    fsize = m * (ne3 + mp + m)
    xsize = m * mn
    fo = np.concatenate(([0], np.cumsum(fsize)[:-1])).astype(np.int64)
    xo = np.concatenate(([0], np.cumsum(xsize)[:-1])).astype(np.int64)
    mmax = int(m.max())
    # the kept rows of each cell as runs of consecutive state indices
    brk = np.flatnonzero(np.diff(keep_row) != 1) + 1         # run starts (condensed)
    starts = sorted_unique(np.concatenate((brk, cs[:-1])))
    lens = np.diff(np.append(starts, keep_row.size))
    rp = np.searchsorted(starts, cs)
    cell_of_run = np.searchsorted(cs, starts, side="right") - 1
    run = np.stack([keep_row[starts], starts - cs[cell_of_run], lens], axis=1)
    ecol = _ranges(e0, es) if len(b) else np.zeros(1, np.int64)
    nrun = np.diff(rp)
    two3 = (nrun == 2) & (lens[np.minimum(rp[:-1], lens.size - 1)] == 3) & (
        lens[np.minimum(rp[:-1] + 1, lens.size - 1)] == 3)
    ne = np.diff(ce)
    ne_p = np.concatenate(([0], ne[:-1]))
    ne_n = np.concatenate((ne[1:], [0]))
    nblk = np.diff(cb)
    b0 = np.minimum(cb[:-1], max(len(b) - 2, 0))          # (checked only where nblk == 2)
    pv = ((nblk == 2) & (es[b0] == 4) & (ks[b0] == 3) & (diag[b0] == 0)
          & (es[b0 + 1] == 3) & (ks[b0 + 1] == 3) & (diag[b0 + 1] == 1)) if len(b) > 1 else False
    pv = np.broadcast_to(pv, (ncell,))
    pv3 = pv & np.concatenate(([False], pv[:-1])) & np.concatenate((pv[1:], [False]))
    nrelax = np.zeros(ncell, np.int64)         # unknowns of relaxation blocks per cell
    if len(rq):
        np.add.at(nrelax, cell[rq[:, 0]], rq[:, 1])
    kv6 = ((mp == 6) & (m == 6) & (mn == 6) & (ne_p == 7) & (ne == 7) & (ne_n == 7)
           & (np.diff(cf) - nrelax == 13) & two3 & pv3)
    i32 = lambda a: np.ascontiguousarray(a, dtype=np.int32)  # noqa: E731
    return dict(ncell=ncell, mmax=mmax, cf=i32(cf), cs=i32(cs), cb=i32(cb), ce=i32(ce),
                eo=i32(eo[:-1] if len(b) else [0]), fo=fo, xo=xo,
                F=np.zeros(max(int(fsize.sum()), 1)), X=np.zeros(max(int(xsize.sum()), 1)),
                ge=np.zeros(max(int(es.sum()), 1)), T=np.zeros(mmax * (2 * mmax + 3)),
                rp=i32(rp), run=i32(run.ravel()), ecol=i32(ecol), kv6=i32(kv6)), None
