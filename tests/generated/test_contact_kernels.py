"""The generated rod-obstacle contact kernels (rod_contact_<kind>, _jac, _diagnostics,
_bound; derive/contact.py): the AD of their energy, dissipation function and friction's
virtual power, central differences, the power identity with a moving obstacle,
objectivity, the analytic normal force, stick, slip and rolling, the obstacles' shapes."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from derive import contact as ct
from generated import rod_layout as L
from runtime.model.quaternion import quat_exp, quat_mul, quat_rotation
from tests.kernel_calls import call

KINDS = L.OBSTACLE_KINDS
#: surfaces sampled per kind: (kind, where)
SURFACES = [("plane", "face"), ("sphere", "face"), ("cylinder", "mantle"),
            ("cylinder", "cap"), ("cylinder", "infinite"), ("pipe", "mantle"),
            ("pipe", "infinite")]
O, K = L.OBS_OFFSETS, L.CNT_OFFSETS
R_OBS, LENGTH, EDGE = 0.5, 1.2, 0.004
RADIUS, DELTA = 0.02, 0.01


def _unit(v):
    return v / np.linalg.norm(v)


def _perp(a, rng):
    return _unit(np.cross(a, rng.standard_normal(3)))


def _set(vec, offsets, **fields):
    out = vec.copy()
    for name, value in fields.items():
        value = np.atleast_1d(np.asarray(value, dtype=float))
        out[offsets[name]:offsets[name] + value.size] = value
    return out


def _cnt(k=1e4, delta=DELTA, c=30.0, mu=0.4, v_s=0.3, r=RADIUS, h=0.1):
    return _set(np.zeros(L.N_CNT), K, k=k, delta=delta, c=c, mu=mu, v_s=v_s, r=r, h=h)


def _obstacle(rng, moving=True, length=LENGTH):
    """A random pose (non-unit quaternion), motion, point and axis of any length."""
    return _set(np.zeros(L.N_OBS), O, c=rng.standard_normal(3),
                q=_unit(rng.standard_normal(4)) * rng.uniform(0.7, 1.3),
                v=rng.standard_normal(3) if moving else np.zeros(3),
                w=rng.standard_normal(3) if moving else np.zeros(3),
                point=0.3 * rng.standard_normal(3),
                axis=_unit(rng.standard_normal(3)) * rng.uniform(0.5, 2.0),
                radius=R_OBS, length=length, edge=EDGE)


def _field(obs, name, size=3):
    return obs[O[name]:O[name] + size]


def _surface(kind, where, obs, rng):
    """A point of the obstacle's surface and its outward normal (obstacle frame)."""
    P0, a = _field(obs, "point"), _unit(_field(obs, "axis"))
    if kind == "plane":
        return P0 + 0.3 * _perp(a, rng), a
    if kind == "sphere":
        n = _unit(rng.standard_normal(3))
        return P0 + R_OBS * n, n
    perp = _perp(a, rng)
    if where == "cap":
        return P0 + LENGTH * a + 0.4 * R_OBS * perp, a
    z = rng.uniform(0.35, 0.65) * LENGTH
    if kind == "cylinder":
        return P0 + z * a + R_OBS * perp, perp
    return P0 + z * a + R_OBS * perp, -perp


def _case(kind, where, rng, moving=True, gaps=(-2 * DELTA, DELTA), h=0.1) -> dict:
    """A segment of length h near the obstacle's surface: its ends at gaps drawn from
    ``gaps``, tangent to the surface (any direction in the tangent plane), random
    velocities, frame and angular velocity; the obstacle moving."""
    obs = _obstacle(rng, moving, length=0.0 if where == "infinite" else LENGTH)
    if where == "infinite":
        where = "mantle"
    point, n = _surface(kind, where, obs, rng)
    t = _perp(n, rng)
    ends = [point + s * t * h / 2 + n * (RADIUS + rng.uniform(*gaps)) for s in (-1, 1)]
    qo, c = _field(obs, "q", 4), _field(obs, "c")
    phi_a, phi_b = (c + quat_rotation(qo) @ e for e in ends)
    return {"phi_a": phi_a, "phi_b": phi_b, "v_a": rng.standard_normal(3),
            "v_b": rng.standard_normal(3),
            "p": _unit(rng.standard_normal(4)) * rng.uniform(0.7, 1.3),
            "Omega": rng.standard_normal(3), "obs": obs,
            "cnt": _cnt(h=h * rng.uniform(0.8, 1.2))}


def _Q(kind, x):
    return call(f"rod_contact_{kind}", **x)["Q"]


def _diag(kind, x):
    return call(f"rod_contact_{kind}_diagnostics", **x)


def _with(x, **cnt):
    return {**x, "cnt": _set(x["cnt"], K, **cnt)}


def _rel(a, b):
    return np.abs(np.asarray(a) - np.asarray(b)).max() / max(np.abs(b).max(), 1e-300)


def _velocities(x):
    return np.r_[x["v_a"], x["v_b"], x["Omega"]]


def test_layout_tables_name_the_kernels_blocks_and_columns():
    assert L.NQ == ct.NQ == 3 and len(L.QUADRATURE[0]) == L.NQ
    assert L.QUADRATURE == ((0.0, 0.5, 1.0), (1 / 6, 2 / 3, 1 / 6))
    assert L.OBS_OFFSETS == ct.OBS_OFFSETS and L.CNT_OFFSETS == ct.CNT_OFFSETS
    assert L.N_CONTACT_FORCES == 9 and L.N_CONTACT_JAC_COLUMNS == 19
    assert [n for n, _ in L.CONTACT_JAC_COLUMNS] == ["phi_a", "phi_b", "p", "v_a", "v_b",
                                                     "Omega"]
    for kind in KINDS:
        sig = L.KERNELS[f"rod_contact_{kind}"]
        assert list(sig["inputs"]) == ["phi_a", "phi_b", "v_a", "v_b", "p", "Omega", "obs",
                                       "cnt"]
        assert [sig["inputs"][n][0] for n, _ in L.CONTACT_JAC_COLUMNS] \
            == [s for _, s in L.CONTACT_JAC_COLUMNS]
        assert L.KERNELS[f"rod_contact_{kind}_jac"]["outputs"]["dQ_dx"] == [9, 19]
        assert L.KERNELS[f"rod_contact_{kind}_diagnostics"]["outputs"]["points"] == [L.NQ, 4]
    for n in (2, 3, 4):     # the Gauss-Lobatto rules integrate x^k exactly to 2n - 3
        xs, ws = ct.gauss_lobatto(n)
        for k in range(2 * n - 2):
            assert sum(w * x**k for x, w in zip(xs, ws, strict=True)) == \
                pytest.approx(1 / (k + 1), rel=1e-15)


@pytest.mark.parametrize("kind,where", SURFACES)
def test_forces_equal_casadi_ad_of_the_definitions(kind, where):
    """The kernel's closed forms against the definitions (derive.contact): E of the gaps,
    D with gdot by forward AD along the rod's and the obstacle's motion, Q = -dE/dphi -
    dD/dv plus the gradient of the friction's virtual power."""
    s = ct.contact_symbols()
    d = ct.contact_definitions(s, kind)
    ref = ca.Function("ref", list(s.inputs().values()),
                      [ct.contact_forces_ad(s, kind), d["E"], d["D"], d["P_fric"]],
                      list(s.inputs()), ["Q", "E", "D", "P_fric"])
    rng = np.random.default_rng(20)
    for _ in range(3):
        x = _case(kind, where, rng)
        want = {k: np.array(v).ravel() for k, v in ref(**x).items()}
        got = _diag(kind, x)
        assert want["E"][0] > 1e-3 and want["P_fric"][0] > 1e-3     # in contact, slipping
        assert _rel(_Q(kind, x), want["Q"]) < 1e-12
        assert _rel(got["E"], want["E"]) < 1e-12
        assert _rel(got["P_diss"], 2 * want["D"] + want["P_fric"]) < 1e-12
        assert _rel(got["P_fric"], want["P_fric"]) < 1e-12


@pytest.mark.parametrize("kind,where", SURFACES)
def test_normal_forces_are_central_differences_of_E_and_D(kind, where):
    """Elastic Q (c = 0, mu = 0) = -dE/dphi by central differences of the diagnostics'
    E, with no torque; damping Q (its difference with c) = -dD/dv, D = P_diss/2, by
    central differences (D is quadratic in v: exact to rounding)."""
    rng = np.random.default_rng(21)
    x = _case(kind, where, rng)
    xe = _with(x, c=0.0, mu=0.0)
    Qe, Qd = _Q(kind, xe), _Q(kind, _with(x, mu=0.0)) - _Q(kind, xe)
    assert not Qe[6:].any() and not Qd[6:].any()
    h = 1e-7
    fd_e, fd_d = np.zeros(6), np.zeros(6)
    for k, (phi, v) in enumerate((("phi_a", "v_a"), ("phi_b", "v_b"))):
        for i in range(3):
            e = h * np.eye(3)[i]
            fd_e[3 * k + i] = -(_diag(kind, {**xe, phi: xe[phi] + e})["E"]
                                - _diag(kind, {**xe, phi: xe[phi] - e})["E"])[0] / (2 * h)
            xm = _with(x, mu=0.0)
            fd_d[3 * k + i] = -(_diag(kind, {**xm, v: xm[v] + e})["P_diss"]
                                - _diag(kind, {**xm, v: xm[v] - e})["P_diss"])[0] / (4 * h)
    assert np.abs(Qe[:6] - fd_e).max() < 1e-6 * np.abs(Qe).max()
    assert np.abs(Qd[:6] - fd_d).max() < 1e-6 * np.abs(Qd).max()


@pytest.mark.parametrize("kind,where", SURFACES)
def test_jacobian_equals_central_differences_of_Q(kind, where):
    rng = np.random.default_rng(22)
    x = _case(kind, where, rng)
    J = call(f"rod_contact_{kind}_jac", **x)["dQ_dx"]
    assert J.shape == (9, 19)
    fd = np.zeros((9, 19))
    for name, size in L.CONTACT_JAC_COLUMNS:
        k = L.CONTACT_JAC_OFFSETS[name]
        for c in range(size):
            h = 1e-7 * max(1.0, abs(x[name][c]))
            e = h * np.eye(size)[c]
            fd[:, k + c] = (_Q(kind, {**x, name: x[name] + e})
                            - _Q(kind, {**x, name: x[name] - e})) / (2 * h)
    assert np.abs(J - fd).max() < 1e-6 * np.abs(J).max()
    for name in ("p", "Omega", "v_a"):      # the friction's dependence is there
        k = L.CONTACT_JAC_OFFSETS[name]
        assert np.abs(J[:, k:k + 3]).max() > 1e-5 * np.abs(J).max()


def _flow(x, t):
    """Rod and obstacle after time t at constant velocities (exact): phi' = v,
    p' = 1/2 p*(0, Omega); c' = v_o, q_o' = 1/2 (0, w_o)*q_o."""
    obs = x["obs"]
    c, qo = _field(obs, "c"), _field(obs, "q", 4)
    v, w = _field(obs, "v"), _field(obs, "w")
    return {**x, "phi_a": x["phi_a"] + t * x["v_a"], "phi_b": x["phi_b"] + t * x["v_b"],
            "p": quat_mul(x["p"], quat_exp(t * x["Omega"])),
            "obs": _set(obs, O, c=c + t * v, q=quat_mul(quat_exp(t * w), qo))}


@pytest.mark.parametrize("kind,where", SURFACES)
def test_power_identity_with_a_moving_obstacle(kind, where):
    """Q . (v_a, v_b, Omega) = -dE/dt - P_diss + P_obs along the rod's and the obstacle's
    motion (dE/dt by fourth-order differences in time); P_diss >= P_fric >= 0;
    P_obs = -(F_obs . v_o + M_obs . w_o)."""
    rng = np.random.default_rng(23)
    for _ in range(3):
        x = _case(kind, where, rng)
        d = _diag(kind, x)
        P = _Q(kind, x) @ _velocities(x)
        h = 1e-4
        E = [_diag(kind, _flow(x, t))["E"][0] for t in (-2 * h, -h, h, 2 * h)]
        dE = (E[0] - 8 * E[1] + 8 * E[2] - E[3]) / (12 * h)
        rhs = -dE - d["P_diss"][0] + d["P_obs"][0]
        assert abs(P - rhs) < 1e-8 * max(abs(P), abs(dE), d["P_diss"][0])
        assert d["P_diss"][0] > d["P_fric"][0] > 0
        obs = x["obs"]
        assert d["P_obs"][0] == pytest.approx(
            -(d["F_obs"] @ _field(obs, "v") + d["M_obs"] @ _field(obs, "w")), rel=1e-12)


@pytest.mark.parametrize("kind,where", SURFACES)
def test_reaction_on_the_obstacle_balances_the_rod(kind, where):
    """F_obs = -(f_a + f_b); M_obs = -(moment of Q about c), the torque spatial."""
    rng = np.random.default_rng(24)
    x = _case(kind, where, rng)
    Q, d = _Q(kind, x), _diag(kind, x)
    c = _field(x["obs"], "c")
    assert _rel(d["F_obs"], -(Q[0:3] + Q[3:6])) < 1e-14
    M = (np.cross(x["phi_a"] - c, Q[0:3]) + np.cross(x["phi_b"] - c, Q[3:6])
         + quat_rotation(x["p"]) @ Q[6:9])
    assert _rel(d["M_obs"], -M) < 1e-12


@pytest.mark.parametrize("kind,where", SURFACES)
def test_objectivity(kind, where):
    """A rigid rotation and translation of rod and obstacle together rotates the forces,
    the obstacle's load and the quadrature points and leaves the material torque, E,
    the powers and the gaps; a rigid spin w superposed on both (v += w x phi,
    Omega += R^T w, v_o += w x c, w_o += w) changes no force."""
    rng = np.random.default_rng(25)
    x = _case(kind, where, rng)
    q = _unit(rng.standard_normal(4))
    R, b = quat_rotation(q), rng.standard_normal(3)
    obs = x["obs"]
    y = {**x, "phi_a": R @ x["phi_a"] + b, "phi_b": R @ x["phi_b"] + b,
         "v_a": R @ x["v_a"], "v_b": R @ x["v_b"], "p": quat_mul(q, x["p"]),
         "obs": _set(obs, O, c=R @ _field(obs, "c") + b, q=quat_mul(q, _field(obs, "q", 4)),
                     v=R @ _field(obs, "v"), w=R @ _field(obs, "w"))}
    Q, Qy = _Q(kind, x), _Q(kind, y)
    assert _rel(Qy, np.r_[R @ Q[0:3], R @ Q[3:6], Q[6:9]]) < 1e-12
    d, dy = _diag(kind, x), _diag(kind, y)
    for k in ("E", "P_diss", "P_fric", "P_obs", "g_min"):
        assert _rel(dy[k], d[k]) < 1e-11, k
    for k in ("F_obs", "M_obs"):
        assert _rel(dy[k], R @ d[k]) < 1e-12, k
    assert _rel(dy["points"][:, :3], d["points"][:, :3] @ R.T + b) < 1e-13
    w = rng.standard_normal(3)
    z = {**x, "v_a": x["v_a"] + np.cross(w, x["phi_a"]),
         "v_b": x["v_b"] + np.cross(w, x["phi_b"]),
         "Omega": x["Omega"] + quat_rotation(x["p"]).T @ w,
         "obs": _set(obs, O, v=_field(obs, "v") + np.cross(w, _field(obs, "c")),
                     w=_field(obs, "w") + w)}
    assert _rel(_Q(kind, z), Q) < 1e-12
    assert _rel(_diag(kind, z)["P_diss"], d["P_diss"]) < 1e-12


@pytest.mark.parametrize("kind,where", SURFACES)
def test_nothing_beyond_the_cutoff_and_the_bound_is_below_every_gap(kind, where):
    """A segment CONTACT_CUTOFF delta away exerts nothing above round-off (relative to
    k delta h, also at 100 m/s toward the obstacle); the bound kernel is below the gap of
    every point along random segments near the obstacle."""
    rng = np.random.default_rng(26)
    far = L.CONTACT_CUTOFF * DELTA
    x = _case(kind, where, rng, gaps=(far, 1.2 * far))
    x = {**x, "v_a": 100 * x["v_a"], "v_b": 100 * x["v_b"]}
    bound = call(f"rod_contact_{kind}_bound", phi_a=x["phi_a"], phi_b=x["phi_b"],
                 obs=x["obs"], cnt=x["cnt"])["g_lb"][0]
    assert bound > 0.9 * far
    scale = 1e4 * DELTA * 0.1
    assert np.abs(_Q(kind, x)).max() < 1e-16 * scale
    assert _diag(kind, x)["E"][0] < 1e-16 * scale * DELTA
    for _ in range(5):
        x = _case(kind, where, rng, gaps=(-3 * DELTA, 20 * DELTA), h=0.3)
        bound = call(f"rod_contact_{kind}_bound", phi_a=x["phi_a"], phi_b=x["phi_b"],
                     obs=x["obs"], cnt=x["cnt"])["g_lb"][0]
        for s0 in np.linspace(0, 1, 21):
            pt = x["phi_a"] + s0 * (x["phi_b"] - x["phi_a"])
            g = _diag(kind, {**x, "phi_a": pt, "phi_b": pt})["g_min"][0]
            assert bound <= g + 1e-12


def _resting(rng, pen_a, pen_b, h=0.2, k=1e4, c=0.0, mu=0.0, v_s=0.01):
    """A segment along a plane (obstacle at rest), its ends pen_a, pen_b deep."""
    obs = _obstacle(rng, moving=False)
    point, n = _surface("plane", "face", obs, rng)
    t = _perp(n, rng)
    Ro, c0 = quat_rotation(_field(obs, "q", 4)), _field(obs, "c")
    phi_a = c0 + Ro @ (point + n * (RADIUS - pen_a))
    phi_b = c0 + Ro @ (point + t * h + n * (RADIUS - pen_b))
    return {"phi_a": phi_a, "phi_b": phi_b, "v_a": np.zeros(3), "v_b": np.zeros(3),
            "p": _unit(rng.standard_normal(4)), "Omega": np.zeros(3), "obs": obs,
            "cnt": _cnt(k=k, c=c, mu=mu, v_s=v_s, h=h)}, Ro @ n, Ro @ t


def test_plane_normal_force_is_k_times_penetration_times_h():
    """-g >> delta: a level segment pressed pen into a plane feels k pen h, half on each
    node; a tilted one the linear element's consistent load, f_a = k h (2 pen_a +
    pen_b)/6, and E = k h (pen_a^2 + pen_a pen_b + pen_b^2)/6 (Simpson is exact)."""
    rng = np.random.default_rng(27)
    k, h = 1e4, 0.2
    pen = 30 * DELTA
    x, n, _ = _resting(rng, pen, pen, h=h, k=k)
    Q = _Q("plane", x)
    assert _rel(Q[0:3] + Q[3:6], k * pen * h * n) < 1e-10
    assert _rel(Q[0:3], Q[3:6]) < 1e-12 and not Q[6:].any()
    pa, pb = 30 * DELTA, 50 * DELTA
    x, n, _ = _resting(rng, pa, pb, h=h, k=k)
    Q = _Q("plane", x)
    assert _rel(Q[0:3], k * h * (2 * pa + pb) / 6 * n) < 1e-10
    assert _rel(Q[3:6], k * h * (pa + 2 * pb) / 6 * n) < 1e-10
    assert _diag("plane", x)["E"][0] == pytest.approx(k * h * (pa**2 + pa * pb + pb**2) / 6,
                                                       rel=1e-10)
    assert _diag("plane", x)["g_min"][0] == pytest.approx(-pb, rel=1e-12)
    # light contact: smooth, below k pen h, zero force at g >> delta
    forces = []
    for g in (-DELTA, 0.0, DELTA, 5 * DELTA):
        x, n, _ = _resting(rng, -g, -g, h=h, k=k)
        forces.append(_Q("plane", x)[0:6].reshape(2, 3).sum(axis=0) @ n)
    assert forces[0] < k * DELTA * h and np.all(np.diff(forces) < 0) and forces[-1] > 0


def test_normal_damping_opposes_the_approach_and_vanishes_apart():
    """Approaching the plane at gdot < 0 adds c |gdot| h (deep contact); at the same
    speed but 40 delta away, nothing."""
    rng = np.random.default_rng(28)
    x, n, _ = _resting(rng, 30 * DELTA, 30 * DELTA, c=50.0)
    Q0 = _Q("plane", x)
    approach = {**x, "v_a": -0.3 * n, "v_b": -0.3 * n}
    Q = _Q("plane", approach)
    assert _rel((Q - Q0)[0:3] + (Q - Q0)[3:6], 50.0 * 0.3 * 0.2 * n) < 1e-10
    far, _, _ = _resting(rng, -40 * DELTA, -40 * DELTA, c=50.0)
    far = {**far, "v_a": -0.3 * n, "v_b": -0.3 * n}
    assert np.abs(_Q("plane", far)).max() < 1e-15


def _tangential(Q, n):
    f = Q[0:3] + Q[3:6]
    return f - n * (n @ f)


def test_friction_sticks_viscously_slips_at_mu_and_opposes_the_slip():
    """A segment deep on a plane, sliding at v_t along it: |v_t| << v_s gives the viscous
    force -mu f_n v_t/v_s, |v_t| >> v_s gives mu f_n against v_t; its moment about the
    centreline is -r n x f_t (material: R^T of it); a spin about the normal has no
    resultant slip at the middle."""
    rng = np.random.default_rng(29)
    mu, v_s, k, h = 0.4, 0.01, 1e4, 0.2
    pen = 30 * DELTA
    x, n, t = _resting(rng, pen, pen, h=h, k=k, mu=mu, v_s=v_s)
    fn = k * pen * h
    b = np.cross(n, t)
    for vt in (1e-4 * v_s * t, 1e-4 * v_s * _unit(t + 2 * b)):
        Q = _Q("plane", {**x, "v_a": vt, "v_b": vt})
        assert _rel(_tangential(Q, n), -mu * fn * vt / v_s) < 1e-7
    for direction in (t, _unit(t - 0.5 * b)):
        vt = 1e4 * v_s * direction
        xs = {**x, "v_a": vt, "v_b": vt}
        Q = _Q("plane", xs)
        ft = _tangential(Q, n)
        assert _rel(ft, -mu * fn * direction) < 1e-7
        R = quat_rotation(x["p"])
        assert _rel(R @ Q[6:9], np.cross(-RADIUS * n, ft)) < 1e-12
        d = _diag("plane", xs)
        assert d["P_fric"][0] == pytest.approx(mu * fn * 1e4 * v_s, rel=1e-7)


def test_rolling_without_slip_meets_no_friction():
    """A segment rolling on a plane about its own axis, v = w x (r n) at every point
    (w = R Omega along the segment), has zero slip: no friction, no dissipation, the
    forces of the segment at rest; rolling at the same speed with the wrong sense slips
    at 2 |v| and is resisted with mu f_n."""
    rng = np.random.default_rng(30)
    mu, v_s, k, h = 0.5, 1e-3, 1e4, 0.2
    pen = 30 * DELTA
    x, n, t = _resting(rng, pen, pen, h=h, k=k, mu=mu, v_s=v_s, c=20.0)
    w = 7.0 * t
    v = np.cross(w, RADIUS * n)
    Omega = quat_rotation(x["p"]).T @ w
    rolling = {**x, "v_a": v, "v_b": v, "Omega": Omega}
    assert _rel(_Q("plane", rolling), _Q("plane", x)) < 1e-14
    assert _diag("plane", rolling)["P_diss"][0] < 1e-25
    skid = {**rolling, "Omega": -Omega}
    ft = _tangential(_Q("plane", skid), n)
    slip = 2 * np.linalg.norm(v)
    assert _rel(ft, -mu * k * pen * h * _unit(v) * slip / np.hypot(slip, v_s)) < 1e-9


def test_a_moving_obstacle_drags_a_resting_segment_and_delivers_power():
    """A plane sliding at u under a resting segment pulls it along with mu f_n (slip) and
    delivers P_obs = mu f_n |u| > 0; a plane moving along its normal into the segment
    pushes through the damping (gdot = -u)."""
    rng = np.random.default_rng(31)
    mu, v_s, k, h, c = 0.3, 1e-3, 1e4, 0.2, 40.0
    pen = 30 * DELTA
    x, n, t = _resting(rng, pen, pen, h=h, k=k, mu=mu, v_s=v_s, c=c)
    moving = {**x, "obs": _set(x["obs"], O, v=2.0 * t)}
    Q, d = _Q("plane", moving), _diag("plane", moving)
    assert _rel(_tangential(Q, n), mu * k * pen * h * t) < 1e-6
    assert d["P_obs"][0] == pytest.approx(mu * k * pen * h * 2.0, rel=1e-6)
    pushing = {**x, "obs": _set(x["obs"], O, v=0.5 * n)}
    f = _Q("plane", pushing)
    assert (f[0:3] + f[3:6]) @ n == pytest.approx(k * pen * h + c * 0.5 * h, rel=1e-9)


def _axis_frame(obs):
    Ro, c = quat_rotation(_field(obs, "q", 4)), _field(obs, "c")
    return Ro, c, _field(obs, "point"), _unit(_field(obs, "axis"))


@pytest.mark.parametrize("kind", ["sphere", "cylinder", "pipe"])
def test_curved_obstacles_push_along_their_normal(kind):
    """A very short segment pressed pen into a sphere, a cylinder's mantle or a pipe's
    wall (far from the ends) feels k pen h along the surface's outward normal (radial,
    perpendicular to the axis, inward for the pipe)."""
    rng = np.random.default_rng(32)
    pen, k, h = 20 * DELTA, 1e4, 0.1
    for _ in range(3):
        obs = _obstacle(rng, moving=False)
        point, n = _surface(kind, "mantle", obs, rng)
        t = _perp(n, rng)
        Ro, c, _, _ = _axis_frame(obs)
        ends = [point + s * 1e-6 * t + n * (RADIUS - pen) for s in (-1, 1)]
        x = {"phi_a": c + Ro @ ends[0], "phi_b": c + Ro @ ends[1], "v_a": np.zeros(3),
             "v_b": np.zeros(3), "p": _unit(rng.standard_normal(4)), "Omega": np.zeros(3),
             "obs": obs, "cnt": _cnt(k=k, h=h)}
        Q = _Q(kind, x)      # the axis/centre regularisation shifts d by ~(eps R)^2/2R
        assert _rel(Q[0:3] + Q[3:6], k * pen * h * (Ro @ n)) < 1e-7


def test_capped_cylinder_faces_and_rims():
    """A capped cylinder (length L, rims rounded over e << r): its end face pushes like
    a plane; near a rim the gap is the distance to the rim circle minus r (the rod's
    radius rounds the rim) to within e^2/d; an infinite one (L <= 0) has no caps."""
    rng = np.random.default_rng(33)
    obs = _obstacle(rng, moving=False)
    Ro, c, P0, a = _axis_frame(obs)
    perp = _perp(a, rng)
    pen, k, h = 20 * DELTA, 1e4, 0.1
    ends = [P0 + LENGTH * a + 0.3 * R_OBS * perp + s * 0.02 * np.cross(a, perp)
            + a * (RADIUS - pen) for s in (-1, 1)]
    x = {"phi_a": c + Ro @ ends[0], "phi_b": c + Ro @ ends[1], "v_a": np.zeros(3),
         "v_b": np.zeros(3), "p": _unit(rng.standard_normal(4)), "Omega": np.zeros(3),
         "obs": obs, "cnt": _cnt(k=k, h=h)}
    Q = _Q("cylinder", x)
    assert _rel(Q[0:3] + Q[3:6], k * pen * h * (Ro @ a)) < 1e-8
    for angle in (0.3, 0.8, 1.2):          # around the rim (beyond it at 45 degrees)
        direction = np.cos(angle) * perp + np.sin(angle) * a
        for dist in (RADIUS, RADIUS + 3 * DELTA, RADIUS - 0.5 * DELTA):
            pt = c + Ro @ (P0 + LENGTH * a + R_OBS * perp + dist * direction)
            g = _diag("cylinder", {**x, "phi_a": pt, "phi_b": pt})["g_min"][0]
            assert abs(g - (dist - RADIUS)) < EDGE**2 / dist
    beyond = c + Ro @ (P0 + (LENGTH + RADIUS + 50 * DELTA) * a + 0.3 * R_OBS * perp)
    x = {**x, "phi_a": beyond, "phi_b": beyond + 0.05 * (Ro @ np.cross(a, perp))}
    assert np.abs(_Q("cylinder", x)).max() < 1e-15
    infinite = _Q("cylinder", {**x, "obs": _set(obs, O, length=0.0)})   # deep inside it
    f = infinite[0:3] + infinite[3:6]
    assert abs(f @ (Ro @ a)) < 1e-12 * np.linalg.norm(f) and f @ (Ro @ perp) > 0


def test_pipe_open_ends_switch_the_contact_off():
    """A segment pressed into a pipe's wall feels the wall inside the pipe, half of it at
    the end's plane and nothing 40 e beyond it; an infinite pipe has no ends; a rod on
    the axis (where the normal is not defined) has finite, zero forces."""
    rng = np.random.default_rng(34)
    obs = _obstacle(rng, moving=False)
    Ro, c, P0, a = _axis_frame(obs)
    perp = _perp(a, rng)
    pen, k, h = 20 * DELTA, 1e4, 0.1
    b = _unit(np.cross(a, perp))

    def at(z):
        ends = [P0 + z * a + (R_OBS - RADIUS + pen) * perp + s * 1e-6 * b for s in (-1, 1)]
        return {"phi_a": c + Ro @ ends[0], "phi_b": c + Ro @ ends[1], "v_a": np.zeros(3),
                "v_b": np.zeros(3), "p": _unit(rng.standard_normal(4)),
                "Omega": np.zeros(3), "obs": obs, "cnt": _cnt(k=k, h=h)}

    inside = (_Q("pipe", at(0.5 * LENGTH))[0:3] + _Q("pipe", at(0.5 * LENGTH))[3:6])
    assert _rel(inside, -k * pen * h * (Ro @ perp)) < 1e-8
    at_end = _diag("pipe", at(LENGTH))["E"][0] / _diag("pipe", at(0.5 * LENGTH))["E"][0]
    assert at_end == pytest.approx(0.5, rel=1e-12)
    assert np.abs(_Q("pipe", at(LENGTH + 40 * EDGE))).max() < 1e-15 * k * pen * h
    assert np.abs(_Q("pipe", at(-40 * EDGE))).max() < 1e-15 * k * pen * h
    x = at(LENGTH + 40 * EDGE)
    infinite = {**x, "obs": _set(obs, O, length=-1.0)}
    assert _rel(_Q("pipe", infinite)[0:3] + _Q("pipe", infinite)[3:6],
                -k * pen * h * (Ro @ perp)) < 1e-8
    axis = {**x, "phi_a": c + Ro @ (P0 + 0.2 * a), "phi_b": c + Ro @ (P0 + 0.4 * a)}
    for name in ("rod_contact_pipe", "rod_contact_pipe_jac"):
        out = next(iter(call(name, **axis).values()))
        assert np.all(np.isfinite(out)) and np.abs(out).max() < 1e-15


def test_segment_through_a_sphere_centre_is_finite():
    """The regularised distance keeps a rod through the centre finite: a strong force
    out of the sphere, a finite Jacobian."""
    rng = np.random.default_rng(35)
    obs = _obstacle(rng, moving=False)
    Ro, c, P0, _ = _axis_frame(obs)
    d = _unit(rng.standard_normal(3))
    x = {"phi_a": c + Ro @ P0, "phi_b": c + Ro @ (P0 + 0.1 * d), "v_a": np.zeros(3),
         "v_b": np.zeros(3), "p": _unit(rng.standard_normal(4)), "Omega": np.zeros(3),
         "obs": obs, "cnt": _cnt()}
    Q = _Q("sphere", x)
    J = call("rod_contact_sphere_jac", **x)["dQ_dx"]
    assert np.all(np.isfinite(Q)) and np.all(np.isfinite(J))
    assert (Q[3:6] @ (Ro @ d)) > 0.5 * 1e4 * R_OBS * 0.1 / 6


def test_generated_contact_c_compiles_and_equals_the_serialised_kernels(tmp_path):
    """rod_contact_kernels.c (its own file: ~1.05 MB, beside rod_kernels.c's 1 MB bound)
    compiles on its own (-O0 here, quick) and every kernel in it equals the serialised
    one; the file stays below 1.5 MB."""
    import ctypes
    import subprocess

    from derive.artifacts import generated_dir
    from runtime.native import find_compiler
    from tests.generated.test_contact_pair_kernel import _case as pair_case
    from tests.kernel_calls import call_compiled, kernels

    src = generated_dir() / "rod_contact_kernels.c"
    assert src.stat().st_size < 1_500_000
    compiler = find_compiler()
    if compiler is None:
        pytest.skip("no C compiler")
    lib_path = tmp_path / "contact.so"
    subprocess.run([compiler, "-O0", "-fPIC", "-shared", "-std=c99", "-o", str(lib_path),
                    str(src), "-lm"], check=True, capture_output=True)
    lib = ctypes.CDLL(str(lib_path))
    rng = np.random.default_rng(36)
    names = [n for n in L.KERNELS if n.startswith("rod_contact_")]
    assert len(names) == 4 * len(KINDS) + 4
    for name in names:
        f = kernels()[name]
        kind = name.split("_")[2]
        x = pair_case(0.7, rng) if kind == "pair" else _case(kind, "mantle", rng)
        args = {f.name_in(i): x[f.name_in(i)] for i in range(f.n_in())}
        got, want = call_compiled(lib, name, **args), call(name, **args)
        for k in want:
            assert np.allclose(got[k], want[k], rtol=1e-13, atol=1e-13 * np.abs(want[k]).max())


def test_jacobian_where_the_smoothings_arguments_vanish():
    """Exactly zero arguments of the softplus (a node at g = 0 on a plane; a node on a
    capped cylinder's end plane, z = L, beside the rim): the Jacobian is still the
    central differences' (the geometry's softplus has exact derivatives of every order
    there; fmax(x, 0) + ln(1 + e^-|x|) would give a second derivative of 0)."""
    ident = np.array([1.0, 0, 0, 0])
    ez = np.array([0.0, 0, 1])
    rng = np.random.default_rng(37)
    obs = _set(np.zeros(L.N_OBS), O, q=ident, v=rng.standard_normal(3),
               w=rng.standard_normal(3), axis=ez, radius=R_OBS, length=LENGTH, edge=0.01)
    base = {"v_a": rng.standard_normal(3), "v_b": rng.standard_normal(3),
            "p": _unit(rng.standard_normal(4)), "Omega": rng.standard_normal(3),
            "obs": obs, "cnt": _cnt()}
    cases = [("plane", {"phi_a": np.array([0.1, 0.2, RADIUS]),
                        "phi_b": np.array([0.2, 0.25, RADIUS - 0.5 * DELTA])}),
             ("cylinder", {"phi_a": np.array([R_OBS + 0.005, 0.0, LENGTH]),
                           "phi_b": np.array([R_OBS + 0.03, 0.05, LENGTH + 0.01])})]
    for kind, nodes in cases:
        x = {**base, **nodes}
        J = call(f"rod_contact_{kind}_jac", **x)["dQ_dx"]
        fd = np.zeros((9, 19))
        for name, size in L.CONTACT_JAC_COLUMNS:
            k = L.CONTACT_JAC_OFFSETS[name]
            for c in range(size):
                e = 1e-7 * np.eye(size)[c]
                fd[:, k + c] = (_Q(kind, {**x, name: x[name] + e})
                                - _Q(kind, {**x, name: x[name] - e})) / 2e-7
        assert np.abs(J - fd).max() < 1e-6 * np.abs(J).max(), kind


@pytest.mark.parametrize("kind", ["cylinder", "pipe"])
def test_an_infinite_cylinder_needs_no_edge(kind):
    """length <= 0 with edge = 0 (the rounding is unused): every kernel is finite and
    the same as with any edge."""
    rng = np.random.default_rng(38)
    x = _case(kind, "infinite", rng)
    for length in (0.0, -1.0):
        y = {**x, "obs": _set(x["obs"], O, edge=0.0, length=length)}
        z = {**x, "obs": _set(x["obs"], O, edge=0.3, length=length)}
        for suffix in ("", "_jac", "_diagnostics"):
            got = call(f"rod_contact_{kind}{suffix}", **y)
            want = call(f"rod_contact_{kind}{suffix}", **z)
            for k in want:
                assert np.all(np.isfinite(got[k])) and np.array_equal(got[k], want[k]), k


def test_a_round_rod_across_an_incline_rolls():
    """A rigid round segment (mass m, length h, radius r, inertia m r^2/2 about its axis)
    lying across an incline at theta, integrated with the plane kernel's force and torque
    (scipy BDF): without friction it slides, s = g sin(theta) t^2/2; with mu above
    tan(theta)/3 it rolls, s = 2/3 g sin(theta) t^2/2 and omega = -v/r; with less it slides
    and turns, s = g (sin - mu cos) t^2/2, omega = -2 mu g cos(theta) t/r (rigid-body
    mechanics; the regularised friction creeps by ~v_s)."""
    from scipy.integrate import solve_ivp

    m, h, r, g, theta, t_end = 1.0, 1.0, 0.05, 9.81, 0.3, 0.5
    k = 1e5
    n = np.array([-np.sin(theta), 0, np.cos(theta)])
    down = np.array([-np.cos(theta), 0, -np.sin(theta)])
    obs = _set(np.zeros(L.N_OBS), O, q=[1.0, 0, 0, 0], axis=n)
    e = np.array([0, 0.5 * h, 0])

    def run(mu):
        cnt = _cnt(k=k, delta=1e-5, c=2 * np.sqrt(k * m / h), mu=mu, v_s=1e-3, r=r, h=h)

        def rhs(t, y):
            Q = _Q("plane", {"phi_a": y[0:3] - e, "phi_b": y[0:3] + e, "v_a": y[3:6],
                             "v_b": y[3:6], "p": [1.0, 0, 0, 0], "Omega": [0, y[6], 0],
                             "obs": obs, "cnt": cnt})
            return np.r_[y[3:6], (Q[0:3] + Q[3:6]) / m - [0, 0, g], Q[7] / (0.5 * m * r**2)]

        y0 = np.r_[n * (r - m * g * np.cos(theta) / (k * h)), np.zeros(4)]
        y = solve_ivp(rhs, (0, t_end), y0, method="BDF", rtol=1e-8, atol=1e-10).y[:, -1]
        return (y[0:3] - y0[0:3]) @ down, y[6], y[3:6] @ down

    s, omega, _ = run(0.0)
    assert s == pytest.approx(0.5 * g * np.sin(theta) * t_end**2, rel=1e-6) and omega == 0.0
    s, omega, v = run(0.5)
    assert s == pytest.approx(0.5 * 2 / 3 * g * np.sin(theta) * t_end**2, rel=1e-3)
    assert omega == pytest.approx(-v / r, rel=1e-3)
    mu = 0.05
    s, omega, _ = run(mu)
    assert s == pytest.approx(0.5 * g * (np.sin(theta) - mu * np.cos(theta)) * t_end**2,
                              rel=1e-3)
    assert omega == pytest.approx(-2 * mu * g * np.cos(theta) * t_end / r, rel=1e-3)


@pytest.mark.parametrize("restitution", [0.2, 0.5, 0.8])
def test_damping_from_a_restitution_coefficient(restitution):
    """A rigid segment (mass m, length h) hitting a plane flat at v0 rebounds at
    restitution * v0 when c = 2 zeta sqrt(k m/h), zeta = -ln e/sqrt(pi^2 + ln^2 e) (the
    linear spring-dashpot's; its penetration 30 delta deep), the rule docs/design.md
    gives the runtime's default."""
    from scipy.integrate import solve_ivp

    m, h, k, delta, v0 = 2.0, 0.5, 1e6, 1e-6, 0.3
    lg = np.log(restitution)
    c = 2 * (-lg / np.sqrt(np.pi**2 + lg**2)) * np.sqrt(k * m / h)
    obs = _set(np.zeros(L.N_OBS), O, q=[1.0, 0, 0, 0], axis=[0, 0, 1.0])
    cnt = _cnt(k=k, delta=delta, c=c, mu=0.0, r=0.01, h=h)
    e = np.array([0.5 * h, 0, 0])

    def rhs(t, y):
        x, v = np.r_[0, 0, y[0]], np.r_[0, 0, y[1]]
        Q = _Q("plane", {"phi_a": x - e, "phi_b": x + e, "v_a": v, "v_b": v,
                         "p": [1.0, 0, 0, 0], "Omega": np.zeros(3), "obs": obs, "cnt": cnt})
        return [y[1], (Q[2] + Q[5]) / m]

    def left(t, y):
        return y[0] - 0.01 - 50 * delta
    left.terminal, left.direction = True, 1
    sol = solve_ivp(rhs, (0, 1.0), [0.01 + 20 * delta, -v0], method="BDF", events=left,
                    rtol=1e-9, atol=1e-12)
    assert v0 * np.sqrt(m / (k * h)) > 30 * delta
    assert sol.y[1, -1] == pytest.approx(restitution * v0, rel=2e-3)
