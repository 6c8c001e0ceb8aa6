"""The parameters of a fit: start values, bounds and the scaled coordinates the solver sees.

A physical parameter theta that the problem file requires to be positive (moduli, times,
densities, section dimensions: the key catalogue's range "> 0" or ">= a" with a >= 0) is
fitted in log scale, ``u = ln(theta / theta_0)`` with theta_0 its start value: a step in
u is a relative change, the parameter can never leave its sign, and moduli (1e6 Pa) and
times (0.05 s) become numbers of the same size. Any other parameter (a Poisson's ratio, a
load component) is fitted as ``u = (theta - theta_0) / scale`` with ``scale`` its start's
size (or its range's width, or 1). Both start at u = 0.

Bounds come from the key catalogue (:data:`runtime.problem.keys.KEYS`, the ranges that
``kvrod problem-keys`` prints; :func:`catalogue_range`) and, for the retardation times of a
Kelvin-Voigt rod, from the problem itself (the largest tau the rod accepts,
``schema.VISCOUS_RATE_MAX`` over its stiffest element mode's omega_max^2). ``--bounds``
may narrow them, never widen them.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from runtime.errors import ParameterError

_NUM = r"[-+]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][-+]?\d+)?(?:/\d+)?"


def _number(text: str) -> float:
    if "/" in text:
        a, b = text.split("/")
        return float(a) / float(b)
    return float(text)


@dataclass(frozen=True)
class Range:
    """An allowed interval ``low ... high`` (either end may be infinite; ``open_low``:
    low itself excluded)."""

    low: float = -math.inf
    high: float = math.inf
    open_low: bool = False
    open_high: bool = False

    def contains(self, v: float) -> bool:
        lo_ok = v > self.low if self.open_low else v >= self.low
        hi_ok = v < self.high if self.open_high else v <= self.high
        return lo_ok and hi_ok

    def describe(self) -> str:
        lo = "" if self.low == -math.inf else f"{self.low:g} {'<' if self.open_low else '<='} "
        hi = "" if self.high == math.inf else f" {'<' if self.open_high else '<='} {self.high:g}"
        if not lo and not hi:
            return "any number"
        return f"{lo}value{hi}"

    @property
    def positive(self) -> bool:
        """Only values > 0 make sense (log scale): a lower bound >= 0."""
        return self.low >= 0.0


def parse_range(allowed: str) -> Range:
    """A :class:`Range` from the catalogue's ``allowed`` text: "> 0", ">= 1e-12",
    "1e-30 ... 1e30", "-1 < nu <= 1/2", "0 < angle <= 360", "-90 ... 90", "a number";
    anything else (text that names no number range) is unbounded."""
    head = re.split(r"[;(,]", allowed, maxsplit=1)[0].strip()
    m = re.fullmatch(rf"(>=?)\s*({_NUM})", head)
    if m:
        return Range(_number(m.group(2)), math.inf, open_low=m.group(1) == ">")
    m = re.fullmatch(rf"({_NUM})\s*\.\.\.\s*(<?)\s*({_NUM})", head)
    if m:
        return Range(_number(m.group(1)), _number(m.group(3)), open_high=m.group(2) == "<")
    m = re.fullmatch(rf"({_NUM})\s*(<=?)\s*[A-Za-z_]\w*\s*(<=?)\s*({_NUM})", head)
    if m:
        return Range(_number(m.group(1)), _number(m.group(4)), open_low=m.group(2) == "<",
                     open_high=m.group(3) == "<")
    return Range()


def catalogue_key(path: str) -> tuple[str, str]:
    """(table, name) of the key catalogue entry of a dotted parameter path: array indices
    dropped (``material.branches.0.tau`` -> ("material.branches", "tau")), an assembly's
    ``rods.NAME.`` prefix and a zone's ``zones.K.`` prefix dropped (their keys are the
    problem's), ``materials.steel.tau`` -> ("materials.NAME", "tau"),
    ``loads.K.time.KEY`` -> ("<time>", KEY), a vector component (``loads.0.vector.1``) ->
    its vector."""
    parts = path.split(".")
    if len(parts) > 2 and parts[0] == "rods":
        parts = parts[2:]
    if len(parts) > 2 and parts[0] == "materials":
        parts[1] = "NAME"
    parts = [p for p in parts if not p.isdigit()]
    if len(parts) > 1 and parts[0] == "zones" and parts[1] in ("material", "section"):
        parts = parts[1:]
    if "time" in parts[:-1] or "translation_time" in parts[:-1] or "rotation_time" in parts[:-1]:
        return "<time>", parts[-1]
    return ".".join(parts[:-1]), parts[-1]


def catalogue_range(path: str) -> tuple[Range, str]:
    """(allowed range, unit) of a parameter's key in the catalogue; unbounded and "-" for
    a key the catalogue does not list as a number range."""
    from runtime.problem.keys import KEYS

    table, name = catalogue_key(path)
    for k in KEYS:
        if k.table == table and k.name == name:
            return parse_range(k.allowed), k.unit
    return Range(), "-"


@dataclass(frozen=True)
class ParameterSpec:
    """One fitted parameter: ``name`` as the user wrote it, its key ``path``, ``start``
    value (SI), allowed ``bounds`` (:class:`Range`), ``log`` scale or not, ``unit``, and
    ``scale`` (linear parameters: the size of a unit step of u)."""

    name: str
    path: str
    start: float
    bounds: Range
    log: bool
    unit: str = "-"
    scale: float = 1.0

    # -- scaled coordinates -----------------------------------------------------------------
    def to_u(self, theta: float) -> float:
        if self.log:
            return math.log(theta / self.start) if theta > 0 else -math.inf
        return (theta - self.start) / self.scale

    def from_u(self, u: float) -> float:
        if self.log:
            with np.errstate(over="ignore"):
                return float(self.start * np.exp(u))
        return self.start + self.scale * u

    def dtheta_du(self, theta: float) -> float:
        """d theta / d u at theta (the Jacobian's column factor)."""
        return theta if self.log else self.scale

    def u_bounds(self) -> tuple[float, float]:
        lo, hi = self.bounds.low, self.bounds.high
        return (self.to_u(lo) if (not self.log or lo > 0) and math.isfinite(lo) else -math.inf,
                self.to_u(hi) if math.isfinite(hi) else math.inf)

    @property
    def coordinates(self) -> str:
        """The scaled coordinate in words (fit.json, the design doc)."""
        return (f"ln({self.name} / {self.start:.6g})" if self.log
                else f"({self.name} - {self.start:.6g}) / {self.scale:.6g}")


def make_spec(name: str, path: str, start: float, *, limit: Range | None = None,
              bounds: tuple[float | None, float | None] | None = None) -> ParameterSpec:
    """The :class:`ParameterSpec` of a parameter (ParameterError naming it when its start or
    the asked bounds are outside what the catalogue allows).

    ``limit``: a further range the problem imposes (a Kelvin-Voigt rod's largest tau);
    ``bounds``: (low, high) from ``--bounds`` (None: keep the catalogue's end).
    """
    rng, unit = catalogue_range(path)
    if limit is not None:
        rng = Range(max(rng.low, limit.low), min(rng.high, limit.high),
                    rng.open_low if rng.low >= limit.low else limit.open_low,
                    rng.open_high if rng.high <= limit.high else limit.open_high)
    allowed = rng
    if bounds is not None:
        lo, hi = bounds
        for v in (lo, hi):
            if v is not None and not (math.isfinite(v) and allowed.contains(v)):
                raise ParameterError(f"--bounds {name}", v,
                                     f"{allowed.describe()} ({path}'s range)")
        if lo is not None and hi is not None and not lo < hi:
            raise ParameterError(f"--bounds {name}", f"{lo:g}:{hi:g}", "LOW < HIGH")
        rng = Range(rng.low if lo is None else lo, rng.high if hi is None else hi,
                    rng.open_low if lo is None else False,
                    rng.open_high if hi is None else False)
    if not (math.isfinite(start) and rng.contains(start)):
        raise ParameterError(f"{name} (start)", start, f"{rng.describe()} [{unit}]"
                             + (" (the --bounds)" if bounds is not None else
                                f" ({path}'s range)"))
    log = rng.positive
    if log and start <= 0:
        raise ParameterError(f"{name} (start)", start, f"> 0 [{unit}]: a positive parameter "
                             f"is fitted in log scale; give --start {name}=VALUE")
    if log:
        scale = 1.0
    elif start != 0:
        scale = abs(start)
    elif math.isfinite(rng.high - rng.low):
        scale = 0.1 * (rng.high - rng.low)
    else:
        scale = 1.0
    return ParameterSpec(name, path, float(start), rng, log, unit, scale)


def parse_assignments(items: list[str], flag: str, names: list[str]
                      ) -> dict[str, str]:
    """``P=TEXT`` items of a repeatable flag, each P one of the fitted ``names``
    (ParameterError naming the flag otherwise)."""
    out: dict[str, str] = {}
    for item in items:
        key, sep, text = item.partition("=")
        key = key.strip()
        if not sep or not text.strip():
            raise ParameterError(flag, item, "P=VALUE with P one of the fitted parameters")
        if key not in names:
            raise ParameterError(flag, key, f"one of the fitted parameters ({', '.join(names)})")
        if key in out:
            raise ParameterError(flag, key, "each parameter once")
        out[key] = text.strip()
    return out


def parse_start(items: list[str], names: list[str]) -> dict[str, float]:
    """``--start P=V`` -> {P: V} (V a finite number)."""
    out = {}
    for k, text in parse_assignments(items, "--start", names).items():
        try:
            v = float(text)
        except ValueError:
            v = math.nan
        if not math.isfinite(v):
            raise ParameterError(f"--start {k}", text, "a finite number (SI units)")
        out[k] = v
    return out


def parse_bounds(items: list[str], names: list[str]
                 ) -> dict[str, tuple[float | None, float | None]]:
    """``--bounds P=LO:HI`` -> {P: (LO, HI)}; an empty LO or HI keeps the catalogue's end."""
    out = {}
    for k, text in parse_assignments(items, "--bounds", names).items():
        lo_t, sep, hi_t = text.partition(":")
        if not sep:
            raise ParameterError(f"--bounds {k}", text, "LOW:HIGH (either may be empty)")
        vals = []
        for t in (lo_t, hi_t):
            if not t.strip():
                vals.append(None)
                continue
            try:
                vals.append(float(t))
            except ValueError:
                raise ParameterError(f"--bounds {k}", text, "LOW:HIGH, numbers in SI "
                                     "units (either may be empty)") from None
        out[k] = (vals[0], vals[1])
    return out


def kelvin_voigt_tau_limit(problem) -> Range:
    """The retardation times a Kelvin-Voigt rod (every rod of an assembly) accepts:
    0 ... VISCOUS_RATE_MAX / omega_max^2 (``Problem.element_rates``; the schema refuses a
    larger tau, so the fit never tries one)."""
    from runtime.problem.schema import VISCOUS_RATE_MAX

    rods = getattr(problem, "rods", None)
    problems = list(rods.values()) if isinstance(rods, Mapping) else [problem]
    w2 = max(p.element_rates()[0] for p in problems)
    return Range(0.0, VISCOUS_RATE_MAX / w2)


#: leaf names of the Kelvin-Voigt retardation times (bounded by the problem itself)
RETARDATION_TIMES = ("tau", "tau_S", "tau_B")


def problem_limit(problem, path: str) -> Range | None:
    """A range the problem (not only the catalogue) imposes on a key: the Kelvin-Voigt
    retardation times (:func:`kelvin_voigt_tau_limit`); None for the others."""
    table, name = catalogue_key(path)
    if table in ("material", "materials.NAME") and name in RETARDATION_TIMES:
        return kelvin_voigt_tau_limit(problem)
    return None
