"""Derivatives of the damped modes (issue 34; runtime/analysis/modal_sensitivity.py):
d omega / d theta and d zeta / d theta against central differences of independent modal
analyses with the parameter changed (Kelvin-Voigt about the reference and about a
loaded static state, a generalized Maxwell rod, a degenerate pair split by the
parameter), and ``kvrod modes --sensitivities`` against differences of ``kvrod modes``."""

from __future__ import annotations

import json

import numpy as np
import pytest

from runtime.analysis.modal import modal_analysis
from runtime.analysis.modal_sensitivity import analysed_problem, modal_sensitivities
from runtime.problem.assemble import build_model
from runtime.problem.parameters import resolve_parameters, with_parameters
from runtime.problem.registry import load_problem
from runtime.simulate.simulate import static_equilibrium

COUNT = 6


def _modes(problem, deformed):
    p = analysed_problem(problem, deformed)
    model = build_model(p)
    y = static_equilibrium(p, model).y if deformed else None
    return model, y, modal_analysis(model, y, count=COUNT)


def _differences(problem, name, value, deformed, step=1e-5):
    h = step * abs(value)
    _, _, plus = _modes(with_parameters(problem, {name: value + h}), deformed)
    _, _, minus = _modes(with_parameters(problem, {name: value - h}), deformed)
    return {key: np.array([(getattr(a, key) - getattr(b, key)) / (2 * h)
                           for a, b in zip(plus, minus, strict=True)])
            for key in ("omega", "zeta")}


def _check(problem, names, deformed, rtol):
    model, y, modes = _modes(problem, deformed)
    resolved = resolve_parameters(problem, names)
    got = modal_sensitivities(problem, resolved, modes, model, y, deformed)
    for r in resolved:
        fd = _differences(problem, r.name, r.value, deformed)
        for key in ("omega", "zeta"):
            scale = max(np.abs(fd[key]).max(), 1e-300)
            if np.abs(fd[key]).max() == 0.0:        # tau moves no natural frequency
                assert np.abs(got[r.name][key]).max() <= 1e-12 * np.abs(
                    fd["zeta"]).max() * max(m.omega for m in modes), (r.name, key)
                continue
            assert np.abs(got[r.name][key] - fd[key]).max() < rtol * scale, (r.name, key)
    return modes, got


RECTANGLE = {"rod.elements": 10, "section.height": 0.012}


def test_kelvin_voigt_modes_about_the_reference():
    prob = load_problem("examples/cantilever.toml").with_overrides(RECTANGLE)
    _check(prob, ["youngs_modulus", "tau_S", "density", "section.width"], False, 1e-5)


def test_kelvin_voigt_modes_about_a_loaded_static_state():
    """Deformed: the equilibrium moves with the parameter (static sensitivities) and the
    load enters the geometric stiffness."""
    prob = load_problem("examples/cantilever.toml").with_overrides(RECTANGLE)
    _check(prob, ["youngs_modulus", "tau_S", "tip_force"], True, 1e-5)


def test_generalized_maxwell_modes():
    prob = load_problem("examples/maxwell_cantilever.toml").with_overrides(
        {"rod.elements": 8, "section.height": 0.012})
    _check(prob, ["material.branches.0.youngs_modulus", "material.branches.1.tau",
                  "youngs_modulus"], False, 1e-4)


def test_a_degenerate_pair_split_by_the_parameter():
    """A square section: the two bending families coincide; the width stiffens one
    (omega proportional to w) and not the other. Differences of modes sorted by
    frequency cross there (each sees the mean), the pair's sum is smooth: it must agree,
    and the derivatives must split (one near omega / w, one near 0)."""
    prob = load_problem("examples/cantilever.toml").with_overrides({"rod.elements": 10})
    model, y, modes = _modes(prob, False)
    r = resolve_parameters(prob, ["section.width"])
    got = modal_sensitivities(prob, r, modes, model, y, False)["section.width"]["omega"]
    fd = _differences(prob, "section.width", r[0].value, False)["omega"]
    width = r[0].value
    for a in range(0, COUNT, 2):
        assert modes[a].omega == pytest.approx(modes[a + 1].omega, rel=1e-8)
        assert got[a] + got[a + 1] == pytest.approx(fd[a] + fd[a + 1], rel=1e-5)
        lo, hi = sorted(got[a:a + 2])
        assert abs(lo) < 1e-3 * hi
        assert hi == pytest.approx(modes[a].omega / width, rel=0.05)


def test_kvrod_modes_writes_derivatives_that_match_differences_of_kvrod_modes(tmp_path):
    from kvrod.cli import main

    common = ["modes", "examples/cantilever.toml", "--n-elements", "8", "--count", "4",
              "--set", "section.height=0.012"]
    assert main([*common, "--sensitivities", "material.tau_S,E", "--out",
                 str(tmp_path / "s")]) == 0
    sens = json.loads((tmp_path / "s" / "modes.json").read_text())["sensitivities"]
    assert set(sens) == {"material.tau_S", "tau_S", "E", "youngs_modulus"}
    for name, key, value in (("tau_S", "material.tau_S", 0.04),
                             ("E", "material.youngs_modulus", 1e6)):
        h = 1e-5 * value
        modes = []
        for sign in (1.0, -1.0):
            out = tmp_path / f"{name}{sign:+.0f}"
            assert main([*common, "--set", f"{key}={value + sign * h!r}", "--out",
                         str(out)]) == 0
            modes.append(json.loads((out / "modes.json").read_text())["modes"])
        for q in ("omega", "zeta"):
            fd = np.array([(a[q] - b[q]) / (2 * h) for a, b in zip(*modes, strict=True)])
            got = np.array(sens[name][q])
            assert got.shape == (4,)
            assert np.abs(got - fd).max() <= 1e-5 * np.abs(fd).max() + 1e-12 * np.abs(
                got).max() + (1e-9 if q == "omega" and name == "tau_S" else 0.0), (name, q)
