"""The error test's tolerances near obstacles (issue 32, item 6; docs/design.md, section 14).

A rod with obstacles gets, for every segment whose gap bound lies within its length of an
obstacle, the absolute tolerance of its nodes' velocities raised to the positions' times
the contact's rate ``sqrt(k / rho A)``, and while any segment is that near, the angular
velocities of all its segments to the rotation's times the same rate
(``kvrod_contact_error_weights``). Checked here: the weights against
the rule written out in NumPy from the problem's own numbers (the plane's gap, the law's
stiffness, the section's rho A), the compiled step loop against the Python path of bdf.py
step for step on a rod landing on a floor, and that a cable landing on a floor takes far
fewer steps with the rule than without, its energy audit closed either way.
"""

from __future__ import annotations

import math
import tempfile
from pathlib import Path

import numpy as np
import pytest

from runtime.problem.assemble import build_model
from runtime.problem.registry import load_problem
from runtime.problem.schema import Problem
from runtime.simulate.simulate import default_atol, simulate
from runtime.solvers.bdf import BDF
from runtime.solvers.integrator import consistent_initial
from runtime.solvers.native.loader import load

FLOOR = -0.3


def _cable(N: int, t_end: float, floor: bool = True) -> Problem:
    """bench/contact.py's cable (1 m, 2 mm polymer, pinned, released horizontal), N
    elements, onto a floor 0.3 m below the pin."""
    from bench.contact import problem
    from runtime.io.results import write_problem

    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "cable.toml"
        write_problem(path, problem(floor, N, t_end))
        return load_problem(path)


def test_velocity_tolerances_near_a_floor_follow_the_positions_times_the_contact_rate():
    p = _cable(10, 0.1)
    m = build_model(p)
    assert m.state_error_weights is not None
    y = m.reference.copy()
    r = float(p.contact_radii()[0])
    h = p.rod.length / m.N
    # the rod sloping down to the floor: the first nodes far above it, the last on it
    z = np.linspace(1.0, 0.0, m.N + 1) ** 2 + FLOOR + r
    y[m.phi_index[:, 2]] = z
    y[m.v_index] = np.linspace(-1.0, 1.0, m.v_index.size).reshape(m.v_index.shape)
    y[m.omega_index] = 0.5
    rtol = 1e-6
    atol = default_atol(p, m, y)
    w0 = 1.0 / (rtol * np.abs(y) + atol)
    w = w0.copy()
    w[m.v_index[-1, 0]] = 0.0                    # left out of the test: stays out
    m.state_error_weights(y, rtol, atol, w)

    law = p.contact_law()
    rate = math.sqrt(law.stiffness / p.segment_matrices()["rhoA"][0])
    want = w0.copy()
    gaps = z - FLOOR - r
    near = 0
    for s in range(m.N):
        a, b = m.phi_index[s], m.phi_index[s + 1]
        bound = 0.5 * (gaps[s] + gaps[s + 1]) - 0.5 * np.linalg.norm(y[b] - y[a])
        if bound > max(h, r):
            continue
        near += 1
        for q in np.concatenate([m.v_index[s], m.v_index[s + 1]]):
            want[q] = 1.0 / (rtol * abs(y[q]) + max(atol[q], rate * atol[m.phi_index[0, 0]]))
    for q in m.omega_index.ravel():              # a rod near an obstacle: every segment's
        want[q] = 1.0 / (rtol * abs(y[q]) + max(atol[q], rate * atol[m.p_index[0, 0]]))
    want[m.v_index[-1, 0]] = 0.0
    assert 0 < near < m.N                        # some segments near the floor, some not
    assert np.allclose(w, want, rtol=1e-14, atol=0.0)
    assert np.array_equal(w[m.phi_index], w0[m.phi_index])   # positions untouched
    assert np.any(w[m.v_index] < 1e-3 * w0[m.v_index])        # and loosened by far
    # lifted far off the floor: nothing changes
    y[m.phi_index[:, 2]] += 1.0
    w = 1.0 / (rtol * np.abs(y) + atol)
    w1 = w.copy()
    m.state_error_weights(y, rtol, atol, w)
    assert np.array_equal(w, w1)


def test_a_rod_without_obstacles_keeps_its_tolerances():
    m = build_model(_cable(10, 0.1, floor=False))
    assert m.state_error_weights is None
    assert m.c_kernels().error_weights == 0


@pytest.mark.skipif(load() is None, reason="no C compiler")
def test_the_compiled_loop_takes_the_python_paths_steps_on_a_rod_landing_on_a_floor():
    p = _cable(8, 0.25)
    m = build_model(p)
    m.at(0.0)
    y0, yp0 = consistent_initial(m, 0.0, m.initial_state(0.0), np.zeros(m.n))
    atol = default_atol(p, m, y0)
    kw = dict(rtol=1e-6, atol=atol)
    py = BDF(m, 0.0, y0, yp0, 0.25, compiled_loop=False, **kw)
    c = BDF(m, 0.0, y0, yp0, 0.25, **kw)
    assert not py.compiled and c.compiled and c.core.s.errw
    landed = False
    while py.status == "running" and py.nstep < 20_000:
        py.step()
        c.step()
        assert c.t == py.t and c.order == py.order and c.counters == py.counters
        assert np.array_equal(c.y, py.y) and np.array_equal(c.yp, py.yp)
        landed = landed or bool(np.min(py.y[m.phi_index[:, 2]]) < FLOOR + 0.0021)
    assert py.status == "finished" and landed


def test_a_cable_landing_on_a_floor_takes_far_fewer_steps_with_its_audit_closed():
    """Deterministic step counts, not times."""
    p = _cable(20, 0.5)
    runs = {}
    for rule in (True, False):
        m = build_model(p)
        if not rule:
            m.contact._struct.tolerance_rate = 0.0      # the run's tolerances everywhere
        res = simulate(p, model=m)
        assert res.status == "finished"
        assert res.audit().max_rel < 1e-4
        assert res.obstacles[0]["gap_min"].min() > -0.1 * float(p.contact_radii()[0])
        runs[rule] = res.counters["nstep"]
    assert runs[True] < 0.7 * runs[False]
