"""Ctrl-C and SIGTERM around compiled code and file writes (issue 30).

* :func:`runtime.signals.held_signals` delivers a signal after the block, a second one at
  once;
* :func:`runtime.signals.run_interruptibly` raises a signal's exception in the main thread
  while the worker is still busy (the worker is then told to stop);
* an NPZ write interrupted anywhere ends in KeyboardInterrupt, never another exception
  (an interrupt inside ``zipfile`` left the archive's writer open and ``np.savez`` raised
  "Can't close the ZIP file while there is an open writing handle", which the command
  line reported as an error of kvrod);
* an interrupted simulation inside a calibration raises the interrupt, not RuntimeError
  (``kvrod calibrate`` said "internal error").

The signals are sent to this process (pytest runs the tests in the main thread, where
Python delivers them).
"""

from __future__ import annotations

import signal
import sys
import threading
import time

import numpy as np
import pytest

from runtime.signals import check_cancelled, held_signals, run_interruptibly


def test_a_held_signal_is_delivered_after_the_block():
    reached = []
    with pytest.raises(KeyboardInterrupt):
        with held_signals():
            signal.raise_signal(signal.SIGINT)
            reached.append("end of the block")
    assert reached == ["end of the block"]
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


def test_a_second_signal_while_held_acts_at_once():
    reached = []
    with pytest.raises(KeyboardInterrupt):
        with held_signals():
            signal.raise_signal(signal.SIGINT)
            signal.raise_signal(signal.SIGINT)
            reached.append("after the second signal")
    assert reached == []


def test_a_signal_reaches_the_caller_while_the_worker_is_busy():
    progress = {"steps": 0, "finished": False}

    def work():                       # 30 s of work in 0.05 s steps, each releasing the GIL
        for _ in range(600):
            time.sleep(0.05)
            progress["steps"] += 1
            check_cancelled()
        progress["finished"] = True

    timer = threading.Timer(0.3, signal.raise_signal, (signal.SIGINT,))
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            run_interruptibly(work)
    finally:
        timer.cancel()
    steps = progress["steps"]
    assert not progress["finished"] and steps < 600
    for _ in range(100):               # told to stop, it stops at its next check
        if not any(t.name == "kvrod-work" and t.is_alive() for t in threading.enumerate()):
            break
        time.sleep(0.05)
    assert progress["steps"] < 600 and not progress["finished"]


def test_the_worker_returns_its_value_and_raises_its_error():
    assert run_interruptibly(lambda a, b=0: a + b, 2, b=3) == 5
    with pytest.raises(ZeroDivisionError):
        run_interruptibly(lambda: 1 / 0)
    out = []
    t = threading.Thread(target=lambda: out.append(run_interruptibly(lambda: "plain call")))
    t.start()
    t.join()
    assert out == ["plain call"]


def test_an_npz_write_interrupted_anywhere_ends_in_keyboard_interrupt(tmp_path):
    """A SIGINT at every third Python line of a write (the window where an interrupt
    became a ValueError spans some 40 lines of zipfile): only KeyboardInterrupt comes out,
    after the file is complete, or before anything of it was written."""
    from runtime.io.results import read_npz, write_npz

    a = np.arange(1000.0)
    path = tmp_path / "x.npz"
    outcomes: dict[str, int] = {}
    n = -1
    while True:
        n += 3
        path.unlink(missing_ok=True)
        count = [0]

        def trace(frame, event, arg, count=count, n=n):
            if event in ("call", "line"):
                count[0] += 1
                if count[0] == n:
                    signal.raise_signal(signal.SIGINT)
            return trace

        sys.settrace(trace)
        try:
            write_npz(path, a=a, b=2 * a)
            sys.settrace(None)
            break                                   # n beyond the write's last line
        except BaseException as exc:  # noqa: BLE001 - what comes out is the test
            sys.settrace(None)
            kind = type(exc).__name__
            if path.exists():
                assert np.array_equal(read_npz(path)["b"], 2 * a), n
                kind += " after the file"
            outcomes[kind] = outcomes.get(kind, 0) + 1
    assert set(outcomes) <= {"KeyboardInterrupt", "KeyboardInterrupt after the file"}, \
        outcomes
    assert outcomes.get("KeyboardInterrupt after the file", 0) > 30
    assert not [p for p in tmp_path.iterdir() if ".tmp" in p.name]


def test_an_interrupted_simulation_in_a_calibration_is_an_interrupt():
    from runtime.problem.registry import load_problem
    from runtime.study.calibration import _simulate_tip

    problem = load_problem("cantilever", {"n_elements": 4})
    timer = threading.Timer(1.5, signal.raise_signal, (signal.SIGINT,))
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            _simulate_tip(problem, 0.05, 20000.0)        # minutes of stepping
    finally:
        timer.cancel()


def test_npz_files_are_deflated_archives_that_np_load_reads_back(tmp_path):
    """write_npz writes what np.savez_compressed wrote (one deflated ``<key>.npy`` entry
    per array; zlib level NPZ_COMPRESSLEVEL instead of the default): every dtype and
    shape comes back as it went in."""
    import zipfile

    from runtime.io.results import read_npz, write_npz

    arrays = {"t": np.linspace(0.0, 1.0, 501), "count": np.array(7),
              "index": np.arange(12, dtype=np.int32).reshape(3, 4),
              "names": np.array(["start", "end"]), "empty": np.zeros((0, 3)),
              "flags": np.array([True, False]), "fortran": np.asfortranarray(np.eye(3)[:, :2])}
    path = write_npz(tmp_path / "x.npz", **arrays)
    with zipfile.ZipFile(path) as z:
        infos = z.infolist()
    assert sorted(i.filename for i in infos) == sorted(f"{k}.npy" for k in arrays)
    assert all(i.compress_type == zipfile.ZIP_DEFLATED for i in infos)
    back = read_npz(path)
    for k, a in arrays.items():
        assert back[k].dtype == a.dtype and back[k].shape == a.shape, k
        assert np.array_equal(back[k], a), k
    assert [p.name for p in tmp_path.iterdir()] == ["x.npz"]
