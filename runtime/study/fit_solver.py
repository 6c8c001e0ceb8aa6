"""Nonlinear least squares with an exact Jacobian, in scaled parameters.

The fit minimises ``1/2 |r(theta)|^2`` over the scaled coordinates u of
:class:`~runtime.study.fit_parameters.ParameterSpec` with SciPy's trust-region reflective
method (``scipy.optimize.least_squares(method="trf", tr_solver="exact")``): away from the
bounds each step is the Levenberg-Marquardt step of the trust-region subproblem (Moré's
algorithm, as MINPACK's ``lmder``), near a bound the step is reflected and scaled
(Coleman-Li), so bounded parameters never leave their range. The Jacobian is the model's
own (``evaluate`` returns r and dr/dtheta together: one simulation with sensitivities gives
both), chained to u by ``dtheta/du``; there is no finite difference anywhere.

``least_squares`` asks for the residual at a trial point and, when the step is accepted,
for the Jacobian at the same point: the pair is computed once and cached.

**When to stop.** The residual of a simulation is smooth in the parameters only up to the
integrator's tolerance: a nearby parameter takes other steps, so the cost near the
optimum carries a jitter of about ``sqrt(n) sigma delta`` (n data, sigma their noise,
delta the integrator's error), which at the paper's cantilever (rtol 1e-6, n = 800,
0.1 mm) is as large as the cost's own change over a third of a standard error. There
SciPy's tests on the cost's reduction (``ftol``, the trust region's ratio) see noise and
go on shrinking the region for a dozen evaluations. The exact Jacobian does not suffer:
the fit stops as soon as the Gauss-Newton step ``-(J^T J)^-1 J^T r`` at an accepted point
is below ``step_tol`` (a tenth) of a standard error in the metric of the confidence
ellipsoid, ``|J step| / s`` (for one parameter ``|step| / se``; for collinear parameters
it still counts a step along their well-determined combination in full), a change no
measurement could tell (SciPy's ``callback``, which stops on
``StopIteration``). A tenth, not less: the integrator's jitter alone moves the
Gauss-Newton step by 1-2 % of a standard error there, so a 1 % test seldom passes and
the fit wastes a dozen evaluations (16 instead of 2 from the truth on a 1.5 s record of
the cantilever at N = 4). Where the jitter is larger than that (the paper's cantilever, N =
50, 4 s: a remaining Gauss-Newton step of 0.2-0.4 standard errors that no trial step
confirms), the fit also stops at an accepted point whose Gauss-Newton step is below
``SETTLE_TOL`` (half) a standard error as soon as a trial step from it fails to lower
the cost: the cost cannot resolve the rest, and SciPy would otherwise shrink its trust
region down to ``xtol`` for eight evaluations more. ``xtol``, ``ftol`` and ``gtol`` stay
as the last resort (a noise-free record has no standard error to compare with).

A trial point whose model cannot be evaluated (:class:`ModelFailure`: a failed
simulation, a value the problem refuses) returns non-finite residuals, on which the
trust region shrinks and the step is retried closer (SciPy's own handling); at the start
it is an error.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import least_squares

from runtime.study.fit_parameters import ParameterSpec

#: a model: theta (p,) in SI -> (residuals (m,), d residuals / d theta (m, p))
Evaluate = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]]


#: stop when the Gauss-Newton step is below this many standard errors (|J step| / s)
STEP_TOL = 0.1
#: ... or when it is below this fraction and a trial step fails to lower the cost
SETTLE_TOL = 0.5


class ModelFailure(RuntimeError):
    """The model could not be evaluated at a parameter point (the message says why)."""


@dataclass
class SolveOutcome:
    """The result of :func:`solve`: the parameters ``theta`` (SI) and scaled ``u``, the
    residual ``r`` and the Jacobian ``jac_u`` = dr/du there, ``nfev`` model evaluations
    (``njev`` of them accepted steps), SciPy's ``status`` (> 0 converged, 0 the
    evaluation budget spent) and ``message``, the ``cost`` 1/2 |r|^2, ``at_bound`` per
    parameter (-1 lower, 1 upper, 0 free) and the messages of the trial points that
    failed."""

    theta: np.ndarray
    u: np.ndarray
    r: np.ndarray
    jac_u: np.ndarray
    nfev: int
    njev: int
    status: int
    message: str
    cost: float
    at_bound: np.ndarray
    failures: list[str] = field(default_factory=list)

    @property
    def converged(self) -> bool:
        return self.status > 0


def jacobian_u(specs: Sequence[ParameterSpec], theta: np.ndarray, jac_theta: np.ndarray
               ) -> np.ndarray:
    """dr/du = dr/dtheta diag(dtheta/du)."""
    return jac_theta * np.array([s.dtheta_du(float(v)) for s, v in
                                 zip(specs, theta, strict=True)])[None, :]


def gauss_newton_ratio(r: np.ndarray, J: np.ndarray, u: np.ndarray, lb: np.ndarray,
                       ub: np.ndarray) -> float:
    """The Gauss-Newton step at u in standard errors: ``|J step| / s``, the step's length
    in the metric of the confidence ellipsoid (s^2 = |r|^2 / (n - p)), so a step along a
    well-determined combination counts in full even where the parameters themselves are
    collinear and their own standard errors huge (for one parameter: |step| / se). A
    parameter at a bound whose step points out of its range is held; inf without a
    residual degree of freedom or with a rank-deficient J."""
    n, p = J.shape
    span = np.maximum(1.0, np.abs(u))
    free = np.ones(p, bool)
    for _ in range(2):
        idx = np.flatnonzero(free)
        if idx.size == 0 or n - idx.size < 1:
            return math.inf
        Jf = J[:, idx]
        step, _, rank, _ = np.linalg.lstsq(Jf, -r, rcond=None)
        if rank < idx.size:
            return math.inf
        out = ((step < 0) & (u[idx] - lb[idx] <= 1e-6 * span[idx])) | (
            (step > 0) & (ub[idx] - u[idx] <= 1e-6 * span[idx]))
        if not out.any():
            break
        free[idx[out]] = False
    else:
        return math.inf
    s2 = float(r @ r) / (n - idx.size)
    if s2 <= 0:
        return math.inf
    return float(np.linalg.norm(Jf @ step) / math.sqrt(s2))


class _Settled(Exception):
    """A trial step from a point whose Gauss-Newton step is below SETTLE_TOL standard
    errors failed to lower the cost (module docstring)."""


def solve(evaluate: Evaluate, specs: Sequence[ParameterSpec], u0: np.ndarray | None = None,
          *, max_evaluations: int = 60, xtol: float = 1e-8, ftol: float = 1e-8,
          gtol: float = 1e-10, step_tol: float | None = STEP_TOL) -> SolveOutcome:
    """Minimise 1/2 |r|^2 over the scaled parameters (see the module docstring).

    Parameters
    ----------
    evaluate : callable
        theta (p,) in SI -> (r (m,), dr/dtheta (m, p)); raises :class:`ModelFailure` where
        the model cannot be evaluated.
    specs : sequence of ParameterSpec
        The parameters (start values, bounds, scaling).
    u0 : array, optional
        Start in scaled coordinates (default 0: the specs' start values).
    max_evaluations : int
        Most model evaluations (``least_squares``' ``max_nfev``).
    xtol, ftol, gtol : float
        ``least_squares``' tolerances (on u, the cost and the scaled gradient).
    step_tol : float or None
        Stop when the Gauss-Newton step is below this fraction of every free parameter's
        standard error (module docstring); None: SciPy's tests only.

    Returns
    -------
    SolveOutcome
    """
    p = len(specs)
    u0 = np.zeros(p) if u0 is None else np.asarray(u0, dtype=float).copy()
    bounds = np.array([s.u_bounds() for s in specs], dtype=float).reshape(p, 2)
    lb, ub = bounds[:, 0], bounds[:, 1]
    u0 = np.clip(u0, lb, ub)
    cache: dict[bytes, tuple[np.ndarray, np.ndarray | None]] = {}  # the last few points
    size: list[int] = []
    failures: list[str] = []
    evaluations, accepted = [0], [0]

    def theta_of(u: np.ndarray) -> np.ndarray:
        return np.array([s.from_u(float(v)) for s, v in zip(specs, u, strict=True)])

    def run(u: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
        key = np.asarray(u, dtype=float).tobytes()
        if key in cache:
            return cache[key]
        theta = theta_of(u)
        evaluations[0] += 1
        try:
            r, J = evaluate(theta)
            r = np.asarray(r, dtype=float)
            J = jacobian_u(specs, theta, np.asarray(J, dtype=float).reshape(r.size, p))
            if not (np.all(np.isfinite(r)) and np.all(np.isfinite(J))):
                raise ModelFailure("the model's residual or sensitivities are not finite")
        except ModelFailure as exc:
            if not size:
                raise
            at = ", ".join(f"{s.name} = {v:.6g}" for s, v in zip(specs, theta, strict=True))
            failures.append(f"{at}: {exc}")
            r, J = np.full(size[0], np.inf), None
        size[:] = [r.size]
        if len(cache) >= 4:
            cache.pop(next(iter(cache)))
        cache[key] = (r, J)
        return r, J

    def jac(u: np.ndarray) -> np.ndarray:
        accepted[0] += 1
        J = run(u)[1]
        assert J is not None, "least_squares asked for the Jacobian at a failed point"
        return J

    # the last accepted point, its Gauss-Newton step in standard errors, and the trial
    # points asked for since it was accepted
    state = {"u": None, "ratio": math.inf, "trials": 0, "stop": ""}

    def fun(u: np.ndarray) -> np.ndarray:
        if state["u"] is not None and step_tol is not None:
            state["trials"] += 1
            if state["trials"] >= 2 and state["ratio"] <= SETTLE_TOL:
                raise _Settled
        return run(u)[0]

    def callback(intermediate_result) -> None:
        # SciPy stops on StopIteration (a returned True is ignored)
        if step_tol is None:
            return
        u = np.asarray(intermediate_result.x, dtype=float)
        r, J = run(u)
        if J is None:
            return
        state.update(u=u.copy(), ratio=gauss_newton_ratio(r, J, u, lb, ub), trials=0)
        if state["ratio"] <= step_tol:
            state["stop"] = (f"the Gauss-Newton step is {state['ratio']:.2g} standard errors, "
                             f"below {step_tol:g}")
            raise StopIteration

    try:
        sol = least_squares(fun, u0, jac=jac, bounds=(lb, ub), method="trf",
                            tr_solver="exact", x_scale=1.0, xtol=xtol, ftol=ftol, gtol=gtol,
                            max_nfev=max_evaluations, callback=callback)
        u = np.asarray(sol.x, dtype=float)
        status, message = int(sol.status), str(sol.message)
        if state["stop"]:
            status, message = 5, state["stop"]
    except _Settled:
        u = np.asarray(state["u"], dtype=float)
        status = 6
        message = (f"the Gauss-Newton step is {state['ratio']:.2g} standard errors, below "
                   f"{SETTLE_TOL:g}, and a step toward it did not lower the cost: the "
                   "model's own error (a simulation's: the integrator's) hides the rest")
    r, J = run(u)
    nfev, njev = evaluations[0], accepted[0]
    assert J is not None, "the solution is an accepted point"
    at = np.zeros(p, dtype=int)
    span = np.maximum(1.0, np.abs(u))
    at[np.isfinite(lb) & (u - lb <= 1e-6 * span)] = -1
    at[np.isfinite(ub) & (ub - u <= 1e-6 * span)] = 1
    return SolveOutcome(theta=theta_of(u), u=u, r=np.asarray(r), jac_u=np.asarray(J),
                        nfev=nfev, njev=njev, status=status,
                        message=message, cost=float(0.5 * np.dot(r, r)),
                        at_bound=at, failures=failures)
