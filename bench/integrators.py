"""kvrod's BDF against SUNDIALS (IDAS, CVODES through CasADi) and SciPy at matched accuracy.

The problem is the paper's cantilever (Sect. 5, ``examples/cantilever.toml``): L = 0.3 m,
1 cm x 1 cm, rho = 1000 kg/m^3, E = 1 MPa, nu = 0.3, tau_S = tau_B = 0.04 s, clamped at
s = 0, free at s = L. The static equilibrium under the dead tip force 0.05 N along e1
(``static_equilibrium``) is released at rest (the force's "release" time function is off
from t = 0) and integrated over ``T`` seconds (:func:`bench.idas_script.released_rod`).

Accuracy is the largest tip-x error over an output grid of 100 points per second against
a reference run of kvrod at rtol = 1e-9 (cross-checked against IDAS at 1e-9). Every
integrator gets the same per-component absolute tolerances, kvrod's ``default_atol`` at
its rtol (the ones ``kvrod simulate`` uses: per field, scaled by the motion; 1e-3 rtol
times 0.22 m for positions), and its rtol is scanned in half decades; the loosest rtol with
max tip error <= 1e-5 m is the "matched" run. The matched runs are then timed again,
alternating kvrod and each opponent (A B A B ...), and the medians are compared.

How each integrator sees the rod (the residual is linear in y' with a constant diagonal
``D = dF/dy'``: F = D y' + g(t, y); only the clamped node's velocity is algebraic):

- kvrod: ``F(t, y, y') = 0`` and its banded iteration matrix from the compiled kernels
  (ctypes), LAPACK band LU (``runtime.solvers.integrator.solve`` with ``t_eval``).
- SUNDIALS, the strong configurations (:mod:`bench.idas_script`): the ODE form
  ``y_d' = -g_d(t, y)/D_d`` in per-component scaled variables (or the semi-explicit DAE
  form), residual and exact sparse Jacobian expanded to SX and generated flat into one C
  library (gcc -O2 -march=native, cached by content hash), CSparse sparse LU, IDAS with
  ``abstolv`` (or CVODES, whose scalar abstol is per component through the scaling), the
  consistent initial derivative given (``init_xdot``). The flat C grows with N (5.5 MB at
  N = 50); where gcc cannot build it in reasonable time and memory (N = 1000) the "map"
  build stands in: the MX function over the per-element kernels, generated and compiled
  the same way (C loops over kernel calls, size independent of N).
- Earlier configurations, kept for comparison (:func:`idas_configs`): the DAE form with
  CasADi's own integrator ``jit`` (gcc -O2 on the functions the integrator derives from
  the MX function), the MX function generated and compiled here ("map", the earlier
  "external"), the SX and MX virtual machines; CSparse or CasADi's default QR.
- SciPy ``solve_ivp`` (Radau, BDF): the ODE form on the differential components,
  compiled residual through ctypes, sparse Jacobian ``-D^-1 dg/dy`` (CSC, fixed pattern).
  Fair up to SciPy's per-call Python overhead, which is part of what a SciPy user pays.

Per-step cost = wall time / accepted steps (kvrod ``nstep``, SUNDIALS ``nsteps``).
"""

from __future__ import annotations

import atexit
import contextlib
import math
import shutil
import statistics
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import scipy.sparse as sp
from scipy.integrate import solve_ivp

from bench.idas_script import Opponent, ReleasedRod, build_function, integrate, released_rod
from runtime import native
from runtime.solvers.integrator import solve

TIP_TOL = 1e-5  # m, matched accuracy: max tip-x error over the run
REF_RTOL = 1e-9
RTOL_SCAN = (1e-3, 3e-4, 1e-4, 3e-5, 1e-5, 3e-6, 1e-6, 3e-7, 1e-7, 3e-8, 1e-8)
OUT_PER_SECOND = 100
#: repeats of each matched run in the final alternating comparison (medians)
DUEL_REPEATS = 7


@dataclass(frozen=True)
class Config:
    """A SUNDIALS configuration: solver, form, function build, linear solver, CasADi's
    integrator jit, scalar atol = rtol (the earlier protocol) instead of default_atol."""

    solver: str = "idas"
    form: str = "ode"
    build: str = "flat"
    linear_solver: str = "csparse"
    jit: bool = False
    scalar_atol: bool = False

    @property
    def name(self) -> str:
        b = "jit" if self.jit else self.build
        s = f"{self.solver} ({self.form}, {b}, {self.linear_solver}"
        return s + (", atol = rtol)" if self.scalar_atol else ")")


#: the strong configurations compared at matched accuracy, per N (flat up to 200)
STRONG = (Config("idas", "ode", "flat"), Config("cvodes", "ode", "flat"),
          Config("idas", "ode", "kernels"), Config("cvodes", "ode", "kernels"))
STRONG_LARGE = (Config("idas", "ode", "kernels"), Config("cvodes", "ode", "kernels"))
STRONG_QUICK = STRONG_LARGE
#: every configuration of the N = 50 table (the earlier ones last)
ALL_CONFIGS = (
    Config("idas", "ode", "flat"), Config("cvodes", "ode", "flat"),
    Config("idas", "dae", "flat"), Config("idas", "ode", "kernels"),
    Config("cvodes", "ode", "kernels"), Config("idas", "ode", "map"),
    Config("idas", "ode", "sx"),
    Config("idas", "dae", "mx", jit=True), Config("idas", "dae", "mx", "qr", jit=True),
    Config("idas", "dae", "map"), Config("idas", "dae", "sx"), Config("idas", "dae", "mx"),
    Config("idas", "dae", "mx", jit=True, scalar_atol=True),
)
#: the flat C grows with N: 5.5 MB at N = 50 (gcc -O2 ~45 s), 22 MB at N = 200 (~340 s,
#: 3.5 GB); at N = 1000 it would be ~110 MB, beyond this machine (23 GB, 2 cores)
FLAT_MAX_N = 200
FLAT_SKIPPED = ("flat SX build not made for N > 200: its C grows linearly with N (5.5 MB at "
                "N = 50, 22 MB at N = 200, where gcc -O2 took 255-340 s and 3.5-3.8 GB); N = 1000 "
                "would be ~110 MB of straight-line C")


def strong_configs(N: int, quick: bool = False) -> tuple[Config, ...]:
    if quick:
        return STRONG_QUICK
    return STRONG if N <= FLAT_MAX_N else STRONG_LARGE


# --------------------------------------------------------------------------------------
# The scenario
# --------------------------------------------------------------------------------------

_RODS: dict[tuple[int, float, float | None], ReleasedRod] = {}
_REFS: dict[tuple[int, float], np.ndarray] = {}  # reference tip x per (N, T)
_OPPS: dict[tuple[int, str, str], Opponent] = {}


def rod(N: int, T: float = 10.0, tau: float | None = None) -> ReleasedRod:
    """The released cantilever with N elements (tau: tau_S = tau_B, default 0.04 s)."""
    key = (N, T, tau)
    if key not in _RODS:
        _RODS[key] = released_rod(N, T, overrides=None if tau is None else {"tau": tau})
    return _RODS[key]


def grid(T: float) -> np.ndarray:
    return np.linspace(0.0, T, int(round(OUT_PER_SECOND * T)) + 1)


def opponent(r: ReleasedRod, form: str, build_kind: str) -> Opponent:
    key = (r.N, form, build_kind)
    if key not in _OPPS or _OPPS[key].fn is None:
        _OPPS[key] = build_function(r, form, build_kind)
    return _OPPS[key]


def tip_error(tip: np.ndarray, ref: np.ndarray) -> float:
    return float(np.max(np.abs(np.asarray(tip) - ref)))


def _median_time(fn, repeat: int) -> tuple[float, list[float], Any]:
    walls, out = [], None
    for _ in range(max(1, repeat)):
        t0 = time.perf_counter()
        out = fn()
        walls.append(time.perf_counter() - t0)
    return statistics.median(walls), walls, out


# --------------------------------------------------------------------------------------
# kvrod
# --------------------------------------------------------------------------------------


def run_kvrod(r: ReleasedRod, T: float, rtol: float, repeat: int = 1,
              atol: float | np.ndarray | None = None, **options: Any) -> dict:
    """kvrod's BDF on the released rod (default_atol at rtol): wall time (median of
    ``repeat``), counters, tip x on the output grid."""
    g = grid(T)
    a = r.atol(rtol) if atol is None else atol

    def go():
        return solve(r.model, (0.0, T), r.y0, r.yp0, rtol=rtol, atol=a, t_eval=g, **options)

    wall, walls, s = _median_time(go, repeat)
    if not s.success:
        return {"integrator": "kvrod", "rtol": rtol, "ok": False, "message": s.message,
                "wall": wall}
    k = s.counters
    return {"integrator": "kvrod", "rtol": rtol, "ok": True, "wall": wall, "walls": walls,
            "steps": k["nstep"], "us_per_step": 1e6 * wall / k["nstep"], "nfev": k["nfev"],
            "njev": k["njev"], "nlu": k["nlu"], "nni": k["nni"], "netf": k["netf"],
            "ncfn": k["ncfn"], "tip": s.y[r.tip_x]}


# --------------------------------------------------------------------------------------
# SUNDIALS through CasADi
# --------------------------------------------------------------------------------------

_CC_CACHE = """#!/bin/sh
# CasADi's shell-compiler call "cc FLAGS -c SRC -o OBJ" (or a link step), cached by the
# SHA-256 of SRC: an integrator rebuilt for another rtol generates the same C.
src=""; obj=""; prev=""
for a in "$@"; do
  [ "$prev" = "-c" ] && src="$a"
  [ "$prev" = "-o" ] && obj="$a"
  prev="$a"
done
case "$src" in *.c) ;; *) exec {cc} "$@" ;; esac
key=$(cat "$src" | sha256sum | cut -c1-32)
if [ -f "{dir}/$key.o" ]; then cp "{dir}/$key.o" "$obj"; exit 0; fi
{cc} "$@" && cp "$obj" "{dir}/$key.o"
"""
_JIT_DIR: Path | None = None


def _jit_options() -> dict:
    """CasADi integrator options to jit-compile its DAE functions (gcc -O2, cached by
    source hash for this process)."""
    global _JIT_DIR
    cc = native.find_compiler()
    if cc is None:
        raise RuntimeError("no C compiler for CasADi's jit")
    if _JIT_DIR is None:
        _JIT_DIR = Path(tempfile.mkdtemp(prefix="kvrod_jit_"))
        atexit.register(shutil.rmtree, _JIT_DIR, True)
        script = _JIT_DIR / "cc_cache.sh"
        script.write_text(_CC_CACHE.replace("{cc}", cc).replace("{dir}", str(_JIT_DIR)))
        script.chmod(0o755)
    return {"jit": True, "compiler": "shell", "jit_temp_suffix": False,
            "jit_options": {"compiler": str(_JIT_DIR / "cc_cache.sh"), "linker": cc,
                            "flags": ["-O2"], "directory": str(_JIT_DIR) + "/"}}


def run_sundials(r: ReleasedRod, cfg: Config, T: float, rtol: float,
                 repeat: int = 1) -> dict:
    """One SUNDIALS configuration on the released rod at rtol (atol: default_atol, or
    rtol for ``cfg.scalar_atol``): median wall time of the integrator call, set-up
    time, counters, tip x on the output grid."""
    opp = opponent(r, cfg.form, cfg.build)
    extra = None
    ctx: Any = contextlib.nullcontext()
    if cfg.jit:
        extra = _jit_options()
        ctx = contextlib.chdir(_JIT_DIR)   # CasADi writes the jit source to the cwd
    atol = rtol if cfg.scalar_atol else None
    with ctx:
        run = integrate(r, opp, T, 1.0 / OUT_PER_SECOND, rtol, atol, cfg.solver,
                        cfg.linear_solver, repeat=repeat, extra=extra)
    if not run.ok:
        return {"integrator": cfg.name, "rtol": rtol, "ok": False, "message": run.message}
    st = run.stats
    nls = st.get("nlinsetups", 0)
    return {"integrator": cfg.name, "rtol": rtol, "ok": True, "wall": run.wall,
            "walls": run.walls, "setup_seconds": run.setup, "steps": run.steps,
            "us_per_step": run.us_per_step, "nfev": st.get("nfevals"), "njev": nls,
            "nlu": nls, "nni": st.get("nniters"), "netf": st.get("netfails"),
            "ncfn": st.get("nncfails"), "tip": run.tip_x}


def opponent_info(r: ReleasedRod, cfg: Config) -> dict:
    opp = opponent(r, cfg.form, cfg.build)
    return {"config": cfg.name, "cached": opp.cached, "seconds": dict(opp.seconds),
            "c_bytes": opp.c_bytes}


# --------------------------------------------------------------------------------------
# SciPy solve_ivp on the ODE form
# --------------------------------------------------------------------------------------


class OdeForm:
    """y_d' = -g_d(t, y)/D_d on the differential components (algebraic ones fixed)."""

    def __init__(self, r: ReleasedRod) -> None:
        m = self.model = r.model
        self.di = r.di
        self.D = r.D[self.di]
        self.y = r.y0.copy()  # algebraic entries stay at their consistent values
        self.zero = np.zeros(m.n)
        self.res = np.empty(m.n)
        self._sel = sp.diags(-1.0 / self.D) @ sp.eye(m.n, format="csr")[self.di]

    def rhs(self, t: float, yd: np.ndarray) -> np.ndarray:
        self.y[self.di] = yd
        self.model.residual(t, self.y, self.zero, self.res)
        return -self.res[self.di] / self.D

    def jac(self, t: float, yd: np.ndarray) -> sp.csc_matrix:
        self.y[self.di] = yd
        J = self.model.dF_dy_sparse(t, self.y, self.zero)
        return (self._sel @ J[:, self.di]).tocsc()


def run_scipy(r: ReleasedRod, T: float, rtol: float, method: str) -> dict:
    g = grid(T)
    atol = r.atol(rtol)

    def go():
        ode = OdeForm(r)
        return ode, solve_ivp(ode.rhs, (0.0, T), r.y0[ode.di], method=method, t_eval=g,
                              rtol=rtol, atol=atol[ode.di], jac=ode.jac)

    wall, _, (ode, sol) = _median_time(go, 1)
    name = f"scipy {method}"
    if not sol.success:
        return {"integrator": name, "rtol": rtol, "ok": False, "message": sol.message,
                "wall": wall}
    k = int(np.nonzero(ode.di == r.tip_x)[0][0])
    return {"integrator": name, "rtol": rtol, "ok": True, "wall": wall, "steps": None,
            "nfev": int(sol.nfev), "njev": int(sol.njev), "nlu": int(sol.nlu),
            "tip": sol.y[k]}


# --------------------------------------------------------------------------------------
# Matched accuracy
# --------------------------------------------------------------------------------------


def matched(runner, ref: np.ndarray, rtols=RTOL_SCAN, budget: float = math.inf,
            start: float | None = None) -> dict:
    """The loosest rtol of the scan with max tip error <= TIP_TOL, and the runs made.

    Without ``start``: from loose to tight, stopping at the first pass. With ``start`` (an
    rtol of the scan, e.g. another integrator's match): from there looser while it
    passes, or tighter until it passes. A run slower than ``budget`` s ends the scan.
    """
    rtols = list(rtols)
    scan: list[dict] = []

    def attempt(rtol: float) -> dict:
        r = runner(rtol)
        if r.get("ok"):
            r["tip_error"] = tip_error(r["tip"], ref)
        entry = {k: v for k, v in r.items() if k != "tip"}
        entry["pass"] = bool(r.get("ok") and r["tip_error"] <= TIP_TOL)
        scan.append(entry)
        return entry

    if start is None or start not in rtols:
        order = rtols
    else:
        i0 = rtols.index(start)
        e = attempt(start)
        if e["pass"]:
            best = e
            for rtol in reversed(rtols[:i0]):
                e = attempt(rtol)
                if not e["pass"]:
                    break
                best = e
            return {"matched": best, "scan": scan}
        if e.get("wall", 0.0) > budget:
            return {"matched": None, "scan": scan}
        order = rtols[i0 + 1:]
    for rtol in order:
        e = attempt(rtol)
        if e["pass"]:
            return {"matched": e, "scan": scan}
        if e.get("wall", 0.0) > budget:
            break
    return {"matched": None, "scan": scan}


def duel(r: ReleasedRod, T: float, kvrod_rtol: float, opponents: dict[str, tuple[Config,
         float]], repeats: int = DUEL_REPEATS) -> dict:
    """Alternate kvrod and every opponent at their matched rtols ``repeats`` times
    (A B C A B C ...); median wall time, per-step cost and all walls of each, and for each
    opponent the median of the paired ratios kvrod / opponent (repeat by repeat, so that
    the ratio holds when the machine's speed drifts)."""
    names = ["kvrod", *opponents]
    walls: dict[str, list[float]] = {k: [] for k in names}
    steps: dict[str, int] = {}
    for _ in range(repeats):
        k = run_kvrod(r, T, kvrod_rtol)
        walls["kvrod"].append(k["wall"])
        steps["kvrod"] = k["steps"]
        for name, (cfg, rtol) in opponents.items():
            o = run_sundials(r, cfg, T, rtol)
            walls[name].append(o["wall"])
            steps[name] = o["steps"]
    out = {}
    for name in names:
        med = statistics.median(walls[name])
        out[name] = {"median": med, "walls": walls[name], "steps": steps[name],
                     "us_per_step": 1e6 * med / steps[name]}
        if name != "kvrod":
            out[name]["paired_ratio_kvrod_over_this"] = statistics.median(
                a / b for a, b in zip(walls["kvrod"], walls[name], strict=True))
    return out


def compare(N: int, T: float, configs: tuple[Config, ...], scipy_methods=("BDF", "Radau"),
            scipy_budget: float = 60.0, cross_check: Config | None = None,
            repeats: int = DUEL_REPEATS, log=print) -> dict:
    """Reference, cross-check, matched-accuracy scans of kvrod and every configuration,
    then the alternating timing of the matched runs, for N elements."""
    r = rod(N, T)
    ref_run = run_kvrod(r, T, REF_RTOL)
    ref = _REFS[(N, T)] = ref_run["tip"]
    out: dict[str, Any] = {"N": N, "n": r.n, "T": T, "static_seconds": r.static_seconds,
                           "reference": {k: v for k, v in ref_run.items() if k != "tip"},
                           "builds": {}}
    for cfg in configs:
        t0 = time.perf_counter()
        info = opponent_info(r, cfg)
        info["wall_seconds"] = time.perf_counter() - t0
        out["builds"][cfg.name] = info
        log(f"  N={N}: {cfg.name}: functions ready in {info['wall_seconds']:.1f} s "
            f"({'cached library' if info['cached'] else info['seconds']})")
    cc = cross_check or configs[0]
    idas_ref = run_sundials(r, cc, T, REF_RTOL)
    out["cross_check"] = {"config": cc.name, "rtol": REF_RTOL, "wall": idas_ref.get("wall"),
                          "steps": idas_ref.get("steps"),
                          "max_tip_diff": tip_error(idas_ref["tip"], ref)
                          if idas_ref.get("ok") else None}
    log(f"  N={N}: reference {ref_run['wall']:.2f} s; {cc.name} at 1e-9 differs by "
        f"{out['cross_check']['max_tip_diff']}")
    out["kvrod"] = matched(lambda rt: run_kvrod(r, T, rt), ref)
    log(f"  N={N}: kvrod {_fmt(out['kvrod'])}")
    start = out["kvrod"]["matched"]["rtol"] if out["kvrod"]["matched"] else None
    out["opponents"] = {}
    for cfg in configs:
        out["opponents"][cfg.name] = matched(lambda rt, c=cfg: run_sundials(r, c, T, rt),
                                             ref, start=start)
        log(f"  N={N}: {cfg.name} {_fmt(out['opponents'][cfg.name])}")
    for method in scipy_methods:
        key = f"scipy {method}"
        out["opponents"][key] = matched(lambda rt, m=method: run_scipy(r, T, rt, m), ref,
                                        budget=scipy_budget)
        log(f"  N={N}: {key} {_fmt(out['opponents'][key])}")
    # alternating timing of the matched runs
    contenders = {c.name: (c, out["opponents"][c.name]["matched"]["rtol"]) for c in configs
                  if out["opponents"][c.name]["matched"]}
    if out["kvrod"]["matched"] and contenders:
        out["duel"] = duel(r, T, out["kvrod"]["matched"]["rtol"], contenders, repeats)
        d = out["duel"]
        best = min(contenders, key=lambda c: d[c]["median"])
        idas = [c for c in contenders if c.startswith("idas")]
        best_idas = min(idas, key=lambda c: d[c]["median"]) if idas else None
        out["strongest"] = best
        out["strongest_idas"] = best_idas
        out["ratio_kvrod_over_strongest"] = d[best]["paired_ratio_kvrod_over_this"]
        out["ratio_kvrod_over_strongest_idas"] = (
            d[best_idas]["paired_ratio_kvrod_over_this"] if best_idas else None)
        log(f"  N={N}: duel medians: " + ", ".join(
            f"{n} {d['median']:.3f} s ({d['us_per_step']:.0f} us/step)"
            for n, d in out["duel"].items()))
    return out


def _fmt(m: dict) -> str:
    r = m["matched"]
    if r is None:
        return "no rtol in the scan reached the accuracy"
    steps = r.get("steps")
    return (f"rtol {r['rtol']:.0e}: {r['wall']:.3f} s, {steps if steps else '-'} steps, "
            f"err {r['tip_error']:.1e}")


def idas_configs(N: int, T: float, rtol: float, configs=ALL_CONFIGS, repeat: int = 3,
                 log=print) -> list[dict]:
    """Every configuration (and kvrod) at one rtol: build/compile times, median wall
    time of ``repeat`` integrations, per-step cost, counters and tip error."""
    r = rod(N, T)
    if (N, T) not in _REFS:
        _REFS[(N, T)] = run_kvrod(r, T, REF_RTOL)["tip"]
    ref = _REFS[(N, T)]
    rows = []
    k = run_kvrod(r, T, rtol, repeat=repeat)
    rows.append({"config": "kvrod", **{a: b for a, b in k.items() if a != "tip"},
                 "tip_error": tip_error(k["tip"], ref)})
    for cfg in configs:
        info = opponent_info(r, cfg)
        o = run_sundials(r, cfg, T, rtol, repeat=repeat)
        row = {"config": cfg.name, **info, **{a: b for a, b in o.items() if a != "tip"}}
        if o.get("ok"):
            row["tip_error"] = tip_error(o["tip"], ref)
        rows.append(row)
        log(f"  {cfg.name}: {o.get('wall', math.nan):.3f} s, {o.get('steps')} steps, "
            f"{o.get('us_per_step', math.nan):.0f} us/step")
    return rows


# --------------------------------------------------------------------------------------
# Where kvrod's time goes
# --------------------------------------------------------------------------------------


def breakdown(N: int, T: float, rtol: float) -> dict:
    """Split kvrod's wall time into residual, Jacobian, LU, Newton solves (condensed band
    solve and updates), the drive (loads re-applied at a new t) and the integrator's own
    arithmetic (predictor, coefficients, error test, history, weights, norms, the loop).

    The parts are timed inside the compiled step loop (``timing`` in native/step_loop.c: two
    clock reads per call); output handling is left out (no t_eval). The Python path of
    the same algorithm (same steps) is timed beside it for comparison."""
    from runtime.solvers.bdf import BDF
    from runtime.solvers.native.step_loop import CoreStruct

    r = rod(N, T)
    m = r.model
    t0 = time.perf_counter()
    sc = BDF(m, 0.0, r.y0, r.yp0, T, rtol=rtol, atol=r.atol(rtol))
    if sc.core is None:
        raise RuntimeError("no compiled step loop (no C compiler)")
    sc.core.s.timing = 1
    while sc.status == "running":
        sc.advance(T)
    total_c = time.perf_counter() - t0
    parts = dict(zip(CoreStruct.SECTIONS, sc.core.s.sec, strict=True))
    parts.pop("energies")
    parts["integrator"] = max(total_c - sum(parts.values()), 0.0)

    t0 = time.perf_counter()
    s = BDF(m, 0.0, r.y0, r.yp0, T, rtol=rtol, atol=r.atol(rtol), compiled_loop=False)
    while s.status == "running":
        s.step()
    total_py = time.perf_counter() - t0
    if s.counters != sc.counters:
        raise RuntimeError(f"the compiled loop and the Python path took different steps: "
                           f"{sc.counters} != {s.counters}")
    return {"N": N, "T": T, "rtol": rtol, "total": total_c, "seconds": parts,
            "counters": sc.counters, "us_per_step": 1e6 * total_c / sc.counters["nstep"],
            "python_path": {"total": total_py,
                            "us_per_step": 1e6 * total_py / s.counters["nstep"]},
            "note": "parts timed inside the compiled loop (two clock reads per call); "
                    "integrator = total minus parts: predictor, coefficients, error test, "
                    "history, weights, norms, the loop itself"}
