"""Tests of references.viscoelastic_material (generalized Maxwell, 3-D Kelvin-Voigt)."""

from __future__ import annotations

import numpy as np
import pytest

from references.viscoelastic_material import (
    GeneralizedMaxwell,
    example_two_branch,
    fit_first_order,
    kelvin_voigt_complex_modulus,
    kelvin_voigt_uniaxial,
    maxwell_step_stress,
    relaxation_modulus_laplace,
    shear_bulk_from_E_nu,
    talbot_inverse,
)

E0, NU = 1.0e6, 0.3
G0, K0 = shear_bulk_from_E_nu(E0, NU)
MAT2 = example_two_branch()
T_GRID = np.concatenate([[1e-5], np.geomspace(1e-4, 1.0, 25), [3.0]])


def test_talbot_known_transform():
    t = np.array([0.01, 0.1, 1.0, 5.0])
    np.testing.assert_allclose(talbot_inverse(lambda s: 1 / (s + 2.0), t), np.exp(-2 * t),
                               rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(talbot_inverse(lambda s: 1 / s**2, t), t, rtol=1e-10)


@pytest.mark.parametrize("mode", ["uniaxial", "shear"])
def test_expm_matches_ode(mode):
    a = maxwell_step_stress(MAT2, T_GRID, 2e-3, mode=mode)
    b = maxwell_step_stress(MAT2, T_GRID, 2e-3, mode=mode, method="ode")
    np.testing.assert_allclose(a, b, rtol=1e-9)


@pytest.mark.parametrize(
    "mat",
    [
        MAT2,
        GeneralizedMaxwell(G0, K0, G=(5e5,), K=(0.0,), tau=(0.03,)),  # deviatoric branch only
        GeneralizedMaxwell(G0, K0, G=(0.0,), K=(2e6,), tau=(0.03,)),  # bulk branch only
        GeneralizedMaxwell(0.5 * G0, 2 * K0, G=(1e5, 3e5, 2e5), K=(4e5, 0.0, 1e6),
                           tau=(1e-3, 0.02, 0.5)),
    ],
)
def test_time_domain_matches_inverse_laplace(mat):
    """Two independent routes to E_relax(t): internal-variable ODEs vs Talbot(E(s)/s)."""
    td = maxwell_step_stress(mat, T_GRID)
    tl = relaxation_modulus_laplace(mat, T_GRID)
    np.testing.assert_allclose(td, tl, rtol=1e-7)
    # shear: also against the Prony series itself
    gs = maxwell_step_stress(mat, T_GRID, mode="shear")
    np.testing.assert_allclose(gs, relaxation_modulus_laplace(mat, T_GRID, mode="shear"),
                               rtol=1e-7)
    prony = mat.G_inf + sum(g * np.exp(-T_GRID / t) for g, t in zip(mat.G, mat.tau, strict=True))
    np.testing.assert_allclose(gs, prony, rtol=1e-12)


def test_glassy_and_relaxed_limits():
    s = maxwell_step_stress(MAT2, np.array([0.0, 50.0]), 1.0)
    assert s[0] == pytest.approx(MAT2.E_glassy(), rel=1e-13)
    assert s[1] == pytest.approx(MAT2.E_relaxed(), rel=1e-13)
    assert MAT2.E_relaxed() == pytest.approx(E0, rel=1e-13)
    # monotone relaxation
    e = maxwell_step_stress(MAT2, T_GRID)
    assert (np.diff(e) < 0).all()


def test_proportional_branch_is_a_prony_series():
    """K_j/K_inf = G_j/G_inf: E(s) = E_inf phi(s), so E_relax = E_inf (1 + c e^{-t/tau})."""
    c, tau = 0.7, 0.05
    mat = GeneralizedMaxwell(G0, K0, G=(c * G0,), K=(c * K0,), tau=(tau,))
    e = maxwell_step_stress(mat, T_GRID)
    np.testing.assert_allclose(e, E0 * (1 + c * np.exp(-T_GRID / tau)), rtol=1e-12)


def test_lateral_stress_matters():
    """Non-proportional branches: E_relax is not E_inf + sum E_j e^{-t/tau_j} with the branch
    'Young's moduli' E_j = 9 K_j G_j/(3K_j + G_j) (the naive rod model)."""
    naive = E0 + sum(9 * k * g / (3 * k + g) * np.exp(-T_GRID / t)
                     for g, k, t in zip(MAT2.G, MAT2.K, MAT2.tau, strict=True))
    e = maxwell_step_stress(MAT2, T_GRID)
    assert np.max(np.abs(e / naive - 1)) > 1e-2


def test_two_branch_example_values():
    t1 = MAT2.tau[0]
    e = maxwell_step_stress(MAT2, np.array([0.0, t1, 10 * t1]))
    np.testing.assert_allclose(e, [1.733157894737e6, 1.420142388610e6, 1.100281321931e6],
                               rtol=1e-11)


# ----------------------------------------------------------------------------- Kelvin-Voigt
def _ramp(tau_S, tau_B, t):
    t1, eps0 = 0.05, 1e-3
    return kelvin_voigt_uniaxial(t, [0.0, t1], [0.0, eps0], E=E0, nu=NU, tau_S=tau_S,
                                 tau_B=tau_B), t1, eps0


@pytest.mark.parametrize("tau", [0.02, 0.04])
def test_kelvin_voigt_equal_times_is_exact(tau):
    t = np.array([0.0, 0.01, 0.03, 0.049, 0.05, 0.06, 0.2])
    r, t1, eps0 = _ramp(tau, tau, t)
    rate = np.where(t < t1, eps0 / t1, 0.0)
    np.testing.assert_allclose(r.stress, E0 * (r.strain + tau * rate), rtol=1e-12,
                               atol=1e-9 * E0 * eps0)
    np.testing.assert_allclose(r.lateral_strain, -NU * r.strain, rtol=1e-12, atol=1e-18)


@pytest.mark.parametrize("tau_S, tau_B", [(0.04, 0.0), (0.04, 0.12), (0.02, 0.08)])
def test_kelvin_voigt_ramp_matches_inverse_laplace(tau_S, tau_B):
    """sigma = eps0/t1 (H(t) - H(t - t1)), H = L^-1[E(s)/s^2] (unit-rate response)."""
    t = np.array([0.001, 0.02, 0.049, 0.051, 0.08, 0.3, 1.0])
    r, t1, eps0 = _ramp(tau_S, tau_B, t)
    G = lambda s: G0 * (1 + s * tau_S)  # noqa: E731
    K = lambda s: K0 * (1 + s * tau_B)  # noqa: E731

    def H(s):
        return 9 * K(s) * G(s) / (3 * K(s) + G(s)) / s**2

    ref = talbot_inverse(H, t)
    late = t > t1
    ref[late] -= talbot_inverse(H, t[late] - t1)
    np.testing.assert_allclose(r.stress, eps0 / t1 * ref, rtol=1e-8)


def test_kelvin_voigt_complex_modulus_and_first_order():
    w = np.geomspace(1e-3, 0.3, 30)  # omega tau <= 0.036: fit truncation ~ 1e-10
    for tau_S, tau_B in [(0.04, 0.04), (0.04, 0.0), (0.04, 0.12), (0.02, 0.08)]:
        Es = kelvin_voigt_complex_modulus(w, E=E0, nu=NU, tau_S=tau_S, tau_B=tau_B)
        Gs, Ks = G0 * (1 + 1j * w * tau_S), K0 * (1 + 1j * w * tau_B)
        np.testing.assert_allclose(Es, 9 * Ks * Gs / (3 * Ks + Gs), rtol=1e-13)
        c = fit_first_order(w, Es, E0)
        tau_E = ((1 - 2 * NU) * tau_B + 2 * (1 + NU) * tau_S) / 3  # hand derivation
        tau_m = (2 * (1 + NU) * tau_B + (1 - 2 * NU) * tau_S) / 3
        assert c[0] == pytest.approx(tau_E, rel=1e-9)
        assert c[1] == pytest.approx((tau_B - tau_m) * (tau_S - tau_m), rel=1e-7, abs=1e-12)
        diff = np.abs(Es - E0 * (1 + 1j * w * tau_E)) / E0
        if tau_S == tau_B:
            assert np.max(diff) < 1e-14  # exactly Kelvin-Voigt
        else:
            # O(omega^2): the difference divided by omega^2 tends to |c2|
            assert diff[0] / w[0] ** 2 == pytest.approx(abs(c[1]), rel=1e-3)
            assert np.all(diff <= abs(c[1]) * w**2 * (1 + 1e-12))
