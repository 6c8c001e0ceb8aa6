"""Tests of references.pendulum (rigid compound pendulum, elliptic-function solution)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from references.pendulum import (
    angle,
    angular_velocity,
    ode_angle,
    period,
    quarter_period,
    rod_pivot_inertia,
    tip_position,
)

L, A_SIDE, RHO, G = 0.3, 0.01, 1000.0, 9.81
M = RHO * A_SIDE**2 * L
I_O = rod_pivot_inertia(M, L, A_SIDE**2 / 12)
KW = {"I_O": I_O, "m": M, "g": G, "d": L / 2}


@pytest.mark.parametrize("theta0", [math.pi / 2, 0.3, -2.5])
def test_elliptic_matches_ode(theta0):
    T = period(theta0=theta0, **KW)
    t = np.linspace(0.0, 3 * T, 301)
    th_ode, om_ode = ode_angle(t, theta0=theta0, **KW)
    np.testing.assert_allclose(angle(t, theta0=theta0, **KW), th_ode, atol=1e-9)
    w0 = math.sqrt(M * G * L / 2 / I_O)
    np.testing.assert_allclose(angular_velocity(t, theta0=theta0, **KW), om_ode, atol=1e-9 * w0)


def test_quarter_period_is_first_bottom_crossing():
    def bottom(_t, y):
        return y[0]

    bottom.terminal = True
    bottom.direction = -1
    w2 = M * G * (L / 2) / I_O
    sol = solve_ivp(lambda _t, y: [y[1], -w2 * math.sin(y[0])], (0, 10), [math.pi / 2, 0.0],
                    method="DOP853", rtol=1e-13, atol=1e-14, events=bottom)
    tq = quarter_period(**KW)
    assert sol.t_events[0][0] == pytest.approx(tq, rel=1e-10)
    assert angle(tq, **KW) == pytest.approx(0.0, abs=1e-14)
    assert period(**KW) == pytest.approx(4 * tq, rel=1e-15)
    # T = 4 sqrt(I_O/(m g d)) K(1/sqrt 2); K(m = 1/2) = 1.854074677301372
    assert period(**KW) == pytest.approx(4 * math.sqrt(I_O / (M * G * L / 2)) * 1.854074677301372,
                                         rel=1e-14)


def test_small_amplitude_period():
    th0 = 1e-3
    T = period(theta0=th0, **KW)
    T0 = 2 * math.pi * math.sqrt(I_O / (M * G * L / 2))
    assert T == pytest.approx(T0 * (1 + th0**2 / 16), rel=1e-12)


def test_energy_and_tip():
    t = np.linspace(0.0, 2 * period(**KW), 97)
    th, om = angle(t, **KW), angular_velocity(t, **KW)
    energy = 0.5 * I_O * om**2 - M * G * (L / 2) * np.cos(th)
    np.testing.assert_allclose(energy, 0.0, atol=1e-14 * M * G * L)
    x, z = tip_position(t, L=L, **{k: KW[k] for k in ("I_O", "m", "g")})
    np.testing.assert_allclose(np.hypot(x, z), L, rtol=1e-14)
    assert (x[0], z[0]) == pytest.approx((L, 0.0), abs=1e-15)
    xb, zb = tip_position(quarter_period(**KW), L=L, I_O=I_O, m=M, g=G)
    assert (float(xb), float(zb)) == pytest.approx((0.0, -L), abs=1e-14)
    # half period: the rod reaches the horizontal on the other side (x = -L)
    xh, zh = tip_position(2 * quarter_period(**KW), L=L, I_O=I_O, m=M, g=G)
    assert (float(xh), float(zh)) == pytest.approx((-L, 0.0), abs=1e-12)


def test_section_rotary_inertia_slows_the_swing():
    slender = rod_pivot_inertia(M, L)
    assert slender == pytest.approx(M * L * L / 3)
    tq_s = quarter_period(I_O=slender, m=M, g=G, d=L / 2)
    tq = quarter_period(**KW)
    # T ~ sqrt(I_O): relative change (1 + 3 a^2 / (12 L^2))^(1/2) - 1
    assert tq / tq_s == pytest.approx(math.sqrt(1 + A_SIDE**2 / (4 * L * L)), rel=1e-14)
