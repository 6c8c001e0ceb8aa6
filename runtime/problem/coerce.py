"""Coercion and validation of problem values: the one place that turns user input (TOML
tables, Python values, command-line strings) into checked numbers.

Every check raises :class:`runtime.errors.ParameterError` naming the value by its dotted
path in the problem (e.g. ``section.width``), the value and the allowed range.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from runtime.errors import ParameterError


def _is_number(v: Any) -> bool:
    return isinstance(v, (int, float, np.integer, np.floating)) and not isinstance(v, bool)


def number(path: str, value: Any, *, low: float = -math.inf, high: float = math.inf,
           low_incl: bool = True, high_incl: bool = True, allowed: str | None = None) -> float:
    """A finite float in [low, high] (bounds inclusive unless said otherwise)."""
    if not _is_number(value) or not math.isfinite(float(value)):
        raise ParameterError(path, value, allowed or _range(low, high, low_incl, high_incl))
    v = float(value)
    ok = (v >= low if low_incl else v > low) and (v <= high if high_incl else v < high)
    if not ok:
        raise ParameterError(path, value, allowed or _range(low, high, low_incl, high_incl))
    return v


def positive(path: str, value: Any, allowed: str | None = None) -> float:
    """A finite float > 0."""
    return number(path, value, low=0.0, low_incl=False, allowed=allowed)


def nonnegative(path: str, value: Any) -> float:
    """A finite float >= 0."""
    return number(path, value, low=0.0)


def integer(path: str, value: Any, low: int = -(2**62), high: int = 2**62) -> int:
    """An integer in [low, high] (a float, even 2.0, is not: TOML distinguishes them)."""
    if isinstance(value, bool):
        raise ParameterError(path, value, f"integer {low} ... {high}")
    if not isinstance(value, (int, np.integer)) or not low <= int(value) <= high:
        raise ParameterError(path, value, f"integer {low} ... {high}")
    return int(value)


def choice(path: str, value: Any, options: Sequence[str]) -> str:
    """One of the given strings."""
    if not isinstance(value, str) or value not in options:
        raise ParameterError(path, value, "one of " + ", ".join(repr(o) for o in options))
    return value


def boolean(path: str, value: Any) -> bool:
    if not isinstance(value, (bool, np.bool_)):
        raise ParameterError(path, value, "true or false")
    return bool(value)


def string(path: str, value: Any) -> str:
    if not isinstance(value, str) or not value:
        raise ParameterError(path, value, "a non-empty string")
    return value


def vector(path: str, value: Any, size: int = 3, *, nonzero: bool = False) -> tuple[float, ...]:
    """A tuple of ``size`` finite floats (non-zero length if asked)."""
    if isinstance(value, (str, bytes, Mapping)) or not hasattr(value, "__len__"):
        raise ParameterError(path, value, f"{size} finite numbers")
    vals = list(value)
    if len(vals) != size or not all(_is_number(v) and math.isfinite(float(v)) for v in vals):
        raise ParameterError(path, value, f"{size} finite numbers")
    out = tuple(float(v) for v in vals)
    if nonzero and not any(out):
        raise ParameterError(path, value, f"{size} finite numbers, not all zero")
    return out


def unit_vector(path: str, value: Any) -> tuple[float, float, float]:
    """A non-zero 3-vector, normalised."""
    v = np.array(vector(path, value, 3, nonzero=True))
    return tuple(float(c) for c in v / np.linalg.norm(v))


def table(path: str, value: Any) -> Mapping[str, Any]:
    """A TOML table (mapping)."""
    if not isinstance(value, Mapping):
        raise ParameterError(path, value, "a table")
    return value


def no_unknown_keys(path: str, mapping: Mapping[str, Any], allowed: Sequence[str]) -> None:
    """Reject keys not in ``allowed`` (names the first unknown one and the allowed ones)."""
    for key in mapping:
        if key not in allowed:
            where = f"{path}.{key}" if path else key
            raise ParameterError(where, mapping[key],
                                 "a known key; allowed here: " + ", ".join(allowed))


def exclusive(path: str, mapping: Mapping[str, Any], *groups: Sequence[str]) -> None:
    """At most one of the key groups may be present (e.g. tau vs tau_S/tau_B)."""
    present = [g for g in groups if any(k in mapping for k in g)]
    if len(present) > 1:
        names = [next(k for k in g if k in mapping) for g in present]
        raise ParameterError(f"{path}.{names[1]}" if path else names[1], mapping[names[1]],
                             f"not together with {names[0]!r}: give one of "
                             + " or ".join("/".join(g) for g in groups))


def _range(low: float, high: float, low_incl: bool, high_incl: bool) -> str:
    lo = ("[" if low_incl else "(") + (f"{low:g}" if math.isfinite(low) else "-inf")
    hi = (f"{high:g}" if math.isfinite(high) else "inf") + ("]" if high_incl else ")")
    return f"finite, {lo}, {hi}"
