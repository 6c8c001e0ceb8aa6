"""Rigid motions that a rod's supports leave free, and the gauge that holds them in statics.

A discrete rod whose strains all carry stiffness has exactly the rigid motions of the
whole rod as zero-energy motions (objectivity of V and U). The supports remove some: a
held node (``clamped`` or ``pinned``) its translation and the rotations that move it, a
clamped frame every rotation. What is left is computed from the geometry of the state, not
guessed from the end kinds: the infinitesimal rigid motions ``dphi_i = t + w x (phi_i -
c)``, ``dtheta_j = R_j^T w`` (``R_j`` the segment frames; material rotation increments as
in :mod:`runtime.model.statics`) that keep every held node in place and every clamped frame
fixed. Examples: a pinned-pinned rod of any shape keeps the rotation about the line
through its pins (for a straight rod along that line: the spin about its own axis; for an
arc: the rotation about its chord), a pinned-free rod the three rotations about its pin, a
free-free rod all six motions.

Statics (:meth:`RodStatics.hold_rigid_motions <runtime.model.statics.RodStatics>`):

* the loads must do no work along a free motion (a free-free rod under a net force, a
  horizontal pinned-free rod under gravity): otherwise there is no equilibrium where the
  rod is, and the problem is refused before any work (:class:`runtime.errors.IllPosedError`,
  naming the motion and the key that holds it);
* else the free motions are held by a **gauge**: segment ``m`` (the middle one) keeps its
  rotation, and node ``m`` its position, along the free motions (a penalty on those six
  local coordinates, projected on the free motions, see :class:`StaticGauge`). The gauge
  reacts only to a net load along the free motions, so where that is zero at the
  equilibrium (checked afterwards: :meth:`StaticGauge.reaction`), the gauge changes
  nothing: the equilibrium is that of the rod with the motion held at its reference value
  (a straight pinned-pinned beam under transverse gravity: the same sag as with its spin
  held at a support).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from runtime.errors import IllPosedError
from runtime.model.layout_tables import layout_blocks
from runtime.model.quaternion import quat_mul, quat_rotation

__all__ = ["RigidMotions", "StaticGauge", "check_stiffness", "external_wrench",
           "refuse_loaded_motions", "rigid_motions"]

#: relative size of a load along a free rigid motion that counts as zero
LOAD_RTOL = 1e-8
#: largest strain estimate (load / stiffness) statics attempts: beyond it the equilibrium
#: cannot be resolved in double precision (Newton's increments would lie below the
#: rounding of the positions)
STRAIN_LIMIT = 1.0 / (4.0 * float(np.finfo(float).eps))


def _skew(r: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -r[2], r[1]], [r[2], 0.0, -r[0]], [-r[1], r[0], 0.0]])


def _fmt(v: np.ndarray) -> str:
    return "[" + ", ".join(f"{x:.4g}" for x in np.asarray(v, dtype=float)) + "]"


@dataclass(frozen=True)
class RigidMotions:
    """The free rigid motions of a rod at a state.

    basis : (n_static, k) increments in the static layout (positions in m, material
        rotation increments in rad) of k independent rigid motions (their twists are
        orthonormal in the scaled coordinates ``(t, w L)``); zero at held nodes.
    twist : (6, k) their translation t (m) and rotation w (rad) about ``centre``.
    centre : (3,) the point the rotations are taken about (m): the held node if one is
        held, else the centroid of the nodes.
    what : the motions in words, e.g. "the rotation about the line through the pinned
        ends (the spin about the rod's own axis)".
    hold : the problem key that holds them, e.g. ``start.kind = "clamped"``.
    """

    basis: np.ndarray
    twist: np.ndarray
    centre: np.ndarray
    what: str
    hold: str

    @property
    def k(self) -> int:
        """Number of free rigid motions."""
        return int(self.basis.shape[1])

    @property
    def axis(self) -> np.ndarray | None:
        """Unit axis of the free rotation when exactly one rotation is free, else None."""
        w = self.twist[3:]
        if self.k != 1 or not np.any(w):
            return None
        return w[:, 0] / np.linalg.norm(w[:, 0])


def _null_space(C: np.ndarray, rtol: float = 1e-9) -> np.ndarray:
    """Orthonormal basis (6, k) of the null space of C (m, 6), built deterministically:
    the unit vectors e_0..e_5 projected on the null space and orthonormalised in that
    order (an SVD's basis of a repeated singular value depends on the LAPACK build)."""
    if C.shape[0] == 0:
        return np.eye(6)
    _, s, Vt = np.linalg.svd(C)
    rank = int(np.sum(s > rtol * max(float(s[0]), 1.0)))
    Nul = Vt[rank:].T
    if Nul.shape[1] == 0:
        return Nul
    P = Nul @ Nul.T
    out: list[np.ndarray] = []
    for e in np.eye(6):
        v = P @ e
        for u in out:
            v = v - (u @ v) * u
        n = float(np.linalg.norm(v))
        if n > 1e-6:
            out.append(v / n)
        if len(out) == Nul.shape[1]:
            break
    return np.column_stack(out)


def _straight_along(phi: np.ndarray, a: np.ndarray, p: np.ndarray, L: float) -> bool:
    """All nodes on the line through p along a (to 1e-9 L)."""
    d = phi - p
    return bool(np.all(np.linalg.norm(d - np.outer(d @ a, a), axis=1) <= 1e-9 * L))


def rigid_motions(model, y: np.ndarray, static_layout: tuple | None = None) -> RigidMotions:
    """The rigid motions of the rod of ``model`` at state ``y`` that its supports leave
    free (see the module docstring).

    ``static_layout``: (n_static, phi_cols (N+1, 3), theta_cols (N, 3)) of the static
    problem (:class:`~runtime.model.statics.RodStatics`); by default from
    ``generated/rod_layout.py``.
    """
    from generated import rod_layout as RL

    a = model.arrays
    N = model.N
    if static_layout is None:
        phi_cols = layout_blocks(RL.static_phi, 0, N, 3)
        theta_cols = layout_blocks(RL.static_theta, 1, N, 3)
        n_static = RL.n_static(N)
    else:
        n_static, phi_cols, theta_cols = static_layout
    phi = np.asarray(y)[model.phi_index]                       # (N+1, 3)
    R = quat_rotation(np.asarray(y)[model.p_index])             # (N, 3, 3)
    L = float(np.sum(a.seg_field("h")))
    held = [(e, i) for e, i in (("start", 0), ("end", N)) if a.held(e)]
    clamped = [e for e, _ in held if a.clamped(e)]
    c = phi[held[0][1]].copy() if held else phi.mean(axis=0)
    rows = []
    for _, i in held:       # dphi_i = t + w x (phi_i - c) = 0, w scaled by 1/L
        rows.append(np.hstack([np.eye(3), -_skew(phi[i] - c) / L]))
    for _ in clamped:       # the clamp frame: w = 0
        rows.append(np.hstack([np.zeros((3, 3)), np.eye(3)]))
    C = np.vstack(rows) if rows else np.zeros((0, 6))
    U = _null_space(C)                                          # (6, k) in (t, w L)
    k = U.shape[1]
    twist = np.vstack([U[:3], U[3:] / L])                       # (t [m], w [rad])
    basis = np.zeros((n_static, k))
    for j in range(k):
        t, w = twist[:3, j], twist[3:, j]
        basis[phi_cols.ravel(), j] = (t + np.cross(w, phi - c)).ravel()
        basis[theta_cols.ravel(), j] = np.einsum("nij,i->nj", R, w).ravel()
        for _, i in held:   # exactly zero at held nodes (round-off of the projection)
            basis[phi_cols[i], j] = 0.0
    what, hold = _describe(k, held, clamped, phi, twist, c, L)
    return RigidMotions(basis=basis, twist=twist, centre=c, what=what, hold=hold)


#: a rigid motion is held by the obstacles when the contact's stiffness along it exceeds
#: this share of the static Jacobian's largest diagonal entry (the rod's own stiffness
#: vanishes along rigid motions of an unstressed state up to round-off, ~1e-16 of it)
CONTACT_HOLD_RTOL = 1e-9


def restrain_by_contact(J, motions: RigidMotions) -> RigidMotions:
    """The part of ``motions`` that the obstacles leave free: the rigid motions along which
    the static Jacobian ``J`` (n_static x n_static, the contact's stiffness included,
    taken at an unstressed state where the rod's own stiffness vanishes along rigid
    motions) stores no energy. A rod lying on a frictionless table keeps its slides and
    turn on the table and its spin; a rod touching nothing keeps all of them."""
    if motions.k == 0:
        return motions
    B = motions.basis
    G = B.T @ (J @ B)
    G = 0.5 * (G + G.T)
    scale = float(np.max(np.abs(J.diagonal()))) if J.shape[0] else 0.0
    lam, V = np.linalg.eigh(G)
    free = V[:, lam <= CONTACT_HOLD_RTOL * scale]
    if free.shape[1] == motions.k:
        return motions
    k = free.shape[1]
    what = (f"{k} rigid motion{'s' if k != 1 else ''} that the obstacles do not hold "
            f"(of {motions.what}, which its supports leave free)")
    return RigidMotions(basis=B @ free, twist=motions.twist @ free, centre=motions.centre,
                        what=what, hold=motions.hold + " or friction on an obstacle")


def _describe(k: int, held, clamped, phi, twist, c, L) -> tuple[str, str]:
    if k == 0:
        return "none", ""
    if not held:
        return ("its translations and rotations (a free-free rod)",
                'start.kind (or end.kind) = "clamped" or "pinned"')
    if len(held) == 1:
        end, i = held[0]
        return (f"the rotations about its pinned {end} (node {i})", f'{end}.kind = "clamped"')
    if k == 1 and np.any(twist[3:, 0]):
        a = twist[3:, 0] / np.linalg.norm(twist[3:, 0])
        what = "the rotation about the line through its pinned ends"
        if _straight_along(phi, a, c, L):
            what += " (the spin about the rod's own axis)"
        else:
            what += " (its chord)"
        return what, 'start.kind (or end.kind) = "clamped"'
    return (f"{k} rigid motions (both ends pinned at the same point: the rotations about "
            "it)", 'start.kind (or end.kind) = "clamped"')


def external_wrench(st, y: np.ndarray, centre: np.ndarray) -> tuple[np.ndarray, np.ndarray,
                                                                       float, float]:
    """The external loads at load factor 1 on the rod at state ``y``: net force (N), net
    moment about ``centre`` (N m), and their scales (sum of the magnitudes of the nodal
    forces, N; of their moments about ``centre`` plus the segment moments, N m).

    ``st``: a :class:`~runtime.model.statics.RodStatics` inside ``model.statics()``; the
    load is ``-(R(y; 1) - R(y; 0))`` of the rod's momentum rows. A held node's row is its
    prescribed velocity, so loads on held nodes are left out: they go straight into the
    support and do no work along a motion the supports leave free."""
    model = st.model
    saved = model.load_scale
    r1, r0 = np.empty(model.n), np.empty(model.n)
    y0 = st.at_rest(y)
    try:
        t = getattr(st, "time", 0.0)
        st.load_scale = 1.0
        model.residual(t, y0, model._zeros, r1)
        st.load_scale = 0.0
        model.residual(t, y0, model._zeros, r0)
    finally:
        st.load_scale = saved
    d = r0 - r1                                          # the loads (residual = K x - f)
    f = d[model.v_index]                                 # (N+1, 3) spatial forces
    mloc = d[model.omega_index]                          # (N, 3) material torques
    R = quat_rotation(y0[model.p_index])
    m = np.einsum("nij,nj->ni", R, mloc)                 # spatial
    r = y0[model.phi_index] - centre
    F = f.sum(axis=0)
    M = np.cross(r, f).sum(axis=0) + m.sum(axis=0)
    F_scale = float(np.sum(np.linalg.norm(f, axis=1)))
    M_scale = float(np.sum(np.linalg.norm(np.cross(r, f), axis=1))
                    + np.sum(np.linalg.norm(m, axis=1)))
    return F, M, F_scale, M_scale


def refuse_loaded_motions(st, y: np.ndarray, motions: RigidMotions) -> None:
    """IllPosedError when the loads at load factor 1 work along a free rigid motion at
    ``y`` (no equilibrium where the rod is); names the motion, the load and the key that
    holds it."""
    if motions.k == 0:
        return
    F, M, Fs, Ms = external_wrench(st, y, motions.centre)
    L = float(np.sum(st.model.arrays.seg_field("h")))
    scale = Fs + Ms / L
    if not (math.isfinite(scale) and scale > 0):
        return
    t, w = motions.twist[:3], motions.twist[3:]
    # generalised load along each free motion (N for translations, N m / L for rotations)
    g = t.T @ F + w.T @ M
    norms = np.linalg.norm(t, axis=0) + L * np.linalg.norm(w, axis=0)
    if np.all(np.abs(g) <= LOAD_RTOL * scale * norms):
        return
    # the load along the free motions in words
    free_translation = bool(np.any(np.abs(t) > 1e-9))
    if motions.axis is not None:
        load = (f"a moment of {float(M @ motions.axis):.4g} N m about that line (axis "
                f"{_fmt(motions.axis)})")
    elif free_translation and np.linalg.norm(F) > LOAD_RTOL * scale:
        load = f"a net force of {_fmt(F)} N"
    else:
        at = "its pin" if not free_translation else "the centroid"
        load = f"a net moment of {_fmt(M)} N m about {at} at {_fmt(motions.centre)} m"
    raise IllPosedError(
        f"statics: the rod has no equilibrium where it is: its supports leave "
        f"{motions.what} free, and the loads have {load}; hold "
        f"{'it' if motions.k == 1 else 'them'} with {motions.hold} (or balance the loads)",
        key=motions.hold)


def check_stiffness(st, y: np.ndarray) -> None:
    """IllPosedError when the loads at load factor 1 would strain the rod beyond what
    double precision can resolve (load / stiffness above :data:`STRAIN_LIMIT`, or a
    stiffness that is not a normal positive number), e.g. ``youngs_modulus = 1e-300``."""
    model = st.model
    a = model.arrays
    L = float(np.sum(a.seg_field("h")))
    CF = a.seg_field("C_F")
    CM = a.jnt_field("C_M")
    joints = np.ones(model.N + 1, dtype=bool)            # joints 0, N exist at clamps only
    joints[0], joints[-1] = a.clamped("start"), a.clamped("end")
    CM = CM[joints] if np.any(joints) else CM[1:-1]
    F, _, Fs, Ms = external_wrench(st, y, np.asarray(y)[model.phi_index].mean(axis=0))
    load = Fs + Ms / L
    cf = float(np.min(CF)) if CF.size else math.inf
    cm = float(np.min(CM)) if CM.size else math.inf
    tiny = float(np.finfo(float).tiny)
    bad = not (cf > tiny * 1e10 and cm > tiny * 1e10)
    strain = max(load / cf, load * L / cm) if not bad else math.inf
    if load > 0 and (bad or not strain <= STRAIN_LIMIT):
        why = ("below the normal range of doubles" if bad else
               f"they would strain it by ~{strain:.3g}, beyond {STRAIN_LIMIT:.2g}")
        raise IllPosedError(
            f"statics: the rod is too soft for its loads to be solved in double precision: "
            f"E A, G A >= {cf:.3g} N and E I, G J >= {cm:.3g} N m^2 against loads of "
            f"{load:.3g} N ({why}); check material.youngs_modulus (its units) and the "
            "loads", key="material.youngs_modulus")


class StaticGauge:
    """Holds the free rigid motions in statics (see the module docstring).

    Segment ``m`` and node ``m`` (the middle of the rod) carry a penalty
    ``f = K_g x`` on their six local coordinates ``x`` = (rotation vector of
    ``conj(p_ref) p`` (material, rad), ``phi - phi_ref`` (m)), with
    ``K_g = S^1/2 Q Q^T S^1/2``, Q an orthonormal basis of ``S^1/2 B``, B the free motions
    restricted to those coordinates and S the static Jacobian's diagonal there (the local
    stiffness, so the penalty is as stiff as the rod). K_g vanishes on the directions no
    rigid motion uses, so it holds exactly the free motions. At an equilibrium of the
    penalised rod, ``z^T f = -z^T (load)`` for every free motion z: the penalty's force
    (:meth:`reaction`) is the net load along the free motions, and where that is zero the
    equilibrium is the rod's own, with the motions at their reference values (to the
    solver's tolerance).
    """

    def __init__(self, st, y_ref: np.ndarray, motions: RigidMotions, diag: np.ndarray
                 ) -> None:
        model = st.model
        N = model.N
        self.motions = motions
        self.segment = m = (N + 1) // 2                       # segment m (1..N), node m
        self.cols = np.r_[st.theta_cols[m - 1], st.phi_cols[m]]
        B = motions.basis[self.cols]                          # (6, k)
        if m == N and model.arrays.held("end"):               # N = 1: node m is held
            B[3:] = 0.0
        s = np.abs(np.asarray(diag, dtype=float)[self.cols])
        s = np.where(s > 0, s, max(float(np.max(s)), 1.0))
        r = np.sqrt(s)
        Q, _ = np.linalg.qr(r[:, None] * B)
        self.K = (r[:, None] * Q) @ (Q.T * r[None, :])
        self.K = 0.5 * (self.K + self.K.T)
        self.p_ref = np.array(y_ref[model.p_index[m - 1]], dtype=float)
        self.p_ref /= np.linalg.norm(self.p_ref)
        self.phi_ref = np.array(y_ref[model.phi_index[m]], dtype=float)
        self._p_index, self._phi_index = model.p_index[m - 1], model.phi_index[m]

    def coordinates(self, y: np.ndarray) -> np.ndarray:
        """The six local coordinates x (rad, m) of state y."""
        p = np.asarray(y)[self._p_index]
        q = quat_mul(self.p_ref * np.array([1.0, -1.0, -1.0, -1.0]), p / np.linalg.norm(p))
        if q[0] < 0:
            q = -q
        v = q[1:]
        s = float(np.linalg.norm(v))
        rot = (2.0 * math.atan2(s, q[0]) / s) * v if s > 1e-12 else 2.0 * v
        return np.r_[rot, np.asarray(y)[self._phi_index] - self.phi_ref]

    def force(self, y: np.ndarray) -> np.ndarray:
        """The penalty's generalised force K_g x (N m material, then N), (6,)."""
        return self.K @ self.coordinates(y)

    def reaction(self, st, y: np.ndarray) -> tuple[float, float, float, float]:
        """(|moment| N m, |force| N, moment scale, force scale) the gauge exerts at y,
        against the scales of the loads (:func:`external_wrench`)."""
        f = self.force(y)
        R = quat_rotation(np.asarray(y)[self._p_index])
        _, _, Fs, Ms = external_wrench(st, y, self.motions.centre)
        return (float(np.linalg.norm(R @ f[:3])), float(np.linalg.norm(f[3:])), Ms, Fs)

    def doubt(self, st, y: np.ndarray, rtol: float = 1e-6) -> str | None:
        """None when the gauge's reaction at the equilibrium y is negligible (below
        ``rtol`` of the loads' force and moment scales), else why the gauge changed the
        answer: the deformed rod's loads turn it along a free motion (for example a beam
        whose sag leaves the plane through its pins), so it has no equilibrium with that
        motion at its reference value."""
        mom, force, Ms, Fs = self.reaction(st, y)
        if mom <= rtol * max(Ms, 1e-300) and force <= rtol * max(Fs, 1e-300):
            return None
        return (f"the loads on the deformed rod act along {self.motions.what}, which its "
                f"supports leave free (the gauge holding them reacts with a moment of "
                f"{mom:.3g} N m and a force of {force:.3g} N, against loads of {Ms:.3g} N m "
                f"and {Fs:.3g} N): no equilibrium with them at their reference; hold them "
                f"with {self.motions.hold}")

    def describe(self) -> str:
        """The gauge in words (for the static summary)."""
        return (f"{self.motions.what} held at its reference by a gauge at segment "
                f"{self.segment} and node {self.segment}; the gauge's reaction vanishes at "
                "the equilibrium (checked), so it changes nothing")
