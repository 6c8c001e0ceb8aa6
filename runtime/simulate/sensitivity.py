"""Exact sensitivities of a run's outputs to problem parameters (issue 34).

:func:`simulate_with_sensitivities` runs a problem as
:func:`~runtime.simulate.simulate.simulate` does and carries the forward sensitivities of
the state with respect to the parameters asked (IDAS's staggered corrector in the BDF
integrator, ``runtime/solvers/sensitivity.py``; the residual's exact tangent,
``runtime/model/native/rod_tangent.c``): the same steps as the plain run. The initial
sensitivities are those of the static equilibrium (``simulation.initial = "static"``:
implicit function theorem, ``static_sensitivities``) or of the reference at rest
(the geometry's derivative; zero for a material parameter), then made consistent with
the equations at t = 0 (and at every restart of the integrator).

The parameters are named as :mod:`runtime.problem.parameters` resolves them; the
derivative of the rod's numbers with respect to each is exact where their build is
linear in it, a stated Richardson difference elsewhere (``Sensitivities.errors``).

Channels (``Sensitivities.channels``), each shaped like the output it differentiates:
``"tip/<p>"``, ``"start/<p>"`` (3, n) (the ends' positions, series.npz's ``tip`` and
``start``), ``"end_rotation/<p>"``, ``"start_rotation/<p>"`` (3, n) (the ends' rotation
vectors), ``"centreline/<p>"`` (m, 3, N+1) at the frame times; each under the name as
asked and under its unique short alias.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from runtime.problem.parameters import (  # noqa: F401  (the API of this module)
    ResolvedParameter,
    array_directions,
    resolve_parameters,
    with_parameters,
)

__all__ = ["Sensitivities", "ResolvedParameter", "resolve_parameters", "with_parameters",
           "simulate_with_sensitivities", "static_with_sensitivities"]


@dataclass
class Sensitivities:
    """Sensitivities of a run's outputs: ``parameters`` (names as asked), ``values``
    (their values, SI, by name), ``t`` (the output grid, s), ``channels``
    (``"<channel>/<parameter>"`` -> array shaped like the channel: derivative of the
    output per unit of the parameter), ``counters`` (the integrator's sensitivity
    counters), ``errors`` (per parameter: the estimated relative error of the derivative
    of the rod's numbers, 0 where their build is linear in it), ``aliases``
    (name -> the short alias its channels are also stored under)."""

    parameters: tuple[str, ...]
    values: dict[str, float]
    t: np.ndarray
    channels: dict[str, np.ndarray]
    counters: dict[str, int]
    errors: dict[str, float] = field(default_factory=dict)
    aliases: dict[str, str] = field(default_factory=dict)

    def arrays(self) -> dict[str, np.ndarray]:
        """The NPZ content of ``sensitivities.npz``: every channel, ``t``, and the
        ``parameters`` record (structured: name, value, alias, difference error)."""
        rec = np.array([(p, self.values[p], self.aliases.get(p, ""),
                         self.errors.get(p, 0.0)) for p in self.parameters],
                       dtype=[("name", "U200"), ("value", "f8"), ("alias", "U200"),
                              ("difference_error", "f8")])
        return {**self.channels, "t": self.t, "parameters": rec}

    def summary(self) -> dict[str, Any]:
        """What summary.json records of them (the counters are the run's own)."""
        return {"parameters": dict(self.values), "aliases": dict(self.aliases),
                "difference_errors": dict(self.errors),
                "channels": sorted({k.split("/", 1)[0] for k in self.channels}),
                "file": "sensitivities.npz"}


def _labels(resolved: Sequence[ResolvedParameter]) -> list[tuple[str, ...]]:
    """The names each parameter's channels are stored under (an alias shared by two
    parameters asked, or equal to another's name, is left out)."""
    names = {r.name for r in resolved}
    count: dict[str, int] = {}
    for r in resolved:
        if r.alias:
            count[r.alias] = count.get(r.alias, 0) + 1
    out = []
    for r in resolved:
        extra = (r.alias,) if (r.alias and r.alias != r.name and count[r.alias] == 1
                               and r.alias not in names) else ()
        out.append((r.name, *extra))
    return out


class SensitivityRun:
    """What :func:`~runtime.simulate.simulate.simulate` does for the sensitivities of one
    run of a single rod: the directions on the model, the initial sensitivities, the
    solver's options, the channels at the end."""

    def __init__(self, problem, resolved: Sequence[ResolvedParameter],
                 errcon: bool = False) -> None:
        self.problem = problem
        self.resolved = list(resolved)
        self.errcon = errcon
        self.info: list = []
        self.static: np.ndarray | None = None
        #: the run's Sensitivities once it is over (None before, or when the static solve
        #: failed before the integration)
        self.collected: Sensitivities | None = None

    def prepare(self, model) -> None:
        """The parameters' directions on the model (before its static solve)."""
        dirs, self.info = array_directions(self.problem, self.resolved, model.arrays)
        model.set_directions(dirs)

    def pbar(self) -> np.ndarray:
        return np.array([abs(r.value) if r.value != 0.0 else d.step / 1e-3
                         for r, d in zip(self.resolved, self.info, strict=True)])

    def initial(self, model, static_state: np.ndarray | None) -> np.ndarray:
        """The sensitivities of the initial state (k, n) before they are made consistent:
        the static equilibrium's (its relaxation terms relaxed as the state's), or the
        reference's."""
        if static_state is not None:
            from runtime.model.static_sensitivity import static_sensitivities

            with model.statics():
                s = static_sensitivities(model, static_state)
            self.static = s.copy()
            return model.relaxed_sensitivities(0.0, model.relaxed(static_state), s)
        return np.array([d.reference for d in self.info])

    def options(self, model, t0: float, y0: np.ndarray, yp0: np.ndarray,
                s0: np.ndarray) -> dict[str, Any]:
        from runtime.solvers.initial import consistent_sensitivities

        s, sp = consistent_sensitivities(model, t0, y0, yp0, s0)
        return {"sensitivities": (s, sp, self.pbar()), "sens_errcon": self.errcon}

    def collect(self, res, sampler_arrays: dict, centreline, counters: dict
                ) -> Sensitivities:
        """The channels of a finished (or stopped) run."""
        model = res.model
        sens = sampler_arrays.get("sens", {})
        channels: dict[str, np.ndarray] = {}
        labels = _labels(self.resolved)
        rot = self._rotations(res, sens, sampler_arrays)
        for i, names in enumerate(labels):
            arrays = {"tip": sens["tip"][i] if "tip" in sens else np.zeros((3, 0)),
                      "start": sens["start"][i] if "start" in sens else np.zeros((3, 0))}
            held_at = getattr(model.drive, "held_positions", None)
            for end, node, key in (("start", 0, "start"), ("end", model.N, "tip")):
                if node in model.held_nodes and held_at is not None and res.t.size:
                    d = self.info[i].drive
                    if d is not None:     # a held end moves with the parameter exactly
                        arrays[key] = _held_sensitivity(model, i, end, res.t)
            for end, r in rot.items():
                arrays[f"{end}_rotation"] = r[i]
            if centreline is not None and centreline.srec:
                arrays["centreline"] = np.stack([f[i] for f in centreline.srec])
            for name in names:
                for ch, v in arrays.items():
                    channels[f"{ch}/{name}"] = v
        return Sensitivities(
            parameters=tuple(r.name for r in self.resolved),
            values={r.name: r.value for r in self.resolved}, t=np.array(res.t),
            channels=channels,
            counters={k: int(v) for k, v in counters.items() if k.endswith("S")},
            errors={r.name: float(d.error) for r, d in zip(self.resolved, self.info,
                                                           strict=True)},
            aliases={r.name: lab[1] for r, lab in zip(self.resolved, labels, strict=True)
                     if len(lab) > 1})

    def _rotations(self, res, sens: dict, samples: dict) -> dict[str, np.ndarray]:
        """d(end rotation vectors)/d theta, (k, 3, n) per end: the rotation vectors are
        smooth functions of the end segments' quaternions, differentiated along their
        sensitivities by a central difference of that function (relative step 1e-6)."""
        from runtime.model.quaternion import quat_log, quat_mul
        from runtime.simulate.simulate import reference_end_quaternions

        model = res.model
        if "p_first" not in sens or not res.t.size:
            return {}
        ref = reference_end_quaternions(model)
        conj = np.array([1.0, -1.0, -1.0, -1.0])
        first, last = samples["p_first"].T, samples["p_last"].T   # (m, 4k) each
        out: dict[str, list[np.ndarray]] = {"start": [], "end": []}
        eps = 1e-6
        for i in range(len(self.resolved)):
            dq = {"first": sens["p_first"][i].T, "last": sens["p_last"][i].T}

            def rv(sign: float, i=i, dq=dq) -> dict[str, np.ndarray]:
                q = model.end_quaternions(res.t, first + sign * eps * dq["first"],
                                          last + sign * eps * dq["last"])
                return {end: quat_log(quat_mul(v, ref[end] * conj)).T for end, v in q.items()}

            p, m = rv(1.0), rv(-1.0)
            for end in out:
                d = (p[end] - m[end]) / (2 * eps)
                if model.arrays.clamped(end):       # the clamp frame: prescribed
                    d = (_clamp_rotation_sensitivity(model, i, end, res.t, ref)
                         if self.info[i].drive is not None else np.zeros_like(d))
                out[end].append(d)
        return {end: np.array(v) for end, v in out.items()}


def _held_sensitivity(model, i: int, end: str, ts: np.ndarray) -> np.ndarray:
    """d(prescribed position of a held end)/d theta_i at the times ts (3, m): the
    parameter's direction of the driven entries at each time."""
    d = model.directions
    out = np.empty((3, ts.size))
    for j, t in enumerate(ts):
        model.at(float(t))
        out[:, j] = d.arrays[i].param("r_" + end)
    return out


def _clamp_rotation_sensitivity(model, i: int, end: str, ts: np.ndarray, ref) -> np.ndarray:
    """d(rotation vector of a clamped end)/d theta_i (3, m): from the clamp frame's
    direction at each time (a prescribed rotation whose angle is the parameter)."""
    from runtime.model.quaternion import quat_log, quat_mul

    conj = np.array([1.0, -1.0, -1.0, -1.0])
    d = model.directions.arrays[i]
    out = np.empty((3, ts.size))
    eps = 1e-6
    for j, t in enumerate(ts):
        model.at(float(t))
        p = model.arrays.param("p_" + end).copy()
        dp = d.param("p_" + end).copy()
        a = quat_log(quat_mul((p + eps * dp) / np.linalg.norm(p + eps * dp), ref[end] * conj))
        b = quat_log(quat_mul((p - eps * dp) / np.linalg.norm(p - eps * dp), ref[end] * conj))
        out[:, j] = (a - b) / (2 * eps)
    return out


def simulate_with_sensitivities(problem, parameters: Sequence[str], *,
                                progress: Callable[[float], object] | None = None,
                                errcon: bool = False, **kwargs):
    """Run ``problem`` (a Problem; an Assembly: ``runtime.simulate.assembly``) with
    the forward sensitivities of its outputs to ``parameters`` (names as
    ``resolve_parameters`` takes them; validated before anything runs).

    Returns ``(result, Sensitivities)``: the run's result as ``simulate`` gives it
    (the same steps) and the sensitivities on its output grid. ``errcon``: the
    sensitivities in the error test (IDAS's errconS; the steps may then differ).
    Further keyword arguments go to ``simulate``."""
    from runtime.problem.schema import Problem

    resolved = resolve_parameters(problem, parameters)
    if not isinstance(problem, Problem):
        from runtime.simulate.assembly_sensitivity import simulate_assembly_sensitivities

        return simulate_assembly_sensitivities(problem, resolved, progress=progress,
                                               errcon=errcon, **kwargs)
    from runtime.simulate.simulate import simulate

    run = SensitivityRun(problem, resolved, errcon)
    res = simulate(problem, progress=progress, sensitivity=run, **kwargs)
    sens = run.collected
    if sens is None:          # the static solve failed: nothing integrated
        sens = Sensitivities(tuple(r.name for r in resolved),
                             {r.name: r.value for r in resolved}, np.zeros(0), {}, {})
    return res, sens


def static_with_sensitivities(problem, parameters: Sequence[str]):
    """The static equilibrium of ``problem``
    (:func:`~runtime.simulate.simulate.static_equilibrium`) and its sensitivities to
    ``parameters`` by the implicit function theorem (one factorisation of the static
    Jacobian, every parameter a solve).

    Returns ``(StaticOutcome, Sensitivities)`` with the channels of static.npz and the
    static summary (``static_sensitivity_channels``); ``t`` = [0]."""
    from runtime.problem.schema import Problem

    resolved = resolve_parameters(problem, parameters)
    if not isinstance(problem, Problem):
        from runtime.simulate.assembly_sensitivity import static_assembly_sensitivities

        return static_assembly_sensitivities(problem, resolved)
    from runtime.problem.assemble import build_model
    from runtime.simulate.simulate import static_equilibrium

    model = build_model(problem)
    run = SensitivityRun(problem, resolved)
    run.prepare(model)
    outcome = static_equilibrium(problem, model)
    return outcome, static_sensitivity_channels(model, outcome.y, run)


def static_sensitivity_channels(model, y: np.ndarray, run: SensitivityRun) -> Sensitivities:
    """The sensitivities of a rod's static equilibrium ``y`` (its model carrying the
    directions of ``run``, ``SensitivityRun.prepare``): channels ``"y/<p>"`` (n),
    ``"positions/<p>"`` (3, N+1), ``"tip/<p>"``, ``"start/<p>"`` (3,) (static.npz's and
    the summary's), ``"end_rotation/<p>"``, ``"start_rotation/<p>"`` (3,)."""
    from runtime.model.static_sensitivity import static_sensitivities

    with model.statics():
        S = static_sensitivities(model, y)
    resolved = run.resolved
    labels = _labels(resolved)
    channels: dict[str, np.ndarray] = {}
    rot = _static_rotations(model, y, S)
    for i, names in enumerate(labels):
        pos = S[i][model.phi_index].T
        arrays = {"y": S[i].copy(), "positions": pos, "tip": pos[:, -1].copy(),
                  "start": pos[:, 0].copy()}
        for end, r in rot.items():
            arrays[f"{end}_rotation"] = r[i]
        for name in names:
            for ch, v in arrays.items():
                channels[f"{ch}/{name}"] = v
    return Sensitivities(tuple(r.name for r in resolved), {r.name: r.value for r in resolved},
                         np.zeros(1), channels, {"static_solves": len(resolved)},
                         {r.name: float(d.error) for r, d in zip(resolved, run.info,
                                                                 strict=True)},
                         {r.name: lab[1] for r, lab in zip(resolved, labels, strict=True)
                          if len(lab) > 1})


def _static_rotations(model, y: np.ndarray, S: np.ndarray) -> dict[str, np.ndarray]:
    """d(end rotation vectors)/d theta of a static state, (k, 3) per end (a central
    difference of the smooth map from the end segments' quaternions, relative step
    1e-6)."""
    from runtime.model.quaternion import quat_log, quat_mul
    from runtime.simulate.simulate import reference_end_quaternions

    ref = reference_end_quaternions(model)
    conj = np.array([1.0, -1.0, -1.0, -1.0])
    idx = model.end_segments()
    out: dict[str, list] = {"start": [], "end": []}
    eps = 1e-6
    t = np.zeros(1)
    for i in range(S.shape[0]):
        vals = {}
        for sign in (1.0, -1.0):
            ys = y + sign * eps * S[i]
            with model.statics():
                q = model.end_quaternions(t, ys[idx["first"]][None], ys[idx["last"]][None])
            vals[sign] = {end: quat_log(quat_mul(v, ref[end] * conj))[0] for end, v in q.items()}
        for end in out:
            out[end].append((vals[1.0][end] - vals[-1.0][end]) / (2 * eps))
    return {end: np.array(v) for end, v in out.items()}
