"""Cross sections: rectangle, ellipse, circle (Sect. 3.1, footnote 1) and tube (hollow circle).

Area and moments by explicit integration over each shape; torsion constants J_T from
Prandtl's stress function (Saint-Venant torsion: Laplace psi = -2 in A, psi = 0 on the
boundary, J_T = 2 <psi>); kappa_3 = J_T / I3. The tube is multiply connected: psi is only
constant (not zero) on the inner boundary, that constant is fixed by a single-valued warping
function, and J_T = 2 <psi> + 2 psi_i A_hole. The cross-section integrals of the stored
energy and dissipation densities are integrated explicitly over each shape and shown equal
to the moment-rule results of steps stored_energy and dissipation.

Transverse shear correction factors are *cited* from Cowper (1966), not derived (the paper
cites them too); the step only checks their consistency (ellipse -> circle, tube -> circle
as the hole closes, tube -> Cowper's thin-walled tube as the wall thins).
"""

from __future__ import annotations

from functools import cache

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
_r = sp.Symbol("varrho", positive=True)            # radius on the positive axis
r_o, r_i = sp.symbols("r_o r_i", positive=True)   # tube: outer and inner radius, r_i < r_o
m_t = sp.Symbol("m", nonnegative=True)             # tube: radius ratio r_i / r_o in [0, 1)

MONOMIALS = {"A": sp.Integer(1), "S1": xi1, "S2": xi2, "I12": xi1 * xi2, "I2": xi1**2,
             "I1": xi2**2}


def integrate_rectangle(f: sp.Expr) -> sp.Expr:
    """Integral of f over |xi1| <= b/2, |xi2| <= d/2."""
    return sp.factor(sp.integrate(f, (xi1, -b / 2, b / 2), (xi2, -d / 2, d / 2)))


@cache
def _ellipse_monomial(p: int, q: int, a: sp.Expr, bb: sp.Expr) -> sp.Expr:
    """Integral of xi1^p xi2^q over xi1^2/bb^2 + xi2^2/a^2 <= 1 (elliptic polar coordinates)."""
    g = (bb * _rho * sp.cos(_th)) ** p * (a * _rho * sp.sin(_th)) ** q * a * bb * _rho
    return sp.factor(sp.integrate(sp.expand(g), (_rho, 0, 1), (_th, 0, 2 * sp.pi)))


def integrate_ellipse(f: sp.Expr, a=a_e, bb=b_e) -> sp.Expr:
    """Integral of f over xi1^2/b^2 + xi2^2/a^2 <= 1 (elliptic polar coordinates).

    f must be a polynomial in xi1, xi2; it is integrated monomial by monomial, each monomial
    explicitly in elliptic polar coordinates.
    """
    poly = sp.Poly(sp.expand(f), xi1, xi2)
    return sp.factor(sum((c * _ellipse_monomial(p, q, a, bb) for (p, q), c in poly.terms()),
                         sp.Integer(0)))


@cache
def _tube_monomial(a: int, b: int) -> sp.Expr:
    """Integral of xi1^a xi2^b over the annulus r_i <= |xi| <= r_o in polar coordinates."""
    g = (_rho * sp.cos(_th)) ** a * (_rho * sp.sin(_th)) ** b * _rho
    return sp.factor(sp.integrate(g, (_th, 0, 2 * sp.pi), (_rho, r_i, r_o)))


def integrate_tube(f: sp.Expr) -> sp.Expr:
    """Integral of f over the annulus r_i <= |xi| <= r_o (polar coordinates) [m^(2+deg f)].

    f must be a polynomial in xi1, xi2 (coefficients free of them); it is integrated
    monomial by monomial, each monomial explicitly in polar coordinates.
    """
    poly = sp.Poly(sp.expand(f), xi1, xi2)
    return sp.expand(sum((c * _tube_monomial(a, b) for (a, b), c in poly.terms()),
                         sp.Integer(0)))


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


def _warping_gradient(psi: sp.Expr) -> sp.Matrix:
    """grad w of the Saint-Venant warping belonging to the Prandtl function psi.

    With twist rate theta, tau_13 = G theta (d_1 w - xi2) and tau_23 = G theta (d_2 w + xi1)
    (warping) must equal G theta d_2 psi and -G theta d_1 psi (stress function); solved for
    grad w: (d_2 psi + xi2, -d_1 psi - xi1) [m].
    """
    w1, w2 = sp.symbols("w_1 w_2")
    sol = sp.solve([sp.Eq(w1 - xi2, sp.diff(psi, xi2)), sp.Eq(w2 + xi1, -sp.diff(psi, xi1))],
                   [w1, w2], dict=True)[0]
    return sp.Matrix([sol[w1], sol[w2]])


def _circulation(grad_w: sp.Matrix, radius) -> sp.Expr:
    """Contour integral of dw = grad w . dxi around the circle |xi| = radius (counterclockwise)."""
    on = {xi1: radius * sp.cos(_th), xi2: radius * sp.sin(_th)}
    dxi = sp.Matrix([sp.diff(v, _th) for v in on.values()])
    integrand = sp.trigsimp(sp.expand((grad_w.subs(on, simultaneous=True).T * dxi)[0, 0]))
    return sp.factor(sp.integrate(integrand, (_th, 0, 2 * sp.pi)))


def tube_torsion() -> dict[str, sp.Expr]:
    """Saint-Venant torsion of the annulus r_i <= rho <= r_o by Prandtl's stress function.

    Axisymmetric ansatz psi = c0 + c1 log(rho) + c2 rho^2 (log(rho) is harmonic): Laplace
    psi = -2 fixes c2; psi = 0 on the outer boundary; on the inner boundary psi = psi_i, a
    constant that is *not* zero (multiply connected section) and is fixed by requiring the
    warping w to be single valued (zero circulation of grad w around the hole). J_T follows
    from the torque M3 = <xi1 tau_23 - xi2 tau_13> = G theta J_T and equals
    2 <psi> + 2 psi_i A_hole. Setting psi = 0 on both boundaries instead (the simply connected
    recipe) gives a multivalued warping: its circulation is reported.
    """
    c0, c1, c2, psi_i = sp.symbols("c_0 c_1 c_2 psi_i")
    rho2 = xi1**2 + xi2**2
    psi = c0 + c1 * sp.log(rho2) / 2 + c2 * rho2
    lap = sp.cancel(laplacian(psi))                              # = 4 c2: log(rho) is harmonic
    psi = psi.subs(c2, sp.solve(sp.Eq(lap, -2), c2)[0])
    radial = sp.expand_log(psi.subs({xi1: _r, xi2: 0}), force=True)   # psi(rho), rho > 0
    grad_w = _warping_gradient(psi)
    circ = _circulation(grad_w, r_i)
    sol = sp.solve([sp.Eq(radial.subs(_r, r_o), 0), sp.Eq(radial.subs(_r, r_i), psi_i),
                    sp.Eq(circ, 0)], [c0, c1, psi_i], dict=True)[0]
    psi_t = sp.factor(psi.subs(sol))
    grad_w_t = grad_w.subs(sol).applyfunc(sp.cancel)
    torque = sp.factor(integrate_tube(-xi1 * sp.diff(psi_t, xi1) - xi2 * sp.diff(psi_t, xi2)))
    prandtl = sp.factor(2 * integrate_tube(psi_t) + 2 * sol[psi_i] * sp.pi * r_i**2)
    # the simply connected recipe psi = 0 on both circles: a multivalued warping
    wrong = sp.solve([sp.Eq(radial.subs(_r, r_o), 0), sp.Eq(radial.subs(_r, r_i), 0)],
                     [c0, c1], dict=True)[0]
    circ_wrong = sp.factor(circ.subs(wrong))
    return {"psi": psi_t, "psi_inner": sp.factor(sol[psi_i]),
            "laplacian_psi": sp.expand(laplacian(psi_t)),
            "warping_gradient": grad_w_t, "warping_circulation": sp.factor(circ.subs(sol)),
            "J_T": torque, "J_T_prandtl": prandtl,
            "two_psi_only": sp.factor(2 * integrate_tube(psi_t)),
            "psi_zero_both_warping_circulation": circ_wrong}


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


def cowper_tube(m) -> sp.Expr:
    """Cowper (1966) factor of a hollow circle with radius ratio m = r_i / r_o (cited)."""
    return 6 * (1 + nu) * (1 + m**2) ** 2 / ((7 + 6 * nu) * (1 + m**2) ** 2
                                            + (20 + 12 * nu) * m**2)


def cross_sections(kinematics: Step, stored_energy: Step, dissipation: Step) -> Step:
    """Section constants of three shapes; moment rules against explicit integration."""
    rect = {k: integrate_rectangle(f) for k, f in MONOMIALS.items()}
    ell = {k: integrate_ellipse(f) for k, f in MONOMIALS.items()}
    circ = {k: sp.factor(v.subs({a_e: r, b_e: r})) for k, v in ell.items()}
    tube = {k: sp.factor(integrate_tube(f)) for k, f in MONOMIALS.items()}
    tor_r, tor_e, tor_t = rectangle_torsion(), ellipse_torsion(), tube_torsion()
    I3_t = sp.factor(tube["I1"] + tube["I2"])
    kappa3_t = sp.factor(tor_t["J_T"] / I3_t)
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
                                     ("ellipse", integrate_ellipse, ell),
                                     ("tube", integrate_tube, tube)):
        to_shape = {A: consts["A"], I1: consts["I1"], I2: consts["I2"],
                    I3: consts["I1"] + consts["I2"]}
        for dens_name, dens in (("energy", two_psi), ("dissipation", two_psi_kv)):
            explicit = integrate(dens)
            by_rules = section_integral(dens).subs(to_shape)
            residual = sp.expand(explicit - by_rules)          # cheap normal form first
            checks[f"{dens_name}_{label}_explicit_minus_rules"] = (
                residual if residual == 0 else sp.simplify(residual))
    return make_step(
        name="cross_sections",
        assumptions=(
            "rectangle: width b along xi1, height d along xi2; ellipse: half axes a along xi2, "
            "b along xi1; circle: radius r; tube: annulus r_i <= |xi| <= r_o, m = r_i/r_o",
            "Saint-Venant torsion (Prandtl stress function) for J_T; for the tube an "
            "axisymmetric stress function, constant on each boundary, single-valued warping",
            "transverse shear factors from Cowper (1966): cited, not derived",
        ),
        symbol_assumptions=("b, d, a, r > 0", "n odd positive integer, n = 2m + 1",
                            "0 < r_i < r_o (r_i = 0: the solid circle)"),
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
            **{f"tube_{k}": v for k, v in tube.items()},
            "tube_I3": I3_t,
            "tube_laplacian_psi": tor_t["laplacian_psi"],
            "tube_psi": tor_t["psi"],
            "tube_psi_inner": tor_t["psi_inner"],
            "tube_warping_circulation": tor_t["warping_circulation"],
            "tube_warping_gradient": tor_t["warping_gradient"],
            "tube_J_T": tor_t["J_T"],
            "tube_J_T_prandtl": tor_t["J_T_prandtl"],
            "tube_two_psi_only": tor_t["two_psi_only"],
            "tube_psi_zero_both_warping_circulation":
                tor_t["psi_zero_both_warping_circulation"],
            "tube_kappa_3": kappa3_t,
            "tube_to_circle_I1": sp.factor(tube["I1"].subs(r_i, 0)),
            "cowper_tube": cowper_tube(m_t),
            "cowper_tube_to_circle": sp.factor(cowper_tube(m_t).subs(m_t, 0)),
            "cowper_tube_thin_wall": sp.factor(sp.limit(cowper_tube(m_t), m_t, 1)),
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
            "tube_A": sp.pi * (r_o**2 - r_i**2),
            "tube_S1": 0, "tube_S2": 0, "tube_I12": 0,
            "tube_I1": sp.pi / 4 * (r_o**4 - r_i**4), "tube_I2": sp.pi / 4 * (r_o**4 - r_i**4),
            "tube_I3": sp.pi / 2 * (r_o**4 - r_i**4),
            "tube_laplacian_psi": sp.Integer(-2),
            "tube_psi": (r_o**2 - xi1**2 - xi2**2) / 2,
            "tube_warping_circulation": sp.Integer(0),
            "tube_warping_gradient": sp.zeros(2, 1),
            "tube_J_T": sp.pi / 2 * (r_o**4 - r_i**4),
            "tube_J_T_prandtl": sp.pi / 2 * (r_o**4 - r_i**4),
            "tube_kappa_3": sp.Integer(1),
            "tube_to_circle_I1": sp.pi / 4 * r_o**4,
            "cowper_tube_to_circle": cowper_circle(),
            "cowper_tube_thin_wall": 2 * (1 + nu) / (4 + 3 * nu),
            **{k: sp.Integer(0) for k in checks},
        },
        notes=(
            "kappa_3 = 1 - (I1 - I2)^2/(I1 + I2)^2 <= 1 for the ellipse, = 1 only for the "
            "circle; the ellipse attains Nikolai's bound C_T <= 4 G I1 I2/(I1 + I2).",
            "Rectangle: J_T = b d^3/3 - (64 d^4/pi^5) sum_m tanh((2m+1) pi b/(2d))/(2m+1)^5; "
            "the power part sums in closed form (sum over odd n of 1/n^4 = pi^4/96).",
            "Tube: psi = (r_o^2 - rho^2)/2 vanishes on the outer circle but equals "
            "psi_i = (r_o^2 - r_i^2)/2 on the inner one; the constant is admissible because the "
            "section is multiply connected, and the log(rho) term is excluded because it would "
            "make the warping multivalued. grad w = 0: the annulus does not warp, so "
            "J_T = I3 and kappa_3 = 1. 2 <psi> alone (the simply connected formula) misses "
            "2 psi_i A_hole.",
            "Cowper's hollow-circle factor is cited; tube_to_circle (m = 0) gives the solid "
            "circle, m -> 1 Cowper's thin-walled tube 2(1 + nu)/(4 + 3 nu).",
        ),
    )
