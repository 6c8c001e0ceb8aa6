"""Cross-section constants from textbook formulas (independent of kvrod).

Conventions (the paper's directors): the section lies in the ``xi1``-``xi2`` plane spanned
by the directors ``d1``, ``d2``; ``d3`` is the section normal. SI units (m, m^2, m^4).

- ``A``: area; ``I1 = <xi2^2>``: second moment about the ``xi1`` axis (bending about
  ``d1``, deflection along ``d2``); ``I2 = <xi1^2>``: about the ``xi2`` axis;
  ``I3 = I1 + I2``: polar moment (rotary inertia of the section about ``d3``).
- ``J_T``: Saint-Venant torsion constant, so that the torsional stiffness is ``G J_T``.
- Shear factors: ``kappa_1`` for shear along ``xi1`` (``GA1 = kappa_1 G A``), ``kappa_2``
  along ``xi2``; ``kappa_3 = J_T / I3`` is the torsion factor (``G J_T = kappa_3 G I3``).
  The transverse factors are Cowper's (1966) ``nu``-dependent ones: G. R. Cowper,
  "The shear coefficient in Timoshenko's beam theory", J. Appl. Mech. 33 (1966) 335-340,
  Table 1.

Shapes:

- rectangle, width ``b`` along ``xi1``, height ``d`` along ``xi2``::

      A = b d,  I1 = b d^3 / 12,  I2 = d b^3 / 12
      J_T = a^3 c / 3 [1 - 192 a / (pi^5 c) sum_{n odd} tanh(n pi c / (2a)) / n^5]

  with ``a = min(b, d)``, ``c = max(b, d)`` (Timoshenko and Goodier 1970, Sect. 109);
  Cowper ``kappa = 10 (1 + nu) / (12 + 11 nu)`` in both directions (his formula does not
  depend on the aspect ratio).
- solid circle, radius ``r``: ``A = pi r^2``, ``I1 = I2 = pi r^4 / 4``, ``J_T = pi r^4 / 2``,
  Cowper ``kappa = 6 (1 + nu) / (7 + 6 nu)``.
- ellipse, half axis ``a`` along ``xi2`` and ``b`` along ``xi1``: ``A = pi a b``,
  ``I1 = pi b a^3 / 4``, ``I2 = pi a b^3 / 4``, ``J_T = pi a^3 b^3 / (a^2 + b^2)``
  (Timoshenko and Goodier, Sect. 105). Cowper's ellipse factor for shear along the half
  axis ``p`` (the other half axis ``q``)::

      kappa = 12 (1 + nu) p^2 (3 p^2 + q^2) / ((40 + 37 nu) p^4 + (16 + 10 nu) p^2 q^2 + nu q^4)

  so ``kappa_2`` uses ``(p, q) = (a, b)`` and ``kappa_1`` uses ``(p, q) = (b, a)``. Checks
  (in the tests): ``p = q`` gives the circle; for a narrow ellipse loaded along its long
  axis (``q -> 0``) and ``nu = 0`` it tends to ``0.9``, the energy-consistent factor of the
  elementary (Jourawski) shear stress ``tau = V p^2 (1 - y^2/p^2) / (3 I)``, which fixes the
  orientation of the formula.
- hollow circle (tube), outer radius ``r_o``, inner ``r_i``, ``m = r_i / r_o``:
  ``A = pi (r_o^2 - r_i^2)``, ``I1 = I2 = pi (r_o^4 - r_i^4) / 4``,
  ``J_T = pi (r_o^4 - r_i^4) / 2`` and Cowper's::

      kappa = 6 (1 + nu) (1 + m^2)^2 / ((7 + 6 nu) (1 + m^2)^2 + (20 + 12 nu) m^2)

  (``m = 0``: solid circle; ``m -> 1``: thin-walled tube ``2 (1 + nu) / (4 + 3 nu)``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.special import expit, zeta

__all__ = [
    "Section",
    "circle",
    "cowper_circle",
    "cowper_ellipse",
    "cowper_rectangle",
    "cowper_tube",
    "ellipse",
    "rectangle",
    "rectangle_torsion_constant",
    "tube",
]


@dataclass(frozen=True)
class Section:
    """Section constants (m^2, m^4; factors dimensionless). See the module docstring."""

    A: float
    I1: float
    I2: float
    I3: float
    J_T: float
    kappa_1: float
    kappa_2: float
    kappa_3: float

    def stiffnesses(self, E: float, G: float) -> tuple[float, float, float, float, float, float]:
        """``(GA1, GA2, EA, EI1, EI2, GJ)`` in N, N, N, N m^2, N m^2, N m^2.

        ``GA1 = kappa_1 G A``, ``GA2 = kappa_2 G A``, ``EI1 = E I1``, ``EI2 = E I2``,
        ``GJ = G J_T``; the order is that of the diagonal ``C_F``, ``C_M`` in the director
        frame (``d1``, ``d2``, ``d3``).
        """
        return (
            self.kappa_1 * G * self.A,
            self.kappa_2 * G * self.A,
            E * self.A,
            E * self.I1,
            E * self.I2,
            G * self.J_T,
        )


def _positive(**kw: float) -> None:
    for name, val in kw.items():
        if not (val > 0 and math.isfinite(val)):
            raise ValueError(f"{name} must be positive and finite, got {val!r}")


def _poisson(nu: float) -> None:
    if not -1.0 < nu <= 0.5:
        raise ValueError(f"Poisson's ratio must lie in (-1, 0.5], got {nu!r}")


def cowper_rectangle(nu: float) -> float:
    """Cowper's (1966) shear correction factor of a rectangle, ``10(1+nu)/(12+11nu)``."""
    return 10.0 * (1.0 + nu) / (12.0 + 11.0 * nu)


def cowper_circle(nu: float) -> float:
    """Cowper's (1966) shear correction factor of a solid circle, ``6(1+nu)/(7+6nu)``."""
    return 6.0 * (1.0 + nu) / (7.0 + 6.0 * nu)


def cowper_tube(nu: float, m: float) -> float:
    """Cowper's (1966) factor of a hollow circle with radius ratio ``m = r_i / r_o``."""
    if not 0.0 <= m < 1.0:
        raise ValueError(f"radius ratio must lie in [0, 1), got {m!r}")
    p = (1.0 + m * m) ** 2
    return 6.0 * (1.0 + nu) * p / ((7.0 + 6.0 * nu) * p + (20.0 + 12.0 * nu) * m * m)


def cowper_ellipse(nu: float, p: float, q: float) -> float:
    """Cowper's (1966) factor of an ellipse sheared along its half axis ``p`` (other: ``q``).

    ``12 (1+nu) p^2 (3p^2 + q^2) / ((40+37nu) p^4 + (16+10nu) p^2 q^2 + nu q^4)``.
    """
    _positive(p=p, q=q)
    p2, q2 = p * p, q * q
    return (
        12.0
        * (1.0 + nu)
        * p2
        * (3.0 * p2 + q2)
        / ((40.0 + 37.0 * nu) * p2 * p2 + (16.0 + 10.0 * nu) * p2 * q2 + nu * q2 * q2)
    )


def rectangle_torsion_constant(a: float, b: float, terms: int = 50) -> float:
    """Saint-Venant torsion constant of an ``a x b`` rectangle (m^4), series solution.

    ``J_T = a^3 b / 3 [1 - (192 a)/(pi^5 b) sum_{n odd} tanh(n pi b / (2a)) / n^5]`` with
    ``a <= b`` (Timoshenko and Goodier, Sect. 109). For a square ``J_T = 0.1405770 a^4``.
    The arguments may be given in either order. The sum is evaluated without truncation
    error as ``(31/32) zeta(5) - sum_{n odd} (1 - tanh x_n) / n^5``, whose terms
    ``1 - tanh x_n = 2 / (1 + exp(2 x_n))`` decay like ``exp(-n pi)``; ``terms`` odd terms
    of this correction are summed (50 is far beyond double precision).
    """
    if a <= 0 or b <= 0:
        raise ValueError(f"sides must be positive, got a={a!r}, b={b!r}")
    a, b = min(a, b), max(a, b)
    n = np.arange(1, 2 * terms, 2, dtype=float)
    x = n * math.pi * b / (2 * a)
    s = (31.0 / 32.0) * float(zeta(5.0)) - float(np.sum(2.0 * expit(-2.0 * x) / n**5))
    return a**3 * b / 3.0 * (1.0 - 192.0 * a / (math.pi**5 * b) * s)


def rectangle(b: float, d: float, nu: float) -> Section:
    """Rectangle of width ``b`` along ``xi1`` and height ``d`` along ``xi2`` (m)."""
    _positive(b=b, d=d)
    _poisson(nu)
    I1, I2 = b * d**3 / 12.0, d * b**3 / 12.0
    J = rectangle_torsion_constant(b, d)
    k = cowper_rectangle(nu)
    return Section(b * d, I1, I2, I1 + I2, J, k, k, J / (I1 + I2))


def circle(r: float, nu: float) -> Section:
    """Solid circle of radius ``r`` (m); ``J_T = I3 = pi r^4 / 2``."""
    _positive(r=r)
    _poisson(nu)
    I = math.pi * r**4 / 4.0
    k = cowper_circle(nu)
    return Section(math.pi * r * r, I, I, 2.0 * I, 2.0 * I, k, k, 1.0)


def ellipse(a: float, b: float, nu: float) -> Section:
    """Ellipse with half axis ``a`` along ``xi2`` and ``b`` along ``xi1`` (m)."""
    _positive(a=a, b=b)
    _poisson(nu)
    I1, I2 = math.pi * b * a**3 / 4.0, math.pi * a * b**3 / 4.0
    J = math.pi * a**3 * b**3 / (a * a + b * b)
    return Section(
        math.pi * a * b,
        I1,
        I2,
        I1 + I2,
        J,
        cowper_ellipse(nu, b, a),
        cowper_ellipse(nu, a, b),
        J / (I1 + I2),
    )


def tube(r_o: float, r_i: float, nu: float) -> Section:
    """Hollow circle with outer radius ``r_o`` and inner radius ``0 <= r_i < r_o`` (m)."""
    _positive(r_o=r_o)
    if not 0.0 <= r_i < r_o:
        raise ValueError(f"need 0 <= r_i < r_o, got r_i={r_i!r}, r_o={r_o!r}")
    _poisson(nu)
    I = math.pi * (r_o**4 - r_i**4) / 4.0
    k = cowper_tube(nu, r_i / r_o)
    return Section(math.pi * (r_o * r_o - r_i * r_i), I, I, 2.0 * I, 2.0 * I, k, k, 1.0)
