"""Root of a scalar function on a bracket, to round-off (Illinois regula falsi).

Why not :func:`scipy.optimize.brentq`: importing ``scipy.optimize`` costs about 0.15 s
(it pulls in linprog, shgo, sparse.linalg and docstring processing), a sixth of the whole
``kvrod simulate`` process for the paper's cantilever, only to locate the maxima of the
tip on each step's interpolant. The functions here are smooth polynomials on short
intervals, where the Illinois variant of regula falsi converges superlinearly (order
about 1.44) and keeps the bracket, so it is as robust as bisection and needs a handful of
evaluations.
"""

from __future__ import annotations

import math
from collections.abc import Callable


def bracketed_root(f: Callable[[float], float], a: float, b: float,
                   fa: float | None = None, fb: float | None = None, *,
                   xtol: float = 0.0, max_iter: int = 200) -> float:
    """A root of ``f`` in ``[a, b]`` given ``f(a)``, ``f(b)`` of opposite signs (or zero).

    Stops when the bracket is narrower than ``xtol`` plus four ulps of its ends, or at a
    zero. Raises ValueError when the ends have the same sign.
    """
    fa = f(a) if fa is None else fa
    fb = f(b) if fb is None else fb
    if fa == 0.0:
        return a
    if fb == 0.0:
        return b
    if math.copysign(1.0, fa) == math.copysign(1.0, fb):
        raise ValueError(f"no sign change on [{a!r}, {b!r}]: f = {fa!r}, {fb!r}")
    side = 0
    for _ in range(max_iter):
        tol = xtol + 4.0 * math.ulp(max(abs(a), abs(b)))
        if abs(b - a) <= tol:
            break
        c = (a * fb - b * fa) / (fb - fa)
        if not (min(a, b) < c < max(a, b)):     # round-off at the ends: bisect
            c = 0.5 * (a + b)
        fc = f(c)
        if fc == 0.0:
            return c
        if math.copysign(1.0, fc) == math.copysign(1.0, fb):
            b, fb = c, fc
            if side == -1:        # the same end twice: halve the other end's value
                fa *= 0.5
            side = -1
        else:
            a, fa = c, fc
            if side == 1:
                fb *= 0.5
            side = 1
    return a if abs(fa) < abs(fb) else b
