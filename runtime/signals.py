"""Ctrl-C (SIGINT) and SIGTERM around work that Python cannot interrupt at any point.

Python runs a signal's handler (``KeyboardInterrupt``; the command line's SIGTERM handler
raises :class:`runtime.errors.Terminated`) in the main thread between two bytecodes, so:

* :func:`held_signals`: a block that must not be cut in the middle (a file being written:
  an interrupt inside ``zipfile`` left the archive's writer open and became a
  ``ValueError``, "internal error" on the command line) runs to its end and the signal is
  delivered right after it. A second signal while the first is held acts at once (a
  write that hangs can still be stopped).
* :func:`run_interruptibly`: a long computation in compiled code that holds the main
  thread for seconds (a sparse factorization in SciPy, which releases the GIL) runs in a
  worker thread while the main thread waits in short slices, so a signal's exception is
  raised in the main thread within a fraction of a second. The worker is told to stop
  (its ``cancel`` event) and is left to end by itself (a daemon thread: it does not keep
  the process alive).

Both do nothing special outside the main thread (where Python delivers no signals).
"""

from __future__ import annotations

import contextlib
import signal
import threading
from collections.abc import Callable, Iterator
from typing import Any, TypeVar

T = TypeVar("T")

#: the signals held or waited on
SIGNALS = tuple(getattr(signal, name) for name in ("SIGINT", "SIGTERM") if hasattr(signal, name))
#: how long the main thread waits for a worker between two looks at its signals (s)
POLL_S = 0.05


def _in_main_thread() -> bool:
    return threading.current_thread() is threading.main_thread()


@contextlib.contextmanager
def held_signals() -> Iterator[None]:
    """Hold SIGINT and SIGTERM during the block; deliver the first one received after it
    (its handler then raises where the block ends). A second signal meanwhile is delivered
    at once (the original handlers are back after the first)."""
    if not _in_main_thread():
        yield
        return
    pending: list[int] = []
    saved: list[tuple[int, Any]] = []

    def restore() -> None:            # may run twice (from hold, then at the end)
        for sig, old in saved:
            signal.signal(sig, old)

    def hold(signum, frame) -> None:
        pending.append(signum)
        restore()

    try:
        for sig in SIGNALS:
            old = signal.getsignal(sig)
            if old is None or old is signal.SIG_IGN:   # not set from Python, or ignored
                continue
            saved.append((sig, old))
            signal.signal(sig, hold)
        yield
    finally:
        restore()
        for sig in pending[:1]:
            signal.raise_signal(sig)


class Cancelled(BaseException):  # noqa: N818 - a request, not an error
    """Raised inside a worker of :func:`run_interruptibly` whose caller was interrupted
    (by :func:`check_cancelled`), so that it stops at its next check."""


_local = threading.local()
#: the "finished" events of the workers of :func:`run_interruptibly` (one still unset
#: after its caller was interrupted: that worker runs on until its compiled code returns).
#: Not Thread.is_alive: a Thread.join interrupted by a signal can leave a running thread
#: marked as stopped (Python 3.11: measured, the worker inside SuperLU "stopped").
_running: list[threading.Event] = []


def workers_alive() -> bool:
    """Whether a worker of :func:`run_interruptibly` is still running (after an interrupt:
    its caller was interrupted). A process should then end with ``os._exit``: at the
    interpreter's normal exit such a thread, still inside compiled code, may crash it
    (measured: SciPy's SuperLU under a finalizing interpreter, a segmentation fault)."""
    _running[:] = [e for e in _running if not e.is_set()]
    return bool(_running)


def check_cancelled() -> None:
    """In a worker of :func:`run_interruptibly`: raise :class:`Cancelled` once its caller
    has been interrupted (elsewhere: nothing). Long computations call it between steps."""
    event = getattr(_local, "cancel", None)
    if event is not None and event.is_set():
        raise Cancelled()


def run_interruptibly(fn: Callable[..., T], *args: Any, **kwargs: Any) -> T:
    """``fn(*args, **kwargs)``, with the main thread free for signals meanwhile.

    In the main thread ``fn`` runs in a daemon worker thread and the main thread waits for
    it in slices of ``POLL_S`` s: Ctrl-C or SIGTERM raise their exception here within
    about that time whenever the worker's compiled code releases the GIL (code that holds
    it, such as the mesher, must keep each call short). The worker's exception or result
    is the call's. Outside the main thread ``fn`` is simply called.
    """
    if not _in_main_thread():
        return fn(*args, **kwargs)
    cancel, done = threading.Event(), threading.Event()
    box: dict[str, Any] = {}

    def work() -> None:
        _local.cancel = cancel
        try:
            box["value"] = fn(*args, **kwargs)
        except Cancelled:
            pass
        except BaseException as exc:  # noqa: BLE001 - handed to the caller
            box["error"] = exc
        finally:
            done.set()

    worker = threading.Thread(target=work, name=f"kvrod-{getattr(fn, '__name__', 'work')}",
                              daemon=True)
    _running[:] = [e for e in _running if not e.is_set()]
    _running.append(done)              # before start: a signal may come during it
    try:
        worker.start()
        while not done.wait(POLL_S):
            pass
    except BaseException:
        cancel.set()
        raise
    if "error" in box:
        raise box.pop("error")
    return box["value"]
