"""Consistent initial values of ``F(t, y, y') = 0`` (IDA's ``IDA_YA_YDP_INIT``): at the
start of a run and at every restart of the integrator."""

from __future__ import annotations

import math

import numpy as np

from runtime.solvers.protocols import ResidualProblem, band_storage

from .bdf import IntegrationError
from .native.band import band_solve


def consistent_initial(
    problem: ResidualProblem,
    t0: float,
    y0: np.ndarray,
    yp0_guess: np.ndarray,
    *,
    tol: float = 1e-10,
    max_iter: int = 20,
) -> tuple[np.ndarray, np.ndarray]:
    """Consistent initial values like IDA's ``IDA_YA_YDP_INIT``.

    Keeps the differential components of ``y0`` and solves ``F(t0, y, y') = 0`` for the
    differential components of ``y'`` and the algebraic components of ``y`` (given by
    ``problem.differential``), by Newton's method with the exact iteration matrix
    (columns of dF/dy' for differential, of dF/dy for algebraic unknowns) and a
    backtracking line search on ``|F|``.

    Returns ``(y0, yp0)`` (new arrays). Raises
    :class:`~runtime.solvers.bdf.IntegrationError` (with the initial guess as state) if
    Newton does not reach ``max|F| <= tol * scale``, where ``scale`` is ``max(1, max|F|)``
    at the guess.
    """
    n = int(problem.n)
    kl, ku = int(problem.kl), int(problem.ku)
    diff = np.asarray(problem.differential, dtype=bool)
    y = np.array(y0, dtype=float)
    yp = np.array(yp0_guess, dtype=float)
    res = np.empty(n)
    ab = band_storage(n, kl, ku)
    ab1 = band_storage(n, kl, ku)

    def fnorm(yv: np.ndarray, ypv: np.ndarray) -> float:
        problem.residual(t0, yv, ypv, res)
        return float(np.max(np.abs(res), initial=0.0))

    r = fnorm(y, yp)
    scale = max(1.0, r) if math.isfinite(r) else 1.0
    for _ in range(max_iter):
        if not math.isfinite(r):
            break
        if r <= tol * scale:
            return y, yp
        f = res.copy()
        if hasattr(problem, "newton_system"):   # coupled blocks (an assembly): sparse
            du, info = _sparse_mixed_solve(problem, t0, y, yp, diff, f)
        else:
            ab.fill(0.0)
            problem.jacobian_band(t0, y, yp, 0.0, ab)  # dF/dy
            ab1.fill(0.0)
            problem.jacobian_band(t0, y, yp, 1.0, ab1)  # dF/dy + dF/dy'
            ab1 -= ab  # dF/dy'
            ab[:, diff] = ab1[:, diff]
            du, info = band_solve(ab, kl, ku, f)
        if info != 0:
            break
        lam = 1.0
        while lam >= 1.0 / 1024:
            yt, ypt = y.copy(), yp.copy()
            ypt[diff] -= lam * du[diff]
            yt[~diff] -= lam * du[~diff]
            rt = fnorm(yt, ypt)
            if math.isfinite(rt) and rt <= (1.0 - 1e-4 * lam) * r:
                break
            lam *= 0.5
        else:
            break
        y, yp, r = yt, ypt, rt
    if math.isfinite(r) and r <= tol * scale:
        return y, yp
    raise IntegrationError(
        f"consistent_initial: Newton for the algebraic components of y and the "
        f"differential components of y' at t0 = {t0:.9g} did not converge (max|F| = "
        f"{r:.3g}, target {tol * scale:.3g}). Check that the problem is index 1 and that "
        "the algebraic equations are solvable near the given y0.",
        t=float(t0),
        y=np.array(y0, dtype=float),
        yp=np.array(yp0_guess, dtype=float),
        h=0.0,
        residual_norm=r,
        worst_index=int(np.argmax(np.abs(res))) if n else -1,
    )


def _sparse_mixed_solve(problem, t0: float, y: np.ndarray, yp: np.ndarray,
                        diff: np.ndarray, f: np.ndarray) -> tuple[np.ndarray, int]:
    """The Newton step of :func:`consistent_initial` for a problem whose Jacobian is not
    banded (``dF_dy_sparse``, ``dF_dyp_sparse``: an assembly of rods), by SciPy's sparse
    LU; info 1 when singular."""
    import scipy.sparse as sp
    import scipy.sparse.linalg as spla

    Jy = problem.dF_dy_sparse(t0, y, yp).tocsc()
    Jp = problem.dF_dyp_sparse(t0, y, yp).tocsc()
    d = sp.diags(diff.astype(float))
    M = (Jp @ d + Jy @ sp.diags((~diff).astype(float))).tocsc()
    try:
        return spla.splu(M).solve(f), 0
    except RuntimeError:               # "Factor is exactly singular"
        return f, 1
