"""O(h^2) convergence of the clamped cantilever (half-length clamp joint, docs/design.md
section 7):
static small-deflection tip displacement vs Timoshenko, and the first frequency."""

from __future__ import annotations

from dataclasses import asdict

import numpy as np
import scipy.linalg as sl
import scipy.sparse.linalg as spl

from references import sections
from runtime.model.statics import RodStatics
from tests.rods import rod_model

E, NU, RHO, LEN, W, H = 1e6, 0.3, 1000.0, 0.3, 0.01, 0.01


class _Ref:
    """Section constants and moduli from the independent references."""

    @staticmethod
    def rectangle_section(w: float, h: float, nu: float) -> dict[str, float]:
        return asdict(sections.rectangle(w, h, nu))

    @staticmethod
    def shear_modulus(E: float, nu: float) -> float:
        return E / (2 * (1 + nu))


def _constitutive() -> _Ref:
    return _Ref()


def _model(N, start="clamped", end="free", loads=()):
    return rod_model(N, start, end, loads=list(loads), tau=0.0,
                     section={"kind": "rectangle", "width": W, "height": H},
                     density=RHO, youngs_modulus=E, poisson_ratio=NU)


def _linear_static_tip(m) -> float:
    """One Newton step from the reference: the linear static tip x."""
    st = RodStatics(m)
    with m.statics():
        y = m.initial_state()
        r = np.empty(st.n_static)
        st.static_residual(y, r)
        dx = spl.spsolve(st.static_jacobian_sparse(y), -r)
        return m.tip_position(st.static_retract(y, dx))[0]


def _tip_linear(N, F):
    return _linear_static_tip(_model(N, loads=[{"kind": "force", "vector": [F, 0.0, 0.0]}]))


def test_static_tip_deflection_converges_at_second_order_to_timoshenko():
    F = 1e-5
    c = _constitutive()
    s = c.rectangle_section(W, H, NU)
    G = c.shear_modulus(E, NU)
    exact = F * LEN**3 / (3 * E * s["I2"]) + F * LEN / (s["kappa_1"] * G * s["A"])
    errs = [_tip_linear(N, F) - exact for N in (5, 10, 20, 40)]
    orders = np.log2(np.abs(errs[:-1]) / np.abs(errs[1:]))
    assert np.all(np.abs(orders - 2.0) < 0.05), orders
    assert abs(errs[-1]) < 1e-3 * exact


def _first_frequency(N):
    m = _model(N)
    y, yp = m.initial_state(), np.zeros(m.n)
    A = m.dF_dy_sparse(0.0, y, yp).toarray()
    B = m.dF_dyp_sparse(0.0, y, yp).toarray()
    lam = sl.eigvals(A, -B)  # dF/dy v + lam dF/dy' v = 0
    lam = lam[np.isfinite(lam)]
    om = np.abs(lam.imag[np.abs(lam.imag) > 1e-6])
    return om.min()


def test_first_frequency_converges_at_second_order():
    w = [_first_frequency(N) for N in (10, 20, 40)]
    ratio = (w[1] - w[0]) / (w[2] - w[1])
    assert abs(np.log2(ratio) - 2.0) < 0.1, ratio
    c = _constitutive()
    s = c.rectangle_section(W, H, NU)
    eb = 1.8751041**2 * np.sqrt(E * s["I2"] / (RHO * s["A"] * LEN**4))
    w_inf = w[2] + (w[2] - w[1]) / 3  # Richardson
    assert abs(w_inf / eb - 1) < 2e-3  # Timoshenko corrections are ~1e-4 here


def test_gravity_load_converges_at_second_order_to_timoshenko():
    """Uniform load through the lumped nodal masses: q L^4/(8 EI) + q L^2/(2 kappa G A)."""
    g = 1e-3
    c = _constitutive()
    s = c.rectangle_section(W, H, NU)
    G = c.shear_modulus(E, NU)
    q = RHO * s["A"] * g
    exact = q * LEN**4 / (8 * E * s["I2"]) + q * LEN**2 / (2 * s["kappa_1"] * G * s["A"])
    errs = []
    for N in (5, 10, 20):
        m = _model(N, loads=[{"kind": "gravity", "vector": [g, 0.0, 0.0]}])
        errs.append(_linear_static_tip(m) - exact)
    orders = np.log2(np.abs(errs[:-1]) / np.abs(errs[1:]))
    assert np.all(np.abs(orders - 2.0) < 0.05), orders


def test_pinned_pinned_first_frequency_second_order_and_timoshenko_limit():
    def first(N):
        m = _model(N, "pinned", "pinned")
        y, yp = m.initial_state(), np.zeros(m.n)
        A = m.dF_dy_sparse(0.0, y, yp).toarray()
        B = m.dF_dyp_sparse(0.0, y, yp).toarray()
        lam = sl.eigvals(A, -B)
        lam = lam[np.isfinite(lam)]
        return np.abs(lam.imag[np.abs(lam.imag) > 1e-3]).min()

    w = [first(N) for N in (10, 20, 40)]
    assert abs(np.log2((w[1] - w[0]) / (w[2] - w[1])) - 2.0) < 0.1
    c = _constitutive()
    s = c.rectangle_section(W, H, NU)
    G = c.shear_modulus(E, NU)
    eb = np.pi**2 * np.sqrt(E * s["I2"] / (RHO * s["A"] * LEN**4))
    # Timoshenko: omega ~ omega_EB (1 - pi^2/2 (r/L)^2 (1 + E/(kappa G))), r^2 = I/A
    tim = eb * (1 - np.pi**2 / 2 * s["I2"] / s["A"] / LEN**2 * (1 + E / (s["kappa_1"] * G)))
    w_inf = w[2] + (w[2] - w[1]) / 3
    assert abs(w_inf / tim - 1) < 3e-4
