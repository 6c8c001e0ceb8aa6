"""Rods with coupled sections (issue 26): full 6x6 stiffness and viscosity, mass centre
off the centreline, product of inertia. Jacobians against finite differences, the
energy balance along the flow, rigid motions, objectivity, the diagonal case through the
coupled kernels, the condensed Newton's structure, and the linear static response of
random sections against K^-1 f computed here."""

from __future__ import annotations

import numpy as np
import pytest

from runtime.model.arrays import coupled_arrays
from runtime.model.quaternion import quat_exp, quat_mul, quat_rotation
from runtime.model.rod import RodModel
from runtime.model.statics import RodStatics
from runtime.solvers.native.condensed import CondensedNewton
from runtime.solvers.statics import solve_static
from tests.coupled import coupled_model
from tests.rods import random_state, residual, rod_model

BCS = [("clamped", "free"), ("free", "free"), ("clamped", "clamped"), ("pinned", "clamped")]


def dense_jac(m, y, yp, cy, cj):
    ab = np.zeros((m.ldab, m.n), order="F")
    m.jacobian_band2(0.0, y, yp, cy, cj, ab)
    return m.band_to_csc(ab, m.kl, m.ku).toarray()


@pytest.mark.parametrize("start,end", BCS)
def test_coupled_jacobians_match_central_differences(start, end):
    rng = np.random.default_rng(11)
    m = coupled_model(rng, 5, start, end)
    y, yp = random_state(m, rng), rng.standard_normal(m.n)
    Jy, Jyp = dense_jac(m, y, yp, 1.0, 0.0), dense_jac(m, y, yp, 0.0, 1.0)
    eps = 1e-6
    Ny, Nyp = np.empty_like(Jy), np.empty_like(Jyp)
    for k in range(m.n):
        e = np.zeros(m.n)
        e[k] = eps
        Ny[:, k] = (residual(m, y + e, yp) - residual(m, y - e, yp)) / (2 * eps)
        Nyp[:, k] = (residual(m, y, yp + e) - residual(m, y, yp - e)) / (2 * eps)
    assert np.abs(Jy - Ny).max() <= 1e-6 * np.abs(Jy).max()
    assert np.abs(Jyp - Nyp).max() <= 1e-6 * max(1.0, np.abs(Jyp).max())
    rows, cols = np.nonzero(np.abs(Jy) + np.abs(Jyp))
    assert (rows - cols).max() <= m.kl and (cols - rows).max() <= m.ku


@pytest.mark.parametrize("start,end", [("clamped", "free"), ("free", "free"),
                                       ("pinned", "clamped")])
def test_coupled_energy_identity_along_the_flow(start, end):
    """d/dt (T + W) = -2D + P_ext + P_bc with y' solved from F(y, y') = 0 (the rate of
    T + W by central differences of the energies along y')."""
    rng = np.random.default_rng(12)
    m = coupled_model(rng, 6, start, end, varying=True)
    for _ in range(2):
        y = random_state(m, rng, unit=True)
        d = m.differential
        B = dense_jac(m, y, np.zeros(m.n), 0.0, 1.0)
        r0 = residual(m, y, np.zeros(m.n))
        yp = np.zeros(m.n)
        yp[d] = np.linalg.solve(B[np.ix_(d, d)], -r0[d])
        assert np.abs(residual(m, y, yp)).max() < 1e-8 * np.abs(r0).max()
        diag = m.diagnostics(0.0, y, yp)
        eps = 1e-6
        E = lambda z: sum(m.energy_scalars(0.0, z)[:2])  # noqa: E731
        lhs = (E(y + eps * yp) - E(y - eps * yp)) / (2 * eps)
        rhs = -diag["dissipation_rate"] + diag["external_power"] + diag["boundary_power"]
        scale = abs(diag["dissipation_rate"]) + abs(diag["external_power"]) + abs(lhs)
        assert abs(lhs - rhs) <= 2e-7 * scale
        assert diag["dissipation_rate"] > 0


def test_coupled_rigid_motion_gives_no_internal_forces_and_objectivity():
    rng = np.random.default_rng(13)
    m = coupled_model(rng, 6, "free", "free", loads=False)
    q = quat_exp(np.array([0.7, -1.1, 0.4]))
    R = quat_rotation(q)
    w, v0, c = np.array([2.0, -1.0, 3.0]), np.array([0.3, 0.1, -0.5]), np.array([0.1, -.2, .3])
    y = m.reference.copy()
    y[m.phi_index] = y[m.phi_index] @ R.T + c
    y[m.p_index] = quat_mul(np.broadcast_to(q, (m.N, 4)), y[m.p_index]) * rng.uniform(
        0.5, 2.0, (m.N, 1))
    y[m.v_index] = v0 + np.cross(w, y[m.phi_index])
    Rs = quat_rotation(y[m.p_index])
    y[m.omega_index] = np.einsum("kji,j->ki", Rs, w)
    d = m.diagnostics(0.0, y)
    assert abs(d["elastic"]) < 1e-20 and abs(d["dissipation_rate"]) < 1e-20
    assert np.allclose(d["resultants"]["F"], 0, atol=1e-12)
    assert np.allclose(d["resultants"]["M"], 0, atol=1e-12)
    # the residual of the rigid motion (zero accelerations) is inertial only: the same
    # with the stiffness and viscosity scaled (any internal force would change with them)
    r1 = residual(m, y, np.zeros(m.n))
    a = m.arrays.copy()
    a.segc[:, :36] *= 7.0
    a.jntc *= 7.0
    m7 = RodModel(a, m.reference)
    assert np.allclose(residual(m7, y, np.zeros(m.n)), r1, rtol=0, atol=1e-12)
    # objectivity: a superposed rotation and a superposed rigid velocity
    y = random_state(m, rng)
    base = m.diagnostics(0.0, y)
    y2 = y.copy()
    y2[m.phi_index] = y[m.phi_index] @ R.T + c
    y2[m.v_index] = y[m.v_index] @ R.T
    y2[m.p_index] = quat_mul(np.broadcast_to(q, (m.N, 4)), y[m.p_index])
    rot = m.diagnostics(0.0, y2)
    y3 = y.copy()
    y3[m.v_index] += v0 + np.cross(w, y[m.phi_index])
    y3[m.omega_index] += np.einsum("kji,j->ki", quat_rotation(y[m.p_index]), w)
    spin = m.diagnostics(0.0, y3)
    for key in ("elastic", "dissipation_rate", "kinetic"):
        assert rot[key] == pytest.approx(base[key], rel=1e-11)
    assert spin["elastic"] == pytest.approx(base["elastic"], rel=1e-12)
    assert spin["dissipation_rate"] == pytest.approx(base["dissipation_rate"], rel=1e-10)


@pytest.mark.parametrize("start,end", BCS)
def test_diagonal_matrices_through_the_coupled_kernels_are_the_diagonal_rod(start, end):
    """The coupled path with diagonal 6x6 matrices, no offset and no I12 is the diagonal
    rod to rounding (residual, Jacobian, energies, resultants, reactions)."""
    rng = np.random.default_rng(14)
    m = rod_model(6, start, end)
    a = m.arrays
    K = np.array([np.diag(np.r_[a.seg_field("C_F")[i], a.jnt_field("C_M")[1]])
                  for i in range(6)])
    V = np.array([np.diag(np.r_[a.seg_field("V_F")[i], a.jnt_field("V_M")[1]])
                  for i in range(6)])
    mc = RodModel(coupled_arrays(a, K, V), m.reference, drive=m.drive)
    assert mc.coupled and not m.coupled
    y, yp = random_state(m, rng), rng.standard_normal(m.n)
    r = residual(m, y, yp)
    assert np.abs(residual(mc, y, yp) - r).max() <= 1e-13 * np.abs(r).max()
    J = dense_jac(m, y, yp, 1.0, 3.0)
    assert np.abs(dense_jac(mc, y, yp, 1.0, 3.0) - J).max() <= 1e-13 * np.abs(J).max()
    d, dc = m.diagnostics(0.0, y, yp), mc.diagnostics(0.0, y, yp)
    for k in ("kinetic", "elastic", "dissipation_rate", "external_power", "boundary_power",
              *m.reaction_names):
        assert dc[k] == pytest.approx(d[k], rel=1e-12, abs=1e-15)
    for k in ("F", "M"):
        assert np.allclose(dc["resultants"][k], d["resultants"][k], rtol=1e-12, atol=1e-15)


def test_coupled_rod_condenses_block_tridiagonally():
    rng = np.random.default_rng(15)
    m = coupled_model(rng, 9, "clamped", "free")
    cond = CondensedNewton.build(m, m.n, m.kl, m.ku, m.ldab)
    assert cond is not None and cond.block_tridiagonal, cond.band_reason


@pytest.mark.parametrize("start", ["clamped"])
def test_random_sections_stretch_and_twist_as_the_inverse_stiffness_says(start):
    """A rod of a random coupled section pulled by an axial force at its free end (and
    clamped at the other): uniform strains
    [Gamma - e3; K] = K^-1 (0, 0, F, 0, 0, 0) (linear: a small load) in every segment and
    joint, the free end's included (its condensation is exact for a moment-free end)."""
    for seed in (21, 22, 23):
        rng = np.random.default_rng(seed)
        F = 1.2e-6
        loads = [{"kind": "force", "at": "end", "vector": [0.0, 0.0, F]}]
        m = coupled_model(rng, 8, start, "free", loads=loads, offset=False)
        K = np.block([[m.arrays.segc_field("C_FF")[1].reshape(3, 3),
                       m.arrays.segc_field("C_FM")[1].reshape(3, 3)],
                      [m.arrays.segc_field("C_FM")[1].reshape(3, 3).T,
                       m.arrays.jntc_field("C_MM")[1].reshape(3, 3)]])
        want = np.linalg.solve(K, [0, 0, F, 0, 0, 0])
        with m.statics():
            st = RodStatics(m)
            res = solve_static(st, m.initial_state())
        assert res.converged
        d = m.diagnostics(0.0, res.y)
        G = d["strains"]["V"] - np.array([[0], [0], [1.0]])
        U = d["strains"]["U"][:, 0 if start == "clamped" else 1:-1]   # existing joints
        scale = np.linalg.norm(want)
        assert np.abs(G - want[:3, None]).max() <= 1e-3 * scale
        assert np.abs(U - want[3:, None]).max() <= 1e-3 * scale


def test_coupled_stencil_table_is_the_assembled_pattern():
    """The coupled element stencils (derive/discrete_rod.py), from which the coupled band
    widths follow, cover exactly the non-zeros of the compiled Jacobian of a coupled rod
    (all ends clamped, follower loads present), and the band is tight."""
    from derive import discrete_rod as dr
    from tests.runtime.test_rod_features import FOLLOWER

    N = 6
    m = coupled_model(np.random.default_rng(16), N, "clamped", "clamped", loads=FOLLOWER)
    table = np.zeros((m.n, m.n), dtype=bool)
    for rows, cols in dr.element_stencils(N, 0, coupled=True):
        table[np.ix_(rows, cols)] = True
    pattern = m.sparsity().toarray() != 0
    assert not np.any(pattern & ~table), "an entry outside the stencil table"
    r, c = np.nonzero(pattern)
    assert (r - c).max() == m.kl and (c - r).max() == m.ku


def test_strain_rates_and_vtk_dissipation_of_a_coupled_rod():
    """RodModel.strain_rates against central differences of the strains along the
    velocity field, and the VTK output's per-element dissipation rates adding up to the
    rod's 2D (coupled viscosity blocks)."""
    from runtime.io.vtk import element_fields
    from runtime.model.quaternion import quat_mul as qm

    rng = np.random.default_rng(17)
    for start, end in (("clamped", "free"), ("free", "clamped")):
        m = coupled_model(rng, 6, start, end)
        y = random_state(m, rng, unit=True)
        Vd, Ud = m.strain_rates(0.0, y)
        eps = 1e-7

        def moved(s, m=m, y=y):
            z = y.copy()
            z[m.phi_index] += s * y[m.v_index]
            om = y[m.omega_index]
            z[m.p_index] = qm(y[m.p_index], quat_exp(s * om))
            return m.diagnostics(0.0, z)["strains"]

        sp_, sm_ = moved(eps), moved(-eps)
        assert np.allclose((sp_["V"] - sm_["V"]) / (2 * eps), Vd, rtol=1e-6, atol=1e-6)
        assert np.allclose((sp_["U"] - sm_["U"]) / (2 * eps), Ud, rtol=1e-6,
                           atol=1e-6 * np.abs(Ud).max())
        cell, point = element_fields(m, 0.0, y)
        total = cell["dissipation_rate_2D"].sum() + point["dissipation_rate_2D"].sum()
        assert total == pytest.approx(m.diagnostics(0.0, y)["dissipation_rate"], rel=1e-10)


def test_the_casadi_backend_refuses_a_coupled_rod_with_a_clear_message():
    from runtime.errors import GeneratedCodeError

    m = coupled_model(np.random.default_rng(18), 3)
    with pytest.raises(GeneratedCodeError, match="coupled sections.*compiled backend"):
        RodModel(m.arrays, m.reference, backend="casadi")


#: point moments at both ends, dead and follower (the free ends' condensations carry
#: them: docs/design.md, section 10, "Free ends"), beside a force and gravity
END_MOMENTS = [
    {"kind": "moment", "at": "end", "vector": [0.001, 0.002, -0.003]},
    {"kind": "moment", "at": "end", "frame": "follower", "vector": [-0.002, 0.001, 0.002]},
    {"kind": "moment", "at": "start", "vector": [0.002, -0.001, 0.001]},
    {"kind": "moment", "at": "start", "frame": "follower", "vector": [0.001, 0.003, -0.002]},
    {"kind": "force", "at": "end", "vector": [0.05, -0.02, 0.01]},
    {"kind": "gravity", "vector": [0.0, -9.81, 1.0]},
]


@pytest.mark.parametrize("start,end", [("free", "free"), ("pinned", "free"),
                                       ("free", "pinned")])
def test_coupled_jacobians_with_end_moments_match_central_differences(start, end):
    """Dead and follower moments at free and pinned ends: the condensation's resultant
    C_FE M turns with the end segment for a dead moment (its Jacobian entry)."""
    rng = np.random.default_rng(31)
    m = coupled_model(rng, 4, start, end, loads=END_MOMENTS)
    assert np.abs(m.arrays.segc_field("C_FE")[[0, -1]]).max() > 0
    y, yp = random_state(m, rng), rng.standard_normal(m.n)
    Jy = dense_jac(m, y, yp, 1.0, 0.0)
    eps = 1e-6
    Ny = np.empty_like(Jy)
    for k in range(m.n):
        e = np.zeros(m.n)
        e[k] = eps
        Ny[:, k] = (residual(m, y + e, yp) - residual(m, y - e, yp)) / (2 * eps)
    assert np.abs(Jy - Ny).max() <= 1e-6 * np.abs(Jy).max()


@pytest.mark.parametrize("start,end", [("free", "free"), ("pinned", "free")])
def test_coupled_energy_identity_with_end_moments(start, end):
    """d/dt (T + W) = -2D + P_ext + P_bc along the flow with moments at both ends: the
    power of a free end's moment through its condensed joint is part of P_ext."""
    rng = np.random.default_rng(32)
    m = coupled_model(rng, 5, start, end, loads=END_MOMENTS, varying=True)
    for _ in range(2):
        y = random_state(m, rng, unit=True)
        d = m.differential
        B = dense_jac(m, y, np.zeros(m.n), 0.0, 1.0)
        r0 = residual(m, y, np.zeros(m.n))
        yp = np.zeros(m.n)
        yp[d] = np.linalg.solve(B[np.ix_(d, d)], -r0[d])
        diag = m.diagnostics(0.0, y, yp)
        eps = 1e-6
        E = lambda z: sum(m.energy_scalars(0.0, z)[:2])  # noqa: E731
        lhs = (E(y + eps * yp) - E(y - eps * yp)) / (2 * eps)
        rhs = -diag["dissipation_rate"] + diag["external_power"] + diag["boundary_power"]
        scale = abs(diag["dissipation_rate"]) + abs(diag["external_power"]) + abs(lhs)
        assert abs(lhs - rhs) <= 2e-7 * scale


def _linear_static(m, f):
    """f(y) of the linear static response: dx = -J0^-1 r from the reference (r the
    residual of the loads, J0 the unloaded stiffness), f by central differences along it,
    (f(y(dx)) - f(y(-dx)))/2, so that terms of second order in the loads drop out."""
    import scipy.sparse.linalg as spl

    with m.statics():
        st = RodStatics(m)
        y = m.initial_state()
        r = np.empty(st.n_static)
        st.load_scale = 1.0
        st.static_residual(y, r)
        st.load_scale = 0.0
        dx = spl.spsolve(st.static_jacobian_sparse(y), -r)
        return 0.5 * (f(st.static_retract(y, dx)) - f(st.static_retract(y, -dx)))


def _section(m) -> np.ndarray:
    a = m.arrays
    B = a.segc_field("C_FM")[0].reshape(3, 3)
    return np.block([[a.segc_field("C_FF")[1].reshape(3, 3), B],
                     [B.T, a.jntc_field("C_MM")[1].reshape(3, 3)]])


@pytest.mark.parametrize("start,end,at,frame,F", [
    ("clamped", "free", "end", "dead", 0.0), ("clamped", "free", "end", "follower", 0.0),
    ("clamped", "free", "end", "dead", 1.0), ("free", "clamped", "start", "dead", 0.0),
    ("free", "clamped", "start", "follower", 1.0)])
def test_random_sections_under_an_end_moment_strain_as_the_inverse_stiffness_says(
        start, end, at, frame, F):
    """A random coupled section under a moment (and an axial force) at its free end:
    uniform strains K^-1 (n, m) in every segment and joint, the end segment's included
    (its condensation carries the moment: it used to assume none, and the end segment
    was O(1) off, the tip stretch O(h)). At s = 0 the resultants are minus the loads."""
    Mv, Fv = np.array([0.3, -0.2, 0.5]) * 1e-7, np.array([0.0, 0.0, F * 1e-5])
    for seed in (41, 42):
        loads = [{"kind": "moment", "at": at, "frame": frame, "vector": list(Mv)},
                 {"kind": "force", "at": at, "vector": list(Fv)}]
        m = coupled_model(np.random.default_rng(seed), 8, start, end, loads=loads,
                          offset=False)
        sign = 1.0 if at == "end" else -1.0
        want = np.linalg.solve(_section(m), sign * np.r_[Fv, Mv])
        G = _linear_static(m, lambda y, m=m: m.diagnostics(0.0, y)["strains"]["V"])
        U = _linear_static(m, lambda y, m=m: m.diagnostics(0.0, y)["strains"]["U"])
        U = U[:, 0 if start == "clamped" else 1:-1 if end == "free" else None]
        assert np.abs(G - want[:3, None]).max() <= 1e-6 * np.abs(want[:3]).max()
        assert np.abs(U - want[3:, None]).max() <= 1e-6 * np.abs(want[3:]).max()


def test_coupled_cantilever_under_a_tip_force_and_moment_converges_at_second_order():
    """A random coupled section, clamped, under a transverse force and a moment at its
    free end (the resultants vary along the rod): the linear tip displacement and
    rotation against the closed form of references/coupled_rods.py converge at second
    order (with the moment-free condensation the end segment was O(1) off and the tip
    first order); the interior strains are the continuum's. The end segment's own
    strain converges at first order when the strains vary along the rod (its virtual
    joint takes the segment's strain for the end's, as the clamp joint does)."""
    from references import coupled_rods as ref

    Mv, Fv = np.array([0.3, -0.2, 0.5]) * 1e-7, np.array([1.0, -0.5, 0.0]) * 1e-7 / 0.3
    errs = []
    for N in (8, 16, 32):
        m = coupled_model(np.random.default_rng(43), N, "clamped", "free", offset=False,
                          loads=[{"kind": "moment", "at": "end", "vector": list(Mv)},
                                 {"kind": "force", "at": "end", "vector": list(Fv)}])
        assert np.allclose(m.arrays.param("p_start"), [1, 0, 0, 0])   # straight along e3
        L = float(np.sum(m.arrays.seg_field("h")))
        want = ref.coupled_cantilever(_section(m), Fv, Mv, L)
        tip = _linear_static(m, m.tip_position)
        R = _linear_static(m, lambda y, m=m: m.end_frames(0.0, y)["end"])
        rot = np.array([R[2, 1], R[0, 2], R[1, 0]])        # the rotation's skew part
        s_mid = (np.arange(N) + 0.5) * L / N
        G = _linear_static(m, lambda y, m=m: m.diagnostics(0.0, y)["strains"]["V"]).T
        g_want = want["strains"](s_mid)[:, :3]
        errs.append([np.abs(tip - want["tip"]).max() / np.abs(want["tip"]).max(),
                     np.abs(rot - want["rotation"]).max() / np.abs(want["rotation"]).max()])
        inner = slice(N // 2 - 1, N // 2 + 1)      # exact for linear strain fields
        assert np.abs(G[inner] - g_want[inner]).max() < 1e-5 * np.abs(g_want).max()
    errs = np.array(errs)
    orders = np.log2(errs[:-1] / errs[1:])
    assert np.all(orders > 1.85), (errs, orders)
    assert errs[-1, 0] < 1e-3
