"""Bathe-Bolourchi 45-degree bend (references.bend45): converged tips, convergence, literature."""

from __future__ import annotations

import math

import numpy as np
import pytest

from references.bend45 import (
    BEND45,
    BEND45_TIPS,
    bend45_convergence,
    bend45_solve,
    bend45_table,
    bend45_tip,
)

# Simo and Vu-Quoc (1986), 8 linear elements, mapped to this placement (x, y, z)
SIMO_VU_QUOC = {300.0: (58.84, 22.33, 40.08), 450.0: (52.32, 18.62, 48.39),
                600.0: (47.23, 15.79, 53.37)}


@pytest.fixture(scope="module")
def table():
    return bend45_table()


def test_table_matches_stored_converged_tips(table):
    for P, tip in table.items():
        np.testing.assert_allclose(tip, BEND45_TIPS[P], rtol=0, atol=1e-9)


def test_unloaded_arc_and_load_steps():
    s = bend45_solve(600.0, load_steps=1, n_points=5)
    R = BEND45["R"]
    phi = s.s / R
    ref = np.column_stack([R * np.sin(phi), R * (1 - np.cos(phi)), 0 * phi])
    np.testing.assert_allclose(s.r_ref, ref, atol=1e-12 * R)
    # one continuation step reaches the same (principal) solution
    np.testing.assert_allclose(s.tip, BEND45_TIPS[600.0], atol=1e-9)


def test_director_choice_does_not_matter_for_the_square():
    a = bend45_tip(600.0, director="out_of_plane")
    np.testing.assert_allclose(a, BEND45_TIPS[600.0], atol=1e-9)
    with pytest.raises(ValueError):
        bend45_tip(600.0, director="diagonal")


def test_tolerance_study():
    tips = bend45_convergence(600.0, rtols=(1e-8, 1e-10, 1e-12))
    ref = np.asarray(BEND45_TIPS[600.0])
    errs = [float(np.max(np.abs(t - ref))) for t in tips.values()]
    assert errs[0] > errs[1] > errs[2]
    assert errs[0] < 1e-5 and errs[1] < 1e-7 and errs[2] < 1e-10


def test_literature_eight_elements_close_but_not_converged(table):
    for P, tip in table.items():
        diff = np.abs(np.asarray(tip) - SIMO_VU_QUOC[P])
        assert diff.max() < 0.15, (P, diff)  # 8 linear elements: within about 0.1
    # Bathe and Bolourchi (1979) at 600: (47.2, 15.9, 53.4)
    assert np.abs(table[600.0] - (47.2, 15.9, 53.4)).max() < 0.25


def test_virtual_work_tip_load():
    """d(potential)/dP = -(z displacement of the tip) for the dead load (0, 0, P)."""
    P, h = 600.0, 1e-2
    s = bend45_solve(P)
    L = BEND45["R"] * BEND45["angle"]
    g = np.r_[s.base_force / P, s.base_moment / (P * L)]
    pots = [bend45_solve(p, load_steps=[1.0], guess=g).potential for p in (P - h, P + h)]
    assert (pots[1] - pots[0]) / (2 * h) == pytest.approx(-s.tip_displacement[2], rel=1e-8)
    assert s.tip_displacement[2] == s.tip[2]
    assert math.isfinite(s.elastic_energy) and s.elastic_energy > 0
