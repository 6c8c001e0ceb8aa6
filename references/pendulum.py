"""Rigid compound pendulum released from rest: exact solution by Jacobi elliptic functions.

Independent of kvrod (NumPy/SciPy only). SI units; angles in rad.

A rigid body of mass ``m`` pinned at ``O``, centre of mass at distance ``d`` from the pin,
moment of inertia ``I_O`` about the pin axis, under gravity ``g``. With ``theta`` the angle
of the line ``O -> centre of mass`` from the downward vertical::

    I_O theta'' = -m g d sin(theta),     theta(0) = theta0,  theta'(0) = 0.

With ``w0 = sqrt(m g d / I_O)`` and the modulus ``k = sin(theta0 / 2)`` (parameter
``m_J = k^2`` in :func:`scipy.special.ellipj`), the solution is (Lawden 1989, ch. 5)::

    sin(theta/2) = k sn(K(k) - w0 t; k),      theta' = -2 k w0 cn(K(k) - w0 t; k),

with the quarter period ``K(k)/w0`` (time to reach the bottom ``theta = 0``) and the
period ``T = 4 K(k) / w0 = 4 sqrt(I_O / (m g d)) K(sin(theta0/2))``.

For a uniform rod of length ``L`` pinned at one end, ``d = L/2`` and
``I_O = m L^2 / 3 + m r^2`` with ``r^2 = I/A`` the squared radius of gyration of the cross
section about the pin-parallel axis (rotary inertia of the sections, ``rho I L = m I/A``;
:func:`rod_pivot_inertia`). Released horizontally, ``theta0 = pi/2``.

Tip coordinates (:func:`tip_position`): pin at the origin, ``x`` horizontal in the plane of
motion pointing along the initial rod for ``theta0 > 0``, ``z`` vertically up (gravity
``-g e_z``): ``x = L sin(theta)``, ``z = -L cos(theta)``.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.integrate import solve_ivp
from scipy.special import ellipj, ellipk

__all__ = [
    "angle",
    "angular_velocity",
    "ode_angle",
    "period",
    "quarter_period",
    "rod_pivot_inertia",
    "tip_position",
]


def rod_pivot_inertia(m: float, L: float, r2: float = 0.0) -> float:
    """``I_O = m (L^2 / 3 + r2)`` (kg m^2) of a uniform rod about its end; ``r2 = I/A``."""
    return m * (L * L / 3.0 + r2)


def _w0(I_O: float, m: float, g: float, d: float) -> float:
    if I_O <= 0 or m <= 0 or g <= 0 or d <= 0:
        raise ValueError("I_O, m, g, d must be positive")
    return math.sqrt(m * g * d / I_O)


def _modulus(theta0: float) -> float:
    if not 0.0 <= abs(theta0) < math.pi:
        raise ValueError(f"need |theta0| < pi, got {theta0!r}")
    return math.sin(abs(theta0) / 2.0)


def quarter_period(
    *, I_O: float, m: float, g: float, d: float, theta0: float = math.pi / 2
) -> float:
    """Time from release to the bottom, ``K(sin(theta0/2)) / w0`` (s)."""
    k = _modulus(theta0)
    return float(ellipk(k * k)) / _w0(I_O, m, g, d)


def period(*, I_O: float, m: float, g: float, d: float, theta0: float = math.pi / 2) -> float:
    """``T = 4 sqrt(I_O / (m g d)) K(sin(theta0/2))`` (s)."""
    return 4.0 * quarter_period(I_O=I_O, m=m, g=g, d=d, theta0=theta0)


def angle(
    t: float | np.ndarray,
    *,
    I_O: float,
    m: float,
    g: float,
    d: float,
    theta0: float = math.pi / 2,
) -> np.ndarray:
    """``theta(t) = 2 arcsin(k sn(K - w0 t; k))`` (rad), sign of ``theta0``."""
    k = _modulus(theta0)
    w0 = _w0(I_O, m, g, d)
    u = float(ellipk(k * k)) - w0 * np.asarray(t, dtype=float)
    sn, _, _, _ = ellipj(u, k * k)
    return math.copysign(1.0, theta0) * 2.0 * np.arcsin(np.clip(k * sn, -1.0, 1.0))


def angular_velocity(
    t: float | np.ndarray,
    *,
    I_O: float,
    m: float,
    g: float,
    d: float,
    theta0: float = math.pi / 2,
) -> np.ndarray:
    """``theta'(t) = -2 k w0 cn(K - w0 t; k)`` (rad/s), sign of ``theta0``."""
    k = _modulus(theta0)
    w0 = _w0(I_O, m, g, d)
    u = float(ellipk(k * k)) - w0 * np.asarray(t, dtype=float)
    _, cn, _, _ = ellipj(u, k * k)
    return -math.copysign(1.0, theta0) * 2.0 * k * w0 * cn


def tip_position(
    t: float | np.ndarray,
    *,
    L: float,
    I_O: float,
    m: float,
    g: float,
    d: float | None = None,
    theta0: float = math.pi / 2,
) -> tuple[np.ndarray, np.ndarray]:
    """Tip ``(x, z) = (L sin theta, -L cos theta)`` (m) of a rod of length ``L``; ``d``
    defaults to ``L/2`` (uniform rod)."""
    d = 0.5 * L if d is None else d
    th = angle(t, I_O=I_O, m=m, g=g, d=d, theta0=theta0)
    return L * np.sin(th), -L * np.cos(th)


def ode_angle(
    t: np.ndarray,
    *,
    I_O: float,
    m: float,
    g: float,
    d: float,
    theta0: float = math.pi / 2,
    rtol: float = 1e-12,
) -> tuple[np.ndarray, np.ndarray]:
    """Direct integration (DOP853) of ``I_O theta'' = -m g d sin theta``: ``(theta, theta')``
    at the (increasing, nonnegative) times ``t`` - a cross-check of :func:`angle`."""
    w2 = m * g * d / I_O
    t = np.asarray(t, dtype=float)
    sol = solve_ivp(
        lambda _t, y: [y[1], -w2 * math.sin(y[0])],
        (0.0, float(t[-1])),
        [theta0, 0.0],
        method="DOP853",
        t_eval=t,
        rtol=rtol,
        atol=1e-14,
    )
    if not sol.success:  # pragma: no cover
        raise RuntimeError(sol.message)
    return sol.y[0], sol.y[1]


if __name__ == "__main__":  # pragma: no cover
    # the paper's rod: L = 0.3 m, 1 cm square, rho = 1000 kg/m^3, g = 9.81 m/s^2
    L, a, rho, g = 0.3, 0.01, 1000.0, 9.81
    m = rho * a * a * L
    for name, I_O in (
        ("slender m L^2/3", rod_pivot_inertia(m, L)),
        ("with rho I L", rod_pivot_inertia(m, L, a * a / 12)),
    ):
        q = quarter_period(I_O=I_O, m=m, g=g, d=L / 2)
        print(f"{name:16s} I_O = {I_O:.10e}  t_bottom = {q:.12f}  T = {4 * q:.12f}")
        for tt in (0.1, 0.2, q):
            x, z = tip_position(tt, L=L, I_O=I_O, m=m, g=g)
            print(f"    t = {tt:.6f}: theta = {angle(tt, I_O=I_O, m=m, g=g, d=L / 2):.12f}"
                  f"  tip = ({x:.12f}, {z:.12f})")
