"""`kvrod sweep STUDY.toml`: parameter studies on Dask.

By default the points run on a LocalCluster with one worker process per core; with
``--scheduler tcp://host:8786`` they run on an existing Dask cluster::

    dask scheduler                          # on the head node (port 8786)
    dask worker tcp://host:8786             # on every compute node (kvrod installed)
    kvrod sweep study.toml --scheduler tcp://host:8786 --out results/study
"""

from __future__ import annotations

import sys
import time
from pathlib import Path


class _ProgressBar:
    """A tqdm bar over the points to run, made when the run knows how many (on a
    terminal only; redrawn at most every 0.2 s, so a study of tiny points does not spend
    its time drawing)."""

    def __init__(self) -> None:
        self.bar = None

    def start(self, pr) -> None:
        if not sys.stderr.isatty():
            return
        from tqdm import tqdm

        self.bar = tqdm(total=pr.total - pr.skipped, desc="points", unit="pt",
                        dynamic_ncols=True, mininterval=0.2)
        self.bar.set_postfix_str(f"done 0, failed 0, skipped {pr.skipped}", refresh=False)
        self._drawn = 0.0

    def update(self, pr) -> None:
        if self.bar is None:
            return
        now = time.monotonic()
        self.bar.n = pr.done + pr.failed
        if now - self._drawn >= 0.2 or self.bar.n == self.bar.total:
            self._drawn = now
            self.bar.set_postfix_str(f"done {pr.done}, failed {pr.failed}, running "
                                     f"{pr.running}, queued {pr.queued}, skipped "
                                     f"{pr.skipped}", refresh=False)
            self.bar.refresh()

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


def _cmd_sweep(args) -> int:
    from kvrod.errors import CliError

    if args.workers is not None and args.workers < 1:
        raise CliError(f"kvrod sweep: --workers {args.workers} must be >= 1")
    if args.serial and args.scheduler:
        raise CliError("kvrod sweep: --serial and --scheduler exclude each other")
    import math

    from runtime.io import folder as F
    from runtime.study.sweep import StudyError, load_study

    try:
        study = load_study(args.study, max_points=math.inf if args.yes else None)
    except StudyError as exc:
        raise CliError(f"kvrod sweep: {exc}") from exc
    safe = "".join(ch if ch.isalnum() or ch in "-_." else "_" for ch in study.name)
    out = Path(args.out) if args.out else Path("results") / f"sweep-{safe}"
    F.check_output_path(out)
    holder = F.lock_holder(out)
    if holder is not None:
        raise CliError(f"kvrod sweep: results folder {str(out)!r} is in use by process "
                       f"{holder} (lock file {F.LOCK_NAME}); wait for it or choose another --out")
    saved = out / "study.toml"
    if saved.exists() and not args.overwrite:
        try:
            same = saved.read_text() == study.source
        except OSError:
            same = False
        if not same:
            raise CliError(f"kvrod sweep: {str(out)!r} holds a different study (study.toml); "
                           "use --overwrite to replace it or choose another --out")
    if not args.serial:           # the engine is importable before anything is written
        if not args.scheduler:    # our own workers' imports, on another core meanwhile
            from runtime.study.worker_boot import start_fork_server

            start_fork_server()   # stopped when this process exits
        import runtime.study.sweep_dask  # noqa: F401
    with F.claim(out, "sweep", overwrite=args.overwrite,
                 names=("study.toml", "study.csv", "progress.json", "summary.png",
                        "points", ".sweep-token")) as claimed:
        claimed.keep()
        return _run_sweep(args, study, out)


def _run_sweep(args, study, out: Path) -> int:
    from kvrod.errors import CliError

    n = len(study.points)
    where = ("serial (this process)" if args.serial else
             f"scheduler {args.scheduler}" if args.scheduler else
             f"LocalCluster, {args.workers or 'one per core'} worker processes")
    print(f"study {study.name!r}: {n} points of problem {study.problem!r} on {where}; "
          f"results in {out}", flush=True)
    bar = _ProgressBar()
    try:
        if args.serial:
            from runtime.study.sweep import run_study_serial

            report = run_study_serial(study, out, progress=bar.update, on_start=bar.start,
                                      rerun_failed=not args.keep_failed)
        else:
            from runtime.study.sweep_dask import run_study_dask

            def dashboard(link: str) -> None:
                from importlib.util import find_spec

                note = ("" if find_spec("bokeh") else
                        " (its pages need bokeh: pip install -e '.[sweep]')")
                print(f"Dask dashboard: {link}{note}", flush=True)

            try:
                report = run_study_dask(study, out, scheduler=args.scheduler,
                                        n_workers=args.workers, progress=bar.update,
                                        on_start=bar.start, on_dashboard=dashboard,
                                        rerun_failed=not args.keep_failed)
            except (OSError, TimeoutError) as exc:      # unreachable scheduler, no workers
                msg = " ".join(str(exc).split()) or type(exc).__name__
                raise CliError(f"kvrod sweep: Dask: {msg}") from exc
    finally:
        bar.close()
    print(f"{len(report.computed)} points run ({len(report.failed)} failed), "
          f"{len(report.skipped)} already finished, in {report.wall_time_s:.1f} s "
          f"[{report.engine}]")
    if report.timing_line():
        print(report.timing_line())
    print(f"wrote {out}/study.csv, {out}/points/<id>/summary.json, series.npz"
          + (f", {out}/summary.png" if (out / "summary.png").exists() else ""))
    if report.failed:
        print(f"kvrod sweep: {len(report.failed)} point(s) failed; see the 'message' column "
              f"of {out}/study.csv (run again on restart unless --keep-failed)",
              file=sys.stderr)
        return 1
    return 0


def add_commands(sub, parser_class) -> None:
    """Register `kvrod sweep` on the top-level subparsers."""
    s = sub.add_parser("sweep", help="run a parameter study (TOML) on Dask, local or cluster",
                       description=__doc__.splitlines()[0] if __doc__ else None)
    s.add_argument("study", help="study file (TOML: problem, [fixed], [grid] / [[points]])")
    s.add_argument("--scheduler", metavar="ADDRESS",
                   help="address of a running Dask scheduler, e.g. tcp://host:8786 "
                        "(default: start a LocalCluster on this machine)")
    s.add_argument("--workers", type=int, metavar="K",
                   help="LocalCluster worker processes (default: one per core); with "
                        "--scheduler: wait for K workers before starting")
    s.add_argument("--out", metavar="DIR",
                   help="study folder (default: results/sweep-<study name>)")
    s.add_argument("--serial", action="store_true",
                   help="run the points one after another in this process (no Dask)")
    s.add_argument("--keep-failed", action="store_true",
                   help="on restart, do not rerun points that failed before")
    s.add_argument("--yes", action="store_true",
                   help="run a study above 10000 points (refused otherwise)")
    s.add_argument("--overwrite", action="store_true",
                   help="replace a different study's results in --out (default: refuse)")
    s.set_defaults(func=_cmd_sweep)
    _ = parser_class
