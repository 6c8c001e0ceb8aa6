"""The sweeps bench section's pieces (``python -m bench --only sweeps``): paired whole-
process timing, a large serial study's first row kept through Ctrl-C, the derived
efficiency, the Markdown."""

from __future__ import annotations

import sys

import pytest

from bench import sweeps as sw


def test_paired_runs_in_turn_and_takes_per_pair_ratios(tmp_path):
    env = sw.child_env(tmp_path / "pyc")
    slow = [sys.executable, "-c", "import time; time.sleep(0.2)"]
    bare = [sys.executable, "-c", "pass"]
    r = sw.paired(lambda i: bare, lambda i: slow, 2, env, tmp_path, lambda m: None, "x")
    assert r["pairs"] == 2 and len(r["A_walls"]) == len(r["B_walls"]) == 2
    assert r["B_wall"] >= 0.2 and r["ratio_wall"] < 1.0 and not r["failed"]
    assert 0 < r["A_cpu"] < r["A_wall"] + 1.0


def test_a_large_serial_study_keeps_its_first_row_through_ctrl_c(tmp_path):
    """Issue 30: a 40,000-point --serial study writes its first row soon (no expansion
    of the grid first), and Ctrl-C keeps it (exit 130)."""
    env = sw.child_env(tmp_path / "pyc")
    r = sw.first_row(sw.Size(serial_points=40_000), tmp_path, env)
    assert r["points"] == 40_000
    assert r["seconds_to_first_row"] is not None
    assert r["exit_code"] == 130 and r["rows_kept_after_ctrl_c"] >= 1


def test_derived_efficiency_and_markdown():
    worker = {"fixed_cpu": 0.01, "fixed_wall": 0.05, "point_wall": 0.02, "point_cpu": 0.02,
              "simulate_wall": 0.01, "simulate_cpu": 0.01, "points": 5}
    client = {"dask_cpu_per_point_on_worker": 0.001, "loop_per_point": 0.0004,
              "process_cpu_per_point": 0.0006}
    d = sw.derived(worker, client, cluster_start_s=1.0)
    per_point = 0.35 + 0.01 + 0.001
    assert d["efficiency"] == pytest.approx(0.35 / per_point)
    assert d["client_utilisation"] == pytest.approx(16 / per_point * 0.001)
    assert d["efficiency_with_cluster_start"] == pytest.approx(
        256 * 0.35 / (16 * (16 * per_point + 1.0)))
    assert d["workers_one_client_feeds"] == pytest.approx(per_point / 0.001)
    # a client slower than its workers caps the efficiency by its utilisation
    slow = sw.derived(worker, {**client, "loop_per_point": 0.05}, cluster_start_s=1.0)
    assert slow["client_utilisation"] > 1 and slow["efficiency"] < d["efficiency"] / 2


def test_the_efficiency_verdict_comes_from_the_largest_machine_measured(tmp_path):
    """A many-core record (bench.sweep_cores) gives the verdict; the figure derived from
    this machine's costs stands beside it. Without one, the derived figure is marked so."""
    import json

    est = {"efficiency": 0.98, "efficiency_with_cluster_start": 0.89}
    rec = tmp_path / "sweep_cores.json"
    rec.write_text(json.dumps({
        "efficiency_whole_commands": 0.43, "points": 256, "workers": 16,
        "point_s_measured": 0.258,
        "machine_before": {"cpus": 16, "cpu_model": "Some CPU"}}))
    t = sw.efficiency_target(est, rec)
    assert t["value"] == 0.43 and t["verdict"] == "missed"
    assert "MEASURED" in t["note"] and "16 CPUs" in t["note"] and "0.98" in t["note"]
    t = sw.efficiency_target(est, tmp_path / "none.json")
    assert t["value"] == 0.98 and t["verdict"] == "met" and "DERIVED" in t["note"]


def test_the_tiny_study_is_the_issues_tiny_point():
    import tomllib

    from runtime.study.sweep import study_from_dict

    s = study_from_dict(tomllib.loads(sw.tiny_study(500)))
    assert len(s.points) == 500
    assert {(p.params["n_elements"], p.params["t_end"]) for p in s.points} == {(4, 0.05)}
