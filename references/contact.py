"""Independent references for rods in contact with rigid bodies (NumPy only, no kvrod code).

SI units, angles in rad, gravity ``g`` in m/s^2, weights per length ``q`` in N/m.
Coulomb friction with one coefficient ``mu`` (static = kinetic). Each function states its
assumptions, derivation and source; the tests (``tests/references/test_contact_refs.py``)
check the derived ones against separately written numerical models.

- :func:`lifted_rod`, :func:`lifted_rod_curve`: a heavy rod on a rigid flat table lifted at
  one end by a vertical force (rigid-contact beam theory, Euler-Bernoulli and Timoshenko);
- :func:`incline`, :func:`incline_slide_distance`, :func:`round_rod_across_incline`: a
  rod on an inclined plane (sticking, sliding; a round rod lying across the slope rolls);
- :func:`capstan_ratio`, :func:`capstan_profile`: the capstan (Euler-Eytelwein) equation,
  membrane limit; :func:`capstan_ratio_rod`: a rod of finite radius, stress free as
  wrapped, with the friction at its surface;
- :func:`flat_drop`: a rod dropped flat onto a rigid floor (contact time, rest height);
- :func:`draped_cable`, :func:`draped_cable_max_overhang`: a heavy flexible cable hanging
  over a cylinder (tension, contact pressure, slip limit with friction);
- :func:`insertion_force_capstan`, :func:`bend_entry_force`: a rod pushed through a
  curved pipe (membrane capstan limit; the frictionless configurational force).
"""

from __future__ import annotations

import math

import numpy as np

__all__ = [
    "bend_entry_force",
    "capstan_profile",
    "capstan_ratio",
    "capstan_ratio_rod",
    "draped_cable",
    "draped_cable_max_overhang",
    "flat_drop",
    "incline",
    "incline_slide_distance",
    "insertion_force_capstan",
    "lifted_rod",
    "lifted_rod_curve",
    "round_rod_across_incline",
]


def _positive(name: str, value: float, *, allow_inf: bool = False) -> float:
    v = float(value)
    if not (v > 0 and (allow_inf or math.isfinite(v))):
        rng = "> 0 (inf allowed)" if allow_inf else "finite and > 0"
        raise ValueError(f"{name} must be {rng}, got {value!r}")
    return v


def _nonnegative(name: str, value: float) -> float:
    v = float(value)
    if not (v >= 0 and math.isfinite(v)):
        raise ValueError(f"{name} must be finite and >= 0, got {value!r}")
    return v


def _angle(name: str, value: float, upper: float) -> float:
    v = float(value)
    if not (0 <= v < upper):
        raise ValueError(f"{name} must be in [0, {upper:g}) rad, got {value!r}")
    return v


# ----------------------------------------------------------------- rod lifted off a table
def lifted_rod(F: float, *, q: float, EI: float, kGA: float = math.inf,
               L: float | None = None) -> dict[str, float]:
    """A heavy straight rod lying on a rigid flat table, one end lifted by a vertical force.

    ``F`` (N) upward at the end, weight per length ``q`` (N/m), bending stiffness ``EI``
    (N m^2), shear stiffness ``kGA`` (N; ``inf``: Euler-Bernoulli), rod length ``L`` (m;
    ``None``: semi-infinite). Linear beam theory (small slopes), inextensible, rigid
    frictionless table; ``x`` is measured from the lifted end. The rod leaves the table
    at ``x = a`` (the lifted length) and lies flat beyond it.

    Statics of the lifted part: shear ``Q = q x - F`` and moment ``M = F x - q x^2/2``.
    On the table ``w = 0``; contact gives forces but no couples, so the moment is
    continuous at ``x = a``.

    Euler-Bernoulli: on the table the curvature, hence ``M``, vanishes, so ``M(a) = 0``::

        a = 2 F / q,    end height h = q a^4 / (24 EI) = (2 F)^4 / (24 EI q^3),
        end slope q a^3 / (12 EI),

    with ``w = w' = w'' = 0`` at ``x = a`` (lift-off). The shear is not continuous there:
    ``Q(a-) = F`` is carried by a point reaction ``F`` from the table at the lift-off point
    (the lifted part weighs ``2F``; the lifting force carries half of it). (The "shear
    continuity" condition, ``Q(a) = 0``, would give ``a = F/q`` with a nonzero moment at
    the lift-off point; it is wrong.) Derived here; the lift-off conditions
    ``w = w' = w'' = 0`` are those of a heavy elastica leaving a rigid flat support, as in
    Vella, Boudaoud and Adda-Bedia, Phys. Rev. Lett. 103, 174301 (2009), "Statics and
    inertial dynamics of a ruck in a rug".

    Timoshenko (derived here, checked against an obstacle finite-element model in the
    tests): on the table ``w = 0`` but the sections may still rotate, ``psi = C
    exp(-(x - a)/l)`` with ``l = sqrt(EI / kGA)`` (a rotational boundary layer), so
    ``M(a) = -EI C / l``; the lift-off point is where the slope ``w'(a-) = psi + Q/kGA``
    vanishes (equivalently: no point reaction; the table pressure carries the extra
    ``q a - F`` over the boundary layer). This gives ``M(a) = l (q a - F)`` and::

        a = ((a0 - 2 l) + sqrt(a0^2 + 4 l^2)) / 2,     a0 = 2F/q,
        h = (F a^3/3 - q a^4/8) / EI + q a^2 / (2 kGA),

    both reducing to the Euler-Bernoulli values for ``l = 0`` (the relative change of
    ``h`` is second order in ``l / a``: about ``6 (l/a0)^2``). Valid when the part on the
    table is long against ``l``.

    Range: ``F > 0``; with a finite ``L`` the lifted length must be shorter than the rod
    (Euler-Bernoulli: ``F < q L / 2``). For ``F >= q L/2`` there is no such equilibrium:
    the whole rod pivots rigidly about its far end (moment balance ``F L = q L^2/2``) and
    the small-deflection theory does not apply. Returns ``lifted_length`` ``a`` (m),
    ``end_height`` (m), ``end_slope`` (rad, magnitude of ``dw/dx`` at the lifted end),
    ``liftoff_point_force`` (N: the table's point reaction at ``x = a``, ``F`` for
    Euler-Bernoulli, 0 with shear), ``boundary_layer`` ``l`` (m) and ``table_force``
    (N, total upward force of the table: ``q L - F``; ``nan`` for ``L = None``).
    """
    F, q, EI = _positive("F", F), _positive("q", q), _positive("EI", EI)
    kGA = _positive("kGA", kGA, allow_inf=True)
    ell = math.sqrt(EI / kGA)
    a0 = 2.0 * F / q
    a = 0.5 * ((a0 - 2.0 * ell) + math.sqrt(a0 * a0 + 4.0 * ell * ell))
    if L is not None:
        L = _positive("L", L)
        if a >= L:
            raise ValueError(f"F must be below about q L / 2 = {q * L / 2:g} N (the "
                             f"lifted length {a:g} m must be shorter than L = {L:g} m), "
                             f"got F = {F!r}")
    h = (F * a**3 / 3.0 - q * a**4 / 8.0) / EI + q * a * a / (2.0 * kGA)
    C = -(q * a - F) / kGA                     # section rotation at the lift-off point
    psi0 = C - (F * a * a / 2.0 - q * a**3 / 6.0) / EI
    slope = psi0 - F / kGA                     # w'(0) = psi(0) + Q(0)/kGA, Q(0) = -F
    return {"lifted_length": a, "end_height": h, "end_slope": -slope,
            "liftoff_point_force": F if kGA == math.inf else 0.0,
            "boundary_layer": ell,
            "table_force": q * L - F if L is not None else math.nan}


def lifted_rod_curve(x: np.ndarray | float, F: float, *, q: float, EI: float,
                     kGA: float = math.inf) -> np.ndarray:
    """Height ``w(x)`` (m) of the rod of :func:`lifted_rod` at the distance ``x`` (m) from
    the lifted end (0 on the table, ``x >= a``)::

        w(x) = -int_x^a (psi + Q/kGA) d xi,   psi(xi) = C - int_xi^a M/EI,

    ``C = -(q a - F)/kGA`` (0 for Euler-Bernoulli). Euler-Bernoulli, with ``xi = a - x``:
    ``w = q a xi^3/(12 EI) - q xi^4/(24 EI)``.
    """
    res = lifted_rod(F, q=q, EI=EI, kGA=kGA)
    a = res["lifted_length"]
    x = np.asarray(x, dtype=float)
    C = -(q * a - F) / kGA

    def p1(t):   # int_0^t M
        return F * t * t / 2.0 - q * t**3 / 6.0

    def p2(t):   # int_0^t p1
        return F * t**3 / 6.0 - q * t**4 / 24.0

    def pq(t):   # int_0^t Q
        return -F * t + q * t * t / 2.0

    xc = np.minimum(x, a)
    int_psi = C * (a - xc) - p1(a) * (a - xc) / EI + (p2(a) - p2(xc)) / EI
    return -(int_psi + (pq(a) - pq(xc)) / kGA)


# ------------------------------------------------------------------------------ incline
def incline(theta: float, mu: float, g: float = 9.81) -> dict[str, float | bool]:
    """A rod lying along the fall line of an incline (or any block that cannot roll).

    Incline angle ``theta`` (rad), Coulomb coefficient ``mu``. Normal force per weight
    ``cos theta``, driving force per weight ``sin theta``. Sticking from rest while the
    friction can hold it, ``mu cos theta >= sin theta``, i.e. ``mu >= tan theta``
    (equality: impending slip, still at rest); otherwise it slides down with::

        acceleration = g (sin theta - mu cos theta)

    (any statics/dynamics text, e.g. Meriam and Kraige, Engineering Mechanics: Dynamics).
    Returns ``sticks``, ``acceleration`` (m/s^2 along the slope, 0 if sticking) and
    ``friction_force_per_weight`` (``sin theta`` sticking, ``mu cos theta`` sliding).
    """
    theta = _angle("theta", theta, math.pi / 2)
    mu, g = _nonnegative("mu", mu), _positive("g", g)
    sticks = mu * math.cos(theta) >= math.sin(theta)
    if sticks:
        return {"sticks": True, "acceleration": 0.0,
                "friction_force_per_weight": math.sin(theta)}
    return {"sticks": False, "acceleration": g * (math.sin(theta) - mu * math.cos(theta)),
            "friction_force_per_weight": mu * math.cos(theta)}


def incline_slide_distance(t: np.ndarray | float, *, theta: float, mu: float,
                           g: float = 9.81) -> np.ndarray:
    """Distance (m) slid down the slope after the time ``t`` (s) from rest:
    ``d = g (sin theta - mu cos theta) t^2 / 2`` when sliding, 0 when it sticks
    (:func:`incline`)."""
    t = np.asarray(t, dtype=float)
    if np.any(t < 0):
        raise ValueError(f"t must be >= 0, got {t!r}")
    return 0.5 * float(incline(theta, mu, g)["acceleration"]) * t * t


def round_rod_across_incline(theta: float, mu: float, g: float = 9.81,
                             inertia_ratio: float = 0.5) -> dict[str, float | bool]:
    """A round rod lying across the slope (axis horizontal) rolls: it never sticks.

    ``inertia_ratio`` ``k = I / (m r^2)`` about the rod's axis (1/2 for a solid circular
    section, 1 for a thin tube). Rolling without slipping needs the friction
    ``k/(1+k) m g sin theta <= mu m g cos theta``, i.e. ``mu >= k tan theta / (1 + k)``
    (``tan theta / 3`` for a solid rod); then the axis accelerates at
    ``g sin theta / (1 + k)`` (``2/3 g sin theta``). Otherwise it slides while spinning
    up: the axis accelerates at ``g (sin theta - mu cos theta)`` and the spin at
    ``mu g cos theta / (k r)``. (Rigid-body dynamics, e.g. Meriam and Kraige.) Returns
    ``rolls_without_slip``, ``acceleration`` (m/s^2 of the axis along the slope).
    The incline test of a Cosserat rod therefore sticks only if the rod lies along the
    fall line (:func:`incline`) or its rotation about its axis is held.
    """
    theta = _angle("theta", theta, math.pi / 2)
    mu, g = _nonnegative("mu", mu), _positive("g", g)
    k = _positive("inertia_ratio", inertia_ratio)
    if mu >= k * math.tan(theta) / (1 + k):
        return {"rolls_without_slip": True, "acceleration": g * math.sin(theta) / (1 + k)}
    return {"rolls_without_slip": False,
            "acceleration": g * (math.sin(theta) - mu * math.cos(theta))}


# ------------------------------------------------------------------------------ capstan
def capstan_ratio(mu: float, wrap_angle: float) -> float:
    """Tension ratio ``T_load / T_hold = exp(mu wrap_angle)`` at which a rope slips on a
    fixed cylinder (Euler 1762, Eytelwein 1808).

    Membrane limit: a perfectly flexible (no bending stiffness), extensible or not,
    weightless rope, in a plane normal to the cylinder axis, with Coulomb friction
    ``mu``; ``wrap_angle`` (rad) is the angle between the directions of the two free
    strands (any number of turns). Equilibrium of an element ``ds`` on the radius ``R``:
    normal ``p = T/R``, tangential ``dT/ds = mu p`` at impending slip, so
    ``dT/dphi = mu T``. Independent of ``R``. With bending stiffness ``EI`` the rope
    leaves the cylinder before the membrane tangent points, with point reactions there;
    the correction is governed by ``sqrt(EI/T)/R`` (Singh, J. Elasticity 151, 2022,
    321-346, "Planar equilibria of an elastic rod wrapped around a circular capstan"),
    so a rod comparison must have ``sqrt(EI/T) << R``.
    """
    mu = _nonnegative("mu", mu)
    wrap_angle = _nonnegative("wrap_angle", wrap_angle)
    return math.exp(mu * wrap_angle)


def capstan_ratio_rod(mu: float, wrap_angle: float, *, drum_radius: float,
                      rod_radius: float) -> float:
    """Tension ratio ``T_load / T_hold`` of a round rod of radius r slipping on a fixed drum
    of radius R, its centreline on the radius ``rho = R + r``, the friction acting at the
    rod's surface (on the drum, r inside the centreline).

    Assumptions: planar, the rod stress free in its wrapped shape (curvature 1/rho: the
    bending moment is the same all along the wrap, so the bending stiffness enters only
    through the shear), inextensible and unshearable, Coulomb friction ``mu`` fully
    mobilized in one direction; the held strand leaves the wrap at its start free of
    shear (a free end or a straight strand), the loaded end is held by a support that
    takes the wrap's shear (a clamp at the wrap's end). Per length, with the tension T,
    the shear Q (outward), the pressure p and the friction ``f = mu p`` (toward the held
    end) at the surface: the friction's moment about the centreline ``r f`` is carried
    by the shear, ``Q = r mu p``; along the tangent ``T' = f - Q/rho = mu (R/rho) p``
    (the tension grows by R/rho of the friction); across it ``p = T/rho - Q'``. So
    ``(T, p)' = A (T, p)`` with constant A, whose eigenvalues solve
    ``r mu lambda^2 + lambda - mu R/rho^2 = 0``; with ``p(0) = 0`` (no shear at the held
    start: a boundary layer of length ``~ r mu``) and the layer decayed at the loaded end,
    ``T_load/T_hold = lambda_-/(lambda_- - lambda_+) exp(lambda_+ rho wrap_angle)``.
    For r -> 0 this is :func:`capstan_ratio`; for ``r/R = 0.01``, ``mu = 0.3``, half a turn
    it is 1.1 % below it. Derived here; checked against a chain of rigid links on the
    drum (tests/references/test_contact_refs.py)."""
    mu = _nonnegative("mu", mu)
    wrap_angle = _nonnegative("wrap_angle", wrap_angle)
    R = _positive("drum_radius", drum_radius)
    r = _nonnegative("rod_radius", rod_radius)
    rho = R + r
    if r * mu == 0.0:
        return math.exp(mu * R / rho * wrap_angle)
    disc = math.sqrt(1.0 + 4.0 * r * mu * mu * R / rho**2)
    lam_p = 2.0 * mu * R / rho**2 / (1.0 + disc)      # (-1 + disc)/(2 r mu), no cancellation
    lam_m = (-1.0 - disc) / (2.0 * r * mu)
    return lam_m / (lam_m - lam_p) * math.exp(lam_p * rho * wrap_angle)


def capstan_profile(phi: np.ndarray | float, *, T_hold: float, mu: float, R: float
                    ) -> tuple[np.ndarray, np.ndarray]:
    """Tension ``T(phi) = T_hold exp(mu phi)`` (N) and contact pressure ``p = T/R`` (N/m)
    along the wrap of :func:`capstan_ratio` at impending slip, ``phi`` (rad) measured from
    the holding strand's tangent point; ``R`` (m) is the radius of the rope's centreline
    (cylinder radius plus rope radius)."""
    T_hold, R = _positive("T_hold", T_hold), _positive("R", R)
    mu = _nonnegative("mu", mu)
    phi = np.asarray(phi, dtype=float)
    if np.any(phi < 0):
        raise ValueError(f"phi must be >= 0, got {phi!r}")
    T = T_hold * np.exp(mu * phi)
    return T, T / R


# ---------------------------------------------------------------------------- flat drop
def flat_drop(h0: float, *, radius: float, g: float = 9.81) -> dict[str, float]:
    """A straight rod of round section released from rest, horizontal, with its centreline
    at the height ``h0`` (m) above a rigid flat floor.

    It falls as a rigid body (no rotation, uniform gravity): it touches the floor when the
    centreline is at ``radius`` (m) above it, after ``t = sqrt(2 (h0 - radius) / g)`` at
    the speed ``sqrt(2 g (h0 - radius))``. At rest on the floor its centreline height is
    ``radius`` everywhere (no sag: the support is continuous and uniform, so the
    distributed contact pressure equals the weight per length and the rod carries no
    bending moment). Returns ``time_to_contact`` (s), ``impact_speed`` (m/s) and
    ``rest_height`` (m).
    """
    radius, g = _positive("radius", radius), _positive("g", g)
    h0 = float(h0)
    if not (h0 >= radius and math.isfinite(h0)):
        raise ValueError(f"h0 must be finite and >= radius = {radius:g} m, got {h0!r}")
    return {"time_to_contact": math.sqrt(2.0 * (h0 - radius) / g),
            "impact_speed": math.sqrt(2.0 * g * (h0 - radius)), "rest_height": radius}


# ------------------------------------------------------------------- cable over cylinder
def draped_cable(phi: np.ndarray | float, *, q: float, R: float, h_low: float,
                 mu: float = 0.0) -> dict[str, np.ndarray | float]:
    """A heavy, perfectly flexible, inextensible cable hanging over a fixed horizontal
    cylinder, both ends free.

    Weight per length ``q`` (N/m); ``R`` (m) the radius of the cable's centreline on the
    cylinder; the two free parts hang vertically (nothing pulls them sideways), so the
    cable touches the upper half circle ``phi`` in ``[-pi/2, pi/2]`` (``phi`` from the top,
    positive towards the heavier side), with ``h_low`` (m) hanging below the tangent
    point on the lighter side (``phi = -pi/2``). Equilibrium of an element::

        dT/dphi = mu (T + q R cos phi) - q R sin phi,    p = T/R + q cos phi

    (tangential: weight component ``-q sin phi`` plus friction ``mu p`` against the slip
    towards ``phi > 0``; normal: the contact pressure ``p`` balances ``T/R`` and the
    weight component ``q cos phi``). Solution with ``T(-pi/2) = q h_low``::

        T = c exp(mu phi) + A cos phi + B sin phi,
        A = q R (1 - mu^2)/(1 + mu^2),  B = 2 mu q R/(1 + mu^2),
        c = (q h_low + B) exp(mu pi/2).

    ``mu = 0`` (smooth): ``T = q (h_low + R cos phi)``, both overhangs equal, the tension
    is largest on top and ``p = q h_low/R + 2 q cos phi``; the total upward force of the
    cylinder equals the weight ``q (2 h_low + pi R)``. (The simple estimate ``p = T/R``
    with ``T = q h`` misses the cable's own weight on the arc: ``T`` grows by ``q R``
    from the tangent points to the top and the weight adds ``q cos phi``.) With friction
    the formula is the profile at impending slip; the heavier side then hangs
    :func:`draped_cable_max_overhang`. Derived here by the integrating factor; the tests
    check it against the global balance of forces and moments. Returns ``T`` (N), ``p``
    (N/m) at ``phi`` and ``h_high`` (m), the overhang of the heavier side.
    """
    q, R = _positive("q", q), _positive("R", R)
    h_low, mu = _nonnegative("h_low", h_low), _nonnegative("mu", mu)
    phi = np.asarray(phi, dtype=float)
    if np.any(np.abs(phi) > math.pi / 2 + 1e-12):
        raise ValueError(f"phi must be in [-pi/2, pi/2], got {phi!r}")
    A = q * R * (1 - mu * mu) / (1 + mu * mu)
    B = 2 * mu * q * R / (1 + mu * mu)
    c = (q * h_low + B) * math.exp(mu * math.pi / 2)
    T = c * np.exp(mu * phi) + A * np.cos(phi) + B * np.sin(phi)
    return {"T": T, "p": T / R + q * np.cos(phi),
            "h_high": draped_cable_max_overhang(h_low, R=R, mu=mu)}


def draped_cable_max_overhang(h_low: float, *, R: float, mu: float) -> float:
    """Longest overhang (m) of the heavier side of :func:`draped_cable` before it slips::

        h_high = exp(mu pi) h_low + 2 mu R (1 + exp(mu pi)) / (1 + mu^2)

    (``T(pi/2) = q h_high``). ``mu = 0``: ``h_high = h_low``; ``R -> 0``: the capstan
    ratio ``exp(mu pi)`` of a half turn; the second term is the friction of the arc's own
    weight. Independent of ``q``."""
    R, h_low, mu = _positive("R", R), _nonnegative("h_low", h_low), _nonnegative("mu", mu)
    e = math.exp(mu * math.pi)
    return e * h_low + 2 * mu * R * (1 + e) / (1 + mu * mu)


# --------------------------------------------------------------------- rod in a bent pipe
def insertion_force_capstan(F_out: float, *, mu: float, bend_angle: float) -> float:
    """Push force (N) needed at the entry of a bend to drive a rod through it against the
    force ``F_out`` (N) resisting at the exit: ``F_in = F_out exp(mu bend_angle)``.

    Membrane (soft-string) limit: the rod carries the axial compression ``P`` and no
    bending moment; in a bend of radius ``R`` it presses on the outer wall with
    ``p = P/R`` and friction ``mu p`` opposes the motion, so ``dP/ds = mu P/R`` — the
    capstan equation for compression (the soft-string torque-and-drag model of
    Johancsik, Friesen and Dawson, J. Petrol. Tech. 36, 1984). Assumes quasi-static
    sliding, a bend of constant curvature over the angle ``bend_angle`` (rad), the rod
    conforming to the bend, no buckling in the straight parts, weightless rod. A rod of
    bending stiffness ``EI`` in a bend of constant radius carries the constant moment
    ``EI/R`` (no shear, so the same equation holds along the conforming arc); bending
    adds forces only at the entry and exit transitions: without friction the net is
    :func:`bend_entry_force` while the tip is inside the bend and 0 once the rod runs
    through it; with friction the transition point forces add friction that depends on
    the clearance of the pipe and has no closed form.
    """
    F_out = _nonnegative("F_out", F_out)
    return F_out * capstan_ratio(mu, bend_angle)


def bend_entry_force(EI: float, R: float) -> float:
    """Frictionless push force ``EI / (2 R^2)`` (N) to advance an elastic rod whose tip is
    inside a bend of constant radius ``R`` (m) of a smooth channel.

    Energy balance (quasi-static, frictionless, inextensible rod, straight before the
    bend): advancing by ``ds`` moves the steady entry transition along and adds ``ds`` of
    rod bent to the curvature ``1/R``, the elastic energy ``EI/(2 R^2) ds``; the push does
    the work ``F ds``. This is the configurational (Eshelby-like) force ``M^2/(2 EI)`` with
    ``M = EI/R`` of Bigoni, Dal Corso, Bosi and Misseroni (Mech. Mater. 80, 2015,
    "Eshelby-like forces acting on elastic structures: theoretical and experimental
    proof"). Once the tip has left the bend into a straight pipe the stored energy is
    constant and the frictionless push force is 0.
    """
    return _positive("EI", EI) / (2.0 * _positive("R", R) ** 2)
