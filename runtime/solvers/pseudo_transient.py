"""Pseudo-transient continuation (Kelley and Keyes 1998) towards a static equilibrium.

``(J + M / d) dx = -R`` with a mass-like matrix M and a pseudo time step d grown as the
residual falls (switched evolution relaxation, ``d <- d |R_old| / |R|``): the first steps
move the structure like heavily damped dynamics, the last are Newton's. It finds the
equilibria that load stepping cannot reach: a mechanism whose stiffness is singular where
it starts (an assembly hanging from a ball joint), a rod whose supports are obstacles (a
smooth contact law is nearly a step on the scale of a Newton step, and the active set
changes under it). The static problem ``st`` provides ``n_static``, ``load_scale``,
``static_residual(y, out)``, ``static_jacobian_sparse(y)`` and ``static_retract(y, dx)``.
"""

from __future__ import annotations

import numpy as np


def pseudo_transient(st, y0: np.ndarray, M=None, *, tol: float = 1e-8,
                     max_iter: int = 400, first_step: float = 1e-6,
                     min_growth: float = 1.0) -> tuple[np.ndarray, bool]:
    """(y, converged): a state near the equilibrium at load factor 1 from ``y0``.

    ``M``: a sparse (n_static, n_static) mass matrix; None: the static Jacobian's
    diagonal at ``y0`` (each coordinate relaxes on the time scale of its own stiffness).
    Converged: the residual fell by ``tol`` or the pseudo time step reached Newton's
    regime (d times the stiffness over the mass above 1e12), where a Newton solve
    finishes. ``first_step``: d times the stiffness over the mass at the start;
    ``min_growth``: the least factor d grows by on a step that does not raise the
    residual (SER alone stalls when the first steps hardly change it: a rod lying on an
    obstacle whose load is far from the contact's push)."""
    import scipy.sparse as sp
    import scipy.sparse.linalg as spla

    st.load_scale = 1.0
    y = np.array(y0, dtype=float)
    r = np.empty(st.n_static)
    st.static_residual(y, r)
    J = st.static_jacobian_sparse(y)
    if M is None:
        dg = np.abs(J.diagonal())
        dg[dg == 0.0] = max(float(dg.max(initial=0.0)), 1.0)
        M = sp.diags(dg)
    scale = float(abs(J.diagonal()).max()) / max(float(abs(M.diagonal()).max()), 1e-300)
    d = first_step / scale
    r0 = rn = float(np.linalg.norm(r))
    for _ in range(max_iter):
        if rn <= tol * max(r0, 1e-300):
            return y, True
        J = st.static_jacobian_sparse(y)
        dx = spla.spsolve((J + M / d).tocsc(), -r)
        y_new = st.static_retract(y, dx)
        st.static_residual(y_new, r)
        rn_new = float(np.linalg.norm(r))
        if not np.isfinite(rn_new):
            return y, False
        y = y_new
        grow = min(max(rn / max(rn_new, 1e-300), 0.5), 10.0)
        d *= max(grow, min_growth) if rn_new <= rn else grow
        rn = rn_new
        if d * scale > 1e12:
            return y, True
    return y, False


__all__ = ["pseudo_transient"]
