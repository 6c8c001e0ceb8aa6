"""Green-Lagrange strain of the rod kinematics: exact (18), small-strain (19), components (20)."""

from __future__ import annotations

import sympy as sp

from derive.step import Step, make_step
from derive.symbols import H1, H2, H3, I_3, J0, Hvec, e3

_eps = sp.Symbol("epsilon", positive=True)  # bookkeeping parameter for the order in |H|


def green_lagrange(kinematics: Step) -> Step:
    """E = (F^T F - I)/2 from the pseudo-polar F of (16), then its linearisation in H."""
    Fhat = kinematics.results["F_hat_of_H"]          # I + H (x) e3 / J0
    C = (Fhat.T * Fhat).applyfunc(sp.expand)          # R_rel^T R_rel = I drops out
    E_exact = ((C - I_3) / 2).applyfunc(sp.expand)
    # small strain: keep first order in H (H -> eps H), then J0 -> 1 (weak reference curvature)
    scaled = E_exact.subs({H1: _eps * H1, H2: _eps * H2, H3: _eps * H3}, simultaneous=True)
    E_first = scaled.applyfunc(lambda c: sp.expand(c).coeff(_eps, 1))
    E_small = E_first.subs(J0, 1)
    Hn2 = (Hvec.T * Hvec)[0, 0]
    sym = Hvec * e3.T + e3 * Hvec.T
    return make_step(
        name="green_lagrange",
        assumptions=(
            "C = F^T F with F = R_rel (I + H (x) a0^(3) / J0); R_rel orthogonal",
            "(19): |H| << 1 (drop O(|H|^2)) and J0 ~ 1 (moderate reference curvature)",
        ),
        symbol_assumptions=("J_0 > 0", "H_k real"),
        inputs=("kinematics",),
        results={
            "C": C,
            "E_exact": E_exact,
            "E_small": E_small,
            "E_12": E_exact[0, 1], "E_11": E_exact[0, 0], "E_22": E_exact[1, 1],
            "E_13": E_exact[0, 2], "E_23": E_exact[1, 2], "E_33": E_exact[2, 2],
        },
        stated={
            "E_exact": sym / (2 * J0) + Hn2 / (2 * J0**2) * e3 * e3.T,
            "E_small": sym / 2,
            "E_11": sp.Integer(0), "E_22": sp.Integer(0), "E_12": sp.Integer(0),
            "E_13": H1 / (2 * J0), "E_23": H2 / (2 * J0),
            "E_33": H3 / J0 + Hn2 / (2 * J0**2),
        },
        notes=("(20): E_a3 ~ H_a/2 and E_33 ~ H_3 follow from E_small.",),
    )
