"""Cross sections: rectangle, ellipse, circle (Sect. 3.1, footnote 1).

Area and moments by explicit integration over each shape; torsion constants J_T from
Prandtl's stress function (Saint-Venant torsion: Laplace psi = -2 in A, psi = 0 on the
boundary, J_T = 2 <psi>); kappa_3 = J_T / I3. The cross-section integrals of the stored
energy and dissipation densities are integrated explicitly over each shape and shown equal
to the moment-rule results of steps stored_energy and dissipation.

Transverse shear correction factors are *cited* from Cowper (1966), not derived (the paper
cites them too); the step only checks their consistency (ellipse -> circle).
"""

from __future__ import annotations

import sympy as sp

from derive.moments import section_integral
from derive.step import Step, make_step
from derive.steps.energy import substitute_H
from derive.symbols import I1, I2, I3, A, nu, xi1, xi2

b, d = sp.symbols("b d", positive=True)          # rectangle: width b along xi1, height d along xi2
a_e, b_e = sp.symbols("a b", positive=True)       # ellipse: half axis a along xi2, b along xi1
r = sp.Symbol("r", positive=True)
n = sp.Symbol("n", positive=True, integer=True)
m = sp.Symbol("m", nonnegative=True, integer=True)
_rho, _th = sp.symbols("varrho theta", nonnegative=True)

MONOMIALS = {"A": sp.Integer(1), "S1": xi1, "S2": xi2, "I12": xi1 * xi2, "I2": xi1**2,
             "I1": xi2**2}


def integrate_rectangle(f: sp.Expr) -> sp.Expr:
    """Integral of f over |xi1| <= b/2, |xi2| <= d/2."""
    return sp.factor(sp.integrate(f, (xi1, -b / 2, b / 2), (xi2, -d / 2, d / 2)))


def integrate_ellipse(f: sp.Expr, a=a_e, bb=b_e) -> sp.Expr:
    """Integral of f over xi1^2/b^2 + xi2^2/a^2 <= 1 (elliptic polar coordinates)."""
    g = f.subs({xi1: bb * _rho * sp.cos(_th), xi2: a * _rho * sp.sin(_th)}, simultaneous=True)
    return sp.factor(sp.integrate(sp.expand(g * a * bb * _rho), (_rho, 0, 1), (_th, 0, 2 * sp.pi)))


def laplacian(f: sp.Expr) -> sp.Expr:
    return sp.diff(f, xi1, 2) + sp.diff(f, xi2, 2)


def rectangle_torsion() -> dict[str, sp.Expr]:
    """Saint-Venant series for the rectangle, term by term (n odd, thickness d along xi2)."""
    c_n = 8 * d**2 * sp.Symbol("sgn") / (n**3 * sp.pi**3)      # sgn = (-1)^((n-1)/2)
    psi_n = c_n * (1 - sp.cosh(n * sp.pi * xi1 / d) / sp.cosh(n * sp.pi * b / (2 * d))) \
        * sp.cos(n * sp.pi * xi2 / d)
    lap_n = sp.simplify(laplacian(psi_n))
    # the constant 2 on (-d/2, d/2) as a cosine series over odd n = 2m+1
    fourier_2 = sp.simplify(2 / d * sp.integrate(2 * sp.cos(n * sp.pi * xi2 / d),
                                                 (xi2, -d / 2, d / 2)))
    fourier_odd = sp.simplify(fourier_2.subs(n, 2 * m + 1))
    J_n = sp.simplify(2 * sp.integrate(psi_n, (xi1, -b / 2, b / 2), (xi2, -d / 2, d / 2)))
    J_m = sp.expand(J_n.subs(n, 2 * m + 1).subs(sp.Symbol("sgn"), (-1) ** m))
    J_m = sp.expand(sp.simplify(J_m))
    # split the term into its power part and its tanh part and sum the former in closed form
    tanh_part = sum((t for t in J_m.as_ordered_terms() if t.has(sp.tanh)), sp.Integer(0))
    power_part = sp.simplify(J_m - tanh_part)
    power_sum = sp.simplify(sp.summation(power_part, (m, 0, sp.oo)))
    return {"psi_n": psi_n, "laplacian_psi_n": lap_n, "fourier_coefficient_of_2": fourier_odd,
            "J_term": J_m, "J_power_sum": power_sum, "J_tanh_term": sp.simplify(tanh_part),
            "J_T": power_sum + sp.Sum(sp.simplify(tanh_part), (m, 0, sp.oo))}


def ellipse_torsion() -> dict[str, sp.Expr]:
    """Prandtl function c (1 - xi1^2/b^2 - xi2^2/a^2) and J_T = 2 <psi>."""
    c = sp.Symbol("c")
    psi = c * (1 - xi1**2 / b_e**2 - xi2**2 / a_e**2)
    c_sol = sp.solve(sp.Eq(laplacian(psi), -2), c)[0]
    psi = psi.subs(c, c_sol)
    return {"psi": psi, "J_T": sp.factor(2 * integrate_ellipse(psi))}


def cowper_rectangle() -> sp.Expr:
    """Cowper (1966) shear correction factor of a rectangle (cited)."""
    return 10 * (1 + nu) / (12 + 11 * nu)


def cowper_ellipse(a, bb) -> sp.Expr:
    """Cowper (1966) factor of an ellipse for shear along the half axis ``a`` (cited)."""
    return 12 * (1 + nu) * a**2 * (3 * a**2 + bb**2) / (
        (40 + 37 * nu) * a**4 + (16 + 10 * nu) * a**2 * bb**2 + nu * bb**4)


def cowper_circle() -> sp.Expr:
    """Cowper (1966) factor of a solid circle (cited)."""
    return 6 * (1 + nu) / (7 + 6 * nu)


def cross_sections(kinematics: Step, stored_energy: Step, dissipation: Step) -> Step:
    """Section constants of three shapes; moment rules against explicit integration."""
    rect = {k: integrate_rectangle(f) for k, f in MONOMIALS.items()}
    ell = {k: integrate_ellipse(f) for k, f in MONOMIALS.items()}
    circ = {k: sp.factor(v.subs({a_e: r, b_e: r})) for k, v in ell.items()}
    tor_r, tor_e = rectangle_torsion(), ellipse_torsion()
    J_e = tor_e["J_T"]
    I3_e = ell["I1"] + ell["I2"]
    kappa3_e = sp.factor(J_e / I3_e)
    kappa3_c = sp.simplify(kappa3_e.subs({a_e: r, b_e: r}))
    ii1, ii2 = sp.symbols("I_1 I_2", positive=True)
    nikolai = sp.factor(4 * ii1 * ii2 / (ii1 + ii2))
    # the energy and dissipation densities: explicit integration against the moment rules
    two_psi = substitute_H(2 * stored_energy.results["Psi_SVK"], kinematics)
    dH = dissipation.results["dH"]
    two_psi_kv = sp.expand(dissipation.results["two_Psi_KV"].subs(
        {sp.Symbol("dH1", real=True): dH[0], sp.Symbol("dH2", real=True): dH[1],
         sp.Symbol("dH3", real=True): dH[2]}, simultaneous=True))
    checks = {}
    for label, integrate, consts in (("rectangle", integrate_rectangle, rect),
                                     ("ellipse", integrate_ellipse, ell)):
        to_shape = {A: consts["A"], I1: consts["I1"], I2: consts["I2"],
                    I3: consts["I1"] + consts["I2"]}
        for dens_name, dens in (("energy", two_psi), ("dissipation", two_psi_kv)):
            explicit = integrate(dens)
            by_rules = section_integral(dens).subs(to_shape)
            checks[f"{dens_name}_{label}_explicit_minus_rules"] = sp.simplify(explicit - by_rules)
    return make_step(
        name="cross_sections",
        title="Cross sections: area, moments, torsion constants, shear correction factors",
        equations=("Sect. 3.1", "(7)", "footnote 1"),
        assumptions=(
            "rectangle: width b along xi1, height d along xi2; ellipse: half axes a along xi2, "
            "b along xi1; circle: radius r",
            "Saint-Venant torsion (Prandtl stress function) for J_T",
            "transverse shear factors from Cowper (1966): cited, not derived",
        ),
        symbol_assumptions=("b, d, a, r > 0", "n odd positive integer, n = 2m + 1"),
        inputs=("kinematics", "stored_energy", "dissipation"),
        results={
            **{f"rectangle_{k}": v for k, v in rect.items()},
            **{f"ellipse_{k}": v for k, v in ell.items()},
            **{f"circle_{k}": v for k, v in circ.items()},
            "rectangle_psi_n": tor_r["psi_n"],
            "rectangle_laplacian_psi_n": tor_r["laplacian_psi_n"],
            "rectangle_fourier_coefficient_of_2": tor_r["fourier_coefficient_of_2"],
            "rectangle_J_T_term": tor_r["J_term"],
            "rectangle_J_T_power_sum": tor_r["J_power_sum"],
            "rectangle_J_T_tanh_term": tor_r["J_tanh_term"],
            "rectangle_J_T": tor_r["J_T"],
            "ellipse_psi": tor_e["psi"],
            "ellipse_J_T": J_e,
            "ellipse_J_T_in_moments": sp.factor(nikolai.subs({ii1: ell["I1"], ii2: ell["I2"]})),
            "ellipse_kappa_3": kappa3_e,
            "ellipse_kappa_3_deficit": sp.factor(1 - kappa3_e),
            "circle_kappa_3": kappa3_c,
            "nikolai_bound": nikolai,
            "cowper_rectangle": cowper_rectangle(),
            "cowper_ellipse_along_a": cowper_ellipse(a_e, b_e),
            "cowper_ellipse_along_b": cowper_ellipse(b_e, a_e),
            "cowper_circle": cowper_circle(),
            "cowper_ellipse_to_circle": sp.factor(cowper_ellipse(r, r)),
            **checks,
        },
        stated={
            "rectangle_A": b * d, "rectangle_I1": b * d**3 / 12, "rectangle_I2": d * b**3 / 12,
            "rectangle_S1": 0, "rectangle_S2": 0, "rectangle_I12": 0,
            "ellipse_A": sp.pi * a_e * b_e, "ellipse_I1": sp.pi / 4 * a_e**3 * b_e,
            "ellipse_I2": sp.pi / 4 * a_e * b_e**3,
            "ellipse_S1": 0, "ellipse_S2": 0, "ellipse_I12": 0,
            "circle_I1": sp.pi / 4 * r**4, "circle_I2": sp.pi / 4 * r**4,
            "rectangle_laplacian_psi_n": -8 * sp.Symbol("sgn") / (n * sp.pi)
                                         * sp.cos(n * sp.pi * xi2 / d),
            "rectangle_fourier_coefficient_of_2": 8 * (-1) ** m / ((2 * m + 1) * sp.pi),
            "rectangle_J_T_power_sum": b * d**3 / 3,
            "rectangle_J_T_tanh_term": -64 * d**4 / (sp.pi**5 * (2 * m + 1) ** 5)
                                        * sp.tanh((2 * m + 1) * sp.pi * b / (2 * d)),
            "ellipse_J_T": sp.pi * a_e**3 * b_e**3 / (a_e**2 + b_e**2),
            "ellipse_J_T_in_moments": sp.pi * a_e**3 * b_e**3 / (a_e**2 + b_e**2),
            "ellipse_kappa_3": 4 * ell["I1"] * ell["I2"] / (ell["I1"] + ell["I2"]) ** 2,
            "ellipse_kappa_3_deficit": (ell["I1"] - ell["I2"]) ** 2 / (ell["I1"] + ell["I2"]) ** 2,
            "circle_kappa_3": sp.Integer(1),
            "cowper_ellipse_to_circle": cowper_circle(),
            **{k: sp.Integer(0) for k in checks},
        },
        notes=(
            "kappa_3 = 1 - (I1 - I2)^2/(I1 + I2)^2 <= 1 for the ellipse, = 1 only for the "
            "circle; the ellipse attains Nikolai's bound C_T <= 4 G I1 I2/(I1 + I2).",
            "Rectangle: J_T = b d^3/3 - (64 d^4/pi^5) sum_m tanh((2m+1) pi b/(2d))/(2m+1)^5; "
            "the power part sums in closed form (sum over odd n of 1/n^4 = pi^4/96).",
        ),
    )
