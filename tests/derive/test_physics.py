"""The derived rod parameters against independent numerical 3-D evaluations and limits."""

from __future__ import annotations

import numpy as np
import sympy as sp
from hypothesis import given, settings
from hypothesis import strategies as st

from derive import formulas, step
from derive.symbols import eta, nu, tau_B, tau_S, zeta


def kv_dissipation_density_numeric(dH, zeta_, eta_, nu_):
    """2 Psi_KV from a plain NumPy 3-D evaluation (no SymPy): the ULC strain rate
    (dH (x) e3 + e3 (x) dH)/2 - nu dH3 (I - e3 e3), contracted with
    V = zeta I(x)I + 2 eta (II - I(x)I/3)."""
    e3 = np.array([0.0, 0.0, 1.0])
    D = 0.5 * (np.outer(dH, e3) + np.outer(e3, dH)) - nu_ * dH[2] * (np.eye(3) - np.outer(e3, e3))
    tr = np.trace(D)
    S = zeta_ * tr * np.eye(3) + 2 * eta_ * (D - tr / 3 * np.eye(3))
    return float(np.sum(S * D)), S, D


@settings(max_examples=60, deadline=None)
@given(st.floats(-0.99, 0.5), st.floats(0.0, 10.0), st.floats(0.01, 10.0),
       st.lists(st.floats(-1, 1), min_size=3, max_size=3))
def test_eta_E_equals_numeric_3d_dissipation(nu_, zeta_, eta_, dH):
    dH = np.array(dH)
    two_psi, S, D = kv_dissipation_density_numeric(dH, zeta_, eta_, nu_)
    f = formulas()
    eta_E = float(f["eta_E"].subs({zeta: zeta_, eta: eta_, nu: nu_}))
    predicted = eta_E * dH[2] ** 2 + eta_ * (dH[0] ** 2 + dH[1] ** 2)
    assert np.isclose(two_psi, predicted, rtol=1e-10, atol=1e-12)
    # what the resultants see: only the S_i3 column pairs with the rates
    seen = 2 * (S[0, 2] * D[0, 2] + S[1, 2] * D[1, 2]) + S[2, 2] * D[2, 2]
    eta_E_naive = float(f["eta_E_naive"].subs({zeta: zeta_, eta: eta_, nu: nu_}))
    assert np.isclose(seen, eta_E_naive * dH[2] ** 2 + eta_ * (dH[0] ** 2 + dH[1] ** 2),
                      rtol=1e-10, atol=1e-12)
    missed = float(f["in_plane_dissipation"].subs({zeta: zeta_, eta: eta_, nu: nu_}))
    assert np.isclose(two_psi - seen, missed * dH[2] ** 2, rtol=1e-9, atol=1e-12)


@settings(max_examples=60, deadline=None)
@given(st.floats(0.01, 0.5), st.floats(0.0, 1.0), st.floats(0.001, 1.0))
def test_naive_too_small_iff_tau_B_below_tau_S(nu_, tB, tS):
    f = formulas()
    vals = {nu: nu_, tau_B: tB, tau_S: tS}
    diff = float((f["tau_E"] - f["tau_E_naive"]).subs(vals))
    assert np.isclose(diff, 2 * nu_ / 3 * (tS - tB), rtol=1e-12, atol=1e-15)
    if tB < tS:
        assert diff > 0


def test_trouton_and_special_cases():
    f = formulas()
    assert sp.simplify(f["eta_E"].subs(nu, sp.Rational(1, 2)) - 3 * eta) == 0
    assert sp.simplify(f["eta_E_naive"].subs(nu, sp.Rational(1, 2)) - 2 * eta) == 0
    assert sp.simplify(f["eta_E"].subs(nu, 0) - f["eta_E_naive"].subs(nu, 0)) == 0
    assert sp.simplify(f["tau_E"].subs(tau_B, tau_S) - tau_S) == 0
    assert sp.simplify(f["tau_E_naive"].subs(tau_B, tau_S) - tau_S) == 0


def test_footnote14_elastic_analogue_is_E():
    analogue = step("dissipation").results["elastic_analogue_footnote14"]
    assert analogue == sp.Symbol("E", positive=True)


def test_damping_is_stiffness_times_retardation_times():
    r = step("dissipation").results
    expected = sp.diag(tau_S, tau_S, r["tau_E"])
    assert all(sp.simplify(a - b) == 0 for a, b in zip(r["tau_matrix_F"], expected, strict=True))


def test_moment_rules_agree_with_explicit_integration():
    r = step("cross_sections").results
    keys = [k for k in r if k.endswith("_explicit_minus_rules")]
    assert len(keys) == 6                    # energy, dissipation x rectangle, ellipse, tube
    assert all(r[k] == 0 for k in keys)


def test_square_torsion_constant_against_reference_table():
    """J_T of a square = 0.1406 a^4 (Timoshenko & Goodier's table value beta = 0.141)."""
    from references.beams import rectangle_torsion_constant

    r = step("cross_sections").results
    b, d, m = sp.symbols("b d", positive=True) + (sp.Symbol("m", nonnegative=True, integer=True),)
    expr = r["rectangle_J_T"].subs({b: 1, d: 1})
    value = float(sp.N(expr.replace(sp.Sum, lambda f, lim: sp.Sum(f, (lim[0], 0, 200)).doit())))
    assert abs(value - 0.140577) < 2e-6
    assert abs(value - rectangle_torsion_constant(1.0, 1.0)) < 1e-9


def test_ellipse_kappa3_below_one_and_circle_one():
    r = step("cross_sections").results
    a, b = sp.symbols("a b", positive=True)
    k = sp.lambdify((a, b), r["ellipse_kappa_3"])
    assert abs(k(1.0, 1.0) - 1) < 1e-15
    assert k(1.0, 2.0) < 1 and k(3.0, 1.0) < 1


def test_tube_torsion_is_multiply_connected_and_warp_free():
    """Annulus: psi constant but non-zero on the hole, single-valued (zero) warping,
    J_T = I3 = pi/2 (r_o^4 - r_i^4); the simply connected recipes fail."""
    r = step("cross_sections").results
    r_o, r_i = sp.symbols("r_o r_i", positive=True)
    assert sp.simplify(r["tube_psi_inner"] - (r_o**2 - r_i**2) / 2) == 0
    assert r["tube_warping_gradient"] == sp.zeros(2, 1)
    assert sp.simplify(r["tube_J_T"] - r["tube_I3"]) == 0 and r["tube_kappa_3"] == 1
    # 2 <psi> alone misses 2 psi_i A_hole; psi = 0 on both circles makes w multivalued
    assert sp.simplify(r["tube_J_T"] - r["tube_two_psi_only"]
                       - 2 * r["tube_psi_inner"] * sp.pi * r_i**2) == 0
    vals = {r_o: 2, r_i: 1}
    assert float(r["tube_psi_zero_both_warping_circulation"].subs(vals)) != 0


def test_cowper_tube_limits_and_monotone():
    """Cowper's hollow circle: solid circle at m = 0, thin-walled tube at m -> 1, and the
    factor falls monotonically with m in between (nu = 0.3)."""
    r = step("cross_sections").results
    m = sp.Symbol("m", nonnegative=True)
    k = sp.lambdify(m, r["cowper_tube"].subs(nu, sp.Rational(3, 10)))
    ms = np.linspace(0, 1, 101)
    vals = np.array([k(x) for x in ms])
    assert np.isclose(vals[0], 6 * 1.3 / (7 + 1.8)) and np.isclose(vals[-1], 2 * 1.3 / 4.9)
    assert np.all(np.diff(vals) < 0)


def test_maxwell_limit():
    r = step("maxwell_limit").results
    assert r["error_order_omega"] == 2


def test_biot_closed_form_eigenpairs_numerically():
    """Appendix A1: lambda_k^2, N1, N2 (Jacobi angle) and N3 diagonalise C = I + 2E exactly;
    U = sum lambda_k N_k (x) N_k is the polar stretch of F = I + H (x) e3 / J0."""
    rng = np.random.default_rng(7)
    for _ in range(20):
        H = rng.normal(scale=0.3, size=3)
        J0 = 1 + rng.uniform(-0.2, 0.2)
        Ht = H / J0
        e3 = np.array([0.0, 0.0, 1.0])
        F = np.eye(3) + np.outer(H, e3) / J0
        C = F.T @ F
        q = Ht[2] + 0.5 * Ht @ Ht
        p = np.hypot(Ht[0], Ht[1])
        lam2 = [1 + q + np.sqrt(q**2 + p**2), 1 + q - np.sqrt(q**2 + p**2), 1.0]
        # Jacobi angle: p cos(2 th) + q sin(2 th) = 0, and the in-plane unit vector
        th = 0.5 * np.arctan2(-p, q)
        m = np.array([Ht[0], Ht[1], 0.0]) / p
        N1 = np.cos(th) * m + np.sin(th) * e3
        N2 = -np.sin(th) * m + np.cos(th) * e3
        N3 = np.cross(H, e3) / np.hypot(H[0], H[1])
        pairs = [(lam2[0], N1), (lam2[1], N2), (lam2[2], N3)]
        got = sorted((float(N @ C @ N), i) for i, (_, N) in enumerate(pairs))
        for _, N in pairs:
            assert np.allclose(C @ N, (N @ C @ N) * N, atol=1e-12)
        assert np.allclose(sorted(lam2), [g for g, _ in got], atol=1e-12)
        U = sum(np.sqrt(N @ C @ N) * np.outer(N, N) for _, N in pairs)
        w, V = np.linalg.eigh(C)
        assert np.allclose(U, V @ np.diag(np.sqrt(w)) @ V.T, atol=1e-12)
        R = F @ np.linalg.inv(U)
        assert np.allclose(R.T @ R, np.eye(3), atol=1e-12) and np.linalg.det(R) > 0
