"""Generalized Maxwell steps: rod Prony series, real interlacing zeros, limits, tau_E."""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

from derive import formulas, step
from derive.steps.maxwell_rod import maxwell_moduli
from derive.symbols import G_inf, K_inf, omega, s_lap, tau_B, tau_S

s = s_lap


def rod_E_of_s(M: int, values: dict) -> sp.Expr:
    """E(s) of M explicit branches from the step's E(K, G) (a rational function of s)."""
    f = formulas()
    K, G = maxwell_moduli(M)
    E = f["E_of_KG"].subs({sp.Symbol("K", positive=True): K, sp.Symbol("G", positive=True): G},
                          simultaneous=True)
    return sp.cancel(sp.together(E.subs(values)))


def random_branches(M: int, seed: int) -> dict:
    """Rational moduli in [0.1, 5] and times spread over four decades."""
    rng = np.random.default_rng(seed)
    vals = {K_inf: sp.Rational(int(rng.integers(1, 50)), 10),
            G_inf: sp.Rational(int(rng.integers(1, 50)), 10)}
    taus = sorted({int(rng.integers(1, 10_000)) for _ in range(M)})
    while len(taus) < M:                                    # distinct times
        taus = sorted(set(taus) | {int(rng.integers(1, 10_000))})
    for j in range(1, M + 1):
        vals[sp.Symbol(f"K_{j}", positive=True)] = sp.Rational(int(rng.integers(1, 50)), 10)
        vals[sp.Symbol(f"G_{j}", positive=True)] = sp.Rational(int(rng.integers(1, 50)), 10)
        vals[sp.Symbol(f"tau_{j}", positive=True)] = sp.Rational(taus[j - 1], 1000)
    return vals


def prony_by_residues(E: sp.Expr, digits: int = 40) -> tuple[sp.Float, list, list]:
    """(E(0), E_k, theta_k) from the poles of E (mpmath roots at ``digits``) and residues."""
    num, den = sp.fraction(E)
    poles = sp.Poly(den, s).nroots(n=digits, maxsteps=200)
    dden = sp.diff(den, s)
    E_k, theta = [], []
    for p in poles:
        assert abs(sp.im(p)) < 1e-30, "a complex pole"
        p = sp.re(p)
        res = num.subs(s, p) / dden.subs(s, p)
        E_k.append(sp.N(res / p, digits))
        theta.append(sp.N(-1 / p, digits))
    return E.subs(s, 0), E_k, theta


@pytest.mark.parametrize("M", [1, 2, 3, 4])
def test_zeros_real_negative_interlacing_and_moduli_positive(M):
    """The poles of E(s) are the branch poles plus one zero of 3K + G in each gap: real,
    negative, interlacing; every Prony modulus is positive; the Prony sum is E(s)."""
    for seed in range(3):
        vals = random_branches(M, seed)
        E = rod_E_of_s(M, vals)
        E0, E_k, theta = prony_by_residues(E)
        taus = sorted((float(vals[sp.Symbol(f"tau_{j}", positive=True)])
                       for j in range(1, M + 1)), reverse=True)
        th = sorted((float(t) for t in theta), reverse=True)
        assert len(th) == 2 * M and all(t > 0 for t in th) and all(e > 0 for e in E_k)
        # theta_1 > tau_(1) >= theta_2 > ...: the branch times themselves and one zero per gap
        zeros = [t for t in th if min(abs(t - u) for u in taus) > 1e-12 * t]
        assert len(zeros) == M
        assert zeros[0] > taus[0]
        for k in range(1, M):
            assert taus[k] < zeros[k] < taus[k - 1]
        for z in (sp.Rational(3, 10) + sp.I, 7 * sp.I, sp.Rational(5, 2)):
            prony = E0 + sum(e * z * t / (1 + z * t) for e, t in zip(E_k, theta, strict=True))
            assert abs(complex(sp.N(prony - E.subs(s, z), 30))) < 1e-20


def test_residue_formulas_against_partial_fractions_M3():
    """E_k at the branch poles is the branch Young's modulus; at the zeros of D it is
    -3 G(s_k)^2/(s_k D'(s_k)) (formula table), for a random M = 3 material."""
    f = formulas()
    vals = random_branches(3, 11)
    E = rod_E_of_s(3, vals)
    _, E_k, theta = prony_by_residues(E)
    K, G = (x.subs(vals) for x in maxwell_moduli(3))
    D = 3 * K + G
    branch = {}
    for j in range(1, 4):
        kj, gj, tj = (vals[sp.Symbol(f"{n}_{j}", positive=True)] for n in ("K", "G", "tau"))
        branch[float(tj)] = float(f["prony_E_branch"].subs(
            {sp.Symbol("K_j", positive=True): kj, sp.Symbol("G_j", positive=True): gj}))
    root_formula = f["prony_E_root"]
    names = {str(x): x for x in root_formula.free_symbols}
    for e, t in zip(E_k, theta, strict=True):
        t = float(t)
        hit = [b for b in branch if abs(b - t) < 1e-12 * t]
        if hit:
            assert np.isclose(float(e), branch[hit[0]], rtol=1e-12)
            continue
        sk = -1 / sp.Float(t, 40)
        value = root_formula.subs({names["s_k"]: sk, names["G_k"]: G.subs(s, sk),
                                   names["dD_k"]: sp.diff(D, s).subs(s, sk)})
        assert np.isclose(float(e), float(value), rtol=1e-10)


def test_secular_matrix_eigenvalues_are_the_zeros():
    """The zeros of D(s) are minus the eigenvalues of T = diag(1/tau) - z z^T/c_0 (M = 4)."""
    vals = random_branches(4, 5)
    K, G = (x.subs(vals) for x in maxwell_moduli(4))
    num = sp.numer(sp.together(3 * K + G))
    zeros = sorted(float(sp.re(r)) for r in sp.Poly(num, s).nroots(n=30))
    c_inf = float((3 * K_inf + G_inf).subs(vals))
    cs = [float(vals[sp.Symbol(f"K_{j}", positive=True)] * 3
                + vals[sp.Symbol(f"G_{j}", positive=True)]) for j in range(1, 5)]
    lam = [1 / float(vals[sp.Symbol(f"tau_{j}", positive=True)]) for j in range(1, 5)]
    z = np.sqrt(np.array(cs) * np.array(lam))
    T = np.diag(lam) - np.outer(z, z) / (c_inf + sum(cs))
    eig = np.linalg.eigvalsh(T)
    assert np.all(eig > 0)
    assert np.allclose(sorted(-eig), zeros, rtol=1e-8)


def test_instantaneous_and_equilibrium_limits():
    r = step("maxwell_rod").results
    E1 = r["M1_E_of_s"]
    G_1, K_1 = sp.symbols("G_1 K_1", positive=True)
    at_oo = sp.limit(E1, s, sp.oo)
    inst = r["E_instantaneous"].subs(sp.Symbol("M", integer=True, nonnegative=True), 1).doit()
    inst = inst.subs({sp.IndexedBase("G", positive=True)[1]: G_1,
                      sp.IndexedBase("K", positive=True)[1]: K_1})
    assert sp.simplify(at_oo - inst) == 0
    assert sp.simplify(E1.subs(s, 0) - r["E_inf"]) == 0
    assert sp.simplify(at_oo - 9 * (K_inf + K_1) * (G_inf + G_1)
                       / (3 * (K_inf + K_1) + G_inf + G_1)) == 0


def test_kelvin_voigt_limit_of_the_maxwell_material():
    r = step("maxwell_material").results
    eta_j, zeta_j = sp.symbols("eta_j zeta_j", positive=True)
    assert r["kv_limit_G_branch"] == eta_j * s and r["kv_limit_K_branch"] == zeta_j * s
    assert r["kv_limit_stress_minus_dissipation"] == sp.zeros(3, 3)
    # numerically: a stiff fast branch with G_j tau_j = eta is G + s eta at moderate s
    tau, eta = 1e-7, 2.0
    branch = sp.lambdify((sp.Symbol("G_j", positive=True), s, sp.Symbol("tau_j", positive=True)),
                         r["G_branch"])
    assert np.isclose(branch(eta / tau, 3.0 + 4.0j, tau), (3.0 + 4.0j) * eta, rtol=1e-5)


def test_tau_E_of_the_exact_uniaxial_modulus_is_the_papers():
    """kelvin_voigt_uniaxial: E(s) = E (1 + s tau_E) + O(s^2) with the dissipation step's
    tau_E; the remainder is zero iff tau_B = tau_S; its frequency form is O((omega tau)^2)."""
    r = step("kelvin_voigt_uniaxial").results
    assert sp.simplify(r["tau_E_exact"] - step("dissipation").results["tau_E"]) == 0
    assert r["remainder_equal_times"] == 0
    nu = sp.Symbol("nu", real=True)
    vals = {nu: sp.Rational(3, 10), tau_B: sp.Rational(1, 100), tau_S: sp.Rational(4, 100)}
    rel = r["relative_error_i_omega"].subs(vals).subs(sp.Symbol("tau_D", positive=True),
                                                      r["tau_D"].subs(vals))
    lo = [float(rel.subs(omega, w)) for w in (1e-3, 2e-3)]
    assert np.isclose(lo[1] / lo[0], 4.0, rtol=1e-5)               # second order in omega
    E = sp.Symbol("E", positive=True)
    exact = sp.lambdify(s, r["E_of_s"].subs(vals).subs(E, 1))
    tE = float(r["tau_E_exact"].subs(vals))
    w = 3.0
    assert np.isclose(abs(exact(1j * w) - (1 + 1j * w * tE)), float(rel.subs(omega, w)),
                      rtol=1e-12)


def test_maxwell_limit_shows_the_papers_error_bound():
    r = step("maxwell_limit")
    assert r.matches["error_bound"] and r.matches["error_integrand"]
    assert r.results["error_order_omega"] == 2
