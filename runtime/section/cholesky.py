"""Sparse Cholesky factorization of a finite-element matrix with several unknowns per node.

The section's warping matrix (symmetric positive definite once six dofs are pinned) is
factored once and the factor is applied to every right-hand side. SciPy's SuperLU
factorizes it column by column with level-2 BLAS (about 0.4 GFlop/s on one core, most of
``kvrod section``'s time on a fine mesh); here the same fill-reducing ordering drives a
supernodal multifrontal Cholesky whose fronts are dense LAPACK calls (potrf, trsm, gemm):

1. *Blocks*: the connected components of the matrix graph are factored separately (an
   isotropic section's in-plane and axial warping do not couple: two smaller factors).
2. *Ordering and fill* on the node graph (one row per node, the pattern of P^T |A| P):
   SuperLU's minimum degree on A^T + A (``MMD_AT_PLUS_A``) and its symbolic factor, cheap
   on the scalar node matrix; each node's unknowns are then numbered together.
3. *Supernodes*: runs of consecutive columns whose structures nest (fundamental
   supernodes), amalgamated with their last child while the explicit zeros this adds stay
   few, so that the fronts are large enough for dense BLAS.
4. *Numeric*: in elimination-tree order each front gathers its columns of A and its
   children's update matrices (extend-add), factors its pivot block L11 = chol(F11),
   L21 = F21 L11^-T, and passes F22 - L21 L21^T to its parent. This loop runs in C
   (``multifrontal.c``) where a compiler is at hand, with SciPy's own LAPACK and BLAS
   routines: the same factor bit for bit, without NumPy's per-call overhead (two thirds
   of the loop's time); the NumPy loop is the fallback and the tests' oracle.
5. *Solve*: forward and backward substitution front by front (dtrsm with U11, products
   with X), in C as well (``kv_mf_solve``: the Python loop's per-front overhead was half
   of its ~0.1 s a solve on a 20k-element mesh), with the Python loop as fallback, for a
   single right-hand side, and as the tests' oracle.

No pivoting: the matrix must be symmetric positive definite (a failed pivot raises).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from scipy.linalg import blas, lapack
from scipy.sparse.csgraph import connected_components

from runtime.section import multifrontal

#: amalgamation: a merged supernode of at most this many nodes is always accepted, a
#: larger one while its explicit zeros are at most ZERO_SHARE of its entries
SMALL_NODES = 4
#: the supernodes and the numeric phase in C where they can be compiled (multifrontal.c;
#: the same supernodes and factor as the Python and NumPy loops, bit for bit); False: those
#: loops
NATIVE = True
ZERO_SHARE = ((16, 0.8), (48, 0.1), (np.inf, 0.05))


@dataclass
class _Front:
    """One supernode of one block: pivot unknowns r0:r1 (the block's elimination
    numbering), update unknowns ``upd`` (sorted, all >= r1), the factors U11 (upper,
    F11 = U11^T U11) and X = U11^-T F12."""

    r0: int
    r1: int
    upd: np.ndarray
    U11: np.ndarray
    X: np.ndarray


@dataclass
class _Packed:
    """The fronts with k > 0 of a block factored in C, as ``multifrontal.solve_fronts``
    takes them: first unknowns, pivot counts, offsets of U11 (then X) in ``out``, the
    update unknowns ``upd_all[ulo:ulo + un]`` (int64)."""

    r0: np.ndarray
    kf: np.ndarray
    off: np.ndarray
    upd_all: np.ndarray
    ulo: np.ndarray
    un: np.ndarray
    out: np.ndarray


@dataclass
class _Block:
    """A connected component: its unknowns in elimination order and its fronts (also
    packed for the compiled solve when the compiled factorization made them)."""

    order: np.ndarray
    fronts: list[_Front]
    packed: _Packed | None = None


@dataclass
class _Symbolic:
    """The node graph's ordering and supernodes: ``rank`` the elimination position of
    each node, supernode g holding positions bounds[g]:bounds[g + 1] with the nodes
    ``below[below_ptr[g]:below_ptr[g + 1]]`` (positions, sorted) in its update set,
    ``parent[g]`` (-1 at a root)."""

    rank: np.ndarray
    bounds: np.ndarray
    below: np.ndarray
    below_ptr: np.ndarray
    parent: np.ndarray


class NotPositiveDefinite(np.linalg.LinAlgError):
    """A pivot block of the matrix is not positive definite."""


class CholeskyFactor:
    """A = L L^T of a sparse symmetric positive definite matrix, block by block;
    :meth:`solve` applies A^-1 to one or many right-hand sides."""

    def __init__(self, n: int, blocks: list[_Block]) -> None:
        self.n = n
        self._blocks = blocks

    @property
    def nnz(self) -> int:
        """Entries stored in L (upper triangles of the pivot blocks and the X blocks)."""
        return sum(f.U11.shape[0] * (f.U11.shape[0] + 1) // 2 + f.X.size
                   for b in self._blocks for f in b.fronts)

    def solve(self, b: np.ndarray) -> np.ndarray:
        """x with A x = b; b (n,) or (n, k)."""
        b = np.asarray(b, dtype=float)
        if b.shape[0] != self.n:
            raise ValueError(f"b has {b.shape[0]} rows, the matrix {self.n}")
        x = np.empty_like(b)
        lib = multifrontal.load() if NATIVE else None
        for blk in self._blocks:
            y = np.asfortranarray(b[blk.order].reshape(blk.order.size, -1))
            if lib is not None and blk.packed is not None and y.shape[1] >= 2:
                pk = blk.packed
                multifrontal.solve_fronts(lib, pk.r0, pk.kf, pk.off, pk.upd_all, pk.ulo,
                                          pk.un, pk.out, y)
                x[blk.order] = y.reshape((blk.order.size,) + b.shape[1:])
                continue
            for f in blk.fronts:                             # L y = b
                yo = blas.dtrsm(1.0, f.U11, y[f.r0:f.r1], lower=0, trans_a=1)
                y[f.r0:f.r1] = yo
                if f.upd.size:
                    y[f.upd] -= f.X.T @ yo
            for f in reversed(blk.fronts):                   # L^T x = y
                rhs = y[f.r0:f.r1]
                if f.upd.size:
                    rhs = rhs - f.X @ y[f.upd]
                y[f.r0:f.r1] = blas.dtrsm(1.0, f.U11, rhs, lower=0, trans_a=0)
            x[blk.order] = y.reshape((blk.order.size,) + b.shape[1:])
        return x


def cholesky(A: sp.spmatrix, node: np.ndarray) -> CholeskyFactor:
    """Factor the sparse symmetric positive definite ``A`` (n x n, both triangles stored,
    any SciPy format; a COO matrix may hold duplicate entries, which add) whose unknown i
    belongs to node ``node[i]`` (a node's unknowns are eliminated together; nodes are
    numbered 0 ... max(node)).

    Raises
    ------
    NotPositiveDefinite
        A pivot block is not positive definite (A is not, or is too ill-conditioned).
    """
    A = sp.csr_matrix(A, dtype=float)
    A.sum_duplicates()                           # (a CSR or CSC input keeps them)
    A.eliminate_zeros()
    n = A.shape[0]
    node = np.asarray(node, dtype=np.int64)
    sym = _symbolic(A, node, int(node.max()) + 1)
    ncomp, label = _components(A)
    rank = sym.rank[node]
    blocks = []
    for c in range(ncomp):
        idx = np.flatnonzero(label == c)
        blocks.append(_factor_block(A, idx, rank[idx], sym))
    return CholeskyFactor(n, blocks)


def _components(A: sp.csr_matrix) -> tuple[int, np.ndarray]:
    """The connected components of A's graph, numbered in the order of their smallest
    unknown (as ``connected_components(A, directed=False)`` numbers them).

    A's pattern is symmetric but for entries that summed to an exact zero in one triangle
    only: its strong components (no transpose: SciPy's undirected search builds A^T
    first, half its time on a 20k-element mesh) are then its components when no entry
    links two of them, which is checked; otherwise the undirected search runs."""
    ncomp, label = connected_components(A, directed=True, connection="strong")
    if ncomp > 1:
        row = np.repeat(np.arange(A.shape[0]), np.diff(A.indptr))
        if not np.array_equal(label[row], label[A.indices]):
            return connected_components(A, directed=False)
    first = np.full(ncomp, A.shape[0])
    np.minimum.at(first, label, np.arange(A.shape[0]))
    relabel = np.empty(ncomp, dtype=label.dtype)
    relabel[np.argsort(first)] = np.arange(ncomp)
    return ncomp, relabel[label]


def _symbolic(A: sp.csr_matrix, node: np.ndarray, m: int) -> _Symbolic:
    """Ordering and supernodes of the node graph (an edge for every entry (i, j) of A
    between node[i] and node[j]), shared by all blocks: a block's fill under the same
    ordering is part of the whole graph's."""
    L, perm = _node_factor(A, node, m)
    order, bounds, tops = _supernodes(L)
    newpos = np.empty(m, dtype=np.int64)
    newpos[order] = np.arange(m)
    # each supernode's update set: its top column's structure below the diagonal, in new
    # positions, sorted (all supernodes at once: a sort by (supernode, position))
    lo, hi = L.indptr[tops] + 1, L.indptr[tops + 1]
    size = hi - lo
    ptr = np.concatenate([[0], np.cumsum(size)])
    seg = np.repeat(np.arange(tops.size), size)
    pos = newpos[L.indices[np.repeat(lo - ptr[:-1], size) + np.arange(ptr[-1])]]
    below = pos[np.lexsort((pos, seg))]
    owner = np.repeat(np.arange(bounds.size - 1), np.diff(bounds))
    parent = np.full(tops.size, -1, dtype=np.int64)      # the owner of the first below
    has = size > 0
    parent[has] = owner[below[ptr[:-1][has]]]
    return _Symbolic(rank=newpos[perm], bounds=bounds, below=below, below_ptr=ptr,
                     parent=parent)


def _node_factor(A: sp.csr_matrix, node: np.ndarray, m: int
                 ) -> tuple[sp.csc_matrix, np.ndarray]:
    """The node graph's factor L (CSC, sorted; columns in elimination order) and the
    ordering (node perm[j] is eliminated j-th)."""
    # the graph as the pattern of P^T |A| P (P: unknown -> node), sparse products in C
    # (not one COO entry per entry of A: 4.2 M of them on a 20k-element mesh)
    n = A.shape[0]
    P = sp.csr_matrix((np.ones(n), node, np.arange(n + 1)), shape=(n, m))
    PT = sp.csr_matrix((np.ones(n), (node, np.arange(n))), shape=(m, n))
    pattern = sp.csr_matrix((np.ones(A.nnz), A.indices, A.indptr), shape=A.shape)
    G = PT @ pattern @ P
    G.sum_duplicates()                           # canonical: sorted, as the ordering saw it
    G = G + G.T
    G.data[:] = 1.0
    deg = np.asarray(G.sum(axis=1)).ravel()
    # strictly diagonally dominant on the node graph: no cancellation, no pivoting
    S = (sp.diags(deg + 1.0) - G * (0.5 / deg.max())).tocsc()
    lu = spla.splu(S, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                   options={"SymmetricMode": True})
    if not np.array_equal(lu.perm_c, lu.perm_r):
        raise RuntimeError("the node ordering pivoted off the diagonal")
    L = lu.L.tocsc()
    L.sort_indices()
    return L, lu.perm_c


def _supernodes(L: sp.csc_matrix) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`_supernodes_python` in C where it is compiled (``multifrontal.c``: the same
    integers; its Python loops cost ~70 ms a factorization of a 20k-element mesh)."""
    lib = multifrontal.load() if NATIVE else None
    if lib is None:
        return _supernodes_python(L)
    return multifrontal.supernodes(lib, L.indptr, L.indices, L.shape[0], SMALL_NODES,
                                   ZERO_SHARE)


def _supernodes_python(L: sp.csc_matrix) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Supernodes of the node factor L (columns in elimination order): fundamental ones
    (chains j -> j + 1 of nested structure), then each child merged into its parent while
    the merged front stays small or its explicit zeros few (CHOLMOD's relaxed
    amalgamation). Returns (order, bounds, top): the columns renumbered so that every
    supernode is contiguous (a postorder of the supernodal tree: the same fill), supernode
    g holding the new columns bounds[g]:bounds[g + 1], top[g] its last original column
    (whose structure below is its update set)."""
    m = L.shape[0]
    cnt = np.diff(L.indptr)                      # column counts, diagonal included
    parent = np.full(m, -1)
    has = cnt > 1
    parent[has] = L.indices[L.indptr[:-1][has] + 1]
    j = np.arange(m - 1)
    chain = np.zeros(m, dtype=bool)
    chain[:-1] = (parent[:-1] == j + 1) & (cnt[:-1] == cnt[1:] + 1)
    starts = np.flatnonzero(np.r_[True, ~chain[:-1]])
    ends = np.r_[starts[1:], m]
    ns = starts.size
    owner = np.repeat(np.arange(ns), ends - starts)
    top = ends - 1
    sparent = np.where(parent[top] >= 0, owner[np.maximum(parent[top], 0)], -1)
    ncols = (ends - starts).tolist()
    nupd = (cnt[top] - 1).tolist()
    true = [k * (k + 1) // 2 + k * u for k, u in zip(ncols, nupd, strict=True)]
    children: list[list[int]] = [[] for _ in range(ns)]
    for c, p in enumerate(sparent.tolist()):
        if p >= 0:
            children[p].append(c)
    merged_into = list(range(ns))                # a merged supernode's host
    members: list[list[int]] = [[g] for g in range(ns)]
    kids: list[list[int]] = [[] for _ in range(ns)]
    for p in range(ns):                          # children (smaller index) come first
        for c in children[p]:
            k = ncols[p] + ncols[c]
            dense = k * (k + 1) // 2 + k * nupd[p]
            zeros = 1.0 - (true[p] + true[c]) / dense
            limit = next(z for size, z in ZERO_SHARE if k <= size)
            if k <= SMALL_NODES or zeros <= limit:
                ncols[p] = k
                true[p] += true[c]
                members[p] = members[c] + members[p]
                kids[p].extend(kids[c])
                merged_into[c] = p
            else:
                kids[p].append(c)
    roots = [g for g in range(ns) if sparent[g] < 0 or False]
    order: list[np.ndarray] = []
    bounds = [0]
    tops = []
    stack = [(g, False) for g in reversed(roots)]
    while stack:                                 # postorder of the merged tree
        g, done = stack.pop()
        if done:
            cols = np.concatenate([np.arange(starts[h], ends[h]) for h in members[g]])
            order.append(np.sort(cols))
            bounds.append(bounds[-1] + cols.size)
            tops.append(int(top[g]))
            continue
        stack.append((g, True))
        stack.extend((c, False) for c in reversed(kids[g]))
    return np.concatenate(order), np.array(bounds), np.array(tops)


def _factor_block(A: sp.csr_matrix, idx: np.ndarray, rank: np.ndarray,
                  sym: _Symbolic) -> _Block:
    """Numeric multifrontal factorization of the block of unknowns ``idx`` (their nodes'
    ranks ``rank``) of A (canonical CSR; a connected component of its graph)."""
    order = np.argsort(rank, kind="stable")       # the block's unknowns, node by node
    m = sym.bounds[-1]
    start = np.searchsorted(rank[order], np.arange(m + 1))   # node k: start[k]:start[k+1]
    n = idx.size
    perm = idx[order]
    B = A[perm][:, perm]                          # the block, permuted
    row = np.repeat(np.arange(n), np.diff(B.indptr))
    up = B.indices >= row                         # its upper triangle, as CSR
    indptr = np.concatenate([[0], np.cumsum(np.bincount(row[up], minlength=n))])
    Ap = sp.csr_matrix((B.data[up], B.indices[up], indptr), shape=(n, n))
    row = row[up]
    # every supernode's update unknowns, at once: upd of s = upd_all[uptr[s]:uptr[s + 1]]
    below = sym.below
    size = start[below + 1] - start[below]
    upd_all = np.repeat(start[below] - np.cumsum(size) + size, size) + np.arange(size.sum())
    nfront = sym.below_ptr.size - 1
    front_of = np.repeat(np.arange(nfront), np.diff(sym.below_ptr))
    per = np.bincount(front_of, weights=size, minlength=nfront).astype(np.int64)
    uptr = np.concatenate([[0], np.cumsum(per)])
    lib = multifrontal.load() if NATIVE else None
    if lib is not None:
        fronts, packed = _numeric_native(lib, sym, start, upd_all, uptr, Ap, n)
        return _Block(order=idx[order], fronts=fronts, packed=packed)
    fronts = _numeric_numpy(sym, start, upd_all, uptr, Ap, row, n)
    return _Block(order=idx[order], fronts=fronts)


def _numeric_native(lib, sym: _Symbolic, start: np.ndarray, upd_all: np.ndarray,
                    uptr: np.ndarray, Ap: sp.csr_matrix, n: int
                    ) -> tuple[list[_Front], _Packed]:
    """The fronts by multifrontal.c (:func:`_numeric_numpy`'s factor, bit for bit), also
    packed for the compiled solve."""
    code, k, off, out, (s, info) = multifrontal.factor_fronts(
        lib, sym.bounds, start, upd_all, uptr, sym.parent, Ap, n)
    if code == 1:
        raise NotPositiveDefinite(
            f"the matrix is not positive definite (pivot {int(start[sym.bounds[s]]) + info}"
            f" of a block of {n} unknowns)")
    if code == 2:
        raise RuntimeError("the symbolic factor misses an entry of the matrix")
    if code == 3:
        raise RuntimeError("a child front's update unknowns are not in its parent")
    if code != 0:
        raise MemoryError("the multifrontal factorization ran out of memory")
    fronts = []
    for g in np.flatnonzero(k > 0).tolist():
        kg, o = int(k[g]), int(off[g])
        upd = upd_all[uptr[g]:uptr[g + 1]]
        r0 = int(start[sym.bounds[g]])
        U11 = out[o:o + kg * kg].reshape(kg, kg, order="F")
        X = out[o + kg * kg:o + kg * (kg + upd.size)].reshape(kg, upd.size, order="F")
        fronts.append(_Front(r0=r0, r1=r0 + kg, upd=upd, U11=U11, X=X))
    g = np.flatnonzero(k > 0)
    i64 = lambda a: np.ascontiguousarray(a, dtype=np.int64)  # noqa: E731
    packed = _Packed(r0=i64(start[sym.bounds[g]]), kf=i64(k[g]), off=i64(off[g]),
                     upd_all=i64(upd_all), ulo=i64(uptr[g]), un=i64(uptr[g + 1] - uptr[g]),
                     out=out)
    return fronts, packed


def _numeric_numpy(sym: _Symbolic, start: np.ndarray, upd_all: np.ndarray,
                   uptr: np.ndarray, Ap: sp.csr_matrix, row: np.ndarray,
                   n: int) -> list[_Front]:
    """The fronts in NumPy (the fallback without a compiler, and the C code's oracle)."""
    loc = np.empty(n, dtype=np.int64)
    stamp = np.full(n, -1, dtype=np.int64)
    fronts: list[_Front] = []
    pending: dict[int, list[tuple[np.ndarray, np.ndarray]]] = {}
    for s, (a, b) in enumerate(zip(sym.bounds[:-1].tolist(), sym.bounds[1:].tolist(),
                                   strict=True)):
        upd = upd_all[uptr[s]:uptr[s + 1]]
        r0, r1 = int(start[a]), int(start[b])
        k = r1 - r0
        children = pending.pop(s, ())
        if k == 0 and not children:
            continue
        loc[r0:r1] = np.arange(k)
        loc[upd] = k + np.arange(upd.size)
        stamp[r0:r1] = s
        stamp[upd] = s
        F = np.zeros((k + upd.size, k + upd.size), order="F")
        p0, p1 = Ap.indptr[r0], Ap.indptr[r1]
        cols = Ap.indices[p0:p1]
        if np.any(stamp[cols] != s):
            raise RuntimeError("the symbolic factor misses an entry of the matrix")
        F[row[p0:p1] - r0, loc[cols]] = Ap.data[p0:p1]      # upper triangle
        for cu, U in children:
            if np.any(stamp[cu] != s):
                raise RuntimeError("a child front's update unknowns are not in its parent")
            li = loc[cu]                          # increasing: upper goes to upper
            F[np.ix_(li, li)] += U
        if k == 0:                                # nothing of this block to eliminate here
            pending.setdefault(int(sym.parent[s]), []).append((upd, F))
            continue
        U11, info = lapack.dpotrf(F[:k, :k], lower=0, clean=1)
        if info != 0:
            raise NotPositiveDefinite(
                f"the matrix is not positive definite (pivot {r0 + info} of a block of "
                f"{n} unknowns)")
        if upd.size:
            X = blas.dtrsm(1.0, U11, F[:k, k:], lower=0, trans_a=1)
            U = blas.dsyrk(-1.0, X, beta=1.0, c=F[k:, k:], trans=1, lower=0)
            pending.setdefault(int(sym.parent[s]), []).append((upd, U))
        else:
            X = np.zeros((k, 0))
        fronts.append(_Front(r0=r0, r1=r1, upd=upd, U11=U11, X=X))
    return fronts
