"""How the worker processes of a sweep's own LocalCluster start, without importing Dask.

A worker process started the default way (``spawn``: a new interpreter) imports Dask's
``distributed``, NumPy, SciPy and kvrod's runtime and loads the compiled kernels, about
0.7 s of CPU each, all at once when the cluster starts; on a machine of 16 cores that is
16 interpreters reading the same files while nothing runs, and on 2 cores it delays the
first points. Instead ``kvrod sweep`` starts a *fork server* (Python's ``forkserver``
start method) as its first act, before its own (the client's) import of Dask: one
process that imports all of it once, loads the kernels (:func:`warm_up`; those compiled
already: :mod:`runtime.study.worker_preload`), freezes its
heap (``gc.freeze``: the workers then share its pages instead of copying them), and forks
a worker in milliseconds whenever the cluster asks for one. It works on a core of its own
while the client imports Dask. Measured on 2 cores (2 workers, 40 tiny points, whole
``kvrod sweep``): the cluster ready 0.5 s after the run's start instead of 1.0 s.

The fork server starts with the environment a Dask nanny gives a worker it spawns
(``distributed.nanny.pre-spawn-environ``: one BLAS and OpenMP thread, glibc's trim
threshold, a fixed hash seed; :func:`dask_pre_spawn_environ`), so that NumPy, imported
there once, keeps one thread in every worker as it would after ``spawn``, and with SIGINT
ignored, which its children keep: Ctrl-C reaches only the sweep, which cancels its tasks
and closes the cluster (and which ignores SIGINT itself while its cluster starts, as it
did with spawned workers: a half-started cluster cannot be closed cleanly). The process
that started it stops it when it exits (SIGTERM: it may still be importing), so nothing
of it outlives the command.

Where it is used: only by our own LocalCluster (workers you start on a cluster keep their
own way), only on Linux (macOS has ``forkserver`` too, but forking after its system
frameworks and BLAS are loaded is why CPython spawns there), only when this process
started the server (:func:`start_fork_server`: the CLI does; a library user may) and no
other fork server ran in it before, and only while what the preloaded state depends on
is what it was at the server's start (:func:`_fingerprint`: ``KVROD_*``, the compiler
and cache variables): a forked worker has the server's environment and the
kernels it loaded. Otherwise the workers are spawned, as before (:func:`start_method`).
For the cluster's lifetime a worker its nanny restarts (after it died) is forked too.
"""

from __future__ import annotations

import atexit
import contextlib
import multiprocessing
import os
import signal
import sys
import threading
from collections.abc import Iterator, Mapping
from pathlib import Path

#: modules the fork server imports before it forks any worker: Dask's worker side and
#: the module whose import loads the kernels (:mod:`runtime.study.worker_preload`)
PRELOAD = ("distributed", "runtime.study.sweep", "runtime.study.worker_preload")
#: the hash seed a Dask nanny gives a worker when none is set (distributed.nanny.Nanny)
DASK_HASH_SEED = "6640"

#: environment variables besides KVROD_* that the preloaded state depends on: the
#: compiler and its search path (runtime.native), the kernel cache's default folder
FINGERPRINT_VARIABLES = ("CC", "CFLAGS", "PATH", "HOME", "XDG_CACHE_HOME", "TMPDIR")

_server_pid: int | None = None                 # the fork server this process started
_started_with: dict[str, str] | None = None    # _fingerprint() at its start


def _fingerprint() -> dict[str, str]:
    """What the preloaded state depends on, which a forked worker inherits from the
    server's start and a spawned one would take from this process now: kvrod's variables,
    the compiler's and the cache folder's. (Not ``sys.path``: a Dask scheduler in this
    process adds its scratch folders to it; the server keeps the one it started with.)"""
    return {k: v for k, v in os.environ.items()
            if k.startswith("KVROD_") or k in FINGERPRINT_VARIABLES}


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


def kernels_built() -> bool:
    """Whether :func:`warm_up` would load the kernels without compiling them."""
    from runtime.model import build
    from runtime.solvers.native import loader

    return build.library_built() and loader.built()


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


def _platform_forks() -> bool:
    return (sys.platform.startswith("linux")
            and "forkserver" in multiprocessing.get_all_start_methods())


def start_fork_server() -> bool:
    """Start the fork server of this process's sweep workers (see the module docstring),
    returning at once: its imports run in its own process. Idempotent. False, starting
    nothing, where it is not used: not Linux, no ``distributed``, a fork server that this
    process did not start is running already (someone else's: left alone), or it cannot
    start (say, no writable temporary folder for its socket)."""
    global _server_pid, _started_with
    if _server_pid is not None:
        return True
    from importlib.util import find_spec
    from multiprocessing import forkserver

    if not _platform_forks() or find_spec("distributed") is None:
        return False
    server = forkserver._forkserver             # the process's one fork server
    if getattr(server, "_forkserver_pid", None) is not None:
        return False
    env = dask_pre_spawn_environ()              # imports dask.config: before SIGINT goes
    multiprocessing.get_context("forkserver").set_forkserver_preload(list(PRELOAD))
    try:
        with children_ignore_sigint(), _environ(env):
            forkserver.ensure_running()
    except OSError:               # no socket in the temporary folder, no process: spawn
        return False
    _server_pid = getattr(server, "_forkserver_pid", None)
    _started_with = _fingerprint()
    atexit.register(stop_fork_server)
    return True


def stop_fork_server() -> None:
    """Stop the fork server this process started, and reap it (at exit): SIGTERM, since
    it may still be importing or compiling; then multiprocessing's own stop, which closes
    its pipe, waits for it and removes its socket. Its workers are gone by then (a
    cluster's close waits for them)."""
    global _server_pid, _started_with
    pid, _server_pid, _started_with = _server_pid, None, None
    if pid is None:
        return
    from multiprocessing import forkserver

    with contextlib.suppress(ProcessLookupError):
        os.kill(pid, signal.SIGTERM)
    try:
        forkserver._forkserver._stop()
    except (AttributeError, OSError):           # a Python without it: reap it ourselves
        with contextlib.suppress(ChildProcessError):
            os.waitpid(pid, 0)


def start_method() -> str:
    """The start method for the workers of a LocalCluster started now: ``forkserver``
    when this process started the fork server and its :func:`_fingerprint` is what it
    was then, else ``spawn``."""
    if _started_with is not None and _started_with == _fingerprint():
        return "forkserver"
    return "spawn"


def cluster_config() -> dict[str, str]:
    """Dask settings for the lifetime of our own LocalCluster: the fork server's start
    method where :func:`start_method` allows (restarted workers are forked too); nothing,
    so a user's own setting stands, where it does not."""
    if start_method() != "forkserver":
        return {}
    return {"distributed.worker.multiprocessing-method": "forkserver"}
