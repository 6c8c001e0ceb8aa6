"""Contact's cost (issue 32): a cable falling onto a floor and coming to rest against the
same cable swinging free for the same time.

The cable: 1 m, N = 200 (or N_QUICK), a 2 mm round section of a stiff polymer (E = 2 GPa,
rho = 1400 kg/m^3, tau = 0.01 s), pinned at s = 0 at the origin, released horizontal under
gravity. ``fall``: a floor 0.3 m below the pin (friction 0.3): the cable swings down, its
far part hits the floor, slides and comes to rest lying on it. ``free``: the same file
without the floor: it swings as a damped pendulum chain. Both are written from one mapping
(``problem(floor)``) into a temporary folder and run as whole processes, ``python -m
kvrod.cli simulate FILE --out DIR --overwrite``, after one warm-up each (the compile cache
warm, the contact library included), in PAIRS pairs run in turn; the ratio fall/free is
taken pair by pair and its median reported (a slow spell of the shared machine spoils one
pair). CPU time of each child from the operating system. The issue's target: the fall at
most 3x the free swing. Then self-contact's share of a step at N = 1000
(:mod:`bench.self_contact_share`).

``python -m bench --only contact`` runs this section alone; ``--quick``: N = 50, 0.5 s,
one pair, no warm-up (a smoke run, not a measurement).
"""

from __future__ import annotations

import os
import statistics
import tempfile
from pathlib import Path
from typing import Any

from bench import self_contact_share
from bench.maxwell_kv import machine, timed_process
from bench.meta import target, targets_md

N_FULL, T_FULL = 200, 2.0
N_QUICK, T_QUICK = 50, 0.5
PAIRS = 3
#: issue 32: the fall at most this many times the free swing, whole processes
RATIO_MAX = 3.0
TIMEOUT = 900.0


def problem(floor: bool, N: int, T: float) -> dict[str, Any]:
    """The cable's problem mapping (module docstring)."""
    m: dict[str, Any] = {
        "name": "falling_cable" if floor else "swinging_cable",
        "description": "pinned cable released horizontal" + (" onto a floor" if floor else ""),
        "rod": {"length": 1.0, "elements": int(N),
                "geometry": {"kind": "straight", "direction": [1.0, 0.0, 0.0],
                             "normal": [0.0, 1.0, 0.0]}},
        "section": {"kind": "circle", "radius": 0.002},
        "material": {"youngs_modulus": 2e9, "poisson_ratio": 0.4, "density": 1400.0,
                     "tau": 0.01},
        "start": {"kind": "pinned"},
        "end": {"kind": "free"},
        "loads": [{"kind": "gravity", "vector": [0.0, 0.0, -9.81]}],
        "simulation": {"t_end": float(T), "output_step": 0.01, "initial": "reference"},
    }
    if floor:
        m["obstacles"] = [{"kind": "plane", "point": [0.0, 0.0, -0.3],
                           "normal": [0.0, 0.0, 1.0], "friction": 0.3}]
    return m


def _write(path: Path, mapping: dict) -> Path:
    from runtime.io.results import write_problem

    write_problem(path, mapping)
    return path


def whole_process(file: Path, out: Path) -> tuple[float, float, int, str]:
    """One ``kvrod simulate`` process: (wall s, CPU s of the child, exit code, last
    stderr line)."""
    return timed_process(["simulate", str(file), "--out", str(out), "--overwrite"], TIMEOUT)


def _summary(out: Path) -> dict[str, Any]:
    import json

    s = json.loads((out / "summary.json").read_text())
    o = (s.get("obstacles") or [{}])[0]
    return {"steps": s["counters"]["nstep"], "counters": s["counters"],
            "audit": s["energy_balance_max_rel"], "wall_in_summary": s["wall_time_s"],
            "gap_min": (o.get("gap_min") or {}).get("value")}


def run(quick: bool = False, log=print, pairs: int | None = None) -> dict:
    """The section's document (module docstring)."""
    N, T = (N_QUICK, T_QUICK) if quick else (N_FULL, T_FULL)
    pairs = (1 if quick else PAIRS) if pairs is None else pairs
    doc: dict[str, Any] = {"quick": quick, "N": N, "T": T, "pairs": pairs,
                           "machine": machine(),
                           "load_average_at_start": [round(v, 2) for v in os.getloadavg()]}
    names = ("fall", "free")
    rows: dict[str, dict[str, list[float]]] = {k: {"walls": [], "cpu": []} for k in names}
    failed = ""
    with tempfile.TemporaryDirectory(prefix="kvrod-bench-contact-") as tmp:
        root = Path(tmp)
        files = {k: _write(root / f"{k}.toml", problem(k == "fall", N, T)) for k in names}
        if not quick:
            for k in names:
                *_, rc, err = whole_process(files[k], root / f"warm-{k}")
                if rc:
                    failed = f"{k}: {err}"
        for j in range(pairs if not failed else 0):
            for k in names:
                wall, cpu, rc, err = whole_process(files[k], root / k)
                if rc:
                    failed = f"{k}: {err}"
                    break
                rows[k]["walls"].append(wall)
                rows[k]["cpu"].append(cpu)
            if failed:
                break
            log(f"  pair {j + 1}/{pairs}: fall {rows['fall']['walls'][-1]:.2f} s, free "
                f"{rows['free']['walls'][-1]:.2f} s")
        runs = {k: _summary(root / k) for k in names if (root / k / "summary.json").exists()}
    n = min(len(rows["fall"]["walls"]), len(rows["free"]["walls"]))
    ratios = [a / b for a, b in zip(rows["fall"]["walls"][:n], rows["free"]["walls"][:n],
                                    strict=True)]
    cpu_ratios = [a / b for a, b in zip(rows["fall"]["cpu"][:n], rows["free"]["cpu"][:n],
                                        strict=True)]
    doc.update({"whole_process": {k: {**rows[k], "median": statistics.median(rows[k]["walls"])
                                      if rows[k]["walls"] else None} for k in names},
                "ratios": ratios, "median_ratio": statistics.median(ratios) if n else None,
                "cpu_ratios": cpu_ratios,
                "median_cpu_ratio": statistics.median(cpu_ratios) if n else None,
                "runs": runs, "failed": failed,
                "load_average_at_end": [round(v, 2) for v in os.getloadavg()]})
    doc["targets"] = [target("cable falling onto a floor / swinging free, whole processes "
                             f"(N = {N}, {T:g} s), paired median", doc["median_ratio"],
                             RATIO_MAX, note="quick run" if quick else "")]
    log("  self-contact's share of a step")
    sc = self_contact_share.run(quick, log=log)
    doc["self_contact"] = sc
    doc["targets"].append(target(
        f"self-contact: search and forces, share of a step at N = {sc['N']}",
        sc["share_search_forces"], self_contact_share.SHARE_MAX,
        note=f"all contact costs {100 * sc['share_all_contact']:.0f} % of a step"
             + ("; quick run" if quick else "")))
    return doc


def markdown(doc: dict) -> list[str]:
    lines = ["## Contact: a cable falling onto a floor against the free swing (issue 32)", "",
             f"`python -m bench --only contact`: N = {doc['N']}, {doc['T']:g} s, "
             f"{doc['pairs']} pairs of whole `kvrod simulate` processes (bench/contact.py); "
             f"load average {doc['load_average_at_start']} at the start, "
             f"{doc.get('load_average_at_end')} at the end.", ""]
    if doc.get("failed"):
        lines += [f"Failed: {doc['failed']}", ""]
    lines += ["| run | median wall [s] | steps | energy audit | smallest gap [m] |",
              "|---|---:|---:|---:|---:|"]
    for k, label in (("fall", "onto the floor"), ("free", "swinging free")):
        w = doc["whole_process"][k]["median"]
        r = doc["runs"].get(k, {})
        gap = r.get("gap_min")
        lines.append(f"| {label} | {'-' if w is None else f'{w:.2f}'} | {r.get('steps', '-')} "
                     f"| {r.get('audit', float('nan')):.2e} | "
                     f"{'-' if gap is None else f'{gap:.2e}'} |")
    mr, mc = doc.get("median_ratio"), doc.get("median_cpu_ratio")
    lines += ["", f"Paired median ratio fall / free: wall {'-' if mr is None else f'{mr:.2f}'}, "
              f"CPU {'-' if mc is None else f'{mc:.2f}'}.", ""]
    lines += self_contact_share.markdown(doc.get("self_contact") or {})
    lines += targets_md(doc.get("targets", []))
    return lines
