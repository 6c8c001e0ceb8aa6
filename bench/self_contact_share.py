"""Self-contact's share of a step at N = 1000 (issue 32, item 6: "contact search and
forces take at most 30 % of a step at N = 1000 with self-contact on").

The rod: a coil spring whose turns touch, N = 1000 (10 turns of coil radius 5 cm, a 3 mm
round wire, pitch 2 r + 10 um: every segment has the segments one turn up and one turn
down in reach, about 2,000 pairs), clamped at its lower end, free at the top, settling
under its own weight with ``contact.self = true`` for ``T`` seconds.

- **Search and forces per residual**: the rod's residual in the touching state with
  self-contact on minus the same rod's residual without it (``contact`` removed), each the
  median of ``CALLS`` calls: the broad phase, the pair kernels and their forces.
- **A step**: ``simulate()``'s loop over the run (the counters' steps), in process, with
  self-contact on.
- **Share**: search-and-forces per residual times residuals per step, over the time per
  step. Besides it the whole extra cost of a step with self-contact (couplings in the
  Jacobian, their factorisation) is given as 1 - (time per step without) / (time per step
  with), from the same run without ``contact``; without contact the turns pass through one
  another, so that run's steps differ, and only its cost per step is used.
"""

from __future__ import annotations

import math
import os
import statistics
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

N_FULL, T_FULL = 1000, 0.005
N_QUICK, T_QUICK = 200, 0.005
CALLS = 50
#: issue 32: search and forces at most this share of a step
SHARE_MAX = 0.30
R_WIRE, R_COIL, TURNS = 0.003, 0.05, 10.0


def problem(N: int, T: float, self_contact: bool) -> dict[str, Any]:
    """The coil's problem mapping (module docstring)."""
    m: dict[str, Any] = {
        "name": "touching_coil" if self_contact else "coil_without_contact",
        "description": "coil spring with touching turns settling under its weight",
        "rod": {"elements": int(N),
                "geometry": {"kind": "helix", "coil_radius": R_COIL,
                             "pitch": 2 * R_WIRE + 1e-5, "turns": TURNS,
                             "handedness": "right", "axis": [0.0, 0.0, 1.0],
                             "radial": [1.0, 0.0, 0.0]}},
        "section": {"kind": "circle", "radius": R_WIRE},
        "material": {"youngs_modulus": 1e7, "poisson_ratio": 0.45, "density": 1100.0,
                     "tau": 0.01},
        "start": {"kind": "clamped"},
        "end": {"kind": "free"},
        "loads": [{"kind": "gravity", "vector": [0.0, 0.0, -9.81]}],
        "simulation": {"t_end": float(T), "output_step": float(T) / 4,
                       "initial": "reference"},
    }
    if self_contact:
        m["contact"] = {"self": True}
    return m


def _load(mapping: dict, folder: Path):
    from runtime.io.results import write_problem
    from runtime.problem.registry import load_problem

    path = folder / f"{mapping['name']}.toml"
    write_problem(path, mapping)
    return load_problem(path)


def _residual_seconds(model, y: np.ndarray) -> float:
    yp = np.zeros_like(y)
    out = np.empty_like(y)
    model.residual(0.0, y, yp, out)                        # first call: buffers, pairs
    times = []
    for _ in range(CALLS):
        t0 = time.perf_counter()
        model.residual(0.0, y, yp, out)
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def run(quick: bool = False, log=print) -> dict[str, Any]:
    """The measurement's document (module docstring)."""
    from runtime.problem.assemble import build_model
    from runtime.simulate.simulate import simulate

    N, T = (N_QUICK, T_QUICK) if quick else (N_FULL, T_FULL)
    doc: dict[str, Any] = {"N": N, "T": T, "quick": quick,
                           "load_average_at_start": [round(v, 2) for v in os.getloadavg()]}
    with tempfile.TemporaryDirectory(prefix="kvrod-bench-selfcontact-") as tmp:
        on = _load(problem(N, T, True), Path(tmp))
        off = _load(problem(N, T, False), Path(tmp))
        m_on, m_off = build_model(on), build_model(off)
        y = m_on.initial_state(0.0)
        pairs = int(m_on.self_contact_values(0.0, y)["pairs"])
        r_on, r_off = _residual_seconds(m_on, y), _residual_seconds(m_off, y)
        runs = {}
        for key, p in (("on", on), ("off", off)):
            t0 = time.perf_counter()
            res = simulate(p)
            wall = time.perf_counter() - t0
            c = res.counters
            runs[key] = {"status": res.status, "wall": wall, "steps": c["nstep"],
                         "residuals": c["nfev"], "jacobians": c["njev"],
                         "per_step": wall / max(c["nstep"], 1),
                         "audit": res.summary()["energy_balance_max_rel"]}
            log(f"  {key}: {c['nstep']} steps, {wall:.2f} s, {res.status}")
    a = runs["on"]
    search_forces = max(r_on - r_off, 0.0)
    share = search_forces * a["residuals"] / a["steps"] / a["per_step"]
    extra = 1.0 - runs["off"]["per_step"] / a["per_step"]
    doc.update({"pairs_in_reach": pairs, "residual_on_s": r_on, "residual_off_s": r_off,
                "runs": runs, "share_search_forces": share, "share_all_contact": extra,
                "load_average_at_end": [round(v, 2) for v in os.getloadavg()]})
    log(f"  residual {1e3 * r_on:.2f} ms with self-contact ({pairs} pairs in reach), "
        f"{1e3 * r_off:.2f} ms without; search and forces {100 * share:.1f} % of a step, "
        f"all contact costs {100 * extra:.0f} %")
    return doc


def markdown(doc: dict) -> list[str]:
    """Lines of the contact section's README part."""
    if not doc:
        return []
    a, b = doc["runs"]["on"], doc["runs"]["off"]
    share, extra = doc["share_search_forces"], doc["share_all_contact"]
    return [
        f"Self-contact at N = {doc['N']} (bench/self_contact_share.py: a coil of touching "
        f"turns settling for {doc['T']:g} s, {doc['pairs_in_reach']} pairs in reach; load "
        f"{doc['load_average_at_start']}): residual {1e3 * doc['residual_on_s']:.2f} ms "
        f"with self-contact, {1e3 * doc['residual_off_s']:.2f} ms without; with it "
        f"{a['steps']} steps of {1e3 * a['per_step']:.1f} ms ({a['residuals']} residuals, "
        f"{a['jacobians']} Jacobians, audit {a['audit']:.1e}), without it "
        f"{1e3 * b['per_step']:.1f} ms a step. Search and forces: "
        f"{100 * share:.1f} % of a step; every cost of the contact together (the "
        f"couplings in the Jacobian and their factorisation too): "
        f"{100 * extra:.0f} % of a step." if math.isfinite(extra) else "", ""]
