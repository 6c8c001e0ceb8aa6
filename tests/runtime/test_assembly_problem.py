"""Assembly problem files (issue 31): several rods, joints, rigid bodies.

Parsing, the round trip (from_mapping(to_mapping()) and a results folder's problem.toml),
overrides (paths through rods.NAME, joints, bodies, loads; the short aliases broadcast to
every rod), points and the nodes they place, load routing, analysis.maxima, the key
catalogue against the parser, and one bad-input row per refusal (a single line naming
the key path)."""

from __future__ import annotations

import copy
import math
import subprocess
import sys
import tomllib
from typing import Any

import numpy as np
import pytest

from runtime.errors import ParameterError
from runtime.io.results import write_problem
from runtime.problem import coerce, keys
from runtime.problem.assembly import (
    ASSEMBLY_TOP_KEYS,
    Assembly,
    Body,
    Joint,
    Point,
)
from runtime.problem.geometry import discretize
from runtime.problem.registry import EXAMPLES_DIR, builtin_names, load_config, load_problem
from runtime.problem.schema import Problem

EXAMPLES = ("assembly_two_rod_cantilever", "assembly_harness", "assembly_tip_body",
            "assembly_double_pendulum", "assembly_l_frame")
MATERIAL = {"density": 1000.0, "youngs_modulus": 1.0e6, "poisson_ratio": 0.3, "tau": 0.04}
SPRING = [[1.0e3 if i == j else 0.0 for j in range(6)] for i in range(6)]


def _base() -> dict[str, Any]:
    """Two rods: a (0.3 m up z from the origin, clamped) and b (0.2 m along x from a's
    end), welded; a body at b's end; gravity and a force at b's end."""
    return {
        "name": "frame", "description": "an L of two rods",
        "rods": {
            "a": {"rod": {"length": 0.3, "elements": 6,
                          "geometry": {"kind": "straight", "direction": [0.0, 0.0, 1.0]}},
                  "section": {"kind": "rectangle", "width": 0.01, "height": 0.01},
                  "material": dict(MATERIAL), "start": {"kind": "clamped"}},
            "b": {"rod": {"length": 0.2, "elements": 4,
                          "geometry": {"kind": "straight", "direction": [1.0, 0.0, 0.0],
                                       "origin": [0.0, 0.0, 0.3]}},
                  "section": {"kind": "circle", "radius": 0.005},
                  "material": dict(MATERIAL)},
        },
        "joints": [{"kind": "weld", "between": ["a.end", "b.start"]}],
        "bodies": [{"name": "m", "at": "b.end", "mass": 0.01}],
        "loads": [{"kind": "gravity", "vector": [0.0, 0.0, -9.81]},
                  {"kind": "force", "at": "b.end", "vector": [0.0, 0.01, 0.0],
                   "time": {"kind": "release", "start": 0.0}}],
        "simulation": {"t_end": 1.0, "output_step": 0.01},
        "analysis": {"maxima": "b.end.y"},
    }


# -- parsing --------------------------------------------------------------------------------
def test_rods_joints_bodies_and_loads_are_read_in_file_order():
    a = Assembly.from_mapping(_base())
    assert a.rod_names == ("a", "b") and a.rod_index("b") == 1
    assert isinstance(a.rods["a"], Problem) and a.rods["a"].name == "a"
    assert a.rods["a"].start.kind == "clamped" and a.rods["a"].end.kind == "free"
    assert a.rods["b"].start.kind == "free" and a.rods["b"].end.kind == "free"
    j = a.joints[0]
    assert isinstance(j, Joint) and (j.index, j.kind) == (0, "weld")
    assert j.first == Point("a", 0.3, "a.end") and j.second == Point("b", 0.0, "b.start")
    b = a.bodies[0]
    assert isinstance(b, Body) and (b.name, b.at.label, b.mass) == ("m", "b.end", 0.01)
    assert np.array_equal(b.inertia, np.zeros((3, 3))) and np.array_equal(b.offset, [0, 0, 0])
    assert a.analysis.point == Point("b", 0.2, "b.end") and a.analysis.axis == 1
    # every rod keeps the assembly's settings and no maxima of its own
    for p in a.rods.values():
        assert p.simulation == a.simulation and p.simulation.t_end == 1.0
        assert p.analysis.maxima is None
    assert a.rods["b"].rod.geometry.origin == (0.0, 0.0, 0.3)


def test_joint_kinds_carry_their_parameters():
    m = _base()
    m["joints"] = [
        {"kind": "hinge", "between": ["a.end", "b.start"], "axis": [0.0, 2.0, 0.0],
         "rotational_stiffness": 0.5, "rotational_viscosity": 0.01},
        {"kind": "ball", "between": ["ground", "a@0.15"]},
        {"kind": "spring", "between": ["b.end", "ground"], "stiffness_matrix": SPRING},
    ]
    a = Assembly.from_mapping(m)
    hinge, ball, spring = a.joints
    assert np.array_equal(hinge.axis, [0.0, 1.0, 0.0])          # normalised
    assert (hinge.rotational_stiffness, hinge.rotational_viscosity) == (0.5, 0.01)
    assert ball.first == Point("a", 0.15, "a@0.15") and ball.second is None and ball.grounded
    assert (ball.rotational_stiffness, ball.rotational_viscosity, ball.axis) == (0.0, 0.0, None)
    assert spring.stiffness_matrix.shape == (6, 6)
    assert np.array_equal(spring.stiffness_matrix, np.array(SPRING))
    assert np.array_equal(spring.viscosity_matrix, np.zeros((6, 6)))
    assert ball.to_mapping()["between"] == ["a@0.15", "ground"]     # ground written second


def test_an_inertia_given_by_its_diagonal_and_an_offset():
    m = _base()
    m["bodies"] = [{"at": "a@0.1", "mass": 2.0, "inertia": [1.0, 2.0, 3.0],
                    "offset": [0.0, 0.01, 0.0]},
                   {"name": "other", "at": "b.end", "mass": 0.0,
                    "inertia": [[2.0, 0.5, 0.0], [0.5, 2.0, 0.0], [0.0, 0.0, 1.0]]}]
    a = Assembly.from_mapping(m)
    assert np.array_equal(a.bodies[0].inertia, np.diag([1.0, 2.0, 3.0]))
    assert a.bodies[0].name == "body0" and np.array_equal(a.bodies[0].offset, [0, 0.01, 0])
    assert a.bodies[1].inertia[0, 1] == 0.5


# -- points and nodes -----------------------------------------------------------------------
def test_a_node_at_every_named_point():
    m = _base()
    m["rods"]["a"]["rod"]["elements"] = 7          # 0.3/7: no uniform node at 0.1 or 0.25
    m["bodies"][0]["at"] = "a@0.1"
    m["loads"][1]["at"] = "a@0.25"
    a = Assembly.from_mapping(m)
    assert a.points_on("a") == (0.1, 0.25, 0.3)
    assert a.rods["a"].points == (0.1, 0.25, 0.3)
    s = a.rods["a"].node_arc_lengths()
    assert len(s) == 8
    for p in (0.1, 0.25):
        assert np.min(np.abs(s - p)) <= 1e-12, (p, s)
    # elements need not be equal
    assert np.ptp(np.diff(s)) > 1e-3
    # without the points the rod's grid is the uniform one, bit for bit
    m2 = _base()
    m2["rods"]["a"]["rod"]["elements"] = 7
    plain = Assembly.from_mapping(m2).rods["a"].node_arc_lengths()
    assert np.array_equal(plain, np.arange(8) * (0.3 / 7))


def test_points_are_parsed_and_placed():
    a = Assembly.from_mapping(_base())
    p = a.point("b@0.05")
    assert (p.rod, p.s, p.label, p.end) == ("b", 0.05, "b@0.05", None)
    assert a.point("a.start").end == "start" and a.point("b.end").s == 0.2
    assert np.allclose(a.reference_position(a.point("b@0.05")), [0.05, 0.0, 0.3])
    assert np.allclose(a.reference_position(a.point("a.end")),
                       a.reference_position(a.point("b.start")), atol=1e-15)
    assert np.allclose(a.reference_frame(a.point("a.end"))[:, 2], [0, 0, 1])


def test_a_single_rod_problem_has_no_points_and_does_not_write_them():
    p = load_problem("cantilever")
    assert p.points == () and "points" not in p.to_mapping()
    q = Problem.from_mapping(p.to_mapping(), points=(0.1,))
    assert 0.1 in q.breakpoints() and q != p
    assert np.min(np.abs(q.node_arc_lengths() - 0.1)) <= 1e-15
    assert q.with_overrides({"rod.elements": 7}).points == (0.1,)    # kept by overrides


def test_two_rods_welded_end_to_end_have_the_one_rods_nodes():
    two = load_problem("assembly_two_rod_cantilever")
    one = load_problem("cantilever")
    nodes = []
    for p in two.rods.values():
        d = discretize(p.rod.geometry, p.rod.elements, p.node_arc_lengths())
        nodes.append(d.nodes)
    joined = np.vstack([nodes[0], nodes[1][1:]])
    ref = discretize(one.rod.geometry, one.rod.elements, one.node_arc_lengths()).nodes
    assert np.allclose(joined, ref, rtol=0, atol=1e-15)
    for p in two.rods.values():     # the same section, material, tip load and settings
        assert (p.section, p.material, p.simulation) == (one.section, one.material,
                                                         one.simulation)
    assert two.rods["tip"].loads == one.loads and two.rods["root"].loads == ()


# -- loads ----------------------------------------------------------------------------------
def test_loads_are_routed_to_their_rods():
    m = _base()
    m["loads"] += [{"kind": "distributed", "vector": [1.0, 0.0, 0.0], "rods": ["b"]},
                   {"kind": "moment", "at": "a@0.2", "vector": [0.0, 0.0, 1e-4],
                    "frame": "follower"}]
    a = Assembly.from_mapping(m)
    ka = [ld.kind for ld in a.rods["a"].loads]
    kb = [ld.kind for ld in a.rods["b"].loads]
    assert ka == ["gravity", "moment"] and kb == ["gravity", "force", "distributed"]
    force = a.rods["b"].loads[1]
    assert (force.at, force.s, force.time.kind) == ("end", None, "release")
    moment = a.rods["a"].loads[1]
    assert (moment.at, moment.s, moment.frame) == (None, 0.2, "follower")
    assert a.loads[2].rods == ("b",) and a.loads[2].acts_on("b") and not a.loads[2].acts_on("a")
    assert a.loads[3].point == Point("a", 0.2, "a@0.2")
    # bodies feel every gravity load, limited to some rods or not
    m["loads"][0]["rods"] = ["a"]
    g = Assembly.from_mapping(m).gravity_loads()
    assert len(g) == 1 and g[0].vector == (0.0, 0.0, -9.81)
    assert [ld.kind for ld in Assembly.from_mapping(m).rods["b"].loads] == ["force",
                                                                           "distributed"]


def test_a_rod_problems_load_error_names_the_assemblys_load():
    m = _base()
    m["loads"][1]["vector"] = [0.0, 1e12, 0.0]      # beyond LOAD_STRAIN_MAX on rod b
    with pytest.raises(ParameterError) as exc:
        Assembly.from_mapping(m)
    assert exc.value.name == "loads.1.vector" and "[rod b]" in str(exc.value)


# -- round trip -----------------------------------------------------------------------------
@pytest.mark.parametrize("name", EXAMPLES)
def test_examples_load_and_round_trip(name, tmp_path):
    a = load_problem(name)
    assert isinstance(a, Assembly) and name in builtin_names()
    again = Assembly.from_mapping(a.to_mapping(), base=a.base)
    assert again == a and again.to_mapping() == a.to_mapping()
    # a results folder's problem.toml loads again to the same assembly
    f = write_problem(tmp_path / "problem.toml", a.to_mapping())
    assert f is not None
    assert load_problem(f) == a
    assert load_config(f) == (str(f), {})
    a.check_simulable()
    assert a.describe_material()


def test_shared_and_own_materials_of_composite_sections(tmp_path):
    m = _base()
    comp = {"kind": "composite", "regions": [
        {"material": "pvc", "shape": {"kind": "circle", "radius": 0.004}}]}
    pvc = {"youngs_modulus": 3e7, "poisson_ratio": 0.45, "density": 1350.0, "tau_S": 0.2}
    m["materials"] = {"pvc": pvc}
    for r in ("a", "b"):
        m["rods"][r]["section"] = copy.deepcopy(comp)
        del m["rods"][r]["material"]
    m["rods"]["b"]["materials"] = {"pvc": dict(pvc),                     # the same: fine
                                   "pe": {"youngs_modulus": 1e9, "poisson_ratio": 0.4,
                                          "density": 950.0}}
    m["rods"]["b"]["section"]["regions"].append(
        {"material": "pe", "shape": {"kind": "tube", "inner_radius": 0.004,
                                     "outer_radius": 0.005}})
    a = Assembly.from_mapping(m)
    assert set(a.materials) == {"pvc"}
    assert a.rods["a"].section.used_materials().keys() == {"pvc"}
    assert a.rods["b"].section.used_materials().keys() == {"pvc", "pe"}
    out = a.to_mapping()
    assert "pvc" in out["materials"] and set(out["rods"]["b"]["materials"]) == {"pe"}
    assert "materials" not in out["rods"]["a"]
    assert Assembly.from_mapping(out) == a
    # a shared material's key is swept once for every rod that names it
    b = a.with_overrides({"materials.pvc.tau_S": 0.1})
    assert b.materials["pvc"]["tau_S"] == 0.1
    assert dict(b.rods["a"].section.materials)["pvc"].to_mapping()["tau_S"] == 0.1
    # the same name with another content is refused
    m["rods"]["b"]["materials"]["pvc"]["tau_S"] = 0.3
    with pytest.raises(ParameterError, match=r"'rods\.b\.materials\.pvc'"):
        Assembly.from_mapping(m)


# -- overrides ------------------------------------------------------------------------------
def test_dotted_paths_through_rods_joints_bodies_and_loads():
    a = Assembly.from_mapping(_base())
    b = a.with_overrides({"rods.b.material.youngs_modulus": 2e6, "bodies.0.mass": 0.5,
                          "loads.1.vector": [0.0, 0.0, 0.02], "simulation.t_end": 2.0,
                          "rods.a.rod.elements": 8})
    assert b.rods["b"].material.youngs_modulus == 2e6
    assert b.rods["a"].material.youngs_modulus == 1e6
    assert b.bodies[0].mass == 0.5 and b.rods["a"].rod.elements == 8
    assert b.rods["b"].loads[1].vector == (0.0, 0.0, 0.02)
    assert b.simulation.t_end == 2.0 and all(p.simulation.t_end == 2.0
                                             for p in b.rods.values())
    # appending a joint, a body and a load at the index one past the end
    c = a.with_overrides({"joints.1": {"kind": "ball", "between": ["b@0.1", "ground"]},
                          "bodies.1": {"name": "n", "at": "a@0.1", "mass": 1.0},
                          "loads.2": {"kind": "force", "at": "a@0.2",
                                      "vector": [1e-3, 0.0, 0.0]}})
    assert len(c.joints) == 2 and c.joints[1].first.label == "b@0.1"
    assert c.bodies[1].name == "n" and c.points_on("a") == (0.1, 0.2, 0.3)
    assert c.points_on("b") == (0.0, 0.1, 0.2)
    assert a == Assembly.from_mapping(_base())            # the original is untouched
    with pytest.raises(ParameterError, match=r"'joints\.3'.*0 \.\.\. 1.*appends"):
        a.with_overrides({"joints.3": {"kind": "weld", "between": ["b@0.1", "ground"]}})


def test_aliases_broadcast_to_every_rod():
    a = Assembly.from_mapping(_base())
    b = a.with_overrides({"tau": 0.02, "E": 3e6, "n_elements": 10, "damping": "naive"})
    for p in b.rods.values():
        assert (p.material.tau_S, p.material.tau_B, p.material.youngs_modulus) == (
            0.02, 0.02, 3e6)
        assert p.rod.elements == 10 and p.damping == "naive"
    c = a.with_overrides({"t_end": 3.0, "rtol": 1e-5, "load_steps": 4})
    assert (c.simulation.t_end, c.simulation.rtol, c.statics.load_steps) == (3.0, 1e-5, 4)
    assert c.rods["a"].simulation.t_end == 3.0
    # the alias names the value when a rod refuses it
    with pytest.raises(ParameterError) as exc:
        a.with_overrides({"E": -1.0})
    assert exc.value.name == "E (rods.a.material.youngs_modulus)"
    with pytest.raises(ParameterError) as exc:
        a.with_overrides({"width": 0.02})                  # rod b has a circle section
    assert exc.value.name.startswith("width (rods.b.section.width)")


@pytest.mark.parametrize(("alias", "needle"), [("length", "rods.NAME.rod.length"),
                                               ("tip_force", "loads.K.vector")])
def test_aliases_without_meaning_for_an_assembly_are_refused(alias, needle):
    with pytest.raises(ParameterError) as exc:
        Assembly.from_mapping(_base()).with_overrides({alias: 0.5})
    assert exc.value.name == alias and needle in str(exc.value)


@pytest.mark.parametrize(("key", "needle"), [
    ("rods.c.material.tau", "a rod of the assembly: a, b"),
    ("rods.a.colour.x", "rods.a.KEY"),
    ("bogus", "a dotted path"),
    ("colour.x", "a dotted path"),
])
def test_override_paths_that_do_not_exist_are_refused(key, needle):
    with pytest.raises(ParameterError) as exc:
        Assembly.from_mapping(_base()).with_overrides({key: 1.0})
    assert key in str(exc.value) and needle in str(exc.value)


def test_load_problem_applies_overrides_to_a_built_in_assembly():
    a = load_problem("assembly_harness", {"n_elements": 8, "rods.left.material.tau": 0.0})
    assert all(p.rod.elements == 8 for p in a.rods.values())
    assert a.rods["left"].material.tau_S == 0.0 and a.rods["trunk"].material.tau_S == 0.01
    # 8 elements on the 0.4 m trunk: a node still at the splice trunk@0.2 and clip
    assert 0.2 in a.rods["trunk"].node_arc_lengths()
    s = a.rods["left"].node_arc_lengths()
    assert np.min(np.abs(s - 0.15)) <= 1e-15


# -- the key catalogue ----------------------------------------------------------------------
def _table_of(path: str, allowed) -> str | None:
    if path == "":
        return "" if "rods" in allowed else None
    parts = path.split(".")
    if len(parts) == 2 and parts[0] == "rods":
        return "rods.NAME"
    head = path.split("[")[0]
    if head == "loads" and path.count("[") == 1 and "." not in path:
        # the assembly's own check (at without s, or rods); the single-rod keys of a
        # load are in KEYS
        return "loads" if ("rods" in allowed or ("at" in allowed and "s" not in allowed)) \
            else None
    if head in ("joints", "bodies") and "." not in path:
        return head
    return "analysis" if path == "analysis" else None


def _variants():
    for kind in ("weld", "ball", "hinge", "spring"):
        yield "joints", kind
    for kind in ("gravity", "distributed", "force", "moment"):
        yield "loads", kind
    for table in ("", "rods.NAME", "bodies", "analysis"):
        yield table, None


def _variant(table: str, kind: str | None) -> tuple[dict, dict]:
    m = _base()
    if table == "joints":
        j = {"kind": kind, "between": ["a.end", "b.start"]}
        if kind == "hinge":
            j["axis"] = [0.0, 1.0, 0.0]
        if kind == "spring":
            j["stiffness_matrix"] = copy.deepcopy(SPRING)
        m["joints"] = [j]
        return m, j
    if table == "loads":
        ld = {"kind": kind, "vector": [0.0, 0.0, -1e-3]}
        if kind in ("force", "moment"):
            ld["at"] = "b@0.1"
        else:
            ld["rods"] = ["a"]
        m["loads"] = [ld]
        return m, ld
    if table == "rods.NAME":
        return m, m["rods"]["a"]
    if table == "bodies":
        return m, m["bodies"][0]
    if table == "analysis":
        return m, m["analysis"]
    return m, m


@pytest.mark.parametrize(("table", "kind"), list(_variants()))
def test_the_catalogue_lists_exactly_the_keys_the_assembly_parser_accepts(monkeypatch,
                                                                           table, kind):
    seen: dict[str, set[str]] = {}
    original = coerce.no_unknown_keys

    def record(path, mapping, allowed):
        t = _table_of(path, allowed)
        if t is not None:
            seen.setdefault(t, set()).update(allowed)
        return original(path, mapping, allowed)

    monkeypatch.setattr(coerce, "no_unknown_keys", record)
    m, _ = _variant(table, kind)
    Assembly.from_mapping(m)
    accepted = set(seen[table])
    catalogued = {k.name for k in keys.ASSEMBLY_KEYS if k.table == table
                  and (not k.kinds or kind is None or kind in k.kinds)}
    if table == "loads":     # kind, vector, time, frame: as a single rod's (KEYS)
        accepted -= {k.name for k in keys.KEYS if k.table == "loads"} - catalogued
    assert accepted == catalogued, (table, kind)
    assert {k.name for k in keys.ASSEMBLY_KEYS if k.table == ""} == set(ASSEMBLY_TOP_KEYS)


def _invalid_cases():
    for k in keys.ASSEMBLY_KEYS:
        if k.invalid is None:
            continue
        kind = k.kinds[0] if k.kinds else ("weld" if k.table == "joints" else "force"
                                           if k.table == "loads" else None)
        yield pytest.param(k, kind, id=f"{k.table or 'top'}.{k.name}[{kind}]")


@pytest.mark.parametrize(("key", "kind"), list(_invalid_cases()))
def test_each_documented_assembly_range_is_enforced_and_the_error_names_the_key(key, kind):
    m, t = _variant(key.table, kind)
    t[key.name] = copy.deepcopy(key.invalid)
    with pytest.raises(ParameterError) as exc:
        Assembly.from_mapping(m)
    assert key.name in exc.value.name, str(exc.value)


def test_the_reference_documents_the_assembly_keys_and_the_broadcast():
    md, text = keys.markdown(), keys.text()
    for k in keys.ASSEMBLY_KEYS:
        assert f"`{k.name}`" in md and k.unit and k.default and k.allowed and k.doc
    assert "`[[joints]]`" in md and "`[[bodies]]`" in md and "`[rods.NAME]`" in md
    for doc in (md, text):
        assert "broadcast" in doc and "every rod" in doc
        assert "rods.NAME.material.youngs_modulus" in doc or "rods.NAME.material." in doc


# -- bad input: one line naming the key -----------------------------------------------------
def _set(path: str, value: Any):
    def edit(m):
        node = m
        parts = path.split(".")
        for p in parts[:-1]:
            node = node[int(p)] if isinstance(node, list) else node[p]
        last = parts[-1]
        if isinstance(node, list):
            node[int(last)] = value
        else:
            node[last] = value
    return edit


def _drop(path: str):
    def edit(m):
        node = m
        parts = path.split(".")
        for p in parts[:-1]:
            node = node[int(p)] if isinstance(node, list) else node[p]
        del node[parts[-1]]
    return edit


def _joint(**j):
    def edit(m):
        m["joints"].append(j)
    return edit


def _body(**b):
    def edit(m):
        m["bodies"].append(b)
    return edit


def _many(*edits):
    def edit(m):
        for e in edits:
            e(m)
    return edit


NOT_PSD = [[1.0 if i == j else 0.0 for j in range(6)] for i in range(6)]
NOT_PSD[5][5] = -2.0
NOT_SYM = copy.deepcopy(SPRING)
NOT_SYM[0][3] = 10.0
NAN = float("nan")

BAD = [
    # unknown rod or point names; @S outside the rod
    ("unknown rod", _set("joints.0.between.0", "arm.end"), "joints[0].between[0]",
     "unknown rod 'arm': the rods are a (0.3 m), b (0.2 m)"),
    ("bad point form", _set("joints.0.between.1", "b.middle"), "joints[0].between[1]",
     "NAME@S"),
    ("@S beyond L", _set("joints.0.between.1", "b@0.25"), "joints[0].between[1]",
     "0 <= S <= 0.2 m"),
    ("@S negative", _set("bodies.0.at", "b@-0.1"), "bodies[0].at", "0 <= S <= 0.2 m"),
    ("@S not a number", _set("bodies.0.at", "b@x"), "bodies[0].at", "NAME@S"),
    ("@S nan", _set("bodies.0.at", "b@nan"), "bodies[0].at", "0 <= S"),
    ("load at unknown point", _set("loads.1.at", "c.end"), "loads[1].at", "unknown rod 'c'"),
    ("load at missing", _drop("loads.1.at"), "loads[1].at", "the point the load acts at"),
    ("load at a node index", _set("loads.1.at", 3), "loads[1].at", "NAME.start"),
    ("load s", _set("loads.1.s", 0.1), "loads[1].s", 'at = "NAME@S"'),
    ("load rods unknown", _set("loads.0.rods", ["a", "c"]), "loads[0].rods[1]", "a, b"),
    ("load rods empty", _set("loads.0.rods", []), "loads[0].rods", "non-empty"),
    ("load rods on a point load", _set("loads.1.rods", ["a"]), "loads[1].rods",
     "gravity and distributed"),
    ("maxima unknown rod", _set("analysis.maxima", "c.end.x"), "analysis.maxima",
     "unknown rod 'c'"),
    ("maxima component", _set("analysis.maxima", "b.end.w"), "analysis.maxima",
     "NAME.end.x"),
    ("maxima single-rod form", _set("analysis.maxima", "end.x"), "analysis.maxima",
     "names no rod in an assembly"),
    ("maxima @S outside", _set("analysis.maxima", "a@0.4.x"), "analysis.maxima",
     "0 <= S <= 0.3 m"),
    # points that do not coincide; redundant and self joints
    ("not coincident", _set("rods.b.rod.geometry.origin", [0.0, 0.0, 0.31]),
     "joints[0].between", "0.01 m apart"),
    ("interior points apart", _set("joints.0.between", ["a@0.1", "b.start"]),
     "joints[0].between", "0.2 m apart"),
    ("point with itself", _set("joints.0.between", ["a.end", "a@0.3"]),
     "joints[0].between[1]", "with itself"),
    ("same pair twice", _joint(kind="ball", between=["b.start", "a.end"]),
     "joints[1].between", "joints[0] (weld) holds the same two points"),
    ("same point to ground twice",
     _many(_joint(kind="weld", between=["b.end", "ground"]),
           _joint(kind="ball", between=["ground", "b@0.2"])),
     "joints[2].between", "the same point to ground"),
    ("ground with ground", _joint(kind="weld", between=["ground", "ground"]),
     "joints[1].between[1]", "a point"),
    ("between not two", _set("joints.0.between", ["a.end"]), "joints[0].between",
     "two points"),
    ("joint kind", _set("joints.0.kind", "glue"), "joints[0].kind", "'weld'"),
    ("joint kind missing", _drop("joints.0.kind"), "joints[0].kind", "'hinge'"),
    # hinge axes and kind-specific keys
    ("zero hinge axis", _joint(kind="hinge", between=["b.end", "ground"], axis=[0, 0, 0]),
     "joints[1].axis", "not all zero"),
    ("nan hinge axis", _joint(kind="hinge", between=["b.end", "ground"], axis=[NAN, 0, 1]),
     "joints[1].axis", "finite"),
    ("hinge without axis", _joint(kind="hinge", between=["b.end", "ground"]),
     "joints[1].axis", "the hinge's axis"),
    ("axis on a weld", _set("joints.0.axis", [0, 1, 0]), "joints[0].axis",
     "only for kind = 'hinge'"),
    ("axis on a ball", _joint(kind="ball", between=["b.end", "ground"], axis=[0, 1, 0]),
     "joints[1].axis", "only for kind = 'hinge'"),
    ("rotational stiffness on a weld", _set("joints.0.rotational_stiffness", 1.0),
     "joints[0].rotational_stiffness", "'ball' or 'hinge'"),
    ("rotational viscosity on a spring",
     _joint(kind="spring", between=["b.end", "ground"], stiffness_matrix=SPRING,
            rotational_viscosity=0.1),
     "joints[1].rotational_viscosity", "'ball' or 'hinge'"),
    ("negative rotational stiffness",
     _joint(kind="ball", between=["b.end", "ground"], rotational_stiffness=-1.0),
     "joints[1].rotational_stiffness", "[0, inf]"),
    ("stiffness matrix on a ball",
     _joint(kind="ball", between=["b.end", "ground"], stiffness_matrix=SPRING),
     "joints[1].stiffness_matrix", "only for kind = 'spring'"),
    # spring matrices
    ("spring without stiffness", _joint(kind="spring", between=["b.end", "ground"]),
     "joints[1].stiffness_matrix", "6x6"),
    ("spring not symmetric",
     _joint(kind="spring", between=["b.end", "ground"], stiffness_matrix=NOT_SYM),
     "joints[1].stiffness_matrix", "[0][3] = 10 and [3][0] = 0 differ"),
    ("spring not PSD",
     _joint(kind="spring", between=["b.end", "ground"], stiffness_matrix=NOT_PSD),
     "joints[1].stiffness_matrix", "most negative eigenvalue is -2"),
    ("viscosity not PSD",
     _joint(kind="spring", between=["b.end", "ground"], stiffness_matrix=SPRING,
            viscosity_matrix=NOT_PSD),
     "joints[1].viscosity_matrix", "most negative eigenvalue is -2"),
    ("spring 5x5",
     _joint(kind="spring", between=["b.end", "ground"],
            stiffness_matrix=[[1.0] * 5] * 5), "joints[1].stiffness_matrix", "6x6"),
    # bodies
    ("negative mass", _set("bodies.0.mass", -1.0), "bodies[0].mass", "[0, inf]"),
    ("nan mass", _set("bodies.0.mass", NAN), "bodies[0].mass", "finite"),
    ("mass missing", _drop("bodies.0.mass"), "bodies[0].mass", "kg"),
    ("inertia not symmetric", _set("bodies.0.inertia", [[1, 2, 0], [0, 1, 0], [0, 0, 1]]),
     "bodies[0].inertia", "symmetric"),
    ("inertia not PSD", _set("bodies.0.inertia", [[1, 2, 0], [2, 1, 0], [0, 0, 1]]),
     "bodies[0].inertia", "most negative eigenvalue is -1"),
    ("inertia negative diagonal", _set("bodies.0.inertia", [1.0, -1.0, 1.0]),
     "bodies[0].inertia", "most negative eigenvalue is -1"),
    ("inertia 2x2", _set("bodies.0.inertia", [[1, 0], [0, 1]]), "bodies[0].inertia",
     "3x3"),
    ("offset of two", _set("bodies.0.offset", [0.0, 0.1]), "bodies[0].offset",
     "3 finite numbers"),
    ("duplicate body names", _body(name="m", at="a.end", mass=1.0), "bodies[1].name",
     "bodies[0] has it"),
    ("body at a missing point", _set("bodies.0.at", "c@0.1"), "bodies[0].at",
     "unknown rod 'c'"),
    ("body without at", _drop("bodies.0.at"), "bodies[0].at", "welded"),
    # single-rod tables beside [rods]; unknown keys; zero rods; bad names
    *[(f"[{k}] beside [rods]", _set(k, {}), k, f"rods.NAME.{k}")
      for k in ("rod", "section", "material", "start", "end")],
    ("[[zones]] beside [rods]", _set("zones", []), "zones", "[[rods.a.zones]]"),
    ("unknown top key", _set("joint", []), "joint", "allowed here: name"),
    ("unknown rod key", _set("rods.a.colour", "red"), "rods.a.colour", "allowed here: rod"),
    ("loads in a rod", _set("rods.a.loads", []), "rods.a.loads", "at the top"),
    ("unknown joint key", _set("joints.0.strength", 1.0), "joints[0].strength",
     "allowed here: kind, between"),
    ("unknown body key", _set("bodies.0.colour", "red"), "bodies[0].colour",
     "allowed here: name, at"),
    ("unknown load key", _set("loads.0.at", "a.end"), "loads[0].at", "allowed here"),
    ("zero rods", _set("rods", {}), "rods", "at least one rod"),
    ("rods not a table", _set("rods", ["a"]), "rods", "a table"),
    ("rod named ground", lambda m: m["rods"].__setitem__("ground", m["rods"].pop("b")),
     "rods.ground", "not 'ground'"),
    ("rod name with a dot", lambda m: m["rods"].__setitem__("b.c", m["rods"].pop("b")),
     "rods.b.c", "letters, digits"),
    # errors inside a rod's table name the rod
    ("rod length", _set("rods.a.rod.length", -1.0), "rods.a.rod.length", "(0, inf]"),
    ("rod width", _set("rods.a.section.width", 0.0), "rods.a.section.width", ""),
    ("rod material", _set("rods.b.material.youngs_modulus", -5.0),
     "rods.b.material.youngs_modulus", ""),
    ("rod end kind", _set("rods.b.end", {"kind": "glued"}), "rods.b.end.kind", "'free'"),
    ("too few elements for the points",
     _many(_set("rods.b.rod.elements", 2), _body(name="n", at="b@0.05", mass=1.0),
           _body(name="o", at="b@0.15", mass=1.0)),
     "rods.b.rod.elements", ">= 3: a node goes at each of the 2 zone boundaries, point "
     "loads and named points"),
    ("rod zone", _set("rods.b.zones", [{"from": 0.0, "to": 0.5, "material": {"tau": 0.0}}]),
     "rods.b.zones[0].to", "0.2 m"),
    ("rod materials without composite", _set("rods.a.materials", {"x": MATERIAL}),
     "rods.a.materials", "composite"),
    ("shared materials without composite", _set("materials", {"x": MATERIAL}), "materials",
     "composite section in a rod"),
    ("simulation", _set("simulation.t_end", 0.0), "simulation.t_end", "(0, inf]"),
    ("joints not an array", _set("joints", {"kind": "weld"}), "joints", "[[joints]]"),
]


@pytest.mark.parametrize(("edit", "key", "needle"), [b[1:] for b in BAD],
                         ids=[b[0] for b in BAD])
def test_bad_assembly_input_is_one_line_naming_the_key(edit, key, needle):
    m = _base()
    edit(m)
    with pytest.raises(ParameterError) as exc:
        Assembly.from_mapping(m)
    msg = str(exc.value)
    assert "\n" not in msg
    assert exc.value.name == key, msg
    assert f"parameter {key!r}" in msg and needle in msg, msg


def test_a_bad_assembly_file_on_the_command_line_is_one_line(tmp_path):
    m = _base()
    m["joints"][0]["between"] = ["a.end", "b@0.05"]
    import tomli_w

    f = tmp_path / "bad.toml"
    f.write_text(tomli_w.dumps(m))
    r = subprocess.run([sys.executable, "-m", "kvrod.cli", "static", str(f), "--out",
                        str(tmp_path / "out")], capture_output=True, text=True, timeout=120,
                       cwd=tmp_path)
    assert r.returncode == 2, (r.stdout, r.stderr)
    err = r.stderr.strip().splitlines()
    assert len(err) == 1 and "Traceback" not in r.stderr, r.stderr
    assert "joints[0].between" in err[0] and "apart" in err[0] and "bad.toml" in err[0]
    assert not (tmp_path / "out").exists()


def test_the_examples_parse_as_plain_toml_with_their_documented_keys():
    for name in EXAMPLES:
        doc = tomllib.loads((EXAMPLES_DIR / f"{name}.toml").read_text())
        assert "rods" in doc and "rod" not in doc
        text = (EXAMPLES_DIR / f"{name}.toml").read_text()
        assert text.startswith("#") and "Reference" in text, name
        assert math.isfinite(load_problem(name).simulation.t_end)
