"""Checkpoints written on a thread while the run goes on (runtime/io/runs.py,
``CheckpointWriter``): in order, never overtaking the final summary, their errors
raised on the run's thread."""

from __future__ import annotations

import json
import threading
import time

import numpy as np
import pytest

from runtime.io.runs import CheckpointWriter

ARGV = ["simulate", "cantilever", "--n-elements", "4", "--t-end", "2.5"]


@pytest.fixture(autouse=True)
def _checkpoint_every_simulated_second(monkeypatch):
    """The runs here take milliseconds, and kvrod simulate writes no checkpoint in a run
    shorter than a second of wall time (runs.CHECKPOINT_WALL); these tests are about
    what happens to a checkpoint, so every simulated second gets one."""
    monkeypatch.setenv("KVROD_CHECKPOINT_WALL", "0")


def _main(argv) -> int:
    from kvrod.cli import main

    return main([str(a) for a in argv])


def test_the_writer_copies_the_state_and_keeps_the_order():
    written, threads = [], set()

    def write(st):
        time.sleep(0.02)
        threads.add(threading.get_ident())
        written.append((st["t"], st["y"].copy()))

    w = CheckpointWriter(write)
    y = np.arange(3.0)
    w.submit({"t": 1.0, "y": y})
    y[:] = -1.0                       # the run goes on changing its arrays
    w.submit({"t": 2.0, "y": y})
    w.wait()
    assert [t for t, _ in written] == [1.0, 2.0]
    assert np.array_equal(written[0][1], [0.0, 1.0, 2.0])
    assert np.array_equal(written[1][1], [-1.0, -1.0, -1.0])
    assert threading.get_ident() not in threads


def test_an_error_of_the_writer_is_raised_by_the_next_call():
    def write(st):
        raise OSError(28, "No space left on device")

    w = CheckpointWriter(write)
    w.submit({"t": 1.0})
    with pytest.raises(OSError, match="No space left"):
        w.wait()
    w.wait()                          # raised once, then the writer is clean
    w.submit({"t": 2.0})
    assert "No space left" in w.wait_noting("ValueError: boom")


def test_a_slow_checkpoint_does_not_overtake_the_final_summary(tmp_path, monkeypatch):
    import runtime.io.results as results

    original = results.write_checkpoint

    def slow(*a, **k):
        time.sleep(0.5)               # far longer than the rest of the run
        return original(*a, **k)

    monkeypatch.setattr(results, "write_checkpoint", slow)
    out = tmp_path / "run"
    assert _main([*ARGV, "--out", out]) == 0
    s = json.loads((out / "summary.json").read_text())
    assert s["status"] == "finished" and s["t_reached"] == pytest.approx(2.5)
    assert not (out / "checkpoint.npz").exists()


def test_a_checkpoint_that_cannot_be_written_fails_the_run_and_says_why(tmp_path,
                                                                        monkeypatch):
    import runtime.io.results as results

    def full(*a, **k):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(results, "write_checkpoint", full)
    out = tmp_path / "run"
    assert _main([*ARGV, "--out", out]) != 0
    s = json.loads((out / "summary.json").read_text())
    assert s["status"] == "failed" and "No space left" in s["message"]


def test_as_a_context_it_waits_and_keeps_a_failed_checkpoint_on_the_exception():
    def full(st):
        time.sleep(0.05)
        raise OSError(28, "No space left on device")

    with pytest.raises(KeyboardInterrupt) as err:
        with CheckpointWriter(full) as w:
            w.submit({"t": 1.0})
            raise KeyboardInterrupt
    assert any("No space left" in n for n in getattr(err.value, "__notes__", []))
    assert w._thread is None                     # waited for before leaving
    with pytest.raises(OSError, match="No space left"):
        with CheckpointWriter(full) as w:
            w.submit({"t": 1.0})


def _count_checkpoints(monkeypatch) -> list[float]:
    """The times of the checkpoints written from now on (results.write_checkpoint still
    writes them)."""
    import runtime.io.results as results

    written: list[float] = []
    original = results.write_checkpoint

    def counted(out, params, state):
        written.append(float(state["t"]))
        return original(out, params, state)

    monkeypatch.setattr(results, "write_checkpoint", counted)
    return written


def test_a_run_shorter_than_a_checkpoints_worth_writes_none(tmp_path, monkeypatch):
    """By default (runs.CHECKPOINT_WALL: a second of wall time) a run of milliseconds
    writes no checkpoint and ends as it does with one every simulated second."""
    written = _count_checkpoints(monkeypatch)
    monkeypatch.delenv("KVROD_CHECKPOINT_WALL")
    assert _main([*ARGV, "--out", tmp_path / "a"]) == 0
    assert written == []
    monkeypatch.setenv("KVROD_CHECKPOINT_WALL", "0")
    assert _main([*ARGV, "--out", tmp_path / "b"]) == 0
    assert [round(t) for t in written] == [1, 2]
    with np.load(tmp_path / "a" / "series.npz") as a, np.load(tmp_path / "b" / "series.npz") as b:
        assert np.array_equal(a["tip"], b["tip"])


def test_an_assembly_keeps_the_same_checkpoint_rule(tmp_path, monkeypatch):
    """An assembly's run (runs.run_assembly_and_write) writes its checkpoints by the same
    wall-time rule as a rod's: none in a run of milliseconds by default, one per
    ``checkpoint_every`` with KVROD_CHECKPOINT_WALL=0, and the same results either way."""
    from runtime.io.runs import run_and_write
    from runtime.problem.registry import load_problem

    written = _count_checkpoints(monkeypatch)
    p = load_problem("examples/assembly_l_frame.toml",
                     {"rods.column.rod.elements": 4, "rods.beam.rod.elements": 3,
                      "simulation.t_end": 0.02, "simulation.output_step": 0.001})
    monkeypatch.delenv("KVROD_CHECKPOINT_WALL")
    a, _ = run_and_write(p, tmp_path / "a", "t", checkpoint_every=0.005)
    assert a.status == "finished" and written == []
    monkeypatch.setenv("KVROD_CHECKPOINT_WALL", "0")
    b, _ = run_and_write(p, tmp_path / "b", "t", checkpoint_every=0.005)
    assert b.status == "finished"
    # at the first step past each cadence point
    assert [round(t / 0.005) for t in written] == [1, 2, 3]
    assert np.array_equal(a.kinetic, b.kinetic) and np.array_equal(a.t, b.t)


@pytest.mark.parametrize("value", ["-1", "soon", "inf"])
def test_a_bad_checkpoint_wall_is_refused_before_anything_is_written(tmp_path, monkeypatch,
                                                                    capsys, value):
    monkeypatch.setenv("KVROD_CHECKPOINT_WALL", value)
    out = tmp_path / "run"
    assert _main([*ARGV, "--out", out]) == 2
    err = capsys.readouterr().err
    assert "KVROD_CHECKPOINT_WALL" in err and ">= 0" in err
    assert not out.exists()
