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


class _GaussOnInterpolants:
    """int 2D dt and int P dt over every step on its interpolant, 5-point Gauss-Legendre:
    the audit's former rule, with two more nodes (exact to degree 9)."""

    name, sparse = "gauss", False
    X, W = np.polynomial.legendre.leggauss(5)

    def __init__(self, model):
        self.model, self.d, self.w = model, 0.0, 0.0

    def step(self, run, dense, t0, t1):
        h = t1 - t0
        if h == 0.0:
            return
        tq = t0 + h * (self.X + 1.0) / 2.0
        ys, yps = dense.values(tq)
        e = self.model.energies(tq, ys, yps)
        w = self.W / 2.0 * h
        self.d += float(w @ e[:, 2])
        self.w += float(w @ (e[:, 3] + e[:, 4]))


@pytest.mark.parametrize("name, overrides, rel", [
    ("cantilever", {"rod.elements": 8, "simulation.t_end": 2.0}, 1e-6),
    ("examples/base_excitation.toml", {"rod.elements": 6, "simulation.t_end": 1.0}, 1e-5),
])
def test_the_audit_agrees_with_gauss_legendre_on_the_interpolants(name, overrides, rel,
                                                                  monkeypatch):
    """Both integrate the same trajectory; they differ by the quadrature error only (the
    compiled loop's audit, the reference in Python every step beside it)."""
    p = load_problem(name, overrides)
    got = {}
    run_loop = S.run_loop

    def with_reference(model, *a, observers=(), **kw):
        got["ref"] = ref = _GaussOnInterpolants(model)
        return run_loop(model, *a, observers=[*observers, ref], **kw)

    monkeypatch.setattr(S, "run_loop", with_reference)
    res = S.simulate(p)
    assert res.status == "finished"
    ref = got["ref"]
    diss, work = res.dissipated[-1], res.external_work[-1]
    scale = max(abs(diss), abs(work), abs(ref.d), abs(ref.w))
    assert scale > 0
    assert abs(diss - ref.d) <= rel * scale
    assert abs(work - ref.w) <= rel * scale
