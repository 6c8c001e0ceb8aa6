"""Independent references for rods with coupled sections (issue 26), NumPy/SciPy only.

Strain order (Gamma1, Gamma2, Gamma3, K1, K2, K3) and resultants (T1, T2, T3, M1, M2, M3)
as in kvrod's sections; SI units. Each from textbook mechanics, none from the solver:

- the linear uniform state of a straight rod under end loads: x = K^-1 f (the strains of
  a section with stiffness K under the resultants f; the rod pulled by an axial force and
  free to twist stretches and twists by the third and sixth entries);
- the Kelvin-Voigt Euler-Bernoulli cantilever (complex-modulus beam): rho A w_tt +
  (EI + eta I d/dt) w'''' = 0 has the modes of the elastic beam, beta_1 L = 1.87510407,
  with eigenvalues lambda^2 + 2 zeta omega lambda + omega^2 = 0, omega = beta^2
  sqrt(EI / rho A), zeta = omega (eta I) / (2 EI);
- the creep of a uniform strain under a viscous coupling: the quasi-static two-degree-of-
  freedom model V x' + K x = f of one section (the rod's inertia negligible against its
  retardation times): x(t) = K^-1 f + expm(-V^-1 K t) (x0 - K^-1 f);
- the cantilever with a step in EI (two zones): the tip deflection and rotation under a
  tip force by the moment-area method.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.linalg import expm

#: first root of cos(x) cosh(x) + 1 = 0 (clamped-free beam)
BETA1_L = 1.8751040687119611


def uniform_strain(K: np.ndarray, f: np.ndarray) -> np.ndarray:
    """x = K^-1 f: the six strains (Gamma - Gamma0, K - K0) of a section of stiffness K
    (6x6) under the resultants f (T1, T2, T3, M1, M2, M3)."""
    return np.linalg.solve(np.asarray(K, dtype=float), np.asarray(f, dtype=float))


def kelvin_voigt_cantilever(EI: float, VI: float, rhoA: float, L: float, beta_L: float =
                            BETA1_L) -> dict[str, float]:
    """The mode of a Kelvin-Voigt Euler-Bernoulli cantilever with bending stiffness EI
    (N m^2), bending viscosity VI (N m^2 s), mass per length rhoA (kg/m), length L (m):
    ``omega`` (undamped, rad/s), ``zeta``, the damped eigenvalue ``lambda`` (1/s)."""
    omega = beta_L**2 / L**2 * math.sqrt(EI / rhoA)
    zeta = omega * VI / (2.0 * EI)
    lam = complex(-zeta * omega, omega * math.sqrt(max(1.0 - zeta**2, 0.0)))
    return {"omega": omega, "zeta": zeta, "lambda": lam}


def creep(K: np.ndarray, V: np.ndarray, x0: np.ndarray, t: np.ndarray,
          f: np.ndarray | None = None) -> np.ndarray:
    """x(t) (len(t), n) of V x' + K x = f from x(0) = x0 (K, V n x n, V invertible)."""
    K, V = np.asarray(K, dtype=float), np.asarray(V, dtype=float)
    f = np.zeros(K.shape[0]) if f is None else np.asarray(f, dtype=float)
    xs = np.linalg.solve(K, f)
    A = -np.linalg.solve(V, K)
    return np.array([xs + expm(A * float(tk)) @ (np.asarray(x0, dtype=float) - xs)
                     for tk in np.atleast_1d(t)])


def stepped_cantilever(EI_1: float, EI_2: float, L1: float, L: float, P: float
                       ) -> dict[str, float]:
    """A cantilever clamped at s = 0, EI_1 on [0, L1], EI_2 on [L1, L], a transverse tip
    force P: the tip deflection and rotation from the curvature M(s)/EI(s), M(s) =
    P (L - s) (moment-area: rotation = int M/EI ds, deflection = int (L - s) M/EI ds)."""
    def seg(EI, a, b):        # int_a^b (L-s) ds / EI and int_a^b (L-s)^2 ds / EI
        return ((L - a) ** 2 - (L - b) ** 2) / (2 * EI), ((L - a) ** 3 - (L - b) ** 3) / (3 * EI)

    r1, d1 = seg(EI_1, 0.0, L1)
    r2, d2 = seg(EI_2, L1, L)
    return {"rotation": P * (r1 + r2), "deflection": P * (d1 + d2)}
