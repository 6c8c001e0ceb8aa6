"""`kvrod modes`, `calibrate`, `compare-damping`, `notes-beyond` (issue 7: beyond the paper).

Wired into `kvrod/cli.py` by ``add_commands(subparsers, parser_class)``. Heavy imports
happen inside the commands; library code never prints, these commands do.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path


def _cli_error(message: str) -> Exception:
    from kvrod.cli import CliError

    return CliError(message)


# --------------------------------------------------------------------------------------
# kvrod modes
# --------------------------------------------------------------------------------------


def modes_table(modes) -> str:
    """The table printed by `kvrod modes` (one line per mode)."""
    head = (f"{'mode':>4}  {'family':<10} {'f [Hz]':>10} {'omega [rad/s]':>14} "
            f"{'zeta [-]':>9} {'lambda [1/s]':>30} {'analytic omega':>15} {'diff':>8}")
    lines = [head, "-" * len(head)]
    for m in modes:
        l1, l2 = m.eigenvalues
        lam = (f"{l1.real:.4g} +- {abs(l1.imag):.4g}i" if l1.imag != 0
               else f"{l1.real:.4g}, {l2.real:.4g}")
        ref = f"{m.analytic_omega:15.5f}" if m.analytic_omega else f"{'-':>15}"
        diff = (f"{(m.omega / m.analytic_omega - 1) * 100:+7.3f}%" if m.analytic_omega
                else f"{'':>8}")
        lines.append(f"{m.index:>4}  {m.family:<10} {m.frequency_hz:10.5f} {m.omega:14.5f} "
                     f"{m.zeta:9.5f} {lam:>30} {ref} {diff}")
    return "\n".join(lines)


def plot_mode_shapes(modes, length: float, path: Path) -> Path:
    """Mode shapes as PNG: displacements (solid) and rotations times L (dashed), scaled
    together to max 1; components below 1e-6 of the largest are left out."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    n = len(modes)
    cols = min(3, n)
    rows = math.ceil(n / cols)
    fig, axes = plt.subplots(rows, cols, figsize=(4.2 * cols, 2.8 * rows), squeeze=False)
    for ax, m in zip(axes.ravel(), modes, strict=False):
        N = m.rotation.shape[1]
        s_n = np.linspace(0.0, length, N + 1)
        s_s = (s_n[:-1] + s_n[1:]) / 2
        d, r = m.displacement, m.rotation * length  # rotations as theta L (m)
        scale = max(np.abs(d).max(), np.abs(r).max()) or 1.0
        for c, lab in enumerate(("x", "y", "z")):
            if np.abs(d[c]).max() > 1e-6 * scale:
                ax.plot(s_n, d[c] / scale, "-", color=f"C{c}", label=f"u_{lab}")
            if np.abs(r[c]).max() > 1e-6 * scale:
                ax.plot(s_s, r[c] / scale, "--", color=f"C{c}", label=f"theta_{c + 1} L")
        ax.set_title(f"{m.index}: {m.family}, f = {m.frequency_hz:.4g} Hz, "
                     f"zeta = {m.zeta:.3g}", fontsize=8)
        ax.set_xlabel("s [m]", fontsize=8)
        ax.tick_params(labelsize=7)
        ax.legend(fontsize=6, loc="best")
        ax.grid(alpha=0.3)
    for ax in axes.ravel()[n:]:
        ax.set_visible(False)
    fig.tight_layout()
    from runtime.io.atomic import save_figure

    try:
        return save_figure(fig, path, dpi=110)
    finally:
        plt.close(fig)


def run_modes(problem, count: int = 10, deformed: bool = False) -> dict:
    """Modal analysis of a problem; returns {"modes", "model", "static_tip", ...}.

    Straight (default): about the stress-free reference without loads; deformed: about
    the static equilibrium under the problem's loads at t = 0-. Continuum reference
    frequencies (the independent ``references`` package) are attached where they apply.
    """
    from dataclasses import replace

    from kvrod import continuum
    from runtime.analysis.modal import modal_analysis
    from runtime.problem.assemble import build_model
    from runtime.simulate.simulate import static_equilibrium

    p = problem if deformed else replace(problem, loads=())
    model = build_model(p)
    y_eq, tip = None, None
    if deformed:
        st = static_equilibrium(p, model)
        y_eq, tip = st.y, st.tip
    modes = modal_analysis(model, y_eq, count=count)
    if not deformed:
        continuum.attach(problem, modes)
    return {"problem": problem, "model": model, "modes": modes, "deformed": deformed,
            "static_tip": tip}


def _cmd_modes(args) -> int:
    from kvrod.problem_args import problem_from_args

    if args.count < 1:
        raise _cli_error(f"kvrod modes: --count must be >= 1, got {args.count}")
    problem = problem_from_args(args, "modes")
    nq = 6 * problem.rod.elements
    if args.count > nq:
        raise _cli_error(f"kvrod modes: --count {args.count} exceeds the {nq} degrees of "
                         f"freedom of {problem.rod.elements} elements")
    out = Path(args.out) if args.out else Path("results") / (
        f"modes-{problem.name}" + ("-deformed" if args.deformed else ""))
    from kvrod.outputs import results_folder

    with results_folder(out, "modes", markers=("modes.json",), overwrite=args.overwrite,
                        names=("modes.json", "mode_shapes.png")):
        return _modes_into(args, problem, out)


def _modes_into(args, problem, out: Path) -> int:
    from runtime.io.results import write_json

    res = run_modes(problem, args.count, args.deformed)
    modes = res["modes"]
    m = problem.material
    state = "pre-deformed by its static loads" if args.deformed else "straight, unloaded"
    print(f"{problem.name}: N = {problem.rod.elements}, tau_S = {m.tau_S} s, tau_B = "
          f"{m.tau_B} s (tau_E = {m.tau_E:.6g} s), {state}")
    if res["static_tip"] is not None:
        print(f"static tip [m]: {[round(float(v), 6) for v in res['static_tip']]}")
    print(modes_table(modes))
    write_json(out / "modes.json", {
        "problem": problem.name, "parameters": problem.to_mapping(), "tau_E": m.tau_E,
        "deformed": args.deformed, "static_tip": res["static_tip"],
        "modes": [md.to_dict() for md in modes]})
    plot_mode_shapes(modes, problem.rod.length, out / "mode_shapes.png")
    print(f"wrote {out}/modes.json, mode_shapes.png")
    return 0


# --------------------------------------------------------------------------------------
# kvrod calibrate
# --------------------------------------------------------------------------------------


def _cmd_calibrate(args) -> int:
    """Validate the data and the model first, then lock the folder and fit."""
    from kvrod.outputs import results_folder
    from runtime.analysis import calibration as cal
    from runtime.problem.registry import load_problem

    if args.tau0 is not None and not (math.isfinite(args.tau0) and args.tau0 > 0):
        raise _cli_error(f"kvrod calibrate: --tau0 = {args.tau0} must be a finite time > 0 s")
    kw: dict = {}
    if args.tip_force is not None:
        kw["tip_force"] = args.tip_force
    n = args.n_elements or 16
    try:
        if args.mode == "signal":
            data = cal.validate_signal(*cal.load_csv(args.data, ("t", "x")))
            problem = load_problem(args.problem, {"n_elements": n, **kw})
            cal.check_record(data[0], data[1], problem)
        else:
            data = (cal.validate_decrements(*cal.load_csv(args.data, ("delta",))),)
            problem = load_problem(args.problem, {"n_elements": n, **kw})
    except ValueError as exc:
        from runtime.errors import ParameterError

        if isinstance(exc, ParameterError):
            raise
        raise _cli_error(f"kvrod calibrate: {args.data}: {exc}") from None
    with results_folder(Path(args.out), "calibrate", markers=("calibration.json",),
                        overwrite=args.overwrite,
                        names=("calibration.json", "calibration.png")):
        return _calibrate_into(args, Path(args.out), data, problem)


def _calibrate_into(args, out: Path, data: tuple, problem) -> int:
    from runtime.analysis import calibration as cal
    from runtime.io.results import write_json

    if args.mode == "signal":
        res = cal.calibrate_signal(*data, problem=problem, tau0=args.tau0,
                                   n_elements=problem.rod.elements)
    else:
        res = cal.calibrate_decrements(data[0], problem=problem, tau0=args.tau0)
    write_json(out / "calibration.json", {"data": str(args.data), **res.summary()})
    cal.plot_calibration(res, out / "calibration.png")
    lo, hi = res.ci95
    print(f"mode: {res.mode}, {res.n_data} data, start tau0 = {res.tau0 * 1e3:.4f} ms")
    print(f"tau = {res.tau * 1e3:.4f} ms  (standard error {res.std_error * 1e3:.4f} ms; "
          f"95 % CI [{lo * 1e3:.4f}, {hi * 1e3:.4f}] ms)")
    print(f"residual RMS {res.residual_rms:.4g}{' m' if res.mode == 'signal' else ''}, "
          f"{res.nfev} model evaluations; {res.message}")
    print(f"wrote {out}/calibration.json, calibration.png")
    if not res.accepted:
        why = "; ".join(res.doubts) or f"the fit did not converge: {res.message}"
        print(f"kvrod calibrate: fit rejected: {why}", file=sys.stderr)
        return 1
    return 0


# --------------------------------------------------------------------------------------
# kvrod compare-damping (computation: runtime/analysis/compare_damping.py)
# --------------------------------------------------------------------------------------


def compare_table(result) -> str:
    """The table printed by `kvrod compare-damping` (plain text, one line per route)."""
    head = (f"{'case':<8} {'route':<11} {'tau_E [s]':>11} {'zeta meas.':>11} "
            f"{'w tau/2':>9} {'(contin.)':>9} {'modal':>9} {'meas/pred':>10}")
    lines = [head, "-" * len(head)]
    for case, res in result["cases"].items():
        for route, r in res["routes"].items():
            lines.append(f"{case:<8} {route:<11} {r['tau_E']:11.5g} {r['measured_zeta']:11.5f} "
                         f"{r['predicted_zeta']:9.5f} {r['predicted_zeta_continuum']:9.5f} "
                         f"{r['modal_zeta']:9.5f} "
                         f"{r['measured_zeta'] / r['predicted_zeta']:10.4f}")
        lines.append(f"{case:<8} ratio consistent/naive: measured {res['measured_ratio']:.4f}, "
                     f"predicted tau_E/tau~_E = {res['predicted_ratio']:.4f}")
    return "\n".join(lines)


def compare_markdown(result) -> str:
    """The same table as Markdown (written to compare_damping.md)."""
    p = result["parameters"]
    lines = [
        "# eta_E (consistent) against eta~_E (naive): measured damping ratios",
        "",
        f"N = {p['n_elements']}, tau_S = {p['tau_S']:g} s, tau_B = {p['tau_B']:g} s, "
        f"nu = {p['poisson_ratio']:g}; bending: release from F = {p['tip_force']:g} N; "
        f"axial: release from F_z = {p['axial_force']:g} N with tau_S, tau_B scaled to "
        f"{p['axial_tau_S']:.4g} s, {p['axial_tau_B']:.4g} s (naive zeta = "
        f"{p['axial_zeta']:g}).",
        "",
        "| case | route | tau [s] | zeta measured | omega tau/2 (modal omega) | "
        "omega tau/2 (continuum) | measured/predicted |",
        "|---|---|---|---|---|---|---|",
    ]
    for case, res in result["cases"].items():
        for route, r in res["routes"].items():
            lines.append(f"| {case} | {route} | {r['tau_E']:.5g} | {r['measured_zeta']:.5f} | "
                         f"{r['predicted_zeta']:.5f} | {r['predicted_zeta_continuum']:.5f} | "
                         f"{r['measured_zeta'] / r['predicted_zeta']:.4f} |")
    lines += ["", "| case | ratio consistent/naive measured | predicted tau_E/tau~_E | "
              "difference |", "|---|---|---|---|"]
    for case, res in result["cases"].items():
        lines.append(f"| {case} | {res['measured_ratio']:.4f} | {res['predicted_ratio']:.4f} | "
                     f"{(res['measured_ratio'] / res['predicted_ratio'] - 1) * 100:+.3f} % |")
    return "\n".join(lines) + "\n"


def write_compare(result, out: Path) -> list[Path]:
    """compare_damping.json, compare_damping.md, compare_signals.png, compare_zeta.png."""
    from runtime.analysis.compare_damping import plot_compare, summary
    from runtime.io.results import write_json

    out = Path(out)
    paths = [write_json(out / "compare_damping.json", summary(result))]
    from runtime.io.atomic import write_text

    paths.append(write_text(out / "compare_damping.md", compare_markdown(result)))
    return paths + plot_compare(result, out)


def _cmd_compare(args) -> int:
    if args.n_elements < 2:
        raise _cli_error(f"kvrod compare-damping: --n-elements must be >= 2, got "
                         f"{args.n_elements}")
    from kvrod.outputs import results_folder
    from runtime.analysis import compare_damping as cd

    cd.check_inputs(args.n_elements, args.tau_S, args.tau_B, args.nu, args.tip_force,
                    args.rtol)
    with results_folder(Path(args.out), "compare-damping", markers=("compare_damping.json",),
                        overwrite=args.overwrite,
                        names=("compare_damping.json", "compare_damping.md")):
        res = cd.compare_damping(n_elements=args.n_elements, tau_S=args.tau_S,
                                 tau_B=args.tau_B, poisson_ratio=args.nu,
                                 tip_force=args.tip_force, rtol=args.rtol)
        print(compare_table(res))
        paths = write_compare(res, Path(args.out))
    print(f"wrote {Path(args.out)}/{', '.join(p.name for p in paths)}")
    return 0


# --------------------------------------------------------------------------------------
# kvrod notes-beyond (kvrod/beyond.py)
# --------------------------------------------------------------------------------------


def _cmd_notes_beyond(args) -> int:
    from kvrod.beyond import write_beyond_notes
    from kvrod.outputs import check_file_argument, results_folder

    check_file_argument(Path(args.out_notes), "--out-notes")
    with results_folder(Path(args.out), "notes-beyond",
                        markers=("compare-damping/compare_damping.json", "modes/modes.json",
                                 "calibration/calibration.json"),
                        overwrite=args.overwrite,
                        names=("compare-damping", "calibration", "modes", "modes-deformed")):
        path = write_beyond_notes(Path(args.out_notes), Path(args.out))
    print(f"wrote {path} (results under {args.out}/)")
    return 0


# --------------------------------------------------------------------------------------
# wiring
# --------------------------------------------------------------------------------------


def add_commands(sub, parser_class) -> None:
    """Add `modes`, `calibrate`, `compare-damping` and `notes-beyond` to ``sub``.

    parser_class is the one-line-error parser the caller created ``sub`` with (kept for
    symmetry with the other command modules; argparse passes it on to the subparsers).
    """
    _ = parser_class
    m = sub.add_parser("modes", help="damped modal analysis (frequencies, damping ratios, "
                                     "mode shapes)")
    from kvrod.problem_args import add_problem_arguments

    add_problem_arguments(m)
    m.add_argument("--count", type=int, default=10, help="number of modes (default 10)")
    m.add_argument("--deformed", action="store_true",
                   help="linearise about the static state under the problem's loads")
    m.add_argument("--out", help="results folder (default results/modes-SCENARIO[-deformed])")
    m.add_argument("--overwrite", action="store_true",
                   help="replace a result already in --out (default: refuse)")
    m.set_defaults(func=_cmd_modes)

    c = sub.add_parser("calibrate", help="fit tau (= tau_S = tau_B) of the cantilever to "
                                         "measured decay")
    c.add_argument("--data", required=True,
                   help="CSV: columns t, x (signal: time [s] since release, tip x [m]) "
                        "or a column delta (log decrements)")
    c.add_argument("--mode", choices=("signal", "decrements"), default="signal",
                   help="signal: simulate the problem; decrements: linear modal model")
    c.add_argument("--problem", default="cantilever",
                   help="the rod that was measured (problem file or built-in name)")
    c.add_argument("--n-elements", dest="n_elements", type=int,
                   help="elements of the model (default 16)")
    c.add_argument("--tip-force", dest="tip_force", type=float,
                   help="static tip force before release [N] (paper: 0.05)")
    c.add_argument("--tau0", type=float, help="starting value [s] (default: from the data)")
    c.add_argument("--out", default="results/calibration", help="results folder")
    c.add_argument("--overwrite", action="store_true",
                   help="replace a result already in --out (default: refuse)")
    c.set_defaults(func=_cmd_calibrate)

    d = sub.add_parser("compare-damping", help="consistent eta_E vs naive eta~_E in "
                                               "simulation (bending and axial decay)")
    d.add_argument("--n-elements", dest="n_elements", type=int, default=20,
                   help="elements (default 20)")
    d.add_argument("--tau-S", dest="tau_S", type=float, default=0.04,
                   help="shear retardation time [s] (default 0.04)")
    d.add_argument("--tau-B", dest="tau_B", type=float, default=0.0,
                   help="bulk retardation time [s] (default 0: no bulk viscosity)")
    d.add_argument("--nu", type=float, default=0.3, help="Poisson's ratio (default 0.3)")
    d.add_argument("--tip-force", dest="tip_force", type=float, default=0.001,
                   help="static tip force of the bending release [N] (default 0.001: "
                        "small amplitude, linear regime)")
    d.add_argument("--rtol", type=float, default=1e-7, help="integrator tolerance")
    d.add_argument("--out", default="results/compare-damping", help="results folder")
    d.add_argument("--overwrite", action="store_true",
                   help="replace a result already in --out (default: refuse)")
    d.set_defaults(func=_cmd_compare)

    n = sub.add_parser("notes-beyond", help="run compare-damping, modes and calibration "
                                            "(modest settings) and write notes/beyond.md")
    n.add_argument("--out-notes", dest="out_notes", default="notes/beyond.md",
                   help="notes file (default notes/beyond.md; figures go to its "
                        "figures/ folder)")
    n.add_argument("--out", default="results/beyond",
                   help="results folder of the three analyses (default results/beyond)")
    n.add_argument("--overwrite", action="store_true",
                   help="replace the results of an earlier run in --out")
    n.set_defaults(func=_cmd_notes_beyond)
