"""What `kvrod simulate` adds to its integrator, and the integrator beside SUNDIALS (issue 33).

The paper's cantilever (``examples/cantilever.toml``), N = 50, 10 s, rtol 1e-6. Three
ratios, each taken side by side in one run (the commands run in turn, round after round,
in the orders of :data:`ORDERS`; ratios are per round, then their median, so a slow spell
of the shared machine spoils one round, not one command). ``kvrod simulate`` and the
integrator alone run back to back in every round, each first in half of them: a shared
machine changes speed in spells of seconds (both vCPUs of the 2-core VM together, by
~1.3x), and the IDAS script's second between them put a pair into two spells in a third
of the rounds.

1. **summary wall / integrator alone**: ``wall_time_s`` of the ``summary.json`` that a whole
   ``kvrod simulate cantilever --n-elements 50 --t-end 10`` process writes (model build,
   static solve, integration, energy audit, outputs every 5 ms, maxima, reactions, the
   checkpoints of the results folder) over the integrator alone: ``solve`` from the
   released static state with outputs every 10 ms, built with ``load_problem``,
   ``build_model``, ``static_equilibrium``, ``consistent_initial`` and ``default_atol``
   (:func:`integrator_alone`), timed around ``solve`` only, in a process of its own
   (``python -m bench.overhead --integrator-alone``), so that both are the first run in a
   fresh process.
2. **whole processes**: the ``kvrod simulate`` process (start-up, run, summary.json,
   series.npz, problem.toml) against the strong IDAS script
   (``python -m bench.idas_script --n-elements 50 --t-end 10``: start-up, the same rod and
   static solve, its flat SX library from the cache, IDAS, outputs every 5 ms); wall and
   CPU (user + system, of the child).
3. **integrator alone against IDAS**, in this process: the same ``solve`` against IDAS on
   the same released rod and tolerances (kvrod's per-component ``default_atol``, outputs
   every 10 ms) with kvrod's compiled kernels ("kernels": the strongest IDAS configuration
   of section 1 at N = 50) and with the flat SX library of the script ("flat").

Every process runs once before the rounds (not counted: the compile caches, the file
cache). The child processes get a byte-code cache of their own (``PYTHONPYCACHEPREFIX`` in
a temporary folder, ``PYTHONDONTWRITEBYTECODE`` removed), as a user's Python has one. The
document records the machine (platform, CPU model, cores) and the load average before and
after. ``--quick``: 2 s simulated, two rounds, IDAS on the kernels only (no flat build).
``python -m bench --only overhead`` runs this section alone.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from bench.meta import target, targets_md

N, T, RTOL = 50, 10.0, 1e-6
OUTPUT_STEP = 0.01          # s: the integrator alone's outputs (simulate's own: 5 ms)
ROUNDS, QUICK_ROUNDS = 12, 2
#: the rounds' orders, in turn: simulate and the integrator alone adjacent, each first in
#: half of the rounds; the IDAS script before them or after them in half
ORDERS = (("simulate", "integrator", "idas_script"), ("idas_script", "integrator", "simulate"),
          ("integrator", "simulate", "idas_script"), ("idas_script", "simulate", "integrator"))
QUICK_T = 2.0
SUMMARY_RATIO_MAX = 1.3
PROCESS_RATIO_MAX = 0.7
IDAS_RATIO_MAX = 0.4
TIMEOUT = 600.0


def integrator_alone(n_elements: int = N, t_end: float = T, rtol: float = RTOL,
                     output_step: float = OUTPUT_STEP) -> dict[str, Any]:
    """The integrator alone as issue 33 builds it: the cantilever's model, its static
    equilibrium released at t = 0 (the tip load off), consistent initial values and
    ``default_atol``; returns what :func:`time_solve` needs."""
    from runtime.problem.assemble import build_model
    from runtime.problem.registry import load_problem
    from runtime.simulate.simulate import default_atol, static_equilibrium
    from runtime.solvers.integrator import consistent_initial

    problem = load_problem("cantilever", {"n_elements": n_elements, "t_end": t_end,
                                          "rtol": rtol})
    model = build_model(problem)
    static = static_equilibrium(problem, model)
    model.at(0.0)                       # released: the tip load is off from t = 0
    y0, yp0 = consistent_initial(model, 0.0, static.y, np.zeros(model.n))
    atol = default_atol(problem, model, static.y)
    grid = np.linspace(0.0, t_end, int(round(t_end / output_step)) + 1)
    return {"model": model, "y0": y0, "yp0": yp0, "atol": atol, "grid": grid,
            "t_end": t_end, "rtol": rtol}


def time_solve(setup: dict[str, Any]) -> tuple[float, dict[str, int]]:
    """(seconds of one ``solve`` call, its counters)."""
    from runtime.solvers.integrator import solve

    t0 = time.perf_counter()
    res = solve(setup["model"], (0.0, setup["t_end"]), setup["y0"], setup["yp0"],
                rtol=setup["rtol"], atol=setup["atol"], t_eval=setup["grid"])
    wall = time.perf_counter() - t0
    if not res.success:
        raise RuntimeError(f"the integrator alone failed: {res.message}")
    return wall, dict(res.counters)


def machine() -> dict[str, Any]:
    """Platform, CPU model and cores, memory (GiB) and the load average now."""
    import platform

    model = ""
    try:
        with open("/proc/cpuinfo", encoding="utf-8", errors="replace") as f:
            model = next((ln.split(":", 1)[1].strip() for ln in f
                          if ln.startswith("model name")), "")
    except OSError:
        pass
    try:
        mem = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") / 2**30
    except (ValueError, OSError, AttributeError):
        mem = None
    return {"platform": platform.platform(), "cpu_model": model or platform.processor(),
            "cpus": os.cpu_count(), "memory_gib": None if mem is None else round(mem, 1),
            "load_average": [round(v, 2) for v in os.getloadavg()]}


def _child_env(pycache: Path) -> dict[str, str]:
    env = dict(os.environ)
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    env["PYTHONPYCACHEPREFIX"] = str(pycache)
    return env


def _process(cmd: list[str], env: dict[str, str]) -> dict[str, Any]:
    """One whole process: wall and CPU seconds (its own, from the OS), exit code, output."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=TIMEOUT, env=env)
        rc, out, err = p.returncode, p.stdout, p.stderr
    except subprocess.TimeoutExpired:
        rc, out, err = -1, "", f"timed out after {TIMEOUT:g} s"
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return {"wall": wall, "cpu": cpu, "rc": rc, "stdout": out,
            "error": (err.strip().splitlines() or [""])[-1] if rc else ""}


def commands(t_end: float, quick: bool, out: Path) -> dict[str, list[str]]:
    """The three processes of a round (``out``: the simulate command's results folder)."""
    py = sys.executable
    n, t = str(N), f"{t_end:g}"
    return {
        "simulate": [py, "-m", "kvrod.cli", "simulate", "cantilever", "--n-elements", n,
                     "--t-end", t, "--out", str(out), "--overwrite"],
        "integrator": [py, "-m", "bench.overhead", "--integrator-alone", "--n-elements", n,
                       "--t-end", t],
        "idas_script": [py, "-m", "bench.idas_script", "--n-elements", n, "--t-end", t,
                        "--json", *(["--build", "kernels"] if quick else [])],
    }


def _median(v: list[float]) -> float | None:
    return float(statistics.median(v)) if v else None


def _paired(a: list[float], b: list[float]) -> list[float]:
    return [x / y for x, y in zip(a, b, strict=False) if y > 0]


def processes(quick: bool, rounds: int, log=print) -> dict[str, Any]:
    """Ratios 1 and 2 of the module docstring: rounds of the three processes in turn."""
    t_end = QUICK_T if quick else T
    rec: dict[str, dict[str, list]] = {k: {"wall": [], "cpu": []}
                                       for k in ("simulate", "integrator", "idas_script")}
    summary_wall: list[float] = []
    solve_s: list[float] = []
    steps: dict[str, int] = {}
    errors: dict[str, str] = {}
    with tempfile.TemporaryDirectory(prefix="kvrod-bench-overhead-") as tmp:
        root = Path(tmp)
        env = _child_env(root / "pycache")
        cmds = commands(t_end, quick, root / "run")
        names = list(cmds)
        for name in names:                          # warm-up: caches, byte code
            r = _process(cmds[name], env)
            log(f"  warm-up {name}: {r['wall']:.2f} s" + (f" (failed: {r['error']})"
                                                         if r["rc"] else ""))
            if r["rc"]:
                errors[name] = r["error"]
        for k in range(rounds):
            order = ORDERS[k % len(ORDERS)]
            got: dict[str, dict] = {}
            for name in order:
                if name in errors:
                    continue
                r = _process(cmds[name], env)
                if r["rc"]:
                    errors[name] = r["error"]
                    continue
                got[name] = r
            if "simulate" in got:
                s = json.loads((root / "run" / "summary.json").read_text())
                got["simulate"]["summary_wall"] = s["wall_time_s"]
                steps["simulate"] = s["counters"]["nstep"]
            if "integrator" in got:
                d = json.loads(got["integrator"]["stdout"].strip().splitlines()[-1])
                got["integrator"]["solve_s"] = d["solve_s"]
                steps["integrator"] = d["counters"]["nstep"]
            if "idas_script" in got:
                d = json.loads(got["idas_script"]["stdout"].strip().splitlines()[-1])
                steps["idas_script"] = d["steps"]
            if len(got) < len(names) - len([n for n in names if n in errors]):
                continue
            for name, r in got.items():
                rec[name]["wall"].append(r["wall"])
                rec[name]["cpu"].append(r["cpu"])
            if "simulate" in got and "integrator" in got:
                summary_wall.append(got["simulate"]["summary_wall"])
                solve_s.append(got["integrator"]["solve_s"])
            log(f"  round {k + 1}/{rounds}: " + ", ".join(
                f"{n} {r['wall']:.2f} s" for n, r in got.items())
                + (f"; summary wall {summary_wall[-1]:.3f} s, solve {solve_s[-1]:.3f} s"
                   if summary_wall else ""))
    out: dict[str, Any] = {"t_end": t_end, "rounds": rounds, "steps": steps,
                           "errors": errors, "processes": {}}
    for name, r in rec.items():
        out["processes"][name] = {"wall": r["wall"], "cpu": r["cpu"],
                                  "median_wall": _median(r["wall"]),
                                  "median_cpu": _median(r["cpu"])}
    ratios = _paired(summary_wall, solve_s)
    out["summary_over_integrator"] = {
        "summary_wall": summary_wall, "solve_s": solve_s, "ratios": ratios,
        "median_summary_wall": _median(summary_wall), "median_solve_s": _median(solve_s),
        "median_ratio": _median(ratios)}
    sim, ida = rec["simulate"], rec["idas_script"]
    out["process_over_idas_script"] = {
        "wall_ratios": _paired(sim["wall"], ida["wall"]),
        "cpu_ratios": _paired(sim["cpu"], ida["cpu"]),
        "median_wall_ratio": _median(_paired(sim["wall"], ida["wall"])),
        "median_cpu_ratio": _median(_paired(sim["cpu"], ida["cpu"]))}
    return out


def integrator_vs_idas(quick: bool, rounds: int, log=print) -> dict[str, Any]:
    """Ratio 3 of the module docstring: ``solve`` and IDAS in turn in this process."""
    from bench.idas_script import build_function, integrate, released_rod

    t_end = QUICK_T if quick else T
    setup = integrator_alone(t_end=t_end)
    rod = released_rod(N, t_end, RTOL)
    builds = ("kernels",) if quick else ("kernels", "flat")
    opps = {b: build_function(rod, "ode", b) for b in builds}
    grid = setup["grid"]

    def idas(b: str) -> tuple[float, int]:
        r = integrate(rod, opps[b], t_end, OUTPUT_STEP, RTOL, grid=grid)
        if not r.ok:
            raise RuntimeError(f"IDAS ({b}) failed: {r.message}")
        return r.wall, r.steps

    time_solve(setup)                                   # warm-up
    for b in builds:
        idas(b)
    kv: list[float] = []
    opp: dict[str, list[float]] = {b: [] for b in builds}
    steps: dict[str, int] = {}
    for k in range(rounds):
        w, c = time_solve(setup)
        kv.append(w)
        steps["kvrod"] = c["nstep"]
        for b in builds:
            w, s = idas(b)
            opp[b].append(w)
            steps[f"idas ({b})"] = s
        log(f"  round {k + 1}/{rounds}: kvrod {kv[-1]:.3f} s, " + ", ".join(
            f"idas ({b}) {opp[b][-1]:.3f} s" for b in builds))
    out: dict[str, Any] = {"t_end": t_end, "rounds": rounds, "steps": steps,
                           "kvrod": {"walls": kv, "median": _median(kv)}, "idas": {}}
    for b in builds:
        ratios = _paired(kv, opp[b])
        out["idas"][b] = {"walls": opp[b], "median": _median(opp[b]), "ratios": ratios,
                          "median_ratio": _median(ratios)}
    best = min(builds, key=lambda b: out["idas"][b]["median"])
    out["strongest"] = best
    return out


def run(quick: bool = False, log=print, rounds: int | None = None) -> dict[str, Any]:
    """The section's document: machine and load, the three ratios, the targets."""
    from bench.meta import metadata

    rounds = rounds or (QUICK_ROUNDS if quick else ROUNDS)
    before = machine()
    log("  whole processes: kvrod simulate, the integrator alone, the IDAS script")
    proc = processes(quick, rounds, log)
    log("  the integrator alone against IDAS, in one process")
    duel = integrator_vs_idas(quick, rounds, log)
    after = machine()
    note = f"quick run: {QUICK_T:g} s, {rounds} rounds" if quick else ""
    best = duel["strongest"]
    targets = [
        target(f"summary wall of kvrod simulate / the integrator alone (solve, outputs every "
               f"{OUTPUT_STEP * 1e3:g} ms), paired median <= {SUMMARY_RATIO_MAX:g}",
               proc["summary_over_integrator"]["median_ratio"], SUMMARY_RATIO_MAX, note=note),
        target(f"whole kvrod simulate process / the IDAS script's process (wall), paired "
               f"median <= {PROCESS_RATIO_MAX:g}",
               proc["process_over_idas_script"]["median_wall_ratio"], PROCESS_RATIO_MAX,
               note=note),
        target(f"the integrator alone / IDAS ({best}), paired median <= {IDAS_RATIO_MAX:g}",
               duel["idas"][best]["median_ratio"], IDAS_RATIO_MAX, note=note)]
    return {"quick": quick, "N": N, "rtol": RTOL, "machine_before": before,
            "machine_after": after, "bytecode_cache": True, **proc,
            "integrator_vs_idas": duel, "targets": targets, "meta": metadata()}


def markdown(doc: dict) -> list[str]:
    """The section of bench/results/README.md."""

    def f(v, fmt=".3f"):
        return "-" if v is None else format(v, fmt)

    m0, m1 = doc["machine_before"], doc["machine_after"]
    so = doc["summary_over_integrator"]
    po = doc["process_over_idas_script"]
    pr = doc["processes"]
    d = doc["integrator_vs_idas"]
    out = ["## 10. kvrod simulate's own cost beside its integrator and beside IDAS (issue 33)",
           "",
           f"The cantilever, N = {doc['N']}, {doc['t_end']:g} s, rtol {doc['rtol']:g}; "
           f"{doc['rounds']} rounds of the commands in turn (kvrod simulate and the "
           "integrator alone back to back, each first in half of the rounds), one warm-up "
           "each; ratios per round, then their median (paired). Machine: "
           f"{m0['cpu_model']}, {m0['cpus']} cores, {m0['memory_gib']} GiB, "
           f"{m0['platform']}; load average {m0['load_average']} before, "
           f"{m1['load_average']} after. Child processes with a byte-code cache.", "",
           "| measure | median s | ratio (paired median) |", "|:--|---:|---:|",
           f"| summary.json wall_time_s of `kvrod simulate` (outputs every 5 ms) | "
           f"{f(so['median_summary_wall'])} | |",
           f"| integrator alone: `solve`, outputs every 10 ms (own process) | "
           f"{f(so['median_solve_s'])} | summary / this: **{f(so['median_ratio'], '.2f')}** |",
           f"| whole `kvrod simulate` process, wall (CPU) | "
           f"{f(pr['simulate']['median_wall'])} ({f(pr['simulate']['median_cpu'])}) | |",
           f"| whole `python -m bench.idas_script` process, wall (CPU) | "
           f"{f(pr['idas_script']['median_wall'])} ({f(pr['idas_script']['median_cpu'])}) | "
           f"simulate / this: **{f(po['median_wall_ratio'], '.2f')}** "
           f"(CPU {f(po['median_cpu_ratio'], '.2f')}) |",
           f"| integrator alone, in one process with IDAS | {f(d['kvrod']['median'])} | |"]
    for b, r in d["idas"].items():
        out.append(f"| IDAS ({b}), same rod, tolerances and outputs | {f(r['median'])} | "
                   f"integrator / this: **{f(r['median_ratio'], '.2f')}** |")
    st = {**doc.get("steps", {}), **d.get("steps", {})}
    out += ["", "Steps: " + ", ".join(f"{k} {v}" for k, v in st.items()) + "."]
    if doc.get("errors"):
        out += ["", "Failed: " + "; ".join(f"{k}: {v}" for k, v in doc["errors"].items())]
    if doc.get("targets"):
        out += ["", *targets_md(doc["targets"])]
    return out + [""]


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m bench.overhead",
                                 description=__doc__.splitlines()[0])
    ap.add_argument("--integrator-alone", action="store_true",
                    help="time the integrator alone once and print one JSON line")
    ap.add_argument("--n-elements", type=int, default=N)
    ap.add_argument("--t-end", type=float, default=T)
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--processes-only", metavar="JSON", type=Path,
                    help="only the rounds of whole processes (ratios 1 and 2; the IDAS "
                         "script's rounds are left out where CasADi is not installed), "
                         "with the machine, into this JSON file (a quiet machine's check: "
                         "python -m bench.sweep_cores's device run)")
    ap.add_argument("--rounds", type=int, default=None,
                    help=f"rounds (default {ROUNDS}; {QUICK_ROUNDS} with --quick)")
    args = ap.parse_args(argv)
    rounds = args.rounds or (QUICK_ROUNDS if args.quick else ROUNDS)
    if args.processes_only is not None and not args.processes_only.parent.is_dir():
        ap.error(f"--processes-only: the folder {args.processes_only.parent} does not exist")
    if args.integrator_alone:
        wall, counters = time_solve(integrator_alone(args.n_elements, args.t_end))
        print(json.dumps({"solve_s": wall, "counters": counters}))
        return 0
    if args.processes_only is not None:
        m0 = machine()
        doc = processes(args.quick, rounds)
        doc.update(machine_before=m0, machine_after=machine(),
                   affinity=sorted(os.sched_getaffinity(0)))
        args.processes_only.write_text(json.dumps(doc, indent=1) + "\n")
        so = doc["summary_over_integrator"]
        print(f"summary wall / integrator alone: {so['median_ratio']} (paired median of "
              f"{len(so['ratios'])} rounds; per round {[round(r, 3) for r in so['ratios']]})")
        return 0
    print("\n".join(markdown(run(args.quick, rounds=rounds))))
    return 0


if __name__ == "__main__":
    sys.exit(main())
