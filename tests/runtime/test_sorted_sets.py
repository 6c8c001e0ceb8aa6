"""runtime.sorted_sets: NumPy's np.unique and np.union1d, without numpy.ma."""

from __future__ import annotations

import numpy as np
import pytest

from runtime.sorted_sets import sorted_union, sorted_unique


@pytest.mark.parametrize("a", [np.array([]), np.array([3.0]), np.array([2.0, 1.0, 2.0, 0.5]),
                               np.array([5, 5, 5, 1, 9, 1], dtype=np.int32),
                               np.array([0.002, 0.01, 0.05, 0.01, -0.0, 0.0])])
def test_sorted_unique_is_np_unique(a):
    got = sorted_unique(a)
    assert got.dtype == a.dtype
    np.testing.assert_array_equal(got, np.unique(a))


def test_sorted_union_is_np_union1d():
    a, b = np.array([0.05, 0.002, 0.01]), np.array([0.01, 0.3, 0.002])
    np.testing.assert_array_equal(sorted_union(a, b), np.union1d(a, b))
    np.testing.assert_array_equal(sorted_union(a[:0], b[:0]), np.union1d(a[:0], b[:0]))
