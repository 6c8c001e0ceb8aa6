"""Sensitivities of a rod's static equilibrium to its parameters (issue 34): the implicit
function theorem on the static problem in reduced coordinates
(:class:`~runtime.model.statics.RodStatics`).

At an equilibrium ``R(x(theta); theta) = 0`` the derivative solves ``K dx = -R_theta``
with the static Jacobian K (the one Newton's last iteration factors) and ``R_theta`` the
static rows of the residual's exact tangent along the parameter's direction
(:meth:`RodModel.residual_tangent` with zero state direction); a held node's rows are
its prescribed position, so there ``dx`` is that position's derivative. One
factorisation of K serves every parameter. The result is mapped back to the full state
(``dy = T dx``: positions, and quaternions ``dp = 1/2 L(p) [0; dtheta]``), velocities 0.
"""

from __future__ import annotations

import numpy as np

from runtime.model.rod import RodModel
from runtime.model.statics import RodStatics
from runtime.solvers.native.band import BandLU


def static_sensitivities(model: RodModel, y: np.ndarray, time: float = 0.0,
                         statics: RodStatics | None = None) -> np.ndarray:
    """dy/dtheta (k, n) at the static equilibrium ``y`` for the model's parameter
    directions (:meth:`RodModel.set_directions`). Call inside ``with model.statics():``
    (the loads at ``time-``, ends at rest, a Maxwell rod relaxed; the directions are
    relaxed alike). ``statics``: the static problem solved (its gauge is kept; default
    a fresh one, holding the same free rigid motions)."""
    dirs = model.directions
    if dirs is None:
        raise ValueError("static_sensitivities: the model has no parameter directions")
    st = statics
    if st is None:
        st = RodStatics(model, time)
        st.hold_rigid_motions(y)
    kl, ku = st.kl_static, st.ku_static
    ab = np.zeros((2 * kl + ku + 1, st.n_static), order="F")
    st.static_jacobian_band(y, ab)
    lu = BandLU(ab, kl, ku)
    if lu.info != 0:
        raise ValueError("static_sensitivities: the static Jacobian is singular at the "
                         "equilibrium (a mechanism): no sensitivity")
    n = model.n
    y0 = st.at_rest(y)
    zero = np.zeros(n)
    out = np.zeros((len(dirs.arrays), n))
    from runtime.model.statics import _half_L

    Lm = _half_L(y0[model.p_index])                                # (N, 4, 3)
    model.at(st.time)
    for i, d in enumerate(dirs.arrays):
        r = model.residual_tangent(st.time, y0, zero, zero, zero, d)
        rhs = -r[st.static_rows]
        rhs[~st._rowmask] = 0.0
        for end, node in (("start", 0), ("end", model.N)):
            if model.arrays.held(end):
                rhs[st.phi_cols[node]] = d.param("r_" + end)
        dx = lu.solve(rhs)
        out[i, model.phi_index] = dx[st.phi_cols]
        out[i, model.p_index] = np.einsum("nba,na->nb", Lm, dx[st.theta_cols])
    return out
