"""Tests of references.viscoelastic_beam (complex eigenvalues, base excitation)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from references.beams import (
    axial_frequencies,
    euler_bernoulli_frequencies,
    euler_bernoulli_roots,
    rectangle_torsion_constant,
    timoshenko_frequencies,
    torsional_frequencies,
)
from references.viscoelastic_beam import (
    axial_eigenvalues,
    damping_ratio,
    euler_bernoulli_eigenvalues,
    euler_bernoulli_transmissibility,
    euler_bernoulli_transmissibility_closed,
    kelvin_voigt_moduli,
    paper_base_excitation,
    paper_beam,
    resonance,
    timoshenko_eigenvalues,
    timoshenko_transmissibility,
    torsion_eigenvalues,
)
from references.viscoelastic_material import GeneralizedMaxwell

P = paper_beam()
GEO = {k: P[k] for k in ("L", "rho", "A", "I")}
E0, NU, KAPPA = P["E"], P["nu"], P["kappa"]
G0 = E0 / (2 * (1 + NU))
J_T = rectangle_torsion_constant(0.01, 0.01)
I3 = 2 * P["I"]


def kv_roots(omega: np.ndarray, tau: float) -> np.ndarray:
    """Upper root of lambda^2 + omega^2 tau lambda + omega^2 = 0 (underdamped)."""
    return -0.5 * omega**2 * tau + 1j * omega * np.sqrt(1 - (0.5 * omega * tau) ** 2)


def maxwell_oscillator_eigs(omega: float, e_inf: float, e_1: float, tau: float) -> np.ndarray:
    """Eigenvalues of a unit-mass oscillator: spring omega^2 e_inf in parallel with a Maxwell
    element (spring omega^2 e_1 in series with a dashpot omega^2 e_1 tau); state (x, v, y),
    y the displacement of the spring-dashpot node. Independent of any modulus algebra."""
    k_inf, k1 = omega**2 * e_inf, omega**2 * e_1
    c = k1 * tau
    A = np.array([[0.0, 1.0, 0.0], [-(k_inf + k1), 0.0, k1], [k1 / c, 0.0, -k1 / c]])
    ev = np.linalg.eigvals(A)
    return ev[np.argsort(-ev.imag)]


# ----------------------------------------------------------------------------- eigenvalues
def test_undamped_limits():
    E, G = kelvin_voigt_moduli(E0, NU, 0.0, 0.0)
    lam = euler_bernoulli_eigenvalues(3, E=E, **GEO)
    np.testing.assert_allclose(lam.real, 0.0, atol=1e-12)
    np.testing.assert_allclose(lam.imag, euler_bernoulli_frequencies(3, E=E0, **_rAI()), rtol=1e-13)
    lam = timoshenko_eigenvalues(3, kappa=KAPPA, E=E, G=G, **GEO)
    wt = timoshenko_frequencies(3, E=E0, kGA=KAPPA * G0 * P["A"], **_rAI())
    np.testing.assert_allclose(lam.real, 0.0, atol=1e-9)
    np.testing.assert_allclose(lam.imag, wt, rtol=1e-11)
    lam = axial_eigenvalues(3, L=P["L"], rho=P["rho"], E=E)
    np.testing.assert_allclose(lam.imag, axial_frequencies(3, L=P["L"], rho=P["rho"], E=E0),
                               rtol=1e-13)
    lam = torsion_eigenvalues(3, L=P["L"], rho=P["rho"], J_T=J_T, I3=I3, G=G)
    wt = torsional_frequencies(3, L=P["L"], rho=P["rho"], G=G0, J_T=J_T, I3=I3)
    np.testing.assert_allclose(lam.imag, wt, rtol=1e-13)


def _rAI():
    return {"L": P["L"], "rho": P["rho"], "A": P["A"], "I": P["I"]}


@pytest.mark.parametrize("tau", [1e-6, 0.02, 0.04, 0.08])
def test_kelvin_voigt_euler_bernoulli_closed_form(tau):
    E, _ = kelvin_voigt_moduli(E0, NU, tau, tau)
    w = euler_bernoulli_frequencies(3, E=E0, **_rAI())
    n = int(np.sum(0.5 * w * tau < 0.9))  # underdamped modes only
    lam = euler_bernoulli_eigenvalues(n, E=E, **GEO)
    np.testing.assert_allclose(lam, kv_roots(w[:n], tau), rtol=1e-12)
    # zeta = omega tau / 2 exactly for Kelvin-Voigt (|lambda| = omega)
    np.testing.assert_allclose(damping_ratio(lam), 0.5 * w[:n] * tau, rtol=1e-11)


@pytest.mark.parametrize("tau", [0.02, 0.04])
def test_kelvin_voigt_bar_and_shaft(tau):
    E, G = kelvin_voigt_moduli(E0, NU, tau, tau)
    wa = axial_frequencies(2, L=P["L"], rho=P["rho"], E=E0)
    wa = wa[0.5 * wa * tau < 0.9]
    lam = axial_eigenvalues(len(wa), L=P["L"], rho=P["rho"], E=E)
    np.testing.assert_allclose(lam, kv_roots(wa, tau), rtol=1e-12)
    wt = torsional_frequencies(2, L=P["L"], rho=P["rho"], G=G0, J_T=J_T, I3=I3)
    wt = wt[0.5 * wt * tau < 0.9]
    lam = torsion_eigenvalues(len(wt), L=P["L"], rho=P["rho"], J_T=J_T, I3=I3, G=G)
    np.testing.assert_allclose(lam, kv_roots(wt, tau), rtol=1e-12)


@pytest.mark.parametrize("tau", [0.02, 0.04, 0.08])
def test_kelvin_voigt_timoshenko_equal_times(tau):
    """tau_E = tau_S: the whole stiffness operator scales by (1 + s tau), so each undamped
    Timoshenko frequency gives lambda^2 + omega_T^2 tau lambda + omega_T^2 = 0."""
    E, G = kelvin_voigt_moduli(E0, NU, tau, tau)
    wt = timoshenko_frequencies(2, E=E0, kGA=KAPPA * G0 * P["A"], **_rAI())
    wt = wt[0.5 * wt * tau < 0.9]
    lam = timoshenko_eigenvalues(len(wt), kappa=KAPPA, E=E, G=G, **GEO)
    np.testing.assert_allclose(lam, kv_roots(wt, tau), rtol=1e-10)


def test_timoshenko_unequal_times_first_order():
    """Small damping, tau_E != tau_S: zeta = omega/2 (tau_E f_E + tau_S f_S) to first order,
    f_X = d ln omega^2 / d ln X the strain-energy fraction of bending / shear."""
    # a stubby beam so that the shear fraction matters
    L, a, rho = 0.05, 0.01, 1000.0
    A, I = a * a, a**4 / 12
    kw = {"L": L, "rho": rho, "A": A, "I": I}
    tE, tS = 1e-6, 4e-6
    E, G = kelvin_voigt_moduli(E0, NU, tE, tS)
    lam = timoshenko_eigenvalues(2, kappa=KAPPA, E=E, G=G, **kw)
    h, kGA = 1e-4, KAPPA * G0 * A

    def omega(e: float, g: float) -> np.ndarray:
        return timoshenko_frequencies(2, E=E0 * e, kGA=kGA * g, **kw)

    w = omega(1, 1)
    fE = np.log(omega(1 + h, 1) / omega(1 - h, 1)) / h  # central: d ln omega^2 / d ln E
    fG = np.log(omega(1, 1 + h) / omega(1, 1 - h)) / h
    np.testing.assert_allclose(fE + fG, 1.0, atol=1e-8)  # omega^2 homogeneous in stiffness
    assert (fG > 0.04).all()  # shear energy is not negligible here
    zeta = 0.5 * w * (tE * fE + tS * fG)
    # second-order remainder: relative error ~ 3 zeta^2 (zeta = 7e-5, 5.7e-4 here)
    np.testing.assert_allclose(damping_ratio(lam), zeta, rtol=1e-5)
    np.testing.assert_allclose(lam.imag, w, rtol=1e-6)


@pytest.mark.parametrize("tau1", [0.01, 0.1])
def test_single_maxwell_branch_against_oscillator(tau1):
    """E(s) = E_inf + E_1 s tau/(1 + s tau): every mode is a unit oscillator with a Maxwell
    element; compare with the eigenvalues of its 3x3 state matrix."""
    e_inf, e_1 = 1.0, 0.8
    phi = lambda s: e_inf + e_1 * s * tau1 / (1 + s * tau1)  # noqa: E731
    E = lambda s: E0 * phi(s)  # noqa: E731
    G = lambda s: G0 * phi(s)  # noqa: E731
    w = euler_bernoulli_frequencies(2, E=E0, **_rAI())
    lam = euler_bernoulli_eigenvalues(2, E=E, **GEO)
    for wk, lk in zip(w, lam, strict=True):
        ev = maxwell_oscillator_eigs(wk, e_inf, e_1, tau1)
        assert lk == pytest.approx(ev[0], rel=1e-12)
    # Timoshenko with proportional E(s), G(s): same oscillator, frequency omega_T
    wt = timoshenko_frequencies(2, E=E0, kGA=KAPPA * G0 * P["A"], **_rAI())
    lam = timoshenko_eigenvalues(2, kappa=KAPPA, E=E, G=G, **GEO)
    for wk, lk in zip(wt, lam, strict=True):
        assert lk == pytest.approx(maxwell_oscillator_eigs(wk, e_inf, e_1, tau1)[0], rel=1e-10)
    wa = axial_frequencies(1, L=P["L"], rho=P["rho"], E=E0)[0]
    la = axial_eigenvalues(1, L=P["L"], rho=P["rho"], E=E)[0]
    assert la == pytest.approx(maxwell_oscillator_eigs(wa, e_inf, e_1, tau1)[0], rel=1e-12)


def test_generalized_maxwell_material_timoshenko_residual():
    """3-D generalized Maxwell moduli (E(s) and G(s) not proportional): the eigenvalue is a
    zero of the transfer determinant and lies between the relaxed and glassy frequencies."""
    from references.viscoelastic_beam import timoshenko_determinant

    G_inf, K_inf = G0, E0 / (3 * (1 - 2 * NU))
    mat = GeneralizedMaxwell(G_inf, K_inf, G=(2e5, 1e5), K=(1e5, 3e5), tau=(0.01, 0.1))
    lam = timoshenko_eigenvalues(2, kappa=KAPPA, E=mat.E, G=mat.G_s, **GEO)
    for lk in lam:
        d = timoshenko_determinant(
            lk, L=P["L"], rhoA=P["rho"] * P["A"], rhoI=P["rho"] * P["I"],
            EI=mat.E(lk) * P["I"], kGA=KAPPA * P["A"] * mat.G_s(lk),
        )
        assert abs(d) < 1e-10
    g0, k0 = mat.glassy
    lo = timoshenko_frequencies(2, E=mat.E_relaxed(), kGA=KAPPA * G_inf * P["A"], **_rAI())
    hi = timoshenko_frequencies(2, E=mat.E_glassy(), kGA=KAPPA * g0 * P["A"], **_rAI())
    assert (lo < np.abs(lam)).all() and (np.abs(lam) < hi).all()
    assert (damping_ratio(lam) > 0).all()


# ----------------------------------------------------------------------------- base excitation
def _modal_sum_T(omega: float, E, n_modes: int = 300) -> complex:
    """E-B transmissibility by modal superposition (relative motion, normalized modes):
    T = 1 + sum_n phi_n(L) Gamma_n omega^2 / (omega_n^2 E(i w)/E0 - omega^2),
    Gamma_n = int phi_n / int phi_n^2 = 2 sigma_n / (beta_n L). Stable forms of
    sigma_n and phi_n(L) = 2 (cosh x sin x - cos x sinh x)/(sinh x + sin x)."""
    k = np.arange(31, n_modes + 1)  # beyond 30 the roots equal (2k-1) pi/2 to e^-90
    x = np.concatenate([euler_bernoulli_roots(30), (2 * k - 1) * math.pi / 2])
    th, sc = np.tanh(x), 2 * np.exp(-x) / (1 + np.exp(-2 * x))
    sigma = (1 + np.cos(x) * sc) / (th + np.sin(x) * sc)
    phiL = 2 * (np.sin(x) - np.cos(x) * th) / (th + np.sin(x) * sc)
    gam = 2 * sigma / x
    wn = x**2 * math.sqrt(E0 * P["I"] / (P["rho"] * P["A"] * P["L"] ** 4))
    r = E(1j * omega) / E0
    return 1 + np.sum(phiL * gam * omega**2 / (wn**2 * r - omega**2))


@pytest.mark.parametrize("tau", [0.0, 0.04])
def test_euler_bernoulli_transmissibility_three_ways(tau):
    E, _ = kelvin_voigt_moduli(E0, NU, tau, tau)
    w1 = euler_bernoulli_frequencies(1, E=E0, **_rAI())[0]
    omegas = np.array([0.01, 0.5, 0.93, 1.07, 2.0, 5.0, 8.3]) * w1
    T4 = euler_bernoulli_transmissibility(omegas, E=E, **GEO)
    Tc = euler_bernoulli_transmissibility_closed(omegas, E=E, **GEO)
    np.testing.assert_allclose(T4, Tc, rtol=1e-10)
    Tm = np.array([_modal_sum_T(w, E) for w in omegas])
    np.testing.assert_allclose(T4, Tm, rtol=1e-9)
    assert T4[0] == pytest.approx(1.0, abs=1e-3)  # quasi-static: rigid translation


def test_maxwell_transmissibility_modal_sum():
    mat = GeneralizedMaxwell(G0, E0 / (3 * (1 - 2 * NU)), G=(2e5,), K=(1e5,), tau=(0.05,))
    lam = euler_bernoulli_eigenvalues(1, E=mat.E, **GEO)[0]
    omegas = np.array([0.5, 0.9, 1.0, 1.1, 3.0]) * lam.imag
    T4 = euler_bernoulli_transmissibility(omegas, E=mat.E, **GEO)
    Tm = np.array([_modal_sum_T(w, mat.E) for w in omegas])
    np.testing.assert_allclose(T4, Tm, rtol=1e-9)


def _timoshenko_T_exponential(omega, *, E, G, rotary=True):
    """Independent Timoshenko solution: W = sum a_k e^{mu_k x}, Psi = r_k W_k with
    kGA EI mu^4 + mu^2 w^2 (kGA rhoI + rhoA EI) + rhoA w^2 (rhoI w^2 - kGA) = 0 and
    r = (kGA mu^2 + rhoA w^2) / (kGA mu); 4x4 boundary system."""
    L, rhoA = P["L"], P["rho"] * P["A"]
    rhoI = P["rho"] * P["I"] if rotary else 0.0
    s = 1j * omega
    EI, kGA = E(s) * P["I"], KAPPA * P["A"] * G(s)
    w2 = omega**2
    m2 = np.roots([kGA * EI, w2 * (kGA * rhoI + rhoA * EI), rhoA * w2 * (rhoI * w2 - kGA)])
    mu = np.concatenate([np.sqrt(m2 + 0j), -np.sqrt(m2 + 0j)])
    r = (kGA * mu**2 + rhoA * w2) / (kGA * mu)
    e = np.exp(mu * L)
    Mtx = np.array([np.ones(4), r, EI * r * mu * e, kGA * (mu - r) * e])
    a = np.linalg.solve(Mtx, np.array([1, 0, 0, 0], dtype=complex))
    return complex(np.sum(a * e))


@pytest.mark.parametrize("tau", [0.0, 0.04])
def test_timoshenko_transmissibility_exponential_solution(tau):
    E, G = kelvin_voigt_moduli(E0, NU, tau, 2 * tau)
    w1 = euler_bernoulli_frequencies(1, E=E0, **_rAI())[0]
    omegas = np.array([0.3, 0.95, 1.05, 4.0, 9.0]) * w1
    Tt = timoshenko_transmissibility(omegas, kappa=KAPPA, E=E, G=G, **GEO)
    Te = np.array([_timoshenko_T_exponential(w, E=E, G=G) for w in omegas])
    np.testing.assert_allclose(Tt, Te, rtol=1e-10)


def test_timoshenko_transmissibility_tends_to_euler_bernoulli():
    E, _ = kelvin_voigt_moduli(E0, NU, 0.04, 0.04)
    G_stiff = lambda s: 1e6 * E(s)  # noqa: E731
    w1 = euler_bernoulli_frequencies(1, E=E0, **_rAI())[0]
    omegas = np.array([0.5, 1.0, 2.0]) * w1
    Tt = timoshenko_transmissibility(omegas, kappa=KAPPA, E=E, G=G_stiff, rotary_inertia=False,
                                     **GEO)
    Te = euler_bernoulli_transmissibility(omegas, E=E, **GEO)
    np.testing.assert_allclose(Tt, Te, rtol=1e-7)


def test_resonance_near_damped_frequency():
    """Small damping: the peak is at omega_1 (to O(zeta^2)) with |T| ~ T_static_mode/(2 zeta)."""
    tau = 1e-3
    E, _ = kelvin_voigt_moduli(E0, NU, tau, tau)
    lam = euler_bernoulli_eigenvalues(1, E=E, **GEO)[0]
    pk = resonance(lambda w: euler_bernoulli_transmissibility(w, E=E, **GEO),
                   0.8 * lam.imag, 1.2 * lam.imag)
    zeta = float(damping_ratio(lam))
    assert pk.omega == pytest.approx(abs(lam), rel=2 * zeta**2)
    x = euler_bernoulli_roots(1)[0]
    phiL = 2 * (np.cosh(x) * np.sin(x) - np.cos(x) * np.sinh(x)) / (np.sinh(x) + np.sin(x))
    part = phiL * 2 * (np.cosh(x) + np.cos(x)) / (np.sinh(x) + np.sin(x)) / x
    assert pk.gain == pytest.approx(part / (2 * zeta), rel=5 * zeta)


def test_paper_base_excitation_numbers():
    res = paper_base_excitation(0.04)
    eb, ti = res["euler_bernoulli"], res["timoshenko"]
    w1 = euler_bernoulli_frequencies(1, E=E0, **_rAI())[0]
    assert eb["zeta"] == pytest.approx(0.5 * w1 * 0.04, rel=1e-12)
    assert eb["omega_d"] == pytest.approx(w1 * math.sqrt(1 - (0.02 * w1) ** 2), rel=1e-12)
    # regression values (see the report)
    assert eb["T_peak"] == pytest.approx(11.01996, rel=1e-5)
    assert eb["omega_peak"] == pytest.approx(3.561736, rel=1e-5)
    assert eb["amp_1.0"] == pytest.approx(0.01101823, rel=1e-5)
    assert ti["T_peak"] == pytest.approx(11.02388, rel=1e-5)
    assert ti["amp_0.9"] == pytest.approx(0.006268653, rel=1e-5)
    # shear + rotary inertia: slightly lower frequency, nearly equal peak for L/a = 30
    assert ti["omega_d"] < eb["omega_d"]
    assert abs(ti["T_peak"] / eb["T_peak"] - 1) < 1e-3
