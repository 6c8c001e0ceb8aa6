"""The section's sparse Cholesky (runtime/section/cholesky.py) against SciPy's SuperLU and
dense LAPACK solves: finite-element-like matrices with several unknowns per node, coupled
and decoupled (independent blocks), nodes with fewer unknowns, many right-hand sides, and
a matrix that is not positive definite."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from runtime.section.cholesky import NotPositiveDefinite, cholesky


def _grid_matrix(nx: int, ny: int, per_node: int, coupled: bool, seed: int = 0):
    """Sum of random SPD element matrices over the triangles of an nx x ny grid of nodes
    (per_node unknowns each, node-major), plus a small shift: (A csr, node of each
    unknown). Uncoupled: component c of a node couples only with component c."""
    rng = np.random.default_rng(seed)
    idx = np.arange(nx * ny).reshape(ny, nx)
    tri = np.concatenate([
        np.stack([idx[:-1, :-1], idx[:-1, 1:], idx[1:, :-1]], axis=-1).reshape(-1, 3),
        np.stack([idx[1:, 1:], idx[1:, :-1], idx[:-1, 1:]], axis=-1).reshape(-1, 3)])
    k = 3 * per_node
    G = rng.standard_normal((tri.shape[0], k, k))
    Ke = G @ G.transpose(0, 2, 1)
    if not coupled:
        comp = np.tile(np.arange(per_node), 3)
        Ke = Ke * (comp[:, None] == comp[None, :])
    dofs = (per_node * tri[:, :, None] + np.arange(per_node)).reshape(-1, k)
    n = per_node * nx * ny
    rows = np.repeat(dofs, k, axis=1).ravel()
    cols = np.tile(dofs, (1, k)).ravel()
    A = sp.csr_matrix((Ke.ravel(), (rows, cols)), shape=(n, n)) + 1e-3 * sp.eye(n)
    return A.tocsr(), np.arange(n) // per_node


@pytest.mark.parametrize("coupled", [True, False])
def test_solves_like_superlu(coupled):
    A, node = _grid_matrix(23, 17, 3, coupled)
    b = np.random.default_rng(1).standard_normal((A.shape[0], 6))
    f = cholesky(A, node)
    x = f.solve(b)
    ref = spla.splu(A.tocsc()).solve(b)
    assert np.abs(x - ref).max() <= 1e-9 * np.abs(ref).max()
    assert np.abs(A @ x - b).max() <= 1e-10 * np.abs(b).max() * np.abs(A).max()
    # one right-hand side as a vector
    assert np.allclose(f.solve(b[:, 2]), x[:, 2], rtol=0, atol=1e-12 * np.abs(x).max())


def test_decoupled_components_are_factored_apart():
    """An uncoupled matrix splits into one block per component; the result is the same as
    for the whole matrix."""
    A, node = _grid_matrix(15, 11, 3, coupled=False)
    f = cholesky(A, node)
    assert len(f._blocks) == 3
    b = np.random.default_rng(2).standard_normal(A.shape[0])
    assert np.allclose(f.solve(b), np.linalg.solve(A.toarray(), b), rtol=1e-10, atol=0)


def test_pinned_unknowns_and_coo_duplicates():
    """Some nodes with fewer unknowns (pinned dofs removed), the matrix given as COO with
    duplicate entries (element contributions not yet summed)."""
    A, node = _grid_matrix(12, 9, 3, coupled=True, seed=3)
    keep = np.setdiff1d(np.arange(A.shape[0]), [0, 1, 2, 40, 41, 77])
    Af = A[keep][:, keep].tocoo()
    dup = sp.coo_matrix((np.r_[0.5 * Af.data, 0.5 * Af.data], (np.r_[Af.row, Af.row],
                                                              np.r_[Af.col, Af.col])),
                        shape=Af.shape)
    f = cholesky(dup, node[keep])
    b = np.random.default_rng(4).standard_normal((keep.size, 2))
    assert np.allclose(f.solve(b), np.linalg.solve(Af.toarray(), b), rtol=1e-10, atol=0)


def test_small_and_dense():
    M = np.array([[4.0, 1.0, 0.5], [1.0, 3.0, 0.2], [0.5, 0.2, 2.0]])
    f = cholesky(sp.csr_matrix(M), np.zeros(3, dtype=int))
    assert np.allclose(f.solve(np.eye(3)), np.linalg.inv(M), rtol=1e-13, atol=0)
    f1 = cholesky(sp.csr_matrix([[2.0]]), np.zeros(1, dtype=int))
    assert f1.solve(np.array([3.0]))[0] == pytest.approx(1.5)


def test_not_positive_definite_raises():
    A, node = _grid_matrix(8, 8, 2, coupled=True, seed=5)
    A = (A - 50.0 * sp.eye(A.shape[0])).tocsr()
    with pytest.raises(NotPositiveDefinite, match="not positive definite"):
        cholesky(A, node)


def _both_paths(monkeypatch, A, node):
    from runtime.section import cholesky as C

    out = {}
    for native in (False, True):
        monkeypatch.setattr(C, "NATIVE", native)
        out[native] = cholesky(A, node)
    return out[False], out[True]


@pytest.mark.parametrize("case", ["coupled", "uncoupled", "pinned"])
def test_the_compiled_numeric_phase_is_the_numpy_loop_bit_for_bit(case, monkeypatch):
    """multifrontal.c factors every front as the NumPy loop does (same assembly order,
    SciPy's own LAPACK and BLAS): the same factors and solutions, bit for bit."""
    from runtime.section import multifrontal

    if multifrontal.load() is None:
        pytest.skip("no C compiler: the NumPy loop is the only path")
    A, node = _grid_matrix(19, 13, 3, coupled=case != "uncoupled", seed=7)
    if case == "pinned":
        keep = np.setdiff1d(np.arange(A.shape[0]), [0, 1, 2, 40, 41, 77, 300])
        A, node = A[keep][:, keep].tocsr(), node[keep]
    ref, got = _both_paths(monkeypatch, A, node)
    assert len(ref._blocks) == len(got._blocks) == (3 if case == "uncoupled" else 1)
    for rb, gb in zip(ref._blocks, got._blocks, strict=True):
        assert np.array_equal(rb.order, gb.order)
        assert len(rb.fronts) == len(gb.fronts) > 10
        for rf, gf in zip(rb.fronts, gb.fronts, strict=True):
            assert (rf.r0, rf.r1) == (gf.r0, gf.r1) and np.array_equal(rf.upd, gf.upd)
            assert np.array_equal(rf.U11, gf.U11) and np.array_equal(rf.X, gf.X)
    b = np.random.default_rng(8).standard_normal((A.shape[0], 3))
    x = ref.solve(b)
    assert np.allclose(got.solve(b), x, rtol=0, atol=1e-13 * np.abs(x).max())


def _tridiagonal(n: int):
    A = sp.diags([np.full(n - 1, -1.0), np.full(n, 2.5), np.full(n - 1, -1.0)], [-1, 0, 1])
    return A.tocsr(), np.arange(n)


@pytest.mark.parametrize("case, amalgamate, shapes", [
    ("grid, 3 per node", True, None),
    ("grid, 1 per node", False, "one pivot, many updates"),
    ("tridiagonal", True, "many pivots, one update"),
    ("tridiagonal", False, "one pivot, one update"),
])
def test_the_compiled_solve_is_the_python_loop(case, amalgamate, shapes, monkeypatch):
    """multifrontal.c's solve (kv_mf_solve) against the Python loop on the same factor,
    with the fronts where NumPy's matmul leaves the matrix-matrix product (one pivot, one
    update unknown: a matrix-vector product or plain products) among them. The two agree
    bit for bit where NumPy's and SciPy's OpenBLAS take the same kernels (this project's
    machines); the test allows round-off, as other CPUs may differ there."""
    from runtime.section import cholesky as C
    from runtime.section import multifrontal

    if multifrontal.load() is None:
        pytest.skip("no C compiler: the Python loop is the only path")
    monkeypatch.setattr(C, "NATIVE", True)
    if not amalgamate:                   # fundamental supernodes only: fronts of one node
        monkeypatch.setattr(C, "SMALL_NODES", 0)
        monkeypatch.setattr(C, "ZERO_SHARE", ((np.inf, -1.0),))
    if case.startswith("grid"):
        A, node = _grid_matrix(21, 14, 3 if "3" in case else 1, coupled=True, seed=11)
    else:
        A, node = _tridiagonal(200)
    f = cholesky(A, node)
    assert all(b.packed is not None for b in f._blocks)
    kinds = [(fr.r1 - fr.r0, fr.upd.size) for b in f._blocks for fr in b.fronts]
    want = {"one pivot, many updates": lambda m, u: m == 1 and u > 1,
            "many pivots, one update": lambda m, u: m > 1 and u == 1,
            "one pivot, one update": lambda m, u: m == 1 and u == 1}
    if shapes:
        assert sum(want[shapes](m, u) for m, u in kinds) >= 10
    b = np.random.default_rng(12).standard_normal((A.shape[0], 6))
    calls = []
    real = multifrontal.solve_fronts
    monkeypatch.setattr(multifrontal, "solve_fronts",
                        lambda *a: calls.append(1) or real(*a))
    got = f.solve(b)
    assert calls, "the compiled solve did not run"
    for blk in f._blocks:
        monkeypatch.setattr(blk, "packed", None)
    ref = f.solve(b)
    assert len(calls) == 1
    assert np.allclose(got, ref, rtol=0, atol=1e-13 * np.abs(ref).max())
    assert np.abs(A @ got - b).max() <= 1e-10 * np.abs(b).max() * np.abs(A).max()


def test_the_compiled_solve_refuses_a_wrong_layout():
    from runtime.section import multifrontal

    lib = multifrontal.load()
    if lib is None:
        pytest.skip("no C compiler")
    z = np.zeros(1, dtype=np.int64)
    for y in (np.zeros((4, 3)), np.zeros((4, 1), order="F"),
              np.zeros((4, 3), dtype=np.float32, order="F")):
        with pytest.raises(ValueError, match="Fortran order with >= 2 columns"):
            multifrontal.solve_fronts(lib, z, z, z, z, z, z, np.zeros(1), y)


def test_both_numeric_phases_refuse_an_indefinite_matrix_alike(monkeypatch):
    from runtime.section import cholesky as C

    A, node = _grid_matrix(8, 8, 2, coupled=True, seed=5)
    A = (A - 50.0 * sp.eye(A.shape[0])).tocsr()
    messages = []
    for native in (False, True):
        monkeypatch.setattr(C, "NATIVE", native)
        with pytest.raises(NotPositiveDefinite, match="not positive definite") as err:
            cholesky(A, node)
        messages.append(str(err.value))
    assert messages[0] == messages[1]


def _halves(M):
    """M (CSR or CSC, canonical) with every stored entry split into two stored halves,
    duplicates in the same format (SciPy keeps them until summed)."""
    line = np.repeat(np.arange(M.shape[0] if M.format == "csr" else M.shape[1]),
                     np.diff(M.indptr))
    order = np.argsort(np.r_[line, line], kind="stable")
    data = np.r_[0.5 * M.data, 0.5 * M.data][order]
    indices = np.r_[M.indices, M.indices][order]
    kind = sp.csr_matrix if M.format == "csr" else sp.csc_matrix
    out = kind((data, indices, 2 * M.indptr), shape=M.shape)
    assert not out.has_canonical_format
    return out


@pytest.mark.parametrize("fmt", ["csr", "csc", "coo"])
@pytest.mark.parametrize("native", [False, True])
def test_duplicate_entries_add_in_every_format(fmt, native, monkeypatch):
    """A matrix given with each entry split in two stored halves (duplicates) is the
    matrix of their sums, in every SciPy format."""
    from runtime.section import cholesky as C

    monkeypatch.setattr(C, "NATIVE", native)
    A, node = _grid_matrix(10, 8, 3, coupled=True, seed=9)
    if fmt == "coo":
        Ac = A.tocoo()
        dup = sp.coo_matrix((np.r_[0.5 * Ac.data, 0.5 * Ac.data],
                             (np.r_[Ac.row, Ac.row], np.r_[Ac.col, Ac.col])), shape=A.shape)
    else:
        dup = _halves(A.asformat(fmt))
    b = np.random.default_rng(10).standard_normal(A.shape[0])
    x = cholesky(dup, node).solve(b)
    assert np.abs(x - spla.spsolve(A.tocsc(), b)).max() <= 1e-10 * np.abs(x).max()


def _random_graph_matrix(m: int, degree: float, seed: int):
    """A random symmetric pattern on m nodes (about ``degree`` neighbours each, some
    isolated nodes and several components), as an SPD matrix with one unknown a node."""
    rng = np.random.default_rng(seed)
    k = int(degree * m / 2)
    i, j = rng.integers(0, m, k), rng.integers(0, m, k)
    keep = (i != j) & (i < 0.9 * m) & (j < 0.9 * m)       # the last tenth isolated
    G = sp.coo_matrix((np.ones(keep.sum()), (i[keep], j[keep])), shape=(m, m)).tocsr()
    G = G + G.T
    G.data[:] = 1.0
    A = (sp.diags(np.asarray(G.sum(axis=1)).ravel() + 1.0) - 0.4 * G).tocsr()
    return A, np.arange(m)


@pytest.mark.parametrize("case", ["grid", "grid3", "sparse", "dense", "path", "one"])
def test_the_compiled_supernodes_are_the_python_loop_integer_for_integer(case):
    """kv_mf_supernodes (multifrontal.c) gives _supernodes_python's columns, bounds and
    tops on node factors of every shape: a mesh's grid, a random graph with isolated
    nodes and several components, a nearly dense graph (large merged fronts), a path
    (one chain) and a single node; and the symbolic phase built on it the same ranks,
    update sets and tree."""
    from runtime.section import cholesky as C
    from runtime.section import multifrontal

    lib = multifrontal.load()
    if lib is None:
        pytest.skip("no C compiler: the Python loop is the only path")
    if case == "grid":
        A, node = _grid_matrix(31, 23, 1, coupled=True, seed=3)
    elif case == "grid3":
        A, node = _grid_matrix(17, 11, 3, coupled=True, seed=4)
    elif case == "sparse":
        A, node = _random_graph_matrix(3000, 3.0, seed=5)
    elif case == "dense":
        A, node = _random_graph_matrix(120, 60.0, seed=6)
    elif case == "path":
        m = 500
        A = sp.diags([np.full(m - 1, -1.0), np.full(m, 3.0), np.full(m - 1, -1.0)],
                     [-1, 0, 1]).tocsr()
        node = np.arange(m)
    else:
        A, node = sp.csr_matrix(np.array([[2.0]])), np.array([0])
    m = int(node.max()) + 1
    L, _ = C._node_factor(A, node, m)
    ref = C._supernodes_python(L)
    got = multifrontal.supernodes(lib, L.indptr, L.indices, m, C.SMALL_NODES, C.ZERO_SHARE)
    assert len(ref[1]) > (1 if case == "one" else 3) or case in ("path", "one")
    for r, g in zip(ref, got, strict=True):
        assert r.dtype.kind == g.dtype.kind == "i" and np.array_equal(r, g)
    # the whole symbolic phase on either path (the update sets and the tree built on them)
    syms = []
    for native in (False, True):
        C.NATIVE = native
        try:
            syms.append(C._symbolic(A, node, m))
        finally:
            C.NATIVE = True
    for field in ("rank", "bounds", "below", "below_ptr", "parent"):
        assert np.array_equal(getattr(syms[0], field), getattr(syms[1], field)), field


def test_the_update_sets_are_the_top_columns_structure():
    """_symbolic's update set of every supernode is its top column's structure below the
    diagonal (new positions, sorted) and its parent the supernode owning the first of
    them, as the per-supernode loop built them before."""
    from runtime.section import cholesky as C

    A, node = _grid_matrix(23, 19, 2, coupled=True, seed=9)
    m = int(node.max()) + 1
    L, perm = C._node_factor(A, node, m)
    sym = C._symbolic(A, node, m)
    order, bounds, tops = C._supernodes_python(L)
    newpos = np.empty(m, dtype=np.int64)
    newpos[order] = np.arange(m)
    owner = np.repeat(np.arange(bounds.size - 1), np.diff(bounds))
    assert np.array_equal(sym.rank, newpos[perm])
    for g, t in enumerate(tops):
        want = np.sort(newpos[L.indices[L.indptr[t] + 1:L.indptr[t + 1]]])
        got = sym.below[sym.below_ptr[g]:sym.below_ptr[g + 1]]
        assert np.array_equal(got, want)
        assert sym.parent[g] == (owner[want[0]] if want.size else -1)


def test_the_components_are_the_undirected_ones():
    """cholesky's components (strong components of the pattern, no transpose) numbered as
    SciPy's undirected search numbers them: an uncoupled grid (three components), a
    matrix with isolated unknowns, and a pattern whose only link between two blocks
    is an entry in one triangle (an exact zero in the other: the undirected search)."""
    from scipy.sparse.csgraph import connected_components

    from runtime.section.cholesky import _components

    A, _ = _grid_matrix(9, 7, 3, coupled=False, seed=2)
    rng = np.random.default_rng(3)
    p = rng.permutation(A.shape[0])
    cases = [A, A[p][:, p].tocsr(), sp.eye(5, format="csr")]
    B = sp.block_diag([sp.csr_matrix(np.ones((3, 3))), sp.csr_matrix(np.ones((2, 2)))])
    B = B.tolil()
    B[4, 0] = 1.0                          # row 4 reaches block 0, row 0 does not reach 4
    cases.append(B.tocsr())
    for M in cases:
        M = sp.csr_matrix(M)
        ncomp, label = _components(M)
        ref_n, ref = connected_components(M, directed=False)
        assert ncomp == ref_n and np.array_equal(label, ref)
    assert _components(cases[-1])[0] == 1
