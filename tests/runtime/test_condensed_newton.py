"""The condensed Newton solve (kinematic rows eliminated: v by phi' = v, p by
p' = 1/2 p*(0, Omega)) equals the solve with the full band LU, on the rod's own iteration
matrices J = dF/dy + cj dF/dy' at random states, for several ends, a Maxwell rod and a
range of cj; and it is smaller."""

from __future__ import annotations

import numpy as np
import pytest

from runtime.solvers import _bdf_c
from tests.rods import MAXWELL, random_state, rod_model, with_internal_strains

pytestmark = pytest.mark.skipif(_bdf_c.load() is None, reason="no C compiler")


@pytest.mark.parametrize("kw", [dict(), dict(end="clamped"), dict(start="pinned", end="pinned"),
                                dict(start="free", end="clamped"), dict(tau=None, **MAXWELL)])
def test_condensed_solve_equals_the_full_solve(kw):
    rng = np.random.default_rng(2)
    m = rod_model(9, **kw)
    cond = _bdf_c.CondensedNewton.build(m, m.n, m.kl, m.ku, m.ldab)
    assert cond is not None and cond.nc == m.n - 3 * (m.N + 1) - 4 * m.N
    assert 2 * cond.klc + cond.kuc + 1 < m.ldab
    for cj in (1e1, 3e3, 1e6):
        y = random_state(m, rng)
        if m.branches:
            y = with_internal_strains(m, y, rng)
        yp = rng.standard_normal(m.n)
        ab = np.zeros((m.ldab, m.n), order="F")
        m.jacobian_band(0.0, y, yp, cj, ab)
        b = rng.standard_normal(m.n)
        assert cond.factor(ab) == 0
        x = cond.solve(ab, b)
        full, info = _bdf_c.band_solve(ab.copy(order="F"), m.kl, m.ku, b)
        assert info == 0
        np.testing.assert_allclose(x, full, rtol=1e-9, atol=1e-11 * np.abs(full).max())
