"""Straight rod clamped at both ends: linear Timoshenko deflections (closed form).

A straight rod of length ``L`` (m), both ends clamped (position and section rotation
held), bending stiffness ``EI`` (N m^2) and shear stiffness ``kGA`` (N, shear-corrected)
for the plane of the load. Linear Timoshenko theory: ``M = EI psi'``, ``Q = kGA (w' - psi)``,
``Q' = -q``, ``M' = -Q`` with ``w = psi = 0`` at both ends.

The bending moment is the Euler-Bernoulli one even with shear deformation: the extra
condition that fixes the indeterminate end moment is ``int_0^L psi' ds = 0``, i.e.
``int M / EI = 0``, which does not involve ``kGA``. Then ``w = int psi + int Q / kGA``, so
the deflection is the Euler-Bernoulli deflection plus the shear deflection
``int_0^x Q / kGA``:

- uniform load ``q`` (N/m): ``Q = q (L/2 - x)``, end moments ``q L^2 / 12``, midspan
  moment ``q L^2 / 24``::

      w_max = q L^4 / (384 EI) + q L^2 / (8 kGA)

- central point load ``F`` (N): ``Q = F/2`` on the first half, end and midspan moments
  ``F L / 8``::

      w_max = F L^3 / (192 EI) + F L / (4 kGA)

(The bending terms are the standard Euler-Bernoulli results, e.g. in the beam tables of
Roark's Formulas for Stress and Strain; the shear terms follow from the shear force as
above.) For ``kGA = inf``
these are the Euler-Bernoulli values. Valid for small deflections: in a rod whose ends are
held, the deflection ``w`` stretches the axis and produces a tension of order
``EA (w/L)^2``, a relative correction of order ``(w / r_g)^2`` with ``r_g^2 = I / A``.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = [
    "clamped_center_load_deflection",
    "clamped_center_load_end_moment",
    "clamped_uniform_load_curve",
    "clamped_uniform_load_deflection",
    "clamped_uniform_load_end_moment",
]


def _check(L: float, EI: float, kGA: float) -> None:
    if not (L > 0 and math.isfinite(L) and EI > 0 and math.isfinite(EI) and kGA > 0):
        raise ValueError(f"need L, EI > 0 finite and kGA > 0, got {L!r}, {EI!r}, {kGA!r}")


def clamped_uniform_load_deflection(
    q: float, *, L: float, EI: float, kGA: float = math.inf
) -> float:
    """Midspan deflection (m) under a uniform load ``q`` (N/m): ``qL^4/(384EI) + qL^2/(8kGA)``."""
    _check(L, EI, kGA)
    return q * L**4 / (384.0 * EI) + q * L * L / (8.0 * kGA)


def clamped_uniform_load_curve(
    x: np.ndarray | float, q: float, *, L: float, EI: float, kGA: float = math.inf
) -> np.ndarray:
    """Deflection ``w(x)`` (m) under a uniform load ``q`` (N/m)::

        w = q x^2 (L - x)^2 / (24 EI) + q x (L - x) / (2 kGA)

    (bending: the clamped-clamped Euler-Bernoulli curve; shear: ``int_0^x Q / kGA`` with
    ``Q = q (L/2 - x)``); at ``x = L/2`` it is :func:`clamped_uniform_load_deflection`."""
    _check(L, EI, kGA)
    x = np.asarray(x, dtype=float)
    return q * x**2 * (L - x) ** 2 / (24.0 * EI) + q * x * (L - x) / (2.0 * kGA)


def clamped_center_load_deflection(
    F: float, *, L: float, EI: float, kGA: float = math.inf
) -> float:
    """Midspan deflection (m) under a central load ``F`` (N): ``FL^3/(192EI) + FL/(4kGA)``."""
    _check(L, EI, kGA)
    return F * L**3 / (192.0 * EI) + F * L / (4.0 * kGA)


def clamped_uniform_load_end_moment(q: float, L: float) -> float:
    """Magnitude of the end (clamp) moments under a uniform load: ``q L^2 / 12`` (N m)."""
    return q * L * L / 12.0


def clamped_center_load_end_moment(F: float, L: float) -> float:
    """Magnitude of the end (clamp) moments under a central load: ``F L / 8`` (N m)."""
    return F * L / 8.0
