"""Static equilibrium by Newton's method with load stepping (continuation).

The load factor ``problem.load_scale`` goes from 0 to 1.  Each load step is solved by
full Newton (the banded Jacobian is evaluated and factorised every iteration), damped
by a backtracking line search: by default Deuflhard's natural monotonicity test on the
simplified Newton correction (affine invariant), optionally Armijo on the residual
norm, inside a watchdog that keeps fast non-monotone full steps.  When a load step
fails (no convergence within ``max_iter``, a line search that cannot make progress, a
singular Jacobian or non-finite values) the load increment is halved and the step
retried from the last converged state; after easy steps the increment grows again.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from runtime.errors import ParameterError
from runtime.solvers.native.band import BandLU
from runtime.solvers.protocols import StaticProblem, band_storage

__all__ = ["StaticResult", "StaticSolveError", "solve_static"]


class StaticSolveError(RuntimeError):
    """Load stepping failed.

    Attributes
    ----------
    y : ndarray
        Last converged state (at ``load_scale``).
    load_scale : float
        Load factor of ``y`` (0 if not even the unloaded state converged).
    iterations : list of int
        Newton iterations of every converged load step so far.
    residual_norm : float
        Scaled residual norm of the last failed attempt.
    """

    def __init__(
        self,
        message: str,
        *,
        y: np.ndarray,
        load_scale: float,
        iterations: list[int],
        residual_norm: float,
    ) -> None:
        super().__init__(message)
        self.y = y
        self.load_scale = load_scale
        self.iterations = iterations
        self.residual_norm = residual_norm


@dataclass
class StaticResult:
    """Outcome of :func:`solve_static`.

    y : equilibrium state at ``load_scale = 1``.
    iterations : Newton iterations per converged load step (the unloaded check first).
    load_scales : load factor reached by each of those steps.
    total_iterations : all Newton iterations, including those of failed attempts.
    residual_norm : final scaled residual norm (see ``solve_static``).
    line_search_backtracks : total step-length reductions.
    watchdog_restarts : times non-monotone full steps were abandoned for damped ones.
    load_cuts : number of times a load increment was halved.
    """

    y: np.ndarray
    converged: bool
    iterations: list[int]
    load_scales: list[float]
    total_iterations: int
    residual_norm: float
    message: str
    line_search_backtracks: int = 0
    watchdog_restarts: int = 0
    load_cuts: int = 0
    residual_evaluations: int = 0


class _NewtonFailure(Exception):
    def __init__(self, reason: str, rnorm: float) -> None:
        super().__init__(reason)
        self.reason = reason
        self.rnorm = rnorm


def solve_static(
    problem: StaticProblem,
    y0: np.ndarray,
    *,
    load_steps: int = 10,
    tol: float = 1e-10,
    max_iter: int = 50,
    residual_scale: float | np.ndarray | None = None,
    min_load_step: float = 1e-6,
    grow: float = 1.5,
    easy_iterations: int = 4,
    armijo: float = 1e-4,
    min_alpha: float = 1.0 / 64.0,
    step_tol: float = 1e-12,
    line_search: str = "natural",
    watchdog: int = 4,
    stations: tuple[float, ...] = (),
    on_station=None,
    first_load: float = 0.0,
) -> StaticResult:
    """Solve ``R(y; load_scale = 1) = 0`` starting from ``y0`` at zero load.

    Parameters
    ----------
    problem : a :class:`~runtime.solvers.protocols.StaticProblem`; its ``load_scale`` is left at 1
        on success and at the last converged value on failure.
    y0 : full initial state (e.g. the unloaded configuration).
    load_steps : initial number of equal load increments.
    tol : convergence when the scaled residual norm ``rms(R / scale) <= tol``.
    max_iter : Newton iterations allowed per load step before the increment is cut.
    residual_scale : scalar or (n_static,) scale of the residual entries (units of
        force/moment).  Default: the RMS of the external load vector,
        ``R(y0; 1) - R(y0; 0)``, or 1 if there is no load.
    min_load_step : give up when the load increment falls below this.
    grow, easy_iterations : after a load step converging in at most ``easy_iterations``
        iterations, the increment is multiplied by ``grow``.
    line_search : ``"natural"`` (default): accept the damped step ``a dx`` when the
        simplified Newton correction shrinks, ``|J(x)^-1 R(x + a dx)| <= (1 - a/4) |dx|``
        (Deuflhard's natural monotonicity test, NLEQ-ERR); it is affine invariant, so
        residual rows in different units (forces, moments) and stiff directions do not
        reject good Newton steps -- a plain residual-norm test does, and then crawls
        (the static cantilever takes ~30 damped iterations per load step with it).
        ``"residual"``: Armijo on the residual norm,
        ``|R(x + a dx)| <= (1 - armijo a) |R(x)|``.
    watchdog : full Newton steps may raise the residual norm for up to ``watchdog - 1``
        steps if it then falls below its earlier value (rotations make full steps
        non-monotone; plain Newton is fast there); else Newton returns to the last
        reference point and damps.  0 disables it (always damped).
    first_load : the load factor the continuation starts from (default 0, the unloaded
        state); 1: plain Newton at the full load from ``y0``.
    stations, on_station : load factors in (0, 1] the stepping lands on exactly (the
        increment is shortened to reach them); ``on_station(load_factor, y)`` is called
        with the converged state at each (a load-deflection path at chosen loads).
    armijo, min_alpha : Armijo constant; smallest damping factor ``a``.  The factor is
        reduced by model-based guesses safeguarded to [0.1, 0.5] of the previous one;
        below ``min_alpha`` the load step counts as failed and the load increment is cut
        rather than looping.
    step_tol : also converged when the Newton increment's RMS (in the reduced
        coordinates' units, e.g. m and rad) is at most this: the residual is then at
        its round-off floor and cannot meet ``tol``.

    Raises :class:`StaticSolveError` with the last converged state on failure.
    """
    if line_search not in ("natural", "residual"):
        raise ParameterError("line_search", line_search, "'natural' or 'residual'")
    natural = line_search == "natural"
    if load_steps < 1:
        raise ParameterError("load_steps", load_steps, "integers >= 1")
    if not tol > 0:
        raise ParameterError("tol", tol, "> 0")
    marks = sorted({float(x) for x in stations})
    if any(not 0.0 < x <= 1.0 for x in marks):
        raise ParameterError("stations", stations, "load factors in (0, 1]")
    n = int(problem.n_static)
    kl, ku = int(problem.kl_static), int(problem.ku_static)
    #: the problem's own factorisation (``static_factor(y)`` -> ``.info``, ``.solve``:
    #: a sparse static Jacobian), else its band Jacobian and a band LU
    own_factor = getattr(problem, "static_factor", None)
    ab = band_storage(n, kl, ku) if own_factor is None else None
    res = np.empty(n)
    counts = {"iters": 0, "backtracks": 0, "fev": 0, "watchdog": 0}

    if residual_scale is None:
        problem.load_scale = 1.0
        problem.static_residual(y0, res)
        r1 = res.copy()
        problem.load_scale = 0.0
        problem.static_residual(y0, res)
        counts["fev"] += 2
        load_rms = float(np.sqrt(np.mean((r1 - res) ** 2))) if n else 0.0
        scale: float | np.ndarray = load_rms if load_rms > 0 and math.isfinite(load_rms) else 1.0
    else:
        scale = np.asarray(residual_scale, dtype=float)
        if np.any(scale <= 0):
            raise ParameterError("residual_scale", residual_scale, "> 0 (scalar or per entry)")
    inv_scale = 1.0 / scale
    constrain = getattr(problem, "constrain", None)

    def res_norm() -> float:
        r = res * inv_scale
        v = float(np.sqrt(np.dot(r, r) / n)) if n else 0.0
        return v if math.isfinite(v) else math.inf

    def rnorm(y: np.ndarray) -> float:
        problem.static_residual(y, res)
        counts["fev"] += 1
        return res_norm()

    #: the problem's full Newton trial in one call (factor, dx, y_try; ``res`` <- the
    #: residual at y_try), or None where it has none: the same arithmetic as the steps
    #: below (a rod on its compiled kernels: RodStatics.static_newton_trial)
    fused = getattr(problem, "static_newton_trial", None)

    def newton(y: np.ndarray) -> tuple[np.ndarray, int, float]:
        """Newton at the current load; returns (y, iterations, scaled norm).

        Watchdog strategy: full Newton steps are taken as long as the residual falls
        below the last reference value within ``watchdog`` steps (so the non-monotone
        but fast full steps of rotation problems are kept); otherwise Newton restarts
        from the reference point with damped steps (the line search).
        """
        if constrain is not None:   # held nodes to their targets at this load factor
            y = constrain(y)
        r = rnorm(y)
        it = 0
        ref_y, ref_r, left = y, r, watchdog
        damped = watchdog == 0
        while True:
            if r <= tol:
                return y, it, r
            if it >= max_iter:
                raise _NewtonFailure(f"no convergence in {max_iter} iterations", r)
            trial = fused(y, res) if fused is not None else None
            first: tuple[np.ndarray, float] | None = None   # (y + dx, its norm) if formed
            if trial is not None:
                lu, dx, y_full = trial
                if lu.info != 0:
                    raise _NewtonFailure("singular Jacobian", r)
                if y_full is None:
                    raise _NewtonFailure("non-finite Newton step", r)
                counts["fev"] += 1
                first = y_full, res_norm()
            else:
                f = res.copy()
                if own_factor is not None:  # the problem factorises (sparse; a rod's C core)
                    lu = own_factor(y)
                else:
                    ab.fill(0.0)
                    problem.static_jacobian_band(y, ab)
                    lu = BandLU(ab, kl, ku)
                if lu.info != 0:
                    raise _NewtonFailure("singular Jacobian", r)
                dx = -lu.solve(f)
                if not np.all(np.isfinite(dx)):
                    raise _NewtonFailure("non-finite Newton step", r)
            it += 1
            counts["iters"] += 1
            ndx = math.sqrt(float(np.dot(dx, dx)) / n)
            if ndx <= step_tol:
                if first is not None:
                    return first[0], it, first[1]
                y = problem.static_retract(y, dx)
                return y, it, rnorm(y)
            if not damped:
                y_try, r_try = first if first is not None else (
                    (y_try := problem.static_retract(y, dx)), rnorm(y_try))
                if r_try <= (1.0 - armijo) * ref_r:
                    y, r = y_try, r_try
                    ref_y, ref_r, left = y, r, watchdog
                    continue
                left -= 1
                if left > 0 and math.isfinite(r_try):
                    y, r = y_try, r_try  # tentatively accept a non-monotone step
                    continue
                # Watchdog expired: back to the reference point, damped from there
                # (re-evaluating its residual: ``res`` holds the rejected trial's).
                counts["watchdog"] += 1
                y, damped = ref_y, True
                r = rnorm(y)
                continue
            alpha = 1.0
            while True:
                if alpha == 1.0 and first is not None:      # formed by the trial
                    y_try, r_try = first
                else:
                    y_try = problem.static_retract(y, alpha * dx)
                    r_try = rnorm(y_try)
                if not math.isfinite(r_try):
                    alpha *= 0.1
                elif natural:
                    # Deuflhard's natural monotonicity test on the simplified Newton
                    # correction J(y)^-1 R(y_try) (same LU); affine invariant, so badly
                    # scaled rows (stiff axial forces next to bending moments) matter less.
                    dxbar = -lu.solve(res)
                    if math.sqrt(float(np.dot(dxbar, dxbar)) / n) <= (1.0 - 0.25 * alpha) * ndx:
                        break
                    w = dxbar - (1.0 - alpha) * dx
                    nw = math.sqrt(float(np.dot(w, w)) / n)
                    mu = 0.5 * alpha * alpha * ndx / nw if nw > 0 else 0.5 * alpha
                    alpha = min(0.5 * alpha, max(0.1 * alpha, mu))
                else:
                    if r_try <= (1.0 - armijo * alpha) * r:
                        break
                    # Quadratic model of |R|^2 along the step (slope -2 r^2 for Newton),
                    # safeguarded to [0.1, 0.5] of the current alpha.
                    denom = r_try**2 - r**2 * (1.0 - 2.0 * alpha)
                    a_q = r**2 * alpha**2 / denom if denom > 0 else 0.5 * alpha
                    alpha = min(0.5 * alpha, max(0.1 * alpha, a_q))
                counts["backtracks"] += 1
                if alpha < min_alpha:
                    raise _NewtonFailure("line search could not make progress", r)
            y, r = y_try, r_try
            if watchdog > 0 and alpha == 1.0 and r < ref_r:
                # An undamped step passed the test: back in Newton's region, try full steps.
                ref_y, ref_r, left, damped = y, r, watchdog, False

    iterations: list[int] = []
    load_scales: list[float] = []
    cuts = 0

    # Unloaded state first (usually already in equilibrium: zero iterations); or Newton at
    # ``first_load`` from a y0 that lies near that equilibrium (a mechanism, a pendulum,
    # has no unloaded equilibrium where it hangs).
    if not 0.0 <= first_load <= 1.0:
        raise ParameterError("first_load", first_load, "a load factor in [0, 1]")
    lam = float(first_load)
    problem.load_scale = lam
    try:
        y, it, r = newton(np.array(y0, dtype=float))
    except _NewtonFailure as exc:
        what = "the unloaded state" if lam == 0.0 else f"the state at load factor {lam:g}"
        raise StaticSolveError(
            f"solve_static: {what} does not converge ({exc.reason}; scaled "
            f"residual {exc.rnorm:.3g}). Check y0 and the boundary conditions.",
            y=np.array(y0, dtype=float),
            load_scale=lam,
            iterations=[],
            residual_norm=exc.rnorm,
        ) from None
    iterations.append(it)
    load_scales.append(lam)

    dlam = 1.0 / max(1, int(load_steps))
    while lam < 1.0:
        lam_try = min(1.0, lam + dlam)
        if 1.0 - lam_try < 1e-12:
            lam_try = 1.0
        upcoming = [x for x in marks if x > lam + 1e-12]
        if upcoming and lam_try > upcoming[0] - 1e-12:
            lam_try = upcoming[0]
        problem.load_scale = lam_try
        try:
            y_new, it, r_new = newton(y)
        except _NewtonFailure as exc:
            cuts += 1
            dlam *= 0.5
            if dlam < min_load_step:
                problem.load_scale = lam
                raise StaticSolveError(
                    f"solve_static: load stepping stalled at load_scale = {lam:.6g}: the "
                    f"step to {lam_try:.6g} failed ({exc.reason}; scaled residual "
                    f"{exc.rnorm:.3g}) and the increment fell below {min_load_step:g}. "
                    "The equilibrium path may have a limit point (buckling/snap-through) "
                    "or the Jacobian may be wrong.",
                    y=y.copy(),
                    load_scale=lam,
                    iterations=iterations,
                    residual_norm=exc.rnorm,
                ) from None
            continue
        y, lam, r = y_new, lam_try, r_new
        iterations.append(it)
        load_scales.append(lam)
        if on_station is not None and any(abs(lam - x) <= 1e-12 for x in marks):
            on_station(lam, y.copy())
        if it <= easy_iterations:
            dlam *= grow

    return StaticResult(
        y=y,
        converged=True,
        iterations=iterations,
        load_scales=load_scales,
        total_iterations=counts["iters"],
        residual_norm=r,
        message=(
            f"converged in {len(iterations) - 1} load steps, {counts['iters']} Newton "
            f"iterations (scaled residual {r:.3g})"
        ),
        line_search_backtracks=counts["backtracks"],
        watchdog_restarts=counts["watchdog"],
        load_cuts=cuts,
        residual_evaluations=counts["fev"],
    )
