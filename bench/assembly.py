"""What an assembly of rods costs beside the same rods run one by one (issue 31, item 3).

Issue 31's target: an assembly of k rods of N elements takes at most RATIO_MAX (1.3) times
the time of k single-rod runs of the same N with the same steps. Two cases, both built
from the paper's cantilever (``examples/cantilever.toml``: its rod, section, material,
end conditions, released tip load, simulation and statics settings, read through
:func:`runtime.problem.registry.load_problem`, so the cases follow the example):

1. **k independent cantilevers** (:func:`independent_cantilevers`): one assembly file of k
   copies of the cantilever side by side (``[rods.cK]``, each clamped at its start with
   its own released tip load, no joints), against k ``kvrod simulate cantilever`` runs
   of the same N. The rods are identical, so with equal tolerances the assembly's error
   norm would be each rod's; its default tolerances are not quite the single rod's (the
   rotations' scale is d/L, the single rod's the static state's rotation angle:
   :func:`runtime.simulate.assembly.default_atol`), so the steps differ by a few per
   cent. Both step counts are recorded, and the target's ratio is scaled to the same
   steps (A's time times B's steps per run over A's steps) when they differ.
2. **a welded chain** (:func:`welded_chain`): the cantilever cut into k rods of N
   elements welded end to end, against one ``kvrod simulate cantilever`` run of k N
   elements (the same rod: issue 31 has the two equal; here the cost of the joints).
   The steps may differ by the rounding of the two systems (recorded).

Two measures, both paired (A and B in turn, round after round, after a warm-up of each;
the ratio per round, then the median), the order alternating:

* **in process** (:func:`in_process`; the target's measure): ``simulate_assembly`` of the
  assembly (A) against ``k`` ``simulate`` calls of the single rod (B), on models built
  beforehand, in this process (warm: as in a sweep's worker). Each side is split into
  the static solve and the run (initial values, integration, audit, outputs), with the
  integrator's counters. The ratio is also given scaled to the same steps (A's time
  times B's steps over A's steps; the run alone per step).
* **whole processes** (:func:`compare`): ``python -m kvrod.cli simulate ... --out DIR
  --overwrite`` of the assembly (A) against the single-rod processes (B, one after the
  other): A's wall over the sum of B's walls (k start-ups on B's side), and the
  ``summary.json`` ``wall_time_s`` ratio (kvrod simulate's own time; each of B's includes
  a fresh process's first-run costs, k times).

``python -m bench --only assembly`` runs this section; ``--quick`` 2 s simulated, one
round (a smoke run, not a measurement).
"""

from __future__ import annotations

import json
import os
import platform
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from bench.meta import metadata, target, targets_md

K, N, T = 4, 50, 10.0
QUICK_T = 2.0
#: issue 31, item 3: assembly of k rods / k single-rod runs of the same N and steps
RATIO_MAX = 1.3
PAIRS, QUICK_PAIRS = 5, 1
SPACING = 0.05          # m between the independent cantilevers (along y)
TIMEOUT = 900.0


def _cantilever(n_elements: int, t_end: float) -> dict[str, Any]:
    from runtime.problem.registry import load_problem

    return load_problem("cantilever", {"n_elements": n_elements,
                                       "t_end": t_end}).to_mapping()


def _rod_table(single: dict[str, Any], n_elements: int, length: float,
               origin: list[float]) -> dict[str, Any]:
    """A ``[rods.NAME]`` table holding the single rod's rod, section, material and ends."""
    rod = json.loads(json.dumps(single["rod"]))
    rod["elements"] = n_elements
    rod["length"] = length
    rod["geometry"]["origin"] = origin
    return {"rod": rod, "section": single["section"], "material": single["material"],
            "start": single["start"], "end": single["end"]}


def _top(single: dict[str, Any], name: str, maxima: str) -> dict[str, Any]:
    return {"name": name, "description": f"bench/assembly.py: {name}",
            "simulation": single["simulation"], "statics": single["statics"],
            "analysis": {"maxima": maxima}}


def _tip_load(single: dict[str, Any], point: str) -> dict[str, Any]:
    (load,) = single["loads"]
    return {**load, "at": point}


def independent_cantilevers(k: int, n_elements: int, t_end: float) -> dict[str, Any]:
    """The mapping of an assembly of ``k`` copies of the cantilever, ``SPACING`` apart
    along y, each clamped at its start with its own released tip load; no joints."""
    single = _cantilever(n_elements, t_end)
    length = single["rod"]["length"]
    names = [f"c{i}" for i in range(k)]
    doc = _top(single, f"bench_{k}_cantilevers", f"{names[0]}.end.x")
    doc["rods"] = {name: _rod_table(single, n_elements, length, [0.0, SPACING * i, 0.0])
                   for i, name in enumerate(names)}
    doc["loads"] = [_tip_load(single, f"{name}.end") for name in names]
    return doc


def welded_chain(k: int, n_elements: int, t_end: float) -> dict[str, Any]:
    """The mapping of the cantilever cut into ``k`` rods of ``n_elements`` welded end to
    end (the first clamped at its start, the tip load on the last one's end)."""
    single = _cantilever(n_elements, t_end)
    piece = single["rod"]["length"] / k
    direction = single["rod"]["geometry"]["direction"]
    names = [f"r{i}" for i in range(k)]
    doc = _top(single, f"bench_{k}_welded", f"{names[-1]}.end.x")
    rods = {}
    for i, name in enumerate(names):
        table = _rod_table(single, n_elements, piece, [piece * i * d for d in direction])
        if i > 0:
            table["start"] = {"kind": "free"}
        if i < k - 1:
            table["end"] = {"kind": "free"}
        rods[name] = table
    doc["rods"] = rods
    doc["joints"] = [{"kind": "weld", "between": [f"{a}.end", f"{b}.start"]}
                     for a, b in zip(names, names[1:], strict=False)]
    doc["loads"] = [_tip_load(single, f"{names[-1]}.end")]
    return doc


def write_toml(path: Path, mapping: dict[str, Any]) -> Path:
    import tomli_w

    path.write_text(tomli_w.dumps(mapping))
    return path


def _child_env(pycache: Path) -> dict[str, str]:
    env = dict(os.environ)
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    env["PYTHONPYCACHEPREFIX"] = str(pycache)
    return env


def _simulate(spec: str, out: Path, env: dict[str, str], *args: str) -> dict[str, Any]:
    """One whole ``kvrod simulate`` process: wall, CPU (of the child), the summary's wall
    time and steps."""
    cmd = [sys.executable, "-m", "kvrod.cli", "simulate", spec, *args, "--out", str(out),
           "--overwrite"]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=TIMEOUT, env=env)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if p.returncode:
        err = (p.stderr.strip().splitlines() or [""])[-1]
        raise RuntimeError(f"{' '.join(cmd)} failed (exit {p.returncode}): {err}")
    s = json.loads((out / "summary.json").read_text())
    if s.get("status") != "finished":
        raise RuntimeError(f"{' '.join(cmd)}: status {s.get('status')}: {s.get('message')}")
    return {"wall": wall, "cpu": (after.ru_utime - before.ru_utime)
            + (after.ru_stime - before.ru_stime),
            "summary_wall": float(s["wall_time_s"]), "steps": int(s["counters"]["nstep"])}


def _sum(runs: list[dict[str, Any]]) -> dict[str, Any]:
    return {"wall": sum(r["wall"] for r in runs), "cpu": sum(r["cpu"] for r in runs),
            "summary_wall": sum(r["summary_wall"] for r in runs),
            "steps": [r["steps"] for r in runs]}


def _median(v: list[float]) -> float:
    return float(statistics.median(v))


def compare(name: str, assembly: Path, singles: list[tuple[str, ...]], pairs: int,
            root: Path, env: dict[str, str], log) -> dict[str, Any]:
    """PAIRS rounds of the assembly's process (A) and its single-rod processes (B, one
    after the other) in turn, after a warm-up of each; the paired medians."""
    def side_a() -> dict[str, Any]:
        r = _simulate(str(assembly), root / f"{name}-a", env)
        return {**r, "steps": [r["steps"]]}

    def side_b() -> dict[str, Any]:
        return _sum([_simulate(args[0], root / f"{name}-b{i}", env, *args[1:])
                     for i, args in enumerate(singles)])

    side_a(), side_b()                      # warm-up: compile caches, byte code, files
    rounds = []
    for i in range(pairs):
        if i % 2 == 0:                     # the order alternates round by round
            a = side_a()
            b = side_b()
        else:
            b = side_b()
            a = side_a()
        rounds.append({"A": a, "B": b})
        log(f"  {name} round {i + 1}/{pairs}: A {a['wall']:.2f} s (summary "
            f"{a['summary_wall']:.2f} s, steps {a['steps']}), B {b['wall']:.2f} s (summary "
            f"{b['summary_wall']:.2f} s, steps {b['steps']})")
    process = [r["A"]["wall"] / r["B"]["wall"] for r in rounds]
    command = [r["A"]["summary_wall"] / r["B"]["summary_wall"] for r in rounds]
    cpu = [r["A"]["cpu"] / r["B"]["cpu"] for r in rounds]
    # at the same steps: A's time scaled by (B's steps per run / A's steps)
    per_step = [x * statistics.mean(r["B"]["steps"]) / r["A"]["steps"][0]
                for x, r in zip(command, rounds, strict=True)]
    return {"rounds": rounds, "process_ratios": process, "command_ratios": command,
            "cpu_ratios": cpu, "same_steps_ratios": per_step,
            "median_process_ratio": _median(process),
            "median_command_ratio": _median(command), "median_cpu_ratio": _median(cpu),
            "median_same_steps_ratio": _median(per_step),
            "median_A_wall": _median([r["A"]["wall"] for r in rounds]),
            "median_B_wall": _median([r["B"]["wall"] for r in rounds]),
            "median_A_summary": _median([r["A"]["summary_wall"] for r in rounds]),
            "median_B_summary": _median([r["B"]["summary_wall"] for r in rounds]),
            "steps_A": rounds[-1]["A"]["steps"], "steps_B": rounds[-1]["B"]["steps"]}


def _counters(res) -> dict[str, int]:
    return {k: int(v) for k, v in dict(res.counters).items()} if res.counters else {}


def _one(run, *args) -> dict[str, Any]:
    t0 = time.perf_counter()
    res = run(*args)
    total = time.perf_counter() - t0
    static = res.static.wall_time_s if res.static is not None else 0.0
    if res.status != "finished":
        raise RuntimeError(f"in-process run: status {res.status}: {res.message}")
    return {"static_s": static, "run_s": total - static, "total_s": total,
            "counters": _counters(res)}


def in_process(path: Path, n_single: int, k_single: int, t_end: float, rounds: int,
               log) -> dict[str, Any]:
    """``rounds`` rounds in this process, after a warm-up of each side: the assembly's
    ``simulate_assembly`` (A) and ``k_single`` ``simulate`` calls of the single rod (B),
    in turn, on models built beforehand (warm: the library loaded, first-run costs paid,
    as in a sweep's worker). Each side split into static solve and run (the run: initial
    values, integration, audit, outputs), with the integrator's counters; the paired
    medians of A / B, raw and scaled to B's steps."""
    from runtime.problem.assemble import build_model
    from runtime.problem.assemble_system import build_system
    from runtime.problem.registry import load_problem
    from runtime.simulate.assembly import simulate_assembly
    from runtime.simulate.simulate import simulate

    assembly = load_problem(path)
    single = load_problem("cantilever", {"n_elements": n_single, "t_end": t_end})
    t0 = time.perf_counter()
    amap = build_system(assembly)
    build_a = time.perf_counter() - t0
    t0 = time.perf_counter()
    model = build_model(single)
    build_b = time.perf_counter() - t0

    def side_a() -> dict[str, Any]:
        return _one(lambda: simulate_assembly(assembly, amap=amap))

    def side_b() -> dict[str, Any]:
        runs = [_one(lambda: simulate(single, model=model)) for _ in range(k_single)]
        return {"static_s": sum(r["static_s"] for r in runs),
                "run_s": sum(r["run_s"] for r in runs),
                "total_s": sum(r["total_s"] for r in runs), "counters": runs[0]["counters"]}

    side_a(), side_b()
    got = []
    for i in range(rounds):
        if i % 2 == 0:
            a = side_a()
            b = side_b()
        else:
            b = side_b()
            a = side_a()
        got.append({"A": a, "B": b})
        log(f"  in process round {i + 1}/{rounds}: A {a['total_s']:.2f} s (static "
            f"{a['static_s']:.2f} s), B {b['total_s']:.2f} s (static {b['static_s']:.2f} s)")
    steps_a = got[-1]["A"]["counters"]["nstep"]
    steps_b = got[-1]["B"]["counters"]["nstep"]
    ratio = [r["A"]["total_s"] / r["B"]["total_s"] for r in got]
    run_ratio = [r["A"]["run_s"] / r["B"]["run_s"] for r in got]
    static_ratio = [r["A"]["static_s"] / r["B"]["static_s"] for r in got]

    def med(side: str, key: str) -> float:
        return _median([r[side][key] for r in got])

    return {"rounds": got, "k_single": k_single, "build_A_s": build_a,
            "build_B_s": build_b, "steps_A": steps_a, "steps_B": steps_b,
            "counters_A": got[-1]["A"]["counters"], "counters_B": got[-1]["B"]["counters"],
            "median_ratio": _median(ratio),
            "median_same_steps_ratio": _median([x * steps_b / steps_a for x in ratio]),
            "median_run_ratio": _median(run_ratio),
            "median_run_per_step_ratio": _median([x * steps_b / steps_a
                                                  for x in run_ratio]),
            "median_static_ratio": _median(static_ratio),
            "A_static_s": med("A", "static_s"), "A_run_s": med("A", "run_s"),
            "B_static_s": med("B", "static_s"), "B_run_s": med("B", "run_s")}


def machine() -> dict[str, Any]:
    """The CPU model (from /proc/cpuinfo where there is one), cores, platform, load."""
    model = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return {"cpu": model, "cores": os.cpu_count(), "platform": platform.platform(),
            "load_average": [round(v, 2) for v in os.getloadavg()]}


def run(quick: bool = False, log=print, k: int = K, n_elements: int = N,
        t_end: float | None = None, pairs: int | None = None) -> dict[str, Any]:
    """The section's document (module docstring)."""
    t_end = (QUICK_T if quick else T) if t_end is None else t_end
    pairs = (QUICK_PAIRS if quick else PAIRS) if pairs is None else pairs
    if k < 2 or n_elements < 2 or pairs < 1 or not t_end > 0:
        raise ValueError(f"k = {k}, n_elements = {n_elements}, pairs = {pairs}, t_end = "
                         f"{t_end} is outside the allowed range: k >= 2, n_elements >= 2, "
                         "pairs >= 1, t_end > 0")
    doc: dict[str, Any] = {"k": k, "N": n_elements, "t_end": t_end, "pairs": pairs,
                           "machine_at_start": machine()}
    single = ("cantilever", "--n-elements", str(n_elements), "--t-end", f"{t_end:g}")
    chain_single = ("cantilever", "--n-elements", str(k * n_elements), "--t-end",
                    f"{t_end:g}")
    with tempfile.TemporaryDirectory(prefix="kvrod-bench-assembly-") as tmp:
        root = Path(tmp)
        env = _child_env(root / "pycache")
        indep = write_toml(root / "independent.toml",
                           independent_cantilevers(k, n_elements, t_end))
        chain = write_toml(root / "chain.toml", welded_chain(k, n_elements, t_end))
        log(f"== {k} independent cantilevers (N = {n_elements}) | {k} single runs")
        doc["independent"] = compare("independent", indep, [single] * k, pairs, root, env,
                                     log)
        log(f"== {k} welded rods of N = {n_elements} | one rod of N = {k * n_elements}")
        doc["welded"] = compare("welded", chain, [chain_single], pairs, root, env, log)
        log("== in process: where the time goes")
        doc["in_process"] = {
            "independent": in_process(indep, n_elements, k, t_end, pairs, log),
            "welded": in_process(chain, k * n_elements, 1, t_end, pairs, log)}
    doc["machine_at_end"] = machine()
    ind, inp = doc["independent"], doc["in_process"]["independent"]
    same = inp["steps_A"] == inp["steps_B"]
    note = (f"in process, warm; steps: assembly {inp['steps_A']}, each single run "
            f"{inp['steps_B']}" + ("" if same else
                                    f"; raw ratio {inp['median_ratio']:.2f}, the value "
                                    "scaled to the single runs' steps")
            + f"; static solve {inp['median_static_ratio']:.2f}x, run per step "
              f"{inp['median_run_per_step_ratio']:.2f}x")
    doc["targets"] = [
        target(f"{k} cantilevers of N = {n_elements} in one assembly / {k} single-rod runs "
               f"at the same steps, paired median <= {RATIO_MAX}",
               inp["median_ratio"] if same else inp["median_same_steps_ratio"], RATIO_MAX,
               note=note),
        target(f"the same, whole kvrod simulate processes (the single runs' {k} start-ups "
               f"and first-run costs included, raw steps), paired median <= {RATIO_MAX}",
               ind["median_process_ratio"], RATIO_MAX,
               note=f"load average {doc['machine_at_start']['load_average'][0]} at the "
                    f"start, {doc['machine_at_end']['load_average'][0]} at the end"),
    ]
    doc["meta"] = metadata()
    return doc


def _row(label: str, c: dict[str, Any]) -> str:
    return (f"| {label} | {c['median_A_summary']:.2f} | {c['median_B_summary']:.2f} | "
            f"{c['median_command_ratio']:.2f} | {c['median_same_steps_ratio']:.2f} | "
            f"{c['median_A_wall']:.2f} | "
            f"{c['median_B_wall']:.2f} | {c['median_process_ratio']:.2f} | "
            f"{c['median_cpu_ratio']:.2f} | {c['steps_A']} / {c['steps_B']} |")


def _in_process_row(label: str, c: dict[str, Any]) -> str:
    return (f"| {label} | {c['A_static_s']:.3f} | {c['A_run_s']:.3f} | {c['B_static_s']:.3f} "
            f"| {c['B_run_s']:.3f} | {c['median_ratio']:.2f} | "
            f"{c['median_same_steps_ratio']:.2f} | {c['median_static_ratio']:.2f} | "
            f"{c['median_run_per_step_ratio']:.2f} | {c['steps_A']} / {c['steps_B']} |")


def markdown(doc: dict[str, Any]) -> list[str]:
    """The README section."""
    k, n = doc["k"], doc["N"]
    m0, m1 = doc["machine_at_start"], doc["machine_at_end"]
    out = ["## 13. Rod assemblies beside their rods run one by one (issue 31)", "",
           f"The paper's cantilever, {doc['t_end']:g} s simulated, rtol as the example; "
           f"A and B in turn for {doc['pairs']} rounds after a warm-up, paired medians. "
           "Whole `kvrod simulate` processes: 'command' is kvrod simulate's own wall time "
           "(summary.json: build, statics, run, audit, outputs); 'same steps' that ratio "
           "with A's time scaled to B's steps per run (the two sides' default tolerances "
           "differ a little, so their steps do); 'process' the whole "
           f"processes. {m0['cpu']}, {m0['cores']} cores shared with other jobs, load "
           f"average {m0['load_average'][0]} at the start, {m1['load_average'][0]} at the "
           "end.", "",
           "| A / B | A command s | B command s | ratio | same steps | A process s | "
           "B process s | ratio | cpu ratio | steps A / B |",
           "|:--|---:|---:|---:|---:|---:|---:|---:|---:|:--|",
           _row(f"{k} cantilevers N = {n} in one assembly / {k} runs", doc["independent"]),
           _row(f"{k} welded rods of N = {n} / one rod of N = {k * n}", doc["welded"]),
           "", "In process (warm models; B = the single rod's runs, summed; 'same steps': "
           "A scaled to B's steps; 'static', 'run/step': A over B):", "",
           "| A / B | A static s | A run s | B static s | B run s | ratio | same steps | "
           "static | run/step | steps A / B |",
           "|:--|---:|---:|---:|---:|---:|---:|---:|---:|:--|",
           _in_process_row(f"{k} cantilevers N = {n} / {k} runs",
                           doc["in_process"]["independent"]),
           _in_process_row(f"{k} welded rods of N = {n} / one rod of N = {k * n}",
                           doc["in_process"]["welded"])]
    return out + ["", *targets_md(doc["targets"]), ""]
