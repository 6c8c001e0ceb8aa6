r"""Axial stiffness of a helical rod (open-coiled spring): closed forms and 3-D shooting.

Geometry: coil radius ``R`` (m), pitch ``P`` (axial rise per turn, m), ``n`` turns (need not
be an integer), helix angle ``alpha = atan(P / (2 pi R))``, wire length
``l = 2 pi R n / cos(alpha)``. Centerline (axis ``e3``, right-handed helix)::

    r(phi) = (R cos phi, R sin phi, R phi tan(alpha)),   phi = s cos(alpha) / R in [0, Phi],
    Phi = 2 pi n,   curvature kappa = cos^2(alpha) / R,   torsion tau = sin(alpha) cos(alpha) / R.

Wire: equal shear stiffness ``GA`` (shear-corrected) and equal bending stiffness ``EI`` in
both directions, axial ``EA``, torsional ``GJ``. With these the director orientation about
the tangent does not matter; the rod model uses the Frenet-type frame
``(d1, d2, d3) = (B, -N, T)`` (``T`` tangent, ``N`` principal normal towards the axis,
``B = T x N`` binormal), in which the intrinsic curvature is constant:
``K0 = (kappa, 0, tau)`` (the Darboux vector ``tau T + kappa B``).
``frame="frenet"`` uses ``(N, B, T)`` and ``K0 = (0, kappa, tau)`` instead.

Load cases (the start ``s = 0`` at ``(R, 0, 0)`` is clamped in both):

(a) ``"axis"``: the classical spring. A force ``F e3`` acts at the point ``c`` of the coil
    axis at the height of the free end, carried by a rigid arm attached to the end section
    (the end is otherwise free, it may rotate). The deflection is the axial displacement of
    ``c``.
(b) ``"end"``: the force ``F e3`` acts at the end point of the wire, which is free to
    rotate (no end couple); the deflection is the axial displacement of the end point.

Derivation (linear theory, Castigliano): the rod is statically determinate, so in the
reference configuration the resultants at a section ``r(s)`` are ``n = F e3`` and
``m = (p - r(s)) x F e3`` with ``p`` the load point. The complementary energy per length is
``n . C_F^{-1} n / 2 + m . C_M^{-1} m / 2`` with (equal ``EI``, equal ``GA``)::

    C_F^{-1} = I / GA + (1/EA - 1/GA) T T^T,    C_M^{-1} = I / EI + (1/GJ - 1/EI) T T^T,

and ``T = cos(alpha) e_phi + sin(alpha) e3``. The force part is the same for both cases:
``n . C_F^{-1} n = F^2 (sin^2(alpha)/EA + cos^2(alpha)/GA)``.

(a) ``p - r = -R e_rho + (z_c - z) e3`` gives ``m = F R e_phi``: a torque ``F R cos(alpha)``
    and a bending moment ``F R sin(alpha)``, the same in every section. Hence
    ``U = F^2 l / 2 [R^2 (cos^2/GJ + sin^2/EI) + sin^2/EA + cos^2/GA]`` and
    ``delta = dU/dF``::

        delta_axis = F R^2 l [cos^2(alpha)/GJ + sin^2(alpha)/EI]          (Timoshenko, Wahl)
                   + F l [sin^2(alpha)/EA + cos^2(alpha)/GA]              (extension, shear)

    The first line is the classical open-coiled spring formula with the pitch correction
    (Timoshenko, Strength of Materials, Part I, open-coiled helical springs; Wahl,
    Mechanical Springs, 2nd ed. 1963); the closed-coil limit ``alpha -> 0`` is
    ``F R^2 l / GJ = 64 F R^3 n / (G d^4)`` for a round wire of diameter ``d``. The second
    line adds the axial force ``F sin(alpha)`` and shear force ``F cos(alpha)`` of the
    wire.

(b) ``p = r(Phi)`` gives ``m = F R (e_phi(phi) - e_phi(Phi))``: the classical moment plus a
    constant moment ``-F R e_phi(Phi)`` because the line of action of the force is offset by
    ``R`` from the axis. With ``u = Phi - phi``: ``|m|^2 = 2 F^2 R^2 (1 - cos u)``,
    ``T . m = F R cos(alpha) (1 - cos u)``, ``ds = R dphi / cos(alpha)``, and::

        delta_end = F R^3 / cos(alpha) [ 2 (Phi - sin Phi) / EI
                    + (1/GJ - 1/EI) cos^2(alpha) (3 Phi / 2 - 2 sin Phi + sin(2 Phi) / 4) ]
                    + F l [sin^2(alpha)/EA + cos^2(alpha)/GA].

    For an integer number of turns (``sin Phi = sin 2 Phi = 0``)::

        delta_end - delta_axis = F R^2 l [(1 + sin^2(alpha)) / (2 EI) + cos^2(alpha) / (2 GJ)]

    which grows like ``l``, exactly as ``delta_axis`` does: the difference does **not**
    vanish relative to ``delta_axis`` for many turns. It is the bending of the coil as a
    whole by the eccentric load (constant moment ``F R``; the end section rotates and the
    end point, at radius ``R``, moves axially with it); for ``alpha -> 0`` and without the
    extension and shear terms the ratio is ``delta_end / delta_axis = 3/2 + GJ / (2 EI)``
    (1.885 for a round wire with ``nu = 0.3``; 1.880 in stiffness for the example
    ``R = 1 cm``, ``P = 5 mm``, 5 turns, ``d = 2 mm``, ``E = 1 GPa``). Only the part
    oscillating with the fractional turn is bounded and vanishes relatively as ``n`` grows.
    (A load on the end point with the end *guided*, i.e. kept from rotating, is a third
    case, not treated here.)

The shooting check (:func:`spring_stiffness_shooting`) solves the full nonlinear
Simo-Reissner problem with :func:`references.cosserat_bvp.solve_rod` at loads ``+-F`` with
``F`` small and takes the central difference ``2 F / (delta(F) - delta(-F))`` (the even,
quadratic part cancels). Case (a) applies the dead force ``F e3`` at the end point plus the
dead end moment ``(c - r(L)) x F e3`` (the force transported from the axis point ``c``
to the end), and measures the axial displacement of the arm's end
``r(L) + R(L) R_ref(L)^T (c - r_ref(L))``; the arm rotates with the end section, but the
dead moment differs from the rotating one only at second order.
SI units throughout.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .cosserat_bvp import RodStiffness, solve_rod

__all__ = [
    "HelixRod",
    "helix_angle",
    "helix_rod",
    "spring_compliance_axis",
    "spring_compliance_classical",
    "spring_compliance_end",
    "spring_stiffness_shooting",
    "wire_length",
]


def _geometry(R: float, pitch: float, n_turns: float) -> tuple[float, float, float]:
    if not (R > 0 and math.isfinite(R)):
        raise ValueError(f"coil radius must be positive, got {R!r}")
    if not (pitch >= 0 and math.isfinite(pitch)):
        raise ValueError(f"pitch must be >= 0, got {pitch!r}")
    if not n_turns > 0:
        raise ValueError(f"number of turns must be positive, got {n_turns!r}")
    a = math.atan2(pitch, 2.0 * math.pi * R)
    return a, 2.0 * math.pi * R * n_turns / math.cos(a), 2.0 * math.pi * n_turns


def helix_angle(R: float, pitch: float) -> float:
    """Helix angle ``alpha = atan(P / (2 pi R))`` in rad."""
    return _geometry(R, pitch, 1.0)[0]


def wire_length(R: float, pitch: float, n_turns: float) -> float:
    """Wire length ``l = 2 pi R n / cos(alpha)`` (m)."""
    return _geometry(R, pitch, n_turns)[1]


def spring_compliance_classical(
    R: float, pitch: float, n_turns: float, *, EI: float, GJ: float
) -> float:
    """Classical open-coiled spring, load on the axis: ``R^2 l (cos^2/GJ + sin^2/EI)`` (m/N)."""
    a, l, _ = _geometry(R, pitch, n_turns)
    c2, s2 = math.cos(a) ** 2, math.sin(a) ** 2
    return R * R * l * (c2 / GJ + s2 / EI)


def _force_part(a: float, l: float, EA: float, GA: float) -> float:
    return l * (math.sin(a) ** 2 / EA + math.cos(a) ** 2 / GA)


def spring_compliance_axis(
    R: float, pitch: float, n_turns: float, *, EI: float, GJ: float, EA: float, GA: float
) -> float:
    """Load on the axis (rigid arm), with extension and shear (m/N)::

    R^2 l (cos^2/GJ + sin^2/EI) + l (sin^2/EA + cos^2/GA)

    ``EA``, ``GA`` may be ``math.inf`` (the classical formula)."""
    a, l, _ = _geometry(R, pitch, n_turns)
    return spring_compliance_classical(R, pitch, n_turns, EI=EI, GJ=GJ) + _force_part(a, l, EA, GA)


def spring_compliance_end(
    R: float, pitch: float, n_turns: float, *, EI: float, GJ: float, EA: float, GA: float
) -> float:
    """Load at the wire's end point, end free to rotate (m/N); see the module docstring."""
    a, l, Phi = _geometry(R, pitch, n_turns)
    c = math.cos(a)
    bend = 2.0 * (Phi - math.sin(Phi)) / EI + (1.0 / GJ - 1.0 / EI) * c * c * (
        1.5 * Phi - 2.0 * math.sin(Phi) + 0.25 * math.sin(2.0 * Phi)
    )
    return R**3 / c * bend + _force_part(a, l, EA, GA)


@dataclass(frozen=True)
class HelixRod:
    """Arguments of :func:`references.cosserat_bvp.solve_rod` for the helix (SI)."""

    L: float
    r0: np.ndarray
    R0: np.ndarray
    K0: tuple[float, float, float]
    alpha: float


def helix_rod(R: float, pitch: float, n_turns: float, frame: str = "binormal") -> HelixRod:
    """Reference helix starting at ``(R, 0, 0)``: length, clamp frame and ``K0``.

    frame: ``"binormal"`` (``d1 = B``, ``d2 = -N``, ``K0 = (kappa, 0, tau)``) or
    ``"frenet"`` (``d1 = N``, ``d2 = B``, ``K0 = (0, kappa, tau)``).
    """
    a, l, _ = _geometry(R, pitch, n_turns)
    c, s = math.cos(a), math.sin(a)
    T = np.array([0.0, c, s])
    N = np.array([-1.0, 0.0, 0.0])
    B = np.cross(T, N)
    kappa, tau = c * c / R, s * c / R
    if frame == "binormal":
        return HelixRod(l, np.array([R, 0.0, 0.0]), np.column_stack([B, -N, T]),
                        (kappa, 0.0, tau), a)
    if frame == "frenet":
        return HelixRod(l, np.array([R, 0.0, 0.0]), np.column_stack([N, B, T]),
                        (0.0, kappa, tau), a)
    raise ValueError(f"frame must be 'binormal' or 'frenet', got {frame!r}")


def spring_stiffness_shooting(
    R: float,
    pitch: float,
    n_turns: float,
    stiffness: RodStiffness,
    *,
    load: str = "end",
    rel_load: float = 1e-6,
    frame: str = "binormal",
    rtol: float = 1e-12,
) -> float:
    """Exact linear axial stiffness (N/m) from the nonlinear rod at small load.

    load: ``"end"`` (force at the wire's end point, end free) or ``"axis"`` (force at the
    axis point via a rigid arm). rel_load: the load is ``rel_load`` times the force that
    stretches the spring by its wire length according to the axis formula (so the
    deflection is about ``rel_load * l``). Central difference of the responses to ``+-F``.
    """
    if load not in ("end", "axis"):
        raise ValueError(f"load must be 'end' or 'axis', got {load!r}")
    h = helix_rod(R, pitch, n_turns, frame)
    comp = spring_compliance_axis(R, pitch, n_turns, EI=stiffness.EI1, GJ=stiffness.GJ,
                                  EA=stiffness.EA, GA=stiffness.GA1)
    F = rel_load * h.L / comp

    def deflection(Fz: float) -> float:
        kw = {}
        if load == "axis":
            zL = h.r0[2] + h.L * math.sin(h.alpha)
            rL = np.array([R * math.cos(2 * math.pi * n_turns),
                           R * math.sin(2 * math.pi * n_turns), zL])
            c = np.array([0.0, 0.0, zL])
            kw["tip_moment"] = np.cross(c - rL, [0.0, 0.0, Fz])
        sol = solve_rod(h.L, stiffness, r0=h.r0, R0=h.R0, K0=h.K0, tip_force=(0.0, 0.0, Fz),
                        load_steps=1, rtol=rtol, n_points=3, **kw)
        if load == "end":
            return float(sol.tip_displacement[2])
        arm = c - sol.r_ref[-1]
        c_def = sol.r[-1] + sol.R[-1] @ sol.R_ref[-1].T @ arm
        return float(c_def[2] - c[2])

    return 2.0 * F / (deflection(F) - deflection(-F))


if __name__ == "__main__":  # pragma: no cover - report helper
    from .sections import circle

    E, nu, R, pitch, n = 1.0e9, 0.3, 0.01, 0.005, 5
    G = E / (2 * (1 + nu))
    sec = circle(0.001, nu)
    GA, _, EA, EI, _, GJ = sec.stiffnesses(E, G)
    kw = {"EI": EI, "GJ": GJ, "EA": EA, "GA": GA}
    st = RodStiffness.from_section(sec, E, G)
    print(f"alpha = {helix_angle(R, pitch):.9f} rad, l = {wire_length(R, pitch, n):.9f} m")
    rows = [
        ("classical (axis, no EA/GA)", spring_compliance_classical(R, pitch, n, EI=EI, GJ=GJ)),
        ("axis load, with EA and GA", spring_compliance_axis(R, pitch, n, **kw)),
        ("end-point load (formula)", spring_compliance_end(R, pitch, n, **kw)),
    ]
    for name, c in rows:
        print(f"{name:27s} k = {1 / c:.9f} N/m")
    for load in ("axis", "end"):
        k = spring_stiffness_shooting(R, pitch, n, st, load=load, rel_load=1e-7)
        print(f"{'shooting, load = ' + load:27s} k = {k:.9f} N/m")
