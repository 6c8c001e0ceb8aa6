"""Kelvin-Voigt dissipation: viscosity tensor (29), strain rate (30)-(31), density and its
cross-section integral (32), dissipation function (11), damping parameters (3)-(6), (8)-(9)."""

from __future__ import annotations

import sympy as sp

from derive.moments import section_integral
from derive.step import Step, make_step
from derive.steps.energy import (
    SHEAR_CORRECTION_F,
    SHEAR_CORRECTION_M,
    dU_sym,
    dV_sym,
    rod_matrices,
    shear_correct,
    split_normal_shear,
    with_I3,
)
from derive.steps.material import ddot, deviator
from derive.symbols import (
    H1,
    H2,
    H3,
    I1,
    I2,
    I3,
    I_3,
    A,
    E,
    G,
    K,
    U,
    V,
    dH1,
    dH2,
    dH3,
    dHvec,
    e3,
    eta,
    kappa_1,
    kappa_2,
    kappa_3,
    nu,
    tau_B,
    tau_S,
    xi1,
    xi2,
    zeta,
)
from derive.symbols import t as time

_Q = sp.Matrix(3, 3, lambda i, j: sp.Symbol(f"Q{min(i, j) + 1}{max(i, j) + 1}", real=True))


def viscous_stress(Q: sp.Matrix, bulk, shear) -> sp.Matrix:
    """V_KV : Q = zeta tr(Q) I + 2 eta P : Q, (29) (with bulk=zeta, shear=eta)."""
    return bulk * Q.trace() * I_3 + 2 * shear * deviator(Q)


def time_derivative(expr, functions: dict[sp.Symbol, sp.Symbol]) -> sp.Basic:
    """d/dt of ``expr`` where each key symbol is a function of time; the derivative of a
    key is written as its value symbol (e.g. V1 -> dV1). Other symbols are constant."""
    as_fun = {k: sp.Function(k.name)(time) for k in functions}
    moving = expr.subs(as_fun) if not isinstance(expr, sp.MatrixBase) else expr.subs(as_fun)
    d = sp.diff(moving, time)
    back = {sp.Derivative(f, time): functions[k] for k, f in as_fun.items()}
    d = d.subs(back).subs({f: k for k, f in as_fun.items()})
    return d.applyfunc(sp.expand) if isinstance(d, sp.MatrixBase) else sp.expand(d)


def dissipation(kinematics: Step, lateral_contraction: Step, moduli: Step,
                stored_energy: Step) -> Step:
    """2<Psi_KV(dE'/dt)> and the rod damping matrices V_F, V_M with eta_E (5)."""
    VQ = viscous_stress(_Q, zeta, eta)
    VQ_lame = (zeta - sp.Rational(2, 3) * eta) * _Q.trace() * I_3 + 2 * eta * _Q
    # strain rates: strains V, U move, the reference U0 does not (31)
    rates = dict(zip(list(V) + list(U), list(dV_sym) + list(dU_sym), strict=True))
    dH_field = time_derivative(kinematics.results["H"], rates)                    # (31)
    dE_prime = time_derivative(lateral_contraction.results["E_prime"],
                               {H1: dH1, H2: dH2, H3: dH3})                        # (30)
    psi_kv_2x = sp.expand(ddot(dE_prime, viscous_stress(dE_prime, zeta, eta)))   # 2 Psi_KV
    eta_E = sp.factor(psi_kv_2x.coeff(dH3, 2))
    shear_coeff = sp.factor(psi_kv_2x.coeff(dH1, 2))
    # footnote 14: the same contraction with (K, G) in place of (zeta, eta) gives E
    elastic_analogue = sp.factor(eta_E.subs({zeta: K, eta: G}, simultaneous=True)
                                 .subs({K: moduli.results["K"], G: moduli.results["G"]}))
    # cross-section integral (32) with the rate fields (31)
    to_field = {dH1: dH_field[0], dH2: dH_field[1], dH3: dH_field[2]}
    psi_n, psi_s = split_normal_shear(psi_kv_2x, dH3)
    VF_n, VM_n = rod_matrices(sp.expand(psi_n.subs(to_field)), kinematics, rates=True)
    VF_s, VM_s = rod_matrices(sp.expand(psi_s.subs(to_field)), kinematics, rates=True)
    V_F, V_M = VF_n + VF_s, VM_n + VM_s
    rate_vars = list(dV_sym) + list(dU_sym)
    two_D = with_I3(section_integral(psi_kv_2x.subs(to_field)), rate_vars)
    # retardation times: eta = G tau_S, zeta = K tau_B, tau_E := eta_E / E
    in_taus = {eta: moduli.results["G"] * tau_S, zeta: moduli.results["K"] * tau_B}
    tau_E = sp.factor(sp.simplify(eta_E.subs(in_taus) / E))
    C_F, C_M = stored_energy.results["C_F"], stored_energy.results["C_M"]
    to_E = {G: moduli.results["G"]}
    ratio_F = sp.diag(*[sp.factor(V_F[i, i].subs(in_taus) / C_F[i, i].subs(to_E))
                        for i in range(3)])
    ratio_M = sp.diag(*[sp.factor(V_M[i, i].subs(in_taus) / C_M[i, i].subs(to_E))
                        for i in range(3)])
    # (8), (9): the same geometric correction on the shear-type (eta) entries
    V_F9 = VF_n + shear_correct(VF_s, SHEAR_CORRECTION_F)
    V_M9 = VM_n + shear_correct(VM_s, SHEAR_CORRECTION_M)
    C_F7, C_M7 = stored_energy.results["C_F_corrected"], stored_energy.results["C_M_corrected"]
    tau_F = sp.diag(*[sp.factor(V_F9[i, i].subs(in_taus) / C_F7[i, i].subs(to_E))
                      for i in range(3)])
    tau_M = sp.diag(*[sp.factor(V_M9[i, i].subs(in_taus) / C_M7[i, i].subs(to_E))
                      for i in range(3)])
    # special cases
    half = sp.Rational(1, 2)
    eta_E_stated = zeta * (1 - 2 * nu) ** 2 + sp.Rational(4, 3) * eta * (1 + nu) ** 2
    tau_E_stated = ((1 - 2 * nu) * tau_B + 2 * (1 + nu) * tau_S) / 3
    return make_step(
        name="dissipation",
        assumptions=(
            "Kelvin-Voigt solid: S = H : E + V : dE/dt, V constant and isotropic (29)",
            "strain rate of the modified strain (24) with (19): linear in dH/dt",
            "same cross-section approximations as the stored energy (J0 ~ 1, moments)",
            "(8)-(9): the geometric shear corrections of (7) applied to the shear-type "
            "(eta) entries",
        ),
        symbol_assumptions=("zeta, eta > 0 (bulk and shear viscosity)",
                            "tau_S = eta/G, tau_B = zeta/K"),
        inputs=("kinematics", "lateral_contraction", "isotropic_moduli", "stored_energy"),
        results={
            "V_KV_Q": VQ,
            "dH": dH_field,
            "dE_prime": dE_prime,
            "two_Psi_KV": psi_kv_2x,
            "eta_E": eta_E,
            "shear_viscosity_coefficient": shear_coeff,
            "elastic_analogue_footnote14": elastic_analogue,
            "dissipation_density_2x": two_D,
            "V_F": V_F, "V_M": V_M,
            "tau_E": tau_E,
            "V_over_C_F": ratio_F, "V_over_C_M": ratio_M,
            "V_F_corrected": V_F9, "V_M_corrected": V_M9,
            "tau_matrix_F": tau_F, "tau_matrix_M": tau_M,
            "eta_E_nu0": sp.expand(eta_E.subs(nu, 0)),
            "tau_E_nu0": sp.expand(tau_E.subs(nu, 0)),
            "eta_E_nu_half": sp.expand(eta_E.subs(nu, half)),
            "trouton_ratio": sp.simplify(eta_E.subs(nu, half) / eta),
            "tau_E_nu_half": sp.expand(tau_E.subs(nu, half)),
            "tau_E_equal_times": sp.factor(tau_E.subs(tau_B, tau_S)),
        },
        stated={
            "V_KV_Q": VQ_lame,
            "dH": sp.Matrix([dV_sym[0] - xi2 * dU_sym[2], dV_sym[1] + xi1 * dU_sym[2],
                             dV_sym[2] + xi2 * dU_sym[0] - xi1 * dU_sym[1]]),
            "dE_prime": (dHvec * e3.T + e3 * dHvec.T) / 2 - nu * dH3 * (I_3 - e3 * e3.T),
            "eta_E": eta_E_stated,
            "shear_viscosity_coefficient": eta,
            "elastic_analogue_footnote14": E,
            "dissipation_density_2x": sp.expand(
                eta_E_stated * A * dV_sym[2] ** 2 + eta_E_stated * (I1 * dU_sym[0] ** 2
                                                                    + I2 * dU_sym[1] ** 2)
                + eta * A * (dV_sym[0] ** 2 + dV_sym[1] ** 2) + eta * I3 * dU_sym[2] ** 2),
            "V_F": sp.diag(eta * A, eta * A, eta_E_stated * A),
            "V_M": sp.diag(eta_E_stated * I1, eta_E_stated * I2, eta * I3),
            "tau_E": tau_E_stated,
            "V_over_C_F": sp.diag(tau_S, tau_S, tau_E_stated),
            "V_over_C_M": sp.diag(tau_E_stated, tau_E_stated, tau_S),
            "V_F_corrected": sp.diag(eta * A * kappa_1, eta * A * kappa_2, eta_E_stated * A),
            "V_M_corrected": sp.diag(eta_E_stated * I1, eta_E_stated * I2, eta * I3 * kappa_3),
            "tau_matrix_F": sp.diag(tau_S, tau_S, tau_E_stated),
            "tau_matrix_M": sp.diag(tau_E_stated, tau_E_stated, tau_S),
            "eta_E_nu0": zeta + sp.Rational(4, 3) * eta,
            "tau_E_nu0": (tau_B + 2 * tau_S) / 3,
            "eta_E_nu_half": 3 * eta,
            "trouton_ratio": sp.Integer(3),
            "tau_E_nu_half": tau_S,
            "tau_E_equal_times": tau_S,
        },
        notes=(
            "eta_E is the coefficient of (dH3)^2 in 2 Psi_KV: the axial rate dH3 comes with "
            "the in-plane rates -nu dH3 of the lateral contraction, and both dissipate.",
            "D carries the factor 1/2 (footnote 4): the viscous resultants are V_F dV/dt "
            "and V_M dU/dt, the dissipation rate is 2 D.",
            f"Section moments: I3 = I1 + I2 ({I1}, {I2}, {I3}).",
        ),
    )
