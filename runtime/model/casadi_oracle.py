"""The whole rod as CasADi MX functions over the serialised per-element kernels: the
oracle of the C assembly and its fallback.

The rod has two assemblies of the same generated kernels: the C one
(``runtime/model/native/rod_assembly.c``, fast, what runs) and this CasADi MX one, built
independently from the layout tables (tests hold them equal to rounding: the oracle of
the C loops). It also serves as the in-process fallback when no C compiler is available
(residual, Jacobian and energies evaluated through CasADi), for SUNDIALS IDAS cross-checks
and benchmarks (the residual expanded to SX and compiled flat), and for anything that needs
derivatives of the whole rod.

The functions take the arrays of :class:`runtime.model.arrays.RodArrays` as inputs
(``par``; ``seg``, ``jnt``, ``nload``, ``sload`` transposed: one column per element), so
one built function serves every load and motion; which ends are held or clamped is fixed
when it is built (it decides the assembly's structure).
"""

from __future__ import annotations

from pathlib import Path

import casadi as ca
import numpy as np
import scipy.sparse as sp

from generated import rod_layout as L
from runtime.model import build
from runtime.model.arrays import RodArrays


def load_kernels(gdir: Path | None = None) -> dict[str, ca.Function]:
    """The serialised per-element kernels generated/rod_*.casadi, by name (checked
    against generated/MANIFEST.json first)."""
    if gdir is None:
        build.require_casadi_kernels()
    else:
        build.verify_manifest(gdir, tuple(f"{name}.casadi" for name in L.KERNELS))
    gdir = gdir or build.generated_dir()
    return {name: ca.Function.deserialize((gdir / f"{name}.casadi").read_text())
            for name in L.KERNELS}


def _r(start: int, size: int) -> list[int]:
    return list(range(start, start + size))


class CasadiOracle:
    """MX functions of one rod structure (N elements, its held and clamped ends).

    ``residual(t, y, yp, par, seg, jnt, nload, sload) -> F`` (n,);
    ``jacobian(..., cy, cj) -> cy dF/dy + cj dF/dy'`` (sparse n x n);
    ``energies(...) -> (T, W, 2D, P_ext, P_bc, reactions...)`` and
    ``elements(...) -> (V, F, U, M)``.
    Call :meth:`args` to get the numeric inputs of a :class:`RodArrays`.
    """

    def __init__(self, arrays: RodArrays, kernels: dict[str, ca.Function] | None = None):
        self.N = N = arrays.N
        self.B = B = arrays.branches
        self.n = L.n_state(N, B)
        self.held = (arrays.held("start"), arrays.held("end"))
        self.clamped = (arrays.clamped("start"), arrays.clamped("end"))
        k = self.k = kernels or load_kernels()
        t = ca.MX.sym("t")
        y, yp = ca.MX.sym("y", self.n), ca.MX.sym("yp", self.n)
        par = ca.MX.sym("par", L.N_PARAMS)
        seg = ca.MX.sym("seg", L.N_SEGMENT, N)
        jnt = ca.MX.sym("jnt", L.N_JOINT, N + 1)
        nl = ca.MX.sym("nload", L.N_NODE_LOAD, N + 1)
        sl = ca.MX.sym("sload", L.N_SEGMENT_LOAD, N)
        theta = ca.MX.sym("theta", B)
        segb = ca.MX.sym("segb", 3 * B, N)          # term b's moduli in rows 3b..3b+2
        jntb = ca.MX.sym("jntb", 3 * B, N + 1)
        self._inputs = [t, y, yp, par, seg, jnt, nl, sl, theta, segb, jntb]
        self._names = ["t", "y", "yp", "par", "seg", "jnt", "nload", "sload", "theta",
                       "segb", "jntb"]

        def P(name):
            return par[_r(L.PARAM_OFFSETS[name], L.PARAM_SIZES[name])]

        nodes, segs = range(N + 1), range(1, N + 1)

        def g(vec, starts, size):  # columns of gathered fields, (size, K)
            idx = [s + j for s in starts for j in range(size)]
            return ca.reshape(vec[idx], size, len(starts))

        phi_i = [L.node_phi(i, B) for i in nodes]
        v_i = [L.node_v(i, B) for i in nodes]
        p_i = [L.segment_p(i, B) for i in segs]
        om_i = [L.segment_omega(i, B) for i in segs]
        qs_i = [L.segment_q(i, B) for i in segs]
        qj_i = [L.joint_q(j, B) for j in nodes]
        Y = {"phi": g(y, phi_i, 3), "v": g(y, v_i, 3), "p": g(y, p_i, 4), "Om": g(y, om_i, 3)}
        YP = {"phi": g(yp, phi_i, 3), "v": g(yp, v_i, 3), "p": g(yp, p_i, 4),
              "Om": g(yp, om_i, 3)}
        # relaxation terms (generalized Maxwell): internal strains (3B, elements), their
        # resultants -sum_b C_b q_b (3, elements) and 1/theta per row (3B, 1)
        rate = ca.kron(1.0 / theta, ca.DM.ones(3, 1)) if B else ca.MX.zeros(0, 1)

        def q_resultant(C, q, K):
            out = ca.MX.zeros(3, K)
            for b in range(B):
                out -= C[3 * b:3 * b + 3, :] * q[3 * b:3 * b + 3, :]
            return out

        QS, QJ = g(y, qs_i, 3 * B), g(y, qj_i, 3 * B)
        QSd, QJd = g(yp, qs_i, 3 * B), g(yp, qj_i, 3 * B)
        n_q = q_resultant(segb, QS, N)
        m_q = q_resultant(jntb, QJ, N + 1)
        ls = P("load_scale")
        so = L.SEGMENT_OFFSETS
        h = seg[so["h"], :]
        mseg = seg[so["rhoA"], :] * h                        # segment masses (1, N)
        zero = ca.MX.zeros(1, 1)
        mass = 0.5 * (ca.horzcat(zero, mseg) + ca.horzcat(mseg, zero))      # (1, N+1)
        lump = 0.5 * (ca.horzcat(zero, h) + ca.horzcat(h, zero))
        host = [max(i, 1) - 1 for i in nodes]                # column of the host segment
        no = L.NODE_LOAD_OFFSETS
        f_follow = k["rod_rotate"].map(N + 1)(Y["p"][:, host], nl[_r(no["f_follower"], 3), :])
        f_ext = ls * (ca.mtimes(P("gravity"), mass) + ca.mtimes(P("f_dist"), lump)
                      + nl[_r(no["f_dead"], 3), :] + f_follow)           # (3, N+1)
        held = np.zeros(N + 1)
        held[0], held[N] = float(self.held[0]), float(self.held[1])
        def ends(name: str) -> ca.MX:        # a parameter of both ends, zero inside
            return ca.horzcat(P(name + "_start"), ca.MX.zeros(3, N - 1), P(name + "_end"))

        rn = k["rod_node_inertia"].map(N + 1)(Y["phi"], Y["v"], YP["phi"], YP["v"], mass,
                                              f_ext, ca.DM(held).T, ends("r"), ends("v"))
        rs = k["rod_segment_inertia"].map(N)(Y["p"], Y["Om"], YP["p"], YP["Om"], seg)
        lo = L.SEGMENT_LOAD_OFFSETS
        t_dead = k["rod_rotate_transposed"].map(N)(Y["p"], sl[_r(lo["m_dead"], 3), :])
        t_ext = ls * (t_dead + sl[_r(lo["m_follower"], 3), :])
        Q = k["rod_segment_forces"].map(N)(Y["phi"][:, :N], Y["phi"][:, 1:], Y["p"],
                                           Y["v"][:, :N], Y["v"][:, 1:], Y["Om"], seg, n_q)
        wa = np.ones((3, N))
        wb = np.ones((3, N))
        if self.held[0]:
            wa[:, 0] = 0.0
        if self.held[1]:
            wb[:, N - 1] = 0.0

        rows, vals = [], []

        def put(starts, size, block):
            rows.append(np.array([s + j for s in starts for j in range(size)]))
            vals.append(ca.vec(block))

        put(phi_i, 6, rn)                      # node rows (phi, v: consecutive in a cell)
        put(p_i, 7, rs)                        # segment rows (p, Omega)
        put(om_i, 3, -t_ext)
        put(v_i[:N], 3, -Q[0:3, :] * ca.DM(wa))
        put(v_i[1:], 3, -Q[3:6, :] * ca.DM(wb))
        put(om_i, 3, -Q[6:9, :])
        if N > 1:
            hj = jnt[:, 1:N]
            T = k["rod_joint_torques"].map(N - 1)(Y["p"][:, :-1], Y["p"][:, 1:],
                                                  Y["Om"][:, :-1], Y["Om"][:, 1:], hj,
                                                  m_q[:, 1:N])
            put(om_i[:-1], 3, -T[0:3, :])
            put(om_i[1:], 3, -T[3:6, :])
        jt = k["rod_joint_torques"]
        clamp_T = []        # (the joint's torque on the clamp frame, its Omega, p, end)
        if self.clamped[0]:
            T0 = jt(P("p_start"), Y["p"][:, 0], P("Omega_start"), Y["Om"][:, 0], jnt[:, 0],
                    m_q[:, 0])
            put(om_i[:1], 3, -T0[3:6])
            clamp_T.append((T0[0:3], P("Omega_start"), P("p_start"), 0))
        if self.clamped[1]:
            TN = jt(Y["p"][:, N - 1], P("p_end"), Y["Om"][:, N - 1], P("Omega_end"), jnt[:, N],
                    m_q[:, N])
            put(om_i[-1:], 3, -TN[0:3])
            clamp_T.append((TN[3:6], P("Omega_end"), P("p_end"), 1))
        # relaxation rows q' - (strain - q)/theta (strain 0 at an absent clamp joint)
        dV = dU = None
        if B:
            dV = k["rod_segment_branch"].map(N)(Y["phi"][:, :N], Y["phi"][:, 1:], Y["p"],
                                                seg)[0]
            put(qs_i, 3 * B, QSd - rate * (ca.repmat(dV, B, 1) - QS))
            cols = []
            jb = k["rod_joint_branch"]
            for j in nodes:
                a = Y["p"][:, j - 1] if j >= 1 else P("p_start")
                b = Y["p"][:, j] if j + 1 <= N else P("p_end")
                active = (1 <= j <= N - 1) or (j == 0 and self.clamped[0]) or (
                    j == N and self.clamped[1])
                cols.append(jb(a, b, jnt[:, j])[0] if active else ca.MX.zeros(3, 1))
            dU = ca.horzcat(*cols)
            put(qj_i, 3 * B, QJd - rate * (ca.repmat(dU, B, 1) - QJ))
        ridx = np.concatenate(rows)
        S = sp.csc_matrix((np.ones(ridx.size), (ridx, np.arange(ridx.size))),
                          shape=(self.n, ridx.size))
        Sd = ca.DM(ca.Sparsity(self.n, ridx.size, S.indptr.tolist(), S.indices.tolist()),
                   S.data)
        F = ca.mtimes(Sd, ca.vertcat(*vals))
        self.residual = ca.Function("rod_residual", self._inputs, [F], self._names, ["F"])
        cy, cj = ca.MX.sym("c_y"), ca.MX.sym("c_j")
        J = cy * ca.jacobian(F, y) + cj * ca.jacobian(F, yp)
        self.jacobian = ca.Function("rod_residual_jac_y_yp", [*self._inputs, cy, cj], [J],
                                    [*self._names, "c_y", "c_j"], ["J"])

        # energies and powers (as the compiled kvrod_diagnostics)
        kin = ca.sum2(k["rod_node_kinetic"].map(N + 1)(Y["v"], mass)) + ca.sum2(
            k["rod_segment_kinetic"].map(N)(Y["Om"], seg))
        Ws, Ds, V, Fs = k["rod_segment_diagnostics"].map(N)(
            Y["phi"][:, :N], Y["phi"][:, 1:], Y["p"], Y["v"][:, :N], Y["v"][:, 1:], Y["Om"],
            seg, n_q)
        el, dis = ca.sum2(Ws), 2 * ca.sum2(Ds)
        if B:      # stored energy and dissipation of the terms beyond the kernels' W
            active = np.ones((1, N + 1))          # joints 0 and N exist at a clamp only
            active[0, 0], active[0, N] = float(self.clamped[0]), float(self.clamped[1])
            hj_all = jnt[L.JOINT_OFFSETS["h"], :] * ca.DM(active)
            for C, q, d, hh in ((segb, QS, dV, h), (jntb, QJ, dU, hj_all)):
                for b in range(B):
                    x = d - q[3 * b:3 * b + 3, :]
                    Cb = C[3 * b:3 * b + 3, :]
                    el += ca.sum2(0.5 * hh * ca.sum1(Cb * (x * x - d * d)))
                    dis += ca.sum2(hh / theta[b] * ca.sum1(Cb * x * x))
        U = [ca.MX.zeros(3, 1) for _ in range(N + 1)]
        M = [ca.MX.zeros(3, 1) for _ in range(N + 1)]
        jd = k["rod_joint_diagnostics"]
        if N > 1:
            Wj, Dj, Uj, Mj = jd.map(N - 1)(Y["p"][:, :-1], Y["p"][:, 1:], Y["Om"][:, :-1],
                                           Y["Om"][:, 1:], jnt[:, 1:N], m_q[:, 1:N])
            el, dis = el + ca.sum2(Wj), dis + 2 * ca.sum2(Dj)
            for j in range(1, N):
                U[j], M[j] = Uj[:, j - 1], Mj[:, j - 1]
        if self.clamped[0]:
            Wj, Dj, U[0], M[0] = jd(P("p_start"), Y["p"][:, 0], P("Omega_start"),
                                    Y["Om"][:, 0], jnt[:, 0], m_q[:, 0])
            el, dis = el + Wj, dis + 2 * Dj
        if self.clamped[1]:
            Wj, Dj, U[N], M[N] = jd(Y["p"][:, N - 1], P("p_end"), Y["Om"][:, N - 1],
                                    P("Omega_end"), jnt[:, N], m_q[:, N])
            el, dis = el + Wj, dis + 2 * Dj
        pext = ca.sum2(ca.sum1(f_ext * Y["v"])) + ca.sum2(ca.sum1(t_ext * Y["Om"]))
        pbc = ca.MX.zeros(1, 1)
        reaction = [[ca.MX.zeros(3, 1), ca.MX.zeros(3, 1)] for _ in range(2)]
        for Tc, om, pc, end in clamp_T:       # the support's moment, spatial
            pbc -= ca.dot(Tc, om)
            reaction[end][1] = k["rod_rotate"](pc, -Tc)
        for end, i, fint in ((0, 0, Q[0:3, 0]), (1, N, Q[3:6, N - 1])):
            if self.held[end]:
                name = "a_start" if end == 0 else "a_end"
                reaction[end][0] = mass[i] * P(name) - f_ext[:, i] - fint
                pbc += ca.dot(reaction[end][0], Y["v"][:, i])
        scalars = [kin, el, dis, pext, pbc] + [r[c] for e in reaction for r in e
                                               for c in range(3)]
        self.energies = ca.Function("rod_energy", self._inputs, scalars, self._names,
                                    list(L.DIAG_SCALARS))
        self.elements = ca.Function("rod_elements", self._inputs,
                                    [V, Fs, ca.horzcat(*U), ca.horzcat(*M)], self._names,
                                    ["V", "F", "U", "M"])

    @staticmethod
    def args(arrays: RodArrays) -> list[np.ndarray]:
        """Numeric inputs after (t, y, yp): par and the transposed element arrays."""
        B = arrays.branches
        return [arrays.par, arrays.seg.T, arrays.jnt.T, arrays.nload.T, arrays.sload.T,
                arrays.theta, arrays.segb.reshape(arrays.N, 3 * B).T,
                arrays.jntb.reshape(arrays.N + 1, 3 * B).T]
