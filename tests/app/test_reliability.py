"""Issue 6: solver failure keeps results, kill + --resume, VTK read-back, config files."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from runtime.problem.registry import load_problem
from runtime.simulate.simulate import simulate


def CantileverScenario(**kw):  # noqa: N802 - the built-in cantilever with aliases
    return load_problem("cantilever", kw)


def run_cantilever(problem, **kw):
    return simulate(problem, **kw)

KVROD = [sys.executable, "-m", "kvrod"]


def test_impossible_run_fails_with_a_clear_message_and_keeps_results(tmp_path):
    """A minimum step far above what the released rod's stiff transient needs: Newton fails
    at the minimum step; the error names time, step, residual and the worst DOF."""
    sc = CantileverScenario(n_elements=6, t_end=1.0, min_step=0.2)
    run = run_cantilever(sc)
    assert run.status == "failed"
    for piece in ("integration failed at t =", "step size", "residual norm", "worst component"):
        assert piece in run.message, run.message
    assert run.static_tip is not None and run.t.size >= 1 and run.y_last is not None
    from runtime.io.results import write_run

    s = write_run(tmp_path / "failed", run)
    data = json.loads((tmp_path / "failed" / "summary.json").read_text())
    assert data["status"] == "failed" and "worst component" in data["message"]
    assert data["static"]["tip"] == s["static"]["tip"]


def test_non_finite_values_stop_at_once():
    from runtime.solvers.bdf import BDF, IntegrationError
    from tests.rods import rod_model

    model = rod_model(4)
    y = model.initial_state()
    y[-1] = np.nan
    with pytest.raises((IntegrationError, ValueError), match="non-finite|NaN|nan|finite"):
        solver = BDF(model, 0.0, y, np.zeros(model.n), 1.0)
        solver.step()


#: runs `kvrod simulate` in a child that SIGKILLs itself right after its first checkpoint is
#: on disk: the kill is synchronised on that event (no sleeps, no race with a fast machine)
KILL_AFTER_FIRST_CHECKPOINT = """
import os, signal, sys
import runtime.io.results as results
from kvrod.cli import main
_write = results.write_checkpoint
def write_then_die(*args, **kwargs):
    path = _write(*args, **kwargs)
    os.kill(os.getpid(), signal.SIGKILL)
    return path
results.write_checkpoint = write_then_die
sys.exit(main(sys.argv[1:]))
"""


def test_kill_and_resume(tmp_path):
    out = tmp_path / "run"
    flags = ["simulate", "cantilever", "--n-elements", "40", "--t-end", "8", "--rtol", "1e-7",
             "--out", str(out)]
    args = KVROD + flags
    # a checkpoint at the first simulated second, however short the run's wall time
    env = {**os.environ, "KVROD_CHECKPOINT_WALL": "0"}
    p = subprocess.run([sys.executable, "-c", KILL_AFTER_FIRST_CHECKPOINT, *flags],
                       capture_output=True, text=True, timeout=300, env=env)
    assert p.returncode == -signal.SIGKILL, p.stderr
    ckpt = out / "checkpoint.npz"
    assert ckpt.exists(), "no checkpoint was written before the kill"
    summary = json.loads((out / "summary.json").read_text())     # readable, says running
    assert summary["status"] == "running"      # SIGKILL cannot be caught: --resume
    with np.load(ckpt) as saved:
        assert float(saved["t"]) >= 1.0          # the first checkpoint, one simulated second
    # a resume with different parameters is refused, naming the parameter
    bad = subprocess.run(KVROD + ["simulate", "cantilever", "--n-elements", "40", "--t-end",
                                  "8", "--rtol", "1e-6", "--out", str(out), "--resume"],
                         capture_output=True, text=True, timeout=60)
    assert bad.returncode == 2 and "rtol" in bad.stderr
    done = subprocess.run(args + ["--resume"], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    resumed = json.loads((out / "summary.json").read_text())
    assert resumed["status"] == "finished" and resumed["resumed_from_t"] > 0
    assert not ckpt.exists()
    full = run_cantilever(CantileverScenario(n_elements=40, t_end=8.0, rtol=1e-7)).summary()
    a = np.array([p["x"] for p in resumed["peaks"]])
    b = np.array([p["x"] for p in full["peaks"]])
    assert a.size == b.size and np.max(np.abs(a - b)) < 1e-5
    series = np.load(out / "series.npz")
    assert np.all(np.diff(series["t"]) > 0) and series["t"][-1] == pytest.approx(8.0)


def test_vtk_output_reads_back_with_vtk(tmp_path):
    vtk = pytest.importorskip("vtk")
    r = subprocess.run(KVROD + ["simulate", "cantilever", "--n-elements", "8", "--t-end", "1",
                                "--vtk", "0.25", "--out", str(tmp_path)], capture_output=True,
                       text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    pvd = (tmp_path / "vtk" / "rod.pvd").read_text()
    files = [line.split('file="')[1].split('"')[0] for line in pvd.splitlines() if "file=" in line]
    assert len(files) == 5
    reader = vtk.vtkXMLPolyDataReader()
    reader.SetFileName(str(tmp_path / "vtk" / files[0]))
    reader.Update()
    poly = reader.GetOutput()
    assert poly.GetNumberOfPoints() == 9 and poly.GetNumberOfLines() == 8
    summary = json.loads((tmp_path / "summary.json").read_text())
    tip = poly.GetPoint(8)
    assert np.allclose(tip, summary["static"]["tip"], atol=1e-9)      # t = 0: static state
    cd, pd = poly.GetCellData(), poly.GetPointData()
    for name in ("a1", "a2", "a3", "V", "F", "dissipation_rate_2D"):
        assert cd.GetArray(name) is not None, name
    for name in ("U", "M", "v", "dissipation_rate_2D"):
        assert pd.GetArray(name) is not None, name
    # the per-element dissipation adds up to the rod's total 2D at a later snapshot
    from runtime.io.vtk import element_fields
    from runtime.model.rod import RodModel

    sc = CantileverScenario(n_elements=8, t_end=0.3)
    run = run_cantilever(sc, snapshot_every=0.1)
    model: RodModel = run.model
    t, y, yp = run.snapshots[-1]
    cell, point = element_fields(model, t, np.ascontiguousarray(y), np.ascontiguousarray(yp))
    total = model.diagnostics(t, np.ascontiguousarray(y), yp)["dissipation_rate"]
    assert total > 0.0                     # the frame carries the rates of its time
    assert np.isclose(cell["dissipation_rate_2D"].sum() + point["dissipation_rate_2D"].sum(),
                      total, rtol=1e-9)


def test_config_file_resolved_into_summary(tmp_path):
    cfg = tmp_path / "run.toml"
    cfg.write_text('scenario = "cantilever"\n[parameters]\ntau = 0.08\nn_elements = 6\n'
                   "t_end = 0.5\n")
    r = subprocess.run(KVROD + ["simulate", "--config", str(cfg), "--t-end", "0.4",
                                "--out", str(tmp_path / "o")], capture_output=True, text=True,
                       timeout=120)
    assert r.returncode == 0, r.stderr
    s = json.loads((tmp_path / "o" / "summary.json").read_text())
    p = s["parameters"]
    assert p["material"]["tau_S"] == p["material"]["tau_B"] == 0.08
    assert p["rod"]["elements"] == 6
    assert p["simulation"]["t_end"] == 0.4         # the command line overrides the file
    assert s["tau_E"] == pytest.approx(0.08)


def test_results_never_half_written(tmp_path):
    """Atomic writes: the destination is replaced by rename; no temporary files remain."""
    from runtime.io.results import write_json

    write_json(tmp_path / "summary.json", {"a": 1})
    write_json(tmp_path / "summary.json", {"a": 2, "b": float("nan")})
    assert json.loads((tmp_path / "summary.json").read_text()) == {"a": 2, "b": "nan"}
    assert [p.name for p in Path(tmp_path).iterdir()] == ["summary.json"]
