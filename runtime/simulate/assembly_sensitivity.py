"""Sensitivities of an assembly of rods (issue 34): ``simulate_assembly_sensitivities``
and ``static_assembly_sensitivities``, as :mod:`runtime.simulate.sensitivity` for a
single rod. Channels: per rod ``"NAME.start/<p>"`` and ``"NAME.end/<p>"`` (3, n) (series.npz's
``NAME/start``, ``NAME/end``), ``"NAME.centreline/<p>"`` (m, 3, N+1); statics:
``"NAME.positions/<p>"`` (3, N+1), ``"NAME.start/<p>"``, ``"NAME.end/<p>"`` (3,),
``"y/<p>"`` (n)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from runtime.model.system import refuse_pair_sensitivities
from runtime.problem.parameters import ResolvedParameter, system_directions
from runtime.simulate.sensitivity import Sensitivities, _labels


class AssemblySensitivityRun:
    """What ``simulate_assembly`` does for the
    sensitivities of one run (the assembly's counterpart of ``SensitivityRun``)."""

    def __init__(self, problem, resolved: Sequence[ResolvedParameter],
                 errcon: bool = False) -> None:
        contact = getattr(problem, "contact", None)
        if contact is not None and contact.self_contact:
            # refused here, with the problem, before a results folder is touched (the
            # model refuses it too: SystemModel.set_directions)
            refuse_pair_sensitivities()
        self.problem = problem
        self.resolved = list(resolved)
        self.errcon = errcon
        self.dirs = None
        self.collected: Sensitivities | None = None

    def prepare(self, model) -> None:
        self.dirs = system_directions(self.problem, self.resolved, model)
        model.set_directions(self.dirs)

    def pbar(self) -> np.ndarray:
        return np.array([abs(r.value) if r.value != 0.0 else 1.0 for r in self.resolved])

    def initial(self, model, static_state: np.ndarray | None) -> np.ndarray:
        from runtime.model.system_sensitivity import held_sensitivities, static_sensitivities

        if static_state is not None:
            with model.statics():
                S = static_sensitivities(model, static_state)
            y = model.relaxed(static_state)
            for k, rod in enumerate(model.rods):
                sl = model.rod_slice(k)
                S[:, sl] = rod.relaxed_sensitivities(0.0, y[sl], S[:, sl])
            return S
        return np.array([held_sensitivities(model, i, d.reference)
                         for i, d in enumerate(self.dirs.dirs)])

    def options(self, model, t0: float, y0: np.ndarray, yp0: np.ndarray,
                s0: np.ndarray) -> dict[str, Any]:
        from runtime.solvers.initial import consistent_sensitivities

        s, sp = consistent_sensitivities(model, t0, y0, yp0, s0)
        return {"sensitivities": (s, sp, self.pbar()), "sens_errcon": self.errcon}

    def errors(self) -> dict[str, float]:
        return {r.name: float(d.error) for r, d in zip(self.resolved, self.dirs.dirs,
                                                       strict=True)}

    def collect(self, res, samples: dict, centreline, counters: dict, amap) -> Sensitivities:
        model = amap.model
        sens = samples.get("sens", {})
        labels = _labels(self.resolved)
        channels: dict[str, np.ndarray] = {}
        for i, names in enumerate(labels):
            arrays = {}
            for k, rod_name in enumerate(amap.rod_names):
                for end in ("start", "end"):
                    key = f"{rod_name}/{end}"
                    if key in sens:
                        arrays[f"{rod_name}.{end}"] = sens[key][i]
                if centreline is not None and centreline.srec:
                    k0 = sum(model.rods[j].N + 1 for j in range(k))
                    n_nodes = model.rods[k].N + 1
                    arrays[f"{rod_name}.centreline"] = np.stack(
                        [f[i][:, k0:k0 + n_nodes] for f in centreline.srec])
            for name in names:
                for ch, v in arrays.items():
                    channels[f"{ch}/{name}"] = v
        return Sensitivities(tuple(r.name for r in self.resolved),
                             {r.name: r.value for r in self.resolved}, np.array(res.t),
                             channels,
                             {k: int(v) for k, v in counters.items() if k.endswith("S")},
                             self.errors(),
                             {r.name: lab[1] for r, lab in zip(self.resolved, labels,
                                                               strict=True) if len(lab) > 1})


def simulate_assembly_sensitivities(problem, resolved: Sequence[ResolvedParameter], *,
                                    progress=None, errcon: bool = False, **kwargs):
    """(AssemblyResult, Sensitivities) of an assembly's run (the same steps as without)."""
    from runtime.simulate.assembly import simulate_assembly

    run = AssemblySensitivityRun(problem, resolved, errcon)
    res = simulate_assembly(problem, progress=progress, sensitivity=run, **kwargs)
    sens = run.collected
    if sens is None:
        sens = Sensitivities(tuple(r.name for r in resolved),
                             {r.name: r.value for r in resolved}, np.zeros(0), {}, {})
    return res, sens


def static_assembly_sensitivities(problem, resolved: Sequence[ResolvedParameter]):
    """(AssemblyStatic, Sensitivities) of an assembly's static equilibrium."""
    from runtime.problem.assemble_system import build_system
    from runtime.simulate.assembly import static_equilibrium

    amap = build_system(problem)
    run = AssemblySensitivityRun(problem, resolved)
    run.prepare(amap.model)
    st = static_equilibrium(problem, amap)
    return st, static_assembly_channels(amap, st.y, run)


def static_assembly_channels(amap, y: np.ndarray, run: AssemblySensitivityRun
                             ) -> Sensitivities:
    """The static sensitivities' channels of an assembly (see the module docstring)."""
    from runtime.model.system_sensitivity import static_sensitivities

    model = amap.model
    with model.statics():
        S = static_sensitivities(model, y)
    labels = _labels(run.resolved)
    channels: dict[str, np.ndarray] = {}
    for i, names in enumerate(labels):
        arrays: dict[str, np.ndarray] = {"y": S[i].copy()}
        for k, rod_name in enumerate(amap.rod_names):
            pos = S[i][model.phi_index[k]].T
            arrays[f"{rod_name}.positions"] = pos
            arrays[f"{rod_name}.start"] = pos[:, 0].copy()
            arrays[f"{rod_name}.end"] = pos[:, -1].copy()
        for name in names:
            for ch, v in arrays.items():
                channels[f"{ch}/{name}"] = v
    return Sensitivities(tuple(r.name for r in run.resolved),
                         {r.name: r.value for r in run.resolved}, np.zeros(1), channels,
                         {"static_solves": len(run.resolved)}, run.errors(),
                         {r.name: lab[1] for r, lab in zip(run.resolved, labels, strict=True)
                          if len(lab) > 1})
