"""Independent references for rod assemblies (NumPy/SciPy only, no kvrod code).

SI units; angular frequencies in rad/s. Linear (small-amplitude, small-deflection) theory
throughout. Each function states its formula, its derivation and its source; the
derivations that are not textbook results are checked in
``tests/references/test_assemblies_refs.py`` against separately written numerical models
(finite elements, boundary-value solvers, time integration).

- :func:`tip_mass_cantilever_frequencies`, :func:`tip_mass_timoshenko_frequencies`: a
  cantilever carrying a tip body of mass ``M`` and rotary inertia ``J``;
- :func:`l_frame_compliance`, :func:`l_frame_tip`: two members welded at a rigid right
  corner, clamped at one end, loaded at the free tip (unit-load method with bending,
  shear, extension and torsion);
- :func:`propped_cantilever`, :func:`propped_cantilever_deflection`,
  :func:`two_span_beam`: statically indeterminate beams under a uniform load, with the
  exact Timoshenko shear correction;
- :func:`double_pendulum_matrices`, :func:`double_pendulum_frequencies`: two rigid bars
  hinged in a chain, small oscillations under gravity;
- :func:`ring_inplane_frequencies`, :func:`ring_out_of_plane_frequencies`,
  :func:`ring_cosserat_frequencies`: free vibration of a closed circular ring
  (inextensional classical formulas, and the linear Cosserat ring with extension, shear
  and rotary inertia by Fourier modes).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.linalg import expm
from scipy.optimize import brentq

__all__ = [
    "double_pendulum_frequencies",
    "double_pendulum_matrices",
    "l_frame_compliance",
    "l_frame_tip",
    "propped_cantilever",
    "propped_cantilever_deflection",
    "ring_cosserat_frequencies",
    "ring_inplane_frequencies",
    "ring_out_of_plane_frequencies",
    "tip_mass_cantilever_frequencies",
    "tip_mass_frequency_function",
    "tip_mass_timoshenko_frequencies",
    "two_span_beam",
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


def _scan_roots(f, grid: np.ndarray, n: int, what: str) -> np.ndarray:
    """The first ``n`` sign changes of ``f`` on ``grid``, refined by Brent's method; ``f``
    takes an array (the whole grid at once) and returns an array."""
    vals = np.asarray(f(grid), dtype=float)

    def f1(x: float) -> float:
        return float(np.asarray(f(np.array([x])))[0])

    roots: list[float] = []
    for i in range(len(grid) - 1):
        if vals[i] == 0.0:
            roots.append(float(grid[i]))
        elif vals[i] * vals[i + 1] < 0:
            roots.append(brentq(f1, grid[i], grid[i + 1], xtol=1e-15 * grid[-1],
                                rtol=4 * np.finfo(float).eps, maxiter=200))
        if len(roots) == n:
            return np.array(roots)
    raise RuntimeError(f"{what}: found only {len(roots)} of {n} roots below {grid[-1]:g}")


# ------------------------------------------------------------------ cantilever + tip body
def tip_mass_frequency_function(b: float | np.ndarray, mass_ratio: float, inertia_ratio: float
                                ) -> float | np.ndarray:
    """Left side of the tip-body frequency equation divided by ``cosh b`` (no overflow)::

        1 + cos b cosh b + mu b (cos b sinh b - sin b cosh b)
          - j b^3 (cos b sinh b + sin b cosh b) + mu j b^4 (1 - cos b cosh b) = 0

    with ``b = beta L``, ``mu = M / (m L)`` (``mass_ratio``), ``j = J / (m L^3)``
    (``inertia_ratio``); see :func:`tip_mass_cantilever_frequencies`.
    """
    b = np.asarray(b, dtype=float)
    c, s, th, sech = np.cos(b), np.sin(b), np.tanh(b), 1.0 / np.cosh(b)
    mu, j = mass_ratio, inertia_ratio
    return (sech + c + mu * b * (c * th - s) - j * b**3 * (c * th + s)
            + mu * j * b**4 * (sech - c))


def tip_mass_cantilever_frequencies(
    n: int, *, L: float, EI: float, m: float, M: float = 0.0, J: float = 0.0
) -> np.ndarray:
    """First ``n`` bending frequencies (rad/s) of an Euler-Bernoulli cantilever with a tip
    body.

    Beam: length ``L`` (m), bending stiffness ``EI`` (N m^2), mass per length ``m`` (kg/m),
    clamped at ``x = 0``. At ``x = L`` a rigid body of mass ``M`` (kg) whose centre of
    mass is at the beam tip and whose moment of inertia about the tip, for the axis normal
    to the plane of bending, is ``J`` (kg m^2). ``EI w'''' + m w_tt = 0`` with
    ``W = W'= 0`` at the clamp and, from the boundary terms of Hamilton's principle, at the
    tip::

        EI W''(L)  =  omega^2 J W'(L)       (moment = rotary inertia of the body)
        EI W'''(L) = -omega^2 M W(L)        (shear force = inertia of the body)

    ``W = c1 cos bx + c2 sin bx + c3 cosh bx + c4 sinh bx`` (``L = 1``); the 4x4
    determinant of these conditions is ``2 b^6`` times the frequency equation of
    :func:`tip_mass_frequency_function`, ``omega_k = b_k^2 sqrt(EI / (m L^4))``.

    The mass terms are the classical equation of Laura, Pombo and Susemihl (J. Sound Vib.
    37, 1974, 161-168); the rotary-inertia terms are derived here from the determinant (the
    last term has a plus sign: the product ``mu j`` term carries ``+(1 - cos b cosh b)``),
    and the whole equation is checked in the tests against a finite-element model.
    Limits: ``M = J = 0``: ``1 + cos b cosh b = 0`` (1.8751041, 4.6940911, ...);
    ``M -> inf``: the first root tends to 0 with ``omega_1^2 -> 3 EI / (L^3 (M + 33/140
    m L))`` (Rayleigh's quotient with the static shape; the effective mass fraction is
    33/140 = 0.2357 for large ``M`` and 3/1.8751^4 = 0.2427 at ``M = 0``), the higher
    roots tend to the clamped-pinned ones (``tan b = tanh b``: 3.9266, ...); ``J -> inf``
    (``M = 0``): clamped-sliding, ``tan b + tanh b = 0`` (2.3650, ...); both infinite:
    clamped-clamped, ``cos b cosh b = 1`` (4.7300, ...).
    """
    if n < 1:
        raise ValueError(f"n must be >= 1, got {n!r}")
    L, EI, m = _positive("L", L), _positive("EI", EI), _positive("m", m)
    mu, j = _nonnegative("M", M) / (m * L), _nonnegative("J", J) / (m * L**3)
    # roots are about pi apart (interlaced with those of the limiting cases); the first
    # one tends to 0 like (3 / mu)^(1/4) for a heavy tip mass: a geometric start
    grid = np.concatenate([np.geomspace(1e-6, 1.0, 400, endpoint=False),
                           np.arange(1.0, (n + 1.5) * math.pi, 2e-3)])
    roots = _scan_roots(lambda b: tip_mass_frequency_function(b, mu, j), grid, n,
                        "tip_mass_cantilever_frequencies")
    return roots**2 * math.sqrt(EI / (m * L**4))


def _timoshenko_tip_determinant(omega: np.ndarray, L: float, EI: float, kGA: float,
                                m: float, rhoI: float, mu: float, j: float) -> np.ndarray:
    """Clamped / tip-body frequency function at the frequencies ``omega`` (array), in the
    dimensionless state ``(w/L, psi, M L/EI, Q L^2/EI)`` over ``x/L`` in [0, 1]."""
    b2 = m * np.asarray(omega, dtype=float) ** 2 * L**4 / EI
    r2 = rhoI / (m * L * L)
    s2 = EI / (kGA * L * L)
    A = np.zeros((b2.size, 4, 4))
    A[:, 0, 1], A[:, 0, 3], A[:, 1, 2], A[:, 2, 3] = 1.0, s2, 1.0, -1.0
    A[:, 2, 1], A[:, 3, 0] = -b2 * r2, -b2
    P = expm(A)[:, :, 2:]               # the clamp leaves (0, 0, M0, Q0)
    row_m = P[:, 2] - (b2 * j)[:, None] * P[:, 1]     # M(L) = omega^2 J psi(L)
    row_q = P[:, 3] - (b2 * mu)[:, None] * P[:, 0]    # Q(L) = omega^2 M w(L)
    return row_m[:, 0] * row_q[:, 1] - row_m[:, 1] * row_q[:, 0]


def tip_mass_timoshenko_frequencies(
    n: int, *, L: float, EI: float, kGA: float, m: float, rhoI: float,
    M: float = 0.0, J: float = 0.0, points_per_mode: int = 200,
) -> np.ndarray:
    """First ``n`` bending frequencies (rad/s) of a Timoshenko cantilever with a tip body.

    As :func:`tip_mass_cantilever_frequencies` with shear stiffness ``kGA`` (N; ``inf``
    for none) and rotary inertia per length ``rhoI`` (kg m; 0 for none). Timoshenko
    theory in the harmonic state ``(w, psi, M, Q)``::

        w' = psi + Q/kGA,  psi' = M/EI,  M' = -Q - rhoI omega^2 psi,  Q' = -m omega^2 w

    (``M = EI psi'``, ``Q = kGA (w' - psi)``); ``w = psi = 0`` at the clamp, and at the
    tip the body's inertia: ``Q(L) = omega^2 M w(L)``, ``M(L) = omega^2 J psi(L)``
    (boundary terms of Hamilton's principle; ``J`` acts on the section rotation ``psi``).
    The frequency function is the 2x2 determinant of the tip conditions applied to the
    transfer matrix ``expm`` of the first-order system; roots are bracketed on a grid up
    to the Euler-Bernoulli ``(n + 1/2)``-th frequency (shear and rotary inertia only lower
    the frequencies) and refined by Brent's method. With ``kGA = inf``, ``rhoI = 0`` it
    reduces to :func:`tip_mass_cantilever_frequencies`.
    """
    if n < 1:
        raise ValueError(f"n must be >= 1, got {n!r}")
    L, EI, m = _positive("L", L), _positive("EI", EI), _positive("m", m)
    kGA = _positive("kGA", kGA, allow_inf=True)
    rhoI = _nonnegative("rhoI", rhoI)
    mu, j = _nonnegative("M", M) / (m * L), _nonnegative("J", J) / (m * L**3)
    w_eb = tip_mass_cantilever_frequencies(n + 1, L=L, EI=EI, m=m, M=M, J=J)
    w_max = 0.5 * (w_eb[n - 1] + w_eb[n])
    grid = np.concatenate([np.geomspace(1e-4 * w_eb[0], w_eb[0] / 2, 50, endpoint=False),
                           np.linspace(w_eb[0] / 2, w_max, points_per_mode * n + 1)])
    return _scan_roots(lambda w: _timoshenko_tip_determinant(w, L, EI, kGA, m, rhoI, mu, j),
                       grid, n, "tip_mass_timoshenko_frequencies")


# ---------------------------------------------------------------------------- L-frame
def l_frame_compliance(
    *, L1: float, L2: float, EI: float, GJ: float = math.inf, EA: float = math.inf,
    GA: float = math.inf, EI_out: float | None = None, GA_out: float | None = None,
) -> np.ndarray:
    """Tip compliance (6x6, SI) of an L-frame with a rigid right-angled corner.

    Geometry (frame coordinates): member 1 from the clamp at the origin along ``+z`` to
    the corner at ``(0, 0, L1)``; member 2 from the corner along ``+x`` to the free tip at
    ``(L2, 0, L1)``. The frame lies in the ``x-z`` plane; ``y`` is out of plane. The
    returned ``C`` maps the tip load ``(Fx, Fy, Fz, Mx, My, Mz)`` (N, N m) to the tip
    displacement and small rotation ``(ux, uy, uz, thx, thy, thz)`` (m, rad).

    Both members have the same straight uniform section: extension ``EA``, torsion
    ``GJ``, in-plane bending ``EI`` (about ``y``) and shear ``GA`` (shear-corrected,
    ``kappa G A``) in the plane, out-of-plane bending ``EI_out`` and shear ``GA_out``
    (default: the in-plane values). ``inf`` makes a mode rigid.

    Unit-load (Castigliano) method: the tip load gives, at a section of member 2 at
    distance ``s`` from the tip, the force ``F`` and the moment ``Mt + (s, 0, 0) x F``
    (axial ``Fx``; shear ``Fz`` in plane, ``Fy`` out of plane; torsion ``Mx``; bending
    ``My - s Fz`` and ``Mz + s Fy``); in member 1 at height ``z = L1 - h`` the force
    ``F`` and the moment ``Mt + (L2, 0, h) x F`` (axial ``Fz``; shear ``Fx`` in plane,
    ``Fy`` out of plane; torsion ``Mz + L2 Fy``; bending ``My + h Fx - L2 Fz`` in plane
    and ``Mx - h Fy`` out of plane). The complementary energy
    ``U = sum int (N^2/EA + V^2/GA + T^2/GJ + M^2/EI) / 2`` is quadratic in the load, and
    ``C`` is its Hessian. In-plane entries::

        C[ux, ux] = L2/EA + L1/GA + L1^3/(3 EI)
        C[uz, uz] = L1/EA + L2/GA + L2^3/(3 EI) + L2^2 L1/EI
        C[ux, uz] = -L2 L1^2/(2 EI)
        C[thy, thy] = (L1 + L2)/EI,  C[thy, ux] = L1^2/(2 EI),
        C[thy, uz] = -(L2^2/2 + L1 L2)/EI

    out of plane (a force ``Fy`` twists member 1 by ``L2 Fy``)::

        C[uy, uy] = (L1 + L2)/GA_out + (L1^3 + L2^3)/(3 EI_out) + L2^2 L1/GJ
        C[thx, thx] = L2/GJ + L1/EI_out,  C[thz, thz] = L2/EI_out + L1/GJ
        C[uy, thx] = -L1^2/(2 EI_out),  C[uy, thz] = L2^2/(2 EI_out) + L1 L2/GJ

    and zero between the two groups (and ``C[thx, thz] = 0``). Linear theory: small
    displacements, a rigid corner joint (no joint flexibility), no interaction of the
    axial force with bending. (The member formulas are those of any structural-mechanics
    text, e.g. Timoshenko and Young, Theory of Structures; the assembly is derived here
    and checked against a stiffness-method finite-element model in the tests.)
    """
    L1, L2, EI = _positive("L1", L1), _positive("L2", L2), _positive("EI", EI)
    GJ = _positive("GJ", GJ, allow_inf=True)
    EA = _positive("EA", EA, allow_inf=True)
    GA = _positive("GA", GA, allow_inf=True)
    EIo = EI if EI_out is None else _positive("EI_out", EI_out)
    GAo = GA if GA_out is None else _positive("GA_out", GA_out, allow_inf=True)
    C = np.zeros((6, 6))
    ux, uy, uz, tx, ty, tz = range(6)
    C[ux, ux] = L2 / EA + L1 / GA + L1**3 / (3 * EI)
    C[uz, uz] = L1 / EA + L2 / GA + L2**3 / (3 * EI) + L2**2 * L1 / EI
    C[ux, uz] = C[uz, ux] = -L2 * L1**2 / (2 * EI)
    C[ty, ty] = (L1 + L2) / EI
    C[ty, ux] = C[ux, ty] = L1**2 / (2 * EI)
    C[ty, uz] = C[uz, ty] = -(L2**2 / 2 + L1 * L2) / EI
    C[uy, uy] = (L1 + L2) / GAo + (L1**3 + L2**3) / (3 * EIo) + L2**2 * L1 / GJ
    C[tx, tx] = L2 / GJ + L1 / EIo
    C[tz, tz] = L2 / EIo + L1 / GJ
    C[uy, tx] = C[tx, uy] = -L1**2 / (2 * EIo)
    C[uy, tz] = C[tz, uy] = L2**2 / (2 * EIo) + L1 * L2 / GJ
    return C


def l_frame_tip(
    force: np.ndarray | tuple[float, float, float],
    moment: np.ndarray | tuple[float, float, float] = (0.0, 0.0, 0.0), **stiffness: float,
) -> dict[str, np.ndarray]:
    """Tip ``displacement`` (m) and small ``rotation`` (rad) of the L-frame under a tip
    force ``(Fx, Fy, Fz)`` (N) and moment (N m), both in frame coordinates; keyword
    arguments as :func:`l_frame_compliance` (``L1``, ``L2``, ``EI``, ``GJ``, ``EA``,
    ``GA``, ``EI_out``, ``GA_out``)."""
    load = np.concatenate([np.asarray(force, dtype=float).reshape(3),
                           np.asarray(moment, dtype=float).reshape(3)])
    u = l_frame_compliance(**stiffness) @ load
    return {"displacement": u[:3], "rotation": u[3:]}


# ---------------------------------------------------- statically indeterminate beams
def propped_cantilever(q: float, *, L: float, EI: float, kGA: float = math.inf
                       ) -> dict[str, float]:
    """Reactions of a propped cantilever under a uniform load, Timoshenko-exact.

    Clamped at ``x = 0`` (``w = psi = 0``), pinned at ``x = L`` (``w = 0``, ``M = 0``),
    uniform load ``q`` (N/m, positive downward), bending stiffness ``EI`` (N m^2), shear
    stiffness ``kGA`` (N; ``inf``: Euler-Bernoulli). Flexibility method: remove the prop;
    the cantilever's tip deflection under ``q`` is ``q L^4/(8 EI) + q L^2/(2 kGA)``
    (bending plus ``int_0^L Q/kGA`` with ``Q = q (L - x)``), under the prop force ``R``
    ``R (L^3/(3 EI) + L/kGA)``; compatibility gives, with ``e = EI / (kGA L^2)``::

        R_prop  = 3 q L / 8 * (1 + 4 e) / (1 + 3 e)
        R_clamp = q L - R_prop
        M_clamp = q L^2 / 2 - R_prop L = q L^2 / (8 (1 + 3 e))     (hogging)

    Euler-Bernoulli (``e = 0``): ``3qL/8``, ``5qL/8``, ``qL^2/8`` (any beam table, e.g.
    Roark's Formulas for Stress and Strain). The shear correction is exact in linear
    Timoshenko theory (superposition of two statically determinate cantilevers). Returns
    ``R_prop``, ``R_clamp`` (N, upward), ``M_clamp`` (N m, hogging: tension on top),
    ``e``.
    """
    L, EI = _positive("L", L), _positive("EI", EI)
    kGA = _positive("kGA", kGA, allow_inf=True)
    e = EI / (kGA * L * L)
    R_prop = 3.0 * q * L / 8.0 * (1.0 + 4.0 * e) / (1.0 + 3.0 * e)
    return {"R_prop": R_prop, "R_clamp": q * L - R_prop,
            "M_clamp": q * L * L / (8.0 * (1.0 + 3.0 * e)), "e": e}


def propped_cantilever_deflection(x: np.ndarray | float, q: float, *, L: float, EI: float,
                                  kGA: float = math.inf) -> np.ndarray:
    """Deflection ``w(x)`` (m, positive downward) of :func:`propped_cantilever`: the
    cantilever under ``q`` minus the cantilever under the prop force ``R``::

        w = q x^2 (6 L^2 - 4 L x + x^2)/(24 EI) + q (L x - x^2/2)/kGA
            - R (x^2 (3 L - x)/(6 EI) + x/kGA)
    """
    R = propped_cantilever(q, L=L, EI=EI, kGA=kGA)["R_prop"]
    x = np.asarray(x, dtype=float)
    return (q * x**2 * (6 * L * L - 4 * L * x + x * x) / (24 * EI)
            + q * (L * x - x * x / 2) / kGA - R * (x * x * (3 * L - x) / (6 * EI) + x / kGA))


def two_span_beam(q: float, *, L1: float, L2: float | None = None, EI: float,
                  kGA: float = math.inf) -> dict[str, float]:
    """Reactions of a continuous beam over two spans under a uniform load, Timoshenko-exact.

    Pinned supports A at ``x = 0``, B at ``x = L1`` and C at ``x = L1 + L2`` (default
    ``L2 = L1``); uniform load ``q`` (N/m, downward) on both spans; ``EI``, ``kGA`` as in
    :func:`propped_cantilever`. Flexibility method: remove B, leaving a simply supported
    span ``S = L1 + L2``; at ``x = a = L1`` (``b = L2``) the deflection under ``q`` is
    ``q a (S^3 - 2 S a^2 + a^3)/(24 EI) + q a b/(2 kGA)`` and under a point force ``R`` at
    ``a`` it is ``R (a^2 b^2/(3 EI S) + a b/(S kGA))``; compatibility gives::

        R_B = q [a (S^3 - 2 S a^2 + a^3)/(24 EI) + a b/(2 kGA)]
                / [a^2 b^2/(3 EI S) + a b/(S kGA)]
        R_A = q S/2 - R_B b/S,   R_C = q S/2 - R_B a/S,   M_B = R_A a - q a^2/2

    Equal spans ``L`` with ``e = EI/(kGA L^2)``: ``R_B = q L (5 + 12 e)/(4 + 12 e)``
    (Euler-Bernoulli ``5qL/4 = 10qL/8``), ``R_A = R_C = qL - R_B/2`` (``3qL/8``),
    ``M_B = -qL^2/8`` for Euler-Bernoulli (hogging over B). Returns ``R_A``, ``R_B``,
    ``R_C`` (N, upward) and ``M_B`` (N m, sagging positive).
    """
    a = _positive("L1", L1)
    b = a if L2 is None else _positive("L2", L2)
    EI = _positive("EI", EI)
    kGA = _positive("kGA", kGA, allow_inf=True)
    S = a + b
    num = a * (S**3 - 2 * S * a * a + a**3) / (24 * EI) + a * b / (2 * kGA)
    den = a * a * b * b / (3 * EI * S) + a * b / (S * kGA)
    R_B = q * num / den
    R_A = q * S / 2 - R_B * b / S
    R_C = q * S / 2 - R_B * a / S
    return {"R_A": R_A, "R_B": R_B, "R_C": R_C, "M_B": R_A * a - q * a * a / 2}


# ---------------------------------------------------------------------- double pendulum
def double_pendulum_matrices(
    *, m1: float, l1: float, m2: float, l2: float, g: float = 9.81,
    J1: float | None = None, J2: float | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Linearized mass and stiffness matrices ``(M, K)`` of two rigid bars hinged in a chain.

    Bar 1 (mass ``m1`` kg, length ``l1`` m) hangs from a fixed hinge; bar 2 (``m2``,
    ``l2``) hangs from a hinge at the lower end of bar 1; both hinge axes normal to the
    plane of motion; each bar's centre of mass at its mid-length, centroidal moment of
    inertia ``J_i`` (kg m^2) about the hinge-parallel axis (default ``m_i l_i^2 / 12``, a
    thin uniform bar; a rod of section radius of gyration ``r`` has ``m (l^2/12 + r^2)``).
    Generalized coordinates: the angles ``theta1``, ``theta2`` of the bars from the
    downward vertical. Lagrange's equations about ``theta = 0``::

        M = [[J1 + m1 l1^2/4 + m2 l1^2,  m2 l1 l2/2],
             [m2 l1 l2/2,                J2 + m2 l2^2/4]]
        K = g diag(m1 l1/2 + m2 l1,  m2 l2/2)

    (kinetic energy of bar 2: ``m2 |l1 th1' + l2 th2'/2|^2/2 + J2 th2'^2/2``; potential
    energy ``g (m1 l1/2 + m2 l1)(1 - cos th1) + g m2 l2/2 (1 - cos th2)``.)
    """
    m1, l1 = _positive("m1", m1), _positive("l1", l1)
    m2, l2 = _positive("m2", m2), _positive("l2", l2)
    g = _positive("g", g)
    J1 = m1 * l1 * l1 / 12 if J1 is None else _nonnegative("J1", J1)
    J2 = m2 * l2 * l2 / 12 if J2 is None else _nonnegative("J2", J2)
    M = np.array([[J1 + m1 * l1 * l1 / 4 + m2 * l1 * l1, m2 * l1 * l2 / 2],
                  [m2 * l1 * l2 / 2, J2 + m2 * l2 * l2 / 4]])
    K = g * np.diag([m1 * l1 / 2 + m2 * l1, m2 * l2 / 2])
    return M, K


def double_pendulum_frequencies(**params: float) -> np.ndarray:
    """The two small-oscillation frequencies (rad/s, ascending) of the hinged double
    pendulum of :func:`double_pendulum_matrices` (same keyword arguments).

    ``det(K - omega^2 M) = 0`` is ``a w^2 - b w + c = 0`` in ``w = omega^2`` with
    ``a = det M``, ``b = K11 M22 + K22 M11``, ``c = K11 K22``::

        omega_1^2 = 2 c / (b + sqrt(b^2 - 4 a c)),   omega_2^2 = (b + sqrt(b^2 - 4 a c))/(2 a)

    (the discriminant is ``(K11 M22 - K22 M11)^2 + 4 K11 K22 M12^2 >= 0``). Two equal thin
    bars (``m``, ``l``): ``omega^2 = (3 -+ 6/sqrt 7) g/l``, i.e. 0.8557 and 2.2952 times
    ``sqrt(g/l)``; ``m2 -> 0``: ``3g/(2 l1)`` and ``3g/(2 l2)`` (each bar on a fixed hinge).
    """
    M, K = double_pendulum_matrices(**params)
    a = M[0, 0] * M[1, 1] - M[0, 1] ** 2
    b = K[0, 0] * M[1, 1] + K[1, 1] * M[0, 0]
    c = K[0, 0] * K[1, 1]
    disc = math.sqrt((K[0, 0] * M[1, 1] - K[1, 1] * M[0, 0]) ** 2
                     + 4 * K[0, 0] * K[1, 1] * M[0, 1] ** 2)
    return np.sqrt([2 * c / (b + disc), (b + disc) / (2 * a)])


# --------------------------------------------------------------------------- the ring
def ring_inplane_frequencies(n: int | np.ndarray, *, R: float, EI: float, m: float
                             ) -> np.ndarray:
    """In-plane flexural frequencies (rad/s) of a free circular ring, ``n = 2, 3, ...``::

        omega_n = n (n^2 - 1) / sqrt(n^2 + 1) * sqrt(EI / (m R^4))

    ``R``: radius of the centreline (m), ``EI``: bending stiffness in the plane of the
    ring (about the axis normal to it, N m^2), ``m``: mass per length (kg/m). Inextensible,
    unshearable (Euler-Bernoulli) ring without rotary inertia; ``n`` waves round the
    circumference, each frequency a degenerate pair (``cos n theta``, ``sin n theta``).
    Hoppe (J. reine angew. Math. 73, 1871); Love, A Treatise on the Mathematical Theory of
    Elasticity, 4th ed. (vibrations of a circular ring); Blevins, Formulas for Natural
    Frequency and Mode Shape (1979), ring tables. ``n = 1`` gives 0 (rigid translation).
    """
    R, EI, m = _positive("R", R), _positive("EI", EI), _positive("m", m)
    n = np.asarray(n, dtype=float)
    if np.any(n < 1) or np.any(n != np.round(n)):
        raise ValueError(f"n must be integers >= 1, got {n!r}")
    return n * (n * n - 1) / np.sqrt(n * n + 1) * math.sqrt(EI / (m * R**4))


def ring_out_of_plane_frequencies(n: int | np.ndarray, *, R: float, EI: float, GJ: float,
                                  m: float) -> np.ndarray:
    """Out-of-plane (flexural-torsional) frequencies (rad/s) of a free circular ring::

        omega_n^2 = EI n^2 (n^2 - 1)^2 / (m R^4 (n^2 + EI/GJ)),   n = 2, 3, ...

    ``EI``: bending stiffness out of the plane (about the radial axis, N m^2), ``GJ``:
    torsional stiffness (N m^2), ``R``, ``m`` as in :func:`ring_inplane_frequencies`.
    Derivation (Michell, Messenger of Math. 19, 1890; Love, Treatise, 4th ed.; Blevins):
    with the out-of-plane displacement ``w`` and the twist ``beta`` of the sections
    (``' = d/dtheta``) the curvature changes are ``(w''/R - beta)/R`` (bending) and
    ``(beta' + w'/R)/R`` (twist). Without rotary inertia ``beta`` follows statically:
    for ``w = W cos n theta``, ``beta = B cos n theta``, minimizing the strain energy over
    ``B`` leaves ``pi W^2 EI GJ n^2 (n^2 - 1)^2 / (2 R^3 (EI + GJ n^2))`` against the
    kinetic energy ``pi m omega^2 R W^2 / 2``, hence the formula. Circular section
    (``J = 2 I``, ``EI/GJ = 1 + nu``):
    ``omega_n = n (n^2 - 1)/sqrt(n^2 + 1 + nu) sqrt(EI/(m R^4))``.
    Inextensible, unshearable, no rotary inertia; ``n = 1`` gives 0 (rigid rotation
    about a diameter).
    """
    R, EI, m = _positive("R", R), _positive("EI", EI), _positive("m", m)
    GJ = _positive("GJ", GJ, allow_inf=True)
    n = np.asarray(n, dtype=float)
    if np.any(n < 1) or np.any(n != np.round(n)):
        raise ValueError(f"n must be integers >= 1, got {n!r}")
    return np.sqrt(EI * n * n * (n * n - 1) ** 2 / (m * R**4 * (n * n + EI / GJ)))


def ring_cosserat_frequencies(
    n: int, *, R: float, m: float, EA: float, GA_in: float, GA_out: float, EI_in: float,
    EI_out: float, GJ: float, rhoI_in: float, rhoI_out: float, rhoJ: float,
) -> dict[str, np.ndarray]:
    """All frequencies (rad/s) of harmonic ``n = 0, 1, 2, ...`` of a free circular ring in
    linear Cosserat (Simo-Reissner) rod theory: extension, shear and rotary inertia.

    Local frame at the angle ``theta``: radial ``e_r``, tangent ``e_theta``, normal
    ``e_z``. Stiffness: ``EA`` (N) extension, ``GA_in`` / ``GA_out`` (N, shear-corrected)
    shear along ``e_r`` / ``e_z``, ``EI_in`` (N m^2) bending in the plane (about ``e_z``),
    ``EI_out`` out of plane (about ``e_r``), ``GJ`` torsion; inertia: ``m`` (kg/m) and the
    rotary inertias per length ``rhoI_in`` (about ``e_z``), ``rhoI_out`` (about ``e_r``)
    and ``rhoJ`` (about ``e_theta``, polar), kg m. All must be finite and positive.

    Linearized about the circle, with the displacement ``u`` and the rotation vector
    ``phi``, the strains are ``eps = u_,s + e_theta x phi`` and ``kappa = phi_,s``
    (components in the local frame; ``s = R theta``; ``d(e_r)/dtheta = e_theta``,
    ``d(e_theta)/dtheta = -e_r``). For ``(u, phi) = (U, Phi) exp(i n theta)`` they split:

    - in plane, ``(u_r, u_theta, phi_z)``: ``eps_r = (i n u_r - u_theta)/R + phi_z``,
      ``eps_theta = (i n u_theta + u_r)/R``, ``kappa_z = i n phi_z/R``;
    - out of plane, ``(u_z, phi_r, phi_theta)``: ``eps_z = i n u_z/R - phi_r``,
      ``kappa_r = (i n phi_r - phi_theta)/R``, ``kappa_theta = (i n phi_theta + phi_r)/R``.

    With ``strains = B(n) (U, Phi)``, the eigenproblem ``B^H C B v = omega^2 diag(inertia)
    v`` (3x3 in each group) is solved as the singular values ``omega`` of
    ``C^(1/2) B diag(inertia)^(-1/2)``: the three frequencies of each group, returned
    ascending as ``in_plane`` and ``out_of_plane``. (Singular values instead of the
    eigenvalues of the product keep the flexural frequency accurate to ``eps`` times the
    ratio of the largest to the smallest frequency, not its square: a slender ring has
    shear frequencies ~1e3 to 1e4 times the flexural ones.) The lowest is the flexural
    mode for ``n >= 2``; in the limit ``EA, GA -> inf``, ``rhoI -> 0`` it tends to
    :func:`ring_inplane_frequencies` and :func:`ring_out_of_plane_frequencies` (checked in
    the tests, with a finite-element ring). ``n = 0``: the breathing mode ``omega^2 =
    EA/(m R^2)`` and rigid rotation about ``e_z`` (0) in plane, rigid translation along
    ``e_z`` (0) out of plane; ``n = 1``: rigid translations in plane and rigid rotations
    about diameters out of plane (0). Derived here (the linearized Simo-Reissner strains;
    cf. Simo and Vu-Quoc, Comput. Methods Appl. Mech. Eng. 58, 1986).
    """
    if int(n) != n or n < 0:
        raise ValueError(f"n must be an integer >= 0, got {n!r}")
    vals = {k: _positive(k, v) for k, v in dict(
        R=R, m=m, EA=EA, GA_in=GA_in, GA_out=GA_out, EI_in=EI_in, EI_out=EI_out, GJ=GJ,
        rhoI_in=rhoI_in, rhoI_out=rhoI_out, rhoJ=rhoJ).items()}
    r, ik = vals["R"], 1j * n
    B_in = np.array([[ik / r, -1.0 / r, 1.0],       # eps_r
                     [1.0 / r, ik / r, 0.0],        # eps_theta
                     [0.0, 0.0, ik / r]])           # kappa_z
    B_out = np.array([[ik / r, -1.0, 0.0],          # eps_z
                      [0.0, ik / r, -1.0 / r],      # kappa_r
                      [0.0, 1.0 / r, ik / r]])      # kappa_theta
    groups = {
        "in_plane": (B_in, [vals["GA_in"], vals["EA"], vals["EI_in"]],
                     [vals["m"], vals["m"], vals["rhoI_in"]]),
        "out_of_plane": (B_out, [vals["GA_out"], vals["EI_out"], vals["GJ"]],
                         [vals["m"], vals["rhoI_out"], vals["rhoJ"]]),
    }
    out = {}
    for key, (B, C, inertia) in groups.items():
        D = np.sqrt(C)[:, None] * B / np.sqrt(inertia)[None, :]
        out[key] = np.sort(np.linalg.svd(D, compute_uv=False))
    return out
