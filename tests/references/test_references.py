"""Tests of the independent references themselves (no kvrod code involved)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from references.beams import (
    axial_frequencies,
    damped_frequency,
    euler_bernoulli_frequencies,
    euler_bernoulli_roots,
    kelvin_voigt_damping_ratio,
    paper_frequencies,
    rectangle_torsion_constant,
    static_tip_linear,
    timoshenko_frequencies,
    torsional_frequencies,
)
from references.reissner import (
    cowper_rectangle,
    elastica_tip,
    paper_cantilever,
    solve_reissner,
    solve_reissner_bvp,
)

P = paper_cantilever()


# ----------------------------------------------------------------------------- statics
def test_paper_load_parameter():
    assert P["load_parameter"] == pytest.approx(5.4, rel=1e-14)
    assert P["kappa"] == pytest.approx(13.0 / 15.3, rel=1e-14)


@pytest.mark.parametrize("lam", [0.1, 1.0, 5.4, 10.0])
def test_elastica_matches_stiff_reissner(lam):
    L, EI = 0.3, P["EI"]
    F = lam * EI / L**2
    el = elastica_tip(F, EI, L)
    # exact inextensible/unshearable limit (compliances 0) ...
    r = solve_reissner(F, L=L, EA=math.inf, GA=math.inf, EI=EI)
    assert r.tip[0] == pytest.approx(el.x, abs=1e-10 * L)
    assert r.tip[1] == pytest.approx(el.z, abs=1e-10 * L)
    assert r.tip_rotation == pytest.approx(el.theta, abs=1e-10)
    # ... and very large but finite EA, GA: O(F/EA) away
    big = 1e10 * F
    r = solve_reissner(F, L=L, EA=big, GA=big, EI=EI)
    assert r.tip[0] == pytest.approx(el.x, abs=1e-8 * L)
    assert r.tip[1] == pytest.approx(el.z, abs=1e-8 * L)


def test_elastica_sign_and_zero():
    EI, L = P["EI"], P["L"]
    a, b = elastica_tip(0.05, EI, L), elastica_tip(-0.05, EI, L)
    assert b.x == -a.x and b.z == a.z and b.theta == -a.theta
    z = elastica_tip(0.0, EI, L)
    assert (z.x, z.z, z.theta) == (0.0, L, 0.0)


def test_elastica_self_consistency():
    """Base moment F z_tip equals EI theta'(0) = sqrt(2 F EI sin theta_L)."""
    EI, L, F = P["EI"], P["L"], P["F"]
    el = elastica_tip(F, EI, L)
    assert F * el.z == pytest.approx(math.sqrt(2 * F * EI * math.sin(el.theta)), rel=1e-13)
    r = solve_reissner(F, L=L, EA=math.inf, GA=math.inf, EI=EI)
    assert r.base_moment == pytest.approx(F * el.z, rel=1e-9)


@pytest.mark.parametrize("shear", [True, False])
def test_small_load_matches_linear_beam(shear):
    L, EI, EA = P["L"], P["EI"], P["EA"]
    kGA = P["GA_s"] if shear else math.inf
    F1 = 1e-3 * EI / L**2  # load parameter 1e-3
    errs = []
    for F in (F1, 2 * F1):
        r = solve_reissner(F, L=L, EA=EA, GA=kGA, EI=EI)
        lin = static_tip_linear(F, L=L, E=P["E"], I=P["I"], kGA=kGA)
        errs.append(r.tip[0] - lin)
        # relative error O(load^2) (odd in F): 1e-6-ish at load parameter 1e-3
        assert abs(r.tip[0] - lin) < 1e-5 * lin
    # error scales with F^3 (relative error ~ F^2)
    assert errs[1] / errs[0] == pytest.approx(8.0, rel=1e-2)


def test_shooting_matches_collocation():
    L, F = P["L"], P["F"]
    r = solve_reissner(F, L=L, EA=P["EA"], GA=P["GA_s"], EI=P["EI"])
    x, z, th = solve_reissner_bvp(F, L=L, EA=P["EA"], GA=P["GA_s"], EI=P["EI"], tol=1e-10)
    assert x == pytest.approx(r.tip[0], abs=1e-7)
    assert z == pytest.approx(r.tip[1], abs=1e-7)
    assert th == pytest.approx(r.tip_rotation, abs=1e-6)


def test_boundary_conditions_and_strains():
    r = solve_reissner(P["F"], L=P["L"], EA=P["EA"], GA=P["GA_s"], EI=P["EI"])
    assert (r.x[0], r.z[0], r.theta[0]) == (0.0, 0.0, 0.0)
    assert abs(r.residual) < 1e-12 * P["F"] * P["L"]
    assert (r.x[-1], r.z[-1]) == r.tip
    assert np.max(np.abs(r.axial_strain)) <= P["F"] / P["EA"] * (1 + 1e-12)
    assert np.max(np.abs(r.shear_strain)) <= P["F"] / P["GA_s"] * (1 + 1e-12)


def test_paper_tip_about_022m():
    """The paper: 'the tip moves by about 0.22 m'."""
    r = solve_reissner(P["F"], L=P["L"], EA=P["EA"], GA=P["GA_s"], EI=P["EI"])
    assert r.tip[0] == pytest.approx(0.2184305, abs=2e-7)
    assert r.tip[1] == pytest.approx(0.1776602, abs=2e-7)
    el = elastica_tip(P["F"], P["EI"], P["L"])
    assert el.x == pytest.approx(0.2181945, abs=2e-7)
    # extension + shear change the tip by ~0.1 %: resolvable by the 0.1 % acceptance test
    assert 5e-4 < (r.tip[0] - el.x) / el.x < 2e-3


@pytest.mark.parametrize("angle", [0.3, -0.7, math.pi / 2])
def test_oblique_load_virtual_work(angle):
    """Dead load: d(potential at equilibrium)/dF = -(direction . tip displacement)."""
    L, EI, EA, GA = P["L"], P["EI"], P["EA"], P["GA_s"]
    F, h = 0.03, 1e-5

    def pot(f):
        return solve_reissner(f, L=L, EA=EA, GA=GA, EI=EI, angle=angle).potential

    r = solve_reissner(F, L=L, EA=EA, GA=GA, EI=EI, angle=angle)
    u = math.cos(angle) * r.tip[0] + math.sin(angle) * (r.tip[1] - L)
    dpot = (pot(F + h) - pot(F - h)) / (2 * h)
    assert dpot == pytest.approx(-u, rel=1e-6, abs=1e-12)
    if angle == math.pi / 2:  # pure tension: straight bar, stretch F L / EA
        assert r.tip[0] == pytest.approx(0.0, abs=1e-14)
        assert r.tip[1] - L == pytest.approx(F * L / EA, rel=1e-10)


def test_virtual_work_perpendicular():
    L, EI, EA, GA, F, h = P["L"], P["EI"], P["EA"], P["GA_s"], P["F"], 1e-6
    pm = [solve_reissner(f, L=L, EA=EA, GA=GA, EI=EI).potential for f in (F - h, F + h)]
    r = solve_reissner(F, L=L, EA=EA, GA=GA, EI=EI)
    assert (pm[1] - pm[0]) / (2 * h) == pytest.approx(-r.tip[0], rel=1e-6)


def test_cowper_square():
    assert cowper_rectangle(0.0) == pytest.approx(10 / 12)
    assert cowper_rectangle(0.3) == pytest.approx(0.849673, rel=1e-6)


# ----------------------------------------------------------------------------- beams
def test_euler_bernoulli_roots():
    r = euler_bernoulli_roots(5)
    assert r[0] == pytest.approx(1.8751040687119611, rel=1e-14)
    assert r[0] == pytest.approx(1.8751040687, abs=1e-10)
    assert r[1] == pytest.approx(4.6940911329741745, rel=1e-13)
    assert r[2] == pytest.approx(7.8547574382376126, rel=1e-13)
    np.testing.assert_allclose(1 + np.cos(r) * np.cosh(r), 0.0, atol=1e-9)
    # asymptotics (2k-1) pi / 2
    assert r[4] == pytest.approx(9 * math.pi / 2, rel=1e-6)


def _huang(w, *, L, rho, A, E, I, kGA):
    """Closed-form Timoshenko clamped-free frequency equation (Huang 1961)."""
    r2, s2 = I / (A * L * L), E * I / (kGA * L * L)
    b2 = rho * A * w * w * L**4 / (E * I)
    b = math.sqrt(b2)
    root = math.sqrt((r2 - s2) ** 2 + 4 / b2)
    al, be = math.sqrt(0.5 * (root - (r2 + s2))), math.sqrt(0.5 * (root + (r2 + s2)))
    return (
        2
        + (b2 * (r2 - s2) ** 2 + 2) * math.cosh(b * al) * math.cos(b * be)
        - b * (r2 + s2) / math.sqrt(1 - b2 * r2 * s2) * math.sinh(b * al) * math.sin(b * be)
    )


def test_timoshenko_matches_closed_form_equation():
    from scipy.optimize import brentq

    kw = dict(L=P["L"], rho=P["rho"], A=P["A"], E=P["E"], I=P["I"], kGA=P["GA_s"])
    w = timoshenko_frequencies(3, **kw)
    for wi in w:
        wh = brentq(lambda x: _huang(x, **kw), 0.99 * wi, 1.01 * wi, xtol=1e-13)
        assert wi == pytest.approx(wh, rel=1e-8)


@pytest.mark.parametrize("slenderness", [30.0, 100.0, 1000.0])
def test_timoshenko_tends_to_euler_bernoulli(slenderness):
    L, rho, E, nu = 1.0, 1000.0, 1e6, 0.3
    a = L / slenderness
    A, I = a * a, a**4 / 12
    kGA = cowper_rectangle(nu) * E / (2 * (1 + nu)) * A
    we = euler_bernoulli_frequencies(3, L=L, rho=rho, A=A, E=E, I=I)
    wt = timoshenko_frequencies(3, L=L, rho=rho, A=A, E=E, I=I, kGA=kGA)
    assert (wt < we).all()
    # relative correction ~ (beta_k L)^2 (r/L)^2 (1 + E/(kappa G)) / 2, r^2 = I/A
    r2 = I / (A * L * L)
    bound = euler_bernoulli_roots(3) ** 2 * r2 * (1 + E / (kGA / A)) * 1.0
    rel = 1 - wt / we
    assert (rel < bound).all()
    assert (rel > 0.2 * bound).all()


def test_paper_frequencies_and_periods():
    res = paper_frequencies(3)
    we, wt = res["euler_bernoulli"], res["timoshenko"]
    assert 2 * math.pi / we[0] == pytest.approx(1.7618229, rel=1e-7)
    assert 2 * math.pi / wt[0] == pytest.approx(1.7633610, rel=1e-6)
    assert abs(wt[0] / we[0] - 1) < 2e-3  # Timoshenko effect below the 0.2 % tolerance
    assert res["J_T"] == pytest.approx(0.1405770 * 0.01**4, rel=1e-6)
    assert res["axial"][0] == pytest.approx(math.pi / 0.6 * math.sqrt(1000.0), rel=1e-14)


def test_torsion_constant():
    assert rectangle_torsion_constant(1.0, 1.0) == pytest.approx(0.1405770, abs=1e-7)
    # thin strip: b a^3 / 3 (1 - 0.630 a/b)
    assert rectangle_torsion_constant(1.0, 100.0) == pytest.approx(
        100 / 3 * (1 - 0.6302 / 100), rel=1e-5
    )
    assert rectangle_torsion_constant(2.0, 1.0) == rectangle_torsion_constant(1.0, 2.0)


def test_axial_torsion_formulas():
    w = axial_frequencies(3, L=2.0, rho=4.0, E=16.0)
    np.testing.assert_allclose(w, np.array([1, 3, 5]) * math.pi / 4 * 2.0)
    w = torsional_frequencies(2, L=1.0, rho=1.0, G=1.0, J_T=1.0, I3=1.0)
    np.testing.assert_allclose(w, np.array([1, 3]) * math.pi / 2)


def test_kelvin_voigt_modal():
    w1 = paper_frequencies(1)["euler_bernoulli"][0]
    z = np.array([kelvin_voigt_damping_ratio(w1, tau) for tau in (0.02, 0.04, 0.08)])
    np.testing.assert_allclose(z, [0.035663, 0.071326, 0.142652], atol=1e-6)
    assert damped_frequency(2.0, 0.5) == pytest.approx(2.0 * math.sqrt(1 - 0.25))
    assert np.isnan(damped_frequency(10.0, 1.0))


def test_kelvin_voigt_modal_from_ode():
    """zeta = omega tau / 2 follows from m q'' + tau k q' + k q = 0."""
    w, tau = 3.5, 0.04
    lam = np.roots([1.0, tau * w * w, w * w])
    zeta = -lam[0].real / abs(lam[0])
    assert zeta == pytest.approx(kelvin_voigt_damping_ratio(w, tau), rel=1e-12)
    assert abs(lam[0].imag) == pytest.approx(damped_frequency(w, tau), rel=1e-12)
