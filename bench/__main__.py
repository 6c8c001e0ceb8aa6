"""``python -m bench [--quick] [--out DIR] [--only SECTION]``: every benchmark, JSON + Markdown.

Writes ``DIR/integrators.json``, ``scaling.json``, ``codegen.json``, ``peers.json``,
``kernels.json`` (+ ``kernels.md``), ``energy_audit.json``, ``modes.json``, ``maxwell.json``,
``sections.json``, ``overhead.json``, ``maxwell_kv.json``, ``sweeps.json`` (+ ``sweeps.md``),
``assembly.json``, ``sensitivities.json`` (+ ``sensitivities.md``), ``fit.json``,
``contact.json``, ``contact.md`` and ``README.md`` (all tables).
Every JSON document records its date, platform, versions and command line (``meta``) and
its targets with a verdict (``targets``: met / missed / not measured).
``--only SECTION`` (repeatable) reruns just those sections and rebuilds the README from
the JSON of the others. ``--quick``: N = 25 only for the SUNDIALS comparison (IDAS and
CVODES on kvrod's compiled kernels: no flat SX compile) and N = 25, 50 for scaling, 2 s
simulated, SciPy BDF only; modes at N = 50 beside a 2 s simulation; the Maxwell rod at
N = 20, 2 s; the section analysis on a 4-ply strip; the overhead section at 2 s, two rounds;
the assembly section at 2 s, one round;
no codegen / PyElastica / kernel table / energy audit / sweeps (a few minutes).

Timings are medians over repeats (the machine has 2 cores shared with other jobs).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

from bench import assembly as assembly_bench
from bench import codegen_timing, energy_audit, integrators, peers, report, scaling
from bench import contact as contact_bench
from bench import fit as fit_bench
from bench import maxwell as maxwell_bench
from bench import maxwell_kv as maxwell_kv_bench
from bench import modes as modes_bench
from bench import overhead as overhead_bench
from bench import sections as sections_bench
from bench import sensitivities as sensitivities_bench
from bench import sweeps as sweeps_bench
from bench.meta import metadata, target
from runtime.io.results import jsonable

FULL_N = (50, 200, 1000)
QUICK_N = (25,)
RATIO_MAX = 0.5


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
    runs = []
    for N in sizes:
        configs = integrators.strong_configs(N, quick)
        if quick:
            methods: tuple[str, ...] = ("BDF",)
        else:
            methods = ("BDF", "Radau") if N <= 200 else ()
        _log(f"  N={N}: " + ", ".join(c.name for c in configs))
        repeats = 3 if quick else (integrators.DUEL_REPEATS if N <= 200 else 5)
        run = integrators.compare(N, T, configs, scipy_methods=methods, repeats=repeats,
                                  log=_log)
        if N > integrators.FLAT_MAX_N and not quick:
            run["flat_skipped"] = integrators.FLAT_SKIPPED
        runs.append(run)
    doc: dict = {"T": T, "runs": runs, "protocol": integrators.__doc__.split("\n\n", 2)[2]
                 .split("\n\nHow each")[0].replace("\n", " ")}
    if not quick:
        r50 = next((r for r in runs if r["N"] == 50), None)
        rtol50 = r50["kvrod"]["matched"]["rtol"] if r50 and r50["kvrod"]["matched"] else 1e-7
        _log(f"  every configuration at N = 50, rtol = {rtol50:g} ...")
        doc["idas_configs"] = {"N": 50, "T": T, "rtol": rtol50,
                               "rows": integrators.idas_configs(50, T, rtol50, log=_log)}
    doc["breakdown"] = []
    for r in runs:
        if (r["N"] in (50, 1000) or quick) and r["kvrod"]["matched"]:
            doc["breakdown"].append(integrators.breakdown(r["N"], T,
                                                          r["kvrod"]["matched"]["rtol"]))
    doc["targets"] = []
    for N in FULL_N if not quick else sizes:
        r = next((x for x in runs if x["N"] == N), None)
        ratio = r.get("ratio_kvrod_over_strongest") if r else None
        note = (f"strongest: {r['strongest']}" if r and r.get("strongest") else
                "not run")
        if quick:
            note += f"; quick run (N = {N}, {T:g} s), the target is for N = 50, 200, 1000"
        doc["targets"].append(target(
            f"N = {N}: kvrod integrator / strongest SUNDIALS configuration at matched "
            f"accuracy <= {RATIO_MAX}", ratio, RATIO_MAX, note=note))
    doc["meta"] = metadata()
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
    from bench import meta

    meta.COMMAND = ("python -m bench" + (" --quick" if quick else "") + f" --out {out_dir}"
                    + "".join(f" --only {name}" for name in only or ()))
    t0 = time.perf_counter()
    docs: dict = {}

    def keep(name: str, doc: dict) -> None:
        docs[name] = doc
        _write(out_dir / f"{name}.json", json.dumps(_clean(doc), indent=1))

    if "integrators" in chosen:
        _log("== integrators: kvrod vs SUNDIALS (IDAS, CVODES) vs SciPy at matched accuracy")
        keep("integrators", run_integrators(quick))
    if "scaling" in chosen:
        rtol = 1e-7
        prior = (docs.get("integrators") or _load(out_dir, "integrators") or {}).get("runs", [])
        for r in sorted(prior, key=lambda r: r["N"] != 50):   # N = 50 first, else any
            if r["kvrod"]["matched"]:
                rtol = r["kvrod"]["matched"]["rtol"]
                break
        _log("== scaling in N")
        doc = scaling.run(scaling.QUICK_SIZES if quick else scaling.SIZES,
                          T=2.0 if quick else 10.0, rtol=rtol, log=_log,
                          rounds=1 if quick else scaling.ROUNDS)
        doc["meta"] = metadata()
        keep("scaling", doc)
    if "modes" in chosen:
        _log("== damped modes at any size: kvrod modes beside kvrod simulate")
        keep("modes", modes_bench.run(quick, log=_log))
    if "maxwell" in chosen:
        _log("== generalized Maxwell rods: kvrod vs SUNDIALS at matched accuracy")
        keep("maxwell", maxwell_bench.run(quick, log=_log))
    if "sections" in chosen:
        _log("== cross-section analysis: kvrod section beside sectionproperties")
        keep("sections", sections_bench.run(quick, log=_log))
    if "overhead" in chosen:
        _log("== kvrod simulate's own cost beside its integrator and beside IDAS")
        keep("overhead", overhead_bench.run(quick, log=_log))
    if "maxwell_kv" in chosen:
        _log("== generalized Maxwell over Kelvin-Voigt at matched accuracy")
        keep("maxwell_kv", maxwell_kv_bench.run(quick, log=_log))
    if "sensitivities" in chosen:
        _log("== the cost of forward sensitivities: kvrod simulate with k = 0, 1, 2, 4")
        keep("sensitivities", sensitivities_bench.run(quick, log=_log))
        _write(out_dir / "sensitivities.md",
               "\n".join(sensitivities_bench.markdown(docs["sensitivities"])))
    if "fit" in chosen:
        _log("== kvrod fit: two parameters of the paper's cantilever from a 4 s record")
        keep("fit", fit_bench.run(quick, log=_log))
    if "contact" in chosen and not quick:
        _log("== contact: a cable falling onto a floor against the free swing")
        keep("contact", contact_bench.run(quick, log=_log))
        _write(out_dir / "contact.md", "\n".join(contact_bench.markdown(docs["contact"])))
    if "sweeps" in chosen and not quick:
        _log("== sweeps and start-up: whole commands side by side")
        keep("sweeps", sweeps_bench.run(quick, log=_log))
        _write(out_dir / "sweeps.md", "\n".join(sweeps_bench.markdown(docs["sweeps"])))
    if "assembly" in chosen:
        _log("== rod assemblies beside their rods run one by one")
        keep("assembly", assembly_bench.run(quick, log=_log))
    if not quick:
        if "codegen" in chosen:
            _log("== derivation / generate / compile")
            keep("codegen", codegen_timing.run(log=_log))
        if "peers" in chosen:
            _log("== PyElastica")
            doc = peers.run(log=_log)
            doc["targets"] = []
            doc["meta"] = metadata()
            keep("peers", doc)
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
    docs["meta"] = {**metadata(), "quick": quick, "pyelastica": peers.available(),
                    "seconds": time.perf_counter() - t0,
                    "sections_run": [n for n in SECTIONS if n in chosen]}
    md = report.markdown(docs)
    _write(out_dir / "README.md", md)
    _log(md)
    return _clean(docs)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m bench", description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="N = 25 (and 50), 2 s; under a minute")
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
