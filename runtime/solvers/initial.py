"""Consistent initial values of ``F(t, y, y') = 0`` (IDA's ``IDA_YA_YDP_INIT``): at the
start of a run and at every restart of the integrator."""

from __future__ import annotations

import math

import numpy as np

from runtime.solvers.protocols import ResidualProblem, band_storage

from .bdf import IntegrationError
from .native.band import BandLU, band_solve


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


def consistent_sensitivities(problem, t0: float, y: np.ndarray, yp: np.ndarray,
                             s0: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Consistent initial sensitivities: for each parameter i (rows of ``s0``, (k, n))
    keep the differential components of ``s0[i]`` and solve ``F_y s + F_y' s' +
    F_theta_i = 0`` (``problem.sensitivity_residual``) for the differential components
    of ``s'`` and the algebraic components of ``s``: the equations are linear, so one
    solve with the mixed matrix of :func:`consistent_initial` (its columns of dF/dy' for
    differential, of dF/dy for algebraic unknowns) at the state's consistent ``(y,
    y')`` is exact. The algebraic unknowns' rates are the prescribed ones where the
    problem gives them (``sensitivity_prescribed_rates(t, i, sp)``), else 0. Returns
    ``(s, s')`` (new arrays, (k, n))."""
    s = np.array(s0, dtype=float, copy=True)
    k, n = s.shape
    diff = np.asarray(problem.differential, dtype=bool)
    sp = np.zeros_like(s)
    res = np.empty(n)
    sparse = hasattr(problem, "newton_system")
    if not sparse:
        kl, ku = int(problem.kl), int(problem.ku)
        ab = band_storage(n, kl, ku)
        ab1 = band_storage(n, kl, ku)
        problem.jacobian_band(t0, y, yp, 0.0, ab)
        problem.jacobian_band(t0, y, yp, 1.0, ab1)
        ab1 -= ab
        ab[:, diff] = ab1[:, diff]
        lu = BandLU(ab, kl, ku)                 # one factorisation for every parameter
    rates = getattr(problem, "sensitivity_prescribed_rates", None)
    for i in range(k):
        problem.sensitivity_residual(t0, y, yp, i, s[i], sp[i], res)
        if sparse:
            du, info = _sparse_mixed_solve(problem, t0, y, yp, diff, res.copy())
        else:
            du, info = (lu.solve(res), 0) if lu.info == 0 else (res, lu.info)
        if info != 0:
            raise IntegrationError(
                "consistent_sensitivities: the mixed iteration matrix at t0 = "
                f"{t0:.9g} is singular (the problem is not index 1 there)", t=float(t0),
                y=np.array(y), yp=np.array(yp), h=0.0, residual_norm=math.inf,
                worst_index=-1)
        sp[i, diff] -= du[diff]
        s[i, ~diff] -= du[~diff]
        if rates is not None:
            sp[i] = rates(t0, i, sp[i])
    return s, sp
