"""The static Newton iteration's model work in C (runtime/solvers/native/statics.c,
``RodStatics`` on its compiled kernels) against the NumPy methods it replaces: the same
bits for the residual at rest, the gathered band Jacobian, the retraction and whole
static solves (a gauge, obstacles, a Maxwell rod, coupled sections, large rotations)."""

from __future__ import annotations

import numpy as np
import pytest

from runtime.model.statics import RodStatics
from runtime.problem.assemble import build_model
from runtime.problem.registry import load_problem
from runtime.simulate import simulate as S
from runtime.solvers.native.pointers import function_address
from runtime.solvers.protocols import band_storage

CASES = [("cantilever", {"rod.elements": 6}),
         ("maxwell_cantilever", {"rod.elements": 5}),
         ("coupled_strip", {"rod.elements": 5}),
         ("bathe_bolourchi", {"rod.elements": 8}),
         ("contact_lifted_rod", {"rod.elements": 12})]


def _libm_is_numpys() -> bool:
    """Whether NumPy's float64 sin and cos round as the C library's (statics.c calls
    libm's; NumPy 2's are libm's, a build with vectorised ones may differ by an ulp)."""
    import math

    x = np.random.default_rng(0).uniform(-4.0, 4.0, 2000)
    return (np.array_equal(np.sin(x), [math.sin(v) for v in x])
            and np.array_equal(np.cos(x), [math.cos(v) for v in x]))


def _same(a: np.ndarray, b: np.ndarray, rotations: bool) -> bool:
    """Bit for bit; where rotations went through sin and cos and NumPy's differ from
    libm's, to a few ulps."""
    if not rotations or _libm_is_numpys():
        return np.array_equal(a, b)
    return np.allclose(a, b, rtol=1e-13, atol=1e-15)


def _numpy(st: RodStatics):
    """The problem with its NumPy methods (the C core set aside)."""
    core, st._native = st._native, False
    return core


@pytest.mark.parametrize("name, overrides", CASES)
def test_residual_jacobian_and_retraction_are_numpys_bits(name, overrides):
    model = build_model(load_problem(name, overrides))
    rng = np.random.default_rng(5)
    with model.statics():
        st = RodStatics(model)
        core = st._native
        assert core, "the compiled static core is used on the C backend"
        # a Maxwell rod's: the Jacobian without its internal strains' rows and columns
        # (kvrod_jacobian_band_relaxed), checked against the full one below
        relaxed = function_address(model._lib.kvrod_jacobian_band_relaxed)
        assert (core.s.jac == relaxed) == bool(model.branches)
        st.load_scale = 1.0
        for _ in range(3):
            y = model.reference + 0.05 * rng.standard_normal(model.n)
            dx = 0.4 * rng.standard_normal(st.n_static)
            got = {"r": np.empty(st.n_static)}
            st.static_residual(y, got["r"])
            got["y1"] = st.static_retract(y, dx)
            st.static_factor(y)                  # the band, then its LU in place
            band = core.band.copy()
            core.jacobian(y)
            got["J"] = core.band.copy()
            _numpy(st)
            want = {"r": np.empty(st.n_static)}
            st.static_residual(y, want["r"])
            want["y1"] = st.static_retract(y, dx)
            want["J"] = band_storage(st.n_static, st.kl_static, st.ku_static)
            want["J"].fill(0.0)
            st.static_jacobian_band(y, want["J"])
            st._native = core
            for key in want:
                assert _same(got[key], want[key], rotations=key == "y1"), key
            assert not np.array_equal(band, got["J"])   # the factor overwrote its band


@pytest.mark.parametrize("name, overrides", [
    ("cantilever", {"rod.elements": 6}),
    ("bathe_bolourchi", {"rod.elements": 8}),
    ("simply_supported", {"rod.elements": 6}),       # its gauge holds a rigid rotation
    ("rollup", {"rod.elements": 8}),
    ("maxwell_cantilever", {"rod.elements": 6}),
])
def test_a_static_solve_is_the_same_with_and_without_the_c_core(name, overrides,
                                                                monkeypatch):
    p = load_problem(name, overrides)
    native = S.static_equilibrium(p, build_model(p))
    with monkeypatch.context() as mp:
        mp.setattr(RodStatics, "_native_core", lambda self: None)
        plain = S.static_equilibrium(p, build_model(p))
    assert native.per_step == plain.per_step and native.iterations == plain.iterations
    assert _same(native.y, plain.y, rotations=True)


@pytest.mark.parametrize("name, overrides", [
    ("cantilever", {"rod.elements": 6}),
    ("bathe_bolourchi", {"rod.elements": 8}),         # large rotations, damped steps
    ("maxwell_cantilever", {"rod.elements": 5}),
])
def test_the_fused_newton_trial_is_the_step_by_step_one(name, overrides, monkeypatch):
    """solve_static's full Newton trial in one compiled call (static_newton_trial) gives
    what its steps one call after another give: the same states, iterations, residual
    evaluations, line-search and watchdog counts, bit for bit."""
    from runtime.solvers import statics as solver

    results = {}
    for fused in (True, False):
        p = load_problem(name, overrides)
        m = build_model(p)
        with monkeypatch.context() as mp:
            if not fused:
                mp.setattr(RodStatics, "static_newton_trial", None)
            calls: list = []

            def kept(*a, _calls=calls, **k):
                _calls.append(solver.solve_static(*a, **k))
                return _calls[-1]

            mp.setattr(S, "solve_static", kept)
            results[fused] = (S.static_equilibrium(p, m), calls[0])
    (a, ra), (b, rb) = results[True], results[False]
    assert np.array_equal(a.y, b.y) and a.per_step == b.per_step
    for key in ("total_iterations", "line_search_backtracks", "watchdog_restarts",
                "load_cuts", "residual_norm"):
        assert getattr(ra, key) == getattr(rb, key), key


def test_the_factor_solves_the_static_band_system():
    model = build_model(load_problem("cantilever", {"rod.elements": 6}))
    rng = np.random.default_rng(2)
    with model.statics():
        st = RodStatics(model)
        st.load_scale = 1.0
        y = model.reference + 0.02 * rng.standard_normal(model.n)
        st._native.jacobian(y)
        J = st._native.band.copy()
        lu = st.static_factor(y)
        assert lu.info == 0
        b = rng.standard_normal(st.n_static)
        x = lu.solve(b)
        kl, ku, n = st.kl_static, st.ku_static, st.n_static
        dense = np.zeros((n, n))
        for j in range(n):
            for i in range(max(0, j - ku), min(n, j + kl + 1)):
                dense[i, j] = J[kl + ku + i - j, j]
        np.testing.assert_allclose(dense @ x, b, rtol=1e-10, atol=1e-10 * np.abs(b).max())
