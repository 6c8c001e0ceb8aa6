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
  tip force by the moment-area method;
- the linear cantilever of one coupled section under an end force and moment: statically
  determinate, n = F and m(s) = M + (L - s) e3 x F, so x(s) = K^-1 (n, m(s)) is linear in
  s and the tip displacement and rotation are its integrals in closed form.
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


def coupled_cantilever(K: np.ndarray, F, M, L: float) -> dict:
    """The straight cantilever along e3 (clamped at s = 0, length L, m) of one section of
    stiffness K (6x6, strain order Gamma1..3, K1..3) under a force F (N) and a moment M
    (N m) at s = L, linear (small loads): the resultants are n = F and
    m(s) = M + (L - s) e3 x F, so the strains x(s) = K^-1 (n, m(s)) = x0 + (L - s) x1
    with x0 = K^-1 (F, M), x1 = K^-1 (0, e3 x F). The rotation is
    theta(s) = int_0^s K = s k0 + (L s - s^2/2) k1 and the tip displacement
    u(L) = int_0^L (Gamma - e3 + theta x e3) ds = L g0 + L^2/2 g1 + (L^2/2 k0 + L^3/3 k1) x e3.

    Returns ``strains`` (a function of s (m, array) giving (len(s), 6)), ``tip`` (the
    tip displacement, m) and ``rotation`` (the tip rotation vector, rad)."""
    K = np.asarray(K, dtype=float)
    F, M = np.asarray(F, dtype=float), np.asarray(M, dtype=float)
    e3 = np.array([0.0, 0.0, 1.0])
    x0 = np.linalg.solve(K, np.r_[F, M])
    x1 = np.linalg.solve(K, np.r_[np.zeros(3), np.cross(e3, F)])
    g0, k0, g1, k1 = x0[:3], x0[3:], x1[:3], x1[3:]

    def strains(s):
        s = np.atleast_1d(np.asarray(s, dtype=float))
        return x0[None, :] + (L - s)[:, None] * x1[None, :]

    tip = L * g0 + L**2 / 2 * g1 + np.cross(L**2 / 2 * k0 + L**3 / 3 * k1, e3)
    return {"strains": strains, "tip": tip, "rotation": L * k0 + L**2 / 2 * k1}
