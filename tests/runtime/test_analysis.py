"""Tests of runtime.analysis.decay on synthetic signals with exactly known answers."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import brentq

from runtime.analysis.decay import (
    BETA1_L,
    cumulative_integral,
    damping_ratios,
    energy_audit,
    exponential_envelope,
    find_maxima,
    linear_damping_ratio,
    log_decrements,
    period_euler_bernoulli,
    periods,
    tip_summary,
)


def damped(zeta: float, omega: float, amp: float = 0.2):
    """x = A exp(-zeta omega t) cos(omega_d t) and its exact derivative."""
    wd = omega * math.sqrt(1 - zeta * zeta)
    s = zeta * omega

    def x(t):
        return amp * np.exp(-s * t) * np.cos(wd * t)

    def dx(t):
        return amp * np.exp(-s * t) * (-s * np.cos(wd * t) - wd * np.sin(wd * t))

    return x, dx, wd


# ----------------------------------------------------------------------------- maxima
@pytest.mark.parametrize("zeta", [0.035663, 0.071326, 0.142652])
def test_dense_recovers_zeta_and_period(zeta):
    omega = 3.5663
    x, dx, wd = damped(zeta, omega)
    t = np.linspace(0.0, 12.0, 61)  # coarse: ~9 samples per period
    tk, xk = find_maxima(t, x(t), sol=x, dsol=dx)
    assert len(tk) >= 5
    z = damping_ratios(log_decrements(xk))
    np.testing.assert_allclose(z, zeta, rtol=0, atol=1e-10)
    np.testing.assert_allclose(periods(tk), 2 * math.pi / wd, rtol=1e-12)
    # without the derivative: values as accurate, times to ~sqrt(eps)
    tk2, xk2 = find_maxima(t, x(t), sol=x)
    np.testing.assert_allclose(damping_ratios(log_decrements(xk2)), zeta, atol=1e-10)
    np.testing.assert_allclose(periods(tk2), 2 * math.pi / wd, rtol=1e-7)


@pytest.mark.parametrize("zeta", [0.035663, 0.071326, 0.142652])
def test_samples_parabolic_and_spline(zeta):
    omega = 3.5663
    x, _, wd = damped(zeta, omega)
    t = np.linspace(0.0, 12.0, 1201)  # ~176 samples per period
    tk, xk = find_maxima(t, x(t))
    z = damping_ratios(log_decrements(xk))
    np.testing.assert_allclose(z, zeta, atol=1e-4)
    np.testing.assert_allclose(periods(tk), 2 * math.pi / wd, rtol=1e-4)
    tk, xk = find_maxima(t, x(t), method="spline")
    np.testing.assert_allclose(damping_ratios(log_decrements(xk)), zeta, atol=1e-7)
    np.testing.assert_allclose(periods(tk), 2 * math.pi / wd, rtol=1e-6)


def test_nonuniform_samples():
    x, _, wd = damped(0.05, 2.0)
    rng = np.random.default_rng(1)
    t = np.sort(rng.uniform(0, 20, 3000))
    tk, xk = find_maxima(t, x(t))
    np.testing.assert_allclose(damping_ratios(log_decrements(xk)), 0.05, atol=2e-4)
    np.testing.assert_allclose(periods(tk), 2 * math.pi / wd, rtol=1e-3)


def test_positive_only_and_t_min():
    t = np.linspace(0, 10, 2001)
    x = np.sin(2 * math.pi * t) * np.where(t < 5, 1.0, 0.5)  # maxima 1 then 0.5
    tk, xk = find_maxima(t, x)
    assert len(tk) == 10 and np.all(xk > 0)
    y = np.sin(2 * math.pi * t) - 2.0  # all maxima negative
    assert find_maxima(t, y)[0].size == 0
    assert find_maxima(t, y, positive_only=False)[0].size == 10
    tk, _ = find_maxima(t, x, t_min=5.0)
    assert tk.min() >= 5.0 and len(tk) == 5


@settings(max_examples=40, deadline=None)
@given(
    zeta=st.floats(min_value=0.002, max_value=0.4),
    omega=st.floats(min_value=0.5, max_value=60.0),
)
def test_property_dense_zeta(zeta, omega):
    x, dx, wd = damped(zeta, omega, amp=1.0)
    T = 2 * math.pi / wd
    t = np.linspace(0.0, 4.2 * T, 40)
    tk, xk = find_maxima(t, x(t), sol=x, dsol=dx)
    assert len(tk) >= 3
    z = damping_ratios(log_decrements(xk))
    np.testing.assert_allclose(z, zeta, rtol=1e-8, atol=1e-11)
    np.testing.assert_allclose(periods(tk), T, rtol=1e-10)


# ----------------------------------------------------------------------------- decrements
def test_decrement_formula_roundtrip():
    zeta = np.array([1e-3, 0.05, 0.3, 0.9])
    delta = 2 * math.pi * zeta / np.sqrt(1 - zeta**2)
    np.testing.assert_allclose(damping_ratios(delta), zeta, rtol=1e-14)
    np.testing.assert_allclose(log_decrements([1.0, math.e**-0.5, math.e**-1.5]), [0.5, 1.0])


def test_exponential_envelope():
    zeta, omega = 0.07, 3.5
    x, dx, _ = damped(zeta, omega)
    t = np.linspace(0, 20, 200)
    tk, xk = find_maxima(t, x(t), sol=x, dsol=dx)
    fit = exponential_envelope(tk, xk)
    assert fit.b == pytest.approx(zeta * omega, rel=1e-10)
    assert fit.rms_log < 1e-10
    np.testing.assert_allclose(fit(tk), xk, rtol=1e-9)
    fit2 = exponential_envelope(tk, xk, first=2, t_max=15.0)
    assert fit2.n == np.sum(tk[2:] <= 15.0) and fit2.b == pytest.approx(zeta * omega)


def test_linear_theory():
    assert BETA1_L == pytest.approx(
        brentq(lambda b: 1 + math.cos(b) * math.cosh(b), 1.5, 2.5, xtol=1e-16), rel=1e-15
    )
    assert BETA1_L**2 == pytest.approx(3.516015, abs=1e-6)
    L, rho, a, E = 0.3, 1000.0, 0.01, 1e6
    T = period_euler_bernoulli(L, rho, a * a, E, a**4 / 12)
    assert T == pytest.approx(1.7618229, rel=1e-7)
    assert period_euler_bernoulli(L, rho, a * a, 4 * E, a**4 / 12) == pytest.approx(T / 2)
    w = 2 * math.pi / T
    assert linear_damping_ratio(w, 0.04) == pytest.approx(0.0713260, rel=1e-6)
    np.testing.assert_allclose(linear_damping_ratio(np.array([1.0, 2.0]), 0.1), [0.05, 0.1])


# ----------------------------------------------------------------------------- energy
def oscillator(m=0.3, c=0.05, k=4.0, forced=False):
    """m q'' + c q' + k q = f(t); D_v = c q'^2 / 2 (so 2 D_v = c q'^2), P = f q'."""
    if forced:

        def q(t):
            return 0.1 * np.sin(1.3 * t) + 0.02 * t * t

        def dq(t):
            return 0.13 * np.cos(1.3 * t) + 0.04 * t

        def ddq(t):
            return -0.169 * np.sin(1.3 * t) + 0.04

    else:
        sig, wd = c / (2 * m), math.sqrt(k / m - (c / (2 * m)) ** 2)

        def q(t):
            return 0.2 * np.exp(-sig * t) * np.cos(wd * t)

        def dq(t):
            return 0.2 * np.exp(-sig * t) * (-sig * np.cos(wd * t) - wd * np.sin(wd * t))

        def ddq(t):  # from the ODE itself
            return -(c * dq(t) + k * q(t)) / m

    def kin(t):
        return 0.5 * m * dq(t) ** 2

    def el(t):
        return 0.5 * k * q(t) ** 2

    def dv(t):
        return 0.5 * c * dq(t) ** 2

    def power(t):
        return (m * ddq(t) + c * dq(t) + k * q(t)) * dq(t)

    return kin, el, dv, power


@pytest.mark.parametrize("forced", [False, True])
def test_energy_audit_trapezoid_and_dense(forced):
    kin, el, dv, power = oscillator(forced=forced)
    # the forced run starts almost at rest: scale by the largest energy instead
    e0 = float(kin(10.0) + el(10.0)) if forced else None
    t = np.linspace(0.0, 10.0, 4001)
    a = energy_audit(t, kin(t), el(t), dv(t), power(t) if forced else None, reference_energy=e0)
    assert a.max_abs_error < 2e-6  # O(h^2) trapezoid error
    assert a.relative_error[0] == 0.0
    t = np.linspace(0.0, 10.0, 101)
    b = energy_audit(t, kin(t), el(t), dv, power if forced else None, reference_energy=e0)
    assert b.max_abs_error < 1e-11  # Gauss-Legendre on the exact dense signals
    # trapezoid error shrinks like h^2
    errs = [
        energy_audit(
            tt, kin(tt), el(tt), dv(tt), power(tt) if forced else None, reference_energy=e0
        ).max_abs_error
        for tt in (np.linspace(0, 10, 501), np.linspace(0, 10, 1001))
    ]
    assert errs[0] / errs[1] == pytest.approx(4.0, rel=0.05)


def test_energy_audit_detects_imbalance():
    kin, el, dv, _ = oscillator()
    t = np.linspace(0.0, 10.0, 201)
    a = energy_audit(t, kin(t), el(t), dv, None)
    bad = energy_audit(t, kin(t), el(t), lambda s: 0.5 * dv(s), None)  # D_v halved
    assert bad.max_abs_error > 1e3 * a.max_abs_error
    assert bad.dissipated[-1] == pytest.approx(0.5 * a.dissipated[-1])
    c = energy_audit(t, kin(t), el(t), dv, reference_energy=2 * a.reference_energy)
    np.testing.assert_allclose(c.relative_error, 0.5 * a.relative_error)


def test_cumulative_integral():
    t = np.linspace(0, 1, 11)
    np.testing.assert_allclose(cumulative_integral(t, 2 * t), t**2, atol=1e-15)
    np.testing.assert_allclose(cumulative_integral(t, fun=lambda s: 7 * s**6), t**7, atol=1e-14)


# ----------------------------------------------------------------------------- bad input
@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda: find_maxima([0.0, 1.0], [1.0, 2.0]), "t needs at least 3"),
        (lambda: find_maxima([0.0, 2.0, 1.0, 3.0], [0, 1, 0, 1]), "t must be strictly"),
        (lambda: find_maxima([0.0, 1.0, 2.0], [0, np.nan, 0]), "x contains a non-finite"),
        (lambda: find_maxima([0.0, 1.0, 2.0], [0, 1, 0, 1]), "same length"),
        (lambda: find_maxima([0.0, 1.0, 2.0], [0, 1, 0], method="x"), "method"),
        (lambda: log_decrements([1.0]), "x_k needs at least 2"),
        (lambda: log_decrements([1.0, -0.5]), "x_k must be positive"),
        (lambda: log_decrements([1.0, np.inf]), "x_k contains a non-finite"),
        (lambda: periods([1.0]), "t_k needs at least 2"),
        (lambda: periods([1.0, 1.0]), "t_k must be strictly"),
        (lambda: damping_ratios([]), "delta needs at least 1"),
        (lambda: exponential_envelope([0, 1, 2], [1, 0.5, 0.25], t_min=1.5), "fewer than 2"),
        (lambda: energy_audit([0.0], [1.0], [1.0], [0.0]), "t needs at least 2"),
        (lambda: energy_audit([0, 1], [0, 0], [0, 0], [0, 0]), "reference_energy"),
        (lambda: energy_audit([0, 1], [1, 1], [1], [0, 0]), "elastic"),
        (lambda: energy_audit([0, 1], [1, 1], [1, 1], [0, np.nan]), "dissipation_rate"),
        (lambda: period_euler_bernoulli(-1.0, 1, 1, 1, 1), "L must be positive"),
        (lambda: linear_damping_ratio(1.0, math.nan), "tau"),
    ],
)
def test_bad_input_raises(call, match):
    with pytest.raises(ValueError, match=match):
        call()


def test_too_few_maxima_for_decrement():
    t = np.linspace(0, 1.2, 50)
    tk, xk = find_maxima(t, np.sin(2 * math.pi * t))
    assert len(xk) == 1
    with pytest.raises(ValueError, match="x_k needs at least 2"):
        log_decrements(xk)


def test_tip_summary():
    x, dx, wd = damped(0.05, 3.0)
    t = np.linspace(0, 10, 101)
    out = tip_summary(t, x(t), sol=x, dsol=dx)
    assert len(out["peaks"]) == len(out["periods"]) + 1 == len(out["damping_ratios"]) + 1
    np.testing.assert_allclose(out["damping_ratios"], 0.05, atol=1e-10)
    assert all(isinstance(p["t"], float) for p in out["peaks"])
    short = tip_summary(t[:30], x(t[:30]))  # one maximum only: lists empty, no error
    assert len(short["peaks"]) == 1 and short["log_decrements"] == []
