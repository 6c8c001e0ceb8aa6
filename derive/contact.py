"""Contact of a rod segment with a rigid obstacle, as CasADi SX kernels (issue 32;
docs/design.md, section 13, "Contact kernels").

**Line contact.** The rod's surface (contact radius r about the centreline) meets the
obstacle along the segment: with ``x(xi) = (1 - xi) phi_a + xi phi_b`` (xi in [0, 1]) the
gap ``g(xi) = d(x(xi)) - r`` (d: the smooth signed distance from a point to the obstacle's
surface, positive outside, in the obstacle's current pose), the contact energy is

    ``E = h sum_i w_i chi_i e(g_i)``,  ``e(g) = k/2 delta^2 softplus(-g/delta)^2``

(h: the segment's reference length; quadrature :data:`QUADRATURE`; chi: a pipe's smooth
switch at its open ends, else 1): ``e ~ 0`` for ``g >> delta``, ``k g^2/2`` for
``-g >> delta``. The normal damping is the dissipation function
``D = h sum_i w_i chi_i c/2 sigmoid(-g_i/delta) gdot_i^2`` with the exact rate
``gdot = grad d . (v_x - v_obs(x))`` (the obstacle's rigid velocity field
``v_obs(x) = v_o + w_o x (x - c)``). Regularised Coulomb friction acts at the rod's
surface point ``y = x - r n`` (n = grad d, the outward normal of the obstacle there):
slip ``v_t = P (v_y - v_obs(y))``, ``P = I - n n^T``, ``v_y = v_x - r omega x n``
(omega = R(p) Omega, the segment's spatial angular velocity), force density
``f_t = -mu f_N v_t / sqrt(|v_t|^2 + v_s^2)`` with the normal force clipped smoothly at 0:
``f_N = chi sigmoid(-g/delta) m(k delta softplus(-g/delta) - c gdot)``,
``m(B) = k delta / beta softplus(beta B / (k delta))`` (:data:`CLIP_SHARPNESS` beta; the
unclipped normal force density is ``sigmoid(-g/delta) B``). Its power on the slip is
``-mu f_N v_t . v_rel / sqrt(...) <= 0``.

**Generalized forces** Q = (f_a, f_b, T), the convention of ``rod_coupled_segment_forces``
(the residual subtracts them): ``f = -dE/dphi - dD/dv`` plus the friction's share by the
shape functions (``(1 - xi) f_t``, ``xi f_t``), T = the friction's moment about the
centreline ``R(p)^T sum (-r n x f_t)`` (material, conjugate to Omega; E does not depend
on p). The obstacle feels the opposite forces at the same points, so
``F_obs = -(f_a + f_b)`` and ``M_obs = -(moment of Q about c)``, and the power the moving
obstacle delivers to the rod is ``P_obs = -(F_obs . v_o + M_obs . w_o)``:
``Q . (v_a, v_b, Omega) = -dE/dt - P_diss + P_obs`` exactly, ``P_diss = 2D + P_fric``.

**Obstacles** (:data:`OBSTACLE_KINDS`; geometry in the obstacle's frame, its current pose
c, q_o, v_o, w_o in :data:`OBS_PARAMS`): plane, sphere, cylinder (outside; capped when
its length is > 0, the rims rounded over ``edge``), pipe (inside a cylinder; open ends
switched off over ``edge``). The distance to an axis or centre is regularised,
``sqrt(rho^2 + (eps R)^2)`` (:data:`AXIS_REGULARISATION` eps), so a rod on a pipe's axis
or through a sphere's centre has finite, smooth forces.

:func:`contact_definitions` and :func:`contact_forces_ad` are the definitions (E, D by
forward AD along the rod's and the obstacle's motion, Q by CasADi AD and the friction's
virtual power); :func:`contact_quantities` evaluates the same in closed form (what the
kernels do). The rod-rod kernel is :mod:`derive.contact_pair`. The layout tables here
are the one source for ``generated/rod_layout.py`` and ``.h``.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import casadi as ca

from derive.discrete_rod import (
    _field,
    _fn,
    _offsets,
    _size,
    qmul,
    rotate,
    rotate_transposed,
    rotation,
    torque_from_gradient,
)

# --------------------------------------------------------------------------------------
# Layout (rendered into generated/rod_layout.py and rod_layout.h)
# --------------------------------------------------------------------------------------


def gauss_lobatto(n: int) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """Nodes and weights of the n-point Gauss-Lobatto rule on [0, 1] (n = 2..4), from
    their closed forms (correctly rounded: the generated code is byte-reproducible)."""
    if n == 2:
        return (0.0, 1.0), (0.5, 0.5)
    if n == 3:
        return (0.0, 0.5, 1.0), (1 / 6, 2 / 3, 1 / 6)
    if n == 4:
        a = 0.5 / math.sqrt(5.0)
        return (0.0, 0.5 - a, 0.5 + a, 1.0), (1 / 12, 5 / 12, 5 / 12, 1 / 12)
    raise ValueError(f"n = {n!r} is outside the allowed range: 2..4")


#: quadrature points per segment (a compile-time constant of the layout)
NQ = 3
#: Gauss-Lobatto on [0, 1] (Simpson for NQ = 3): the nodes are quadrature points, so a
#: rod's end pushed into an obstacle is felt at the end and the points lie h/2 apart
#: along the rod; exact to degree 2 NQ - 3 (the deep-contact energy of a straight
#: segment over a plane, quadratic in xi, and its forces, cubic, are exact)
QUADRATURE: tuple[tuple[float, ...], tuple[float, ...]] = gauss_lobatto(NQ)
#: obstacle kernels, in order: rod_contact_<kind>
OBSTACLE_KINDS: tuple[str, ...] = ("plane", "sphere", "cylinder", "pipe")
#: beta of the friction's smooth clip of the normal force (error <= ln 2/beta k delta)
CLIP_SHARPNESS = 4.0
#: eps: the distance to a sphere's centre or a cylinder's axis is sqrt(rho^2 + (eps R)^2)
AXIS_REGULARISATION = 1e-4
#: a segment whose gap is above CONTACT_CUTOFF delta everywhere contributes nothing above
#: round-off: every term carries sigmoid(-g/delta) or softplus(-g/delta) < exp(-40)
CONTACT_CUTOFF = 40.0

#: parameters of one obstacle (its current pose first, written by the runtime's drive
#: from the obstacle's motion): (name, size, unit, meaning)
OBS_PARAMS: tuple[tuple[str, int, str, str], ...] = (
    ("c", 3, "m", "position of the obstacle frame's origin (spatial); the reference "
                  "point of F_obs, M_obs and of the motion"),
    ("q", 4, "1", "orientation of the obstacle frame (quaternion, scalar first, any norm)"),
    ("v", 3, "m/s", "velocity of the origin c (spatial)"),
    ("w", 3, "rad/s", "angular velocity of the obstacle (spatial)"),
    ("point", 3, "m", "plane: a point of the plane; sphere: its centre; cylinder, pipe: "
                      "a point on the axis (obstacle frame)"),
    ("axis", 3, "1", "plane: its outward normal; cylinder, pipe: the axis direction "
                     "(obstacle frame, any length > 0; unused by a sphere)"),
    ("radius", 1, "m", "sphere, cylinder, pipe: the radius (> 0)"),
    ("length", 1, "m", "cylinder, pipe: length from the point along the axis; <= 0: "
                       "infinite"),
    ("edge", 1, "m", "cylinder: rounding of the rims; pipe: length over which an open end "
                     "switches the contact off (> 0 when length > 0, else unused)"),
)
#: parameters of one rod-obstacle contact on one segment
CNT_PARAMS: tuple[tuple[str, int, str, str], ...] = (
    ("k", 1, "N/m^2", "stiffness per length (> 0)"),
    ("delta", 1, "m", "smoothing length of the gap, the penetration tolerance scale (> 0)"),
    ("c", 1, "N s/m^2", "normal damping per length (>= 0)"),
    ("mu", 1, "1", "Coulomb friction coefficient (>= 0)"),
    ("v_s", 1, "m/s", "slip velocity tolerance of the regularised friction (> 0)"),
    ("r", 1, "m", "contact radius of the rod (>= 0)"),
    ("h", 1, "m", "reference length of the segment (the weight of its line integral)"),
)
#: blocks of rod_contact_<kind>'s Q (N, N, N m): forces on nodes a, b (spatial), torque on
#: the segment (material, conjugate to Omega)
CONTACT_FORCES: tuple[tuple[str, int], ...] = (("f_a", 3), ("f_b", 3), ("T", 3))
#: columns of rod_contact_<kind>_jac (rows: CONTACT_FORCES)
CONTACT_JAC_COLUMNS: tuple[tuple[str, int], ...] = (
    ("phi_a", 3), ("phi_b", 3), ("p", 4), ("v_a", 3), ("v_b", 3), ("Omega", 3))
#: columns of rod_contact_<kind>_diagnostics' ``points`` (NQ rows)
CONTACT_POINT_COLUMNS: tuple[tuple[str, int], ...] = (("x", 3), ("g", 1))

OBS_OFFSETS, N_OBS = _offsets(OBS_PARAMS), _size(OBS_PARAMS)
CNT_OFFSETS, N_CNT = _offsets(CNT_PARAMS), _size(CNT_PARAMS)
CONTACT_FORCE_OFFSETS, N_CONTACT_FORCES = _offsets(CONTACT_FORCES), _size(CONTACT_FORCES)
CONTACT_JAC_OFFSETS, N_CONTACT_JAC_COLUMNS = (_offsets(CONTACT_JAC_COLUMNS),
                                              _size(CONTACT_JAC_COLUMNS))


def _obs(op, name):
    """A named entry of the obstacle parameter vector (:data:`OBS_PARAMS`)."""
    return _field(op, OBS_OFFSETS, OBS_PARAMS, name)


def _cnt(cp, name):
    """A named entry of the contact parameter vector (:data:`CNT_PARAMS`)."""
    return _field(cp, CNT_OFFSETS, CNT_PARAMS, name)


# --------------------------------------------------------------------------------------
# The contact law (shared with derive.contact_pair)
# --------------------------------------------------------------------------------------


def softplus(x):
    """``ln(1 + e^x)`` without overflow, ``x + ln(1 + e^-x)`` for x > 0 and
    ``ln(1 + e^x)`` else, each side's branch analytic (the branches' switches hold only
    ``-|x|`` and ``max(x, 0)``, one exp and one log1p): CasADi's derivatives of every
    order are the exact ones at every x, where ``fmax(x, 0) + ln(1 + e^-|x|)`` gives 0 for
    the second derivative at x = 0 (the derivative of fabs there is 0)."""
    pos = x > 0
    return ca.if_else(pos, x, 0) + ca.log1p(ca.exp(ca.if_else(pos, -x, x)))


def sigmoid(x):
    """``1/(1 + e^-x)`` without overflow (as a tanh)."""
    return 0.5 + 0.5 * ca.tanh(0.5 * x)


def smooth_max(a, b, eps):
    """``(a + b + sqrt((a - b)^2 + eps^2))/2``: max(a, b) to within eps/2."""
    return 0.5 * (a + b + ca.sqrt((a - b) ** 2 + eps**2))


def smooth_min(a, b, eps):
    """``(a + b - sqrt((a - b)^2 + eps^2))/2``: min(a, b) to within eps/2."""
    return 0.5 * (a + b - ca.sqrt((a - b) ** 2 + eps**2))


def energy_density(g, k, delta):
    """``e(g) = k/2 delta^2 softplus(-g/delta)^2`` (J/m), g the gap (m)."""
    return 0.5 * k * delta**2 * softplus(-g / delta) ** 2


@dataclass(frozen=True)
class GapLaw:
    """The normal law at one gap g with rate gdot (per length): energy density e (J/m),
    normal force density ``f_n = -de/dg - c sigmoid gdot`` (N/m, along grad g, may be
    negative while separating), its smooth clip ``f_N >= 0`` for the friction, and the
    damping's dissipated power ``P_d = c sigmoid gdot^2 = 2 D`` (W/m)."""

    e: ca.SX
    f_n: ca.SX
    f_N: ca.SX
    P_d: ca.SX


def gap_law(g, gdot, k, delta, c) -> GapLaw:
    """:class:`GapLaw` of ``e(g)`` and the damping ``D = c/2 sigmoid(-g/delta) gdot^2``."""
    x = -g / delta
    sp, sg = softplus(x), sigmoid(x)
    B = k * delta * sp - c * gdot
    kd = k * delta / CLIP_SHARPNESS
    return GapLaw(e=0.5 * k * delta**2 * sp**2, f_n=sg * B,
                  f_N=sg * kd * softplus(B / kd), P_d=c * sg * gdot**2)


def friction(v_rel, n, f_N, mu, v_s) -> tuple[ca.SX, ca.SX]:
    """Regularised Coulomb friction density ``f_t = -mu f_N v_t/sqrt(|v_t|^2 + v_s^2)``,
    ``v_t = v_rel - n (n . v_rel)`` (N/m), and its dissipated power ``-f_t . v_rel >= 0``
    (W/m; ``|n| <= 1``)."""
    v_t = v_rel - n * ca.dot(n, v_rel)
    a = mu * f_N / ca.sqrt(ca.dot(v_t, v_t) + v_s**2)
    return -a * v_t, a * ca.dot(v_t, v_rel)


# --------------------------------------------------------------------------------------
# Obstacle geometry: signed distance d (m) and switch chi in the obstacle's frame
# --------------------------------------------------------------------------------------


def _unit(a):
    return a / ca.sqrt(ca.dot(a, a))


def _axial(xo, obs):
    """(z, rho_reg): coordinate along the unit axis from the point, regularised distance
    from the axis ``sqrt(rho^2 + (eps R)^2)``."""
    a = _unit(_obs(obs, "axis"))
    u = xo - _obs(obs, "point")
    z = ca.dot(a, u)
    w = u - z * a
    R = _obs(obs, "radius")
    return z, ca.sqrt(ca.dot(w, w) + (AXIS_REGULARISATION * R) ** 2)


def _plane(xo, obs):
    return ca.dot(_unit(_obs(obs, "axis")), xo - _obs(obs, "point")), 1


def _sphere(xo, obs):
    u = xo - _obs(obs, "point")
    R = _obs(obs, "radius")
    return ca.sqrt(ca.dot(u, u) + (AXIS_REGULARISATION * R) ** 2) - R, 1


def _cylinder(xo, obs):
    """Outside a cylinder: ``rho - R`` when infinite; capped (length L > 0): with
    ``a = (rho - R, -z, z - L)`` and the rounding e, ``d = e |softplus(a/e)| -
    e softplus(-lse_e(a)/e)`` (lse_e: the log-sum-exp max at scale e): smooth
    everywhere, ``max(a)`` deep inside, outside the exact distance (whose level sets
    round the rims with the radius d) to within ``e exp(-d/e)`` over the faces and about
    ``(e ln 2)^2/(2 d)`` where a rim's rounding meets a face (each component a_i is
    smoothed by ``e softplus(a_i/e) - max(a_i, 0) <= e ln 2``): ``e <~ sqrt(r delta)``
    keeps the rims' error at the rod's surface below delta."""
    z, rho = _axial(xo, obs)
    R, L = _obs(obs, "radius"), _obs(obs, "length")
    e = ca.if_else(L > 0, _obs(obs, "edge"), 1)      # unused, and finite, when infinite
    dr = rho - R
    a = [dr / e, -z / e, (z - L) / e]
    outer = e * ca.sqrt(sum(softplus(ai) ** 2 for ai in a))
    m = ca.fmax(ca.fmax(a[0], a[1]), a[2])
    lse = m + ca.log(sum(ca.exp(ai - m) for ai in a))
    capped = outer - e * softplus(-lse)
    return ca.if_else(L > 0, capped, dr), 1


def _pipe(xo, obs):
    """Inside a cylinder: ``d = R - rho``; open ends (length L > 0): the contact is
    switched off beyond them, ``chi = sigmoid(z/e) sigmoid((L - z)/e)``."""
    z, rho = _axial(xo, obs)
    R, L = _obs(obs, "radius"), _obs(obs, "length")
    e = ca.if_else(L > 0, _obs(obs, "edge"), 1)      # unused, and finite, when infinite
    chi = ca.if_else(L > 0, sigmoid(z / e) * sigmoid((L - z) / e), 1)
    return R - rho, chi


#: signed distance and switch of each kind, ``(x_o, obs) -> (d, chi)`` (obstacle frame)
GEOMETRY: dict[str, Callable] = {"plane": _plane, "sphere": _sphere,
                                 "cylinder": _cylinder, "pipe": _pipe}


def geometry_function(kind: str) -> ca.Function:
    """``(x_o, obs) -> (d, grad d, chi, grad chi)`` of one kind, obstacle frame (gradients
    by CasADi AD), as an SX function to inline at every quadrature point."""
    xo, obs = ca.SX.sym("x_o", 3), ca.SX.sym("obs", N_OBS)
    d, chi = GEOMETRY[kind](xo, obs)
    chi = ca.SX(chi)
    return ca.Function(f"geometry_{kind}", [xo, obs],
                       [d, ca.gradient(d, xo), chi, ca.gradient(chi, xo)])


# --------------------------------------------------------------------------------------
# Kernels
# --------------------------------------------------------------------------------------


@dataclass(frozen=True)
class ContactSym:
    """Inputs of the rod-obstacle kernels (names as in :func:`contact_kernels`)."""

    phi_a: ca.SX
    phi_b: ca.SX
    v_a: ca.SX
    v_b: ca.SX
    p: ca.SX
    omega: ca.SX
    obs: ca.SX     # OBS_PARAMS
    cnt: ca.SX     # CNT_PARAMS

    def inputs(self) -> dict[str, ca.SX]:
        """The kernels' named inputs, in order."""
        return {"phi_a": self.phi_a, "phi_b": self.phi_b, "v_a": self.v_a,
                "v_b": self.v_b, "p": self.p, "Omega": self.omega, "obs": self.obs,
                "cnt": self.cnt}

    def jac_columns(self) -> ca.SX:
        """The variables of :data:`CONTACT_JAC_COLUMNS`, stacked."""
        return ca.vertcat(self.phi_a, self.phi_b, self.p, self.v_a, self.v_b, self.omega)


def contact_symbols() -> ContactSym:
    """Fresh SX symbols of the rod-obstacle kernels' inputs."""
    S = ca.SX.sym
    return ContactSym(S("phi_a", 3), S("phi_b", 3), S("v_a", 3), S("v_b", 3), S("p", 4),
                      S("Omega", 3), S("obs", N_OBS), S("cnt", N_CNT))


def _params(s: ContactSym):
    return (_cnt(s.cnt, "k"), _cnt(s.cnt, "delta"), _cnt(s.cnt, "c"), _cnt(s.cnt, "mu"),
            _cnt(s.cnt, "v_s"), _cnt(s.cnt, "r"), _cnt(s.cnt, "h"))


def point_function(kind: str) -> ca.Function:
    """The contact at one centreline point x with velocity v_x of a segment turning at
    omega (spatial), as an SX function to inline at every quadrature point:
    ``(x, v_x, omega, obs, cnt) -> (f, m, e, P_d, P_f, g)`` per length: the force
    density (N/m) at x, the friction's moment density about x (N, spatial), the energy
    density ``chi e`` (J/m), the damping's and the friction's dissipated power (W/m) and
    the gap (m).

    In the obstacle frame ``x_o = R_o^T (x - c)``, (d, grad d, chi, grad chi) of
    :data:`GEOMETRY`, spatial ``n = R_o grad d``; ``gdot = n . (v_x - v_obs(x))`` is d's
    exact rate along the rod's and the obstacle's motion. The force density is
    ``chi f_n n - e grad chi`` (``-grad(chi e)`` and the damping ``-dD/dv_x``) plus the
    friction ``f_t`` at ``y = x - r n``, whose moment about x is ``-r n x f_t``."""
    S = ca.SX.sym
    x, v_x, omega = S("x", 3), S("v_x", 3), S("omega", 3)
    obs, cnt = S("obs", N_OBS), S("cnt", N_CNT)
    k, delta, c, mu, v_s, r = (_cnt(cnt, n) for n in ("k", "delta", "c", "mu", "v_s", "r"))
    co, qo, vo, wo = (_obs(obs, n) for n in ("c", "q", "v", "w"))
    Ro = rotation(qo)
    d, gd, chi, gchi = geometry_function(kind)(Ro.T @ (x - co), obs)
    n, n_chi = Ro @ gd, Ro @ gchi
    gdot = ca.dot(n, v_x - vo - ca.cross(wo, x - co))
    law = gap_law(d - r, gdot, k, delta, c)
    y = x - r * n
    v_rel = v_x - r * ca.cross(omega, n) - vo - ca.cross(wo, y - co)
    f_t, p_f = friction(v_rel, n, chi * law.f_N, mu, v_s)
    f = chi * law.f_n * n - law.e * n_chi + f_t
    return ca.Function(f"contact_point_{kind}", [x, v_x, omega, obs, cnt],
                       [f, ca.cross(-r * n, f_t), chi * law.e, chi * law.P_d, p_f, d - r])


def contact_quantities(s: ContactSym, kind: str) -> dict[str, ca.SX]:
    """Closed forms of the contact of one segment with an obstacle of ``kind``: the
    densities of :func:`point_function` at each quadrature point x (weight ``h w_i``),
    their forces on the nodes by the shape functions, the friction's moments (T, material).
    Returns Q, the energy E, the dissipated powers, the obstacle's load (F_obs, M_obs
    about c), P_obs, the gaps and the quadrature points."""
    h = _cnt(s.cnt, "h")
    co, vo, wo = (_obs(s.obs, n) for n in ("c", "v", "w"))
    omega = rotate(s.p, s.omega)
    point = point_function(kind)
    f_a, f_b, M = ca.SX.zeros(3), ca.SX.zeros(3), ca.SX.zeros(3)
    E, P_d, P_f, gaps, points = 0, 0, 0, [], []
    for xi, wq in zip(*QUADRATURE, strict=True):
        x = (1 - xi) * s.phi_a + xi * s.phi_b
        f, m, e, p_d, p_f, g = point(x, (1 - xi) * s.v_a + xi * s.v_b, omega, s.obs, s.cnt)
        W = h * wq
        f_a += W * (1 - xi) * f
        f_b += W * xi * f
        M += W * m
        E += W * e
        P_d += W * p_d
        P_f += W * p_f
        gaps.append(g)
        points.append(ca.horzcat(x.T, g))
    F_obs = -(f_a + f_b)
    M_obs = -(ca.cross(s.phi_a - co, f_a) + ca.cross(s.phi_b - co, f_b) + M)
    g_min = gaps[0]
    for g in gaps[1:]:
        g_min = ca.fmin(g_min, g)
    return {"Q": ca.vertcat(f_a, f_b, rotate_transposed(s.p, M)), "E": E,
            "P_diss": P_d + P_f, "P_fric": P_f, "F_obs": F_obs, "M_obs": M_obs,
            "P_obs": -(ca.dot(F_obs, vo) + ca.dot(M_obs, wo)), "g_min": g_min,
            "points": ca.vertcat(*points)}


def contact_jacobian(s: ContactSym, kind: str) -> ca.SX:
    """dQ/dx (9 x 19) in :data:`CONTACT_JAC_COLUMNS` by the chain rule through the
    quadrature points: each point's (f, m) differentiated in (x, v_x, omega) (6 x 9, CasADi
    AD of :func:`point_function`), mapped by the shape functions and ``omega = R(p)
    Omega``, and ``T = R(p)^T M`` (8-25 % fewer instructions than AD of Q whole)."""
    S = ca.SX.sym
    x, v_x, om = S("x", 3), S("v_x", 3), S("omega", 3)
    out = ca.vertcat(*point_function(kind)(x, v_x, om, s.obs, s.cnt)[0:2])
    dpoint = ca.Function("dpoint", [x, v_x, om, s.obs, s.cnt],
                         [out, ca.jacobian(out, ca.vertcat(x, v_x, om))])
    h = _cnt(s.cnt, "h")
    omega = rotate(s.p, s.omega)
    d_omega = ca.jacobian(omega, ca.vertcat(s.p, s.omega))               # 3 x 7
    J_f, J_M, M = ca.SX.zeros(6, 19), ca.SX.zeros(3, 19), ca.SX.zeros(3)
    for xi, wq in zip(*QUADRATURE, strict=True):
        fm, J = dpoint((1 - xi) * s.phi_a + xi * s.phi_b, (1 - xi) * s.v_a + xi * s.v_b,
                       omega, s.obs, s.cnt)
        J_om = J[:, 6:9] @ d_omega
        cols = ca.horzcat((1 - xi) * J[:, 0:3], xi * J[:, 0:3], J_om[:, 0:4],
                          (1 - xi) * J[:, 3:6], xi * J[:, 3:6], J_om[:, 4:7])
        W = h * wq
        J_f += ca.vertcat(W * (1 - xi) * cols[0:3, :], W * xi * cols[0:3, :])
        J_M += W * cols[3:6, :]
        M += W * fm[3:6]
    Ms = S("M", 3)
    T = rotate_transposed(s.p, Ms)
    dT_dM, dT_dp = (ca.substitute(ca.jacobian(T, v), Ms, M) for v in (Ms, s.p))
    J_T = dT_dM @ J_M + ca.horzcat(ca.SX.zeros(3, 6), dT_dp, ca.SX.zeros(3, 9))
    return ca.vertcat(J_f, J_T)


def contact_definitions(s: ContactSym, kind: str) -> dict[str, ca.SX]:
    """The definitions, written apart from the closed forms: E of the gaps (CasADi AD
    only through d), ``gdot`` by forward AD of g along ``phi' = v``, ``c' = v_o``,
    ``q_o' = 1/2 (0, w_o)*q_o`` (the spatial angular velocity), D, and the friction's
    virtual power ``P_v(v_a, v_b, Omega) = h sum w_i f_t . v_y`` at the state's f_t
    (its gradient in the velocities is the friction's Q)."""
    k, delta, c, mu, v_s, r, h = _params(s)
    co, qo, vo, wo = (_obs(s.obs, n) for n in ("c", "q", "v", "w"))
    S = ca.SX.sym
    va_h, vb_h, om_h = S("v_a_hat", 3), S("v_b_hat", 3), S("Omega_hat", 3)
    pose = ca.vertcat(s.phi_a, s.phi_b, co, qo)
    rate = ca.vertcat(s.v_a, s.v_b, vo, 0.5 * qmul(ca.vertcat(0, wo), qo))
    E, D, P_v, P_f = 0, 0, 0, 0
    X = S("x", 3)
    d_X, chi_X = GEOMETRY[kind](rotate_transposed(qo, X - co), s.obs)
    n_X = ca.gradient(d_X, X)
    for xi, wq in zip(*QUADRATURE, strict=True):
        x = (1 - xi) * s.phi_a + xi * s.phi_b
        d, chi, n = ca.substitute([d_X, ca.SX(chi_X), n_X], [X], [x])
        g = d - r
        gdot = ca.jtimes(g, pose, rate)
        E += h * wq * chi * energy_density(g, k, delta)
        sg = sigmoid(-g / delta)
        D += h * wq * chi * 0.5 * c * sg * gdot**2
        B = k * delta * softplus(-g / delta) - c * gdot
        f_N = chi * sg * k * delta / CLIP_SHARPNESS * softplus(CLIP_SHARPNESS * B / (k * delta))
        y = x - r * n

        def v_surface(va, vb, om, xi=xi, n=n):
            return (1 - xi) * va + xi * vb - r * ca.cross(rotate(s.p, om), n)

        v_obs = vo + ca.cross(wo, y - co)
        v_t = v_surface(s.v_a, s.v_b, s.omega) - v_obs
        v_t = v_t - n * ca.dot(n, v_t)
        f_t = -mu * f_N * v_t / ca.sqrt(ca.dot(v_t, v_t) + v_s**2)
        P_v += h * wq * ca.dot(f_t, v_surface(va_h, vb_h, om_h))
        P_f += -h * wq * ca.dot(f_t, v_surface(s.v_a, s.v_b, s.omega) - v_obs)
    hat = ca.vertcat(va_h, vb_h, om_h)
    Q_f = ca.substitute(ca.gradient(P_v, hat), hat, ca.vertcat(s.v_a, s.v_b, s.omega))
    return {"E": E, "D": D, "Q_fric": Q_f, "P_fric": P_f}


def contact_forces_ad(s: ContactSym, kind: str) -> ca.SX:
    """Q = (f_a, f_b, T) by CasADi AD of the definitions (:func:`contact_definitions`):
    ``f = -dE/dphi - dD/dv`` + friction, ``T = torque_from_gradient(p, dE/dp) - dD/dOmega``
    + friction (E and D do not depend on p or Omega: the normal law exerts no torque)."""
    f = contact_definitions(s, kind)
    gE = ca.gradient(f["E"], ca.vertcat(s.phi_a, s.phi_b, s.p))
    gD = ca.gradient(f["D"], ca.vertcat(s.v_a, s.v_b, s.omega))
    return ca.vertcat(-gE[0:6] - gD[0:6], torque_from_gradient(s.p, gE[6:10]) - gD[6:9]) \
        + f["Q_fric"]


def contact_gap_bound(phi_a, phi_b, obs, cnt, kind: str) -> ca.SX:
    """A lower bound of the gap over the whole segment: the gap at its midpoint minus
    half its length (d is 1-Lipschitz; the capped cylinder's smoothing is covered by the
    margin of :data:`CONTACT_CUTOFF`). A segment with ``bound > CONTACT_CUTOFF delta``
    need not be evaluated."""
    co, qo = _obs(obs, "c"), _obs(obs, "q")
    m = 0.5 * (phi_a + phi_b)
    d, _ = GEOMETRY[kind](rotate_transposed(qo, m - co), obs)
    u = phi_b - phi_a
    return d - _cnt(cnt, "r") - 0.5 * ca.sqrt(ca.dot(u, u))


def contact_kernels() -> list[ca.Function]:
    """Per kind of :data:`OBSTACLE_KINDS`: ``rod_contact_<kind>``: Q (9) = (f_a, f_b, T)
    (:data:`CONTACT_FORCES`); ``rod_contact_<kind>_jac``: dQ/dx (9 x 19, dense, column-
    major in C) in the columns (phi_a, phi_b, p, v_a, v_b, Omega)
    (:data:`CONTACT_JAC_COLUMNS`; :func:`contact_jacobian`);
    ``rod_contact_<kind>_diagnostics``: E (J), P_diss (W, damping and friction), F_obs
    (3, N: the force on the obstacle, spatial), M_obs (3, N m: its moment about c),
    P_obs (W: power of the obstacle's motion on the rod), g_min (m: the smallest gap of
    the quadrature points), points (NQ x 4: each point's position and gap), P_fric (W:
    the friction's part of P_diss); ``rod_contact_<kind>_bound``: g_lb (m), a lower
    bound of the segment's gap (:func:`contact_gap_bound`). Inputs, in order: phi_a,
    phi_b, v_a, v_b (3), p (4), Omega (3), obs (:data:`OBS_PARAMS`), cnt
    (:data:`CNT_PARAMS`); the bound takes phi_a, phi_b, obs, cnt."""
    out = []
    for kind in OBSTACLE_KINDS:
        s = contact_symbols()
        q = contact_quantities(s, kind)
        ins = s.inputs()
        name = f"rod_contact_{kind}"
        out += [
            _fn(name, ins, {"Q": q["Q"]}),
            _fn(name + "_jac", ins, {"dQ_dx": ca.densify(contact_jacobian(s, kind))}),
            _fn(name + "_diagnostics", ins,
                {k: q[k] for k in ("E", "P_diss", "F_obs", "M_obs", "P_obs", "g_min",
                                   "points", "P_fric")}),
            _fn(name + "_bound", {"phi_a": s.phi_a, "phi_b": s.phi_b, "obs": s.obs,
                                  "cnt": s.cnt},
                {"g_lb": contact_gap_bound(s.phi_a, s.phi_b, s.obs, s.cnt, kind)}),
        ]
    return out
