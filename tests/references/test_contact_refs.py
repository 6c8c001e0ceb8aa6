"""Tests of references.contact against special cases and separately written numerical
models (an obstacle finite-element beam, ODE integration, discrete friction models)."""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.sparse as sp
from scipy.integrate import quad, solve_ivp
from scipy.sparse.linalg import spsolve

from references.contact import (
    bend_entry_force,
    capstan_profile,
    capstan_ratio,
    capstan_ratio_rod,
    draped_cable,
    draped_cable_max_overhang,
    flat_drop,
    incline,
    incline_slide_distance,
    insertion_force_capstan,
    lifted_rod,
    lifted_rod_curve,
    round_rod_across_incline,
)


# ---------------------------------------------------------------- rod lifted off a table
def _beam_element(h: float, EI: float, GA: float) -> np.ndarray:
    """Exact two-node Timoshenko element (Euler-Bernoulli for GA = inf), (w1, th1, w2, th2)."""
    phi = 12.0 * EI / (GA * h * h)
    c = EI / (h**3 * (1.0 + phi))
    return c * np.array([
        [12.0, 6 * h, -12.0, 6 * h],
        [6 * h, (4 + phi) * h * h, -6 * h, (2 - phi) * h * h],
        [-12.0, -6 * h, 12.0, -6 * h],
        [6 * h, (2 - phi) * h * h, -6 * h, (4 + phi) * h * h]])


def fe_lifted_rod(F, q, EI, kGA, L, N):
    """Obstacle problem: a beam of N elements on nodal unilateral supports w_i >= 0, its
    weight q down and F up at node 0. The contact set is searched by bisection on the
    first node in contact, k; the returned state satisfies the Karush-Kuhn-Tucker
    conditions (gaps >= 0 off contact, reactions >= 0 on contact), which for this convex
    problem identify the minimizer of the energy without assuming any lift-off condition.
    Returns the nodal w, the nodal reactions and k."""
    h = L / N
    nd = 2 * (N + 1)
    ke = _beam_element(h, EI, kGA)
    rows, cols, vals = [], [], []
    for e in range(N):
        idx = np.arange(2 * e, 2 * e + 4)
        rows.append(np.repeat(idx, 4))
        cols.append(np.tile(idx, 4))
        vals.append(ke.ravel())
    K = sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                      shape=(nd, nd))
    f = np.zeros(nd)
    for e in range(N):
        f[2 * e:2 * e + 4] += -q * np.array([h / 2, h * h / 12, h / 2, -h * h / 12])
    f[0] += F

    def solve(k):
        free = np.r_[np.arange(0, 2 * k), np.arange(2 * k + 1, nd, 2)]
        u = np.zeros(nd)
        u[free] = spsolve(K[free][:, free].tocsc(), f[free])
        return u, (K @ u - f)[0::2]

    lo, hi = 1, N
    while hi - lo >= 1:
        k = (lo + hi) // 2
        u, lam = solve(k)
        if u[0:2 * k:2].min() < -1e-10 * abs(u[0]):
            hi = k                      # penetrates: the contact starts earlier
        elif lam[k:].min() < -1e-10 * F:
            lo = k                      # the table pulls: the contact starts later
        else:
            return u[0::2], lam, k
    raise AssertionError("no contact set satisfies the KKT conditions")


def test_lifted_rod_euler_bernoulli_values():
    r = lifted_rod(0.3, q=2.0, EI=0.7)
    assert r["lifted_length"] == pytest.approx(0.3)
    assert r["end_height"] == pytest.approx(0.6**4 / (24 * 0.7 * 8.0))
    assert r["end_slope"] == pytest.approx(2.0 * 0.3**3 / (12 * 0.7))
    assert r["liftoff_point_force"] == 0.3 and r["boundary_layer"] == 0.0
    assert math.isnan(r["table_force"])
    assert lifted_rod(0.3, q=2.0, EI=0.7, L=1.0)["table_force"] == pytest.approx(1.7)
    x = np.array([0.0, 0.1, 0.3, 0.5])
    xi = np.maximum(0.3 - x, 0.0)
    np.testing.assert_allclose(lifted_rod_curve(x, 0.3, q=2.0, EI=0.7),
                               2.0 * 0.3 * xi**3 / (12 * 0.7) - 2.0 * xi**4 / (24 * 0.7),
                               rtol=1e-13, atol=1e-17)


def test_lifted_rod_range():
    with pytest.raises(ValueError, match="F must be below"):
        lifted_rod(1.0, q=2.0, EI=1.0, L=1.0)   # F = q L / 2: the rod tips up rigidly
    lifted_rod(0.99, q=2.0, EI=1.0, L=1.0)
    with pytest.raises(ValueError, match="F must be"):
        lifted_rod(0.0, q=2.0, EI=1.0)


def test_lifted_rod_euler_bernoulli_against_obstacle_fe():
    F, q, EI, L, N = 0.5, 1.0, 1.3, 2.0, 300
    r = lifted_rod(F, q=q, EI=EI, L=L)
    w, lam, k = fe_lifted_rod(F, q, EI, math.inf, L, N)
    h = L / N
    assert abs(k * h - r["lifted_length"]) <= h + 1e-12        # a = 2F/q, not F/q
    assert w[0] == pytest.approx(r["end_height"], rel=2e-5)
    x = np.linspace(0.0, L, N + 1)
    np.testing.assert_allclose(w, lifted_rod_curve(x, F, q=q, EI=EI), rtol=0,
                               atol=3e-5 * r["end_height"])
    # the point reaction F at the lift-off node (plus that node's share of the weight)
    assert lam[k] == pytest.approx(F + q * h / 2, rel=0.03)
    assert lam.sum() == pytest.approx(q * L - F, rel=1e-10)


def test_lifted_rod_timoshenko_against_obstacle_fe():
    """With shear the sections rotate on the table over l = sqrt(EI/kGA): the rod leaves
    earlier, has no point reaction, and the end rises by ~6 (l/a)^2 more."""
    F, q, EI, L, N = 0.5, 1.0, 1.0, 2.0, 600
    kGA = EI / 0.05**2
    r = lifted_rod(F, q=q, EI=EI, kGA=kGA, L=L)
    eb = lifted_rod(F, q=q, EI=EI, L=L)
    assert r["end_height"] / eb["end_height"] - 1 == pytest.approx(0.0145, abs=1e-3)
    w, lam, k = fe_lifted_rod(F, q, EI, kGA, L, N)
    h = L / N
    assert abs(k * h - r["lifted_length"]) <= h + 1e-12
    assert r["lifted_length"] < eb["lifted_length"] - 10 * h
    assert w[0] == pytest.approx(r["end_height"], rel=2e-5)
    assert lam[k] < 0.05 * F
    x = np.linspace(0.0, L, N + 1)
    np.testing.assert_allclose(w, lifted_rod_curve(x, F, q=q, EI=EI, kGA=kGA), rtol=0,
                               atol=1e-4 * r["end_height"])


# ------------------------------------------------------------------------------ incline
def test_incline():
    th = math.radians(30.0)
    assert incline(th, math.tan(th))["sticks"]                    # impending slip: rests
    assert incline(th, 0.6)["acceleration"] == 0.0
    a = incline(th, 0.2, g=9.81)["acceleration"]
    assert a == pytest.approx(9.81 * (0.5 - 0.2 * math.sqrt(3) / 2))
    t = np.array([0.0, 0.5, 1.0])
    np.testing.assert_allclose(incline_slide_distance(t, theta=th, mu=0.2), 0.5 * a * t * t)
    np.testing.assert_array_equal(incline_slide_distance(t, theta=th, mu=0.7), 0.0)
    with pytest.raises(ValueError, match="theta must be"):
        incline(math.pi / 2, 0.1)


def test_incline_against_block_simulation():
    """A block on a slope with a smooth Coulomb law, friction mu N tanh(v/eps) (no stick
    branch): it creeps at O(eps) when the references say it sticks, else slides."""
    g, th, eps = 9.81, math.radians(25.0), 1e-7

    def run(mu):
        def rhs(_t, y):
            return [y[1], g * math.sin(th) - mu * g * math.cos(th) * math.tanh(y[1] / eps)]
        return solve_ivp(rhs, (0.0, 1.0), [0.0, 0.0], method="Radau", rtol=1e-9,
                         atol=1e-13).y[0, -1]

    assert incline(th, 0.6)["sticks"] and 0 <= run(0.6) < 1e-6
    assert run(0.3) == pytest.approx(float(incline_slide_distance(1.0, theta=th, mu=0.3)),
                                     rel=1e-5)


def test_round_rod_across_incline():
    th = math.radians(20.0)
    r = round_rod_across_incline(th, 0.2)
    assert r["rolls_without_slip"]
    assert r["acceleration"] == pytest.approx(2 / 3 * 9.81 * math.sin(th))
    r = round_rod_across_incline(th, 0.1)                 # mu < tan(theta)/3 = 0.121
    assert not r["rolls_without_slip"]
    assert r["acceleration"] == pytest.approx(9.81 * (math.sin(th) - 0.1 * math.cos(th)))
    assert incline(th, 0.5)["sticks"]                       # lying along the fall line


# ------------------------------------------------------------------------------ capstan
@pytest.mark.parametrize("mu, wrap", [(0.3, math.pi), (0.1, 3 * 2 * math.pi), (0.5, 0.7)])
def test_capstan_against_polygon(mu, wrap):
    """A rope over N frictional pegs on the circle (turn wrap/N each): at slip
    T_out/T_in = ((1 + mu t)/(1 - mu t))^N with t = tan(wrap/(2N)); N -> inf."""
    logs = []
    for N in (1000, 2000):
        t = math.tan(wrap / (2 * N))
        logs.append(N * math.log((1 + mu * t) / (1 - mu * t)))
    extrap = (4 * logs[1] - logs[0]) / 3          # the error is O(1/N^2)
    assert math.exp(extrap) == pytest.approx(capstan_ratio(mu, wrap), rel=1e-8)
    T, p = capstan_profile([0.0, wrap], T_hold=2.0, mu=mu, R=0.1)
    assert T[1] / T[0] == pytest.approx(capstan_ratio(mu, wrap))
    np.testing.assert_allclose(p, T / 0.1)
    assert capstan_ratio(0.0, 5.0) == 1.0


def _rigid_links_on_drum(mu: float, wrap: float, R: float, r: float, n: int) -> float:
    """T_load/T_hold of n rigid links (chords of the centreline's circle of radius R + r,
    their midpoints on it) slipping on the drum: on each link the pressure P at its
    midpoint's surface point (r inside the centreline, on the drum), the friction mu P
    there toward the held end, the internal forces at its ends; the bending moment the
    same at both ends (the rod stress free as wrapped). Force and moment balance of each
    link in turn, from the held end (its force along the first tangent, no shear)."""
    rho, dth = R + r, wrap / n
    d = 2.0 * rho * math.tan(dth / 2)

    def cross(a, b):
        return a[0] * b[1] - a[1] * b[0]

    N = np.array([0.0, 1.0])                      # T_hold = 1 along the tangent at 0
    for i in range(n):
        th = (i + 0.5) * dth
        e_r, t = np.array([-math.cos(th), math.sin(th)]), np.array([math.sin(th), math.cos(th)])
        # moments about the midpoint: d/2 t x (N_next + N) + (-r e_r) x (-mu P t) = 0 with
        # N_next = N - P (e_r - mu t) (forces)
        P = -d * cross(t, N) / (cross(e_r, t) * (d / 2 + r * mu))
        N = N - P * (e_r - mu * t)
    return float(N @ np.array([math.sin(wrap), math.cos(wrap)]))


@pytest.mark.parametrize("mu, wrap, R, r", [(0.3, math.pi, 0.1, 0.001), (0.5, 2.0, 0.1, 0.02),
                                            (0.1, 6 * math.pi, 0.05, 0.01)])
def test_capstan_of_a_rod_against_rigid_links(mu, wrap, R, r):
    """The rod's capstan ratio against the chain of rigid links (n -> inf, O(1/n^2))."""
    a, b = (_rigid_links_on_drum(mu, wrap, R, r, n) for n in (1000, 2000))
    assert (4 * b - a) / 3 == pytest.approx(capstan_ratio_rod(mu, wrap, drum_radius=R,
                                                              rod_radius=r), rel=1e-8)
    assert capstan_ratio_rod(mu, wrap, drum_radius=R, rod_radius=0.0) == pytest.approx(
        capstan_ratio(mu, wrap), rel=1e-15)
    assert capstan_ratio_rod(0.0, wrap, drum_radius=R, rod_radius=r) == 1.0
    # the example's wire (r/R = 0.01) over half a turn: 1.1 % below the membrane's
    assert capstan_ratio_rod(0.3, math.pi, drum_radius=0.1, rod_radius=0.001) == \
        pytest.approx(0.98903 * capstan_ratio(0.3, math.pi), rel=1e-5)


# ---------------------------------------------------------------------------- flat drop
def test_flat_drop_against_free_fall():
    r = flat_drop(0.5, radius=0.01, g=9.81)
    sol = solve_ivp(lambda _t, y: [y[1], -9.81], (0.0, 1.0), [0.5, 0.0], rtol=1e-12,
                    atol=1e-14, events=lambda _t, y: y[0] - 0.01)
    assert r["time_to_contact"] == pytest.approx(sol.t_events[0][0], rel=1e-9)
    assert r["impact_speed"] == pytest.approx(-sol.y_events[0][0][1], rel=1e-9)
    assert r["rest_height"] == 0.01
    with pytest.raises(ValueError, match="h0 must be"):
        flat_drop(0.005, radius=0.01)


# ------------------------------------------------------------------ cable over cylinder
@pytest.mark.parametrize("mu, h_low", [(0.0, 0.3), (0.25, 0.3), (0.6, 0.0), (0.4, 1.5)])
def test_draped_cable_global_balance(mu, h_low):
    """Forces and moments on the whole cable (hanging parts, arc weight, contact pressure
    and friction from the cylinder) balance; the tension solves the element ODE."""
    q, R = 3.0, 0.2
    h_high = draped_cable_max_overhang(h_low, R=R, mu=mu)

    def p(phi):
        return float(draped_cable(phi, q=q, R=R, h_low=h_low, mu=mu)["p"])

    # cylinder on cable: p n - mu p t, n = (sin, cos), t = (cos, -sin) (slip towards phi > 0)
    Fx = quad(lambda f: (p(f) * math.sin(f) - mu * p(f) * math.cos(f)) * R,
              -math.pi / 2, math.pi / 2, epsabs=1e-11)[0]
    Fy = quad(lambda f: (p(f) * math.cos(f) + mu * p(f) * math.sin(f)) * R,
              -math.pi / 2, math.pi / 2, epsabs=1e-11)[0]
    weight = q * (h_low + h_high + math.pi * R)
    assert Fx == pytest.approx(0.0, abs=1e-10 * weight)
    assert Fy == pytest.approx(weight, rel=1e-10)
    # moments about the axis: friction holds the difference of the hanging weights
    fr = mu * R * quad(p, -math.pi / 2, math.pi / 2, epsabs=1e-11)[0]
    assert fr == pytest.approx(q * (h_high - h_low), abs=1e-10 * weight)
    # the tension profile integrates the element equilibrium from the light side
    sol = solve_ivp(lambda f, T: mu * (T + q * R * math.cos(f)) - q * R * math.sin(f),
                    (-math.pi / 2, math.pi / 2), [q * h_low], rtol=1e-12, atol=1e-14,
                    dense_output=True)
    phi = np.linspace(-math.pi / 2, math.pi / 2, 7)
    res = draped_cable(phi, q=q, R=R, h_low=h_low, mu=mu)
    np.testing.assert_allclose(res["T"], sol.sol(phi)[0], rtol=1e-9)
    assert res["T"][-1] == pytest.approx(q * h_high, rel=1e-12)
    assert np.all(res["p"] >= 0)


def test_draped_cable_limits():
    q, R = 2.0, 0.3
    res = draped_cable(np.array([-math.pi / 2, 0.0, math.pi / 2]), q=q, R=R, h_low=1.0)
    np.testing.assert_allclose(res["T"], [q, q * (1 + R), q], rtol=1e-14)
    np.testing.assert_allclose(res["p"], [q / R, q / R + 2 * q, q / R], rtol=1e-14)
    assert draped_cable_max_overhang(1.0, R=R, mu=0.0) == 1.0
    # thin cylinder: the capstan ratio of half a turn
    assert draped_cable_max_overhang(1.0, R=1e-9, mu=0.3) == pytest.approx(
        capstan_ratio(0.3, math.pi), rel=1e-8)


# ------------------------------------------------------------------ rod in a bent pipe
def test_insertion_force():
    assert insertion_force_capstan(2.0, mu=0.0, bend_angle=1.0) == 2.0
    two = insertion_force_capstan(insertion_force_capstan(1.0, mu=0.2, bend_angle=0.4),
                                  mu=0.2, bend_angle=0.6)
    assert two == pytest.approx(insertion_force_capstan(1.0, mu=0.2, bend_angle=1.0))
    assert insertion_force_capstan(1.0, mu=0.3, bend_angle=math.pi / 2) == pytest.approx(
        math.exp(0.3 * math.pi / 2))
    assert bend_entry_force(2.0, 0.5) == pytest.approx(4.0)
