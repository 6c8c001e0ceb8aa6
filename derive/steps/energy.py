"""Stored energy: density (26), cross-section integral (27), rod energy (10) with (2), (7);
and the kinetic energy of Sect. 3.5."""

from __future__ import annotations

import sympy as sp

from derive.moments import quadratic_form_matrix, section_integral
from derive.step import Step, make_step
from derive.steps.material import ddot
from derive.symbols import (
    H1,
    H2,
    H3,
    I1,
    I2,
    I3,
    U0,
    A,
    E,
    G,
    Om1,
    Om2,
    Om3,
    U,
    V,
    dphi1,
    dphi2,
    dphi3,
    dU1,
    dU2,
    dU3,
    dV1,
    dV2,
    dV3,
    e1,
    e2,
    kappa_1,
    kappa_2,
    kappa_3,
    nu,
    xi1,
    xi2,
)

#: strain changes Delta V = V - e3, Delta U = U - U0 as independent symbols
DELTA_V = sp.Matrix(sp.symbols("DeltaV1:4", real=True))
DELTA_U = sp.Matrix(sp.symbols("DeltaU1:4", real=True))
dV_sym = sp.Matrix([dV1, dV2, dV3])
dU_sym = sp.Matrix([dU1, dU2, dU3])
STRAIN_VARS = list(V) + list(U)
TO_DELTAS = {**{V[i]: DELTA_V[i] + (1 if i == 2 else 0) for i in range(3)},
             **{U[i]: DELTA_U[i] + U0[i] for i in range(3)}}


def strain_changes() -> tuple[sp.Matrix, sp.Matrix]:
    """(Delta V, Delta U) = (V - e3, U - U0) in the strain symbols."""
    return V - sp.Matrix([0, 0, 1]), U - U0


def substitute_H(expr: sp.Expr, kinematics: Step) -> sp.Expr:
    """Replace the abstract H1..H3 by their section fields (17)."""
    H = kinematics.results["H"]
    return sp.expand(expr.subs({H1: H[0], H2: H[1], H3: H[2]}, simultaneous=True))


def with_I3(expr: sp.Expr, variables: list[sp.Symbol]) -> sp.Expr:
    """Write I1 + I2 as I3 in a polynomial in ``variables`` (coefficients factored first)."""
    poly = sp.Poly(sp.expand(expr), *variables)
    return sum((sp.factor(c).subs(I1 + I2, I3)
                * sp.prod(v**k for v, k in zip(variables, m, strict=True))
                for m, c in poly.terms()), sp.Integer(0))


def split_normal_shear(psi: sp.Expr, normal: sp.Symbol) -> tuple[sp.Expr, sp.Expr]:
    """Split a density quadratic in (H1, H2, H3) into its normal (H3) and shear (H_a) parts.

    Raises if the two parts are coupled, so the split is exact.
    """
    shear = sp.expand(psi.subs(normal, 0))
    normal_part = sp.expand(psi - shear)
    if sp.expand(normal_part - normal_part.subs({H1: 0, H2: 0})) != 0:
        raise AssertionError("normal and shear parts of the density are coupled")
    return normal_part, shear


#: geometric shear corrections of (7)/(8): A -> kappa_a A on the transverse-shear rows,
#: I3 = I1 + I2 -> kappa_3 I3 on the torsion row
SHEAR_CORRECTION_F = {0: {A: kappa_1 * A}, 1: {A: kappa_2 * A}, 2: {}}
SHEAR_CORRECTION_M = {0: {}, 1: {}, 2: {I3: kappa_3 * I3}}


def shear_correct(mat: sp.Matrix, rows: dict) -> sp.Matrix:
    """Apply the row-wise geometric substitutions ``rows`` to a diagonal rod matrix."""
    return sp.diag(*[mat[i, i].subs(rows[i]) for i in range(3)])


def rod_matrices(density_2x: sp.Expr, kinematics: Step, rates: bool) -> tuple[sp.Matrix, sp.Matrix]:
    """(3x3, 3x3) rod matrices of a section-integrated density quadratic in the strains.

    ``density_2x`` is a 3-D density in H1..H3 (or their rates dH1..dH3 when ``rates``); it
    is evaluated on the section fields (17)/(31), integrated by the moment rules and
    written as dV.M_F.dV + dU.M_M.dU (no coupling terms, or this raises).
    """
    field = substitute_H(density_2x, kinematics) if not rates else density_2x
    integrated = section_integral(field)
    if rates:
        variables = list(dV_sym) + list(dU_sym)
        expr = integrated
    else:
        variables = list(DELTA_V) + list(DELTA_U)
        expr = sp.expand(integrated.subs(TO_DELTAS, simultaneous=True))
    M = quadratic_form_matrix(expr, variables)
    if M[:3, 3:] != sp.zeros(3, 3):
        raise AssertionError("the density couples forces and moments")
    return M[:3, :3].applyfunc(lambda c: sp.factor(c).subs(I1 + I2, I3)), \
        M[3:, 3:].applyfunc(lambda c: sp.factor(c).subs(I1 + I2, I3))


def stored_energy(kinematics: Step, lateral_contraction: Step) -> Step:
    """2<Psi_SVK(E')> = dV.C_F.dV + dU.C_M.dU: rod stiffnesses from the 3-D density."""
    S, Ep = lateral_contraction.results["S_prime"], lateral_contraction.results["E_prime"]
    psi = sp.factor(ddot(S, Ep) / 2)                       # (26): Psi = 1/2 S' : E'
    psi_normal, psi_shear = split_normal_shear(sp.expand(psi), H3)
    two_psi_bar = section_integral(substitute_H(2 * psi, kinematics))   # (27)
    # the shear part carries the shear modulus G = E/(2(1+nu)); write it with the symbol G
    G_of_E = E / (2 * (1 + nu))
    CF_n, CM_n = rod_matrices(2 * psi_normal, kinematics, rates=False)
    CF_s, CM_s = rod_matrices(sp.expand(2 * psi_shear / G_of_E * G), kinematics, rates=False)
    C_F, C_M = CF_n + CF_s, CM_n + CM_s
    dV, dU = strain_changes()
    rod_form = with_I3((dV.T * C_F * dV + dU.T * C_M * dU)[0, 0], STRAIN_VARS)
    C_F7 = CF_n + shear_correct(CF_s, SHEAR_CORRECTION_F)
    C_M7 = CM_n + shear_correct(CM_s, SHEAR_CORRECTION_M)
    # kinetic energy density: x_dot = R (Phi_dot + xi_a Omega x e_a) (Sect. 3.5)
    Om = sp.Matrix([Om1, Om2, Om3])
    xdot = sp.Matrix([dphi1, dphi2, dphi3]) + xi1 * Om.cross(e1) + xi2 * Om.cross(e2)
    two_T_bar = with_I3(section_integral((xdot.T * xdot)[0, 0]),
                        [dphi1, dphi2, dphi3, Om1, Om2, Om3])
    return make_step(
        name="stored_energy",
        assumptions=("dV = J0 ds dxi1 dxi2 ~ ds dxi1 dxi2 (J0 ~ 1)",
                     "section moments: <1> = A, <xi_a> = 0, <xi1 xi2> = 0, <xi2^2> = I1, "
                     "<xi1^2> = I2",
                     "(7): geometric shear corrections A -> kappa_a A, I3 -> J_T = kappa_3 I3 "
                     "on the shear-type (G) entries only"),
        symbol_assumptions=("I3 = I1 + I2",),
        inputs=("kinematics", "lateral_contraction"),
        results={
            "Psi_SVK": psi,
            "two_Psi_section": two_psi_bar,
            "Psi_normal": psi_normal, "Psi_shear": psi_shear,
            "C_F": C_F, "C_M": C_M,
            "stored_energy_density_2x": rod_form,
            "C_F_corrected": C_F7, "C_M_corrected": C_M7,
            "kinetic_density_2x_over_rho": two_T_bar,
        },
        stated={
            "Psi_SVK": (E * H3**2 + E / (2 * (1 + nu)) * (H1**2 + H2**2)) / 2,
            "two_Psi_section": sp.expand(
                E * A * (V[2] - 1) ** 2 + E / (2 * (1 + nu)) * A * (V[0] ** 2 + V[1] ** 2)
                + E * I1 * (U[0] - U0[0]) ** 2 + E * I2 * (U[1] - U0[1]) ** 2
                + E / (2 * (1 + nu)) * (I1 + I2) * (U[2] - U0[2]) ** 2),
            "C_F": sp.diag(G * A, G * A, E * A),
            "C_M": sp.diag(E * I1, E * I2, G * I3),
            "C_F_corrected": sp.diag(G * A * kappa_1, G * A * kappa_2, E * A),
            "C_M_corrected": sp.diag(E * I1, E * I2, G * I3 * kappa_3),
            "kinetic_density_2x_over_rho": A * (dphi1**2 + dphi2**2 + dphi3**2)
                                           + I1 * Om1**2 + I2 * Om2**2 + I3 * Om3**2,
        },
        notes=("The shear part of Psi carries G = E/(2(1+nu)) (isotropic_moduli); the rod "
               "matrices write it with the symbol G.",),
    )
