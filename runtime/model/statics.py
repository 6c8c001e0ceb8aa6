"""The rod's static problem in reduced coordinates (for :func:`runtime.solvers.statics.
solve_static` and the modal analysis).

Unknowns per cell (``generated/rod_layout.py``): node positions ``dphi`` (m) and segment
rotation increments ``dtheta`` (rad, material, ``p <- p exp(dtheta/2)``); rows: the force
balance of every node and the torque balance of every segment at rest. A held node's rows
and unknowns are replaced by identities (its position is prescribed: :meth:`constrain`).
Loads are evaluated as in statics (:meth:`RodModel.statics`: at ``t = 0-``, the load factor
also scaling prescribed end motion). Rigid motions the supports leave free (a pinned-pinned
rod's spin, a free-free rod) are held by a gauge (:meth:`RodStatics.hold_rigid_motions`,
:mod:`runtime.model.rigid`).
"""

from __future__ import annotations

import ctypes
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    import scipy.sparse as sp

from generated import rod_layout as L
from runtime.errors import GeneratedCodeError
from runtime.model.layout_tables import layout_blocks
from runtime.model.rigid import (
    StaticGauge,
    check_stiffness,
    refuse_loaded_motions,
    restrain_by_contact,
    rigid_motions,
)
from runtime.model.rod import RodModel
from runtime.solvers.native.pointers import function_address
from runtime.solvers.native.static_core import NativeStatics, StaticLayout


def largest_displacement(model: RodModel, y: np.ndarray) -> dict:
    """The node that moved most from the reference: {"node": i, "s": arc length (m),
    "position": phi_i (m), "displacement": phi_i - phi_ref (m), "magnitude": (m)} (for a
    rod held at both ends, where the "tip" is a support)."""
    d = y[model.phi_index] - model.reference[model.phi_index]
    mag = np.linalg.norm(d, axis=1)
    i = int(np.argmax(mag))
    s = float(np.sum(model.arrays.seg_field("h")[:i, 0]))
    return {"node": i, "s": s, "position": [float(v) for v in y[model.phi_index[i]]],
            "displacement": [float(v) for v in d[i]], "magnitude": float(mag[i])}


def _half_L(p: np.ndarray) -> np.ndarray:
    """dp/dtheta = 1/2 L(p) [0; I] per segment, (N, 4, 3), for quaternions p (N, 4)
    (``p <- p*exp(dtheta/2)``): the rotation block of :meth:`RodStatics.tangent`."""
    p0, q = p[:, 0], p[:, 1:]
    qx = np.zeros((p.shape[0], 3, 3))                          # [q]x, (N, 3, 3)
    qx[:, 0, 1], qx[:, 0, 2] = -q[:, 2], q[:, 1]
    qx[:, 1, 0], qx[:, 1, 2] = q[:, 2], -q[:, 0]
    qx[:, 2, 0], qx[:, 2, 1] = -q[:, 1], q[:, 0]
    Lm = np.empty((p.shape[0], 4, 3))
    Lm[:, 0, :] = -q
    Lm[:, 1:, :] = p0[:, None, None] * np.eye(3) + qx
    return 0.5 * Lm


class RodStatics:
    """:class:`~runtime.solvers.protocols.StaticProblem` of a :class:`RodModel`.

    Use inside ``with model.statics(time):`` so that loads and ends are driven as in
    statics (at ``time-``, 0 by default).
    """

    def __init__(self, model: RodModel, time: float = 0.0) -> None:
        self.model = m = model
        #: the time (s) whose loads and end positions statics sees (at ``time-``; 0: the
        #: loads before a run, a later time: the equilibrium a released rod settles to)
        self.time = float(time)
        N = self.N = m.N
        self.n_static = L.n_static(N)
        self.kl_static, self.ku_static = ((L.COUPLED_STATIC_KL, L.COUPLED_STATIC_KU)
                                          if m.coupled else (L.STATIC_KL, L.STATIC_KU))
        # node 0's force rows, then per cell i segment i's torques and node i's forces
        self.static_rows = np.concatenate(
            [m.v_index[0], np.hstack([m.omega_index, m.v_index[1:]]).ravel()])
        self.phi_cols = layout_blocks(L.static_phi, 0, N, 3)
        self.theta_cols = layout_blocks(L.static_theta, 1, N, 3)
        fixed = []
        for end, i in (("start", 0), ("end", N)):
            if m.arrays.held(end):
                fixed += list(self.phi_cols[i])
        self.fixed_cols = np.array(fixed, dtype=int)
        self._fixed_matrix = None     # built on first use (scipy.sparse imports slowly)
        self._rowmask = np.ones(self.n_static, dtype=bool)
        self._rowmask[self.fixed_cols] = False
        self._plan: tuple[np.ndarray, ...] | None = None   # static_jacobian_band's gather
        # flat index tables of the Newton loop's gathers (static_retract, the Jacobian's
        # rotation weights) and buffers reused by every call: a fresh array per call
        # misses the model's pointer cache (~3 us each) and the fancy 2-D indices cost
        # more than the arithmetic at a few elements (issue 33: the tiny sweep point)
        self._phi_flat, self._phi_cols_flat = m.phi_index.ravel(), self.phi_cols.ravel()
        self._theta_flat = self.theta_cols.ravel()
        self._y0 = np.empty(m.n)
        self._r = np.empty(m.n)
        self._weights: np.ndarray | None = None
        self._weight_src: np.ndarray | None = None
        self._weight_sign: np.ndarray | None = None
        # the rod's band Jacobian, kept between Newton iterations (a fresh one costs its
        # page faults: 1.4 MB for the Maxwell cantilever, every iteration)
        self._ab: np.ndarray | None = None
        # solve_static moves held nodes to their targets when the load factor changes;
        # only needed when an end moves (a fixed end stays where the reference put it)
        moving = bool(getattr(m.drive, "moving_ends", False))
        self.constrain = self._constrain if moving else None
        #: the gauge holding free rigid motions (:meth:`hold_rigid_motions`), or None
        self.gauge: StaticGauge | None = None
        self._native = None      # NativeStatics, or False where there is none
        if m.self_contact is not None:
            # self-contact couples segments far apart: the static Jacobian is not banded,
            # solve_static factorises it sparse (static_factor)
            self.static_factor = self._static_factor_sparse
        elif self._native_core() is not None:
            # the band path's Jacobian, LU and solves in C (statics.c): the same bits
            self.static_factor = self._static_factor_native

    def _native_core(self):
        """The Newton iteration's model work in C (:mod:`runtime.solvers.native.static_core`:
        residual, gathered band Jacobian and its LU, retraction; the same arithmetic as
        the NumPy methods below, bit for bit), or None: the CasADi backend, self-contact,
        no compiled helpers."""
        if self._native is None:
            self._native = False
            m = self.model
            if m._lib is None or m.self_contact is not None:
                return None
            if self._plan is None:
                self._plan = self._gather_plan()
            self._half_L_weights(m.reference)          # the weight tables
            src, widx, dst, _ = self._plan
            layout = StaticLayout(
                n=m.n, ns=self.n_static, kl=self.kl_static, ku=self.ku_static, ldab=m.ldab,
                velocities=np.flatnonzero(m.velocity_mask), rows=self.static_rows,
                fixed=self.fixed_cols, plan=(src, widx, dst), weight_src=self._weight_src,
                weight_sign=self._weight_sign, phi=self._phi_flat,
                phi_cols=self._phi_cols_flat, p_index=m.p_index, theta=self._theta_flat)

            jac, ctx, keep = m._lib.kvrod_jacobian_band, m._struct, m
            if m.branches and not m.coupled:
                # the static band reads no row or column of the internal strains: their
                # branch kernels need not run and their columns not be cleared
                # (kvrod_jacobian_band_relaxed on a copy of the rod's struct that marks
                # none of them; the same entries elsewhere, bit for bit)
                from runtime.model.arrays import RodStruct

                need = np.full(m.n, 3, np.uint8)
                need[np.ravel(m.q_segment_index)] = 0
                need[np.ravel(m.q_joint_index)] = 0
                ctx = RodStruct.from_buffer_copy(m._struct)
                ctx.relax_need = need.ctypes.data
                jac, keep = m._lib.kvrod_jacobian_band_relaxed, (m, ctx, need)
            core = NativeStatics.build(layout, self.time,
                                       function_address(m._lib.kvrod_residual),
                                       function_address(jac), ctypes.addressof(ctx),
                                       keep=keep)
            self._native = core if core is not None else False
        return self._native or None

    def _static_factor_native(self, y: np.ndarray):
        """LU of the static band Jacobian at y (gauge included) in C, with the ``info`` /
        ``solve`` face of ``BandLU``: valid until the next call."""
        core = self._native
        m = self.model
        m._time(self.time)
        rc = core.jacobian(np.ascontiguousarray(y, dtype=float))
        if rc:
            raise GeneratedCodeError(f"kvrod_jacobian_band failed (code {rc})")
        self._add_gauge_stiffness(core.band)
        return core.factor()

    def static_newton_trial(self, y: np.ndarray, res: np.ndarray):
        """One full Newton trial from y in one compiled call, where there is a native core
        and no gauge (else None: the caller goes step by step): ``(factor, dx, y_try)``
        with dx = -J(y)^-1 res (res: the residual at y), y_try = y retracted by dx, and
        ``res`` <- the residual at y_try; what :meth:`static_factor`, its ``solve``,
        :meth:`static_retract` and :meth:`static_residual` give, the same bits. ``factor``
        (``info``, ``solve``) is valid until the next factorisation; ``factor.info != 0``
        (J singular) or a dx that is not finite leave y_try None."""
        core = self._native
        if not core or self.gauge is not None:
            return None
        self.model._time(self.time)
        code, aux, lu, dx, y_try = core.trial(np.ascontiguousarray(y, dtype=float), res, res)
        if code in (1, 4):
            what = "kvrod_jacobian_band" if code == 1 else "kvrod_residual"
            raise GeneratedCodeError(f"{what} failed (code {aux})")
        return lu, dx, (y_try if code == 0 else None)

    def _add_gauge_stiffness(self, ab: np.ndarray) -> None:
        """The gauge's stiffness into a static band (LAPACK storage), if there is one."""
        if self.gauge is not None:
            c, kl, ku = self.gauge.cols, self.kl_static, self.ku_static
            ab[kl + ku + c[:, None] - c[None, :], c[None, :]] += self.gauge.K

    def _static_factor_sparse(self, y: np.ndarray):
        """SuperLU factors of :meth:`jacobian_csr` (fixed columns and gauge included)
        with the ``info``/``solve`` face of ``BandLU`` (self-contact only)."""
        from runtime.model.system_statics import _SparseLU

        return _SparseLU(self.jacobian_csr(y))

    def rigid_motions(self, y: np.ndarray):
        """The rigid motions the supports leave free at state y
        (:func:`runtime.model.rigid.rigid_motions`), in this problem's layout."""
        return rigid_motions(self.model, y, (self.n_static, self.phi_cols, self.theta_cols))

    def hold_rigid_motions(self, y: np.ndarray) -> StaticGauge | None:
        """Check that statics from ``y`` is well posed and hold the free rigid motions.

        Call inside ``with model.statics():`` before solving. Raises
        :class:`~runtime.errors.IllPosedError` (before any work) when the loads at load
        factor 1 are beyond what double precision resolves on this rod's stiffness, or do
        work along a free rigid motion (no equilibrium where the rod is); otherwise sets
        and returns :attr:`gauge` (None when the supports leave nothing free)."""
        self.gauge = None
        check_stiffness(self, y)
        motions = self.rigid_motions(y)
        if motions.k and self.model.contact is not None:
            saved = self.load_scale
            try:                # the obstacles' full stiffness (statics scales it)
                self.load_scale = 1.0
                J = self.jacobian_csr(y)
            finally:
                self.load_scale = saved
            motions = restrain_by_contact(J, motions)
        if motions.k == 0:
            return None
        refuse_loaded_motions(self, y, motions)
        ab = np.zeros((2 * self.kl_static + self.ku_static + 1, self.n_static), order="F")
        self.static_jacobian_band(y, ab)
        self.gauge = StaticGauge(self, y, motions, ab[self.kl_static + self.ku_static])
        return self.gauge

    @property
    def load_scale(self) -> float:
        return self.model.load_scale

    @load_scale.setter
    def load_scale(self, value: float) -> None:
        self.model.load_scale = value
        self.model.at(self.time)

    def at_rest(self, y: np.ndarray) -> np.ndarray:
        """y with every velocity zero (copy)."""
        y0 = np.array(y, dtype=float)
        y0[self.model.velocity_mask] = 0.0
        return y0

    def _at_rest_buffer(self, y: np.ndarray) -> np.ndarray:
        """:meth:`at_rest` into a buffer of this problem's (overwritten by the next call)."""
        y0 = self._y0
        y0[:] = y
        y0[self.model.velocity_mask] = 0.0
        return y0

    def _constrain(self, y: np.ndarray) -> np.ndarray:
        """Held nodes at their prescribed positions at the current load factor, at rest."""
        return self.at_rest(self.model.constrain(y))

    def static_residual(self, y: np.ndarray, out: np.ndarray) -> None:
        """Force/torque balance at rest (n_static,): node 0 forces, then per cell i the
        segment i torques (material) and node i forces; zero on held nodes."""
        m = self.model
        core = self._native
        if core:
            m._time(self.time)
            rc = core.residual(np.ascontiguousarray(y, dtype=float), out)
            if rc:
                raise GeneratedCodeError(f"kvrod_residual failed (code {rc})")
        else:
            r = self._r
            m.residual(self.time, self._at_rest_buffer(y), m._zeros, r)
            out[:] = r[self.static_rows]
            out[self.fixed_cols] = 0.0
        if self.gauge is not None:
            out[self.gauge.cols] += self.gauge.force(y)

    def jacobian_csr(self, y: np.ndarray) -> sp.csr_matrix:
        import scipy.sparse as sp

        m = self.model
        y0 = self.at_rest(y)
        ab = np.zeros((m.ldab, m.n), order="F")
        m.jacobian_band2(self.time, y0, m._zeros, 1.0, 0.0, ab)
        Jd = m.band_to_csc(ab, m.kl, m.ku)
        if m.self_contact is not None:      # the pairs' entries between their segments
            Jd = Jd + m._self_couplings(self.time, y0)
        Jd = Jd.tocsr()[self.static_rows]
        J = (Jd @ self.tangent(y0)).tocsr()
        keep = sp.diags(self._rowmask.astype(float))
        if self._fixed_matrix is None:
            f = self.fixed_cols
            self._fixed_matrix = sp.csr_matrix((np.ones(f.size), (f, f)),
                                               shape=(self.n_static, self.n_static))
        out = (keep @ J).tocsr() + self._fixed_matrix
        if self.gauge is not None:
            c = self.gauge.cols
            r, q = np.meshgrid(c, c, indexing="ij")
            out = out + sp.csr_matrix((self.gauge.K.ravel(), (r.ravel(), q.ravel())),
                                      shape=out.shape)
        return out.tocsr()

    def tangent(self, y: np.ndarray) -> sp.csc_matrix:
        """T (n x n_static): dy = T dx; dphi -> phi (identity), dtheta -> dp = 1/2 L(p) [0; I]."""
        import scipy.sparse as sp

        m, N = self.model, self.N
        Lm = _half_L(y[m.p_index])
        rows_p = np.broadcast_to(m.p_index[:, :, None], (N, 4, 3))
        cols_p = np.broadcast_to(self.theta_cols[:, None, :], (N, 4, 3))
        rows = np.concatenate([m.phi_index.ravel(), rows_p.ravel()])
        cols = np.concatenate([self.phi_cols.ravel(), cols_p.ravel()])
        vals = np.concatenate([np.ones(m.phi_index.size), Lm.ravel()])
        return sp.csc_matrix((vals, (rows, cols)), shape=(m.n, self.n_static))

    def static_jacobian_sparse(self, y: np.ndarray) -> sp.csc_matrix:
        """d(static residual)/d(dphi, dtheta) at dx = 0 (CSC)."""
        return self.jacobian_csr(y).tocsc()

    def _gather_plan(self) -> tuple[np.ndarray, ...]:
        """Where each entry of the static band comes from: J_s = S J T (S: the static rows,
        T: :meth:`tangent`, identity on positions, 1/2 L(p) on rotations), entry by entry.
        Per contribution: the flat index into the full band (F order), the index of its
        weight in ``[1, Lm.ravel()...]`` and the flat index into the static band; plus the
        identity entries of held nodes. Built once; NumPy only (why not scipy.sparse
        products, as :meth:`jacobian_csr`: its import alone costs 0.1 s of every run)."""
        m, N = self.model, self.N
        kl, ku, ldab = m.kl, m.ku, m.ldab
        kls, kus = self.kl_static, self.ku_static
        ld_s = 2 * kls + kus + 1
        row_s = np.full(m.n, -1)
        row_s[self.static_rows] = np.arange(self.n_static)
        row_s[self.static_rows[~self._rowmask]] = -1          # held rows: identities
        # (full column, static column, weight index) of T's entries
        cols = [(m.phi_index.ravel(), self.phi_cols.ravel(), np.zeros(m.phi_index.size, int))]
        b, a = np.meshgrid(np.arange(4), np.arange(3), indexing="ij")   # Lm[i, b, a]
        b, a = b.ravel(), a.ravel()
        cols.append((m.p_index[:, b].ravel(), self.theta_cols[:, a].ravel(),
                     (1 + 12 * np.arange(N)[:, None] + 3 * b + a).ravel()))
        j, cs, w = (np.concatenate(x) for x in zip(*cols, strict=True))
        offs = np.arange(-ku, kl + 1)                           # rows r = j + off
        r = j[:, None] + offs
        ok = (r >= 0) & (r < m.n)
        r = np.where(ok, r, 0)
        rs = row_s[r]
        ok &= rs >= 0
        jj, cc, ww = (np.broadcast_to(x[:, None], r.shape)[ok] for x in (j, cs, w))
        r, rs = r[ok], rs[ok]
        dband = kls + kus + rs - cc
        # the full band's stored entries beyond the static band are structural zeros of
        # J_s (kvrod's stencil; tests/runtime/test_statics_band.py compares with the
        # sparse product on random states)
        inside = (dband >= kls) & (dband < ld_s)
        r, jj, cc, ww, dband = r[inside], jj[inside], cc[inside], ww[inside], dband[inside]
        src = (kl + ku + r - jj) + jj * ldab
        dst = dband + cc * ld_s
        f = self.fixed_cols
        return src, ww, dst, (kls + kus) + f * ld_s

    def static_jacobian_band(self, y: np.ndarray, out_ab: np.ndarray) -> None:
        """Static Jacobian in LAPACK band storage (2 kl_static + ku_static + 1, n_static):
        the band of :meth:`jacobian_csr`, gathered from the rod's band Jacobian."""
        kl, ku = self.kl_static, self.ku_static
        if out_ab.shape != (2 * kl + ku + 1, self.n_static):
            raise TypeError(f"out_ab must have shape {(2 * kl + ku + 1, self.n_static)}")
        if self._plan is None:
            self._plan = self._gather_plan()
        src, widx, dst, fixed = self._plan
        m = self.model
        y0 = self._at_rest_buffer(y)
        if self._ab is None:
            self._ab = np.zeros((m.ldab, m.n), order="F")
        ab = self._ab                      # (jacobian_band2 writes all of J's band)
        m.jacobian_band2(self.time, y0, m._zeros, 1.0, 0.0, ab)
        weights = self._half_L_weights(y0)
        vals = ab.ravel(order="F")[src] * weights[widx]
        flat = np.bincount(dst, weights=vals, minlength=out_ab.size)
        flat[fixed] += 1.0
        out_ab[:] = flat.reshape(out_ab.shape, order="F")
        self._add_gauge_stiffness(out_ab)

    def _half_L_weights(self, y0: np.ndarray) -> np.ndarray:
        """``[1, 0.5 Lm.ravel()]`` (:func:`_half_L` of the state's quaternions, the weights of
        :meth:`_gather_plan`) as one gather: every entry of L(p) is one component of p,
        signed, so 0.5 L(p) is that component times +-0.5, the same rounding as
        :func:`_half_L`'s (zeros may differ in sign only, which no sum starting from +0
        in :meth:`static_jacobian_band` can see)."""
        if self._weights is None:
            # Lm[b, a] (b = 0..3, a = 0..2) = sign * p[k]: row 0 is -q, rows 1..3 are
            # p0 I + [q]x, with [q]x as in _half_L
            k = np.zeros((4, 3), dtype=int)
            sign = np.zeros((4, 3))
            k[0], sign[0] = (1, 2, 3), -1.0
            for r in range(3):
                k[1 + r, r], sign[1 + r, r] = 0, 1.0
            for (r, a), (kk, sg) in {(0, 1): (3, -1.0), (0, 2): (2, 1.0), (1, 0): (3, 1.0),
                                     (1, 2): (1, -1.0), (2, 0): (2, -1.0),
                                     (2, 1): (1, 1.0)}.items():
                k[1 + r, a], sign[1 + r, a] = kk, sg
            p_index = self.model.p_index
            self._weight_src = p_index[:, k.ravel()].ravel()
            self._weight_sign = np.tile(0.5 * sign.ravel(), self.N)
            self._weights = np.empty(1 + self._weight_src.size)
            self._weights[0] = 1.0
        w = self._weights
        np.multiply(y0[self._weight_src], self._weight_sign, out=w[1:])
        return w

    def static_retract(self, y: np.ndarray, dx: np.ndarray) -> np.ndarray:
        """New state: phi += dphi, p <- p*exp(dtheta/2) renormalised; velocities kept.

        The arithmetic of :func:`~runtime.model.quaternion.quat_exp`, then
        :func:`~runtime.model.quaternion.quat_mul`, then the normalisation, operation by
        operation on the same arrays (the same bits), in fewer NumPy calls: at a few
        elements the calls, not the arithmetic, are the cost."""
        core = self._native
        if core:
            return core.retract(np.ascontiguousarray(y, dtype=float),
                                np.ascontiguousarray(dx, dtype=float))
        m = self.model
        y1 = np.array(y, dtype=float)
        dx = np.asarray(dx)
        y1[self._phi_flat] += dx[self._phi_cols_flat]
        y1[m.p_index] = _rotate(y1[m.p_index], dx[self._theta_flat].reshape(-1, 3))
        return y1


#: quat_mul's cross product, component by component: av[_C1] * bv[_C2] - av[_C2] * bv[_C1]
_C1, _C2 = np.array([1, 2, 0]), np.array([2, 0, 1])


def _rotate(p: np.ndarray, th: np.ndarray) -> np.ndarray:
    """``p * exp(th / 2)`` normalised, (N, 4) from quaternions p (N, 4) and rotation
    vectors th (N, 3): ``quat_mul(p, quat_exp(th))`` over its norm, the same operations
    on every element (the elementwise products and sums in the same order, the same
    reductions over the last axis of contiguous arrays; a test compares the bits)."""
    a = np.sqrt(np.add.reduce(th * th, axis=-1))            # np.linalg.norm(th, axis=-1)
    e = np.empty(th.shape[:-1] + (4,))
    e[:, 0] = np.cos(a / 2)
    sinc = np.where(a > 1e-8, np.sin(a / 2) / np.where(a > 0, a, 1.0), 0.5 - a**2 / 48)
    e[:, 1:] = sinc[:, None] * th
    a0, av, b0, bv = p[:, 0], p[:, 1:], e[:, 0], e[:, 1:]
    out = np.empty(p.shape)
    out[:, 0] = a0 * b0 - np.add.reduce(av * bv, axis=-1)
    out[:, 1:] = (a0[:, None] * bv + b0[:, None] * av
                  + (av.take(_C1, axis=1) * bv.take(_C2, axis=1)
                     - av.take(_C2, axis=1) * bv.take(_C1, axis=1)))
    return out / np.sqrt(np.add.reduce(out * out, axis=-1))[:, None]
