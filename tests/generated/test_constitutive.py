"""generated/constitutive.py agrees with the SymPy formula table; it validates input."""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp
from hypothesis import given, settings
from hypothesis import strategies as st

from derive import formulas
from derive.formulas import in_material_parameters
from derive.symbols import I1, I2, I3, A, E, eta, kappa_1, kappa_2, kappa_3, nu, tau_B, tau_S, zeta
from generated import constitutive as gc

f = formulas()
MAT = (E, nu, tau_S, tau_B, A, I1, I2, I3, kappa_1, kappa_2, kappa_3)

taus = st.one_of(st.just(0.0), st.floats(1e-6, 1.0))
points = st.tuples(st.floats(1e3, 1e11), st.floats(-0.99, 0.5), taus, taus,
                   st.floats(1e-6, 1e-2), st.floats(1e-12, 1e-6), st.floats(1e-12, 1e-6),
                   st.floats(1e-12, 1e-5), st.floats(0.1, 1), st.floats(0.1, 1), st.floats(0.1, 1))


#: the SymPy matrices, lambdified with mpmath (an evaluation path independent of the template)
REFERENCE = {k: sp.lambdify(MAT, in_material_parameters(f[k]), "mpmath")
             for k in ("C_F", "C_M", "V_F", "V_M", "V_F_naive", "V_M_naive")}


def close(a, b):
    return np.allclose(np.asarray(a, float), np.asarray(b.tolist(), float), rtol=1e-12, atol=0)


@settings(max_examples=40, deadline=None)
@given(points)
def test_matrices_match_sympy(p):
    CF, CM = gc.stiffness_matrices(p[0], p[1], *p[4:])
    assert close(CF, REFERENCE["C_F"](*p)) and close(CM, REFERENCE["C_M"](*p))
    for route, kF, kM in (("consistent", "V_F", "V_M"), ("naive", "V_F_naive", "V_M_naive")):
        VF, VM = gc.damping_matrices(*p, route=route)
        assert close(VF, REFERENCE[kF](*p)), (route, VF, REFERENCE[kF](*p))
        assert close(VM, REFERENCE[kM](*p)), (route, VM, REFERENCE[kM](*p))


@settings(max_examples=40, deadline=None)
@given(st.floats(0, 10), st.floats(0.01, 10), st.floats(-0.99, 0.5))
def test_scalars_match_sympy(z, e, n):
    v = {zeta: z, eta: e, nu: n, tau_B: z, tau_S: e}
    assert np.isclose(gc.extensional_viscosity(z, e, n), float(f["eta_E"].subs(v)), rtol=1e-12)
    assert np.isclose(gc.extensional_viscosity_naive(z, e, n), float(f["eta_E_naive"].subs(v)),
                      rtol=1e-12)
    assert np.isclose(gc.in_plane_dissipation(z, e, n), float(f["in_plane_dissipation"].subs(v)),
                      rtol=1e-12, atol=1e-14)
    assert np.isclose(gc.retardation_time_extension(z, e, n), float(f["tau_E"].subs(v)), rtol=1e-12)


def test_damping_equals_stiffness_times_taus_paper_example():
    """Sect. 5: tau_B = tau_S = tau -> V = tau C for both routes."""
    sec = gc.rectangle_section(0.01, 0.01, 0.3)
    args = (1e6, 0.3, 0.04, 0.04, sec["A"], sec["I1"], sec["I2"], sec["I3"],
            sec["kappa_1"], sec["kappa_2"], sec["kappa_3"])
    CF, CM = gc.stiffness_matrices(1e6, 0.3, *args[4:])
    for route in ("consistent", "naive"):
        VF, VM = gc.damping_matrices(*args, route=route)
        assert np.allclose(VF, 0.04 * CF, rtol=1e-14) and np.allclose(VM, 0.04 * CM, rtol=1e-14)


def test_sections():
    sq = gc.rectangle_section(0.01, 0.01, 0.3)
    assert np.isclose(sq["I1"], 1e-8 / 12) and np.isclose(sq["A"], 1e-4)
    assert np.isclose(sq["kappa_3"], 0.843462, atol=2e-6)
    assert np.isclose(sq["kappa_1"], 10 * 1.3 / (12 + 3.3))
    c = gc.circle_section(0.02, 0.3)
    assert np.isclose(c["kappa_3"], 1.0) and np.isclose(c["kappa_1"], 6 * 1.3 / (7 + 1.8))
    e = gc.ellipse_section(0.02, 0.01, 0.3)          # a along xi2 -> I1 = pi a^3 b / 4
    assert np.isclose(e["I1"], np.pi * 0.02**3 * 0.01 / 4)
    assert e["kappa_3"] < 1
    thin = gc.rectangle_section(1.0, 0.01, 0.3)      # thin strip: J -> b d^3 / 3 (1 - 0.63 d/b)
    assert np.isclose(thin["J_T"], 1.0 * 0.01**3 / 3 * (1 - 0.630 * 0.01), rtol=1e-3)
    assert np.isclose(gc.rectangle_section(0.02, 0.01, 0.3)["J_T"],
                      gc.rectangle_section(0.01, 0.02, 0.3)["J_T"], rtol=1e-13)


def test_circle_torsion_factor_is_one_for_every_radius():
    """kappa_3 = J_T / I3 is exactly 1 for a circle (the derived quotient, not the ratio of
    the rounded constants, which exceeded the bound 1 by an ulp and was rejected)."""
    for r in np.geomspace(1e-6, 10.0, 200):
        k = gc.circle_section(float(r), 0.3)
        assert k["kappa_3"] == 1.0
        gc.stiffness_matrices(2.1e11, 0.3, k["A"], k["I1"], k["I2"], k["I3"], k["kappa_1"],
                              k["kappa_2"], k["kappa_3"])


def test_tube_section():
    """Tube against the difference of two solid circles, the solid limit and thin walls."""
    t = gc.tube_section(0.02, 0.015, 0.3)
    outer, inner = gc.circle_section(0.02, 0.3), gc.circle_section(0.015, 0.3)
    for key in ("A", "I1", "I2", "I3", "J_T"):
        assert np.isclose(t[key], outer[key] - inner[key], rtol=1e-13), key
    assert t["kappa_3"] == 1.0 and set(t) == set(outer)
    m = 0.75
    assert np.isclose(t["kappa_1"], 6 * 1.3 * (1 + m**2) ** 2
                      / ((7 + 1.8) * (1 + m**2) ** 2 + (20 + 3.6) * m**2))
    solid = gc.tube_section(0.02, 0.0, 0.3)
    for key in outer:
        assert np.isclose(solid[key], outer[key], rtol=1e-13), key
    thin = gc.tube_section(1.0, 1.0 - 1e-6, 0.3)       # Cowper's thin-walled tube
    assert np.isclose(thin["kappa_1"], 2 * 1.3 / 4.9, rtol=1e-5)
    assert np.isclose(thin["A"], 2 * np.pi * 1e-6, rtol=1e-5)
    arr = gc.tube_section(np.array([0.02, 0.03]), np.array([0.0, 0.01]), 0.3)
    assert arr["A"].shape == (2,) and np.allclose(arr["kappa_3"], 1.0)


@pytest.mark.parametrize(("call", "match"), [
    (lambda: gc.shear_modulus(-1.0, 0.3), r"'E' = -1.0 is outside the allowed range: \(0, inf\) Pa"),
    (lambda: gc.shear_modulus(1.0, 0.6), r"'nu' = 0.6 .*\(-1, 0.5\]"),
    (lambda: gc.bulk_modulus(1.0, 0.5), r"'nu' = 0.5 .*\(-1, 0.5\)"),
    (lambda: gc.shear_modulus(float("nan"), 0.3), "'E' = nan"),
    (lambda: gc.extensional_viscosity(-1.0, 1.0, 0.3), "'zeta' = -1.0"),
    (lambda: gc.retardation_time_extension(0.1, -0.1, 0.3), "'tau_S' = -0.1"),
    (lambda: gc.rectangle_section(0.0, 0.01, 0.3), "'width' = 0.0"),
    (lambda: gc.ellipse_section(0.01, float("inf"), 0.3), "'b' = inf"),
    (lambda: gc.tube_section(0.0, 0.0, 0.3), r"'r_outer' = 0.0 .*\(0, inf\) m"),
    (lambda: gc.tube_section(0.02, -0.001, 0.3), r"'r_inner' = -0.001 .*\[0, inf\) m"),
    (lambda: gc.tube_section(0.02, 0.02, 0.3), r"'r_inner' = 0.02 .*\[0, r_outer\)"),
    (lambda: gc.tube_section(np.array([0.02, 0.01]), np.array([0.01, 0.03]), 0.3),
     r"'r_inner' = 0.03 .*\[0, r_outer\) = \[0, 0.01\) m"),
    (lambda: gc.tube_section(0.02, 0.01, 0.7), "'nu' = 0.7"),
    (lambda: gc.stiffness_matrices(1.0, 0.3, 1.0, 1.0, 1.0, 2.0, 1.2, 1.0, 1.0), "'kappa_1' = 1.2"),
    (lambda: gc.damping_matrices(1.0, 0.3, 0.1, 0.1, 1, 1, 1, 2, route="bogus"), "route"),
])
def test_bad_parameters(call, match):
    with pytest.raises(gc.ParameterError, match=match):
        call()


def test_incompressible_limit_is_finite():
    VF, VM = gc.damping_matrices(1e6, 0.5, 0.04, 0.01, 1e-4, 1e-9, 1e-9, 2e-9)
    assert np.isclose(VF[2, 2], 1e6 * 1e-4 * 0.04)       # tau_E = tau_S at nu = 1/2
    VFn, _ = gc.damping_matrices(1e6, 0.5, 0.04, 0.01, 1e-4, 1e-9, 1e-9, 2e-9, route="naive")
    assert VFn[2, 2] < VF[2, 2]
