"""Damped modes of an assembly of rods about an equilibrium (issue 31).

The assembly's residual linearised in the reduced coordinates of its statics
(:class:`~runtime.model.system_statics.SystemStatics`: node displacements and segment
rotation increments, a tied node moving with its master, supports fixed):
``M q'' + C q' + K q = 0`` with M from the momentum rows' y'-derivative, C from their
velocity derivative and K from their position/rotation derivative (the loads of statics
at the equilibrium included: a hanging pendulum's gravity stiffness is in K). The
eigenvalues are those of the first-order pencil ``[[I, 0], [0, M]] x' = [[0, I], [-K,
-C]] x``: all of them by LAPACK (QZ) up to ``DENSE_MAX`` unknowns, else the lowest undamped
modes by shift-invert Lanczos and the damped ones from the pencil projected on them
(Rayleigh-Ritz: exact for proportional damping, close for light damping).

Each mode reports its undamped frequency omega (rad/s, from ``K phi = omega^2 M phi``),
the damped pair and damping ratio, and how its kinetic energy splits over the rods.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from runtime.model.system import SystemModel
from runtime.model.system_statics import SystemStatics

#: largest reduced system solved whole by QZ (unknowns q; the pencil has twice as many)
DENSE_MAX = 1500


@dataclass
class AssemblyMode:
    """One mode: ``omega`` (rad/s, undamped), ``eigenvalue`` (1/s, damped, Im >= 0),
    ``zeta`` (damping ratio), ``rods``: the fraction of the mode's kinetic energy in each
    rod (name: fraction); ``shape``: the mass-normalised reduced shape (nq,)."""

    index: int
    omega: float
    eigenvalue: complex
    zeta: float
    rods: dict[str, float] = field(default_factory=dict)
    shape: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False)

    @property
    def frequency_hz(self) -> float:
        return self.omega / (2.0 * math.pi)

    def to_dict(self) -> dict:
        lam = self.eigenvalue
        return {"index": self.index, "omega": self.omega, "frequency_hz": self.frequency_hz,
                "zeta": None if math.isnan(self.zeta) else self.zeta,
                "eigenvalue": [float(lam.real), float(lam.imag)],
                "kinetic_energy_fractions": self.rods}


def linear_matrices(model: SystemModel, y_eq: np.ndarray, t: float = 0.0):
    """(M, C, K, statics) of the assembly linearised at the equilibrium ``y_eq``, in the
    reduced coordinates of :class:`SystemStatics` (sparse CSC)."""
    import scipy.sparse as sp

    st = SystemStatics(model, t)
    y0 = model.constrain(np.array(y_eq, dtype=float))
    y0[model.velocity_mask] = 0.0
    zero = np.zeros(model.n)
    Fy = model.dF_dy_sparse(t, y0, zero).tocsr()
    Fp = model.dF_dyp_sparse(t, y0, zero).tocsr()
    rows = st.static_rows
    T = st.tangent(y0).tocsc()
    # velocities: the same map as positions (a tied node's velocity is its master's),
    # angular velocities directly in the rotation increments' columns
    vr, vc = [], []
    for (r, i), c in st._phi_col.items():
        vr += list(model.v_index[r][i])
        vc += [c, c + 1, c + 2]
    for (r, i), master in st._tied.items():
        if master in st._phi_col:
            c = st._phi_col[master]
            vr += list(model.v_index[r][i])
            vc += [c, c + 1, c + 2]
    om = np.concatenate([o.ravel() for o in model.omega_index])
    vr += list(om)
    vc += list((st._theta_cols[:, None] + np.arange(3)).ravel())
    S = sp.csc_matrix((np.ones(len(vr)), (vr, vc)), shape=(model.n, st.n_static))
    Fm, Pm = Fy[rows], Fp[rows]
    M = (Pm @ S).tocsc()
    C = (Fm @ S).tocsc()
    K = (Fm @ T).tocsc()
    return M, C, K, st


def assembly_modes(model: SystemModel, y_eq: np.ndarray, count: int = 10,
                   t: float = 0.0) -> list[AssemblyMode]:
    """The ``count`` lowest modes of the assembly about the equilibrium ``y_eq`` (see the
    module docstring). Use inside ``with model.statics(t)``: the loads there are those the
    equilibrium carries."""
    import scipy.linalg as sla

    if count < 1:
        raise ValueError(f"count = {count}: at least one mode")
    M, C, K, st = linear_matrices(model, y_eq, t)
    nq = M.shape[0]
    if nq <= DENSE_MAX:
        Md, Cd, Kd = M.toarray(), C.toarray(), K.toarray()
        w2, Phi = sla.eig(Kd, Md)
        w2 = np.real(w2)
        order = np.argsort(np.where(np.isfinite(w2), w2, np.inf))
        E = np.block([[np.eye(nq), np.zeros((nq, nq))], [np.zeros((nq, nq)), Md]])
        A = np.block([[np.zeros((nq, nq)), np.eye(nq)], [-Kd, -Cd]])
        lam, X = sla.eig(A, E)
    else:
        import scipy.sparse.linalg as spla

        k = min(2 * count + 4, nq - 2)
        shift = -1e-6 * float(abs(K.diagonal()).max())   # below the rigid modes' 0
        w2, Phi = spla.eigs(K, k=k, M=M, sigma=shift)
        order = np.argsort(np.real(w2))
        w2, Phi = np.real(w2[order]), np.real(Phi[:, order])
        Mr, Cr, Kr = (np.asarray(Phi.T @ (X @ Phi)) for X in (M, C, K))
        m = Mr.shape[0]
        E = np.block([[np.eye(m), np.zeros((m, m))], [np.zeros((m, m)), Mr]])
        A = np.block([[np.zeros((m, m)), np.eye(m)], [-Kr, -Cr]])
        lam, Xr = sla.eig(A, E)
        X = np.vstack([Phi @ Xr[:m], Phi @ Xr[m:]])
        order = np.arange(w2.size)
    lam = np.asarray(lam)
    ok = np.isfinite(lam)
    lam, X = lam[ok], X[:, ok]
    modes: list[AssemblyMode] = []
    used = np.zeros(lam.size, dtype=bool)
    Mcsr = M.tocsr()
    rod_of_dof = _rod_of_dof(model, st)
    for k, j in enumerate(order[:count]):
        omega = math.sqrt(max(float(w2[j]), 0.0))
        phi = np.real(Phi[:, j]) if Phi.ndim == 2 else np.zeros(nq)
        nrm = float(phi @ (Mcsr @ phi))
        if nrm > 0:
            phi = phi / math.sqrt(nrm)
        # the damped eigenvalue whose eigenvector projects most on this mode
        q = X[:nq]
        score = np.abs(phi @ (Mcsr @ q)) / (np.linalg.norm(q, axis=0) + 1e-300)
        score[used | (lam.imag < -1e-12 * np.abs(lam))] = -1.0
        i = int(np.argmax(score))
        used[i] = True
        li = complex(lam[i])
        if omega == 0.0:
            zeta = math.nan
        elif abs(li.imag) > 1e-12 * abs(li):
            zeta = -li.real / abs(li)
        else:
            # overdamped: the pair of real roots with lambda1 lambda2 = omega^2 and
            # lambda1 + lambda2 = -2 zeta omega; its partner is the other real root that
            # projects most on this mode
            score[i] = -1.0
            real = np.abs(lam.imag) <= 1e-12 * np.abs(lam)
            score[~real] = -1.0
            i2 = int(np.argmax(score))
            if score[i2] > 0:
                used[i2] = True
                zeta = -(li.real + float(lam[i2].real)) / (2.0 * omega)
            else:
                zeta = -li.real / omega
        ke = phi * (Mcsr @ phi)
        frac = {}
        total = float(np.sum(ke)) or 1.0
        for r, name in enumerate(model.names):
            frac[name] = float(np.sum(ke[rod_of_dof == r]) / total)
        modes.append(AssemblyMode(k + 1, omega, li, zeta, frac, phi))
    return modes


def _rod_of_dof(model: SystemModel, st: SystemStatics) -> np.ndarray:
    """The rod of every reduced unknown (for the energy split)."""
    out = np.zeros(st.n_static, dtype=int)
    for (r, _i), c in st._phi_col.items():
        out[c:c + 3] = r
    k = 0
    for r, rod in enumerate(model.rods):
        for _ in range(rod.N):
            c = st._theta_cols[k]
            out[c:c + 3] = r
            k += 1
    return out
