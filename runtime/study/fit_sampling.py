"""Where the model of a fit is evaluated: on the record's own times, or interpolated.

A simulation writes its series (and its sensitivities) on a uniform output grid
``k * simulation.output_step`` (``runtime.simulate.simulate``), from the integrator's own
interpolating polynomial between its steps. A record whose times all lie on such a grid
(a logger at a fixed rate, from t = 0 or from any multiple of its step, gaps allowed) is
compared **on the grid**: the output step is the record's step and the model is the
integrator's value at the record's times exactly. Any other record (an irregular clock, a
camera with dropped frames at odd times) is compared **interpolated**: the output step is
the record's typical step, or a hundredth of the record's period where that is finer,
and the model and its sensitivities are interpolated to the record's times by one cubic
spline (the interpolation is linear in the data, so the sensitivities' spline is the
spline's sensitivity); its error, (5/384) (omega h)^4 of the amplitude, is below 1e-7
of it at a hundred outputs per period, far below any measurement's noise.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

#: a time is on the grid k * h when |t / h - k| is below this
GRID_TOL = 1e-6
#: outputs per period of the record's oscillation for an interpolated record
OUTPUTS_PER_PERIOD = 100


@dataclass(frozen=True)
class Sampling:
    """How a record's times map to the model's output grid: ``output_step`` and ``t_end``
    (s) of the simulation, and either ``index`` (the output sample of each record time:
    on the grid) or None (interpolated by a cubic spline)."""

    output_step: float
    t_end: float
    index: np.ndarray | None

    @property
    def on_grid(self) -> bool:
        return self.index is not None

    def describe(self) -> str:
        if self.on_grid:
            return (f"on the record's own times: the simulation's output step is the "
                    f"record's, {self.output_step:.6g} s, so the model is the integrator's "
                    "value at each measured time")
        return (f"interpolated: the record's times are not a uniform grid, so the model is "
                f"sampled every {self.output_step:.6g} s and interpolated to them (cubic "
                "spline, the sensitivities likewise)")

    def values(self, t_model: np.ndarray, series: np.ndarray, t_data: np.ndarray
               ) -> np.ndarray:
        """``series`` (..., n) on ``t_model`` at the record's times ``t_data`` (..., m)."""
        if self.index is not None:
            return series[..., self.index]
        from scipy.interpolate import CubicSpline

        return CubicSpline(t_model, series, axis=-1)(t_data)


def sampling(t: np.ndarray, period: float = math.inf) -> Sampling:
    """The :class:`Sampling` of a record with times ``t`` (s, increasing, >= 0) whose
    oscillation has ``period`` (s; inf if none): on the grid of the record's median step
    if every time is a multiple of it, else interpolated (module docstring)."""
    t = np.asarray(t, dtype=float)
    if not (t.size and t[-1] > 0):
        raise ValueError("a record needs a time after t = 0")
    dt = float(np.median(np.diff(t))) if t.size >= 2 else float(t[-1])
    k = t / dt
    if np.all(np.abs(k - np.round(k)) <= GRID_TOL):
        index = np.round(k).astype(int)
        return Sampling(dt, float(index[-1] * dt), index)
    h = min(dt, period / OUTPUTS_PER_PERIOD) if math.isfinite(period) else dt
    t_end = float(t[-1])
    n = max(1, math.ceil(t_end / h - 1e-9))
    h = t_end / n
    return Sampling(h, float(n * h), None)
