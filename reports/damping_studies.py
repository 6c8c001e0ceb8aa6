"""`kvrod notes-beyond`: three analyses beyond the paper with modest settings, and
notes/beyond.md.

1. eta_E against eta~_E in simulation (runtime/study/compare_damping.py) at N = 20;
2. damped modal analysis of the paper's cantilever at N = 50 (runtime/analysis/modal.py), straight
   and pre-deformed by the static tip load;
3. calibration of tau from a synthetic tip signal with known tau plus noise
   (runtime/study/calibration.py).

Every result is written to a results folder in the same form as the command quoted next
to it in the notes (``kvrod compare-damping``, ``kvrod modes``, ``kvrod calibrate``), so
each number can be regenerated on its own. Wall times, the first C compilation and the
machine go to ``timings.json`` / ``run-info.md`` in the results folder, not into the notes.
Runtime about 20-30 s.
"""

from __future__ import annotations

import math
import shutil
from pathlib import Path

import numpy as np

from derive.templating import render
from runtime.analysis.records import load_csv
from runtime.io.atomic import write_text

TEMPLATE_DIR = Path(__file__).parent / "templates"

#: settings of the notes (modest, < 2 min in total)
COMPARE_N = 20
MODES_N = 50
MODES_COUNT = 12
DISTINCT_MODES = 5
CAL_TAU = 0.05          # s, the "unknown" of the synthetic data
CAL_NOISE = 1e-3        # m, standard deviation of the added noise
CAL_DATA_N = 32         # elements of the simulation that makes the data
CAL_MODEL_N = 16        # elements of the calibration model (kvrod calibrate default)
CAL_T_END = 4.0         # s of record
CAL_DT = 0.01           # s sampling of the record
CAL_SEED = 7


def _rel(p: Path) -> str:
    """POSIX form of a path for the commands quoted in the notes."""
    return Path(p).as_posix()


# --------------------------------------------------------------------------------------
# 1. compare-damping
# --------------------------------------------------------------------------------------


def _compare(out: Path) -> dict:
    from reports.analyses import write_compare
    from runtime.problem.registry import load_problem
    from runtime.study import compare_damping as cd

    res = cd.compare_damping(n_elements=COMPARE_N)
    paths = write_compare(res, out)
    cases = {}
    for case, c in res["cases"].items():
        routes = {}
        for route, r in c["routes"].items():
            routes[route] = {
                "tau": r["tau_E"], "zeta": r["measured_zeta"],
                "pred": r["predicted_zeta"], "pred_cont": r["predicted_zeta_continuum"],
                "omega": r["omega"], "omega_cont": r["omega_continuum"],
                "rel": r["measured_zeta"] / r["predicted_zeta"] - 1,
                "cycles": len(r["measured_zeta_per_cycle"])}
        cases[case] = {"routes": routes, "measured_ratio": c["measured_ratio"],
                       "predicted_ratio": c["predicted_ratio"],
                       "rel": c["measured_ratio"] / c["predicted_ratio"] - 1,
                       "tau_S": c["tau_S"], "tau_B": c["tau_B"]}
    sc = load_problem("cantilever")
    area = dict(sc.section.dims)["width"] * dict(sc.section.dims)["height"]
    strain = res["parameters"]["axial_force"] / (sc.material.youngs_modulus * area)
    return {"parameters": res["parameters"], "cases": cases, "axial_strain": strain,
            "figures": [p for p in paths if p.suffix == ".png"],
            "command": f"kvrod compare-damping --n-elements {COMPARE_N} --out {_rel(out)}"}


# --------------------------------------------------------------------------------------
# 2. modes
# --------------------------------------------------------------------------------------


def _write_modes(res: dict, out: Path) -> list[Path]:
    """modes.json and mode_shapes.png (with modes.npz, mode_shapes_3d.png) as `kvrod
    modes` writes them (``reports.analyses.write_modes``); returns [modes.json,
    mode_shapes.png]."""
    from reports.analyses import write_modes

    paths = write_modes(res, out)
    return [paths[0], *[p for p in paths if p.name == "mode_shapes.png"]]


def _distinct(modes: list, count: int, rtol: float = 1e-6) -> list[list]:
    """The first ``count`` groups of modes with (numerically) equal frequencies."""
    groups: list[list] = []
    for m in modes:
        if groups and abs(m.omega - groups[-1][0].omega) <= rtol * m.omega:
            groups[-1].append(m)
        else:
            groups.append([m])
    return groups[:count]


def _modes(out: Path) -> dict:
    from reports.analyses import run_modes
    from runtime.analysis.modal import family_retardation_time
    from runtime.problem.registry import load_problem

    problem = load_problem("cantilever", {"n_elements": MODES_N})
    straight = run_modes(problem, MODES_COUNT)
    deformed = run_modes(problem, MODES_COUNT, deformed=True)
    figs = _write_modes(straight, out / "modes")[1:]
    figs += _write_modes(deformed, out / "modes-deformed")[1:]
    sc, model = straight["problem"], straight["model"]
    groups = _distinct(straight["modes"], DISTINCT_MODES)
    if len(groups) < DISTINCT_MODES:
        raise RuntimeError(f"only {len(groups)} distinct modes among the {MODES_COUNT} "
                           "computed; raise MODES_COUNT")
    rows = []
    for k, g in enumerate(groups, start=1):
        m = g[0]
        tau = family_retardation_time(model, m.family)
        w_ref = m.analytic_omega
        z_ref = None if w_ref is None else w_ref * tau / 2
        rows.append({
            "k": k, "families": " / ".join(sorted({x.family for x in g})),
            "multiplicity": len(g), "f": m.frequency_hz, "omega": m.omega,
            "zeta": m.zeta, "overdamped": m.zeta > 1, "tau": tau,
            "analytic_omega": w_ref, "analytic_f": None if w_ref is None
            else w_ref / (2 * math.pi),
            "omega_rel": None if w_ref is None else m.omega / w_ref - 1,
            "analytic_zeta": z_ref,
            "zeta_rel": None if z_ref is None else m.zeta / z_ref - 1})
    # frequency shift of the pre-deformed state: pair modes by (family, rank in family)
    ref = {(m.family, m.family_index): m for m in straight["modes"]}
    shift = []
    for m in deformed["modes"][:6]:
        s = ref.get((m.family, m.family_index))
        shift.append({"family": m.family, "k": m.family_index, "omega_def": m.omega,
                      "zeta_def": m.zeta, "omega_str": None if s is None else s.omega,
                      "rel": None if s is None else m.omega / s.omega - 1})
    cmd = f"kvrod modes cantilever --n-elements {MODES_N} --count {MODES_COUNT}"
    mat = sc.material
    return {"n": MODES_N, "count": MODES_COUNT, "tau_S": mat.tau_S, "tau_B": mat.tau_B,
            "tau_E": mat.tau_E, "rows": rows, "shift": shift,
            "static_tip": [float(v) for v in deformed["static_tip"]],
            "tip_force": float(np.linalg.norm(sc.loads[0].vector)), "figures": figs,
            "command": f"{cmd} --out {_rel(out / 'modes')}",
            "command_deformed": f"{cmd} --deformed --out {_rel(out / 'modes-deformed')}"}


# --------------------------------------------------------------------------------------
# 3. calibration
# --------------------------------------------------------------------------------------


def _calibration(out: Path) -> dict:
    from runtime.io.results import write_json
    from runtime.problem.registry import load_problem
    from runtime.simulate.simulate import simulate
    from runtime.study import calibration as cal

    out.mkdir(parents=True, exist_ok=True)
    sc = load_problem("cantilever", {"tau": CAL_TAU, "n_elements": CAL_DATA_N,
                                     "t_end": CAL_T_END, "output_step": CAL_DT})
    run = simulate(sc).finished("synthetic data run")
    rng = np.random.default_rng(CAL_SEED)
    t, x = run.t, run.tip[0] + CAL_NOISE * rng.standard_normal(run.t.size)
    data = out / "synthetic.csv"
    lines = [f"# synthetic tip signal: kvrod cantilever (paper's, N = {CAL_DATA_N}), "
             f"tau_S = tau_B = {CAL_TAU} s, release from F = "
             f"{float(np.linalg.norm(sc.loads[0].vector))} N, "
             f"+ N(0, {CAL_NOISE} m) noise, seed {CAL_SEED}", "t,x"]
    lines += [f"{a:.6f},{b:.10e}" for a, b in zip(t, x, strict=True)]
    write_text(data, "\n".join(lines) + "\n")
    # exactly what `kvrod calibrate --data synthetic.csv` does (the cantilever, N = 16)
    td, xd = load_csv(data, ("t", "x"))
    res = cal.calibrate_signal(td, xd, problem=load_problem("cantilever"),
                               n_elements=CAL_MODEL_N)
    write_json(out / "calibration.json", {"data": str(data), **res.summary()})
    fig = cal.plot_calibration(res, out / "calibration.png")
    lo, hi = res.ci95
    return {"tau_true": CAL_TAU, "noise": CAL_NOISE, "seed": CAL_SEED,
            "data_n": CAL_DATA_N, "model_n": CAL_MODEL_N, "t_end": CAL_T_END, "dt": CAL_DT,
            "samples": int(td.size), "tip_force": float(np.linalg.norm(sc.loads[0].vector)),
            "tau": res.tau,
            "se": res.std_error, "lo": lo, "hi": hi, "tau0": res.tau0,
            "error": res.tau / CAL_TAU - 1, "inside": bool(lo < CAL_TAU < hi),
            "rms": res.residual_rms, "nfev": res.nfev, "success": res.success,
            "message": res.message, "figures": [fig],
            "command": f"kvrod calibrate --data {_rel(data)} --out {_rel(out)}"}


# --------------------------------------------------------------------------------------
# notes
# --------------------------------------------------------------------------------------


def write_beyond_notes(path: Path = Path("notes/beyond.md"),
                       out: Path = Path("results/beyond"),
                       command: str = "kvrod notes-beyond") -> Path:
    """Run the three analyses, write their results under ``out`` and render ``path``.

    Figures are copied next to the notes into ``path.parent / "figures"`` with the prefix
    ``beyond_``; the measurements of this run (``command``) go to ``out/run-info.md``.
    Returns the notes path. Raises RuntimeError if a simulation fails.
    """
    from reports.run_info import Timings

    path, out = Path(path), Path(out)
    timings = Timings(command)
    timings.compile_native()
    with timings.phase("compare-damping"):
        compare = _compare(out / "compare-damping")
    with timings.phase("modes"):
        modes = _modes(out)
    with timings.phase("calibration"):
        calib = _calibration(out / "calibration")
    timings.figures["calibration: model runs of the fit"] = calib["nfev"]
    fig_dir = path.parent / "figures"
    fig_dir.mkdir(parents=True, exist_ok=True)
    links: dict[str, str] = {}
    for key, src in (("compare_signals", compare["figures"][0]),
                     ("compare_zeta", compare["figures"][1]),
                     ("mode_shapes", modes["figures"][0]),
                     ("mode_shapes_deformed", modes["figures"][1]),
                     ("calibration", calib["figures"][0])):
        dst = fig_dir / f"beyond_{key}.png"
        shutil.copyfile(src, dst)
        links[key] = f"figures/{dst.name}"
    ctx = {"compare": compare, "modes": modes, "cal": calib, "fig": links,
           "out": _rel(out), "notes": _rel(path)}
    text = render(TEMPLATE_DIR, "beyond.md.jinja", **ctx)
    write_text(path, text)
    timings.write(out)
    return path
