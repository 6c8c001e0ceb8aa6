"""Static 3-D Simo-Reissner (Cosserat) rod boundary-value problems, solved by shooting.

Independent reference for kvrod's static solutions (written from scratch, NumPy/SciPy only).

Unknowns along the reference arclength ``s`` in ``[0, L]`` (m):

- ``r(s)``: centerline position (m);
- ``R(s) = [d1 d2 d3]``: rotation from the material (director) frame to the spatial frame,
  carried as a unit quaternion ``q = (w, x, y, z)`` (``R(q)`` maps director components to
  spatial components; ``d3`` is the section normal);
- ``n(s)``, ``m(s)``: internal force (N) and moment (N m), spatial components, exerted by
  the part ``(s, L]`` on the part ``[0, s]``.

Material law in the director frame, with ``N = R^T n``, ``M = R^T m``::

    N = C_F (Gamma - Gamma0),   C_F = diag(GA1, GA2, EA)
    M = C_M (K - K0),           C_M = diag(EI1, EI2, GJ)

``Gamma0`` (default ``(0, 0, 1)``) and ``K0`` (intrinsic curvature and twist, default 0)
may be constants or functions of ``s``; ``GA1``, ``GA2``, ``EA`` may be ``math.inf``
(unshearable / inextensible: ``Gamma = Gamma0``). ``EI1`` is the bending stiffness about
``d1`` (deflection along ``d2``), ``GA1`` the shear stiffness along ``d1``.

Kinematics and balance (no distributed couples)::

    r' = R Gamma,              R' = R [K]x     (q' = q (0, K) / 2)
    n' + lambda f = 0,         m' + r' x n = 0

with a constant dead distributed force ``f`` per unit reference length (N/m, e.g.
``rho A g``) and optional dead point forces ``P_k`` at interior stations ``s_k``, where the
force resultant jumps: ``n(s_k+) = n(s_k-) - P_k``. ``lambda`` is the load factor of the
continuation.

Boundary conditions: clamped at ``s = 0`` (``r = r0``, ``R = R0``) and at ``s = L`` either

- ``end="free"``: dead force and moment, ``n(L) = F``, ``m(L) = M``; or
- ``end="clamped"``: ``r(L) = r_ref(L) + u_L`` and ``R(L) = exp([theta_L]x) R_ref(L)``, where
  ``r_ref``, ``R_ref`` is the unloaded (intrinsic) configuration and ``u_L``, ``theta_L`` a
  prescribed end displacement and rotation vector (default 0: both ends held in place).

Method: single shooting on the six base resultants ``(n(0), m(0))`` with
:func:`scipy.integrate.solve_ivp` (DOP853, rtol 1e-12 by default) and Newton's method on
the six end conditions (forces scaled by the load scale ``F_s``, moments by ``F_s L``,
positions by ``L``, rotations in rad). The Jacobian is a forward-difference one; all
perturbed copies are integrated as one batched system so they share the adaptive steps,
which makes the differences smooth (internal numerical differentiation); a column whose
response is lost in round-off gets a larger step. The unloaded reference configuration is
copy 0 of the same batch, and the integrator carries the other copies as *differences*
from it, with the error control applied to the differences: displacements ``r - r_ref``
are then accurate relative to their own size (about 1e-12 at rtol 1e-12, down to a
round-off floor of about 1e-15 L), which the small-load linear checks need. Loads (and
prescribed end motion) are applied by continuation from zero with a secant predictor, so
the solution branch connected to the unloaded state is followed. A straight rod clamped
at both ends with ``EA = inf`` has an indeterminate axial force and is rejected (singular
Jacobian).

Also accumulated along ``s``: the elastic energy ``W = 1/2 int (N . C_F^-1 N + M . C_M^-1 M)``
and, for dead forces only, the total potential ``W - (F . u(L) + int f . u + sum P_k . u(s_k))``
whose derivative with respect to a load amplitude is minus the conjugate displacement (a
dead end moment is not conservative in 3-D, so no potential is reported when ``M != 0``).
SI units throughout.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp
from scipy.spatial.transform import Rotation

__all__ = [
    "RodSolution",
    "RodStiffness",
    "quat_to_matrix",
    "solve_rod",
]

Vec = Sequence[float] | np.ndarray
VecField = Vec | Callable[[float], Vec]

# state layout of one copy: r(3) q(4) n(3) m(3) W(1) Phi(1), Phi = int f . r ds
_D = 15
_R, _Q, _N, _M, _W, _PHI = slice(0, 3), slice(3, 7), slice(7, 10), slice(10, 13), 13, 14


@dataclass(frozen=True)
class RodStiffness:
    """Diagonal section stiffnesses: ``C_F = diag(GA1, GA2, EA)`` (N) and
    ``C_M = diag(EI1, EI2, GJ)`` (N m^2). ``GA1``, ``GA2``, ``EA`` may be ``math.inf``."""

    GA1: float
    GA2: float
    EA: float
    EI1: float
    EI2: float
    GJ: float

    def __post_init__(self) -> None:
        for name in ("GA1", "GA2", "EA"):
            if not getattr(self, name) > 0:
                raise ValueError(f"{name} must be positive (inf allowed)")
        for name in ("EI1", "EI2", "GJ"):
            v = getattr(self, name)
            if not (v > 0 and math.isfinite(v)):
                raise ValueError(f"{name} must be positive and finite, got {v!r}")

    @classmethod
    def from_section(cls, section, E: float, G: float) -> RodStiffness:
        """From a :class:`references.sections.Section` and moduli ``E``, ``G`` (Pa)."""
        return cls(*section.stiffnesses(E, G))

    @classmethod
    def isotropic(
        cls, *, EA: float, GA: float, EI: float, GJ: float
    ) -> RodStiffness:
        """Equal shear and bending stiffnesses in both directions."""
        return cls(GA, GA, EA, EI, EI, GJ)

    def compliances(self) -> tuple[np.ndarray, np.ndarray]:
        """``(1/GA1, 1/GA2, 1/EA)`` and ``(1/EI1, 1/EI2, 1/GJ)``; ``1/inf = 0``."""
        cF = 1.0 / np.array([self.GA1, self.GA2, self.EA], dtype=float)
        cM = 1.0 / np.array([self.EI1, self.EI2, self.GJ], dtype=float)
        return cF, cM


@dataclass(frozen=True)
class RodSolution:
    """Equilibrium of the rod. Arrays are sampled on ``s`` (m, shape ``(n,)``).

    ``r``, ``r_ref`` (n, 3): deformed and unloaded centerline (m); ``displacement = r - r_ref``
    (same integration steps, so the common integration error cancels); ``R``, ``R_ref``
    (n, 3, 3): director frames; ``n``, ``m`` (n, 3): spatial resultants (N, N m);
    ``Gamma``, ``K`` (n, 3): strains and curvatures in the director frame (1, 1/m).
    ``base_force = n(0)``, ``base_moment = m(0)``; ``elastic_energy`` (J); ``potential``
    (J, NaN if a dead end moment acts); ``residual``: norm of the scaled end conditions;
    ``newton_iterations``: total over the continuation.
    """

    s: np.ndarray
    r: np.ndarray
    R: np.ndarray
    n: np.ndarray
    m: np.ndarray
    Gamma: np.ndarray
    K: np.ndarray
    r_ref: np.ndarray
    R_ref: np.ndarray
    displacement: np.ndarray
    base_force: np.ndarray
    base_moment: np.ndarray
    elastic_energy: float
    potential: float
    residual: float
    newton_iterations: int

    @property
    def tip(self) -> np.ndarray:
        """Deformed end position ``r(L)`` (m)."""
        return self.r[-1]

    @property
    def tip_displacement(self) -> np.ndarray:
        """``r(L) - r_ref(L)`` (m)."""
        return self.displacement[-1]

    @property
    def tip_rotation(self) -> np.ndarray:
        """Rotation vector (rad) of ``R(L) R_ref(L)^T``: the end's rotation from the
        unloaded state, spatial components."""
        return Rotation.from_matrix(self.R[-1] @ self.R_ref[-1].T).as_rotvec()


def quat_to_matrix(q: np.ndarray) -> np.ndarray:
    """Rotation matrices of quaternions ``q = (w, x, y, z)`` (normalized here).

    ``q`` has shape ``(4, ...)``; the result has shape ``(3, 3, ...)``::

        R = [[1 - 2(y^2 + z^2), 2(xy - wz),       2(xz + wy)      ],
             [2(xy + wz),       1 - 2(x^2 + z^2), 2(yz - wx)      ],
             [2(xz - wy),       2(yz + wx),       1 - 2(x^2 + y^2)]]
    """
    q = np.asarray(q, dtype=float)
    w, x, y, z = q * (np.sqrt(2.0) / np.sqrt(np.sum(q * q, axis=0)))  # sqrt(2) q / |q|
    xx, yy, zz = x * x, y * y, z * z
    xy, xz, yz, wx, wy, wz = x * y, x * z, y * z, w * x, w * y, w * z
    R = np.empty((3, 3) + q.shape[1:])
    R[0, 0] = 1.0 - yy - zz
    R[0, 1] = xy - wz
    R[0, 2] = xz + wy
    R[1, 0] = xy + wz
    R[1, 1] = 1.0 - xx - zz
    R[1, 2] = yz - wx
    R[2, 0] = xz - wy
    R[2, 1] = yz + wx
    R[2, 2] = 1.0 - xx - yy
    return R


def _quat_tensors() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Constant tensors for the batched right-hand side.

    ``T``: ``|q|^2 R(q) = T_ijab q_a q_b``, from ``|q|^2 R = (w^2 - v.v) I + 2 v v^T + 2 w [v]x``
    (``q = (w, v)``); ``P``: ``(q (0, K) / 2)_a = P_abc q_b K_c``, from
    ``q (0, K) = (-v . K, w K + v x K)``; ``eps``: the Levi-Civita symbol.
    """
    eps = np.zeros((3, 3, 3))
    for i, j, k in ((0, 1, 2), (1, 2, 0), (2, 0, 1)):
        eps[i, j, k], eps[i, k, j] = 1.0, -1.0
    eye3 = np.eye(3)
    T = np.zeros((3, 3, 4, 4))
    T[:, :, 0, 0] = eye3
    for a in range(3):
        T[:, :, a + 1, a + 1] -= eye3
        for b in range(3):
            T[a, b, a + 1, b + 1] += 2.0
        # 2 w [v]x: ([v]x)_ij = -eps_ijk v_k, split symmetrically between (0, k) and (k, 0)
        T[:, :, 0, a + 1] -= eps[:, :, a]
        T[:, :, a + 1, 0] -= eps[:, :, a]
    P = np.zeros((4, 4, 3))
    for c in range(3):
        P[0, c + 1, c] = -0.5
        P[c + 1, 0, c] = 0.5
        P[1:, 1:, c] = 0.5 * eps[:, :, c]  # (v x K)_a = eps_abc v_b K_c
    return T, P, eps


def _matrix_to_quat(R: np.ndarray) -> np.ndarray:
    x, y, z, w = Rotation.from_matrix(R).as_quat()  # scipy: scalar last
    return np.array([w, x, y, z])


def _field(v: VecField, name: str) -> Callable[[float], np.ndarray]:
    if callable(v):
        return lambda s: np.asarray(v(s), dtype=float).reshape(3)
    a = np.asarray(v, dtype=float).reshape(3)
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name} must be finite, got {a!r}")
    return lambda s: a


_T_ROT, _T_QK, _EPS = _quat_tensors()
_FLOOR = 1e-11  # scaled residual below which Newton only polishes


class _Shooter:
    """Batched integration of ``k`` copies of the rod ODE (state ``(15, k)``)."""

    def __init__(
        self,
        L: float,
        stiffness: RodStiffness,
        r0: np.ndarray,
        R0: np.ndarray,
        K0: Callable[[float], np.ndarray],
        Gamma0: Callable[[float], np.ndarray],
        f: np.ndarray,
        point_forces: list[tuple[float, np.ndarray]],
        F_s: float,
        rtol: float,
    ) -> None:
        self.L = L
        self.cF, self.cM = stiffness.compliances()
        self.r0, self.q0 = r0, _matrix_to_quat(R0)
        self.K0, self.Gamma0 = K0, Gamma0
        self.f = f
        self.point_forces = point_forces
        self.F_s = F_s
        self.rtol = rtol
        scales = np.ones(_D)
        scales[_R] = L
        scales[_N] = F_s
        scales[_M] = F_s * L
        scales[_W] = F_s * L
        scales[_PHI] = max(float(np.linalg.norm(f)), 1e-300) * L * L
        # absolute tolerances: 1e-3 rtol of the scales, but not below the round-off of the
        # differences f(y_0 + d) - f(y_0) (about 1e-16 of the scales), which would make the
        # error estimate noise and the steps collapse
        self.atol = max(1e-3 * rtol, 1e-15) * scales

    def rhs(self, s: float, zflat: np.ndarray, lam: np.ndarray) -> np.ndarray:
        """Right-hand side in difference form: copy 0 and the differences of the others."""
        Z = zflat.reshape(_D, -1)
        F = self.f_states(s, _undiff(Z), lam)
        F[:, 1:] -= F[:, :1]
        return F.reshape(-1)

    def f_states(self, s: float, y: np.ndarray, lam: np.ndarray) -> np.ndarray:
        """Right-hand side of the states ``y`` (15, k) of all copies (a few NumPy calls on
        whole batches: the batches are small, so the call overhead dominates)."""
        q = y[_Q]
        nm = y[_N.start : _M.stop].reshape(2, 3, -1)  # (n, m)
        k = q.shape[1]
        qq = (q[:, None, :] * q[None, :, :]).reshape(16, k)
        R = (_T_ROT.reshape(9, 16) @ qq).reshape(3, 3, k) / np.einsum("ak,ak->k", q, q)
        NM = np.einsum("jik,cjk->cik", R, nm)  # (N, M) in the director frame
        G = self.Gamma0(s)[:, None] + self.cF[:, None] * NM[0]
        K = self.K0(s)[:, None] + self.cM[:, None] * NM[1]
        rp = np.einsum("ijk,jk->ik", R, G)
        dy = np.empty_like(y)
        dy[_R] = rp
        dy[_Q] = _T_QK.reshape(4, 12) @ (q[:, None, :] * K[None, :, :]).reshape(12, k)
        dy[_N] = -self.f[:, None] * lam[None, :]
        dy[_M] = -np.einsum("ijk,jb,kb->ib", _EPS, rp, nm[0])
        dy[_W] = 0.5 * (self.cF @ (NM[0] * NM[0]) + self.cM @ (NM[1] * NM[1]))
        dy[_PHI] = self.f @ y[_R]
        return dy

    def initial(self, x: np.ndarray) -> np.ndarray:
        """Initial states of copies with scaled base resultants ``x`` (6, k)."""
        k = x.shape[1]
        Y = np.zeros((_D, k))
        Y[_R] = self.r0[:, None]
        Y[_Q] = self.q0[:, None]
        Y[_N] = x[:3] * self.F_s
        Y[_M] = x[3:] * self.F_s * self.L
        return Y

    def integrate(self, x: np.ndarray, lam: np.ndarray, s_eval: np.ndarray | None = None):
        """Integrate copies from ``s = 0`` to ``L``; returns the end states ``(15, k)``, the
        states just before each point force and, if ``s_eval`` is given, the samples
        ``(15, k, len(s_eval))`` (a sample at a station takes the left limit).

        Copy 0 must be the unloaded reference (``x = 0``, ``lam = 0``). The integrator
        carries copy 0 and the *differences* of the other copies from it, with the
        tolerances applied to the differences, so displacements are accurate relative to
        their own size down to the round-off floor (about 1e-15 L).
        """
        Y = self.initial(x)
        k = Y.shape[1]
        Z = Y.copy()
        Z[:, 1:] -= Z[:, :1]
        atol = np.repeat(self.atol, k)
        stations = [s for s, _ in self.point_forces] + [self.L]
        samples = None if s_eval is None else np.empty((_D, k, len(s_eval)))
        at_forces = []
        a = 0.0
        for i, b in enumerate(stations):
            sol = solve_ivp(
                self.rhs,
                (a, b),
                Z.reshape(-1),
                method="DOP853",
                rtol=self.rtol,
                atol=atol,
                args=(lam,),
                dense_output=s_eval is not None,
            )
            if sol.status != 0:  # pragma: no cover - integrator failure
                raise RuntimeError(f"solve_ivp failed: {sol.message}")
            Z = sol.y[:, -1].reshape(_D, k).copy()
            if s_eval is not None:
                sel = (s_eval >= a) & (s_eval <= b) if i == 0 else (s_eval > a) & (s_eval <= b)
                if np.any(sel):
                    samples[:, :, sel] = _undiff(sol.sol(s_eval[sel]).reshape(_D, k, -1))
                    samples[:, :, s_eval == b] = _undiff(Z)[:, :, None]
            if i < len(self.point_forces):
                at_forces.append(_undiff(Z))
                P = self.point_forces[i][1][:, None]
                Z[_N, :1] -= P * lam[None, :1]
                Z[_N, 1:] -= P * (lam[None, 1:] - lam[None, :1])
            a = b
        return _undiff(Z), at_forces, samples


def _undiff(Z: np.ndarray) -> np.ndarray:
    """States of all copies from copy 0 and the differences (axis 1 indexes copies)."""
    Y = Z.copy()
    Y[:, 1:] += Z[:, :1]
    return Y


def _rotvec(Rm: np.ndarray) -> np.ndarray:
    return Rotation.from_matrix(Rm).as_rotvec()


def solve_rod(
    L: float,
    stiffness: RodStiffness,
    *,
    r0: Vec = (0.0, 0.0, 0.0),
    R0: np.ndarray | None = None,
    K0: VecField = (0.0, 0.0, 0.0),
    Gamma0: VecField = (0.0, 0.0, 1.0),
    end: str = "free",
    tip_force: Vec = (0.0, 0.0, 0.0),
    tip_moment: Vec = (0.0, 0.0, 0.0),
    distributed_force: Vec = (0.0, 0.0, 0.0),
    point_forces: Sequence[tuple[float, Vec]] = (),
    end_displacement: Vec = (0.0, 0.0, 0.0),
    end_rotation: Vec = (0.0, 0.0, 0.0),
    load_steps: int | Sequence[float] = 10,
    guess: Vec | None = None,
    rtol: float = 1e-12,
    res_tol: float = 1e-15,
    max_newton: int = 40,
    fd_step: float = 1e-7,
    n_points: int = 201,
) -> RodSolution:
    """Equilibrium of a clamped rod under dead loads, by shooting (see the module docstring).

    L: reference length (m). stiffness: :class:`RodStiffness`. r0, R0: clamp position (m)
    and director frame (columns ``d1, d2, d3``; default identity, i.e. the rod starts along
    ``e3``). K0, Gamma0: intrinsic curvature/twist (1/m) and strain (constants or
    functions of ``s``). end: ``"free"`` (dead ``tip_force`` in N and ``tip_moment`` in N m
    at ``s = L``) or ``"clamped"`` (``end_displacement`` in m and ``end_rotation``, a
    rotation vector in rad, relative to the unloaded end). distributed_force: dead force per
    unit reference length (N/m); point_forces: dead ``(s_k, P_k)`` with ``0 < s_k < L``.
    load_steps: number of equal continuation steps, or the increasing load factors (ending
    at 1). guess: scaled base resultants ``(n(0)/F_s, m(0)/(F_s L))`` used as the predictor
    of the first step (the load scale ``F_s`` is the largest of ``|F|``, ``|M|/L``,
    ``|f| L`` and ``|P_k|``, or ``max(EI, GJ)/L^2`` without loads). rtol: integrator
    tolerance. Newton stops when the scaled residual is below res_tol, or when it no longer
    decreases (or only slowly) below 1e-11, i.e. at the round-off floor of the shooting;
    it fails above 1e-9. n_points: samples of the result.
    """
    if not (L > 0 and math.isfinite(L)):
        raise ValueError(f"L must be positive and finite, got {L!r}")
    if end not in ("free", "clamped"):
        raise ValueError(f"end must be 'free' or 'clamped', got {end!r}")
    R0 = np.eye(3) if R0 is None else np.asarray(R0, dtype=float)
    if not np.allclose(R0.T @ R0, np.eye(3), atol=1e-12) or np.linalg.det(R0) < 0:
        raise ValueError("R0 must be a rotation matrix")
    F = np.asarray(tip_force, dtype=float).reshape(3)
    M = np.asarray(tip_moment, dtype=float).reshape(3)
    f = np.asarray(distributed_force, dtype=float).reshape(3)
    pf = sorted(((float(s), np.asarray(P, dtype=float).reshape(3)) for s, P in point_forces),
                key=lambda t: t[0])
    if any(not 0.0 < s < L for s, _ in pf):
        raise ValueError("point forces must act at 0 < s < L")
    uL = np.asarray(end_displacement, dtype=float).reshape(3)
    thL = np.asarray(end_rotation, dtype=float).reshape(3)
    if end == "free" and (np.any(uL) or np.any(thL)):
        raise ValueError("end_displacement/end_rotation need end='clamped'")
    if end == "clamped" and (np.any(F) or np.any(M)):
        raise ValueError("tip_force/tip_moment need end='free'")

    load_scale = max(
        float(np.linalg.norm(F)),
        float(np.linalg.norm(M)) / L,
        float(np.linalg.norm(f)) * L,
        max((float(np.linalg.norm(P)) for _, P in pf), default=0.0),
    )
    F_s = load_scale if load_scale > 0 else max(
        stiffness.EI1, stiffness.EI2, stiffness.GJ) / L**2
    sh = _Shooter(L, stiffness, np.asarray(r0, dtype=float).reshape(3), R0,
                  _field(K0, "K0"), _field(Gamma0, "Gamma0"), f, pf, F_s, rtol)

    def residuals(Y: np.ndarray, lam: float) -> np.ndarray:
        """Scaled end conditions of copies 1.. (copy 0 is the unloaded reference)."""
        ref, Yc = Y[:, :1], Y[:, 1:]
        if end == "free":
            rn = (Yc[_N] - lam * F[:, None]) / F_s
            rm = (Yc[_M] - lam * M[:, None]) / (F_s * L)
            return np.vstack([rn, rm])
        ru = (Yc[_R] - ref[_R] - lam * uL[:, None]) / L
        Rref = quat_to_matrix(ref[_Q])[:, :, 0]
        Rt = Rotation.from_rotvec(lam * thL).as_matrix() @ Rref
        Rc = quat_to_matrix(Yc[_Q])
        rr = np.stack([_rotvec(Rt.T @ Rc[:, :, j]) for j in range(Yc.shape[1])], axis=1)
        return np.vstack([ru, rr])

    def shoot(xs: np.ndarray, lam: float) -> np.ndarray:
        k = xs.shape[1]
        x_all = np.hstack([np.zeros((6, 1)), xs])
        lam_all = np.r_[0.0, np.full(k, lam)]
        Y, _, _ = sh.integrate(x_all, lam_all)
        return residuals(Y, lam)

    h_mul = np.ones(6)  # per-unknown enlargement of the difference step (kept across calls)

    def res_and_jac(x: np.ndarray, lam: float) -> tuple[np.ndarray, np.ndarray]:
        """Residual and forward-difference Jacobian. A column whose response is too small to
        be resolved against round-off (e.g. the axial force of a stiff straight rod under a
        tiny load) is recomputed with a larger step aiming at a response of 1e-7: the
        response, not the step, measures the nonlinearity, so this stays accurate."""
        while True:
            h = fd_step * np.maximum(1.0, np.abs(x)) * h_mul
            xs = np.hstack([x[:, None], x[:, None] + np.diag(h)])
            res = shoot(xs, lam)
            dres = res[:, 1:] - res[:, :1]
            resp = np.linalg.norm(dres, axis=0)
            grow = (resp < 1e-9) & (h_mul < 1e12)
            if not np.any(grow):
                break
            h_mul[grow] *= np.minimum(1e12 / h_mul[grow],
                                      1e-7 / np.maximum(resp[grow], 1e-7 / 1e6))
        if np.any(resp == 0.0):
            raise RuntimeError(
                "singular shooting Jacobian: the end conditions do not determine the base "
                "resultants (e.g. an inextensible straight rod clamped at both ends)"
            )
        return res[:, 0], dres / h[None, :]

    if isinstance(load_steps, int):
        if load_steps < 1:
            raise ValueError(f"load_steps must be >= 1, got {load_steps!r}")
        lams = [j / load_steps for j in range(1, load_steps + 1)]
    else:
        lams = [float(v) for v in load_steps]
        if not lams or lams[-1] != 1.0 or any(b <= a for a, b in zip([0.0] + lams, lams,
                                                                         strict=False)):
            raise ValueError("load factors must increase and end at 1")

    x_prev, lam_prev = np.zeros(6), 0.0
    x = np.zeros(6) if guess is None else np.asarray(guess, dtype=float).reshape(6)
    x_prev2, lam_prev2 = None, None
    total_it = 0
    res_norm = math.inf
    for i, lam in enumerate(lams):
        if i > 0 or guess is None:
            if x_prev2 is None:
                x = x_prev.copy()
            else:  # secant predictor
                x = x_prev + (x_prev - x_prev2) * (lam - lam_prev) / (lam_prev - lam_prev2)
        res, J = res_and_jac(x, lam)
        res_norm = float(np.linalg.norm(res))
        for _ in range(max_newton):
            if res_norm <= res_tol:
                break
            total_it += 1
            dx = np.linalg.solve(J, -res)
            t = 1.0
            while True:  # backtracking, unless already near the round-off floor
                res_new, J_new = res_and_jac(x + t * dx, lam)
                new_norm = float(np.linalg.norm(res_new))
                if new_norm < res_norm or t < 1.0 / 64 or res_norm < _FLOOR:
                    break
                t *= 0.5
            if new_norm >= res_norm:  # no descent: the residual is at its noise floor
                break
            slow = new_norm > 0.25 * res_norm
            x, res, J, res_norm = x + t * dx, res_new, J_new, new_norm
            if slow and res_norm < _FLOOR:  # linear convergence at the floor: done
                break
        if res_norm > 1e-9:
            raise RuntimeError(
                f"Newton did not converge at load factor {lam}: residual {res_norm:.3e}"
            )
        x_prev2, lam_prev2, x_prev, lam_prev = x_prev, lam_prev, x.copy(), lam

    # final dense pass: reference copy and solution share the steps
    s = np.linspace(0.0, L, n_points)
    Y, at_forces, S = sh.integrate(np.hstack([np.zeros((6, 1)), x[:, None]]),
                                   np.array([0.0, 1.0]), s_eval=s)
    res_norm = float(np.linalg.norm(residuals(Y, 1.0)))
    ref, sol = S[:, 0, :], S[:, 1, :]
    r, r_ref = sol[_R].T, ref[_R].T
    R = np.moveaxis(quat_to_matrix(sol[_Q]), -1, 0)
    R_ref = np.moveaxis(quat_to_matrix(ref[_Q]), -1, 0)
    n, m = sol[_N].T, sol[_M].T
    cF, cM = stiffness.compliances()
    Nm = np.einsum("kji,kj->ki", R, n)
    Mm = np.einsum("kji,kj->ki", R, m)
    Gamma = np.array([sh.Gamma0(si) for si in s]) + cF * Nm
    Kc = np.array([sh.K0(si) for si in s]) + cM * Mm
    W = float(Y[_W, 1])
    if np.any(M):
        potential = math.nan
    else:
        work = float(F @ (Y[_R, 1] - Y[_R, 0])) + float(Y[_PHI, 1] - Y[_PHI, 0])
        for (_, P), Yk in zip(pf, at_forces, strict=True):
            work += float(P @ (Yk[_R, 1] - Yk[_R, 0]))
        potential = W - work
    return RodSolution(
        s=s,
        r=r,
        R=R,
        n=n,
        m=m,
        Gamma=Gamma,
        K=Kc,
        r_ref=r_ref,
        R_ref=R_ref,
        displacement=r - r_ref,
        base_force=x[:3] * F_s,
        base_moment=x[3:] * F_s * L,
        elastic_energy=W,
        potential=potential,
        residual=res_norm,
        newton_iterations=total_it,
    )
