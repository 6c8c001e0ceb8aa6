"""Problems extend from the command line and from Python (issue 22, item 6): whole tables
and arrays of tables as override values, appending an array entry at index len(array)."""

from __future__ import annotations

import pytest

from kvrod.problem_args import parse_set
from runtime.errors import ParameterError
from runtime.problem.registry import load_problem
from runtime.problem.schema import Problem

FORCE = {"kind": "force", "vector": [0.0, 0.0, 0.01]}


def test_set_appends_a_load_with_an_inline_table():
    key, value = parse_set('loads.1={kind="force", vector=[0,0,0.01], at="start"}')
    assert key == "loads.1" and value == {"kind": "force", "vector": [0, 0, 0.01],
                                          "at": "start"}
    base = load_problem("cantilever")
    p = load_problem("cantilever", {key: value})
    assert len(p.loads) == len(base.loads) + 1
    assert p.loads[:-1] == base.loads          # the existing load is untouched
    new = p.loads[-1]
    assert (new.kind, new.vector, new.at) == ("force", (0.0, 0.0, 0.01), "start")


def test_set_replaces_an_entry_and_a_sub_key():
    p = load_problem("cantilever", {"loads.0": {"kind": "gravity", "vector": [0, 0, -9.81]}})
    assert len(p.loads) == 1 and p.loads[0].kind == "gravity"
    q = load_problem("cantilever", {"loads.0.vector": [0.0, 0.0, 1.0]})
    assert q.loads[0].vector == (0.0, 0.0, 1.0)
    # append, then change a key of the appended entry (overrides apply in order)
    r = load_problem("cantilever", {"loads.1": FORCE, "loads.1.vector": [0.0, 1.0, 0.0]})
    assert r.loads[1].vector == (0.0, 1.0, 0.0)


@pytest.mark.parametrize("key", ["loads.2", "loads.-1", "loads.x"])
def test_an_index_beyond_the_append_position_names_the_range(key):
    with pytest.raises(ParameterError) as exc:
        load_problem("cantilever", {key: FORCE})
    msg = str(exc.value)
    assert "loads" in msg and "0 ... 1" in msg and "appends" in msg, msg


def test_a_sub_key_of_a_missing_entry_says_how_to_append():
    with pytest.raises(ParameterError) as exc:
        load_problem("cantilever", {"loads.1.vector": [0, 0, 1]})
    msg = str(exc.value)
    assert "0 ... 0" in msg and "to append" in msg and "loads.1" in msg, msg


def test_maxwell_branch_appended_and_checked_as_in_a_file():
    base = load_problem("maxwell_cantilever")
    n = len(base.material.branches)
    branch = {"tau": 0.5, "youngs_modulus": 1e5, "poisson_ratio": 0.3}
    p = load_problem("maxwell_cantilever", {f"material.branches.{n}": branch})
    assert len(p.material.branches) == n + 1 and p.material.branches[-1].tau == 0.5
    with pytest.raises(ParameterError, match=r"material\.branches.*tau"):
        load_problem("maxwell_cantilever", {f"material.branches.{n}": {**branch, "tau": 0.0}})


def test_python_overrides_take_whole_tables_and_arrays():
    material = {"density": 500.0, "youngs_modulus": 2e6, "poisson_ratio": 0.25, "tau": 0.01}
    loads = [{"kind": "gravity", "vector": [0.0, 0.0, -9.81]}, FORCE]
    ov = {"material": material, "loads": loads}
    p = load_problem("cantilever", ov)
    m = p.material
    assert (m.density, m.youngs_modulus, m.poisson_ratio, m.tau_S, m.tau_B) == (
        500.0, 2e6, 0.25, 0.01, 0.01)
    assert [ld.kind for ld in p.loads] == ["gravity", "force"]
    assert ov == {"material": material, "loads": loads}      # the caller's dicts unchanged
    assert "tau" in material and len(loads) == 2
    q = Problem.with_overrides(load_problem("cantilever"), ov)
    assert q == p
    # the same as a file with those tables
    assert p.to_mapping()["material"] == Problem.from_mapping(
        {**load_problem("cantilever").to_mapping(), "material": material}
    ).to_mapping()["material"]


@pytest.mark.parametrize("ov, needle", [
    ({"material": {"density": -1.0}}, "material.density"),
    ({"material": {"youngs_modulus": 1e6, "tau": 0.01, "tau_S": 0.02}}, "tau_S"),
    ({"loads": {"kind": "force"}}, "loads"),
    ({"loads": [{"kind": "force", "vectr": [0, 0, 1]}]}, "vectr"),
    ({"material": 3}, "material"),
    ({"sectoin": {"kind": "circle"}}, "sectoin"),
])
def test_whole_table_overrides_are_validated_as_a_file(ov, needle):
    with pytest.raises(ParameterError) as exc:
        load_problem("cantilever", ov)
    assert needle in str(exc.value)


def test_index_zero_of_a_missing_array_appends_its_first_entry():
    """``--set zones.0={...}`` on a problem without zones (and ``loads.0`` without loads)
    makes the array of tables, as the index one past the last entry does; it used to make
    a table {"0": ...} that was refused as "an array of tables [[zones]]"."""
    zone = {"from": 0.0, "to": 0.15, "material": {"youngs_modulus": 2e6}}
    p = load_problem("cantilever", {"zones.0": zone})
    assert len(p.zones) == 1 and (p.zones[0].start, p.zones[0].end) == (0.0, 0.15)
    assert p.zones[0].material.youngs_modulus == 2e6
    q = load_problem("cantilever", {"loads": [], "loads.0": FORCE})
    assert len(q.loads) == 1
    base = load_problem("cantilever").to_mapping()
    base.pop("loads")
    r = Problem.from_mapping(base).with_overrides({"loads.0": FORCE})
    assert len(r.loads) == 1 and r.loads[0].vector == (0.0, 0.0, 0.01)
    with pytest.raises(ParameterError) as exc:     # a sub-key of a missing entry
        load_problem("cantilever", {"zones.0.from": 0.1})
    assert "zones.0" in str(exc.value) and "append" in str(exc.value)
