"""The compiled step loop (runtime/solvers/native/step_loop.c) against the Python path of bdf.py.

The two implement the same algorithm statement for statement and round alike, so they
must take *identical* steps: same times, states, orders and counters after every step,
on problems called through Python callbacks (chains, DAEs, fixed steps) and on the rod's
compiled kernels (loads constant, loads moved with time through the drive callback, a
generalized Maxwell rod). The run loop's observers, moved into the compiled loop (energy
audit, samples) or called only at its stops (maxima, snapshots, progress), must give the
series of the every-step Python run.
"""

from __future__ import annotations

import math
import os
from functools import partial

import numpy as np
import pytest

from runtime.problem.registry import load_problem
from runtime.simulate.simulate import simulate, static_equilibrium
from runtime.solvers import driver
from runtime.solvers.bdf import BDF, IntegrationError
from runtime.solvers.integrator import consistent_initial
from runtime.solvers.native.loader import load
from tests.rods import MAXWELL, rod_model
from tests.runtime.problems import KVChain, Oscillator, Robertson, Scalar

pytestmark = pytest.mark.skipif(load() is None, reason="no C compiler")


def _pair(problem, y0, yp0, t_end, **kw) -> tuple[BDF, BDF]:
    py = BDF(problem, 0.0, y0, yp0, t_end, compiled_loop=False, **kw)
    c = BDF(problem, 0.0, y0, yp0, t_end, **kw)
    assert not py.compiled and c.compiled
    return py, c


def _assert_same_steps(py: BDF, c: BDF, max_steps: int = 100_000) -> None:
    while py.status == "running" and py.nstep < max_steps:
        py.step()
        c.step()
        assert c.t == py.t and c.t_old == py.t_old and c.order == py.order
        assert np.array_equal(c.y, py.y) and np.array_equal(c.yp, py.yp)
        assert c.counters == py.counters
    assert c.status == py.status
    a, b = py.dense_output(), c.dense_output()
    tm = 0.5 * (py.t_old + py.t)
    assert np.array_equal(a(tm), b(tm)) and np.array_equal(a.derivative(tm), b.derivative(tm))


def test_same_steps_on_a_stiff_chain_through_callbacks():
    chain = KVChain(M=15)
    y0 = chain.initial()
    py, c = _pair(chain, y0, chain.rhs(y0), 2.0, rtol=1e-6, atol=1e-8)
    _assert_same_steps(py, c)
    assert py.nstep > 100 and py.netf > 0      # error-test failures happened on the way


def test_same_steps_on_a_dae_with_suppressed_algebraic_error():
    prob = Robertson()
    py, c = _pair(prob, np.array([1.0, 0.0, 0.0]), np.array([-0.04, 0.04, 0.0]), 4e5,
                  rtol=1e-6, atol=np.array([1e-8, 1e-12, 1e-8]), suppress_alg=True)
    _assert_same_steps(py, c)
    assert py.status == "finished"


@pytest.mark.parametrize("max_order", [1, 5])
def test_same_steps_at_a_fixed_step_and_limited_order(max_order):
    prob = Oscillator(1.0)
    y0 = np.array([1.0, 0.0])
    py, c = _pair(prob, y0, np.array([0.0, -1.0]), 1.0, fixed_step=0.01,
                  max_order=max_order)
    _assert_same_steps(py, c)
    assert py.nstep == 100


def _released(model):
    """The reference at rest under the rod's dead loads: consistent (y0, y0')."""
    model.at(0.0)
    return consistent_initial(model, 0.0, model.initial_state(0.0), np.zeros(model.n))


_KV, _MAXWELL, _PINNED = dict(), dict(tau=None, **MAXWELL), dict(start="pinned", end="clamped")


@pytest.mark.parametrize("kw,chunk", [(_KV, 1), (_KV, 2), (_KV, None), (_MAXWELL, 2),
                                      (_MAXWELL, None), (_PINNED, 1), (_PINNED, None)])
def test_same_steps_on_the_rod_kernels(kw, chunk, monkeypatch):
    """Also: the compiled loop evaluates J element by element and factors each cell
    behind the sweep (step_loop.c's jac_factor_cells), with windows slid after every
    1 or 2 elements or by the default chunk; the Python path stores the whole J first.
    A Maxwell rod's loop forms only what the factorisation reads of the internal
    strains' rows and columns (kvrod_jacobian_band_cells_relaxed), the Python path all
    of J: the same steps."""
    from runtime.solvers.native.step_loop import CoreLink

    if chunk is not None:
        monkeypatch.setattr(CoreLink, "JAC_CHUNK", chunk)
    m = rod_model(8, **kw)          # dead loads at the end and gravity: the rod moves
    y0, yp0 = _released(m)
    py, c = _pair(m, y0, yp0, 0.3, rtol=1e-6, atol=1e-8)
    assert c.core.s.jac_cells and c.core.s.jchunk == CoreLink.JAC_CHUNK
    kern = m.c_kernels()
    expect = kern.jacobian_cells_relaxed[0] if m.branches else kern.jacobian_cells
    assert c.core.s.jac_cells == expect
    _assert_same_steps(py, c)
    assert py.nstep > 50


def test_same_steps_with_the_configuration_error_test_and_the_order_bound():
    """A generalized Maxwell rod as simulate runs it: velocities out of the error test,
    orders 3-5 only on steps above D_k / sigma_g (issue 27)."""
    m = rod_model(8, tau=None, **MAXWELL)
    y0, yp0 = _released(m)
    sigma = m.glassy_decay_rate()
    assert math.isfinite(sigma) and sigma > 0.0
    py, c = _pair(m, y0, yp0, 0.5, rtol=1e-6, atol=1e-8, error_mask=~m.velocity_mask,
                  stiff_decay_rate=sigma)
    _assert_same_steps(py, c)
    assert py.nstep > 50


def test_same_steps_with_time_dependent_loads_through_the_drive_callback():
    p = load_problem("examples/base_excitation.toml",
                     {"rod.elements": 6, "simulation.t_end": 0.6})
    from runtime.problem.assemble import build_model

    m = build_model(p)
    assert m.drive is not None and m.drive.time_dependent
    y0 = m.constrain(m.initial_state(0.0))
    y0, yp0 = consistent_initial(m, 0.0, y0, np.zeros(m.n))
    calls = {"n": 0}
    kern = m.c_kernels()
    inner = kern.drive

    def counting(t):
        calls["n"] += 1
        return inner(t)

    py, c = _pair(m, y0, yp0, 0.6, rtol=1e-6, atol=1e-9)
    c._core._set_drive(counting)
    _assert_same_steps(py, c)
    # the clamp moves at every t: the loads are re-driven for every new time
    assert calls["n"] >= c.nstep


def test_advance_stops_at_t_stop_at_a_watched_sign_change_and_after_max_steps():
    prob = Oscillator(2.0)      # x = cos(2 t): the velocity turns negative at once
    s = BDF(prob, 0.0, np.array([1.0, 0.0]), np.array([0.0, -4.0]), 10.0, rtol=1e-8,
            atol=1e-10)
    assert s.advance(0.1) == "tstop" and s.t_old < 0.1 <= s.t
    n = s.nstep
    assert s.advance(5.0, max_steps=3) == "max_steps" and s.nstep == n + 3
    s.watch([(1, +1.0)])        # v = -2 sin(2 t) crosses zero upwards at t = pi/2
    assert s.advance(10.0) == "watch"
    assert s.t_old < math.pi / 2 <= s.t
    assert s.advance(10.0) == "watch" and s.t_old < 3 * math.pi / 2 <= s.t
    s.watch([])
    assert s.advance(20.0) == "finished" and s.t == 10.0 and s.status == "finished"


def test_an_exception_in_a_python_callback_comes_through():
    def f(t, y):
        if t > 0.3:
            raise ValueError("model broke at t > 0.3")
        return -y

    s = BDF(Scalar(f, lambda t, y: -1.0), 0.0, np.array([1.0]), np.array([-1.0]), 1.0)
    with pytest.raises(ValueError, match="model broke"):
        while s.status == "running":
            s.advance(1.0)
    assert s.status == "failed" and 0.0 < s.t <= 0.3


@pytest.mark.parametrize("compiled", [False, True])
def test_failures_are_reported_alike(compiled):
    # y' = y^2 from 1 blows up at t = 1: both paths stop there with the same report
    prob = Scalar(lambda t, y: y * y, lambda t, y: 2.0 * y)
    s = BDF(prob, 0.0, np.array([1.0]), np.array([1.0]), 2.0, compiled_loop=compiled)
    with pytest.raises(IntegrationError) as info:
        while s.status == "running":
            s.advance(2.0)
    err = info.value
    assert 0.99 < err.t < 1.0 and err.t == s.t and err.worst_index == 0
    assert "Integration failed after the accepted point" in str(err)


# ---- the run loop --------------------------------------------------------------------
def _simulate(problem, python: bool, monkeypatch, **kw):
    with monkeypatch.context() as mp:
        if python:
            mp.setattr(driver, "BDF", partial(BDF, compiled_loop=False))
        return simulate(problem, **kw)


@pytest.mark.parametrize("name, overrides", [
    ("cantilever", {"rod.elements": 8, "simulation.t_end": 3.6}),
    ("examples/base_excitation.toml", {"rod.elements": 6, "simulation.t_end": 2.0}),
    ("examples/maxwell_cantilever.toml", {"rod.elements": 6, "simulation.t_end": 1.0}),
])
def test_observers_in_the_compiled_loop_give_the_python_series(name, overrides, monkeypatch):
    p = load_problem(name, overrides)
    snaps = {False: [], True: []}
    runs = {py: _simulate(p, py, monkeypatch, snapshot_every=0.25,
                          snapshot_sink=lambda t, y, yp, py=py: snaps[py].append((t, y)))
            for py in (True, False)}
    a, b = runs[True], runs[False]
    assert a.status == b.status == "finished" and a.counters == b.counters
    for key in ("t", "tip", "start", "peaks_t", "peaks_x", "centreline_t", "centreline"):
        assert np.array_equal(getattr(a, key), getattr(b, key)), key
    for key in ("kinetic", "elastic", "dissipated", "external_work"):
        x, y = getattr(a, key), getattr(b, key)
        np.testing.assert_allclose(y, x, rtol=1e-12, atol=1e-15 * np.abs(x).max()), key
    assert a.reactions.keys() == b.reactions.keys() == {"start"}
    for what in ("force", "moment"):
        x, y = a.reactions["start"][what], b.reactions["start"][what]
        np.testing.assert_allclose(y, x, rtol=1e-12, atol=1e-14 * np.abs(x).max())
    for end in ("start", "end"):
        assert np.array_equal(a.end_quaternions[end], b.end_quaternions[end])
    assert a.t.size == round(p.simulation.t_end / p.simulation.output_step) + 1
    assert [t for t, _ in snaps[True]] == [t for t, _ in snaps[False]]
    assert len(snaps[True]) == int(p.simulation.t_end / 0.25) + 1
    for (_, y1), (_, y2) in zip(snaps[True], snaps[False], strict=True):
        assert np.array_equal(y1, y2)
    if name == "cantilever":
        assert a.peaks_x.size >= 3


def test_the_compiled_loop_calls_python_rarely_unless_an_observer_needs_every_step():
    p = load_problem("cantilever", {"rod.elements": 6, "simulation.t_end": 2.0})
    ticks: list[float] = []
    run = simulate(p, progress=ticks.append)
    assert run.counters["nstep"] > 400
    assert len(ticks) <= 110 and ticks[-1] == 2.0      # about Progress.ticks stops

    seen: list[float] = []

    class EveryStep:                                    # not sparse: sees every step
        def step(self, run, dense, t0, t1):
            seen.append(t1)

    m = run.model
    y0, yp0 = _released(m)
    res = driver.run_loop(m, 0.0, y0, yp0, 0.5, rtol=1e-6, atol=1e-8, observers=[EveryStep()])
    assert res.status == "finished" and len(seen) == res.counters["nstep"] > 10


def test_maxima_come_from_kept_steps_and_the_loop_runs_to_its_stop(monkeypatch):
    """The tip's maxima: the steps where its velocity changes sign are kept for a replay
    (watch_rep) instead of a return to Python each, and a loop that stops on signals
    itself is not cut into chunks of steps: one call of the compiled loop for the whole
    run (more than _CHUNK steps, several maxima), with the Python path's maxima bit for
    bit (such a call ends after its step on Ctrl-C: the test of signals during
    callbacks)."""
    from runtime.solvers.native.step_loop import CoreLink

    p = load_problem("cantilever", {"rod.elements": 8, "simulation.t_end": 6.0})
    calls: list[int] = []
    advance = CoreLink.advance

    def counted(self, *a):
        calls.append(self.s.nstep)
        return advance(self, *a)

    with monkeypatch.context() as mp:
        mp.setattr(CoreLink, "advance", counted)
        a = simulate(p)
    b = _simulate(p, True, monkeypatch)
    assert a.counters == b.counters and a.counters["nstep"] > driver._CHUNK
    assert a.peaks_t.size >= 4 and len(calls) == 1
    assert np.array_equal(a.peaks_t, b.peaks_t) and np.array_equal(a.peaks_x, b.peaks_x)
    assert np.array_equal(a.maxima_t, b.maxima_t)


def test_frames_and_snapshots_come_from_kept_steps_not_stops(monkeypatch):
    """The snapshots are taken on copies of the steps that reach their times, handed to
    Python in batches (a 2-row buffer here), the centreline frames inside the compiled
    loop (its frame grid) or, where that is refused, on copied steps as well: the loop
    stops only for the maxima and the end, and the frames are those of a run that stops
    at each of them (observers called at every step), the same bits all three ways."""
    from runtime.solvers.native.step_loop import CoreLink

    p = load_problem("cantilever", {"rod.elements": 6, "simulation.t_end": 2.0,
                                    "simulation.centreline_frames": 41})
    calls = {"advance": 0}
    advance = CoreLink.advance

    def counted(self, *args):
        calls["advance"] += 1
        return advance(self, *args)

    monkeypatch.setattr(CoreLink, "REPLAY_ROWS", 2, raising=False)
    monkeypatch.setattr(CoreLink, "advance", counted)
    snaps: dict[bool, list] = {False: [], True: []}
    runs = {py: _simulate(p, py, monkeypatch, snapshot_every=0.05,
                          snapshot_sink=lambda t, y, yp, py=py: snaps[py].append((t, y, yp)))
            for py in (False, True)}
    a, b = runs[True], runs[False]
    assert calls["advance"] <= 2 * (b.peaks_t.size + 2) < 41
    assert b.centreline.shape == (41, 3, 7) and np.array_equal(a.centreline, b.centreline)
    assert np.array_equal(a.centreline_t, b.centreline_t)
    assert len(snaps[False]) == len(snaps[True]) >= 40
    for (t1, y1, yp1), (t2, y2, yp2) in zip(snaps[True], snaps[False], strict=True):
        assert t1 == t2 and np.array_equal(y1, y2) and np.array_equal(yp1, yp2)
    from runtime.simulate.observers import Centreline

    monkeypatch.setattr(Centreline, "into_core", lambda self, solver: False)
    replayed = _simulate(p, False, monkeypatch)
    assert np.array_equal(replayed.centreline, b.centreline)


def test_checkpoints_wait_for_their_wall_time(monkeypatch):
    """run_loop's checkpoint_wall: a checkpoint only once that much wall time has passed
    since the previous one, the first since the loop started: none in a run shorter than
    it; 0: one at every point of the cadence. With a clock on which every reading is a
    second later, every point of the cadence is past the wall time again. The run is the
    same either way."""
    import itertools

    from runtime.solvers import driver

    p = load_problem("cantilever", {"rod.elements": 6, "simulation.t_end": 2.0})
    every: list[dict] = []
    none: list[dict] = []
    a = simulate(p, checkpoint=every.append, checkpoint_every=0.25)
    b = simulate(p, checkpoint=none.append, checkpoint_every=0.25, checkpoint_wall=1e9)
    ts = [s["t"] for s in every]
    assert len(ts) == 7 and all(t >= 0.25 * (k + 1) for k, t in enumerate(ts))
    assert none == []
    clock = itertools.count(0.0, 1.0)

    class SlowClock:
        @staticmethod
        def perf_counter() -> float:
            return float(next(clock))

    monkeypatch.setattr(driver, "time", SlowClock)
    slow: list[dict] = []
    c = simulate(p, checkpoint=slow.append, checkpoint_every=0.25, checkpoint_wall=1.0)
    assert [s["t"] for s in slow] == ts
    for r in (b, c):
        assert a.counters == r.counters and np.array_equal(a.tip, r.tip)
        assert np.array_equal(a.dissipated, r.dissipated)


def test_a_fast_long_run_checkpoints_once_per_wall_interval(monkeypatch):
    """A run whose wall time is long only because its simulated time is: on a clock that
    gives 0.01 s of wall time per simulated second, checkpoint_wall = 1 s means a
    checkpoint about every 100 simulated seconds. The loop learns the pace at the first
    cadence point and then stops where the next checkpoint is due (stopping only at the
    next cadence point, it ran on to the end after the first). The steps are those of a
    run without checkpoints."""
    from runtime.solvers import driver

    p = load_problem("cantilever", {"rod.elements": 4, "simulation.t_end": 250.0})
    plain = simulate(p)
    holder = {}

    class Tracked(driver.BDF):
        def __init__(self, *a, **k):
            super().__init__(*a, **k)
            holder["solver"] = self

    class SimulatedClock:
        @staticmethod
        def perf_counter() -> float:
            s = holder.get("solver")
            return 0.0 if s is None else 0.01 * abs(s.t)

    monkeypatch.setattr(driver, "BDF", Tracked)
    monkeypatch.setattr(driver, "time", SimulatedClock)
    got: list[dict] = []
    r = simulate(p, checkpoint=got.append, checkpoint_every=1.0, checkpoint_wall=1.0)
    ts = [s["t"] for s in got]
    assert len(ts) == 2 and ts[0] >= 100.0 and ts[1] - ts[0] >= 100.0, ts
    assert r.counters == plain.counters and np.array_equal(r.tip, plain.tip)


def test_cadence_points():
    from runtime.solvers.driver import _cadence_point

    assert _cadence_point(1.0, 0.5, 1.0, 1.0) == 1.0
    assert _cadence_point(1.0, 1.0, 1.0, 1.0) == 1.0
    assert _cadence_point(1.0, 3.2, 1.0, 1.0) == 4.0
    assert _cadence_point(-1.0, -3.2, 0.5, -1.0) == -3.5       # backwards in time


def test_a_release_holds_no_signals_and_calls_no_drive_back(monkeypatch):
    """After a release the loads stay as they are to the end of the run (its end is taken
    from the left): the compiled loop calls no drive back and solve's output stops hold no
    signals (each hold cost ~30 us of Python, a fifth of the N = 50 integration)."""
    from runtime.solvers.integrator import solve
    from runtime.solvers.native import step_loop

    p = load_problem("cantilever", {"rod.elements": 6, "simulation.t_end": 1.0})
    model = simulate(p).model
    y0, yp0 = _released(model)
    ref = solve(model, (0.0, 1.0), y0, yp0, rtol=1e-6, atol=1e-8,
                t_eval=np.linspace(0.0, 1.0, 51), compiled_loop=False)
    held, calls, runs = [], [], []
    hold = step_loop._call_holding_signals
    monkeypatch.setattr(step_loop, "_call_holding_signals",
                        lambda *a: held.append(1) or hold(*a))
    go, advance = step_loop.CoreLink._set_drive, step_loop.CoreLink.advance

    def counted(self, fn):
        go(self, lambda t: calls.append(t) or fn(t))

    monkeypatch.setattr(step_loop.CoreLink, "_set_drive", counted)
    monkeypatch.setattr(step_loop.CoreLink, "advance",
                        lambda self, *a: runs.append(1) or advance(self, *a))
    res = solve(model, (0.0, 1.0), y0, yp0, rtol=1e-6, atol=1e-8,
                t_eval=np.linspace(0.0, 1.0, 51))
    assert model.c_kernels().drive is not None and res.counters == ref.counters
    assert np.array_equal(res.y, ref.y) and np.array_equal(res.yp, ref.yp)
    assert held == [] and len(calls) == len(runs) > 0     # Python's own, one per run


def test_samples_pass_through_a_small_buffer_unchanged(monkeypatch):
    """The compiled loop hands its output rows to Python whenever its buffer is full (the
    memory of a long run stays bounded): a 5-row buffer gives the same series."""
    from runtime.solvers.native.step_loop import CoreLink

    p = load_problem("cantilever", {"rod.elements": 6, "simulation.t_end": 1.0})
    ref = simulate(p)
    monkeypatch.setattr(CoreLink, "SAMPLE_ROWS", 5)
    small = simulate(p)
    assert ref.t.size == 201 and np.array_equal(small.t, ref.t)
    for key in ("tip", "start", "kinetic", "elastic", "dissipated", "external_work"):
        assert np.array_equal(getattr(small, key), getattr(ref, key)), key


def test_a_signal_during_callbacks_is_delivered_after_the_compiled_loop_returns():
    """Ctrl-C while C runs with Python callbacks: the handler's KeyboardInterrupt comes out
    of advance() with the solver's state pulled back, not printed and lost by ctypes (a
    signal's exception can fire on a callback's first line, before any try)."""
    import os
    import signal

    calls = {"n": 0}

    def f(t, y):
        calls["n"] += 1
        if calls["n"] == 50:
            os.kill(os.getpid(), signal.SIGINT)
        return -y

    # Python's own Ctrl-C handler, whatever the test process inherited (a background job
    # of a non-interactive shell starts with SIGINT ignored, and the kill would be lost)
    inherited = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        s = BDF(Scalar(f, lambda t, y: -1.0), 0.0, np.array([1.0]), np.array([-1.0]), 100.0)
        with pytest.raises(KeyboardInterrupt):
            s.advance(100.0)
        assert 0.0 < s.t < 100.0 and s.nfev >= 50 and abs(s.y[0] - math.exp(-s.t)) < 1e-4
        assert signal.getsignal(signal.SIGINT) is signal.default_int_handler
    finally:
        signal.signal(signal.SIGINT, inherited)


@pytest.mark.parametrize("n", [7, 13006, 40001])
@pytest.mark.parametrize("k", [1, 3, 5])
def test_interpolation_in_c_sums_like_numpy_at_every_size_and_alignment(n, k):
    """kv_interp (one pass over phi, vectorised per order, non-temporal stores from 256 kB
    per output row, rows of odd n alternating in alignment) gives y = phi_0 + c_1 phi_1
    + ... and y' = 0 + d_1 phi_1 + ... summed in j order: NumPy's sums term by term; y
    alone and y at tn (kv_interp_at_tn) are the same bits."""
    import ctypes

    from runtime.solvers.dense import _interp_coefficients

    lib = load()
    rng = np.random.default_rng(n + k)
    phi = rng.standard_normal((k + 1, n))
    psi = np.cumsum(rng.uniform(0.01, 0.02, 6))
    ts = np.array([-0.003, -0.0071, 0.0])
    y, yp = np.full((3, n), np.nan), np.full((3, n), np.nan)
    P = lambda a: a.ctypes.data  # noqa: E731
    lib.kv_interp(k, n, 3, ctypes.c_double(0.0), P(psi), P(phi), P(ts), P(y), P(yp))
    c, d = _interp_coefficients(ts, 0.0, psi, k)
    for i in range(3):
        wy, wyp = phi[0].copy(), np.zeros(n)
        for j in range(1, k + 1):
            wy += c[j, i] * phi[j]
            wyp += d[j, i] * phi[j]
        assert np.array_equal(y[i], wy) and np.array_equal(yp[i], wyp), i
    y_only = np.full((3, n), np.nan)         # out_yp NULL: y alone, the same bits
    lib.kv_interp(k, n, 3, ctypes.c_double(0.0), P(psi), P(phi), P(ts), P(y_only), None)
    assert np.array_equal(y_only, y)
    # at t = tn itself (ts[2] = 0), read off phi_0 where it is not zero: the same bits,
    # signed zeros included (phi_0 = -0.0 stays -0.0 only if every term is -0.0)
    # and non-finite values summed as kv_interp sums them
    phi[0, ::3], phi[0, 1::7] = 0.0, -0.0
    phi[0, 2::11], phi[0, 4::13] = np.inf, np.nan
    phi[1:, ::5] = -np.abs(phi[1:, ::5])
    at = np.full(n, np.nan)
    lib.kv_interp(k, n, 1, ctypes.c_double(0.0), P(psi), P(phi), P(ts[2:]), P(y_only), None)
    lib.kv_interp_at_tn(k, n, P(psi), P(phi), P(at))
    assert np.array_equal(np.signbit(at), np.signbit(y_only[0]))
    assert np.array_equal(at, y_only[0], equal_nan=True)


@pytest.mark.parametrize("moving", [False, True])
def test_solve_interpolates_its_output_grid_in_the_compiled_loop(moving, monkeypatch):
    """solve(t_eval=...) with the compiled loop fills the output grid there, after each
    step that reaches an output (issue 33: a return to Python per output cost ~25 us,
    a fifth of the N = 50 integration): the loop returns a few times, not once per
    output, and the outputs are those of the NumPy path and of a run that stops at each
    output (a progress callback) bit for bit, through a moving clamp's drive callback
    too; a terminal event keeps the outputs up to its time only."""
    from runtime.problem.assemble import build_model
    from runtime.solvers.integrator import solve
    from runtime.solvers.native import step_loop

    if moving:
        model = build_model(load_problem("examples/base_excitation.toml",
                                         {"rod.elements": 6, "simulation.t_end": 0.6}))
        y0 = model.constrain(model.initial_state(0.0))
        y0, yp0 = consistent_initial(model, 0.0, y0, np.zeros(model.n))
    else:                                  # released from its static deflection
        problem = load_problem("cantilever", {"rod.elements": 6})
        model = build_model(problem)
        y_static = static_equilibrium(problem, model).y
        model.at(0.0)
        y0, yp0 = consistent_initial(model, 0.0, y_static, np.zeros(model.n))
    grid = np.linspace(0.0, 0.6, 61)
    kw = dict(rtol=1e-6, atol=1e-9, t_eval=grid)
    ref = solve(model, (0.0, 0.6), y0, yp0, compiled_loop=False, **kw)
    ticks: list[float] = []
    stopped = solve(model, (0.0, 0.6), y0, yp0, progress=ticks.append, **kw)
    runs: list[int] = []
    advance = step_loop.CoreLink.advance
    monkeypatch.setattr(step_loop.CoreLink, "advance",
                        lambda self, *a: runs.append(1) or advance(self, *a))
    res = solve(model, (0.0, 0.6), y0, yp0, **kw)
    assert res.status == 0 and res.counters == ref.counters == stopped.counters
    assert res.counters["nstep"] > 100 and len(ticks) >= grid.size // 2
    assert 0 < len(runs) <= 2 + res.counters["nstep"] // 1000 < grid.size // 10
    for other in (ref, stopped):
        assert np.array_equal(res.t, other.t)
        assert np.array_equal(res.y, other.y) and np.array_equal(res.yp, other.yp)

    i_x = int(model.phi_index[-1][0])
    x_mid = float(res.y[i_x, grid.size // 2])

    def crossing(t, y, yp):                # the tip passes its x at t = 0.3 s
        return y[i_x] - x_mid
    crossing.terminal = True
    ev = solve(model, (0.0, 0.6), y0, yp0, events=crossing, **kw)
    ev_ref = solve(model, (0.0, 0.6), y0, yp0, events=crossing, compiled_loop=False, **kw)
    assert ev.status == 1 and np.array_equal(ev.t, ev_ref.t)
    assert ev.t.size < grid.size and ev.t[-1] <= ev.t_events[0][0]
    assert np.array_equal(ev.y, ev_ref.y)


_FOLLOWER = [{"kind": "force", "at": "end", "frame": "follower", "vector": [0.02, 0.01, -0.03]},
             {"kind": "moment", "at": "end", "frame": "follower",
              "vector": [-0.002, 0.001, 0.002]},
             {"kind": "gravity", "vector": [0.0, -9.81, 1.0]}]


@pytest.mark.parametrize("kw", [dict(), dict(tau=None, **MAXWELL),
                                dict(start="pinned", end="clamped"),
                                dict(start="clamped", end="clamped", loads=_FOLLOWER),
                                dict(loads=_FOLLOWER)])
def test_the_audits_powers_are_the_energies_own_bits(kw):
    """The energy audit's quadrature points evaluate 2D and the powers alone
    (kvrod_audit_powers, CKernels.audit_energies): bit for bit the values of the full
    energies (kvrod_energies), so that the audit and every output stay the same; the
    kinetic energy and the supports' moments are not evaluated there (left 0)."""
    from tests.kernel_calls import energies_through
    from tests.rods import random_state

    m = rod_model(7, **kw)
    kern = m.c_kernels()
    assert kern.audit_energies and kern.audit_energies != kern.energies
    rng = np.random.default_rng(7)
    ys = np.array([random_state(m, rng) for _ in range(5)])
    yps = rng.standard_normal(ys.shape)
    m.at(0.0)
    full = energies_through(kern, kern.energies, ys, yps)
    powers = energies_through(kern, kern.audit_energies, ys, yps)
    assert np.array_equal(powers[:, 2:5], full[:, 2:5])
    assert np.all(full[:, [2, 3]] != 0.0) and np.all(full[:, 0] > 0.0)
    assert np.all(powers[:, 0] == 0.0)


def test_the_output_grid_in_the_compiled_loop_backwards_and_at_the_start():
    """The grid in the compiled loop integrating backwards (t_eval descending), with an
    output at t0 (the initial values) and one at the very end: the NumPy path's bits."""
    from runtime.solvers.integrator import solve

    p = Oscillator()
    for span, t_eval in (((5.0, 0.0), np.linspace(5.0, 0.0, 41)),
                         ((0.0, 5.0), np.array([0.0, 1e-4, 2.5, 5.0]))):
        a = solve(p, span, np.array([1.0, 0.0]), None, t_eval=t_eval, rtol=1e-8, atol=1e-10)
        b = solve(p, span, np.array([1.0, 0.0]), None, t_eval=t_eval, rtol=1e-8, atol=1e-10,
                  compiled_loop=False)
        assert a.status == 0 and a.counters == b.counters and np.array_equal(a.t, t_eval)
        assert np.array_equal(a.y, b.y) and np.array_equal(a.yp, b.yp)
        np.testing.assert_allclose(a.y[0], np.cos(2.0 * (t_eval - span[0])), atol=1e-6)


def _kept_links(monkeypatch) -> list:
    """The list that every CoreLink made from now on (in this test) is appended to."""
    from runtime.solvers.native import step_loop

    links: list = []
    init = step_loop.CoreLink.__init__

    def kept(self, *a, **k):
        init(self, *a, **k)
        links.append(self)

    monkeypatch.setattr(step_loop.CoreLink, "__init__", kept)
    return links


def _runs_with_and_without_the_audit_thread(problem, monkeypatch, **kw):
    """(one-thread run, two-thread run, CoreLinks of the latter) of ``simulate`` (the
    thread asked for whatever the machine's CPUs)."""
    from runtime.solvers.native import step_loop

    links = _kept_links(monkeypatch)
    monkeypatch.setattr(step_loop, "audit_thread_wanted", lambda: False)
    one = simulate(problem, **kw)
    assert links and all(link.s.async_runs == 0 for link in links)
    links.clear()
    monkeypatch.setattr(step_loop, "audit_thread_wanted", lambda: True)
    two = simulate(problem, **kw)
    return one, two, links


#: the audit's thread is built with POSIX threads (step_loop.c: KV_THREADS), not on Windows
needs_threads = pytest.mark.skipif(os.name == "nt", reason="no POSIX threads")


@needs_threads
@pytest.mark.parametrize("name, overrides, rows", [
    ("cantilever", {"rod.elements": 8, "simulation.t_end": 2.0}, None),
    ("cantilever", {"rod.elements": 8, "simulation.t_end": 2.0}, 3),
    ("examples/maxwell_cantilever.toml", {"rod.elements": 6, "simulation.t_end": 1.0}, None),
    ("examples/coupled_strip.toml", {"rod.elements": 6, "simulation.t_end": 0.5}, 7),
])
def test_the_audit_on_its_own_thread_gives_the_one_thread_series(name, overrides, rows,
                                                                  monkeypatch):
    """The energy audit and the samples on a second thread (step_loop.c, audit_async):
    the same values bit for bit (a Kelvin-Voigt, a generalized Maxwell and a coupled rod,
    whose energies read y' too; a few-row sample buffer, drained before each flush), and
    the thread did run."""
    from runtime.solvers.native.step_loop import CoreLink

    if rows is not None:
        monkeypatch.setattr(CoreLink, "SAMPLE_ROWS", rows)
    p = load_problem(name, overrides)
    a, b, links = _runs_with_and_without_the_audit_thread(p, monkeypatch)
    assert a.status == b.status == "finished" and a.counters == b.counters
    assert sum(link.s.async_runs for link in links) >= 1
    for key in ("t", "tip", "start", "kinetic", "elastic", "dissipated", "external_work",
                "peaks_t", "peaks_x", "y_last"):
        assert np.array_equal(getattr(a, key), getattr(b, key)), key
    for end, r in a.reactions.items():
        for what, v in r.items():
            assert np.array_equal(v, b.reactions[end][what]), (end, what)


def test_the_audit_thread_waits_while_python_sees_replayed_steps(monkeypatch):
    """Snapshots come to Python in batches of replayed steps (here 2 rows) while the loop
    runs; their sink drives the model to each snapshot's time (diagnostics, as the VTK
    frames do): the audit's thread is drained first, and the series and the snapshots
    are the one-thread run's."""
    from runtime.problem.assemble import build_model
    from runtime.solvers.native.step_loop import CoreLink

    monkeypatch.setattr(CoreLink, "REPLAY_ROWS", 2, raising=False)
    p = load_problem("cantilever", {"rod.elements": 6, "simulation.t_end": 1.5})
    model = build_model(p)
    seen: dict[int, list] = {0: [], 1: []}
    which = {"k": 0}

    def sink(t, y, yp):
        d = model.diagnostics(t, y, yp)
        seen[which["k"]].append((t, d["elastic"], d["kinetic"]))

    def run(threaded):
        from runtime.solvers.native import step_loop

        which["k"] = int(threaded)
        monkeypatch.setattr(step_loop, "audit_thread_wanted", lambda: threaded)
        return simulate(p, model=model, snapshot_every=0.05, snapshot_sink=sink)

    a, b = run(False), run(True)
    assert a.counters == b.counters and len(seen[0]) == len(seen[1]) > 20
    assert seen[0] == seen[1]
    for key in ("t", "tip", "kinetic", "elastic", "dissipated", "external_work"):
        assert np.array_equal(getattr(a, key), getattr(b, key)), key


def test_the_audit_stays_in_the_loop_while_the_loads_move(monkeypatch):
    """Base excitation drives the clamp with t: the energies must see the loads of their
    own time, so those calls keep the audit in the loop (no second thread); same series."""
    p = load_problem("examples/base_excitation.toml", {"rod.elements": 6,
                                                       "simulation.t_end": 0.5})
    a, b, links = _runs_with_and_without_the_audit_thread(p, monkeypatch)
    assert a.counters == b.counters and links
    assert all(link.s.async_runs == 0 for link in links)
    for key in ("t", "tip", "kinetic", "elastic", "dissipated", "external_work"):
        assert np.array_equal(getattr(a, key), getattr(b, key)), key


@needs_threads
def test_a_failure_of_the_energies_on_the_audits_thread_fails_the_run(monkeypatch):
    """Energies that return an error code (at their 801st call, after the worker has
    started: step_loop.c, async_after) on the worker: the run fails with the compiled
    functions' message and keeps the samples of the one-thread run's failure, no more
    (the loop may take a few more steps before it sees it)."""
    import ctypes
    import threading

    from runtime.model.rod import RodModel
    from runtime.solvers.native import step_loop

    EN = ctypes.CFUNCTYPE(ctypes.c_int, ctypes.c_void_p, ctypes.c_int, ctypes.c_void_p,
                          ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p)
    calls = {"n": 0, "failed_on": None}
    c_kernels = RodModel.c_kernels

    def failing(self):
        kern = c_kernels(self)
        real = EN(kern.energies)

        def en(ctx, m, ts, ys, yps, out):
            calls["n"] += 1
            if calls["n"] <= 800:
                return real(ctx, m, ts, ys, yps, out)
            if calls["failed_on"] is None:
                calls["failed_on"] = threading.get_ident()
            return -3

        cb = EN(en)
        kern.keep = (kern.keep, cb, real)
        kern.energies = ctypes.cast(cb, ctypes.c_void_p).value
        kern.audit_energies = 0
        return kern

    monkeypatch.setattr(RodModel, "c_kernels", failing)
    p = load_problem("cantilever", {"rod.elements": 6, "simulation.t_end": 2.0})
    runs = {}
    for threaded in (False, True):
        calls["n"], calls["failed_on"] = 0, None
        monkeypatch.setattr(step_loop, "audit_thread_wanted", lambda t=threaded: t)
        runs[threaded] = simulate(p)
        assert (calls["failed_on"] == threading.get_ident()) is not threaded
    a, b = runs[False], runs[True]
    for run in (a, b):
        assert run.status == "failed" and "energies" in run.message
    assert 100 < a.t.size < 401 and np.all(np.isfinite(a.dissipated))
    for key in ("t", "tip", "kinetic", "elastic", "dissipated", "external_work"):
        assert np.array_equal(getattr(a, key), getattr(b, key)), key


def test_the_audit_thread_is_asked_for_with_two_cpus_unless_switched_off(monkeypatch):
    import os

    from runtime.solvers.native import step_loop

    monkeypatch.delenv("KVROD_AUDIT_THREAD", raising=False)
    monkeypatch.setattr(os, "sched_getaffinity", lambda pid: {0, 1}, raising=False)
    assert step_loop.audit_thread_wanted()
    monkeypatch.setenv("KVROD_AUDIT_THREAD", "0")
    assert not step_loop.audit_thread_wanted()
    monkeypatch.setenv("KVROD_AUDIT_THREAD", "1")
    monkeypatch.setattr(os, "sched_getaffinity", lambda pid: {3}, raising=False)
    assert not step_loop.audit_thread_wanted()


def test_a_sweeps_workers_keep_the_audit_in_the_loop(monkeypatch):
    """Their cores run points: a second thread per point would only add its cost."""
    import os

    from runtime.study.worker_boot import warm_up

    monkeypatch.setenv("KVROD_AUDIT_THREAD", "")      # restored (to unset) afterwards
    monkeypatch.delenv("KVROD_AUDIT_THREAD")
    warm_up()
    assert os.environ["KVROD_AUDIT_THREAD"] == "0"


@pytest.mark.parametrize("name, overrides, no_yp", [
    ("cantilever", {"rod.elements": 8, "simulation.t_end": 2.0}, 1),
    ("examples/maxwell_cantilever.toml", {"rod.elements": 6, "simulation.t_end": 1.0}, 1),
    ("examples/coupled_strip.toml", {"rod.elements": 6, "simulation.t_end": 0.5}, 0),
])
def test_the_audit_interpolates_without_rates_where_the_energies_ignore_them(
        name, overrides, no_yp, monkeypatch):
    """A rod whose energies read no y' (no coupled sections, no contact) has the audit's
    and the samples' states interpolated without it (en_no_yp); the series are those of
    the run that interpolates y' too, bit for bit, with and without the audit's thread."""
    from runtime.model.rod import RodModel
    from runtime.solvers.native import step_loop

    p = load_problem(name, overrides)
    links = _kept_links(monkeypatch)
    runs = {}
    for thread in (False, True):
        monkeypatch.setattr(step_loop, "audit_thread_wanted", lambda t=thread: t)
        links.clear()
        runs[thread, "own"] = simulate(p)
        assert links and all(link.s.en_no_yp == no_yp for link in links)
        kernels = RodModel.c_kernels

        def with_rates(self, _k=kernels):
            kern = _k(self)
            kern.energies_read_rates = True
            return kern

        with monkeypatch.context() as mp:
            mp.setattr(RodModel, "c_kernels", with_rates)
            links.clear()
            runs[thread, "rates"] = simulate(p)
            assert links and all(link.s.en_no_yp == 0 for link in links)
    ref = runs[False, "rates"]
    for key, r in runs.items():
        assert r.status == "finished" and r.counters == ref.counters, key
        for name_ in ("t", "tip", "kinetic", "elastic", "dissipated", "external_work",
                      "y_last"):
            assert np.array_equal(getattr(r, name_), getattr(ref, name_)), (key, name_)
