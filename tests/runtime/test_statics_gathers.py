"""The static Newton loop's gathers (issue 33, the tiny sweep point) round exactly as the
NumPy formulas they replace: the retraction against ``quat_mul(p, quat_exp(dtheta))``
normalised, the Jacobian's rotation weights against :func:`_half_L`, and the whole band
against the same gather with :func:`_half_L`'s weights, bit for bit."""

from __future__ import annotations

import numpy as np
import pytest

from runtime.model.quaternion import quat_exp, quat_mul
from runtime.model.statics import RodStatics, _half_L, _rotate
from tests.rods import MAXWELL, random_state, rod_model


def _bits(a: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(a, dtype=float).view(np.int64)


def test_rotate_rounds_as_quat_mul_of_quat_exp():
    rng = np.random.default_rng(33)
    for trial in range(400):
        n = int(rng.integers(1, 40))
        p = rng.normal(size=(n, 4))
        p /= np.linalg.norm(p, axis=1)[:, None]
        th = rng.normal(size=(n, 3)) * 10.0 ** rng.uniform(-12, 0.5)
        th[rng.integers(0, n)] = 0.0 if trial % 3 == 0 else th[0]   # the series branch
        ref = quat_mul(p, quat_exp(th))
        ref = ref / np.linalg.norm(ref, axis=1)[:, None]
        assert np.array_equal(_bits(_rotate(p, th)), _bits(ref))


@pytest.mark.parametrize("kw", [dict(), dict(start="pinned", end="pinned"),
                                dict(tau=None, **MAXWELL)])
def test_retract_and_band_as_the_formulas(kw):
    m = rod_model(6, **kw)
    st = RodStatics(m)
    kl, ku = st.kl_static, st.ku_static
    for seed in range(3):
        rng = np.random.default_rng(seed)
        y = random_state(m, rng)
        dx = rng.normal(size=st.n_static) * 1e-3
        # the retraction as written before the gathers
        ref = np.array(y, dtype=float)
        ref[m.phi_index] += dx[st.phi_cols]
        p = quat_mul(ref[m.p_index], quat_exp(dx[st.theta_cols]))
        ref[m.p_index] = p / np.linalg.norm(p, axis=1)[:, None]
        assert np.array_equal(_bits(st.static_retract(y, dx)), _bits(ref))
        # the weights: equal values (zeros may differ in sign only)
        y0 = st.at_rest(y)
        w = st._half_L_weights(y0)
        w_ref = np.concatenate([[1.0], _half_L(y0[m.p_index]).ravel()])
        assert np.array_equal(w, w_ref)
        # the band from those weights, bit for bit
        ab = np.zeros((2 * kl + ku + 1, st.n_static), order="F")
        st.static_jacobian_band(y, ab)
        src, widx, dst, fixed = st._gather_plan()
        full = np.zeros((m.ldab, m.n), order="F")
        m.jacobian_band2(st.time, y0, m._zeros, 1.0, 0.0, full)
        flat = np.bincount(dst, weights=full.ravel(order="F")[src] * w_ref[widx],
                           minlength=ab.size)
        flat[fixed] += 1.0
        assert np.array_equal(_bits(ab), _bits(flat.reshape(ab.shape, order="F")))
        # the residual through the reused buffers, as from a fresh state at rest
        r1, r2 = np.empty(st.n_static), np.empty(st.n_static)
        st.static_residual(y, r1)
        full_r = np.empty(m.n)
        m.residual(st.time, st.at_rest(y), m._zeros, full_r)
        r2[:] = full_r[st.static_rows]
        r2[~st._rowmask] = 0.0
        assert np.array_equal(_bits(r1), _bits(r2))
