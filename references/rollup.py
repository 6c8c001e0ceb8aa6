"""Roll-up of a straight cantilever by a dead end moment about a principal axis (closed form).

A straight rod of length ``L`` (m), clamped at ``s = 0``, loaded at ``s = L`` by an end
moment ``M`` (N m) about a principal axis of the section, with bending stiffness ``EI``
(N m^2) about that axis. Moment balance ``m' + r' x n = 0`` with ``n = 0`` (no force
anywhere) gives a constant moment ``m = M``, so the curvature is constant, ``K = M / EI``,
and the centerline is a circular arc of radius ``rho = EI / M``. Since ``n = 0`` there is
no extension and no shear (for any ``EA``, ``GA``). The moment vector stays perpendicular
to the bending plane, so a dead and a follower moment give the same solution.

In the bending plane, with ``u`` the transverse coordinate (towards the side the rod rolls
to) and ``w`` the coordinate along the undeformed axis, ``theta = M s / EI``::

    u(s) = rho (1 - cos theta),   w(s) = rho sin theta

and at the tip ``theta_L = M L / EI``. ``M = pi EI / L`` gives a half circle (tip at
``u = 2 L / pi``, ``w = 0``); ``M = 2 pi EI / L`` closes the circle and the end returns to
the clamp with its original orientation.

Sign convention for the 3-D check (rod along ``d3 = e3``, ``R0 = I``): a moment ``M e2``
(about ``d2``, stiffness ``EI2``) rolls the rod towards ``+e1``: ``x = u``, ``z = w``; a
moment ``M e1`` (about ``d1``, stiffness ``EI1``) rolls it towards ``-e2``: ``y = -u``.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["closing_moment", "rollup_curve", "rollup_tip"]


def _check(EI: float, L: float) -> None:
    if not (EI > 0 and math.isfinite(EI) and L > 0 and math.isfinite(L)):
        raise ValueError(f"EI and L must be positive and finite, got EI={EI!r}, L={L!r}")


def rollup_curve(
    s: np.ndarray | float, M: float, EI: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(u, w, theta)`` at arclengths ``s`` (m): transverse and axial coordinates (m) and
    the section rotation (rad). Regular at ``M = 0`` (``u = 0``, ``w = s``)."""
    s = np.asarray(s, dtype=float)
    th = M * s / EI
    # rho (1 - cos th) = s * 2 sin^2(th/2) / th;  rho sin th = s * sinc(th)
    half = 0.5 * th
    u = s * half * np.sinc(half / np.pi) ** 2
    w = s * np.sinc(th / np.pi)
    return u, w, th


def rollup_tip(M: float, EI: float, L: float) -> tuple[float, float, float]:
    """Tip ``(u, w, theta)``: ``((EI/M)(1 - cos(ML/EI)), (EI/M) sin(ML/EI), ML/EI)``."""
    _check(EI, L)
    u, w, th = rollup_curve(L, M, EI)
    return float(u), float(w), float(th)


def closing_moment(EI: float, L: float) -> float:
    """The end moment ``2 pi EI / L`` (N m) that rolls the rod into a full circle."""
    _check(EI, L)
    return 2.0 * math.pi * EI / L
