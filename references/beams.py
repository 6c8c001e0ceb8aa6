"""Linear cantilever references: frequencies, static tip, Kelvin-Voigt modal damping.

Independent of kvrod (NumPy/SciPy only). SI units; angular frequencies in rad/s.

- Euler-Bernoulli clamped-free bending: roots ``beta_k L`` of ``1 + cos(bL) cosh(bL) = 0``,
  ``omega_k = (beta_k L)^2 sqrt(EI / (rho A L^4))`` (Craig and Kurdila 2006, ch. 13.2).
- Timoshenko clamped-free bending (shear ``kappa G A``, rotary inertia ``rho I``)::

      rho A w_tt   = kappa G A (w'' - psi')
      rho I psi_tt = E I psi'' + kappa G A (w' - psi)

  with ``w = psi = 0`` at the clamp and shear force ``kappa G A (w' - psi) = 0`` and moment
  ``E I psi' = 0`` at the free end. The frequency equation is the 2x2 determinant of the
  free-end conditions applied to the transfer matrix of the first-order system in
  ``(w, psi, M, Q)``; its roots are bracketed on a grid and refined with Brent's method.
  (Cross-checked in the tests against Huang's 1961 closed-form frequency equation.)
- Axial clamped-free bar: ``omega_k = (2k-1) pi / (2L) sqrt(E / rho)``.
- Torsion clamped-free: ``omega_k = (2k-1) pi / (2L) sqrt(G J_T / (rho I_3))`` with the
  Saint-Venant torsion constant ``J_T`` (series for a rectangle) and the polar moment
  ``I_3 = I_1 + I_2`` (rotary inertia of the section about its normal, paper Sect. 2.2);
  ``rectangle_torsion_constant`` lives in :mod:`.sections` and is re-exported here.
- Small-deflection static tip under a tip force: ``F L^3 / (3 E I) + F L / (kappa G A)``.
- Linear Kelvin-Voigt damping ``V = tau C`` (paper Eq. (9) with ``tau_B = tau_S = tau_E``) is
  stiffness proportional, so each undamped mode ``omega_k`` gets the damping ratio
  ``zeta_k = omega_k tau / 2`` and the damped frequency ``omega_k sqrt(1 - zeta_k^2)``.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.linalg import expm
from scipy.optimize import brentq

from .sections import cowper_rectangle, rectangle_torsion_constant

__all__ = [
    "axial_frequencies",
    "damped_frequency",
    "euler_bernoulli_frequencies",
    "euler_bernoulli_roots",
    "kelvin_voigt_damping_ratio",
    "rectangle_torsion_constant",
    "static_tip_linear",
    "timoshenko_frequencies",
    "torsional_frequencies",
]


def euler_bernoulli_roots(n: int) -> np.ndarray:
    """First ``n`` roots ``beta_k L`` of ``1 + cos(x) cosh(x) = 0`` (dimensionless).

    Solved as ``cos(x) + 1/cosh(x) = 0`` (no overflow) by Brent's method in the bracket
    ``[(k - 1/2) pi, k pi]`` - the k-th root lies there since the sign of ``cos x`` changes
    at ``(k - 1/2) pi`` and ``1/cosh`` is small and positive.
    """
    if n < 1:
        raise ValueError(f"n must be >= 1, got {n!r}")

    def g(x: float) -> float:
        return math.cos(x) + 1.0 / math.cosh(x)

    roots = []
    for k in range(1, n + 1):
        a, b = (k - 1) * math.pi + 0.5 * math.pi, k * math.pi
        if g(a) * g(b) > 0:  # pragma: no cover - cannot happen for the intervals above
            a = (k - 1) * math.pi
        roots.append(brentq(g, a, b, xtol=1e-15, rtol=4 * np.finfo(float).eps, maxiter=200))
    return np.array(roots)


def euler_bernoulli_frequencies(
    n: int, *, L: float, rho: float, A: float, E: float, I: float
) -> np.ndarray:
    """Cantilever bending frequencies ``omega_k = (beta_k L)^2 sqrt(E I / (rho A L^4))``, rad/s."""
    return euler_bernoulli_roots(n) ** 2 * math.sqrt(E * I / (rho * A * L**4))


def _timoshenko_matrix(
    omega: float, rho: float, A: float, E: float, I: float, kGA: float, L: float
):
    """First-order system in the dimensionless state ``(w/L, psi, M L/EI, Q L^2/EI)``.

    ``Q = kGA (w' - psi)`` shear force, ``M = EI psi'`` bending moment; harmonic motion gives
    ``Q' = -rho A omega^2 w`` and ``M' = -Q - rho I omega^2 psi``. In these variables every
    entry is O(1) or O(b^2), so the transfer matrix is well conditioned also for very
    slender beams.
    """
    b2 = rho * A * omega**2 * L**4 / (E * I)
    r2 = I / (A * L * L)
    s2 = E * I / (kGA * L * L)
    return np.array(
        [
            [0.0, 1.0, 0.0, s2],
            [0.0, 0.0, 1.0, 0.0],
            [0.0, -b2 * r2, 0.0, -1.0],
            [-b2, 0.0, 0.0, 0.0],
        ]
    )


def timoshenko_determinant(
    omega: float, *, L: float, rho: float, A: float, E: float, I: float, kGA: float
) -> float:
    """Clamped-free Timoshenko frequency function (zero at the natural frequencies).

    Transfer matrix ``P = expm(A)`` over the dimensionless length 1; the clamp leaves
    ``(0, 0, M0, Q0)``, the free end needs ``M(L) = Q(L) = 0``: ``det P[2:, 2:] = 0``.
    """
    P = expm(_timoshenko_matrix(omega, rho, A, E, I, kGA, L))
    return float(P[2, 2] * P[3, 3] - P[2, 3] * P[3, 2])


def timoshenko_frequencies(
    n: int,
    *,
    L: float,
    rho: float,
    A: float,
    E: float,
    I: float,
    kGA: float,
    points_per_mode: int = 200,
) -> np.ndarray:
    """First ``n`` clamped-free Timoshenko bending frequencies (rad/s).

    kGA: shear stiffness ``kappa G A`` (N); rotary inertia ``rho I`` is included. The roots
    are bracketed on a grid up to 1.05 times the n-th Euler-Bernoulli frequency (Timoshenko
    frequencies lie below) and refined by Brent's method to full precision.
    """
    w_eb = euler_bernoulli_frequencies(n + 1, L=L, rho=rho, A=A, E=E, I=I)
    w_max = 0.5 * (w_eb[n - 1] + w_eb[n])
    grid = np.linspace(1e-3 * w_eb[0], w_max, points_per_mode * n + 1)

    def f(w: float) -> float:
        return timoshenko_determinant(w, L=L, rho=rho, A=A, E=E, I=I, kGA=kGA)

    vals = np.array([f(w) for w in grid])
    roots: list[float] = []
    for i in range(len(grid) - 1):
        if vals[i] == 0.0:
            roots.append(float(grid[i]))
        elif vals[i] * vals[i + 1] < 0:
            roots.append(brentq(f, grid[i], grid[i + 1], xtol=1e-14 * w_max, rtol=1e-15))
        if len(roots) == n:
            break
    if len(roots) < n:  # pragma: no cover
        raise RuntimeError(f"found only {len(roots)} Timoshenko roots below {w_max}")
    return np.array(roots)


def axial_frequencies(n: int, *, L: float, rho: float, E: float) -> np.ndarray:
    """Clamped-free bar: ``omega_k = (2k-1) pi / (2L) sqrt(E / rho)`` in rad/s."""
    k = np.arange(1, n + 1)
    return (2 * k - 1) * math.pi / (2 * L) * math.sqrt(E / rho)


def torsional_frequencies(
    n: int, *, L: float, rho: float, G: float, J_T: float, I3: float
) -> np.ndarray:
    """Clamped-free torsion: ``omega_k = (2k-1) pi/(2L) sqrt(G J_T / (rho I3))`` in rad/s."""
    k = np.arange(1, n + 1)
    return (2 * k - 1) * math.pi / (2 * L) * math.sqrt(G * J_T / (rho * I3))


def static_tip_linear(F: float, *, L: float, E: float, I: float, kGA: float = math.inf) -> float:
    """Small-deflection tip displacement (m): ``F L^3/(3 E I) + F L/(kappa G A)``."""
    return F * L**3 / (3.0 * E * I) + F * L / kGA


def kelvin_voigt_damping_ratio(omega: float | np.ndarray, tau: float) -> float | np.ndarray:
    """Modal damping ratio of stiffness-proportional Kelvin-Voigt damping: ``omega tau / 2``."""
    return 0.5 * np.asarray(omega) * tau


def damped_frequency(omega: float | np.ndarray, tau: float) -> float | np.ndarray:
    """Damped frequency ``omega sqrt(1 - zeta^2)`` with ``zeta = omega tau / 2`` (rad/s);
    NaN for overdamped modes (``zeta >= 1``)."""
    z = kelvin_voigt_damping_ratio(omega, tau)
    with np.errstate(invalid="ignore"):
        return np.asarray(omega) * np.sqrt(1.0 - np.asarray(z) ** 2)


def paper_frequencies(n: int = 3) -> dict[str, np.ndarray | float]:
    """The paper's Sect. 5 cantilever (L = 0.3 m, 1 cm square, rho = 1000 kg/m^3, E = 1 MPa,
    nu = 0.3): E-B and Timoshenko bending, axial and torsional frequencies (rad/s)."""
    L, a, rho, E, nu = 0.3, 0.01, 1000.0, 1.0e6, 0.3
    A, I = a * a, a**4 / 12
    G = E / (2 * (1 + nu))
    kappa = cowper_rectangle(nu)
    J_T = rectangle_torsion_constant(a, a)
    return {
        "euler_bernoulli": euler_bernoulli_frequencies(n, L=L, rho=rho, A=A, E=E, I=I),
        "timoshenko": timoshenko_frequencies(n, L=L, rho=rho, A=A, E=E, I=I, kGA=kappa * G * A),
        "axial": axial_frequencies(n, L=L, rho=rho, E=E),
        "torsional": torsional_frequencies(n, L=L, rho=rho, G=G, J_T=J_T, I3=2 * I),
        "J_T": J_T,
    }


if __name__ == "__main__":  # pragma: no cover
    res = paper_frequencies(3)
    print(f"J_T = {res['J_T']:.10e} m^4 = {res['J_T'] / 0.01**4:.10f} a^4")
    for key in ("euler_bernoulli", "timoshenko", "axial", "torsional"):
        w = np.asarray(res[key])
        print(f"{key:16s} omega = {w}  f = {w / (2 * math.pi)}  T = {2 * math.pi / w}")
    w1 = float(np.asarray(res["euler_bernoulli"])[0])
    for tau in (0.02, 0.04, 0.08):
        z = w1 * tau / 2
        d = 2 * math.pi * z / math.sqrt(1 - z * z)
        Td = 2 * math.pi / (w1 * math.sqrt(1 - z * z))
        print(f"tau = {tau}: zeta_1 = {z:.6f}  delta_1 = {d:.6f}  T_d = {Td:.6f}")
