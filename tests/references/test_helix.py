"""Coil spring axial stiffness (references.helix): formulas, limits and the 3-D shooting."""

from __future__ import annotations

import math

import numpy as np
import pytest

from references.cosserat_bvp import RodStiffness, solve_rod
from references.helix import (
    helix_angle,
    helix_rod,
    spring_compliance_axis,
    spring_compliance_classical,
    spring_compliance_end,
    spring_stiffness_shooting,
    wire_length,
)
from references.sections import circle

# the example of the report: R = 1 cm, pitch 5 mm, 5 turns, round wire r = 1 mm
E, NU = 1.0e9, 0.3
G = E / (2 * (1 + NU))
SEC = circle(0.001, NU)
GA, _, EA, EI, _, GJ = SEC.stiffnesses(E, G)
ST = RodStiffness.from_section(SEC, E, G)
RC, PITCH = 0.01, 0.005
KW = {"EI": EI, "GJ": GJ, "EA": EA, "GA": GA}


def test_example_numbers():
    n = 5
    k_cl = 1 / spring_compliance_classical(RC, PITCH, n, EI=EI, GJ=GJ)
    k_ax = 1 / spring_compliance_axis(RC, PITCH, n, **KW)
    k_end = 1 / spring_compliance_end(RC, PITCH, n, **KW)
    assert k_cl == pytest.approx(19.198045545, rel=1e-9)
    assert k_ax == pytest.approx(19.090645408, rel=1e-9)
    assert k_end == pytest.approx(10.153395518, rel=1e-9)
    # closed-coil textbook value G d^4 / (64 R^3 n) is 0.17 % stiffer (pitch correction)
    k_closed = G * 0.002**4 / (64 * RC**3 * n)
    assert k_closed == pytest.approx(19.230769, rel=1e-6)
    assert 0 < k_closed / k_cl - 1 < 3e-3


def test_formula_limits():
    # alpha -> 0: closed coil, F R^2 l / GJ; round wire: 64 R^3 n / (G d^4)
    c = spring_compliance_classical(RC, 0.0, 3, EI=EI, GJ=GJ)
    assert c == pytest.approx(2 * math.pi * RC**3 * 3 / GJ, rel=1e-15)
    assert c == pytest.approx(64 * RC**3 * 3 / (G * 0.002**4), rel=1e-14)
    assert helix_angle(RC, 0.0) == 0.0 and wire_length(RC, 0.0, 2) == 4 * math.pi * RC
    # infinitely stiff in extension and shear: the classical formula
    inf = {"EI": EI, "GJ": GJ, "EA": math.inf, "GA": math.inf}
    assert spring_compliance_axis(RC, PITCH, 4, **inf) == spring_compliance_classical(
        RC, PITCH, 4, EI=EI, GJ=GJ)
    # alpha -> 90 deg (straight bar along the axis, R -> 0 relative to the pitch): l / EA
    c = spring_compliance_axis(1e-9, 1.0, 1.0, **KW)
    assert c == pytest.approx(1.0 / EA, rel=1e-6)


def test_end_load_does_not_approach_the_classical_formula():
    """Integer turns: delta_end - delta_axis = F R^2 l [(1 + sin^2)/(2 EI) + cos^2/(2 GJ)],
    a fixed fraction of delta_axis for any number of turns (coil bending)."""
    a = helix_angle(RC, PITCH)
    ratios = []
    for n in (1, 5, 50, 500):
        l = wire_length(RC, PITCH, n)
        extra = RC**2 * l * ((1 + math.sin(a) ** 2) / (2 * EI) + math.cos(a) ** 2 / (2 * GJ))
        d_end, d_ax = spring_compliance_end(RC, PITCH, n, **KW), spring_compliance_axis(
            RC, PITCH, n, **KW)
        assert d_end - d_ax == pytest.approx(extra, rel=1e-9)
        ratios.append(d_end / d_ax)
    assert max(ratios) - min(ratios) < 1e-9
    # closed-coil, no shear/extension: ratio 3/2 + GJ / (2 EI)
    inf = {"EI": EI, "GJ": GJ, "EA": math.inf, "GA": math.inf}
    r0 = spring_compliance_end(RC, 0.0, 7, **inf) / spring_compliance_axis(RC, 0.0, 7, **inf)
    assert r0 == pytest.approx(1.5 + GJ / (2 * EI), rel=1e-12)
    # fractional turns: the oscillating part is bounded, so it fades like 1/n
    dev = [abs(spring_compliance_end(RC, PITCH, n + 0.25, **KW)
               / spring_compliance_axis(RC, PITCH, n + 0.25, **KW) - ratios[0]) for n in (4, 40)]
    assert dev[1] < 0.15 * dev[0]


@pytest.mark.parametrize("frame", ["binormal", "frenet"])
def test_unloaded_helix_and_frame(frame):
    n = 1.3
    h = helix_rod(RC, PITCH, n, frame)
    s = solve_rod(h.L, ST, r0=h.r0, R0=h.R0, K0=h.K0, load_steps=1, n_points=41)
    a = h.alpha
    phi = s.s * math.cos(a) / RC
    exact = np.column_stack([RC * np.cos(phi), RC * np.sin(phi), RC * phi * math.tan(a)])
    np.testing.assert_allclose(s.r_ref, exact, atol=1e-14)
    T = np.column_stack([-np.sin(phi) * math.cos(a), np.cos(phi) * math.cos(a),
                         np.full_like(phi, math.sin(a))])
    N = np.column_stack([-np.cos(phi), -np.sin(phi), 0 * phi])
    np.testing.assert_allclose(s.R_ref[:, :, 2], T, atol=1e-13)
    d1 = np.cross(T, N) if frame == "binormal" else N
    np.testing.assert_allclose(s.R_ref[:, :, 0], d1, atol=1e-13)
    assert s.r_ref[-1, 2] == pytest.approx(n * PITCH, rel=1e-13)


@pytest.mark.parametrize(("n", "load"), [(2.3, "axis"), (2.3, "end"), (5, "end")])
def test_shooting_matches_formulas(n, load):
    k = spring_stiffness_shooting(RC, PITCH, n, ST, load=load, rel_load=1e-7)
    f = spring_compliance_axis if load == "axis" else spring_compliance_end
    assert k * f(RC, PITCH, n, **KW) == pytest.approx(1.0, rel=1e-8)


def test_shooting_frame_and_small_pitch():
    n = 1.6
    a = spring_stiffness_shooting(RC, PITCH, n, ST, load="end", frame="frenet", rel_load=1e-7)
    assert a * spring_compliance_end(RC, PITCH, n, **KW) == pytest.approx(1.0, rel=1e-8)
    # nearly closed coil (alpha = 1.6e-4): the alpha -> 0 limit of the solver
    p = 1e-5
    b = spring_stiffness_shooting(RC, p, n, ST, load="axis", rel_load=1e-7)
    assert b * spring_compliance_axis(RC, p, n, **KW) == pytest.approx(1.0, rel=1e-8)
    # closed-coil torsion + shear (the shear term is 0.56 % here); alpha^2 = 2.5e-8
    l = wire_length(RC, p, n)
    assert b * (RC**2 * l / GJ + l / GA) == pytest.approx(1.0, rel=1e-7)


def test_invalid_input():
    with pytest.raises(ValueError):
        helix_rod(RC, PITCH, 1.0, "darboux")
    with pytest.raises(ValueError):
        spring_stiffness_shooting(RC, PITCH, 1.0, ST, load="middle")
    with pytest.raises(ValueError):
        helix_angle(-1.0, PITCH)
    with pytest.raises(ValueError):
        wire_length(RC, PITCH, 0.0)
