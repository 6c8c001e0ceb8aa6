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
* :class:`ShapeModel` (a static shape of a single rod): the static equilibrium and its
  sensitivities by the implicit function theorem (one factorisation,
  ``static_sensitivity_channels``); the node positions (3, N+1) and ``positions/<p>`` are
  taken to the measured arc lengths linearly: the discrete rod's centreline is straight
  between its nodes, so this is the model's own centreline, not an approximation of it.

Measured modes and an assembly's shape are refused before anything runs
(:func:`check_model`): the modal analysis has no derivatives in this build, and an
assembly's static sensitivities come with the assembly's sensitivity module.

A trial point the problem refuses (a value out of a key's range) or whose run fails is a
:class:`~runtime.study.fit_solver.ModelFailure`; an interrupted run (Ctrl-C, SIGTERM)
raises its interrupt.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from runtime.errors import IllPosedError, ParameterError
from runtime.study.fit_data import DataError, FitData
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


class ShapeModel:
    """A static shape of a single rod against its static equilibrium (module docstring)."""

    kind = "shape"

    def __init__(self, problem, names: Sequence[str], data: FitData) -> None:
        self.names = tuple(names)
        self.problem = problem
        self.data = data
        self.evaluations = 0
        self.counters: dict[str, int] = {}
        self._last: tuple[bytes, Curves] | None = None

    def set_window(self, t_end: float | None) -> None:
        """A shape has no time: the whole shape is always fitted."""

    def evaluate(self, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(r, dr/dtheta) at the measured arc lengths (module docstring)."""
        from runtime.problem.assemble import build_model
        from runtime.simulate.sensitivity import (
            SensitivityRun,
            resolve_parameters,
            static_sensitivity_channels,
            with_parameters,
        )
        from runtime.simulate.simulate import static_equilibrium
        from runtime.solvers.statics import StaticSolveError

        values = dict(zip(self.names, (float(v) for v in theta), strict=True))
        try:
            problem = with_parameters(self.problem, values)
            model = build_model(problem)
            run = SensitivityRun(problem, resolve_parameters(problem, self.names))
            run.prepare(model)
            outcome = static_equilibrium(problem, model)
        except (ParameterError, IllPosedError) as exc:
            raise ModelFailure(f"the problem refuses these values: {exc}") from None
        except StaticSolveError as exc:
            raise ModelFailure(f"the static solve failed: {exc}") from None
        sens = static_sensitivity_channels(model, outcome.y, run)
        self.evaluations += 1
        self.counters["static_solves"] = self.counters.get("static_solves", 0) + 1
        self.counters["newton_iterations"] = (self.counters.get("newton_iterations", 0)
                                              + int(outcome.iterations))
        s_nodes = np.asarray(problem.node_arc_lengths(), dtype=float)
        pos = model.positions(outcome.y)
        s = self.data.abscissa
        rs, Js, curves = [], [], {}
        for col in self.data.columns:
            rs.append(np.interp(s, s_nodes, pos[col.component]) - col.values)
            Js.append(np.stack([np.interp(s, s_nodes,
                                          sens.channels[f"positions/{p}"][col.component])
                                for p in self.names], axis=1))
            curves[col.name] = pos[col.component]
        r = np.concatenate(rs)
        self._last = (np.asarray(theta, float).tobytes(), Curves(s_nodes, curves, r))
        return r, np.concatenate(Js, axis=0)

    def curves(self, theta: np.ndarray) -> Curves:
        """The equilibrium's centreline at ``theta`` (the last evaluation's if it was
        there)."""
        if self._last is None or self._last[0] != np.asarray(theta, float).tobytes():
            self.evaluate(theta)
        assert self._last is not None
        return self._last[1]


def check_model(problem, data: FitData) -> None:
    """Refuse, in one line and before anything is written, data whose model cannot give
    exact sensitivities in this build (module docstring)."""
    from runtime.problem.schema import Problem

    if data.kind == "modes":
        raise DataError(f"data file {data.path!r} holds measured modes: fitting modes "
                        "needs the derivatives of the modal analysis, which this build "
                        "does not have yet; fit a record (t, end.x, ...) or a static "
                        "shape (s, x, y, z) instead")
    if not isinstance(problem, Problem):
        import importlib.util

        if data.kind == "shape" or importlib.util.find_spec(
                "runtime.simulate.assembly_sensitivity") is None:
            raise DataError(f"data file {data.path!r}: fitting an assembly's "
                            f"{'shape' if data.kind == 'shape' else 'record'} needs "
                            "the assembly's sensitivities, which this build does not "
                            "have yet; fit a single rod")


def model_for(problem, names: Sequence[str], data: FitData, period: float):
    """The model of ``data``'s kind (a record: :class:`SeriesModel`; a shape:
    :class:`ShapeModel`), after :func:`check_model`."""
    check_model(problem, data)
    if data.kind == "series":
        return SeriesModel(problem, names, data, period)
    return ShapeModel(problem, names, data)
