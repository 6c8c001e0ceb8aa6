"""Benchmark of the generated rod kernels: ``python -m bench.kernels``.

Reports, for N = 25, 50, 200, 1000: per-cell cost of the residual and of residual plus
banded Jacobian through the compiled C API (``RodModel.residual`` / ``jacobian_band`` of
``build_model(load_problem("cantilever"))``: ctypes, one call per evaluation, best of 5
batches), the cost of driving the arrays to a new time (``RodModel.at``, which the
residual calls first), the compile time of the generated C (fresh cache), and the
generated code size. Writes ``bench/results/kernels.json`` and ``kernels.md``.
Targets (docs/design.md, section 7): residual <= 0.1 us/cell, residual + Jacobian <= 1 us/cell,
compile <= 5 s independent of N.
"""

from __future__ import annotations

import itertools
import json
import os
import platform
import tempfile
import time
from pathlib import Path

import numpy as np

from bench.meta import metadata, target, targets_md
from runtime import native
from runtime.model import build
from runtime.problem.assemble import build_model
from runtime.problem.registry import load_problem

SIZES = (25, 50, 200, 1000)
RESULTS = Path(__file__).resolve().parent / "results"


def _best_per_call(fn, min_time: float = 0.3, repeat: int = 5) -> float:
    """Best-of-`repeat` mean time per call (s), each batch lasting about min_time."""
    fn()
    k, t = 1, 0.0
    while True:
        t0 = time.perf_counter()
        for _ in range(k):
            fn()
        t = time.perf_counter() - t0
        if t > min_time / 5:
            break
        k *= 4
    best = t / k
    for _ in range(repeat):
        t0 = time.perf_counter()
        for _ in range(k):
            fn()
        best = min(best, (time.perf_counter() - t0) / k)
    return best


def compile_time() -> float:
    """Seconds to compile the generated C into an empty cache."""
    cc = native.find_compiler()
    if cc is None:
        return float("nan")
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        build.compile_library(cc, outdir=Path(tmp))
        return time.perf_counter() - t0


def run() -> dict:
    gdir = build.generated_dir()
    sizes = {f.name: f.stat().st_size
             for f in (*build.source_paths(gdir), *build.header_paths(gdir))}
    rows = []
    for N in SIZES:
        m = build_model(load_problem("cantilever", {"n_elements": N}))
        m.at(0.0)
        rng = np.random.default_rng(0)
        y = m.initial_state() + 1e-3 * rng.standard_normal(m.n)
        yp = rng.standard_normal(m.n)
        res = np.empty(m.n)
        ab = np.zeros((2 * m.kl + m.ku + 1, m.n), order="F")
        t_res = _best_per_call(lambda m=m, y=y, yp=yp, res=res: m.residual(0.0, y, yp, res))
        t_jac = _best_per_call(lambda m=m, y=y, yp=yp, ab=ab: m.jacobian_band(0.0, y, yp, 10.0,
                                                                              ab))
        clock = itertools.count(1)
        t_at = _best_per_call(lambda m=m, c=clock: m.at(1e-9 * next(c)))  # a new t each call
        rows.append({"N": N, "n": m.n, "backend": m.backend,
                     "residual_us_per_cell": 1e6 * t_res / N,
                     "jacobian_us_per_cell": 1e6 * t_jac / N,
                     "residual_plus_jacobian_us_per_cell": 1e6 * (t_res + t_jac) / N,
                     "residual_us_per_call": 1e6 * t_res, "jacobian_us_per_call": 1e6 * t_jac,
                     "at_new_time_us_per_call": 1e6 * t_at})
    comp = compile_time()
    worst_res = max(r["residual_us_per_cell"] for r in rows)
    worst_both = max(r["residual_plus_jacobian_us_per_cell"] for r in rows)
    return {"machine": {"platform": platform.platform(), "cpus": os.cpu_count(),
                        "compiler": native.find_compiler(), "cflags": list(native.CFLAGS)},
            "generated_bytes": sizes, "generated_bytes_total": sum(sizes.values()),
            "compile_seconds": comp, "results": rows,
            "targets": [target("residual <= 0.1 us/cell (worst N)", worst_res, 0.1),
                        target("residual + Jacobian <= 1 us/cell (worst N)", worst_both, 1.0),
                        target("compile <= 5 s", comp if comp == comp else None, 5.0)],
            "meta": metadata()}


def markdown(doc: dict) -> str:
    lines = ["# Rod kernel benchmark", "",
             f"compiler `{doc['machine']['compiler']}` {' '.join(doc['machine']['cflags'])}, "
             f"{doc['machine']['cpus']} CPUs; generated C+H "
             f"{doc['generated_bytes_total'] / 1024:.0f} KiB (independent of N); "
             f"compile {doc['compile_seconds']:.2f} s (target <= 5 s).", "",
             "| N | n | residual us/cell | Jacobian us/cell | residual+Jacobian us/cell | "
             "at(new t) us |", "|---:|---:|---:|---:|---:|---:|"]
    for r in doc["results"]:
        lines.append(f"| {r['N']} | {r['n']} | {r['residual_us_per_cell']:.3f} | "
                     f"{r['jacobian_us_per_cell']:.3f} | "
                     f"{r['residual_plus_jacobian_us_per_cell']:.3f} | "
                     f"{r.get('at_new_time_us_per_call', float('nan')):.1f} |")
    lines += ["", *targets_md(doc["targets"])]
    return "\n".join(lines) + "\n"


def _write(path: Path, text: str) -> None:
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(text)
    tmp.replace(path)


def main() -> None:
    doc = run()
    RESULTS.mkdir(parents=True, exist_ok=True)
    _write(RESULTS / "kernels.json", json.dumps(doc, indent=2) + "\n")
    _write(RESULTS / "kernels.md", markdown(doc))
    print(markdown(doc))


if __name__ == "__main__":
    main()
