"""What a least-squares fit tells about its parameters: intervals, correlations, and which
parameters the data cannot tell apart.

**Intervals.** At the optimum u* (the scaled coordinates of
:mod:`runtime.study.fit_parameters`) with residual r (n values) and Jacobian J = dr/du
(n x p), the linearised covariance is ``C = s^2 (J^T J)^-1`` with ``s^2 = |r|^2 / (n - p)``
(the residual variance) and the 95 % interval ``u*_i +- t_{0.975, n-p} sqrt(C_ii)``
(Student t): valid for independent measurement errors of equal variance, to first order
in the errors. With the noise level sigma given (``--sigma``) ``s = sigma`` and the normal
quantile 1.96 take their place. The interval is mapped back to the parameter through its
scaling, so a log-scaled parameter (moduli, times) gets ``theta* exp(+- t se)``: positive
and asymmetric. (J^T J)^-1 is formed from the SVD of J; a direction J does not see at all
gives an infinite variance.

**Identifiability.** Collinearity diagnostics after Belsley, Kuh and Welsch (Regression
Diagnostics, 1980, ch. 3): the columns of J are scaled to unit length (the test then does
not depend on units or scaling) and decomposed, ``J_e = U S V^T``. A singular value s_k
small against the largest (condition index ``eta_k = s_max / s_k`` above
:data:`CONDITION_INDEX_MAX` = 30, their threshold for a strong dependency) means that a
change of the parameters along the singular vector v_k leaves the modelled data nearly
unchanged: the record cannot tell those parameters apart. The parameters named are those
with a large part in that vector (``|v_jk| >= 0.3``) or whose variance comes mostly from it
(variance-decomposition proportion ``pi_kj >= 0.5``). The test looks at the model only,
not at the noise: a record that cannot separate two parameters cannot, whatever its noise.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy.stats import norm
from scipy.stats import t as student_t

from runtime.study.fit_parameters import ParameterSpec

#: Belsley, Kuh and Welsch's condition index of a strong near-dependency
CONDITION_INDEX_MAX = 30.0
#: a parameter takes part in a near-dependency with this much of its singular vector ...
COMPONENT_MIN = 0.3
#: ... or this much of its variance from it
PROPORTION_MIN = 0.5
#: a column of J this small against the largest: the data do not depend on the parameter
NULL_COLUMN = 1e-12


@dataclass
class Dependency:
    """A near-dependency of the parameters: its ``condition_index``, the ``names`` involved
    and the singular ``vector`` (one entry per parameter, columns of J at unit length)."""

    condition_index: float
    names: list[str]
    vector: list[float]


@dataclass
class FitStatistics:
    """Intervals and diagnostics at the optimum (see the module docstring): ``dof`` =
    n - p; ``variance`` s^2 (or sigma^2); ``sigma_given``; ``quantile`` (t or normal);
    ``covariance_u`` (p, p) and ``se_u`` (p,) in scaled coordinates; ``intervals``
    [(low, high)] of the parameters (SI); ``correlation`` (p, p); the singular values,
    condition indices and vectors of the column-scaled Jacobian; the near-dependencies
    found and the parameters the data do not depend on at all (``insensitive``)."""

    names: list[str]
    dof: int
    variance: float
    sigma_given: bool
    quantile: float
    covariance_u: np.ndarray
    se_u: np.ndarray
    intervals: list[tuple[float, float]]
    correlation: np.ndarray
    singular_values: np.ndarray
    condition_indices: np.ndarray
    vectors: np.ndarray
    dependencies: list[Dependency] = field(default_factory=list)
    insensitive: list[str] = field(default_factory=list)

    def to_json(self) -> dict:
        return {"dof": self.dof, "residual_variance": self.variance,
                "noise": "given (--sigma)" if self.sigma_given else "estimated from the "
                         "residual, s^2 = |r|^2 / (n - p)",
                "quantile": self.quantile,
                "standard_errors_scaled": {n: float(v) for n, v in
                                           zip(self.names, self.se_u, strict=True)},
                "singular_values": self.singular_values.tolist(),
                "condition_indices": self.condition_indices.tolist(),
                "singular_vectors": self.vectors.T.tolist(),
                "dependencies": [{"condition_index": d.condition_index, "parameters": d.names,
                                  "vector": d.vector} for d in self.dependencies],
                "insensitive": list(self.insensitive)}


def covariance(J: np.ndarray, variance: float) -> np.ndarray:
    """variance (J^T J)^-1 from the SVD of J; directions J does not see (singular values
    below 1e-12 of the largest) have infinite variance in every parameter they touch."""
    p = J.shape[1]
    U, S, Vt = np.linalg.svd(J, full_matrices=False)
    if S.size == 0 or S[0] == 0:
        return np.full((p, p), math.inf)
    keep = S > 1e-12 * S[0]
    V = Vt.T
    C = (V[:, keep] / S[keep] ** 2) @ V[:, keep].T * variance
    blind = np.any(np.abs(V[:, ~keep]) > 1e-8, axis=1) if np.any(~keep) else np.zeros(p, bool)
    C[blind, :] = math.inf
    C[:, blind] = math.inf
    return C


def dependencies(J: np.ndarray, names: Sequence[str]) -> tuple[list[Dependency], list[str],
                                                                 np.ndarray, np.ndarray,
                                                                 np.ndarray]:
    """Belsley's collinearity diagnostics of J (module docstring): (near-dependencies,
    parameters with a zero column, singular values, condition indices, singular vectors as
    columns) of the column-equilibrated Jacobian of the parameters that have an effect."""
    norms = np.linalg.norm(J, axis=0)
    top = float(np.max(norms)) if norms.size else 0.0
    live = norms > NULL_COLUMN * top if top > 0 else np.zeros(len(names), bool)
    insensitive = [n for n, ok in zip(names, live, strict=True) if not ok]
    p = len(names)
    S_all = np.zeros(p)
    eta_all = np.full(p, math.inf)
    V_all = np.zeros((p, p))
    idx = np.flatnonzero(live)
    if idx.size == 0:
        return [], insensitive, S_all, eta_all, V_all
    Je = J[:, idx] / norms[idx]
    _, S, Vt = np.linalg.svd(Je, full_matrices=False)
    V = Vt.T
    with np.errstate(divide="ignore"):
        eta = np.where(S > 0, S[0] / S, math.inf)
        phi = V**2 / np.where(S > 0, S**2, 0.0)[None, :]
    total = phi.sum(axis=1, keepdims=True)
    with np.errstate(invalid="ignore"):
        prop = np.where(np.isfinite(total), phi / total, 1.0)
    found = []
    for k in range(S.size):
        if not eta[k] > CONDITION_INDEX_MAX:
            continue
        big = [j for j in range(idx.size)
               if abs(V[j, k]) >= COMPONENT_MIN or prop[j, k] >= PROPORTION_MIN]
        if len(big) < 2:       # a dependency needs two columns: the next largest joins
            order = np.argsort(-np.abs(V[:, k]))
            big = sorted(set(big) | {int(j) for j in order[:2]})
        vec = np.zeros(p)
        vec[idx] = V[:, k]
        found.append(Dependency(float(eta[k]), [names[idx[j]] for j in big],
                                [float(v) for v in vec]))
    S_all[: S.size] = S
    eta_all[: S.size] = eta
    V_all[np.ix_(idx, np.arange(S.size))] = V
    return found, insensitive, S_all, eta_all, V_all


def fit_statistics(specs: Sequence[ParameterSpec], u: np.ndarray, r: np.ndarray,
                   J: np.ndarray, sigma: float | None = None) -> FitStatistics:
    """Intervals, correlations and identifiability at the optimum (module docstring).

    Parameters
    ----------
    specs : sequence of ParameterSpec
        The parameters (their scaling maps the intervals back).
    u : array (p,)
        The optimum in scaled coordinates.
    r : array (n,)
        The residuals there (in the units of the data, or weighted).
    J : array (n, p)
        dr/du there.
    sigma : float, optional
        The measurement noise's standard deviation, if known (same units as r).
    """
    names = [s.name for s in specs]
    n, p = J.shape
    dof = n - p
    if sigma is not None:
        var, q = float(sigma) ** 2, float(norm.ppf(0.975))
    elif dof >= 1:
        var, q = float(r @ r) / dof, float(student_t.ppf(0.975, dof))
    else:
        var, q = math.inf, math.inf
    C = covariance(J, var) if math.isfinite(var) else np.full((p, p), math.inf)
    se = np.sqrt(np.abs(np.diag(C)))
    intervals = []
    for s, ui, e in zip(specs, u, se, strict=True):
        if not math.isfinite(e * q):
            lo, hi = s.bounds.low, s.bounds.high
            intervals.append((lo if not s.log else max(lo, 0.0), hi))
            continue
        a, b = s.from_u(float(ui - q * e)), s.from_u(float(ui + q * e))
        intervals.append((max(a, s.bounds.low), min(b, s.bounds.high)))
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = C / np.outer(se, se)
    corr[~np.isfinite(corr)] = math.nan
    np.fill_diagonal(corr, 1.0)
    deps, insensitive, S, eta, V = dependencies(J, names)
    return FitStatistics(names, dof, var, sigma is not None, q, C, se, intervals, corr, S, eta,
                         V, deps, insensitive)


def _join(names: Sequence[str]) -> str:
    return names[0] if len(names) == 1 else ", ".join(names[:-1]) + " and " + names[-1]


def dependency_warning(d: Dependency, names: Sequence[str]) -> str:
    """One line: which parameters cannot be told apart, and how strongly."""
    combo = ", ".join(f"{v:+.2f} {n}" for n, v in zip(names, d.vector, strict=True)
                      if n in d.names)
    return (f"{_join(d.names)} cannot be told apart by this record: the Jacobian (columns "
            f"scaled to unit length) has a singular value {1 / d.condition_index:.2g} of its "
            f"largest (condition index {d.condition_index:.3g} > {CONDITION_INDEX_MAX:g}); "
            f"changing them together along [{combo}] (scaled) leaves the modelled data "
            "nearly unchanged, so their values and intervals are not separately "
            "determined; record a motion that excites them differently, or fit fewer "
            "parameters")


def insensitive_warning(name: str) -> str:
    return (f"{name} does not change the modelled data at all (its column of the Jacobian is "
            "zero): this record cannot determine it; leave it out of --params")
