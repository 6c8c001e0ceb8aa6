"""How the worker processes of a sweep's own LocalCluster start, without importing Dask.

A worker process started the default way (``spawn``: a new interpreter) imports Dask's
``distributed``, NumPy, SciPy and kvrod's runtime and loads the compiled kernels, about
0.7 s of CPU each, all at once when the cluster starts; on a machine of 16 cores that is
16 interpreters reading the same files while nothing runs, and on 2 cores it delays the
first points by a second. Instead the sweep starts a *fork server* (Python's
``forkserver`` start method) as its first act, before its own (client's) import of
Dask: one process that imports all of it once, loads the kernels (:func:`warm_up`), and
then forks a worker in milliseconds whenever the cluster asks for one. It works on a
core of its own while the client imports Dask, and the workers start with the kernels
loaded. Measured here (2 workers, 40 tiny points, whole ``kvrod sweep``): the cluster
ready at 0.7-0.8 s instead of 1.0 s, and closed in 0.03 s instead of 0.25 s.

The fork server starts with the environment a Dask nanny gives a worker it spawns
(``distributed.nanny.pre-spawn-environ``: one BLAS and OpenMP thread, glibc's trim
threshold, a fixed hash seed; :func:`dask_pre_spawn_environ`), so that NumPy, imported
there once, keeps one thread in every worker as it would after ``spawn``.

Only our own LocalCluster uses it (workers you start on a cluster keep their own way), and
only where the platform has ``forkserver`` (Linux, macOS) and kvrod's own environment
variables (``KVROD_*``: the kernel cache folder, ``KVROD_NO_COMPILER``, ...) are what they
were when this process started the fork server: a forked worker has the server's
environment and the kernels it loaded with it, so a process whose ``KVROD_*`` variables
have changed since (a test, a library user) starts its workers with ``spawn``, as before.
A worker restarted by its nanny (after it died) is spawned.
"""

from __future__ import annotations

import contextlib
import multiprocessing
import os
import signal
import threading
from collections.abc import Iterator, Mapping
from pathlib import Path

#: modules the fork server imports before it forks any worker: Dask's worker side and
#: the module whose import loads the kernels (:mod:`runtime.study.worker_preload`)
PRELOAD = ("distributed", "runtime.study.sweep", "runtime.study.worker_preload")
#: the hash seed a Dask nanny gives a worker when none is set (distributed.nanny.Nanny)
DASK_HASH_SEED = "6640"

_started_with: dict[str, str] | None = None     # KVROD_* variables at the server's start


def _kvrod_environ() -> dict[str, str]:
    return {k: v for k, v in os.environ.items() if k.startswith("KVROD_")}


def dask_pre_spawn_environ() -> dict[str, str]:
    """The variables a Dask nanny sets before it spawns a worker, as ``distributed``
    computes them (``Nanny.pre_spawn_env``), without importing ``distributed``: the
    ``distributed.nanny.pre-spawn-environ`` setting over its defaults in distributed's
    ``distributed.yaml``, a variable already set winning, and ``PYTHONHASHSEED`` 6640
    unless one other than 0 is set. (A test compares this with distributed's own.)"""
    from importlib.util import find_spec

    import dask.config
    import yaml

    spec = find_spec("distributed")
    defaults: Mapping = {}
    if spec is not None and spec.origin is not None:
        text = Path(spec.origin).with_name("distributed.yaml").read_text()
        defaults = yaml.safe_load(text)["distributed"]["nanny"]["pre-spawn-environ"]
    cfg = {**defaults, **(dask.config.get("distributed.nanny.pre-spawn-environ",
                                          default=None) or {})}
    env = {k: os.environ.get(k, str(v)) for k, v in cfg.items() if v is not None}
    if env.get("PYTHONHASHSEED") in (None, "0"):
        env["PYTHONHASHSEED"] = DASK_HASH_SEED
    return env


@contextlib.contextmanager
def _environ(values: Mapping[str, str]) -> Iterator[None]:
    """``os.environ`` with ``values`` set, restored afterwards."""
    saved = {k: os.environ.get(k) for k in values}
    os.environ.update(values)
    try:
        yield
    finally:
        for k, v in saved.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v


def warm_up() -> dict:
    """Load (compiling on first use) the generated kernels in this process.

    Returns {"pid", "library"} for diagnostics; ``library`` is None when the in-process
    CasADi fallback is used (no C compiler).
    """
    import runtime.simulate.simulate  # noqa: F401 - pay the import once, not in the first task
    from runtime.model import build

    # a sweep's workers fill the cores with points: the energy audit's second thread
    # (step_loop.audit_thread_wanted) would only add its own cost to every point
    os.environ.setdefault("KVROD_AUDIT_THREAD", "0")

    lib = build.load_library()
    try:  # compiled BDF helpers, when this checkout has them
        from runtime.solvers.native import loader

        loader.load()
    except (ImportError, AttributeError):
        pass
    return {"pid": os.getpid(), "library": None if lib is None else str(lib._name)}


@contextlib.contextmanager
def children_ignore_sigint() -> Iterator[None]:
    """Start child processes with SIGINT ignored (an ignored disposition survives exec,
    and Python then installs no KeyboardInterrupt handler): Ctrl-C in the terminal reaches
    the whole process group, and the workers would each print a traceback. Only this
    process handles it, cancels the tasks and closes the cluster. (The fork server ignores
    SIGINT itself and gives its children the disposition it was started with: ignored.)"""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


def start_fork_server() -> bool:
    """Start the fork server of this process's sweep workers (see the module docstring),
    returning at once: its imports run in its own process. Idempotent; False where the
    platform has no ``forkserver`` start method."""
    global _started_with
    if "forkserver" not in multiprocessing.get_all_start_methods():
        return False
    if _started_with is None:
        from multiprocessing import forkserver

        multiprocessing.get_context("forkserver").set_forkserver_preload(list(PRELOAD))
        with children_ignore_sigint(), _environ(dask_pre_spawn_environ()):
            forkserver.ensure_running()
        _started_with = _kvrod_environ()
    return True


def start_method() -> str:
    """The start method for the workers of a LocalCluster started now: ``forkserver``
    when this process started the fork server and its ``KVROD_*`` variables are what they
    were then, else ``spawn``."""
    if _started_with is not None and _started_with == _kvrod_environ():
        return "forkserver"
    return "spawn"
