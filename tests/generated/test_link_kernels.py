"""The generated link kernels (rod_link_forces, _jac, _diagnostics; derive/links.py):
the AD of their W and D, central differences, objectivity, the power balance, the side
made of two frames and the joints they model."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from derive import links as lk
from generated import rod_layout as L
from runtime.model import build
from runtime.model.quaternion import quat_exp, quat_mul, quat_rotation
from tests.kernel_calls import call, call_compiled

SIDES = [(True, True), (True, False), (False, True), (False, False)]
ID = np.array([1.0, 0.0, 0.0, 0.0])


def _conj(p):
    return np.r_[p[0], -p[1:]]


def _unit(rng):
    q = rng.standard_normal(4)
    return q / np.linalg.norm(q)


def _side(rng, two: bool):
    """A side's two frames: a random non-unit quaternion and a neighbour within ~0.4 rad
    (adjacent segments at an interior node), or zero (one frame)."""
    p1 = _unit(rng) * rng.uniform(0.7, 1.4)
    if not two:
        return p1, np.zeros(4)
    return p1, quat_mul(p1, quat_exp(0.4 * rng.standard_normal(3))) * rng.uniform(0.7, 1.4)


def _params(K, V, d0, r0):
    return np.concatenate([K.ravel(), V.ravel(), d0, r0])


def _random_case(rng, two_a=True, two_b=True, K=None, V=None) -> dict:
    """A link between two random points and sides: K symmetric positive definite, V
    positive semi-definite of rank 4, the reference ~0.5 rad and ~0.1 m away."""
    pa1, pa2 = _side(rng, two_a)
    pb1, pb2 = _side(rng, two_b)
    phi_a, phi_b = rng.standard_normal(3), rng.standard_normal(3)
    pa, pb = pa1 + pa2, pb1 + pb2
    B = rng.standard_normal((6, 6))
    K = B @ B.T + 0.2 * np.eye(6) if K is None else K
    C = rng.standard_normal((6, 4))
    V = 0.1 * C @ C.T if V is None else V
    d0 = quat_rotation(pa).T @ (phi_b - phi_a) + 0.1 * rng.standard_normal(3)
    r0 = quat_mul(quat_mul(_conj(pa), pb), quat_exp(0.5 * rng.standard_normal(3)))
    om = [rng.standard_normal(3) * (1.0 if p.any() else 0.0) for p in (pa1, pa2, pb1, pb2)]
    return {"phi_a": phi_a, "phi_b": phi_b, "v_a": rng.standard_normal(3),
            "v_b": rng.standard_normal(3), "p_a1": pa1, "p_a2": pa2, "p_b1": pb1,
            "p_b2": pb2, "Omega_a1": om[0], "Omega_a2": om[1], "Omega_b1": om[2],
            "Omega_b2": om[3], "lnk": _params(K, V, d0, r0 * rng.uniform(0.5, 2.0))}


def _with_lnk(x, K=None, V=None):
    lnk = x["lnk"].copy()
    if K is not None:
        lnk[L.LINK_OFFSETS["K"]:L.LINK_OFFSETS["K"] + 36] = np.ravel(K)
    if V is not None:
        lnk[L.LINK_OFFSETS["V"]:L.LINK_OFFSETS["V"] + 36] = np.ravel(V)
    return {**x, "lnk": lnk}


def _Q(x):
    return call("rod_link_forces", **x)["Q"]


def _diag(x):
    return call("rod_link_diagnostics", **x)


def _block(Q, name):
    k = L.LINK_FORCE_OFFSETS[name]
    return Q[k:k + 3]


FRAMES = (("p_a1", "Omega_a1", "T_a1"), ("p_a2", "Omega_a2", "T_a2"),
          ("p_b1", "Omega_b1", "T_b1"), ("p_b2", "Omega_b2", "T_b2"))


def _rel(a, b):
    return np.abs(np.asarray(a) - np.asarray(b)).max() / max(np.abs(b).max(), 1e-300)


def test_layout_tables_name_the_kernels_blocks_and_columns():
    f = lk.link_kernels()[1]
    assert f.name() == "rod_link_forces_jac" and f.size_out(0) == (18, 40)
    assert L.N_LINK_FORCES == 18 and L.N_LINK_JAC_COLUMNS == 40 and L.N_LINK == 79
    assert [n for n, _ in L.LINK_JAC_COLUMNS] == [
        "phi_a", "phi_b", "p_a1", "p_a2", "p_b1", "p_b2", "v_a", "v_b", "Omega_a1",
        "Omega_a2", "Omega_b1", "Omega_b2"]
    assert L.LINK_OFFSETS == lk.LINK_OFFSETS and L.BODY_OFFSETS == lk.BODY_OFFSETS
    assert [L.KERNELS["rod_link_forces"]["inputs"][n][0] for n, _ in L.LINK_JAC_COLUMNS] \
        == [s for _, s in L.LINK_JAC_COLUMNS]


@pytest.mark.parametrize("two_a,two_b", SIDES)
def test_forces_torques_and_rates_equal_casadi_ad_of_W_and_D(two_a, two_b):
    """The kernel's closed forms (generated) against the AD of the definitions: W, D,
    e, the exact rate and Q = (-dW/dphi - dD/dv, torque_from_gradient - dD/dOmega)."""
    s = lk.link_symbols()
    fun = lk.link_functionals(s)
    ref = ca.Function("ref", list(s.inputs().values()),
                      [lk.link_forces_ad(s), fun["W"], fun["D"], fun["e"], fun["edot"]],
                      list(s.inputs()), ["Q", "W", "D", "e", "edot"])
    rng = np.random.default_rng(10)
    for _ in range(4):
        x = _random_case(rng, two_a, two_b)
        want = {k: np.array(v).ravel() for k, v in ref(**x).items()}
        d = _diag(x)
        assert _rel(_Q(x), want["Q"]) < 1e-12
        for k in ("W", "D", "e"):
            assert _rel(d[k], want[k]) < 1e-12, k
        K, V = (x["lnk"][L.LINK_OFFSETS[n]:L.LINK_OFFSETS[n] + 36].reshape(6, 6)
                for n in ("K", "V"))
        assert _rel(d["s"], K @ want["e"] + V @ want["edot"]) < 1e-12


def _rotated(x, key, theta):
    return {**x, key: quat_mul(x[key], quat_exp(theta))}


@pytest.mark.parametrize("two_a,two_b", SIDES)
def test_forces_and_torques_are_central_differences_of_W_and_D(two_a, two_b):
    """Elastic Q (V = 0) = -dW along the points' displacements and the frames' rotation
    increments p <- p*exp(theta/2) (central differences of the diagnostics' W); viscous
    Q (K = 0) = -dD/d(v, Omega) (D is quadratic in them: differences exact to rounding)."""
    rng = np.random.default_rng(11)
    x = _random_case(rng, two_a, two_b)
    xe, xv = _with_lnk(x, V=np.zeros((6, 6))), _with_lnk(x, K=np.zeros((6, 6)))
    Qe, Qv = _Q(xe), _Q(xv)
    assert _rel(Qe + Qv, _Q(x)) < 1e-13
    h = 1e-6
    fd_e, fd_v = np.zeros(18), np.zeros(18)
    for k, (phi, v) in enumerate((("phi_a", "v_a"), ("phi_b", "v_b"))):
        for c in range(3):
            dx = h * np.eye(3)[c]
            fd_e[3 * k + c] = -(_diag({**xe, phi: xe[phi] + dx})["W"]
                                - _diag({**xe, phi: xe[phi] - dx})["W"])[0] / (2 * h)
            fd_v[3 * k + c] = -(_diag({**xv, v: xv[v] + dx})["D"]
                                - _diag({**xv, v: xv[v] - dx})["D"])[0] / (2 * h)
    for p, om, T in FRAMES:
        k = L.LINK_FORCE_OFFSETS[T]
        for c in range(3):
            dth = h * np.eye(3)[c]
            fd_e[k + c] = -(_diag(_rotated(xe, p, dth))["W"]
                            - _diag(_rotated(xe, p, -dth))["W"])[0] / (2 * h)
            fd_v[k + c] = -(_diag({**xv, om: xv[om] + dth})["D"]
                            - _diag({**xv, om: xv[om] - dth})["D"])[0] / (2 * h)
    assert np.abs(Qe - fd_e).max() < 1e-7 * np.abs(Qe).max()
    assert np.abs(Qv - fd_v).max() < 1e-7 * np.abs(Qv).max()


@pytest.mark.parametrize("two_a,two_b", SIDES)
def test_jacobian_equals_central_differences_of_Q(two_a, two_b):
    rng = np.random.default_rng(12)
    x = _random_case(rng, two_a, two_b)
    J = call("rod_link_forces_jac", **x)["dQ_dx"]
    assert J.shape == (18, 40)
    fd = np.zeros((18, 40))
    for name, size in L.LINK_JAC_COLUMNS:
        k = L.LINK_JAC_OFFSETS[name]
        for c in range(size):
            h = 1e-6 * max(1.0, abs(x[name][c]))
            e = h * np.eye(size)[c]
            fd[:, k + c] = (_Q({**x, name: x[name] + e}) - _Q({**x, name: x[name] - e})) / (2 * h)
    assert np.abs(J - fd).max() < 2e-7 * np.abs(J).max()
    if not two_a:      # a zero second frame: its torque moves only with its own p
        rows = J[L.LINK_FORCE_OFFSETS["T_a2"]:L.LINK_FORCE_OFFSETS["T_a2"] + 3]
        k = L.LINK_JAC_OFFSETS["p_a2"]
        assert not np.delete(rows, np.s_[k:k + 4], axis=1).any() and rows[:, k:k + 4].any()


def test_a_zero_second_frame_gets_exactly_zero_torque_and_changes_nothing():
    """p_x2 = 0: T_x2 is exactly 0 whatever Omega_x2, and Q is that of the frame p_x1
    alone; a side split into two shares of one frame with one Omega has the same forces
    and the shares' torques sum to the single frame's."""
    rng = np.random.default_rng(13)
    x = _random_case(rng, False, False)
    Q = _Q(x)
    x_om = {**x, "Omega_a2": rng.standard_normal(3), "Omega_b2": rng.standard_normal(3)}
    Q_om = _Q(x_om)
    for T in ("T_a2", "T_b2"):
        assert np.all(_block(Q, T) == 0.0) and np.all(_block(Q_om, T) == 0.0)
    assert _rel(Q_om, Q) < 1e-14
    lam, mu = 0.3, 0.8
    split = {**x, "p_a1": lam * x["p_a1"], "p_a2": (1 - lam) * x["p_a1"],
             "Omega_a2": x["Omega_a1"], "p_b1": mu * x["p_b1"], "p_b2": 2.0 * x["p_b1"],
             "Omega_b2": x["Omega_b1"]}
    Qs = _Q(split)
    for f in ("f_a", "f_b"):
        assert _rel(_block(Qs, f), _block(Q, f)) < 1e-13
    assert _rel(_block(Qs, "T_a1") + _block(Qs, "T_a2"), _block(Q, "T_a1")) < 1e-13
    assert _rel(_block(Qs, "T_b1") + _block(Qs, "T_b2"), _block(Q, "T_b1")) < 1e-13
    assert _rel(_block(Qs, "T_a1"), lam * _block(Q, "T_a1")) < 1e-13


@pytest.mark.parametrize("two_a,two_b", SIDES)
def test_objectivity(two_a, two_b):
    """A rigid rotation and translation of everything leaves e, the rate and the
    resultant unchanged, rotates the forces and leaves the material torques; a
    superposed rigid spin (v += w x phi, Omega += R^T w) changes no rate and no force;
    the forces and the torques (spatial: R(p_k) T_k) have no resultant."""
    rng = np.random.default_rng(14)
    x = _random_case(rng, two_a, two_b)
    q = _unit(rng)
    R, c = quat_rotation(q), rng.standard_normal(3)
    y = {**x, "phi_a": R @ x["phi_a"] + c, "phi_b": R @ x["phi_b"] + c,
         "v_a": R @ x["v_a"], "v_b": R @ x["v_b"]}
    for p, _, _ in FRAMES:
        y[p] = quat_mul(q, x[p])
    d, dy = _diag(x), _diag(y)
    for k in ("W", "D", "e", "s"):
        assert _rel(dy[k], d[k]) < 1e-12, k
    Q, Qy = _Q(x), _Q(y)
    for f in ("f_a", "f_b"):
        assert _rel(_block(Qy, f), R @ _block(Q, f)) < 1e-12
    for _, _, T in FRAMES:
        assert np.abs(_block(Qy, T) - _block(Q, T)).max() < 1e-12 * np.abs(Q).max()
    w = rng.standard_normal(3)
    z = {**x, "v_a": x["v_a"] + np.cross(w, x["phi_a"]),
         "v_b": x["v_b"] + np.cross(w, x["phi_b"])}
    for p, om, _ in FRAMES:
        if x[p].any():
            z[om] = x[om] + quat_rotation(x[p]).T @ w
    dz = _diag(z)
    assert _rel(dz["s"], d["s"]) < 1e-12 and _rel(dz["D"], d["D"]) < 1e-12
    assert _rel(_Q(z), Q) < 1e-12
    # hence the link's loads are in equilibrium: no net force, no net moment
    assert np.abs(_block(Q, "f_a") + _block(Q, "f_b")).max() == 0.0
    moment = (np.cross(x["phi_a"], _block(Q, "f_a")) + np.cross(x["phi_b"], _block(Q, "f_b"))
              + sum(quat_rotation(x[p]) @ _block(Q, T) for p, _, T in FRAMES if x[p].any()))
    assert np.abs(moment).max() < 1e-12 * np.abs(Q).max() * (1 + np.abs(x["phi_a"]).max()
                                                              + np.abs(x["phi_b"]).max())


def _flow(x, t):
    """The state after time t of the motion phi' = v, p_k' = 1/2 p_k*(0, Omega_k) with
    constant velocities (exact)."""
    y = {**x, "phi_a": x["phi_a"] + t * x["v_a"], "phi_b": x["phi_b"] + t * x["v_b"]}
    for p, om, _ in FRAMES:
        y[p] = quat_mul(x[p], quat_exp(t * x[om]))
    return y


@pytest.mark.parametrize("two_a,two_b", SIDES)
def test_power_of_the_forces_is_minus_the_rate_of_W_minus_2D(two_a, two_b):
    """sum f . v + sum T_k . Omega_k = -dW/dt - 2D along the flow (dW/dt by a
    fourth-order central difference in time): the balance the system's audit uses."""
    rng = np.random.default_rng(15)
    for _ in range(3):
        x = _random_case(rng, two_a, two_b)
        Q = _Q(x)
        P = (_block(Q, "f_a") @ x["v_a"] + _block(Q, "f_b") @ x["v_b"]
             + sum(_block(Q, T) @ x[om] for _, om, T in FRAMES))
        h = 1e-3
        W = [_diag(_flow(x, t))["W"][0] for t in (-2 * h, -h, h, 2 * h)]
        dW = (W[0] - 8 * W[1] + 8 * W[2] - W[3]) / (12 * h)
        D = _diag(x)["D"][0]
        assert abs(P - (-dW - 2 * D)) < 1e-8 * max(abs(P), abs(dW), 2 * D)


# -- the joints of the assembly as links --------------------------------------------------


def test_weld_of_two_frames_is_the_rods_joint():
    """Two rods sharing one node, their end segments welded: translation block 0, the
    rotation block the joint's C_M/h_j and V_M/h_j, r0 = 1; the torques on the two
    frames are the rod joint kernel's (rod_joint_torques) to rounding."""
    rng = np.random.default_rng(16)
    hj, CM, VM = 0.05, np.array([2.0, 3.0, 1.5]), np.array([0.02, 0.01, 0.03])
    pa = _unit(rng) * 1.1
    pb = quat_mul(pa, quat_exp(0.3 * rng.standard_normal(3))) * 0.9
    oa, ob = rng.standard_normal(3), rng.standard_normal(3)
    K, V = np.zeros((6, 6)), np.zeros((6, 6))
    K[3:, 3:], V[3:, 3:] = np.diag(CM / hj), np.diag(VM / hj)
    phi = rng.standard_normal(3)
    x = {"phi_a": phi, "phi_b": phi, "v_a": np.zeros(3), "v_b": np.zeros(3),
         "p_a1": pa, "p_a2": np.zeros(4), "p_b1": pb, "p_b2": np.zeros(4),
         "Omega_a1": oa, "Omega_a2": np.zeros(3), "Omega_b1": ob, "Omega_b2": np.zeros(3),
         "lnk": _params(K, V, np.zeros(3), ID)}
    jnt = np.zeros(L.N_JOINT)
    jnt[L.JOINT_OFFSETS["h"]] = hj
    jnt[L.JOINT_OFFSETS["C_M"]:L.JOINT_OFFSETS["C_M"] + 3] = CM
    jnt[L.JOINT_OFFSETS["V_M"]:L.JOINT_OFFSETS["V_M"] + 3] = VM
    T = call("rod_joint_torques", p_a=pa, p_b=pb, Omega_a=oa, Omega_b=ob, jnt=jnt,
             m_q=np.zeros(3))["T"]
    Q = _Q(x)
    assert _rel(np.r_[_block(Q, "T_a1"), _block(Q, "T_b1")], T) < 1e-13
    assert not Q[:6].any()


def test_ball_with_isotropic_stiffness_and_a_free_hinge():
    """A ball (rotation block k I): W = 2 k tan^2(theta/2) for a relative rotation theta
    about any axis, no force. A hinge with axis a (P's frame) and no stiffness about it:
    turning b about a by 2.5 rad at any rate costs no energy, dissipates nothing and
    exerts nothing; a tilt off the axis is resisted."""
    rng = np.random.default_rng(17)
    k = 3.0
    pa = _unit(rng)
    K = np.zeros((6, 6))
    K[3:, 3:] = k * np.eye(3)
    phi = rng.standard_normal(3)
    for theta in (0.1, 1.0, 2.5):
        axis = rng.standard_normal(3)
        axis /= np.linalg.norm(axis)
        pb = quat_mul(pa, quat_exp(theta * axis))
        x = {"phi_a": phi, "phi_b": phi, "v_a": np.zeros(3), "v_b": np.zeros(3),
             "p_a1": pa, "p_a2": np.zeros(4), "p_b1": pb, "p_b2": np.zeros(4),
             "Omega_a1": np.zeros(3), "Omega_a2": np.zeros(3), "Omega_b1": np.zeros(3),
             "Omega_b2": np.zeros(3), "lnk": _params(K, np.zeros((6, 6)), np.zeros(3), ID)}
        assert _diag(x)["W"][0] == pytest.approx(2 * k * np.tan(theta / 2) ** 2, rel=1e-13)
        assert not _Q(x)[:6].any()
    a = rng.standard_normal(3)
    a /= np.linalg.norm(a)
    Pperp = np.eye(3) - np.outer(a, a)
    Kh, Vh = np.zeros((6, 6)), np.zeros((6, 6))
    Kh[:3, :3], Kh[3:, 3:], Vh[3:, 3:] = 50 * np.eye(3), 4.0 * Pperp, 0.1 * Pperp
    r0 = _unit(rng)
    pb0 = quat_mul(pa, r0)
    for theta in (0.5, 2.5, -2.5):
        pb = quat_mul(quat_mul(pa, quat_exp(theta * a)), r0)   # turned about a (P's frame)
        om_b = quat_rotation(pb).T @ quat_rotation(pa) @ (1.7 * a)   # spinning about a
        x = {"phi_a": phi, "phi_b": phi, "v_a": np.zeros(3), "v_b": np.zeros(3),
             "p_a1": pa, "p_a2": np.zeros(4), "p_b1": pb, "p_b2": np.zeros(4),
             "Omega_a1": np.zeros(3), "Omega_a2": np.zeros(3), "Omega_b1": om_b,
             "Omega_b2": np.zeros(3), "lnk": _params(Kh, Vh, np.zeros(3), r0)}
        d = _diag(x)
        er = np.linalg.norm(d["e"][3:])          # 2 tan(theta/2): what a stiff axis would see
        rate = 1.7 * (1 + er**2 / 4)              # |edot_r|, A a = (1 + |u|^2) a
        assert abs(d["W"][0]) < 1e-14 * 4.0 * er**2 and abs(d["D"][0]) < 1e-14 * 0.1 * rate**2
        assert np.abs(_Q(x)).max() < 1e-14 * 4.0 * er * (1 + er**2 / 4)
        tilt = {**x, "p_b1": quat_mul(quat_exp(0.01 * np.cross(a, rng.standard_normal(3))),
                                      pb), "Omega_b1": np.zeros(3)}
        assert _diag(tilt)["W"][0] > 1e-5 and np.abs(_Q(tilt)[6:]).max() > 1e-3
    assert np.allclose(quat_mul(_conj(pa), pb0), r0)


def test_ground_clamp_at_an_interior_node_holds_the_node_frame():
    """A node's frame given by its two segments p_i = m exp(-theta), p_i+1 = m exp(+theta)
    (the slerp midpoint is m): clamped to a ground frame g with r0 = conj(m) g, bending the
    segments symmetrically about m leaves the clamp unstrained; turning the node by delta
    (spatial) gives e_r = -2 tan(|delta|/2) R(m)^T delta/|delta| (P = the node)."""
    rng = np.random.default_rng(18)
    m, g = _unit(rng), _unit(rng) * 3.0
    K = np.diag([10.0, 10.0, 10.0, 2.0, 2.0, 2.0])
    phi = rng.standard_normal(3)
    base = {"phi_a": phi, "phi_b": phi, "v_a": np.zeros(3), "v_b": np.zeros(3),
            "p_b1": g, "p_b2": np.zeros(4), "Omega_a1": np.zeros(3),
            "Omega_a2": np.zeros(3), "Omega_b1": np.zeros(3), "Omega_b2": np.zeros(3),
            "lnk": _params(K, 0.1 * K, np.zeros(3), quat_mul(_conj(m), g))}
    for theta in (0.05 * rng.standard_normal(3), 0.4 * rng.standard_normal(3)):
        x = {**base, "p_a1": quat_mul(m, quat_exp(-theta)) * 0.9,
             "p_a2": quat_mul(m, quat_exp(theta)) * 0.9}
        assert np.abs(_diag(x)["e"]).max() < 1e-15 and np.abs(_Q(x)).max() < 1e-14
        delta = 0.3 * rng.standard_normal(3)
        turned = {**x, "p_a1": quat_mul(quat_exp(delta), x["p_a1"]),
                  "p_a2": quat_mul(quat_exp(delta), x["p_a2"])}
        n = np.linalg.norm(delta)
        want = -2 * np.tan(n / 2) * quat_rotation(m).T @ delta / n
        assert np.abs(_diag(turned)["e"][3:] - want).max() < 1e-14
        Q = _Q(turned)
        # the torque on the node is shared by its two segments, the ground's opposes it
        Ta = _block(Q, "T_a1") + _block(Q, "T_a2")
        Rg = quat_rotation(g)
        spatial_a = quat_rotation(turned["p_a1"] + turned["p_a2"]) @ Ta
        assert np.abs(spatial_a + Rg @ _block(Q, "T_b1")).max() < 1e-12 * np.abs(Ta).max()


def test_compiled_library_exports_the_link_kernels():
    """rod_kernels.c still compiles with the link kernels; the library's functions are
    the serialised ones (to rounding)."""
    lib = build.load_library()
    if lib is None:
        pytest.skip("no C compiler")
    x = _random_case(np.random.default_rng(19))
    for name in ("rod_link_forces", "rod_link_forces_jac", "rod_link_diagnostics"):
        got, want = call_compiled(lib, name, **x), call(name, **x)
        for k in want:
            assert np.allclose(got[k], want[k], rtol=1e-13, atol=1e-13 * np.abs(want[k]).max())
