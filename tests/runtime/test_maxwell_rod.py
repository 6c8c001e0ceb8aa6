"""The generalized Maxwell rod's assembly: relaxation terms with internal strains.

The compiled C assembly against the CasADi MX assembly and finite differences, the energy
balance with the terms' stored energy and dissipation, the stencil table, the layout, and
the relaxed state of statics."""

from __future__ import annotations

import numpy as np
import pytest

from derive import discrete_rod as dr
from generated import rod_layout as L
from tests.rods import (
    MAXWELL,
    energy_rate_function,
    move_held_ends,
    random_state,
    residual,
    rod_model,
    with_internal_strains,
)

FOLLOWER = [{"kind": "force", "at": "end", "vector": [0.0, 0.02, 0.01], "frame": "follower"},
            {"kind": "moment", "at": 3, "vector": [0.001, 0.0, 0.002], "frame": "dead"},
            {"kind": "gravity", "vector": [0.0, -9.81, 0.5]}]


def _maxwell(start="clamped", end="free", backend="auto", **kw):
    return move_held_ends(rod_model(6, start, end, tau=None, loads=FOLLOWER,
                                    backend=backend, **MAXWELL, **kw))


def test_layout_of_the_relaxation_terms():
    for B in (0, 1, 4, dr.MAX_BRANCHES):
        for N in (1, 2, 3, 7):
            assert L.bandwidths(N, B) == dr.bandwidths(N, B), (N, B)
        c0, c = L.cell_sizes(B)
        assert (c0, c) == (6 + 3 * B, 13 + 6 * B)
        assert L.n_state(5, B) == c0 + 5 * c
    m = _maxwell()
    assert m.branches == 4
    idx = np.concatenate([m.phi_index.ravel(), m.v_index.ravel(), m.p_index.ravel(),
                          m.omega_index.ravel(), m.q_segment_index.ravel(),
                          m.q_joint_index.ravel()])
    assert np.array_equal(np.sort(idx), np.arange(m.n))          # every unknown once
    assert "segment 2 q_segment[4]" in m.describe_dof(int(m.q_segment_index[1, 1, 1]))
    with pytest.raises(ValueError, match="branches"):
        L.n_state(4, dr.MAX_BRANCHES + 1)


@pytest.mark.parametrize("start,end", [("clamped", "free"), ("clamped", "clamped"),
                                       ("pinned", "free")])
def test_compiled_casadi_and_finite_differences_agree(start, end):
    c, f = _maxwell(start, end), _maxwell(start, end, backend="casadi")
    if c.backend != "c":
        pytest.skip("no C compiler")
    rng = np.random.default_rng(3)
    y = with_internal_strains(c, random_state(c, rng), rng)
    yp = rng.standard_normal(c.n)
    r1, r2 = residual(c, y, yp), residual(f, y, yp)
    assert np.abs(r1 - r2).max() <= 1e-12 * np.abs(r1).max()
    assert np.abs(r1[c.q_segment_index]).max() > 0 and np.abs(r1[c.q_joint_index]).max() > 0
    e1, e2 = np.array(c.energy_scalars(0.0, y, yp)), np.array(f.energy_scalars(0.0, y, yp))
    assert np.abs(e1 - e2).max() <= 1e-12 * np.abs(e1).max()
    for cy, cj in ((1.0, 0.0), (0.0, 1.0), (1.0, 37.0)):
        a1 = np.zeros((c.ldab, c.n), order="F")
        a2 = np.zeros((c.ldab, c.n), order="F")
        c.jacobian_band2(0.0, y, yp, cy, cj, a1)
        f.jacobian_band2(0.0, y, yp, cy, cj, a2)
        assert np.abs(a1 - a2).max() <= 1e-12 * np.abs(a1).max()
    J = c.band_to_csc(a1, c.kl, c.ku).toarray()
    Jn = np.zeros_like(J)
    eps = 1e-7
    for k in range(c.n):
        d = np.zeros(c.n)
        d[k] = eps
        Jn[:, k] = ((residual(c, y + d, yp) - residual(c, y - d, yp))
                    + 37.0 * (residual(c, y, yp + d) - residual(c, y, yp - d))) / (2 * eps)
    assert np.abs(J - Jn).max() <= 1e-6 * np.abs(J).max()


def test_stencil_table_is_the_assembled_pattern_with_relaxation_terms():
    """(Branches with the equilibrium Poisson ratio: every term acts on every component,
    so no entry of the table is a structural zero.)"""
    same_nu = {"model": "generalized_maxwell",
               "branches": [{"youngs_modulus": 2e6, "poisson_ratio": 0.3, "tau": 0.01},
                            {"youngs_modulus": 5e5, "poisson_ratio": 0.3, "tau": 0.3}]}
    m = rod_model(5, "free", "clamped", tau=None, loads=FOLLOWER, **same_nu)
    assert m.branches == 2
    table = np.zeros((m.n, m.n), dtype=bool)
    for rows, cols in dr.element_stencils(5, m.branches):
        table[np.ix_(rows, cols)] = True
    pattern = m.sparsity().toarray() != 0
    assert not np.any(pattern & ~table), "an entry outside the stencil table"
    r, c = np.nonzero(pattern)
    # the lower band is attained; the upper band's widest entries are the viscous
    # couplings of node velocities across a cell (V_F), which a pure Maxwell rod lacks
    assert (r - c).max() == m.kl and (c - r).max() <= m.ku


@pytest.mark.parametrize("start,end", [("clamped", "free"), ("clamped", "clamped")])
def test_energy_balance_with_the_terms_stored_and_dissipated_energy(start, end):
    """d/dt (T + W) = -2D + P_ext + P_bc along the flow: W includes the energy stored in
    the relaxation terms, 2D their dissipation rate sum C_b/theta_b (dV - q_b)^2."""
    rng = np.random.default_rng(5)
    m = _maxwell(start, end)
    dE = energy_rate_function(m)
    d = m.differential
    for _ in range(3):
        y = with_internal_strains(m, random_state(m, rng), rng)
        Bm = m.dF_dyp_sparse(0.0, y, np.zeros(m.n)).toarray()
        yp = m.prescribed_rates(0.0, np.zeros(m.n))      # held ends: v(t), a(t)
        r0 = residual(m, y, yp)
        yp[d] = np.linalg.solve(Bm[np.ix_(d, d)], -r0[d])
        T, W, D2, P, Pbc = m.energy_scalars(0.0, y, yp)
        lhs = float(dE(y, yp, m.arrays.par))
        assert D2 > 0
        assert abs(lhs - (-D2 + P + Pbc)) <= 1e-9 * (abs(D2) + abs(P) + abs(Pbc) + abs(lhs))


def test_statics_sees_the_equilibrium_stiffness_and_relaxes_the_terms():
    """A held load lets every term relax: statics uses C_inf (the instantaneous stiffness
    minus the terms'), and the relaxed state has q_b = strain, so it is an equilibrium of
    the full dynamic residual with y' = 0."""
    from runtime.problem.registry import load_problem
    from runtime.simulate.simulate import static_equilibrium

    problem = load_problem("cantilever", {"rod.elements": 8}).with_overrides({})
    mapping = problem.to_mapping()
    mapping["material"] = {"model": "generalized_maxwell", "density": 1000.0,
                           "youngs_modulus": 1e6, "poisson_ratio": 0.3, **{
                               "branches": MAXWELL["branches"]}}
    from runtime.problem.assemble import build_model
    from runtime.problem.schema import Problem

    mx = Problem.from_mapping(mapping)
    kv = Problem.from_mapping({**mapping, "material": {"density": 1000.0,
                                                       "youngs_modulus": 1e6,
                                                       "poisson_ratio": 0.3, "tau": 0.0}})
    m_mx, m_kv = build_model(mx), build_model(kv)
    cf = m_mx.arrays.seg_field("C_F").copy()
    st_mx, st_kv = static_equilibrium(mx, m_mx), static_equilibrium(kv, m_kv)
    assert np.array_equal(m_mx.arrays.seg_field("C_F"), cf)      # restored after statics
    assert np.allclose(st_mx.tip, st_kv.tip, rtol=0, atol=1e-10)  # equilibrium E, nu
    y = m_mx.relaxed(st_mx.y)
    assert np.abs(y[m_mx.q_segment_index]).max() > 1e-4           # strained, relaxed
    m_mx.at(0.0)
    with m_mx.statics():
        pass
    r = residual(m_mx, y, np.zeros(m_mx.n), t=-1e-9)
    load = np.abs(m_mx.arrays.node_load("f_dead")).max()
    assert np.abs(r).max() < 1e-8 * max(load, 1.0)
