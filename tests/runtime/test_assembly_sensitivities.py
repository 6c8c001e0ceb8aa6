"""Sensitivities of assemblies (issue 34; runtime/model/native/system_tangent.c,
runtime/model/system_sensitivity.py, runtime/simulate/assembly_sensitivity.py): the
assembly residual's exact tangent against central differences of the residual (state and
parameter directions: a rod's material and section, a body's mass, inertia and offset,
gravity), whole runs (two welded rods released from their static deflection; a
cantilever with a body at its tip) and static equilibria against central differences of
independent runs, the compiled loop against the NumPy path, and the command line."""

from __future__ import annotations

import json

import numpy as np
import pytest

from runtime.problem.assemble_system import build_system
from runtime.problem.parameters import resolve_parameters, system_directions
from runtime.problem.registry import load_problem
from runtime.simulate import assembly as assembly_module
from runtime.simulate.assembly import simulate_assembly, static_equilibrium
from runtime.simulate.sensitivity import (
    simulate_with_sensitivities,
    static_with_sensitivities,
    with_parameters,
)

BOUND = 2e-3
TIP_BODY = {"rods.beam.rod.elements": 6, "simulation.t_end": 0.05,
            "simulation.output_step": 0.0005}
L_FRAME = {"rods.beam.rod.elements": 5, "rods.column.rod.elements": 6,
           "simulation.t_end": 0.05, "simulation.output_step": 0.0005}


def _residual(model, t, y, yp):
    out = np.empty(model.n)
    model.residual(t, y, yp, out)
    return out


@pytest.mark.parametrize("example,names", [
    ("examples/assembly_tip_body.toml",
     ["rods.beam.material.youngs_modulus", "bodies.0.mass", "bodies.0.inertia.0.0",
      "bodies.0.offset.2", "rods.beam.material.density", "loads.0.vector.2"]),
    ("examples/assembly_l_frame.toml",
     ["rods.column.material.youngs_modulus", "rods.beam.material.tau",
      "rods.beam.section.radius"])])
def test_assembly_residual_tangent_matches_differences(example, names):
    prob = load_problem(example)
    resolved = resolve_parameters(prob, names)
    model = build_system(prob).model
    model.set_directions(system_directions(prob, resolved, model))
    rng = np.random.default_rng(3)
    n, t = model.n, 0.3
    y = model.reference + 1e-6 * rng.standard_normal(n)
    yp = 1e-4 * rng.standard_normal(n)
    dy, dyp = rng.standard_normal(n), rng.standard_normal(n)
    e = 1e-6
    fd = (_residual(model, t, y + e * dy, yp + e * dyp)
          - _residual(model, t, y - e * dy, yp - e * dyp)) / (2 * e)
    got = model.residual_tangent(t, y, yp, dy, dyp, None)
    assert np.abs(got - fd).max() < 1e-7 * np.abs(fd).max()
    zero = np.zeros(n)
    for i, r in enumerate(resolved):
        h = 1e-1 * abs(r.value) if r.value else 1e-3      # the residual is linear in most
        if r.name.endswith("radius"):
            h = 1e-5 * r.value
        plus = build_system(with_parameters(prob, {r.name: r.value + h})).model
        minus = build_system(with_parameters(prob, {r.name: r.value - h})).model
        fd = (_residual(plus, t, y, yp) - _residual(minus, t, y, yp)) / (2 * h)
        got = model.residual_tangent(t, y, yp, zero, zero, i)
        assert np.abs(fd).max() > 0.0, r.name
        assert np.abs(got - fd).max() < 1e-5 * np.abs(fd).max(), r.name


def _run_differences(prob, name, value, rtol=1e-10, step=1e-4):
    d = step * abs(value)
    tight = {"simulation.rtol": rtol}
    p = simulate_assembly(with_parameters(prob, {name: value + d}).with_overrides(tight))
    m = simulate_assembly(with_parameters(prob, {name: value - d}).with_overrides(tight))
    return {k: (p.ends[k] - m.ends[k]) / (2 * d) for k in p.ends}


@pytest.mark.parametrize("example,overrides,names", [
    ("examples/assembly_tip_body.toml", TIP_BODY,
     ["rods.beam.material.youngs_modulus", "bodies.0.mass"]),
    ("examples/assembly_l_frame.toml", L_FRAME,
     ["rods.beam.material.youngs_modulus", "loads.0.vector.1", "rods.column.material.tau"])])
def test_assembly_run_sensitivities_match_differences(example, overrides, names):
    """The tip body starts at rest in the reference (zero initial sensitivities); the
    L-frame from its static deflection (the static sensitivities, then consistent ones)."""
    prob = load_problem(example).with_overrides(overrides)
    res, sens = simulate_with_sensitivities(prob.with_overrides({"simulation.rtol": 1e-8}),
                                            names)
    assert res.status == "finished"
    assert sens.counters["nfevS"] > 0
    for r in resolve_parameters(prob, names):
        fd = _run_differences(prob, r.name, r.value)
        for key, ref in fd.items():
            got = sens.channels[f"{key.replace('/', '.')}/{r.name}"]
            assert got.shape == res.ends[key].shape
            scale = np.abs(ref).max()
            if scale < 1e-9 * np.abs(fd[max(fd, key=lambda k: np.abs(fd[k]).max())]).max():
                continue          # a clamp, or a derivative below the differences' noise
            assert np.abs(got - ref).max() < BOUND * scale, (r.name, key)


def test_assembly_static_sensitivities_match_differences_of_statics():
    prob = load_problem("examples/assembly_l_frame.toml").with_overrides(
        {"rods.beam.rod.elements": 5, "rods.column.rod.elements": 6})
    names = ["rods.beam.material.youngs_modulus", "rods.column.section.radius",
             "loads.0.vector.1"]
    _, sens = static_with_sensitivities(prob, names)
    for r in resolve_parameters(prob, names):
        d = 1e-5 * abs(r.value)
        pp, pm = (with_parameters(prob, {r.name: r.value + s * d}) for s in (1.0, -1.0))
        p, m = static_equilibrium(pp, build_system(pp)), static_equilibrium(pm, build_system(pm))
        fd = (p.y - m.y) / (2 * d)
        got = sens.channels[f"y/{r.name}"]
        assert np.abs(got - fd).max() <= 1e-5 * np.abs(fd).max(), r.name
        amap = build_system(prob)
        idx = amap.model.phi_index[1]
        assert np.array_equal(sens.channels[f"beam.positions/{r.name}"], got[idx].T)


def test_assembly_compiled_loop_and_numpy_path_agree(monkeypatch):
    prob = load_problem("examples/assembly_tip_body.toml").with_overrides(TIP_BODY)
    names = ["rods.beam.material.youngs_modulus", "bodies.0.mass"]
    _, compiled = simulate_with_sensitivities(prob, names)
    run_loop = assembly_module.run_loop

    def numpy_loop(*args, solver_options=None, **kwargs):
        return run_loop(*args, solver_options={**solver_options, "compiled_loop": False},
                        **kwargs)

    monkeypatch.setattr(assembly_module, "run_loop", numpy_loop)
    _, numpy_path = simulate_with_sensitivities(prob, names)
    assert compiled.counters == numpy_path.counters
    for k, v in compiled.channels.items():
        assert np.allclose(v, numpy_path.channels[k], rtol=1e-9, atol=1e-12 * np.abs(v).max())


def test_kvrod_simulate_and_static_write_assembly_sensitivities(tmp_path):
    from kvrod.cli import main

    out = tmp_path / "run"
    assert main(["simulate", "examples/assembly_tip_body.toml", "--t-end", "0.02",
                 "--set", "rods.beam.rod.elements=6", "--sensitivities",
                 "bodies.0.mass,rods.beam.material.youngs_modulus", "--out", str(out)]) == 0
    series, sens = np.load(out / "series.npz"), np.load(out / "sensitivities.npz")
    for name in ("bodies.0.mass", "mass", "youngs_modulus"):
        assert sens[f"beam.end/{name}"].shape == series["beam/end"].shape
        assert sens[f"beam.start/{name}"].shape == series["beam/start"].shape
    assert np.array_equal(sens["t"], series["t"])
    s = json.loads((out / "summary.json").read_text())
    assert s["sensitivities"]["parameters"]["bodies.0.mass"] == 0.2
    out = tmp_path / "static"
    assert main(["static", "examples/assembly_l_frame.toml", "--sensitivities",
                 "rods.beam.material.youngs_modulus", "--out", str(out)]) == 0
    st, sens = np.load(out / "static.npz"), np.load(out / "sensitivities.npz")
    assert sens["beam.positions/rods.beam.material.youngs_modulus"].shape == \
        st["beam/positions"].shape
    assert sens["y/rods.beam.material.youngs_modulus"].shape == st["y"].shape
