"""Parallel efficiency of ``kvrod sweep`` on the cores of one machine, measured (issue 33).

bench/sweeps.py derives the efficiency of 256 points of ~0.35 s on 16 workers from the
costs it measures on 2 cores; this module measures it where a machine has the cores:

* a study of 256 points (16 retardation times x 16 Young's moduli of the paper's
  cantilever, N = 50, rtol 1e-6), its ``t_end`` chosen from one calibration run so that a
  point takes ~0.35 s on this machine;
* the whole ``kvrod sweep STUDY --serial`` command (one process, the points one after
  another) and the whole ``kvrod sweep STUDY --workers W`` command (a LocalCluster of W
  single-threaded worker processes), each from its start to its end, in turn;
* efficiency = serial wall / (W x parallel wall): whole commands, so the parallel one
  pays its cluster's start and close and its client; and, beside it, the points' own
  serial seconds (study.csv's ``wall_time_s``) over W x the parallel wall.

Both commands run the same points into folders of their own, with the compiled kernels
in the cache already (a warm-up run first). One core running alone may run faster than
all of them together (turbo frequencies, a shared memory bus): that goes against the
parallel run, as it does for a user.

    python -m bench.sweep_cores --workers 16 --out DIR   # DIR/sweep_cores.json, .md
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from bench.overhead import machine

POINTS_SIDE = 16                    # 16 x 16 = 256 points
POINT_S = 0.35                      # s: the point's time aimed at
EFFICIENCY_MIN = 0.9
CALIBRATION_T = 10.0                # s simulated in the first calibration run


def calibrate(point_s: float = POINT_S, side: int = POINTS_SIDE) -> dict[str, Any]:
    """``t_end`` (s, rounded to 0.5 s) at which the middle point of the grid takes ~
    ``point_s`` of wall time here: a run of :data:`CALIBRATION_T` s after a warm-up,
    scaled in proportion, then once more from a run at that ``t_end`` (a run's first
    seconds, the large swings, cost more than its later ones)."""
    from runtime.problem.registry import load_problem
    from runtime.simulate.simulate import simulate

    taus, moduli = grid(side)
    mid = {"n_elements": 50, "rtol": 1e-6, "tau": taus[side // 2],
           "youngs_modulus": moduli[side // 2]}

    def wall_at(t_end: float) -> float:
        p = load_problem("cantilever", {**mid, "t_end": t_end})
        t0 = time.perf_counter()
        simulate(p)
        return time.perf_counter() - t0

    wall_at(1.0)                                        # warm-up: kernels, caches
    t_end, runs = CALIBRATION_T, []
    for _ in range(2):
        w = wall_at(t_end)
        runs.append([t_end, w])
        t_end = min(1000.0, max(0.5, round(2.0 * t_end * point_s / w) / 2.0))
    return {"calibration_runs": runs, "t_end": t_end}


def grid(side: int = POINTS_SIDE) -> tuple[list[float], list[float]]:
    """The study's retardation times (s) and Young's moduli (Pa), ``side`` of each."""
    return ([round(0.01 + 0.005 * k, 4) for k in range(side)],
            [round(1.0e6 * (1.0 + 0.1 * k), 1) for k in range(side)])


def study_text(t_end: float, side: int = POINTS_SIDE) -> str:
    """The study file: ``side`` x ``side`` points (tau x Young's modulus)."""
    taus, moduli = grid(side)
    return (f'name = "cores"\nproblem = "cantilever"\n[fixed]\nn_elements = 50\n'
            f"rtol = 1e-6\nt_end = {t_end!r}\n[grid]\ntau = {taus!r}\n"
            f"youngs_modulus = {moduli!r}\n")


def _command(study: Path, out: Path, *flags: str) -> dict[str, Any]:
    """One whole ``kvrod sweep`` process: wall (s), exit code, the points' own seconds."""
    cmd = [sys.executable, "-m", "kvrod.cli", "sweep", str(study), *flags, "--out", str(out)]
    t0 = time.perf_counter()
    p = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    rows = []
    if (out / "study.csv").exists():
        with open(out / "study.csv", newline="") as f:
            rows = list(csv.DictReader(f))
    finished = [r for r in rows if r["status"] == "finished"]
    timing = next((ln for ln in p.stdout.splitlines() if ln.startswith("timing:")), "")
    return {"command": " ".join(cmd[1:]), "wall_s": wall, "rc": p.returncode,
            "timing": timing,
            "points": len(rows), "finished": len(finished),
            "points_s": sum(float(r["wall_time_s"]) for r in finished),
            "stderr_tail": p.stderr.strip().splitlines()[-3:] if p.returncode else []}


def run(workers: int, point_s: float = POINT_S, side: int = POINTS_SIDE,
        log=print) -> dict[str, Any]:
    """The document of the module docstring."""
    m0 = machine()
    cal = calibrate(point_s, side)
    log(f"calibration (t_end s, wall s): {cal['calibration_runs']} -> t_end {cal['t_end']:g} s")
    with tempfile.TemporaryDirectory(prefix="kvrod-bench-cores-") as tmp:
        root = Path(tmp)
        study = root / "study.toml"
        study.write_text(study_text(cal["t_end"], side))
        serial = _command(study, root / "serial", "--serial")
        log(f"serial: {serial['wall_s']:.1f} s, {serial['finished']} points, "
            f"{serial['points_s']:.1f} s of points")
        parallel = _command(study, root / "parallel", "--workers", str(workers))
        log(f"{workers} workers: {parallel['wall_s']:.2f} s, {parallel['finished']} points")
    n = side * side
    ok = serial["finished"] == n and parallel["finished"] == n
    eff = serial["wall_s"] / (workers * parallel["wall_s"]) if ok else None
    eff_points = serial["points_s"] / (workers * parallel["wall_s"]) if ok else None
    return {"workers": workers, "points": n, "point_s_aimed": point_s, **cal,
            "point_s_measured": serial["points_s"] / max(1, serial["finished"]),
            "serial": serial, "parallel": parallel,
            "efficiency_whole_commands": eff, "efficiency_points": eff_points,
            "efficiency_min": EFFICIENCY_MIN,
            "met": None if eff is None else bool(eff >= EFFICIENCY_MIN),
            "machine_before": m0, "machine_after": machine(),
            "python": platform.python_version(), "cpu_count": os.cpu_count(),
            "measured_at": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
            "commit": _commit()}


def _commit() -> str | None:
    """The checkout's commit (a record says which code it measured), None outside git."""
    try:
        r = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True,
                           text=True, timeout=10, cwd=Path(__file__).resolve().parents[1])
    except (OSError, subprocess.SubprocessError):
        return None
    return r.stdout.strip() or None


def markdown(doc: dict[str, Any]) -> list[str]:
    m = doc["machine_before"]
    s, p = doc["serial"], doc["parallel"]
    eff, effp = doc["efficiency_whole_commands"], doc["efficiency_points"]
    verdict = "not measured" if eff is None else ("met" if doc["met"] else "missed")
    eff_s = "-" if eff is None else f"{eff:.3f}"
    effp_s = "-" if effp is None else f"{effp:.3f}"
    return [
        "# kvrod sweep on the cores of one machine (issue 33, item 3)", "",
        f"Machine: {m['cpu_model']}, {m['cpus']} cores, {m['memory_gib']} GiB, "
        f"{m['platform']}, Python {doc['python']}; load average {m['load_average']} before, "
        f"{doc['machine_after']['load_average']} after. Command: "
        f"`python -m bench.sweep_cores --workers {doc['workers']}`.", "",
        f"{doc['points']} points of the cantilever (N = 50, rtol 1e-6, t_end "
        f"{doc['t_end']:g} s: {doc['point_s_measured']:.3f} s a point here, aimed at "
        f"{doc['point_s_aimed']:g} s), a grid of tau x Young's modulus.", "",
        "| command | wall s | points | points' own s |", "|:--|---:|---:|---:|",
        f"| `kvrod sweep --serial` | {s['wall_s']:.2f} | {s['finished']} | "
        f"{s['points_s']:.2f} |",
        f"| `kvrod sweep --workers {doc['workers']}` | {p['wall_s']:.2f} | {p['finished']} | "
        f"{p['points_s']:.2f} |", "",
        f"- parallel efficiency, whole commands: serial wall / ({doc['workers']} x parallel "
        f"wall) = **{eff_s}** (target >= "
        f"{doc['efficiency_min']:.0%}: {verdict})",
        f"- the points' own serial seconds / ({doc['workers']} x parallel wall) = "
        f"{effp_s}",
        "", "Where the commands' time went (their own timing lines, from the run's start "
        "after the interpreter's):", "",
        f"- serial: {s.get('timing') or '(not printed)'}",
        f"- parallel: {p.get('timing') or '(not printed)'}",
        ""]


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m bench.sweep_cores",
                                 description=__doc__.splitlines()[0])
    ap.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    ap.add_argument("--point-s", type=float, default=POINT_S)
    ap.add_argument("--side", type=int, default=POINTS_SIDE,
                    help="points per side of the grid (side^2 points)")
    ap.add_argument("--out", type=Path, required=True)
    args = ap.parse_args(argv)
    if args.workers < 1:
        ap.error(f"--workers must be >= 1, got {args.workers}")
    if not 0 < args.point_s < 60:
        ap.error(f"--point-s must be in (0, 60) s, got {args.point_s}")
    if args.side < 1:
        ap.error(f"--side must be >= 1, got {args.side}")
    args.out.mkdir(parents=True, exist_ok=True)
    doc = run(args.workers, args.point_s, args.side)
    (args.out / "sweep_cores.json").write_text(json.dumps(doc, indent=1) + "\n")
    (args.out / "sweep_cores.md").write_text("\n".join(markdown(doc)))
    print("\n".join(markdown(doc)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
