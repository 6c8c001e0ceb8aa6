"""Parameter studies on Dask (issue 8): study files, equality with serial runs, restart,
failing points, interruption and a worker killed mid-study.

Scenarios are tiny (a 0.1 m cantilever, 4-6 elements, 0.4 s after release: two tip
maxima, about 0.1-0.3 s per point) so the file stays well under its time budget.
"""

from __future__ import annotations

import json
import math
import os
import shutil
import signal
import sys
import time
from pathlib import Path

import pytest

from runtime.study.points import StudyPoint
from runtime.study.sweep import (
    FAILED,
    FINISHED,
    TOKEN_NAME,
    StudyError,
    load_study,
    point_dir,
    read_table,
    run_batch,
    run_study_serial,
    study_from_dict,
)

distributed = pytest.importorskip("distributed")

from runtime.study.sweep_dask import (  # noqa: E402
    BatchPlanner,
    run_study_dask,
    start_local_cluster,
    task_seconds,
)

TINY = {"length": 0.1, "t_end": 0.4, "rtol": 1e-4}
STUDY = {"name": "tiny", "scenario": "cantilever", "fixed": {**TINY, "n_elements": 5},
         "grid": {"tau": [0.01, 0.02, 0.03], "n_elements": [4, 6]},
         "points": [{"tau": 0.02, "min_step": 0.2}]}   # valid, but the integration fails
BAD_ID_PART = "min_step=0.2"
STUDY_TIMEOUT = 120.0


def _table_ids(out: Path) -> list[str]:
    return [r["point_id"] for r in read_table(out / "study.csv")]


def _summary(out: Path, pid: str) -> dict:
    return json.loads((point_dir(out, pid) / "summary.json").read_text())


def _assert_table_complete(out: Path, study) -> dict[str, dict]:
    """Every study point exactly once (rows in the order the points returned), each row
    saying what its summary says; returns rows by id."""
    ids = _table_ids(out)
    assert sorted(ids) == sorted(p.id for p in study.points)
    assert len(set(ids)) == len(ids)
    return _assert_rows_match_summaries(out)


def _assert_rows_match_summaries(out: Path) -> dict[str, dict]:
    rows = {r["point_id"]: r for r in read_table(out / "study.csv")}
    assert len(rows) == len(_table_ids(out))                       # no point twice
    for pid, r in rows.items():
        assert r["status"] == _summary(out, pid)["status"], pid
    return rows


def _wait_idle(client, timeout: float = 60.0) -> None:
    """Until the cluster runs no task (a batch stopped by an interrupt finishes its
    current point on the worker)."""
    deadline = time.monotonic() + timeout
    while any(client.processing().values()) and time.monotonic() < deadline:
        time.sleep(0.05)


@pytest.fixture(scope="module")
def client():
    """The LocalCluster a sweep starts: its workers forked from this process's fork
    server (started as ``kvrod sweep`` starts it) where the platform has one."""
    import dask

    from runtime.study import worker_boot

    worker_boot.start_fork_server()
    with dask.config.set(worker_boot.cluster_config()):      # as run_study_dask holds it
        cluster = start_local_cluster(2)
        c = distributed.Client(cluster, timeout=60)
        c.wait_for_workers(2, timeout=60)
        yield c
        c.close()
        cluster.close()


@pytest.fixture(scope="module")
def study():
    return study_from_dict(STUDY)


@pytest.fixture(scope="module")
def dask_run(client, study, tmp_path_factory):
    out = tmp_path_factory.mktemp("dask")
    links: list[str] = []
    report = run_study_dask(study, out, client=client, timeout=STUDY_TIMEOUT,
                            on_dashboard=links.append)
    report.dashboard = links
    return out, report


# ------------------------------------------------------------------ study definition


def test_grid_product_ids_and_coercion(tmp_path):
    s = study_from_dict(STUDY)
    assert len(s.points) == 7
    assert [(p.params["tau"], p.params["n_elements"]) for p in s.points[:6]] == [
        (0.01, 4), (0.01, 6), (0.02, 4), (0.02, 6), (0.03, 4), (0.03, 6)]
    assert s.points[6].params["n_elements"] == 5 and s.points[6].params["min_step"] == 0.2
    assert s.varied == ("tau", "n_elements", "min_step")
    # stable ids: same parameters (1e6 vs 1000000, order) -> same id; different -> different
    a = study_from_dict({"points": [{"youngs_modulus": 1e6, "tau": 0.02}]}).points[0]
    b = study_from_dict({"points": [{"tau": 0.02, "youngs_modulus": 1000000}]}).points[0]
    c = study_from_dict({"points": [{"tau": 0.02, "youngs_modulus": 2e6}]}).points[0]
    assert a.id == b.id != c.id
    # a point listed twice runs once
    assert len(study_from_dict({"points": [{"tau": 0.02}, {"tau": 0.02}]}).points) == 1
    f = tmp_path / "s.toml"
    f.write_text('scenario = "cantilever"\n[fixed]\nt_end = 0.4\n[grid]\ntau = [0.01, 0.02]\n')
    assert [p.params for p in load_study(f).points] == [
        {"t_end": 0.4, "tau": 0.01}, {"t_end": 0.4, "tau": 0.02}]


def test_example_study_has_16_points():
    s = load_study(Path(__file__).resolve().parents[2] / "examples" / "study_tau.toml")
    assert len(s.points) == 16 and s.problem == "cantilever"


@pytest.mark.parametrize("data, words", [
    ({"grid": {"bogus": [1]}}, ["bogus", "tau_S"]),
    ({"points": [{"tau": 0.02, "tau_S": 0.01}]}, ["tau", "not both"]),
    ({"scenario": "plate", "points": [{"tau": 0.02}]}, ["plate", "cantilever"]),
    ({"grid": {"n_elements": [4.5]}}, ["elements", "4.5"]),
    ({"points": [{"tau": 0.02, "poisson_ratio": 0.7}]}, ["poisson_ratio", "0.7", "1/2"]),
    ({"grid": {"tau": [0.02, float("nan")]}}, ["tau", "finite"]),
    ({"grid": {"tau": []}}, ["tau", "non-empty"]),
    ({"fixed": {"tau": 0.02}}, ["no points"]),
    ({"gird": {"tau": [0.02]}}, ["gird", "grid"]),
])
def test_bad_study_is_a_one_line_error(data, words):
    with pytest.raises(StudyError) as e:
        study_from_dict(data)
    msg = str(e.value)
    assert "\n" not in msg and all(w in msg for w in words), msg


# ------------------------------------------------------------------ engine


FORKS = pytest.mark.skipif(not sys.platform.startswith("linux"),
                           reason="the fork server is used on Linux only")


def _python(code: str, env: dict[str, str] | None = None) -> str:
    """Run ``code`` in a new interpreter at the checkout's root; its stdout."""
    import subprocess

    root = Path(__file__).resolve().parents[2]
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                       timeout=120, cwd=root,
                       env={**(env if env is not None else os.environ),
                            "PYTHONPATH": str(root)})
    assert r.returncode == 0, r.stderr[-2000:]
    return r.stdout


@FORKS
def test_our_cluster_forks_its_workers_with_the_kernels_loaded(client):
    """start_local_cluster's workers come from this process's fork server, which imported
    Dask's worker side and kvrod and loaded the kernels once (runtime.study.worker_boot),
    not from a new interpreter each (spawn: their parent would be this process)."""
    parents = client.run(os.getppid)
    assert len(parents) == 2 and os.getpid() not in parents.values()
    assert len(set(parents.values())) == 1                   # one fork server
    preloaded = client.run(eval, "'runtime.study.worker_preload' in "
                                 "__import__('sys').modules")
    assert all(preloaded.values()), preloaded


@FORKS
def test_a_changed_environment_falls_back_to_spawn(monkeypatch):
    """A worker forked from the fork server has the kernels and the environment the server
    started with: once what they depend on differs here (a kernel cache folder, the
    compiler), workers are spawned; other variables do not matter."""
    from runtime.study import worker_boot

    assert worker_boot.start_fork_server()
    assert worker_boot.start_method() == "forkserver"
    assert worker_boot.cluster_config() == {
        "distributed.worker.multiprocessing-method": "forkserver"}
    monkeypatch.setenv("SOMETHING_ELSE", "1")
    assert worker_boot.start_method() == "forkserver"
    for name, value in (("KVROD_CACHE_DIR", "/nonexistent/elsewhere"), ("CC", "clang")):
        monkeypatch.setenv(name, value)
        assert worker_boot.start_method() == "spawn"
        assert worker_boot.cluster_config() == {}         # a user's own setting stands
        monkeypatch.undo()
    assert worker_boot.start_method() == "forkserver"


@FORKS
def test_the_fork_server_gives_its_workers_dasks_environment_and_no_ctrl_c():
    """In a fresh interpreter without Dask's pre-spawn variables: the fork server's
    children have one BLAS/OpenMP thread and the rest of what a Dask nanny gives a worker
    it spawns (computed here without importing distributed, and equal to a Nanny's own
    figure), and ignore SIGINT; the server is gone when the process has exited."""
    env = {k: v for k, v in os.environ.items()
           if k not in ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS",
                        "MALLOC_TRIM_THRESHOLD_", "PYTHONHASHSEED")}
    out = _python(
        "import json, multiprocessing, os, signal\n"
        "from multiprocessing import forkserver\n"
        "from runtime.study import worker_boot\n"
        "assert worker_boot.start_fork_server()\n"
        "ours = worker_boot.dask_pre_spawn_environ()\n"
        "ctx = multiprocessing.get_context('forkserver')\n"
        "with ctx.Pool(1) as pool:\n"
        "    child = {k: pool.apply(os.getenv, (k,)) for k in ours}\n"
        "    sigint = pool.apply(signal.getsignal, (signal.SIGINT,))\n"
        "here = os.environ.get('OPENBLAS_NUM_THREADS')\n"
        "import distributed\n"
        "nanny = distributed.Nanny('tcp://127.0.0.1:1', nthreads=1)\n"
        "print(json.dumps({'ours': ours, 'nanny': nanny.pre_spawn_env, 'child': child,\n"
        "                  'sigint_ignored': sigint == signal.SIG_IGN,\n"
        "                  'here': here,\n"
        "                  'server': forkserver._forkserver._forkserver_pid}))\n", env)
    got = json.loads(out.strip().splitlines()[-1])
    assert got["ours"] == got["nanny"] and got["ours"]["OPENBLAS_NUM_THREADS"] == "1"
    assert got["child"] == got["ours"] and got["sigint_ignored"]
    assert got["here"] is None            # only the server's environment has them
    assert not Path(f"/proc/{got['server']}").exists()          # stopped at exit


@FORKS
def test_someone_elses_fork_server_is_left_alone():
    """A fork server that this process started for its own use (a forkserver pool)
    before the sweep is neither taken over nor given kvrod's preloads: spawn."""
    out = _python(
        "import multiprocessing\n"
        "from multiprocessing import forkserver\n"
        "forkserver.ensure_running()\n"
        "from runtime.study import worker_boot\n"
        "print(worker_boot.start_fork_server(), worker_boot.start_method())\n")
    assert out.split() == ["False", "spawn"]


@FORKS
def test_a_fork_server_that_cannot_start_means_spawned_workers():
    """No socket for the server (say, no writable temporary folder): workers are spawned,
    the sweep is not stopped."""
    out = _python(
        "from multiprocessing import forkserver\n"
        "def refuse():\n"
        "    raise OSError(30, 'Read-only file system')\n"
        "forkserver.ensure_running = refuse\n"
        "from runtime.study import worker_boot\n"
        "print(worker_boot.start_fork_server(), worker_boot.start_method(),\n"
        "      worker_boot.cluster_config())\n")
    assert out.split() == ["False", "spawn", "{}"]


def test_dask_results_equal_serial_runs(dask_run, study, tmp_path):
    out, report = dask_run
    assert report.total == 7 and not report.skipped
    assert sorted(report.computed) == sorted(p.id for p in study.points)
    serial = run_study_serial(study, tmp_path / "serial", plots=False)
    assert sorted(serial.computed) == sorted(report.computed)
    for p in study.points:
        a, b = _summary(out, p.id), _summary(tmp_path / "serial", p.id)
        assert a["status"] == b["status"]
        if a["status"] != FINISHED:
            continue
        assert a["counters"] == b["counters"]
        assert a["static"]["newton_iterations"] == b["static"]["newton_iterations"]
        assert len(a["peaks"]) == len(b["peaks"]) >= 2
        pairs = [(a["static"]["tip"], b["static"]["tip"]),
                 ([q["x"] for q in a["peaks"]], [q["x"] for q in b["peaks"]]),
                 ([q["t"] for q in a["peaks"]], [q["t"] for q in b["peaks"]]),
                 (a["damping_ratios"], b["damping_ratios"]), (a["periods"], b["periods"]),
                 ([a["energy_balance_max_rel"]], [b["energy_balance_max_rel"]])]
        for xa, xb in pairs:
            assert xa == pytest.approx(xb, rel=1e-10, abs=1e-12)
        assert (point_dir(out, p.id) / "series.npz").exists()


def test_table_plots_and_failing_point(dask_run, study, client):
    out, report = dask_run
    assert report.dashboard == [client.dashboard_link]
    assert report.dashboard[0].startswith("http://")
    rows = _assert_table_complete(out, study)
    bad = [pid for pid in rows if BAD_ID_PART in pid]
    assert len(bad) == 1 and report.failed == bad
    assert rows[bad[0]]["status"] == FAILED
    assert "integration failed" in rows[bad[0]]["message"]
    assert _summary(out, bad[0])["status"] == FAILED
    for pid, r in rows.items():
        if pid in bad:
            continue
        assert r["status"] == FINISHED
        assert 0.05 < float(r["zeta_first"]) < 0.6 and float(r["period_mean"]) > 0
        assert float(r["static_tip_z"]) > 0.09 and float(r["wall_time_s"]) > 0
    assert (out / "summary.png").stat().st_size > 1000
    assert (out / "study.toml").exists() is False  # built from a dict: no source to copy


def test_workers_load_the_kernels_once(dask_run, client):
    def loads() -> int:
        from runtime.model import build

        return build.library_loads()

    # the worker plugin loaded the library once per worker process, before any point
    assert set(client.run(loads).values()) == {1}
    out, _ = dask_run
    pids = {_summary(out, p)["point"]["pid"] for p in _table_ids(out)}
    assert os.getpid() not in pids


def test_restart_skips_finished_points(dask_run, study, client, tmp_path):
    src, _ = dask_run
    out = tmp_path / "restart"
    shutil.copytree(src, out)
    gone = study.points[2].id
    shutil.rmtree(point_dir(out, gone))
    before = {p.id: _summary(out, p.id)["point"]["computed_at"]
              for p in study.points if p.id != gone}
    report = run_study_dask(study, out, client=client, rerun_failed=False,
                            timeout=STUDY_TIMEOUT)
    assert report.computed == [gone]
    assert len(report.skipped) == 6
    after = {pid: _summary(out, pid)["point"]["computed_at"] for pid in before}
    assert after == before                       # nothing else was rerun or rewritten
    rows = _assert_table_complete(out, study)
    assert rows[gone]["status"] == FINISHED
    # by default a failed point is tried again on restart, a finished one never
    report = run_study_dask(study, out, client=client, timeout=STUDY_TIMEOUT)
    assert len(report.computed) == 1 and BAD_ID_PART in report.computed[0]


def test_interrupted_study_leaves_consistent_table_and_resumes(client, study, tmp_path):
    out = tmp_path / "interrupted"
    seen = []

    def interrupt(pr) -> None:
        assert pr.done + pr.failed == 1 and pr.running <= 2     # 2 single-thread workers
        assert pr.running + pr.queued == len(study.points) - 1
        seen.append(pr.last)
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_study_dask(study, out, client=client, progress=interrupt, timeout=STUDY_TIMEOUT)
    assert len(seen) == 1
    _wait_idle(client)
    rows = _assert_rows_match_summaries(out)      # the returned points, each once
    assert rows[seen[0]]["status"] in (FINISHED, FAILED)
    assert all(r["status"] in (FINISHED, FAILED) for r in rows.values())
    done = set(rows)
    progress = json.loads((out / "progress.json").read_text())
    assert progress["running"] == 0 and progress["queued"] == 0
    assert not list(out.rglob(".*.tmp"))            # no half-written files
    assert not (out / ".sweep-token").exists()      # the batches were told to stop
    # a batch being run when the interrupt came finished its current point: on disk,
    # its row comes with the restart
    finished_before = {p.id for p in study.points
                       if (point_dir(out, p.id) / "summary.json").exists()
                       and _summary(out, p.id)["status"] == FINISHED}
    assert {pid for pid in done if rows[pid]["status"] == FINISHED} <= finished_before
    report = run_study_dask(study, out, client=client, timeout=STUDY_TIMEOUT)
    assert not finished_before & set(report.computed)
    assert set(report.computed) | finished_before == {p.id for p in study.points}
    rows = _assert_table_complete(out, study)
    assert sum(r["status"] == FINISHED for r in rows.values()) == 6


@pytest.mark.skipif(sys.platform == "win32", reason="SIGKILL")
def test_worker_killed_mid_study(tmp_path):
    """One of two worker processes is SIGKILLed after the first result: its tasks are
    rescheduled and the study completes, every point exactly once in the table."""
    s = study_from_dict({"fixed": {**TINY, "t_end": 0.8},
                         "grid": {"tau": [0.01, 0.015, 0.02, 0.025, 0.03],
                                  "n_elements": [4, 6]}})
    killed: list[int] = []
    lost: list[str] = []          # task keys the killed worker was running or holding
    with distributed.LocalCluster(n_workers=2, processes=True, threads_per_worker=1,
                                  dashboard_address=":0", scheduler_port=0) as cluster, \
            distributed.Client(cluster, timeout=60) as c:
        c.wait_for_workers(2, timeout=60)
        pids = c.run(os.getpid)

        def kill_one(pr) -> None:
            if killed:
                return
            # one snapshot (a second call may find the task done meanwhile), and only a
            # worker that holds tasks: none busy at this report, wait for the next
            processing = c.processing()
            busy = [a for a, keys in processing.items() if keys and a in pids]
            if not busy:
                return
            os.kill(pids[busy[0]], signal.SIGKILL)
            killed.append(pids[busy[0]])
            lost.extend(processing[busy[0]])

        t0 = time.monotonic()
        report = run_study_dask(s, tmp_path, client=c, progress=kill_one,
                                timeout=STUDY_TIMEOUT)
        assert time.monotonic() - t0 < STUDY_TIMEOUT
        assert killed and lost      # the killed worker held tasks, which were rescheduled
        assert not set(c.run(os.getpid).values()) & set(killed)  # the dead one is gone
    assert report.ok, report
    assert sorted(report.computed) == sorted(p.id for p in s.points)  # each once
    rows = _assert_table_complete(tmp_path, s)
    assert all(r["status"] == FINISHED for r in rows.values())


# ------------------------------------------------------------------ CLI


def _cli(argv: list[str]) -> int:
    """`kvrod sweep ...` through the CLI's parser class and error handling."""
    from kvrod import cli, cli_sweep

    p = cli._Parser(prog="kvrod")
    sub = p.add_subparsers(dest="command", required=True, parser_class=cli._Parser)
    cli_sweep.add_commands(sub, cli._Parser)
    try:
        args = p.parse_args(argv)
        return int(args.func(args) or 0)
    except cli.CliError as exc:
        print(str(exc), file=sys.stderr)
        return 2


def test_cli_serial_and_errors(tmp_path, capsys):
    f = tmp_path / "study.toml"
    f.write_text('name = "cli"\n[fixed]\nlength = 0.1\nt_end = 0.4\nrtol = 1e-4\n'
                 "n_elements = 4\n[grid]\ntau = [0.01, 0.02]\n")
    out = tmp_path / "out"
    assert _cli(["sweep", str(f), "--serial", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "2 points run (0 failed)" in text and (out / "study.csv").exists()
    assert (out / "study.toml").read_text() == f.read_text()
    assert _cli(["sweep", str(f), "--serial", "--out", str(out)]) == 0
    assert "0 points run (0 failed), 2 already finished" in capsys.readouterr().out
    bad = tmp_path / "bad.toml"
    bad.write_text("[grid]\ntua = [0.01]\n")
    assert _cli(["sweep", str(bad)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "tua" in err
    assert _cli(["sweep", str(f), "--workers", "0"]) == 2
    assert _cli(["sweep", str(tmp_path / "missing.toml")]) == 2


# ------------------------------------------------------------------ batches and the table


def test_batches_sized_by_point_time_and_shrinking_to_the_end():
    points = iter([(i, StudyPoint(f"p{i}", {})) for i in range(1000)])
    plan = BatchPlanner(points, 1000)
    assert len(plan.next(4)) == 1                      # no point time known yet
    plan.observe(0.01)                                 # 10 ms points
    assert plan.size(4) == int(task_seconds(4) / 0.01) == 50
    plan.observe(1.0)                                  # mean 0.8 * 0.01 + 0.2 * 1.0
    assert plan.size(4) == 2
    plan.point_seconds = 1e-4                          # tiny: the guided bound rules
    assert plan.size(4) == math.ceil(999 / 8)
    sizes = []
    while batch := plan.next(4):
        sizes.append(len(batch))
    assert sum(sizes) == 999 and sizes == sorted(sizes, reverse=True) and sizes[-1] == 1
    plan.retry([(5, StudyPoint("p5", {})), (6, StudyPoint("p6", {}))])
    assert [len(plan.next(4)) for _ in range(3)] == [1, 1, 0]
    assert task_seconds(500) == 500 / 200 > task_seconds(16) == 0.5


def _figures(summary):
    """A summary without what differs between two runs of a point: where and when it
    ran, and the wall times."""
    if isinstance(summary, dict):
        return {k: _figures(v) for k, v in summary.items()
                if k != "point" and not k.endswith("wall_time_s")}
    return summary


def test_a_worker_without_the_folder_sends_files_and_a_retry_reruns_nothing(tmp_path):
    s = study_from_dict({"fixed": {**TINY, "n_elements": 4, "t_end": 0.2},
                         "grid": {"tau": [0.01, 0.02]}})
    pts = [(p.id, p.params) for p in s.points]
    shared = tmp_path / "shared"
    shared.mkdir()
    (shared / TOKEN_NAME).write_text("abc")
    direct = run_batch(s.problem, pts, s.param_columns, str(shared), "abc")
    assert all(r.files is None for r in direct)
    first = {pid: _summary(shared, pid) for pid, _ in pts}
    # a stale token (the study stopped, or another folder of that name): files as bytes
    sent = run_batch(s.problem, pts, s.param_columns, str(shared), "other")
    assert all(set(r.files) == {"summary.json", "series.npz", "problem.toml"} for r in sent)
    for a, b in zip(direct, sent, strict=True):
        assert a.point_id == b.point_id and a.status == b.status == FINISHED
        assert _figures(json.loads(b.files["summary.json"])) == _figures(first[a.point_id])
        assert {k: v for k, v in a.row.items() if k != "wall_time_s"} == \
            {k: v for k, v in b.row.items() if k != "wall_time_s"}
    # a task run again (its worker died after writing) finds its points finished
    again = run_batch(s.problem, pts, s.param_columns, str(shared), "abc")
    assert [_summary(shared, pid) for pid, _ in pts] == list(first.values())
    assert [r.row for r in again] == [r.row for r in direct]


def test_a_batch_stops_when_the_token_goes(tmp_path, monkeypatch):
    from runtime.study import sweep

    s = study_from_dict({"fixed": {**TINY, "n_elements": 4, "t_end": 0.1},
                         "grid": {"tau": [0.01, 0.02, 0.03]}})
    (tmp_path / TOKEN_NAME).write_text("abc")
    real = sweep.run_point_into

    def run_then_stop(*a, **k):
        summary = real(*a, **k)
        (tmp_path / TOKEN_NAME).unlink()            # Ctrl-C on the client meanwhile
        return summary

    monkeypatch.setattr(sweep, "run_point_into", run_then_stop)
    rows = run_batch(s.problem, [(p.id, p.params) for p in s.points], s.param_columns,
                     str(tmp_path), "abc")
    assert [r.point_id for r in rows] == [s.points[0].id]


def test_study_csv_is_appended_not_rewritten(tmp_path):
    """A restart with nothing to run leaves the table as it was (same file); one that
    runs a point again drops that point's row once and appends the new one."""
    s = study_from_dict({"fixed": {**TINY, "n_elements": 4, "t_end": 0.2},
                         "grid": {"tau": [0.01, 0.02, 0.03]},
                         "points": [{"tau": 0.02, "min_step": 0.2}]})     # fails
    run_study_serial(s, tmp_path, plots=False)
    table = tmp_path / "study.csv"
    ino, text = table.stat().st_ino, table.read_text()
    rows = _assert_table_complete(tmp_path, s)
    assert sum(r["status"] == FAILED for r in rows.values()) == 1
    report = run_study_serial(s, tmp_path, plots=False, rerun_failed=False)
    assert report.computed == [] and table.stat().st_ino == ino and table.read_text() == text
    # by default the failed point runs again: its old row goes, the new one comes last
    report = run_study_serial(s, tmp_path, plots=False)
    assert len(report.computed) == 1 and BAD_ID_PART in report.computed[0]
    assert _table_ids(tmp_path)[-1] == report.computed[0]
    _assert_table_complete(tmp_path, s)
    # a table lost (or a row cut short by a crash) is rebuilt from the summaries
    table.write_text(text[:-5])
    run_study_serial(s, tmp_path, plots=False, rerun_failed=False)
    _assert_table_complete(tmp_path, s)
    table.unlink()
    run_study_serial(s, tmp_path, plots=False, rerun_failed=False)
    assert _assert_table_complete(tmp_path, s).keys() == rows.keys()


def test_a_due_plot_waits_for_the_engine_and_the_report_says_where_time_went(
        tmp_path, monkeypatch):
    """record() only marks the plots due; they are drawn by refresh_plots(), which the
    engines call once their workers have work again (the Dask feeder after topping up
    its tasks), never in the middle of taking results. The report's phases come in
    order and the CLI's timing line shows them."""
    import runtime.study.sweep as sweep

    drawn: list[int] = []
    records: list[int] = []
    monkeypatch.setattr(sweep, "write_plots", lambda out, study, rows: drawn.append(len(rows)))
    record = sweep.StudyRecorder.record

    def counted(self, result):
        r = record(self, result)
        records.append(len(self.rows))
        assert self._plot_due and len(drawn) == len(records) - 1   # due, not drawn yet
        return r
    monkeypatch.setattr(sweep.StudyRecorder, "record", counted)
    monkeypatch.setattr(sweep.StudyRecorder, "__init__", _with_interval(
        sweep.StudyRecorder.__init__, 0.0))                 # every result makes it due
    s = study_from_dict({"fixed": {**TINY, "n_elements": 4, "t_end": 0.2},
                         "grid": {"tau": [0.01, 0.02, 0.03]}})
    report = run_study_serial(s, tmp_path)
    # before the next point, then once at the end (not twice for the last point)
    assert records == [1, 2, 3] and drawn == [1, 2, 3]
    ph = report.phases
    assert 0 <= ph["first_point"] <= ph["last_point"] <= ph["closed"] <= ph["end"]
    assert ph["plots_during_run"] >= 0 and ph["final_plots"] >= 0
    line = report.timing_line()
    assert line.startswith("timing: points returned from") and "end at" in line


def test_a_ctrl_c_between_a_point_s_files_leaves_none_of_them(tmp_path, monkeypatch):
    """run_point_into writes summary.json last; a Ctrl-C after series.npz and
    problem.toml but before it takes them away again (nothing of the point is left, as
    its docstring says), and the point runs again on restart."""
    import runtime.io.results as results
    from runtime.study.sweep import run_point_into

    original = results.write_json

    def interrupted(path, *a, **k):
        if Path(path).name == "summary.json":
            raise KeyboardInterrupt
        return original(path, *a, **k)
    monkeypatch.setattr(results, "write_json", interrupted)
    params = {**TINY, "n_elements": 4, "t_end": 0.05, "tau": 0.02}
    with pytest.raises(KeyboardInterrupt):
        run_point_into(tmp_path, "cantilever", "p1", params)
    assert sorted(os.listdir(point_dir(tmp_path, "p1"))) == []
    monkeypatch.setattr(results, "write_json", original)
    summary = run_point_into(tmp_path, "cantilever", "p1", params)
    assert summary["status"] == FINISHED
    assert {"series.npz", "problem.toml", "summary.json"} <= set(
        os.listdir(point_dir(tmp_path, "p1")))


def _with_interval(init, interval: float):
    def wrapped(self, *a, **k):
        k["plot_interval"] = interval
        init(self, *a, **k)
    return wrapped


@pytest.mark.parametrize("then", ["returns", "raises"])
def test_ctrl_c_stops_a_serial_study_whatever_the_point_made_of_it(tmp_path, monkeypatch, then):
    """A Ctrl-C that the point's own code catches (a run's outputs cut short by it, a
    half-written NPZ: a ValueError replaces the KeyboardInterrupt) still stops the study;
    the interrupted point is not recorded (no failed row, no summary)."""
    import signal

    from runtime.study import sweep

    s = study_from_dict({"fixed": {**TINY, "n_elements": 4, "t_end": 0.1},
                         "grid": {"tau": [0.01, 0.02, 0.03]}})
    real, calls = sweep._simulate, []

    def swallowing(problem, params):
        out = real(problem, params)
        calls.append(params["tau"])
        if len(calls) == 2:
            try:
                signal.raise_signal(signal.SIGINT)
            except KeyboardInterrupt:
                if then == "raises":
                    raise ValueError("could not broadcast input array") from None
        return out

    monkeypatch.setattr(sweep, "_simulate", swallowing)
    with pytest.raises(KeyboardInterrupt):
        run_study_serial(s, tmp_path, plots=False)
    assert calls == [0.01, 0.02]
    rows = read_table(tmp_path / "study.csv")
    assert [r["point_id"] for r in rows] == [s.points[0].id]
    assert not (point_dir(tmp_path, s.points[1].id) / "summary.json").exists()
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


def test_cli_on_a_local_cluster_prints_the_dashboard(tmp_path, capsys):
    f = tmp_path / "study.toml"
    f.write_text('name = "dash"\n[fixed]\nlength = 0.1\nt_end = 0.1\nrtol = 1e-4\n'
                 "n_elements = 4\n[grid]\ntau = [0.01, 0.02]\n")
    out = tmp_path / "out"
    assert _cli(["sweep", str(f), "--workers", "1", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "Dask dashboard: http://" in text and "2 points run (0 failed)" in text
    assert len(read_table(out / "study.csv")) == 2 and not (out / TOKEN_NAME).exists()
