"""Appendix A1: Biot strain; closed-form eigenpairs of C = I + 2E for the rod kinematics (18),
and of C' = I + 2E' with lateral contraction (footnote 19)."""

from __future__ import annotations

import sympy as sp

from derive.step import Step, make_step
from derive.symbols import H1, H2, H3, I_3, J0, Hvec, e3, nu

_x = sp.Symbol("x")   # eigenvalue variable (lambda^2)


def biot_strain(green_lagrange: Step, lateral_contraction: Step) -> Step:
    """Eigenvalues lambda_k^2 of C, the eigenvector N3, and the Biot approximation."""
    E_exact = green_lagrange.results["E_exact"]
    C = (I_3 + 2 * E_exact).applyfunc(sp.expand)
    Ht = Hvec / J0
    q = Ht[2] + (Ht.T * Ht)[0, 0] / 2
    p2 = Ht[0] ** 2 + Ht[1] ** 2
    N3 = Hvec.cross(e3) / sp.sqrt(H1**2 + H2**2)
    N3_residual = (C * N3 - N3).applyfunc(sp.simplify)
    charpoly = sp.factor(sp.expand((C - _x * I_3).det()))
    lam2 = [1 + q + s * sp.sqrt(q**2 + p2) for s in (1, -1)]
    roots_residual = [sp.simplify(sp.expand(charpoly.subs(_x, lv))) for lv in lam2]
    # Biot approximation U ~ I + (H (x) e3 + e3 (x) H)/(2 J0): U^2 - C = O(|H|^2)
    Bmat = (Hvec * e3.T + e3 * Hvec.T) / (2 * J0)
    eps = sp.Symbol("epsilon")
    err = ((I_3 + Bmat) ** 2 - C).subs({H1: eps * H1, H2: eps * H2, H3: eps * H3},
                                        simultaneous=True).applyfunc(sp.expand)
    err_order = min(sp.Poly(c, eps).monoms()[-1][0] for c in err if c != 0)
    # footnote 19: C' = I + 2E' with E' = E - nu E33 (I - e3 e3), E33 exact
    E33 = E_exact[2, 2]
    Cp = (C - 2 * nu * E33 * (I_3 - e3 * e3.T)).applyfunc(sp.expand)
    charpoly_p = sp.expand((Cp - _x * I_3).det())
    lam2_p = [1 + (1 - nu) * q + s * sp.sqrt((1 + nu) ** 2 * q**2 + p2) for s in (1, -1)]
    roots_p = [sp.simplify(sp.expand(charpoly_p.subs(_x, lv))) for lv in lam2_p]
    N3_p = sp.simplify(sp.expand(charpoly_p.subs(_x, 1 - 2 * nu * q)))
    return make_step(
        name="biot_strain",
        assumptions=("exact Green-Lagrange strain (18); H_1^2 + H_2^2 > 0 for N3",),
        symbol_assumptions=("J_0 > 0",),
        inputs=("green_lagrange", "lateral_contraction"),
        results={
            "C": C,
            "C_N3_minus_N3": N3_residual,
            "charpoly_C": charpoly,
            "lambda2_roots_residual": sp.Matrix(roots_residual),
            "biot_square_error_order": sp.Integer(err_order),
            "charpoly_C_prime_at_roots": sp.Matrix(roots_p),
            "charpoly_C_prime_at_N3_value": N3_p,
        },
        stated={
            "C_N3_minus_N3": sp.zeros(3, 1),
            "lambda2_roots_residual": sp.zeros(2, 1),
            "biot_square_error_order": sp.Integer(2),
            "charpoly_C_prime_at_roots": sp.zeros(2, 1),
            "charpoly_C_prime_at_N3_value": sp.Integer(0),
        },
        notes=("lambda_{1,2}^2 - 1 = q +- sqrt(q^2 + H~1^2 + H~2^2), q = H~3 + |H~|^2/2, "
               "H~ = H/J0; N3 = H x a0^(3)/|H_a| has lambda_3^2 = 1.",
               "With lateral contraction the eigenvalues are 1 - 2 nu q (N3) and "
               "1 + (1-nu) q +- sqrt((1+nu)^2 q^2 + H~1^2 + H~2^2).",
               "The Biot approximation U ~ I + (H (x) a3 + a3 (x) H)/(2 J0) squares to C up to "
               "O(|H|^2), so E_B ~ E to first order (19)."),
    )
