"""`kvrod simulate`, `kvrod static` and `kvrod plot`."""

from __future__ import annotations

import math
import sys
from pathlib import Path

from kvrod.problem_args import (
    add_problem_arguments,
    add_sensitivity_arguments,
    problem_from_args,
    sensitivity_names,
)
from kvrod.progress import progress_bar


def _static_lines(st: dict) -> list[str]:
    """What `kvrod static` and `kvrod simulate` print of a static result: the tip of a rod
    with a free end, or the largest displacement and where for a rod held at both ends (its
    "tip" is a support); the gauge of free rigid motions."""
    its = f"(Newton iterations: {st['newton_iterations']})"
    big = st.get("largest_displacement")
    if big:
        pos = [round(v, 9) for v in big["position"]]
        lines = [f"static: largest displacement {big['magnitude']:.6g} m at node "
                 f"{big['node']} (s = {big['s']:.6g} m), position [m] {pos}  {its}"]
    else:
        lines = [f"static tip [m]: {st['tip']}  {its}"]
    if st.get("gauge"):
        lines.append(f"gauge: {st['gauge']}")
    return lines


def _joint_lines(joints: list[dict], run: bool) -> list[str]:
    """What `kvrod static` and `kvrod simulate` print of an assembly's joints: the force
    and moment each exerts on the rod of its first point (static, or the final and largest
    of a run)."""
    out = []
    for j in joints:
        head = f"  joint {j['index']} ({j['kind']} {' - '.join(j['between'])}):"
        if "force" not in j:
            out.append(head + " no samples")
            continue
        if run:
            f, m = j["force"], j["moment"]
            out.append(f"{head} final force [N] {[round(v, 9) for v in f['final']]}, moment "
                       f"[N m] {[round(v, 9) for v in m['final']]}; largest |force| "
                       f"{f['max_norm']:.6g} N at t = {f['t_of_max']:.6g} s")
        else:
            out.append(f"{head} force [N] {[round(v, 9) for v in j['force']]}, moment "
                       f"[N m] {[round(v, 9) for v in j['moment']]}")
    return out


def _print_assembly(s: dict, out: Path, files: str) -> None:
    a = s["assembly"]
    print(f"{s['problem']}: an assembly of {len(a['rods'])} rods ({', '.join(a['rods'])}), "
          f"{a['joints']} joints, {a['bodies']} bodies")
    if s.get("static"):
        print(f"static: Newton iterations {s['static']['newton_iterations']}")
    for k, v in s.get("ends", {}).items():
        print(f"  {k.replace('/', '.')} [m]: {[round(x, 9) for x in v]}")
    print("\n".join(_joint_lines(s.get("joints", []), True)))
    for name, b in s.get("bodies", {}).items():
        print(f"  body {name}: position [m] {[round(x, 9) for x in b['position']]}")
    if s.get("peaks"):
        c = s.get("vibration_centre") or {}
        print(f"maxima: {len(s['peaks'])}, damping ratios: "
              f"{[round(v, 4) for v in s['damping_ratios']]} (about the {c.get('source')})")
    eb = s["energy_balance_max_rel"]
    print(f"energy balance max rel. error: {eb:.2e}" if eb is not None
          else f"energy balance: not applicable ({s['energy_audit']['note']})")
    print(f"counters: {s['counters']}, wall time {s['wall_time_s']:.2f} s")
    print(f"wrote {out}/ {files}")


def _print_summary(s: dict, out: Path, vtk: bool, plots: bool) -> None:
    if "assembly" in s:
        _print_assembly(s, out, "summary.json, series.npz, problem.toml"
                        + (", sensitivities.npz" if "sensitivities" in s else "")
                        + (", vtk/*.pvd" if vtk else "") + (", *.png" if plots else ""))
        return
    if s["static"]["tip"] is not None:
        print("\n".join(_static_lines(s["static"])))
    if s.get("peaks"):
        z = s["damping_ratios"]
        c = s.get("vibration_centre") or {}
        about = (f" (amplitudes about the {c['source']}, {c['coordinate']} = "
                 f"{c['displacement']:+.6g} m from the reference)"
                 if c.get("source", "reference") != "reference" else "")
        print(f"maxima: {len(s['peaks'])}, damping ratios: {[round(v, 4) for v in z]}{about}")
    lp = s.get("linear_prediction")
    if lp:
        print(f"linear prediction zeta_1 = {lp.get('formula', 'omega_1 tau / 2')} = "
              f"{lp['zeta_1']:.4f} for the {lp.get('mode', 'first bending mode')}")
    elif s.get("linear_prediction_note"):
        print(f"linear prediction: not applicable ({s['linear_prediction_note']})")
    eb = s["energy_balance_max_rel"]
    print(f"energy balance max rel. error: {eb:.2e}" if eb is not None
          else f"energy balance: not applicable ({s['energy_audit']['note']})")
    print(f"counters: {s['counters']}, wall time {s['wall_time_s']:.2f} s")
    files = ("summary.json, series.npz, problem.toml"
             + (", sensitivities.npz" if "sensitivities" in s else "")
             + (", vtk/rod.pvd" if vtk else "") + (", *.png" if plots else ""))
    print(f"wrote {out}/ {files}")


def _cmd_simulate(args) -> int:
    from kvrod.errors import CliError

    if args.vtk is not None and not (math.isfinite(args.vtk) and args.vtk > 0):
        raise CliError(f"kvrod simulate: --vtk = {args.vtk} must be > 0 (seconds between "
                       "snapshots)")
    if args.resume and args.overwrite:
        raise CliError("kvrod simulate: --resume and --overwrite exclude each other")
    problem = problem_from_args(args, "simulate")
    sens = sensitivity_names(args, problem, "simulate")
    if sens is not None and args.resume:
        raise CliError("kvrod simulate: --sensitivities with --resume: the sensitivities "
                       "are not kept in checkpoints; rerun with --overwrite")
    from runtime.io.folder import safe_name
    from runtime.io.runs import already_finished, run_and_write

    if args.vtk is not None and problem.simulation.t_end / args.vtk > 100_000:
        raise CliError(f"kvrod simulate: --vtk = {args.vtk} would write "
                       f"{problem.simulation.t_end / args.vtk:.3g} frames (at most 100000; "
                       "t_end/--vtk)")
    out = Path(args.out) if args.out else Path("results") / safe_name(problem.name)
    if args.resume and already_finished(problem, out):
        print(f"{out}: this run has already finished (summary.json); nothing to resume")
        return 0
    run, s = run_and_write(problem, out, problem.name, plots=args.plots, resume=args.resume,
                           progress=progress_bar,
                           vtk_every=args.vtk, overwrite=args.overwrite,
                           sensitivities=sens, sens_errcon=args.sens_errcon)
    _print_summary(s, out, args.vtk is not None, args.plots)
    for w in s.get("warnings", []):
        print(f"kvrod: warning: {w}", file=sys.stderr)
    if run.status != "finished":
        print(f"kvrod simulate: run {run.status}: {run.message}", file=sys.stderr)
        return 1
    return 0


def _cmd_static(args) -> int:
    """`kvrod static PROBLEM --out DIR` (see :func:`static_and_write`)."""
    problem = problem_from_args(args, "static")
    sens = sensitivity_names(args, problem, "static")
    from runtime.io.folder import safe_name
    from runtime.io.runs import static_and_write

    out = Path(args.out) if args.out else Path("results") / f"{safe_name(problem.name)}-static"
    summary, _, _ = static_and_write(problem, out, overwrite=args.overwrite,
                                     sensitivities=sens)
    st = summary["static"]
    if "assembly" in summary:
        print(f"{summary['problem']}: static equilibrium of an assembly of "
              f"{len(summary['assembly']['rods'])} rods (Newton iterations "
              f"{st['newton_iterations']})")
        for k, v in st["ends"].items():
            print(f"  {k} [m]: {[round(x, 9) for x in v]}")
        print("\n".join(_joint_lines(summary["joints"], False)))
        for name, b in summary.get("bodies", {}).items():
            print(f"  body {name}: position [m] {[round(x, 9) for x in b['position']]}")
        print(f"wrote {out}/ summary.json, static.npz, problem.toml"
              + (", sensitivities.npz" if "sensitivities" in summary else ""))
        if summary["status"] != "finished":
            print(f"kvrod static: {summary['message']}", file=sys.stderr)
            return 1
        return 0
    print("\n".join(_static_lines(st)))
    for p in st["path"][:-1]:
        print(f"  at load factor {p['load_factor']:g}: tip [m] {p['tip']}")
    for end, r in st.get("reactions", {}).items():
        f = ", ".join(f"{v:.6g}" for v in r["force"])
        m = ", ".join(f"{v:.6g}" for v in r["moment"])
        print(f"  support at the {end}: force [N] [{f}], moment [N m] [{m}]")
    print(f"wrote {out}/ summary.json, static.npz, problem.toml"
          + (", sensitivities.npz" if "sensitivities" in summary else ""))
    if summary["status"] != "finished":
        print(f"kvrod static: {summary['message']}", file=sys.stderr)
        return 1
    return 0


def _cmd_plot(args) -> int:
    """The pictures of a results folder, written next to its results (reports/plot_folder.py)."""
    from reports.plot_folder import plot_folder

    done = plot_folder(Path(args.folder), animate=args.animate)
    print(f"{args.folder}: {done.kind} result; wrote "
          f"{', '.join(str(p) for p in done.paths) or 'nothing'}")
    for note in done.notes:
        print(f"  {note}")
    return 0


def add_commands(sub, parser_class) -> None:
    s = sub.add_parser("simulate", help="run a rod problem (a .toml file or built-in name)")
    add_problem_arguments(s)
    s.add_argument("--resume", action="store_true",
                   help="continue from DIR/checkpoint.npz of an interrupted run")
    s.add_argument("--vtk", type=float, metavar="DT",
                   help="write ParaView VTK (.vtp + .pvd) every DT seconds")
    s.add_argument("--plots", action="store_true",
                   help="also draw PNG plots (or later: kvrod plot DIR)")
    s.add_argument("--out", help="results folder (default results/<problem name>)")
    s.add_argument("--overwrite", action="store_true",
                   help="replace a finished result in --out (default: refuse)")
    add_sensitivity_arguments(s)
    s.set_defaults(func=_cmd_simulate)

    t = sub.add_parser("static", help="static equilibrium of a rod problem under its loads")
    add_problem_arguments(t)
    t.add_argument("--out", help="results folder (default results/<problem name>-static)")
    t.add_argument("--overwrite", action="store_true",
                   help="replace a finished result in --out (default: refuse)")
    add_sensitivity_arguments(t, errcon=False)
    t.set_defaults(func=_cmd_static)

    pl = sub.add_parser("plot", help="draw the pictures of a results folder: a run, a static "
                                     "result, modes or a sweep")
    pl.add_argument("folder", help="a results folder of kvrod simulate, static, modes or sweep")
    pl.add_argument("--animate", nargs="?", const="gif", choices=("gif", "mp4"),
                    help="also animate a run's centreline: centreline.gif (default) or "
                         ".mp4 (needs ffmpeg on PATH)")
    pl.set_defaults(func=_cmd_plot)

    _ = parser_class
