"""Straight beams simply supported (pinned-pinned) or free at both ends: linear Timoshenko
statics and natural frequencies (closed forms and a transfer-matrix frequency equation).

Independent of kvrod (NumPy/SciPy only). SI units; angular frequencies in rad/s. A beam of
length ``L``, bending stiffness ``EI`` (N m^2), shear stiffness ``kGA`` (N, shear-corrected),
mass per length ``rho A`` and rotary inertia per length ``rho I``. Timoshenko theory::

    rho A w_tt   = kGA (w'' - psi')              Q = kGA (w' - psi)
    rho I psi_tt = EI psi'' + kGA (w' - psi)     M = EI psi'

Simply supported (``w = 0`` and ``M = 0`` at both ends; the ends turn freely):

- uniform load ``q`` (N/m): statically determinate, ``M = q x (L - x) / 2``,
  ``Q = q (L/2 - x)``. The Euler-Bernoulli curve ``q x (L^3 - 2 L x^2 + x^3) / (24 EI)``
  plus the shear deflection ``int_0^x Q / kGA = q x (L - x) / (2 kGA)``; at midspan::

      w_max = 5 q L^4 / (384 EI) + q L^2 / (8 kGA)

  (the bending term is the textbook value, e.g. Roark's Formulas for Stress and Strain;
  valid while ``w`` is small against the radius of gyration: held ends stretch the axis);
- natural frequencies: ``w = W sin(k x)``, ``psi = Psi cos(k x)``, ``k = n pi / L`` satisfy
  both end conditions exactly, and the two equations give the frequency equation::

      (kGA k^2 - rho A omega^2) (EI k^2 + kGA - rho I omega^2) - (kGA k)^2 = 0,

  a quadratic in ``omega^2``: ``a omega^4 - b omega^2 + c = 0`` with ``a = rho A rho I``,
  ``b = rho A (EI k^2 + kGA) + rho I kGA k^2``, ``c = EI kGA k^4``. Its smaller root is the
  n-th bending frequency (the larger one the shear "second spectrum"); without rotary
  inertia ``omega^2 = c / b``. Euler-Bernoulli: ``omega = k^2 sqrt(EI / (rho A))``.

Free at both ends (``M = Q = 0`` at both ends): six rigid motions (omega = 0) and bending
frequencies from the transfer matrix ``P = expm(A)`` of the first-order system in
``(w/L, psi, M L/EI, Q L^2/EI)`` over the dimensionless length: the free start leaves
``(w0, psi0, 0, 0)``, the free end needs ``M = Q = 0``, so ``det P[2:, :2] = 0``; roots are
bracketed above the rigid-body root at 0 and refined with Brent's method. Euler-Bernoulli:
roots ``beta_n L`` of ``cos x cosh x = 1`` (4.7300407, 7.8532046, ...),
``omega_n = (beta_n L)^2 sqrt(EI / (rho A L^4))``.

Bars and shafts: fixed-fixed axial ``omega_n = n pi / L sqrt(E / rho)`` (also free-free),
free-free torsion ``omega_n = n pi / L sqrt(G J_T / (rho I_3))`` (a pinned end leaves the
twist free).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.linalg import expm
from scipy.optimize import brentq

__all__ = [
    "bar_frequencies",
    "free_free_euler_bernoulli_roots",
    "free_free_timoshenko_frequencies",
    "shaft_free_free_frequencies",
    "simply_supported_euler_bernoulli_frequencies",
    "simply_supported_timoshenko_frequencies",
    "simply_supported_uniform_load_curve",
    "simply_supported_uniform_load_deflection",
]


def _check(L: float, EI: float, kGA: float) -> None:
    if not (L > 0 and math.isfinite(L) and EI > 0 and math.isfinite(EI) and kGA > 0):
        raise ValueError(f"need L, EI > 0 finite and kGA > 0, got {L!r}, {EI!r}, {kGA!r}")


def simply_supported_uniform_load_deflection(
    q: float, *, L: float, EI: float, kGA: float = math.inf
) -> float:
    """Midspan deflection (m) under a uniform load ``q`` (N/m):
    ``5 q L^4 / (384 EI) + q L^2 / (8 kGA)``."""
    _check(L, EI, kGA)
    return 5.0 * q * L**4 / (384.0 * EI) + q * L * L / (8.0 * kGA)


def simply_supported_uniform_load_curve(
    x: np.ndarray | float, q: float, *, L: float, EI: float, kGA: float = math.inf
) -> np.ndarray:
    """Deflection ``w(x)`` (m) under a uniform load ``q`` (N/m):
    ``q x (L^3 - 2 L x^2 + x^3) / (24 EI) + q x (L - x) / (2 kGA)``."""
    _check(L, EI, kGA)
    x = np.asarray(x, dtype=float)
    return q * x * (L**3 - 2.0 * L * x**2 + x**3) / (24.0 * EI) + q * x * (L - x) / (2.0 * kGA)


def simply_supported_euler_bernoulli_frequencies(
    n: int, *, L: float, rho: float, A: float, E: float, I: float
) -> np.ndarray:
    """``omega_k = (k pi / L)^2 sqrt(E I / (rho A))``, k = 1..n (rad/s)."""
    k = np.arange(1, n + 1) * math.pi / L
    return k**2 * math.sqrt(E * I / (rho * A))


def simply_supported_timoshenko_frequencies(
    n: int, *, L: float, rho: float, A: float, E: float, I: float, kGA: float,
    rotary_inertia: bool = True,
) -> np.ndarray:
    """First ``n`` bending frequencies (rad/s) of the simply supported Timoshenko beam: the
    smaller root of the quadratic frequency equation (module docstring) for ``k = j pi/L``."""
    _check(L, E * I, kGA)
    if n < 1:
        raise ValueError(f"n must be >= 1, got {n!r}")
    rA, rI, EI = rho * A, (rho * I if rotary_inertia else 0.0), E * I
    out = []
    for j in range(1, n + 1):
        k = j * math.pi / L
        a = rA * rI
        b = rA * (EI * k * k + kGA) + rI * kGA * k * k
        c = EI * kGA * k**4
        # smaller root of a x^2 - b x + c = 0, written without cancellation
        x = 2.0 * c / (b + math.sqrt(b * b - 4.0 * a * c)) if a > 0 else c / b
        out.append(math.sqrt(x))
    return np.array(out)


def free_free_euler_bernoulli_roots(n: int) -> np.ndarray:
    """First ``n`` nonzero roots ``beta_k L`` of ``cos x cosh x = 1`` (dimensionless),
    solved as ``cos x - 1/cosh x = 0`` (no overflow): the k-th lies near ``(k + 1/2) pi``,
    bracketed by ``[k pi + 0.1, (k + 1) pi - 0.1]`` (``1/cosh`` is small there)."""
    if n < 1:
        raise ValueError(f"n must be >= 1, got {n!r}")

    def g(x: float) -> float:
        return math.cos(x) - 1.0 / math.cosh(x)

    return np.array([brentq(g, k * math.pi + 0.1, (k + 1) * math.pi - 0.1, xtol=1e-15,
                            rtol=4 * np.finfo(float).eps) for k in range(1, n + 1)])


def _system(omega: float, *, L: float, rho: float, A: float, E: float, I: float,
            kGA: float, rotary_inertia: bool = True) -> np.ndarray:
    """``y' = S y`` over ``x / L`` for ``y = (w/L, psi, M L/EI, Q L^2/EI)``, harmonic motion:
    ``w' = psi + Q/kGA``, ``psi' = M/EI``, ``M' = -Q - rho I omega^2 psi``,
    ``Q' = -rho A omega^2 w`` (every entry O(1) or O(omega^2))."""
    b2 = rho * A * omega**2 * L**4 / (E * I)
    r2 = I / (A * L * L) if rotary_inertia else 0.0
    s2 = E * I / (kGA * L * L)
    return np.array([[0.0, 1.0, 0.0, s2],
                     [0.0, 0.0, 1.0, 0.0],
                     [0.0, -b2 * r2, 0.0, -1.0],
                     [-b2, 0.0, 0.0, 0.0]])


def free_free_timoshenko_determinant(omega: float, **beam) -> float:
    """``det P[2:, :2]``: zero at the free-free natural frequencies (and at omega = 0)."""
    P = expm(_system(omega, **beam))
    return float(P[2, 0] * P[3, 1] - P[2, 1] * P[3, 0])


def free_free_timoshenko_frequencies(
    n: int, *, L: float, rho: float, A: float, E: float, I: float, kGA: float,
    rotary_inertia: bool = True, points_per_mode: int = 200,
) -> np.ndarray:
    """First ``n`` free-free Timoshenko bending frequencies (rad/s): sign changes of
    :func:`free_free_timoshenko_determinant` on a grid from 0.05 of the first to between
    the n-th and (n+1)-th Euler-Bernoulli frequency (Timoshenko's lie below), refined by
    Brent's method. Rotary inertia ``rho I`` unless ``rotary_inertia=False``."""
    _check(L, E * I, kGA)
    beam = {"L": L, "rho": rho, "A": A, "E": E, "I": I, "kGA": kGA,
            "rotary_inertia": rotary_inertia}
    b = free_free_euler_bernoulli_roots(n + 1)
    w_eb = b**2 * math.sqrt(E * I / (rho * A * L**4))
    w_max = 0.5 * (w_eb[n - 1] + w_eb[n])
    grid = np.linspace(0.05 * w_eb[0], w_max, points_per_mode * n + 1)
    vals = np.array([free_free_timoshenko_determinant(w, **beam) for w in grid])
    roots: list[float] = []
    for i in range(grid.size - 1):
        if vals[i] * vals[i + 1] < 0:
            roots.append(brentq(lambda w: free_free_timoshenko_determinant(w, **beam),
                                grid[i], grid[i + 1], xtol=1e-14 * w_max, rtol=1e-15))
            if len(roots) == n:
                return np.array(roots)
    raise RuntimeError(f"found only {len(roots)} free-free roots below {w_max}")


def bar_frequencies(n: int, *, L: float, rho: float, E: float) -> np.ndarray:
    """Fixed-fixed (or free-free) bar: ``omega_k = k pi / L sqrt(E / rho)`` (rad/s)."""
    return np.arange(1, n + 1) * math.pi / L * math.sqrt(E / rho)


def shaft_free_free_frequencies(
    n: int, *, L: float, rho: float, G: float, J_T: float, I3: float
) -> np.ndarray:
    """Free-free shaft: ``omega_k = k pi / L sqrt(G J_T / (rho I3))`` (rad/s)."""
    return np.arange(1, n + 1) * math.pi / L * math.sqrt(G * J_T / (rho * I3))
