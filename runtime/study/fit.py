"""``kvrod fit``: identify a rod's parameters from measurements (docs/design.md,
"Identification (kvrod fit)").

The data (:mod:`runtime.study.fit_data`) say which model is run: a record a simulation, a
static shape the static equilibrium, measured modes the damped modal analysis. The fit is
nonlinear least squares with the exact Jacobian of the model's sensitivities
(:mod:`runtime.study.fit_solver`) in scaled parameters (:mod:`runtime.study.fit_parameters`);
its intervals, correlations and the parameters the data cannot tell apart come from
:mod:`runtime.study.fit_statistics`.

**Robust start on oscillating records.** The misfit of a time series is not convex in a
frequency-like parameter: a start whose period is off by more than about half a period over
the record lands in a local minimum (the model's peaks matched to the record's next ones).
The fit therefore grows its time window: with T the record's dominant period (the peak of
its amplitude spectrum, :func:`runtime.study.calibration.dominant_period`), it fits first
the record up to T/2, then T, 2T, 4T, ... (each from the last one's result, each ending
where the record is at most 2/3 over), then the whole record. A window of half a period
leaves a start's frequency error of up to ~100 % within the basin, and short windows are
cheap (the simulation ends with them). A record without oscillation (creep, relaxation,
a static shape, modes) is fitted whole at once. The alternative, starting from the
frequency and decay a `kvrod calibrate` style estimate gives, applies only to parameters
whose effect on frequency and decay is known in closed form; the window works for any.
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy.stats import chi2

from runtime.study.fit_data import FitData
from runtime.study.fit_parameters import (
    ParameterSpec,
    make_spec,
    problem_limit,
)
from runtime.study.fit_solver import SolveOutcome, solve
from runtime.study.fit_statistics import (
    FitStatistics,
    dependency_warning,
    fit_statistics,
    insensitive_warning,
)

#: model evaluations of each growing window's fit (the whole record's: max_evaluations)
WINDOW_EVALUATIONS = 12
#: the windows' tolerances (a start for the next window, not the answer)
WINDOW_TOL = 1e-5
#: a residual RMS this many times the noise is a poor fit
POOR_FIT_FACTOR = 3.0
#: ... and this fraction of the column's range at least (a noise-free record: the model's
#: own discretisation, not a misfit)
POOR_FIT_FLOOR = 1e-3
#: a log-scaled parameter whose 95 % interval spans more than this factor is "barely
#: determined"
WIDE_FACTOR = 10.0
#: the default most model evaluations of the whole record's fit
MAX_EVALUATIONS = 40


@dataclass
class FitResult:
    """Everything a fit found (see :meth:`to_json` for fit.json)."""

    specs: list[ParameterSpec]
    data: FitData
    theta: np.ndarray
    outcome: SolveOutcome
    stats: FitStatistics
    windows: list[dict]
    start_curves: object
    fit_curves: object
    sampling: str
    evaluations: int
    counters: dict[str, int]
    wall_time_s: float
    warnings: list[str] = field(default_factory=list)
    sigma: float | None = None

    @property
    def names(self) -> list[str]:
        return [s.name for s in self.specs]

    @property
    def start(self) -> np.ndarray:
        return np.array([s.start for s in self.specs])

    def residual_rms(self) -> dict[str, float]:
        """Residual RMS per data column (in its unit; modes: relative)."""
        return _per_column(self.data, self.outcome.r)

    def start_cost(self) -> float:
        r = self.start_curves.r
        return float(0.5 * r @ r)

    def to_json(self, command: str = "") -> dict:
        """fit.json: ``parameters``, ``confidence`` and ``warnings`` (the keys other tools
        read), then how the fit went."""
        st, out = self.stats, self.outcome
        return {
            "status": "finished",
            "parameters": {n: float(v) for n, v in zip(self.names, self.theta, strict=True)},
            "confidence": {n: [float(a), float(b)] for n, (a, b) in
                           zip(self.names, st.intervals, strict=True)},
            "warnings": list(self.warnings),
            "confidence_method": (
                "95 % intervals from the Jacobian and the residual, linearised at the "
                "optimum: covariance s^2 (J^T J)^-1 in the scaled coordinates, "
                + ("with s = --sigma and the normal quantile" if self.sigma is not None
                   else "s^2 = |r|^2 / (n - p), Student t quantile")
                + f" {st.quantile:.4g}; u +- quantile * se mapped back through the scaling "
                  "(log-scaled parameters: asymmetric, positive)"),
            "model": self.data.model,
            "data": {"file": self.data.path, "kind": self.data.kind, "rows": self.data.rows,
                     "values": self.data.count,
                     "columns": [c.name for c in self.data.columns],
                     "sampling": self.sampling},
            "start": {n: float(v) for n, v in zip(self.names, self.start, strict=True)},
            "bounds": {s.name: [s.bounds.low, s.bounds.high] for s in self.specs},
            "scaled_coordinates": {s.name: s.coordinates for s in self.specs},
            "iterations": out.njev,
            "model_evaluations": self.evaluations,
            "converged": out.converged,
            "message": out.message,
            "cost": out.cost,
            "start_cost": self.start_cost(),
            "residual_rms": self.residual_rms(),
            "residual_rms_all": float(np.sqrt(np.mean(out.r**2))) if out.r.size else 0.0,
            "sigma": self.sigma,
            "correlation": {"parameters": self.names,
                            "matrix": [[None if not math.isfinite(v) else float(v)
                                        for v in row] for row in st.correlation]},
            "statistics": st.to_json(),
            "windows": self.windows,
            "failed_evaluations": list(out.failures),
            "counters": dict(self.counters),
            "wall_time_s": self.wall_time_s,
            "command": command,
        }


def _per_column(data: FitData, r: np.ndarray) -> dict[str, float]:
    out, i = {}, 0
    for c in data.columns:
        k = int(np.count_nonzero(c.measured))
        seg = r[i:i + k]
        out[c.name] = float(np.sqrt(np.mean(seg**2))) if k else 0.0
        i += k
    return out


# --------------------------------------------------------------------------------------
# parameters
# --------------------------------------------------------------------------------------


def parameter_specs(problem, names: Sequence[str], start: Mapping[str, float] | None = None,
                    bounds: Mapping[str, tuple[float | None, float | None]] | None = None
                    ) -> list[ParameterSpec]:
    """The fitted parameters' specs: names checked (``resolve_parameters``: one line naming
    an unknown or non-numeric key), start values (``start``, else the problem's), bounds
    (the key catalogue's, the problem's own, narrowed by ``bounds``)."""
    from runtime.simulate.sensitivity import resolve_parameters

    resolved = resolve_parameters(problem, list(names))
    start = dict(start or {})
    bounds = dict(bounds or {})
    specs = []
    for name, rp in zip(names, resolved, strict=True):
        path = str(rp.paths[0]) if rp.paths else str(rp.key)
        v = start.get(name, float(rp.value))
        specs.append(make_spec(name, path, v, limit=problem_limit(problem, path),
                               bounds=bounds.get(name)))
    return specs


# --------------------------------------------------------------------------------------
# windows
# --------------------------------------------------------------------------------------


def record_period(data: FitData) -> float:
    """The dominant period (s) of a record's most varying column; inf for data without
    time or without oscillation."""
    if data.kind != "series" or data.rows < 8:
        return math.inf
    from runtime.study.calibration import dominant_period

    col = max(data.columns, key=lambda c: float(np.std(c.values)))
    if float(np.std(col.values)) == 0.0:
        return math.inf
    return float(dominant_period(data.abscissa, col.values))


def window_ends(data: FitData, period: float, n_parameters: int) -> list[float]:
    """The growing windows' ends (s), before the whole record (module docstring): T/2, T,
    2T, ... while the record goes on for at least half as long again, and while each
    holds more data than parameters; [] for a record of under two periods."""
    if data.kind != "series" or not math.isfinite(period):
        return []
    t0, t1 = float(data.abscissa[0]), float(data.abscissa[-1])
    if t1 - t0 < 2.0 * period:
        return []
    ends, e = [], 0.5 * period
    while t0 + e <= t0 + (t1 - t0) / 1.5:
        if data.window(t0 + e).count > 2 * n_parameters + 2:
            ends.append(t0 + e)
        e *= 2.0
    return ends


# --------------------------------------------------------------------------------------
# the fit
# --------------------------------------------------------------------------------------


def fit(problem, data: FitData, specs: Sequence[ParameterSpec], *,
        sigma: float | None = None, max_evaluations: int = MAX_EVALUATIONS,
        windows: bool = True) -> FitResult:
    """Fit ``specs`` of ``problem`` to ``data`` (module docstring).

    Parameters
    ----------
    problem : Problem or Assembly
        The rod (its mesh, tolerances, loads; the fitted keys take the specs' values).
    data : FitData
        Checked measurements (:func:`runtime.study.fit_data.read_fit_data` and
        ``check_against_problem``).
    specs : sequence of ParameterSpec
        The fitted parameters (:func:`parameter_specs`).
    sigma : float, optional
        The measurement noise's standard deviation (the data's unit; modes: relative), if
        known: intervals from it instead of the residual, and a test of the fit against it.
    max_evaluations : int
        Most model evaluations of the whole record's fit.
    windows : bool
        Grow the time window on an oscillating record (module docstring).

    Returns
    -------
    FitResult
    """
    from runtime.study.fit_model import model_for

    wall0 = time.perf_counter()
    names = [s.name for s in specs]
    period = record_period(data)
    model = model_for(problem, names, data, period)
    u = np.zeros(len(specs))
    done = []
    for t_w in window_ends(data, period, len(specs)) if windows else []:
        model.set_window(t_w)
        out = solve(model.evaluate, specs, u, max_evaluations=WINDOW_EVALUATIONS,
                    xtol=WINDOW_TOL, ftol=WINDOW_TOL)
        u = out.u
        done.append({"t_end": t_w, "parameters": dict(zip(names, out.theta.tolist(),
                                                          strict=True)),
                     "model_evaluations": out.nfev, "cost": out.cost})
    model.set_window(None)
    out = solve(model.evaluate, specs, u, max_evaluations=max_evaluations)
    done.append({"t_end": data.t_end if data.kind == "series" else None,
                 "parameters": dict(zip(names, out.theta.tolist(), strict=True)),
                 "model_evaluations": out.nfev, "cost": out.cost})
    stats = fit_statistics(specs, out.u, out.r, out.jac_u, sigma)
    fit_curves = model.curves(out.theta)
    start_curves = model.curves(np.array([s.start for s in specs]))
    res = FitResult(specs=list(specs), data=data, theta=out.theta, outcome=out, stats=stats,
                    windows=done, start_curves=start_curves, fit_curves=fit_curves,
                    sampling=model.sampling.describe() if data.kind == "series" else "",
                    evaluations=model.evaluations, counters=dict(model.counters),
                    wall_time_s=0.0, sigma=sigma)
    res.warnings = fit_warnings(res)
    res.wall_time_s = time.perf_counter() - wall0
    return res


def fit_warnings(res: FitResult) -> list[str]:
    """The doubts about a fit, one line each: parameters the data cannot tell apart or do
    not see, parameters at a bound, barely determined ones, a residual far above the noise,
    no convergence, trial points whose model failed."""
    out: list[str] = []
    st, o = res.stats, res.outcome
    names = res.names
    for d in st.dependencies:
        out.append(dependency_warning(d, names))
    out += [insensitive_warning(n) for n in st.insensitive]
    named = {n for d in st.dependencies for n in d.names} | set(st.insensitive)
    for s, v, at in zip(res.specs, res.theta, o.at_bound, strict=True):
        if at:
            b = s.bounds.low if at < 0 else s.bounds.high
            out.append(f"{s.name} = {v:.6g} {s.unit} sits at its {'lower' if at < 0 else 'upper'}"
                       f" bound {b:.6g} {s.unit}: the data pull it further (is the model the "
                       "right one? widen --bounds if the key's range allows); its interval "
                       "is not meaningful")
    for s, v, (lo, hi) in zip(res.specs, res.theta, st.intervals, strict=True):
        if s.name in named or not s.log:
            continue
        if not (lo > 0 and hi / lo <= WIDE_FACTOR):
            out.append(f"{s.name} is barely determined by this record: its 95 % interval "
                       f"[{lo:.4g}, {hi:.4g}] {s.unit} spans more than a factor "
                       f"{WIDE_FACTOR:g} around {v:.4g}")
    out += poor_fit_warnings(res)
    if not o.converged:
        out.append(f"the fit did not converge in {o.nfev} model evaluations "
                   f"(--max-iterations): {o.message}; the values are the best found so far")
    if o.failures:
        out.append(f"{len(o.failures)} trial point(s) could not be evaluated and were "
                   f"stepped back from (first: {o.failures[0]})")
    return out


def poor_fit_warnings(res: FitResult) -> list[str]:
    """A residual far above the noise: with --sigma a chi-square test at 0.1 %, else per
    column against the noise estimated from the column itself (second differences,
    :func:`runtime.study.calibration.noise_rms`)."""
    from runtime.study.calibration import noise_rms

    r, data = res.outcome.r, res.data
    rms = res.residual_rms()
    if res.sigma is not None:
        dof = max(r.size - len(res.specs), 1)
        stat = float(r @ r) / res.sigma**2
        if chi2.sf(stat, dof) < 1e-3:
            total = math.sqrt(float(r @ r) / r.size)
            return [f"poor fit: the residual RMS {total:.4g} is {total / res.sigma:.3g} times "
                    f"the noise --sigma {res.sigma:.4g} (chi-square {stat:.4g} on {dof} "
                    "degrees of freedom, p < 0.001): the model does not explain the data "
                    "(a wrong problem, units, other parameters?)"]
        return []
    out = []
    for c in data.columns:
        v = c.values[c.measured]
        if data.kind == "modes":
            if rms[c.name] > 0.1:
                out.append(f"poor fit of {c.name}: relative residual RMS {rms[c.name]:.3g} "
                           "(over 10 %): the model does not explain the measured modes")
            continue
        noise = noise_rms(v) if v.size > 3 else 0.0
        floor = POOR_FIT_FLOOR * float(np.ptp(v)) if v.size else 0.0
        if rms[c.name] > max(POOR_FIT_FACTOR * noise, floor) and rms[c.name] > 0:
            out.append(f"poor fit of {c.name}: residual RMS {rms[c.name]:.4g} {c.unit} is "
                       f"{rms[c.name] / max(noise, 1e-300):.3g} times the column's noise "
                       f"{noise:.3g} {c.unit} (estimated from its second differences): the "
                       "model does not explain the data (a wrong problem, units, other "
                       "parameters?)")
    return out
