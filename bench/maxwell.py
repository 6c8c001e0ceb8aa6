"""Generalized Maxwell rods at matched accuracy: kvrod against the Kelvin-Voigt run and
against the strongest SUNDIALS configuration (issue 27).

PLACEHOLDER: the protocol is written once measured.
"""

from __future__ import annotations

import math
import statistics
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from bench import integrators as bi
from bench.energy_audit import audit, output_grid
from bench.idas_script import (Opponent, ReleasedRod, build_function, integrate,
                               released_rod, tip_maxima)

N_MAXIMA = 5            # the first five tip maxima after the release (issue 27)
REF_RTOL = 1e-8
KVROD_RTOL = 1e-6       # the example's rtol: kvrod's default run
FULL = (50, 10.0)
QUICK = (20, 2.0)


def example(name: str = "maxwell_cantilever") -> str:
    from runtime.problem.registry import EXAMPLES_DIR

    return str(EXAMPLES_DIR / f"{name}.toml")


@dataclass(frozen=True)
class Config:
    """A SUNDIALS configuration on the Maxwell rod: solver, build of the ODE form's
    functions, what the error test controls, highest BDF order."""

    solver: str = "idas"
    build: str = "kernels"
    error_control: str = "configuration"
    max_order: int = 5

    @property
    def name(self) -> str:
        what = ("velocities out of the error test" if self.error_control == "configuration"
                else "state in the error test")
        return f"{self.solver} ({self.build}, {what}, max order {self.max_order})"


def first_maxima(t: np.ndarray, x: np.ndarray, k: int = N_MAXIMA) -> np.ndarray:
    """The first k maxima after the release (t > 0), NaN where fewer."""
    out = np.full(k, np.nan)
    after = np.asarray(x)[np.asarray(t) > 0][:k]
    out[:after.size] = after
    return out


# --------------------------------------------------------------------------------------
# kvrod in process (simulate(), as `kvrod simulate` runs it)
# --------------------------------------------------------------------------------------


def kvrod_run(N: int, T: float, rtol: float, error_control: str = "auto") -> dict:
    """``simulate`` of the Maxwell example (N, T, rtol, simulation.error_control): wall
    time, counters, first maxima, kvrod's own energy audit."""
    from runtime.problem.registry import load_problem
    from runtime.simulate.simulate import simulate

    p = load_problem(example(), {"rod.elements": N, "simulation.t_end": T,
                                 "simulation.rtol": rtol,
                                 "simulation.error_control": error_control})
    t0 = time.perf_counter()
    res = simulate(p)
    wall = time.perf_counter() - t0
    if res.status != "finished":
        return {"ok": False, "rtol": rtol, "message": res.message}
    return {"ok": True, "integrator": f"kvrod ({error_control})", "rtol": rtol,
            "wall": wall, "steps": int(res.counters["nstep"]),
            "counters": dict(res.counters), "tip": first_maxima(res.peaks_t, res.peaks_x),
            "audit_own": float(res.audit().max_rel),
            "error_control": res.control.describe()}


# --------------------------------------------------------------------------------------
# The opponent
# --------------------------------------------------------------------------------------

_OPPS: dict[tuple, Opponent] = {}


def opponent(rod: ReleasedRod, cfg: Config) -> Opponent:
    ec = cfg.error_control if cfg.solver == "cvodes" else "state"
    key = (rod.N, rod.problem.name, cfg.build, ec)
    if key not in _OPPS:
        _OPPS[key] = build_function(rod, "ode", cfg.build, error_control=ec)
    return _OPPS[key]


def opponent_run(rod: ReleasedRod, cfg: Config, T: float, rtol: float, repeat: int = 1,
                 grid: np.ndarray | None = None) -> dict:
    opp = opponent(rod, cfg)
    dt = rod.problem.simulation.output_step
    run = integrate(rod, opp, T, dt, rtol, None, cfg.solver, repeat=repeat,
                    error_control=cfg.error_control, max_order=cfg.max_order, grid=grid,
                    keep_states=grid is not None)
    if not run.ok:
        return {"ok": False, "integrator": cfg.name, "rtol": rtol, "message": run.message}
    offset = float(rod.model.reference[rod.tip_x])
    pt, px = tip_maxima(run.t, run.tip_x, run.tip_vx, offset)
    out = {"ok": True, "integrator": cfg.name, "rtol": rtol, "wall": run.wall,
           "walls": run.walls, "steps": run.steps, "us_per_step": run.us_per_step,
           "stats": run.stats, "tip": first_maxima(pt, px)}
    if grid is not None:
        out["audit_grid"] = audit(rod, run.t, run.states)["max_rel"]
    return out
