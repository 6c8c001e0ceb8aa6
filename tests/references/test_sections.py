"""Section constants (references.sections) against independent integrals and limits."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import dblquad, quad
from scipy.special import zeta

from references import beams, reissner
from references.sections import (
    circle,
    cowper_circle,
    cowper_ellipse,
    cowper_rectangle,
    cowper_tube,
    ellipse,
    rectangle,
    rectangle_torsion_constant,
    tube,
)


def _ellipse_moments(a: float, b: float) -> tuple[float, float, float]:
    """A, <xi2^2>, <xi1^2> of the ellipse (xi1/b)^2 + (xi2/a)^2 <= 1 by quadrature."""

    def integ(g):
        def lim(x1):
            return a * math.sqrt(max(0.0, 1.0 - (x1 / b) ** 2))

        return dblquad(lambda x2, x1: g(x1, x2), -b, b, lambda x1: -lim(x1), lim,
                       epsabs=1e-14, epsrel=1e-12)[0]

    return integ(lambda x1, x2: 1.0), integ(lambda x1, x2: x2 * x2), integ(lambda x1, x2: x1 * x1)


def test_rectangle_orientation_and_constants():
    b, d, nu = 0.02, 0.05, 0.3
    s = rectangle(b, d, nu)
    assert s.A == pytest.approx(b * d, rel=1e-15)
    assert s.I1 == pytest.approx(b * d**3 / 12, rel=1e-15)  # <xi2^2>, d along xi2
    assert s.I2 == pytest.approx(d * b**3 / 12, rel=1e-15)
    assert s.I3 == s.I1 + s.I2
    assert s.J_T == rectangle_torsion_constant(b, d)
    assert s.kappa_1 == s.kappa_2 == pytest.approx(10 * 1.3 / 15.3, rel=1e-15)
    assert s.kappa_3 == pytest.approx(s.J_T / s.I3, rel=1e-15)
    # square: J_T = 0.1405770 a^4, I3 = a^4 / 6
    sq = rectangle(1.0, 1.0, 0.0)
    assert sq.J_T == pytest.approx(0.1405770, abs=1e-7)
    assert sq.kappa_3 == pytest.approx(6 * 0.1405770, abs=1e-6)
    assert sq.kappa_1 == pytest.approx(10 / 12)


def test_ellipse_moments_by_quadrature():
    a, b = 0.3, 0.7  # a along xi2, b along xi1
    s = ellipse(a, b, 0.25)
    A, I1, I2 = _ellipse_moments(a, b)
    assert s.A == pytest.approx(A, rel=1e-9)
    assert s.I1 == pytest.approx(I1, rel=1e-9)
    assert s.I2 == pytest.approx(I2, rel=1e-9)
    assert s.I1 == pytest.approx(math.pi * b * a**3 / 4, rel=1e-15)
    # circle limit of the torsion constant and of Cowper's factor
    c = ellipse(0.4, 0.4, 0.3)
    assert c.J_T == pytest.approx(math.pi * 0.4**4 / 2, rel=1e-14)
    assert c.kappa_1 == c.kappa_2 == pytest.approx(cowper_circle(0.3), rel=1e-14)
    assert c.kappa_3 == pytest.approx(1.0, rel=1e-14)


def test_ellipse_cowper_orientation():
    """Narrow ellipse sheared along its long axis, nu = 0: the energy-consistent factor of the
    elementary shear stress tau = V p^2 (1 - y^2/p^2) / (3 I), computed here by quadrature."""
    p, q = 1.0, 1.0  # the elementary factor does not depend on the aspect ratio
    I, A = math.pi * p**3 * q / 4, math.pi * p * q

    def tau2_width(y):
        tau = p * p * (1 - (y / p) ** 2) / (3 * I)
        return tau * tau * 2 * q * math.sqrt(1 - (y / p) ** 2)

    k_elem = 1.0 / (A * quad(tau2_width, -p, p, epsabs=1e-14)[0])
    assert k_elem == pytest.approx(0.9, rel=1e-10)
    s = ellipse(1.0, 1e-4, 0.0)  # long axis a along xi2
    assert s.kappa_2 == pytest.approx(k_elem, rel=1e-7)
    assert s.kappa_2 == pytest.approx(cowper_ellipse(0.0, 1.0, 1e-4))
    assert s.kappa_1 == pytest.approx(cowper_ellipse(0.0, 1e-4, 1.0))
    assert s.kappa_1 < 0.76  # sheared across the thin direction: 0.75 for nu = 0
    # general nu along the long axis: 36 (1 + nu) / (40 + 37 nu)
    assert cowper_ellipse(0.3, 1.0, 1e-6) == pytest.approx(36 * 1.3 / 51.1, rel=1e-10)


def test_circle_and_tube():
    nu, r = 0.3, 0.002
    c = circle(r, nu)
    assert c.A == pytest.approx(math.pi * r * r)
    assert c.I1 == c.I2 == pytest.approx(math.pi * r**4 / 4)
    assert c.J_T == c.I3 == pytest.approx(math.pi * r**4 / 2)
    assert c.kappa_1 == pytest.approx(6 * 1.3 / 8.8, rel=1e-15)
    t0 = tube(r, 0.0, nu)
    for name in ("A", "I1", "I2", "I3", "J_T", "kappa_1", "kappa_2", "kappa_3"):
        assert getattr(t0, name) == pytest.approx(getattr(c, name), rel=1e-15)
    t = tube(r, 0.5 * r, nu)
    assert t.A == pytest.approx(math.pi * 0.75 * r * r)
    assert t.I1 == pytest.approx(math.pi * (1 - 0.0625) * r**4 / 4)
    assert t.J_T == t.I3 and t.kappa_3 == 1.0
    m = 0.5
    assert t.kappa_1 == pytest.approx(
        6 * 1.3 * 1.25**2 / (8.8 * 1.25**2 + (20 + 3.6) * 0.25), rel=1e-15
    )
    # thin-walled limit 2 (1 + nu) / (4 + 3 nu)
    assert cowper_tube(nu, 1 - 1e-9) == pytest.approx(2 * 1.3 / 4.9, rel=1e-8)
    assert cowper_tube(nu, m) < cowper_circle(nu)


def test_stiffnesses_order():
    s = rectangle(0.02, 0.05, 0.3)
    E, G = 2e9, 1e9
    GA1, GA2, EA, EI1, EI2, GJ = s.stiffnesses(E, G)
    assert (GA1, GA2, EA) == (s.kappa_1 * G * s.A, s.kappa_2 * G * s.A, E * s.A)
    assert (EI1, EI2, GJ) == (E * s.I1, E * s.I2, G * s.J_T)


def test_reexports_are_the_same_objects():
    assert beams.rectangle_torsion_constant is rectangle_torsion_constant
    assert reissner.cowper_rectangle is cowper_rectangle


@pytest.mark.parametrize(
    "call",
    [
        lambda: rectangle(0.0, 1.0, 0.3),
        lambda: rectangle(1.0, 1.0, 0.6),
        lambda: circle(-1.0, 0.3),
        lambda: ellipse(1.0, math.inf, 0.3),
        lambda: tube(1.0, 1.0, 0.3),
        lambda: cowper_tube(0.3, 1.0),
    ],
)
def test_invalid_input(call):
    with pytest.raises(ValueError):
        call()


def test_torsion_constant_thin_strip_and_convergence():
    # thin strip: J = c a^3 / 3 (1 - 192/pi^5 (31/32) zeta(5) a/c) up to exp(-pi c/(2a))
    a, c = 1.0, 50.0
    J = rectangle_torsion_constant(a, c)
    beta = 192 / math.pi**5 * (31 / 32) * zeta(5)
    assert beta == pytest.approx(0.630249, abs=1e-6)
    assert J == pytest.approx(c * a**3 / 3 * (1 - beta * a / c), rel=1e-14)
    # the plain tanh series converges to the same value (tail ~ 1/(4 N^4))
    for side in (1.0, 2.5):
        n = np.arange(1, 200001, 2, dtype=float)
        plain = side / 3 * (1 - 192 / (math.pi**5 * side)
                            * np.sum(np.tanh(n * math.pi * side / 2) / n**5))
        assert rectangle_torsion_constant(1.0, side) == pytest.approx(plain, rel=1e-14)
    assert rectangle_torsion_constant(1, 1, terms=10) == rectangle_torsion_constant(1, 1)
