"""The naive stress-resultant route (Sect. 4.2) and why it misses in-plane dissipation;
the viscosity constants of the ANCF model (Sect. 4.3)."""

from __future__ import annotations

import sympy as sp

from derive.moments import section_integral
from derive.step import Step, make_step
from derive.steps.dissipation import viscous_stress
from derive.steps.energy import DELTA_U, DELTA_V, TO_DELTAS, dU_sym, dV_sym, substitute_H
from derive.steps.material import deviator
from derive.symbols import (
    H1,
    H2,
    H3,
    I1,
    I2,
    I3,
    I_3,
    U0,
    A,
    E,
    G,
    K,
    U,
    V,
    dH1,
    dH2,
    dH3,
    eta,
    nu,
    tau_B,
    tau_S,
    xi1,
    xi2,
    zeta,
)


def naive_resultants(kinematics: Step, lateral_contraction: Step, moduli: Step,
                     dissipation: Step) -> Step:
    """Material resultants as traction integrals of S = H:E' + V:dE'/dt, and the defect."""
    Ep = lateral_contraction.results["E_prime"]
    dEp = dissipation.results["dE_prime"]
    G_, K_ = moduli.results["G"], moduli.results["K"]
    S_el = (K_ * Ep.trace() * I_3 + 2 * G_ * deviator(Ep)).applyfunc(sp.factor)
    S_v = viscous_stress(dEp, zeta, eta).applyfunc(sp.expand)
    S = (S_el + S_v).applyfunc(sp.expand)
    eta_E_naive = sp.factor(S[2, 2].coeff(dH3))
    in_taus = {eta: G_ * tau_S, zeta: K_ * tau_B}
    tau_E_naive = sp.factor(sp.simplify(eta_E_naive.subs(in_taus) / E))
    # traction integrals with the section fields (17) and (31)
    dH = dissipation.results["dH"]
    fields = {dH1: dH[0], dH2: dH[1], dH3: dH[2]}

    def on_section(expr):
        return substitute_H(sp.expand(expr).subs(fields, simultaneous=True), kinematics)

    F = [section_integral(on_section(S[i, 2])) for i in range(3)]
    M = [section_integral(on_section(xi2 * S[2, 2])),
         section_integral(on_section(-xi1 * S[2, 2])),
         section_integral(on_section(xi1 * S[1, 2] - xi2 * S[0, 2]))]
    resultants = sp.Matrix(F + M).applyfunc(
        lambda c: sp.factor(sp.expand(c.subs(TO_DELTAS, simultaneous=True)))
        .subs(I1 + I2, I3))
    # what the resultants see, against the full viscous stress power
    power_full = sp.expand(sum(S_v[i, j] * dEp[i, j] for i in range(3) for j in range(3)))
    power_in_plane = sp.expand(sum(S_v[a, a] * dEp[a, a] for a in range(2)))
    power_seen = sp.expand(power_full - power_in_plane)
    eta_E = dissipation.results["eta_E"]
    in_plane_coefficient = sp.factor(power_in_plane.coeff(dH3, 2))
    tau_E = dissipation.results["tau_E"]
    taus_from_tildes = sp.factor(sp.expand(tau_E - tau_E_naive))
    tE_stated = (tau_B + 2 * tau_S) / 3
    eE_stated = (1 - 2 * nu) * zeta + sp.Rational(4, 3) * (1 + nu) * eta
    dV, dU = DELTA_V, DELTA_U
    # the viscous rates are written in dV, dU; strain changes in DeltaV, DeltaU
    stated_resultants = sp.Matrix([
        G * A * (dV[0] + tau_S * dV_sym[0]), G * A * (dV[1] + tau_S * dV_sym[1]),
        E * A * (dV[2] + tE_stated * dV_sym[2]),
        E * I1 * (dU[0] + tE_stated * dU_sym[0]), E * I2 * (dU[1] + tE_stated * dU_sym[1]),
        G * I3 * (dU[2] + tau_S * dU_sym[2])]).subs({G: G_})
    lam_v, mu_v = sp.symbols("lambda_v mu_v")
    ancf = sp.solve([sp.Eq(zeta, lam_v + sp.Rational(2, 3) * mu_v), sp.Eq(eta, mu_v)],
                    [lam_v, mu_v], dict=True)[0]
    return make_step(
        name="naive_resultants",
        assumptions=(
            "Simo's material resultants: F_i = <S_i3>, M_1 = <xi2 S_33>, M_2 = <-xi1 S_33>, "
            "M_3 = <xi1 S_23 - xi2 S_13>, with P ~ R_rel S (21)",
            "S = H_SVK : E' + V_KV : dE'/dt with the same modified strain (24)",
        ),
        symbol_assumptions=("tau_S = eta/G, tau_B = zeta/K",),
        inputs=("kinematics", "lateral_contraction", "isotropic_moduli", "dissipation"),
        results={
            "S_total": S,
            "eta_E_naive": eta_E_naive,
            "tau_E_naive": tau_E_naive,
            "resultants": resultants,
            "resultants_in_taus": resultants.subs(in_taus).applyfunc(sp.factor),
            "S_viscous_in_plane": sp.factor(S_v[0, 0]),
            "in_plane_power": power_in_plane,
            "in_plane_dissipation": in_plane_coefficient,
            "eta_E_minus_naive": sp.factor(eta_E - eta_E_naive),
            "power_seen_by_resultants": power_seen,
            "tau_E_minus_naive": taus_from_tildes,
            "S_elastic_in_plane": sp.factor(S_el[0, 0]),
            "ancf_lambda_v": ancf[lam_v], "ancf_mu_v": ancf[mu_v],
            "ancf_lambda_v_taus": sp.expand(ancf[lam_v].subs(in_taus)),
        },
        stated={
            "eta_E_naive": eE_stated,
            "tau_E_naive": tE_stated,
            "resultants_in_taus": stated_resultants,
            "S_viscous_in_plane": ((1 - 2 * nu) * zeta - sp.Rational(2, 3) * (1 + nu) * eta) * dH3,
            "in_plane_dissipation": eta_E - eE_stated,
            "eta_E_minus_naive": -2 * nu * ((1 - 2 * nu) * zeta
                                            - sp.Rational(2, 3) * (1 + nu) * eta),
            "power_seen_by_resultants": eE_stated * dH3**2 + eta * (dH1**2 + dH2**2),
            "tau_E_minus_naive": 2 * nu / 3 * (tau_S - tau_B),
            "S_elastic_in_plane": sp.Integer(0),
            "ancf_lambda_v": zeta - sp.Rational(2, 3) * eta,
            "ancf_lambda_v_taus": K_ * tau_B - sp.Rational(2, 3) * G_ * tau_S,
        },
        notes=(
            "The resultants see only S_i3: their dissipation is eta~_E (dH3)^2 + "
            "eta (dH1^2 + dH2^2). The lateral-contraction rates dE'_aa = -nu dH3 meet a "
            "non-zero viscous in-plane stress and dissipate (eta_E - eta~_E)(dH3)^2 more.",
            "The elastic in-plane stress vanishes by construction of (24), so the stiffnesses "
            "of both routes agree; only the extensional viscosity differs.",
            "tau_E - tau~_E = (2 nu/3)(tau_S - tau_B): the naive value is too small only when "
            "tau_B < tau_S (always at nu = 1/2), exact when tau_B = tau_S (Sect. 5), too "
            "large when tau_B > tau_S.",
            f"Rate symbols: {H1}, {H2}, {H3} -> d/dt; resultant rows F1..F3, M1..M3 in "
            f"DeltaV = V - e3, DeltaU = U - U0 ({V.T}, {U.T}, {U0.T}) and rates dV, dU.",
            f"Bulk modulus K = {sp.sstr(K_)}, symbol {K}.",
        ),
    )
