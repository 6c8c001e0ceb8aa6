"""Forward sensitivities in the BDF integrator (issue 34; runtime/solvers/sensitivity.py,
native/step_loop.c): IDAS's staggered corrector against the closed form of a damped
oscillator's sensitivity, the compiled loop against the NumPy path (the same bits), a
run with sensitivities against the plain run (the same steps and outputs bit for bit),
restarts at the inputs' breakpoints, and the errors one line names."""

from __future__ import annotations

import numpy as np
import pytest

from runtime.problem.registry import load_problem
from runtime.simulate.sensitivity import (
    resolve_parameters,
    simulate_with_sensitivities,
    with_parameters,
)
from runtime.simulate.simulate import simulate
from runtime.solvers.bdf import BDF
from runtime.solvers.protocols import DenseProblem

W, C = 2.0 * np.pi, 0.3          # the oscillator x'' + c x' + w^2 x = 0, x(0) = 1


def oscillator_x(t, w):
    wd = np.sqrt(w * w - C * C / 4)
    return np.exp(-C * t / 2) * (np.cos(wd * t) + C / (2 * wd) * np.sin(wd * t))


class Oscillator(DenseProblem):
    """y = (x, v): x' - v = 0, v' + w^2 x + c v = 0; the parameter w."""

    def __init__(self):
        super().__init__(lambda t, y, yp: np.array([yp[0] - y[1],
                                                    yp[1] + W * W * y[0] + C * y[1]]),
                         lambda t, y, yp: np.array([[0.0, -1.0], [W * W, C]]),
                         lambda t, y, yp: np.eye(2), 2)

    def sensitivity_residual(self, t, y, yp, ip, s, sp, out):
        out[:] = np.array([[0.0, -1.0], [W * W, C]]) @ s + sp + np.array([0.0, 2 * W * y[0]])


@pytest.mark.parametrize("compiled", [False, True])
@pytest.mark.parametrize("errcon", [False, True])
def test_oscillator_sensitivity_matches_the_closed_form(compiled, errcon):
    y0, yp0 = np.array([1.0, 0.0]), np.array([0.0, -W * W])
    s0, sp0 = np.zeros((1, 2)), np.array([[0.0, -2 * W]])
    sol = BDF(Oscillator(), 0.0, y0, yp0, 10.0, rtol=1e-8, atol=1e-11,
              sensitivities=(s0, sp0, np.array([W])), sens_errcon=errcon,
              compiled_loop=compiled)
    while sol.status == "running":
        sol.step()
    e = 1e-6
    exact = (oscillator_x(10.0, W + e) - oscillator_x(10.0, W - e)) / (2 * e)
    assert sol.sensitivities[0, 0] == pytest.approx(exact, rel=1e-4)
    assert sol.counters["nfevS"] > 0 and sol.counters["nniS"] > 0


def _run(prob, compiled, errcon):
    from runtime.problem.assemble import build_model
    from runtime.problem.parameters import array_directions
    from runtime.solvers.initial import consistent_initial, consistent_sensitivities

    m = build_model(prob)
    y0 = m.initial_state(0.0)
    m.enter_piece(0.0, np.inf)
    m.at(0.0)
    y0, yp0 = consistent_initial(m, 0.0, y0, np.zeros(m.n))
    rs = resolve_parameters(prob, ["youngs_modulus", "tau_S"])
    dirs, _ = array_directions(prob, rs, m.arrays)
    m.set_directions(dirs)
    s0, sp0 = consistent_sensitivities(m, 0.0, y0, yp0, np.zeros((2, m.n)))
    sol = BDF(m, 0.0, y0, yp0, 0.2, rtol=1e-6, atol=1e-8, compiled_loop=compiled,
              sensitivities=(s0, sp0, np.array([r.value for r in rs])), sens_errcon=errcon)
    ts = []
    while sol.status == "running":
        sol.step()
        ts.append(sol.t)
    return np.array(ts), sol.y.copy(), sol.sensitivities.copy(), sol.counters


@pytest.mark.parametrize("errcon", [False, True])
def test_compiled_loop_and_numpy_path_take_the_same_steps(errcon):
    prob = load_problem("cantilever").with_overrides({
        "rod.elements": 6, "loads.0.time": {"kind": "step", "start": 0.0},
        "simulation.initial": "reference"})
    a, b = _run(prob, True, errcon), _run(prob, False, errcon)
    assert a[3] == b[3]
    assert np.array_equal(a[0], b[0]) and np.array_equal(a[1], b[1])
    assert np.array_equal(a[2], b[2])


def test_sensitivities_keep_the_plain_run_bit_for_bit():
    """The state's steps, counters and outputs are the plain run's: the sensitivities'
    own iteration matrix never touches the state's."""
    prob = load_problem("cantilever").with_overrides({
        "rod.elements": 8, "simulation.t_end": 0.5, "simulation.output_step": 0.01})
    plain = simulate(prob)
    res, sens = simulate_with_sensitivities(prob, ["E", "tau_S"])
    assert {k: v for k, v in res.counters.items() if not k.endswith("S")} == plain.counters
    for a in ("t", "tip", "start", "kinetic", "elastic", "dissipated", "centreline"):
        assert np.array_equal(getattr(res, a), getattr(plain, a)), a
    assert sens.channels["tip/E"].shape == res.tip.shape
    assert sens.channels["tip/youngs_modulus"] is sens.channels["tip/E"]
    assert sens.channels["centreline/tau_S"].shape == res.centreline.shape
    assert sens.counters["nfevS"] > 0


def test_restarts_at_breakpoints_keep_the_sensitivities_consistent():
    """A ramp of the tip force (restarts where its rate jumps): the sensitivity of the
    tip to the load's size and to E against central differences of whole runs."""
    prob = load_problem("cantilever").with_overrides({
        "rod.elements": 6, "simulation.t_end": 0.4, "simulation.output_step": 0.01,
        "simulation.initial": "reference",
        "loads.0.time": {"kind": "ramp", "start": 0.05, "duration": 0.1}})
    res, sens = simulate_with_sensitivities(prob, ["loads.0.vector.x", "E"])
    tight = {"simulation.rtol": 1e-10}
    for name in ("loads.0.vector.x", "E"):
        v = resolve_parameters(prob, [name])[0].value
        d = 1e-4 * v
        p = simulate(with_parameters(prob, {name: v + d}).with_overrides(tight))
        m = simulate(with_parameters(prob, {name: v - d}).with_overrides(tight))
        fd = (p.tip - m.tip) / (2 * d)
        err = np.abs(sens.channels[f"tip/{name}"] - fd).max() / np.abs(fd).max()
        assert err < 2e-3, (name, err)


def test_bad_names_are_refused_before_anything_runs():
    prob = load_problem("cantilever")
    with pytest.raises(ValueError, match="rod.elements"):
        simulate_with_sensitivities(prob, ["rod.elements"])
    with pytest.raises(ValueError, match="youngs_modulus"):
        simulate_with_sensitivities(prob, ["youngs_modulo"])
