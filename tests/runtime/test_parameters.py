"""Parameters by name (issue 34; runtime/problem/parameters.py): the names a sweep and
``--set`` take, aliases, derived keys, refusals in one line, and the derivatives of the
rod's arrays (exact where the build is linear in the key, a stated difference elsewhere)
against closed forms."""

from __future__ import annotations

import numpy as np
import pytest

from runtime.errors import ParameterError
from runtime.problem.assemble import build_model
from runtime.problem.parameters import array_directions, resolve_parameters, with_parameters
from runtime.problem.registry import load_problem


@pytest.fixture(scope="module")
def cantilever():
    return load_problem("cantilever").with_overrides({"rod.elements": 6})


def test_names_paths_aliases(cantilever):
    r = {x.name: x for x in resolve_parameters(cantilever, [
        "material.youngs_modulus", "E", "tau_S", "tau", "loads.0.vector.x", "tip_force",
        "section.width", "density"])}
    assert r["material.youngs_modulus"].alias == "youngs_modulus"
    assert r["E"].paths == ("material.youngs_modulus",) and r["E"].value == 1e6
    assert r["tau_S"].paths == ("material.tau_S",) and r["tau"].value == 0.04
    assert r["loads.0.vector.x"].key == "loads.0.vector.0"
    assert r["loads.0.vector.x"].value == 0.05 and r["tip_force"].value == 0.05
    assert r["section.width"].alias == "width" and r["density"].value == 1000.0


def test_tau_S_on_a_problem_written_with_tau_holds_tau_B(cantilever):
    q = with_parameters(cantilever, {"tau_S": 0.05})
    assert (q.material.tau_S, q.material.tau_B) == (0.05, 0.04)
    assert q.rod.elements == cantilever.rod.elements
    split = cantilever.with_overrides({"material.tau_S": 0.02, "material.tau_B": 0.03})
    with pytest.raises(ParameterError, match="tau_S and tau_B"):
        resolve_parameters(split, ["tau"])


@pytest.mark.parametrize("name,why", [
    ("rod.elements", "count of elements"), ("simulation.t_end", "setting of the run"),
    ("loads.0.time.start", "breakpoint"), ("section.kind", "name or kind"),
    ("section.shear_correction", "flag")])
def test_refusals_name_the_key_and_why(cantilever, name, why):
    with pytest.raises(ParameterError, match=why) as exc:
        resolve_parameters(cantilever, [name])
    assert name in str(exc.value) and "\n" not in str(exc.value)


def test_unknown_names_list_close_matches(cantilever):
    with pytest.raises(ParameterError, match="close: youngs_modulus"):
        resolve_parameters(cantilever, ["youngs_modulos"])
    with pytest.raises(ParameterError, match="each parameter once"):
        resolve_parameters(cantilever, ["E", "E"])


def test_a_leaf_shared_by_two_keys_needs_its_path():
    p = load_problem("maxwell_cantilever").with_overrides({"rod.elements": 4})
    with pytest.raises(ParameterError, match="several parameters end in it"):
        resolve_parameters(p, ["shear_modulus"])
    r = resolve_parameters(p, ["material.branches.1.tau"])[0]
    assert r.value == 0.01 and r.alias is None
    E1 = resolve_parameters(p, ["material.branches.0.youngs_modulus"])[0].value
    assert E1 == pytest.approx(6.6666666666666667e6, rel=1e-12)


def test_assembly_aliases_set_every_rod():
    a = load_problem("examples/assembly_two_rod_cantilever.toml")
    r = resolve_parameters(a, ["youngs_modulus", "rods.tip.material.tau_S"])
    assert r[0].paths == ("rods.root.material.youngs_modulus",
                          "rods.tip.material.youngs_modulus")
    b = a.with_overrides({"rods.tip.material.youngs_modulus": 2e6})
    with pytest.raises(ParameterError, match="one value on every rod"):
        resolve_parameters(b, ["youngs_modulus"])


def test_directions_are_exact_where_the_build_is_linear(cantilever):
    """dC/dE = C/E and dV/dtau_S from the build by differences: exact to round-off,
    reported as such (error 0)."""
    m = build_model(cantilever)
    rs = resolve_parameters(cantilever, ["E", "density", "tip_force"])
    dirs, info = array_directions(cantilever, rs, m.arrays)
    a = m.arrays
    assert [d.error for d in info] == [0.0, 0.0, 0.0]
    dE = dirs.arrays[0]
    assert np.allclose(dE.seg_field("C_F"), a.seg_field("C_F") / 1e6, rtol=1e-10, atol=0)
    assert np.allclose(dE.jnt_field("C_M"), a.jnt_field("C_M") / 1e6, rtol=1e-10, atol=0)
    assert np.allclose(dirs.arrays[1].seg_field("rhoA"), a.seg_field("rhoA") / 1000.0,
                       rtol=1e-10, atol=0)
    assert info[2].drive is not None and info[0].drive is None


def test_directions_of_a_nonlinear_key_state_their_error(cantilever):
    """EI = E w^3 h / 12: dEI/dw = 3 EI / w, by Richardson to far below its stated error
    bound (the central difference's)."""
    m = build_model(cantilever)
    dirs, info = array_directions(cantilever, resolve_parameters(cantilever,
                                                                 ["section.width"]),
                                  m.arrays)
    assert info[0].error > 0.0
    EI = m.arrays.jnt_field("C_M")[2, 1]
    got = dirs.arrays[0].jnt_field("C_M")[2, 1]
    assert got == pytest.approx(3 * EI / 0.01, rel=1e-9)
    assert abs(got / (3 * EI / 0.01) - 1) < info[0].error
