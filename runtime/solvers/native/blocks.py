"""Newton systems of coupled band blocks (``kv_blocks`` in blocks.c): ``J = A + P_S^T E``,
A block diagonal with banded blocks, E nonzero in a few coupling rows S only (an assembly
of rods: each rod a block, the joints the couplings). Factorised by the blocks' own band
or condensed LUs and the Woodbury identity on the rows S (blocks.c says why)."""

from __future__ import annotations

import ctypes
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from .loader import load


class _BlocksStruct(ctypes.Structure):
    """Mirror of ``kv_blocks`` in blocks.c."""

    _fields_ = ([("n", ctypes.c_int), ("nb", ctypes.c_int)]
                + [(name, ctypes.c_void_p) for name in
                   ("off", "kl", "ku", "ldab", "ab", "cond", "ipiv", "prof")]
                + [("m", ctypes.c_int)]
                + [(name, ctypes.c_void_p) for name in
                   ("srow", "sblk", "er", "ec", "ecb", "ev", "bs0", "bsl", "Z", "zo", "C",
                    "cpiv", "w")]
                + [(name, ctypes.c_int) for name in ("m2", "m2cap", "nz2cap")]
                + [(name, ctypes.c_void_p) for name in
                   ("srow2", "er2", "ec2", "sblk2", "ecb2", "ev2")]
                + [("zcap", ctypes.c_longlong), ("mtot", ctypes.c_int)])


@dataclass
class Block:
    """One diagonal block: ``n`` unknowns from ``offset``, band ``kl``, ``ku``; ``cond``:
    a ``CondensedNewton`` of the block (its kinematic rows eliminated) or None (band LU)."""

    offset: int
    n: int
    kl: int
    ku: int
    cond: object | None = None


class CoupledBlocks:
    """The coupled band blocks of a system and their factors.

    blocks: the diagonal blocks, contiguous and in order (offsets 0, n_0, n_0 + n_1, ...);
    coupling: ``{row: columns}`` the structural nonzeros of E (global indices): every
    entry of J outside the blocks' bands lies in one of these rows (entries of such a row
    inside its block's band may go to either; the caller decides, and writes the values
    into :attr:`ab` (per block, band storage) and :attr:`ev` (E's values in the order of
    :attr:`entries`) before :meth:`factor`).
    """

    def __init__(self, blocks: Sequence[Block], coupling: dict[int, Sequence[int]],
                 dynamic_rows: int = 0, dynamic_entries: int = 0) -> None:
        lib = load()
        if lib is None:
            raise RuntimeError("coupled band blocks need the compiled helpers (a C compiler)")
        self._lib = lib
        self.blocks = list(blocks)
        nb = len(self.blocks)
        off = [0]
        for b in self.blocks:
            if b.offset != off[-1]:
                raise ValueError("CoupledBlocks: blocks must be contiguous and in order")
            off.append(off[-1] + b.n)
        self.n = off[-1]
        self.off = np.array(off, dtype=np.int32)
        # one buffer holds every block's band storage and then E's values, so that a
        # Jacobian entry's destination is one flat index (``ab_start`` + the entry's
        # position in its block's Fortran band storage, or ``ev_start`` + its slot)
        ldab = [2 * b.kl + b.ku + 1 for b in self.blocks]
        sizes = [ld * b.n for ld, b in zip(ldab, self.blocks, strict=True)]
        self.ab_start = np.array(np.cumsum([0] + sizes[:-1]), dtype=np.int64)
        nab = int(sum(sizes))
        self.ldab = np.array(ldab, dtype=np.int32)
        self.ipiv = [np.zeros(max(b.n, 1), dtype=np.int32) for b in self.blocks]
        self.prof = [np.zeros(2 * max(b.n, 1), dtype=np.int32) for b in self.blocks]
        rows = sorted(int(r) for r in coupling)
        self.rows = np.array(rows, dtype=np.int32)
        self.m = m = len(rows)
        block_of = lambda i: int(np.searchsorted(self.off, i, side="right") - 1)  # noqa: E731
        self.sblk = np.array([block_of(r) for r in rows], dtype=np.int32)
        er, ec = [0], []
        for r in rows:
            cols = sorted({int(c) for c in coupling[r]})
            ec += cols
            er.append(len(ec))
        self.er = np.array(er, dtype=np.int32)
        self.ec = np.array(ec, dtype=np.int32)
        self.ecb = np.array([block_of(c) for c in ec], dtype=np.int32)
        #: (row, column) of every E entry, in the order of ev
        self.entries = [(int(r), int(c)) for i, r in enumerate(rows)
                        for c in ec[er[i]:er[i + 1]]]
        #: every block's band storage, then E's values (see above)
        self.buffer = np.zeros(nab + max(len(ec), 1))
        self.ab = [self.buffer[a:a + n].reshape((ld, b.n), order="F")
                   for a, n, ld, b in zip(self.ab_start, sizes, ldab, self.blocks, strict=True)]
        self.ev_start = nab
        self.ev = self.buffer[nab:]
        self._slot = {e: k for k, e in enumerate(self.entries)}
        bsl = [[] for _ in range(nb)]
        for s, b in enumerate(self.sblk):
            bsl[b].append(s)
        self.bs0 = np.array(np.cumsum([0] + [len(x) for x in bsl]), dtype=np.int32)
        flat = [s for x in bsl for s in x]
        self.bsl = np.zeros(max(len(flat) + int(dynamic_rows), 1), dtype=np.int32)
        self.bsl[:len(flat)] = flat
        sizes = [self.blocks[b].n for b in self.sblk]
        #: capacity of the dynamic couplings (rows, entries): :meth:`set_dynamic`
        self.m2cap, self.nz2cap = int(dynamic_rows), int(dynamic_entries)
        mc = m + self.m2cap
        zcap = int(sum(sizes)) + self.m2cap * max((b.n for b in self.blocks), default=0)
        self.zo = np.zeros(max(mc, 1), dtype=np.int64)
        if m:
            self.zo[:m] = np.cumsum([0] + sizes[:-1])
        self.Z = np.zeros(max(zcap, 1))
        self.C = np.zeros(max(mc * mc, 1))
        self.cpiv = np.zeros(max(mc, 1), dtype=np.int32)
        self.w = np.zeros(max(mc, 1))
        self.srow2 = np.zeros(max(self.m2cap, 1), dtype=np.int32)
        self.er2 = np.zeros(self.m2cap + 1, dtype=np.int32)
        self.ec2 = np.zeros(max(self.nz2cap, 1), dtype=np.int32)
        self.ev2 = np.zeros(max(self.nz2cap, 1))
        self.sblk2 = np.zeros(max(self.m2cap, 1), dtype=np.int32)
        self.ecb2 = np.zeros(max(self.nz2cap, 1), dtype=np.int32)
        P = ctypes.c_void_p
        self._abp = (P * nb)(*[a.ctypes.data for a in self.ab])
        self._condp = (P * nb)(*[(b.cond.ptr if b.cond is not None else None)
                                 for b in self.blocks])
        self._ipivp = (P * nb)(*[a.ctypes.data for a in self.ipiv])
        self._profp = (P * nb)(*[a.ctypes.data for a in self.prof])
        self._kl = np.array([b.kl for b in self.blocks], dtype=np.int32)
        self._ku = np.array([b.ku for b in self.blocks], dtype=np.int32)
        s = self._s = _BlocksStruct()
        s.n, s.nb, s.m = self.n, nb, m
        d = lambda a: a.ctypes.data  # noqa: E731
        s.off, s.kl, s.ku, s.ldab = d(self.off), d(self._kl), d(self._ku), d(self.ldab)
        s.ab, s.cond = ctypes.addressof(self._abp), ctypes.addressof(self._condp)
        s.ipiv, s.prof = ctypes.addressof(self._ipivp), ctypes.addressof(self._profp)
        s.srow, s.sblk, s.er, s.ec, s.ecb, s.ev = (d(self.rows if m else self.cpiv),
                                                   d(self.sblk if m else self.cpiv),
                                                   d(self.er), d(self.ec if len(ec) else
                                                                 self.cpiv),
                                                   d(self.ecb if len(ec) else self.cpiv),
                                                   d(self.ev))
        s.bs0, s.bsl, s.Z, s.zo = d(self.bs0), d(self.bsl), d(self.Z), d(self.zo)
        s.C, s.cpiv, s.w = d(self.C), d(self.cpiv), d(self.w)
        s.m2, s.m2cap, s.nz2cap = 0, self.m2cap, self.nz2cap
        s.srow2, s.er2, s.ec2 = d(self.srow2), d(self.er2), d(self.ec2)
        s.sblk2, s.ecb2, s.ev2 = d(self.sblk2), d(self.ecb2), d(self.ev2)
        s.zcap, s.mtot = self.Z.size, m
        #: address of the kv_blocks struct (for the compiled step loop)
        self.ptr = ctypes.addressof(s)

    @property
    def m2_address(self) -> int:
        """Address of the count of dynamic coupling rows (``kv_blocks.m2``): the compiled
        Jacobian of a system writes it with the rows."""
        return ctypes.addressof(self._s) + type(self._s).m2.offset

    def set_dynamic(self, rows: Sequence[int],
                    entries: Sequence[Sequence[tuple[int, float]]]) -> None:
        """The dynamic couplings until the next call: ``rows`` (global) with their
        entries ``(column, value)`` (a row may repeat a fixed coupling row)."""
        if len(rows) > self.m2cap:
            raise ValueError(f"{len(rows)} dynamic coupling rows, capacity {self.m2cap}")
        k = 0
        for t, (r, row) in enumerate(zip(rows, entries, strict=True)):
            self.srow2[t] = r
            self.er2[t] = k
            for c, v in row:
                if k >= self.nz2cap:
                    raise ValueError(f"more than {self.nz2cap} dynamic coupling entries")
                self.ec2[k], self.ev2[k] = c, v
                k += 1
        self.er2[len(rows)] = k
        self._s.m2 = len(rows)

    def zero(self) -> None:
        """Clear every block's band and E's values (before a Jacobian is written)."""
        self.buffer.fill(0.0)

    def block_of(self, i: int) -> int:
        """The block holding global unknown i."""
        return int(np.searchsorted(self.off, i, side="right") - 1)

    def destination(self, row: int, col: int) -> int:
        """Flat index into :attr:`buffer` where J[row, col] is written: its place in its
        block's band when row and col share a block within its band, else its E slot
        (KeyError when it has none: a coupling the pattern did not declare)."""
        b = self.block_of(row)
        blk = self.blocks[b]
        i, j = row - blk.offset, col - blk.offset
        if 0 <= j < blk.n and -blk.kl <= j - i <= blk.ku and (row, col) not in self._slot:
            return int(self.ab_start[b] + (blk.kl + blk.ku + i - j) + j * self.ldab[b])
        return int(self.ev_start + self._slot[(row, col)])

    def factor(self) -> int:
        """Factorise (the blocks, then Z and the capacitance); 0, or > 0 when singular."""
        return int(self._lib.kv_blocks_factor(self.ptr))

    def solve(self, x: np.ndarray) -> np.ndarray:
        """x <- J^-1 x in place (float64, contiguous, length n); returns x."""
        self._lib.kv_blocks_solve(self.ptr, x.ctypes.data)
        return x

    def correct(self, res, scale, ewt, ee, yy, ypw, cj) -> float:
        """The fused simplified-Newton update (``runtime.solvers.newton``'s contract)."""
        d = lambda a: a.ctypes.data  # noqa: E731
        return float(self._lib.kv_blocks_newton(self.ptr, d(res), scale, d(ewt), d(ee),
                                                d(yy), d(ypw), cj))

    def dense(self) -> np.ndarray:
        """J as a dense matrix (tests): the blocks' bands plus E, before :meth:`factor`."""
        from runtime.solvers.protocols import band_to_dense

        J = np.zeros((self.n, self.n))
        for b, a in zip(self.blocks, self.ab, strict=True):
            J[b.offset:b.offset + b.n, b.offset:b.offset + b.n] = band_to_dense(a, b.kl, b.ku)
        for (r, c), v in zip(self.entries, self.ev, strict=False):
            J[r, c] += v
        for t in range(self._s.m2):
            for q in range(self.er2[t], self.er2[t + 1]):
                J[self.srow2[t], self.ec2[q]] += self.ev2[q]
        return J
