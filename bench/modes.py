"""Damped modes at any size: whole ``kvrod modes`` processes beside a 10 s ``kvrod simulate``.

Rows (each a whole process, ``python -m kvrod.cli ...``: start-up, the model with a warm
compile cache, the analysis, modes.json/modes.npz and the two mode-shape figures):

* ``kvrod modes cantilever --n-elements N --count 8`` for N = 50, 1000, 4000 (Kelvin-Voigt);
* ``kvrod modes examples/maxwell_cantilever.toml --n-elements N --count 8`` for N = 50,
  1000 (generalized Maxwell, internal strains in the state);
* ``kvrod simulate cantilever --n-elements 4000 --t-end 10`` (the yardstick).

Timed from outside with a monotonic clock, after one warm-up run of each command (not
counted); ROUNDS rounds in which the commands run in turn, so a slow spell of the shared
machine spoils one round, not every repeat of one command; medians over the rounds, and
for modes at N = 4000 against the simulation the median of the per-round ratios (paired).
From each modes.json: the first damping ratio, and the largest relative difference in zeta
and in omega between the two bending modes of each twin pair (the square section's
symmetry: equal). Targets (issue 27): modes at N = 4000 within the simulation's wall
time; the Maxwell cantilever's first zeta at N = 1000 within 1e-3 (relative) of N = 50;
twins equal to 1e-6.

``--quick``: N = 50 only (both materials), the simulation at N = 50 for 2 s, one round,
no warm-up (a smoke run, not a measurement).
``python -m bench --only modes`` runs this section alone.
"""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from bench.meta import target, targets_md

ROUNDS = 5
QUICK_ROUNDS = 1
COUNT = 8
KV_N = (50, 1000, 4000)
MAXWELL_N = (50, 1000)
SIM_N, SIM_T = 4000, 10.0
QUICK_KV_N = (50,)
QUICK_MAXWELL_N = (50,)
QUICK_SIM_N, QUICK_SIM_T = 50, 2.0
TWIN_MAX = 1e-6
MAXWELL_ZETA_RTOL = 1e-3
RATIO_MAX = 1.0
TIMEOUT = 600.0


def _maxwell_file() -> str:
    from runtime.problem.registry import EXAMPLES_DIR

    return str(EXAMPLES_DIR / "maxwell_cantilever.toml")


def commands(quick: bool) -> list[dict]:
    """The rows: label, kind ("modes" / "simulate"), material, N, and the CLI arguments
    (without ``--out``)."""
    rows = []
    for N in QUICK_KV_N if quick else KV_N:
        rows.append({"label": f"modes KV N={N}", "kind": "modes", "material": "kelvin_voigt",
                     "N": N, "args": ["modes", "cantilever", "--n-elements", str(N),
                                      "--count", str(COUNT)]})
    for N in QUICK_MAXWELL_N if quick else MAXWELL_N:
        rows.append({"label": f"modes Maxwell N={N}", "kind": "modes",
                     "material": "generalized_maxwell", "N": N,
                     "args": ["modes", _maxwell_file(), "--n-elements", str(N), "--count",
                              str(COUNT)]})
    N, T = (QUICK_SIM_N, QUICK_SIM_T) if quick else (SIM_N, SIM_T)
    rows.append({"label": f"simulate KV N={N} {T:g} s", "kind": "simulate",
                 "material": "kelvin_voigt", "N": N, "T": T,
                 "args": ["simulate", "cantilever", "--n-elements", str(N), "--t-end",
                          f"{T:g}"]})
    return rows


def _run(args: list[str], out: Path) -> tuple[float, int, str]:
    """One whole process: (wall s, exit code, last stderr line)."""
    cmd = [sys.executable, "-m", "kvrod.cli", *args, "--out", str(out)]
    t0 = time.perf_counter()
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=TIMEOUT)
        rc, err = p.returncode, (p.stderr.strip().splitlines() or [""])[-1]
    except subprocess.TimeoutExpired:
        rc, err = -1, f"timed out after {TIMEOUT:g} s"
    return time.perf_counter() - t0, rc, err


def twin_spread(modes: list[dict]) -> tuple[float | None, float | None]:
    """Largest relative difference in zeta and in omega between the two bending modes of
    a twin pair (consecutive bending-1/bending-2 within 1e-4 in omega); None without a
    pair."""
    dz, dw = [], []
    for a, b in zip(modes, modes[1:], strict=False):
        if {a["family"], b["family"]} == {"bending-1", "bending-2"} and \
                abs(a["omega"] / b["omega"] - 1) < 1e-4 and a["zeta"] and b["zeta"]:
            dz.append(abs(a["zeta"] / b["zeta"] - 1))
            dw.append(abs(a["omega"] / b["omega"] - 1))
    return (max(dz) if dz else None), (max(dw) if dw else None)


def run(quick: bool = False, log=print, rounds: int | None = None) -> dict:
    """Time the rows (module docstring) and read their results; the section's document."""
    rows = commands(quick)
    rounds = rounds or (QUICK_ROUNDS if quick else ROUNDS)
    load_start = [round(v, 2) for v in os.getloadavg()]
    with tempfile.TemporaryDirectory(prefix="kvrod-bench-modes-") as tmp:
        root = Path(tmp)
        for i, r in enumerate(rows):            # warm-up: compile cache, file cache
            r.update(walls=[], ok=True, message="")
            if quick:
                continue
            wall, rc, err = _run(r["args"], root / f"warm{i}")
            r.update(ok=rc == 0, message=err if rc else "")
            log(f"  warm-up {r['label']}: {wall:.2f} s" + (f" (failed: {err})" if rc else ""))
        for k in range(rounds):
            for i, r in enumerate(rows):
                if not r["ok"]:
                    continue
                out = root / f"r{k}-{i}"
                wall, rc, err = _run(r["args"], out)
                if rc:
                    r.update(ok=False, message=err)
                    log(f"  {r['label']}: failed ({err})")
                    continue
                r["walls"].append(wall)
                if r["kind"] == "modes" and k == 0:
                    modes = json.loads((out / "modes.json").read_text())["modes"]
                    r["first_zeta"] = modes[0]["zeta"]
                    r["first_omega"] = modes[0]["omega"]
                    r["twin_zeta_max"], r["twin_omega_max"] = twin_spread(modes)
                log(f"  round {k + 1}/{rounds} {r['label']}: {wall:.2f} s")
    for r in rows:
        r["median"] = float(np.median(r["walls"])) if r["walls"] else None
    sim = rows[-1]
    big = next((r for r in rows if r["kind"] == "modes" and r["material"] == "kelvin_voigt"
                and r["N"] == sim["N"]), None)
    pair = None
    if big and big["walls"] and sim["walls"]:
        n = min(len(big["walls"]), len(sim["walls"]))
        ratios = [a / b for a, b in zip(big["walls"][:n], sim["walls"][:n], strict=True)]
        pair = {"modes": big["label"], "simulate": sim["label"], "ratios": ratios,
                "median_ratio": float(np.median(ratios))}
    mx = {r["N"]: r for r in rows if r["material"] == "generalized_maxwell" and r["ok"]}
    mx_rel = (abs(mx[1000]["first_zeta"] / mx[50]["first_zeta"] - 1)
              if 50 in mx and 1000 in mx else None)
    twins = [r["twin_zeta_max"] for r in rows if r.get("twin_zeta_max") is not None]
    note_quick = "quick run: N = 50 only" if quick else ""
    targets = [
        target(f"N = {SIM_N}: kvrod modes ({COUNT} lowest Kelvin-Voigt modes) / kvrod "
               f"simulate {SIM_T:g} s, whole processes, paired median <= {RATIO_MAX:g}",
               pair["median_ratio"] if pair and not quick else None, RATIO_MAX,
               note=note_quick),
        target(f"Maxwell cantilever: first zeta at N = 1000 against N = 50, relative <= "
               f"{MAXWELL_ZETA_RTOL:g}", mx_rel, MAXWELL_ZETA_RTOL, note=note_quick),
        target(f"twin bending modes of the square section: zeta equal to {TWIN_MAX:g} "
               "(largest relative difference over all rows)", max(twins) if twins else None,
               TWIN_MAX)]
    from bench.meta import metadata

    return {"quick": quick, "rounds": rounds, "count": COUNT, "rows": rows, "pair": pair,
            "maxwell_first_zeta_rel": mx_rel, "load_average_at_start": load_start,
            "targets": targets, "meta": metadata()}


def markdown(doc: dict) -> list[str]:
    """The section of bench/results/README.md."""
    meta = doc.get("meta", {})
    out = ["## 7. Damped modes at any size (kvrod modes) beside a simulation", "",
           "Whole processes (`python -m kvrod.cli ...`: start-up, model with a warm compile "
           f"cache, the analysis, modes.json/npz and the two mode-shape figures); "
           f"`--count {doc['count']}`; "
           + ("no warm-up, " if doc.get("quick") else "one warm-up each, then ")
           + f"{doc['rounds']} round(s) of all commands in turn; medians. Twin spread: "
           "the largest relative difference in zeta (omega) between the two bending "
           "modes of a pair of the square section. Load average "
           f"{doc.get('load_average_at_start')} at the start, "
           f"{meta.get('load_average_at_end')} at the end.", "",
           "| command | N | median wall s | min-max s | first omega rad/s | first zeta | "
           "twin spread zeta | twin spread omega |",
           "|:--|---:|---:|:--|---:|---:|---:|---:|"]

    def f(v, fmt):
        return "-" if v is None or (isinstance(v, float) and not math.isfinite(v)) \
            else format(v, fmt)

    for r in doc["rows"]:
        walls = r.get("walls") or []
        rng = f"{min(walls):.2f}-{max(walls):.2f}" if walls else "failed"
        cmd = " ".join(a if "/" not in a else "examples/" + Path(a).name for a in r["args"])
        out.append(f"| `kvrod {cmd}` | {r['N']} | {f(r.get('median'), '.2f')} | {rng} | "
                   f"{f(r.get('first_omega'), '.5f')} | {f(r.get('first_zeta'), '.6f')} | "
                   f"{f(r.get('twin_zeta_max'), '.1e')} | {f(r.get('twin_omega_max'), '.1e')} |")
    if doc.get("pair"):
        p = doc["pair"]
        out += ["", f"{p['modes']} / {p['simulate']}: paired median ratio "
                f"{p['median_ratio']:.2f} (rounds: "
                + ", ".join(f"{x:.2f}" for x in p["ratios"]) + ")."]
    if doc.get("maxwell_first_zeta_rel") is not None:
        out += ["", "Maxwell cantilever, first zeta at N = 1000 against N = 50: "
                f"{doc['maxwell_first_zeta_rel']:.1e} (relative)."]
    if doc.get("targets"):
        out += ["", *targets_md(doc["targets"])]
    return out + [""]


if __name__ == "__main__":
    import argparse

    ap = argparse.ArgumentParser(prog="python -m bench.modes", description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true")
    a = ap.parse_args()
    print("\n".join(markdown(run(a.quick))))
