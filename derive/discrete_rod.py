"""Discrete Cosserat rod with Kelvin-Voigt damping as CasADi SX kernels (docs/design.md, section 4).

Quaternion staggered grid of Lang, Linn and Arnold (2011):

* nodes ``phi_0 .. phi_N`` (positions, m) with velocities ``v_i`` (m/s), uniform element
  length ``h = L/N``;
* segments ``i = 1..N`` between nodes ``i-1`` and ``i`` carry a quaternion ``p_i``
  (scalar part first) and the material angular velocity ``Omega_i`` (rad/s);
* shear/extension strain on segments, ``V_i = R(p_i)^T (phi_i - phi_{i-1})/h``, reference
  ``V_0 = e3``;
* curvature at a joint between neighbouring frames a, b (Cayley form)
  ``U = (2/h_j) Im(r)/Re(r)``, ``r = conj(p_a) p_b`` (= rotation angle/h_j + O(theta^3)),
  with ``h_j = h`` at interior joints and ``h_j = h/2`` between a clamp frame and the
  adjacent segment (a half-length curvature cell keeps the O(h^2) accuracy that fixing
  p_1 to the clamp frame would lose, docs/design.md, section 7).

Functionals (paper eqs. (10), (11), footnote 4):

* elastic energy ``W = sum_seg h/2 dV^T C_F dV + sum_joints h_j/2 dU^T C_M dU``;
* dissipation function ``D = sum_seg h/2 Vdot^T V_F Vdot + sum_joints h_j/2 Udot^T V_M Udot``
  with the *exact* time derivatives of the discrete strains along ``phi' = v``,
  ``p' = 1/2 p*(0, Omega)`` (forward AD), so the viscous resultants are ``V_F Vdot`` and
  ``V_M Udot`` and the viscous generalized forces are ``-dD/d(v, Omega)``;
* kinetic energy with lumped nodal masses ``rho A h`` (half at the ends) and segment rotary
  inertia ``rho h diag(I1, I2, I3)``.

Elastic forces are ``-dW/dphi``; the material torque conjugate to ``Omega`` is
``T = -1/2 vec(L(p)^T dW/dp)`` with ``L(p)`` the left quaternion multiplication matrix.
Because all forces are derivatives of W and D, the discrete model is objective and
satisfies ``d/dt (T + W) = -2 D + P_ext`` exactly along its flow.

**Definitions and kernels.** :func:`segment_functionals` / :func:`joint_functionals` define
V, U, W, D with the rates by forward AD (``jtimes``), and :func:`segment_forces_ad` /
:func:`joint_torques_ad` the forces by CasADi AD of W and D -- the definitions. The kernels
evaluate the same quantities in closed (virtual-work) form through the stress resultants
(:func:`segment_quantities`, :func:`joint_quantities`); their Jacobians are formed along
rotation increments, in closed form for the segment (:func:`segment_jacobian`) and by
CasADi AD in the increment for the joint (:func:`joint_jacobian`). All of this is
identical as functions to the AD of the definitions (tests compare them to rounding, and
the assembled Jacobians to finite differences) and makes the residual about 2x and the
Jacobian about 2x cheaper than AD of the definitions.

**Quaternion norm.** We use the *kinematic form* ``p' = 1/2 p*(0, Omega)`` without a norm
constraint. In exact time it preserves ``|p|``; the integrator's drift of ``|p|`` is
harmless because every strain measure is homogeneous of degree 0 in each quaternion:
``R(p)`` is written as ``[(p0^2 - |q|^2) I + 2 q q^T + 2 p0 [q]x] / |p|^2`` and the
Cayley curvature ``Im(r)/Re(r)`` is a ratio of two bilinear forms. Energies, dissipation
and forces therefore do not change when a quaternion is scaled (tested), the torque
formula above is valid for any ``|p|``, and the static solver renormalises after every
update. No square root appears anywhere.

Everything the runtime needs about the state and parameter vectors is defined here once
(:data:`CELL_FIELDS`, :data:`PARAMS`, :data:`SEGMENT_PARAMS`, :data:`JOINT_PARAMS`,
:data:`NODE_LOADS`, :data:`SEGMENT_LOADS`) and rendered into ``generated/rod_layout.py``.

**Per-element parameters.** Stiffness, damping, reference strains (V0, U0: a precurved or
pretwisted rod), lengths and inertia are per segment and per joint, so sections and
materials may vary along the rod; loads are per node and per segment; the global vector
holds gravity, the distributed load, the load factor and the ends (held or free,
clamped or not, their prescribed position, velocity, frame and angular velocity, and the
point moments applied at the end nodes, which a coupled rod's free-end condensation
carries).
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca

# --------------------------------------------------------------------------------------
# Layout: the single source of truth (rendered into generated/rod_layout.py)
# --------------------------------------------------------------------------------------

#: fields of cell 0 (node 0 and joint 0), in order: (name, size, size per relaxation term)
CELL0_FIELDS_B: tuple[tuple[str, int, int], ...] = (("phi", 3, 0), ("v", 3, 0),
                                                     ("q_joint", 0, 3))
#: fields of cell i = 1..N (segment i, node i, joint i), in order, with sizes. The internal
#: strains q (generalized Maxwell, :func:`branch_quantities`) of a rod with B relaxation
#: terms: 3 per term for the segment (toward V - V0) and 3 per term for the joint (toward
#: U - U0); a Kelvin-Voigt rod has B = 0 and cells of 6 and 13.
CELL_FIELDS_B: tuple[tuple[str, int, int], ...] = (
    ("p", 4, 0), ("Omega", 3, 0), ("q_segment", 0, 3), ("phi", 3, 0), ("v", 3, 0),
    ("q_joint", 0, 3))
#: largest number of rod-level relaxation terms (a generous bound: 2 per 3-D branch)
MAX_BRANCHES = 24


def cell_fields(branches: int = 0, first: bool = False) -> tuple[tuple[str, int], ...]:
    """(name, size) of the fields of a cell (``first``: cell 0) for B relaxation terms."""
    return tuple((n, a + b * branches) for n, a, b in (CELL0_FIELDS_B if first else
                                                        CELL_FIELDS_B) if a + b * branches)


#: the Kelvin-Voigt layout (B = 0)
CELL0_FIELDS: tuple[tuple[str, int], ...] = cell_fields(0, first=True)
CELL_FIELDS: tuple[tuple[str, int], ...] = cell_fields(0)

#: parameters of one segment i = 1..N (between nodes i-1 and i): (name, size, unit, meaning)
SEGMENT_PARAMS: tuple[tuple[str, int, str, str], ...] = (
    ("h", 1, "m", "segment length (reference arc length)"),
    ("C_F", 3, "N", "diagonal of C_F = diag(GA_1, GA_2, EA), eq. (7)"),
    ("V_F", 3, "N s", "diagonal of V_F, eq. (9)"),
    ("V0", 3, "1", "reference shear/extension strain of the segment (material)"),
    ("rhoA", 1, "kg/m", "mass per length rho A"),
    ("rhoI", 3, "kg m", "rotary inertia per length rho diag(I1, I2, I3)"),
)
#: parameters of one joint j = 0..N (at node j; j = 0, N only between a clamp frame and
#: the end segment)
JOINT_PARAMS: tuple[tuple[str, int, str, str], ...] = (
    ("h", 1, "m", "joint length: (h_j + h_j+1)/2 inside, h/2 at a clamp"),
    ("C_M", 3, "N m^2", "diagonal of C_M = diag(EI_1, EI_2, GJ_T), eq. (7)"),
    ("V_M", 3, "N m^2 s", "diagonal of V_M, eq. (9)"),
    ("U0", 3, "1/m", "reference curvature and twist (material)"),
)
#: external loads on one node i = 0..N (current values, scaled by load_scale)
NODE_LOADS: tuple[tuple[str, int, str, str], ...] = (
    ("f_dead", 3, "N", "dead point force (spatial)"),
    ("f_follower", 3, "N", "follower point force (material frame of the node's segment)"),
)
#: external loads on one segment i = 1..N (current values, scaled by load_scale)
SEGMENT_LOADS: tuple[tuple[str, int, str, str], ...] = (
    ("m_dead", 3, "N m", "dead point moment (spatial)"),
    ("m_follower", 3, "N m", "follower point moment (material)"),
)
#: global parameters passed to the assembly: (name, size, unit, meaning)
PARAMS: tuple[tuple[str, int, str, str], ...] = (
    ("load_scale", 1, "1", "factor on all external loads (load stepping)"),
    ("gravity", 3, "m/s^2", "gravitational acceleration (spatial)"),
    ("f_dist", 3, "N/m", "dead distributed force per length (spatial)"),
    ("fix_start", 1, "1", "1: node 0 held (clamped or pinned, position prescribed), else 0"),
    ("clamp_start", 1, "1", "1: frame clamped at s = 0 (half-length joint), else 0"),
    ("fix_end", 1, "1", "1: node N held, else 0"),
    ("clamp_end", 1, "1", "1: frame clamped at s = L, else 0"),
    ("r_start", 3, "m", "prescribed position of node 0"),
    ("v_start", 3, "m/s", "prescribed velocity of node 0"),
    ("a_start", 3, "m/s^2", "prescribed acceleration of node 0 (its support's reaction)"),
    ("p_start", 4, "1", "clamp frame quaternion at s = 0 (scalar first)"),
    ("Omega_start", 3, "rad/s", "material angular velocity of the clamp frame at s = 0"),
    ("r_end", 3, "m", "prescribed position of node N"),
    ("v_end", 3, "m/s", "prescribed velocity of node N"),
    ("a_end", 3, "m/s^2", "prescribed acceleration of node N (its support's reaction)"),
    ("p_end", 4, "1", "clamp frame quaternion at s = L (scalar first)"),
    ("Omega_end", 3, "rad/s", "material angular velocity of the clamp frame at s = L"),
    ("m_dead_start", 3, "N m", "dead point moment applied at node 0 (spatial; also in "
                               "segment 1's m_dead): a free end's condensation of a "
                               "coupled rod carries it"),
    ("m_follower_start", 3, "N m", "follower point moment applied at node 0 (material; "
                                   "also in segment 1's m_follower)"),
    ("m_dead_end", 3, "N m", "dead point moment applied at node N (spatial; also in "
                             "segment N's m_dead)"),
    ("m_follower_end", 3, "N m", "follower point moment applied at node N (material; "
                                 "also in segment N's m_follower)"),
)


def _offsets(fields) -> dict[str, int]:
    out, k = {}, 0
    for f in fields:
        out[f[0]] = k
        k += f[1]
    return out


def _size(fields) -> int:
    return sum(f[1] for f in fields)


CELL0_SIZE = _size(CELL0_FIELDS)
CELL_SIZE = _size(CELL_FIELDS)
CELL0_OFFSETS = _offsets(CELL0_FIELDS)
CELL_OFFSETS = _offsets(CELL_FIELDS)
PARAM_OFFSETS = _offsets(PARAMS)
PARAM_SIZES = {name: size for name, size, *_ in PARAMS}
N_PARAMS = _size(PARAMS)
SEGMENT_OFFSETS, N_SEGMENT = _offsets(SEGMENT_PARAMS), _size(SEGMENT_PARAMS)
JOINT_OFFSETS, N_JOINT = _offsets(JOINT_PARAMS), _size(JOINT_PARAMS)
NODE_LOAD_OFFSETS, N_NODE_LOAD = _offsets(NODE_LOADS), _size(NODE_LOADS)
SEGMENT_LOAD_OFFSETS, N_SEGMENT_LOAD = _offsets(SEGMENT_LOADS), _size(SEGMENT_LOADS)

#: reduced coordinates of the static problem: cell 0 = dphi_0, cell i = (dtheta_i, dphi_i)
STATIC_CELL0_FIELDS: tuple[tuple[str, int], ...] = (("phi", 3),)
STATIC_CELL_FIELDS: tuple[tuple[str, int], ...] = (("theta", 3), ("phi", 3))
STATIC_CELL0_SIZE = _size(STATIC_CELL0_FIELDS)
STATIC_CELL_SIZE = _size(STATIC_CELL_FIELDS)
STATIC_CELL_OFFSETS = _offsets(STATIC_CELL_FIELDS)


def static_cell_start(i: int) -> int:
    """Index of the first static unknown of cell i (cell 0: node 0's phi)."""
    return 0 if i == 0 else STATIC_CELL0_SIZE + STATIC_CELL_SIZE * (i - 1)


#: diagnostics vector: scalars then per-element arrays (sizes in multiples of N or N+1).
#: The scalars: kinetic and elastic energy (J), dissipation rate 2D, power of the loads and
#: of the prescribed end motion (W), then the force (N) and moment (N m, about the node)
#: that each support exerts on the rod, spatial (zero at a free end; the moment also at a
#: pinned one): m a - f_ext - f_int at the held node, minus the clamp joint's torque on
#: the clamp frame
DIAG_ENERGIES = ("kinetic", "elastic", "dissipation_rate", "external_power",
                 "boundary_power")
DIAG_REACTIONS = tuple(f"{end}_{what}_{c}" for end in ("start", "end")
                       for what in ("force", "moment") for c in "xyz")
DIAG_SCALARS = DIAG_ENERGIES + DIAG_REACTIONS

# --------------------------------------------------------------------------------------
# Quaternion algebra (scalar part first), CasADi SX
# --------------------------------------------------------------------------------------


def skew(a):
    """[a]x, the 3x3 cross-product matrix."""
    return ca.vertcat(
        ca.horzcat(0, -a[2], a[1]),
        ca.horzcat(a[2], 0, -a[0]),
        ca.horzcat(-a[1], a[0], 0),
    )


def qmul(a, b):
    """Quaternion product a*b (4-vectors, scalar first)."""
    a0, av, b0, bv = a[0], a[1:4], b[0], b[1:4]
    return ca.vertcat(a0 * b0 - ca.dot(av, bv), a0 * bv + b0 * av + ca.cross(av, bv))


def qconj(a):
    """Conjugate quaternion."""
    return ca.vertcat(a[0], -a[1:4])


def left_matrix(p):
    """L(p) with p*q = L(p) q (4x4)."""
    p0, q = p[0], p[1:4]
    top = ca.horzcat(p0, -q.T)
    bot = ca.horzcat(q, p0 * ca.SX.eye(3) + skew(q))
    return ca.vertcat(top, bot)


def rotation(p):
    """R(p), homogeneous of degree 0 in p: [(p0^2-|q|^2) I + 2 q q^T + 2 p0 [q]x] / |p|^2."""
    p0, q = p[0], p[1:4]
    n2 = ca.dot(p, p)
    return ((p0**2 - ca.dot(q, q)) * ca.SX.eye(3) + 2 * (q @ q.T) + 2 * p0 * skew(q)) / n2


def qdot(p, omega):
    """Kinematic equation p' = 1/2 p*(0, Omega) (material angular velocity)."""
    return 0.5 * qmul(p, ca.vertcat(0, omega))


def torque_from_gradient(p, dWdp):
    """Material torque conjugate to Omega: T = -1/2 vec(L(p)^T dW/dp) (valid for any |p|)."""
    return -0.5 * (left_matrix(p).T @ dWdp)[1:4]


def _field(vec, offsets: dict[str, int], fields, name: str):
    k, size = offsets[name], dict((f[0], f[1]) for f in fields)[name]
    return vec[k] if size == 1 else vec[k : k + size]


def _seg(sp, name):
    """A named entry of the segment parameter vector (:data:`SEGMENT_PARAMS`)."""
    return _field(sp, SEGMENT_OFFSETS, SEGMENT_PARAMS, name)


def _jnt(jp, name):
    """A named entry of the joint parameter vector (:data:`JOINT_PARAMS`)."""
    return _field(jp, JOINT_OFFSETS, JOINT_PARAMS, name)


def _quad(diag, x):
    return ca.dot(x, diag * x)


# --------------------------------------------------------------------------------------
# Strains and element functionals
# --------------------------------------------------------------------------------------


def shear_strain(phi_a, phi_b, p, h):
    """V = R(p)^T (phi_b - phi_a)/h (3,), dimensionless."""
    return rotation(p).T @ (phi_b - phi_a) / h


def curvature(p_a, p_b, hj):
    """Cayley curvature U = (2/h_j) Im(r)/Re(r), r = conj(p_a) p_b (3,), 1/m."""
    r = qmul(qconj(p_a), p_b)
    return 2.0 / hj * r[1:4] / r[0]


@dataclass(frozen=True)
class _Sym:
    phi_a: ca.SX
    phi_b: ca.SX
    p: ca.SX
    v_a: ca.SX
    v_b: ca.SX
    omega: ca.SX
    p_b: ca.SX
    omega_b: ca.SX
    sp: ca.SX      # segment parameters (SEGMENT_PARAMS)
    jp: ca.SX      # joint parameters (JOINT_PARAMS)
    n_q: ca.SX     # resultant of the relaxation terms on a segment (3, N): -sum_b C_b q_b
    m_q: ca.SX     # the same on a joint (3, N m): -sum_b C_b q_b


def _symbols() -> _Sym:
    S = ca.SX.sym
    return _Sym(S("phi_a", 3), S("phi_b", 3), S("p", 4), S("v_a", 3), S("v_b", 3),
                S("Omega", 3), S("p_b", 4), S("Omega_b", 3), S("seg", N_SEGMENT),
                S("jnt", N_JOINT), S("n_q", 3), S("m_q", 3))


def rotate_transposed(p, x):
    """R(p)^T x without forming R (degree 0 in p)."""
    p0, q = p[0], p[1:4]
    return ((p0**2 - ca.dot(q, q)) * x + 2 * ca.dot(q, x) * q - 2 * p0 * ca.cross(q, x)) / ca.dot(
        p, p)


def rotate(p, x):
    """R(p) x without forming R (degree 0 in p)."""
    p0, q = p[0], p[1:4]
    return ((p0**2 - ca.dot(q, q)) * x + 2 * ca.dot(q, x) * q + 2 * p0 * ca.cross(q, x)) / ca.dot(
        p, p)


# -- the functionals (definitions) -----------------------------------------------------


def segment_functionals(s: _Sym) -> dict[str, ca.SX]:
    """V, its exact rate Vdot, elastic energy W and dissipation function D of a segment.

    ``W = h/2 dV^T C_F dV`` (10), ``D = h/2 Vdot^T V_F Vdot`` (11). The rate is the
    forward-AD derivative of V along ``phi' = v``, ``p' = 1/2 p*(0, Omega)``.
    """
    h = _seg(s.sp, "h")
    V = shear_strain(s.phi_a, s.phi_b, s.p, h)
    Vdot = ca.jtimes(V, ca.vertcat(s.phi_a, s.phi_b, s.p),
                     ca.vertcat(s.v_a, s.v_b, qdot(s.p, s.omega)))
    dV = V - _seg(s.sp, "V0")
    return {"V": V, "Vdot": Vdot, "W": h / 2 * _quad(_seg(s.sp, "C_F"), dV),
            "D": h / 2 * _quad(_seg(s.sp, "V_F"), Vdot)}


def joint_functionals(s: _Sym) -> dict[str, ca.SX]:
    """U, its exact rate Udot, W and D of a joint of length h_j (Cayley curvature)."""
    hj = _jnt(s.jp, "h")
    U = curvature(s.p, s.p_b, hj)
    Udot = ca.jtimes(U, ca.vertcat(s.p, s.p_b),
                     ca.vertcat(qdot(s.p, s.omega), qdot(s.p_b, s.omega_b)))
    dU = U - _jnt(s.jp, "U0")
    return {"U": U, "Udot": Udot, "W": hj / 2 * _quad(_jnt(s.jp, "C_M"), dU),
            "D": hj / 2 * _quad(_jnt(s.jp, "V_M"), Udot)}


def segment_forces_ad(s: _Sym) -> ca.SX:
    """Generalized forces of a segment by CasADi AD of W and D (the definition).

    ``Q = [-dW/dphi_a - dD/dv_a; -dW/dphi_b - dD/dv_b; T]`` with the torque
    ``T = -1/2 vec(L(p)^T dW/dp) - dD/dOmega``; the relaxation terms' resultant ``n_q``
    (held fixed here, :func:`branch_quantities`) adds the work ``h n_q . dV``.
    """
    f = segment_functionals(s)
    Wq = f["W"] + _seg(s.sp, "h") * ca.dot(s.n_q, f["V"] - _seg(s.sp, "V0"))
    gW = ca.gradient(Wq, ca.vertcat(s.phi_a, s.phi_b, s.p))
    gD = ca.gradient(f["D"], ca.vertcat(s.v_a, s.v_b, s.omega))
    return ca.vertcat(-gW[0:3], -gW[3:6], torque_from_gradient(s.p, gW[6:10])) - gD


def joint_torques_ad(s: _Sym) -> ca.SX:
    """Torques of a joint on its two segments by CasADi AD of W and D (the definition);
    the relaxation terms' resultant ``m_q`` adds the work ``h_j m_q . dU``."""
    f = joint_functionals(s)
    Wq = f["W"] + _jnt(s.jp, "h") * ca.dot(s.m_q, f["U"] - _jnt(s.jp, "U0"))
    gW = ca.gradient(Wq, ca.vertcat(s.p, s.p_b))
    gD = ca.gradient(f["D"], ca.vertcat(s.omega, s.omega_b))
    return ca.vertcat(torque_from_gradient(s.p, gW[0:4]),
                      torque_from_gradient(s.p_b, gW[4:8])) - gD


# -- the same quantities in closed form (what the kernels evaluate) --------------------


def segment_quantities(s: _Sym) -> dict[str, ca.SX]:
    """Closed forms of the segment's strain, rate, W, D, resultant and forces.

    With the resultant ``n = C_F dV + V_F Vdot`` (eq. (1)) the virtual work of W and D gives
    ``f_b = -R n``, ``f_a = R n``, ``T = h V x n``; the rate is
    ``Vdot = R^T (v_b - v_a)/h + V x Omega``. These are identically the AD derivatives
    (:func:`segment_forces_ad`, :func:`segment_functionals`; equality is tested to
    rounding) but cost about a third to evaluate and to differentiate again.
    """
    h = _seg(s.sp, "h")
    V = rotate_transposed(s.p, s.phi_b - s.phi_a) / h
    dV = V - _seg(s.sp, "V0")
    Vdot = rotate_transposed(s.p, s.v_b - s.v_a) / h + ca.cross(V, s.omega)
    C_F, V_F = _seg(s.sp, "C_F"), _seg(s.sp, "V_F")
    n = C_F * dV + V_F * Vdot + s.n_q
    Rn = rotate(s.p, n)
    Q = ca.vertcat(Rn, -Rn, h * ca.cross(V, n))
    return {"V": V, "Vdot": Vdot, "W": h / 2 * _quad(C_F, dV), "D": h / 2 * _quad(V_F, Vdot),
            "Q": Q, "F": n}


def joint_quantities(s: _Sym) -> dict[str, ca.SX]:
    """Closed forms of the joint's curvature, rate, W, D, resultant and torques.

    With ``r = conj(p_a) p_b``, ``u = Im(r)/Re(r)``, ``U = (2/h_j) u``,
    ``A = I + [u]x + u u^T`` (so that ``dU = (1/h_j) A dtheta_b`` for
    ``p_b <- p_b*exp(dtheta_b/2)``), ``w = Omega_b - R(r)^T Omega_a``:
    ``Udot = A w / h_j``, resultant ``m = C_M dU + V_M Udot``, torques
    ``T_b = -A^T m``, ``T_a = R(r) A^T m``. Identically the AD derivatives
    (:func:`joint_torques_ad`; tested).
    """
    r = qmul(qconj(s.p), s.p_b)
    return _joint_of_r(r, s.omega, s.omega_b, s.jp, s.m_q)


def _joint_of_r(r, oa, ob, jp, m_q) -> dict[str, ca.SX]:
    hj = _jnt(jp, "h")
    u = r[1:4] / r[0]
    U = 2.0 / hj * u
    w = ob - rotate_transposed(r, oa)
    Aw = w + ca.cross(u, w) + u * ca.dot(u, w)
    Udot = Aw / hj
    dU = U - _jnt(jp, "U0")
    C_M, V_M = _jnt(jp, "C_M"), _jnt(jp, "V_M")
    m = C_M * dU + V_M * Udot + m_q
    Atm = m - ca.cross(u, m) + u * ca.dot(u, m)
    T = ca.vertcat(rotate(r, Atm), -Atm)
    return {"U": U, "Udot": Udot, "W": hj / 2 * _quad(C_M, dU), "D": hj / 2 * _quad(V_M, Udot),
            "T": T, "M": m}


def _joint_torques_of_r(r, oa, ob, jp, m_q) -> ca.SX:
    return _joint_of_r(r, oa, ob, jp, m_q)["T"]


def branch_quantities(s: _Sym) -> dict[str, ca.SX]:
    """What the relaxation terms (generalized Maxwell rod) need of an element.

    Each of B terms b carries an internal strain ``q_b`` per element that relaxes toward
    the element's strain, ``q_b' = (dV - q_b)/theta_b`` (segment, ``dV = V - V0``) and
    ``q_b' = (dU - q_b)/theta_b`` (joint, ``dU = U - U0``), with the resultant
    ``n = C_inf dV + sum_b C_b (dV - q_b) = C_F dV + n_q``, ``C_F = C_inf + sum_b C_b`` (the
    instantaneous stiffness) and ``n_q = -sum_b C_b q_b`` (and likewise ``m`` on joints).
    The assembly therefore needs the strain, its derivative and the forces per unit
    resultant: segment ``dV``, ``d dV/d(phi_b, p)`` (3x7; ``d/dphi_a = -d/dphi_b``) and
    ``G = d(f_b, T)/dn`` (6x3); joint ``dU``, ``d dU/d(p_a, p_b)`` (3x8) and
    ``G = d(T_a, T_b)/dm`` (6x3).
    """
    seg = segment_quantities(s)
    dV = seg["V"] - _seg(s.sp, "V0")
    jnt = joint_quantities(s)
    dU = jnt["U"] - _jnt(s.jp, "U0")
    return {"dV": dV, "dV_dx": ca.jacobian(dV, ca.vertcat(s.phi_b, s.p)),
            "G_seg": ca.jacobian(seg["Q"][3:9], s.n_q),
            "dU": dU, "dU_dx": ca.jacobian(dU, ca.vertcat(s.p, s.p_b)),
            "G_jnt": ca.jacobian(jnt["T"], s.m_q)}


def _increment_projection(p):
    """P(p) (3x4) with dtheta = P(p) dp for p <- p*exp(dtheta/2): 2 vec(conj(p) dp)/|p|^2.

    Exact for the derivative of any function that is homogeneous of degree 0 in p (the
    radial part of dp does not change it)."""
    return 2 / ca.dot(p, p) * ca.horzcat(-p[1:4], p[0] * ca.SX.eye(3) - skew(p[1:4]))


def _right_matrix(q):
    """Rm(q) with a*q = Rm(q) a (4x4)."""
    q0, v = q[0], q[1:4]
    return ca.vertcat(ca.horzcat(q0, -v.T), ca.horzcat(v, q0 * ca.SX.eye(3) - skew(v)))


def segment_jacobian(s: _Sym) -> ca.SX:
    """d(f_b, T)/d(phi_b, p, v_b, Omega) (6x13) of :func:`segment_quantities`, closed form.

    With R = R(p), V = R^T d/h, g = R^T (v_b - v_a)/h, n = C_F dV + V_F (g + V x Omega),
    ``dn/dV = C_F - V_F [Omega]x`` and, for the rotation increment p <- p*exp(theta/2)
    (V -> V + V x theta, g -> g + g x theta, R -> R (I + [theta]x)),
    ``dn/dtheta = C_F [V]x + V_F ([g]x - [Omega]x [V]x)``; f_b = -R n and T = h V x n give
    the blocks below. The p columns are d/dtheta times :func:`_increment_projection`
    (exact because f_b and T are homogeneous of degree 0 in p). Equal to CasADi AD of
    :func:`segment_forces_ad` to rounding (tested); about 3x cheaper.
    """
    h = _seg(s.sp, "h")
    R = rotation(s.p)
    RT = R.T
    V = RT @ (s.phi_b - s.phi_a) / h
    g = RT @ (s.v_b - s.v_a) / h
    C, Vf = ca.diag(_seg(s.sp, "C_F")), ca.diag(_seg(s.sp, "V_F"))
    n = C @ (V - _seg(s.sp, "V0")) + Vf @ (g + ca.cross(V, s.omega)) + s.n_q
    Vx, nx, Ox = skew(V), skew(n), skew(s.omega)
    NV = C - Vf @ Ox
    Nth = C @ Vx + Vf @ (skew(g) - Ox @ Vx)
    J_phi = ca.vertcat(-R @ NV @ RT / h, (Vx @ NV - nx) @ RT)
    J_th = ca.vertcat(-R @ (Nth - nx), h * (Vx @ Nth - nx @ Vx))
    J_v = ca.vertcat(-R @ Vf @ RT / h, Vx @ Vf @ RT)
    J_om = ca.vertcat(-R @ Vf @ Vx, h * Vx @ Vf @ Vx)
    return ca.horzcat(J_phi, J_th @ _increment_projection(s.p), J_v, J_om)


def joint_jacobian(s: _Sym) -> ca.SX:
    """d(T_a, T_b)/d(p_a, p_b, Omega_a, Omega_b) (6x14) of :func:`joint_quantities`.

    The torques depend on the quaternions through r = conj(p_a) p_b only and are homogeneous
    of degree 0 in r. Under r <- r*exp(theta/2): u <- u + 1/2 A theta, R(r) <- R(r)(I +
    [theta]x) to first order; CasADi AD in theta at 0 gives J_theta (6x3), and
    ``p_b <- p_b*exp(theta_b/2)`` is ``theta = theta_b``, ``p_a <- p_a*exp(theta_a/2)`` is
    ``theta = -R(r)^T theta_a``, so d/dp_b = J_theta P(p_b) and
    d/dp_a = -J_theta R(r)^T P(p_a) (:func:`_increment_projection`).
    """
    pa, pb, oa, ob, jp = s.p, s.p_b, s.omega, s.omega_b, s.jp
    hj = _jnt(jp, "h")
    r = qmul(qconj(pa), pb)
    u0 = r[1:4] / r[0]
    a0 = rotate_transposed(r, oa)
    th = ca.SX.sym("theta", 3)
    u = u0 + 0.5 * (th + ca.cross(u0, th) + u0 * ca.dot(u0, th))
    w = ob - (a0 + ca.cross(a0, th))
    Aw = w + ca.cross(u, w) + u * ca.dot(u, w)
    m = _jnt(jp, "C_M") * (2.0 / hj * u - _jnt(jp, "U0")) + _jnt(jp, "V_M") * Aw / hj + s.m_q
    Atm = m - ca.cross(u, m) + u * ca.dot(u, m)
    T = ca.vertcat(rotate(r, Atm + ca.cross(th, Atm)), -Atm)
    J_th = ca.substitute(ca.jacobian(T, th), th, ca.DM.zeros(3))
    # T is affine in w = Omega_b - R^T Omega_a: dT_b/dw = -A^T V_M A / h_j, dT_a/dw = -R dT_b/dw
    R = rotation(r)
    A = ca.SX.eye(3) + skew(u0) + u0 @ u0.T
    K = A.T @ (ca.diag(_jnt(jp, "V_M")) @ A) / hj
    J_w = ca.vertcat(R @ K, -K)
    return ca.horzcat(-J_th @ R.T @ _increment_projection(pa),
                      J_th @ _increment_projection(pb), -J_w @ R.T, J_w)


# --------------------------------------------------------------------------------------
# Kernels
# --------------------------------------------------------------------------------------

_OPTS = {"cse": True}


def _fn(name, ins: dict, outs: dict) -> ca.Function:
    return ca.Function(name, list(ins.values()), list(outs.values()), list(ins), list(outs),
                       _OPTS)


def kernels() -> list[ca.Function]:
    """All per-element CasADi kernels, in a fixed order (see their docstrings in layout).

    Segment stencil inputs: phi_a, phi_b (3), p (4), v_a, v_b (3), Omega (3), seg
    (:data:`SEGMENT_PARAMS`). Joint stencil inputs: p_a, p_b (4), Omega_a, Omega_b (3), jnt
    (:data:`JOINT_PARAMS`). Jacobian kernels return dense blocks (column-major in C). The
    segment Jacobian is reduced: rows (force on node b, torque), columns (phi_b, p, v_b,
    Omega); since the segment depends on phi_b - phi_a and v_b - v_a only and its forces
    balance (f_a = -f_b), d/dphi_a = -d/dphi_b, d/dv_a = -d/dv_b and df_a = -df_b.
    The external loads enter through :func:`rotate` (follower forces, material -> spatial)
    and :func:`rotate_transposed` (dead moments, spatial -> material).
    """
    s = _symbols()
    S = ca.SX.sym
    seg_in = {"phi_a": s.phi_a, "phi_b": s.phi_b, "p": s.p, "v_a": s.v_a, "v_b": s.v_b,
              "Omega": s.omega, "seg": s.sp, "n_q": s.n_q}
    seg = segment_quantities(s)
    jnt_in = {"p_a": s.p, "p_b": s.p_b, "Omega_a": s.omega, "Omega_b": s.omega_b,
              "jnt": s.jp, "m_q": s.m_q}
    jnt = joint_quantities(s)
    br = branch_quantities(s)

    # segment inertia and kinematics rows: [p' - 1/2 p*(0,Omega); J Omega' + Omega x J Omega]
    p, om = s.p, s.omega
    pd, omd = S("p_dot", 4), S("Omega_dot", 3)
    cy, cj = S("c_y"), S("c_j")
    Jd = _seg(s.sp, "h") * _seg(s.sp, "rhoI")
    r_seg = ca.vertcat(pd - qdot(p, om), Jd * omd + ca.cross(om, Jd * om))
    xs, xds = ca.vertcat(p, om), ca.vertcat(pd, omd)
    J_seg = cy * ca.jacobian(r_seg, xs) + cj * ca.jacobian(r_seg, xds)
    seg_in_in = {"p": p, "Omega": om, "p_dot": pd, "Omega_dot": omd, "seg": s.sp}

    # node rows: [phi' - v; m v' - f] for a free node, [phi - r_held; v - v_held] for a
    # held one: its position and velocity are prescribed (algebraic rows), so a held end
    # sits at r(t) to round-off at every step rather than at the integral of v(t) to the
    # integration error; f is the total external force
    phi, v = s.phi_a, s.v_a
    phid, vd = S("phi_dot", 3), S("v_dot", 3)
    m, f, held = S("m"), S("f", 3), S("held")
    rr, vr = S("r_held", 3), S("v_held", 3)
    r_node = ca.vertcat((1 - held) * (phid - v) + held * (phi - rr),
                        (1 - held) * (m * vd - f) + held * (v - vr))
    xn, xdn = ca.vertcat(phi, v), ca.vertcat(phid, vd)
    J_node = cy * ca.jacobian(r_node, xn) + cj * ca.jacobian(r_node, xdn)
    node_in = {"phi": phi, "v": v, "phi_dot": phid, "v_dot": vd, "m": m, "f": f,
               "held": held, "r_held": rr, "v_held": vr}

    x = S("x", 3)
    return [
        _fn("rod_segment_forces", seg_in, {"Q": seg["Q"]}),
        _fn("rod_segment_forces_jac", seg_in, {"dQb_dxb": ca.densify(segment_jacobian(s))}),
        _fn("rod_joint_torques", jnt_in, {"T": jnt["T"]}),
        _fn("rod_joint_torques_jac", jnt_in, {"dT_dx": ca.densify(joint_jacobian(s))}),
        _fn("rod_segment_inertia", seg_in_in, {"r": r_seg}),
        _fn("rod_segment_inertia_jac", {**seg_in_in, "c_y": cy, "c_j": cj},
            {"J": ca.densify(J_seg)}),
        _fn("rod_node_inertia", node_in, {"r": r_node}),
        _fn("rod_node_inertia_jac", {**node_in, "c_y": cy, "c_j": cj}, {"J": ca.densify(J_node)}),
        _fn("rod_rotate", {"p": p, "x": x}, {"Rx": rotate(p, x)}),
        _fn("rod_rotate_jac", {"p": p, "x": x}, {"dRx_dp": ca.densify(
            ca.jacobian(rotate(p, x), p))}),
        _fn("rod_rotate_transposed", {"p": p, "x": x}, {"RTx": rotate_transposed(p, x)}),
        _fn("rod_rotate_transposed_jac", {"p": p, "x": x}, {"dRTx_dp": ca.densify(
            ca.jacobian(rotate_transposed(p, x), p))}),
        _fn("rod_segment_diagnostics", seg_in,
            {"W": seg["W"], "D": seg["D"], "V": seg["V"], "F": seg["F"]}),
        _fn("rod_joint_diagnostics", jnt_in,
            {"W": jnt["W"], "D": jnt["D"], "U": jnt["U"], "M": jnt["M"]}),
        _fn("rod_segment_kinetic", {"Omega": om, "seg": s.sp},
            {"T": 0.5 * ca.dot(om, Jd * om)}),
        _fn("rod_node_kinetic", {"v": v, "m": m}, {"T": 0.5 * m * ca.dot(v, v)}),
        _fn("rod_segment_branch", {"phi_a": s.phi_a, "phi_b": s.phi_b, "p": s.p,
                                   "seg": s.sp},
            {"dV": br["dV"], "dV_dx": ca.densify(br["dV_dx"]),
             "G": ca.densify(br["G_seg"])}),
        _fn("rod_joint_branch", {"p_a": s.p, "p_b": s.p_b, "jnt": s.jp},
            {"dU": br["dU"], "dU_dx": ca.densify(br["dU_dx"]),
             "G": ca.densify(br["G_jnt"])}),
        # a generalized Maxwell rod's residual: the forces (torques) and the strains of
        # its relaxation rows from one call. The force kernels form these strains anyway;
        # a strain kernel of their own per element (round 3 to 8) cost ~1 us a residual
        # at N = 50. The same SX nodes: the same values as rod_segment_forces and the
        # branch kernels' dV (dU), bit for bit
        _fn("rod_segment_forces_strain", seg_in, {"Q": seg["Q"], "dV": br["dV"]}),
        _fn("rod_joint_torques_strain", jnt_in, {"T": jnt["T"], "dU": br["dU"]}),
    ]


# --------------------------------------------------------------------------------------
# Coupled sections (issue 26): full 6x6 stiffness and viscosity, mass centre off the
# centreline, product of inertia (docs/design.md, section 10)
# --------------------------------------------------------------------------------------

#: per-segment parameters of a rod with coupled sections, beside :data:`SEGMENT_PARAMS`
#: (whose h, V0 and rhoA they use); matrices row-major 3x3 blocks of the section's 6x6
#: matrices in the order (Gamma1, Gamma2, Gamma3, K1, K2, K3) about the centreline
COUPLED_SEGMENT_PARAMS: tuple[tuple[str, int, str, str], ...] = (
    ("C_FF", 9, "N", "stiffness block (Gamma, Gamma), symmetric"),
    ("V_FF", 9, "N s", "viscosity block (Gamma, Gamma), symmetric"),
    ("C_FM", 9, "N m", "stiffness block (Gamma, K): n += C_FM K, m += C_FM^T Gamma"),
    ("V_FM", 9, "N m s", "viscosity block (Gamma, K)"),
    ("w", 2, "m", "weights of the couplings with the joints at nodes i-1 and i "
                  "(h/2 each; 0 where the joint is absent: a free end)"),
    ("rhoJ", 9, "kg m", "rotary inertia per length about the mass centre, 3x3 "
                        "((I11, -I12, 0), (-I12, I22, 0), (0, 0, I33)) rho"),
    ("e", 3, "m", "mass centre in the material frame (e1, e2, 0)"),
    ("C_FE", 9, "1/m", "a free end's share of its applied moment M (material) in the "
                       "resultant: n += C_FE M (1/2 C_FM C_MM^-1 on a free end's segment, "
                       "0 elsewhere; M enters with its sign at s = L, negated at s = 0)"),
)
#: per-joint parameters of a rod with coupled sections, beside :data:`JOINT_PARAMS`
COUPLED_JOINT_PARAMS: tuple[tuple[str, int, str, str], ...] = (
    ("C_MM", 9, "N m^2", "stiffness block (K, K), symmetric"),
    ("V_MM", 9, "N m^2 s", "viscosity block (K, K), symmetric"),
)
COUPLED_SEGMENT_OFFSETS, N_COUPLED_SEGMENT = (_offsets(COUPLED_SEGMENT_PARAMS),
                                              _size(COUPLED_SEGMENT_PARAMS))
COUPLED_JOINT_OFFSETS, N_COUPLED_JOINT = (_offsets(COUPLED_JOINT_PARAMS),
                                          _size(COUPLED_JOINT_PARAMS))


def _cseg(sc, name):
    return _field(sc, COUPLED_SEGMENT_OFFSETS, COUPLED_SEGMENT_PARAMS, name)


def _cjnt(jc, name):
    return _field(jc, COUPLED_JOINT_OFFSETS, COUPLED_JOINT_PARAMS, name)


def _mat3(v):
    """3x3 matrix from 9 row-major entries."""
    return ca.reshape(v, 3, 3).T


def _sym3(v):
    """Symmetric part of the 3x3 matrix of 9 row-major entries (the quadratic forms'
    matrix; the tables hold symmetric blocks, checked where they are built)."""
    M = _mat3(v)
    return 0.5 * (M + M.T)


@dataclass(frozen=True)
class _CSym:
    """Inputs of the coupled segment kernels: segment i, its nodes a = i-1, b = i, its
    neighbours' quaternions and angular velocities (p_a: segment i-1 or the clamp frame
    at s = 0; p_b: segment i+1 or the clamp frame at s = L), the two joints' rows, and
    the moment applied at the rod's free ends among its nodes (:func:`end_moment`)."""

    phi_a: ca.SX
    phi_b: ca.SX
    p_a: ca.SX
    p: ca.SX
    p_b: ca.SX
    v_a: ca.SX
    v_b: ca.SX
    omega_a: ca.SX
    omega: ca.SX
    omega_b: ca.SX
    sp: ca.SX       # SEGMENT_PARAMS
    sc: ca.SX       # COUPLED_SEGMENT_PARAMS
    ja: ca.SX       # JOINT_PARAMS of joint i-1
    jb: ca.SX       # JOINT_PARAMS of joint i
    m_end: ca.SX    # (dead 3 spatial, follower 3 material): M_b - M_a of the free ends


def _csymbols() -> _CSym:
    S = ca.SX.sym
    return _CSym(S("phi_a", 3), S("phi_b", 3), S("p_a", 4), S("p", 4), S("p_b", 4),
                 S("v_a", 3), S("v_b", 3), S("Omega_a", 3), S("Omega", 3), S("Omega_b", 3),
                 S("seg", N_SEGMENT), S("segc", N_COUPLED_SEGMENT), S("jnt_a", N_JOINT),
                 S("jnt_b", N_JOINT), S("m_end", 6))


def end_moment(c: _CSym) -> ca.SX:
    """The moment M (material, N m) that the free ends among segment i's nodes apply,
    in the segment's frame: ``R(p)^T m_dead + m_follower`` of the input ``m_end``, which
    holds the moment at node i (a free end at s = L) minus that at node i-1 (a free end
    at s = 0), scaled by the load factor; zero where no node of the segment is a free
    end. The free end's condensation adds ``C_FE M`` to the segment's resultant
    (docs/design.md, section 10, "Free ends")."""
    return rotate_transposed(c.p, c.m_end[0:3]) + c.m_end[3:6]


def coupled_segment_functionals(c: _CSym) -> dict[str, ca.SX]:
    """Strains, rates, W and D of segment i of a rod with coupled sections (the
    definitions; docs/design.md, section 10).

    ``W_i = h/2 dG^T C_FF dG + w_a dG^T C_FM dU_a + w_b dG^T C_FM dU_b`` with
    ``dG = Gamma_i - V0_i``, ``dU_a = U_{i-1} - U0_{i-1}`` (joint at node i-1, between
    p_a and p), ``dU_b = U_i - U0_i`` (joint at node i, between p and p_b) and
    ``w_a = w_b = h/2``: the coupling with the mean curvature (U_{i-1} + U_i)/2 of the
    segment's two joints; D likewise with V and the exact rates. The joints' own
    ``h_j/2 dU^T C_MM dU`` is in :func:`coupled_joint_quantities`. The end moment's
    term of a free end's condensation is a load (:func:`coupled_segment_forces_ad`).
    """
    h = _seg(c.sp, "h")
    G = shear_strain(c.phi_a, c.phi_b, c.p, h)
    Ua = curvature(c.p_a, c.p, _jnt(c.ja, "h"))
    Ub = curvature(c.p, c.p_b, _jnt(c.jb, "h"))
    x = ca.vertcat(c.phi_a, c.phi_b, c.p_a, c.p, c.p_b)
    xd = ca.vertcat(c.v_a, c.v_b, qdot(c.p_a, c.omega_a), qdot(c.p, c.omega),
                    qdot(c.p_b, c.omega_b))
    Gd, Uad, Ubd = (ca.jtimes(e, x, xd) for e in (G, Ua, Ub))
    dG = G - _seg(c.sp, "V0")
    dUa, dUb = Ua - _jnt(c.ja, "U0"), Ub - _jnt(c.jb, "U0")
    wa, wb = _cseg(c.sc, "w")[0], _cseg(c.sc, "w")[1]
    CFF, VFF = _sym3(_cseg(c.sc, "C_FF")), _sym3(_cseg(c.sc, "V_FF"))
    CFM, VFM = _mat3(_cseg(c.sc, "C_FM")), _mat3(_cseg(c.sc, "V_FM"))
    W = h / 2 * ca.dot(dG, CFF @ dG) + ca.dot(dG, CFM @ (wa * dUa + wb * dUb))
    D = h / 2 * ca.dot(Gd, VFF @ Gd) + ca.dot(Gd, VFM @ (wa * Uad + wb * Ubd))
    return {"V": G, "Vdot": Gd, "dV": dG, "dUa": dUa, "dUb": dUb, "Uad": Uad, "Ubd": Ubd,
            "W": W, "D": D}


def coupled_segment_forces_ad(c: _CSym) -> ca.SX:
    """Forces of a coupled segment on its nodes and torques on its own and neighbouring
    segments, ``Q = (f_a, f_b, T_a, T, T_b)`` (15), by CasADi AD of W and D (the
    definition, as :func:`segment_forces_ad`: the torque conjugate to each Omega is
    ``-1/2 vec(L(p)^T dW/dp) - dD/dOmega``).

    A free end's applied moment M (:func:`end_moment`) adds the potential
    ``h dG^T C_FE M`` of the condensed virtual joint, differentiated at fixed M (the
    moment's own turning with a dead load is the applied torque's, not the joint's)."""
    f = coupled_segment_functionals(c)
    M = ca.SX.sym("M_fixed", 3)
    W = f["W"] + _seg(c.sp, "h") * ca.dot(f["dV"], _mat3(_cseg(c.sc, "C_FE")) @ M)
    gW = ca.gradient(W, ca.vertcat(c.phi_a, c.phi_b, c.p_a, c.p, c.p_b))
    gD = ca.gradient(f["D"], ca.vertcat(c.v_a, c.v_b, c.omega_a, c.omega, c.omega_b))
    Q = ca.vertcat(-gW[0:3] - gD[0:3], -gW[3:6] - gD[3:6],
                   torque_from_gradient(c.p_a, gW[6:10]) - gD[6:9],
                   torque_from_gradient(c.p, gW[10:14]) - gD[9:12],
                   torque_from_gradient(c.p_b, gW[14:18]) - gD[12:15])
    return ca.substitute(Q, M, end_moment(c))


def _joint_kinematics(p_l, p_r, o_l, o_r, hj):
    """u = Im(r)/Re(r), U = 2u/h_j, Udot = A w/h_j (w = Omega_r - R(r)^T Omega_l) of a
    joint between frames p_l, p_r (r = conj(p_l) p_r), and the torques it exerts for a
    moment m: ``(R(r) A^T m, -A^T m)`` (:func:`joint_quantities`)."""
    r = qmul(qconj(p_l), p_r)
    u = r[1:4] / r[0]
    w = o_r - rotate_transposed(r, o_l)
    Udot = (w + ca.cross(u, w) + u * ca.dot(u, w)) / hj

    def torques(m):
        Atm = m - ca.cross(u, m) + u * ca.dot(u, m)
        return rotate(r, Atm), -Atm

    return 2.0 / hj * u, Udot, torques


def coupled_segment_quantities(c: _CSym) -> dict[str, ca.SX]:
    """Closed forms of :func:`coupled_segment_forces_ad` (what the kernels evaluate).

    The virtual work of W and D is ``h n . dGamma + h_a m_a . dU_a + h_b m_b . dU_b`` with
    the segment's resultant ``n = C_FF dG + V_FF Gdot + (C_FM (w_a dU_a + w_b dU_b) +
    V_FM (w_a Udot_a + w_b Udot_b))/h`` and the couplings' moments on the joints
    ``m_a = w_a/h_a (C_FM^T dG + V_FM^T Gdot)`` (m_b likewise), so Q is the segment's
    ``(R n, -R n, h Gamma x n)`` (:func:`segment_quantities`) plus each joint's torques for
    its m (:func:`joint_quantities`). Identically the AD of the definitions (tested).

    A free end's applied moment M (:func:`end_moment`) adds ``n_M = C_FE M`` to n (the
    condensed virtual joint's curvature ``C_MM^-1 (M - C_FM^T dG)``, docs/design.md,
    section 10); its power through that joint, ``P_M = -h n_M . Gdot``, is part of the
    external power (W and D are the moment-free ones).
    """
    h = _seg(c.sp, "h")
    G = rotate_transposed(c.p, c.phi_b - c.phi_a) / h
    Gd = rotate_transposed(c.p, c.v_b - c.v_a) / h + ca.cross(G, c.omega)
    ha, hb = _jnt(c.ja, "h"), _jnt(c.jb, "h")
    Ua, Uad, torques_a = _joint_kinematics(c.p_a, c.p, c.omega_a, c.omega, ha)
    Ub, Ubd, torques_b = _joint_kinematics(c.p, c.p_b, c.omega, c.omega_b, hb)
    dG = G - _seg(c.sp, "V0")
    dUa, dUb = Ua - _jnt(c.ja, "U0"), Ub - _jnt(c.jb, "U0")
    wa, wb = _cseg(c.sc, "w")[0], _cseg(c.sc, "w")[1]
    CFF, VFF = _sym3(_cseg(c.sc, "C_FF")), _sym3(_cseg(c.sc, "V_FF"))
    CFM, VFM = _mat3(_cseg(c.sc, "C_FM")), _mat3(_cseg(c.sc, "V_FM"))
    kw, kd = wa * dUa + wb * dUb, wa * Uad + wb * Ubd
    nM = _mat3(_cseg(c.sc, "C_FE")) @ end_moment(c)
    n = CFF @ dG + VFF @ Gd + (CFM @ kw + VFM @ kd) / h + nM
    mt = CFM.T @ dG + VFM.T @ Gd
    ma, mb = wa / ha * mt, wb / hb * mt
    Rn = rotate(c.p, n)
    Ta_l, Ta_r = torques_a(ma)
    Tb_l, Tb_r = torques_b(mb)
    Q = ca.vertcat(Rn, -Rn, Ta_l, h * ca.cross(G, n) + Ta_r + Tb_l, Tb_r)
    W = h / 2 * ca.dot(dG, CFF @ dG) + ca.dot(dG, CFM @ kw)
    D = h / 2 * ca.dot(Gd, VFF @ Gd) + ca.dot(Gd, VFM @ kd)
    return {"V": G, "W": W, "D": D, "Q": Q, "F": n, "Ma": ma, "Mb": mb,
            "P_M": -h * ca.dot(nM, Gd)}


def coupled_joint_quantities(s: _Sym, jc) -> dict[str, ca.SX]:
    """A joint of a coupled rod: as :func:`joint_quantities` with full matrices,
    ``m = C_MM dU + V_MM Udot``, ``W = h_j/2 dU^T C_MM dU``, ``D = h_j/2 Udot^T V_MM Udot``
    (the closed forms; torques ``T_b = -A^T m``, ``T_a = R(r) A^T m``)."""
    r = qmul(qconj(s.p), s.p_b)
    hj = _jnt(s.jp, "h")
    u = r[1:4] / r[0]
    U = 2.0 / hj * u
    w = s.omega_b - rotate_transposed(r, s.omega)
    Aw = w + ca.cross(u, w) + u * ca.dot(u, w)
    Udot = Aw / hj
    dU = U - _jnt(s.jp, "U0")
    C, V = _sym3(_cjnt(jc, "C_MM")), _sym3(_cjnt(jc, "V_MM"))
    m = C @ dU + V @ Udot
    Atm = m - ca.cross(u, m) + u * ca.dot(u, m)
    T = ca.vertcat(rotate(r, Atm), -Atm)
    return {"U": U, "Udot": Udot, "W": hj / 2 * ca.dot(dU, C @ dU),
            "D": hj / 2 * ca.dot(Udot, V @ Udot), "T": T, "M": m}


def coupled_joint_torques_ad(s: _Sym, jc) -> ca.SX:
    """The coupled joint's torques by AD of its W and D (the definition)."""
    hj = _jnt(s.jp, "h")
    U = curvature(s.p, s.p_b, hj)
    Udot = ca.jtimes(U, ca.vertcat(s.p, s.p_b),
                     ca.vertcat(qdot(s.p, s.omega), qdot(s.p_b, s.omega_b)))
    dU = U - _jnt(s.jp, "U0")
    C, V = _sym3(_cjnt(jc, "C_MM")), _sym3(_cjnt(jc, "V_MM"))
    W = hj / 2 * ca.dot(dU, C @ dU)
    D = hj / 2 * ca.dot(Udot, V @ Udot)
    gW = ca.gradient(W, ca.vertcat(s.p, s.p_b))
    gD = ca.gradient(D, ca.vertcat(s.omega, s.omega_b))
    return ca.vertcat(torque_from_gradient(s.p, gW[0:4]),
                      torque_from_gradient(s.p_b, gW[4:8])) - gD


def coupled_inertia(c: _CSym, p_dot, omega_dot, v_dot_a, v_dot_b, g) -> dict[str, ca.SX]:
    """Inertia of a segment whose mass centre is off the centreline (offset e, material)
    with the full rotary inertia (product I12), by Euler-Lagrange / Euler-Poincare.

    Kinetic energy of segment i besides the lumped node masses (``a = rho A h``,
    ``vbar = (v_a + v_b)/2``, ``J_o = h rhoJ + a (|e|^2 I - e e^T)``, the parallel-axis
    theorem): ``T_i = 1/2 Omega^T J_o Omega + a vbar . R (Omega x e)``; with the nodes'
    ``a/4 (|v_a|^2 + |v_b|^2)`` that is ``a/4 (|v_a + w|^2 + |v_b + w|^2) +
    1/2 Omega^T h rhoJ Omega``, ``w = R (Omega x e)``: positive definite. Its equations:
    the nodes' momentum rows gain ``a/2 R (Omega' x e + Omega x (Omega x e))`` (the time
    derivative of ``dT/dv``), the segment's angular momentum row is
    ``J_o Omega' + Omega x J_o Omega + a e x R^T (vbar' - g)`` (the configuration term of
    Euler-Poincare cancels against the rate of ``a e x R^T vbar``; gravity ``g`` (scaled)
    acting at the mass centre adds the torque ``a e x R^T g``). Returns the rows, the
    kinetic energy T_i and the power of that gravity torque.
    """
    h, rhoA = _seg(c.sp, "h"), _seg(c.sp, "rhoA")
    a = rhoA * h
    e = _cseg(c.sc, "e")
    Jo = h * _sym3(_cseg(c.sc, "rhoJ")) + a * (ca.dot(e, e) * ca.SX.eye(3) - e @ e.T)
    om = c.omega
    vbd = 0.5 * (v_dot_a + v_dot_b)
    r_om = Jo @ omega_dot + ca.cross(om, Jo @ om) + a * ca.cross(e, rotate_transposed(
        c.p, vbd - g))
    r_node = 0.5 * a * rotate(c.p, ca.cross(omega_dot, e) + ca.cross(om, ca.cross(om, e)))
    vb = 0.5 * (c.v_a + c.v_b)
    T = 0.5 * ca.dot(om, Jo @ om) + a * ca.dot(vb, rotate(c.p, ca.cross(om, e)))
    Pg = ca.dot(om, a * ca.cross(e, rotate_transposed(c.p, g)))
    return {"r": ca.vertcat(p_dot - qdot(c.p, om), r_om, r_node, r_node), "T": T,
            "P_g": Pg}


def coupled_kernels() -> list[ca.Function]:
    """The kernels of a rod with coupled sections (:data:`COUPLED_SEGMENT_PARAMS`), used
    by the assembly instead of the diagonal ones for such a rod.

    ``rod_coupled_segment_forces``: Q = (f_a, f_b, T_a, T, T_b) (15) of
    :func:`coupled_segment_quantities`; ``_jac``: dQ/d(phi_a, phi_b, p_a, p, p_b, v_a,
    v_b, Omega_a, Omega, Omega_b) (15 x 33); ``_diagnostics``: W, D, strain, resultant,
    the joint-moment shares and the power of a free end's moment through its condensed
    joint. ``rod_coupled_joint_torques`` (and ``_jac``:
    d/d(p_a, p_b, Omega_a, Omega_b), 6 x 14; ``_diagnostics``): the joint with full
    C_MM, V_MM. ``rod_coupled_inertia``: rows (p kinematics 4, angular momentum 3, node
    a 3, node b 3) of :func:`coupled_inertia`; ``_jac``: cy d/dy + cj d/dy' in the columns
    (p, Omega, v_a, v_b) (13 x 13); ``rod_coupled_kinetic``: T_i and the gravity torque's
    power.
    """
    c = _csymbols()
    S = ca.SX.sym
    seg_in = {"phi_a": c.phi_a, "phi_b": c.phi_b, "p_a": c.p_a, "p": c.p, "p_b": c.p_b,
              "v_a": c.v_a, "v_b": c.v_b, "Omega_a": c.omega_a, "Omega": c.omega,
              "Omega_b": c.omega_b, "seg": c.sp, "segc": c.sc, "jnt_a": c.ja,
              "jnt_b": c.jb, "m_end": c.m_end}
    q = coupled_segment_quantities(c)
    xs = ca.vertcat(c.phi_a, c.phi_b, c.p_a, c.p, c.p_b, c.v_a, c.v_b, c.omega_a, c.omega,
                    c.omega_b)
    s = _symbols()
    jc = S("jntc", N_COUPLED_JOINT)
    jnt_in = {"p_a": s.p, "p_b": s.p_b, "Omega_a": s.omega, "Omega_b": s.omega_b,
              "jnt": s.jp, "jntc": jc}
    jq = coupled_joint_quantities(s, jc)
    xj = ca.vertcat(s.p, s.p_b, s.omega, s.omega_b)
    pd, omd, vda, vdb, g = S("p_dot", 4), S("Omega_dot", 3), S("v_dot_a", 3), S("v_dot_b", 3), \
        S("g", 3)
    cy, cj = S("c_y"), S("c_j")
    iq = coupled_inertia(c, pd, omd, vda, vdb, g)
    Jy = ca.jacobian(iq["r"], ca.vertcat(c.p, c.omega))
    Jyp = ca.jacobian(iq["r"], ca.vertcat(pd, omd, vda, vdb))
    J_inertia = ca.horzcat(cy * Jy, ca.SX.zeros(13, 6)) + cj * Jyp
    in_in = {"p": c.p, "Omega": c.omega, "p_dot": pd, "Omega_dot": omd, "v_dot_a": vda,
             "v_dot_b": vdb, "seg": c.sp, "segc": c.sc, "g": g}
    return [
        _fn("rod_coupled_segment_forces", seg_in, {"Q": q["Q"]}),
        _fn("rod_coupled_segment_forces_jac", seg_in,
            {"dQ_dx": ca.densify(ca.jacobian(q["Q"], xs))}),
        _fn("rod_coupled_segment_diagnostics", seg_in,
            {"W": q["W"], "D": q["D"], "V": q["V"], "F": q["F"], "M_a": q["Ma"],
             "M_b": q["Mb"], "P_M": q["P_M"]}),
        _fn("rod_coupled_joint_torques", jnt_in, {"T": jq["T"]}),
        _fn("rod_coupled_joint_torques_jac", jnt_in,
            {"dT_dx": ca.densify(ca.jacobian(jq["T"], xj))}),
        _fn("rod_coupled_joint_diagnostics", jnt_in,
            {"W": jq["W"], "D": jq["D"], "U": jq["U"], "M": jq["M"]}),
        _fn("rod_coupled_inertia", in_in, {"r": iq["r"]}),
        _fn("rod_coupled_inertia_jac", {**in_in, "c_y": cy, "c_j": cj},
            {"J": ca.densify(J_inertia)}),
        _fn("rod_coupled_kinetic", {"v_a": c.v_a, "v_b": c.v_b, "p": c.p, "Omega": c.omega,
                                    "seg": c.sp, "segc": c.sc, "g": g},
            {"T": iq["T"], "P_g": iq["P_g"]}),
    ]


# --------------------------------------------------------------------------------------
# Structure of the assembled Jacobian (band widths) from the element stencils
# --------------------------------------------------------------------------------------


def cell_start(i: int, branches: int = 0) -> int:
    """Index of the first unknown of cell i in y (B = ``branches`` relaxation terms)."""
    return 0 if i == 0 else (_size(cell_fields(branches, True))
                             + _size(cell_fields(branches)) * (i - 1))


def _field_range(i: int, name: str, branches: int) -> range:
    fields = cell_fields(branches, first=i == 0)
    off, size = _offsets(fields)[name], dict(fields)[name]
    return range(cell_start(i, branches) + off, cell_start(i, branches) + off + size)


def _node(i: int, name: str, branches: int = 0) -> range:
    return _field_range(i, name, branches)


def _segment(i: int, name: str, branches: int = 0) -> range:
    return _field_range(i, name, branches)


def _q_joint(j: int, branches: int) -> list[int]:
    return list(_field_range(j, "q_joint", branches)) if branches else []


def element_stencils(n_elements: int, branches: int = 0,
                     coupled: bool = False) -> list[tuple[list[int], list[int]]]:
    """(rows, columns) of every element's block in dF/dy + c dF/dy' (all ends clamped,
    every load present: the widest pattern) for B = ``branches`` relaxation terms. A
    declarative table of which unknowns each element couples, from which the band widths
    follow; the assembled C Jacobian is tested to have exactly this pattern. ``coupled``:
    a rod with coupled sections (:func:`coupled_kernels`, B = 0): segment i's forces
    also reach the neighbouring segments i-1, i+1 (the couplings with the curvatures of
    its two joints) and its inertia couples its Omega with the velocities of its nodes."""
    N, B = n_elements, branches
    nd = lambda i: [*_node(i, "phi", B), *_node(i, "v", B)]  # noqa: E731
    sg = lambda i: [*_segment(i, "p", B), *_segment(i, "Omega", B)]  # noqa: E731
    qs = lambda i: list(_segment(i, "q_segment", B)) if B else []  # noqa: E731
    out = []
    if coupled:
        if B:
            raise ValueError("coupled sections with relaxation terms are not supported")
        for i in range(1, N + 1):
            nb = [k for k in (i - 1, i + 1) if 1 <= k <= N]
            # the segment's resultant sees its strain and both joints' curvatures and rates
            rows = [*_node(i - 1, "v"), *_node(i, "v"), *_segment(i, "Omega")]
            out.append((rows, [*nd(i - 1), *nd(i), *sg(i)] + [c for k in nb for c in sg(k)]))
            # a neighbour's torque: its joint's kinematics for the coupling's moment, which
            # depends on the segment's strain and strain rate only
            for k in nb:
                out.append((list(_segment(k, "Omega")),
                            [*nd(i - 1), *nd(i), *sg(i), *_segment(k, "p")]))
            vv = [*_node(i - 1, "v"), *_node(i, "v")]
            out.append(([*sg(i), *vv], [*sg(i), *vv]))              # coupled inertia
    for i in range(N + 1):
        out.append((nd(i), nd(i)))                                   # node inertia
        out.append((list(_node(i, "v", B)), list(_segment(max(i, 1), "p", B))))  # follower
    for i in range(1, N + 1):
        out.append((sg(i), sg(i)))                                   # segment inertia
        out.append((list(_segment(i, "Omega", B)), list(_segment(i, "p", B))))  # dead moment
        rows = [*_node(i - 1, "v", B), *_node(i, "v", B), *_segment(i, "Omega", B)]
        out.append((rows, [*nd(i - 1), *nd(i), *sg(i), *qs(i)]))     # segment forces
        if B:                                                        # q' = (V - V0 - q)/theta
            out.append((qs(i), [*_node(i - 1, "phi", B), *_node(i, "phi", B),
                                *_segment(i, "p", B), *qs(i)]))
    for j in range(N + 1):                     # interior joints and the clamp joints
        segs = [k for k in (j, j + 1) if 1 <= k <= N]
        rows = [r for k in segs for r in _segment(k, "Omega", B)]
        out.append((rows, [c for k in segs for c in sg(k)] + _q_joint(j, B)))
        if B:
            out.append((_q_joint(j, B), [c for k in segs for c in _segment(k, "p", B)]
                        + _q_joint(j, B)))
    return out


def bandwidths(n_elements: int, branches: int = 0, coupled: bool = False) -> tuple[int, int]:
    """Exact (kl, ku) of dF/dy + c dF/dy' from :func:`element_stencils`."""
    kl = ku = 0
    for rows, cols in element_stencils(n_elements, branches, coupled):
        for r in rows:
            for c in cols:
                kl, ku = max(kl, r - c), max(ku, c - r)
    return kl, ku


def bandwidth_formula(max_branches: int = MAX_BRANCHES) -> tuple[tuple[int, int], ...]:
    """(kl0, kl1, ku0, ku1) with kl = kl0 + kl1 B, ku = ku0 + ku1 B for N >= 3, checked
    exact for B = 0..``max_branches`` (so the C assembly and the layout can compute the
    band of any B without the stencil table); returned as ((kl0, kl1), (ku0, ku1))."""
    b0, b1 = bandwidths(4, 0), bandwidths(4, 1)
    kl = (b0[0], b1[0] - b0[0])
    ku = (b0[1], b1[1] - b0[1])
    for B in range(max_branches + 1):
        for N in (3, 4, 7):
            got = bandwidths(N, B)
            if got != (kl[0] + kl[1] * B, ku[0] + ku[1] * B):
                raise AssertionError(f"band widths not linear in B at N = {N}, B = {B}: {got}")
    return kl, ku


def static_bandwidths(n_elements: int, coupled: bool = False) -> tuple[int, int]:
    """Exact (kl, ku) of the static Jacobian in reduced coordinates (dphi, dtheta).

    Static rows are the momentum rows (node forces, segment torques) of each cell; columns
    are dphi for nodes and dtheta for segments (dtheta couples exactly like p).
    """
    N = n_elements

    def static_index(k: int, as_row: bool) -> list[int]:
        for i in range(N + 1):
            if k in _node(i, "v" if as_row else "phi"):
                base = 0 if i == 0 else static_cell_start(i) + STATIC_CELL_OFFSETS["phi"]
                return [base + k - _node(i, "v" if as_row else "phi")[0]]
        for i in range(1, N + 1):
            th = static_cell_start(i) + STATIC_CELL_OFFSETS["theta"]
            if as_row and k in _segment(i, "Omega"):
                return [th + k - _segment(i, "Omega")[0]]
            if not as_row and k in _segment(i, "p"):
                return [th, th + 1, th + 2]
        return []

    kl = ku = 0
    for rows, cols in element_stencils(N, 0, coupled):
        for r in rows:
            for rs in static_index(r, True):
                for c in cols:
                    for cs in static_index(c, False):
                        kl, ku = max(kl, rs - cs), max(ku, cs - rs)
    return kl, ku
