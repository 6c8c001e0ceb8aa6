"""The exact uniaxial modulus of the 3-D Kelvin-Voigt solid and the paper's tau_E.

With K(s) = K (1 + s tau_B) and G(s) = G (1 + s tau_S) the lateral-stress-free modulus of
step maxwell_rod is E(s) = 9 K(s) G(s) / (3 K(s) + G(s)). Its first-order Taylor polynomial
in s is exactly E (1 + s tau_E) with the paper's tau_E (6) from the dissipation function (and
not the naive resultant route's), the remainder is O(s^2) in closed form, and it vanishes
identically iff tau_B = tau_S.
"""

from __future__ import annotations

import sympy as sp

from derive.step import Step, make_step
from derive.symbols import E, G, G_of, K, K_of, nu, omega, s_lap, tau_B, tau_S

#: the pole time of the exact modulus: E(s) has its pole at s = -1/tau_D
tau_D = sp.Symbol("tau_D", positive=True)
#: (2/9)(1 + nu)(1 - 2 nu)(tau_B - tau_S)^2 >= 0 for -1 < nu <= 1/2, as a positive symbol
_a = sp.Symbol("a", positive=True)


def _in_times(expr: sp.Expr) -> sp.Expr:
    """Collect in tau_B, tau_S with factored coefficients (readable retardation times)."""
    return sp.collect(sp.expand(expr), [tau_B, tau_S], sp.factor)


def kelvin_voigt_uniaxial(isotropic_moduli: Step, dissipation: Step, naive_resultants: Step,
                          maxwell_rod: Step) -> Step:
    """E(s) of the 3-D Kelvin-Voigt solid [Pa]; tau_E, remainder and frequency-domain error."""
    s = s_lap
    E_of_KG = maxwell_rod.results["E_of_s"]
    kv = {K_of(s): K * (1 + s * tau_B), G_of(s): G * (1 + s * tau_S)}
    E_kv_KG = sp.factor(E_of_KG.subs(kv))
    moduli = {K: isotropic_moduli.results["K"], G: isotropic_moduli.results["G"]}
    E_kv = sp.factor(E_kv_KG.subs(moduli))
    # first-order Taylor polynomial in s
    series = sp.series(E_kv, s, 0, 2).removeO()
    E0 = sp.factor(series.coeff(s, 0))
    tau_E_exact = _in_times(series.coeff(s, 1) / E0)
    tau_E_diss = dissipation.results["tau_E"]
    tau_E_naive = naive_resultants.results["tau_E_naive"]
    # remainder E(s) - E (1 + s tau_E): closed form, and its pole -1/tau_D
    remainder = sp.factor(E_kv - E * (1 + s * tau_E_exact))
    (pole,) = sp.solve(sp.denom(sp.together(remainder)), s)
    tau_D_ = _in_times(-1 / pole)
    coeff = sp.factor(sp.cancel(remainder * (1 + s * tau_D_) / (E * s**2)))
    remainder_closed = coeff * E * s**2 / (1 + s * tau_D)
    # as a Prony series: spring E, dashpot, and one Maxwell branch of time tau_D
    parts = sp.apart(E_kv, s)
    const = sp.factor(sum((p for p in sp.Add.make_args(parts) if not p.has(s)), sp.Integer(0)))
    dashpot = sp.factor(sum((p for p in sp.Add.make_args(parts) if p.is_polynomial(s)
                             and p.has(s)), sp.Integer(0)) / s)
    pole_part = sp.factor(sum((p for p in sp.Add.make_args(parts) if not p.is_polynomial(s)),
                              sp.Integer(0)))
    # pole part r/(1 + s tau_D) = E_D s tau_D/(1 + s tau_D) - E_D with E_D = -r
    E_D = sp.factor(sp.cancel(-pole_part * (1 + s * tau_D_)))
    prony_check = sp.cancel(const - E_D + s * dashpot + E_D * s * tau_D_ / (1 + s * tau_D_)
                            - E_kv)
    # frequency domain: |E*(i w) - E (1 + i w tau_E)| / E
    # (the coefficient is -a with a >= 0 in the modelling range -1 < nu <= 1/2)
    rel_err = sp.simplify(sp.Abs((-_a * E * s**2 / (1 + s * tau_D)).subs(s, sp.I * omega)) / E)
    rel_err = rel_err.subs(_a, sp.factor(-coeff))
    incompressible = sp.factor(E_kv.subs(nu, sp.Rational(1, 2)))
    return make_step(
        name="kelvin_voigt_uniaxial",
        assumptions=(
            "3-D Kelvin-Voigt solid (29): K(s) = K (1 + s tau_B), G(s) = G (1 + s tau_S)",
            "lateral surface stress free at every s (step maxwell_rod): nu(s) varies with s",
        ),
        symbol_assumptions=("E, tau_B, tau_S > 0", "-1 < nu < 1/2", "s complex, omega > 0"),
        inputs=("isotropic_moduli", "dissipation", "naive_resultants", "maxwell_rod"),
        results={
            "E_of_s_in_KG": E_kv_KG,
            "E_of_s": E_kv,
            "E_at_s0": E0,
            "tau_E_exact": tau_E_exact,
            "tau_E_exact_minus_dissipation": sp.factor(tau_E_exact - tau_E_diss),
            "tau_E_exact_minus_naive": sp.factor(tau_E_exact - tau_E_naive),
            "tau_D": tau_D_,
            "remainder": remainder,
            "remainder_coefficient": coeff,
            "remainder_in_tau_D": remainder_closed,
            "remainder_in_tau_D_minus_remainder": sp.cancel(
                remainder_closed.subs(tau_D, tau_D_) - remainder),
            "remainder_equal_times": sp.factor(remainder.subs(tau_B, tau_S)),
            "E_of_s_equal_times": sp.factor(E_kv.subs(tau_B, tau_S)),
            "E_of_s_incompressible": incompressible,
            "prony_dashpot": dashpot,
            "prony_branch_modulus": E_D,
            "prony_minus_E": prony_check,
            "relative_error_i_omega": rel_err,
        },
        stated={
            "E_at_s0": E,
            "tau_E_exact": ((1 - 2 * nu) * tau_B + 2 * (1 + nu) * tau_S) / 3,
            "tau_E_exact_minus_dissipation": sp.Integer(0),
            "tau_E_exact_minus_naive": 2 * nu / 3 * (tau_S - tau_B),
            "remainder_equal_times": sp.Integer(0),
            "remainder_in_tau_D_minus_remainder": sp.Integer(0),
            "E_of_s_equal_times": E * (1 + s * tau_S),
            "E_of_s_incompressible": E * (1 + s * tau_S),
            "prony_minus_E": sp.Integer(0),
            "relative_error_i_omega": sp.Rational(2, 9) * (1 + nu) * (1 - 2 * nu)
                                      * (tau_B - tau_S) ** 2 * omega**2
                                      / sp.sqrt(1 + (omega * tau_D) ** 2),
        },
        notes=(
            "The first-order Taylor polynomial of the exact uniaxial modulus is E (1 + s tau_E) "
            "with the paper's tau_E (6), i.e. the retardation time of the dissipation-function "
            "route; the naive resultant route's tau~_E is off already at first order by "
            "(2 nu/3)(tau_S - tau_B).",
            "remainder = -E (2/9)(1 + nu)(1 - 2 nu)(tau_B - tau_S)^2 s^2 / (1 + s tau_D): "
            "zero iff tau_B = tau_S (then E(s) = E (1 + s tau) exactly, the paper's Sect. 5 "
            "data) or nu = 1/2 (E(s) = 3 G(s)).",
            "As a Prony series the exact modulus is a spring E, a dashpot E tau_B tau_S/tau_D and "
            "one Maxwell branch of time tau_D with modulus "
            "E (2/9)(1 + nu)(1 - 2 nu)(tau_B - tau_S)^2 / tau_D^2 > 0.",
            "Frequency domain: |E*(i w) - E (1 + i w tau_E)| / E = "
            "(2/9)(1 + nu)(1 - 2 nu)(tau_B - tau_S)^2 w^2 / sqrt(1 + (w tau_D)^2) "
            "<= (2/9)(1 + nu)(1 - 2 nu)((tau_B - tau_S) w)^2 = O((w tau)^2), the same order as "
            "the Kelvin-Voigt error of step maxwell_limit.",
        ),
    )
