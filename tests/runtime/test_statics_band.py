"""The static Jacobian gathered into band storage (RodStatics.static_jacobian_band, NumPy
gather plan) equals the band of the sparse product S J T (jacobian_csr) on random states,
for every kind of end, and for a Maxwell rod (whose state carries internal strains)."""

from __future__ import annotations

import numpy as np
import pytest

from runtime.model.statics import RodStatics
from tests.rods import MAXWELL, random_state, rod_model


@pytest.mark.parametrize("kw", [dict(), dict(end="clamped"),
                                dict(start="pinned", end="pinned"),
                                dict(start="free", end="clamped"),
                                dict(tau=None, **MAXWELL)])
def test_band_gather_equals_the_sparse_product(kw):
    m = rod_model(7, **kw)
    st = RodStatics(m)
    kl, ku = st.kl_static, st.ku_static
    for seed in range(3):
        y = random_state(m, np.random.default_rng(seed))
        ab = np.zeros((2 * kl + ku + 1, st.n_static), order="F")
        st.static_jacobian_band(y, ab)
        J = st.jacobian_csr(y).toarray()
        ref = np.zeros_like(ab)
        for j in range(J.shape[1]):
            for i in range(J.shape[0]):
                if J[i, j] != 0.0:
                    assert -ku <= i - j <= kl, "static Jacobian outside its band"
                    ref[kl + ku + i - j, j] = J[i, j]
        np.testing.assert_allclose(ab, ref, rtol=1e-13, atol=1e-13 * np.abs(J).max())
