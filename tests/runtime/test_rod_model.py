"""Patch tests of the discrete rod (issue 3): rigid motion, objectivity, energy identity,
quaternion scaling, Jacobians against finite differences, static problem, parameters."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from runtime.errors import ParameterError
from runtime.model.casadi_oracle import CasadiOracle
from runtime.model.quaternion import quat_exp, quat_mul, quat_rotation
from runtime.model.rod import RodModel
from runtime.model.statics import RodStatics
from tests.rods import random_state, residual, rod_model, rod_problem

BCS = [
    ("clamped", "free"),
    ("pinned", "pinned"),
    ("clamped", "clamped"),
    ("free", "free"),
    ("pinned", "clamped"),
]


def model(N=6, start="clamped", end="free", loads=True, **kw) -> RodModel:
    return rod_model(N, start, end, loads=loads, **kw)


def fields(m: RodModel):
    return m.phi_index, m.v_index, m.p_index, m.omega_index


# --------------------------------------------------------------------------------------


@pytest.mark.parametrize("start,end", BCS)
def test_jacobians_match_central_differences(start, end):
    rng = np.random.default_rng(1)
    m = model(5, start, end)
    y, yp = random_state(m, rng), rng.standard_normal(m.n)
    Jy = m.dF_dy_sparse(0.0, y, yp).toarray()
    Jyp = m.dF_dyp_sparse(0.0, y, yp).toarray()
    eps = 1e-6
    Ny, Nyp = np.empty_like(Jy), np.empty_like(Jyp)
    for k in range(m.n):
        e = np.zeros(m.n)
        e[k] = eps
        Ny[:, k] = (residual(m, y + e, yp) - residual(m, y - e, yp)) / (2 * eps)
        Nyp[:, k] = (residual(m, y, yp + e) - residual(m, y, yp - e)) / (2 * eps)
    scale = np.abs(Jy).max()
    assert np.abs(Jy - Ny).max() <= 1e-6 * scale
    assert np.abs(Jyp - Nyp).max() <= 1e-6 * max(1.0, np.abs(Jyp).max())
    cj = 37.0
    assert np.allclose(
        m.jacobian_sparse(0.0, y, yp, cj).toarray(), Jy + cj * Jyp, rtol=1e-12, atol=1e-12 * scale
    )
    # everything lies inside the declared band
    rows, cols = np.nonzero(Jy + Jyp)
    assert (rows - cols).max() <= m.kl and (cols - rows).max() <= m.ku


def test_differential_mask_matches_dF_dyp():
    for start, end in BCS:
        m = model(4, start, end)
        B = m.dF_dyp_sparse(0.0, m.initial_state(), np.zeros(m.n)).toarray()
        assert np.array_equal(np.any(B != 0, axis=0), m.differential)


@pytest.mark.parametrize(
    "start,end", [("clamped", "free"), ("clamped", "clamped"), ("pinned", "free")]
)
def test_energy_identity_along_the_flow(start, end):
    """d/dt (T + W) = -2D + P_ext at random states, y' solved from F(y, y') = 0."""
    rng = np.random.default_rng(2)
    m = model(7, start, end)
    cr = CasadiOracle(m.arrays)
    ysym = ca.MX.sym("y", m.n)
    dsym = ca.MX.sym("d", m.n)
    out = cr.energies(0.0, ysym, dsym, *CasadiOracle.args(m.arrays))
    dE = ca.Function("dE", [ysym, dsym], [ca.jtimes(out[0] + out[1], ysym, dsym)])
    for _ in range(3):
        y = random_state(m, rng)
        d = m.differential
        B = m.dF_dyp_sparse(0.0, y, np.zeros(m.n)).toarray()
        r0 = residual(m, y, np.zeros(m.n))
        assert np.all(r0[~d] == 0.0)  # consistent: fixed nodes at rest
        yp = np.zeros(m.n)
        yp[d] = np.linalg.solve(B[np.ix_(d, d)], -r0[d])
        assert np.abs(residual(m, y, yp)).max() < 1e-8 * np.abs(r0).max()
        diag = m.diagnostics(0.0, y, yp)
        lhs = float(dE(y, yp))
        rhs = -diag["dissipation_rate"] + diag["external_power"] + diag["boundary_power"]
        scale = abs(diag["dissipation_rate"]) + abs(diag["external_power"]) + abs(lhs)
        assert abs(lhs - rhs) <= 1e-10 * scale
        assert diag["dissipation_rate"] > 0


def rigid_state(m, rng, R_q, c, v0, w):
    """Reference configuration moved rigidly by (R, c) with rigid velocity (v0, w)."""
    y = m.reference.copy()
    iphi, iv, ip, iom = fields(m)
    R = _rot(R_q)
    X = y[iphi]
    y[iphi] = X @ R.T + c
    y[ip] = np.broadcast_to(R_q, (m.N, 4)) * rng.uniform(0.5, 2.0, (m.N, 1))
    y[iv] = v0 + np.cross(w, y[iphi])
    y[iom] = R.T @ w
    return y


def _rot(q):
    return quat_rotation(q)


def test_rigid_motion_gives_no_internal_forces():
    """Translation, finite rotation, rigid velocity and spin: zero strain change and zero
    elastic and viscous internal forces."""
    rng = np.random.default_rng(3)
    m = model(6, "free", "free", loads=False)
    q = quat_exp(np.array([0.7, -1.1, 0.4]))
    y = rigid_state(
        m,
        rng,
        q,
        np.array([0.1, -0.2, 0.3]),
        np.array([0.3, 0.1, -0.5]),
        np.array([2.0, -1.0, 3.0]),
    )
    d = m.diagnostics(0.0, y, np.zeros(m.n))
    assert np.allclose(d["strains"]["V"], np.array([[0], [0], [1]]), atol=1e-13)
    assert np.allclose(d["strains"]["U"], 0.0, atol=1e-12)
    assert abs(d["elastic"]) < 1e-20 and abs(d["dissipation_rate"]) < 1e-20
    assert np.allclose(d["resultants"]["F"], 0, atol=1e-12)
    assert np.allclose(d["resultants"]["M"], 0, atol=1e-12)
    r = residual(m, y, np.zeros(m.n))
    iphi, iv, ip, iom = fields(m)
    assert np.abs(r[iv]).max() < 1e-12  # momentum rows: no internal forces
    # angular momentum rows at zero acceleration: Omega x J Omega only
    rhoI = m.arrays.seg_field("rhoI") * m.arrays.seg_field("h")
    om = y[iom]
    assert np.allclose(r[iom], np.cross(om, rhoI * om), atol=1e-12)


def test_objectivity_of_energies_and_dissipation():
    rng = np.random.default_rng(4)
    m = model(6, "free", "free", loads=False)
    y = random_state(m, rng)
    iphi, iv, ip, iom = fields(m)
    base = m.diagnostics(0.0, y)
    q = quat_exp(np.array([-0.3, 2.0, 0.9]))
    R = _rot(q)
    y2 = y.copy()
    y2[iphi] = y[iphi] @ R.T + np.array([1.0, 2.0, 3.0])
    y2[iv] = y[iv] @ R.T
    y2[ip] = quat_mul(np.broadcast_to(q, (m.N, 4)), y[ip])
    rot = m.diagnostics(0.0, y2)
    # superposed rigid velocity field (w x phi + v0, material Omega + R^T w)
    w, v0 = np.array([0.5, -2.0, 1.0]), np.array([0.2, 0.0, -0.3])
    y3 = y.copy()
    y3[iv] += v0 + np.cross(w, y[iphi])
    Rs = np.array([_rot(p) for p in y[ip]])
    y3[iom] += np.einsum("kji,j->ki", Rs, w)
    spin = m.diagnostics(0.0, y3)
    for key in ("elastic", "dissipation_rate"):
        assert rot[key] == pytest.approx(base[key], rel=1e-12)
        if key == "dissipation_rate":
            assert spin[key] == pytest.approx(base[key], rel=1e-10)
    assert rot["kinetic"] == pytest.approx(base["kinetic"], rel=1e-12)
    for k in ("V", "U"):
        assert np.allclose(rot["strains"][k], base["strains"][k], rtol=1e-11, atol=1e-11)


@pytest.mark.parametrize("start,end", [("clamped", "free"), ("clamped", "clamped")])
def test_quaternion_scaling_has_no_physical_effect(start, end):
    rng = np.random.default_rng(5)
    m = model(6, start, end)
    y, yp = random_state(m, rng, unit=True), rng.standard_normal(m.n)
    iphi, iv, ip, iom = fields(m)
    y2 = y.copy()
    y2[ip] *= 1.3
    d1, d2 = m.diagnostics(0.0, y, yp), m.diagnostics(0.0, y2, yp)
    for key in ("elastic", "dissipation_rate", "external_power", "kinetic"):
        assert d2[key] == pytest.approx(d1[key], rel=1e-12, abs=1e-300)
    r1, r2 = residual(m, y, yp), residual(m, y2, yp)
    mask = np.ones(m.n, bool)
    mask[ip.ravel()] = False  # kinematic rows p' - 1/2 p*(0,Omega) scale with p
    assert np.allclose(r1[mask], r2[mask], rtol=1e-12, atol=1e-12 * np.abs(r1).max())


def test_held_nodes_and_loads():
    m = model(4, "clamped", "free")
    y = m.initial_state()
    r = residual(m, y, np.zeros(m.n))
    iphi, iv, ip, iom = fields(m)
    assert np.all(r[iv[0]] == 0.0)
    # free tip: momentum row = -(m g + F) * load_scale, m the half segment mass
    a = m.arrays
    mtip = a.seg_field("rhoA")[-1, 0] * a.seg_field("h")[-1, 0] / 2
    f = mtip * np.array([0.0, -9.81, 1.0]) + np.array([0.05, -0.02, 0.01])
    assert np.allclose(r[iv[-1]], -f, rtol=1e-12)
    m.load_scale = 0.25
    assert np.allclose(residual(m, y, np.zeros(m.n))[iv[-1]], -0.25 * f, rtol=1e-12)
    # the end moment acts on the last segment (material = spatial at the reference)
    assert np.allclose(residual(m, y, np.zeros(m.n))[iom[-1]],
                       -0.25 * np.array([0.001, 0.002, -0.003]), rtol=1e-12)


@pytest.mark.parametrize("start,end", [("clamped", "free"), ("pinned", "clamped")])
def test_static_jacobian_matches_finite_differences(start, end):
    rng = np.random.default_rng(6)
    m = model(4, start, end)
    m = RodStatics(m)
    y = random_state(m.model, rng, unit=True)
    r0 = np.empty(m.n_static)
    m.static_residual(y, r0)
    K = m.static_jacobian_sparse(y).toarray()
    eps = 1e-6
    Kn = np.empty_like(K)
    rp, rm = np.empty(m.n_static), np.empty(m.n_static)
    for k in range(m.n_static):
        e = np.zeros(m.n_static)
        e[k] = eps
        m.static_residual(m.static_retract(y, e), rp)
        m.static_residual(m.static_retract(y, -e), rm)
        Kn[:, k] = (rp - rm) / (2 * eps)
    # a fixed node's rows are identity rows (its increment is held at 0; residual 0)
    fixed = [0] if start != "free" else []
    fixed += [m.n_static - 3] if end != "free" else []
    for k in fixed:
        assert np.array_equal(K[k : k + 3], np.eye(m.n_static)[k : k + 3])
        assert np.all(r0[k : k + 3] == 0.0)
        Kn[k : k + 3] = K[k : k + 3]
    assert np.abs(K - Kn).max() <= 2e-6 * np.abs(K).max()
    ab = np.zeros((2 * m.kl_static + m.ku_static + 1, m.n_static))
    m.static_jacobian_band(y, ab)
    from scipy.linalg import solve_banded

    x = solve_banded((m.kl_static, m.ku_static), ab[m.kl_static :], r0)
    assert np.allclose(K @ x, r0, rtol=1e-9, atol=1e-12 * np.abs(r0).max())


def test_static_newton_converges_quadratically_and_retract_normalises():
    loads = [{"kind": "force", "vector": [2e-3, 0, 1e-3]},
             {"kind": "moment", "vector": [0, 1e-4, 0]}]
    rod = rod_model(8, tau=0.0, loads=loads)
    m = RodStatics(rod)
    y1 = rod.initial_state()
    r = np.empty(m.n_static)
    norms = []
    for _ in range(6):
        m.static_residual(y1, r)
        norms.append(np.abs(r).max())
        if norms[-1] < 1e-11:
            break
        y1 = m.static_retract(y1, np.linalg.solve(m.static_jacobian_sparse(y1).toarray(), -r))
    assert norms[-1] < 1e-11 and len(norms) <= 6
    assert norms[2] < 10 * norms[1] ** 2 / norms[0]  # quadratic
    q = rod.quaternions(y1)
    assert np.allclose(np.sum(q * q, axis=0), 1.0, rtol=1e-15, atol=1e-15)


@pytest.mark.parametrize(
    "path,value",
    [
        ("rod.length", 0.0),
        ("rod.length", -1.0),
        ("rod.length", float("nan")),
        ("material.density", 0.0),
        ("material.youngs_modulus", -1e6),
        ("section.width", 0.0),
        ("section.height", float("inf")),
        ("material.poisson_ratio", 0.6),
        ("material.poisson_ratio", -1.0),
        ("material.tau_S", -0.01),
        ("material.tau_B", -1.0),
        ("rod.elements", 0),
        ("rod.elements", 2.5),
        ("material.damping", "magic"),
        ("start.kind", "welded"),
        ("loads.0.vector", [1.0, 2.0]),
    ],
)
def test_parameter_validation_names_parameter_value_and_range(path, value):
    with pytest.raises(ParameterError) as exc:
        rod_problem().with_overrides({path: value})
    msg = str(exc.value)
    assert path.split(".")[-1] in msg and "allowed" in msg
    assert repr(value) in msg or str(value) in msg
    assert isinstance(exc.value, ValueError)


def test_limits_are_allowed():
    rod_problem(1, poisson_ratio=0.5, tau=0.0)


@pytest.mark.parametrize("start,end", [("clamped", "free"), ("pinned", "clamped")])
def test_sparse_jacobian_has_a_fixed_pattern_inside_the_band(start, end):
    rng = np.random.default_rng(7)
    m = model(5, start, end, loads=False)
    pat = m.sparsity()
    y, yp = random_state(m, rng), rng.standard_normal(m.n)
    J = m.jacobian_sparse(0.0, y, yp, 5.0)
    assert np.array_equal(J.indptr, pat.indptr) and np.array_equal(J.indices, pat.indices)
    from runtime.solvers.protocols import band_to_dense

    ab = np.zeros((m.ldab, m.n), order="F")
    m.jacobian_band(0.0, y, yp, 5.0, ab)
    dense = band_to_dense(ab, m.kl, m.ku)
    assert np.array_equal(J.toarray(), dense)
    rows, cols = pat.nonzero()
    assert (rows - cols).max() <= m.kl and (cols - rows).max() <= m.ku
    assert m.dF_dy_sparse(0.0, y, yp).nnz == pat.nnz == m.dF_dyp_sparse(0.0, y, yp).nnz
