"""``python -m bench [--quick] [--out DIR]``: every benchmark, JSON + Markdown.

Writes ``DIR/integrators.json``, ``scaling.json``, ``codegen.json``, ``peers.json``,
``kernels.json`` (+ ``kernels.md``), ``energy_audit.json`` and ``README.md`` (all tables).
``--only SECTION`` (repeatable) reruns just those sections and rebuilds the README from
the JSON of the others. ``--quick``: N = 25, 50,
2 s simulated, IDAS without jit, no SciPy Radau / codegen / PyElastica / kernel table
(under a minute).
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
import sys
import time
from pathlib import Path

import casadi
import numpy as np
import scipy

from bench import codegen_timing, energy_audit, integrators, peers, report, scaling
from runtime.io.results import jsonable

FULL_N = (25, 50, 200, 1000)
QUICK_N = (25, 50)


def _clean(obj):
    return jsonable(obj, nonfinite="null")


def _write(path: Path, text: str) -> None:
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(text)
    tmp.replace(path)


def _log(msg: str) -> None:
    print(msg, flush=True)


def run_integrators(quick: bool) -> dict:
    T = 2.0 if quick else 10.0
    sizes = QUICK_N if quick else FULL_N
    how = "expand" if quick else "jit"
    idas_funcs = ("jit-compiled (gcc -O2) residual and sparse Jacobian" if how == "jit"
                  else "expanded SX functions (no compile)")
    runs = []
    for N in sizes:
        if quick:
            methods: tuple[str, ...] = ("BDF",)
        else:
            methods = ("BDF", "Radau") if N <= 200 else ()
        runs.append(integrators.compare(N, T, scipy_methods=methods, idas_how=how, log=_log))
    doc = {"T": T, "runs": runs, "protocol": (
        f"Cantilever release (paper Sect. 5), {T:g} s simulated, output every 0.01 s. "
        "Accuracy: max tip-x error over the outputs against kvrod at rtol = atol = 1e-9. "
        "kvrod: IDA-form residual and banded Jacobian of the compiled kernels, LAPACK band "
        "LU. IDAS (SUNDIALS via CasADi "
        f"{casadi.__version__}): the same residual as a semi-explicit DAE (differential rows "
        "divided by the constant diagonal dF/dy'), state cell by cell, "
        f"{idas_funcs}"
        ", CSparse sparse LU. SciPy solve_ivp: the ODE form y_d' = -g_d(y)/D_d with the "
        "compiled residual and sparse Jacobian (CSC) through Python callbacks; Radau/BDF "
        "scanned from loose to tight (runs over 60 s end the scan); not run at N = 1000.")}
    if not quick:
        rtol50 = next((r["kvrod"]["matched"]["rtol"] for r in runs
                       if r["N"] == 50 and r["kvrod"]["matched"]), 1e-7)
        _log("  IDAS configurations at N = 50 ...")
        jit_s = next((r.get("idas_first_setup_seconds") for r in runs if r["N"] == 50), None)
        doc["idas_configs"] = {"N": 50, "T": T, "rtol": rtol50,
                               "rows": integrators.idas_configs(50, T, rtol50, jit_s)}
    doc["breakdown"] = []
    for r in runs:
        if r["N"] in (50, 1000) and r["kvrod"]["matched"]:
            doc["breakdown"].append(integrators.breakdown(r["N"], T,
                                                          r["kvrod"]["matched"]["rtol"]))
    return doc


SECTIONS = tuple(report.SECTION_MD)


def _load(out_dir: Path, name: str) -> dict | None:
    path = out_dir / f"{name}.json"
    return json.loads(path.read_text()) if path.exists() else None


def run_all(quick: bool = False, out_dir: Path = Path("bench/results"),
            only: tuple[str, ...] | None = None) -> dict:
    """Run the benchmarks and write the JSON documents and README.md into ``out_dir``.

    only: run just these sections (names in SECTIONS); the README then takes the other
    sections from the JSON documents already in ``out_dir`` (and says which were rerun).
    """
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    bad = sorted(set(only or ()) - set(SECTIONS))
    if bad:
        raise ValueError(f"only = {bad} is outside the allowed range: {', '.join(SECTIONS)}")
    chosen = tuple(only) if only else SECTIONS
    t0 = time.perf_counter()
    docs: dict = {}

    def keep(name: str, doc: dict) -> None:
        docs[name] = doc
        _write(out_dir / f"{name}.json", json.dumps(_clean(doc), indent=1))

    if "integrators" in chosen:
        _log("== integrators: kvrod vs IDAS vs SciPy at matched accuracy")
        keep("integrators", run_integrators(quick))
    if "scaling" in chosen:
        rtol = 1e-7
        for r in (docs.get("integrators") or _load(out_dir, "integrators") or {}).get("runs", []):
            if r["N"] == 50 and r["kvrod"]["matched"]:
                rtol = r["kvrod"]["matched"]["rtol"]
        _log("== scaling in N")
        keep("scaling", scaling.run(scaling.QUICK_SIZES if quick else scaling.SIZES,
                                    T=2.0 if quick else 10.0, rtol=rtol, log=_log))
    if not quick:
        if "codegen" in chosen:
            _log("== derivation / generate / compile")
            keep("codegen", codegen_timing.run(log=_log))
        if "peers" in chosen:
            _log("== PyElastica")
            keep("peers", peers.run(log=_log))
        if "kernels" in chosen:
            _log("== generated kernels")
            from bench import kernels

            keep("kernels", kernels.run())
            _write(out_dir / "kernels.md", kernels.markdown(docs["kernels"]))
        if "energy_audit" in chosen:
            _log("== energy audit: kvrod vs IDAS")
            keep("energy_audit", energy_audit.run(log=_log))
    for name in SECTIONS:
        if name not in docs and only and not quick:
            loaded = _load(out_dir, name)
            if loaded is not None:
                docs[name] = loaded
    docs["meta"] = {"quick": quick, "platform": platform.platform(), "cpus": os.cpu_count(),
                    "python": platform.python_version(), "numpy": np.__version__,
                    "scipy": scipy.__version__, "casadi": casadi.__version__,
                    "pyelastica": peers.available(),
                    "date": datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%d %H:%M UTC"),
                    "seconds": time.perf_counter() - t0,
                    "sections_run": [n for n in SECTIONS if n in chosen]}
    md = report.markdown(docs)
    _write(out_dir / "README.md", md)
    _log(md)
    return _clean(docs)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m bench", description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="N = 25, 50, 2 s; under a minute")
    ap.add_argument("--out", default="bench/results", help="results folder")
    ap.add_argument("--only", action="append", choices=SECTIONS,
                    help="run only this section (repeatable); the others are read back "
                         "from the JSON in --out")
    args = ap.parse_args(argv)
    run_all(quick=args.quick, out_dir=Path(args.out),
            only=tuple(args.only) if args.only else None)
    return 0


if __name__ == "__main__":
    sys.exit(main())
