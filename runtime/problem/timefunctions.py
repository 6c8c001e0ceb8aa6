"""Time functions that scale loads and prescribed motions (dimensionless, of t in s).

Kinds (TOML ``time = {kind = "...", ...}``; a missing ``time`` is ``constant``):

* ``constant``: ``value`` (default 1);
* ``ramp``: 0 before ``start``, linear to 1 over ``duration``, then 1;
* ``smooth_ramp``: the same with a cosine profile (continuous rate: for prescribed motion);
* ``step``: 0 before ``start``, 1 from ``start`` on;
* ``release``: 1 before ``start``, 0 from ``start`` on (a load held until it is let go:
  statics at ``t = 0-`` sees it, the motion after ``start`` does not);
* ``harmonic``: ``offset + amplitude sin(2 pi frequency t + phase)`` (frequency in Hz,
  phase in rad);
* ``table``: piecewise linear through ``points = [[t, value], ...]`` (or a CSV ``file``
  with columns t, value), held constant outside.

``value(t, left=True)`` is the limit from the left (the value statics at ``t`` uses).
"""

from __future__ import annotations

import csv
import math
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from runtime.errors import ParameterError
from runtime.problem import coerce as C

KINDS = ("constant", "ramp", "smooth_ramp", "step", "release", "harmonic", "table")
_KEYS = {"constant": ("value",), "ramp": ("start", "duration"),
         "smooth_ramp": ("start", "duration"), "step": ("start",), "release": ("start",),
         "harmonic": ("amplitude", "frequency", "phase", "offset"),
         "table": ("points", "file")}


@dataclass(frozen=True)
class TimeFunction:
    """A dimensionless function of time (see the module docstring for the kinds)."""

    kind: str = "constant"
    value: float = 1.0
    start: float = 0.0
    duration: float = 0.0
    amplitude: float = 1.0
    frequency: float = 0.0
    phase: float = 0.0
    offset: float = 0.0
    points: tuple[tuple[float, float], ...] = ()

    def __post_init__(self) -> None:
        C.choice("time.kind", self.kind, KINDS)
        if self.kind in ("ramp", "smooth_ramp"):
            C.positive("time.duration", self.duration)
        if self.kind == "harmonic":
            C.nonnegative("time.frequency", self.frequency)
        if self.kind == "table":
            if len(self.points) < 2:
                raise ParameterError("time.points", self.points, "at least 2 [t, value] pairs")
            ts = [p[0] for p in self.points]
            if any(b <= a for a, b in zip(ts, ts[1:], strict=False)):
                raise ParameterError("time.points", ts, "strictly increasing times")

    @property
    def is_constant(self) -> bool:
        return self.kind == "constant"

    def value_at(self, t: float, left: bool = False) -> float:
        """f(t); ``left``: the limit from the left at a jump (``step``, ``release``)."""
        k = self.kind
        if k == "constant":
            return self.value
        if k in ("step", "release"):
            on = t > self.start if left else t >= self.start
            return float(on) if k == "step" else float(not on)
        if k in ("ramp", "smooth_ramp"):
            x = min(max((t - self.start) / self.duration, 0.0), 1.0)
            return x if k == "ramp" else 0.5 * (1.0 - math.cos(math.pi * x))
        if k == "harmonic":
            w = 2 * math.pi * self.frequency
            return self.offset + self.amplitude * math.sin(w * t + self.phase)
        ts, vs = self._table()
        return float(np.interp(t, ts, vs))

    def constant_interval(self, t: float) -> tuple[float, float]:
        """``(a, b)`` with ``a <= t < b`` on which f is constant (rate 0), the largest such
        that is known; ``(t, t)`` (empty) when f varies at ``t``. Lets the drive skip
        re-writing loads that do not change (a released load stays off)."""
        inf = math.inf
        k = self.kind
        if k == "constant" or (k == "harmonic" and (self.amplitude == 0.0
                                                    or self.frequency == 0.0)):
            return -inf, inf
        if k in ("step", "release"):
            return (-inf, self.start) if t < self.start else (self.start, inf)
        if k in ("ramp", "smooth_ramp"):
            if t < self.start:
                return -inf, self.start
            end = self.start + self.duration
            return (end, inf) if t >= end else (t, t)
        if k == "table":
            ts = [p[0] for p in self.points]
            vs = [p[1] for p in self.points]
            if t < ts[0]:
                return -inf, ts[0]
            if t >= ts[-1]:
                return ts[-1], inf
            i = int(np.searchsorted(ts, t, side="right")) - 1
            return (ts[i], ts[i + 1]) if vs[i] == vs[i + 1] else (t, t)
        return t, t

    def rate_at(self, t: float, left: bool = False) -> float:
        """df/dt (1/s); ``left``: the limit from the left where the rate jumps (the ends of
        a ramp, the kinks of a table); 0 at the jumps of ``step``/``release`` (they are
        not for motion)."""
        k = self.kind
        if k in ("constant", "step", "release"):
            return 0.0
        if k in ("ramp", "smooth_ramp"):
            x = (t - self.start) / self.duration
            if not (0.0 < x <= 1.0 if left else 0.0 <= x < 1.0):
                return 0.0
            return (1.0 / self.duration if k == "ramp"
                    else 0.5 * math.pi / self.duration * math.sin(math.pi * x))
        if k == "harmonic":
            w = 2 * math.pi * self.frequency
            return self.amplitude * w * math.cos(w * t + self.phase)
        ts, vs = self._table()
        i = int(np.searchsorted(ts, t, side="left" if left else "right")) - 1
        if i < 0 or i >= ts.size - 1:
            return 0.0
        return float((vs[i + 1] - vs[i]) / (ts[i + 1] - ts[i]))

    def accel_at(self, t: float, left: bool = False) -> float:
        """d^2f/dt^2 (1/s^2), the limit from the left with ``left`` (0 on the linear
        pieces of a ramp or table: their kinks are breakpoints, not accelerations)."""
        k = self.kind
        if k == "smooth_ramp":
            x = (t - self.start) / self.duration
            if not (0.0 < x <= 1.0 if left else 0.0 <= x < 1.0):
                return 0.0
            return 0.5 * (math.pi / self.duration) ** 2 * math.cos(math.pi * x)
        if k == "harmonic":
            w = 2 * math.pi * self.frequency
            return -self.amplitude * w * w * math.sin(w * t + self.phase)
        return 0.0

    #: a kink of a table is a breakpoint when its slope changes by more than this
    #: fraction of the table's steepest slope (a finely sampled smooth signal merges)
    KINK_FRACTION = 0.05

    def _table(self) -> tuple[np.ndarray, np.ndarray]:
        return (np.array([p[0] for p in self.points], dtype=float),
                np.array([p[1] for p in self.points], dtype=float))

    def breakpoints(self, t0: float, t1: float) -> list[tuple[float, int]]:
        """Times in ``[t0, t1]`` where f is not smooth, with the order of what jumps there:
        0 the value (``step``, ``release``), 1 the rate (the ends of a ``ramp``, the kinks
        of a ``table``), 2 the second derivative (the ends of a ``smooth_ramp``).

        A table's kink counts when its slope changes by more than ``KINK_FRACTION`` of the
        table's steepest slope, so that a long table sampled from a smooth signal is not
        cut at every point (its pieces are then bounded by :meth:`time_scale`)."""
        k = self.kind
        out: list[tuple[float, int]] = []
        if k in ("step", "release"):
            out = [(self.start, 0)]
        elif k in ("ramp", "smooth_ramp"):
            order = 1 if k == "ramp" else 2
            out = [(self.start, order), (self.start + self.duration, order)]
        elif k == "table":
            ts, vs = self._table()
            slopes = np.concatenate([[0.0], np.diff(vs) / np.diff(ts), [0.0]])
            jump = np.abs(np.diff(slopes))              # at each point
            steep = float(np.max(np.abs(slopes)))
            if steep > 0.0:
                out = [(float(t), 1) for t, j in zip(ts, jump, strict=True)
                       if j > self.KINK_FRACTION * steep]
        return [(t, o) for t, o in out if t0 <= t <= t1]

    def time_scale(self, t: float) -> float:
        """The time (s) over which f changes appreciably on its smooth piece that starts at
        ``t`` (right of a breakpoint at ``t``); inf where f is constant. The run loop
        bounds its steps by a fraction of it, so that an input is resolved even when the
        error test has nothing yet to see (a rod at rest before a pulse)."""
        k = self.kind
        inf = math.inf
        if k in ("ramp", "smooth_ramp"):
            return self.duration if self.start <= t < self.start + self.duration else inf
        if k == "harmonic":
            return (1.0 / self.frequency if self.amplitude != 0.0 and self.frequency > 0.0
                    else inf)
        if k == "table":
            ts, vs = self._table()
            if not ts[0] <= t < ts[-1]:
                return inf
            cuts = [b for b, _ in self.breakpoints(-inf, inf)] + [ts[0], ts[-1]]
            lo = max(c for c in cuts if c <= t)
            hi = min(c for c in cuts if c > t)
            i0 = int(np.searchsorted(ts, lo, side="left"))
            i1 = int(np.searchsorted(ts, hi, side="right"))
            seg_t, seg_v = ts[i0:i1], vs[i0:i1]
            steep = float(np.max(np.abs(np.diff(seg_v) / np.diff(seg_t)))) if seg_t.size > 1 \
                else 0.0
            if steep == 0.0:
                return inf
            # the piece's range over its steepest slope: its length for a straight piece,
            # period/pi for a sampled sine
            return min(hi - lo, float(np.ptp(seg_v)) / steep)
        return inf

    def peak(self, t_end: float) -> float:
        """max |f| over [0, t_end] (for scales: tolerances, checks)."""
        k = self.kind
        if k == "constant":
            return abs(self.value)
        if k in ("ramp", "smooth_ramp", "step", "release"):
            return 1.0
        if k == "harmonic":
            return abs(self.offset) + abs(self.amplitude)
        return max(abs(p[1]) for p in self.points)

    @property
    def continuous(self) -> bool:
        """False for the jumps of ``step`` and ``release`` (not allowed for positions)."""
        return self.kind not in ("step", "release")

    def to_mapping(self) -> dict[str, Any]:
        out: dict[str, Any] = {"kind": self.kind}
        for key in _KEYS[self.kind]:
            if key == "file":
                continue
            v = getattr(self, key)
            out[key] = [list(p) for p in v] if key == "points" else v
        return out

    @classmethod
    def from_mapping(cls, m: Any, path: str = "time", base: Path | None = None
                     ) -> TimeFunction:
        """From a TOML table (``{kind = "ramp", start = 0, duration = 1}``) or a number
        (a constant)."""
        if m is None:
            return cls()
        if not isinstance(m, Mapping):
            return cls(value=C.number(path, m))
        kind = C.choice(f"{path}.kind", m.get("kind", "constant"), KINDS)
        C.no_unknown_keys(path, m, ("kind", *_KEYS[kind]))
        kw: dict[str, Any] = {"kind": kind}
        for key in _KEYS[kind]:
            if key not in m:
                continue
            if key == "points":
                kw["points"] = _points(f"{path}.points", m[key])
            elif key == "file":
                kw["points"] = read_table_csv(f"{path}.file", m[key], base)
            else:
                kw[key] = C.number(f"{path}.{key}", m[key])
        if kind == "table" and "points" not in kw:
            raise ParameterError(f"{path}.points", None, "[[t, value], ...] or file = CSV")
        try:
            return cls(**kw)
        except ParameterError as exc:
            raise ParameterError(exc.name.replace("time", path, 1), exc.value,
                                 exc.allowed) from None


def _points(path: str, value: Any) -> tuple[tuple[float, float], ...]:
    if isinstance(value, (str, bytes, Mapping)) or not hasattr(value, "__len__"):
        raise ParameterError(path, value, "[[t, value], ...]")
    return tuple(C.vector(f"{path}[{i}]", p, 2) for i, p in enumerate(value))


def read_table_csv(path: str, file: Any, base: Path | None = None
                   ) -> tuple[tuple[float, float], ...]:
    """(t, value) rows of a CSV file (header optional; '#' comments)."""
    name = C.string(path, file)
    f = Path(name)
    if not f.is_absolute() and base is not None:
        f = base / f
    try:
        text = f.read_text()
    except OSError as exc:
        raise ParameterError(path, name, f"a readable CSV file ({exc.strerror})") from None
    rows = []
    for i, row in enumerate(csv.reader(line for line in text.splitlines()
                                       if line.strip() and not line.lstrip().startswith("#"))):
        try:
            rows.append((float(row[0]), float(row[1])))
        except (ValueError, IndexError):
            if i == 0:
                continue          # a header line
            raise ParameterError(path, name, f"two numeric columns t, value (row {i + 1})"
                                 ) from None
    if len(rows) < 2 or not all(math.isfinite(a) and math.isfinite(b) for a, b in rows):
        raise ParameterError(path, name, "at least 2 finite rows t, value")
    return tuple(rows)
