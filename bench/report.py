"""Markdown tables for ``bench/results/README.md`` from the benchmark documents."""

from __future__ import annotations

import math
from typing import Any

from bench.energy_audit import markdown as energy_audit_md


def _f(v: Any, fmt: str = ".3f") -> str:
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "-"
    if isinstance(v, int):
        return str(v)
    return format(v, fmt)


def _row(cells: list[str]) -> str:
    return "| " + " | ".join(cells) + " |"


def integrators_md(doc: dict) -> list[str]:
    runs = doc["runs"]
    out = ["## 1. kvrod vs SUNDIALS IDAS (and SciPy) at matched accuracy", "",
           doc["protocol"], ""]
    out += ["| N | kvrod s | IDAS s | kvrod / IDAS | IDAS / kvrod | target |",
            "|---:|---:|---:|---:|---:|:--|"]
    for r in runs:
        a, b = r["kvrod"]["matched"], r["idas"]["matched"]
        ratio = r.get("ratio_kvrod_over_idas")
        target = ""
        if r["N"] in (50, 200) and ratio is not None and doc["T"] == 10.0:
            target = "2x met" if ratio <= 0.5 else "2x missed"
        out.append(_row([str(r["N"]), _f(a and a["wall"]), _f(b and b["wall"]), _f(ratio, ".2f"),
                         _f(ratio and 1.0 / ratio, ".2f"), target]))
    out += ["", "Matched runs (the loosest rtol of the half-decade scan with max tip-x error "
            "<= 1e-5 m; atol = rtol). LU = factorisations; IDAS's Jacobian evaluations "
            "equal its linear-solver setups.", "",
            "| N | integrator | rtol | wall s | steps | residual evals | Jacobian evals | "
            "LU | Newton iters | error test fails | max tip err m |",
            "|---:|:--|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for r in runs:
        for key in ("kvrod", "idas", "scipy_bdf", "scipy_radau"):
            if key not in r:
                continue
            m = r[key]["matched"]
            if m is None:
                last = r[key]["scan"][-1] if r[key]["scan"] else {}
                why = (f"none (scan stopped: {last.get('rtol', 0):.0e} took > 60 s)"
                       if (last.get("wall") or 0) > 60 else "none in scan")
                out.append(_row([str(r["N"]), last.get("integrator", key), why,
                                 _f(last.get("wall")), "-", "-", "-", "-", "-", "-",
                                 _f(last.get("tip_error"), ".1e")]))
                continue
            out.append(_row([str(r["N"]), m["integrator"], f"{m['rtol']:.0e}", _f(m["wall"]),
                             _f(m.get("steps")), _f(m.get("nfev")), _f(m.get("njev")),
                             _f(m.get("nlu")), _f(m.get("nni")), _f(m.get("netf")),
                             _f(m["tip_error"], ".1e")]))
    out += ["", "Reference and cross-check (kvrod at rtol = atol = 1e-9 vs IDAS at 1e-9):", "",
            "| N | n | reference s | IDAS 1e-9 s | max tip-x difference m | "
            "IDAS build + first set-up s |", "|---:|---:|---:|---:|---:|---:|"]
    for r in runs:
        cc = r["cross_check"]
        first = (r["idas_build_seconds"] or 0.0) + (r.get("idas_first_setup_seconds") or 0.0)
        out.append(_row([str(r["N"]), str(r["n"]), _f(r["reference"]["wall"]),
                         _f(cc["idas_wall"]), _f(cc["max_tip_diff"], ".1e"),
                         _f(first, ".1f")]))
    out += ["", "(IDAS build + first set-up: CasADi function construction and, for jit, "
            "the gcc compile of the integrator's functions, once per N; not in the wall "
            "times above, like kvrod's one-off kernel compile.)"]
    if doc.get("idas_configs"):
        cfg = doc["idas_configs"]
        out += ["", f"IDAS configurations at N = {cfg['N']}, rtol = {cfg['rtol']:.0e} "
                f"(T = {cfg['T']:g} s): jit = CasADi jit-compiles the functions the "
                "integrator derives (residual, sparse Jacobian) with gcc -O2; external = DAE "
                "and full Jacobian code-generated here and loaded with casadi.external; "
                "expand = SX virtual machine; mx = MX virtual machine; then the linear solver "
                "(csparse = sparse LU, qr = CasADi's default). Build = function "
                "construction (+ C generation and gcc for external); setup = integrator "
                "construction (includes the jit compile for jit).", "",
                "| config | build s | setup s | run s | steps | LU | max tip err m |",
                "|:--|---:|---:|---:|---:|---:|---:|"]
        for c in cfg["rows"]:
            how = c["how"] + (f" ({c['detail']})" if c.get("detail") else "")
            out.append(_row([how, _f(c.get("build_seconds"), ".2f"),
                             _f(c.get("setup_seconds"), ".2f"), _f(c.get("wall")),
                             _f(c.get("steps")), _f(c.get("nlu")),
                             _f(c.get("tip_error"), ".1e")]))
    if doc.get("breakdown"):
        out += ["", "Where kvrod's time goes (matched rtol, no output points; C helpers "
                "timed through wrappers):", "",
                "| N | T s | total s | residual | Jacobian | LU | Newton solve+update | "
                "norms | integrator Python |", "|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
        for b in doc["breakdown"]:
            s, tot = b["seconds"], b["total"]
            cells = [str(b["N"]), _f(b["T"], "g"), _f(tot)]
            for k in ("residual", "jacobian", "lu", "newton_solve_update", "norms",
                      "python_integrator"):
                cells.append(f"{s.get(k, 0.0):.3f} ({100 * s.get(k, 0.0) / tot:.0f} %)")
            out.append(_row(cells))
    return out + [""]


def scaling_md(doc: dict) -> list[str]:
    out = ["## 2. Scaling in N (kvrod)", "",
           f"Cantilever release, rtol = atol = {doc['rtol']:.0e}, T = {doc['T']:g} s, "
           "output every 0.1 s, one subprocess per N. Peak RSS is the whole process "
           "(Python, NumPy, SciPy, CasADi); tracemalloc peak is the solve's own Python/NumPy "
           "allocations.", "",
           "| N | n | wall s | s per simulated s | steps | LU | peak RSS MiB | "
           "solve alloc peak MiB |", "|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for r in doc["rows"]:
        if not r.get("ok"):
            out.append(_row([str(r["N"]), "-", "failed", "-", "-", "-", "-", "-"]))
            continue
        out.append(_row([str(r["N"]), str(r["n"]), _f(r["wall"]),
                         _f(r["wall_per_simulated_second"], ".4f"), str(r["nstep"]),
                         str(r["nlu"]), _f(r["peak_rss_MiB"], ".0f"),
                         _f(r["solve_tracemalloc_peak_MiB"], ".1f")]))
    out += ["", f"Log-log slope of time against N: {_f(doc['loglog_slope'], '.2f')} over all "
            f"N, {_f(doc['loglog_slope_N_ge_200'], '.2f')} for N >= 200 (target <= 1.1)."]
    n1000 = [r for r in doc["rows"] if r.get("N") == 1000 and r.get("ok")]
    if n1000 and doc["T"] == 10.0:
        w = n1000[0]["wall"]
        out.append(f"N = 1000 for 10 s simulated: {w:.2f} s (target < 5 s: "
                   f"{'met' if w < 5 else 'missed'}).")
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
           "| N | residual us/cell | Jacobian us/cell | residual+Jacobian us/cell |",
           "|---:|---:|---:|---:|"]
    for r in doc["results"]:
        out.append(_row([str(r["N"]), f"{r['residual_us_per_cell']:.3f}",
                         f"{r['jacobian_us_per_cell']:.3f}",
                         f"{r['residual_plus_jacobian_us_per_cell']:.3f}"]))
    return out + [""]


#: the README's sections, in order: document name -> Markdown lines
SECTION_MD = {"integrators": integrators_md, "scaling": scaling_md, "codegen": codegen_md,
              "peers": peers_md, "kernels": kernels_md, "energy_audit": energy_audit_md}


def markdown(docs: dict) -> str:
    meta = docs["meta"]
    lines = ["# kvrod benchmarks", "",
             f"`python -m bench{' --quick' if meta['quick'] else ''}` on {meta['platform']}, "
             f"{meta['cpus']} CPUs, Python {meta['python']}, NumPy {meta['numpy']}, SciPy "
             f"{meta['scipy']}, CasADi {meta['casadi']}; {meta['date']}; total "
             f"{meta['seconds']:.0f} s.", ""]
    if meta.get("sections_run") and set(meta["sections_run"]) != set(SECTION_MD) \
            and not meta["quick"]:
        lines += [f"This run: {', '.join(meta['sections_run'])}; the other sections are read "
                  "back from their JSON in this folder (earlier runs, same machine).", ""]
    if meta["quick"]:
        lines += ["Quick mode: N = 25, 50 only, 2 s simulated, IDAS on the expanded (SX) "
                  "function (no jit compile), no SciPy Radau, no codegen timing, no "
                  "PyElastica, no kernel table. Use the full run for the quoted figures.", ""]
    for name, section_md in SECTION_MD.items():
        if name in docs:
            lines += section_md(docs[name])
    return "\n".join(lines).rstrip() + "\n"
