"""Tests of references.assemblies against special cases, literature values and separately
written numerical models (finite elements, a boundary-value solver, time integration)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_bvp, solve_ivp
from scipy.linalg import block_diag

from references.assemblies import (
    double_pendulum_frequencies,
    double_pendulum_matrices,
    l_frame_compliance,
    l_frame_tip,
    propped_cantilever,
    propped_cantilever_deflection,
    ring_cosserat_frequencies,
    ring_inplane_frequencies,
    ring_out_of_plane_frequencies,
    tip_mass_cantilever_frequencies,
    tip_mass_frequency_function,
    tip_mass_timoshenko_frequencies,
    two_span_beam,
)
from references.beams import timoshenko_frequencies


# ------------------------------------------------------------ finite elements (tests only)
def lowest_eigenvalues(K: np.ndarray, M: np.ndarray, n: int) -> np.ndarray:
    """The n smallest eigenvalues of K v = lambda M v (M positive definite) through the
    Cholesky factor of M (NumPy's LAPACK: SciPy's threaded BLAS is pathologically slow on
    small matrices when the machine is oversubscribed)."""
    Li = np.linalg.inv(np.linalg.cholesky(M))
    return np.linalg.eigvalsh(Li @ K @ Li.T)[:n]


def beam_stiffness(h: float, EI: float, GA: float) -> np.ndarray:
    """Two-node beam element in (v1, th1, v2, th2), th = dv/dx for Euler-Bernoulli; with
    shear the exact Timoshenko element (Przemieniecki, Theory of Matrix Structural
    Analysis, 1968), Phi = 12 EI / (GA h^2)."""
    phi = 12.0 * EI / (GA * h * h)
    c = EI / (h**3 * (1.0 + phi))
    return c * np.array([
        [12.0, 6 * h, -12.0, 6 * h],
        [6 * h, (4 + phi) * h * h, -6 * h, (2 - phi) * h * h],
        [-12.0, -6 * h, 12.0, -6 * h],
        [6 * h, (2 - phi) * h * h, -6 * h, (4 + phi) * h * h]])


def beam_consistent_mass(h: float, m: float) -> np.ndarray:
    """Consistent mass of the cubic Hermite element (Euler-Bernoulli), (v1, th1, v2, th2)."""
    return m * h / 420.0 * np.array([
        [156.0, 22 * h, 54.0, -13 * h],
        [22 * h, 4 * h * h, 13 * h, -3 * h * h],
        [54.0, 13 * h, 156.0, -22 * h],
        [-13 * h, -3 * h * h, -22 * h, 4 * h * h]])


def frame_stiffness(p1, p2, e2, *, EA, GJ, EI2, EI3, GA2, GA3) -> np.ndarray:
    """12x12 global stiffness of a straight 3-D Timoshenko frame element from p1 to p2.

    Local axes: e1 along the element, e2 given (normal to e1), e3 = e1 x e2. Node DOFs
    (u1, u2, u3, th1, th2, th3) in global axes. Bending with displacement along e2 uses
    EI3 (about e3) and GA2; along e3 uses EI2 (about e2) and GA3 (th2 = -dw3/dx)."""
    p1, p2 = np.asarray(p1, float), np.asarray(p2, float)
    h = float(np.linalg.norm(p2 - p1))
    e1 = (p2 - p1) / h
    e2 = np.asarray(e2, float) - np.dot(e2, e1) * e1
    e2 /= np.linalg.norm(e2)
    e3 = np.cross(e1, e2)
    k = np.zeros((12, 12))
    ax, tw = [0, 6], [3, 9]
    k[np.ix_(ax, ax)] = EA / h * np.array([[1.0, -1.0], [-1.0, 1.0]])
    k[np.ix_(tw, tw)] = GJ / h * np.array([[1.0, -1.0], [-1.0, 1.0]])
    k[np.ix_([1, 5, 7, 11], [1, 5, 7, 11])] = beam_stiffness(h, EI3, GA2)
    flip = np.diag([1.0, -1.0, 1.0, -1.0])
    k[np.ix_([2, 4, 8, 10], [2, 4, 8, 10])] = flip @ beam_stiffness(h, EI2, GA3) @ flip
    Lam = np.vstack([e1, e2, e3])
    T = block_diag(Lam, Lam, Lam, Lam)
    return T.T @ k @ T


# ------------------------------------------------------------------ cantilever + tip body
def fe_tip_body_frequencies(n, *, L, EI, m, M, J, n_el=40):
    """Hermite Euler-Bernoulli cantilever, consistent mass, tip body as point inertia
    (40 elements: discretization error ~1e-7 in the third mode, round-off ~1e-8 in the
    first; finer meshes lose to round-off)."""
    h = L / n_el
    nd = 2 * (n_el + 1)
    K, Mm = np.zeros((nd, nd)), np.zeros((nd, nd))
    ke, me = beam_stiffness(h, EI, math.inf), beam_consistent_mass(h, m)
    for e in range(n_el):
        idx = slice(2 * e, 2 * e + 4)
        K[idx, idx] += ke
        Mm[idx, idx] += me
    Mm[-2, -2] += M
    Mm[-1, -1] += J
    w2 = lowest_eigenvalues(K[2:, 2:], Mm[2:, 2:], n)
    return np.sqrt(w2)


def fe_timoshenko_tip_body(n, *, L, EI, kGA, m, rhoI, M, J, n_el):
    """Exact-stiffness Timoshenko elements with lumped mass and rotary inertia."""
    h = L / n_el
    nd = 2 * (n_el + 1)
    K = np.zeros((nd, nd))
    ke = beam_stiffness(h, EI, kGA)
    for e in range(n_el):
        K[2 * e:2 * e + 4, 2 * e:2 * e + 4] += ke
    mass = np.zeros(nd)
    mass[0::2], mass[1::2] = m * h, rhoI * h
    mass[-2], mass[-1] = m * h / 2 + M, rhoI * h / 2 + J
    w2 = lowest_eigenvalues(K[2:, 2:], np.diag(mass[2:]), n)
    return np.sqrt(w2)


def test_tip_body_no_body_is_the_cantilever():
    w = tip_mass_cantilever_frequencies(4, L=1.0, EI=1.0, m=1.0)
    np.testing.assert_allclose(np.sqrt(w), [1.8751040687, 4.6940911330, 7.8547574382,
                                            10.9955407349], rtol=1e-10)


def test_tip_mass_tabulated_roots():
    """First root b of a cantilever with an end mass M/(m L) = 0.2, 0.5, 1, 2 as tabulated
    to four digits in the literature (e.g. Blevins, Formulas for Natural Frequency and
    Mode Shape, cantilever with an end mass): 1.6164, 1.4200, 1.2479, 1.0762."""
    for mu, b in ((0.2, 1.6164), (0.5, 1.4200), (1.0, 1.2479), (2.0, 1.0762)):
        w1 = tip_mass_cantilever_frequencies(1, L=1.0, EI=1.0, m=1.0, M=mu)[0]
        assert math.sqrt(w1) == pytest.approx(b, abs=6e-5)


@pytest.mark.parametrize("M, J", [(0.3, 0.0), (0.0, 0.02), (0.7, 0.05), (5.0, 0.4)])
def test_tip_body_against_finite_elements(M, J):
    L, EI, m = 0.8, 3.0, 1.7
    ref = tip_mass_cantilever_frequencies(3, L=L, EI=EI, m=m, M=M * m * L, J=J * m * L**3)
    fe = fe_tip_body_frequencies(3, L=L, EI=EI, m=m, M=M * m * L, J=J * m * L**3)
    np.testing.assert_allclose(fe, ref, rtol=1e-6)
    # the sign of the mu j b^4 term matters: the other sign misses the FE roots
    b = np.sqrt(ref * math.sqrt(m * L**4 / EI))
    wrong = tip_mass_frequency_function(b, M, J) - 2 * M * J * b**4 * (
        1 / np.cosh(b) - np.cos(b))
    if M * J > 0:
        assert np.all(np.abs(wrong) > 1e-3)


def test_tip_body_limits():
    # a heavy tip mass: the spring-mass limit with the effective mass 33/140 m L
    for mu, frac in ((0.0, 3 / 1.8751040687**4), (1e4, 33 / 140)):
        w1 = tip_mass_cantilever_frequencies(1, L=1.0, EI=1.0, m=1.0, M=mu)[0]
        assert 3.0 / w1**2 - mu == pytest.approx(frac, abs=2e-5)
    # a huge tip inertia: a slow mode of the body on the beam (omega^2 -> 3 EI/(M L^3) or
    # EI/(J L)), the other roots tend to the clamped-pinned / clamped-sliding /
    # clamped-clamped ones
    b = np.sqrt(tip_mass_cantilever_frequencies(3, L=1.0, EI=1.0, m=1.0, M=1e9))
    assert b[0] == pytest.approx(3e-9**0.25, rel=1e-8)
    assert b[1:] == pytest.approx([3.9266023120, 7.0685827500], rel=1e-6)
    b = np.sqrt(tip_mass_cantilever_frequencies(3, L=1.0, EI=1.0, m=1.0, J=1e9))
    assert b[0] == pytest.approx(1e-9**0.25, rel=1e-8)
    assert b[1:] == pytest.approx([2.3650203606, 5.4978039150], rel=1e-6)
    b = np.sqrt(tip_mass_cantilever_frequencies(3, L=1.0, EI=1.0, m=1.0, M=1e8, J=1e8))
    assert b[2] == pytest.approx(4.7300407449, rel=1e-6)
    assert b[0] < 0.02 and b[1] < 0.02  # the two rigid-body-like modes of the heavy body


def test_tip_body_timoshenko():
    L, EI, m = 0.5, 2.0, 1.2
    kw = dict(L=L, EI=EI, m=m, M=0.4 * m * L, J=0.03 * m * L**3)
    eb = tip_mass_cantilever_frequencies(3, **kw)
    np.testing.assert_allclose(
        tip_mass_timoshenko_frequencies(3, kGA=math.inf, rhoI=0.0, **kw), eb, rtol=1e-11)
    # no tip body: the clamped-free Timoshenko references agree
    E, rho, A, I, kGA = 1.0e7, 1000.0, 1e-3, 2e-7, 3.0e3
    np.testing.assert_allclose(
        tip_mass_timoshenko_frequencies(3, L=L, EI=E * I, kGA=kGA, m=rho * A, rhoI=rho * I),
        timoshenko_frequencies(3, L=L, rho=rho, A=A, E=E, I=I, kGA=kGA), rtol=1e-10)
    # stubby beam with a tip body: against lumped Timoshenko FE (Richardson, O(h^2))
    kw = dict(L=L, EI=E * I, kGA=kGA, m=rho * A, rhoI=rho * I, M=0.5 * rho * A * L,
              J=0.05 * rho * A * L**3)
    ref = tip_mass_timoshenko_frequencies(3, **kw)
    f1, f2 = (fe_timoshenko_tip_body(3, n_el=n, **kw) for n in (100, 200))
    np.testing.assert_allclose((4 * f2 - f1) / 3, ref, rtol=1e-8)
    eb = tip_mass_cantilever_frequencies(3, L=L, EI=E * I, m=rho * A, M=kw["M"], J=kw["J"])
    assert np.all(ref < eb) and ref[2] < 0.95 * eb[2]  # shear and rotary inertia matter


def test_tip_body_bad_input():
    with pytest.raises(ValueError, match="M must be"):
        tip_mass_cantilever_frequencies(2, L=1.0, EI=1.0, m=1.0, M=-1.0)
    with pytest.raises(ValueError, match="n must be"):
        tip_mass_cantilever_frequencies(0, L=1.0, EI=1.0, m=1.0)


# ---------------------------------------------------------------------------- L-frame
def fe_l_frame(load, *, L1, L2, EI, GJ, EA, GA, EI_out, GA_out, n_el=3):
    """Stiffness-method model of the L-frame: Timoshenko frame elements, rigid corner."""
    pts = ([(0.0, 0.0, L1 * i / n_el) for i in range(n_el + 1)]
           + [(L2 * i / n_el, 0.0, L1) for i in range(1, n_el + 1)])
    nn = len(pts)
    K = np.zeros((6 * nn, 6 * nn))
    # e2 = y (out of plane) for both members: bending along e2 is out of plane
    prm = dict(EA=EA, GJ=GJ, EI2=EI, EI3=EI_out, GA2=GA_out, GA3=GA)
    for i in range(nn - 1):
        ke = frame_stiffness(pts[i], pts[i + 1], (0.0, 1.0, 0.0), **prm)
        K[6 * i:6 * i + 12, 6 * i:6 * i + 12] += ke
    f = np.zeros(6 * nn)
    f[-6:] = load
    u = np.zeros(6 * nn)
    u[6:] = np.linalg.solve(K[6:, 6:], f[6:])
    return u[-6:]


STIFF = dict(L1=0.7, L2=0.45, EI=2.0, GJ=1.3, EA=4e3, GA=90.0, EI_out=3.1, GA_out=120.0)


@pytest.mark.parametrize("load", [(1.0, 0, 0, 0, 0, 0), (0, 1.0, 0, 0, 0, 0),
                                  (0, 0, 1.0, 0, 0, 0), (0.3, -0.8, 0.5, 0, 0, 0),
                                  (0.2, 0.1, -0.4, 0.3, -0.2, 0.7)])
def test_l_frame_against_stiffness_method(load):
    ref = l_frame_tip(load[:3], load[3:], **STIFF)
    fe = fe_l_frame(np.asarray(load, float), **STIFF)
    scale = np.max(np.abs(fe))
    np.testing.assert_allclose(ref["displacement"], fe[:3], rtol=0, atol=1e-11 * scale)
    np.testing.assert_allclose(ref["rotation"], fe[3:], rtol=0, atol=1e-11 * scale)


def test_l_frame_compliance_properties():
    C = l_frame_compliance(**STIFF)
    np.testing.assert_array_equal(C, C.T)
    assert np.all(np.linalg.eigvalsh(C) > 0)
    # bending only, L1 = L2 = EI = 1 (hand values)
    C = l_frame_compliance(L1=1.0, L2=1.0, EI=1.0, GJ=math.inf)
    assert C[0, 0] == pytest.approx(1 / 3) and C[2, 2] == pytest.approx(4 / 3)
    assert C[0, 2] == pytest.approx(-0.5) and C[1, 1] == pytest.approx(2 / 3)
    # each flexibility adds its own term: torsion of member 1 under Fy
    base = l_frame_tip((0, 1.0, 0), L1=1.0, L2=2.0, EI=1.0)["displacement"][1]
    tors = l_frame_tip((0, 1.0, 0), L1=1.0, L2=2.0, EI=1.0, GJ=4.0)["displacement"][1]
    assert tors - base == pytest.approx(2.0**2 * 1.0 / 4.0)
    with pytest.raises(ValueError, match="GJ must be"):
        l_frame_compliance(L1=1.0, L2=1.0, EI=1.0, GJ=0.0)


# -------------------------------------------------- statically indeterminate beams
def bvp_beam(spans, q, EI, kGA, left, right):
    """Timoshenko beam over consecutive spans (pinned interior supports), solved by
    solve_bvp in the stacked state (w, psi, M, Q) per span on t in [0, 1]; w positive
    in the load direction, M = EI psi', Q = kGA (w' - psi), M' = -Q, Q' = -q."""
    ns = len(spans)

    def rhs(t, y):
        out = np.empty_like(y)
        for k, Lk in enumerate(spans):
            w, psi, M, Q = y[4 * k:4 * k + 4]
            out[4 * k:4 * k + 4] = Lk * np.array(
                [psi + Q / kGA, M / EI, -Q, -q * np.ones_like(w)])
        return out

    def bc(ya, yb):
        res = []
        res += [ya[0], ya[1]] if left == "clamped" else [ya[0], ya[2]]
        for k in range(ns - 1):   # interior support: w = 0 both sides, psi and M continuous
            res += [yb[4 * k], ya[4 * k + 4], yb[4 * k + 1] - ya[4 * k + 5],
                    yb[4 * k + 2] - ya[4 * k + 6]]
        last = 4 * (ns - 1)
        res += [yb[last], yb[last + 2]] if right == "pinned" else [yb[last], yb[last + 1]]
        return np.array(res)

    t = np.linspace(0.0, 1.0, 11)
    sol = solve_bvp(rhs, bc, t, np.zeros((4 * ns, t.size)), tol=1e-10, max_nodes=10000)
    assert sol.success, sol.message
    return sol


def test_propped_cantilever_euler_bernoulli():
    r = propped_cantilever(2.0, L=3.0, EI=5.0)
    assert r["R_prop"] == pytest.approx(3 * 2.0 * 3.0 / 8)
    assert r["R_clamp"] == pytest.approx(5 * 2.0 * 3.0 / 8)
    assert r["M_clamp"] == pytest.approx(2.0 * 9.0 / 8)


@pytest.mark.parametrize("e", [0.0, 0.002, 0.05])
def test_propped_cantilever_against_bvp(e):
    q, L, EI = 1.5, 0.8, 2.0
    kGA = math.inf if e == 0 else EI / (e * L * L)
    r = propped_cantilever(q, L=L, EI=EI, kGA=kGA)
    s = bvp_beam([L], q, EI, kGA, "clamped", "pinned")
    assert r["R_clamp"] == pytest.approx(s.sol(0.0)[3], rel=1e-8)
    assert r["R_prop"] == pytest.approx(-s.sol(1.0)[3], rel=1e-8)
    assert r["M_clamp"] == pytest.approx(s.sol(0.0)[2], rel=1e-8)
    x = np.linspace(0.0, L, 9)
    w = propped_cantilever_deflection(x, q, L=L, EI=EI, kGA=kGA)
    np.testing.assert_allclose(w, s.sol(x / L)[0], rtol=0, atol=1e-9 * np.max(w))
    if e == 0.05:
        assert r["R_prop"] / (3 * q * L / 8) - 1 > 0.03  # the shear correction matters


@pytest.mark.parametrize("spans, e", [((1.0, 1.0), 0.0), ((1.0, 1.0), 0.04),
                                      ((0.6, 1.1), 0.0), ((0.6, 1.1), 0.03)])
def test_two_span_against_bvp(spans, e):
    q, EI = 2.0, 3.0
    kGA = math.inf if e == 0 else EI / (e * spans[0] ** 2)
    r = two_span_beam(q, L1=spans[0], L2=spans[1], EI=EI, kGA=kGA)
    s = bvp_beam(list(spans), q, EI, kGA, "pinned", "pinned")
    assert r["R_A"] == pytest.approx(s.sol(0.0)[3], rel=1e-8)
    assert r["R_B"] == pytest.approx(s.sol(0.0)[7] - s.sol(1.0)[3], rel=1e-8)
    assert r["R_C"] == pytest.approx(-s.sol(1.0)[7], rel=1e-8)
    assert r["M_B"] == pytest.approx(-s.sol(1.0)[2], rel=1e-7)
    assert r["R_A"] + r["R_B"] + r["R_C"] == pytest.approx(q * sum(spans))
    if spans[0] == spans[1]:
        L = spans[0]
        assert r["R_B"] == pytest.approx(q * L * (5 + 12 * e) / (4 + 12 * e))
        if e == 0:
            assert r["R_A"] == pytest.approx(3 * q * L / 8)
            assert r["R_B"] == pytest.approx(10 * q * L / 8)
            assert r["M_B"] == pytest.approx(-q * L * L / 8)


# ---------------------------------------------------------------------- double pendulum
def test_double_pendulum_equal_bars():
    w = double_pendulum_frequencies(m1=2.0, l1=0.5, m2=2.0, l2=0.5, g=9.81)
    np.testing.assert_allclose(w**2 * 0.5 / 9.81, [3 - 6 / math.sqrt(7), 3 + 6 / math.sqrt(7)],
                               rtol=1e-13)
    # light lower bar: each bar swings on its own hinge
    w = double_pendulum_frequencies(m1=1.0, l1=0.5, m2=1e-9, l2=0.3, g=9.81)
    np.testing.assert_allclose(w, np.sqrt([1.5 * 9.81 / 0.5, 1.5 * 9.81 / 0.3]), rtol=1e-7)
    M, K = double_pendulum_matrices(m1=1.0, l1=0.5, m2=0.4, l2=0.3)
    np.testing.assert_allclose(lowest_eigenvalues(K, M, 2),
                               double_pendulum_frequencies(m1=1.0, l1=0.5, m2=0.4, l2=0.3)**2,
                               rtol=1e-12)


@pytest.mark.parametrize("mode", [0, 1])
def test_double_pendulum_against_nonlinear_simulation(mode):
    """Released at a tiny amplitude in a linear mode, the nonlinear equations of motion
    (written here from the Lagrangian of two bars) oscillate at the reference frequency."""
    m1, l1, m2, l2, g = 0.8, 0.6, 0.5, 0.35, 9.81
    J1, J2 = m1 * l1**2 / 12 + 1e-4, m2 * l2**2 / 12   # a bar with section inertia
    w = double_pendulum_frequencies(m1=m1, l1=l1, m2=m2, l2=l2, g=g, J1=J1, J2=J2)[mode]
    a11, a22 = J1 + m1 * l1**2 / 4 + m2 * l1**2, J2 + m2 * l2**2 / 4
    a12 = m2 * l1 * l2 / 2
    k1, k2 = (m1 / 2 + m2) * g * l1, m2 * g * l2 / 2
    # mode shape from the linear problem of this test: (k1 - w^2 a11) x1 = w^2 a12 x2
    shape = np.array([w**2 * a12, k1 - w**2 * a11])
    th0 = 1e-5 * shape / np.max(np.abs(shape))

    def rhs(_t, y):
        t1, t2, v1, v2 = y
        d = t1 - t2
        A = np.array([[a11, a12 * math.cos(d)], [a12 * math.cos(d), a22]])
        b = -np.array([a12 * math.sin(d) * v2**2 + k1 * math.sin(t1),
                       -a12 * math.sin(d) * v1**2 + k2 * math.sin(t2)])
        return [v1, v2, *np.linalg.solve(A, b)]

    T = 2 * math.pi / w
    sol = solve_ivp(rhs, (0.0, 3 * T), [*th0, 0.0, 0.0], rtol=1e-11, atol=1e-18,
                    dense_output=True)
    t = np.linspace(0.0, 3 * T, 301)
    th = sol.sol(t)[:2]
    np.testing.assert_allclose(th, np.outer(th0, np.cos(w * t)), rtol=0, atol=1e-9 * 1e-5)


# ------------------------------------------------------------------------------ the ring
def fe_ring(N, *, R, m, EA, GA_in, GA_out, EI_in, EI_out, GJ, rhoI_in, rhoI_out, rhoJ):
    """Polygon of N straight Timoshenko frame elements with lumped inertia; returns the
    sorted frequencies of the in-plane (ux, uy, thz) and out-of-plane (uz, thx, thy)
    degrees of freedom. Massless rotations (rotary inertia 0) are condensed statically."""
    ang = 2 * math.pi * np.arange(N) / N
    pts = np.c_[R * np.cos(ang), R * np.sin(ang), np.zeros(N)]
    K = np.zeros((6 * N, 6 * N))
    ez = np.array([0.0, 0.0, 1.0])
    for i in range(N):
        j = (i + 1) % N
        e1 = pts[j] - pts[i]
        e2 = np.cross(ez, e1 / np.linalg.norm(e1))      # in plane; e3 = e1 x e2 = ez
        ke = frame_stiffness(pts[i], pts[j], e2, EA=EA, GJ=GJ, EI2=EI_out, EI3=EI_in,
                             GA2=GA_in, GA3=GA_out)
        idx = np.r_[6 * i:6 * i + 6, 6 * j:6 * j + 6]
        K[np.ix_(idx, idx)] += ke
    h = 2 * R * math.sin(math.pi / N)
    Mm = np.zeros((6 * N, 6 * N))
    for i in range(N):
        er = pts[i] / R
        et = np.cross(ez, er)
        Lam = np.vstack([er, et, ez])
        Mm[6 * i:6 * i + 3, 6 * i:6 * i + 3] = m * h * np.eye(3)
        Mm[6 * i + 3:6 * i + 6, 6 * i + 3:6 * i + 6] = h * Lam.T @ np.diag(
            [rhoI_out, rhoJ, rhoI_in]) @ Lam
    out = {}
    for key, local in (("in_plane", [0, 1, 5]), ("out_of_plane", [2, 3, 4])):
        dofs = np.array([6 * i + d for i in range(N) for d in local])
        k, mm = K[np.ix_(dofs, dofs)], Mm[np.ix_(dofs, dofs)]
        massive = np.diag(mm) > 0
        if not np.all(massive):
            a, b = massive, ~massive
            k = k[np.ix_(a, a)] - k[np.ix_(a, b)] @ np.linalg.solve(k[np.ix_(b, b)],
                                                                     k[np.ix_(b, a)])
            mm = mm[np.ix_(a, a)]
        w2 = lowest_eigenvalues(k, mm, 11)
        out[key] = np.sqrt(np.clip(w2, 0.0, None))
    return out


def fe_ring_flexural(waves, **prm):
    """Richardson-extrapolated FE frequencies of the flexural pairs with n waves (meshes
    N and 2N): {n: {"in_plane": ..., "out_of_plane": ...}}."""
    coarse, fine = fe_ring(48, **prm), fe_ring(96, **prm)
    # 3 rigid modes, then pairs n = 2, 3, ...
    return {n: {k: (4 * fine[k][3 + 2 * (n - 2)] - coarse[k][3 + 2 * (n - 2)]) / 3
                for k in fine} for n in waves}


def test_ring_classical_formulas():
    assert ring_inplane_frequencies(2, R=1.0, EI=1.0, m=1.0) == pytest.approx(6 / math.sqrt(5))
    nu = 0.3
    w = ring_out_of_plane_frequencies([2, 3], R=1.0, EI=1.0, GJ=1 / (1 + nu), m=1.0)
    np.testing.assert_allclose(w, [6 / math.sqrt(5.3), 24 / math.sqrt(10.3)], rtol=1e-14)
    np.testing.assert_array_equal(ring_inplane_frequencies(1, R=2.0, EI=3.0, m=1.0), 0.0)
    # torsionally rigid: the out-of-plane formula becomes the in-plane one with n^2 + 0
    w = ring_out_of_plane_frequencies(3, R=1.0, EI=1.0, GJ=math.inf, m=1.0)
    assert w == pytest.approx(8.0)
    with pytest.raises(ValueError, match="n must be"):
        ring_inplane_frequencies(0, R=1.0, EI=1.0, m=1.0)


def test_ring_classical_against_finite_elements():
    """Inextensible-like, unshearable, no rotary inertia: FE polygon vs Hoppe / Michell."""
    R, m, EI_in, EI_out, GJ = 0.4, 0.3, 2.0, 1.5, 1.1
    prm = dict(R=R, m=m, EA=1e7 * EI_in / R**2, GA_in=math.inf, GA_out=math.inf,
               EI_in=EI_in, EI_out=EI_out, GJ=GJ, rhoI_in=0.0, rhoI_out=0.0, rhoJ=0.0)
    for n, fe in fe_ring_flexural((2, 3), **prm).items():
        assert fe["in_plane"] == pytest.approx(
            ring_inplane_frequencies(n, R=R, EI=EI_in, m=m), rel=1e-5)
        assert fe["out_of_plane"] == pytest.approx(
            ring_out_of_plane_frequencies(n, R=R, EI=EI_out, GJ=GJ, m=m), rel=1e-5)


def _ring_section(R, r, E=2e9, nu=0.35, rho=1200.0, kappa=0.9):
    """A circular section of radius r on a ring of radius R (all Cosserat constants)."""
    A, I = math.pi * r * r, math.pi * r**4 / 4
    G = E / (2 * (1 + nu))
    return dict(R=R, m=rho * A, EA=E * A, GA_in=kappa * G * A, GA_out=kappa * G * A,
                EI_in=E * I, EI_out=E * I, GJ=G * 2 * I, rhoI_in=rho * I, rhoI_out=rho * I,
                rhoJ=2 * rho * I)


def test_ring_cosserat_limits():
    # stiff and light sections: the classical formulas, error linear in the ratio
    R, m, EI = 1.0, 1.0, 1.0
    for eps in (1e-6, 1e-8):
        w = ring_cosserat_frequencies(2, R=R, m=m, EA=1 / eps, GA_in=1 / eps, GA_out=1 / eps,
                                      EI_in=EI, EI_out=EI, GJ=1 / 1.3, rhoI_in=eps,
                                      rhoI_out=eps, rhoJ=2 * eps)
        assert w["in_plane"][0] == pytest.approx(
            ring_inplane_frequencies(2, R=R, EI=EI, m=m), rel=10 * eps)
        assert w["out_of_plane"][0] == pytest.approx(
            ring_out_of_plane_frequencies(2, R=R, EI=EI, GJ=1 / 1.3, m=m), rel=10 * eps)
    prm = _ring_section(0.5, 0.02)
    scale = math.sqrt(prm["EI_in"] / (prm["m"] * prm["R"] ** 4))
    w0 = ring_cosserat_frequencies(0, **prm)
    assert w0["in_plane"][0] < 1e-9 * scale and w0["out_of_plane"][0] < 1e-9 * scale
    assert math.sqrt(prm["EA"] / (prm["m"] * prm["R"] ** 2)) in [
        pytest.approx(x, rel=1e-12) for x in w0["in_plane"]]
    w1 = ring_cosserat_frequencies(1, **prm)
    assert w1["in_plane"][0] < 1e-9 * scale and w1["out_of_plane"][0] < 1e-9 * scale
    with pytest.raises(ValueError, match="rhoJ must be"):
        ring_cosserat_frequencies(2, **{**prm, "rhoJ": 0.0})


def test_ring_cosserat_against_finite_elements():
    """A stubby ring (R/r = 8): extension, shear and rotary inertia lower the flexural
    frequencies by 3 % (n = 2) and 6 % (n = 3); the FE polygon with Timoshenko elements
    agrees to its discretization error (~1e-5 after extrapolation)."""
    prm = _ring_section(0.16, 0.02)
    for n, fe in fe_ring_flexural((2, 3), **prm).items():
        ref = ring_cosserat_frequencies(n, **prm)
        assert fe["in_plane"] == pytest.approx(ref["in_plane"][0], rel=2e-5)
        assert fe["out_of_plane"] == pytest.approx(ref["out_of_plane"][0], rel=2e-5)
        classical = ring_inplane_frequencies(n, R=prm["R"], EI=prm["EI_in"], m=prm["m"])
        assert ref["in_plane"][0] < classical * 0.98
