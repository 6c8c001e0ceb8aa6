"""`kvrod simulate`, `kvrod static`, `kvrod plot` and `kvrod reproduce`."""

from __future__ import annotations

import contextlib
import math
import sys
from pathlib import Path

from kvrod.problem_args import add_problem_arguments, problem_from_args


def _progress(t_end: float, desc: str):
    """A tqdm bar over simulated time, redrawn at most every 0.2 s; returns (callback,
    close). Not shown when stderr is not a terminal."""
    from tqdm import tqdm

    bar = tqdm(total=round(t_end, 6), desc=desc, unit="s sim", leave=False, mininterval=0.2,
               disable=not sys.stderr.isatty(),
               bar_format="{desc}: {percentage:3.0f}%|{bar}| {n:.2f}/{total:.2f} s [{elapsed}]")
    step = t_end / 200.0
    last = [0.0]

    def update(t: float) -> None:
        if t - last[0] >= step or t >= t_end:
            last[0] = t
            bar.n = round(min(t, t_end), 6)
            bar.refresh() if not bar.disable else None

    return update, bar.close


def _already_finished(problem, out: Path) -> bool:
    """True when DIR holds a finished run of exactly this problem (and no checkpoint)."""
    import json

    from runtime.io.results import CHECKPOINT, jsonable

    path = out / "summary.json"
    if (out / CHECKPOINT).exists() or not path.exists():
        return False
    try:
        data = json.loads(path.read_text())
    except (OSError, ValueError):
        return False
    return (isinstance(data, dict) and data.get("status") == "finished"
            and data.get("parameters") == jsonable(problem.to_mapping()))


def run_and_write(problem, out: Path, label: str, plots: bool = False, resume: bool = False,
                  vtk_every: float | None = None, checkpoint_every: float = 1.0,
                  overwrite: bool = False, progress: bool = True) -> tuple:
    """Run one problem into results folder ``out`` and write its results.

    Everything that can be checked is checked before anything is written (parameters, the
    folder, an existing result, the checkpoint to resume, the generated code). Then the
    folder is locked (``.kvrod.lock``), ``summary.json`` says "running" (with t_reached)
    while the run goes and a checkpoint is written every ``checkpoint_every`` simulated
    seconds; when the run stops, ``summary.json`` says "finished", "failed" or
    "interrupted" (never "running", except after SIGKILL). ``resume`` continues from
    DIR/checkpoint.npz (VTK frames before the checkpoint are kept); ``overwrite`` replaces
    a finished result. Returns (result, summary).
    """
    from runtime.io import folder as F
    from runtime.io.results import (
        CHECKPOINT,
        jsonable,
        load_checkpoint,
        write_checkpoint,
        write_run,
        write_status,
    )
    from runtime.model import build
    from runtime.simulate.simulate import simulate

    out = Path(out)
    params = jsonable(problem.to_mapping())
    F.check_output_path(out)
    if not resume:
        F.refuse_existing(out, "simulate", overwrite=overwrite, resumable=True)
    state = load_checkpoint(out, params) if resume else None
    if state is not None:
        import numpy as np

        from generated import rod_layout
        from runtime.io.results import CheckpointError

        n = rod_layout.n_state(problem.rod.elements)
        for key in ("y", "yp"):
            if np.shape(state[key]) != (n,) or not np.all(np.isfinite(state[key])):
                raise CheckpointError(f"--resume: checkpoint {str(out / CHECKPOINT)!r} holds a "
                                      f"state {key} of shape {np.shape(state[key])}, this "
                                      f"problem needs ({n},) finite values; start again with "
                                      "--overwrite")
    build.require_generated()
    with F.claim(out, "simulate", overwrite=overwrite and not resume) as claimed:
        t_start = float(state["t"]) if state else 0.0
        write_status(out, params, "running", t_start)
        claimed.keep()

        def on_checkpoint(st):
            if series is not None:       # the frames so far survive a kill after this
                series.write_collection()
            write_checkpoint(out, params, st)
            write_status(out, params, "running", st["t"])

        series = None
        if vtk_every is not None:
            from runtime.io.vtk import VtkSeries
            from runtime.problem.assemble import build_model

            series = VtkSeries(out / "vtk", build_model(problem),
                               resume_from=t_start if state else None)
        cb, close = (_progress(problem.simulation.t_end, label) if progress
                     else (None, lambda: None))
        try:
            run = simulate(problem, progress=cb, checkpoint=on_checkpoint,
                           checkpoint_every=checkpoint_every, resume=state,
                           snapshot_every=vtk_every,
                           snapshot_sink=series.add if series else None)
        except BaseException as exc:   # a bug or resource error: say so, keep the checkpoint
            write_status(out, params, "failed", t_start, f"{type(exc).__name__}: {exc}")
            raise
        finally:
            close()
            if series is not None:
                series.close()
        extra = {"resumed_from_t": t_start} if state else None
        try:
            summary = write_run(out, run, extra=extra)
        except BaseException as exc:   # e.g. disk full: do not leave "running" behind
            with contextlib.suppress(Exception):
                write_status(out, params, "failed", run.t_last,
                             f"the results could not be written: {exc}")
            raise
        if run.status == "finished":
            (out / CHECKPOINT).unlink(missing_ok=True)
        if run.interrupt is not None:
            raise run.interrupt
        if plots and run.t.size > 1:
            from runtime.io.plots import plot_run

            plot_run(run, out)
    return run, summary


def _print_summary(s: dict, out: Path, vtk: bool, plots: bool) -> None:
    tip = s["static"]["tip"]
    if tip is not None:
        print(f"static tip [m]: {tip}  (Newton iterations: {s['static']['newton_iterations']})")
    if s.get("peaks"):
        z = s["damping_ratios"]
        print(f"maxima: {len(s['peaks'])}, damping ratios: {[round(v, 4) for v in z]}")
    lp = s.get("linear_prediction")
    if lp:
        print(f"linear prediction zeta_1 = omega_1 tau/2 = {lp['zeta_1']:.4f}")
    eb = s["energy_balance_max_rel"]
    print(f"energy balance max rel. error: {eb:.2e}" if eb is not None
          else f"energy balance: not applicable ({s['energy_audit']['note']})")
    print(f"counters: {s['counters']}, wall time {s['wall_time_s']:.2f} s")
    files = "summary.json, series.npz, problem.toml" + (", vtk/rod.pvd" if vtk else "") + (
        ", *.png" if plots else "")
    print(f"wrote {out}/ {files}")


def _cmd_simulate(args) -> int:
    from kvrod.cli import CliError

    if args.vtk is not None and not (math.isfinite(args.vtk) and args.vtk > 0):
        raise CliError(f"kvrod simulate: --vtk = {args.vtk} must be > 0 (seconds between "
                       "snapshots)")
    if args.resume and args.overwrite:
        raise CliError("kvrod simulate: --resume and --overwrite exclude each other")
    problem = problem_from_args(args, "simulate")
    if args.vtk is not None and problem.simulation.t_end / args.vtk > 100_000:
        raise CliError(f"kvrod simulate: --vtk = {args.vtk} would write "
                       f"{problem.simulation.t_end / args.vtk:.3g} frames (at most 100000; "
                       "t_end/--vtk)")
    out = Path(args.out) if args.out else Path("results") / problem.name
    if args.resume and _already_finished(problem, out):
        print(f"{out}: this run has already finished (summary.json); nothing to resume")
        return 0
    run, s = run_and_write(problem, out, problem.name, plots=args.plots, resume=args.resume,
                           vtk_every=args.vtk, overwrite=args.overwrite)
    _print_summary(s, out, args.vtk is not None, args.plots)
    for w in s.get("warnings", []):
        print(f"kvrod: warning: {w}", file=sys.stderr)
    if run.status != "finished":
        print(f"kvrod simulate: run {run.status}: {run.message}", file=sys.stderr)
        return 1
    return 0


def _cmd_static(args) -> int:
    """Static equilibrium of a problem under its loads at t = 0-: summary.json with the
    end positions and Newton iterations, static.npz with the state."""
    import time

    from kvrod.outputs import results_folder
    from runtime.io.results import jsonable, write_json, write_npz, write_problem
    from runtime.model import build
    from runtime.problem.assemble import build_model
    from runtime.simulate.simulate import static_equilibrium
    from runtime.solvers.statics import StaticSolveError

    problem = problem_from_args(args, "static")
    out = Path(args.out) if args.out else Path("results") / f"{problem.name}-static"
    build.require_generated()
    with results_folder(out, "static", markers=("summary.json",), overwrite=args.overwrite,
                        names=("summary.json", "static.npz", "problem.toml")):
        wall0 = time.perf_counter()
        model = build_model(problem)
        params = jsonable(problem.to_mapping())
        try:
            st = static_equilibrium(problem, model)
            status, message, y, its, per = "finished", "ok", st.y, st.iterations, st.per_step
        except StaticSolveError as exc:
            status, message, y, its, per = ("failed", f"static solve failed: {exc}", exc.y,
                                            sum(exc.iterations), list(exc.iterations))
        pos = model.positions(y)
        summary = {"status": status, "message": message, "problem": problem.name,
                   "parameters": params,
                   "static": {"tip": pos[:, -1].tolist(), "start": pos[:, 0].tolist(),
                              "newton_iterations": int(its),
                              "newton_iterations_per_load_step": per,
                              "wall_time_s": time.perf_counter() - wall0},
                   "backend": model.backend}
        write_npz(out / "static.npz", y=y, positions=pos, quaternions=model.quaternions(y),
                  reference=model.positions(model.reference))
        write_problem(out / "problem.toml", params)
        write_json(out / "summary.json", summary)
    print(f"static tip [m]: {summary['static']['tip']}  (Newton iterations: {its})")
    print(f"wrote {out}/ summary.json, static.npz, problem.toml")
    if status != "finished":
        print(f"kvrod static: {message}", file=sys.stderr)
        return 1
    return 0


def _cmd_plot(args) -> int:
    """Plots of a finished (or stopped) run folder, written next to its results."""
    from kvrod.cli import CliError
    from runtime.io.plots import plot_folder

    out = Path(args.folder)
    if not (out / "summary.json").exists() or not (out / "series.npz").exists():
        raise CliError(f"kvrod plot: {str(out)!r} holds no run (summary.json, series.npz)")
    paths = plot_folder(out)
    print(f"wrote {', '.join(str(p) for p in paths)}")
    return 0


def _cmd_reproduce(args) -> int:
    from kvrod.reproduce import reproduce

    out = reproduce(Path(args.out), n_elements=args.n_elements, t_end=args.t_end,
                    notes=Path(args.notes), rtol=args.rtol, derive=not args.skip_derive,
                    overwrite=args.overwrite)
    print(f"wrote {out}")
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
    s.set_defaults(func=_cmd_simulate)

    t = sub.add_parser("static", help="static equilibrium of a rod problem under its loads")
    add_problem_arguments(t)
    t.add_argument("--out", help="results folder (default results/<problem name>-static)")
    t.add_argument("--overwrite", action="store_true",
                   help="replace a finished result in --out (default: refuse)")
    t.set_defaults(func=_cmd_static)

    pl = sub.add_parser("plot", help="draw the PNG plots of a results folder")
    pl.add_argument("folder", help="a results folder of kvrod simulate")
    pl.set_defaults(func=_cmd_plot)

    r = sub.add_parser("reproduce", help="reproduce the paper's Sect. 5 (figures + notes)")
    r.add_argument("--out", default="results/reproduce", help="results folder")
    r.add_argument("--notes", default="notes/reproduction.md", help="notes file to write")
    r.add_argument("--n-elements", dest="n_elements", type=int, default=100)
    r.add_argument("--t-end", dest="t_end", type=float, default=10.0)
    r.add_argument("--rtol", type=float, default=1e-7,
                   help="relative tolerance (1e-7: energy audits below 1e-5; see the note)")
    r.add_argument("--overwrite", action="store_true",
                   help="replace the results of an earlier reproduction in --out")
    r.add_argument("--skip-derive", action="store_true",
                   help="do not regenerate notes/derivation.md")
    r.set_defaults(func=_cmd_reproduce)
    _ = parser_class
