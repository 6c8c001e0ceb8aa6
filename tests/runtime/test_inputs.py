"""Inputs are never stepped over (issue 22): the run stops at every breakpoint of its loads
and end motion, restarts where one jumps, holds prescribed ends at r(t) to round-off, and
reports what the supports exert; each against a reference computed apart from kvrod."""

from __future__ import annotations

import math
from functools import partial
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from references.beams import euler_bernoulli_frequencies
from references.transient import cantilever_tip_response
from runtime.problem.registry import load_problem
from runtime.problem.timefunctions import TimeFunction
from runtime.simulate.simulate import simulate
from runtime.solvers import driver
from runtime.solvers.bdf import BDF

PULSE = [[0.0, 0.0], [0.05, 0.0], [0.0525, 1.0], [0.055, 0.0]]
CLAMP_RAMP = {"translation": [0.005, 0.0, 0.0],
              "translation_time": {"kind": "smooth_ramp", "start": 0.0, "duration": 0.005}}


def _cantilever(t_end: float, **over):
    """The paper's cantilever at rest (``initial = "reference"``); ``over``: dotted keys of
    the problem file, whole tables allowed (set in the TOML document)."""
    import tomllib

    from runtime.problem.schema import Problem

    doc = tomllib.loads(Path("examples/cantilever.toml").read_text())
    over = {"simulation.t_end": t_end, "simulation.initial": "reference", **over}
    for key, value in over.items():
        if "." not in key:
            doc[key] = value
            continue
        node, *path, last = key.split(".")
        t = doc.setdefault(node, {})
        for k in path:
            t = t[int(k)] if isinstance(t, list) else t.setdefault(k, {})
        if isinstance(t, list):
            idx = int(last)
            (t.append if idx == len(t) else t.__setitem__)(*(
                (value,) if idx == len(t) else (idx, value)))
        else:
            t[last] = value
    return Problem.from_mapping(doc, name="cantilever")


# ---- time functions ------------------------------------------------------------------
def test_time_functions_declare_their_breakpoints():
    assert TimeFunction(kind="ramp", start=1.0, duration=2.0).breakpoints(0, 10) == [
        (1.0, 1), (3.0, 1)]
    assert TimeFunction(kind="smooth_ramp", start=0.0, duration=0.5).breakpoints(0, 1) == [
        (0.0, 2), (0.5, 2)]
    assert TimeFunction(kind="release", start=0.2).breakpoints(0, 1) == [(0.2, 0)]
    assert TimeFunction(kind="harmonic", amplitude=1, frequency=3).breakpoints(0, 9) == []
    pulse = TimeFunction(kind="table", points=tuple(map(tuple, PULSE)))
    assert pulse.breakpoints(0, 1) == [(0.05, 1), (0.0525, 1), (0.055, 1)]
    assert pulse.breakpoints(0.051, 1) == [(0.0525, 1), (0.055, 1)]
    # a long table sampled from a smooth signal is cut at its ends only; its pieces are
    # bounded by the signal's own time scale (period / pi for a sine)
    t = np.linspace(0.0, 1.0, 2001)
    sine = TimeFunction(kind="table", points=tuple(zip(t, np.sin(2 * np.pi * t),
                                                       strict=True)))
    assert [b for b, _ in sine.breakpoints(0, 2)] == [0.0, 1.0]
    assert sine.time_scale(0.3) == pytest.approx(1 / np.pi, rel=1e-3)


def test_one_sided_rates_at_the_kinks():
    f = TimeFunction(kind="ramp", start=1.0, duration=2.0)
    assert (f.rate_at(1.0, left=True), f.rate_at(1.0)) == (0.0, 0.5)
    assert (f.rate_at(3.0, left=True), f.rate_at(3.0)) == (0.5, 0.0)
    g = TimeFunction(kind="smooth_ramp", start=0.0, duration=0.5)
    assert g.accel_at(0.0, left=True) == 0.0
    assert g.accel_at(0.0) == pytest.approx(0.5 * (np.pi / 0.5) ** 2)
    h = TimeFunction(kind="harmonic", amplitude=2.0, frequency=1.5, phase=0.3)
    w, t = 2 * np.pi * 1.5, 0.7
    assert h.accel_at(t) == pytest.approx(-2.0 * w * w * np.sin(w * t + 0.3))


# ---- a short load pulse --------------------------------------------------------------
@pytest.mark.parametrize("t_end", [1.0, 10.0])
def test_a_short_load_pulse_acts_in_full(t_end):
    """The paper's cantilever at rest, hit by a 5 ms triangular tip force pulse at
    t = 50 ms: its tip maximum against the modal superposition of Euler-Bernoulli modes
    (references/transient.py), whatever t_end is (it used to be stepped over)."""
    p = _cantilever(t_end, **{"loads.0.time": {"kind": "table", "points": PULSE}})
    run = simulate(p)
    assert run.status == "finished", run.message
    t = np.linspace(0.0, 1.0, 40001)
    ref = cantilever_tip_response(t, [(a, 0.05 * b) for a, b in PULSE], L=0.3,
                                  EI=1e6 * 1e-8 / 12, rhoA=0.1, tau_E=0.04, modes=10)
    assert run.tip[0].max() == pytest.approx(ref.max(), rel=1e-2)
    assert not run.summary()["warnings"]
    assert run.audit().applicable and run.audit().max_rel < 1e-4


def test_both_drivers_and_both_loops_stop_at_the_breakpoints(monkeypatch):
    """The compiled loop and the NumPy path take the same steps across the pulse's
    restarts; ``solve`` (the other driver) lands on them too."""
    p = _cantilever(0.2, **{"rod.elements": 8, "loads.0.time": {"kind": "table",
                                                                 "points": PULSE}})
    runs = []
    for python in (False, True):
        with monkeypatch.context() as mp:
            if python:
                mp.setattr(driver, "BDF", partial(BDF, compiled_loop=False))
            runs.append(simulate(p))
    a, b = runs
    assert a.counters == b.counters
    assert np.array_equal(a.tip, b.tip)

    from runtime.problem.assemble import build_model
    from runtime.solvers.initial import consistent_initial
    from runtime.solvers.integrator import solve

    model = build_model(p)
    y0, yp0 = consistent_initial(model, 0.0, model.initial_state(0.0), np.zeros(model.n))
    res = solve(model, (0.0, 0.2), y0, model.prescribed_rates(0.0, yp0), rtol=1e-6,
                atol=1e-9, dense_output=True)
    assert res.success, res.message
    for tb in (0.05, 0.0525, 0.055):
        assert np.min(np.abs(res.sol.ts - tb)) == 0.0     # a step ends on each
    i_tip = model.phi_index[-1][0]
    assert float(res.sol(0.2)[i_tip]) == pytest.approx(a.tip[0][-1], rel=1e-3, abs=1e-7)


# ---- a fast end motion ---------------------------------------------------------------
@pytest.mark.parametrize("t_end", [1.0, 10.0])
def test_a_fast_clamp_ramp_is_followed_exactly(t_end):
    """The cantilever without load, its clamp translated 5 mm by a 5 ms smooth ramp from
    t = 0: the clamp sits at its prescribed position at every accepted step and every
    output to 1e-12 relative, and the rod follows (it used to stay at x = 0, or fail
    at t = 0)."""
    p = _cantilever(t_end, **{"loads.0.vector": [0.0, 0.0, 0.0], "start.motion": CLAMP_RAMP})
    f = TimeFunction(kind="smooth_ramp", start=0.0, duration=0.005)
    worst: list[float] = []

    class Held:                                     # every accepted step
        def step(self, run, dense, t0, t1):
            m = run.solver.problem
            x = run.y[m.phi_index[0]]
            worst.append(abs(x[0] - 0.005 * f.value_at(t1)) + abs(x[1]) + abs(x[2]))

    from runtime.simulate import simulate as S

    real = S.run_loop
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(S, "run_loop", lambda *a, **k: real(
            *a, **{**k, "observers": [*k["observers"], Held()]}))
        run = simulate(p)
    assert run.status == "finished", run.message
    assert max(worst) <= 1e-12 * 0.005
    expect = np.array([0.005 * f.value_at(t) for t in run.t])
    assert np.max(np.abs(run.start[0] - expect)) <= 1e-12 * 0.005
    assert np.max(np.abs(run.start[1:])) == 0.0
    assert run.tip[0].max() > 0.005                       # the rod came along
    if t_end == 10.0:                                     # ... and vibrates about x = 5 mm
        last = run.t > t_end - 2 * 1.762                  # two periods of the first mode
        assert np.mean(run.tip[0][last]) == pytest.approx(0.005, abs=3e-4)
    assert run.audit().max_rel < 1e-4, run.audit()


def test_a_prescribed_extension_is_exact():
    """A short rod clamped at both ends, its end pulled 0.2 mm along the axis by a ramp and
    held: the end node sits at the prescribed position (1e-12 relative) at t_end, and the
    axial reaction is EA times the strain (the rod at rest again, held)."""
    over = {"rod.length": 0.05, "rod.elements": 6, "end": {"kind": "clamped", "motion": {
        "translation": [0.0, 0.0, 2e-4],
        "translation_time": {"kind": "ramp", "start": 0.0, "duration": 0.02}}},
        "loads.0.vector": [0.0, 0.0, 0.0], "simulation.rtol": 1e-8}
    p = _cantilever(1.0, **over)
    run = simulate(p)
    assert run.status == "finished", run.message
    assert run.y_last[run.model.phi_index[-1][2]] == pytest.approx(0.05 + 2e-4, rel=1e-12,
                                                                    abs=0.0)
    EA = 1e6 * 1e-4
    Fz = run.reactions["end"]["force"][2, -1]
    assert Fz == pytest.approx(EA * 2e-4 / 0.05, rel=1e-3)
    assert run.reactions["start"]["force"][2, -1] == pytest.approx(-Fz, rel=1e-6)


# ---- reactions and end rotations -----------------------------------------------------
def test_static_reactions_balance_the_loads_and_the_tip_twist():
    """Statics of a cantilever bent and twisted by a tip force and moment: the clamp's
    reaction balances them (force and moment about the clamp on the deformed rod: the
    rod's global equilibrium, independent of the discretisation), and the end rotation
    about the axis is M_t L / GJ (linear torsion)."""
    from runtime.simulate.simulate import static_equilibrium

    Mt = 1e-5
    p = _cantilever(1.0, **{"simulation.initial": "static", "loads.0.vector": [0.002, 0, 0],
                            "loads.0.time": 1.0,
                            "loads.1": {"kind": "moment", "at": "end", "vector": [0, 0, Mt]}})
    from runtime.problem.assemble import build_model

    m = build_model(p)
    st = static_equilibrium(p, m)
    F, M = st.reactions["start"]["force"], st.reactions["start"]["moment"]
    tip = st.tip
    assert F == pytest.approx([-0.002, 0.0, 0.0], abs=1e-12)
    arm = tip - m.start_position(st.y)
    expect = -(np.cross(arm, [0.002, 0.0, 0.0]) + [0.0, 0.0, Mt])
    assert M == pytest.approx(expect, rel=1e-9, abs=1e-13)
    # the twist alone: G = E/(2(1+nu)), J of a square 0.140577 a^4 (Saint-Venant)
    p = _cantilever(1.0, **{"simulation.initial": "static", "loads.0.vector": [0, 0, Mt],
                            "loads.0.time": 1.0, "loads.0.kind": "moment"})
    m = build_model(p)
    R = static_equilibrium(p, m).end_frames["end"]
    twist = math.atan2(R[1, 0] - R[0, 1], R[0, 0] + R[1, 1])
    G, J = 1e6 / 2.6, 0.140577 * 0.01**4
    assert twist == pytest.approx(Mt * 0.3 / (G * J), rel=1e-4)


def test_dynamic_reaction_includes_the_inertia():
    """A short, stiff rod clamped to a base shaken along its axis at 2 Hz (far below its
    axial frequency): the rod moves with the base, and the clamp's axial reaction is the
    rod's mass times the base acceleration (rigid body, to (omega/omega_axial)^2)."""
    A, f = 1e-3, 2.0
    # r = A (1 - cos(w t)): from rest, without a velocity jump at t = 0
    over = {"rod.length": 0.05, "rod.elements": 4, "material.youngs_modulus": 1e7,
            "material.tau": 1e-3, "simulation.rtol": 1e-8,
            "start.motion": {"translation": [0.0, 0.0, A], "translation_time": {
                "kind": "harmonic", "amplitude": 1.0, "frequency": f, "offset": 1.0,
                "phase": -math.pi / 2}},
            "loads.0.vector": [0.0, 0.0, 0.0], "simulation.output_step": 0.005}
    run = simulate(_cantilever(1.0, **over))
    assert run.status == "finished", run.message
    mass = 1000.0 * 1e-4 * 0.05
    w = 2 * math.pi * f
    # the support's force on the rod accelerates it: + m a (a = A w^2 cos(w t))
    expect = mass * A * w * w * np.cos(w * run.t)
    Fz = run.reactions["start"]["force"][2]
    settled = run.t > 0.01                       # the strain's creep (1/tau) has settled
    assert np.max(np.abs(Fz - expect)[settled]) <= 2e-3 * mass * A * w * w
    # the rotation of the tip stays zero (a pure axial motion)
    assert np.max(np.abs(run.end_rotations()["end"])) < 1e-9


def test_the_summary_s_end_rotation_is_the_series_last_bit_for_bit():
    """summary.json's end rotation comes from the last output time alone
    (``end_rotations(last=True)``): the same numbers as the series' last column."""
    run = simulate(load_problem("cantilever", {"n_elements": 6, "t_end": 0.3}))
    full, last = run.end_rotations(), run.end_rotations(last=True)
    assert full.keys() == last.keys() == {"start", "end"}
    for end in full:
        assert last[end].shape == (3, 1) and np.array_equal(full[end][:, -1:], last[end])
    assert np.linalg.norm(last["end"]) > 0.1          # a bent tip: not a trivial zero
    assert run.summary()["end_rotation"]["end"]["rotation_vector"] == [
        float(v) for v in full["end"][:, -1]]


def test_end_rotation_of_a_bent_cantilever_is_second_order():
    """Tip rotation of a cantilever under a small tip force against Euler-Bernoulli
    F L^2 / (2 EI) plus nothing from shear: the frame extrapolated half a segment beyond
    the last segment converges at second order (the last segment's own frame would be
    first order)."""
    from runtime.problem.assemble import build_model
    from runtime.simulate.simulate import static_equilibrium

    F, L, EI = 1e-5, 0.3, 1e6 * 1e-8 / 12
    errs = []
    for n in (8, 16):
        p = load_problem("examples/cantilever.toml", {"rod.elements": n,
                                                      "loads.0.vector": [F, 0, 0]})
        m = build_model(p)
        st = static_equilibrium(p, m)
        R = st.end_frames["end"]
        angle = math.atan2(R[0, 2], R[2, 2])
        errs.append(abs(angle - F * L**2 / (2 * EI)) / (F * L**2 / (2 * EI)))
    assert errs[1] < 5e-3 and errs[0] / errs[1] > 3.0


# ---- every output at its own time ----------------------------------------------------
def test_vtk_frames_carry_the_clamp_curvature_of_their_time(tmp_path):
    """A clamp turned by 90 degrees about e2 over 0.5 s: the curvature of the clamp joint in
    each VTK frame is that between the clamp frame of the frame's time (computed here with
    SciPy's rotations) and the first segment's frame in the same file."""
    vtk = pytest.importorskip("vtk")
    from vtk.util.numpy_support import vtk_to_numpy

    from runtime.io.vtk import VtkSeries, read_pvd
    from runtime.problem.assemble import build_model

    p = _cantilever(1.0, **{"rod.elements": 8, "loads.0.vector": [0.0, 0.0, 0.0],
                            "start.motion": {"rotation_axis": [0, 1, 0],
                                             "rotation_angle": 90.0, "rotation_time": {
                                                 "kind": "smooth_ramp", "start": 0.0,
                                                 "duration": 0.5}}})
    model = build_model(p)
    series = VtkSeries(tmp_path, model)
    run = simulate(p, model=model, snapshot_every=0.125, snapshot_sink=series.add)
    series.close()
    assert run.status == "finished", run.message
    ramp = TimeFunction(kind="smooth_ramp", start=0.0, duration=0.5)
    h0 = 0.5 * 0.3 / 8
    checked = 0
    for t, name in read_pvd(tmp_path / "rod.pvd"):
        r = vtk.vtkXMLPolyDataReader()
        r.SetFileName(str(tmp_path / name))
        r.Update()
        out = r.GetOutput()
        cell, point = out.GetCellData(), out.GetPointData()
        d = [vtk_to_numpy(cell.GetArray(k))[0] for k in ("a1", "a2", "a3")]
        seg1 = Rotation.from_matrix(np.column_stack(d))
        clamp = Rotation.from_rotvec([0.0, math.radians(90.0) * ramp.value_at(t), 0.0])
        rel = (clamp.inv() * seg1).as_quat()            # x, y, z, w
        U0 = 2.0 / h0 * rel[:3] / rel[3]
        got = vtk_to_numpy(point.GetArray("U"))[0]
        assert got == pytest.approx(U0, rel=1e-6, abs=1e-9 * max(1.0, np.abs(U0).max()))
        checked += 1
    assert checked == 9


# ---- results that say when they are doubtful ----------------------------------------
def test_warnings_for_coarse_outputs_and_maxima_about_the_sag():
    """A steel tube cantilever sagging under gravity with maxima asked of end.z: it rings
    about its sag (the maxima are counted about that equilibrium: they were all "below
    the reference" and none was found); the default output step is coarse for its first
    mode, and the summary says that."""
    p = _cantilever(0.2, **{
        "section": {"kind": "tube", "outer_radius": 0.01, "inner_radius": 0.008},
        "material.youngs_modulus": 2.1e11, "material.density": 7850.0,
        "material.tau": 1e-4, "rod.elements": 10, "rod.geometry.direction": [1.0, 0, 0],
        "rod.geometry.normal": [0.0, 0, 1.0],
        "loads.0": {"kind": "gravity", "vector": [0.0, 0.0, -9.81],
                    "time": {"kind": "ramp", "start": 0.0, "duration": 0.01}},
        "analysis.maxima": "end.z"})
    run = simulate(p)
    s = run.summary()
    w = s["warnings"]
    assert run.status == "finished" and run.peaks_x.size > 3
    assert s["vibration_centre"]["source"] == "static equilibrium"
    assert s["vibration_centre"]["displacement"] < 0.0 and np.all(run.maxima_x[1:] < 0.0)
    assert not any("found no maxima" in s for s in w), w
    omega = euler_bernoulli_frequencies(1, L=0.3, rho=7850.0, A=np.pi * (1e-4 - 0.64e-4),
                                        E=2.1e11, I=np.pi / 4 * (1e-8 - 0.8**4 * 1e-8))[0]
    assert 2 * np.pi / omega / 0.005 < 20
    assert any("samples per period" in s for s in w), w


def test_maxima_that_never_turn_back_are_explained():
    """An overdamped cantilever (tau = 10 s) pushed by a ramped tip force creeps towards
    its equilibrium without turning back: no maxima, and the summary says why."""
    p = _cantilever(0.3, **{"material.tau": 10.0, "rod.elements": 6,
                            "loads.0.time": {"kind": "ramp", "start": 0.0, "duration": 0.05}})
    run = simulate(p)
    w = run.summary()["warnings"]
    assert run.peaks_x.size == 0
    assert any("found no maxima" in s and "without turning back" in s for s in w), w


def test_a_load_too_small_to_see_is_flagged():
    p = _cantilever(0.5, **{"loads.0.vector": [1e-300, 0.0, 0.0],
                            "loads.0.time": {"kind": "table", "points": PULSE}})
    run = simulate(p)
    assert run.status == "finished"
    assert any("stored no measurable energy" in s for s in run.summary()["warnings"])
