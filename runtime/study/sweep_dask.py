"""The distributed engine of parameter studies: Dask ``distributed``.

By default a :class:`distributed.LocalCluster` with one single-threaded worker process
per core is started (nothing to set up); with ``scheduler="tcp://host:8786"`` a
:class:`distributed.Client` connects to an existing scheduler (``dask scheduler`` plus
``dask worker tcp://host:8786`` on the machines of a cluster).

Compiled code never travels: :class:`KvrodWorkerSetup`, a worker plugin, loads (and on
first use compiles) the generated kernels into each worker process's cache once, when the
worker starts (also on workers that join or are restarted later).

What scales (issue 33): a task is a *batch* of points (:func:`runtime.study.sweep.run_batch`)
sized from the points' measured CPU times to last about :func:`task_seconds` (short points
are batched, long ones go one per task), shrinking towards the end so that the workers
finish together (guided self-scheduling: never more than a 1/(2 x slots) share of what
is left). Tasks are made as workers free up, a few per worker slot ahead, never the
whole study at once: a study of 10^9 points starts at once and holds memory of its
in-flight batches only. A worker that sees the study folder (the client's token file
there, :data:`runtime.study.sweep.TOKEN_NAME`) writes each point's folder itself and
returns only the table rows; one that does not (no shared file system) returns the files
as bytes for the client to write. The client appends rows to ``study.csv`` and counts.

A worker that dies mid-task loses nothing: the scheduler reschedules its task on the
other workers (points the dead worker had finished are found finished and not run
again); a batch that fails as a whole (e.g. a point that kills its worker repeatedly,
``distributed.scheduler.allowed-failures``) is split into single-point tasks, so only
the culprit is recorded as a failed point. Ctrl-C (or any error) cancels the queued
tasks and removes the token file, so a batch being run stops after its current point;
rows of points written meanwhile are added to the table when the run closes.
"""

from __future__ import annotations

import asyncio
import collections
import contextlib
import logging
import math
import os
import time
import uuid
from collections.abc import Callable, Iterator
from pathlib import Path

from distributed import Client, LocalCluster, WorkerPlugin, as_completed

from runtime.io.atomic import write_text
from runtime.signals import held_signals
from runtime.study import worker_boot
from runtime.study.points import StudyPoint
from runtime.study.sweep import (
    TOKEN_NAME,
    PointResult,
    Study,
    StudyRecorder,
    StudyReport,
    SweepProgress,
    failure_outcome,
    run_batch,
    table_row,
    write_point,
)

#: a task's target duration (s) on a small cluster; larger clusters get longer tasks so
#: that the scheduler handles at most :data:`TASKS_PER_SECOND` of them
TASK_SECONDS = 0.5
TASKS_PER_SECOND = 200.0
#: most points in one task, and tasks kept submitted per worker slot
MAX_BATCH = 1000
AHEAD = 2
#: Dask settings of the LocalCluster a sweep starts: its processes' housekeeping at
#: rest (measured, 2-worker cluster: 80 ms of CPU a second with Dask's defaults, 15 ms
#: with these), which on a machine whose cores all run points is taken from the points.
#: No statistical profiler in the workers (a stack sample every 10 ms: the dashboard's
#: profile page stays empty), the event loop's latency check every second instead of
#: every 20 ms, system and worker-memory monitors every 2 s and 1 s (instead of 0.5 s and
#: 0.1 s). Clusters started otherwise keep their own settings (docs/sweeps.md).
LOCAL_CLUSTER_CONFIG = {"distributed.worker.profile.enabled": False,
                        "distributed.admin.tick.interval": "1s",
                        "distributed.admin.system-monitor.interval": "2s",
                        "distributed.worker.memory.monitor-interval": "1s"}


class KvrodWorkerSetup(WorkerPlugin):
    """Worker plugin: compile/load the generated kernels once per worker process (a
    worker forked from the fork server has them already: then this costs nothing)."""

    name = "kvrod-setup"
    idempotent = True

    async def setup(self, worker) -> None:  # noqa: D401 - WorkerPlugin API
        """Run :func:`runtime.study.worker_boot.warm_up` off the event loop (compiling
        takes a few seconds)."""
        loop = asyncio.get_running_loop()
        await loop.run_in_executor(None, worker_boot.warm_up)


def task_seconds(slots: int) -> float:
    """Target duration of one task (s) for ``slots`` worker threads: TASK_SECONDS, longer
    on a cluster whose workers would otherwise return more than TASKS_PER_SECOND tasks."""
    return max(TASK_SECONDS, slots / TASKS_PER_SECOND)


class BatchPlanner:
    """Hands out the points to run in batches (see the module docstring).

    ``points``: (position, point) pairs to run, made as asked for; ``n``: how many.
    The batch size is 1 until a point's time is known, then
    ``min(task_seconds / point time, what is left / (2 slots), MAX_BATCH)``, at least 1.
    A point's time is the CPU time its worker spent on it: on a machine whose cores are
    shared with other work the wall time stretches, the tasks would shrink and Dask's
    cost per task (milliseconds of CPU in the scheduler and the worker) would grow with
    their number. Points given back (:meth:`retry`) go first, one per task.
    """

    def __init__(self, points: Iterator[tuple[int, StudyPoint]], n: int) -> None:
        self._points = points
        self.left = n                 # points not handed out yet (retries not counted)
        self._retry: collections.deque[tuple[int, StudyPoint]] = collections.deque()
        self.point_seconds: float | None = None   # running mean of the points' times

    def observe(self, seconds: float) -> None:
        """A point's measured time (s) on a worker."""
        a = self.point_seconds
        self.point_seconds = seconds if a is None else 0.8 * a + 0.2 * seconds

    def size(self, slots: int) -> int:
        """Points in the next batch."""
        if self.point_seconds is None:
            return 1
        by_time = task_seconds(slots) / max(self.point_seconds, 1e-6)
        guided = math.ceil(self.left / (2 * max(slots, 1)))
        return max(1, min(int(by_time), guided, MAX_BATCH))

    def retry(self, points: list[tuple[int, StudyPoint]]) -> None:
        """Points of a batch that did not come back: run again, one per task."""
        self._retry.extend(points)

    def next(self, slots: int) -> list[tuple[int, StudyPoint]]:
        """The next batch ([] when every point has been handed out)."""
        if self._retry:
            return [self._retry.popleft()]
        batch = []
        for _ in range(self.size(slots)):
            item = next(self._points, None)
            if item is None:
                break
            batch.append(item)
        self.left -= len(batch)
        return batch


def default_workers() -> int:
    """Worker processes of the default LocalCluster: one per core."""
    return max(1, os.cpu_count() or 1)


def start_local_cluster(n_workers: int | None = None) -> LocalCluster:
    """A LocalCluster of single-threaded worker processes (scheduler and dashboard on free
    ports) that leave Ctrl-C to this process: forked from this process's fork server
    where :func:`runtime.study.worker_boot.start_method` allows (a caller keeps
    :func:`runtime.study.worker_boot.cluster_config` set for the cluster's lifetime so
    that restarted workers are forked too), else spawned."""
    # silence_logs: the workers log a warning for every task cancelled by an interrupted
    # study, and, when the cluster closes (at the end or after Ctrl-C), a worker whose
    # heartbeat meets the scheduler already gone logs an ERROR with two tracebacks
    # ("Failed to communicate with scheduler during heartbeat": a race, ~1 close in 10
    # here). Nothing a worker logs is the user's only news of a failure: a point's error,
    # a killed worker and a timeout come back through its future and go to study.csv
    # with their message, so the workers of our own cluster log only what is critical
    import dask

    start = worker_boot.cluster_config()
    if start:
        # our fork server runs already with its own preload list: distributed's first
        # forkserver context would otherwise import every optional package it knows
        # (pandas, ...) in this process only to set a list that no longer matters
        import distributed.utils

        distributed.utils._forkserver_preload_set = True
    # spawned workers take this process's SIGINT disposition, forked ones the fork
    # server's (ignored); either way this process ignores SIGINT while the cluster starts
    # (a second or so: the fork server never compiles): a LocalCluster interrupted half
    # started cannot be closed cleanly (distributed's own tracebacks at exit)
    with worker_boot.children_ignore_sigint(), \
            dask.config.set({**LOCAL_CLUSTER_CONFIG, **start}):
        return LocalCluster(n_workers=n_workers or default_workers(), threads_per_worker=1,
                            processes=True, dashboard_address=":0", scheduler_port=0,
                            silence_logs=logging.CRITICAL)


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


def dashboard_link(client: Client) -> str | None:
    """The address of the Dask dashboard of ``client``'s scheduler, or None."""
    try:
        return client.dashboard_link or None
    except (AttributeError, KeyError, ValueError):
        return None


class _Feeder:
    """The client's loop state: tasks in flight, their points, the time it works."""

    def __init__(self, client: Client, study: Study, rec: StudyRecorder, token: str,
                 timeout: float | None) -> None:
        self.client, self.study, self.rec, self.token = client, study, rec, token
        self.plan = BatchPlanner(rec.todo(), rec.n_todo)
        self.batches: dict[str, list[tuple[int, StudyPoint]]] = {}
        # with_results: the results come over while the client records the previous ones
        self.done = as_completed(loop=client.loop, timeout=timeout, with_results=True,
                                 raise_errors=False)
        self.slots = 1
        self._slots_at = -math.inf
        self._out = str(rec.out.resolve())
        self._tag = uuid.uuid4().hex[:8]
        self.tasks = 0

    def refresh_slots(self) -> None:
        """Worker threads now (workers join and leave); asked at most every 5 s (a
        round trip to the scheduler)."""
        now = time.monotonic()
        if now - self._slots_at >= 5.0:
            self._slots_at = now
            self.slots = max(1, sum(self.client.nthreads().values()))
            self.rec.slots = self.slots

    def fill(self) -> None:
        """Submit batches until AHEAD per worker slot are in flight."""
        self.refresh_slots()
        while len(self.batches) < AHEAD * self.slots:
            batch = self.plan.next(self.slots)
            if not batch:
                return
            self.tasks += 1
            f = self.client.submit(
                run_batch, self.study.problem, [(p.id, p.params) for _, p in batch],
                self.study.param_columns, self._out, self.token,
                key=f"kvrod-batch-{self._tag}-{self.tasks}", pure=False)
            self.batches[f.key] = batch
            self.done.add(f)
            self.rec.mark_running(batch)

    def take(self, future, results) -> Iterator[SweepProgress]:
        """Record the points of a returned task (progress after each)."""
        batch = self.batches.pop(future.key)
        if future.status == "finished":
            back = {r.point_id for r in results}
            for r in results:
                self.plan.observe(r.cpu_s or r.wall_time_s)
                yield self.rec.record(r)
            # a batch stops early only when the token file went away: run the rest again
            self.plan.retry([item for item in batch if item[1].id not in back])
        elif len(batch) > 1:           # split: only the culprit should fail
            self.plan.retry(batch)
        else:
            exc = future.exception() if future.status == "error" else None
            msg = (f"task error: {type(exc).__name__}: {exc}" if exc is not None
                   else f"task {future.status}")
            yield self.rec.record(_failed(self.study, self.rec.out, batch[0][1], msg))
        future.release()

    def cancel(self) -> None:
        with _quiet_distributed():
            for f in list(self.done.futures):
                if not f.done():
                    f.cancel()


def _failed(study: Study, out: Path, point: StudyPoint, message: str) -> PointResult:
    """A point whose task could not run: a failed summary, written by the client."""
    outcome = failure_outcome(study.problem, point, message)
    summary = write_point(out, outcome)
    return PointResult(point.id, summary["status"], table_row(study, point, summary), 0.0)


def run_study_dask(study: Study, out: Path, *, client: Client | None = None,
                   scheduler: str | None = None, n_workers: int | None = None,
                   progress: Callable[[SweepProgress], object] | None = None,
                   rerun_failed: bool = True, plots: bool = True,
                   plot_interval: float = 10.0, connect_timeout: float = 30.0,
                   wait_timeout: float = 300.0, timeout: float | None = None,
                   on_start: Callable[[SweepProgress], object] | None = None,
                   on_dashboard: Callable[[str], object] | None = None) -> StudyReport:
    """Run a study on Dask; returns the :class:`runtime.study.sweep.StudyReport`.

    client: an existing Client (tests); else scheduler: address of an existing scheduler
    (n_workers, if given, is the number of workers to wait for); else a LocalCluster with
    n_workers processes (default one per core) is started and closed at the end.
    ``on_start(SweepProgress)`` is called once the resume scan is done,
    ``on_dashboard(link)`` with the Dask dashboard's address once connected, and
    ``progress(SweepProgress)`` after every returned point. Finished points in ``out``
    are skipped; failed ones are run again unless rerun_failed is False.
    connect_timeout (s) bounds connecting to a scheduler, wait_timeout (s) waiting for
    n_workers of its workers; timeout (s), if given, bounds the whole study
    (TimeoutError). On KeyboardInterrupt (or any error) the outstanding tasks are
    cancelled, running batches stop after their current point, and the table gets the
    rows of the points written before the exception propagates.
    """
    t0 = time.perf_counter()
    rec = StudyRecorder(study, out, rerun_failed=rerun_failed, plots=plots,
                        plot_interval=plot_interval)
    own_cluster = own_client = None
    engine = "dask (no points to run)"
    token_file = rec.out / TOKEN_NAME
    feeder: _Feeder | None = None
    interrupted = False
    lifetime = contextlib.ExitStack()          # settings held until the cluster closed
    try:
        if on_start is not None:
            on_start(rec.progress)
        if rec.n_todo:
            if client is None:
                if scheduler is not None:
                    engine = f"dask scheduler {scheduler}"
                    client = own_client = Client(scheduler, timeout=connect_timeout)
                    if n_workers:
                        client.wait_for_workers(n_workers, timeout=wait_timeout)
                else:
                    import dask

                    # restarted workers start as the first ones did (cluster_config)
                    lifetime.enter_context(dask.config.set(worker_boot.cluster_config()))
                    method = worker_boot.start_method()
                    own_cluster = start_local_cluster(n_workers)
                    engine = (f"dask LocalCluster ({len(own_cluster.workers)} workers, "
                              f"{method})")
                    with dask.config.set(LOCAL_CLUSTER_CONFIG):
                        client = own_client = Client(own_cluster)
            else:
                engine = f"dask client {client.scheduler.address}"
            rec.mark("engine")
            link = dashboard_link(client)
            if on_dashboard is not None and link:
                on_dashboard(link)
            client.register_plugin(KvrodWorkerSetup())
            token = uuid.uuid4().hex
            write_text(token_file, token)
            feeder = _Feeder(client, study, rec, token, timeout)
            busy = time.perf_counter()
            feeder.fill()
            while feeder.batches:
                rec.report.client_seconds += time.perf_counter() - busy
                ready = feeder.done.next_batch(block=True)
                busy = time.perf_counter()
                for future, result in ready:
                    for pr in feeder.take(future, result):
                        if progress is not None:
                            progress(pr)
                feeder.fill()
                if feeder.batches:           # once the workers have their tasks again
                    rec.refresh_plots()      # (after the last point: close() draws)
            rec.report.client_seconds += time.perf_counter() - busy
    except BaseException:
        interrupted = True
        if feeder is not None:
            feeder.cancel()
        raise
    finally:
        with contextlib.suppress(OSError):
            token_file.unlink(missing_ok=True)       # running batches stop
        # a Ctrl-C amid the close would leave the cluster half closed, for distributed's
        # exit handler to wait 10 s on: it is held until the cluster is closed and the
        # table complete (a fraction of a second), then delivered
        with held_signals():
            with lifetime, _quiet_distributed() if interrupted else contextlib.nullcontext():
                if own_client is not None:
                    own_client.close()
                if own_cluster is not None:
                    own_cluster.close()
            report = rec.close()
    report.wall_time_s = time.perf_counter() - t0
    report.engine = engine
    report.tasks = feeder.tasks if feeder is not None else 0
    return report
