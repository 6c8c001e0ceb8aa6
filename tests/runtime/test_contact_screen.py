"""The contact's cheap paths keep its bits (issue 32, item 6; docs/design.md, section 14,
"Cost of contact, measured and missed").

(1) The in-reach screen of planes (rod_contact.c ``screened_far``): a segment is in reach
where its bound kernel (``rod_contact_plane_bound``) is at most CONTACT_CUTOFF delta, and
the error test's tolerances are loosened where that bound is within max(h, r): checked
here against the kernel itself, called segment by segment, on a rod crossing a tilted
plane whose pose has a quaternion of norm 1.7, moved so that chosen segments' bounds lie
just above, at and just below the thresholds (within and beyond the screen's margin).
(2) The energy audit's quadrature points on a rod with obstacles (kvrod_audit_powers):
2D and the powers bit for bit the full energies' (kvrod_energies_contact).
"""

from __future__ import annotations

import numpy as np
import pytest

from generated import rod_layout as L
from runtime.model.quaternion import quat_rotation
from runtime.problem.assemble import build_model
from tests.kernel_calls import call_compiled, energies_through
from tests.runtime.test_contact_tolerances import _cable


def _tilted(m, rng):
    """Obstacle 0 turned and moved: q of norm 1.7, its point shifted; (n, q)."""
    q = rng.standard_normal(4)
    q *= 1.7 / np.linalg.norm(q)
    q[0] = abs(q[0]) + 1.0                 # a turn well away from a half turn
    c = 0.05 * rng.standard_normal(3)
    m.contact.set_pose(0, c, q, np.zeros(3), np.zeros(3))
    a = m.contact.obs_field("axis")[0]
    n = quat_rotation(q / np.linalg.norm(q)) @ (a / np.linalg.norm(a))
    return n


def _bounds(m, y):
    """Every segment's gap bound by the compiled kernel, one call each."""
    obs = m.contact.obs[0]
    out = []
    for s in range(m.N):
        pa, pb = y[m.phi_index[s]], y[m.phi_index[s + 1]]
        out.append(call_compiled(m._clib, "rod_contact_plane_bound", phi_a=pa, phi_b=pb,
                                 obs=obs, cnt=m.contact.cnt[0, s])["g_lb"][0])
    return np.array(out)


def _states(m, rng, n, threshold):
    """Rods across the plane, each moved along its normal so that one segment's bound
    lands at threshold (1 + eps) for eps across the screen's margin and beyond."""
    delta = float(m.contact.cnt_field("delta")[0, 0])
    for eps in (-1e-3, -1e-9, 0.0, 1e-9, 1e-6, 1e-3, 1.0, 1e3, 1e6):
        y = m.reference.copy()
        z = np.linspace(-1.0, 1.0, m.N + 1)
        y[m.phi_index] = (np.outer(np.linspace(-0.5, 0.5, m.N + 1), [1.0, 0.3, -0.2])
                          + 0.01 * rng.standard_normal((m.N + 1, 3))
                          + np.outer(0.02 * z, n))
        b = _bounds(m, y)
        j = int(rng.integers(m.N))
        y[m.phi_index] += np.outer(np.ones(m.N + 1), n) * (
            threshold + eps * max(threshold, delta) - b[j])
        yield y


def test_the_screen_keeps_the_segments_in_reach_and_the_loosened_tolerances():
    rng = np.random.default_rng(5)
    m = build_model(_cable(40, 0.1))
    m.at(0.0)
    n = _tilted(m, rng)
    delta = float(m.contact.cnt_field("delta")[0, 0])
    cutoff = L.CONTACT_CUTOFF * delta
    near_edge = 0
    for y in _states(m, rng, n, cutoff):
        b = _bounds(m, y)
        near_edge += np.any(np.abs(b - cutoff) <= 1e-6 * cutoff)
        values = m.contact_values(0.0, y)[0]
        assert values[11] == np.count_nonzero(b <= cutoff)
    assert near_edge >= 3                    # the chosen bounds did land at the cutoff

    h = float(m.contact.cnt_field("h")[0, 0])
    r = float(m.contact.cnt_field("r")[0, 0])
    band = max(h, r)
    rtol, atol = 1e-6, np.full(m.n, 1e-9)
    touched = 0
    for y in _states(m, rng, n, band):
        b = _bounds(m, y)
        w0 = 1.0 / (rtol * np.abs(y) + atol)
        w = w0.copy()
        m.state_error_weights(y, rtol, atol, w)
        for s in range(m.N):
            moved = np.any(w[m.v_index[s]] != w0[m.v_index[s]]) or \
                np.any(w[m.v_index[s + 1]] != w0[m.v_index[s + 1]])
            if b[s] <= band:
                assert moved
                touched += 1
            elif s == 0 or b[s - 1] > band:   # a node of no near segment stays
                if s == m.N - 1 or b[s + 1] > band:
                    assert not moved
    assert touched > 0


@pytest.mark.parametrize("friction", [0.0, 0.3])
def test_the_audits_powers_with_obstacles_are_the_energies_own_bits(friction):
    """kvrod_audit_powers on a rod with a floor: 2D and P_ext, P_bc those of
    kvrod_energies_contact bit for bit (the contact's dissipation and its supports'
    share included), the kinetic energy and the obstacle's values not evaluated."""
    import tempfile
    from pathlib import Path

    from bench.contact import problem
    from runtime.io.results import write_problem
    from runtime.problem.registry import load_problem
    from tests.rods import random_state

    mapping = problem(True, 12, 0.1)
    mapping["obstacles"][0]["friction"] = friction
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "cable.toml"
        write_problem(path, mapping)
        m = build_model(load_problem(path))
    kern = m.c_kernels()
    assert kern.audit_energies and kern.audit_energies != kern.energies
    rng = np.random.default_rng(3)
    ys = []
    for _ in range(6):                     # the rod lowered onto the floor, partly in it
        y = random_state(m, rng)
        z = y[m.phi_index[:, 2]]
        y[m.phi_index[:, 2]] = -0.3 + 0.002 + 1e-7 * rng.standard_normal(z.size)
        ys.append(y)
    ys = np.array(ys)
    yps = rng.standard_normal(ys.shape)
    m.at(0.0)
    full = energies_through(kern, kern.energies, ys, yps)
    powers = energies_through(kern, kern.audit_energies, ys, yps)
    assert np.array_equal(powers[:, 2:5], full[:, 2:5])
    assert np.all(full[:, 2] != 0.0) and np.all(full[:, 0] > 0.0)
    assert np.all(powers[:, 0] == 0.0)
    in_reach = full[:, len(L.DIAG_SCALARS) + 11]
    assert np.all(in_reach > 0)            # the floor's terms are in these sums
    assert np.all(np.isnan(powers[:, len(L.DIAG_SCALARS):]))   # its values not written
