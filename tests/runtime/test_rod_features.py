"""The rod model's problem features: follower loads, moving ends, curved and
tapered rods, the two assemblies (compiled C and the CasADi MX function), the stencil
table the band widths come from, objectivity of precurved rods."""

from __future__ import annotations

import math

import numpy as np
import pytest

from derive import discrete_rod as dr
from runtime.model.quaternion import quat_exp, quat_mul, quat_rotation
from runtime.problem.assemble import build_model
from tests.rods import (
    energy_rate_function,
    move_held_ends,
    random_state,
    residual,
    rod_model,
    rod_problem,
)

FOLLOWER = [
    {"kind": "force", "at": "end", "vector": [0.01, 0.02, -0.03], "frame": "follower"},
    {"kind": "force", "at": 2, "vector": [0.0, 0.01, 0.0]},
    {"kind": "moment", "at": "end", "vector": [0.0, 0.001, 0.002], "frame": "follower"},
    {"kind": "moment", "at": 3, "vector": [0.001, 0.0, 0.0]},
    {"kind": "distributed", "vector": [0.0, 0.0, -0.5]},
    {"kind": "gravity", "vector": [1.0, -9.81, 0.0]},
]
ARC = {"kind": "arc", "radius": 0.2, "angle": 80.0, "direction": [1, 0, 0],
       "toward": [0, 1, 0]}
HELIX = {"kind": "helix", "coil_radius": 0.02, "pitch": 0.01, "turns": 1.5}


def _moving(start="clamped", end="free", **kw):
    return move_held_ends(rod_model(6, start, end, loads=FOLLOWER, **kw))


@pytest.mark.parametrize("geometry", [None, ARC, HELIX])
@pytest.mark.parametrize("start,end", [("clamped", "free"), ("clamped", "clamped"),
                                       ("pinned", "pinned")])
def test_compiled_and_casadi_assemblies_agree(geometry, start, end):
    rng = np.random.default_rng(3)
    kw = {"geometry": geometry} if geometry else {}
    c = _moving(start, end, **kw)
    f = rod_model(6, start, end, loads=FOLLOWER, backend="casadi", **kw)
    f.arrays.par[:] = c.arrays.par
    f.drive = None
    y, yp = random_state(c, rng), rng.standard_normal(c.n)
    rc, rf = residual(c, y, yp), residual(f, y, yp)
    assert np.allclose(rc, rf, rtol=1e-12, atol=1e-12 * np.abs(rc).max())
    for cy in (1.0, 0.0):
        abc = np.zeros((c.ldab, c.n), order="F")
        abf = np.zeros_like(abc)
        c.jacobian_band2(0.0, y, yp, cy, 7.0, abc)
        f.jacobian_band2(0.0, y, yp, cy, 7.0, abf)
        assert np.allclose(abc[c.kl:], abf[c.kl:], rtol=1e-11,
                           atol=1e-11 * np.abs(abc).max())
    ec, ef = c.energy_scalars(0.0, y, yp), f.energy_scalars(0.0, y, yp)
    assert np.allclose(ec, ef, rtol=1e-11, atol=1e-14)
    dc, df = c.diagnostics(0.0, y, yp), f.diagnostics(0.0, y, yp)
    for k in ("V", "U"):
        assert np.allclose(dc["strains"][k], df["strains"][k], rtol=1e-11, atol=1e-12)


@pytest.mark.parametrize("start,end", [("clamped", "free"), ("pinned", "clamped")])
def test_follower_loads_and_moving_ends_jacobians_match_finite_differences(start, end):
    rng = np.random.default_rng(4)
    m = _moving(start, end, geometry=ARC)
    y, yp = random_state(m, rng), rng.standard_normal(m.n)
    J = m.jacobian_sparse(0.0, y, yp, 5.0).toarray()
    eps = 1e-6
    Jn = np.empty_like(J)
    for k in range(m.n):
        e = np.zeros(m.n)
        e[k] = eps
        Jn[:, k] = ((residual(m, y + e, yp) - residual(m, y - e, yp))
                    + 5.0 * (residual(m, y, yp + e) - residual(m, y, yp - e))) / (2 * eps)
    assert np.abs(J - Jn).max() <= 1e-6 * np.abs(J).max()


@pytest.mark.parametrize("start,end", [("clamped", "free"), ("clamped", "clamped"),
                                       ("pinned", "free")])
def test_energy_balance_includes_the_power_of_prescribed_motion(start, end):
    """d/dt (T + W) = -2D + P_ext + P_bc along the flow, with moving held ends (their
    velocity and the clamp frames' angular velocity prescribed) and follower loads."""

    rng = np.random.default_rng(5)
    m = _moving(start, end, geometry=HELIX)
    dE = energy_rate_function(m)
    d = m.differential
    for _ in range(3):
        y = random_state(m, rng)
        B = m.dF_dyp_sparse(0.0, y, np.zeros(m.n)).toarray()
        r0 = residual(m, y, np.zeros(m.n))
        assert np.abs(r0[~d]).max() < 1e-14      # held positions and velocities prescribed
        yp = m.prescribed_rates(0.0, np.zeros(m.n))      # their rates: v(t), a(t)
        r0 = residual(m, y, yp)
        yp[d] = np.linalg.solve(B[np.ix_(d, d)], -r0[d])
        assert np.abs(residual(m, y, yp)).max() < 1e-8 * np.abs(r0).max()
        T, W, D2, P, Pbc = m.energy_scalars(0.0, y, yp)
        lhs = float(dE(y, yp, m.arrays.par))
        assert Pbc != 0.0
        assert abs(lhs - (-D2 + P + Pbc)) <= 1e-9 * (abs(D2) + abs(P) + abs(Pbc) + abs(lhs))


def test_stencil_table_is_the_assembled_pattern():
    """The declarative element stencils (derive/discrete_rod.py), from which the band
    widths follow, cover exactly the non-zeros of the compiled Jacobian (all ends clamped,
    every load present)."""
    N = 5
    m = rod_model(N, "clamped", "clamped", loads=FOLLOWER)
    table = np.zeros((m.n, m.n), dtype=bool)
    for rows, cols in dr.element_stencils(N):
        table[np.ix_(rows, cols)] = True
    pattern = m.sparsity().toarray() != 0
    assert not np.any(pattern & ~table), "an entry outside the stencil table"
    # the table is tight on the band: its widest entries are real entries
    r, c = np.nonzero(pattern)
    assert (r - c).max() == m.kl and (c - r).max() == m.ku


@pytest.mark.parametrize("geometry", [ARC, HELIX, {"kind": "straight", "twist": 5.0}])
def test_precurved_rod_is_stress_free_and_objective(geometry):
    """The reference of a precurved/pretwisted rod carries no force; rotated and shifted
    rigidly, still none (zero strain energy, zero internal forces)."""
    m = rod_model(8, "free", "free", loads=False, geometry=geometry)
    y = m.reference.copy()
    d = m.diagnostics(0.0, y)
    assert d["elastic"] < 1e-25 and np.abs(residual(m, y, np.zeros(m.n))).max() < 1e-12
    q = quat_exp(np.array([0.4, -1.3, 2.2]))
    R = quat_rotation(q)
    y2 = y.copy()
    y2[m.phi_index] = y[m.phi_index] @ R.T + np.array([0.3, -1.0, 2.0])
    y2[m.p_index] = quat_mul(np.broadcast_to(q, (m.N, 4)), y[m.p_index])
    d2 = m.diagnostics(0.0, y2)
    assert d2["elastic"] < 1e-25
    assert np.abs(d2["resultants"]["F"]).max() < 1e-10
    assert np.abs(d2["resultants"]["M"]).max() < 1e-10
    assert np.abs(residual(m, y2, np.zeros(m.n))).max() < 1e-10


def test_taper_varies_the_section_along_the_rod():
    m = rod_model(4, loads=False, section={"kind": "circle", "radius": 0.01,
                                            "radius_end": 0.005})
    EA = m.arrays.seg_field("C_F")[:, 2]
    assert np.all(np.diff(EA) < 0)
    r_mid = 0.01 + (0.005 - 0.01) * (np.arange(4) + 0.5) / 4
    assert np.allclose(EA, 1e6 * np.pi * r_mid**2, rtol=1e-12)
    EI_seg = 1e6 * np.pi / 4 * r_mid**4
    CM = m.arrays.jnt_field("C_M")[:, 0]      # joints: the adjacent half cells in series
    assert np.allclose(CM[1:-1], 2.0 / (1.0 / EI_seg[:-1] + 1.0 / EI_seg[1:]), rtol=1e-12)
    assert CM[0] == pytest.approx(EI_seg[0]) and CM[-1] == pytest.approx(EI_seg[-1])


def _arc_tip_under_load(geometry, N: int = 16) -> np.ndarray:
    """Static end position of a precurved rod (radius 0.2 m, 90 degrees) under a dead tip
    force out of its plane."""
    from dataclasses import replace

    from runtime.simulate.simulate import static_equilibrium

    base = rod_problem(N, loads=[{"kind": "force", "at": "end", "vector": [0.0, 0.0, 0.02]}],
                       geometry={"kind": "arc", "radius": 0.2, "angle": 90.0})
    problem = base if geometry is None else replace(base, rod=replace(base.rod,
                                                                       geometry=geometry))
    model = build_model(problem)
    return static_equilibrium(problem, model).tip


def test_curve_and_points_geometries_reproduce_the_arc():
    """A callable quarter circle (Curve: parallel-transported frames) and a polyline through
    41 points of it (points: a cubic spline) give the Arc geometry's solution."""
    from runtime.problem.geometry import Curve, geometry_from_mapping

    R, L = 0.2, 0.2 * math.pi / 2

    def circle(s):
        a = np.asarray(s) / R
        return np.stack([R * np.sin(a), R * (1 - np.cos(a)), 0 * a], axis=-1)

    arc = _arc_tip_under_load(None)
    curve = _arc_tip_under_load(Curve(function=circle, curve_length=L, normal=(0.0, 1.0, 0.0)))
    pts = circle(np.linspace(0.0, L, 41))
    points = _arc_tip_under_load(geometry_from_mapping(
        {"kind": "points", "points": pts.tolist(), "normal": [0.0, 1.0, 0.0]}, None))
    assert np.linalg.norm(curve - arc) < 1e-8 * L
    assert np.linalg.norm(points - arc) < 1e-4 * L
    assert np.linalg.norm(arc - pts[-1]) > 0.05 * L          # the load does deflect the rod
