"""The generated rigid-body kernels (rod_body_inertia, _jac, _kinetic; derive/links.py):
Euler-Lagrange / Euler-Poincare of the body's kinetic energy checked by finite
differences in time along a smooth trajectory, the power identity, the power of gravity,
the Jacobian and the AD derivation."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from derive import links as lk
from generated import rod_layout as L
from runtime.model import build
from runtime.model.quaternion import quat_exp, quat_mul, quat_rotation
from tests.kernel_calls import call, call_compiled


def _body(rng, offset: bool = True) -> np.ndarray:
    """Mass, a random symmetric positive definite inertia about the mass centre and a
    mass centre off the node."""
    B = rng.standard_normal((3, 3))
    J = 0.02 * (B @ B.T + 0.3 * np.eye(3))
    e = 0.1 * rng.standard_normal(3) if offset else np.zeros(3)
    return np.r_[rng.uniform(0.5, 2.0), J.ravel(), e]


def _parts(bdy):
    o = L.BODY_OFFSETS
    return bdy[o["M"]], bdy[o["J"]:o["J"] + 9].reshape(3, 3), bdy[o["e"]:o["e"] + 3]


class Trajectory:
    """A smooth motion of the node and the frame: phi(t) a cubic, p(t) a quadratic
    quaternion (not unit: every measure is of degree 0), Omega = 2 Im(conj(p) p')/|p|^2,
    so that R(p)' = R(p) [Omega]x; derivatives in t exact by CasADi AD."""

    def __init__(self, rng):
        t = ca.SX.sym("t")
        c = [rng.standard_normal(3) for _ in range(4)]
        phi = c[0] + c[1] * t + c[2] * t**2 + c[3] * t**3
        q = [rng.standard_normal(4) for _ in range(3)]
        q[0] = q[0] + np.r_[2.5, 0, 0, 0]
        p = q[0] + q[1] * t + q[2] * t**2
        pd = ca.jacobian(p, t)
        conj = ca.vertcat(p[0], -p[1:4])
        prod = ca.vertcat(conj[0] * pd[0] - ca.dot(conj[1:4], pd[1:4]),
                          conj[0] * pd[1:4] + pd[0] * conj[1:4] + ca.cross(conj[1:4], pd[1:4]))
        om = 2 * prod[1:4] / ca.dot(p, p)
        v = ca.jacobian(phi, t)
        self._f = ca.Function("traj", [t], [phi, v, ca.jacobian(v, t), p, om,
                                            ca.jacobian(om, t)])

    def __call__(self, t: float) -> dict[str, np.ndarray]:
        keys = ("phi", "v", "v_dot", "p", "Omega", "Omega_dot")
        return {k: np.array(x).ravel() for k, x in zip(keys, self._f(t), strict=True)}


def _T(v, p, om, bdy):
    return call("rod_body_kinetic", v=v, p=p, Omega=om, g=np.zeros(3), bdy=bdy)["T"][0]


def _T_numpy(v, p, om, bdy):
    M, J, e = _parts(bdy)
    vc = v + quat_rotation(p) @ np.cross(om, e)
    return 0.5 * M * vc @ vc + 0.5 * om @ J @ om


def _rows(s, g, bdy):
    return call("rod_body_inertia", v=s["v"], v_dot=s["v_dot"], p=s["p"], Omega=s["Omega"],
                Omega_dot=s["Omega_dot"], g=g, bdy=bdy)["r"]


def _grad(f, x, h):
    out = np.zeros(len(x))
    for c in range(len(x)):
        e = h * np.eye(len(x))[c]
        out[c] = (f(x + e) - f(x - e)) / (2 * h)
    return out


@pytest.mark.parametrize("offset", [True, False])
def test_rows_are_euler_lagrange_and_euler_poincare_by_differences_in_time(offset):
    """Along a smooth trajectory, the kernel's rows equal the equations formed from the
    kinetic energy by finite differences only: the momenta dT/dv, dT/dOmega by central
    differences of T, their rates by central differences in time, the configuration
    term dT/dtheta along p <- p*exp(theta/2) by central differences, and the potential
    of gravity U = -M g . (phi + R e) likewise."""
    rng = np.random.default_rng(20 + offset)
    bdy, g = _body(rng, offset), np.array([0.3, -9.81, 0.5])
    M, _, e = _parts(bdy)
    traj = Trajectory(rng)

    def momenta(t):
        s = traj(t)
        Pv = _grad(lambda v: _T(v, s["p"], s["Omega"], bdy), s["v"], 1e-3)
        Po = _grad(lambda o: _T(s["v"], s["p"], o, bdy), s["Omega"], 1e-3)
        return Pv, Po

    def dtheta(f, p):
        return _grad(lambda th: f(quat_mul(p, quat_exp(th))), np.zeros(3), 1e-5)

    for t in (-0.3, 0.0, 0.4):
        s = traj(t)
        ht = 1e-4
        (Pv1, Po1), (Pv2, Po2) = momenta(t + ht), momenta(t - ht)
        dPv, dPo = (Pv1 - Pv2) / (2 * ht), (Po1 - Po2) / (2 * ht)
        _, Po = momenta(t)
        dT_dth = dtheta(lambda p: _T(s["v"], p, s["Omega"], bdy), s["p"])
        dU_dth = dtheta(lambda p: -M * g @ quat_rotation(p) @ e, s["p"])
        want = np.r_[dPv - M * g, dPo + np.cross(s["Omega"], Po) - dT_dth + dU_dth]
        got = _rows(s, g, bdy)
        assert np.abs(got - want).max() < 1e-6 * np.abs(want).max()
        assert _T(s["v"], s["p"], s["Omega"], bdy) == pytest.approx(
            _T_numpy(s["v"], s["p"], s["Omega"], bdy), rel=1e-13)


def test_power_identity_and_the_power_of_gravity():
    """dT/dt (central differences in time) = v . r_v + Omega . r_Om without gravity: the
    rows are the forces that move the body; P_g = -dU/dt (U = -M g . (phi + R e)) =
    what gravity contributes to the rows' power."""
    rng = np.random.default_rng(22)
    bdy, g = _body(rng), np.array([0.3, -9.81, 0.5])
    M, _, e = _parts(bdy)
    traj = Trajectory(rng)
    for t in (-0.2, 0.1, 0.5):
        s = traj(t)
        h = 1e-3
        T = [_T(*(traj(t + k * h)[n] for n in ("v", "p", "Omega")), bdy)
             for k in (-2, -1, 1, 2)]
        dT = (T[0] - 8 * T[1] + 8 * T[2] - T[3]) / (12 * h)
        r0 = _rows(s, np.zeros(3), bdy)
        P = s["v"] @ r0[:3] + s["Omega"] @ r0[3:]
        assert abs(P - dT) < 1e-9 * max(abs(dT), abs(P))
        U = [-M * g @ (traj(t + k * h)["phi"] + quat_rotation(traj(t + k * h)["p"]) @ e)
             for k in (-2, -1, 1, 2)]
        dU = (U[0] - 8 * U[1] + 8 * U[2] - U[3]) / (12 * h)
        Pg = call("rod_body_kinetic", v=s["v"], p=s["p"], Omega=s["Omega"], g=g,
                  bdy=bdy)["P_g"][0]
        rg = _rows(s, g, bdy)
        assert Pg == pytest.approx(-dU, rel=1e-9)
        assert Pg == pytest.approx(s["v"] @ (r0[:3] - rg[:3]) + s["Omega"] @ (r0[3:] - rg[3:]),
                                   rel=1e-12)


def test_rows_equal_the_ad_derivation():
    """The kernel's closed form against Euler-Lagrange / Euler-Poincare formed by CasADi
    AD of T and of the potential of gravity (derive.links.body_equations_ad)."""
    S = ca.SX.sym
    v, vd, p, om, omd, g = S("v", 3), S("vd", 3), S("p", 4), S("om", 3), S("omd", 3), \
        S("g", 3)
    b = S("b", lk.N_BODY)
    ref = ca.Function("ref", [v, vd, p, om, omd, g, b],
                      [lk.body_equations_ad(v, vd, p, om, omd, g, b)["r"]])
    rng = np.random.default_rng(23)
    for _ in range(4):
        x = [rng.standard_normal(3), rng.standard_normal(3), rng.standard_normal(4) * 1.3,
             rng.standard_normal(3), rng.standard_normal(3), rng.standard_normal(3),
             _body(rng)]
        want = np.array(ref(*x)).ravel()
        got = call("rod_body_inertia", v=x[0], v_dot=x[1], p=x[2], Omega=x[3],
                   Omega_dot=x[4], g=x[5], bdy=x[6])["r"]
        assert np.abs(got - want).max() < 1e-13 * np.abs(want).max()


def test_jacobian_equals_central_differences():
    """c_y dr/d(v, p, Omega) + c_j dr/d(v', p', Omega') in the columns (v, p, Omega); the
    rows do not depend on v nor on p' (the body has no kinematic row of its own)."""
    rng = np.random.default_rng(24)
    x = {"v": rng.standard_normal(3), "v_dot": rng.standard_normal(3),
         "p": rng.standard_normal(4), "Omega": rng.standard_normal(3),
         "Omega_dot": rng.standard_normal(3), "g": rng.standard_normal(3), "bdy": _body(rng)}
    cy, cj = 0.7, 43.0
    J = call("rod_body_inertia_jac", **x, c_y=cy, c_j=cj)["J"]
    assert J.shape == (6, 10)

    def r(**kw):
        return call("rod_body_inertia", **{**x, **kw})["r"]

    fd = np.zeros((6, 10))
    for name, dname in (("v", "v_dot"), ("p", None), ("Omega", "Omega_dot")):
        k = L.BODY_JAC_OFFSETS[name]
        for c in range(len(x[name])):
            h = 1e-6
            e = h * np.eye(len(x[name]))[c]
            fd[:, k + c] = cy * (r(**{name: x[name] + e}) - r(**{name: x[name] - e})) / (2 * h)
            if dname:
                fd[:, k + c] += cj * (r(**{dname: x[dname] + e})
                                      - r(**{dname: x[dname] - e})) / (2 * h)
    assert np.abs(J - fd).max() < 1e-7 * np.abs(J).max()
    kv, kp = L.BODY_JAC_OFFSETS["v"], L.BODY_JAC_OFFSETS["p"]
    assert not call("rod_body_inertia_jac", **x, c_y=1.0, c_j=0.0)["J"][:, kv:kv + 3].any()
    assert not call("rod_body_inertia_jac", **x, c_y=0.0, c_j=1.0)["J"][:, kp:kp + 4].any()


def test_a_body_with_its_mass_centre_at_the_node_is_a_point_mass_and_a_rigid_body():
    """e = 0: r_v = M (v' - g), r_Om = J Omega' + Omega x J Omega (Euler's equations)."""
    rng = np.random.default_rng(25)
    bdy = _body(rng, offset=False)
    M, J, _ = _parts(bdy)
    s = {"v": rng.standard_normal(3), "v_dot": rng.standard_normal(3),
         "p": rng.standard_normal(4), "Omega": rng.standard_normal(3),
         "Omega_dot": rng.standard_normal(3)}
    g = rng.standard_normal(3)
    r = _rows(s, g, bdy)
    assert np.allclose(r[:3], M * (s["v_dot"] - g), rtol=1e-14, atol=0)
    want = J @ s["Omega_dot"] + np.cross(s["Omega"], J @ s["Omega"])
    assert np.allclose(r[3:], want, rtol=1e-13, atol=1e-15)


def test_compiled_library_exports_the_body_kernels():
    lib = build.load_library()
    if lib is None:
        pytest.skip("no C compiler")
    rng = np.random.default_rng(26)
    x = {"v": rng.standard_normal(3), "v_dot": rng.standard_normal(3),
         "p": rng.standard_normal(4), "Omega": rng.standard_normal(3),
         "Omega_dot": rng.standard_normal(3), "g": rng.standard_normal(3), "bdy": _body(rng),
         "c_y": 1.0, "c_j": 17.0}
    for name in ("rod_body_inertia", "rod_body_inertia_jac", "rod_body_kinetic"):
        f_in = {k: x[k] for k in L.KERNELS[name]["inputs"]}
        got, want = call_compiled(lib, name, **f_in), call(name, **f_in)
        for k in want:
            assert np.allclose(got[k], want[k], rtol=1e-13, atol=1e-13 * np.abs(want[k]).max())
