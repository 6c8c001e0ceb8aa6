"""The second stage of the condensed Newton systems (``CondensedNewton`` in condensed.py,
the ``q_`` fields of ``kv_cond`` in condensed.c): relaxation blocks eliminated on the
block tridiagonal path.

A relaxation block is a contiguous range of unknowns q whose rows (the same range)
involve q only on the diagonal, plus unknowns of the first stage (kept, or eliminated by
a kinematic block), "sources" x: ``D dq + A dx = r_q`` with D diagonal, as the rod's
internal strains, ``q_b' = (strain(x) - q_b)/theta_b``, whose iteration-matrix block in q
is ``(cj + 1/theta_b) I``. So ``dq = D^-1 r_q - A' dx`` with ``A' = D^-1 A``, and the kept
rows that involve q see ``J[kept, x] - J[kept, q] A'`` (and ``r - J[kept, q] D^-1 r_q``):
the condensation of the first stage then runs on that as on a rod without relaxation
terms. The fill ``J[kept, q] A'`` couples the cells of the rows that involve q with the
cells of its sources, which must therefore be neighbours (checked here on J's pattern;
the rod's segment strains depend on the segment's frame and its two nodes, its joint
strains on the two frames of the joint).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: most unknowns and sources of one block (KV_QMAX, KV_QMAX_SRC in condensed.c; the rod:
#: 3 per relaxation term, at most 24 terms; 10 sources)
MAX_SIZE = 72
MAX_SOURCES = 32


@dataclass(frozen=True)
class RelaxationBlock:
    """One relaxation block: the unknowns ``offset .. offset + size - 1`` of B terms of
    ``channels`` = c strains each, unknown u = b c + k for term b, strain k (size = B c),
    with the structure of a generalized Maxwell rod's internal strains,
    ``q_bk' = (strain_k(x) - q_bk) / theta_b`` in the rows and ``- sum_b C_bk q_bk`` in
    the resultants that the other rows see (runtime/model/native/rod_assembly.c):

    * row u: diagonal in the block (``cj + rates[u]``), and on the other unknowns
      ``-rates[u] dstrain_k/dx``: the rows of one strain differ by the factor
      ``rates[u]`` (1/theta_b) only;
    * column u: ``moduli[u] G[r, k]`` in every other row r (G from the state): the
      columns of one strain differ by the factor ``moduli[u]`` (C_bk) only.

    The elimination (condensed.c, ``kv_cond``) forms the products of a block per strain,
    not per unknown, from these factors; the rates must be positive and finite, the
    moduli finite.
    """

    offset: int
    channels: int
    rates: np.ndarray
    moduli: np.ndarray

    @property
    def size(self) -> int:
        return int(np.size(self.rates))


def _structure(blocks) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray] | str:
    """Per block its strains c; per unknown nu = its rate / the first term's and mu = its
    modulus / the reference term's (the q_nu, q_mu tables); per strain the reference
    unknown (the term of the largest modulus), ``b c + k``; or why the blocks do not
    have the structure. Blocks of one shape (the rod's) are done together."""
    nch = np.array([b.channels for b in blocks], dtype=np.int64)
    nu, mu, ref = [], [], []
    shapes = {(int(b.channels), np.shape(b.rates), np.shape(b.moduli)) for b in blocks}
    groups = ([blocks] if len(shapes) == 1 else [[b] for b in blocks])
    for grp in groups:
        b0 = grp[0]
        c = int(b0.channels)
        r = np.array([np.asarray(b.rates, float) for b in grp])
        mdl = np.array([np.asarray(b.moduli, float) for b in grp])
        if c < 1 or r.ndim != 2 or mdl.shape != r.shape or r.shape[1] % c:
            return (f"relaxation block at {b0.offset}: {r.shape[-1]} rates, "
                    f"{mdl.shape[-1]} moduli, {c} strains: expected B x strains of each")
        if not (np.all(np.isfinite(r)) and np.all(r > 0.0) and np.all(np.isfinite(mdl))):
            return (f"relaxation block at {b0.offset}: rates must be positive and finite, "
                    "moduli finite")
        R, M = r.reshape(len(grp), -1, c), mdl.reshape(len(grp), -1, c)
        # rows of strain k: multiples of the first term's (A[u] = nu_u A[k])
        nu.append((R / R[:, :1]).ravel())
        # columns of strain k: multiples of the reference term's (its largest modulus;
        # a strain without any modulus has columns of zeros: mu 0)
        kb = np.argmax(np.abs(M), axis=1)                                  # (blocks, c)
        Mr = np.take_along_axis(M, kb[:, None, :], axis=1)
        mu.append(np.divide(M, Mr, out=np.zeros_like(M), where=Mr != 0.0).ravel())
        ref.append((kb * c + np.arange(c)).ravel())
    cat = lambda a: np.concatenate(a) if a else np.zeros(0)  # noqa: E731
    return nch, cat(nu), cat(mu), cat(ref).astype(np.int64)


def _ranges(starts, lengths):
    """The concatenated ranges starts[i] .. starts[i] + lengths[i] - 1 (int64)."""
    starts, lengths = np.asarray(starts, np.int64), np.asarray(lengths, np.int64)
    first = np.cumsum(lengths) - lengths
    return np.repeat(starts - first, lengths) + np.arange(int(lengths.sum()))


def relaxation_tables(n: int, blocks, cf, keep_row, col2c, ecol_pos,
                      i, j):
    """The tables of the ``q_`` fields of ``kv_cond`` for the relaxation ``blocks``
    (:class:`RelaxationBlock`, sorted by offset) on cells ``cf`` (first index of each cell
    and n), and None; or None and why the blocks cannot be eliminated on the block path.

    ``keep_row``/``col2c``: the kept rows and the condensed index of each column (-1:
    eliminated), with the relaxation blocks eliminated; ``ecol_pos``: the position of a
    first-stage eliminated column in the block order (-1 for others); ``i, j``: J's
    structural nonzeros.
    """
    q = np.array([(b.offset, np.size(b.rates)) for b in blocks],
                 dtype=np.int64).reshape(-1, 2)
    nq = len(q)
    st = _structure(blocks)
    if isinstance(st, str):
        return None, st
    nch, q_nu, q_mu, qref = st
    ncell = len(cf) - 1
    cell = np.repeat(np.arange(ncell), np.diff(cf))
    # disjoint ranges inside the state (sorted by offset: each ends before the next)
    if nq and (np.any(q[:, 1] < 1) or q[0, 0] < 0 or np.any(q[:, 0] + q[:, 1] > n)
               or np.any(q[:-1, 0] + q[:-1, 1] > q[1:, 0])):
        return None, "relaxation blocks are not disjoint ranges of the state"
    qid = np.full(n, -1, np.int64)
    qid[_ranges(q[:, 0], q[:, 1])] = np.repeat(np.arange(nq), q[:, 1])
    if np.any(q[:, 1] > MAX_SIZE):
        return None, f"a relaxation block has more than {MAX_SIZE} unknowns"
    qcell = cell[q[:, 0]]
    if np.any(cell[q[:, 0] + q[:, 1] - 1] != qcell):
        return None, "a relaxation block spans two cells"
    kept = np.zeros(n, bool)
    kept[keep_row] = True
    # the rows of the blocks: diagonal in their own unknowns, no other block's
    bi, bj = qid[i], qid[j]
    own = (bi >= 0) & (bj == bi)
    if np.any(own & (i != j)):
        r = int(i[own & (i != j)][0])
        return None, f"row {r} of a relaxation block is not diagonal in the block"
    if np.any((bi >= 0) & (bj >= 0) & (bj != bi)):
        return None, "a relaxation block's rows involve another block's unknowns"
    diag = np.zeros(n, bool)
    diag[i[own]] = True
    if not diag[qid >= 0].all():
        return None, "a relaxation block has a structurally zero diagonal entry"
    # rows involving q: kept rows only (a kinematic row never involves q)
    link = (bj >= 0) & (bi < 0)
    if np.any(~kept[i[link]]):
        return None, "a kinematic row involves a relaxation block's unknowns"
    # sources: the other columns of the blocks' rows, in column order per block
    src = (bi >= 0) & (bj < 0)
    sb, sj = bi[src], j[src]
    order = np.lexsort((sj, sb))
    sb, sj = sb[order], sj[order]
    first = np.ones(sb.size, bool)
    first[1:] = (sb[1:] != sb[:-1]) | (sj[1:] != sj[:-1])
    sb, sj = sb[first], sj[first]
    so = np.searchsorted(sb, np.arange(nq + 1))
    if np.any(np.diff(so) > MAX_SOURCES):
        return None, f"a relaxation block's rows involve more than {MAX_SOURCES} unknowns"
    tgt = np.where(col2c[sj] >= 0, col2c[sj], -1 - ecol_pos[sj])
    if np.any((col2c[sj] < 0) & (ecol_pos[sj] < 0)):
        return None, ("a relaxation block's rows involve an unknown that is neither kept "
                      "nor eliminated")
    lb, li = bj[link], i[link]
    lcell = cell[li]
    big = np.iinfo(np.int64).max
    # per block: the lowest and highest cell of the kept rows that involve it (lo > hi:
    # none) and of its sources
    llo, lhi = np.full(nq, big), np.full(nq, -1)
    np.minimum.at(llo, lb, lcell)
    np.maximum.at(lhi, lb, lcell)
    slo, shi = np.full(nq, big), np.full(nq, -1)
    np.minimum.at(slo, sb, cell[sj])
    np.maximum.at(shi, sb, cell[sj])
    linked, sourced = lhi >= 0, shi >= 0
    both = linked & sourced
    bad = both & ((lhi - slo > 1) | (shi - llo > 1))
    if bad.any():
        b = int(np.flatnonzero(bad)[0])
        return None, (f"the fill of relaxation block {b} (cell {qcell[b]}) couples cells "
                      f"that are not neighbours")
    bad = linked & ((lhi > qcell + 1) | (llo < qcell - 1))
    if bad.any():
        b = int(np.flatnonzero(bad)[0])
        return None, f"relaxation block {b} (cell {qcell[b]}) is involved beyond its neighbours"
    fac = np.where(linked, llo, qcell)     # the factor step that forms A' (its first link)
    bad = (sourced & ((shi > fac + 1) | (slo < fac - 1))) | (np.abs(qcell - fac) > 1)
    if bad.any():
        b = int(np.flatnonzero(bad)[0])
        return None, f"relaxation block {b}'s columns are not in the factor's window"
    fin = np.where(sourced, slo, qcell)    # the backward step that finishes dq
    # the cell by cell Newton update: after the last backward step that reads or writes
    # the cell (its own, its blocks' finish, a finish reading its unknowns as sources)
    upd = np.arange(ncell)
    np.minimum.at(upd, qcell, fin)
    np.minimum.at(upd, cell[sj], fin[sb])
    ucell = np.lexsort((-np.arange(ncell), -upd)).astype(np.int32)
    # per cell, the range of blocks its kept rows involve (W: J[kept rows, their q]) and
    # their columns, block after block
    k0, k1 = np.zeros(ncell, np.int64), np.zeros(ncell, np.int64)
    if lb.size:
        k0[:] = big
        np.minimum.at(k0, lcell, lb)
        np.maximum.at(k1, lcell, lb + 1)
        k0[k1 == 0] = 0
    kb = np.stack([k0, k1], axis=1)
    bsel = _ranges(k0, k1 - k0)
    # ... their reference columns (one per strain)
    co = np.concatenate(([0], np.cumsum(nch)))
    kn = np.zeros(ncell, np.int64)
    np.add.at(kn, np.repeat(np.arange(ncell), k1 - k0), nch[bsel])
    kcol = np.repeat(q[bsel, 0], nch[bsel]) + qref[_ranges(co[bsel], nch[bsel])]
    m = np.diff(np.searchsorted(keep_row, cf))
    kco = np.concatenate(([0], np.cumsum(kn)))
    kwo = np.concatenate(([0], np.cumsum(m * kn)[:-1])).astype(np.int64)
    ns = np.diff(so)
    ao = np.concatenate(([0], np.cumsum(nch * ns)[:-1]))
    eo = np.concatenate(([0], np.cumsum(q[:, 1])[:-1]))
    nqe = int(q[:, 1].sum())
    by_fac = np.argsort(fac, kind="stable")
    by_fin = np.argsort(fin, kind="stable")
    i32 = lambda a: np.ascontiguousarray(a, dtype=np.int32)  # noqa: E731
    return dict(
        q_off=i32(q[:, 0]), q_sz=i32(q[:, 1]), q_nch=i32(nch), q_eo=i32(eo), q_co=i32(co),
        q_so=i32(so), q_src=i32(sj), q_tgt=i32(tgt), q_ao=i32(ao),
        q_nu=np.ascontiguousarray(q_nu), q_mu=np.ascontiguousarray(q_mu),
        q_A=np.zeros(max(int((nch * ns).sum()), 1)), q_dinv=np.zeros(nqe),
        q_kap=np.zeros(nqe), q_g=np.zeros(nqe), q_dc=np.zeros(nqe), q_kc=np.zeros(nqe),
        q_gh=np.zeros(max(int(nch.sum()), 1)),
        q_cb=i32(np.searchsorted(qcell, np.arange(ncell + 1))),
        q_fk=i32(np.searchsorted(fac[by_fac], np.arange(ncell + 1))), q_fl=i32(by_fac),
        q_kb=i32(kb.ravel()), q_kco=i32(kco), q_kcol=i32(np.append(kcol, 0)),
        q_kwo=kwo, q_W=np.zeros(max(int((m * kn).sum()), 1)),
        q_bk=i32(np.searchsorted(fin[by_fin], np.arange(ncell + 1))), q_bl=i32(by_fin),
        q_ucell=ucell, q_ustep=i32(upd[ucell])), None
