"""The cost of forward sensitivities (issue 34, item 4): whole ``kvrod simulate`` processes
with k = 0, 1, 2, 4 sensitivities.

The paper's cantilever (``examples/cantilever.toml``), N = 50, 10 s, rtol 1e-6, released
from its static deflection; the parameters ``youngs_modulus``, ``tau_S``, ``density``,
``tip_force`` (the first k). Every round runs the four processes in turn (order rotated);
the ratio time(k) / time(0) is taken per round, then its median (paired: a slow spell of
the shared machine spoils one round, not one command). Wall and CPU (user + system of
the child) are both recorded; the target is the issue's ``time(k) <= (1 + 0.5 k)
time(0)`` on the wall median. One warm-up of each process first (compile caches, file
cache), child processes with a byte-code cache of their own (as
:mod:`bench.overhead`). The document records the machine and the load average before
and after. ``--quick``: 2 s simulated, two rounds. ``python -m bench --only
sensitivities`` runs this section alone (bench/results/sensitivities.json and .md).
"""

from __future__ import annotations

import json
import sys
import tempfile
from pathlib import Path
from typing import Any

from bench.meta import target, targets_md
from bench.overhead import _child_env, _median, _paired, _process, machine

N, T, RTOL = 50, 10.0, 1e-6
QUICK_T = 2.0
ROUNDS, QUICK_ROUNDS = 5, 2
PARAMETERS = ("youngs_modulus", "tau_S", "density", "tip_force")
KS = (0, 1, 2, 4)


def command(k: int, t_end: float, out: Path) -> list[str]:
    """``kvrod simulate`` of the cantilever with the first k :data:`PARAMETERS`."""
    cmd = [sys.executable, "-m", "kvrod.cli", "simulate", "cantilever", "--n-elements",
           str(N), "--t-end", f"{t_end:g}", "--out", str(out), "--overwrite"]
    return cmd + (["--sensitivities", ",".join(PARAMETERS[:k])] if k else [])


def run(quick: bool = False, log=print, rounds: int | None = None) -> dict[str, Any]:
    """The section's document (see the module docstring)."""
    from bench.meta import metadata

    rounds = rounds or (QUICK_ROUNDS if quick else ROUNDS)
    t_end = QUICK_T if quick else T
    before = machine()
    rec: dict[int, dict[str, list[float]]] = {k: {"wall": [], "cpu": [], "summary": []}
                                              for k in KS}
    counters: dict[int, dict[str, int]] = {}
    errors: dict[str, str] = {}
    with tempfile.TemporaryDirectory(prefix="kvrod-bench-sens-") as tmp:
        root = Path(tmp)
        env = _child_env(root / "pycache")
        cmds = {k: command(k, t_end, root / f"k{k}") for k in KS}
        for k in KS:
            r = _process(cmds[k], env)
            log(f"  warm-up k = {k}: {r['wall']:.2f} s"
                + (f" (failed: {r['error']})" if r["rc"] else ""))
            if r["rc"]:
                errors[f"k={k}"] = r["error"]
        if errors:
            rounds = 0
        for j in range(rounds):
            order = list(KS[j % len(KS):] + KS[:j % len(KS)])
            got: dict[int, dict] = {}
            for k in order:
                r = _process(cmds[k], env)
                if r["rc"]:
                    errors[f"k={k}"] = r["error"]
                    break
                s = json.loads((root / f"k{k}" / "summary.json").read_text())
                r["summary"] = s["wall_time_s"]
                counters[k] = s["counters"]
                got[k] = r
            if len(got) < len(KS):
                continue
            for k, r in got.items():
                for key in ("wall", "cpu", "summary"):
                    rec[k][key].append(r[key])
            log(f"  round {j + 1}/{rounds}: " + ", ".join(
                f"k={k} {got[k]['wall']:.2f} s" for k in KS))
    after = machine()
    rows = []
    for k in KS:
        walls = _paired(rec[k]["wall"], rec[0]["wall"])
        cpus = _paired(rec[k]["cpu"], rec[0]["cpu"])
        sums = _paired(rec[k]["summary"], rec[0]["summary"])
        rows.append({"k": k, "parameters": list(PARAMETERS[:k]),
                     "median_wall": _median(rec[k]["wall"]),
                     "median_cpu": _median(rec[k]["cpu"]),
                     "median_summary_wall": _median(rec[k]["summary"]),
                     "walls": rec[k]["wall"], "cpus": rec[k]["cpu"],
                     "wall_ratios": walls, "median_wall_ratio": _median(walls),
                     "median_cpu_ratio": _median(cpus),
                     "median_summary_ratio": _median(sums),
                     "counters": counters.get(k, {})})
    note = f"quick run: {QUICK_T:g} s, {rounds} rounds" if quick else ""
    targets = [target(f"whole kvrod simulate process with k = {r['k']} sensitivities / "
                      f"without (wall, paired median) <= {1 + 0.5 * r['k']:g}",
                      r["median_wall_ratio"], 1 + 0.5 * r["k"], note=note)
               for r in rows if r["k"] > 0]
    return {"quick": quick, "N": N, "t_end": t_end, "rtol": RTOL, "rounds": rounds,
            "machine_before": before, "machine_after": after, "rows": rows,
            "errors": errors, "targets": targets, "meta": metadata()}


def markdown(doc: dict) -> list[str]:
    """The section of bench/results/README.md (and sensitivities.md)."""

    def f(v, fmt=".3f"):
        return "-" if v is None else format(v, fmt)

    m0, m1 = doc["machine_before"], doc["machine_after"]
    out = ["## 12. The cost of forward sensitivities (issue 34)", "",
           f"Whole `kvrod simulate cantilever --n-elements {doc['N']} --t-end "
           f"{doc['t_end']:g}` processes (rtol {doc['rtol']:g}, released from the static "
           "deflection) with k sensitivities (`--sensitivities`, the first k of "
           f"{', '.join(PARAMETERS)}); {doc['rounds']} rounds of the four commands in turn "
           "(order rotated), one warm-up each; ratios per round, then their median "
           f"(paired). Machine: {m0['cpu_model']}, {m0['cpus']} cores; load average "
           f"{m0['load_average']} before, {m1['load_average']} after.", "",
           "| k | wall median s | CPU median s | summary wall s | wall / k=0 | CPU / k=0 | "
           "summary / k=0 | target | steps | sens. iterations |",
           "|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|"]
    for r in doc["rows"]:
        c = r.get("counters", {})
        out.append(f"| {r['k']} | {f(r['median_wall'])} | {f(r['median_cpu'])} | "
                   f"{f(r['median_summary_wall'])} | **{f(r['median_wall_ratio'], '.2f')}** | "
                   f"{f(r['median_cpu_ratio'], '.2f')} | "
                   f"{f(r['median_summary_ratio'], '.2f')} | <= {1 + 0.5 * r['k']:g} | "
                   f"{c.get('nstep', '-')} | {c.get('nniS', '-')} |")
    out += ["", "The steps are the plain run's (the sensitivities do not enter the error "
            "test by default): the extra cost is the sensitivities' corrector (one solve "
            "per parameter and iteration with the state's factorisation) and their residual "
            "tangent."]
    if doc.get("errors"):
        out += ["", "Failed: " + "; ".join(f"{k}: {v}" for k, v in doc["errors"].items())]
    if doc.get("targets"):
        out += ["", *targets_md(doc["targets"])]
    return out + [""]


def main(argv: list[str] | None = None) -> int:
    import argparse

    ap = argparse.ArgumentParser(prog="python -m bench.sensitivities",
                                 description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args(argv)
    print("\n".join(markdown(run(args.quick))))
    return 0


if __name__ == "__main__":
    sys.exit(main())
