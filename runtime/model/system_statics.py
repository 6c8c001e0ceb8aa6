"""The static problem of an assembly of rods in reduced coordinates (for
:func:`runtime.solvers.statics.solve_static` and the modal analysis).

Unknowns: each rod's node positions ``dphi`` (m) and segment rotation increments
``dtheta`` (rad, material, ``p <- p exp(dtheta/2)``), as for a single rod
(:class:`~runtime.model.statics.RodStatics`); a held node (a rod's own held end, a
support, a node tied to another) has no unknowns of its own: a support's position is
fixed, a tied node moves with its master (its positions follow the master's columns).
Rows: the force balance of every free node (a master's with its slaves' forces: the
system's residual adds them) and the torque balance of every segment, at rest. The
Jacobian is sparse (the joints couple rods anywhere) and factored by SuperLU.

Rigid motions that the supports leave free are refused by name before any work (a single
rod holds them by a gauge; an assembly's are not analysed: its joints may make any rod
part of a mechanism).
"""

from __future__ import annotations

import numpy as np

from runtime.errors import IllPosedError
from runtime.model.quaternion import quat_exp, quat_mul
from runtime.model.statics import _half_L
from runtime.model.system import SystemModel


class _SparseLU:
    """SuperLU factors with the ``info``/``solve`` face of ``BandLU``."""

    def __init__(self, A) -> None:
        import scipy.sparse.linalg as spla

        try:
            self._lu = spla.splu(A.tocsc())
            self.info = 0
        except RuntimeError:            # exactly singular
            self._lu, self.info = None, 1

    def solve(self, b: np.ndarray) -> np.ndarray:
        if self._lu is None:
            raise ValueError("the static Jacobian is singular")
        return self._lu.solve(np.asarray(b, dtype=float))


class _Gauge:
    """A penalty ``K_g Z Z^T d`` on the reduced displacement d from the gauge's state
    along the orthonormal free motions Z (see :meth:`SystemStatics.hold_rigid_motions`);
    K_g the static stiffness's mean singular value scale, so it neither dominates nor
    vanishes in the factorisation."""

    def __init__(self, st: SystemStatics, y0: np.ndarray, Z: np.ndarray, k: float) -> None:
        self.st, self.y0, self.Z, self.k = st, np.array(y0, dtype=float), Z, k

    def force(self, y: np.ndarray) -> np.ndarray:
        d = self.st.reduced_difference(y, self.y0)
        return self.k * (self.Z @ (self.Z.T @ d))

    def stiffness(self):
        import scipy.sparse as sp

        return sp.csc_matrix(self.k * (self.Z @ self.Z.T))

    def describe(self) -> str:
        return (f"{self.Z.shape[1]} rigid motion(s) the supports leave free and the loads "
                "do not move are held where they start (a penalty projected on them)")


class SystemStatics:
    """:class:`~runtime.solvers.protocols.StaticProblem` of a :class:`SystemModel` (see the
    module docstring). Use inside ``with model.statics(time):``."""

    def __init__(self, model: SystemModel, time: float = 0.0) -> None:
        self.model = m = model
        self.time = float(time)
        held = {(k, i) for k, r in enumerate(m.rods) for i in r.held_nodes}
        self._tied = {(h.rod, h.node): h.master for h in m.holds if h.master is not None}
        held |= {(h.rod, h.node) for h in m.holds}
        cols, rows = [], []
        phi_col: dict[tuple[int, int], int] = {}
        theta_cols = []
        k = 0
        for r, rod in enumerate(m.rods):
            for i in range(rod.N + 1):
                if (r, i) not in held:
                    phi_col[(r, i)] = k
                    cols.append(("phi", r, i))
                    rows += list(m.v_index[r][i])
                    k += 3
            for s in range(rod.N):
                theta_cols.append(k)
                rows += list(m.omega_index[r][s])
                k += 3
        self.n_static = k
        self.kl_static = self.ku_static = 0
        self.static_rows = np.array(rows, dtype=int)
        self._phi_col = phi_col
        self._theta_cols = np.array(theta_cols, dtype=int)
        self._p_index = np.concatenate([p for p in m.p_index])
        # the positions each static column moves: a free node's, and its slaves' with it
        pr, pc = [], []
        for (r, i), c in phi_col.items():
            pr += list(m.phi_index[r][i])
            pc += [c, c + 1, c + 2]
        for (r, i), master in self._tied.items():
            mr, mi = master
            if (mr, mi) in phi_col:
                c = phi_col[(mr, mi)]
                pr += list(m.phi_index[r][i])
                pc += [c, c + 1, c + 2]
        self._pos_rows, self._pos_cols = np.array(pr, dtype=int), np.array(pc, dtype=int)
        self.constrain = None          # the retraction keeps the holds
        self.gauge = None

    @property
    def load_scale(self) -> float:
        return self.model.load_scale

    @load_scale.setter
    def load_scale(self, value: float) -> None:
        self.model.load_scale = value
        self.model.at(self.time)

    def at_rest(self, y: np.ndarray) -> np.ndarray:
        y0 = np.array(y, dtype=float)
        y0[self.model.velocity_mask] = 0.0
        return y0

    #: a singular value of the unloaded static stiffness below this fraction of the
    #: largest is a rigid motion the supports leave free
    RIGID_RTOL = 1e-9
    #: largest reduced problem whose free motions are found (dense SVD)
    RIGID_DENSE_MAX = 4000

    def hold_rigid_motions(self, y: np.ndarray) -> float:
        """Check that statics from ``y`` is well posed and hold the rigid motions that
        neither supports nor loads resist. Returns the load factor Newton starts from.

        The unloaded static stiffness at ``y``: regular, statics starts unloaded (0, as a
        rod's). Else its null space Z (the free rigid motions; dense SVD): the part along
        which the loads do no work is held by a gauge (a penalty on the reduced
        displacement from ``y`` projected on it, ``K_g Z Z^T``; it reacts only to a net
        load along those motions, which there is none of: the spin of a beam on pins
        about their line); a motion the loads work along (a pendulum not hanging
        straight, a mechanism the loads move) is left to the loaded problem: the
        stiffness under the full load must then be regular (1: Newton starts loaded) or
        the caller must first move the mechanism (``pseudo_transient``). Raises
        :class:`~runtime.errors.IllPosedError` (before any work) when the problem is too
        large for the analysis and singular."""
        self.gauge = None
        saved = self.load_scale
        try:
            self.load_scale = 0.0
            J0 = self.static_jacobian_sparse(y)
            if _SparseLU(J0).info == 0:
                return 0.0
            if self.n_static > self.RIGID_DENSE_MAX:
                raise IllPosedError(
                    f"statics of this assembly: its supports leave a rigid motion free (the "
                    f"static stiffness is singular; the free motions of {self.n_static} "
                    "unknowns are not analysed); hold it with a joint to \"ground\" or a "
                    "clamped or pinned end, or simulate it (simulation.initial = "
                    "\"reference\")")
            Jd = J0.toarray()
            _, sv, vt = np.linalg.svd(Jd)
            Z = vt[sv <= self.RIGID_RTOL * sv[0]].T                 # (n_static, k)
            r0, r1 = np.empty(self.n_static), np.empty(self.n_static)
            self.static_residual(y, r0)
            self.load_scale = 1.0
            self.static_residual(y, r1)
            f = r1 - r0
            c = Z.T @ f
            free = Z
            if np.linalg.norm(c) > 1e-9 * max(np.linalg.norm(f), 1e-300):
                u = Z @ (c / np.linalg.norm(c))                        # the loaded motion
                free = Z - np.outer(u, u @ Z)
                q, rr, _ = np.linalg.svd(free, full_matrices=False)
                free = q[:, rr > 1e-8]
            if free.shape[1]:
                self.gauge = _Gauge(self, y, free, float(sv[0]) / self.n_static)
            if free.shape[1] == Z.shape[1]:
                return 0.0
            if self.static_factor(y).info == 0:       # at the full load, with the gauge
                return 1.0
        finally:
            self.load_scale = saved
        raise IllPosedError(
            "statics of this assembly: its loads act along a rigid motion its supports "
            "leave free and do not hold it where it starts (a mechanism out of its "
            "equilibrium); hold it with a joint to \"ground\" or a clamped or pinned end, "
            "or simulate it (simulation.initial = \"reference\")")

    def static_residual(self, y: np.ndarray, out: np.ndarray) -> None:
        m = self.model
        r = np.empty(m.n)
        m.residual(self.time, self.at_rest(y), m._zeros, r)
        out[:] = r[self.static_rows]
        if self.gauge is not None:
            out += self.gauge.force(y)

    def reduced_difference(self, y: np.ndarray, y0: np.ndarray) -> np.ndarray:
        """The reduced coordinates of y relative to y0 (n_static,): the free nodes'
        displacements, the segments' rotation vectors (material, 2 Im(conj(p0) p)/|.|)."""
        m = self.model
        dx = np.zeros(self.n_static)
        for (r, i), c in self._phi_col.items():
            ix = m.phi_index[r][i]
            dx[c:c + 3] = y[ix] - y0[ix]
        p, p0 = y[self._p_index], y0[self._p_index]
        rel = quat_mul(p0 * np.array([1.0, -1.0, -1.0, -1.0]), p)
        rel /= (np.linalg.norm(p, axis=1) * np.linalg.norm(p0, axis=1))[:, None]
        dx[self._theta_cols[:, None] + np.arange(3)] = 2.0 * rel[:, 1:]
        return dx

    def tangent(self, y: np.ndarray):
        """T (n x n_static): dy = T dx (positions, slaves with their masters; rotations
        1/2 L(p) [0; I])."""
        import scipy.sparse as sp

        m = self.model
        Lm = _half_L(y[self._p_index])                      # (Nt, 4, 3)
        ns = self._theta_cols.size
        rows_p = np.broadcast_to(self._p_index[:, :, None], (ns, 4, 3))
        cols_p = np.broadcast_to(self._theta_cols[:, None, None] + np.arange(3), (ns, 4, 3))
        rows = np.concatenate([self._pos_rows, rows_p.ravel()])
        cols = np.concatenate([self._pos_cols, cols_p.ravel()])
        vals = np.concatenate([np.ones(self._pos_rows.size), Lm.ravel()])
        return sp.csc_matrix((vals, (rows, cols)), shape=(m.n, self.n_static))

    def static_jacobian_sparse(self, y: np.ndarray):
        m = self.model
        y0 = self.at_rest(y)
        Jd = m.jacobian_sparse(self.time, y0, m._zeros, 1.0, 0.0).tocsr()[self.static_rows]
        return (Jd @ self.tangent(y0)).tocsc()

    def static_factor(self, y: np.ndarray) -> _SparseLU:
        """The factors of the static Jacobian at y (``solve_static`` uses them), the
        gauge's stiffness included."""
        J = self.static_jacobian_sparse(y)
        if self.gauge is not None:
            J = J + self.gauge.stiffness()
        return _SparseLU(J)

    def static_jacobian_band(self, y, out_ab) -> None:
        raise NotImplementedError("an assembly's static Jacobian is sparse (static_factor)")

    def static_retract(self, y: np.ndarray, dx: np.ndarray) -> np.ndarray:
        """phi += dphi (slaves with their masters), p <- p exp(dtheta/2) renormalised."""
        m = self.model
        y1 = np.array(y, dtype=float)
        dx = np.asarray(dx)
        np.add.at(y1, self._pos_rows, dx[self._pos_cols])
        th = dx[self._theta_cols[:, None] + np.arange(3)]
        p = quat_mul(y1[self._p_index], quat_exp(th))
        y1[self._p_index] = p / np.linalg.norm(p, axis=1)[:, None]
        return m.constrain(y1)

