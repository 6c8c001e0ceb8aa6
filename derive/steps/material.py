"""Isotropic linear elasticity: moduli, SVK energy (22), stress (23), and why a rigid
section fails for nu > 0; then uniform lateral contraction (24), (25)."""

from __future__ import annotations

import sympy as sp

from derive.step import Step, make_step
from derive.symbols import H3, I_3, E, Hvec, K, e3, lam, mu, nu, xi1, xi2

#: a generic (not necessarily symmetric) strain-like tensor for tensor identities
_Q = sp.Matrix(3, 3, lambda i, j: sp.Symbol(f"Q{i + 1}{j + 1}", real=True))
_Qsym = sp.Matrix(3, 3, lambda i, j: _Q[min(i, j), max(i, j)])


def ddot(A_: sp.Matrix, B_: sp.Matrix) -> sp.Expr:
    """Double contraction A : B = sum_ij A_ij B_ij."""
    return sum(A_[i, j] * B_[i, j] for i in range(3) for j in range(3))


def deviator(Q: sp.Matrix) -> sp.Matrix:
    """P : Q = Q - tr(Q)/3 I, the projection onto traceless tensors."""
    return Q - Q.trace() / 3 * I_3


def svk_energy(Q: sp.Matrix, lam_, mu_) -> sp.Expr:
    """Psi_SVK(Q) = lambda/2 tr(Q)^2 + mu Q:Q, the first form of (22)."""
    return lam_ / 2 * Q.trace() ** 2 + mu_ * ddot(Q, Q)


def tensor_gradient(psi: sp.Expr, Q: sp.Matrix) -> sp.Matrix:
    """d psi / dQ entrywise (Q a matrix of independent symbols)."""
    return Q.applyfunc(lambda q: sp.diff(psi, q))


def isotropic_moduli() -> Step:
    """E, nu from a uniaxial-stress test of S = lambda tr(E) I + 2 mu E; inverse relations."""
    e = sp.Symbol("e", positive=True)
    nu_ = sp.Symbol("nu_", real=True)
    strain = sp.diag(-nu_ * e, -nu_ * e, e)
    psi = svk_energy(_Q, lam, mu)
    S = tensor_gradient(psi, _Q).subs(dict(zip(_Q, strain, strict=True)))
    nu_of_lame = sp.solve(sp.Eq(S[0, 0], 0), nu_)[0]
    E_of_lame = sp.simplify((S[2, 2] / e).subs(nu_, nu_of_lame))
    sol = sp.solve([sp.Eq(E, E_of_lame), sp.Eq(nu, nu_of_lame)], [lam, mu], dict=True)[0]
    lam_E, mu_E = sp.factor(sol[lam]), sp.factor(sol[mu])
    K_E = sp.factor(lam_E + sp.Rational(2, 3) * mu_E)
    return make_step(
        name="isotropic_moduli",
        assumptions=("homogeneous isotropic linear elastic (SVK) material",
                     "uniaxial stress: S_11 = S_22 = 0 under lateral strain -nu e"),
        symbol_assumptions=("lambda, mu, E > 0", "-1 < nu < 1/2 for K finite"),
        results={
            "S_SVK": tensor_gradient(psi, _Q).subs(dict(zip(_Q, _Qsym, strict=True))),
            "nu": nu_of_lame, "E": E_of_lame,
            "lambda": lam_E, "mu": mu_E, "G": mu_E, "K": K_E,
            "lambda_plus_2mu": sp.factor(lam_E + 2 * mu_E),
            "lambda_1m2nu": sp.factor(lam_E * (1 - 2 * nu)),
        },
        stated={
            "S_SVK": lam * _Qsym.trace() * I_3 + 2 * mu * _Qsym,
            "nu": lam / (2 * (lam + mu)),
            "G": E / (2 * (1 + nu)),
            "lambda": 2 * (E / (2 * (1 + nu))) * nu / (1 - 2 * nu),
            "lambda_plus_2mu": 2 * (E / (2 * (1 + nu))) * (1 - nu) / (1 - 2 * nu),
            "K": E / (3 * (1 - 2 * nu)),
            "lambda_1m2nu": nu / (1 + nu) * E,
        },
    )


def svk_material(moduli: Step, green_lagrange: Step) -> Step:
    """(22) energy identity, (23) stress, and the rigid-section stresses S ~ H_SVK : E."""
    psi_lame = svk_energy(_Qsym, lam, mu)
    psi_bulk = K / 2 * _Qsym.trace() ** 2 + mu * ddot(deviator(_Qsym), deviator(_Qsym))
    identity = sp.expand(psi_lame - psi_bulk.subs(K, lam + sp.Rational(2, 3) * mu))
    S_bulk = K * _Qsym.trace() * I_3 + 2 * mu * deviator(_Qsym)
    E_small = green_lagrange.results["E_small"]
    S_rigid = (lam * E_small.trace() * I_3 + 2 * mu * E_small).applyfunc(sp.expand)
    S11_of_nu = sp.factor(S_rigid[0, 0].subs({lam: moduli.results["lambda"],
                                              mu: moduli.results["mu"]}))
    return make_step(
        name="svk_material",
        assumptions=("Psi_e(0) = 0, no initial stress; quadratic in E (small strain)",
                     "push-forward with F ~ R_rel (21)",
                     "rigid cross section (no lateral contraction) for S_rigid"),
        symbol_assumptions=("K = lambda + 2 mu / 3",),
        inputs=("isotropic_moduli", "green_lagrange"),
        results={
            "energy_identity_residual": identity,
            "S_bulk_form": (S_bulk.subs(K, lam + sp.Rational(2, 3) * mu)).applyfunc(sp.expand),
            "S_rigid": S_rigid,
            "S_alpha_alpha_rigid_of_nu": S11_of_nu,
            "S_alpha_alpha_rigid_limit_nu_half": sp.limit(S11_of_nu, nu, sp.Rational(1, 2), "-"),
        },
        stated={
            "energy_identity_residual": sp.Integer(0),
            "S_bulk_form": moduli.results["S_SVK"],
            "S_rigid": lam * H3 * I_3 + mu * (Hvec * e3.T + e3 * Hvec.T),
        },
        notes=("S_11 = S_22 = lambda H_3 grows without bound as nu -> 1/2: a rigid section "
               "is strictly consistent only with nu = 0, which motivates (24).",),
    )


def lateral_contraction(moduli: Step, green_lagrange: Step) -> Step:
    """(24) uniform lateral contraction, its in-plane warping field, and the stress (25)."""
    E_small = green_lagrange.results["E_small"]
    E33 = E_small[2, 2]
    E_ulc = (E_small - nu * E33 * (I_3 - e3 * e3.T)).applyfunc(sp.expand)
    lam_E, mu_E = moduli.results["lambda"], moduli.results["mu"]
    S_ulc = (lam_E * E_ulc.trace() * I_3 + 2 * mu_E * E_ulc).applyfunc(sp.factor)
    # an in-plane warping w_a(xi) realising (24) at leading order: d_a w_a = -nu H3,
    # d_1 w_2 + d_2 w_1 = 0, with H3 linear in xi (17); quadratic polynomial ansatz
    c = sp.symbols("c0:12")
    h0, h1, h2 = sp.symbols("h0 h1 h2", real=True)      # H3 = h0 + h1 xi1 + h2 xi2
    mons = [1, xi1, xi2, xi1**2, xi1 * xi2, xi2**2]
    w1 = sum(ci * m for ci, m in zip(c[:6], mons, strict=True))
    w2 = sum(ci * m for ci, m in zip(c[6:], mons, strict=True))
    H3_lin = h0 + h1 * xi1 + h2 * xi2
    eqs = [sp.diff(w1, xi1) + nu * H3_lin, sp.diff(w2, xi2) + nu * H3_lin,
           sp.diff(w2, xi1) + sp.diff(w1, xi2)]
    conds = [co for eq in eqs for co in sp.Poly(sp.expand(eq), xi1, xi2).coeffs()]
    conds += [w1.subs({xi1: 0, xi2: 0}), w2.subs({xi1: 0, xi2: 0})]   # no rigid translation
    conds += [sp.diff(w2, xi1).subs({xi1: 0, xi2: 0}) - sp.diff(w1, xi2).subs({xi1: 0, xi2: 0})]
    sol = sp.solve(conds, c, dict=True)[0]
    w = sp.Matrix([w1, w2]).subs(sol).applyfunc(sp.factor)
    return make_step(
        name="lateral_contraction",
        assumptions=("in-plane stresses S_ab vanish (rod asymptotics: Love, Berdichevsky)",
                     "E_aa = -nu E_33 (no sum), E_12 = 0, with E_33 ~ H_3"),
        symbol_assumptions=("-1 < nu < 1/2",),
        inputs=("isotropic_moduli", "green_lagrange"),
        results={
            "E_prime": E_ulc,
            "tr_E_prime": sp.factor(E_ulc.trace()),
            "S_prime": S_ulc,
            "warping_w": w,
        },
        stated={
            "tr_E_prime": (1 - 2 * nu) * H3,
            "S_prime": nu / (1 + nu) * E * H3 * e3 * e3.T
                       + E / (2 * (1 + nu)) * (Hvec * e3.T + e3 * Hvec.T),
        },
        notes=(
            "The stated (25) is nu/(1+nu) E H3 a3(x)a3 + G (H(x)a3 + a3(x)H); its 33 entry "
            "is E H3 (G = E/(2(1+nu))): S'_ab = 0, S'_a3 = G H_a, S'_33 = E H_3.",
            "warping_w: a quadratic in-plane warping field satisfying the ULC conditions "
            "(Love's anticlastic field), so (24) is kinematically realisable.",
        ),
    )
