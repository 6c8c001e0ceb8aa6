"""Issue 6: every bad input gives one clear error naming the parameter (CLI: one line,
non-zero exit, no traceback); valid inputs never raise (Hypothesis)."""

from __future__ import annotations

import math
import re
import subprocess
import sys

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from generated import constitutive as gc
from runtime.errors import ParameterError
from runtime.problem.registry import ProblemFileError, load_config, load_problem


def CantileverScenario(**kw):  # noqa: N802 - the built-in cantilever with aliases
    return load_problem("cantilever", kw)


ConfigError = ProblemFileError

CLI_BAD = [
    # (argv, substring expected in the one-line message)
    (["simulate", "cantilever", "--E", "0"], "youngs_modulus"),
    (["simulate", "cantilever", "--E=-1e6"], "youngs_modulus"),
    (["simulate", "cantilever", "--E", "nan"], "youngs_modulus"),
    (["simulate", "cantilever", "--E", "inf"], "youngs_modulus"),
    (["simulate", "cantilever", "--nu", "0.50001"], "poisson_ratio"),
    (["simulate", "cantilever", "--nu", "-1"], "poisson_ratio"),
    (["simulate", "cantilever", "--nu", "-1.5"], "poisson_ratio"),
    (["simulate", "cantilever", "--nu", "0.7"], "poisson_ratio"),
    (["simulate", "cantilever", "--tau", "-0.01"], "tau"),
    (["simulate", "cantilever", "--tau", "nan"], "tau"),
    (["simulate", "cantilever", "--tau-S", "-1"], "tau_S"),
    (["simulate", "cantilever", "--tau-B", "inf"], "tau_B"),
    (["simulate", "cantilever", "--n-elements", "0"], "rod.elements"),
    (["simulate", "cantilever", "--n-elements", "-3"], "rod.elements"),
    (["simulate", "cantilever", "--n-elements", "2.5"], "n-elements"),
    (["simulate", "cantilever", "--t-end", "0"], "t_end"),
    (["simulate", "cantilever", "--t-end", "-1"], "t_end"),
    (["simulate", "cantilever", "--t-end", "nan"], "t_end"),
    (["simulate", "cantilever", "--rtol", "0"], "rtol"),
    (["simulate", "cantilever", "--rtol", "2"], "rtol"),
    (["simulate", "cantilever", "--tip-force", "inf"], "tip_force"),
    (["simulate", "cantilever", "--tip-force", "abc"], "tip-force"),
    (["simulate", "cantilever", "--damping", "magic"], "damping"),
    (["simulate", "cantilever", "--vtk", "0"], "--vtk"),
    (["simulate", "no_such_problem"], "unknown problem"),
    (["simulate"], "name a problem"),
    (["simulate", "cantilever", "--bogus"], "unrecognized"),
    (["simulate", "cantilever", "--config", "/nonexistent/run.toml"], "cannot read"),
    (["derive", "show", "no_such_step"], "unknown step"),
    (["derive", "show"], "required"),
    (["derive", "bogus"], "invalid choice"),
    (["derive", "export", "nope"], "unknown step"),
    (["generate", "--chek"], "unrecognized"),
    (["frobnicate"], "invalid choice"),
    (["reproduce", "--n-elements", "x"], "n-elements"),
    (["static", "rollup", "--set", "statics.report=[1.5]"], "statics.report[0]"),
    (["static", "rollup", "--set", "statics.report=0.5"], "statics.report"),
]


@pytest.mark.parametrize(("argv", "needle"), CLI_BAD, ids=[" ".join(a) for a, _ in CLI_BAD])
def test_cli_bad_input(argv, needle, tmp_path):
    r = subprocess.run([sys.executable, "-m", "kvrod.cli", *argv, *(
        ["--out", str(tmp_path)] if argv[0] == "simulate" else [])],
        capture_output=True, text=True, timeout=120, cwd=tmp_path)
    assert r.returncode == 2, (r.returncode, r.stdout, r.stderr)
    err = r.stderr.strip().splitlines()
    err = [e for e in err if "%|" not in e]          # progress bars never start, but be safe
    assert len(err) == 1, r.stderr
    assert "Traceback" not in r.stderr
    assert needle in err[0], err[0]


CONFIG_BAD = [
    ('scenario = "cantilever"\n[parameters]\ntau = "x"\n', "material.tau)' = 'x'"),
    ('scenario = "pendulum_x"\n', "unknown problem"),
    ('scenario = "cantilever"\n[parameters]\nyoung = 1e6\n', "unknown parameter 'young'"),
    ('scenario = "cantilever"\n[parameters]\nn_elements = 2.5\n', "rod.elements)' = 2.5"),
    ('scenario = "cantilever"\n[parameters]\nn_elements = true\n', "rod.elements)' = True"),
    ('scenario = "cantilever"\n[parameters\n', "malformed TOML"),
    ('scenario = "cantilever"\nparameters = 3\n', "must be a table"),
    ('scenario = "cantilever"\n[other]\nx = 1\n', "unknown table"),
    ('scenario = "cantilever"\n[parameters]\ndamping = 1\n', "section.damping)' = 1"),
    ('scenario = ["cantilever"]\n', "must be a string"),
    ('scenario = "cantilever"\n[parameters]\ntau = 0.1\ntau_S = 0.2\n', "both given"),
]


@pytest.mark.parametrize(("text", "needle"), CONFIG_BAD)
def test_config_bad_input(text, needle, tmp_path):
    f = tmp_path / "run.toml"
    f.write_text(text)
    with pytest.raises(ValueError, match=re.escape(needle)):
        name, kw = load_config(f)
        load_problem(name, kw)


def test_config_values_are_validated_by_the_problem(tmp_path):
    f = tmp_path / "run.toml"
    f.write_text('scenario = "cantilever"\n[parameters]\nyoungs_modulus = -5.0\n')
    name, kw = load_config(f)
    with pytest.raises(ValueError, match="youngs_modulus"):
        load_problem(name, kw)


API_BAD = [
    ({"youngs_modulus": 0.0}, "youngs_modulus"), ({"density": -1.0}, "density"),
    ({"length": 0.0}, "length"), ({"width": -0.01}, "width"), ({"height": math.nan}, "height"),
    ({"poisson_ratio": 0.5000001}, "poisson_ratio"), ({"poisson_ratio": -1.0}, "poisson_ratio"),
    ({"tau_S": -1e-3}, "tau_S"), ({"n_elements": 0}, "elements"),
    ({"t_end": math.inf}, "t_end"), ({"output_step": 0.0}, "output_step"),
    ({"min_step": -1.0}, "min_step"), ({"atol": 0.0}, "atol"),
]


@pytest.mark.parametrize(("kw", "needle"), API_BAD)
def test_api_bad_input(kw, needle):
    with pytest.raises(ValueError, match=needle) as info:
        CantileverScenario(**kw)
    assert "range" in str(info.value) or "allowed" in str(info.value)


def test_nu_one_half_only_where_nothing_divides_by_1_minus_2nu():
    assert np.isfinite(gc.damping_matrices(1e6, 0.5, 0.04, 0.01, 1e-4, 1e-9, 1e-9, 2e-9)[0]).all()
    with pytest.raises(gc.ParameterError, match=r"'nu' = 0.5 .*\(-1, 0.5\)"):
        gc.bulk_modulus(1e6, 0.5)


@settings(max_examples=60, deadline=None)
@example(E=100.0, nu=0.49999999999999994, tS=0.0, tB=3.0, w=1.0, h=1.0)  # 2*nu*tB - tB cancelled
@given(E=st.floats(1e2, 1e12), nu=st.floats(-0.999, 0.5),
       tS=st.one_of(st.just(0.0), st.floats(1e-9, 10)),
       tB=st.one_of(st.just(0.0), st.floats(1e-9, 10)),
       w=st.floats(1e-4, 1.0), h=st.floats(1e-4, 1.0))
def test_constitutive_property(E, nu, tS, tB, w, h):
    """Valid parameters never raise; matrices are finite, diagonal, positive (semi)definite,
    and damping = stiffness x retardation times (9)."""
    sec = gc.rectangle_section(w, h, nu)
    geo = (sec["A"], sec["I1"], sec["I2"], sec["I3"], sec["kappa_1"], sec["kappa_2"],
           sec["kappa_3"])
    CF, CM = gc.stiffness_matrices(E, nu, *geo)
    VF, VM = gc.damping_matrices(E, nu, tS, tB, *geo)
    tE = gc.retardation_time_extension(tB, tS, nu)
    for m in (CF, CM):
        assert np.all(np.isfinite(m)) and np.all(np.diag(m) > 0)
    assert np.allclose(np.diag(VF), np.diag(CF) * [tS, tS, tE], rtol=1e-12, atol=0)
    assert np.allclose(np.diag(VM), np.diag(CM) * [tE, tE, tS], rtol=1e-12, atol=0)
    assert 0 < sec["kappa_3"] <= 1 and 0 < sec["kappa_1"] <= 1


@settings(max_examples=40, deadline=None)
@given(E=st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.just(0.0)),
       nu=st.floats(allow_nan=True, allow_infinity=True),
       n=st.integers(-5, 400))
def test_scenario_builder_property(E, nu, n):
    """The builder accepts exactly the documented ranges, otherwise raises ValueError."""
    valid = math.isfinite(E) and E > 0 and math.isfinite(nu) and -1 < nu <= 0.5 and n >= 1
    if valid:
        try:
            sc = CantileverScenario(youngs_modulus=E, poisson_ratio=nu, n_elements=n)
        except ParameterError as exc:  # a rod so stiff that t_end spans > 1e6 periods
            assert exc.name == "simulation.t_end" and E > 1e12, exc
        else:
            assert sc.rod.elements == n
    else:
        with pytest.raises(ValueError):
            CantileverScenario(youngs_modulus=E, poisson_ratio=nu, n_elements=n)
