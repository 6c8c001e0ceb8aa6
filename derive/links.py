"""Links between rod frames and rigid bodies welded at rod nodes, as CasADi SX kernels
(issue 31; docs/design.md, section 12).

**Link.** A 6x6 Kelvin-Voigt spring between two sides a (called P) and b. Each side is
a point (a node position ``phi_x``, velocity ``v_x``) with a frame given as the SUM of
two quaternions, ``p_a = p_a1 + p_a2``, ``p_b = p_b1 + p_b2`` (scalar part first,
unnormalised): one segment's frame (``p_x2 = 0``, ``Omega_x2 = 0``), the frame at a
rod's interior node (its two adjacent segments: their normalised sum is the slerp
midpoint, second order), or a ground frame (a constant quaternion, ``Omega = 0``). Every
measure is homogeneous of degree 0 in ``p_a`` and in ``p_b``, as in the rod
(:mod:`derive.discrete_rod`). The strain, in P's material frame:

* ``e_t = R(p_a)^T (phi_b - phi_a) - d0`` (m);
* ``e_r = 2 Im(d)/Re(d)``, ``d = conj(p_a) p_b conj(r0)`` (1), the Cayley vector of the
  rotation ``d`` that takes the reference relative orientation to the current one:
  ``p_b = p_a d r0`` for unit quaternions, so ``R(p_b) = R(p_a) R(d) R(r0)`` and the
  spatial axis of ``d`` is ``R(p_a) Im(d)``: components in P's frame. ``r0 =
  conj(p_a0) p_b0`` (the reference sums) makes ``e_r = 0`` in the reference; ``e_r`` is
  ``theta`` times the axis to O(theta^3) and singular at a relative rotation of pi.

``W = 1/2 e^T K e``, ``D = 1/2 edot^T V edot`` with the exact rate along ``phi' = v``,
``p_xk' = 1/2 p_xk*(0, Omega_xk)`` (forward AD over all four quaternions), K, V the
symmetric parts of the 6x6 matrices of :data:`LINK_PARAMS` (order t1, t2, t3, r1, r2,
r3). The generalized forces are ``f = -dW/dphi - dD/dv`` on the two points (spatial) and
``T = -1/2 vec(L(p_xk)^T dW/dp_xk) - dD/dOmega_xk`` on the four frames (material,
conjugate to their Omega): the convention of Q in ``rod_coupled_segment_forces``. Since
``dW/dp_x1 = dW/dp_x2 = dW/dp_x``, a zero ``p_x2`` gets exactly zero torque.
:func:`link_functionals` and :func:`link_forces_ad` are these definitions;
:func:`link_quantities` evaluates the same in closed form (what the kernels do).

**Body.** A rigid body welded at a rod node, its frame the material frame of one of the
node's segments (quaternion p, angular velocity Omega): mass M, inertia J about its mass
centre and mass centre offset e from the node (both material, :data:`BODY_PARAMS`),
``T = 1/2 M |v + R (Omega x e)|^2 + 1/2 Omega^T J Omega``, gravity at the mass centre.
:func:`body_equations_ad` derives its rows by Euler-Lagrange (node) and Euler-Poincare
(frame) with CasADi AD of T and of the potential of gravity; :func:`body_inertia` is
the closed form the kernel evaluates (equal to rounding, tested).

The layout tables here are the one source for ``generated/rod_layout.py`` and ``.h``.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca

from derive.discrete_rod import (
    _field,
    _fn,
    _offsets,
    _size,
    _sym3,
    qconj,
    qdot,
    qmul,
    rotate,
    rotate_transposed,
    rotation,
    torque_from_gradient,
)

# --------------------------------------------------------------------------------------
# Layout (rendered into generated/rod_layout.py and rod_layout.h)
# --------------------------------------------------------------------------------------

#: parameters of one link: (name, size, unit, meaning). Matrices row-major 6x6 in the
#: strain order (t1, t2, t3, r1, r2, r3): translation first, in P's (side a's) frame
LINK_PARAMS: tuple[tuple[str, int, str, str], ...] = (
    ("K", 36, "N/m | N | N m", "stiffness 6x6, symmetric positive semi-definite: "
                               "translation block N/m, couplings N, rotation block N m"),
    ("V", 36, "N s/m | N s | N m s", "viscosity 6x6, symmetric positive semi-definite "
                                     "(same blocks times s)"),
    ("d0", 3, "m", "reference offset R(p_a0)^T (phi_b0 - phi_a0) of b from a, P's frame"),
    ("r0", 4, "1", "reference relative quaternion conj(p_a0) p_b0 of the side sums "
                   "(scalar first, any norm)"),
)
#: parameters of one rigid body welded at a node (frame: the material frame of one of
#: the node's segments)
BODY_PARAMS: tuple[tuple[str, int, str, str], ...] = (
    ("M", 1, "kg", "mass"),
    ("J", 9, "kg m^2", "inertia about the mass centre, material frame, 3x3 row-major, "
                       "symmetric"),
    ("e", 3, "m", "mass centre offset from the node, material frame"),
)
#: blocks of the link's generalized forces Q (rod_link_forces): forces on the points
#: (spatial, N), torques on the frames (material, N m, conjugate to their Omega)
LINK_FORCES: tuple[tuple[str, int], ...] = (
    ("f_a", 3), ("f_b", 3), ("T_a1", 3), ("T_a2", 3), ("T_b1", 3), ("T_b2", 3))
#: columns of rod_link_forces_jac (rows: LINK_FORCES)
LINK_JAC_COLUMNS: tuple[tuple[str, int], ...] = (
    ("phi_a", 3), ("phi_b", 3), ("p_a1", 4), ("p_a2", 4), ("p_b1", 4), ("p_b2", 4),
    ("v_a", 3), ("v_b", 3), ("Omega_a1", 3), ("Omega_a2", 3), ("Omega_b1", 3),
    ("Omega_b2", 3))
#: rows of rod_body_inertia: added to the node's momentum row and to the segment's
#: angular momentum row
BODY_ROWS: tuple[tuple[str, int], ...] = (("v", 3), ("Omega", 3))
#: columns of rod_body_inertia_jac (y and y' of the node's v, the segment's p and Omega)
BODY_JAC_COLUMNS: tuple[tuple[str, int], ...] = (("v", 3), ("p", 4), ("Omega", 3))

LINK_OFFSETS, N_LINK = _offsets(LINK_PARAMS), _size(LINK_PARAMS)
BODY_OFFSETS, N_BODY = _offsets(BODY_PARAMS), _size(BODY_PARAMS)
LINK_FORCE_OFFSETS, N_LINK_FORCES = _offsets(LINK_FORCES), _size(LINK_FORCES)
LINK_JAC_OFFSETS, N_LINK_JAC_COLUMNS = _offsets(LINK_JAC_COLUMNS), _size(LINK_JAC_COLUMNS)
BODY_ROW_OFFSETS, N_BODY_ROWS = _offsets(BODY_ROWS), _size(BODY_ROWS)
BODY_JAC_OFFSETS, N_BODY_JAC_COLUMNS = _offsets(BODY_JAC_COLUMNS), _size(BODY_JAC_COLUMNS)


def _lnk(lp, name):
    """A named entry of the link parameter vector (:data:`LINK_PARAMS`)."""
    return _field(lp, LINK_OFFSETS, LINK_PARAMS, name)


def _bdy(bp, name):
    """A named entry of the body parameter vector (:data:`BODY_PARAMS`)."""
    return _field(bp, BODY_OFFSETS, BODY_PARAMS, name)


def _mat6_sym(v):
    """Symmetric part of the 6x6 matrix of 36 row-major entries (the quadratic form's
    matrix; the runtime checks that the given one is symmetric)."""
    M = ca.reshape(v, 6, 6).T
    return 0.5 * (M + M.T)


# --------------------------------------------------------------------------------------
# Link
# --------------------------------------------------------------------------------------


@dataclass(frozen=True)
class LinkSym:
    """Inputs of the link kernels (names as in :func:`link_kernels`)."""

    phi_a: ca.SX
    phi_b: ca.SX
    v_a: ca.SX
    v_b: ca.SX
    p_a1: ca.SX
    p_a2: ca.SX
    p_b1: ca.SX
    p_b2: ca.SX
    omega_a1: ca.SX
    omega_a2: ca.SX
    omega_b1: ca.SX
    omega_b2: ca.SX
    lnk: ca.SX     # LINK_PARAMS

    def inputs(self) -> dict[str, ca.SX]:
        """The kernels' named inputs, in order."""
        return {"phi_a": self.phi_a, "phi_b": self.phi_b, "v_a": self.v_a, "v_b": self.v_b,
                "p_a1": self.p_a1, "p_a2": self.p_a2, "p_b1": self.p_b1, "p_b2": self.p_b2,
                "Omega_a1": self.omega_a1, "Omega_a2": self.omega_a2,
                "Omega_b1": self.omega_b1, "Omega_b2": self.omega_b2, "lnk": self.lnk}

    def jac_columns(self) -> ca.SX:
        """The variables of :data:`LINK_JAC_COLUMNS`, stacked."""
        return ca.vertcat(self.phi_a, self.phi_b, self.p_a1, self.p_a2, self.p_b1,
                          self.p_b2, self.v_a, self.v_b, self.omega_a1, self.omega_a2,
                          self.omega_b1, self.omega_b2)


def link_symbols() -> LinkSym:
    """Fresh SX symbols of the link's inputs."""
    S = ca.SX.sym
    return LinkSym(S("phi_a", 3), S("phi_b", 3), S("v_a", 3), S("v_b", 3), S("p_a1", 4),
                   S("p_a2", 4), S("p_b1", 4), S("p_b2", 4), S("Omega_a1", 3),
                   S("Omega_a2", 3), S("Omega_b1", 3), S("Omega_b2", 3),
                   S("lnk", N_LINK))


def link_strain(phi_a, phi_b, p_a, p_b, lnk) -> ca.SX:
    """``e = (R(p_a)^T (phi_b - phi_a) - d0, 2 Im(d)/Re(d))`` (6: m, 1),
    ``d = conj(p_a) p_b conj(r0)``: the link's strain in P's (side a's) frame."""
    e_t = rotation(p_a).T @ (phi_b - phi_a) - _lnk(lnk, "d0")
    d = qmul(qmul(qconj(p_a), p_b), qconj(_lnk(lnk, "r0")))
    return ca.vertcat(e_t, 2 * d[1:4] / d[0])


def link_functionals(s: LinkSym) -> dict[str, ca.SX]:
    """Strain e, its exact rate edot, ``W = 1/2 e^T K e`` and ``D = 1/2 edot^T V edot``
    of a link (the definitions): the rate is the forward-AD derivative of e along
    ``phi' = v`` and ``p_xk' = 1/2 p_xk*(0, Omega_xk)`` for all four quaternions."""
    e = link_strain(s.phi_a, s.phi_b, s.p_a1 + s.p_a2, s.p_b1 + s.p_b2, s.lnk)
    x = ca.vertcat(s.phi_a, s.phi_b, s.p_a1, s.p_a2, s.p_b1, s.p_b2)
    xd = ca.vertcat(s.v_a, s.v_b, qdot(s.p_a1, s.omega_a1), qdot(s.p_a2, s.omega_a2),
                    qdot(s.p_b1, s.omega_b1), qdot(s.p_b2, s.omega_b2))
    ed = ca.jtimes(e, x, xd)
    K, V = _mat6_sym(_lnk(s.lnk, "K")), _mat6_sym(_lnk(s.lnk, "V"))
    return {"e": e, "edot": ed, "W": 0.5 * ca.dot(e, K @ e), "D": 0.5 * ca.dot(ed, V @ ed)}


def link_forces_ad(s: LinkSym) -> ca.SX:
    """Q = (f_a, f_b, T_a1, T_a2, T_b1, T_b2) (18) by CasADi AD of W and D (the
    definition): ``f = -dW/dphi - dD/dv``, ``T = torque_from_gradient(p_xk, dW/dp_xk)
    - dD/dOmega_xk``."""
    f = link_functionals(s)
    gW = ca.gradient(f["W"], ca.vertcat(s.phi_a, s.phi_b, s.p_a1, s.p_a2, s.p_b1, s.p_b2))
    gD = ca.gradient(f["D"], ca.vertcat(s.v_a, s.v_b, s.omega_a1, s.omega_a2, s.omega_b1,
                                        s.omega_b2))
    return ca.vertcat(-gW[0:3] - gD[0:3], -gW[3:6] - gD[3:6],
                      torque_from_gradient(s.p_a1, gW[6:10]) - gD[6:9],
                      torque_from_gradient(s.p_a2, gW[10:14]) - gD[9:12],
                      torque_from_gradient(s.p_b1, gW[14:18]) - gD[12:15],
                      torque_from_gradient(s.p_b2, gW[18:22]) - gD[15:18])


def _side(p1, p2, om1, om2):
    """The frame ``p = p1 + p2`` of a side, its angular velocity and the split of a torque.

    With ``p_k' = 1/2 p_k*(0, Omega_k)``, ``p' = 1/2 p*(s, omega)`` where the scalar s only
    scales p (which no measure sees) and ``omega = A_1 Omega_1 + A_2 Omega_2``,
    ``A_k = (c_k0 I + [c_k]x)/|p|^2``, ``c_k = conj(p) p_k`` (``A_1 + A_2 = I``). Rotation
    increments map alike, so the torque T conjugate to the side's rotation acts on frame
    k as ``A_k^T T`` (zero for ``p_k = 0``). Returns (p, omega, split)."""
    p = p1 + p2
    n2 = ca.dot(p, p)
    c1, c2 = qmul(qconj(p), p1), qmul(qconj(p), p2)
    omega = (c1[0] * om1 + ca.cross(c1[1:4], om1) + c2[0] * om2 + ca.cross(c2[1:4], om2)) / n2

    def split(T):
        return ((c1[0] * T - ca.cross(c1[1:4], T)) / n2,
                (c2[0] * T - ca.cross(c2[1:4], T)) / n2)

    return p, omega, split


def _link_core(s: LinkSym, p_a, om_a, p_b, om_b) -> dict[str, ca.SX]:
    """The link between single frames p_a, p_b with angular velocities om_a, om_b:
    strain, rate, W, D, resultant, the force on a and the torques conjugate to the
    sides' rotations (:func:`link_quantities`)."""
    r0 = _lnk(s.lnk, "r0")
    x = rotate_transposed(p_a, s.phi_b - s.phi_a)
    xd = rotate_transposed(p_a, s.v_b - s.v_a) + ca.cross(x, om_a)
    r = qmul(qconj(p_a), p_b)
    d = qmul(r, qconj(r0))
    u = d[1:4] / d[0]
    wd = rotate(r0, om_b - rotate_transposed(r, om_a))
    e = ca.vertcat(x - _lnk(s.lnk, "d0"), 2 * u)
    ed = ca.vertcat(xd, wd + ca.cross(u, wd) + u * ca.dot(u, wd))
    K, V = _mat6_sym(_lnk(s.lnk, "K")), _mat6_sym(_lnk(s.lnk, "V"))
    res = K @ e + V @ ed
    n, m = res[0:3], res[3:6]
    T_b = -rotate_transposed(r0, m - ca.cross(u, m) + u * ca.dot(u, m))
    return {"e": e, "edot": ed, "W": 0.5 * ca.dot(e, K @ e), "D": 0.5 * ca.dot(ed, V @ ed),
            "s": res, "f_a": rotate(p_a, n), "T_a": ca.cross(x, n) - rotate(r, T_b),
            "T_b": T_b}


def link_quantities(s: LinkSym) -> dict[str, ca.SX]:
    """Closed forms of the link's strain, rate, W, D, resultant and forces.

    With the sides' frames and angular velocities (:func:`_side`), ``x = R_a^T (phi_b -
    phi_a)``, ``r = conj(p_a) p_b``, ``u = Im(d)/Re(d)``, ``A = I + [u]x + u u^T``:
    ``edot_t = R_a^T (v_b - v_a) + x x omega_a``, ``edot_r = A R(r0) (omega_b -
    R(r)^T omega_a)`` (``d <- d*exp(theta/2)`` changes ``2u`` by ``A theta``). With the
    resultant ``s = K e + V edot = (n, m)`` the virtual work gives ``f_a = R_a n = -f_b``,
    ``T_b = -R(r0)^T A^T m``, ``T_a = x x n - R(r) T_b``, each side's torque split on its
    two frames. Identically the AD of the definitions (:func:`link_forces_ad`; tested).
    """
    p_a, om_a, split_a = _side(s.p_a1, s.p_a2, s.omega_a1, s.omega_a2)
    p_b, om_b, split_b = _side(s.p_b1, s.p_b2, s.omega_b1, s.omega_b2)
    c = _link_core(s, p_a, om_a, p_b, om_b)
    return {**c, "Q": ca.vertcat(c["f_a"], -c["f_a"], *split_a(c["T_a"]),
                                 *split_b(c["T_b"]))}


def link_jacobian(s: LinkSym) -> ca.SX:
    """dQ/dx (18 x 40) of :func:`link_quantities` in the columns :data:`LINK_JAC_COLUMNS`,
    by the chain rule through the sides (CasADi AD of each stage: 13k SX instructions,
    against 21k for AD of Q as one expression).

    The core (f_a, T_a, T_b) is differentiated in the sides' frames and angular
    velocities as free variables (it depends on phi_b - phi_a and v_b - v_a only, so
    d/dphi_a = -d/dphi_b and d/dv_a = -d/dv_b), then composed with ``p_x = p_x1 + p_x2``
    and ``omega_x(p_x1, p_x2, Omega_x1, Omega_x2)``; each torque split ``A_k^T T`` adds
    its own derivative in (p_x1, p_x2) at fixed T.
    """
    S = ca.SX.sym
    pa, pb, oa, ob = S("p_a", 4), S("p_b", 4), S("omega_a", 3), S("omega_b", 3)
    core = _link_core(s, pa, oa, pb, ob)
    Qc = ca.vertcat(core["f_a"], core["T_a"], core["T_b"])
    Jc = ca.jacobian(Qc, ca.vertcat(s.phi_b, s.v_b, pa, pb, oa, ob))        # 9 x 20
    p_a, om_a, split_a = _side(s.p_a1, s.p_a2, s.omega_a1, s.omega_a2)
    p_b, om_b, split_b = _side(s.p_b1, s.p_b2, s.omega_b1, s.omega_b2)
    Jc, Qc = ca.substitute([Jc, Qc], [pa, pb, oa, ob], [p_a, p_b, om_a, om_b])
    J_phi, J_v, J_pa, J_pb, J_oa, J_ob = (Jc[:, k:k + n] for k, n in
                                          ((0, 3), (3, 3), (6, 4), (10, 4), (14, 3), (17, 3)))
    xa = ca.vertcat(s.p_a1, s.p_a2, s.omega_a1, s.omega_a2)
    xb = ca.vertcat(s.p_b1, s.p_b2, s.omega_b1, s.omega_b2)
    Ja = ca.horzcat(J_pa, J_pa, ca.SX.zeros(9, 6)) + J_oa @ ca.jacobian(om_a, xa)  # 9 x 14
    Jb = ca.horzcat(J_pb, J_pb, ca.SX.zeros(9, 6)) + J_ob @ ca.jacobian(om_b, xb)
    core_rows = ca.horzcat(-J_phi, J_phi, Ja[:, 0:8], Jb[:, 0:8], -J_v, J_v, Ja[:, 8:14],
                           Jb[:, 8:14])                                     # 9 x 40
    T = S("T", 3)
    rows = [core_rows[0:3, :], -core_rows[0:3, :]]
    for split, T_x, k, first, x in ((split_a, Qc[3:6], 3, 6, xa[0:8]),
                                    (split_b, Qc[6:9], 6, 14, xb[0:8])):
        parts = ca.vertcat(*split(T))                                       # 6
        dT, dx = ca.substitute([ca.jacobian(parts, T), ca.jacobian(parts, x)], [T], [T_x])
        rows.append(dT @ core_rows[k:k + 3, :]
                    + ca.horzcat(ca.SX.zeros(6, first), dx, ca.SX.zeros(6, 32 - first)))
    return ca.vertcat(*rows)


def link_kernels() -> list[ca.Function]:
    """``rod_link_forces``: Q (18) = (f_a, f_b, T_a1, T_a2, T_b1, T_b2)
    (:data:`LINK_FORCES`); ``rod_link_forces_jac``: dQ/dx (18 x 40, dense, column-major
    in C) in the columns (phi_a, phi_b, p_a1, p_a2, p_b1, p_b2, v_a, v_b, Omega_a1,
    Omega_a2, Omega_b1, Omega_b2) (:data:`LINK_JAC_COLUMNS`; no y' dependence)
    (:func:`link_jacobian`); ``rod_link_diagnostics``: W (J), D (W), e (6: m, 1), the
    resultant s = K e + V edot (6: force N and moment N m in P's frame). Inputs, in
    order: phi_a, phi_b, v_a, v_b (3), p_a1, p_a2, p_b1, p_b2 (4), Omega_a1, Omega_a2,
    Omega_b1, Omega_b2 (3), lnk (:data:`LINK_PARAMS`)."""
    s = link_symbols()
    q = link_quantities(s)
    ins = s.inputs()
    return [
        _fn("rod_link_forces", ins, {"Q": q["Q"]}),
        _fn("rod_link_forces_jac", ins,
            {"dQ_dx": ca.densify(link_jacobian(s))}),
        _fn("rod_link_diagnostics", ins, {"W": q["W"], "D": q["D"], "e": q["e"],
                                          "s": q["s"]}),
    ]


# --------------------------------------------------------------------------------------
# Rigid body at a node
# --------------------------------------------------------------------------------------


def body_kinetic_energy(v, p, omega, bdy) -> ca.SX:
    """``T = 1/2 M |v + R(p) (Omega x e)|^2 + 1/2 Omega^T J Omega`` (J), the body's
    kinetic energy (velocity of its mass centre: the node's v plus the frame's rotation
    about the node)."""
    M, e = _bdy(bdy, "M"), _bdy(bdy, "e")
    vc = v + rotate(p, ca.cross(omega, e))
    return 0.5 * M * ca.dot(vc, vc) + 0.5 * ca.dot(omega, _sym3(_bdy(bdy, "J")) @ omega)


def body_gravity_power(v, p, omega, g, bdy) -> ca.SX:
    """``P_g = M g . (v + R(p) (Omega x e))`` (W), the power of gravity on the body."""
    return _bdy(bdy, "M") * ca.dot(g, v + rotate(p, ca.cross(omega, _bdy(bdy, "e"))))


def body_equations_ad(v, v_dot, p, omega, omega_dot, g, bdy) -> dict[str, ca.SX]:
    """The body's rows by CasADi AD (the definition).

    Euler-Lagrange for the node, with the potential ``U_g = -M g . (phi + R(p) e)``:
    ``r_v = d/dt dT/dv + dU_g/dphi``; Euler-Poincare for the frame with material angular
    velocity: ``r_Om = d/dt dT/dOmega + Omega x dT/dOmega - dT/dtheta + dU_g/dtheta``,
    ``d/dtheta`` along ``p <- p*exp(theta/2)`` (``-torque_from_gradient`` of the
    quaternion gradient). The time derivatives are forward AD along ``v' = v_dot``,
    ``p' = 1/2 p*(0, Omega)``, ``Omega' = Omega_dot``.
    """
    T = body_kinetic_energy(v, p, omega, bdy)
    Ug = -_bdy(bdy, "M") * ca.dot(g, rotate(p, _bdy(bdy, "e")))   # + the phi part: -M g.phi
    x, xd = ca.vertcat(v, p, omega), ca.vertcat(v_dot, qdot(p, omega), omega_dot)
    Pv, Pom = ca.gradient(T, v), ca.gradient(T, omega)
    r_v = ca.jtimes(Pv, x, xd) - _bdy(bdy, "M") * g
    r_om = (ca.jtimes(Pom, x, xd) + ca.cross(omega, Pom)
            + torque_from_gradient(p, ca.gradient(T, p))
            - torque_from_gradient(p, ca.gradient(Ug, p)))
    return {"r": ca.vertcat(r_v, r_om), "T": T}


def body_inertia(v_dot, p, omega, omega_dot, g, bdy) -> ca.SX:
    """Closed form of :func:`body_equations_ad` (what the kernel evaluates):
    ``r_v = M (v' - g) + M R (Omega' x e + Omega x (Omega x e))``,
    ``r_Om = J_o Omega' + Omega x J_o Omega + M e x R^T (v' - g)``,
    ``J_o = J + M (|e|^2 I - e e^T)`` (parallel axes). The configuration term of
    Euler-Poincare cancels the part ``-M e x (Omega x R^T v)`` of the rate of
    ``dT/dOmega = J_o Omega + M e x R^T v`` with ``Omega x (M e x R^T v)`` (Jacobi), so
    neither row depends on v. Same as ``coupled_inertia`` for a segment's mass centre."""
    M, e = _bdy(bdy, "M"), _bdy(bdy, "e")
    Jo = _sym3(_bdy(bdy, "J")) + M * (ca.dot(e, e) * ca.SX.eye(3) - e @ e.T)
    r_v = M * (v_dot - g) + M * rotate(p, ca.cross(omega_dot, e)
                                       + ca.cross(omega, ca.cross(omega, e)))
    r_om = (Jo @ omega_dot + ca.cross(omega, Jo @ omega)
            + M * ca.cross(e, rotate_transposed(p, v_dot - g)))
    return ca.vertcat(r_v, r_om)


def body_kernels() -> list[ca.Function]:
    """``rod_body_inertia``: r (6) = (r_v to add to the node's momentum row, r_Om to add
    to the segment's angular momentum row) (:data:`BODY_ROWS`); ``rod_body_inertia_jac``:
    ``c_y dr/d(v, p, Omega) + c_j dr/d(v', p', Omega')`` (6 x 10) in the columns (v, p,
    Omega) (:data:`BODY_JAC_COLUMNS`); ``rod_body_kinetic``: T (J) and the power of
    gravity on the body P_g (W). Inputs: v, v_dot (3), p (4), Omega, Omega_dot, g (3,
    gravity already scaled), bdy (:data:`BODY_PARAMS`)."""
    S = ca.SX.sym
    v, vd, p, om, omd, g = S("v", 3), S("v_dot", 3), S("p", 4), S("Omega", 3), \
        S("Omega_dot", 3), S("g", 3)
    bdy, cy, cj = S("bdy", N_BODY), S("c_y"), S("c_j")
    r = body_inertia(vd, p, om, omd, g, bdy)
    ins = {"v": v, "v_dot": vd, "p": p, "Omega": om, "Omega_dot": omd, "g": g, "bdy": bdy}
    J = (cy * ca.jacobian(r, ca.vertcat(v, p, om))
         + cj * ca.horzcat(ca.jacobian(r, vd), ca.SX.zeros(6, 4), ca.jacobian(r, omd)))
    return [
        _fn("rod_body_inertia", ins, {"r": r}),
        _fn("rod_body_inertia_jac", {**ins, "c_y": cy, "c_j": cj}, {"J": ca.densify(J)}),
        _fn("rod_body_kinetic", {"v": v, "p": p, "Omega": om, "g": g, "bdy": bdy},
            {"T": body_kinetic_energy(v, p, om, bdy),
             "P_g": body_gravity_power(v, p, om, g, bdy)}),
    ]


def kernels() -> list[ca.Function]:
    """The link and body kernels, in a fixed order (generated into rod_kernels.c)."""
    return link_kernels() + body_kernels()
