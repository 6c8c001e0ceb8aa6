"""The bracketed root finder used for maxima and events, against closed-form roots."""

from __future__ import annotations

import math

import numpy as np
import pytest

from runtime.solvers.roots import bracketed_root


@pytest.mark.parametrize("f, a, b, root", [
    (lambda x: x * x - 2.0, 0.0, 2.0, math.sqrt(2.0)),
    (math.cos, 0.0, 3.0, math.pi / 2),
    (lambda x: (x - 0.3) ** 3, 0.0, 1.0, 0.3),                 # a triple root
    (lambda x: math.tanh(50 * (x - 0.7)), 0.0, 1.0, 0.7),       # steep
    (lambda x: np.polyval([1, -3, 0, 1e-3], x), 2.0, 4.0, None),  # a cubic, checked by value
])
def test_root_to_round_off(f, a, b, root):
    x = bracketed_root(f, a, b)
    assert a <= x <= b
    if root is not None:
        assert x == pytest.approx(root, abs=1e-10 if root == 0.3 else 4e-15)
    else:
        assert abs(f(x)) < 1e-12


def test_ends_and_bad_bracket():
    assert bracketed_root(lambda x: x - 1.0, 1.0, 2.0) == 1.0
    assert bracketed_root(lambda x: x - 2.0, 1.0, 2.0) == 2.0
    assert bracketed_root(lambda x: 1.0 - x, 0.0, 3.0) == pytest.approx(1.0, abs=1e-15)
    with pytest.raises(ValueError, match="no sign change"):
        bracketed_root(lambda x: x * x + 1.0, -1.0, 1.0)
