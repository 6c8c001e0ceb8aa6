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
for the Jacobian at the same point: the pair is computed once and cached. A trial point
whose model cannot be evaluated (:class:`ModelFailure`: a failed simulation, a value the
problem refuses) returns non-finite residuals, on which the trust region shrinks and the
step is retried closer (SciPy's own handling); at the start it is an error.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import least_squares

from runtime.study.fit_parameters import ParameterSpec

#: a model: theta (p,) in SI -> (residuals (m,), d residuals / d theta (m, p))
Evaluate = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]]


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


def solve(evaluate: Evaluate, specs: Sequence[ParameterSpec], u0: np.ndarray | None = None,
          *, max_evaluations: int = 60, xtol: float = 1e-8, ftol: float = 1e-8,
          gtol: float = 1e-10) -> SolveOutcome:
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

    def theta_of(u: np.ndarray) -> np.ndarray:
        return np.array([s.from_u(float(v)) for s, v in zip(specs, u, strict=True)])

    def run(u: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
        key = np.asarray(u, dtype=float).tobytes()
        if key in cache:
            return cache[key]
        theta = theta_of(u)
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

    def fun(u: np.ndarray) -> np.ndarray:
        return run(u)[0]

    def jac(u: np.ndarray) -> np.ndarray:
        J = run(u)[1]
        assert J is not None, "least_squares asked for the Jacobian at a failed point"
        return J

    sol = least_squares(fun, u0, jac=jac, bounds=(lb, ub), method="trf", tr_solver="exact",
                        x_scale=1.0, xtol=xtol, ftol=ftol, gtol=gtol,
                        max_nfev=max_evaluations)
    u = np.asarray(sol.x, dtype=float)
    r, J = run(u)
    if J is None:                               # pragma: no cover - sol.x was accepted
        J = np.asarray(sol.jac, dtype=float)
    at = np.zeros(p, dtype=int)
    span = np.maximum(1.0, np.abs(u))
    at[np.isfinite(lb) & (u - lb <= 1e-6 * span)] = -1
    at[np.isfinite(ub) & (ub - u <= 1e-6 * span)] = 1
    return SolveOutcome(theta=theta_of(u), u=u, r=np.asarray(r), jac_u=np.asarray(J),
                        nfev=int(sol.nfev), njev=int(sol.njev or 0), status=int(sol.status),
                        message=str(sol.message), cost=float(0.5 * np.dot(r, r)),
                        at_bound=at, failures=failures)
