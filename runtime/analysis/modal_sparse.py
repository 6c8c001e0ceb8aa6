"""Damped modes at any size: shift-invert on the sparse first-order pencil.

The linearised rod (``runtime.analysis.modal.Linearization``) is the pencil
``E x' + A x = 0``, ``x = (q, w)`` for a Kelvin-Voigt rod and ``x = (q, w, z)`` for a
generalized Maxwell rod, whose internal strains obey ``z' = (strain(q) - z) / theta_b``
(the rows are local to a segment or joint, so they keep the pencil sparse). Every block
couples nearest-neighbour cells only: a sparse LU of ``A + sigma E`` costs O(n). SuperLU
with its default COLAMD ordering (measured on this machine: N = 4000 Kelvin-Voigt, 48 000
unknowns, 0.04 s; the Maxwell cantilever at N = 1000, 30 009 unknowns with its internal
strains, 0.03 s); a reverse Cuthill-McKee ordering gives bandwidth 6 to 12 and the same
fill, so no banded solver of our own is needed.

Four steps (``sparse_modes``):

1. **Undamped modes.** The ``m = count + 6`` eigenpairs of ``K phi = omega^2 M phi``
   nearest the target ``omega_t^2`` (0: the lowest) by shift-invert Lanczos
   (``scipy.sparse.linalg.eigsh``; ``eigs`` for the non-symmetric K of a loaded state) with
   ARPACK's start vector fixed. The rigid motions the stiffness does not resist are
   deflated exactly through the bordered matrix ``[[K - sigma M, M Z], [Z^T M, 0]]``.
2. **Modal projection** (the prediction). The pencil restricted to
   ``V = diag(B, B, Z)`` and tested with ``diag(M B, B, Z)`` (Galerkin): B the modes and
   the static response to their damping forces (modal truncation augmentation, empty for
   stiffness-proportional damping), Z an orthonormal basis of the internal strains they
   drive (the columns of the z rows' coupling to q and w, separately for each relaxation
   rate, so the projection is exact on the z rows). Its eigenvalues (QZ on equilibrated
   rows, as the dense oracle) predict the damped eigenvalues: exactly for
   stiffness-proportional damping, to the coupling of the modes through C otherwise.
3. **Refinement in the pencil.** The predictions with a share of at least 10 % in the
   wanted modes are grouped (within a relative 1e-6: the twin bending pairs of a circular
   or square section form one group). Per group one sparse LU of ``A + sigma E`` with
   sigma next to the prediction, then block inverse iteration with a Rayleigh-Ritz step on
   ``T = (A + sigma E)^-1 E`` (eigenvalue ``lambda = sigma - 1/mu`` of T's ``mu``) from
   the lifted predicted eigenvectors plus two fixed pseudo-random vectors, until the Ritz
   values settle to 1e-13. Written by hand rather than ARPACK's ``eigs`` because that
   iterates one start vector: the second vector of a doubly degenerate eigenvalue enters
   its Krylov space only through rounding (twins came out slowly, or as one vector twice),
   and its small restarted basis took 0.35 s per eigenvalue at N = 1000; a block of g + 2
   vectors started next to the answer converges in a few solves.
4. **Rayleigh functional step** on the second-order problem ``T(lambda) q = 0`` of the
   positions (the internal strains eliminated per frequency: a sparse nq x nq matrix at
   each lambda): one or two steps of ``X <- T(s)^-1 T'(s) X`` and the eigenvalues of the
   projected ``X^T T(lambda) X`` (two-sided where T is not symmetric). The pencil's
   conditioning grows with the spread of the rod's frequencies ((N/L)^2): zeta of the
   first mode lost 5e-7 at N = 4000 in the pencil, 2e-9 after this step. A twin pair is
   one 2 x 2 projected problem with a double eigenvalue, so the twins' zeta agree to its
   round-off (1e-9 at N = 4000), not to the whole pencil's.

Everything is deterministic: fixed start vectors, SuperLU's fixed ordering, ordering
rules that do not depend on round-off (groups by relative distance, Ritz values by
distance to the shift).
"""

from __future__ import annotations

import math

import numpy as np
import scipy.linalg as la
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from runtime.analysis.modal import (
    Linearization,
    _clusters,
    _is_symmetric,
    _m_orthonormal,
    _singular,
    _span_clusters,
    _start_vector,
)

__all__ = ["deflated_inverse", "refine", "reduced_pencil", "sparse_modes",
           "undamped_modes"]

#: undamped modes computed beyond those shown (context for the projection and pairing)
EXTRA_MODES = 6
#: a prediction is refined when this share of it lies in the wanted modes
PICK_SHARE = 0.1
#: predictions within this relative distance are refined together (degenerate groups)
GROUP_RTOL = 1e-6
#: the refinement stops when every Ritz value of the group moved less than this (relative)
REFINE_RTOL = 1e-13
#: at most this many block inverse iterations per group
REFINE_MAXIT = 60
#: at most this many Rayleigh functional steps on T (:meth:`_SecondOrder.polish`)
POLISH_MAXIT = 4
#: a refined pair with a backward error above this is doubtful (a warning)
BACKWARD_ERROR_WARN = 1e-8


def deflated_inverse(lin: Linearization, Zn: np.ndarray, shift: float = 0.0
                     ) -> spla.LinearOperator:
    """x = (K - shift M)^-1 b on the M-orthogonal complement of span(Zn) (K Zn = 0 =
    Zn^T K): the solution of the bordered system
    ``[[K - shift M, M Zn], [Zn^T M, 0]] [x; mu] = [b; 0]``, regular though K is singular.
    As ARPACK's shift-invert operator it maps the rigid motions to 0, so they are never
    returned, and it is M-symmetric."""
    nq, k = lin.nq, Zn.shape[1]
    MZ = sp.csc_matrix(np.asarray(lin.M @ Zn))
    Kb = sp.bmat([[lin.K - shift * lin.M, MZ], [MZ.T, None]]).tocsc()
    try:
        lu = spla.splu(Kb)
    except RuntimeError as exc:
        raise _singular(exc) from None
    pad = np.zeros(k)

    def solve(b: np.ndarray) -> np.ndarray:
        return lu.solve(np.r_[np.ravel(b), pad])[:nq]

    return spla.LinearOperator((nq, nq), matvec=solve, dtype=float)


def undamped_modes(lin: Linearization, m: int, Zn: np.ndarray, shift: float = 0.0
                   ) -> tuple[np.ndarray, np.ndarray]:
    """The m eigenpairs (omega^2 ascending, M-normalised real vectors (nq, m)) of
    ``K phi = omega^2 M phi`` nearest ``shift`` (rad^2/s^2) in the M-orthogonal complement
    of the unresisted rigid motions Zn."""
    v0 = _start_vector(lin.nq)
    opinv = None
    if Zn.shape[1]:
        opinv = deflated_inverse(lin, Zn, shift)
        v0 = v0 - Zn @ (Zn.T @ (lin.M @ v0))     # start in the elastic complement
    try:
        if _is_symmetric(lin.K):  # Lanczos: M-orthogonal eigenvectors, repeated ones too
            w2, Phi = spla.eigsh(lin.K, k=m, M=lin.M, sigma=shift, which="LM", v0=v0,
                                 OPinv=opinv)
        else:
            w2, Phi = spla.eigs(lin.K, k=m, M=lin.M, sigma=shift, which="LM", v0=v0,
                                OPinv=opinv)
    except RuntimeError as exc:   # SuperLU: "Factor is exactly singular"
        raise _singular(exc) from None
    order = np.argsort(w2.real, kind="stable")
    w2, Phi = w2.real[order], Phi[:, order].real
    Phi = _span_clusters(lin, np.sqrt(np.maximum(w2, 0.0)), Phi)
    Phi /= np.sqrt(np.einsum("ik,ik->k", Phi, lin.M @ Phi))[None, :]
    return w2, Phi


def highest_omega2(lin: Linearization) -> float:
    """An upper bound (rad^2/s^2) of the discrete rod's natural frequencies squared: the
    largest eigenvalue of ``K phi = omega^2 M phi`` by Lanczos (ARPACK, regular mode with
    M; ``eigs`` for a non-symmetric K), a Ritz value converged to 1e-10 and raised by
    1e-6 so that it bounds the spectrum. A shift beyond it is no use to shift-invert (the
    nearest modes are the highest ones whatever the target) and a shift far beyond it
    loses every digit of ``K - shift M`` (a target of 1e30 Hz gave 1.7e22 Hz)."""
    v0 = _start_vector(lin.nq)
    if _is_symmetric(lin.K):
        top = spla.eigsh(lin.K, k=1, M=lin.M, which="LA", v0=v0, tol=1e-10,
                         return_eigenvectors=False)
    else:
        top = spla.eigs(lin.K, k=1, M=lin.M, which="LR", v0=v0, tol=1e-10,
                        return_eigenvectors=False)
    return float(np.max(top.real)) * (1.0 + 1e-6)


def _z_basis(lin: Linearization, Phi: np.ndarray) -> np.ndarray:
    """Orthonormal basis (nz, r) of the internal strains driven by the modes Phi: the
    columns of the z rows' coupling to q and w (``A[z, q] Phi``, ``A[z, w] Phi``), split by
    relaxation rate (the diagonal of ``A[z, z]`` over that of ``E[z, z]``), so that the
    Galerkin projection of the z rows is exact when those blocks are diagonal."""
    nq, n = lin.nq, lin.E.shape[0]
    if n == 2 * nq:
        return np.zeros((0, 0))
    z = slice(2 * nq, n)
    Ezz, Azz = lin.E[z, z].tocsr(), lin.A[z, z].tocsr()
    drive = np.column_stack([np.asarray(lin.A[z, :nq] @ Phi),
                             np.asarray(lin.A[z, nq:2 * nq] @ Phi)])
    diag = (abs(Ezz - sp.diags(Ezz.diagonal())).sum() == 0
            and abs(Azz - sp.diags(Azz.diagonal())).sum() == 0
            and np.all(Ezz.diagonal() != 0))
    if diag:
        rate = Azz.diagonal() / Ezz.diagonal()
        groups = [rate == r for r in np.unique(rate)]
    else:
        groups = [np.ones(n - 2 * nq, dtype=bool)]
    cols = []
    for g in groups:
        D = np.where(g[:, None], drive, 0.0)
        if np.any(D):
            cols.append(la.orth(D, rcond=1e-12))
    return np.column_stack(cols) if cols else np.zeros((n - 2 * nq, 0))


def reduced_pencil(lin: Linearization, Phi: np.ndarray
                   ) -> tuple[np.ndarray, np.ndarray, sp.csc_matrix]:
    """The Galerkin projection (Ar, Er, V) of the pencil on the modes Phi (M-orthonormal):
    ``V = diag(Phi, Phi, Z)`` (Z: :func:`_z_basis`), test space ``diag(M Phi, Phi, Z)``;
    the kinematic rows ``q' - w = 0`` become ``a' - b = 0``."""
    n = lin.E.shape[0]
    Z = _z_basis(lin, Phi)
    blocks = [Phi, Phi] + ([Z] if Z.size else [])
    V = sp.block_diag([sp.csc_matrix(b) for b in blocks], format="csc")
    W = sp.block_diag([sp.csc_matrix(np.asarray(lin.M @ Phi)), sp.csc_matrix(Phi)]
                      + ([sp.csc_matrix(Z)] if Z.size else []), format="csc")
    assert V.shape[0] == n and W.shape[0] == n
    Ar = np.asarray((W.T @ (lin.A @ V)).todense())
    Er = np.asarray((W.T @ (lin.E @ V)).todense())
    return Ar, Er, V


def _equilibration(A: sp.spmatrix, E: sp.spmatrix) -> np.ndarray:
    """Row scales d: each row of [A E] scaled to max 1 (the eigenvalues do not change;
    the internal-strain rows of a fast Maxwell branch carry 1/theta_b ~ 1e12)."""
    a = np.asarray(abs(A).max(axis=1).todense()).ravel()
    e = np.asarray(abs(E).max(axis=1).todense()).ravel()
    return 1.0 / np.maximum(np.maximum(a, e), 1e-300)


def refine(A: sp.spmatrix, E: sp.spmatrix, sigma: complex, X0: np.ndarray,
           ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The g = X0.shape[1] eigenvalues of ``-A x = lambda E x`` nearest sigma, from start
    vectors X0 (n, g) near their eigenvectors: block inverse iteration on
    ``T = (A + sigma E)^-1 E`` with a Rayleigh-Ritz step (module docstring, step 3).

    Returns (lambda (g,), eigenvectors (n, g), backward errors (g,)): sorted by distance
    to sigma; the backward error is ``|(A + lambda E) x| / ((|A| + |lambda| |E|) |x|)``
    (infinity norms). A and E should be row-equilibrated. A real sigma with real A and E
    iterates in real arithmetic."""
    n, g = X0.shape
    real = complex(sigma).imag == 0
    dtype = float if real else complex
    s = float(np.real(sigma)) if real else complex(sigma)
    try:
        lu = spla.splu((A + s * E).astype(dtype).tocsc())
    except RuntimeError:  # sigma is an eigenvalue to round-off: step off it
        s = s * (1 + 1e-9) + (0 if real else 1e-12j * abs(s))
        lu = spla.splu((A + s * E).astype(dtype).tocsc())
    rng = np.random.default_rng(20131105)       # fixed: the same iteration every run
    start = [X0.real, X0.imag] if real else [X0.astype(complex)]
    lam, X = _block_inverse(lu.solve, lambda Z: E @ Z,
                            np.column_stack(start + [rng.standard_normal((n, 2))]), g, s,
                            real)
    nA = float(abs(A).sum(axis=1).max())
    nE = float(abs(E).sum(axis=1).max())
    res = np.array([np.abs(A @ X[:, i] + lam[i] * (E @ X[:, i])).max()
                    / ((nA + abs(lam[i]) * nE) * np.abs(X[:, i]).max()) for i in range(g)])
    return lam, X, res


def _block_inverse(solve, apply_E, B: np.ndarray, g: int, s: complex, real: bool
                   ) -> tuple[np.ndarray, np.ndarray]:
    """Block inverse iteration Z <- solve(apply_E(Z)) from the columns of B with a
    Rayleigh-Ritz step each time; the g Ritz values of largest |mu| (nearest the shift s:
    lambda = s - 1/mu) and their vectors (unit 2-norm), once they move less than
    REFINE_RTOL."""
    B = B[:, np.linalg.norm(B, axis=0) > 0]
    Z, _ = np.linalg.qr(B)
    lam_old = None
    for _ in range(REFINE_MAXIT):
        Y = solve(np.asarray(apply_E(Z)))
        mu, S = la.eig(Z.conj().T @ Y)
        order = np.argsort(-np.abs(mu), kind="stable")
        mu, S = mu[order], S[:, order]
        lam = s - 1.0 / mu[:g]
        X = Y @ S
        Z, _ = np.linalg.qr(_real_basis(X, mu) if real else X)
        if lam_old is not None and np.all(np.abs(lam - lam_old) <= REFINE_RTOL * np.abs(lam)):
            break
        lam_old = lam
    X = X[:, :g]
    return lam, X / np.linalg.norm(X, axis=0)[None, :]


def _real_basis(X: np.ndarray, mu: np.ndarray) -> np.ndarray:
    """A real basis of the span of the Ritz vectors X of a real operator (eigenvalues mu):
    a real vector for a real mu, real and imaginary parts for a conjugate pair (the order
    of the columns kept)."""
    cols: list[np.ndarray] = []
    skip = False
    for i in range(X.shape[1]):
        if skip:
            skip = False
            continue
        if mu[i].imag != 0 and i + 1 < X.shape[1] and mu[i + 1] == np.conj(mu[i]):
            cols += [X[:, i].real, X[:, i].imag]
            skip = True
        else:
            cols.append(X[:, i].real)
    return np.column_stack(cols)


class _SecondOrder:
    """The pencil read as the (rational) second-order problem of the positions q:

        T(lambda) = lambda^2 M + lambda (C + Mq) + K
                    - sum_k (G_k + lambda H_k) / (lambda + r_k),

    ``G_k = Kz_k Azq_k``, ``H_k = Kz_k Azw_k``: the internal strains of rate r_k
    eliminated per frequency (a sparse nq x nq matrix at every lambda). Available
    (``ok``) when the kinematic rows are ``q' - w = 0`` and the internal-strain blocks
    diagonal, as :func:`runtime.analysis.modal.linearize` builds them. The eigenvalues
    of the pencil are those of T, a pencil eigenvector's q part is T's eigenvector.
    ``symmetric``: every matrix of T symmetric (a straight rod, and conservative loaded
    states), so that a right eigenvector is a left one too (``x^T T(lambda) = 0``)."""

    def __init__(self, lin: Linearization) -> None:
        nq, n = lin.nq, lin.E.shape[0]
        A, E = lin.A.tocsr(), lin.E.tocsr()
        q, w, z = slice(0, nq), slice(nq, 2 * nq), slice(2 * nq, n)
        eye = sp.identity(nq, format="csr")
        self.groups: list[tuple[float, sp.csr_matrix, sp.csr_matrix]] = []
        self.symmetric = False
        self.ok = (_small(E[q, q] - eye) and _small(E[q, nq:]) and _small(A[q, q])
                   and _small(A[q, w] + eye) and _small(A[q, z]))
        if self.ok and n > 2 * nq:
            Ezz, Azz = E[z, z], A[z, z]
            self.ok = (_small(E[w, z]) and _small(E[z, :2 * nq])
                       and _small(Ezz - sp.diags(Ezz.diagonal()))
                       and _small(Azz - sp.diags(Azz.diagonal()))
                       and bool(np.all(Ezz.diagonal() != 0)))
        if not self.ok:
            return
        self.M, self.C, self.K = E[w, w], (A[w, w] + E[w, q]).tocsr(), A[w, q]
        if n > 2 * nq:
            e, d = E[z, z].diagonal(), A[z, z].diagonal()
            rate = d / e
            Kz = A[w, z].tocsc()
            for r in np.unique(rate):
                k = np.flatnonzero(rate == r)
                Kk = Kz[:, k] @ sp.diags(1.0 / e[k])
                self.groups.append((float(r), (Kk @ A[z, :nq][k]).tocsr(),
                                    (Kk @ A[z, w][k]).tocsr()))
        mats = [self.M, self.C, self.K] + [X for _, G, H in self.groups for X in (G, H)]
        self.symmetric = all(_small(X - X.T, float(abs(X).max()) if X.nnz else 1.0)
                             for X in mats)

    def T(self, lam: complex) -> sp.csc_matrix:
        """T(lambda) (sparse; real for a real lambda)."""
        out = lam**2 * self.M + lam * self.C + self.K
        for r, G, H in self.groups:
            out = out - (G + lam * H) / (lam + r)
        return out.tocsc()

    def dT(self, lam: complex) -> sp.csr_matrix:
        """T'(lambda)."""
        out = 2 * lam * self.M + self.C
        for r, G, H in self.groups:
            out = out - H / (lam + r) + (G + lam * H) / (lam + r) ** 2
        return out.tocsr()

    def projected(self, lam: np.ndarray, X: np.ndarray, Y: np.ndarray) -> np.ndarray:
        """The eigenvalues of ``Y^T T(mu) X`` (g x g, linearised exactly and solved
        dense), each the one nearest its estimate in ``lam``: a two-sided Rayleigh-Ritz
        step (symmetric for a symmetric T, Y = X). A twin pair is one 2 x 2 problem with a
        double eigenvalue."""
        g = lam.size
        nb = 2 + len(self.groups)
        I, O = np.eye(g), np.zeros((g, g))
        rows = [[O] * nb for _ in range(nb)]
        rows[0][1] = -I
        rows[1][0], rows[1][1] = Y.T @ (self.K @ X), Y.T @ (self.C @ X)
        for j, (r, G, H) in enumerate(self.groups):
            rows[1][2 + j] = -I
            rows[2 + j][0] = -(Y.T @ (G @ X))
            rows[2 + j][1] = -(Y.T @ (H @ X))
            rows[2 + j][2 + j] = r * I
        As = np.block(rows).astype(complex)
        Es = la.block_diag(I, Y.T @ (self.M @ X), *([I] * len(self.groups)))
        dr = 1.0 / np.maximum(np.abs(As).max(axis=1), np.abs(Es).max(axis=1))
        mu = la.eigvals(-As * dr[:, None], Es * dr[:, None])
        mu = mu[np.isfinite(mu)]
        out = np.array(lam, dtype=complex)
        for i, v in enumerate(lam):
            j = int(np.argmin(np.abs(mu - v)))
            out[i] = mu[j]
            mu = np.delete(mu, j)
        return out

    def polish(self, lam: np.ndarray, Xq: np.ndarray) -> np.ndarray:
        """Rayleigh functional iteration on T from the pencil's eigenvalues lam (g,) and
        their eigenvectors' q parts Xq (nq, g): ``X <- T(s)^-1 T'(s) X`` (and the left
        vectors with the transpose, unless T is symmetric) at s = the mean of the current
        estimates, then :meth:`projected`; one step from the pencil's estimates (within
        1e-6), more while they move more than 1e-6 and converge (at most POLISH_MAXIT).
        Why: the pencil's eigenvectors are accurate to its conditioning, which for the
        slow eigenvalues of a long rod (shear modes (N/L)^2 times stiffer than the first
        bending mode) costs digits (5e-7 in zeta at N = 4000, and the twins of a Maxwell
        rod at N = 1000 apart by 1e-6) that T keeps (1e-9)."""
        X = Y = Xq
        cur = np.array(lam, dtype=complex)
        prev = math.inf
        for _ in range(POLISH_MAXIT):
            s = complex(np.mean(cur))
            real = s.imag == 0
            sv = s.real if real else s
            try:
                lu = spla.splu(self.T(sv))
            except RuntimeError:      # T(s) singular to round-off: s is the eigenvalue
                break
            D = self.dT(sv)
            X, _ = np.linalg.qr(lu.solve(np.asarray(D @ (X.real if real else X))))
            Y = X if self.symmetric else np.linalg.qr(
                lu.solve(np.asarray(D.T @ (Y.real if real else Y)), trans="T"))[0]
            new = self.projected(cur, X, Y)
            step = float(np.max(np.abs(new - cur) / np.abs(new)))
            cur = new
            # a step from estimates within 1e-6 leaves an error of their error times
            # (1e-6 / the gap to the next eigenvalue): below the projection's round-off
            # (1e-10 for the first mode at N = 4000); or the steps no longer shrink
            if step <= 1e-6 or step > 0.1 * prev:
                break
            prev = step
        return cur


def _same(l1: complex, x1: np.ndarray, l2: complex, x2: np.ndarray) -> bool:
    """Whether two refined eigenpairs are one (eigenvalues within 1e-8, vectors parallel
    to 1e-4, conjugates included): two predictions refined to the same eigenvalue."""
    for a, v in ((l2, x2), (np.conj(l2), np.conj(x2))):
        if abs(l1 - a) <= 1e-8 * max(abs(l1), 1e-300):
            cos = abs(np.vdot(x1, v)) / (np.linalg.norm(x1) * np.linalg.norm(v))
            if cos > 1 - 1e-4:
                return True
    return False


def _small(X: sp.spmatrix, scale: float = 1.0) -> bool:
    """Whether every entry of X is below 1e-12 scale (round-off of an exact zero)."""
    return X.nnz == 0 or float(abs(X).max()) <= 1e-12 * scale


def _groups(values: np.ndarray, rtol: float = GROUP_RTOL) -> list[np.ndarray]:
    """Indices of ``values`` (complex) grouped by chains of relative distance <= rtol,
    in the order of the values sorted by (|value|, real part, imaginary part)."""
    order = np.lexsort((values.imag, values.real, np.abs(values)))
    groups: list[list[int]] = []
    for i in order:
        for grp in groups:
            if any(abs(values[i] - values[j]) <= rtol * max(abs(values[i]), abs(values[j]),
                                                           1e-300) for j in grp):
                grp.append(int(i))
                break
        else:
            groups.append([int(i)])
    return [np.array(g) for g in groups]


def _augmented_basis(lin: Linearization, Phi: np.ndarray, Zn: np.ndarray, shift: float,
                     so: _SecondOrder) -> np.ndarray:
    """[Phi, R] (nq, m + r), M-orthonormal: the modes and the static response to their
    damping forces, ``R = (K - shift M)^-1 [C Phi, G_k Phi]`` (modal truncation
    augmentation) M-orthogonalised against Phi, the directions below 1e-5 of their size
    dropped (none are left for stiffness-proportional damping, C Phi = tau K Phi). Why:
    the slow root of an overdamped mode whose damping is not proportional (a torsion mode
    of a loaded rod coupled to bending) is a quasi-static balance of stiffness and
    damping forces that the modes alone predict poorly (-20 for -15.98 with 14 modes of
    the tests' loaded rod; in a cluster of roots near -1/tau a refinement from there found
    the wrong one); with R, -15.99."""
    forces = [np.asarray((so.C if so.ok else lin.C) @ Phi)]
    if so.ok:
        forces += [np.asarray(G @ Phi) for _, G, _ in so.groups]
    F = np.column_stack(forces)
    if not np.any(F):
        return Phi
    if Zn.shape[1]:
        op = deflated_inverse(lin, Zn, shift)
        R = np.column_stack([op.matvec(f) for f in F.T])
    else:
        try:
            R = spla.splu((lin.K - shift * lin.M).tocsc()).solve(F)
        except RuntimeError:          # shift on an eigenvalue: no augmentation
            return Phi
    size2 = float(np.max(np.einsum("ik,ik->k", R, lin.M @ R)))
    R -= Phi @ (Phi.T @ (lin.M @ R))
    G = R.T @ (lin.M @ R)
    ev, U = la.eigh(0.5 * (G + G.T))
    # directions above 1e-5 of the responses' M-norm: the rest is the round-off of
    # (K - shift M)^-1 (its condition number times eps: 5e-7 at N = 4000)
    keep = ev > 1e-10 * size2
    R = R @ (U[:, keep] / np.sqrt(ev[keep]))
    R -= Phi @ (Phi.T @ (lin.M @ R))          # once more, against round-off
    return np.column_stack([Phi, _m_orthonormal(R, lin.M)]) if R.shape[1] else Phi


def sparse_modes(lin: Linearization, wanted: np.ndarray, w2: np.ndarray, Phi: np.ndarray,
                 maxwell: bool, Zn: np.ndarray | None = None, shift: float = 0.0
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Damped eigenvalues (one per conjugate pair, Im >= 0; for a Maxwell rod the
    oscillatory ones only), their eigenvectors' q parts (nq, k) and backward errors in
    the pencil (:func:`refine`) for the undamped modes ``wanted`` (indices into Phi's
    columns), by modal projection and refinement (module docstring, steps 2 to 4);
    ``w2``, ``Phi``: the undamped modes
    (:func:`undamped_modes`), computed with the deflated rigid motions Zn at ``shift``."""
    m = Phi.shape[1]
    Zn = np.zeros((lin.nq, 0)) if Zn is None else Zn
    so = _SecondOrder(lin)
    B = _augmented_basis(lin, Phi, Zn, shift, so)
    Ar, Er, V = reduced_pencil(lin, B)
    dr = 1.0 / np.maximum(np.abs(Ar).max(axis=1), np.abs(Er).max(axis=1))
    mu, Y = la.eig(-Ar * dr[:, None], Er * dr[:, None])
    fin = np.isfinite(mu)
    mu, Y = mu[fin], Y[:, fin]
    tiny = np.abs(mu.imag) <= 1e-7 * np.abs(mu)
    mu = np.where(tiny, mu.real + 0j, mu)
    keep = (mu.imag > 0) | ((mu.imag == 0) & (not maxwell))
    mu, Y = mu[keep], Y[:, keep]
    # the predictions the wanted modes may be paired with: a share of their q part's
    # M-norm of at least PICK_SHARE in the wanted modes (where damping couples modes, not
    # proportional or about a loaded state, a wanted mode's slow eigenvalue can have most
    # of its participation in its neighbours or beyond the modes computed: 18 % in its
    # own mode for the torsion mode of the tests' loaded rod)
    part = np.abs(Y[:m]) ** 2
    total = np.maximum(np.sum(np.abs(Y[:B.shape[1]]) ** 2, axis=0), 1e-300)
    omega = np.sqrt(np.maximum(w2, 0.0))
    cl = _clusters(omega)
    owner = np.empty(m, dtype=int)
    for c, g in enumerate(cl):
        owner[g] = c
    want = owner[np.asarray(wanted, dtype=int)]
    if want.size == 0:
        return np.zeros(0, dtype=complex), np.zeros((lin.nq, 0), dtype=complex), np.zeros(0)
    pick = part[np.isin(owner, want)].sum(axis=0) >= PICK_SHARE * total
    mu, Y = mu[pick], Y[:, pick]
    if mu.size == 0:
        return np.zeros(0, dtype=complex), np.zeros((lin.nq, 0), dtype=complex), np.zeros(0)
    X0 = np.asarray(V @ Y)
    d = _equilibration(lin.A, lin.E)
    Ad, Ed = (sp.diags(d) @ lin.A).tocsc(), (sp.diags(d) @ lin.E).tocsc()
    lams: list[complex] = []
    vecs: list[np.ndarray] = []
    errs: list[float] = []
    found: list[tuple[complex, np.ndarray]] = []
    for grp in _groups(mu):
        s = complex(np.mean(mu[grp]))
        s = complex(s.real * (1 + 1e-7), s.imag * (1 + 1e-7)) if s != 0 else 1e-12
        lam, X, res = refine(Ad, Ed, s, X0[:, grp])
        if so.ok:
            fixed = so.polish(lam, X[: lin.nq])
            # a step far beyond the pencil's own accuracy went to another eigenvalue of
            # T: the pencil's eigenvalue stands
            good = np.abs(fixed - lam) <= 1e-4 * np.abs(lam)
            lam = np.where(good, fixed, lam)
        for la_, x, err in zip(lam, X.T, res, strict=True):
            la_ = complex(la_)
            if any(_same(la_, x, l2, x2) for l2, x2 in found):
                continue              # found from another prediction already
            found.append((la_, x))
            if abs(la_.imag) <= 1e-7 * abs(la_):
                la_ = complex(la_.real, 0.0)
            if la_.imag < 0:
                la_, x = la_.conjugate(), x.conj()
            if maxwell and la_.imag == 0:
                continue
            lams.append(la_)
            vecs.append(x[: lin.nq])
            errs.append(float(err))
    if not lams:
        return (np.zeros(0, dtype=complex), np.zeros((lin.nq, 0), dtype=complex),
                np.zeros(0))
    return np.array(lams), np.array(vecs).T, np.array(errs)
