"""Tests of the static Newton solver with load stepping."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_bvp

from runtime.solvers.statics import StaticSolveError, solve_static
from tests.runtime.problems import AtanStatic, FoldStatic, PlanarElastica, SpringChainStatic


def test_spring_chain_matches_exact_solution():
    prob = SpringChainStatic(n=10, k=1.0, k3=5.0, P=20.0)
    res = solve_static(prob, np.zeros(10), load_steps=5)
    assert res.converged and prob.load_scale == 1.0
    assert np.allclose(res.y, prob.exact(), rtol=1e-10, atol=1e-12)
    assert res.iterations[0] == 0  # unloaded state already in equilibrium
    assert len(res.iterations) == len(res.load_scales) >= 2
    assert res.load_scales[-1] == 1.0
    assert res.total_iterations >= sum(res.iterations) > 0
    assert res.residual_norm <= 1e-10
    assert "Newton iterations" in res.message


def _elastica_reference(PL2_EI: float) -> tuple[float, float]:
    """Tip (x, y)/L of the continuous inextensible elastica, EI theta'' + P cos theta = 0,
    theta(0) = 0, theta'(1) = 0, solved independently with solve_bvp."""
    s = np.linspace(0.0, 1.0, 201)

    def rhs(s, u):  # u = [theta, theta', x, y]
        return np.vstack([u[1], -PL2_EI * np.cos(u[0]), np.cos(u[0]), np.sin(u[0])])

    def bc(ua, ub):
        return np.array([ua[0], ub[1], ua[2], ua[3]])

    guess = np.zeros((4, s.size))
    guess[2] = s
    sol = solve_bvp(rhs, bc, s, guess, tol=1e-10, max_nodes=100000)
    assert sol.success
    return float(sol.y[2, -1]), float(sol.y[3, -1])


def test_elastica_converges_to_reference():
    prob = PlanarElastica(n=200, P=3.0)
    res = solve_static(prob, np.zeros(prob.n_static))
    x_ref, y_ref = _elastica_reference(3.0)
    x, y = prob.tip(res.y)
    assert abs(x - x_ref) < 2e-4 and abs(y - y_ref) < 2e-4
    assert y_ref > 0.6  # a large deflection
    assert all(i <= 8 for i in res.iterations)


@pytest.mark.parametrize("line_search", ["natural", "residual"])
@pytest.mark.parametrize("watchdog", [0, 4])
@pytest.mark.parametrize("c", [3.0, -4.0, 10.0])
def test_line_search_handles_overshooting_newton(c, watchdog, line_search):
    # Full Newton from 0 diverges for atan(x - c), |c| > 1.39; damped Newton converges
    # within the single load step.
    prob = AtanStatic([c])
    res = solve_static(
        prob, np.zeros(1), load_steps=1, grow=1.0, watchdog=watchdog, line_search=line_search
    )
    assert res.converged
    assert abs(res.y[0] - c) < 1e-9
    assert res.line_search_backtracks > 0
    assert res.load_cuts == 0
    assert (res.watchdog_restarts > 0) == (watchdog > 0)
    assert len(res.iterations) == 2 and res.iterations[1] < 20


def test_failed_line_search_cuts_the_load_step():
    # Coupled through the norm, the residual line search fails at full load; the load
    # step is cut instead of looping, and the run still converges.
    prob = AtanStatic([3.0, -4.0, 0.5])
    res = solve_static(
        prob, np.zeros(3), load_steps=1, grow=1.0, watchdog=0, line_search="residual"
    )
    assert res.converged and res.load_cuts >= 1
    assert np.allclose(res.y, [3.0, -4.0, 0.5], atol=1e-9)
    assert res.total_iterations > sum(res.iterations)  # the failed attempt is counted
    # The default (watchdog + natural monotonicity) needs no cut.
    res = solve_static(prob, np.zeros(3), load_steps=1, grow=1.0)
    assert res.converged and res.load_cuts == 0


def test_large_elastica_load_in_one_step():
    prob = PlanarElastica(n=50, P=20.0)
    res = solve_static(prob, np.zeros(prob.n_static), load_steps=1)
    assert res.converged and res.load_scales[-1] == 1.0
    r = np.empty(prob.n_static)
    prob.static_residual(res.y, r)
    assert np.abs(r).max() < 1e-8


def test_limit_point_raises_with_last_converged_state():
    prob = FoldStatic()
    with pytest.raises(StaticSolveError) as info:
        solve_static(prob, np.array([np.sqrt(2.0)]), load_steps=10, max_iter=30)
    err = info.value
    assert 0.6 < err.load_scale <= 2.0 / 3.0
    assert abs(err.y[0] ** 2 - (2.0 - 3.0 * err.load_scale)) < 1e-9
    assert prob.load_scale == err.load_scale
    assert "load_scale" in str(err)


def test_load_steps_drive_the_arrays_only_where_the_load_factor_reaches_them(monkeypatch):
    """A load step of a rod whose inputs do not read the load factor (external loads take
    it from the arrays) does not drive the arrays again; a prescribed end motion, scaled by
    it in statics, is driven at every load factor (its end lands where the motion puts
    it at t = 0-, as it did before)."""
    from runtime.problem.assemble import ProblemDrive, build_model
    from runtime.problem.registry import load_problem
    from runtime.simulate.simulate import static_equilibrium

    calls: list[float] = []
    original = ProblemDrive.apply

    def counted(self, a, t, **kw):
        calls.append(kw.get("scale", 1.0))
        return original(self, a, t, **kw)

    monkeypatch.setattr(ProblemDrive, "apply", counted)
    p = load_problem("cantilever", {"rod.elements": 6, "statics.load_steps": 5})
    static_equilibrium(p, build_model(p))
    assert len(calls) <= 4            # build, the statics block's entry and exit

    calls.clear()
    p = load_problem("examples/base_excitation.toml", {"rod.elements": 6,
                                                       "statics.load_steps": 5})
    m = build_model(p)
    st = static_equilibrium(p, m)
    scales = sorted(set(calls))                 # every load factor the steps took
    assert scales[0] == 0.0 and scales[-1] == 1.0 and len(scales) >= 4, calls
    held = m.drive.held_positions("start", np.array([0.0]))[:, 0]
    assert np.array_equal(st.y[m.phi_index[0]], held)
