"""Sweeps that scale and start-up (issue 33, items 3 and 5; issue 30's large serial study).

Every time here is of a whole process (``python -m kvrod ...``, start-up included) or of
work inside this process, taken side by side: the commands of a pair run in turn
(A B A B ...) after one warm-up each, and a ratio is the median of the per-pair ratios,
so that the shared machine's slow spells spoil a pair, not a command. Wall time is a
monotonic clock around the child; CPU time is the child's own (``os.wait4``: user +
system, of it and of the processes it waited for: a sweep's Dask workers are reaped by
its fork server, which the sweep reaps at exit, so their CPU is in it).

Children run with a bytecode cache (``PYTHONPYCACHEPREFIX`` in a temporary folder,
``PYTHONDONTWRITEBYTECODE`` removed, filled by the warm-up): an installed kvrod has its
``.pyc`` files; a checkout run with ``PYTHONDONTWRITEBYTECODE=1`` compiles every module
on every start (measured separately: ``version_no_pyc``).

Measured:

* start-up: ``kvrod --version`` and ``kvrod simulate cantilever --n-elements 10`` (the
  default 10 s simulated), each beside ``python -c pass`` (targets: 0.3 s and 0.6 s);
* tiny points: a study of ``tiny_points`` points of the cantilever at N = 4 over 0.05 s
  (tau x Young's modulus), the whole ``kvrod sweep --workers 2`` beside ``kvrod sweep
  --serial`` (target: >= 50 points/s on 2 workers);
* the worker's time per tiny point (:func:`runtime.study.sweep.run_batch` in this
  process, writing the point folders) beside ``simulate()`` alone on the same points:
  the difference is the fixed cost of a point (problem, model, files, row; target: the
  point under 15 ms);
* the client's cost per point on a 2-worker LocalCluster: the time its loop works
  (submitting, taking results, appending rows, counting), and the CPU of the client
  process (with the LocalCluster's scheduler and nannies in it) beyond its idle rate;
  the workers' CPU per point beside the in-process point (the Dask cost on a worker);
* a 40,000-point serial study (``--serial --yes``): seconds from the command's start to
  its first row in study.csv; Ctrl-C then keeps that row (issue 30);
* derived, not measured (the largest machine measured has 2 cores): the parallel
  efficiency of 256 points of 0.35 s on 16 workers of one machine, and the number of
  workers whose points one client keeps up with (:func:`derived`).

``python -m bench --only sweeps`` runs this section; ``--quick`` a smoke run (fewer
points and pairs, not a measurement).
"""

from __future__ import annotations

import contextlib
import json
import os
import resource
import shutil
import signal
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from bench.meta import metadata, target, targets_md

ROOT = Path(__file__).resolve().parents[1]
VERSION_MAX_S = 0.3
SIMULATE_MAX_S = 0.6
TINY_RATE_MIN = 50.0
TINY_POINT_MAX_S = 0.015
EFFICIENCY_MIN = 0.9
#: the 16-core study of issue 33: points, their time (s), workers
BIG_POINTS, BIG_POINT_S, BIG_WORKERS = 256, 0.35, 16
CLUSTER_WORKERS = 500


@dataclass(frozen=True)
class Size:
    """How much to run: pairs of whole commands, and the points of the studies."""

    startup_pairs: int = 10
    simulate_pairs: int = 5
    sweep_pairs: int = 3
    tiny_points: int = 500
    worker_points: int = 60
    client_points: int = 500
    serial_points: int = 40_000


QUICK = Size(startup_pairs=2, simulate_pairs=1, sweep_pairs=1, tiny_points=40,
             worker_points=8, client_points=40, serial_points=40_000)


def tiny_study(n: int) -> str:
    """A study of about ``n`` tiny points: the cantilever at N = 4 over 0.05 s, a grid of
    retardation times x Young's moduli (10 moduli)."""
    m = max(1, n // 10)
    taus = ", ".join(f"{0.01 + 1e-4 * i:.4f}" for i in range(m))
    moduli = ", ".join(f"{1e6 * (1 + 0.1 * i):.1f}" for i in range(min(n, 10)))
    return (f'name = "tiny"\nproblem = "cantilever"\n[fixed]\nn_elements = 4\n'
            f"t_end = 0.05\n[grid]\ntau = [{taus}]\nyoungs_modulus = [{moduli}]\n")


def child_env(pycache: Path) -> dict[str, str]:
    """The children's environment: this checkout first on the path, a bytecode cache."""
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT), *filter(None, [env.get("PYTHONPATH")])])
    env["PYTHONPYCACHEPREFIX"] = str(pycache)
    return env


def run_child(cmd: Sequence[str], env: dict[str, str], cwd: Path,
              timeout: float = 900.0) -> dict[str, Any]:
    """One whole process: wall (s), cpu (s: user + system, with what it waited for) and
    its exit code."""
    err_file = tempfile.TemporaryFile()
    t0 = time.perf_counter()
    p = subprocess.Popen(list(cmd), env=env, cwd=cwd, stdout=subprocess.DEVNULL,
                         stderr=err_file, start_new_session=True)
    deadline = t0 + timeout
    while True:
        pid, status, ru = os.wait4(p.pid, os.WNOHANG)
        if pid:
            break
        if time.perf_counter() > deadline:
            with contextlib.suppress(ProcessLookupError):
                os.killpg(p.pid, signal.SIGKILL)
            pid, status, ru = os.wait4(p.pid, 0)
            break
        time.sleep(0.002)
    wall = time.perf_counter() - t0
    p.returncode = os.waitstatus_to_exitcode(status)
    err_file.seek(0)
    err = err_file.read().decode(errors="replace")
    err_file.close()
    return {"wall": wall, "cpu": ru.ru_utime + ru.ru_stime, "rc": p.returncode,
            "stderr": err.strip().splitlines()[-1:] if p.returncode else []}


def paired(a: Callable[[int], Sequence[str]], b: Callable[[int], Sequence[str]], pairs: int,
           env: dict[str, str], cwd: Path, log: Callable[[str], object],
           label: str) -> dict[str, Any]:
    """``pairs`` runs of A and B in turn after one warm-up each; medians of wall and CPU,
    and the medians of the per-pair ratios A/B. ``a(i)``, ``b(i)``: the i-th command."""
    run_child(a(-1), env, cwd)
    run_child(b(-1), env, cwd)
    ra, rb = [], []
    for i in range(pairs):
        ra.append(run_child(a(i), env, cwd))
        rb.append(run_child(b(i), env, cwd))
        log(f"  {label} pair {i + 1}/{pairs}: A {ra[-1]['wall']:.3f} s (cpu "
            f"{ra[-1]['cpu']:.3f}), B {rb[-1]['wall']:.3f} s (cpu {rb[-1]['cpu']:.3f})")

    def med(rs, k):
        return statistics.median(r[k] for r in rs)

    failed = [r for r in ra + rb if r["rc"]]
    pairs_ab = list(zip(ra, rb, strict=True))
    return {"A": " ".join(map(str, a(0))), "B": " ".join(map(str, b(0))), "pairs": pairs,
            "A_wall": med(ra, "wall"), "A_cpu": med(ra, "cpu"),
            "B_wall": med(rb, "wall"), "B_cpu": med(rb, "cpu"),
            "A_walls": [r["wall"] for r in ra], "B_walls": [r["wall"] for r in rb],
            "ratio_wall": statistics.median(x["wall"] / y["wall"] for x, y in pairs_ab),
            "ratio_cpu": statistics.median(x["cpu"] / y["cpu"] for x, y in pairs_ab),
            "failed": [r["stderr"] for r in failed]}


def _kvrod(*args: str) -> list[str]:
    return [sys.executable, "-m", "kvrod", *args]


def startup(size: Size, root: Path, env: dict[str, str], log) -> dict[str, Any]:
    """``kvrod --version`` and ``kvrod simulate`` (N = 10) beside ``python -c pass``."""
    bare = [sys.executable, "-c", "pass"]
    version = paired(lambda i: _kvrod("--version"), lambda i: bare, size.startup_pairs,
                     env, root, log, "kvrod --version | python -c pass")
    no_pyc = {k: v for k, v in env.items() if k != "PYTHONPYCACHEPREFIX"}
    no_pyc["PYTHONDONTWRITEBYTECODE"] = "1"
    version_no_pyc = paired(lambda i: _kvrod("--version"), lambda i: bare,
                            size.startup_pairs, no_pyc, root, log,
                            "kvrod --version without .pyc | python -c pass")
    simulate = paired(lambda i: _kvrod("simulate", "cantilever", "--n-elements", "10",
                                       "--out", str(root / f"sim{i}"), "--overwrite"),
                      lambda i: bare, size.simulate_pairs, env, root, log,
                      "kvrod simulate N=10 | python -c pass")
    return {"version": version, "version_no_pyc": version_no_pyc, "simulate": simulate}


def tiny_sweep(size: Size, root: Path, env: dict[str, str], log) -> dict[str, Any]:
    """The whole ``kvrod sweep`` of tiny points on 2 workers beside ``--serial``."""
    study = root / "tiny.toml"
    study.write_text(tiny_study(size.tiny_points))
    from runtime.study.sweep import load_study

    n = len(load_study(study).points)

    def dask(i):
        return _kvrod("sweep", str(study), "--workers", "2", "--out", str(root / f"d{i}"))

    def serial(i):
        return _kvrod("sweep", str(study), "--serial", "--out", str(root / f"s{i}"))

    r = paired(dask, serial, size.sweep_pairs, env, root, log,
               "kvrod sweep --workers 2 | --serial")
    # on 2 cores with nothing else running the command cannot beat its CPU time / 2 (the
    # workers' CPU is in it: the sweep reaps its fork server, their parent, at exit)
    r.update(points=n, points_per_s=n / r["A_wall"], serial_points_per_s=n / r["B_wall"],
             cpu_bound_points_per_s=n / (r["A_cpu"] / 2))
    return r


def worker_cost(size: Size, root: Path) -> dict[str, Any]:
    """Per tiny point in this process: run_batch (the worker's task: the point, its
    folder, its row) beside simulate() alone on the same points, in turn; CPU and wall."""
    from runtime.problem.registry import load_problem
    from runtime.simulate.simulate import simulate
    from runtime.study.sweep import TOKEN_NAME, base_problem, load_study, run_batch

    study_file = root / "worker.toml"
    study_file.write_text(tiny_study(size.worker_points))
    s = load_study(study_file)
    out = root / "worker"
    out.mkdir()
    (out / TOKEN_NAME).write_text("bench")
    pts = list(s.points)
    run_batch(s.problem, [(pts[0].id, pts[0].params)], s.param_columns, str(out), "bench")
    batch, alone = [], []
    for p in pts[1:]:
        w, c = time.perf_counter(), time.process_time()
        run_batch(s.problem, [(p.id, p.params)], s.param_columns, str(out), "bench")
        batch.append((time.perf_counter() - w, time.process_time() - c))
        w, c = time.perf_counter(), time.process_time()
        simulate(load_problem(base_problem(s.problem), p.params))
        alone.append((time.perf_counter() - w, time.process_time() - c))
    med = statistics.median
    return {"points": len(batch),
            "point_wall": med(b[0] for b in batch), "point_cpu": med(b[1] for b in batch),
            "simulate_wall": med(a[0] for a in alone),
            "simulate_cpu": med(a[1] for a in alone),
            "fixed_wall": med(b[0] - a[0] for b, a in zip(batch, alone, strict=True)),
            "fixed_cpu": med(b[1] - a[1] for b, a in zip(batch, alone, strict=True))}


def _cpu_self() -> float:
    ru = resource.getrusage(resource.RUSAGE_SELF)
    return ru.ru_utime + ru.ru_stime


def client_cost(size: Size, root: Path, worker: dict[str, Any]) -> dict[str, Any]:
    """A study of tiny points on a 2-worker LocalCluster started by this process: the
    client loop's own time, the client process's CPU beyond its idle rate, and the
    workers' CPU per point."""
    from distributed import Client

    from runtime.study.sweep import load_study
    from runtime.study.sweep_dask import KvrodWorkerSetup, run_study_dask, start_local_cluster

    study_file = root / "client.toml"
    study_file.write_text(tiny_study(size.client_points))
    s = load_study(study_file)
    t0 = time.perf_counter()
    cluster = start_local_cluster(2)
    client = Client(cluster)
    try:
        client.register_plugin(KvrodWorkerSetup())
        startup_s = time.perf_counter() - t0
        c0, w0 = _cpu_self(), time.perf_counter()
        time.sleep(3.0)
        idle = (_cpu_self() - c0) / (time.perf_counter() - w0)
        busy0 = client.run(time.process_time)
        c0 = _cpu_self()
        report = run_study_dask(s, root / "client", client=client, plots=False)
        process_cpu = _cpu_self() - c0
        busy1 = client.run(time.process_time)
    finally:
        client.close()
        cluster.close()
    n = len(report.computed)
    worker_cpu = sum(busy1[k] - busy0[k] for k in busy0) / n
    return {"points": n, "tasks": report.tasks, "wall": report.wall_time_s,
            "points_per_s": n / report.wall_time_s, "cluster_start_s": startup_s,
            "loop_per_point": report.client_seconds / n,
            "process_cpu_per_point": max(0.0, process_cpu - idle * report.wall_time_s) / n,
            "idle_cpu_per_s": idle, "worker_cpu_per_point": worker_cpu,
            "dask_cpu_per_point_on_worker": worker_cpu - worker["point_cpu"]}


@contextlib.contextmanager
def _sigint_inherited():
    """Children started meanwhile take Ctrl-C: a bench started in the background of a
    non-interactive shell (``python -m bench ... &``) has SIGINT ignored, and an ignored
    signal stays ignored across exec (a caught one is reset to the default)."""
    ignored = signal.getsignal(signal.SIGINT) is signal.SIG_IGN
    if ignored:
        signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        yield
    finally:
        if ignored:
            signal.signal(signal.SIGINT, signal.SIG_IGN)


def first_row(size: Size, root: Path, env: dict[str, str]) -> dict[str, Any]:
    """``kvrod sweep --serial --yes`` of a large grid: seconds to its first row, then
    Ctrl-C; the row is still there."""
    axis = max(1, round(size.serial_points ** 0.5))
    study = root / "large.toml"
    study.write_text(
        'name = "large"\nproblem = "cantilever"\n[fixed]\nn_elements = 4\nt_end = 0.05\n'
        f"[grid]\ntau = [{', '.join(f'{0.01 + 1e-6 * i:.6f}' for i in range(axis))}]\n"
        f"youngs_modulus = [{', '.join(f'{1e6 + i:.1f}' for i in range(axis))}]\n")
    out = root / "large"
    err = root / "large.stderr"
    t0 = time.perf_counter()
    with open(err, "w") as err_file, _sigint_inherited():
        p = subprocess.Popen(
            _kvrod("sweep", str(study), "--serial", "--yes", "--out", str(out)),
            env={**env, "PYTHONFAULTHANDLER": "1"}, cwd=root, stdout=subprocess.DEVNULL,
            stderr=err_file, start_new_session=True)
    table = out / "study.csv"
    seconds, stuck = None, None
    try:
        while p.poll() is None and time.perf_counter() - t0 < 300:
            with contextlib.suppress(OSError):
                if table.read_text().count("\n") >= 2:
                    seconds = time.perf_counter() - t0
                    break
            time.sleep(0.01)
    finally:
        with contextlib.suppress(ProcessLookupError):
            os.killpg(p.pid, signal.SIGINT)
        try:
            rc = p.wait(timeout=60)
        except subprocess.TimeoutExpired:     # say where it was (faulthandler on SIGABRT)
            with contextlib.suppress(OSError):
                stuck = [ln.strip() for ln in Path(f"/proc/{p.pid}/status").read_text()
                         .splitlines() if ln.startswith(("SigIgn", "SigBlk", "SigCgt"))]
            os.kill(p.pid, signal.SIGABRT)
            time.sleep(2.0)
            with contextlib.suppress(ProcessLookupError):
                os.killpg(p.pid, signal.SIGKILL)
            rc = p.wait()
            stuck = (stuck or []) + err.read_text().splitlines()[-40:]
    rows = table.read_text().count("\n") - 1 if table.exists() else 0
    return {"points": axis * axis, "seconds_to_first_row": seconds, "exit_code": rc,
            "rows_kept_after_ctrl_c": rows, "not_stopped_by_ctrl_c": stuck}


def derived(worker: dict[str, Any], client: dict[str, Any], cluster_start_s: float,
            point_s: float = BIG_POINT_S, points: int = BIG_POINTS,
            workers: int = BIG_WORKERS) -> dict[str, Any]:
    """Parallel efficiency of ``points`` points of ``point_s`` on ``workers`` workers of
    one machine, from the measured costs (derived, not measured).

    Per point a worker spends ``point_s`` + the fixed cost f (its problem, model, files,
    row: :func:`worker_cost`, CPU time: the wall time of a loaded machine is not the
    point's) + the Dask cost on a worker d (points of 0.35 s go one per task, two per
    worker ahead); the client keeps two tasks per worker in flight, so while its loop keeps up
    (utilisation u = workers / (point_s + f + d) x its cost per point < 1) no worker
    waits for it. Efficiency = points x point_s / (workers x wall), wall = the rounds'
    time (points of equal length: no tail) and, in the second figure, the cluster's
    start-up as measured here (2 workers; 16 start in parallel on 16 cores) and its
    close.
    """
    f = max(0.0, worker["fixed_cpu"])
    d = max(0.0, client["dask_cpu_per_point_on_worker"])
    per_point = point_s + f + d
    rounds = -(-points // workers)
    steady = point_s / per_point
    client_s = client["loop_per_point"] + client["process_cpu_per_point"]
    u = workers / per_point * client_s
    wall = rounds * per_point
    with_start = points * point_s / (workers * (wall + cluster_start_s))
    # the workers one client feeds at u = 1 with points of point_s
    feeds = per_point / client_s if client_s > 0 else None
    return {"point_s": point_s, "points": points, "workers": workers,
            "fixed_s": f, "dask_s": d, "client_s_per_point": client_s,
            "client_utilisation": u, "efficiency": steady if u < 1 else steady / u,
            "efficiency_with_cluster_start": with_start,
            "cluster_start_s": cluster_start_s,
            "workers_one_client_feeds": feeds,
            "client_utilisation_500_workers": CLUSTER_WORKERS / per_point * client_s}


#: the last many-core measurement (python -m bench.sweep_cores), committed with the results
SWEEP_CORES_RECORD = ROOT / "bench" / "results" / "sweep_cores.json"


def efficiency_target(est: dict[str, Any], record: Path = SWEEP_CORES_RECORD) -> dict:
    """The efficiency target: its verdict from the largest machine measured (the
    many-core record of bench/sweep_cores.py, where there is one), the figure derived
    from this machine's costs beside it; derived only when nothing was measured."""
    text = (f">= {EFFICIENCY_MIN:.0%} parallel efficiency, {BIG_POINTS} points of "
            f"{BIG_POINT_S} s on {BIG_WORKERS} workers")
    derived_note = (f"derived from this machine's costs: {est['efficiency']:.2f}, "
                    f"{est['efficiency_with_cluster_start']:.2f} with the cluster's start-up")
    try:
        rec = json.loads(record.read_text())
        value = float(rec["efficiency_whole_commands"])
        m = rec["machine_before"]
        when = (f"at {rec['commit']}, {rec['measured_at']}" if rec.get("commit")
                else "by an earlier version (round 13, before the fork server)")
        where = (f"MEASURED by bench.sweep_cores on {m['cpus']} CPUs ({m['cpu_model']}), "
                 f"{rec['points']} points of {rec['point_s_measured']:.3f} s on "
                 f"{rec['workers']} workers, whole commands, {when}")
    except (OSError, ValueError, KeyError, TypeError):
        return target(text, est["efficiency"], EFFICIENCY_MIN, below=False,
                      note=f"DERIVED, not measured ({derived_note})")
    return target(text, value, EFFICIENCY_MIN, below=False, note=f"{where}; {derived_note}")


def run(quick: bool = False, log: Callable[[str], object] = print,
        size: Size | None = None) -> dict[str, Any]:
    """The section's document (module docstring)."""
    size = size or (QUICK if quick else Size())
    load_start = [round(v, 2) for v in os.getloadavg()]
    with tempfile.TemporaryDirectory(prefix="kvrod-bench-sweeps-") as tmp:
        root = Path(tmp)
        env = child_env(root / "pycache")
        log("  start-up ...")
        start = startup(size, root, env, log)
        log("  tiny points, whole commands ...")
        sweep = tiny_sweep(size, root, env, log)
        log("  the worker's time per tiny point ...")
        worker = worker_cost(size, root)
        log(f"    {worker['point_wall'] * 1e3:.1f} ms a point, of which "
            f"{worker['fixed_wall'] * 1e3:.1f} ms beside simulate()")
        log("  the client's cost per point ...")
        client = client_cost(size, root, worker)
        log(f"    loop {client['loop_per_point'] * 1e3:.2f} ms, process "
            f"{client['process_cpu_per_point'] * 1e3:.2f} ms a point")
        log("  a large serial study: its first row ...")
        large = first_row(size, root, env)
        shutil.rmtree(root / "pycache", ignore_errors=True)
    est = derived(worker, client, client["cluster_start_s"])
    doc = {"size": size.__dict__, "load_average_at_start": load_start, "startup": start,
           "tiny_sweep": sweep, "worker": worker, "client": client, "large_serial": large,
           "derived_16_workers": est}
    doc["targets"] = [
        target(f"kvrod --version, whole process: median wall < {VERSION_MAX_S} s",
               start["version"]["A_wall"], VERSION_MAX_S, strict=True,
               note=f"cpu {start['version']['A_cpu']:.3f} s; load average at start "
                    f"{load_start[0]}"),
        target(f"kvrod simulate cantilever --n-elements 10 (10 s simulated), whole "
               f"process: median wall < {SIMULATE_MAX_S} s", start["simulate"]["A_wall"],
               SIMULATE_MAX_S, strict=True,
               note=f"cpu {start['simulate']['A_cpu']:.3f} s"),
        target(f"tiny points on 2 local workers, whole kvrod sweep: >= {TINY_RATE_MIN:g} "
               "points/s", sweep["points_per_s"], TINY_RATE_MIN, below=False,
               note=f"{sweep['points']} points; cpu of the whole command "
                    f"{sweep['A_cpu']:.1f} s: at most {sweep['cpu_bound_points_per_s']:.0f} "
                    "points/s on 2 idle cores"),
        target(f"a tiny point (cantilever N = 4, 0.05 s) on a worker < "
               f"{TINY_POINT_MAX_S * 1e3:g} ms (CPU time)", worker["point_cpu"],
               TINY_POINT_MAX_S, strict=True,
               note=f"simulate() alone {worker['simulate_cpu'] * 1e3:.1f} ms CPU; wall "
                    f"{worker['point_wall'] * 1e3:.1f} ms under the load"),
        efficiency_target(est),
    ]
    doc["meta"] = metadata()
    return doc


def _ms(v: float | None) -> str:
    return "-" if v is None else f"{v * 1e3:.1f}"


def markdown(doc: dict[str, Any]) -> list[str]:
    """The README section."""
    s, w, c, d = doc["startup"], doc["worker"], doc["client"], doc["derived_16_workers"]
    t, big = doc["tiny_sweep"], doc["large_serial"]
    first = big["seconds_to_first_row"]
    feeds = d["workers_one_client_feeds"]
    end_load = (doc["meta"].get("load_average_at_end") or ["-"])[0]
    out = ["## 12. Sweeps and start-up (issues 30 and 33)", "",
           f"Whole processes timed in turn (A B A B ..., medians; ratio = median of the "
           f"per-pair ratios); {doc['meta']['cpus']} CPUs shared with other jobs, load "
           f"average {doc['load_average_at_start'][0]} at the start and "
           f"{end_load} at the end: wall times "
           "under load, CPU times beside them. Children have a bytecode cache "
           "(an installed kvrod's .pyc).", "",
           "| command (A) | beside (B) | A wall s | A cpu s | B wall s | A/B wall |",
           "|:--|:--|---:|---:|---:|---:|"]
    for key, label in (("version", "kvrod --version"),
                       ("version_no_pyc", "kvrod --version, no .pyc"),
                       ("simulate", "kvrod simulate cantilever --n-elements 10"),
                       ):
        r = s[key]
        out.append(f"| {label} | python -c pass | {r['A_wall']:.3f} | {r['A_cpu']:.3f} | "
                   f"{r['B_wall']:.3f} | {r['ratio_wall']:.2f} |")
    out.append(f"| kvrod sweep, {t['points']} tiny points, --workers 2 | the same, --serial | "
               f"{t['A_wall']:.2f} | {t['A_cpu']:.2f} | {t['B_wall']:.2f} | "
               f"{t['ratio_wall']:.2f} |")
    out += ["", f"Tiny points (cantilever N = 4, 0.05 s): {t['points_per_s']:.1f} points/s "
            f"on 2 workers, whole command ({t['serial_points_per_s']:.1f} serial). "
            f"The whole command's CPU time bounds it at {t['cpu_bound_points_per_s']:.0f} "
            f"points/s on 2 idle cores. A tiny point on a worker: {_ms(w['point_cpu'])} ms "
            f"cpu ({_ms(w['point_wall'])} ms wall), of which simulate() "
            f"{_ms(w['simulate_cpu'])} ms; fixed cost (problem, model, files, row) "
            f"{_ms(w['fixed_cpu'])} ms cpu.",
            f"Client per point (2-worker LocalCluster, {c['points']} points in {c['tasks']} "
            f"tasks, {c['points_per_s']:.1f} points/s): its loop {_ms(c['loop_per_point'])} "
            f"ms, the client process (scheduler and nannies in it) "
            f"{_ms(c['process_cpu_per_point'])} ms cpu beyond its idle "
            f"{c['idle_cpu_per_s'] * 1e3:.0f} ms/s; Dask on a worker "
            f"{_ms(c['dask_cpu_per_point_on_worker'])} ms cpu a point; cluster start "
            f"{c['cluster_start_s']:.2f} s.",
            f"A {big['points']}-point serial study: first row after "
            f"{'-' if first is None else f'{first:.2f}'} s; Ctrl-C kept "
            f"{big['rows_kept_after_ctrl_c']} row(s) (exit {big['exit_code']}).",
            "",
            f"Derived from this machine's costs ({doc['meta']['cpus']} cores; a "
            f"measurement on many cores, where there is one, is in the target below): "
            f"{d['points']} points of {d['point_s']} s on "
            f"{d['workers']} workers: a point costs {d['point_s']} + {_ms(d['fixed_s'])} ms "
            f"fixed + {_ms(d['dask_s'])} ms Dask; the client's {_ms(d['client_s_per_point'])}"
            f" ms a point is {d['client_utilisation']:.1%} of its time, so the efficiency is "
            f"{d['efficiency']:.1%} ({d['efficiency_with_cluster_start']:.1%} with the "
            f"cluster's start-up of {d['cluster_start_s']:.2f} s). One client keeps up with "
            f"about {'-' if feeds is None else f'{feeds:.0f}'} workers of such points (500 "
            "workers: "
            f"{d['client_utilisation_500_workers']:.0%} of its time).", ""]
    return out + [*targets_md(doc["targets"]), ""]
