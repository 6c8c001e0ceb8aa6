"""Rod kinematics from 3-D placements: (14)-(17).

All vectors are written in components on the reference material basis a0^(k) (k = 1, 2, 3);
current quantities are first written on the current basis a^(k) and carried over with the
relative rotation R_rel = a^(k) (x) a0^(k), which drops out of every frame-indifferent
quantity. With d_s a0^(k) = u0 x a0^(k) and d_s a^(k) = u x a^(k), the material components
of d_s a^(alpha) are U x e_alpha.
"""

from __future__ import annotations

import sympy as sp

from derive.step import Step, make_step
from derive.symbols import (
    I_3,
    J0,
    U0,
    U01,
    U02,
    U03,
    U,
    V,
    e1,
    e2,
    e3,
    xi1,
    xi2,
)
from derive.symbols import Hvec as Hsym


def kinematics() -> Step:
    """Basis vectors, J_0, dual basis, deformation gradient (16) and strain vector H (17)."""
    xis = (xi1, xi2)
    # reference placement (14): X = phi0 + xi_a a0^(a); d_s phi0 = a0^(3) = e3
    G = [e1, e2, e3 + sum((x * U0.cross(ea) for x, ea in zip(xis, (e1, e2), strict=True)),
                          sp.zeros(3, 1))]
    J0_derived = sp.expand(sp.Matrix.hstack(*G).det())
    Gdual = [G[(i + 1) % 3].cross(G[(i + 2) % 3]) / J0_derived for i in range(3)]
    # current placement (15) with w = 0: d_s phi = V_k a^(k), d_s a^(a) = u x a^(a)
    g = [e1, e2, V + sum((x * U.cross(ea) for x, ea in zip(xis, (e1, e2), strict=True)),
                         sp.zeros(3, 1))]
    # F = g_k (x) G^k = R_rel . Fhat ; Fhat in reference material components
    Fhat = sum((g[k] * Gdual[k].T for k in range(3)), sp.zeros(3, 3)).applyfunc(sp.cancel)
    # pseudo-polar form (16): Fhat - I has the single column H/J0 along a0^(3)
    H = (J0_derived * (Fhat - I_3) * e3).applyfunc(lambda c: sp.expand(sp.cancel(c)))
    structure_residual = (Fhat - I_3 - H * e3.T / J0_derived).applyfunc(sp.cancel)
    if structure_residual != sp.zeros(3, 3):
        raise AssertionError("deformation gradient is not of pseudo-polar form (16)")
    Fhat_of_H = I_3 + Hsym * e3.T / J0

    dU = U - U0
    stated_H = sp.Matrix([
        V[0] - xi2 * dU[2],
        V[1] + xi1 * dU[2],
        (V[2] - 1) + xi2 * dU[0] - xi1 * dU[1],
    ])
    stated_J0 = 1 + xi2 * U01 - xi1 * U02
    return make_step(
        name="kinematics",
        assumptions=(
            "prismatic rod: every cross section occupies the same domain A",
            "centroid at the origin and directors along principal axes of A",
            "plane, rigid sections (warping w = 0) for the kinematics",
            "arc-length parametrisation, no initial shear: V0 = e3",
            "R_rel = R R0^T is a rotation; it drops out of C = F^T F",
        ),
        symbol_assumptions=("xi1, xi2, V_k, U_k, U0_k real",),
        results={
            "G_1": G[0], "G_2": G[1], "G_3": G[2],
            "J_0": J0_derived,
            "G^1": Gdual[0].applyfunc(sp.cancel),
            "G^2": Gdual[1].applyfunc(sp.cancel),
            "G^3": Gdual[2].applyfunc(sp.cancel),
            "F_hat": Fhat,
            "H": H,
            "F_hat_of_H": Fhat_of_H,
        },
        stated={
            "J_0": stated_J0,
            "G^1": e1 + xi2 * U03 / stated_J0 * e3,
            "G^2": e2 - xi1 * U03 / stated_J0 * e3,
            "G^3": e3 / stated_J0,
            "H": stated_H,
            "F_hat": I_3 + stated_H * e3.T / stated_J0,
        },
        notes=(
            "F = R_rel . Fhat; the step derives Fhat - I = (g_3 - G_3) (x) G^3 and so "
            "H := g_3 - G_3 (components on a0^(k)); F_hat_of_H is the structure (16) "
            "in the abstract symbols H1, H2, H3, J_0 used by the next steps.",
        ),
    )
