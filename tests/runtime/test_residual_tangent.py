"""The residual's exact tangent (issue 34; runtime/model/native/rod_tangent.c):
``F_y dy + F_y' dy' + F_p dA`` against central differences of the residual in random
state directions and random directions of every array of the rod (Kelvin-Voigt,
generalized Maxwell, coupled sections; every kind of end; dead and follower loads,
follower loads appearing only in the direction), against the banded Jacobian, and
against the CasADi oracle's forward derivative (an independent assembly)."""

from __future__ import annotations

import numpy as np
import pytest

from runtime.model.sensitivity import zeros_like
from tests.coupled import coupled_model
from tests.rods import (
    MAXWELL,
    move_held_ends,
    random_state,
    residual,
    rod_model,
    with_internal_strains,
)

BCS = [("clamped", "free"), ("free", "free"), ("clamped", "clamped"), ("pinned", "clamped")]
TABLES = ("par", "seg", "jnt", "nload", "sload", "theta", "segb", "jntb")
#: entries of par that are flags or the load factor: the tangent has no direction there
FLAGS = ("fix_start", "clamp_start", "fix_end", "clamp_end")


def random_direction(m, rng):
    """Random derivatives of every entry of the rod's arrays (flags excluded)."""
    d = zeros_like(m.arrays)
    for k in TABLES + (("segc", "jntc") if m.arrays.coupled else ()):
        a = getattr(d, k)
        a[...] = rng.standard_normal(a.shape) * np.maximum(np.abs(getattr(m.arrays, k)), 1e-3)
    for name in FLAGS:
        d.param(name)[:] = 0.0
    return d


def shifted(m, d, eps):
    """Set the model's arrays to A + eps dA (in place)."""
    for k in TABLES + (("segc", "jntc") if m.arrays.coupled else ()):
        getattr(m.arrays, k)[...] = getattr(m._base, k) + eps * getattr(d, k)


def check(m, rng, y, yp, with_params=True, rtol=1e-7):
    m.drive = None           # nothing rewrites the arrays set here (load factor included)
    m._base = m.arrays.copy()
    dy, dyp = rng.standard_normal(m.n), rng.standard_normal(m.n)
    d = random_direction(m, rng) if with_params else None
    tan = m.residual_tangent(0.0, y, yp, dy, dyp, d)
    eps = 1e-6
    if with_params:
        shifted(m, d, eps)
    fp = residual(m, y + eps * dy, yp + eps * dyp)
    if with_params:
        shifted(m, d, -eps)
    fm = residual(m, y - eps * dy, yp - eps * dyp)
    if with_params:
        shifted(m, d, 0.0)
    fd = (fp - fm) / (2 * eps)
    scale = np.abs(fd).max()
    assert np.abs(tan - fd).max() <= rtol * scale, (np.abs(tan - fd).max(), scale)
    return tan


@pytest.mark.parametrize("start,end", BCS)
def test_kelvin_voigt_tangent_matches_central_differences(start, end):
    rng = np.random.default_rng(3)
    m = move_held_ends(rod_model(6, start, end))
    m.arrays.node_load("f_follower")[-1] = [0.01, 0.02, -0.03]
    m.arrays.segment_load("m_follower")[2] = [0.001, 0.0, 0.002]
    y, yp = random_state(m, rng), rng.standard_normal(m.n)
    check(m, rng, y, yp)
    check(m, rng, y, yp, with_params=False)


def test_follower_load_only_in_the_direction():
    """A follower load that is zero in the rod but not in the direction (a parameter that
    switches it on) is differentiated too."""
    rng = np.random.default_rng(4)
    m = rod_model(5, "clamped", "free")
    y, yp = random_state(m, rng), rng.standard_normal(m.n)
    m.drive = None
    m._base = m.arrays.copy()
    d = zeros_like(m.arrays)
    d.node_load("f_follower")[-1] = [1.0, 2.0, 3.0]
    d.segment_load("m_dead")[1] = [0.5, -0.5, 1.0]
    tan = m.residual_tangent(0.0, y, yp, np.zeros(m.n), np.zeros(m.n), d)
    eps = 1e-6
    shifted(m, d, eps)
    fp = residual(m, y, yp)
    shifted(m, d, -eps)
    fm = residual(m, y, yp)
    shifted(m, d, 0.0)
    assert np.abs(tan - (fp - fm) / (2 * eps)).max() <= 1e-7 * np.abs(tan).max()
    assert np.abs(tan).max() > 0.0


@pytest.mark.parametrize("start,end", [("clamped", "free"), ("free", "free"),
                                       ("clamped", "clamped")])
def test_maxwell_tangent_matches_central_differences(start, end):
    rng = np.random.default_rng(5)
    m = rod_model(5, start, end, tau=None, **MAXWELL)
    assert m.branches > 0
    y = with_internal_strains(m, random_state(m, rng), rng)
    check(m, rng, y, rng.standard_normal(m.n))


@pytest.mark.parametrize("start,end", BCS)
def test_coupled_tangent_matches_central_differences(start, end):
    rng = np.random.default_rng(6)
    m = coupled_model(rng, 5, start, end)
    m.arrays.param("m_follower_end")[:] = [0.001, -0.002, 0.0005]
    y, yp = random_state(m, rng), rng.standard_normal(m.n)
    check(m, rng, y, yp)


def test_state_direction_is_the_band_jacobian():
    """Along a state direction the tangent is J dy for the compiled band Jacobian."""
    rng = np.random.default_rng(7)
    m = rod_model(7, "pinned", "clamped")
    y, yp = random_state(m, rng), rng.standard_normal(m.n)
    dy, dyp = rng.standard_normal(m.n), rng.standard_normal(m.n)
    tan = m.residual_tangent(0.0, y, yp, dy, dyp)
    Jy, Jyp = m.dF_dy_sparse(0.0, y, yp), m.dF_dyp_sparse(0.0, y, yp)
    ref = Jy @ dy + Jyp @ dyp
    assert np.abs(tan - ref).max() <= 1e-12 * np.abs(ref).max()


@pytest.mark.parametrize("maxwell", [False, True])
def test_tangent_equals_the_casadi_oracle(maxwell):
    """The CasADi MX assembly (runtime/model/casadi_oracle.py), differentiated forward by
    CasADi, gives the same tangent: the C assembly's derivative written by hand agrees
    with AD of an independent assembly."""
    rng = np.random.default_rng(8)
    kw = {"tau": None, **MAXWELL} if maxwell else {}
    c = rod_model(5, "clamped", "free", **kw)
    o = rod_model(5, "clamped", "free", backend="casadi", **kw)
    y = random_state(c, rng)
    if maxwell:
        y = with_internal_strains(c, y, rng)
    yp, dy, dyp = (rng.standard_normal(c.n) for _ in range(3))
    d = random_direction(c, rng)
    a = c.residual_tangent(0.0, y, yp, dy, dyp, d)
    b = o.residual_tangent(0.0, y, yp, dy, dyp, d)
    assert o.backend == "casadi"
    assert np.abs(a - b).max() <= 1e-10 * np.abs(a).max()
