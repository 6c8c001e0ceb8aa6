"""Wall time per simulated second and peak memory of kvrod's integrator against N.

Each N runs in a fresh subprocess (``python -m bench.scaling N T rtol``) so that the peak
resident set size (``VmHWM`` of /proc/self/status) belongs to that run alone; the child
also reports the peak of Python/NumPy allocations during the solve (``tracemalloc``,
measured in a second, shorter solve so that tracing does not slow the timed one). A
0.01 s solve first warms up the process (library loading, first touches of the arrays).
The sizes run in ROUNDS rounds (N = 25 .. 4000, then again), one timed solve per size and
round, and each size's time is the median over the rounds: on a shared machine a slow
spell then spoils one size in one round, not all repeats of a size (the slope and the
N = 1000 figure are within such spells' reach otherwise). The
cantilever release of :mod:`bench.integrators` (``released_rod``), one rtol for all N
(the matched rtol at N = 50) with kvrod's per-component ``default_atol``, output every
0.1 s. The log-log slope of time against N is a least-squares fit, over all N and over
N >= 200 (the target: <= 1.05 up to N = 4000, on the N >= 200 fit).
"""

from __future__ import annotations

import json
import math
import resource
import subprocess
import sys
import time
import tracemalloc
from pathlib import Path

import numpy as np

from bench.meta import target

SIZES = (25, 50, 100, 200, 500, 1000, 2000, 4000)
QUICK_SIZES = (25, 50)
SLOPE_MAX = 1.05
N1000_MAX_SECONDS = 1.5
ROUNDS = 5


def _peak_rss_kib() -> float:
    """Peak resident set of this process image (VmHWM; ru_maxrss survives exec on Linux,
    so a child would report its parent's peak)."""
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("VmHWM:"):
                return float(line.split()[1])
    except OSError:
        pass
    return float(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss)


def one(N: int, T: float, rtol: float, repeats: int = 1) -> dict:
    """Run in this process: static solve, release, integrate T seconds; timings, memory."""
    from bench.idas_script import released_rod
    from runtime.solvers.integrator import solve

    c = released_rod(N, T)
    atol = c.atol(rtol)
    grid = np.linspace(0.0, T, int(round(10 * T)) + 1)
    # warm-up (first calls: library loading, page faults of the work arrays)
    solve(c.model, (0.0, 0.01), c.y0, c.yp0, rtol=rtol, atol=atol)
    walls = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        s = solve(c.model, (0.0, T), c.y0, c.yp0, rtol=rtol, atol=atol, t_eval=grid)
        walls.append(time.perf_counter() - t0)
    wall = float(np.median(walls))
    rss_kib = _peak_rss_kib()
    Tm = min(T, 0.2)
    tracemalloc.start()
    solve(c.model, (0.0, Tm), c.y0, c.yp0, rtol=rtol, atol=atol,
          t_eval=np.linspace(0.0, Tm, 3))
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    return {"N": N, "n": c.model.n, "T": T, "rtol": rtol, "ok": bool(s.success),
            "wall": wall, "walls": walls, "wall_per_simulated_second": wall / T,
            "us_per_step": 1e6 * wall / s.counters["nstep"],
            "static_seconds": c.static_seconds, **s.counters,
            "peak_rss_MiB": rss_kib / 1024.0, "solve_tracemalloc_peak_MiB": peak / 2**20}


def _child(N: int, T: float, rtol: float, timeout: float) -> dict:
    cmd = [sys.executable, "-m", "bench.scaling", str(N), repr(T), repr(rtol)]
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, check=True)
        return json.loads(p.stdout.strip().splitlines()[-1])
    except (subprocess.SubprocessError, json.JSONDecodeError, IndexError) as exc:
        return {"N": N, "ok": False, "message": str(exc)[-300:]}


def run(sizes=SIZES, T: float = 10.0, rtol: float = 1e-7, timeout: float = 600.0,
        log=print, rounds: int = ROUNDS) -> dict:
    by_n: dict[int, dict] = {}
    for k in range(rounds):
        for N in sizes:
            if k and not by_n[N].get("ok"):
                continue
            row = _child(N, T, rtol, timeout)
            if not row.get("ok"):
                by_n[N] = row
                log(f"  N={N}: failed ({row.get('message', '')})")
                continue
            first = by_n.setdefault(N, row)
            if first is not row:
                first["walls"] += row["walls"]
                first["peak_rss_MiB"] = max(first["peak_rss_MiB"], row["peak_rss_MiB"])
            log(f"  N={N} (round {k + 1}/{rounds}): {row['wall']:.2f} s for {T:g} s "
                f"simulated, {row['nstep']} steps, peak RSS {row['peak_rss_MiB']:.0f} MiB")
    rows = [by_n[N] for N in sizes]
    for r in rows:
        if r.get("ok"):
            r["wall"] = float(np.median(r["walls"]))
            r["wall_per_simulated_second"] = r["wall"] / T
            r["us_per_step"] = 1e6 * r["wall"] / r["nstep"]
    good = [r for r in rows if r.get("ok")]
    slope = None
    if len(good) >= 2:
        x = np.log([r["N"] for r in good])
        y = np.log([r["wall_per_simulated_second"] for r in good])
        slope = float(np.polyfit(x, y, 1)[0])
    big = [r for r in good if r["N"] >= 200]
    slope_large = None
    if len(big) >= 2:
        slope_large = float(np.polyfit(np.log([r["N"] for r in big]),
                                       np.log([r["wall_per_simulated_second"] for r in big]),
                                       1)[0])
    n1000 = [r_ for r_ in good if r_["N"] == 1000]
    targets = [
        target(f"log-log slope of time in N, N = 200 to 4000, <= {SLOPE_MAX}", slope_large,
               SLOPE_MAX, note="fit over N = " + ", ".join(str(r_["N"]) for r_ in big)
               if big else "no N >= 200 in this run"),
        target(f"N = 1000, 10 s simulated: kvrod integration < {N1000_MAX_SECONDS} s",
               n1000[0]["wall"] if n1000 and T == 10.0 else None, N1000_MAX_SECONDS,
               strict=True)]
    return {"T": T, "rtol": rtol, "rounds": rounds, "rows": rows, "loglog_slope": slope,
            "loglog_slope_N_ge_200": slope_large, "targets": targets}


def main(argv: list[str]) -> None:
    N, T, rtol = int(argv[0]), float(argv[1]), float(argv[2])
    out = one(N, T, rtol)
    print(json.dumps({k: (None if isinstance(v, float) and not math.isfinite(v) else v)
                      for k, v in out.items()}))


if __name__ == "__main__":
    main(sys.argv[1:])
