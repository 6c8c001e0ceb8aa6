"""What `kvrod fit` costs (issue 34): two parameters of the paper's cantilever from a 4 s record.

The record is made by kvrod itself: ``examples/cantilever.toml`` (N = 50) with the truth
E = 1.3 MPa, tau = 0.05 s, released from its static deflection, the tip's x every 5 ms for
4 s (the file's output step) plus Gaussian noise of 0.1 mm (seed 2024), written as the CSV
a user would give (``t,end.x``). Timed is the whole process a user runs,

    kvrod fit examples/cantilever.toml --data record.csv --params youngs_modulus,tau --out DIR

started from the file's values (E = 1 MPa, tau = 0.04 s): interpreter start, imports, the
checks, the growing windows, the whole record's fit, fit.json and fit.png. Each round runs
the process once (one warm-up first, not counted: compile caches, file cache); the median
of the rounds is quoted, with the model evaluations and iterations of fit.json, the values
found and their errors against the truth, and the load average before and after (the
machine is shared). ``--quick``: N = 16, one round.
``python -m bench --only fit`` runs this section alone.
"""

from __future__ import annotations

import json
import statistics
import sys
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

from bench.meta import metadata, target, targets_md
from bench.overhead import _child_env, _process, machine

N, T, QUICK_N = 50, 4.0, 16
ROUNDS, QUICK_ROUNDS = 3, 1
TRUTH = {"youngs_modulus": 1.3e6, "tau": 0.05}
NOISE = 1e-4                    # m
SEED = 2024
WALL_MAX = 30.0                 # s, the target


def write_record(path: Path, n_elements: int = N, t_end: float = T) -> Path:
    """The synthetic record of the module docstring as a CSV (t, end.x)."""
    from runtime.problem.registry import EXAMPLES_DIR, load_problem
    from runtime.simulate.simulate import simulate

    truth = load_problem(EXAMPLES_DIR / "cantilever.toml",
                         {"material.youngs_modulus": TRUTH["youngs_modulus"],
                          "material.tau": TRUTH["tau"], "rod.elements": n_elements,
                          "simulation.t_end": t_end})
    run = simulate(truth).finished("the truth's simulation")
    x = run.tip[0] + NOISE * np.random.default_rng(SEED).standard_normal(run.t.size)
    lines = ["t,end.x"] + [f"{t:.6f},{v:.9e}" for t, v in zip(run.t, x, strict=True)]
    path.write_text("\n".join(lines) + "\n")
    return path


def command(data: Path, out: Path, n_elements: int) -> list[str]:
    from runtime.problem.registry import EXAMPLES_DIR

    cmd = [sys.executable, "-m", "kvrod.cli", "fit", str(EXAMPLES_DIR / "cantilever.toml"),
           "--data", str(data), "--params", "youngs_modulus,tau", "--out", str(out),
           "--overwrite"]
    return cmd + (["--n-elements", str(n_elements)] if n_elements != N else [])


def run(quick: bool = False, log=print) -> dict[str, Any]:
    """Time the whole `kvrod fit` process (module docstring); the JSON document."""
    n = QUICK_N if quick else N
    rounds = QUICK_ROUNDS if quick else ROUNDS
    before = machine()
    walls: list[float] = []
    cpus: list[float] = []
    fits: list[dict] = []
    error = ""
    with tempfile.TemporaryDirectory(prefix="kvrod-bench-fit-") as tmp:
        root = Path(tmp)
        env = _child_env(root / "pycache")
        data = write_record(root / "record.csv", n)
        cmd = command(data, root / "fit", n)
        warm = _process(cmd, env)
        log(f"  warm-up: {warm['wall']:.1f} s" + (f" (exit {warm['rc']}: {warm['error']})"
                                                   if warm["rc"] else ""))
        for k in range(rounds):
            r = _process(cmd, env)
            if r["rc"] not in (0, 1):
                error = r["error"]
                log(f"  round {k + 1}: failed: {error}")
                break
            doc = json.loads((root / "fit" / "fit.json").read_text())
            walls.append(r["wall"])
            cpus.append(r["cpu"])
            fits.append(doc)
            log(f"  round {k + 1}/{rounds}: {r['wall']:.1f} s wall, {r['cpu']:.1f} s CPU, "
                f"{doc['model_evaluations']} model evaluations; "
                + ", ".join(f"{p} = {v:.6g}" for p, v in doc["parameters"].items()))
    last = fits[-1] if fits else {}
    errors = {p: (last["parameters"][p] / v - 1.0) for p, v in TRUTH.items()} if fits else {}
    med = float(statistics.median(walls)) if walls else None
    doc: dict[str, Any] = {
        "N": n, "t_end": T, "noise_m": NOISE, "seed": SEED, "truth": TRUTH,
        "start": last.get("start"), "rounds": len(walls),
        "command": "kvrod fit examples/cantilever.toml --data record.csv --params "
                   "youngs_modulus,tau --out DIR" + (f" --n-elements {n}" if n != N else ""),
        "wall": walls, "cpu": cpus, "median_wall": med,
        "median_cpu": float(statistics.median(cpus)) if cpus else None,
        "model_evaluations": last.get("model_evaluations"),
        "iterations": last.get("iterations"), "windows": last.get("windows"),
        "parameters": last.get("parameters"), "confidence": last.get("confidence"),
        "relative_errors": errors, "warnings": last.get("warnings"),
        "fit_wall_time_s": last.get("wall_time_s"), "error": error,
        "machine_before": before, "machine_after": machine()}
    note = f"median of {len(walls)} round(s); load average {before['load_average']} before"
    if quick:
        note += f"; quick run (N = {n}), the target is for N = {N}"
    doc["targets"] = [
        target(f"whole `kvrod fit` process, 2 parameters, paper's cantilever, {T:g} s record "
               f"< {WALL_MAX:g} s", med, WALL_MAX, strict=True, note=note),
        target("E and tau recovered within 1 %",
               max((abs(v) for v in errors.values()), default=None), 0.01,
               note="largest relative error against the truth")]
    doc["meta"] = metadata()
    return doc


def markdown(doc: dict) -> list[str]:
    """The section of bench/results/README.md."""

    def f(v, fmt=".2f"):
        return "-" if v is None else format(v, fmt)

    m0, m1 = doc["machine_before"], doc["machine_after"]
    out = ["## 13. kvrod fit: two parameters of the paper's cantilever (issue 34)", "",
           f"`{doc['command']}` on a {doc['t_end']:g} s record of the tip's x (every 5 ms, "
           f"N = {doc['N']}, truth E = {doc['truth']['youngs_modulus']:g} Pa, tau = "
           f"{doc['truth']['tau']:g} s, Gaussian noise {doc['noise_m'] * 1e3:g} mm, seed "
           f"{doc['seed']}), started from the file's values; the whole process, "
           f"{doc['rounds']} round(s) after a warm-up. Machine: {m0['cpu_model']}, "
           f"{m0['cpus']} cores; load average {m0['load_average']} before, "
           f"{m1['load_average']} after.", "",
           "| measure | value |", "|:--|--:|",
           f"| whole process, median wall (CPU) | {f(doc['median_wall'])} s "
           f"({f(doc['median_cpu'])} s) |",
           f"| model evaluations (simulations with 2 sensitivities) | "
           f"{doc['model_evaluations']} |",
           f"| iterations (accepted steps) of the whole record's fit | {doc['iterations']} |"]
    for p, v in (doc.get("parameters") or {}).items():
        lo, hi = doc["confidence"][p]
        out.append(f"| {p} | {v:.6g} (95 %: {lo:.6g} ... {hi:.6g}; error "
                   f"{doc['relative_errors'][p] * 100:+.3f} %) |")
    if doc.get("windows"):
        out.append("| windows (s) | " + ", ".join(
            f"{w['t_end']:.3g}: {w['model_evaluations']} evaluations"
            for w in doc["windows"]) + " |")
    if doc.get("error"):
        out += ["", f"Failed: {doc['error']}"]
    return out + ["", *targets_md(doc["targets"]), ""]


def main(argv: list[str] | None = None) -> int:
    import argparse

    ap = argparse.ArgumentParser(prog="python -m bench.fit", description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args(argv)
    print("\n".join(markdown(run(args.quick))))
    return 0


if __name__ == "__main__":
    sys.exit(main())
