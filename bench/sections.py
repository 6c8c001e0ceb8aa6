"""Cross-section analysis speed (issue 33, item 4): ``kvrod section`` on a 20k-element
composite, and kvrod beside the peer code sectionproperties on the same mesh.

The composite: a 16-ply angle-ply laminate strip, plies of 0.125 mm alternately +30 and
-30 degrees (the glass/epoxy plies of examples/fibre_strip_section.toml, anisotropic: the
warping's three components couple), 40 mm x 2 mm; the refinement loop (tol 1e-4) ends on a
mesh of about 20,300 six-node triangles. ``--quick``: 4 plies of 0.5 mm, 20 mm wide
(about 2,000 triangles).

Every measurement runs in a child process with one thread (OMP_NUM_THREADS,
OPENBLAS_NUM_THREADS, MKL_NUM_THREADS = 1), in ROUNDS rounds of three children in turn (a
slow spell of the shared machine spoils one round, not every repeat of one command):

1. kvrod in-process: ``analyse_section`` of the laminate (every mesh of the refinement
   loop, each mesh's time: meshing and the finite-element analysis), then the analysis of
   the finest mesh alone twice (:func:`runtime.section.analysis._solve_mesh`: element
   arrays, assembly, the factorization, both systems, the 6x6 forms), with the laminate's
   plies and with one isotropic material (E 20 GPa, nu 0.3) in every ply;
2. sectionproperties on that same mesh (its nodes, six-node triangles and regions handed
   over as its mesh), the isotropic material in every ply (it has no anisotropic
   materials): ``calculate_geometric_properties()`` then ``calculate_warping_properties()``
   with its faster solver (a probe of "direct" and "cgs" in the first round picks it; a
   solver that fails, as cgs can on a small mesh, is left out);
   the ``Section`` construction is not counted;
3. the whole ``kvrod section FILE --out DIR`` process (start-up, the analysis, section.json,
   section.png).

Times are CPU seconds of the child (``time.process_time``, or the child's user + system
time for the whole process: on a shared machine the wall clock also counts the waits for a
core) with the wall seconds beside them; medians over the rounds, the kvrod /
sectionproperties ratio the median of the per-round ratios (paired). The two codes'
results on the shared mesh are compared (EA, EI1, EI2, the torsional stiffness: the same
quadratic elements on the same mesh, so they agree closely).
"""

from __future__ import annotations

import json
import math
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from bench.meta import metadata, target, targets_md

ROUNDS = 3
QUICK_ROUNDS = 1
TIMEOUT = 1200.0
#: issue 33, item 4: the composite's analysis on one core under this many seconds
ANALYSIS_MAX_S = 5.0
#: and at most sectionproperties' warping analysis of the same mesh
RATIO_MAX = 1.0
#: the laminate: plies, ply thickness [m], width [m]
FULL = {"plies": 16, "ply": 0.000125, "width": 0.04}
QUICK = {"plies": 4, "ply": 0.0005, "width": 0.02}
#: the isotropic stand-in for the cross-check with sectionproperties
ISO_E, ISO_NU, ISO_RHO = 20e9, 0.3, 1900.0
ONE_THREAD = {"OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}


def laminate(plies: int, ply: float, width: float) -> dict[str, Any]:
    """The section file's mapping: ``plies`` plies of thickness ``ply`` alternately
    +30 / -30 degrees, ``width`` wide, the plies' materials of
    examples/fibre_strip_section.toml."""
    import tomllib

    from runtime.problem.registry import EXAMPLES_DIR

    src = tomllib.loads((EXAMPLES_DIR / "fibre_strip_section.toml").read_text())
    regions = []
    for i in range(plies):
        centre = round((i + 0.5 - plies / 2) * ply, 12)
        regions.append({"name": f"ply {i + 1}",
                        "material": "ply_plus" if i % 2 == 0 else "ply_minus",
                        "shape": {"kind": "rectangle", "width": width, "height": ply,
                                  "centre": [0.0, centre]}})
    return {"name": f"laminate{plies}",
            "description": f"{plies}-ply angle-ply laminate (+30/-30), {width * 1e3:g} x "
                           f"{plies * ply * 1e3:g} mm",
            "section": {"kind": "composite", "regions": regions},
            "materials": src["materials"]}


def _isotropic(spec: dict) -> dict:
    mats = {"iso": {"youngs_modulus": ISO_E, "poisson_ratio": ISO_NU, "density": ISO_RHO}}
    regions = [{**r, "material": "iso"} for r in spec["section"]["regions"]]
    return {"regions": regions, "materials": mats}


def _child_kvrod(spec: dict, mesh_file: Path) -> dict:
    """In a one-thread child: the analysis with each mesh's time, then the finest mesh
    alone with the laminate's and with the isotropic materials."""
    import numpy as np

    from runtime.section import analysis
    from runtime.section.materials import materials_from_mapping
    from runtime.section.regions import regions_from_mapping

    regions = regions_from_mapping(spec["section"]["regions"])
    mats = materials_from_mapping(spec["materials"])
    levels: list[dict] = []
    solve_level = analysis._solve_level

    def timed_level(*args, **kwargs):
        c, w = time.process_time(), time.perf_counter()
        lev = solve_level(*args, **kwargs)
        levels.append({"elements": int(lev.mesh.elements.shape[0]),
                       "nodes": int(lev.mesh.nodes.shape[0]),
                       "cpu": time.process_time() - c, "wall": time.perf_counter() - w})
        return lev

    analysis._solve_level = timed_level
    try:
        c, w = time.process_time(), time.perf_counter()
        res = analysis.analyse_section(regions, mats)
        total = {"cpu": time.process_time() - c, "wall": time.perf_counter() - w}
    finally:
        analysis._solve_level = solve_level
    mesh = res.mesh
    np.savez(mesh_file, nodes=mesh.nodes, elements=mesh.elements, region=mesh.region)

    def on_mesh(materials: dict, names: list[str]) -> tuple[dict, Any]:
        used = [materials[n] for n in names]
        # the reference scales only condition the solve (any sensible choice: same SI)
        c0 = max(float(np.max(np.abs(m.stiffness))) for m in used)
        v0 = max([float(np.max(np.abs(m.viscosity))) for m in used] + [c0 * 1e-300])
        c, w = time.process_time(), time.perf_counter()
        lev = analysis._solve_mesh(mesh, used, np.array(res.elastic_centroid),
                                   math.sqrt(res.area), c0, v0)
        return {"cpu": time.process_time() - c, "wall": time.perf_counter() - w}, lev

    names = [r.material for r in regions]
    aniso, _ = on_mesh(mats, names)
    iso_spec = _isotropic(spec)
    iso_mats = materials_from_mapping(iso_spec["materials"])
    iso, lev = on_mesh(iso_mats, ["iso"] * len(regions))
    K = lev.K
    return {"levels": levels, "analysis": total, "elements": res.n_elements,
            "nodes": res.n_nodes, "converged": res.converged,
            "achieved_change": res.achieved_change, "finest_mesh": {"laminate": aniso,
                                                                    "isotropic": iso},
            "isotropic_results": {"EA": float(K[2, 2]), "EI1": float(K[3, 3]),
                                  "EI2": float(K[4, 4]),
                                  "GJ": float(1.0 / lev.Fc[5, 5])}}


def _child_sectionproperties(spec: dict, mesh_file: Path, solvers: list[str]) -> dict:
    """In a one-thread child: sectionproperties on kvrod's finest mesh, the isotropic
    material in every region, with each of ``solvers``."""
    import numpy as np
    from sectionproperties.analysis import Section
    from sectionproperties.pre.geometry import CompoundGeometry, Geometry
    from sectionproperties.pre.pre import Material

    from runtime.section.regions import regions_from_mapping

    data = np.load(mesh_file)
    regions = regions_from_mapping(_isotropic(spec)["regions"])
    iso = Material("iso", ISO_E, ISO_NU, 1.0, ISO_RHO, "grey")
    geom = CompoundGeometry([Geometry(r.shape.polygon(1e-3 * math.sqrt(r.shape.area)),
                                      material=iso) for r in regions])
    # Triangle's midside order (1-2, 2-0, 0-1), as sectionproperties reads it
    geom.mesh = {"vertices": data["nodes"],
                 "triangles": data["elements"][:, [0, 1, 2, 4, 5, 3]],
                 "triangle_attributes": data["region"][:, None].astype(float)}
    out = {}
    for solver in solvers:
        sec = Section(geom)
        c, w = time.process_time(), time.perf_counter()
        sec.calculate_geometric_properties()
        cg, wg = time.process_time() - c, time.perf_counter() - w
        try:
            sec.calculate_warping_properties(solver_type=solver)
        except RuntimeError as exc:       # e.g. cgs: "Lagrangian multiplier ... tolerance"
            out[solver] = {"ok": False, "error": str(exc)}
            continue
        eixx, eiyy, _ = sec.get_eic()
        out[solver] = {"ok": True, "cpu": time.process_time() - c,
                       "wall": time.perf_counter() - w,
                       "geometric_cpu": cg, "geometric_wall": wg,
                       "EA": float(sec.get_ea()), "EI1": float(eixx), "EI2": float(eiyy),
                       # its composite torsion constant is modulus weighted: E J
                       "GJ": float(sec.get_ej()) / (2.0 * (1.0 + ISO_NU))}
    return out


def _run_child(args: list[str], log) -> dict:
    env = {**os.environ, **ONE_THREAD}
    cmd = [sys.executable, "-m", "bench.sections", *args]
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=TIMEOUT, env=env)
    if p.returncode != 0:
        log(f"    failed: {' '.join(args[:1])}: {p.stderr.strip().splitlines()[-1:]}")
        return {"ok": False, "error": p.stderr.strip()[-2000:]}
    return {"ok": True, **json.loads(p.stdout.strip().splitlines()[-1])}


def _whole_process(section_file: Path, out_dir: Path) -> dict:
    env = {**os.environ, **ONE_THREAD}
    cmd = [sys.executable, "-m", "kvrod.cli", "section", str(section_file), "--out",
           str(out_dir), "--overwrite"]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    w = time.perf_counter()
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=TIMEOUT, env=env)
    wall = time.perf_counter() - w
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return {"ok": p.returncode == 0, "wall": wall, "cpu": cpu,
            "error": p.stderr.strip()[-2000:] if p.returncode else ""}


def _version(package: str) -> str | None:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version(package)
    except PackageNotFoundError:
        return None


def _median(xs: list[float]) -> float | None:
    xs = [x for x in xs if x is not None]
    return statistics.median(xs) if xs else None


def run(quick: bool = False, log=print, size: dict | None = None,
        rounds: int | None = None) -> dict:
    """The section's document: per-round rows, medians, the cross-check and targets."""
    import tomli_w

    size = size or (QUICK if quick else FULL)
    rounds = rounds or (QUICK_ROUNDS if quick else ROUNDS)
    spec = laminate(**size)
    rows: list[dict] = []
    with tempfile.TemporaryDirectory(prefix="kvrod_bench_sections_") as tmp:
        tmp_dir = Path(tmp)
        section_file = tmp_dir / f"{spec['name']}.toml"
        section_file.write_text(tomli_w.dumps({k: v for k, v in spec.items()}))
        spec_file = tmp_dir / "spec.json"
        spec_file.write_text(json.dumps(spec))
        mesh_file = tmp_dir / "finest_mesh.npz"
        solver = None
        for r in range(rounds):
            log(f"  round {r + 1}/{rounds}: kvrod analysis ...")
            k = _run_child(["--child", "kvrod", str(spec_file), str(mesh_file)], log)
            solvers = ["direct", "cgs"] if solver is None else [solver]
            log(f"  round {r + 1}/{rounds}: sectionproperties ({', '.join(solvers)}) ...")
            s = (_run_child(["--child", "sectionproperties", str(spec_file), str(mesh_file),
                             *solvers], log) if k.get("ok") else {"ok": False})
            ran = [name for name in solvers if s.get(name, {}).get("ok")]
            if solver is None and ran:
                solver = min(ran, key=lambda name: s[name]["cpu"])
            log(f"  round {r + 1}/{rounds}: kvrod section (whole process) ...")
            whole = _whole_process(section_file, tmp_dir / "out")
            rows.append({"round": r + 1, "kvrod": k, "sectionproperties": s,
                         "whole_process": whole})
    return _summary(spec, size, rows, solver, quick)


def _summary(spec: dict, size: dict, rows: list[dict], solver: str | None,
             quick: bool) -> dict:
    ok = [r for r in rows if r["kvrod"].get("ok")]
    paired = [r for r in ok if solver and r["sectionproperties"].get(solver, {}).get("ok")]
    analysis_cpu = _median([r["kvrod"]["analysis"]["cpu"] for r in ok])
    whole_cpu = _median([r["whole_process"]["cpu"] for r in rows if r["whole_process"]["ok"]])
    mesh_cpu = _median([r["kvrod"]["finest_mesh"]["laminate"]["cpu"] for r in ok])
    sp_cpu = _median([r["sectionproperties"][solver]["cpu"] for r in paired])
    ratios = [r["kvrod"]["finest_mesh"]["laminate"]["cpu"] / r["sectionproperties"][solver]["cpu"]
              for r in paired]
    ratios_iso = [r["kvrod"]["finest_mesh"]["isotropic"]["cpu"]
                  / r["sectionproperties"][solver]["cpu"] for r in paired]
    ratios_wall = [r["kvrod"]["finest_mesh"]["laminate"]["wall"]
                   / r["sectionproperties"][solver]["wall"] for r in paired]
    n = ok[0]["kvrod"]["elements"] if ok else None
    cross = None
    if paired:
        kv = paired[0]["kvrod"]["isotropic_results"]
        spr = paired[0]["sectionproperties"][solver]
        cross = {key: {"kvrod": kv[key], "sectionproperties": spr[key],
                       "relative_difference": abs(kv[key] - spr[key]) / abs(spr[key])}
                 for key in ("EA", "EI1", "EI2", "GJ")}
    note = f"{spec['description']}, {n} elements"
    if quick:
        note += "; quick run: the target is for the 16-ply laminate (about 20,300 elements)"
    targets = [
        target(f"kvrod's analysis of the composite (every mesh of the refinement loop), "
               f"one core, CPU s < {ANALYSIS_MAX_S:g}", analysis_cpu, ANALYSIS_MAX_S,
               strict=True, note=note),
        target("kvrod / sectionproperties on the same (finest) mesh, CPU, paired median "
               f"<= {RATIO_MAX:g}", _median(ratios), RATIO_MAX,
               note=f"kvrod with the anisotropic plies, sectionproperties isotropic "
                    f"(solver {solver})"),
        target(f"the whole `kvrod section` process (start-up, analysis, section.json, "
               f"section.png), one core, CPU s < {ANALYSIS_MAX_S:g}", whole_cpu,
               ANALYSIS_MAX_S, strict=True, note=note),
    ]
    return {"composite": {"description": spec["description"], **size,
                          "elements": n,
                          "nodes": ok[0]["kvrod"]["nodes"] if ok else None},
            "rounds": rows, "sectionproperties_solver": solver,
            "sectionproperties_version": _version("sectionproperties"),
            "median": {"analysis_cpu": analysis_cpu,
                       "analysis_wall": _median([r["kvrod"]["analysis"]["wall"] for r in ok]),
                       "finest_mesh_cpu": mesh_cpu,
                       "finest_mesh_isotropic_cpu": _median(
                           [r["kvrod"]["finest_mesh"]["isotropic"]["cpu"] for r in ok]),
                       "sectionproperties_cpu": sp_cpu,
                       "sectionproperties_wall": _median(
                           [r["sectionproperties"][solver]["wall"] for r in paired]),
                       "whole_process_cpu": whole_cpu,
                       "whole_process_wall": _median([r["whole_process"]["wall"]
                                                      for r in rows
                                                      if r["whole_process"]["ok"]]),
                       "ratio_cpu": _median(ratios), "ratio_isotropic_cpu": _median(ratios_iso),
                       "ratio_wall": _median(ratios_wall)},
            "cross_check": cross, "targets": targets, "meta": metadata(),
            "protocol": __doc__.split("\n\n", 2)[2].split("\n\nTimes are")[0]
            .replace("\n", " ")}


def markdown(doc: dict) -> list[str]:
    c, m = doc["composite"], doc["median"]

    def f(v: Any, fmt: str = ".2f") -> str:
        return "-" if v is None else format(v, fmt)

    out = ["## 9. Cross-section analysis: kvrod section beside sectionproperties", "",
           f"{c['description']}: the refinement loop ends at {c['elements']} six-node "
           f"triangles ({c['nodes']} nodes). Each measurement in a one-thread child "
           f"process, {len(doc['rounds'])} round(s) in turn; CPU seconds of the child "
           "(wall seconds beside: the machine is shared), medians over the rounds, the "
           "ratio the median of the per-round ratios. sectionproperties "
           f"{doc.get('sectionproperties_version', '')} with solver "
           f"`{doc['sectionproperties_solver']}` (the faster of direct and cgs that ran) on "
           "kvrod's finest mesh, an isotropic material in every ply (it has no "
           "anisotropic ones); its Section construction is not counted.", "",
           "| what | CPU s | wall s |", "|:--|---:|---:|",
           f"| kvrod analysis, every mesh (`analyse_section`) | {f(m['analysis_cpu'])} | "
           f"{f(m['analysis_wall'])} |",
           f"| kvrod on the finest mesh, laminate (anisotropic plies) | "
           f"{f(m['finest_mesh_cpu'])} | - |",
           f"| kvrod on the finest mesh, isotropic plies | "
           f"{f(m['finest_mesh_isotropic_cpu'])} | - |",
           f"| sectionproperties, geometric + warping, finest mesh | "
           f"{f(m['sectionproperties_cpu'])} | {f(m['sectionproperties_wall'])} |",
           f"| `kvrod section` whole process | {f(m['whole_process_cpu'])} | "
           f"{f(m['whole_process_wall'])} |", "",
           f"kvrod / sectionproperties on the same mesh: {f(m['ratio_cpu'])} (CPU, "
           f"laminate), {f(m['ratio_isotropic_cpu'])} (CPU, isotropic plies), "
           f"{f(m['ratio_wall'])} (wall, laminate).", "",
           "Each mesh of the refinement loop (kvrod, first round: meshing and analysis):", "",
           "| mesh | elements | nodes | CPU s | wall s |", "|---:|---:|---:|---:|---:|"]
    first = next((r["kvrod"] for r in doc["rounds"] if r["kvrod"].get("ok")), None)
    for i, lev in enumerate(first["levels"] if first else []):
        out.append(f"| {i + 1} | {lev['elements']} | {lev['nodes']} | {f(lev['cpu'])} | "
                   f"{f(lev['wall'])} |")
    if doc.get("cross_check"):
        out += ["", "Same mesh, same isotropic material: kvrod against sectionproperties "
                "(relative difference): " + ", ".join(
                    f"{k} {v['relative_difference']:.1e}"
                    for k, v in doc["cross_check"].items()) + "."]
    return out + ["", *targets_md(doc["targets"]), ""]


def main(argv: list[str]) -> int:
    """``python -m bench.sections --child kvrod|sectionproperties SPEC MESH [SOLVERS]``:
    one measurement, its JSON on the last line of stdout."""
    if len(argv) < 4 or argv[0] != "--child":
        print(main.__doc__, file=sys.stderr)
        return 2
    spec = json.loads(Path(argv[2]).read_text())
    if argv[1] == "kvrod":
        doc = _child_kvrod(spec, Path(argv[3]))
    else:
        doc = _child_sectionproperties(spec, Path(argv[3]), argv[4:] or ["direct"])
    print(json.dumps(doc))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
