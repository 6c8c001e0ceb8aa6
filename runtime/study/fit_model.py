"""The rod as the model of a fit: residuals and their exact Jacobian from one run with
sensitivities (:mod:`runtime.simulate.sensitivity`).

A model holds the problem, the fitted parameters' names and the data; ``evaluate(theta)``
sets the parameters (``with_parameters``: the same problem and mesh, new values), runs the
model with forward sensitivities and returns ``r = model - data`` at the measured points and
``dr/dtheta`` from the sensitivity channels. Nothing is differenced.

* :class:`SeriesModel` (a record): ``simulate_with_sensitivities`` up to the record's
  end (or the current window's), outputs where :mod:`runtime.study.fit_sampling` puts them;
  the channels ``tip/<p>``, ``start/<p>``, ``NAME.end/<p>``, ``NAME.start/<p>`` (3, n). The
  run keeps no centreline frames and analyses no maxima (a fit needs neither).

A trial point the problem refuses (a value out of a key's range) or whose run fails is a
:class:`~runtime.study.fit_solver.ModelFailure`; an interrupted run (Ctrl-C, SIGTERM)
raises its interrupt.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from runtime.errors import ParameterError
from runtime.study.fit_data import FitData
from runtime.study.fit_sampling import Sampling, sampling
from runtime.study.fit_solver import ModelFailure


@dataclass
class Curves:
    """The model at one parameter point, for the plot and the report: ``x`` (the model's
    abscissa: its output times, s) and ``columns`` {data column: model values there}, and
    the residual ``r`` at the data."""

    x: np.ndarray
    columns: dict[str, np.ndarray]
    r: np.ndarray = field(repr=False)


def _series_of(result, channel: str) -> np.ndarray:
    """The (3, n) positions of a sensitivity channel name in a run's result: ``tip`` and
    ``start`` of a rod, ``NAME.end`` / ``NAME.start`` of an assembly (``ends["NAME/end"]``)."""
    if channel == "tip":
        return result.tip
    if channel == "start":
        return result.start
    name, end = channel.rsplit(".", 1)
    return result.ends[f"{name}/{end}"]


class SeriesModel:
    """A record against a simulation (module docstring)."""

    kind = "series"

    def __init__(self, problem, names: Sequence[str], data: FitData, period: float) -> None:
        self.names = tuple(names)
        self.data_all = data
        self.period = period
        self.base = problem.with_overrides({"simulation.centreline_frames": 0,
                                            "analysis": {}})
        self.evaluations = 0
        self.counters: dict[str, int] = {}
        self._last: tuple[bytes, Curves] | None = None
        self.set_window(None)

    def set_window(self, t_end: float | None) -> None:
        """Fit the record up to ``t_end`` (s) from now on (None: the whole record)."""
        self.data = self.data_all if t_end is None else self.data_all.window(t_end)
        self.sampling: Sampling = sampling(self.data.abscissa, self.period)
        self.problem = self.base.with_overrides(
            {"simulation.t_end": self.sampling.t_end,
             "simulation.output_step": self.sampling.output_step})

    def _key(self, theta: np.ndarray) -> tuple:
        return (np.asarray(theta, float).tobytes(), self.sampling.t_end,
                self.sampling.output_step)

    def _run(self, theta: np.ndarray):
        from runtime.simulate.sensitivity import simulate_with_sensitivities, with_parameters

        values = dict(zip(self.names, (float(v) for v in theta), strict=True))
        try:
            problem = with_parameters(self.problem, values)
        except ParameterError as exc:
            raise ModelFailure(f"the problem refuses these values: {exc}") from None
        result, sens = simulate_with_sensitivities(problem, self.names)
        self.evaluations += 1
        for k, v in sens.counters.items():
            self.counters[k] = self.counters.get(k, 0) + int(v)
        for k, v in getattr(result, "counters", {}).items():
            self.counters[k] = self.counters.get(k, 0) + int(v)
        if result.interrupt is not None:
            raise result.interrupt
        if result.status != "finished":
            raise ModelFailure(f"the simulation {result.status}: {result.message}")
        return result, sens

    def evaluate(self, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(r, dr/dtheta) on the current window (module docstring)."""
        result, sens = self._run(theta)
        s, t = self.sampling, self.data.abscissa
        rs, Js, curves = [], [], {}
        for col in self.data.columns:
            model = _series_of(result, col.channel)[col.component]
            at = s.values(result.t, model, t)
            rs.append(at - col.values)
            Js.append(np.stack([s.values(result.t,
                                         sens.channels[f"{col.channel}/{p}"][col.component], t)
                                for p in self.names], axis=1))
            curves[col.name] = model
        r = np.concatenate(rs)
        self._last = (self._key(theta), Curves(result.t, curves, r))
        return r, np.concatenate(Js, axis=0)

    def curves(self, theta: np.ndarray) -> Curves:
        """The model over the whole record at ``theta`` (the last evaluation's, if it was
        there; else one run more)."""
        self.set_window(None)
        if self._last is None or self._last[0] != self._key(theta):
            self.evaluate(theta)
        assert self._last is not None
        return self._last[1]


def model_for(problem, names: Sequence[str], data: FitData, period: float):
    """The model of ``data``'s kind (a record: :class:`SeriesModel`)."""
    if data.kind == "series":
        return SeriesModel(problem, names, data, period)
    raise NotImplementedError(f"fits to {data.kind} data")
