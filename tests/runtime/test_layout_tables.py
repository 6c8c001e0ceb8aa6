"""The whole-table forms of build-time helpers against their per-element definitions:
the state layout's index tables (runtime/model/layout_tables.py) against
generated/rod_layout's per-element functions, and quat_from_matrix on many matrices at
once against an independent conversion (SciPy's Rotation)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from generated import rod_layout as L
from runtime.model.layout_tables import layout_blocks, layout_table
from runtime.model.quaternion import quat_from_matrix, quat_rotation


@pytest.mark.parametrize("B", [0, 1, 3])
@pytest.mark.parametrize("N", [1, 2, 7])
def test_layout_tables_are_the_per_element_indices(N, B):
    cases = [(lambda i: L.node_phi(i, B), 0, N), (lambda i: L.node_v(i, B), 0, N),
             (lambda i: L.segment_p(i, B), 1, N), (lambda i: L.segment_omega(i, B), 1, N),
             (lambda i: L.segment_q(i, B), 1, N), (lambda j: L.joint_q(j, B), 0, N),
             (L.static_phi, 0, N), (L.static_theta, 1, N)]
    for at, first, last in cases:
        expected = [at(i) for i in range(first, last + 1)]
        assert layout_table(at, first, last).tolist() == expected
        assert np.array_equal(layout_blocks(at, first, last, 3),
                              np.array(expected)[:, None] + np.arange(3))
    assert layout_table(L.static_phi, 3, 2).size == 0
    with pytest.raises(ValueError, match="first"):
        layout_table(L.static_phi, -1, 2)


def test_model_index_tables_cover_the_state_once():
    """A Maxwell rod's tables (positions, velocities, quaternions, angular velocities,
    internal strains) partition its state."""
    from runtime.problem.assemble import build_model
    from runtime.problem.registry import load_problem

    m = build_model(load_problem("examples/maxwell_cantilever.toml", {"rod.elements": 5}))
    idx = np.concatenate([a.ravel() for a in (m.phi_index, m.v_index, m.p_index,
                                              m.omega_index, m.q_segment_index,
                                              m.q_joint_index)])
    assert np.array_equal(np.sort(idx), np.arange(m.n))


def test_quat_from_matrix_on_many_matrices_matches_scipy():
    rng = np.random.default_rng(3)
    q = rng.normal(size=(400, 4))
    # near the four branches of Shepperd's method: half turns about each axis, identity
    q[:4] = [[1, 0, 0, 0], [1e-9, 1, 0, 0], [0, 1e-9, 1, 0], [0, 0, 1e-9, 1]]
    R = quat_rotation(q)
    p = quat_from_matrix(R)
    assert p.shape == (400, 4) and np.all(p[:, 0] >= 0)
    assert np.allclose(np.linalg.norm(p, axis=1), 1.0, atol=1e-15)
    ref = Rotation.from_matrix(R).as_quat()[:, [3, 0, 1, 2]]     # scalar first
    ref *= np.where(ref[:, :1] < 0, -1.0, 1.0)
    assert np.max(np.abs(p - ref)) < 1e-13
    assert np.max(np.abs(quat_rotation(p) - R)) < 1e-14
    # one matrix and stacked shapes keep their leading shape
    assert quat_from_matrix(R[5]).shape == (4,)
    assert np.array_equal(quat_from_matrix(R[:6].reshape(2, 3, 3, 3)).reshape(6, 4), p[:6])
