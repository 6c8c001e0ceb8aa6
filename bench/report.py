"""Markdown tables for ``bench/results/README.md`` from the benchmark documents."""

from __future__ import annotations

import math
from typing import Any

from bench.assembly import markdown as assembly_md
from bench.contact import markdown as contact_md
from bench.energy_audit import markdown as energy_audit_md
from bench.fit import markdown as fit_md
from bench.maxwell import QUICK as MAXWELL_QUICK
from bench.maxwell import markdown as maxwell_md
from bench.maxwell_kv import markdown as maxwell_kv_md
from bench.meta import targets_md
from bench.modes import markdown as modes_md
from bench.overhead import markdown as overhead_md
from bench.sections import markdown as sections_md
from bench.sensitivities import markdown as sensitivities_md
from bench.sweeps import markdown as sweeps_md


def _f(v: Any, fmt: str = ".3f") -> str:
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "-"
    if isinstance(v, int):
        return str(v)
    return format(v, fmt)


def _row(cells: list[str]) -> str:
    return "| " + " | ".join(cells) + " |"


def _us(v: Any) -> str:
    return _f(v, ".0f")


def integrators_md(doc: dict) -> list[str]:
    runs = doc["runs"]
    out = ["## 1. kvrod vs SUNDIALS (IDAS, CVODES) and SciPy at matched accuracy", "",
           doc["protocol"], "",
           "Strong SUNDIALS configurations (`bench/idas_script.py`): the ODE form "
           "y_d' = -g_d/D_d in per-component scaled variables; *flat* = residual and exact "
           "sparse Jacobian expanded to SX and generated into one C library (gcc -O2 "
           "-march=native, cached by content hash); *kernels* = kvrod's own compiled "
           "residual and banded Jacobian behind CasADi's external-function API "
           "(`bench/idas_kernels.c`, compiled with kvrod's own flags, -O3 -march=native; "
           "compile independent of N); CSparse LU; IDAS with "
           "`abstolv`, CVODES with its scalar abstol on the scaled state (= the same "
           "per-component atol). Times: medians of the matched runs timed alternately "
           "(kvrod, then each configuration, repeated); ratios: medians of the ratios of "
           "each repeat (paired); per step = wall / accepted steps.",
           "",
           "| N | kvrod s | kvrod us/step | strongest SUNDIALS | its s | its us/step | "
           "kvrod / strongest | strongest IDAS | kvrod / IDAS |",
           "|---:|---:|---:|:--|---:|---:|---:|:--|---:|"]
    for r in runs:
        d = r.get("duel") or {}
        k = d.get("kvrod", {})
        best = r.get("strongest")
        b = d.get(best, {}) if best else {}
        out.append(_row([str(r["N"]), _f(k.get("median")), _us(k.get("us_per_step")),
                         best or "-", _f(b.get("median")), _us(b.get("us_per_step")),
                         _f(r.get("ratio_kvrod_over_strongest"), ".2f"),
                         r.get("strongest_idas") or "-",
                         _f(r.get("ratio_kvrod_over_strongest_idas"), ".2f")]))
    if doc.get("targets"):
        out += ["", *targets_md(doc["targets"])]
    out += ["", "Alternating timing of the matched runs (median and range of the repeats):",
            "", "| N | integrator | rtol | median s | min-max s | steps | us/step | "
            "kvrod / this (paired) |", "|---:|:--|---:|---:|:--|---:|---:|---:|"]
    for r in runs:
        for name, d in (r.get("duel") or {}).items():
            m = r["kvrod"]["matched"] if name == "kvrod" else r["opponents"][name]["matched"]
            out.append(_row([str(r["N"]), name, f"{m['rtol']:.0e}", _f(d["median"]),
                             f"{min(d['walls']):.3f}-{max(d['walls']):.3f}",
                             str(d["steps"]), _us(d["us_per_step"]),
                             _f(d.get("paired_ratio_kvrod_over_this"), ".2f")]))
    out += ["", "Matched runs (the loosest rtol of the half-decade scan with max tip-x error "
            "<= 1e-5 m; one run each, so their times are noisier than the medians above). "
            "LU = factorisations; SUNDIALS's Jacobian evaluations equal its linear-solver "
            "set-ups.", "",
            "| N | integrator | rtol | wall s | steps | us/step | residual evals | "
            "Jacobian evals | LU | Newton iters | error test fails | max tip err m |",
            "|---:|:--|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for r in runs:
        entries = [("kvrod", r["kvrod"]), *r["opponents"].items()]
        for key, res in entries:
            m = res["matched"]
            if m is None:
                last = res["scan"][-1] if res["scan"] else {}
                why = (f"none (scan stopped: {last.get('rtol', 0):.0e} took > 60 s)"
                       if (last.get("wall") or 0) > 60 else "none in scan")
                out.append(_row([str(r["N"]), last.get("integrator", key), why,
                                 _f(last.get("wall")), "-", "-", "-", "-", "-", "-", "-",
                                 _f(last.get("tip_error"), ".1e")]))
                continue
            out.append(_row([str(r["N"]), m["integrator"], f"{m['rtol']:.0e}", _f(m["wall"]),
                             _f(m.get("steps")), _us(m.get("us_per_step")),
                             _f(m.get("nfev")), _f(m.get("njev")), _f(m.get("nlu")),
                             _f(m.get("nni")), _f(m.get("netf")), _f(m["tip_error"], ".1e")]))
    out += ["", "Reference and cross-check (kvrod at rtol = 1e-9 with default_atol against a "
            "SUNDIALS configuration at 1e-9), and the one-off cost of each configuration's "
            "functions (SX/MX construction, C generation, gcc; 0 when the library was in the "
            "cache):", "",
            "| N | n | reference s | cross-check | its s | max tip-x difference m | "
            "functions: build / codegen / compile s (C MB) |",
            "|---:|---:|---:|:--|---:|---:|:--|"]
    for r in runs:
        cc = r["cross_check"]
        builds = []
        for name, b in r.get("builds", {}).items():
            sec = b["seconds"]
            mb = f", {b['c_bytes'] / 2**20:.1f} MB" if b.get("c_bytes") else ""
            how = ("cached" if b["cached"] else
                   f"{sec.get('build', 0):.1f} / {sec.get('codegen', 0):.1f} / "
                   f"{sec.get('compile', 0):.1f}{mb}")
            builds.append(f"{name}: {how}")
        out.append(_row([str(r["N"]), str(r["n"]), _f(r["reference"]["wall"]), cc["config"],
                         _f(cc.get("wall")), _f(cc.get("max_tip_diff"), ".1e"),
                         "; ".join(builds)]))
    for r in runs:
        if r.get("flat_skipped"):
            out += ["", f"N = {r['N']}: {r['flat_skipped']}."]
    if doc.get("idas_configs"):
        cfg = doc["idas_configs"]
        out += ["", f"Every configuration at N = {cfg['N']}, rtol = {cfg['rtol']:.0e}, "
                f"T = {cfg['T']:g} s (median of 3 runs each, atol = default_atol unless "
                "marked): *flat*, *kernels* as above; *map* = the MX function over the "
                "per-element kernel maps generated to C and compiled (the earlier "
                "\"external\"); *jit* = CasADi's integrator jit-compiles the functions it "
                "derives from the MX DAE (gcc -O2); *sx* / *mx* = CasADi's SX / MX virtual "
                "machines; then the linear solver (csparse = sparse LU, qr = CasADi's "
                "default). Build s = construction + C generation + gcc (0: cached); set-up s "
                "= integrator construction (includes the jit compile).", "",
                "| config | build s | set-up s | run s | steps | us/step | LU | max tip err m |",
                "|:--|---:|---:|---:|---:|---:|---:|---:|"]
        for c in cfg["rows"]:
            sec = c.get("seconds") or {}
            build_s = sum(sec.get(k, 0.0) for k in ("build", "codegen", "compile"))
            out.append(_row([c["config"], "-" if c["config"] == "kvrod" else
                             ("cached" if c.get("cached") else _f(build_s, ".1f")),
                             _f(c.get("setup_seconds"), ".2f"), _f(c.get("wall")),
                             _f(c.get("steps")), _us(c.get("us_per_step")),
                             _f(c.get("nlu")), _f(c.get("tip_error"), ".1e")]))
    if doc.get("breakdown"):
        out += ["", "Where kvrod's time goes (matched rtol, no output points; total = the "
                "compiled step loop, its parts timed inside it; integrator = the rest: "
                "predictor, coefficients, error test, history, weights, norms; drive = "
                "loads re-applied at a new t; the last column is the Python path of the "
                "same algorithm, same steps, for comparison):", "",
                "| N | T s | total s | us/step | residual | Jacobian | drive | LU | "
                "Newton solve+update | integrator | Python path s |",
                "|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
        for b in doc["breakdown"]:
            s_, tot = b["seconds"], b["total"]
            cells = [str(b["N"]), _f(b["T"], "g"), _f(tot), _us(b.get("us_per_step"))]
            for k in ("residual", "jacobian", "drive", "lu", "newton_solve_update",
                      "integrator"):
                cells.append(f"{s_.get(k, 0.0):.3f} ({100 * s_.get(k, 0.0) / tot:.0f} %)")
            cells.append(_f(b.get("python_path", {}).get("total")))
            out.append(_row(cells))
    return out + [""]


def scaling_md(doc: dict) -> list[str]:
    out = ["## 2. Scaling in N (kvrod)", "",
           f"Cantilever release, rtol = {doc['rtol']:.0e} with default_atol, T = "
           f"{doc['T']:g} s, output every 0.1 s, one subprocess per N and round, "
           f"{doc.get('rounds', 1)} rounds over all N, the median over the rounds (a slow "
           "spell of a shared machine spoils one size in one round, not all repeats of "
           "it). Peak RSS is the whole process (Python, NumPy, SciPy, "
           "CasADi); tracemalloc peak is the solve's own Python/NumPy allocations.", "",
           "| N | n | wall s | s per simulated s | steps | us/step | LU | peak RSS MiB | "
           "solve alloc peak MiB |", "|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for r in doc["rows"]:
        if not r.get("ok"):
            out.append(_row([str(r["N"]), "-", "failed", "-", "-", "-", "-", "-", "-"]))
            continue
        out.append(_row([str(r["N"]), str(r["n"]), _f(r["wall"]),
                         _f(r["wall_per_simulated_second"], ".4f"), str(r["nstep"]),
                         _us(r.get("us_per_step")), str(r["nlu"]),
                         _f(r["peak_rss_MiB"], ".0f"),
                         _f(r["solve_tracemalloc_peak_MiB"], ".1f")]))
    out += ["", f"Log-log slope of time against N: {_f(doc['loglog_slope'], '.2f')} over all "
            f"N, {_f(doc['loglog_slope_N_ge_200'], '.2f')} for N >= 200."]
    if doc.get("targets"):
        out += ["", *targets_md(doc["targets"])]
    return out + [""]


def codegen_md(doc: dict) -> list[str]:
    out = ["## 3. Derivation, generation, compilation", "",
           "Each in a fresh Python process (seconds inside the child; imports apart).", "",
           "| stage | seconds | imports s | process s |", "|:--|---:|---:|---:|"]
    names = {"derivation": "derivation (`derive.pipeline.run()`)",
             "generate": "`kvrod generate` (`write_tree` into a temp dir)",
             "compile": "compile (`runtime.model.build.load_library()`, empty cache)"}
    for r in doc["rows"]:
        if not r.get("ok"):
            out.append(_row([names[r["stage"]], "failed", "-", "-"]))
            continue
        out.append(_row([names[r["stage"]], _f(r["seconds"], ".2f"),
                         _f(r["import_seconds"], ".2f"), _f(r["process_seconds"], ".2f")]))
    return out + [""]


def peers_md(doc: dict) -> list[str]:
    out = ["## 4. PyElastica (explicit; no strain-rate damping)", "",
           "PyElastica cannot represent Kelvin-Voigt (strain-rate) damping: its dampers act "
           "on absolute velocities. An explicit method with Kelvin-Voigt damping is limited "
           "by the fastest decay rate of the linearised rod (eigenvalues of -D^-1 dg/dy at "
           "the straight state, F = D y' + g):", "",
           "| N | max abs(lambda) 1/s | explicit dt ~ 2/abs(lambda) s | steps for 10 s |",
           "|---:|---:|---:|---:|"]
    for e in doc["estimates"]:
        out.append(_row([str(e["N"]), f"{e['lambda_max_abs']:.2e}", f"{e['dt_explicit']:.1e}",
                         f"{e['steps_for_10s']:.1e}"]))
    if doc.get("skipped"):
        return out + ["", doc["skipped"], ""]
    out += ["", f"PyElastica {doc['pyelastica']} (numba warm-up {doc['warmup_seconds']:.1f} s, "
            "not counted). Square section imposed on its circular rod (stiffness and "
            "inertia overridden). Its own damper: velocity damping at nu = omega_1^2 tau_E "
            "(same first-mode damping ratio as Kelvin-Voigt). Static tip error against the "
            "Simo-Reissner shooting solution; kvrod's static error beside it.", "",
           "| N | static tip err m | kvrod static err m | stable dt s | undamped 10 s: steps "
            "| wall s | period s | damped 10 s: wall s | kvrod period s |",
            "|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for c in doc["cases"]:
        u, d = c["undamped"], c["damped"]
        out.append(_row([str(c["N"]), f"{c['static']['tip_error']:.1e}",
                         f"{c['kvrod_static_tip_error']:.1e}", _f(c["dt_stable"], ".2e"),
                         str(u["steps"]), _f(u["wall"], ".2f"), _f(u["period"], ".4f"),
                         _f(d["wall"], ".2f"), _f(c["kvrod_period"], ".4f")]))
    return out + [""]


def kernels_md(doc: dict) -> list[str]:
    out = ["## 5. Generated kernels", "",
           f"Compile {doc['compile_seconds']:.2f} s; generated C+H "
           f"{doc['generated_bytes_total'] / 1024:.0f} KiB.", "",
           "| N | residual us/cell | Jacobian us/cell | residual+Jacobian us/cell | "
           "at(new t) us |", "|---:|---:|---:|---:|---:|"]
    for r in doc["results"]:
        out.append(_row([str(r["N"]), f"{r['residual_us_per_cell']:.3f}",
                         f"{r['jacobian_us_per_cell']:.3f}",
                         f"{r['residual_plus_jacobian_us_per_cell']:.3f}",
                         _f(r.get("at_new_time_us_per_call"), ".1f")]))
    if isinstance(doc.get("targets"), list):
        out += ["", *targets_md(doc["targets"])]
    return out + [""]


#: the README's sections, in order: document name -> Markdown lines
SECTION_MD = {"integrators": integrators_md, "scaling": scaling_md, "codegen": codegen_md,
              "peers": peers_md, "kernels": kernels_md, "energy_audit": energy_audit_md,
              "modes": modes_md, "maxwell": maxwell_md, "sections": sections_md,
              "overhead": overhead_md, "maxwell_kv": maxwell_kv_md,
              "sweeps": sweeps_md, "assembly": assembly_md,
              "sensitivities": sensitivities_md, "fit": fit_md, "contact": contact_md}


def markdown(docs: dict) -> str:
    meta = docs["meta"]
    lines = ["# kvrod benchmarks", "",
             f"`python -m bench{' --quick' if meta['quick'] else ''}` on {meta['platform']}, "
             f"{meta['cpus']} CPUs, Python {meta['python']}, NumPy {meta['numpy']}, SciPy "
             f"{meta['scipy']}, CasADi {meta['casadi']}; {meta['date']}; total "
             f"{meta['seconds']:.0f} s. Command: `{meta.get('command', '')}`.", ""]
    if meta.get("sections_run") and set(meta["sections_run"]) != set(SECTION_MD) \
            and not meta["quick"]:
        lines += [f"This run: {', '.join(meta['sections_run'])}; the other sections are read "
                  "back from their JSON in this folder (earlier runs, same machine).", ""]
    if meta["quick"]:
        lines += ["Quick mode: N = 25 (scaling: 25, 50) only, 2 s simulated, IDAS and CVODES "
                  "on kvrod's compiled kernels (no flat SX compile), SciPy BDF only, no "
                  "codegen timing, PyElastica, kernel table or energy audit; modes at N = 50 "
                  f"only; the Maxwell rod at N = {MAXWELL_QUICK.N}, {MAXWELL_QUICK.T:g} s; "
                  "sections on a 4-ply strip (about 2,000 elements), one round; assemblies at 2 s, "
                  "one round. "
                  "Use the full run for the quoted figures.", ""]
    for name, section_md in SECTION_MD.items():
        if name in docs:
            lines += section_md(docs[name])
    return "\n".join(lines).rstrip() + "\n"
