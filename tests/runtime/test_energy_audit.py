"""The energy audit's quadrature (runtime.simulate.observers.EnergyIntegrator and
``audit_step`` in native/step_loop.c): 2D and P at the steps' ends, each step integrated on
the cubic through the last four ends.

References: exact integrals of polynomials on uneven nodes, and Gauss-Legendre (5 nodes)
on every step's own interpolant, computed here from the dense output independently of
the audit's arithmetic."""

from __future__ import annotations

import numpy as np
import pytest

from runtime.problem.registry import load_problem
from runtime.simulate import simulate as S
from runtime.simulate.observers import audit_integral, audit_polynomial
from runtime.solvers.native.step_loop import AUDIT_NODES


@pytest.mark.parametrize("m", [2, 3, 4])
def test_the_polynomial_integrates_polynomials_of_its_degree_exactly(m):
    rng = np.random.default_rng(7)
    t0, h = 1.3, 0.02
    # uneven earlier nodes (steps that grew and shrank), then t0 and t0 + h
    back = np.cumsum(rng.uniform(0.2, 3.0, m - 2) * h)[::-1]
    ht = [*(t0 - back).tolist(), t0, t0 + h]
    a, b = rng.standard_normal(m), rng.standard_normal(m)        # degree m - 1
    a[0] += 10.0             # 2D: positive (a negative mean over a step is cut off)

    def f(c, t):
        return sum(c[k] * (t - 1.0) ** k for k in range(m))

    def F(c, t):
        return sum(c[k] * (t - 1.0) ** (k + 1) / (k + 1) for k in range(m))

    hg = [(f(a, t), f(b, t)) for t in ht]
    coef = audit_polynomial(ht, hg, t0, h)
    assert len(coef[0]) == AUDIT_NODES
    for x in (0.0, 0.3, 1.0):
        t = t0 + x * h
        for c, p in ((a, coef[0]), (b, coef[1])):
            exact = F(c, t) - F(c, t0)
            assert audit_integral(m, p, x) * h == pytest.approx(exact, rel=1e-11,
                                                                abs=1e-15)


def test_a_negative_mean_of_2d_over_a_step_takes_the_steps_straight_line():
    """2D of four step ends of a cable leaving a floor (contact_flat_drop, W): the cubic
    through them integrates negative over the last step; the audit takes the trapezoid
    of the step's two ends. P (any sign) keeps its cubic."""
    h = 1.675e-7
    ht = [0.0958060, 0.0958062680 - 0.9e-7, 0.0958062680, 0.0958062680 + h]
    g2d = [598.0, 568.0, 6.7e-8, 5.6e-20]
    p_ext = [-3.0, 1.0, -2.0, 4.0]
    coef = audit_polynomial(ht, list(zip(g2d, p_ext, strict=True)), ht[2], h)
    assert audit_integral(4, coef[0], 1.0) * h == pytest.approx((6.7e-8 + 5.6e-20) / 2 * h)
    cubic = audit_polynomial(ht, list(zip(p_ext, p_ext, strict=True)), ht[2], h)
    assert coef[1] == cubic[1]


class _GaussOnInterpolants:
    """int 2D dt and int P dt over every step on its interpolant, 5-point Gauss-Legendre:
    the audit's former rule, with two more nodes (exact to degree 9); also their values
    at the output times ``t_out`` (Gauss on the part of the step before each)."""

    name, sparse = "gauss", False
    X, W = np.polynomial.legendre.leggauss(5)

    def __init__(self, model, t_out):
        self.model, self.d, self.w = model, 0.0, 0.0
        self.t_out, self.k, self.at_out = np.asarray(t_out), 1, [(0.0, 0.0)]

    def _integrals(self, dense, a, b):
        tq = a + (b - a) * (self.X + 1.0) / 2.0
        ys, yps = dense.values(tq)
        e = self.model.energies(tq, ys, yps)
        w = self.W / 2.0 * (b - a)
        return float(w @ e[:, 2]), float(w @ (e[:, 3] + e[:, 4]))

    def step(self, run, dense, t0, t1):
        if t1 == t0:
            return
        while self.k < self.t_out.size and self.t_out[self.k] <= t1 + 1e-12 * max(1, t1):
            d, w = self._integrals(dense, t0, min(self.t_out[self.k], t1))
            self.at_out.append((self.d + d, self.w + w))
            self.k += 1
        d, w = self._integrals(dense, t0, t1)
        self.d += d
        self.w += w


def _with_observer(monkeypatch, make):
    """simulate()'s run loop with one more observer ``make(model)`` (not sparse: every
    step, the compiled loop's audit after each), returned in ``got["obs"]``."""
    got = {}
    run_loop = S.run_loop

    def with_observer(model, *a, observers=(), **kw):
        got["obs"] = obs = make(model, observers)
        return run_loop(model, *a, observers=[*observers, obs], **kw)

    monkeypatch.setattr(S, "run_loop", with_observer)
    return got


@pytest.mark.parametrize("name, overrides, rel", [
    ("cantilever", {"rod.elements": 8, "simulation.t_end": 2.0}, 2e-6),       # 2D
    ("examples/base_excitation.toml", {"rod.elements": 6, "simulation.t_end": 1.0}, 1e-5),
    ("examples/pendulum.toml", {"rod.elements": 6, "simulation.t_end": 0.5}, 1e-6),  # P
])
def test_the_audit_agrees_with_gauss_legendre_on_the_interpolants(name, overrides, rel,
                                                                  monkeypatch):
    """Both integrate the same trajectory; they differ by the quadrature error only (the
    compiled loop's audit, the reference in Python every step beside it), at the end of
    the run and at every output time (inside steps: the audit's partial integrals)."""
    p = load_problem(name, overrides)
    t_out = np.arange(0.0, p.simulation.t_end + 0.5 * p.simulation.output_step,
                      p.simulation.output_step)
    got = _with_observer(monkeypatch, lambda model, obs: _GaussOnInterpolants(
        model, t_out[t_out <= p.simulation.t_end]))
    res = S.simulate(p)
    assert res.status == "finished"
    ref = got["obs"]
    at_out = np.array(ref.at_out)
    assert at_out.shape == (res.t.size, 2)
    scales = []
    for k, got_k in enumerate((res.dissipated, res.external_work)):
        scales.append(max(np.abs(got_k).max(), np.abs(at_out[:, k]).max()))
        np.testing.assert_allclose(got_k, at_out[:, k], rtol=0, atol=rel * scales[-1])
    assert max(scales) > 0
    assert abs(res.dissipated[-1] - ref.d) <= rel * max(scales)
    assert abs(res.external_work[-1] - ref.w) <= rel * max(scales)


class _StepDissipation:
    """The audit's running dissipation after every step (the compiled loop's)."""

    name, sparse = "steps", False

    def __init__(self, energy):
        self.energy, self.values = energy, []

    def step(self, run, dense, t0, t1):
        self.values.append(self.energy.dissipated)


def test_no_step_dissipates_a_negative_energy_through_impacts(monkeypatch):
    """A cable dropped on a floor: 2D falls from hundreds of watts to nothing within a
    step as a segment leaves the floor; the cubic through the last four step ends
    overshoots below zero there (ten steps did before the audit fell back to the step's
    straight line), the audit's dissipation must never decrease."""
    from runtime.simulate.observers import EnergyIntegrator

    p = load_problem("contact_flat_drop", {})
    got = _with_observer(monkeypatch, lambda model, obs: _StepDissipation(
        next(o for o in obs if isinstance(o, EnergyIntegrator))))
    res = S.simulate(p)
    assert res.status == "finished"
    d = np.array(got["obs"].values)
    assert d.size == res.counters["nstep"] and d[-1] > 0
    assert np.all(np.diff(d) >= 0.0)
    assert np.all(np.diff(res.dissipated) >= 0.0)


def test_a_restart_begins_the_audit_nodes_again():
    """The nodes of the audit's polynomial are the ends of the steps since the last
    (re)start: an input may jump at a restart (P does), so the compiled loop's nodes
    (CoreLink.push) and the Python integrator's (its restart hook) begin again there."""
    from runtime.problem.assemble import build_model
    from runtime.simulate.observers import EnergyIntegrator
    from runtime.solvers.bdf import BDF
    from runtime.solvers.integrator import consistent_initial

    p = load_problem("cantilever", {"rod.elements": 4})
    model = build_model(p)
    y_static = S.static_equilibrium(p, model).y
    model.at(0.0)
    y0, yp0 = consistent_initial(model, 0.0, y_static, np.zeros(model.n))
    solver = BDF(model, 0.0, y0, yp0, 1.0, rtol=1e-6, atol=1e-8)
    energy = EnergyIntegrator(model)
    assert energy.attach(solver)
    solver.advance(0.2, 1000)
    assert solver.core.s.nh == AUDIT_NODES
    solver.restart(solver.y.copy(), solver.yp.copy())
    assert solver.core.s.nh == 0
    solver.advance(0.3, 1000)
    assert solver.core.s.nh == AUDIT_NODES

    python = EnergyIntegrator(model)
    python._ht, python._hg = [0.0, 0.1], [(1.0, 0.0), (1.0, 0.0)]
    python.restart(None, type("R", (), {"t": 0.3, "y_after": y0, "y_before": y0})())
    assert python._ht == [] and python._hg == []
