"""The least-squares and statistics core of `kvrod fit` on analytic models with exact
Jacobians (the rod itself: tests/runtime/test_fit.py): recovery, interval coverage at the
stated rate, the scaled coordinates, bounds, failed trial points, and the identifiability
warning of parameters the data cannot separate."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.stats import binom

from runtime.errors import ParameterError
from runtime.study.fit_parameters import (
    Range,
    catalogue_key,
    catalogue_range,
    make_spec,
    parse_bounds,
    parse_range,
    parse_start,
)
from runtime.study.fit_solver import ModelFailure, solve
from runtime.study.fit_statistics import CONDITION_INDEX_MAX, fit_statistics

T = np.linspace(0.0, 4.0, 200)


def damped(theta, t=T):
    """x = A exp(-d t) cos(w t) and its exact Jacobian in (A, d, w)."""
    A, d, w = theta
    e, c, s = np.exp(-d * t), np.cos(w * t), np.sin(w * t)
    x = A * e * c
    J = np.stack([e * c, -t * A * e * c, -t * A * e * s], axis=1)
    return x, J


def specs_for(start, names=("A", "d", "w")):
    return [make_spec(n, f"material.{'youngs_modulus' if n != 'w' else 'tau'}", v)
            for n, v in zip(names, start, strict=True)]


def test_recovers_damped_oscillation_with_intervals():
    truth = np.array([0.05, 0.3, 7.0])
    rng = np.random.default_rng(0)
    data = damped(truth)[0] + 1e-4 * rng.standard_normal(T.size)

    def evaluate(theta):
        x, J = damped(theta)
        return x - data, J

    specs = specs_for([0.04, 0.25, 6.5])
    out = solve(evaluate, specs)
    assert out.converged
    assert np.allclose(out.theta, truth, rtol=1e-2)
    st = fit_statistics(specs, out.u, out.r, out.jac_u)
    for (lo, hi), v in zip(st.intervals, truth, strict=True):
        assert lo < v < hi
        assert lo > 0                      # log scale: positive intervals
    assert st.dof == T.size - 3
    assert np.allclose(np.diag(st.correlation), 1.0)
    assert not st.dependencies
    assert math.sqrt(st.variance) == pytest.approx(1e-4, rel=0.15)


def test_interval_coverage_matches_95_percent():
    """40 seeded noise draws: the 95 % intervals of the decay rate cover the truth at a rate
    a binomial(40, 0.95) count allows (two-sided 0.1 % tails); the scaled coordinates are
    logarithmic, the intervals asymmetric."""
    truth = np.array([0.05, 0.3, 7.0])
    clean = damped(truth)[0]
    specs = specs_for(truth)
    draws, hits = 40, np.zeros(3, int)
    rng = np.random.default_rng(12345)
    for _ in range(draws):
        data = clean + 2e-3 * rng.standard_normal(T.size)
        out = solve(lambda th, data=data: (damped(th)[0] - data, damped(th)[1]), specs)
        st = fit_statistics(specs, out.u, out.r, out.jac_u)
        hits += [lo <= v <= hi for (lo, hi), v in zip(st.intervals, truth, strict=True)]
    lo, hi = binom.ppf(0.001, draws, 0.95), binom.ppf(0.999, draws, 0.95)
    assert np.all((hits >= lo) & (hits <= hi)), hits


def test_collinear_parameters_are_named():
    """x = a b t: a and b enter only as their product; the warning names both, with a
    condition index far above the threshold; a third, separate parameter is not named."""
    t = np.linspace(0, 1, 50)

    def evaluate(theta):
        a, b, c = theta
        x = a * b * t + c * t**2
        J = np.stack([b * t, a * t, t**2], axis=1)
        return x - (2.0 * t + 0.5 * t**2 + 1e-3 * np.sin(40 * t)), J

    specs = specs_for([1.0, 1.5, 0.4], names=("a", "b", "c"))
    out = solve(evaluate, specs)
    st = fit_statistics(specs, out.u, out.r, out.jac_u)
    assert len(st.dependencies) == 1
    d = st.dependencies[0]
    assert sorted(d.names) == ["a", "b"]
    assert d.condition_index > 1e6 > CONDITION_INDEX_MAX
    # the product is determined, the factors are not: infinite intervals for a and b
    assert st.intervals[0][1] == math.inf


def test_bounds_hold_and_are_reported():
    """A linear parameter whose optimum lies beyond its upper bound stops at the bound."""
    x = np.linspace(0, 1, 30)

    def evaluate(theta):
        return theta[0] * x - 0.8 * x, x[:, None]

    spec = make_spec("nu", "material.poisson_ratio", 0.3)
    assert not spec.log and spec.bounds.high == 0.5
    out = solve(evaluate, [spec])
    assert out.theta[0] == pytest.approx(0.5, abs=1e-9)
    assert out.at_bound.tolist() == [1]


def test_failed_trial_points_shrink_the_step():
    """A model that fails above a threshold: the solver steps back and still converges;
    the failures are kept; a failure at the start is raised."""
    t = np.linspace(0, 1, 40)
    data = 1.9 * t

    def evaluate(theta):
        if theta[0] > 2.0:       # the Gauss-Newton step from 1.36 lands at 2.03
            raise ModelFailure("integrator failed")
        return theta[0] * t - data, t[:, None]

    spec = make_spec("E", "material.youngs_modulus", 0.5)
    out = solve(evaluate, [spec])
    assert out.theta[0] == pytest.approx(1.9, rel=1e-8)
    assert out.failures and "integrator failed" in out.failures[0]
    with pytest.raises(ModelFailure):
        solve(evaluate, [make_spec("E", "material.youngs_modulus", 4.0)])


def test_catalogue_ranges():
    assert parse_range("> 0") == Range(0.0, math.inf, open_low=True)
    assert parse_range(">= 1e-12") == Range(1e-12, math.inf)
    assert parse_range("-1 < nu <= 1/2 (Maxwell: < 1/2)") == Range(-1.0, 0.5, open_low=True)
    assert parse_range("1e-30 ... 1e30") == Range(1e-30, 1e30)
    assert parse_range("a number") == Range()
    assert catalogue_key("rods.arm.material.branches.1.tau") == ("material.branches", "tau")
    assert catalogue_key("loads.0.time.frequency") == ("<time>", "frequency")
    rng, unit = catalogue_range("material.youngs_modulus")
    assert rng.positive and unit == "Pa"


def test_spec_refusals_name_the_parameter():
    with pytest.raises(ParameterError, match="tau_B"):
        make_spec("tau_B", "material.tau_B", 0.0)        # log scale needs a start > 0
    with pytest.raises(ParameterError, match="--bounds nu"):
        make_spec("nu", "material.poisson_ratio", 0.3, bounds=(-2.0, None))
    with pytest.raises(ParameterError, match="nu"):
        make_spec("nu", "material.poisson_ratio", 0.3, bounds=(0.0, 0.2))  # start outside
    s = make_spec("tau", "material.tau", 0.04, bounds=(0.01, 0.1))
    assert s.u_bounds() == pytest.approx((math.log(0.25), math.log(2.5)))
    assert parse_start(["tau=0.05"], ["tau"]) == {"tau": 0.05}
    assert parse_bounds(["tau=:0.2"], ["tau"]) == {"tau": (None, 0.2)}
    with pytest.raises(ParameterError, match="--start"):
        parse_start(["E=1"], ["tau"])
    with pytest.raises(ParameterError, match="--bounds tau"):
        parse_bounds(["tau=0.1"], ["tau"])


def test_stops_where_the_models_jitter_hides_the_rest():
    """A model whose residual carries a deterministic jitter (as a simulation's does: a
    nearby parameter takes other steps) of a tenth of the noise, incoherent between nearby
    points: the fit stops within a few evaluations of reaching the optimum, by the
    Gauss-Newton test, still inside the intervals; SciPy's own tests alone (step_tol None)
    spend far more evaluations probing the jitter for the same answer."""
    truth = np.array([0.05, 0.3, 7.0])
    data = damped(truth)[0] + 1e-4 * np.random.default_rng(1).standard_normal(T.size)

    def evaluate(theta):
        x, J = damped(theta)
        seed = int.from_bytes(np.asarray(theta, float).tobytes()[-4:], "little")
        jitter = 1e-5 * np.random.default_rng(seed).standard_normal(T.size)
        return x + jitter - data, J

    specs = specs_for([0.045, 0.28, 6.9])
    ours = solve(evaluate, specs)
    scipy_only = solve(evaluate, specs, step_tol=None)
    assert ours.converged and ours.status in (5, 6), ours.message
    assert "standard errors" in ours.message
    st = fit_statistics(specs, ours.u, ours.r, ours.jac_u)
    for (lo, hi), v in zip(st.intervals, truth, strict=True):
        assert lo < v < hi
    assert ours.nfev <= 8, ours.nfev
    assert scipy_only.nfev >= ours.nfev + 4, (scipy_only.nfev, scipy_only.message)
