"""3-D shooting solver (references.cosserat_bvp) against the planar reference, closed forms
(roll-up, torsion, stretching) and invariances."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import simpson
from scipy.spatial.transform import Rotation

from references.cosserat_bvp import RodStiffness, solve_rod
from references.reissner import paper_cantilever, solve_reissner
from references.rollup import closing_moment, rollup_curve, rollup_tip

P = paper_cantilever()
ST = RodStiffness.isotropic(EA=P["EA"], GA=P["GA_s"], EI=P["EI"], GJ=0.7 * P["EI"])


@pytest.mark.parametrize(
    ("angle", "EA", "GA"),
    [(0.0, P["EA"], P["GA_s"]), (-0.7, P["EA"], P["GA_s"]), (0.3, math.inf, math.inf)],
)
def test_planar_case_matches_reissner(angle, EA, GA):
    """Rod along e3, dead tip force in the e1-e3 plane: the planar shooting reference."""
    L, F = P["L"], P["F"]
    st = RodStiffness.isotropic(EA=EA, GA=GA, EI=P["EI"], GJ=P["EI"])
    force = (F * math.cos(angle), 0.0, F * math.sin(angle))
    s = solve_rod(L, st, tip_force=force, load_steps=6, n_points=11)
    r = solve_reissner(F, L=L, EA=EA, GA=GA, EI=P["EI"], angle=angle)
    assert s.tip[0] == pytest.approx(r.tip[0], abs=1e-11 * L)
    assert s.tip[1] == 0.0
    assert s.tip[2] == pytest.approx(r.tip[1], abs=1e-11 * L)
    assert s.tip_rotation[1] == pytest.approx(r.tip_rotation, abs=1e-10)
    assert s.base_moment[1] == pytest.approx(r.base_moment, abs=1e-11 * F * L)
    assert s.elastic_energy == pytest.approx(r.elastic_energy, rel=1e-9)
    assert s.potential == pytest.approx(r.potential, rel=1e-9)
    np.testing.assert_allclose(s.base_force, force, atol=1e-13 * F)
    assert s.residual < 1e-12


def test_rigid_motion_invariance():
    """Rotating clamp frame, position and loads by Q rotates the solution by Q."""
    Q = Rotation.from_rotvec([0.3, -1.1, 0.5]).as_matrix()
    r0 = np.array([0.1, -0.2, 0.3])
    st = RodStiffness(0.9 * P["GA_s"], P["GA_s"], P["EA"], P["EI"], 1.7 * P["EI"], 0.6 * P["EI"])
    K0 = (1.0, -0.5, 2.0)
    F = np.array([0.02, -0.03, 0.01])
    M = np.array([0.001, 0.002, -0.0015])
    a = solve_rod(P["L"], st, K0=K0, tip_force=F, tip_moment=M, load_steps=4, n_points=21)
    b = solve_rod(P["L"], st, r0=r0, R0=Q, K0=K0, tip_force=Q @ F, tip_moment=Q @ M,
                  load_steps=4, n_points=21)
    np.testing.assert_allclose(b.r, r0 + a.r @ Q.T, atol=1e-11 * P["L"])
    np.testing.assert_allclose(b.R, Q @ a.R, atol=1e-10)
    np.testing.assert_allclose(b.Gamma, a.Gamma, atol=1e-10)
    np.testing.assert_allclose(b.K, a.K, atol=1e-9)
    assert b.elastic_energy == pytest.approx(a.elastic_energy, rel=1e-10)
    assert math.isnan(a.potential)  # dead moment: no potential


def test_balance_and_material_law_along_the_rod():
    F = np.array([0.02, -0.03, 0.01])
    f = np.array([0.0, 0.05, -0.02])
    s = solve_rod(P["L"], ST, K0=(0.5, 0.0, 1.0), tip_force=F, distributed_force=f,
                  load_steps=4, n_points=51)
    np.testing.assert_allclose(s.n, F + np.outer(P["L"] - s.s, f), atol=1e-12)
    # material law: N = C_F (Gamma - (0,0,1)), M = C_M (K - K0)
    N = np.einsum("kji,kj->ki", s.R, s.n)
    M = np.einsum("kji,kj->ki", s.R, s.m)
    np.testing.assert_allclose(N[:, 2], ST.EA * (s.Gamma[:, 2] - 1.0), atol=1e-12)
    np.testing.assert_allclose(M[:, 0], ST.EI1 * (s.K[:, 0] - 0.5), atol=1e-12)
    # orthonormal frames and zero end moment
    np.testing.assert_allclose(np.einsum("kji,kjl->kil", s.R, s.R), np.broadcast_to(
        np.eye(3), s.R.shape), atol=1e-13)
    np.testing.assert_allclose(s.m[-1], 0.0, atol=1e-12 * np.linalg.norm(F) * P["L"])


def test_virtual_work_3d():
    """Dead forces: d(potential)/d(amplitude) = -(load direction . displacement)."""
    F0 = np.array([0.03, -0.02, 0.01])
    f0 = np.array([0.0, 0.04, 0.0])
    h = 1e-4

    def solve(t, guess=None):
        return solve_rod(P["L"], ST, K0=(2.0, 0.0, 1.0), tip_force=t * F0,
                         distributed_force=t * f0, load_steps=[1.0] if guess is not None else 3,
                         guess=guess, n_points=401)

    s = solve(1.0)
    g = np.r_[s.base_force, s.base_moment / P["L"]] / np.linalg.norm(F0)  # F_s = |F0|
    dpot = (solve(1 + h, g).potential - solve(1 - h, g).potential) / (2 * h)
    # conjugate displacement: F0 . u(L) + int f0 . u ds (Simpson on the 401 samples)
    work = F0 @ s.tip_displacement + simpson(s.displacement @ f0, x=s.s)
    assert dpot == pytest.approx(-work, rel=1e-7)


def test_pure_torsion_and_stretch():
    L, T = P["L"], 1e-3
    s = solve_rod(L, ST, tip_moment=(0.0, 0.0, T), load_steps=1, n_points=5)
    np.testing.assert_allclose(s.tip_rotation, [0.0, 0.0, T * L / ST.GJ], atol=1e-14)
    np.testing.assert_allclose(s.tip_displacement, 0.0, atol=1e-15)
    # clamped end moved along the axis: N = EA delta / L exactly (straight bar)
    d = 1e-3 * L
    s = solve_rod(L, ST, end="clamped", end_displacement=(0.0, 0.0, d), load_steps=1)
    np.testing.assert_allclose(s.n, np.broadcast_to([0.0, 0.0, ST.EA * d / L], s.n.shape),
                               rtol=1e-10, atol=1e-12 * ST.EA * d / L)
    # clamped end twisted: torque GJ theta / L
    th = 0.4
    s = solve_rod(L, ST, end="clamped", end_rotation=(0.0, 0.0, th), load_steps=2)
    assert s.base_moment[2] == pytest.approx(ST.GJ * th / L, rel=1e-10)
    np.testing.assert_allclose(s.base_moment[:2], 0.0, atol=1e-12 * ST.GJ * th / L)


@pytest.mark.parametrize("fraction", [0.5, 1.0])
def test_rollup_by_end_moment(fraction):
    """Dead end moment about d2: circle of radius EI2/M; 2 pi EI/L closes it."""
    st = RodStiffness(2.0, 3.0, 5.0, 0.7, 1.3, 0.9)  # shear/extension play no role
    L = 2.0
    M = fraction * closing_moment(st.EI2, L)
    s = solve_rod(L, st, tip_moment=(0.0, M, 0.0), load_steps=int(8 * fraction), n_points=41)
    u, w, th = rollup_curve(s.s, M, st.EI2)
    np.testing.assert_allclose(s.r[:, 0], u, atol=1e-11 * L)
    np.testing.assert_allclose(s.r[:, 2], w, atol=1e-11 * L)
    np.testing.assert_allclose(s.r[:, 1], 0.0, atol=1e-14)
    np.testing.assert_allclose(s.Gamma, np.broadcast_to([0, 0, 1.0], s.Gamma.shape), atol=1e-13)
    np.testing.assert_allclose(s.n, 0.0, atol=1e-12 * M / L)
    tip = rollup_tip(M, st.EI2, L)
    if fraction == 1.0:  # the end returns to the clamp with its orientation
        np.testing.assert_allclose(s.tip, 0.0, atol=1e-11 * L)
        np.testing.assert_allclose(s.R[-1], np.eye(3), atol=1e-11)
        assert tip[0] == pytest.approx(0.0, abs=1e-15) and tip[1] == pytest.approx(0, abs=1e-15)
    else:  # half circle: tip at u = 2L/pi, w = 0
        assert tip[0] == pytest.approx(2 * L / math.pi, rel=1e-15)
        assert s.tip[0] == pytest.approx(2 * L / math.pi, rel=1e-11)
        assert s.tip_rotation[1] == pytest.approx(math.pi, rel=1e-11)


def test_rollup_about_d1_and_closed_form_limits():
    st = RodStiffness(2.0, 3.0, 5.0, 0.7, 1.3, 0.9)
    L, M = 2.0, 0.3
    s = solve_rod(L, st, tip_moment=(M, 0.0, 0.0), load_steps=1, n_points=5)
    u, w, th = rollup_tip(M, st.EI1, L)
    np.testing.assert_allclose(s.tip, [0.0, -u, w], atol=1e-12)
    assert rollup_tip(0.0, 1.0, 2.0) == (0.0, 2.0, 0.0)
    u, w, th = rollup_tip(1e-9, 1.0, 1.0)
    assert u == pytest.approx(0.5e-9, rel=1e-8) and w == pytest.approx(1.0, rel=1e-15)
    assert rollup_tip(-0.3, 1.0, 2.0)[0] == pytest.approx(-rollup_tip(0.3, 1.0, 2.0)[0])


def test_continuation_and_guess_give_the_same_solution():
    F = (0.05, 0.02, -0.01)
    a = solve_rod(P["L"], ST, tip_force=F, load_steps=5, n_points=3)
    g = np.r_[a.base_force, a.base_moment / P["L"]] / np.linalg.norm(F)
    b = solve_rod(P["L"], ST, tip_force=F, load_steps=[1.0], guess=g, n_points=3)
    c = solve_rod(P["L"], ST, tip_force=F, load_steps=[0.2, 0.7, 1.0], n_points=3)
    np.testing.assert_allclose(b.tip, a.tip, atol=1e-13)
    np.testing.assert_allclose(c.tip, a.tip, atol=1e-13)
    assert b.newton_iterations <= 2


@pytest.mark.parametrize(
    "kw",
    [
        {"end": "pinned"},
        {"R0": np.diag([1.0, 1.0, -1.0])},
        {"end": "clamped", "tip_force": (1.0, 0, 0)},
        {"end_displacement": (1.0, 0, 0)},
        {"point_forces": [(0.0, (1.0, 0, 0))]},
        {"load_steps": [0.5, 0.4, 1.0]},
        {"load_steps": 0},
        {"K0": (math.nan, 0, 0)},
    ],
)
def test_invalid_input(kw):
    with pytest.raises(ValueError):
        solve_rod(1.0, ST, **kw)
    with pytest.raises(ValueError):
        RodStiffness(1.0, 1.0, 1.0, math.inf, 1.0, 1.0)
