"""The distributed engine of parameter studies: Dask ``distributed``.

By default a :class:`distributed.LocalCluster` with one single-threaded worker process
per core is started (nothing to set up); with ``scheduler="tcp://host:8786"`` a
:class:`distributed.Client` connects to an existing scheduler (``dask scheduler`` plus
``dask worker tcp://host:8786`` on the machines of a cluster).

Compiled code never travels: :class:`KvrodWorkerSetup`, a worker plugin, loads (and on
first use compiles) the generated kernels into each worker process's cache once, when the
worker starts (also on workers that join or are restarted later). Tasks ship a parameter
dict to :func:`runtime.study.sweep.run_point` and get back a
:class:`runtime.study.sweep.PointOutcome`;
the client writes the point folders, so workers need no shared file system.

A worker that dies mid-task loses nothing: the scheduler reschedules its tasks on the
other workers; a task that kills workers repeatedly (``distributed.scheduler.allowed-
failures``) comes back as an error and is recorded as a failed point. Every point is
written once by the client as its result arrives, and the table is rebuilt from the
per-point summaries at the end, so it holds every point exactly once.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import os
import signal
import threading
import time
import uuid
from collections.abc import Callable, Iterator
from pathlib import Path

from distributed import Client, LocalCluster, WorkerPlugin, as_completed

from runtime.study.sweep import (
    PointOutcome,
    Study,
    StudyRecorder,
    StudyReport,
    SweepProgress,
    failure_outcome,
    run_point,
)


def warm_up() -> dict:
    """Load (compiling on first use) the generated kernels in this process.

    Returns {"pid", "library"} for diagnostics; ``library`` is None when the in-process
    CasADi fallback is used (no C compiler).
    """
    import runtime.simulate.simulate  # noqa: F401 - pay the import once, not in the first task
    from runtime.model import build

    lib = build.load_library()
    try:  # compiled BDF helpers, when this checkout has them
        from runtime.solvers.native import loader

        loader.load()
    except (ImportError, AttributeError):
        pass
    return {"pid": os.getpid(), "library": None if lib is None else str(lib._name)}


class KvrodWorkerSetup(WorkerPlugin):
    """Worker plugin: compile/load the generated kernels once per worker process."""

    name = "kvrod-setup"
    idempotent = True

    async def setup(self, worker) -> None:  # noqa: D401 - WorkerPlugin API
        """Run :func:`warm_up` off the event loop (compiling takes a few seconds)."""
        loop = asyncio.get_running_loop()
        await loop.run_in_executor(None, warm_up)


def _outcome(study: Study, point, future) -> PointOutcome:
    """The task's PointOutcome, or a failed one when the task errored (e.g. KilledWorker)."""
    if future.status == "finished":
        outcome = future.result()
        if isinstance(outcome, PointOutcome):
            return outcome
        return failure_outcome(study.problem, point, f"unexpected task result {outcome!r}")
    if future.status == "error":
        exc = future.exception()
        return failure_outcome(study.problem, point, f"task error: {type(exc).__name__}: {exc}")
    return failure_outcome(study.problem, point, f"task {future.status}")


def default_workers() -> int:
    """Worker processes of the default LocalCluster: one per core."""
    return max(1, os.cpu_count() or 1)


@contextlib.contextmanager
def _children_ignore_sigint() -> Iterator[None]:
    """Start child processes with SIGINT ignored (an ignored disposition survives exec,
    and Python then installs no KeyboardInterrupt handler): Ctrl-C in the terminal reaches
    the whole process group, and the workers would each print a traceback. Only this
    process handles it, cancels the tasks and closes the cluster."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


def start_local_cluster(n_workers: int | None = None) -> LocalCluster:
    """A LocalCluster of single-threaded worker processes (scheduler and dashboard on free
    ports) that leave Ctrl-C to this process."""
    # silence_logs: the workers log a warning for every task cancelled by an interrupted
    # study; keep their logs to errors
    with _children_ignore_sigint():
        return LocalCluster(n_workers=n_workers or default_workers(), threads_per_worker=1,
                            processes=True, dashboard_address=":0", scheduler_port=0,
                            silence_logs=logging.ERROR)


@contextlib.contextmanager
def _quiet_distributed() -> Iterator[None]:
    """Silence distributed's loggers while a cluster is torn down after an interrupt."""
    loggers = [logging.getLogger(n) for n in ("distributed", "tornado", "asyncio")]
    levels = [lg.level for lg in loggers]
    for lg in loggers:
        lg.setLevel(logging.CRITICAL)
    try:
        yield
    finally:
        for lg, lv in zip(loggers, levels, strict=True):
            lg.setLevel(lv)


def run_study_dask(study: Study, out: Path, *, client: Client | None = None,
                   scheduler: str | None = None, n_workers: int | None = None,
                   progress: Callable[[SweepProgress], object] | None = None,
                   rerun_failed: bool = True, plots: bool = True,
                   plot_interval: float = 10.0, connect_timeout: float = 30.0,
                   wait_timeout: float = 300.0,
                   timeout: float | None = None) -> StudyReport:
    """Run a study on Dask; returns the :class:`runtime.study.sweep.StudyReport`.

    client: an existing Client (tests); else scheduler: address of an existing scheduler
    (n_workers, if given, is the number of workers to wait for); else a LocalCluster with
    n_workers processes (default one per core) is started and closed at the end.
    progress(SweepProgress) is called after every returned point. Finished points in
    ``out`` are skipped; failed ones are run again unless rerun_failed is False.
    connect_timeout (s) bounds connecting to a scheduler, wait_timeout (s) waiting for
    n_workers of its workers;
    timeout (s), if given, bounds the whole study (TimeoutError).
    On KeyboardInterrupt (or any error) the outstanding tasks are cancelled and the table
    is rebuilt from the per-point summaries before the exception propagates.
    """
    t0 = time.perf_counter()
    rec = StudyRecorder(study, out, rerun_failed=rerun_failed, plots=plots,
                        plot_interval=plot_interval)
    own_cluster = own_client = None
    engine = "dask (no points to run)"
    futures = []
    interrupted = False
    try:
        if rec.todo:
            if client is None:
                if scheduler is not None:
                    engine = f"dask scheduler {scheduler}"
                    client = own_client = Client(scheduler, timeout=connect_timeout)
                    if n_workers:
                        client.wait_for_workers(n_workers, timeout=wait_timeout)
                else:
                    own_cluster = start_local_cluster(n_workers)
                    engine = f"dask LocalCluster ({len(own_cluster.workers)} workers)"
                    client = own_client = Client(own_cluster)
            else:
                engine = f"dask client {client.scheduler.address}"
            client.register_plugin(KvrodWorkerSetup())
            rec.slots = sum(client.nthreads().values()) or None
            tag = uuid.uuid4().hex[:8]
            by_key = {}
            for p in rec.todo:
                f = client.submit(run_point, study.problem, p.id, p.params,
                                  key=f"kvrod-point-{p.id}-{tag}", pure=False)
                by_key[f.key] = p
                futures.append(f)
            rec.mark_running(p.id for p in rec.todo)
            for f in as_completed(futures, timeout=timeout):
                outcome = _outcome(study, by_key[f.key], f)
                f.release()
                pr = rec.record(outcome)
                if progress is not None:
                    progress(pr)
    except BaseException:
        interrupted = True
        with _quiet_distributed():
            for f in futures:
                if not f.done():
                    f.cancel()
        raise
    finally:
        report = rec.close()
        with _quiet_distributed() if interrupted else contextlib.nullcontext():
            if own_client is not None:
                own_client.close()
            if own_cluster is not None:
                own_cluster.close()
    report.wall_time_s = time.perf_counter() - t0
    report.engine = engine
    return report
