"""Validation of section input: the few checks the section layer needs, raising the
project's :class:`runtime.errors.ParameterError` with the dotted key path (e.g.
``section.regions[1].shape.radius``). The problem layer's ``runtime/problem/coerce.py`` does
the same for the problem tables; it sits above this package, so its helpers are not
imported here."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from runtime.errors import ParameterError


def is_number(v: Any) -> bool:
    return isinstance(v, (int, float, np.integer, np.floating)) and not isinstance(v, bool)


def number(path: str, value: Any, allowed: str = "a finite number", *,
           low: float = -math.inf, high: float = math.inf, low_incl: bool = True,
           high_incl: bool = True) -> float:
    """A finite float in [low, high] (bounds inclusive unless said otherwise)."""
    if not is_number(value) or not math.isfinite(float(value)):
        raise ParameterError(path, value, allowed)
    v = float(value)
    if not ((v >= low if low_incl else v > low) and (v <= high if high_incl else v < high)):
        raise ParameterError(path, value, allowed)
    return v


def positive(path: str, value: Any, unit: str) -> float:
    return number(path, value, f"a finite number > 0 ({unit})", low=0.0, low_incl=False)


def nonnegative(path: str, value: Any, unit: str) -> float:
    return number(path, value, f"a finite number >= 0 ({unit})", low=0.0)


def table(path: str, value: Any) -> Mapping[str, Any]:
    if not isinstance(value, Mapping):
        raise ParameterError(path, value, "a table")
    return value


def string(path: str, value: Any) -> str:
    if not isinstance(value, str) or not value:
        raise ParameterError(path, value, "a non-empty string")
    return value


def no_unknown_keys(path: str, m: Mapping[str, Any], allowed: Sequence[str]) -> None:
    for key in m:
        if key not in allowed:
            raise ParameterError(f"{path}.{key}", m[key],
                                 "a known key; allowed here: " + ", ".join(allowed))


def required(path: str, m: Mapping[str, Any], key: str, allowed: str) -> Any:
    if key not in m:
        raise ParameterError(f"{path}.{key}", None, allowed)
    return m[key]


#: lengths of a section (m), as the problem's section dimensions take them: beyond them
#: the powers of a length in the section's integrals leave the normal floating-point range
LENGTH_MIN, LENGTH_MAX = 1e-30, 1e30


def length(path: str, value: Any) -> float:
    """A length in m, LENGTH_MIN ... LENGTH_MAX."""
    return number(path, value, f"a length {LENGTH_MIN:g} ... {LENGTH_MAX:g} m (> 0; beyond "
                  "any section, its powers must stay normal floating-point numbers)",
                  low=LENGTH_MIN, high=LENGTH_MAX)


def point(path: str, value: Any) -> tuple[float, float]:
    """A point (x1, x2) in m, each coordinate at most LENGTH_MAX in size."""
    if isinstance(value, (str, bytes, Mapping)) or not hasattr(value, "__len__") \
            or len(value) != 2 or not all(is_number(v) and abs(float(v)) <= LENGTH_MAX
                                          for v in value):
        raise ParameterError(path, value, f"two finite numbers [x1, x2] in m, each at most "
                             f"{LENGTH_MAX:g} m in size")
    return float(value[0]), float(value[1])


def points(path: str, value: Any, minimum: int = 3) -> tuple[tuple[float, float], ...]:
    """A list of at least ``minimum`` points [[x1, x2], ...] in m."""
    if isinstance(value, (str, bytes, Mapping)) or not hasattr(value, "__len__") \
            or len(value) < minimum:
        raise ParameterError(path, value, f"a list of at least {minimum} points "
                             "[[x1, x2], ...] in m")
    return tuple(point(f"{path}[{i}]", p) for i, p in enumerate(value))


def matrix6(path: str, value: Any, unit: str) -> np.ndarray:
    """A 6x6 matrix of finite numbers (a list of 6 rows of 6)."""
    allowed = f"a 6x6 matrix (6 rows of 6 finite numbers) in {unit}, Voigt order 11, 22, " \
              "33, 23, 13, 12"
    if isinstance(value, (str, bytes, Mapping)) or not hasattr(value, "__len__") \
            or len(value) != 6:
        raise ParameterError(path, value, allowed)
    rows = []
    for i, row in enumerate(value):
        if isinstance(row, (str, bytes, Mapping)) or not hasattr(row, "__len__") \
                or len(row) != 6 or not all(is_number(v) and math.isfinite(float(v))
                                            for v in row):
            raise ParameterError(f"{path}[{i}]", row, allowed)
        rows.append([float(v) for v in row])
    return np.array(rows)
