"""Rod clamped at both ends: linear Timoshenko formulas against the 3-D shooting solver."""

from __future__ import annotations

import math

import numpy as np
import pytest

from references.clamped import (
    clamped_center_load_deflection,
    clamped_center_load_end_moment,
    clamped_uniform_load_curve,
    clamped_uniform_load_deflection,
    clamped_uniform_load_end_moment,
)
from references.cosserat_bvp import RodStiffness, solve_rod
from references.sections import rectangle

# stubby steel-like rectangle so that shear deflection matters (~12 % of the total)
E, NU, B, D, L = 2.0e11, 0.3, 0.02, 0.05, 0.5
G = E / (2 * (1 + NU))
SEC = rectangle(B, D, NU)  # b along d1, d along d2
ST = RodStiffness.from_section(SEC, E, G)
EI1, GA2 = E * SEC.I1, SEC.kappa_2 * G * SEC.A  # load along d2: bending about d1


def test_formulas():
    assert clamped_uniform_load_deflection(1.0, L=1.0, EI=1.0) == 1 / 384
    assert clamped_center_load_deflection(1.0, L=1.0, EI=1.0) == 1 / 192
    assert clamped_uniform_load_deflection(1.0, L=2.0, EI=1.0, kGA=4.0) == 16 / 384 + 4 / 32
    assert clamped_center_load_deflection(2.0, L=2.0, EI=1.0, kGA=4.0) == 16 / 192 + 4 / 16
    assert clamped_uniform_load_end_moment(1.0, 2.0) == 1 / 3
    assert clamped_center_load_end_moment(1.0, 2.0) == 0.25
    with pytest.raises(ValueError):
        clamped_uniform_load_deflection(1.0, L=1.0, EI=0.0)


def test_uniform_load_gravity_like():
    q = 1e-3 * EI1 / L**3  # w / L ~ 3e-6: membrane effect (w / r_g)^2 ~ 1e-8
    s = solve_rod(L, ST, end="clamped", distributed_force=(0.0, -q, 0.0), load_steps=1,
                  n_points=101)
    w = -s.displacement[50, 1]
    expect = clamped_uniform_load_deflection(q, L=L, EI=EI1, kGA=GA2)
    shear = q * L * L / (8 * GA2)
    assert 0.05 < shear / expect < 0.2
    assert w == pytest.approx(expect, rel=1e-8)
    # the whole curve, not only midspan
    x = np.linspace(0.0, L, 101)
    np.testing.assert_allclose(-s.displacement[:, 1],
                               clamped_uniform_load_curve(x, q, L=L, EI=EI1, kGA=GA2),
                               rtol=0, atol=1e-8 * w)
    assert clamped_uniform_load_curve(L / 2, q, L=L, EI=EI1, kGA=GA2) == pytest.approx(expect)
    # symmetry, reactions, clamp moments (Euler-Bernoulli values also with shear)
    np.testing.assert_allclose(s.displacement[:, 1], s.displacement[::-1, 1], atol=1e-8 * w)
    assert s.base_force[1] == pytest.approx(-q * L / 2, rel=1e-10)
    assert s.base_moment[0] == pytest.approx(clamped_uniform_load_end_moment(q, L), rel=1e-8)
    np.testing.assert_allclose(s.displacement[:, 0], 0.0, atol=1e-13 * L)
    # axial motion only at second order (shortening of the deflected span)
    assert np.max(np.abs(s.displacement[:, 2])) < 10 * w * w / L


def test_uniform_load_euler_bernoulli_limit():
    # unshearable (extensible: with EA = inf too the axial force of the straight clamped
    # rod would be indeterminate and the shooting Jacobian singular)
    st = RodStiffness(math.inf, math.inf, ST.EA, ST.EI1, ST.EI2, ST.GJ)
    q = 1e-3 * EI1 / L**3
    s = solve_rod(L, st, end="clamped", distributed_force=(0.0, -q, 0.0), load_steps=1,
                  n_points=3)
    expect = clamped_uniform_load_deflection(q, L=L, EI=EI1)
    assert -s.displacement[1, 1] == pytest.approx(expect, rel=1e-8)


def test_central_point_load_other_plane():
    """Load along d1: bending about d2 (EI2), shear GA1."""
    EI2, GA1 = E * SEC.I2, SEC.kappa_1 * G * SEC.A
    F = 1e-3 * EI2 / L**2
    s = solve_rod(L, ST, end="clamped", point_forces=[(L / 2, (F, 0.0, 0.0))], load_steps=1,
                  n_points=101)
    w = s.displacement[50, 0]
    assert w == pytest.approx(clamped_center_load_deflection(F, L=L, EI=EI2, kGA=GA1), rel=1e-8)
    assert s.base_force[0] == pytest.approx(F / 2, rel=1e-10)
    # (membrane tension changes the clamp moment at relative order (w / r_g)^2 ~ 1e-7)
    assert abs(s.base_moment[1]) == pytest.approx(clamped_center_load_end_moment(F, L), rel=1e-6)
    np.testing.assert_allclose(s.displacement[:, 0], s.displacement[::-1, 0], atol=1e-8 * w)
    # the force resultant jumps by F at midspan; Clapeyron: potential = -F w / 2
    assert s.n[49, 0] - s.n[51, 0] == pytest.approx(F, rel=1e-10)
    assert s.potential == pytest.approx(-0.5 * F * w, rel=1e-7)


def test_small_load_error_is_quadratic():
    """Relative error vs the linear formula grows like the load squared (membrane tension)."""
    errs = []
    for q in (3e-2 * EI1 / L**3, 6e-2 * EI1 / L**3):
        s = solve_rod(L, ST, end="clamped", distributed_force=(0.0, -q, 0.0), load_steps=1,
                      n_points=3)
        lin = clamped_uniform_load_deflection(q, L=L, EI=EI1, kGA=GA2)
        errs.append(-s.displacement[1, 1] / lin - 1)
    assert errs[0] < 0  # tension stiffens
    assert 1e-7 < -errs[0] < 1e-6
    assert errs[1] / errs[0] == pytest.approx(4.0, rel=2e-3)
