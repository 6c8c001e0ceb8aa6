"""Contact at a held end, and the capstan example (issue 32).

A held node's rows are its end condition's, so the compiled residual leaves the contact
force on that node to the support: the support's reaction (and its power) must include
it. Checked against the contact kernel evaluated in Python (derive.contact, CasADi) on a
clamped rod pressed into a floor and sliding on it. The capstan example: its arc sits
where the wire settles on the drum (a clamp farther out lifts the wire's last elements
off the drum and loses wrap angle), and a short run holds the capstan ratio with the
clamp's reaction along the strand and the forces on the wire in balance."""

from __future__ import annotations

import math

import casadi as ca
import numpy as np
import pytest

from derive import contact as C
from references.contact import capstan_ratio, capstan_ratio_rod
from runtime.problem.assemble import build_model
from runtime.problem.registry import load_problem
from runtime.problem.schema import Problem
from runtime.simulate.simulate import simulate


def _clamped_rod_on_floor(obstacles: bool) -> Problem:
    """A steel rod along x (0.3 m, 5 mm radius, 6 elements), clamped at s = 0, resting on a
    floor with friction 0.3 (its centreline at its radius above it)."""
    m = {"name": "held_on_floor",
         "rod": {"length": 0.3, "elements": 6,
                 "geometry": {"kind": "straight", "direction": [1.0, 0.0, 0.0]}},
         "section": {"kind": "circle", "radius": 0.005},
         "material": {"density": 7850.0, "youngs_modulus": 2.1e11, "poisson_ratio": 0.3,
                      "tau": 1e-4},
         "start": {"kind": "clamped"}, "end": {"kind": "free"},
         "simulation": {"t_end": 0.1, "initial": "reference"}}
    if obstacles:
        m["obstacles"] = [{"kind": "plane", "point": [0.0, 0.0, -0.005],
                           "normal": [0.0, 0.0, 1.0], "friction": 0.3}]
    return Problem.from_mapping(m)


def test_the_contact_force_on_a_held_node_is_in_its_supports_reaction():
    """The rod pressed 1e-7 m into the floor and sliding along it at 1 cm/s (the clamped
    node too, as a moving clamp would): the start's reaction and the boundary power with
    the floor differ from those without it by exactly the contact force the kernel puts
    on node 0 (f_a of segment 1), and its power."""
    with_floor, bare = (build_model(_clamped_rod_on_floor(o)) for o in (True, False))
    y = with_floor.initial_state()
    assert np.array_equal(y, bare.initial_state())
    for i in with_floor.phi_index:
        y[i[2]] -= 1e-7
    v = np.array([0.01, 0.0, 0.0])
    for i in with_floor.v_index:
        y[i] = v
    s = C.contact_symbols()
    q = ca.Function("Q", list(s.inputs().values()), [C.contact_quantities(s, "plane")["Q"]])
    with_floor.at(0.0)
    ph, vi = with_floor.phi_index, with_floor.v_index
    Q = np.array(q(y[ph[0]], y[ph[1]], y[vi[0]], y[vi[1]], y[with_floor.p_index[0]],
                   y[with_floor.omega_index[0]], with_floor.contact.obs[0],
                   with_floor.contact.cnt[0, 0])).ravel()
    f_a = Q[0:3]
    assert f_a[2] > 1.0 and f_a[0] == pytest.approx(-0.3 * f_a[2], rel=1e-3)  # pressed, sliding
    R, R0 = (m.reactions(0.0, y)["start"]["force"] for m in (with_floor, bare))
    np.testing.assert_allclose(R - R0, -f_a, rtol=1e-9, atol=1e-12 * abs(f_a[2]))
    P, P0 = (m.diagnostics(0.0, y)["boundary_power"] for m in (with_floor, bare))
    assert P - P0 == pytest.approx(-f_a @ v, rel=1e-9)


def test_the_capstan_arc_lies_where_the_wire_settles_on_the_drum():
    """The example's nodes at (R + r)/cos(pi/(2N)) from the drum's axis: the chords'
    midpoints touch the drum, and the clamped end is where the free wire settles (1e-5 m
    farther out lifted the wire's last 4 elements off the drum: ratio 2.42 for 2.57)."""
    p = load_problem("contact_capstan")
    drum = p.obstacles[0]
    R, r, N = drum.radius, p.contact_law().radius[0], p.rod.elements
    rho = (R + r) / math.cos(math.pi / (2 * N))
    assert p.rod.geometry.radius == pytest.approx(rho, rel=1e-9)
    assert drum.point[0] == pytest.approx(rho, rel=1e-9)


def test_the_capstan_example_holds_the_capstan_ratio():
    """The capstan example until the drum has turned 0.02 s (steady from 0.31 s): the
    clamp holds T_hold times the capstan ratio along the strand (within 3 % of
    exp(mu pi), 1 % of the rod's, whose friction acts at its surface), its reaction tilted
    by less than 1.5 degrees, and the weight, the clamp and the drum balance."""
    p = load_problem("contact_capstan", {"simulation.t_end": 0.32})
    run = simulate(p)
    assert run.status == "finished", run.message
    k = np.searchsorted(run.t, 0.31)
    F = run.reactions["end"]["force"][:, k:]
    drum = run.obstacles[0]["force"][:, k:]
    weight = np.array([0.0, 0.0, -10.0])
    np.testing.assert_allclose(F + drum + weight[:, None], 0.0, atol=1e-6 * 10.0)
    ratio = -F[2] / 10.0
    assert np.ptp(ratio) < 1e-6                     # steady
    mu, wrap = p.obstacles[0].friction, math.pi
    assert ratio[-1] == pytest.approx(capstan_ratio(mu, wrap), rel=0.03)
    assert ratio[-1] == pytest.approx(capstan_ratio_rod(mu, wrap, drum_radius=0.1,
                                                        rod_radius=0.001), rel=0.01)
    assert abs(F[0, -1]) < math.tan(math.radians(1.5)) * abs(F[2, -1])
