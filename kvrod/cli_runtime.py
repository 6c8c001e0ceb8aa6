"""`kvrod simulate` and `kvrod reproduce` (the runtime side of the CLI)."""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path


def _progress(t_end: float, desc: str):
    """A tqdm bar over simulated time; returns (callback, close)."""
    from tqdm import tqdm

    bar = tqdm(total=round(t_end, 6), desc=desc, unit="s sim", leave=False,
               bar_format="{desc}: {percentage:3.0f}%|{bar}| {n:.2f}/{total:.2f} s [{elapsed}]")

    def update(t: float) -> None:
        bar.n = round(min(t, t_end), 6)
        bar.refresh() if bar.n >= t_end or int(t * 20) != int((t - 1e-9) * 20) else None

    return update, bar.close


def scenario_from_args(args):
    """Scenario from defaults <- config file (--config) <- command-line flags."""
    from runtime.config import load_config
    from runtime.scenarios import CantileverScenario

    kw: dict = {}
    if getattr(args, "config", None):
        name, kw = load_config(Path(args.config))
        if args.scenario is not None and args.scenario != name:
            from kvrod.cli import CliError

            raise CliError(f"kvrod simulate: scenario {args.scenario!r} on the command line "
                           f"but {name!r} in {args.config}")
    if args.tau is not None:
        kw.update(tau_S=args.tau, tau_B=args.tau)
    for name in ("tau_S", "tau_B"):
        if getattr(args, name) is not None:
            kw[name] = getattr(args, name)
    for name, attr in (("youngs_modulus", "E"), ("tip_force", "tip_force"),
                       ("n_elements", "n_elements"), ("t_end", "t_end"), ("rtol", "rtol"),
                       ("damping", "damping"), ("poisson_ratio", "nu"),
                       ("max_order", "max_order")):
        v = getattr(args, attr)
        if v is not None:
            kw[name] = v
    return CantileverScenario(**kw)


def run_and_write(scenario, out: Path, label: str, plots: bool = True, resume: bool = False,
                  vtk_every: float | None = None, checkpoint_every: float = 1.0,
                  overwrite: bool = False, progress: bool = True) -> tuple:
    """Run one scenario into results folder ``out`` and write its results.

    Everything that can be checked is checked before anything is written (parameters, the
    folder, an existing result, the checkpoint to resume, the generated code). Then the
    folder is locked (``.kvrod.lock``), ``summary.json`` says "running" (with t_reached)
    while the run goes and a checkpoint is written every simulated second; when the run
    stops, ``summary.json`` says "finished", "failed" or "interrupted" (never "running",
    except after SIGKILL). ``resume`` continues from DIR/checkpoint.npz (VTK frames before
    the checkpoint are kept); ``overwrite`` replaces a finished result.
    """
    from dataclasses import asdict

    from runtime.io import folder as F
    from runtime.io.results import (
        CHECKPOINT,
        load_checkpoint,
        write_checkpoint,
        write_run,
        write_status,
    )
    from runtime.model import build
    from runtime.scenarios import run_cantilever

    out = Path(out)
    params = {**asdict(scenario), "tau_E": scenario.tau_E}
    F.check_output_path(out)
    if not resume:
        F.refuse_existing(out, "simulate", overwrite=overwrite, resumable=True)
    state = load_checkpoint(out, params) if resume else None
    build.require_generated()
    with F.claim(out, "simulate", overwrite=overwrite and not resume) as claimed:
        t_start = float(state["t"]) if state else 0.0
        write_status(out, params, "running", t_start)
        claimed.keep()

        def on_checkpoint(run, st):
            write_checkpoint(out, params, st)
            write_status(out, params, "running", st["t"])

        series = None
        if vtk_every is not None:
            from runtime.io.vtk import VtkSeries
            from runtime.model.rod import RodModel

            series = VtkSeries(out / "vtk", RodModel(scenario.rod_parameters(),
                                                     tip_force=(scenario.tip_force, 0, 0)),
                               resume_from=t_start if state else None)
        cb, close = _progress(scenario.t_end, label) if progress else (None, lambda: None)
        try:
            run = run_cantilever(scenario, progress=cb, checkpoint=on_checkpoint,
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
        summary = write_run(out, run, extra=extra)
        if run.status == "finished":
            (out / CHECKPOINT).unlink(missing_ok=True)
        if run.interrupt is not None:
            raise run.interrupt
        if plots and run.t.size > 1:
            from runtime.io import plots as P

            P.plot_tip([run], [label], out / "tip.png")
            P.plot_energy(run, out / "energy.png")
            if run.peaks_x.size >= 2:
                P.plot_damping_vs_amplitude([run], [label],
                                            [scenario.linear_prediction()["zeta_1"]],
                                            out / "damping_ratio.png")
    return run, summary


def _already_finished(scenario, out: Path) -> bool:
    """True when DIR holds a finished run of exactly these parameters (and no checkpoint)."""
    import json
    from dataclasses import asdict

    from runtime.io.results import CHECKPOINT, jsonable

    path = out / "summary.json"
    if (out / CHECKPOINT).exists() or not path.exists():
        return False
    try:
        data = json.loads(path.read_text())
    except (OSError, ValueError):
        return False
    wanted = jsonable({**asdict(scenario), "tau_E": scenario.tau_E})
    return data.get("status") == "finished" and data.get("parameters") == wanted


def _cmd_simulate(args) -> int:
    from kvrod.cli import CliError

    if args.scenario is not None and args.scenario != "cantilever":
        raise CliError(f"kvrod simulate: unknown scenario {args.scenario!r}; "
                       "scenarios are: cantilever")
    if args.scenario is None and not args.config:
        raise CliError("kvrod simulate: name a scenario (cantilever) or give --config FILE")
    if args.vtk is not None and not (math.isfinite(args.vtk) and args.vtk > 0):
        raise CliError(f"kvrod simulate: --vtk = {args.vtk} must be > 0 (seconds between "
                       "snapshots)")
    if args.resume and args.overwrite:
        raise CliError("kvrod simulate: --resume and --overwrite exclude each other")
    sc = scenario_from_args(args)
    if args.vtk is not None and sc.t_end / args.vtk > 100_000:
        raise CliError(f"kvrod simulate: --vtk = {args.vtk} would write "
                       f"{sc.t_end / args.vtk:.3g} frames (at most 100000; t_end/--vtk)")
    out = Path(args.out)
    if args.resume and _already_finished(sc, out):
        print(f"{out}: this run has already finished (summary.json); nothing to resume")
        return 0
    run, s = run_and_write(sc, out, "cantilever", resume=args.resume, vtk_every=args.vtk,
                           overwrite=args.overwrite)
    tip = s["static"]["tip"]
    print(f"static tip [m]: {tip}  (Newton iterations: {s['static']['newton_iterations']})")
    z = s["damping_ratios"]
    print(f"maxima: {len(s['peaks'])}, damping ratios: {[round(v, 4) for v in z]}")
    print(f"linear prediction zeta_1 = omega_1 tau/2 = {s['linear_prediction']['zeta_1']:.4f}")
    eb = s["energy_balance_max_rel"]
    print(f"energy balance max rel. error: {eb:.2e}" if eb is not None
          else "energy balance: not applicable (no energy in the run)")
    print(f"counters: {s['counters']}, wall time {s['wall_time_s']:.2f} s")
    print(f"wrote {out}/summary.json, series.npz, *.png" + (", vtk/rod.pvd" if args.vtk else ""))
    for w in s.get("warnings", []):
        print(f"kvrod: warning: {w}", file=sys.stderr)
    if run.status != "finished":
        print(f"kvrod simulate: run {run.status}: {run.message}", file=sys.stderr)
        return 1
    return 0


def _cmd_reproduce(args) -> int:
    from kvrod.reproduce import reproduce

    out = reproduce(Path(args.out), n_elements=args.n_elements, t_end=args.t_end,
                    notes=Path(args.notes), rtol=args.rtol, derive=not args.skip_derive,
                    overwrite=args.overwrite)
    print(f"wrote {out}")
    return 0


def add_commands(sub, parser_class) -> None:
    s = sub.add_parser("simulate", help="run a scenario (the paper's damped cantilever)")
    s.add_argument("scenario", nargs="?", help="scenario name: cantilever")
    s.add_argument("--config", help="TOML file with the scenario parameters (flags override)")
    s.add_argument("--resume", action="store_true",
                   help="continue from DIR/checkpoint.npz of an interrupted run")
    s.add_argument("--vtk", type=float, metavar="DT",
                   help="write ParaView VTK (.vtp + .pvd) every DT seconds")
    s.add_argument("--tau", type=float, help="tau_S = tau_B = tau_E [s] (paper: 0.04)")
    s.add_argument("--tau-S", dest="tau_S", type=float, help="shear retardation time [s]")
    s.add_argument("--tau-B", dest="tau_B", type=float, help="bulk retardation time [s]")
    s.add_argument("--E", type=float, help="Young's modulus [Pa] (paper: 1e6)")
    s.add_argument("--nu", type=float, help="Poisson's ratio [-] (paper: 0.3)")
    s.add_argument("--tip-force", dest="tip_force", type=float, help="dead tip force [N]")
    s.add_argument("--n-elements", dest="n_elements", type=int, help="elements (default 50)")
    s.add_argument("--t-end", dest="t_end", type=float, help="simulated time [s] (10)")
    s.add_argument("--rtol", type=float, help="relative tolerance (1e-6)")
    s.add_argument("--max-order", dest="max_order", type=int,
                   help="highest BDF order 1-5 (default 5)")
    s.add_argument("--damping", choices=("consistent", "naive"),
                   help="extensional viscosity eta_E (consistent) or eta~_E (naive)")
    s.add_argument("--out", default="results/cantilever", help="results folder")
    s.add_argument("--overwrite", action="store_true",
                   help="replace a finished result in --out (default: refuse)")
    s.set_defaults(func=_cmd_simulate)

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
    _ = argparse  # parser_class is used by the caller's subparsers
    _ = parser_class
