"""Generalized Maxwell rods at matched accuracy: kvrod beside SUNDIALS (IDAS, CVODES).

The problem is ``examples/maxwell_cantilever.toml``: the paper's cantilever (L = 0.3 m,
1 cm x 1 cm, rho = 1000 kg/m^3, equilibrium spring E = 1 MPa, nu = 0.3) in a 3-branch
generalized Maxwell material (times 2, 10, 50 ms), deflected statically by the dead tip
force 0.05 N and released at rest with its relaxation terms relaxed, over T seconds
(N = 50, T = 10 s; quick: N = 20, T = 2 s).

Accuracy is the largest error of the tip-x values of the first five tip maxima after the
release (fewer when T holds fewer), against two references that are computed
independently, kvrod and IDAS each at a tight rtol with every unknown in the error test
(their difference is reported: it is the check that the references are good enough); a
run's error is the larger of its errors against the two. kvrod's default run (rtol 1e-6,
``simulation.error_control = "auto"``: velocities out of the error test, BDF order 3-5
only where |h| sigma_g >= D_k) has error E. For each SUNDIALS configuration, rtol is
scanned on a ladder of factors of about 3 from kvrod's rtol (looser while the error stays
<= E, else tighter until it is <= E; a run slower than the budget ends the scan); its
matched run is the fastest run of the scan with error <= E (the loosest such rtol unless
a tighter one ran faster: SUNDIALS gets its best). The matched runs and kvrod are then
timed in alternating rounds in this one process; the medians are compared.

What each wall time includes: kvrod = the in-process ``simulate()`` call on a model built
beforehand (static equilibrium, consistent initial values, the BDF integration, outputs
every 5 ms, tip maxima, energy bookkeeping); SUNDIALS = the ``integrate()`` call of the
CasADi integrator (the integration and its outputs every 5 ms; not the rod, its statics,
the functions or the integrator's construction). SUNDIALS gets kvrod's own compiled
residual and banded Jacobian (the "kernels" build of :mod:`bench.idas_script`: the ODE
form y_d' = -g_d/D_d in per-component scaled variables, CSparse LU) and kvrod's
per-component atol (``default_atol`` at its rtol); "velocities out of the error test"
multiplies the velocities' atol (CVODES: their scaling) by 2^40, as kvrod's error mask.
"""

from __future__ import annotations

import math
import re
import statistics
import time
from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

from bench.idas_script import (
    OUT_OF_TEST,
    Opponent,
    ReleasedRod,
    build_function,
    integrate,
    released_rod,
    tip_maxima,
)
from bench.meta import metadata, target, targets_md

N_MAXIMA = 5            # the first five tip maxima after the release (issue 27)
KVROD_RTOL = 1e-6       # the example's rtol: kvrod's default run
PROBLEM = "maxwell_cantilever"
KV_PROBLEM = "cantilever"
#: the rtol ladder of the SUNDIALS scans (factors of about 3)
LADDER = (3e-5, 1e-5, 3e-6, 1e-6, 3e-7, 1e-7, 3e-8, 1e-8)
#: the references must agree to this fraction of kvrod's error E (target)
REF_FRACTION = 0.1
#: issue 27: a Maxwell run costs at most this many Kelvin-Voigt runs (target)
MAXWELL_OVER_KV_MAX = 3.0


@dataclass(frozen=True)
class Size:
    """One mode of the section: elements, simulated seconds, the references' rtol, the
    ladder, timing rounds, and the wall-time budget (s) of one scan run."""

    N: int
    T: float
    ref_rtol: float
    ladder: tuple[float, ...]
    repeats: int
    budget: float


FULL = Size(50, 10.0, 1e-9, LADDER, 3, 300.0)
QUICK = Size(20, 2.0, 1e-8, LADDER[:-1], 1, 60.0)


@dataclass(frozen=True)
class Config:
    """A SUNDIALS configuration on the Maxwell rod: solver, what the error test controls,
    highest BDF order, CVODES's stability limit detection (``extra`` CasADi options)."""

    solver: str = "idas"
    error_control: str = "configuration"
    max_order: int = 5
    stability_limit_detection: bool = False
    build: str = "kernels"

    @property
    def name(self) -> str:
        what = ("velocities out of the error test" if self.error_control == "configuration"
                else "state in the error test")
        sld = ", stability limit detection" if self.stability_limit_detection else ""
        return f"{self.solver} ({self.build}, {what}, max order {self.max_order}{sld})"

    def extra(self) -> dict:
        return {STABLIM_OPTION: True} if self.stability_limit_detection else {}


#: CVODES's stability limit detection (CVodeSetStabLimDet) under the option name the brief
#: asks for; CasADi 3.8's CVODES interface has no such option (checked at run time)
STABLIM_OPTION = "stability_limit_detection"

#: the configurations, the strongest candidate first (same error control as kvrod). CVODES
#: at order 5 is held to tiny steps by the glassy modes whatever its rtol (the instability
#: that its stability limit detection would catch); capped at order 2 (A-stable) it is not.
#: IDAS capped at order 2 was slower at matched error than at order 5 at N = 6, 10, 20
#: (2-18x in wall time): not in the table.
CONFIGS = (Config("idas", "configuration", 5), Config("idas", "state", 5),
           Config("cvodes", "configuration", 5),
           Config("cvodes", "configuration", 5, stability_limit_detection=True),
           Config("cvodes", "configuration", 2))


def stability_limit_detection_available() -> tuple[bool, str]:
    """Whether CasADi's CVODES takes ``stability_limit_detection`` (and why not)."""
    x = ca.SX.sym("x")
    try:
        ca.integrator("probe", "cvodes", {"x": x, "ode": -x}, 0.0, [1.0],
                      {STABLIM_OPTION: True})
    except RuntimeError as exc:
        first = next((ln.strip() for ln in str(exc).splitlines() if "nknown" in ln),
                     str(exc).strip().splitlines()[-1])
        return False, (f"CasADi {ca.__version__} does not expose CVODES's stability limit "
                       f"detection (CVodeSetStabLimDet): casadi.integrator refuses the "
                       f"option {STABLIM_OPTION!r} ({first[:160]})")
    return True, ""


# --------------------------------------------------------------------------------------
# The error measure
# --------------------------------------------------------------------------------------


def first_maxima(t: np.ndarray, x: np.ndarray, k: int = N_MAXIMA) -> tuple[list, list]:
    """The first k tip maxima after the release (t > 0): times (s) and x values (m)."""
    t, x = np.asarray(t, dtype=float), np.asarray(x, dtype=float)
    keep = t > 0
    return t[keep][:k].tolist(), x[keep][:k].tolist()


def maxima_error(run: dict, refs: dict[str, dict]) -> dict:
    """Errors of ``run``'s first maxima against each reference: x (m, the measure) and t
    (s, for information), over the maxima the reference has (at most N_MAXIMA); a run
    with fewer maxima than a reference gets an infinite error."""
    out: dict[str, Any] = {"against": {}}
    worst_x = worst_t = 0.0
    for name, ref in refs.items():
        k = len(ref["peaks_x"])
        if len(run["peaks_x"]) < k:
            ex = et = math.inf
        else:
            ex = float(np.max(np.abs(np.subtract(run["peaks_x"][:k], ref["peaks_x"]))))
            et = float(np.max(np.abs(np.subtract(run["peaks_t"][:k], ref["peaks_t"]))))
        out["against"][name] = {"x": ex, "t": et}
        worst_x, worst_t = max(worst_x, ex), max(worst_t, et)
    out["error"], out["error_t"] = worst_x, worst_t
    return out


# --------------------------------------------------------------------------------------
# kvrod in process (simulate(), as `kvrod simulate` runs it)
# --------------------------------------------------------------------------------------


def kvrod_run(N: int, T: float, rtol: float, error_control: str = "auto",
              problem: str = PROBLEM) -> dict:
    """``simulate`` of a built-in problem (N, T, rtol, simulation.error_control) on a model
    built before the clock starts: wall (s), counters, first maxima, kvrod's own energy
    audit, what the error test controlled."""
    from runtime.problem.assemble import build_model
    from runtime.problem.registry import load_problem
    from runtime.simulate.simulate import simulate

    p = load_problem(problem, {"rod.elements": int(N), "simulation.t_end": float(T),
                               "simulation.rtol": float(rtol),
                               "simulation.error_control": error_control})
    model = build_model(p)
    t0 = time.perf_counter()
    res = simulate(p, model=model)
    wall = time.perf_counter() - t0
    name = f"kvrod ({p.name}, error control {error_control})"
    if res.status != "finished":
        return {"ok": False, "integrator": name, "rtol": rtol, "wall": wall,
                "message": res.message}
    pt, px = first_maxima(res.peaks_t, res.peaks_x)
    k = res.counters
    return {"ok": True, "integrator": name, "problem": p.name, "rtol": rtol, "wall": wall,
            "static_seconds": res.static.wall_time_s if res.static else 0.0,
            "steps": int(k["nstep"]), "us_per_step": 1e6 * wall / max(int(k["nstep"]), 1),
            "counters": {a: int(b) for a, b in k.items()}, "peaks_t": pt, "peaks_x": px,
            "audit_own": float(res.audit().max_rel),
            "error_control": res.control.describe() if res.control else None}


# --------------------------------------------------------------------------------------
# SUNDIALS
# --------------------------------------------------------------------------------------

def opponent(rod: ReleasedRod, cfg: Config, cache: dict | None = None) -> Opponent:
    """The ODE form's functions of ``rod`` for ``cfg`` (CVODES: the velocities scaled out
    when its error test leaves them out; IDAS takes per-component tolerances instead),
    kept in ``cache`` (one per rod) when given."""
    ec = cfg.error_control if cfg.solver == "cvodes" else "state"
    key = (cfg.build, ec)
    if cache is not None and key in cache:
        return cache[key]
    opp = build_function(rod, "ode", cfg.build, error_control=ec)
    if cache is not None:
        cache[key] = opp
    return opp


def sundials_run(rod: ReleasedRod, cfg: Config, T: float, rtol: float,
                 cache: dict | None = None) -> dict:
    """One integration of ``cfg`` at rtol: wall of the integrator call (s), counters,
    first maxima (from the 5 ms outputs by cubic Hermite interpolation of x, x')."""
    opp = opponent(rod, cfg, cache)
    run = integrate(rod, opp, T, rod.problem.simulation.output_step, rtol, None, cfg.solver,
                    error_control=cfg.error_control, max_order=cfg.max_order,
                    extra=cfg.extra())
    if not run.ok:
        return {"ok": False, "integrator": cfg.name, "rtol": rtol, "message": run.message,
                "wall": math.nan}
    pt, px = first_maxima(*tip_maxima(run.t, run.tip_x, run.tip_vx,
                                      float(rod.model.reference[rod.tip_x])))
    st = run.stats
    return {"ok": True, "integrator": cfg.name, "rtol": rtol, "wall": run.wall,
            "setup_seconds": run.setup, "steps": run.steps, "us_per_step": run.us_per_step,
            "nfev": st.get("nfevals"), "nlu": st.get("nlinsetups"),
            "nni": st.get("nniters"), "netf": st.get("netfails"),
            "ncfn": st.get("nncfails"), "peaks_t": pt, "peaks_x": px}


def scan(runner, refs: dict[str, dict], tol: float, ladder=LADDER,
         start: float = KVROD_RTOL, budget: float = math.inf) -> dict:
    """Scan ``ladder`` (loose to tight) for runs whose maxima error is <= ``tol``: from
    ``start`` looser while it passes, or tighter until it passes; a run that fails or
    takes longer than ``budget`` s ends the scan. Returns the matched run (the fastest
    passing run, None if none), the loosest passing rtol, and every run made (without
    their maxima)."""
    ladder = list(ladder)
    runs: list[dict] = []

    def attempt(rtol: float) -> dict:
        r = runner(rtol)
        if r.get("ok"):
            r.update(maxima_error(r, refs))
        r["pass"] = bool(r.get("ok") and r["error"] <= tol)
        runs.append(r)
        return r

    def slim(r: dict | None) -> dict | None:
        return None if r is None else {k: v for k, v in r.items()
                                       if k not in ("peaks_t", "peaks_x")}

    i0 = ladder.index(start) if start in ladder else 0
    first = attempt(ladder[i0])
    matched, stopped = None, ""
    if first["pass"]:
        matched = first
        for rtol in reversed(ladder[:i0]):
            r = attempt(rtol)
            if not r["pass"]:
                break
            matched = r
    else:
        last = first
        for rtol in ladder[i0 + 1:]:
            if not last.get("ok") or last["wall"] > budget:
                break
            last = attempt(rtol)
            if last["pass"]:
                matched = last
                break
        if matched is None:
            stopped = (f"rtol {last['rtol']:.0e} failed: {last.get('message', '')}"
                       if not last.get("ok") else
                       f"rtol {last['rtol']:.0e} took {last['wall']:.1f} s > budget "
                       f"{budget:g} s" if last["wall"] > budget else
                       f"no rtol down to {ladder[-1]:.0e} reached the error")
    passing = [r for r in runs if r["pass"]]
    fastest = min(passing, key=lambda r: r["wall"]) if passing else None
    return {"matched": slim(fastest), "loosest_passing": matched["rtol"] if matched else None,
            "scan": [slim(r) for r in runs], "stopped": stopped}


# --------------------------------------------------------------------------------------
# The section
# --------------------------------------------------------------------------------------


def run(quick: bool = False, log=print, size: Size | None = None,
        configs: tuple[Config, ...] = CONFIGS) -> dict:
    """The section's document (module docstring): references, kvrod's rows, the scans
    and the alternating timing; ``size`` overrides the mode's (tests)."""
    sz = size or (QUICK if quick else FULL)
    if sz.N < 1 or not sz.T > 0 or sz.repeats < 1 or KVROD_RTOL not in sz.ladder:
        raise ValueError(f"size = {sz} is outside the allowed range: N >= 1, T > 0, "
                         f"repeats >= 1, a ladder that holds kvrod's rtol {KVROD_RTOL:g}")
    N, T = sz.N, sz.T
    rod = released_rod(N, T, KVROD_RTOL, problem=PROBLEM)
    opps: dict = {}         # the rod's functions per (build, scaling)
    doc: dict[str, Any] = {"quick": quick, "N": N, "n": rod.n, "T": T,
                           "kvrod_rtol": KVROD_RTOL, "n_maxima": N_MAXIMA,
                           "ladder": list(sz.ladder), "repeats": sz.repeats,
                           "budget_s": sz.budget, "out_of_test_factor": OUT_OF_TEST,
                           "sigma_g": float(rod.model.glassy_decay_rate())}

    # references: kvrod and IDAS, every unknown in the error test
    ref_k = kvrod_run(N, T, sz.ref_rtol, "state")
    ref_cfg = Config("idas", "state", 5)
    ref_i = sundials_run(rod, ref_cfg, T, sz.ref_rtol, opps)
    for r in (ref_k, ref_i):
        if not r["ok"]:
            raise RuntimeError(f"the reference {r['integrator']} at rtol {sz.ref_rtol:g} "
                               f"failed: {r.get('message')}")
    if not ref_k["peaks_x"]:
        raise ValueError(f"T = {T:g} s is outside the allowed range: no tip maximum after "
                         "the release (the first is near 1.8 s)")
    refs = {"kvrod": ref_k, "idas": ref_i}
    cross = maxima_error(ref_i, {"kvrod": ref_k})
    doc["reference"] = {"rtol": sz.ref_rtol, "maxima_compared": len(ref_k["peaks_x"]),
                        "kvrod": ref_k, "idas": ref_i,
                        "max_diff_x": cross["error"], "max_diff_t": cross["error_t"]}
    log(f"  references at rtol {sz.ref_rtol:g}: kvrod {ref_k['wall']:.2f} s "
        f"({ref_k['steps']} steps), IDAS {ref_i['wall']:.2f} s ({ref_i['steps']} steps); "
        f"first-maxima difference {cross['error']:.2e} m")

    # kvrod: the default run (its error E), the full-state contrast, the Kelvin-Voigt rod
    kv_default = kvrod_run(N, T, KVROD_RTOL, "auto")
    if not kv_default["ok"]:
        raise RuntimeError(f"kvrod's default run failed: {kv_default['message']}")
    kv_default.update(maxima_error(kv_default, refs))
    E = kv_default["error"]
    kv_state = kvrod_run(N, T, KVROD_RTOL, "state")
    if kv_state["ok"]:
        kv_state.update(maxima_error(kv_state, refs))
    kv_kv = kvrod_run(N, T, KVROD_RTOL, "auto", problem=KV_PROBLEM)
    log(f"  kvrod default: error {E:.2e} m, {kv_default['steps']} steps; state: "
        f"{kv_state.get('error', math.nan):.2e} m, {kv_state.get('steps')} steps; "
        f"Kelvin-Voigt cantilever {kv_kv.get('steps')} steps")

    # SUNDIALS: the scans
    doc["configs"], doc["skipped"] = [], []
    sld_ok, sld_why = stability_limit_detection_available()
    for cfg in configs:
        if cfg.stability_limit_detection and not sld_ok:
            doc["skipped"].append({"config": cfg.name, "why": sld_why})
            log(f"  {cfg.name}: skipped ({sld_why})")
            continue
        t0 = time.perf_counter()
        opponent(rod, cfg, opps)
        ready = time.perf_counter() - t0
        s = scan(lambda rt, c=cfg: sundials_run(rod, c, T, rt, opps), refs, E, sz.ladder,
                 KVROD_RTOL, sz.budget)
        doc["configs"].append({"config": cfg.name, "solver": cfg.solver,
                               "error_control": cfg.error_control,
                               "max_order": cfg.max_order,
                               "stability_limit_detection": cfg.stability_limit_detection,
                               "functions_seconds": ready, **s,
                               "at_loosest_rung": s["loosest_passing"] == max(sz.ladder)})
        m = s["matched"]
        log(f"  {cfg.name}: " + (f"matched at rtol {m['rtol']:.0e}, error {m['error']:.2e} "
                                 f"m, {m['wall']:.2f} s, {m['steps']} steps"
                                 if m else f"not matched ({s['stopped']})"))

    # alternating timing rounds: kvrod's rows, then each matched configuration
    walls: dict[str, list[float]] = {"kvrod": [], "kvrod_state": [], "kelvin_voigt": []}
    contenders = [(c, next(x for x in configs if x.name == c["config"]))
                  for c in doc["configs"] if c["matched"]]
    for c, _ in contenders:
        walls[c["config"]] = []
    for k in range(sz.repeats):
        for key, args in (("kvrod", ("auto", PROBLEM)), ("kvrod_state", ("state", PROBLEM)),
                          ("kelvin_voigt", ("auto", KV_PROBLEM))):
            r = kvrod_run(N, T, KVROD_RTOL, *args)
            if r["ok"]:
                walls[key].append(r["wall"])
        for c, cfg in contenders:
            r = sundials_run(rod, cfg, T, c["matched"]["rtol"], opps)
            if r["ok"]:
                walls[c["config"]].append(r["wall"])
        log(f"  timing round {k + 1}/{sz.repeats}: " + ", ".join(
            f"{n} {w[-1]:.2f} s" for n, w in walls.items() if w))

    def timed(row: dict, key: str) -> dict:
        w = walls.get(key) or []
        row["timing"] = {"walls": w, "median": statistics.median(w) if w else None}
        return row

    doc["kvrod"] = timed(kv_default, "kvrod")
    doc["kvrod_state"] = timed(kv_state, "kvrod_state")
    doc["kelvin_voigt"] = timed(kv_kv, "kelvin_voigt")
    base = doc["kvrod"]["timing"]["median"]
    for c in doc["configs"]:
        timed(c, c["config"])
        med = c["timing"]["median"]
        c["ratio_to_kvrod"] = med / base if med and base else None
    for key in ("kvrod_state", "kelvin_voigt"):
        med = doc[key]["timing"]["median"]
        doc[key]["ratio_to_kvrod"] = med / base if med and base else None
    kvm = doc["kelvin_voigt"]["timing"]["median"]
    doc["ratio_maxwell_over_kelvin_voigt"] = base / kvm if base and kvm else None
    timed_cfgs = [c for c in doc["configs"] if c["timing"]["median"]]
    best = min(timed_cfgs, key=lambda c: c["timing"]["median"]) if timed_cfgs else None
    doc["strongest"] = best["config"] if best else None
    doc["ratio_strongest_over_kvrod"] = best["ratio_to_kvrod"] if best else None
    doc["protocol"] = " ".join(__doc__.split("\n\n")[2].split())
    doc["walls_include"] = " ".join(__doc__.split("\n\n")[3].split())
    note = f"quick run (N = {N}, {T:g} s)" if quick else ""
    doc["targets"] = [
        target(f"references (kvrod and IDAS at rtol {sz.ref_rtol:g}) agree on the first "
               f"maxima to <= {REF_FRACTION:g} of kvrod's error E (m)", cross["error"],
               REF_FRACTION * E, note=note),
        target(f"kvrod Maxwell / Kelvin-Voigt cantilever wall time (in-process simulate(), "
               f"same N, T, rtol) <= {MAXWELL_OVER_KV_MAX:g}",
               doc["ratio_maxwell_over_kelvin_voigt"], MAXWELL_OVER_KV_MAX,
               note="issue 27's limit is for whole processes (docs/design.md section 11)"
               + (f"; {note}" if note else ""))]
    doc["meta"] = metadata()
    return doc


# --------------------------------------------------------------------------------------
# Markdown
# --------------------------------------------------------------------------------------


def _f(v: Any, fmt: str) -> str:
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "-"
    return format(v, fmt)


def _md(text: str) -> str:
    """Docstring text as Markdown (reST roles and double backticks to code spans)."""
    return re.sub(r":\w+:`([^`]+)`", r"`\1`", text.replace("``", "`"))


def markdown(doc: dict) -> list[str]:
    """The section of bench/results/README.md (every figure from ``doc``)."""
    ref = doc["reference"]
    kv = doc["kvrod"]
    k = ref["maxima_compared"]
    which = "first tip maximum" if k == 1 else f"first {k} tip maxima"
    out = ["## 8. Generalized Maxwell rods: kvrod beside SUNDIALS at matched accuracy", "",
           f"The Maxwell cantilever (`examples/maxwell_cantilever.toml`), N = {doc['N']} "
           f"(n = {doc['n']} unknowns), released and integrated over {doc['T']:g} s. "
           f"Error: the largest tip-x error of the {which} after the release, the "
           "larger of the errors against two references, kvrod and IDAS at "
           f"rtol {ref['rtol']:g} with every unknown in the error test, which differ by "
           f"{_f(ref['max_diff_x'], '.1e')} m (peak times by "
           f"{_f(ref['max_diff_t'], '.1e')} s). kvrod's default run (rtol "
           f"{doc['kvrod_rtol']:g}, velocities out of the error test, order bound at "
           f"sigma_g = {doc['sigma_g']:.4g} 1/s) has error E = {_f(kv['error'], '.2e')} m; "
           "each SUNDIALS configuration is scanned on the rtol ladder "
           + ", ".join(f"{r:.0e}" for r in doc["ladder"]) + " from kvrod's rtol, and its "
           "fastest run with error <= E is timed (the loosest such rtol unless a tighter "
           "one ran faster). Times: "
           f"medians of {doc['repeats']} alternating round(s) in one process; ratio = "
           "wall / kvrod default's wall.", "", _md(doc["walls_include"])
           + f" kvrod's static solve took {_f(kv.get('static_seconds'), '.3f')} s of its "
           "default run's wall.", "",
           "| run | rtol | error m | median wall s | steps | us/step | LU | "
           "error test fails | wall / kvrod |",
           "|:--|---:|---:|---:|---:|---:|---:|---:|---:|"]

    def row(name: str, r: dict | None, ratio: Any, why: str = "") -> None:
        if r is None:
            out.append(f"| {name} | not matched{': ' + why if why else ''} | - | - | - | - "
                       "| - | - | - |")
            return
        med = (r.get("timing") or {}).get("median", r.get("wall"))
        k = r.get("counters") or {}
        steps = r.get("steps")
        loosest = (" (loosest rung)" if r.get("at_loosest_rung")
                   and r["rtol"] == max(doc["ladder"]) else "")
        out.append(f"| {name} | {r['rtol']:.0e}{loosest} | {_f(r.get('error'), '.2e')} | "
                   f"{_f(med, '.3f')} | {_f(steps, 'd')} | "
                   f"{_f(1e6 * med / steps if med and steps else None, '.0f')} | "
                   f"{_f(r.get('nlu', k.get('nlu')), 'd')} | "
                   f"{_f(r.get('netf', k.get('netf')), 'd')} | {_f(ratio, '.2f')} |")

    row("kvrod, default (velocities out of the error test)", kv, 1.0)
    for c in doc["configs"]:
        m = c["matched"]
        if m is not None:
            m = {**m, "timing": c["timing"], "at_loosest_rung": c.get("at_loosest_rung")}
        row(c["config"] + (" **(strongest)**" if c["config"] == doc["strongest"] else ""),
            m, c.get("ratio_to_kvrod"), c.get("stopped", ""))
    row("kvrod, state in the error test (contrast, not matched)", doc["kvrod_state"],
        doc["kvrod_state"].get("ratio_to_kvrod"))
    row("kvrod, Kelvin-Voigt cantilever (same N, T; other problem: no error)",
        doc["kelvin_voigt"], doc["kelvin_voigt"].get("ratio_to_kvrod"))
    for s in doc.get("skipped", []):
        out.append(f"| {s['config']} | skipped | - | - | - | - | - | - | - |")
    out.append("")
    if doc.get("skipped"):
        out += ["Skipped: " + "; ".join(f"{s['config']}: {s['why']}"
                                        for s in doc["skipped"]) + ".", ""]
    if any(c.get("at_loosest_rung") and c["matched"]
           and c["matched"]["rtol"] == max(doc["ladder"]) for c in doc["configs"]):
        out += ["(loosest rung): error <= E at the ladder's loosest rtol; a looser one "
                "might match too.", ""]
    if doc.get("strongest"):
        out += [f"Strongest SUNDIALS configuration: {doc['strongest']}, "
                f"{_f(doc['ratio_strongest_over_kvrod'], '.2f')} times kvrod's wall time at "
                f"matched accuracy. kvrod Maxwell / Kelvin-Voigt wall time: "
                f"{_f(doc['ratio_maxwell_over_kelvin_voigt'], '.2f')}.", ""]
    out += ["Scans (every run made; error in m):", "",
            "| configuration | rtol: error m (wall s, steps) |", "|:--|:--|"]
    for c in doc["configs"]:
        cells = "; ".join(
            f"{r['rtol']:.0e}: " + (f"{_f(r.get('error'), '.2e')} ({r['wall']:.2f} s, "
                                    f"{r['steps']})" if r.get("ok") else "failed")
            for r in c["scan"])
        out.append(f"| {c['config']} | {cells} |")
    if doc.get("targets"):
        out += ["", *targets_md(doc["targets"])]
    return out + [""]
