"""Cross-section integrals <f>_A by the moment rules of Sect. 3.1.

For a section with centroid at the origin and principal axes along the directors,
<1> = A, <xi_a> = 0, <xi_1 xi_2> = 0, <xi_2^2> = I1, <xi_1^2> = I2 (and I3 = I1 + I2).
Densities in this derivation are polynomials of degree <= 2 in (xi_1, xi_2); a higher
monomial has no moment rule and raises, so nothing is integrated silently wrong.
"""

from __future__ import annotations

import sympy as sp

from derive.symbols import I1, I2, A, xi1, xi2

#: monomial exponents (a, b) of xi1^a xi2^b -> their cross-section integral
MOMENT_RULES = {(0, 0): A, (1, 0): 0, (0, 1): 0, (1, 1): 0, (2, 0): I2, (0, 2): I1}


def section_integral(expr: sp.Expr) -> sp.Expr:
    """<expr>_A for a polynomial in xi1, xi2 of degree <= 2, by the moment rules."""
    poly = sp.Poly(sp.expand(expr), xi1, xi2)
    total = sp.Integer(0)
    for (a, b), coeff in poly.terms():
        if (a, b) not in MOMENT_RULES:
            raise ValueError(f"no moment rule for xi1^{a} xi2^{b} (degree > 2)")
        total += coeff * MOMENT_RULES[(a, b)]
    return sp.expand(total)


def quadratic_form_matrix(expr: sp.Expr, variables: list[sp.Symbol]) -> sp.Matrix:
    """Symmetric matrix Q with expr = x^T Q x for a quadratic form in ``variables``.

    Raises when expr has terms that are not quadratic in the variables, so a form with
    linear or constant parts is never mistaken for a quadratic one.
    """
    Q = sp.hessian(expr, variables) / 2
    x = sp.Matrix(variables)
    rest = sp.cancel(sp.expand(expr - (x.T * Q * x)[0, 0]))
    if rest != 0:
        raise ValueError(f"not a quadratic form in {variables}: remainder {rest}")
    return Q.applyfunc(sp.factor)
