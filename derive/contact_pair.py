"""Contact between two rod segments (rod-rod and self contact), as CasADi SX kernels
(issue 32; docs/design.md, section 13, "Contact kernels").

Each segment is a capsule about its centreline, radii r_1 and r_2. The pair interacts
through ONE pair of smoothed closest points (the choice of Tong et al.'s implicit contact
model, IMC 2022), weighted by a contact length W that makes the same law a line contact
when the segments are parallel:

* **Closest points.** Segment 1 ``x(s) = phi_a + s u``, segment 2 ``y(t) = phi_c + t w``;
  ``A = u.u, B = u.w, C = w.w, D = u.r0, E_ = w.r0`` (``r0 = phi_a - phi_c``),
  ``A C - B^2 = A C sin^2(theta)``. Ericson's clamped line-line solution with smooth
  clamps, ``t = clamp((E_ + B s_1)/C)``, ``s = clamp((B t - D)/A)``, ``clamp(z) = z -
  eps softplus((z - 1)/eps) + eps softplus(-z/eps)`` (in (0, 1), :data:`CLAMP_SMOOTHING`
  eps), from ``s_1 = clamp((q^4 s_x + s_m)/(q^4 + 1))``: ``s_x = (B E_ - C D)/(A C -
  B^2)`` the lines' closest point, ``s_m`` the middle of the overlap of segment 2's
  projection on segment 1 (smooth min/max), ``q = l_ov sin(theta)/l_x`` with the
  overlap's length ``l_ov``: crossing segments (``q >> 1``) get the exact closest points,
  parallel ones (where those are not unique) the middle of their overlap.
* **Gap** ``g = sqrt(|x(s) - y(t)|^2 + (eps_r (r_1 + r_2))^2) - r_1 - r_2``
  (:data:`derive.contact.AXIS_REGULARISATION` eps_r: finite at crossing centrelines).
* **Weight** ``W = sqrt(W_l^2 + (l_x sin^2(theta))^2)`` (m), ``W_l = l_ov l_x /
  sqrt(l_x^2 + l_ov^2 sin^2(theta))``: the overlap's length when parallel (so the pairs
  of two parallel rods add up to their overlap, nodes aligned or not, and segments end
  to end weigh nothing), ``~ l_x/sin(theta)`` for oblique segments (the line integral's
  growth as they align, capped by the overlap), l_x for a crossing at right angles.
* **Law** (:func:`derive.contact.gap_law`): ``E = W e(g)``, ``D = W c/2
  sigmoid(-g/delta) gdot^2`` with the exact rate ``gdot`` (forward AD of g along the
  four nodes' velocities), friction at the common contact point ``p_c = (x - r_1 n + y +
  r_2 n)/2`` (n = (x - y)/|x - y|, regularised) on the relative velocity of the two
  segments' material points there, with ``W f_N``.

Q = (f_a, f_b, T_1, f_c, f_d, T_2): ``-dE/dphi - dD/dv`` (AD) plus the friction's share
by the shape functions at s and t; the torques are the friction's moments about x(s) and
y(t) (material). E, D and the friction depend on relative positions and velocities only
and the friction's two forces act at one point: the loads are in equilibrium (total
force and moment zero). A rod's segments near each other along the rod (within
``r_1 + r_2`` of arc length, certainly adjacent ones, which share a node) must not be
paired: their gap is negative by construction.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca

from derive.contact import (
    AXIS_REGULARISATION,
    CLIP_SHARPNESS,
    friction,
    gap_law,
    sigmoid,
    smooth_max,
    smooth_min,
    softplus,
)
from derive.discrete_rod import _field, _fn, _offsets, _size, rotate, rotate_transposed

#: eps of the smooth clamp of the closest points' parameters and of the overlap's smooth
#: min/max (a fraction of the segment)
CLAMP_SMOOTHING = 0.02

#: parameters of one segment pair
PAIR_PARAMS: tuple[tuple[str, int, str, str], ...] = (
    ("k", 1, "N/m^2", "stiffness per length (> 0)"),
    ("delta", 1, "m", "smoothing length of the gap (> 0)"),
    ("c", 1, "N s/m^2", "normal damping per length (>= 0)"),
    ("mu", 1, "1", "Coulomb friction coefficient (>= 0)"),
    ("v_s", 1, "m/s", "slip velocity tolerance (> 0)"),
    ("r_1", 1, "m", "contact radius of segment 1 (>= 0)"),
    ("r_2", 1, "m", "contact radius of segment 2 (>= 0)"),
    ("l_x", 1, "m", "contact length of a crossing at right angles (> 0; r_1 + r_2 "
                    "suggested)"),
)
#: blocks of rod_contact_pair's Q: segment 1 (nodes a, b, its torque), segment 2 (c, d)
PAIR_FORCES: tuple[tuple[str, int], ...] = (
    ("f_a", 3), ("f_b", 3), ("T_1", 3), ("f_c", 3), ("f_d", 3), ("T_2", 3))
#: columns of rod_contact_pair_jac (rows: PAIR_FORCES): the configuration, then the rates
PAIR_JAC_COLUMNS: tuple[tuple[str, int], ...] = (
    ("phi_a", 3), ("phi_b", 3), ("p_1", 4), ("phi_c", 3), ("phi_d", 3), ("p_2", 4),
    ("v_a", 3), ("v_b", 3), ("Omega_1", 3), ("v_c", 3), ("v_d", 3), ("Omega_2", 3))

PAIR_OFFSETS, N_PAIR = _offsets(PAIR_PARAMS), _size(PAIR_PARAMS)
PAIR_FORCE_OFFSETS, N_PAIR_FORCES = _offsets(PAIR_FORCES), _size(PAIR_FORCES)
PAIR_JAC_OFFSETS, N_PAIR_JAC_COLUMNS = _offsets(PAIR_JAC_COLUMNS), _size(PAIR_JAC_COLUMNS)


def _par(pp, name):
    """A named entry of the pair parameter vector (:data:`PAIR_PARAMS`)."""
    return _field(pp, PAIR_OFFSETS, PAIR_PARAMS, name)


@dataclass(frozen=True)
class PairSym:
    """Inputs of the pair kernels (names as in :func:`pair_kernels`)."""

    phi_a: ca.SX
    phi_b: ca.SX
    v_a: ca.SX
    v_b: ca.SX
    p_1: ca.SX
    omega_1: ca.SX
    phi_c: ca.SX
    phi_d: ca.SX
    v_c: ca.SX
    v_d: ca.SX
    p_2: ca.SX
    omega_2: ca.SX
    par: ca.SX     # PAIR_PARAMS

    def inputs(self) -> dict[str, ca.SX]:
        """The kernels' named inputs, in order."""
        return {"phi_a": self.phi_a, "phi_b": self.phi_b, "v_a": self.v_a, "v_b": self.v_b,
                "p_1": self.p_1, "Omega_1": self.omega_1, "phi_c": self.phi_c,
                "phi_d": self.phi_d, "v_c": self.v_c, "v_d": self.v_d, "p_2": self.p_2,
                "Omega_2": self.omega_2, "cnt": self.par}

    def positions(self) -> ca.SX:
        return ca.vertcat(self.phi_a, self.phi_b, self.phi_c, self.phi_d)

    def velocities(self) -> ca.SX:
        return ca.vertcat(self.v_a, self.v_b, self.v_c, self.v_d)

    def jac_columns(self) -> ca.SX:
        """The variables of :data:`PAIR_JAC_COLUMNS`, stacked."""
        return ca.vertcat(self.phi_a, self.phi_b, self.p_1, self.phi_c, self.phi_d, self.p_2,
                          self.v_a, self.v_b, self.omega_1, self.v_c, self.v_d, self.omega_2)


def pair_symbols() -> PairSym:
    """Fresh SX symbols of the pair kernels' inputs."""
    S = ca.SX.sym
    return PairSym(S("phi_a", 3), S("phi_b", 3), S("v_a", 3), S("v_b", 3), S("p_1", 4),
                   S("Omega_1", 3), S("phi_c", 3), S("phi_d", 3), S("v_c", 3), S("v_d", 3),
                   S("p_2", 4), S("Omega_2", 3), S("cnt", N_PAIR))


def smooth_clamp(z, eps=CLAMP_SMOOTHING):
    """``z - eps softplus((z - 1)/eps) + eps softplus(-z/eps)``: in (0, 1), z inside."""
    return z - eps * softplus((z - 1) / eps) + eps * softplus(-z / eps)


def closest_points(phi_a, phi_b, phi_c, phi_d, l_x) -> dict[str, ca.SX]:
    """Smoothed closest points (s, t) of the two segments, their parallelism
    ``sin^2(theta)``, the length of their overlap and the contact length W (see the
    module docstring)."""
    eps = CLAMP_SMOOTHING
    u, w, r0 = phi_b - phi_a, phi_d - phi_c, phi_a - phi_c
    A, B, C = ca.dot(u, u), ca.dot(u, w), ca.dot(w, w)
    D, E = ca.dot(u, r0), ca.dot(w, r0)
    sin2 = (A * C - B**2) / (A * C)
    tau_c, tau_d = -D / A, (B - D) / A
    lo = smooth_max(smooth_min(tau_c, tau_d, eps), 0, eps)
    hi = smooth_min(smooth_max(tau_c, tau_d, eps), 1, eps)
    ov = ca.sqrt(A) * eps * softplus((hi - lo) / eps)
    lx2, ov2 = l_x**2, ov**2
    q4 = (ov2 / lx2) ** 2 * sin2          # (ov sin/l_x)^4 / sin^2
    s1 = smooth_clamp((q4 * (B * E - C * D) / (A * C) + 0.5 * (lo + hi))
                      / (q4 * sin2 + 1))
    t = smooth_clamp((E + B * s1) / C)
    s = smooth_clamp((B * t - D) / A)
    W_line = ov * l_x / ca.sqrt(lx2 + ov2 * sin2)
    return {"s": s, "t": t, "sin2": sin2, "overlap": ov,
            "W": ca.sqrt(W_line**2 + lx2 * sin2**2)}


def _gap(s: PairSym, phi_a, phi_b, phi_c, phi_d) -> dict[str, ca.SX]:
    """Closest points, their positions, the unit normal n (from segment 2 to segment 1,
    regularised) and the gap, for the given node positions."""
    r1, r2 = _par(s.par, "r_1"), _par(s.par, "r_2")
    cp = closest_points(phi_a, phi_b, phi_c, phi_d, _par(s.par, "l_x"))
    x = phi_a + cp["s"] * (phi_b - phi_a)
    y = phi_c + cp["t"] * (phi_d - phi_c)
    dxy = x - y
    dist = ca.sqrt(ca.dot(dxy, dxy) + (AXIS_REGULARISATION * (r1 + r2)) ** 2)
    return {**cp, "x": x, "y": y, "n": dxy / dist, "g": dist - r1 - r2}


def _friction(s: PairSym, geo, f_N):
    """The friction at the common contact point: its force on segment 1 (spatial), the
    moments about x(s) and y(t) (spatial) and its dissipated power."""
    r1, r2 = _par(s.par, "r_1"), _par(s.par, "r_2")
    x, y, n = geo["x"], geo["y"], geo["n"]
    pc = 0.5 * (x - r1 * n + y + r2 * n)
    v1 = s.v_a + geo["s"] * (s.v_b - s.v_a) + ca.cross(rotate(s.p_1, s.omega_1), pc - x)
    v2 = s.v_c + geo["t"] * (s.v_d - s.v_c) + ca.cross(rotate(s.p_2, s.omega_2), pc - y)
    f_t, P_f = friction(v1 - v2, n, f_N, _par(s.par, "mu"), _par(s.par, "v_s"))
    return f_t, ca.cross(pc - x, f_t), ca.cross(pc - y, -f_t), P_f


@dataclass(frozen=True)
class Relative:
    """The relative positions ``u = phi_b - phi_a``, ``w = phi_d - phi_c``,
    ``r0 = phi_a - phi_c`` as symbols (everything of the pair depends on positions only
    through them), and the map of their derivatives to the four nodes'."""

    u: ca.SX
    w: ca.SX
    r0: ca.SX

    @staticmethod
    def symbols() -> Relative:
        S = ca.SX.sym
        return Relative(S("u", 3), S("w", 3), S("r0", 3))

    def stacked(self) -> ca.SX:
        return ca.vertcat(self.u, self.w, self.r0)

    def nodes(self) -> tuple[ca.SX, ca.SX, ca.SX, ca.SX]:
        """Node positions with these differences (phi_c at the origin)."""
        return self.r0, self.r0 + self.u, ca.SX.zeros(3), self.w

    @staticmethod
    def values(s: PairSym) -> ca.SX:
        return ca.vertcat(s.phi_b - s.phi_a, s.phi_d - s.phi_c, s.phi_a - s.phi_c)

    @staticmethod
    def to_nodes(J: ca.SX) -> ca.SX:
        """d/d(u, w, r0) (columns 0:9) -> d/d(phi_a, phi_b, phi_c, phi_d) (12)."""
        du, dw, dr = J[:, 0:3], J[:, 3:6], J[:, 6:9]
        return ca.horzcat(dr - du, du, -dr - dw, dw)


def pair_quantities(s: PairSym) -> dict[str, ca.SX]:
    """Q, E, the dissipated powers and the gap of a segment pair, in the relative
    positions (:class:`Relative`; substitute ``Relative.values`` for them): the normal
    law's forces ``-W e'(g) grad g - e grad W`` and ``-c W sigmoid gdot grad g`` with
    grad g, grad W by CasADi AD (reverse), ``gdot = grad g . v``, the friction in closed
    form. ``rel`` holds the symbols."""
    k, delta, c = _par(s.par, "k"), _par(s.par, "delta"), _par(s.par, "c")
    rel = Relative.symbols()
    geo = _gap(s, *rel.nodes())
    gg = Relative.to_nodes(ca.jacobian(geo["g"], rel.stacked())).T
    gW = Relative.to_nodes(ca.jacobian(geo["W"], rel.stacked())).T
    gdot = ca.dot(gg, s.velocities())
    law = gap_law(geo["g"], gdot, k, delta, c)
    Wc = geo["W"]
    F = Wc * law.f_n * gg - law.e * gW       # = -dE/dX - dD/dV
    f_t, m1, m2, P_f = _friction(s, geo, Wc * law.f_N)
    sp, tp = geo["s"], geo["t"]
    Q = ca.vertcat(F[0:3] + (1 - sp) * f_t, F[3:6] + sp * f_t,
                   rotate_transposed(s.p_1, m1),
                   F[6:9] - (1 - tp) * f_t, F[9:12] - tp * f_t,
                   rotate_transposed(s.p_2, m2))
    return {"rel": rel, "Q": Q, "E": Wc * law.e, "P_diss": Wc * law.P_d + P_f,
            "P_fric": P_f, "g": geo["g"], "st": ca.vertcat(sp, tp), "W": Wc,
            "F_12": Q[0:3] + Q[3:6]}


def pair_jacobian(s: PairSym, q: dict[str, ca.SX]) -> ca.SX:
    """dQ/dx in :data:`PAIR_JAC_COLUMNS` from :func:`pair_quantities` (in the relative
    positions: 9 position columns differentiated instead of 12, a third fewer
    instructions)."""
    rel = q["rel"]
    Q = q["Q"]
    Jx = Relative.to_nodes(ca.jacobian(Q, rel.stacked()))
    Jr = ca.jacobian(Q, ca.vertcat(s.p_1, s.p_2, s.v_a, s.v_b, s.omega_1, s.v_c, s.v_d,
                                   s.omega_2))
    return ca.horzcat(Jx[:, 0:6], Jr[:, 0:4], Jx[:, 6:12], Jr[:, 4:8], Jr[:, 8:26])


def pair_definitions(s: PairSym) -> dict[str, ca.SX]:
    """The definitions: ``E = W e(g)``, ``D = W c/2 sigmoid(-g/delta) gdot^2`` with
    gdot by forward AD (``jtimes``) of g along the velocities, and the friction's virtual
    power at the state's friction force (its gradient in the rates is its Q)."""
    k, delta, c = _par(s.par, "k"), _par(s.par, "delta"), _par(s.par, "c")
    geo = _gap(s, s.phi_a, s.phi_b, s.phi_c, s.phi_d)
    X, V = s.positions(), s.velocities()
    g = geo["g"]
    gdot = ca.jtimes(g, X, V)
    x = -g / delta
    E = geo["W"] * 0.5 * k * delta**2 * softplus(x) ** 2
    D = geo["W"] * 0.5 * c * sigmoid(x) * gdot**2
    B = k * delta * softplus(x) - c * gdot
    f_N = geo["W"] * sigmoid(x) * k * delta / CLIP_SHARPNESS \
        * softplus(CLIP_SHARPNESS * B / (k * delta))
    f_t, _, _, P_f = _friction(s, geo, f_N)
    r1, r2 = _par(s.par, "r_1"), _par(s.par, "r_2")
    pc = 0.5 * (geo["x"] - r1 * geo["n"] + geo["y"] + r2 * geo["n"])
    S = ca.SX.sym
    hat = [S(n, 3) for n in ("va", "vb", "om1", "vc", "vd", "om2")]
    v1 = hat[0] + geo["s"] * (hat[1] - hat[0]) + ca.cross(rotate(s.p_1, hat[2]), pc - geo["x"])
    v2 = hat[3] + geo["t"] * (hat[4] - hat[3]) + ca.cross(rotate(s.p_2, hat[5]), pc - geo["y"])
    P_v = ca.dot(f_t, v1 - v2)
    H = ca.vertcat(*hat)
    Q_f = ca.substitute(ca.gradient(P_v, H), H,
                        ca.vertcat(s.v_a, s.v_b, s.omega_1, s.v_c, s.v_d, s.omega_2))
    return {"E": E, "D": D, "Q_fric": Q_f, "P_fric": P_f}


def pair_forces_ad(s: PairSym) -> ca.SX:
    """Q by CasADi AD of :func:`pair_definitions` (E and D depend on positions and
    velocities only: the normal law exerts no torque)."""
    f = pair_definitions(s)
    gE = ca.gradient(f["E"], s.positions())
    gD = ca.gradient(f["D"], s.velocities())
    F = -gE - gD
    z = ca.SX.zeros(3)
    return ca.vertcat(F[0:3], F[3:6], z, F[6:9], F[9:12], z) + f["Q_fric"]


def pair_gap_bound(phi_a, phi_b, phi_c, phi_d, par) -> ca.SX:
    """A lower bound of the pair's gap: the midpoints' distance minus the half lengths
    and the radii (the smoothed closest points lie on the segments). A pair with ``bound >
    CONTACT_CUTOFF delta`` need not be evaluated."""
    dm = 0.5 * (phi_a + phi_b - phi_c - phi_d)
    u, w = phi_b - phi_a, phi_d - phi_c
    return (ca.sqrt(ca.dot(dm, dm)) - 0.5 * (ca.sqrt(ca.dot(u, u)) + ca.sqrt(ca.dot(w, w)))
            - _par(par, "r_1") - _par(par, "r_2"))


def pair_kernels() -> list[ca.Function]:
    """``rod_contact_pair``: Q (18) = (f_a, f_b, T_1, f_c, f_d, T_2) (:data:`PAIR_FORCES`);
    ``rod_contact_pair_jac``: dQ/dx (18 x 38, dense, column-major in C) in the columns
    (phi_a, phi_b, p_1, phi_c, phi_d, p_2, v_a, v_b, Omega_1, v_c, v_d, Omega_2)
    (:data:`PAIR_JAC_COLUMNS`); ``rod_contact_pair_diagnostics``: E (J), P_diss (W),
    g_min (m: the pair's gap), P_fric (W: the friction's part of P_diss), st (2: the
    contact parameters s, t on the two segments), W (m: the contact length), F_12 (3, N:
    the force segment 2 exerts on segment 1); ``rod_contact_pair_bound``: g_lb (m,
    :func:`pair_gap_bound`). Inputs, in order: phi_a, phi_b, v_a, v_b (3), p_1 (4),
    Omega_1 (3), phi_c, phi_d, v_c, v_d (3), p_2 (4), Omega_2 (3), cnt
    (:data:`PAIR_PARAMS`); the bound takes phi_a, phi_b, phi_c, phi_d, cnt."""
    s = pair_symbols()
    q = pair_quantities(s)
    rel, vals = q["rel"].stacked(), Relative.values(s)
    out = {k: ca.substitute(v, rel, vals) for k, v in q.items() if k != "rel"}
    J = ca.substitute(pair_jacobian(s, q), rel, vals)
    ins = s.inputs()
    return [
        _fn("rod_contact_pair", ins, {"Q": out["Q"]}),
        _fn("rod_contact_pair_jac", ins, {"dQ_dx": ca.densify(J)}),
        _fn("rod_contact_pair_diagnostics", ins,
            {"E": out["E"], "P_diss": out["P_diss"], "g_min": out["g"],
             "P_fric": out["P_fric"], "st": out["st"], "W": out["W"], "F_12": out["F_12"]}),
        _fn("rod_contact_pair_bound", {"phi_a": s.phi_a, "phi_b": s.phi_b, "phi_c": s.phi_c,
                                       "phi_d": s.phi_d, "cnt": s.par},
            {"g_lb": pair_gap_bound(s.phi_a, s.phi_b, s.phi_c, s.phi_d, s.par)}),
    ]
