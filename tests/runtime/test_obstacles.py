"""Obstacles and the contact law in problem files (issue 32): ``[[obstacles]]``, ``[contact]``.

Parsing of each kind, the round trip (from_mapping(to_mapping()) and a results folder's
problem.toml; a problem without contact writes what it wrote before), overrides (paths
through obstacles and contact, appending an obstacle, an assembly's radius table), the
pose and rates of a moving obstacle against finite differences, the signed distances of
each kind against closed forms written here in the obstacle's own axes, the default
contact law (stiffness rule, restitution against a simulated impact), the contact radius
of each section, the starts-inside check, the key catalogue against the parser, the
examples, and one bad-input row per refusal (a single line naming the key path)."""

from __future__ import annotations

import copy
import math
import tomllib
from typing import Any

import numpy as np
import pytest

from runtime.errors import ParameterError
from runtime.io.results import write_problem
from runtime.problem import coerce, keys
from runtime.problem.assembly import Assembly
from runtime.problem.loads import Motion
from runtime.problem.obstacles import (
    PENETRATION_FRACTION,
    RESTITUTION,
    SLIP_VELOCITY,
    STIFFNESS_FACTOR,
    Contact,
    Obstacle,
    damping_ratio,
)
from runtime.problem.registry import EXAMPLES_DIR, builtin_names, load_config, load_problem
from runtime.problem.schema import TOP_KEYS, Problem
from runtime.problem.timefunctions import TimeFunction

MATERIAL = {"density": 7850.0, "youngs_modulus": 2.1e11, "poisson_ratio": 0.3, "tau": 1e-4}
EXAMPLES = ("contact_lifted_rod", "contact_incline", "contact_capstan", "contact_flat_drop",
            "contact_draped_cable", "contact_insertion", "contact_plectoneme",
            "contact_crossing")
PLANE = {"kind": "plane", "point": [0.0, 0.0, -0.005], "normal": [0.0, 0.0, 2.0],
         "friction": 0.3}
SPHERE = {"kind": "sphere", "centre": [0.1, 0.0, 0.05], "radius": 0.02}
CYLINDER = {"kind": "cylinder", "point": [0.0, 0.0, 0.1], "axis": [0.0, 1.0, 0.0],
            "radius": 0.05, "length": 0.2, "friction": 0.1}
PIPE = {"kind": "cylinder", "point": [-0.1, 0.0, 0.0], "axis": [1.0, 0.0, 0.0],
        "radius": 0.02, "inside": True}


def _base() -> dict[str, Any]:
    """A horizontal steel rod along x (0.3 m, 5 mm radius, 6 elements) resting on a floor,
    under a ball and a cylinder, inside a pipe."""
    return {"name": "contact", "rod": {"length": 0.3, "elements": 6,
                                       "geometry": {"kind": "straight",
                                                    "direction": [1.0, 0.0, 0.0]}},
            "section": {"kind": "circle", "radius": 0.005}, "material": dict(MATERIAL),
            "start": {"kind": "free"}, "end": {"kind": "free"},
            "loads": [{"kind": "gravity", "vector": [0.0, 0.0, -9.81]}],
            "simulation": {"t_end": 0.5, "initial": "reference"},
            "obstacles": [copy.deepcopy(o) for o in (PLANE, SPHERE, CYLINDER, PIPE)],
            "contact": {"restitution": 0.2}}


# -- parsing --------------------------------------------------------------------------------
def test_each_kind_is_read_with_its_keys_and_unit_directions():
    p = Problem.from_mapping(_base())
    plane, sphere, cyl, pipe = p.obstacles
    assert [o.index for o in p.obstacles] == [0, 1, 2, 3]
    assert plane.kind == "plane" and plane.normal == (0.0, 0.0, 1.0)     # normalised
    assert plane.axis is None and plane.radius is None and plane.friction == 0.3
    assert sphere.point == (0.1, 0.0, 0.05) and sphere.radius == 0.02
    np.testing.assert_array_equal(sphere.centre, [0.1, 0.0, 0.05])
    assert sphere.direction is None and sphere.friction == 0.0
    assert (cyl.axis, cyl.radius, cyl.length, cyl.inside) == ((0.0, 1.0, 0.0), 0.05, 0.2,
                                                              False)
    assert pipe.inside and pipe.length is None and pipe.motion is None
    assert p.contact == Contact(restitution=0.2)
    assert p.contact.radius is None and p.contact.self_contact is False
    assert p.contact.slip_velocity == SLIP_VELOCITY and p.has_contact


def test_obstacles_without_contact_table_take_the_defaults():
    m = _base()
    del m["contact"]
    p = Problem.from_mapping(m)
    assert p.contact is None and p.has_contact
    law = p.contact_law()
    assert law.restitution == RESTITUTION and law.slip_velocity == SLIP_VELOCITY
    assert law.self_contact is False and law.friction == 0.0


def test_a_problem_without_contact_has_no_law():
    p = load_problem("cantilever")
    assert p.obstacles == () and p.contact is None and not p.has_contact
    assert p.contact_law() is None


def test_self_contact_alone_is_contact():
    m = _base()
    del m["obstacles"]
    m["contact"] = {"self": True}
    p = Problem.from_mapping(m)
    assert p.has_contact and p.obstacles == () and p.contact_law().self_contact
    assert p.with_overrides({"contact.friction": 0.4}).contact_law().friction == 0.4


def test_an_obstacle_built_in_python_is_checked_and_renumbered():
    o = Obstacle(7, "sphere", (0.0, 0.0, 1.0), radius=0.1)
    p = Problem.from_mapping(_base())
    q = Problem(rod=p.rod, section=p.section, material=p.material, start=p.start,
                end=p.end, obstacles=(o,))
    assert q.obstacles[0].index == 0
    with pytest.raises(ParameterError) as exc:
        Obstacle(2, "sphere", (0.0, 0.0, 1.0), radius=-0.1)
    assert exc.value.name == "obstacles[2].radius"


# -- round trip -----------------------------------------------------------------------------
def test_round_trip_and_results_folder(tmp_path):
    m = _base()
    m["obstacles"][1]["motion"] = {"translation": [0.0, 0.0, 0.01],
                                   "translation_time": {"kind": "harmonic",
                                                        "frequency": 2.0},
                                   "rotation_axis": [0.0, 0.0, 1.0],
                                   "rotation_angle": 30.0,
                                   "rotation_time": {"kind": "smooth_ramp",
                                                     "duration": 0.2}}
    m["contact"] = {"radius": 0.005, "self": True, "friction": 0.2, "penetration": 1e-4,
                    "slip_velocity": 1e-3, "restitution": 0.5, "stiffness": 1e6}
    p = Problem.from_mapping(m)
    out = p.to_mapping()
    assert out["obstacles"][0] == {"kind": "plane", "point": [0.0, 0.0, -0.005],
                                   "normal": [0.0, 0.0, 1.0], "friction": 0.3}
    assert "length" not in out["obstacles"][3] and out["obstacles"][3]["inside"] is True
    assert out["contact"] == {"radius": 0.005, "self": True, "friction": 0.2,
                              "penetration": 1e-4,
                              "slip_velocity": 1e-3, "restitution": 0.5, "stiffness": 1e6}
    again = Problem.from_mapping(out)
    assert again == p and again.to_mapping() == out
    f = write_problem(tmp_path / "problem.toml", out)
    assert load_problem(f) == p and load_config(f) == (str(f), {})


def test_a_problem_without_contact_writes_no_new_keys():
    for name in builtin_names():
        if name.startswith("contact_"):
            continue
        p = load_problem(name)
        m = p.to_mapping()
        assert "obstacles" not in m and "contact" not in m, name
        if isinstance(p, Problem):
            assert set(m) <= set(TOP_KEYS) - {"obstacles", "contact"}, name


@pytest.mark.parametrize("name", EXAMPLES)
def test_examples_load_round_trip_and_say_what_they_show(name, tmp_path):
    p = load_problem(name)
    assert name in builtin_names()
    kind = type(p)
    again = kind.from_mapping(p.to_mapping(), base=p.base)
    assert again == p and again.to_mapping() == p.to_mapping()
    f = write_problem(tmp_path / "problem.toml", p.to_mapping())
    assert load_problem(f) == p
    text = (EXAMPLES_DIR / f"{name}.toml").read_text()
    assert text.startswith("#") and "Reference" in text and "kvrod " in text
    doc = tomllib.loads(text)
    assert "obstacles" in doc or doc.get("contact", {}).get("self") is True
    rods = p.rods.values() if isinstance(p, Assembly) else (p,)
    for r in rods:
        assert r.contact_law() is not None


# -- overrides ------------------------------------------------------------------------------
def test_overrides_reach_obstacles_and_contact():
    p = Problem.from_mapping(_base())
    q = p.with_overrides({"obstacles.0.friction": 0.7, "contact.restitution": 0.9,
                          "obstacles.4": {"kind": "sphere", "centre": [0.2, 0.1, 0.0],
                                          "radius": 0.01}})
    assert q.obstacles[0].friction == 0.7 and q.contact.restitution == 0.9
    assert len(q.obstacles) == 5 and q.obstacles[4].kind == "sphere"
    assert q.obstacles[1:4] == p.obstacles[1:4]
    with pytest.raises(ParameterError) as exc:    # [contact] left alone changes nothing
        q.with_overrides({"obstacles": []})
    assert exc.value.name == "contact"
    assert q.with_overrides({"obstacles": [], "contact.self": True}).obstacles == ()
    assert p.obstacles == Problem.from_mapping(_base()).obstacles   # p untouched


def test_set_appends_the_first_obstacle_to_a_problem_without_any():
    from kvrod.problem_args import parse_set

    key, value = parse_set('obstacles.0={kind="plane", point=[0,0,-1], normal=[0,0,1], '
                           'friction=0.3}')
    p = load_problem("cantilever", {"section": {"kind": "circle", "radius": 0.005},
                                    key: value, "contact.self": False})
    assert len(p.obstacles) == 1 and p.obstacles[0].friction == 0.3
    assert p.contact == Contact()


def test_assembly_obstacles_and_contact_stay_at_the_top_and_reach_every_rod(tmp_path):
    from tests.runtime.test_assembly_problem import _base as assembly

    m = assembly()
    m["obstacles"] = [{"kind": "plane", "point": [0.0, 0.0, -0.05], "normal": [0, 0, 1],
                       "friction": 0.4}]
    m["contact"] = {"radius": {"a": 0.008}, "self": True}
    a = Assembly.from_mapping(m)
    assert a.obstacles[0].friction == 0.4 and a.contact.rod_radii == (("a", 0.008),)
    assert a.rods["a"].obstacles == a.obstacles == a.rods["b"].obstacles
    assert a.rods["a"].contact.radius == 0.008 and a.rods["b"].contact.radius is None
    np.testing.assert_array_equal(a.rods["a"].contact_radii(), 0.008)   # rectangle: given
    np.testing.assert_array_equal(a.rods["b"].contact_radii(), 0.005)   # circle: its own
    out = a.to_mapping()
    assert "obstacles" not in out["rods"]["a"] and "contact" not in out["rods"]["b"]
    assert out["contact"]["radius"] == {"a": 0.008}
    again = Assembly.from_mapping(out)
    assert again == a and again.to_mapping() == out
    f = write_problem(tmp_path / "problem.toml", out)
    assert load_problem(f) == a
    b = a.with_overrides({"obstacles.0.friction": 0.1, "contact.radius.b": 0.006,
                          "contact.restitution": 0.5})
    assert b.obstacles[0].friction == 0.1 and b.rods["b"].contact.radius == 0.006
    assert b.rods["a"].contact.restitution == 0.5
    c = Assembly.from_mapping(assembly())
    assert c.obstacles == () and c.contact is None
    assert "obstacles" not in c.to_mapping() and "contact" not in c.to_mapping()


# -- pose and rates -------------------------------------------------------------------------
def _moving() -> Obstacle:
    motion = Motion(translation=(0.02, -0.01, 0.03),
                    translation_time=TimeFunction(kind="harmonic", frequency=1.5, phase=0.3,
                                                  offset=0.2),
                    rotation_axis=(0.0, 0.6, 0.8), rotation_angle=50.0,
                    rotation_time=TimeFunction(kind="smooth_ramp", start=0.1, duration=0.5))
    return Obstacle(0, "cylinder", (0.1, 0.2, -0.3), axis=(1.0, 0.0, 0.0), radius=0.05,
                    motion=motion)


def _rotation(q: np.ndarray) -> np.ndarray:
    """R of a unit quaternion (scalar first), written out here (Rodrigues)."""
    w, v = q[0], q[1:]
    vx = np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])
    return np.eye(3) + 2 * w * vx + 2 * vx @ vx


@pytest.mark.parametrize("t", [0.0, 0.05, 0.3, 0.37, 0.8])
def test_pose_rates_against_finite_differences(t):
    o = _moving()
    c, q, v, om = o.pose(t)
    assert abs(np.linalg.norm(q) - 1.0) < 1e-14
    # the point moves by translation f(t); the rotation is angle g(t) about the axis
    mo = o.motion
    np.testing.assert_allclose(c, np.array(o.point) + np.array(mo.translation)
                               * mo.translation_time.value_at(t), rtol=0, atol=1e-15)
    theta = math.radians(50.0) * mo.rotation_time.value_at(t)
    np.testing.assert_allclose(q, [math.cos(theta / 2), *(math.sin(theta / 2)
                                                          * np.array([0.0, 0.6, 0.8]))],
                               atol=1e-15)
    eps = 1e-6
    cp, qp, _, _ = o.pose(t + eps)
    cm, qm, _, _ = o.pose(t - eps)
    np.testing.assert_allclose(v, (cp - cm) / (2 * eps), rtol=1e-7, atol=1e-10)
    Rdot = (_rotation(qp) - _rotation(qm)) / (2 * eps)
    W = Rdot @ _rotation(q).T                       # the spatial angular velocity, skew
    np.testing.assert_allclose(om, [W[2, 1], W[0, 2], W[1, 0]], rtol=1e-6, atol=1e-9)
    # a material point X of the obstacle: x = c + R (X - point), v = c' + om x (x - c)
    X = np.array([0.3, -0.1, 0.25])

    def place(s: float) -> np.ndarray:
        cc, qq, _, _ = o.pose(s)
        return cc + _rotation(qq) @ (X - np.array(o.point))

    x = place(t)
    np.testing.assert_allclose(v + np.cross(om, x - c), (place(t + eps) - place(t - eps))
                               / (2 * eps), rtol=1e-6, atol=1e-9)
    # distances are carried with the body
    assert o.signed_distance(x, t=t) == pytest.approx(o.signed_distance(X), abs=1e-14)


def test_a_fixed_obstacle_is_at_rest_and_has_no_breakpoints():
    o = Problem.from_mapping(_base()).obstacles[0]
    c, q, v, om = o.pose(0.3)
    np.testing.assert_array_equal(c, o.point)
    np.testing.assert_array_equal(q, [1.0, 0.0, 0.0, 0.0])
    assert not np.any(v) and not np.any(om)
    assert not o.moves and not o.time_dependent and o.breakpoints(0, 10) == []
    assert o.time_scale(0.0) == math.inf and o.steady_interval(1.0) == (-math.inf, math.inf)


def test_breakpoints_time_scale_and_drive_inputs():
    o = _moving()
    assert o.moves and o.time_dependent
    # the smooth ramp's ends (acceleration jumps): restarts, as for an end's motion
    assert o.breakpoints(0.0, 1.0) == [(0.1, True), (0.6, True)]
    assert o.breakpoints(0.2, 0.5) == []
    # the shorter of the ramp's duration and the harmonic's period
    assert o.time_scale(0.3) == pytest.approx(0.5)
    assert o.time_scale(0.7) == pytest.approx(1 / 1.5)
    assert o.inputs() == [(o.motion.translation_time, True), (o.motion.rotation_time, True)]
    assert o.steady_interval(0.3) == (0.3, 0.3)
    still = Obstacle(0, "sphere", (0, 0, 0), radius=1.0, motion=Motion(
        rotation_angle=0.0, rotation_time=TimeFunction(kind="ramp", duration=1.0)))
    assert not still.moves and still.inputs() == [] and still.breakpoints(0, 2) == []
    ramp = Obstacle(0, "plane", (0, 0, 0), normal=(0, 0, 1), motion=Motion(
        translation=(0.0, 0.0, 0.1),
        translation_time=TimeFunction(kind="ramp", start=0.5, duration=1.0)))
    assert ramp.breakpoints(0, 2) == [(0.5, True), (1.5, True)]
    assert ramp.steady_interval(0.2) == (-math.inf, 0.5)
    assert ramp.steady_interval(1.7) == (1.5, math.inf)
    np.testing.assert_allclose(ramp.pose(1.0).velocity, [0.0, 0.0, 0.1])
    np.testing.assert_allclose(ramp.pose(1.5, left=True).velocity, [0.0, 0.0, 0.1])
    np.testing.assert_allclose(ramp.pose(1.5).velocity, [0.0, 0.0, 0.0])


# -- signed distances -----------------------------------------------------------------------
def _frame(axis) -> np.ndarray:
    """An orthonormal basis (rows e1, e2, a) with a the unit axis."""
    a = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    e1 = np.cross(a, [0.3, 0.5, 0.7])
    e1 /= np.linalg.norm(e1)
    return np.array([e1, np.cross(a, e1), a])


RNG = np.random.default_rng(32)
POINTS = RNG.uniform(-0.4, 0.4, (400, 3))


def test_plane_distance():
    o = Obstacle(0, "plane", (0.1, -0.2, 0.05), normal=(1.0, 2.0, -2.0))
    n = np.array([1.0, 2.0, -2.0]) / 3.0
    d = o.signed_distance(POINTS)
    np.testing.assert_allclose(d, (POINTS - [0.1, -0.2, 0.05]) @ n, atol=1e-15)
    # the foot of each point is on the plane, at |d| from it
    foot = POINTS - d[:, None] * n
    np.testing.assert_allclose(o.signed_distance(foot), 0.0, atol=1e-15)
    assert o.signed_distance([0.1, -0.2, 0.05]) == 0.0


def test_sphere_distance():
    o = Obstacle(0, "sphere", (0.05, 0.0, -0.1), radius=0.12)
    d = o.signed_distance(POINTS)
    for x, dx in zip(POINTS[:20], d[:20], strict=True):
        r = math.sqrt(sum((a - b) ** 2 for a, b in zip(x, (0.05, 0.0, -0.1), strict=True)))
        assert dx == pytest.approx(r - 0.12, abs=1e-15)
    assert o.signed_distance([0.05, 0.0, -0.1]) == pytest.approx(-0.12)
    assert d.shape == (400,) and o.signed_distance(POINTS.reshape(20, 20, 3)).shape == (20, 20)


@pytest.mark.parametrize("inside", [False, True])
def test_infinite_cylinder_and_pipe_distance(inside):
    axis = (0.2, -0.5, 1.0)
    o = Obstacle(0, "cylinder", (0.0, 0.1, 0.0), axis=axis, radius=0.15, inside=inside)
    local = (POINTS - [0.0, 0.1, 0.0]) @ _frame(axis).T         # (e1, e2, axial)
    rho = np.hypot(local[:, 0], local[:, 1])
    expected = 0.15 - rho if inside else rho - 0.15
    np.testing.assert_allclose(o.signed_distance(POINTS), expected, atol=1e-14)


def test_finite_cylinder_distance_with_caps_and_rims():
    axis = (0.0, 0.0, 1.0)
    o = Obstacle(0, "cylinder", (0.0, 0.0, -0.1), axis=axis, radius=0.1, length=0.2)
    cases = {(0.3, 0.0, 0.0): 0.2,                     # beside: radial
             (0.0, 0.0, 0.3): 0.2,                     # above the top cap (z = 0.1)
             (0.05, 0.0, -0.25): 0.15,                 # below the bottom cap
             (0.4, 0.0, 0.5): 0.5,                     # off the rim: 0.3 out, 0.4 up
             (0.0, 0.0, 0.0): -0.1,                    # the centre: nearest the wall
             (0.0, 0.0, 0.08): -0.02,                  # near the top cap, inside
             (0.09, 0.0, 0.0): -0.01}                  # near the wall, inside
    for x, d in cases.items():
        assert o.signed_distance(x) == pytest.approx(d, abs=1e-15), x
    # against the distance to a dense sampling of its surface (outside points)
    u = np.linspace(0.0, 2 * np.pi, 361)[:-1]
    z = np.linspace(-0.1, 0.1, 101)
    side = np.stack(np.broadcast_arrays(0.1 * np.cos(u)[:, None], 0.1 * np.sin(u)[:, None],
                                        z[None, :]), -1).reshape(-1, 3)
    rr = np.linspace(0.0, 0.1, 51)
    disc = np.stack(np.broadcast_arrays(rr[:, None] * np.cos(u)[None, :],
                                        rr[:, None] * np.sin(u)[None, :], 0.0), -1
                    ).reshape(-1, 3)
    surface = np.concatenate([side, disc + [0, 0, 0.1], disc - [0, 0, 0.1]])
    pts = POINTS[o.signed_distance(POINTS) > 0.0][:40]
    dmin = np.array([np.min(np.linalg.norm(surface - x, axis=-1)) for x in pts])
    d = o.signed_distance(pts)
    assert np.all(d <= dmin + 1e-15) and np.all(dmin - d < 2e-3)


def test_finite_pipe_acts_between_its_ends_only():
    o = Obstacle(0, "cylinder", (0.0, 0.0, 0.0), axis=(1.0, 0.0, 0.0), radius=0.05,
                 length=0.4, inside=True)
    d = o.signed_distance([[0.1, 0.0, 0.01], [0.1, 0.06, 0.0], [-0.01, 0.0, 0.0],
                           [0.41, 0.07, 0.0], [0.0, 0.0, 0.0], [0.4, 0.05, 0.0]])
    np.testing.assert_allclose(d[[0, 1, 4, 5]], [0.04, -0.01, 0.05, 0.0], atol=1e-15)
    assert d[2] == math.inf and d[3] == math.inf


# -- the contact law and radii --------------------------------------------------------------
def test_the_default_law_of_a_round_rod():
    p = Problem.from_mapping(_base())
    law = p.contact_law()
    r, E, h = 0.005, 2.1e11, 0.3 / 6
    EI = E * math.pi * r**4 / 4
    rhoA = 7850.0 * math.pi * r**2
    assert law.stiffness == pytest.approx(STIFFNESS_FACTOR * EI / h**4, rel=1e-12)
    # the Winkler length (4 EI / k)^(1/4) of the default is half an element
    assert (4 * EI / law.stiffness) ** 0.25 == pytest.approx(h / 2, rel=1e-12)
    np.testing.assert_array_equal(law.radius, np.full(6, r))
    # delta: the penetration under the rod's own weight (its gravity, standard gravity
    # without one), capped at PENETRATION_FRACTION of r (a soft rod)
    g = p.gravity_magnitude() or 9.80665
    q = float(np.min(p.segment_matrices()["rhoA"])) * g
    assert law.penetration == pytest.approx(q / law.stiffness, rel=1e-12)
    assert law.penetration < PENETRATION_FRACTION * r
    soft = _base()
    soft["material"]["youngs_modulus"] = 1e3
    soft_law = Problem.from_mapping(soft).contact_law()
    assert soft_law.penetration == pytest.approx(PENETRATION_FRACTION * r, rel=1e-12)
    zeta = damping_ratio(0.2)
    np.testing.assert_allclose(law.damping, 2 * zeta * math.sqrt(law.stiffness * rhoA),
                               rtol=1e-12)
    assert not law.radius.flags.writeable


def test_the_law_takes_the_softer_bending_stiffness_and_the_shortest_element():
    m = _base()
    m["section"] = {"kind": "rectangle", "width": 0.02, "height": 0.01}
    m["contact"]["radius"] = 0.011
    m["zones"] = [{"from": 0.0, "to": 0.05, "section": {"width": 0.01}}]
    m["loads"].append({"kind": "force", "s": 0.12, "vector": [0.0, 0.0, -1.0]})
    m["obstacles"] = [{"kind": "plane", "point": [0.0, 0.0, -0.011], "normal": [0, 0, 1]}]
    p = Problem.from_mapping(m)
    h = float(np.min(np.diff(p.node_arc_lengths())))
    assert h < 0.3 / 6
    E = 2.1e11
    EI_soft = E * 0.01 * 0.01**3 / 12                 # the zone's 1 cm square, either axis
    assert p.contact_law().stiffness == pytest.approx(STIFFNESS_FACTOR * EI_soft / h**4,
                                                      rel=1e-9)
    q = p.with_overrides({"contact.stiffness": 123.0, "contact.penetration": 1e-3})
    assert q.contact_law().stiffness == 123.0 and q.contact_law().penetration == 1e-3


def _lifted_on_winkler(F: float, q: float, EI: float, k: float, L: float, n: int) -> float:
    """End height (m, above the undeformed table) of a heavy Euler-Bernoulli beam lying on
    a tensionless Winkler foundation of modulus k (N/m^2), lifted at x = 0 by F: Hermite
    beam elements, the foundation lumped to the nodes where they sink (active set)."""
    import scipy.sparse as sp
    import scipy.sparse.linalg as spl

    h, N = L / n, n + 1
    Ke = EI / h**3 * np.array([[12, 6 * h, -12, 6 * h], [6 * h, 4 * h * h, -6 * h, 2 * h * h],
                               [-12, -6 * h, 12, -6 * h], [6 * h, 2 * h * h, -6 * h, 4 * h * h]])
    fe = -q * h * np.array([0.5, h / 12, 0.5, -h / 12])
    dofs = 2 * np.arange(n)[:, None] + np.arange(4)[None, :]
    K = sp.csr_matrix((np.broadcast_to(Ke, (n, 4, 4)).ravel(),
                       (np.repeat(dofs, 4, axis=1).ravel(), np.tile(dofs, (1, 4)).ravel())),
                      shape=(2 * N, 2 * N))
    f = np.zeros(2 * N)
    np.add.at(f, dofs.ravel(), np.tile(fe, n))
    f[0] += F
    weights = np.full(N, h)
    weights[[0, -1]] = h / 2
    active = np.arange(N) > 0
    for _ in range(100):
        springs = np.zeros(2 * N)
        springs[0::2] = np.where(active, k * weights, 0.0)
        w = spl.spsolve((K + sp.diags(springs)).tocsc(), f)[0::2]
        if np.array_equal(w < 0, active):
            return float(w[0])
        active = w < 0
    raise AssertionError("the contact set did not settle")


@pytest.mark.parametrize("ell", [0.1, 0.05])
def test_the_winkler_correction_of_a_lifted_rod(ell):
    """The reason for the default stiffness: a heavy rod lifted at one end off a contact of
    Winkler length l (k = 4 EI / l^4) leaves it at a = 2F/q - l, and its end rises by
    (2 x^3 - 3 x^4) of the rigid table's height, x = l / (2F/q) (derived in
    docs/design.md), here against a beam finite-element model on the foundation; with the
    default l = h/2 the change is below 2e-3 once the lifted length spans 5 elements."""
    F, q, EI, L = 0.0726, 0.2419293, 0.1649336, 2.0     # examples/contact_lifted_rod.toml
    a0 = 2 * F / q
    rigid = q * a0**4 / (24 * EI)
    x = ell / a0
    fe = _lifted_on_winkler(F, q, EI, 4 * EI / ell**4, L, 2000)
    assert (fe - rigid) / rigid == pytest.approx(2 * x**3 - 3 * x**4, abs=2e-6)
    assert 2 * 0.1**3 - 3 * 0.1**4 < 2e-3               # l = h/2, a = 5 h: x = 1/10


def test_restitution_is_the_rebound_of_a_mass_on_the_damped_spring():
    """Integrate m x'' = -k x - c x' (in contact, x < 0) from x' = -v0 until the mass
    leaves (x = 0) with c = 2 zeta sqrt(k m): the rebound speed over v0 is e."""
    from scipy.integrate import solve_ivp

    for e in (0.05, 0.1, 0.5, 0.9, 1.0):
        zeta = damping_ratio(e)
        k, m, v0 = 4.0e6, 0.3, 1.2
        c = 2 * zeta * math.sqrt(k * m)

        def leave(t, y):
            return y[0]
        leave.terminal, leave.direction = True, 1

        def rhs(t, y, k=k, c=c, m=m):
            return [y[1], (-k * y[0] - c * y[1]) / m]

        sol = solve_ivp(rhs, (0, 1.0), [0.0, -v0], events=leave, rtol=1e-11, atol=1e-14,
                        max_step=1e-5, first_step=1e-9)
        # the event at t = 0 (x = 0, leaving downward) is excluded by direction = +1
        rebound = sol.y_events[0][-1][1]
        assert rebound / v0 == pytest.approx(e, rel=1e-6), e


def test_contact_radius_of_each_section():
    m = _base()
    m["obstacles"] = [{"kind": "plane", "point": [0.0, 0.0, -0.01], "normal": [0, 0, 1]}]
    tube = Problem.from_mapping({**m, "section": {"kind": "tube", "outer_radius": 0.006,
                                                  "inner_radius": 0.004}})
    np.testing.assert_array_equal(tube.contact_radii(), 0.006)
    taper = Problem.from_mapping({**m, "section": {"kind": "circle", "radius": 0.005,
                                                   "radius_end": 0.002}})
    x = (np.arange(6) + 0.5) / 6
    np.testing.assert_allclose(taper.contact_radii(), 0.005 + (0.002 - 0.005) * x,
                               rtol=1e-15)
    zoned = Problem.from_mapping({**m, "zones": [{"from": 0.1, "to": 0.2, "section": {
        "kind": "tube", "outer_radius": 0.007, "inner_radius": 0.001}}]})
    np.testing.assert_array_equal(zoned.contact_radii(), [0.005, 0.005, 0.007, 0.007,
                                                          0.005, 0.005])
    given = Problem.from_mapping({**m, "contact": {"radius": 0.004}})
    np.testing.assert_array_equal(given.contact_radii(), 0.004)
    regions = [{"material": "steel", "shape": {"kind": "circle", "radius": 0.002,
                                               "centre": [0.001, 0.0]}},
               {"material": "pvc", "shape": {"kind": "tube", "inner_radius": 0.002,
                                             "outer_radius": 0.0045,
                                             "centre": [0.001, 0.0]}}]
    mats = {"steel": {"youngs_modulus": 2.1e11, "poisson_ratio": 0.3, "density": 7850.0},
            "pvc": {"youngs_modulus": 3e9, "poisson_ratio": 0.4, "density": 1400.0}}
    cable = dict(m)
    del cable["material"]
    cable.update(section={"kind": "composite", "regions": regions}, materials=mats)
    cable["obstacles"] = [{"kind": "plane", "point": [0.0, 0.0, -0.01],
                           "normal": [0.0, 0.0, 1.0]}]
    np.testing.assert_array_equal(Problem.from_mapping(cable).contact_radii(), 0.0045)


def test_the_rod_may_start_touching_but_not_inside():
    m = _base()
    m["obstacles"] = [{"kind": "plane", "point": [0.0, 0.0, -0.005], "normal": [0, 0, 1]}]
    assert Problem.from_mapping(m).obstacles       # resting on it: gap 0
    m["contact"] = {"penetration": PENETRATION_FRACTION * 0.005}
    delta = PENETRATION_FRACTION * 0.005
    m["obstacles"][0]["point"] = [0.0, 0.0, -0.005 + 0.9 * delta]
    assert Problem.from_mapping(m).obstacles       # within the tolerance
    m["obstacles"][0]["point"] = [0.0, 0.0, -0.005 + 1.5 * delta]
    with pytest.raises(ParameterError) as exc:
        Problem.from_mapping(m)
    assert exc.value.name == "obstacles[0]" and "1.5e-05 m inside" in str(exc.value)
    # a tilted plane: the deepest node is named by its arc length
    m["obstacles"][0] = {"kind": "plane", "point": [0.3, 0.0, 0.0],
                         "normal": [-0.01, 0.0, 1.0]}
    with pytest.raises(ParameterError) as exc:
        Problem.from_mapping(m)
    assert "node at s = 0.3 m is 0.005 m inside" in str(exc.value)


def test_the_starts_inside_check_takes_the_pose_at_t0():
    m = _base()
    # a ball that is at the rod's middle at t = 0 (its reference place is clear of it)
    m["obstacles"] = [{"kind": "sphere", "centre": [0.15, 0.0, 0.2], "radius": 0.02,
                       "motion": {"translation": [0.0, 0.0, -0.2],
                                  "translation_time": {"kind": "harmonic",
                                                       "frequency": 1.0, "offset": 1.0,
                                                       "amplitude": 0.0}}}]
    with pytest.raises(ParameterError) as exc:
        Problem.from_mapping(m)
    assert "node at s = 0.15 m is 0.025 m inside" in str(exc.value)
    m["obstacles"][0]["motion"]["translation_time"]["offset"] = 0.0
    assert Problem.from_mapping(m).obstacles


def test_an_assemblys_rod_starting_inside_is_named():
    from tests.runtime.test_assembly_problem import _base as assembly

    m = assembly()
    m["obstacles"] = [{"kind": "sphere", "centre": [0.1, 0.0, 0.3], "radius": 0.01}]
    m["contact"] = {"radius": {"a": 0.007}}
    with pytest.raises(ParameterError) as exc:
        Assembly.from_mapping(m)
    msg = str(exc.value)
    assert exc.value.name == "obstacles[0]" and "[rod b]" in msg and "s = 0.1 m" in msg


# -- the key catalogue ----------------------------------------------------------------------
KIND = {"plane": PLANE, "sphere": SPHERE, "cylinder": CYLINDER}
MOTION = {"translation": [0.0, 0.0, 0.001], "translation_time": {"kind": "smooth_ramp",
                                                                  "duration": 1.0},
          "rotation_axis": [0.0, 0.0, 1.0], "rotation_angle": 10.0,
          "rotation_time": {"kind": "harmonic", "frequency": 1.0}}


def _variant(table: str, kind: str | None) -> tuple[dict, dict]:
    m = _base()
    if table == "obstacles":
        o = copy.deepcopy(KIND[kind or "plane"])
        m["obstacles"] = [o]
        return m, o
    if table == "obstacles.motion":
        o = copy.deepcopy(SPHERE)
        o["motion"] = copy.deepcopy(MOTION)
        m["obstacles"] = [o]
        return m, o["motion"]
    m["contact"] = {"self": True}
    return m, m["contact"]


def _table_of(path: str) -> str | None:
    if path.startswith("obstacles[") and path.endswith("]"):
        return "obstacles"
    if path.startswith("obstacles[") and path.endswith("].motion"):
        return "obstacles.motion"
    return "contact" if path == "contact" else None


@pytest.mark.parametrize(("table", "kind"), [("obstacles", "plane"), ("obstacles", "sphere"),
                                             ("obstacles", "cylinder"),
                                             ("obstacles.motion", None), ("contact", None)])
def test_the_catalogue_lists_exactly_the_keys_the_parser_accepts(monkeypatch, table, kind):
    seen: dict[str, set[str]] = {}
    original = coerce.no_unknown_keys

    def record(path, mapping, allowed):
        t = _table_of(path)
        if t is not None:
            seen.setdefault(t, set()).update(allowed)
        return original(path, mapping, allowed)

    monkeypatch.setattr(coerce, "no_unknown_keys", record)
    m, _ = _variant(table, kind)
    Problem.from_mapping(m)
    assert seen[table] == {k.name for k in keys.CONTACT_KEYS if k.table == table
                           and (not k.kinds or kind is None or kind in k.kinds)}, table
    assert {"obstacles", "contact"} <= set(TOP_KEYS)


def _invalid_cases():
    for k in keys.CONTACT_KEYS:
        kind = k.kinds[0] if k.kinds else ("plane" if k.table == "obstacles" else None)
        yield pytest.param(k, kind, id=f"{k.table}.{k.name}[{kind}]")


@pytest.mark.parametrize(("key", "kind"), list(_invalid_cases()))
def test_each_documented_range_is_enforced_and_the_error_names_the_key(key, kind):
    assert key.invalid is not None
    m, t = _variant(key.table, kind)
    t[key.name] = copy.deepcopy(key.invalid)
    with pytest.raises(ParameterError) as exc:
        Problem.from_mapping(m)
    assert key.name in exc.value.name, str(exc.value)


def test_the_reference_documents_the_contact_keys():
    md, text = keys.markdown(), keys.text()
    for k in keys.CONTACT_KEYS:
        assert f"`{k.name}`" in md and k.unit and k.default and k.allowed and k.doc
        assert f"{k.table}.{k.name}" in text
    assert "`[[obstacles]]`" in md and "`[contact]`" in md
    for doc in (md, text):
        assert "64 EI/h^4" in doc and "restitution" in doc and "contact_" in doc
    paths = [(k.table, k.name, k.kinds) for k in keys.CONTACT_KEYS]
    assert len(paths) == len(set(paths))


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
        del node[int(parts[-1]) if isinstance(node, list) else parts[-1]]
    return edit


def _many(*edits):
    def edit(m):
        for e in edits:
            e(m)
    return edit


NAN, INF = float("nan"), float("inf")

BAD = [
    # zero or non-finite directions
    ("zero normal", _set("obstacles.0.normal", [0, 0, 0]), "obstacles[0].normal",
     "not all zero"),
    ("nan normal", _set("obstacles.0.normal", [NAN, 0, 1]), "obstacles[0].normal",
     "finite"),
    ("zero axis", _set("obstacles.2.axis", [0.0, 0.0, 0.0]), "obstacles[2].axis",
     "not all zero"),
    ("infinite axis", _set("obstacles.3.axis", [INF, 0, 0]), "obstacles[3].axis", "finite"),
    ("normal of two", _set("obstacles.0.normal", [0, 1]), "obstacles[0].normal",
     "3 finite numbers"),
    ("nan point", _set("obstacles.0.point", [0, NAN, 0]), "obstacles[0].point", "finite"),
    # radii
    ("negative sphere radius", _set("obstacles.1.radius", -0.02), "obstacles[1].radius",
     "> 0"),
    ("zero cylinder radius", _set("obstacles.2.radius", 0.0), "obstacles[2].radius", "> 0"),
    ("nan radius", _set("obstacles.1.radius", NAN), "obstacles[1].radius", "> 0"),
    ("radius missing", _drop("obstacles.1.radius"), "obstacles[1].radius", "radius in m"),
    ("radius on a plane", _set("obstacles.0.radius", 0.1), "obstacles[0].radius",
     "a plane has no radius"),
    ("zero length", _set("obstacles.2.length", 0.0), "obstacles[2].length", "> 0"),
    # friction
    ("negative friction", _set("obstacles.0.friction", -0.1), "obstacles[0].friction",
     "0 ... 100"),
    ("nan friction", _set("obstacles.1.friction", NAN), "obstacles[1].friction",
     "Coulomb coefficient"),
    ("friction beyond 100", _set("obstacles.1.friction", 1e3), "obstacles[1].friction",
     "0 ... 100"),
    # kinds and the keys of other kinds
    ("unknown kind", _set("obstacles.0.kind", "cube"), "obstacles[0].kind",
     "'plane', 'sphere', 'cylinder'"),
    ("kind missing", _drop("obstacles.1.kind"), "obstacles[1].kind", "'sphere'"),
    ("inside on a plane", _set("obstacles.0.inside", True), "obstacles[0].inside",
     "only for kind = 'cylinder'"),
    ("inside on a sphere", _set("obstacles.1.inside", True), "obstacles[1].inside",
     "only for kind = 'cylinder'"),
    ("inside not a boolean", _set("obstacles.3.inside", "yes"), "obstacles[3].inside",
     "true or false"),
    ("length on a plane", _set("obstacles.0.length", 1.0), "obstacles[0].length",
     "only for kind = 'cylinder'"),
    ("length on a sphere", _set("obstacles.1.length", 1.0), "obstacles[1].length",
     "only for kind = 'cylinder'"),
    ("axis on a plane", _set("obstacles.0.axis", [0, 0, 1]), "obstacles[0].axis",
     "normal = [x, y, z]"),
    ("normal on a cylinder", _set("obstacles.2.normal", [0, 0, 1]), "obstacles[2].normal",
     "axis = [x, y, z]"),
    ("point on a sphere", _set("obstacles.1.point", [0, 0, 1]), "obstacles[1].point",
     "centre = [x, y, z]"),
    ("normal missing", _drop("obstacles.0.normal"), "obstacles[0].normal", "not all 0"),
    ("unknown obstacle key", _set("obstacles.2.colour", "red"), "obstacles[2].colour",
     "allowed here: kind, point, axis"),
    ("obstacles not an array", _set("obstacles", {"kind": "plane"}), "obstacles",
     "[[obstacles]]"),
    ("obstacle not a table", _set("obstacles.1", "ball"), "obstacles[1]", "a table"),
    # motion
    ("motion jumps", _set("obstacles.1.motion", {"translation": [0, 0, 0.01],
                                                 "translation_time": {"kind": "step"}}),
     "obstacles[1].motion.translation_time.kind", "continuous"),
    ("motion zero axis", _set("obstacles.1.motion", {"rotation_axis": [0, 0, 0]}),
     "obstacles[1].motion.rotation_axis", "not all zero"),
    ("motion unknown key", _set("obstacles.1.motion", {"speed": 1.0}),
     "obstacles[1].motion.speed", "allowed here: translation"),
    ("motion too far", _set("obstacles.1.motion", {"translation": [1e300, 0, 0]}),
     "obstacles[1].motion.translation", "round-off"),
    ("motion too fast", _set("obstacles.1.motion", {
        "translation": [0, 0, 0.01], "translation_time": {"kind": "harmonic",
                                                          "frequency": 1e300}}),
     "obstacles[1].motion.translation_time.frequency", "periods"),
    ("sphere too far", _set("obstacles.1.centre", [1e12, 0, 0]), "obstacles[1].centre",
     "round-off"),
    # the contact table
    ("restitution zero", _set("contact.restitution", 0.0), "contact.restitution", "(0, 1]"),
    ("restitution above 1", _set("contact.restitution", 1.01), "contact.restitution",
     "(0, 1]"),
    ("restitution nan", _set("contact.restitution", NAN), "contact.restitution", "(0, 1]"),
    ("negative contact radius", _set("contact.radius", -0.005), "contact.radius", "> 0"),
    ("contact radius table in a single rod", _set("contact.radius", {"a": 0.01}),
     "contact.radius", "only in an assembly"),
    ("self not a boolean", _set("contact.self", 1), "contact.self", "true or false"),
    ("negative rod-rod friction", _set("contact.friction", -0.2), "contact.friction",
     "0 ... 100"),
    ("zero slip velocity", _set("contact.slip_velocity", 0.0), "contact.slip_velocity",
     "> 0"),
    ("negative stiffness", _set("contact.stiffness", -1.0), "contact.stiffness", "> 0"),
    ("penetration beyond the radius", _set("contact.penetration", 0.006),
     "contact.penetration", "<= the rod's contact radius 0.005 m"),
    ("unknown contact key", _set("contact.damping", 0.5), "contact.damping",
     "allowed here: radius, self"),
    ("contact without obstacles or self", _set("obstacles", []), "contact",
     "changes nothing"),
    ("contact radius missing for a rectangle",
     _set("section", {"kind": "rectangle", "width": 0.01, "height": 0.01}),
     "contact.radius", "required for a rectangle section"),
    ("contact radius missing for given stiffness",
     _many(_set("section", {"kind": "stiffness", "EA": 1e6, "GA1": 1e6, "GA2": 1e6,
                            "EI1": 1.0, "EI2": 1.0, "GJ": 1.0, "rhoA": 0.1, "rhoI1": 1e-6,
                            "rhoI2": 1e-6, "rhoI3": 2e-6}), _drop("material")),
     "contact.radius", "required for a stiffness section"),
    ("contact radius missing in a zone",
     _set("zones", [{"from": 0.1, "to": 0.2, "section": {"kind": "rectangle",
                                                         "width": 0.01, "height": 0.01}}]),
     "contact.radius", "zones[0] has a rectangle section"),
    ("contact radius missing for an eccentric composite",
     _many(_drop("material"),
           _set("section", {"kind": "composite", "regions": [
               {"material": "a", "shape": {"kind": "rectangle", "width": 0.006,
                                           "height": 0.004}}]}),
           _set("materials", {"a": {"youngs_modulus": 1e9, "poisson_ratio": 0.3,
                                    "density": 1000.0}})),
     "contact.radius", "composite section whose regions are not concentric"),
    # a rod starting inside an obstacle
    ("rod inside the floor", _set("obstacles.0.point", [0.0, 0.0, 0.0]), "obstacles[0]",
     "the rod's node at s = 0 m is 0.005 m inside"),
    ("rod inside a ball", _set("obstacles.1.centre", [0.2, 0.0, 0.0]), "obstacles[1]",
     "node at s = 0.2 m is 0.025 m inside"),
    ("rod outside its pipe", _set("obstacles.3.radius", 0.004), "obstacles[3]",
     "0.001 m inside"),
]


@pytest.mark.parametrize(("edit", "key", "needle"), [b[1:] for b in BAD],
                         ids=[b[0] for b in BAD])
def test_bad_contact_input_is_one_line_naming_the_key(edit, key, needle):
    m = _base()
    edit(m)
    with pytest.raises(ParameterError) as exc:
        Problem.from_mapping(m)
    msg = str(exc.value)
    assert "\n" not in msg
    assert exc.value.name == key, msg
    assert f"parameter {key!r}" in msg and needle in msg, msg


ASSEMBLY_BAD = [
    ("contact radius of an unknown rod", {"contact": {"radius": {"c": 0.01}, "self": True}},
     "contact.radius.c", "a radius of a rod of the assembly: a, b"),
    ("contact in a rod's table", {"rods.a.contact": {"self": True}}, "rods.a.contact",
     "stays at the top"),
    ("obstacles in a rod's table", {"rods.b.obstacles": []}, "rods.b.obstacles",
     "stays at the top"),
    ("contact without obstacles or self", {"contact": {"restitution": 0.5}}, "contact",
     "changes nothing"),
    ("a rectangular rod without a radius", {"contact": {"self": True}}, "contact.radius",
     "centreline [rod a]"),
    ("radius table and number", {"contact": {"radius": 0.01, "self": True},
                                 "contact.radius": {"a": 0.01, "b": -1.0}},
     "contact.radius.b", "> 0"),
]


@pytest.mark.parametrize(("edits", "key", "needle"), [b[1:] for b in ASSEMBLY_BAD],
                         ids=[b[0] for b in ASSEMBLY_BAD])
def test_bad_assembly_contact_input_is_one_line_naming_the_key(edits, key, needle):
    from tests.runtime.test_assembly_problem import _base as assembly

    m = assembly()
    for path, value in edits.items():
        node = m
        parts = path.split(".")
        for p in parts[:-1]:
            node = node[p]
        node[parts[-1]] = value
    with pytest.raises(ParameterError) as exc:
        Assembly.from_mapping(m)
    msg = str(exc.value)
    assert "\n" not in msg and exc.value.name == key and needle in msg, msg
