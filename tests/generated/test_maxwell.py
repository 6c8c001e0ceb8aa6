"""generated/constitutive.py's generalized Maxwell functions against SymPy evaluation."""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

from derive import formulas
from derive.steps.maxwell_rod import maxwell_moduli
from derive.symbols import G_inf, K_inf, s_lap
from generated import constitutive as gc

f = formulas()
s = s_lap


def random_material(M: int, seed: int, decades: float = 4.0):
    """Floats (G_inf, K_inf, G_j, K_j, tau_j) with moduli in [0.1, 5] Pa and distinct times
    spread over ``decades`` decades."""
    rng = np.random.default_rng(seed)
    tau = np.sort(10 ** rng.uniform(-decades / 2, decades / 2, M))
    return (float(rng.uniform(0.1, 5)), float(rng.uniform(0.1, 5)), rng.uniform(0.1, 5, M),
            rng.uniform(0.1, 5, M), tau)


def sympy_moduli(G0, K0, G, K, tau):
    """(G(s), K(s), E(s)) as SymPy rational functions of s with exact (rational) inputs."""
    M = len(tau)
    q = sp.nsimplify
    Ks, Gs = maxwell_moduli(M, [q(x) for x in K], [q(x) for x in G], [q(x) for x in tau])
    vals = {K_inf: q(K0), G_inf: q(G0)}
    Ks, Gs = Ks.subs(vals), Gs.subs(vals)
    E = f["E_of_KG"].subs({sp.Symbol("K", positive=True): Ks,
                           sp.Symbol("G", positive=True): Gs}, simultaneous=True)
    return Gs, Ks, sp.cancel(sp.together(E))


@pytest.mark.parametrize("M", [0, 1, 2, 3])
def test_moduli_laplace_match_sympy(M):
    for seed in range(3):
        mat = random_material(M, seed)
        Gs, Ks, Es = sympy_moduli(*mat)
        pts = np.array([0.3 + 1.0j, -0.02 + 5.0j, 2.5, 1e-3j, 40.0 - 1.0j])
        G, K, E = gc.maxwell_moduli_laplace(pts, *mat)
        assert G.shape == K.shape == E.shape == pts.shape
        for i, z in enumerate(pts):
            zz = sp.nsimplify(z.real) + sp.I * sp.nsimplify(z.imag)
            for got, ref in ((G[i], Gs), (K[i], Ks), (E[i], Es)):
                assert np.isclose(got, complex(sp.N(ref.subs(s, zz), 30)), rtol=1e-12, atol=0)


def sympy_prony(G0, K0, G, K, tau, digits=40):
    """(E_inf, E_k, theta_k) from SymPy: poles of E(s) by mpmath roots, residues exactly."""
    _, _, E = sympy_moduli(G0, K0, G, K, tau)
    num, den = sp.fraction(E)
    if not den.has(s):
        return float(E), np.empty(0), np.empty(0)
    dden = sp.diff(den, s)
    E_k, theta = [], []
    for p in sp.Poly(den, s).nroots(n=digits, maxsteps=300):
        p = sp.re(p)
        E_k.append(float(num.subs(s, p) / dden.subs(s, p) / p))
        theta.append(float(-1 / p))
    order = np.argsort(theta)
    return float(E.subs(s, 0)), np.array(E_k)[order], np.array(theta)[order]


@pytest.mark.parametrize("M", [0, 1, 2, 3])
def test_rod_prony_matches_sympy_partial_fractions(M):
    for seed in range(3):
        mat = random_material(M, 10 + seed)
        E_inf, E_k, theta = sympy_prony(*mat)
        r = gc.maxwell_rod_prony(*mat)
        assert np.isclose(r["E_inf"], E_inf, rtol=1e-13)
        got_E, got_theta = r["extension"]
        assert len(got_theta) == 2 * M
        assert np.allclose(got_theta, theta, rtol=1e-11, atol=0)
        assert np.allclose(got_E, E_k, rtol=1e-9, atol=1e-14 * np.sum(E_k))
        assert np.all(got_E > 0) and np.all(got_theta > 0)
        assert np.all(np.diff(got_theta) > 0)                          # sorted by time
        G_j, tau_j = r["shear"]
        assert np.array_equal(tau_j, np.sort(mat[4])) and np.allclose(G_j, mat[2][np.argsort(mat[4])])


@pytest.mark.parametrize("M", [1, 2, 3, 5])
def test_prony_sum_is_E_and_limits(M):
    """E_inf + sum E_k s theta/(1 + s theta) = E(s); s -> oo gives the instantaneous modulus
    9 K0 G0/(3 K0 + G0) with K0 = K_inf + sum K_j; the zeros interlace the branch times."""
    mat = random_material(M, 3 * M, decades=8.0)
    G0, K0, G, K, tau = mat
    r = gc.maxwell_rod_prony(*mat)
    E_k, theta = r["extension"]
    pts = np.array([1e-6j, 0.1 + 0.3j, 7.0, 3e4j, -1e-5 + 2.0j])
    _, _, E = gc.maxwell_moduli_laplace(pts, *mat)
    prony = r["E_inf"] + np.sum(E_k * pts[:, None] * theta / (1 + pts[:, None] * theta), axis=1)
    assert np.allclose(prony, E, rtol=1e-12)
    Ki, Gi = K0 + K.sum(), G0 + G.sum()
    assert np.isclose(r["E_inf"] + E_k.sum(), 9 * Ki * Gi / (3 * Ki + Gi), rtol=1e-13)
    zeros = np.array([t for t in theta if np.min(np.abs(t - tau)) > 1e-12 * t])
    assert len(zeros) == M
    both = np.sort(np.concatenate((tau, zeros)))
    assert np.array_equal(both[0::2], np.sort(tau)) and np.array_equal(both[1::2], np.sort(zeros))


def test_prony_wide_spread_of_times_against_high_precision():
    """Times over 12 decades: every term to 1e-9 relative against 40-digit SymPy roots."""
    mat = (1.0, 2.0, np.array([1.0, 0.5, 3.0, 1.0]), np.array([2.0, 1.0, 5.0, 0.5]),
           np.array([1e-8, 1e-3, 1.0, 1e4]))
    E_inf, E_k, theta = sympy_prony(*mat)
    r = gc.maxwell_rod_prony(*mat)
    assert np.allclose(r["extension"][1], theta, rtol=1e-12, atol=0)
    assert np.allclose(r["extension"][0], E_k, rtol=1e-9, atol=0)


def test_prony_special_cases():
    # no branches: a purely elastic rod
    r = gc.maxwell_rod_prony(1.0, 2.0, [], [], [])
    assert r["E_inf"] == pytest.approx(9 * 2 / 7) and r["extension"][0].size == 0
    assert r["shear"][0].dtype == float and r["shear"][0].size == 0
    # equal times merge into one branch (moduli add)
    a = gc.maxwell_rod_prony(1.0, 2.0, [1.0, 0.5, 2.0], [2.0, 1.0, 1.0], [0.1, 0.1, 3.0])
    b = gc.maxwell_rod_prony(1.0, 2.0, [1.5, 2.0], [3.0, 1.0], [0.1, 3.0])
    for key in ("extension", "shear"):
        assert all(np.allclose(x, y, rtol=1e-14) for x, y in zip(a[key], b[key], strict=True))
    # the branch shares the equilibrium Poisson ratio: E(s) ~ G(s), the zero's term vanishes
    c = gc.maxwell_rod_prony(1.0, 2.0, [3.0], [6.0], [0.5])
    assert c["extension"][0].size == 1 and np.isclose(c["extension"][1][0], 0.5)
    # no equilibrium part (a Maxwell fluid): E_inf = 0, the zero at s = 0 cancels
    d = gc.maxwell_rod_prony(0.0, 0.0, [1.0, 2.0], [1.0, 3.0], [1.0, 0.1])
    assert d["E_inf"] == 0.0 and len(d["extension"][0]) == 3
    _, _, E = gc.maxwell_moduli_laplace(0.7j, 0.0, 0.0, [1.0, 2.0], [1.0, 3.0], [1.0, 0.1])
    Ek, th = d["extension"]
    assert np.isclose(np.sum(Ek * 0.7j * th / (1 + 0.7j * th)), E, rtol=1e-12)
    # a pure bulk branch (G_j = 0) relaxes the extension but not the shear
    e = gc.maxwell_rod_prony(1.0, 2.0, [0.0], [4.0], [0.2])
    assert e["shear"][0].size == 0 and e["extension"][0].size == 1


def test_kelvin_voigt_limit_numerically():
    """Stiff fast branches with G_j tau_j = eta, K_j tau_j = zeta: G(s) -> G + s eta,
    K(s) -> K + s zeta at moderate s."""
    eta, zeta, tau = 0.3, 0.8, 1e-9
    z = np.array([0.5 + 2.0j, 10.0j])
    G, K, _ = gc.maxwell_moduli_laplace(z, 1.0, 2.0, [eta / tau], [zeta / tau], [tau])
    assert np.allclose(G, 1.0 + z * eta, rtol=1e-7) and np.allclose(K, 2.0 + z * zeta, rtol=1e-7)


def test_branch_moduli_from_young():
    G, K = gc.maxwell_branch_moduli(np.array([1e6, 2e6]), 0.3)
    assert np.allclose(G, gc.shear_modulus(np.array([1e6, 2e6]), 0.3), rtol=1e-15)
    assert np.allclose(K, gc.bulk_modulus(np.array([1e6, 2e6]), 0.3), rtol=1e-15)
    assert np.allclose(9 * K * G / (3 * K + G), [1e6, 2e6], rtol=1e-14)   # E(K, G) = E
    G0, K0 = gc.maxwell_branch_moduli(0.0, 0.2)
    assert G0 == 0.0 and K0 == 0.0


@pytest.mark.parametrize(("call", "match"), [
    (lambda: gc.maxwell_rod_prony(1.0, 2.0, [-1.0], [1.0], [1.0]), r"'G_j' = -1.0 .*\[0, inf\) Pa"),
    (lambda: gc.maxwell_rod_prony(1.0, 2.0, [1.0], [1.0], [0.0]), r"'tau_j' = 0.0 .*\(0, inf\) s"),
    (lambda: gc.maxwell_rod_prony(1.0, 2.0, [1.0], [np.nan], [1.0]), "'K_j' = nan"),
    (lambda: gc.maxwell_rod_prony(-1.0, 2.0, [1.0], [1.0], [1.0]), "'G_inf' = -1.0"),
    (lambda: gc.maxwell_rod_prony(1.0, np.inf, [1.0], [1.0], [1.0]), "'K_inf' = inf"),
    (lambda: gc.maxwell_rod_prony([1.0], 2.0, [1.0], [1.0], [1.0]), "'G_inf' .* a scalar"),
    (lambda: gc.maxwell_rod_prony(1.0, 2.0, [1.0, 2.0], [1.0], [1.0, 2.0]),
     r"'K_j' has 1 entries.*\(2, like 'G_j'\)"),
    (lambda: gc.maxwell_moduli_laplace(1j, 1.0, 2.0, [[1.0]], [[1.0]], [[1.0]]),
     "'G_j' has shape"),
    (lambda: gc.maxwell_branch_moduli(1e6, 0.5), r"'nu_j' = 0.5 .*\(-1, 0.5\)"),
    (lambda: gc.maxwell_branch_moduli(-1e6, 0.3), "'E_j' = -1000000.0"),
])
def test_bad_maxwell_parameters(call, match):
    with pytest.raises(gc.ParameterError, match=match):
        call()
