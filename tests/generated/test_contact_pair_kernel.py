"""The generated rod-rod contact kernels (rod_contact_pair, _jac, _diagnostics, _bound;
derive/contact_pair.py): AD of the definitions, central differences, the power
identity, action and reaction, objectivity, the closest points against a brute-force
distance, the contact length of parallel and crossing rods, friction and rolling."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from derive import contact_pair as cp
from derive.contact import AXIS_REGULARISATION
from generated import rod_layout as L
from runtime.model.quaternion import quat_exp, quat_mul, quat_rotation
from tests.kernel_calls import call

K = L.PAIR_OFFSETS
R1, R2, DELTA = 0.02, 0.015, 0.005
#: angles between the segments: crossing, oblique, nearly parallel, parallel
ANGLES = [np.pi / 2, 0.7, 0.05, 0.0]
NODES = (("phi_a", "v_a"), ("phi_b", "v_b"), ("phi_c", "v_c"), ("phi_d", "v_d"))
BLOCKS = ("f_a", "f_b", "T_1", "f_c", "f_d", "T_2")


def _unit(v):
    return v / np.linalg.norm(v)


def _par(k=1e4, delta=DELTA, c=20.0, mu=0.3, v_s=0.1, r_1=R1, r_2=R2, l_x=R1 + R2):
    out = np.zeros(L.N_PAIR)
    for name, v in dict(k=k, delta=delta, c=c, mu=mu, v_s=v_s, r_1=r_1, r_2=r_2,
                        l_x=l_x).items():
        out[K[name]] = v
    return out


def _case(angle, rng, gap=None, s0=None, t0=None, h1=0.2, h2=0.25, **par) -> dict:
    """Two segments at ``angle``, their closest points at s0, t0 (random inside) with the
    surfaces ``gap`` apart (random in [-2 delta, delta]); random velocities and frames."""
    e1 = _unit(rng.standard_normal(3))
    n = _unit(np.cross(e1, rng.standard_normal(3)))
    e2 = np.cos(angle) * e1 + np.sin(angle) * np.cross(n, e1)
    o = rng.standard_normal(3)
    s0 = rng.uniform(0.2, 0.8) if s0 is None else s0
    t0 = rng.uniform(0.2, 0.8) if t0 is None else t0
    gap = rng.uniform(-2 * DELTA, DELTA) if gap is None else gap
    phi_a = o - s0 * h1 * e1
    phi_c = o - n * (R1 + R2 + gap) - t0 * h2 * e2
    return {"phi_a": phi_a, "phi_b": phi_a + h1 * e1, "v_a": rng.standard_normal(3),
            "v_b": rng.standard_normal(3),
            "p_1": _unit(rng.standard_normal(4)) * rng.uniform(0.7, 1.3),
            "Omega_1": rng.standard_normal(3), "phi_c": phi_c, "phi_d": phi_c + h2 * e2,
            "v_c": rng.standard_normal(3), "v_d": rng.standard_normal(3),
            "p_2": _unit(rng.standard_normal(4)) * rng.uniform(0.7, 1.3),
            "Omega_2": rng.standard_normal(3), "cnt": _par(**par)}


def _Q(x):
    return call("rod_contact_pair", **x)["Q"]


def _diag(x):
    return call("rod_contact_pair_diagnostics", **x)


def _block(Q, name):
    k = L.PAIR_FORCE_OFFSETS[name]
    return Q[k:k + 3]


def _rel(a, b):
    return np.abs(np.asarray(a) - np.asarray(b)).max() / max(np.abs(b).max(), 1e-300)


def _with(x, **par):
    cnt = x["cnt"].copy()
    for name, v in par.items():
        cnt[K[name]] = v
    return {**x, "cnt": cnt}


def _rates(x):
    return np.r_[x["v_a"], x["v_b"], x["Omega_1"], x["v_c"], x["v_d"], x["Omega_2"]]


def _power(Q, x):
    return Q[0:9] @ _rates(x)[0:9] + Q[9:18] @ _rates(x)[9:18]


def test_layout_tables_name_the_kernels_blocks_and_columns():
    assert L.N_PAIR_FORCES == 18 and L.N_PAIR_JAC_COLUMNS == 38
    assert L.PAIR_OFFSETS == cp.PAIR_OFFSETS and [n for n, _ in L.PAIR_FORCES] == list(BLOCKS)
    assert [n for n, _ in L.PAIR_JAC_COLUMNS] == [
        "phi_a", "phi_b", "p_1", "phi_c", "phi_d", "p_2", "v_a", "v_b", "Omega_1", "v_c",
        "v_d", "Omega_2"]
    sig = L.KERNELS["rod_contact_pair"]
    assert [sig["inputs"][n][0] for n, _ in L.PAIR_JAC_COLUMNS] \
        == [s for _, s in L.PAIR_JAC_COLUMNS]
    assert L.KERNELS["rod_contact_pair_jac"]["outputs"]["dQ_dx"] == [18, 38]


@pytest.mark.parametrize("angle", ANGLES)
def test_forces_equal_casadi_ad_of_the_definitions(angle):
    """The kernel (gradients in the relative positions, gdot = grad g . v) against the
    definitions (E = W e(g), D with gdot by forward AD over the four nodes, Q by AD of
    both and the friction's virtual power), also for an end against a side and two
    segments end to end."""
    s = cp.pair_symbols()
    d = cp.pair_definitions(s)
    ref = ca.Function("ref", list(s.inputs().values()),
                      [cp.pair_forces_ad(s), d["E"], d["D"], d["P_fric"]], list(s.inputs()),
                      ["Q", "E", "D", "P_fric"])
    rng = np.random.default_rng(40)
    cases = [_case(angle, rng) for _ in range(2)]
    cases += [_case(angle, rng, s0=1.0), _case(angle, rng, s0=1.0, t0=0.0)]
    for x in cases:
        want = {k: np.array(v).ravel() for k, v in ref(**x).items()}
        got = _diag(x)
        assert want["E"][0] > 1e-6 and want["P_fric"][0] > 1e-6
        assert _rel(_Q(x), want["Q"]) < 1e-11
        assert _rel(got["E"], want["E"]) < 1e-12
        assert _rel(got["P_diss"], 2 * want["D"] + want["P_fric"]) < 1e-12


@pytest.mark.parametrize("angle", ANGLES)
def test_normal_forces_are_central_differences_of_E_and_D(angle):
    rng = np.random.default_rng(41)
    x = _case(angle, rng)
    xe = _with(x, c=0.0, mu=0.0)
    xm = _with(x, mu=0.0)
    Qe, Qd = _Q(xe), _Q(xm) - _Q(xe)
    h = 1e-7
    fd_e, fd_d = np.zeros(18), np.zeros(18)
    for k, (phi, v) in enumerate(NODES):
        row = L.PAIR_FORCE_OFFSETS[("f_a", "f_b", "f_c", "f_d")[k]]
        for i in range(3):
            e = h * np.eye(3)[i]
            fd_e[row + i] = -(_diag({**xe, phi: xe[phi] + e})["E"]
                              - _diag({**xe, phi: xe[phi] - e})["E"])[0] / (2 * h)
            fd_d[row + i] = -(_diag({**xm, v: xm[v] + e})["P_diss"]
                              - _diag({**xm, v: xm[v] - e})["P_diss"])[0] / (4 * h)
    assert np.abs(Qe - fd_e).max() < 1e-6 * np.abs(Qe).max()
    assert np.abs(Qd - fd_d).max() < 1e-6 * np.abs(Qd).max()


@pytest.mark.parametrize("angle", ANGLES)
def test_jacobian_equals_central_differences_of_Q(angle):
    rng = np.random.default_rng(42)
    x = _case(angle, rng)
    J = call("rod_contact_pair_jac", **x)["dQ_dx"]
    assert J.shape == (18, 38)
    fd = np.zeros((18, 38))
    for name, size in L.PAIR_JAC_COLUMNS:
        k = L.PAIR_JAC_OFFSETS[name]
        for c in range(size):
            h = 1e-7 * max(1.0, abs(x[name][c]))
            e = h * np.eye(size)[c]
            fd[:, k + c] = (_Q({**x, name: x[name] + e}) - _Q({**x, name: x[name] - e})) / (2 * h)
    assert np.abs(J - fd).max() < 1e-6 * np.abs(J).max()


def _flow(x, t):
    y = {**x}
    for phi, v in NODES:
        y[phi] = x[phi] + t * x[v]
    y["p_1"] = quat_mul(x["p_1"], quat_exp(t * x["Omega_1"]))
    y["p_2"] = quat_mul(x["p_2"], quat_exp(t * x["Omega_2"]))
    return y


@pytest.mark.parametrize("angle", ANGLES)
def test_power_identity(angle):
    """Q . rates = -dE/dt - P_diss (dE/dt by fourth-order differences along the flow);
    P_diss >= P_fric >= 0."""
    rng = np.random.default_rng(43)
    for _ in range(3):
        x = _case(angle, rng)
        d = _diag(x)
        P = _power(_Q(x), x)
        h = 2e-5        # E changes over delta/|v| ~ 5 ms
        E = [_diag(_flow(x, t))["E"][0] for t in (-2 * h, -h, h, 2 * h)]
        dE = (E[0] - 8 * E[1] + 8 * E[2] - E[3]) / (12 * h)
        assert abs(P - (-dE - d["P_diss"][0])) < 1e-8 * max(abs(P), abs(dE), d["P_diss"][0])
        assert d["P_diss"][0] > d["P_fric"][0] > 0


def _resultants(Q, x):
    F = sum(_block(Q, f) for f in ("f_a", "f_b", "f_c", "f_d"))
    M = (sum(np.cross(x[phi], _block(Q, f)) for (phi, _), f in
             zip(NODES, ("f_a", "f_b", "f_c", "f_d"), strict=True))
         + quat_rotation(x["p_1"]) @ _block(Q, "T_1") + quat_rotation(x["p_2"]) @ _block(Q, "T_2"))
    return F, M


@pytest.mark.parametrize("angle", ANGLES)
def test_action_and_reaction(angle):
    """The pair's loads are in equilibrium: total force and total moment (the torques
    spatial) zero, also for friction acting at one point of the two surfaces; F_12 is
    the first segment's share."""
    rng = np.random.default_rng(44)
    for _ in range(3):
        x = _case(angle, rng)
        Q = _Q(x)
        F, M = _resultants(Q, x)
        scale = np.abs(Q).max() * (1 + max(np.abs(x[phi]).max() for phi, _ in NODES))
        assert np.abs(F).max() < 1e-14 * scale and np.abs(M).max() < 1e-14 * scale
        assert _rel(_diag(x)["F_12"], _block(Q, "f_a") + _block(Q, "f_b")) < 1e-14


@pytest.mark.parametrize("angle", ANGLES)
def test_objectivity(angle):
    """A rigid motion of both segments rotates the forces and leaves the material torques,
    E, the powers, the gap and the contact parameters; a superposed rigid spin changes
    no force."""
    rng = np.random.default_rng(45)
    x = _case(angle, rng)
    q = _unit(rng.standard_normal(4))
    R, b = quat_rotation(q), rng.standard_normal(3)
    y = {**x, "p_1": quat_mul(q, x["p_1"]), "p_2": quat_mul(q, x["p_2"])}
    for phi, v in NODES:
        y[phi], y[v] = R @ x[phi] + b, R @ x[v]
    Q, Qy = _Q(x), _Q(y)
    for f in BLOCKS:
        want = _block(Q, f) if f.startswith("T") else R @ _block(Q, f)
        assert np.abs(_block(Qy, f) - want).max() < 1e-12 * np.abs(Q).max(), f
    d, dy = _diag(x), _diag(y)
    for k in ("E", "P_diss", "P_fric", "g_min", "st", "W"):
        assert _rel(dy[k], d[k]) < 1e-11, k
    w = rng.standard_normal(3)
    z = {**x, "Omega_1": x["Omega_1"] + quat_rotation(x["p_1"]).T @ w,
         "Omega_2": x["Omega_2"] + quat_rotation(x["p_2"]).T @ w}
    for phi, v in NODES:
        z[v] = x[v] + np.cross(w, x[phi])
    assert _rel(_Q(z), Q) < 1e-11


def _segment_distance(a, b, c, d) -> float:
    """The exact distance of two segments, brute force: for each s of a fine grid the
    closest t in closed form (clamped), then a golden-section refinement in s."""
    u, w = b - a, d - c

    def dist(s):
        x = a + s * u
        t = np.clip((x - c) @ w / (w @ w), 0.0, 1.0)
        return np.linalg.norm(x - c - t * w)

    grid = np.linspace(0.0, 1.0, 2001)
    k = int(np.argmin([dist(s) for s in grid]))
    lo, hi = grid[max(k - 1, 0)], grid[min(k + 1, len(grid) - 1)]
    g = (np.sqrt(5) - 1) / 2
    for _ in range(80):
        m1, m2 = hi - g * (hi - lo), lo + g * (hi - lo)
        if dist(m1) < dist(m2):
            hi = m2
        else:
            lo = m1
    return min(dist(0.5 * (lo + hi)), dist(0.0), dist(1.0))


def test_gap_is_the_segments_distance_minus_the_radii():
    """Against a brute-force segment distance: never below it (the smoothed points lie
    on the segments; the regularisation only adds), exact (to the regularisation's
    (eps_r (r_1 + r_2))^2/2d, 2e-10 m) for segments crossing at right angles, within
    1e-4 m (second order in the blend of the closest points toward the overlap's middle,
    lam/(sin^2 + lam)) when oblique, and within a few percent of the clamp's smoothing
    where the closest point is an end (T and end-to-end configurations, near parallel)."""
    rng = np.random.default_rng(46)
    for angle, tol in ((np.pi / 2, 1e-9), (1.0, 1e-4), (0.5, 1e-4)):
        for _ in range(3):
            x = _case(angle, rng)
            g = _diag(x)["g_min"][0]
            exact = _segment_distance(x["phi_a"], x["phi_b"], x["phi_c"], x["phi_d"])
            assert 0 <= g - (exact - R1 - R2) < tol
    for angle in (np.pi / 2, 0.7, 0.05, 0.0):
        for s0, t0 in ((1.1, 0.5), (1.05, -0.1), (0.5, 1.3)):
            x = _case(angle, rng, s0=s0, t0=t0, gap=0.0)
            g = _diag(x)["g_min"][0]
            exact = _segment_distance(x["phi_a"], x["phi_b"], x["phi_c"], x["phi_d"])
            assert exact - R1 - R2 - 1e-12 <= g <= exact - R1 - R2 + 0.05 * 0.25


def _straight_rod(origin, e, n_seg, h):
    return [origin + i * h * e for i in range(n_seg + 1)]


def _contact_length(rod1, rod2, x, pen):
    """The effective contact length of two rods pressed pen together: the normal force
    of every pair of their segments the bound admits, over k pen (k of x's cnt)."""
    F = np.zeros(3)
    for i in range(len(rod1) - 1):
        for j in range(len(rod2) - 1):
            y = {**x, "phi_a": rod1[i], "phi_b": rod1[i + 1], "phi_c": rod2[j],
                 "phi_d": rod2[j + 1]}
            b = call("rod_contact_pair_bound", phi_a=y["phi_a"], phi_b=y["phi_b"],
                     phi_c=y["phi_c"], phi_d=y["phi_d"], cnt=y["cnt"])["g_lb"][0]
            if b <= L.CONTACT_CUTOFF * x["cnt"][K["delta"]]:
                F += _diag(y)["F_12"]
    return np.linalg.norm(F) / (x["cnt"][K["k"]] * pen)


def test_parallel_rods_are_a_line_contact_and_crossing_rods_a_point_contact():
    """Two straight parallel rods of 8 segments pressed pen together: their contact
    length (normal force / k pen) is the overlap within 2 % whether the nodes are aligned
    or staggered by h/2 (each segment pair weighs its overlap, segments end to end
    nothing); two rods crossing at right angles weigh l_x inside a segment pair and up
    to twice that at a node (two pairs see the crossing)."""
    rng = np.random.default_rng(47)
    h, n_seg = 0.1, 8
    delta, k = 1e-5, 1e4
    pen = 200 * delta       # -g >> delta: e = k g^2/2
    x = {**_case(0.0, rng), "v_a": np.zeros(3), "v_b": np.zeros(3), "v_c": np.zeros(3),
         "v_d": np.zeros(3), "Omega_1": np.zeros(3), "Omega_2": np.zeros(3),
         "cnt": _par(k=k, delta=delta)}
    e, n, b = np.array([1.0, 0, 0]), np.array([0, 0, 1.0]), np.array([0, 1.0, 0])
    rod1 = _straight_rod(np.zeros(3), e, n_seg, h)
    lx = R1 + R2
    for shift in (0.0, 0.5 * h):
        rod2 = _straight_rod(-n * (R1 + R2 - pen) + shift * e, e, n_seg, h)
        overlap = n_seg * h - shift
        length = _contact_length(rod1, rod2, x, pen)
        assert length == pytest.approx(overlap, rel=0.02)
    crossing = []
    for where in (0.5, 0.25, 0.0):          # along rod 1's segment 5: middle, quarter, node
        rod2 = _straight_rod(-n * (R1 + R2 - pen) + (4 + where) * h * e - 4.5 * h * b, b,
                             n_seg, h)
        crossing.append(_contact_length(rod1, rod2, x, pen))
    assert crossing[0] == pytest.approx(crossing[1], rel=1e-3)
    assert crossing[0] == pytest.approx(lx, rel=1e-2)
    assert crossing[0] < crossing[2] <= 2 * crossing[0] * 1.01


def test_nothing_beyond_the_cutoff_and_the_bound_is_below_the_gap():
    rng = np.random.default_rng(48)
    far = L.CONTACT_CUTOFF * DELTA
    for angle in ANGLES:
        x = _case(angle, rng, gap=1.05 * far)
        x = {**x, **{v: 100 * x[v] for _, v in NODES}}
        assert np.abs(_Q(x)).max() < 1e-16 * 1e4 * DELTA * 0.2
        for _ in range(3):
            x = _case(angle, rng, gap=rng.uniform(-DELTA, 5 * DELTA),
                      s0=rng.uniform(-0.5, 1.5))
            b = call("rod_contact_pair_bound", phi_a=x["phi_a"], phi_b=x["phi_b"],
                     phi_c=x["phi_c"], phi_d=x["phi_d"], cnt=x["cnt"])["g_lb"][0]
            assert b <= _diag(x)["g_min"][0]


def test_friction_between_crossing_rods_and_rolling_over_one():
    """Rod 2 slides across rod 1 (at rest) much faster than v_s: the friction on rod 1 is
    mu times the normal force, along the sliding; rod 2 rolling over rod 1 without slip
    at their contact point (v = w x (p_c - y)) meets no friction."""
    rng = np.random.default_rng(49)
    mu, v_s, k = 0.3, 1e-3, 1e4
    x = _case(np.pi / 2, rng, gap=-4 * DELTA, mu=mu, v_s=v_s, k=k, c=0.0)
    zero = {v: np.zeros(3) for _, v in NODES} | {"Omega_1": np.zeros(3),
                                                 "Omega_2": np.zeros(3)}
    x = {**x, **zero}
    rest = _diag(x)["F_12"]
    st = _diag(x)["st"]
    xs = x["phi_a"] + st[0] * (x["phi_b"] - x["phi_a"])
    y = x["phi_c"] + st[1] * (x["phi_d"] - x["phi_c"])
    n = _unit(xs - y)
    e2 = _unit(x["phi_d"] - x["phi_c"])
    slide = {**x, "v_c": 5.0 * e2, "v_d": 5.0 * e2}
    ft = _diag(slide)["F_12"] - rest
    assert _rel(ft, mu * np.linalg.norm(rest) * e2) < 1e-6
    assert abs(ft @ n) < 1e-9 * np.linalg.norm(ft)
    nr = (xs - y) / np.hypot(np.linalg.norm(xs - y), AXIS_REGULARISATION * (R1 + R2))
    pc = 0.5 * (xs - R1 * nr + y + R2 * nr)      # the kernel's (regularised) normal
    w = 4.0 * e2
    v = np.cross(w, y - pc)       # rod 2's point y moves so that its point at p_c rests
    rolling = {**x, "v_c": v, "v_d": v, "Omega_2": quat_rotation(x["p_2"]).T @ w}
    assert _diag(rolling)["P_fric"][0] < 1e-14 * _diag(slide)["P_fric"][0]
    assert _rel(_Q(rolling), _Q(x)) < 1e-12
