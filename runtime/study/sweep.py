"""Parameter studies: study definition, per-point runs, the serial engine.

A study is a TOML file naming a problem, fixed parameters and the varied ones, either as
a grid (Cartesian product, in the order the keys are written) or as an explicit list::

    name = "tau"                 # optional, used for the default output folder
    problem = "cantilever"       # a problem file or a built-in problem

    [fixed]                      # parameters shared by every point
    t_end = 3.0
    rtol = 1e-6

    [grid]                       # Cartesian product: 4 x 2 = 8 points
    tau = [0.01, 0.02, 0.04, 0.08]
    n_elements = [30, 50]

    [[points]]                   # and/or explicit points (added after the grid)
    tau = 0.04
    poisson_ratio = 0.45

``problem`` names a problem file (its path relative to the study file) or built-in problem
(``scenario``, its earlier name, is accepted too). Parameter names are the short aliases
of the command line (:data:`runtime.problem.schema.ALIASES`: ``tau``, ``tau_S``, ``n_elements``,
``youngs_modulus``, ``tip_force``, ...) or any dotted path of the problem file (e.g.
``loads.0.time.start``); ``tau`` sets tau_S = tau_B = tau (the paper's convention).

Checked when the study is loaded, before anything runs or is written: every name, type
and value, and each grid value in a point of the study (the axis's value with the first
value of every other axis: as many checks as grid values, not as points, so a grid of
40,000 or 10^9 points is loaded at once, never expanded: :mod:`runtime.study.points`),
and every explicit point. A combination that only fails together with another axis's
value is found when its point is reached: that point is recorded as failed with the
message naming the parameter, and the others run. A point whose run fails is recorded
as failed likewise.

Results layout of a study folder ``DIR``::

    DIR/study.toml                       copy of the study file
    DIR/points/<point id>/summary.json   per point (status, message, figures, parameters)
    DIR/points/<point id>/series.npz     per point time series (when a run got that far)
    DIR/points/<point id>/problem.toml   per point: the resolved problem
    DIR/progress.json                    live counts: done, failed, running, queued
    DIR/study.csv                        one row per returned point, appended as points
                                         return (:mod:`runtime.study.table`)
    DIR/summary.png                      damping ratios and periods against a varied parameter

The point id is stable: a readable slug of the varied parameters plus a hash of all of
the point's parameters, so the same point gets the same folder on every run, and a
finished point (summary.json with status "finished" and the same parameters) is not run
again. Every file is written atomically (temporary name, then rename), a point's
summary.json last.

This module holds everything except the distributed engine (``runtime.study.sweep_dask``):
the study, the task functions that workers execute (:func:`run_batch`: a list of
parameter dicts in, small :class:`PointResult` rows out, each point's folder written by
the worker itself where it sees the study folder; :func:`run_point`: one point's files as
bytes, for a worker that does not), the client's bookkeeping (:class:`StudyRecorder`) and
a serial engine (:func:`run_study_serial`). It does not import Dask.
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import signal
import socket
import sys
import threading
import time
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path
from typing import Any

from runtime.io.atomic import write_bytes, write_text
from runtime.io.results import write_json, write_run
from runtime.study.plots import UNITS, plot_axis, write_plots
from runtime.study.points import (
    FAILED,
    FINISHED,
    PENDING,
    RUNNING,
    StudyPoint,
    StudyPoints,
    canonical_json,
    merge,
    point_id,
)
from runtime.study.table import (
    FIGURE_COLUMNS,
    TABLE_NAME,
    TableAppender,
    read_table,
    row_of,
    table_columns,
    table_row,
)

__all__ = ["CONFIRM_FLAG", "FAILED", "FIGURE_COLUMNS", "FINISHED", "MAX_POINTS", "PENDING",
           "RUNNING", "UNITS", "PointOutcome", "PointResult", "Study", "StudyError",
           "StudyPoint", "StudyRecorder", "StudyReport", "SweepProgress", "base_problem",
           "canonical_json", "check_point", "failure_outcome", "is_finished", "load_study",
           "point_dir", "point_id", "read_summary", "read_table", "run_batch", "run_point",
           "run_point_into", "run_study_serial", "study_from_dict", "table_row",
           "write_plots", "write_point"]

#: top-level keys of a study file
STUDY_KEYS = ("name", "problem", "scenario", "fixed", "grid", "points")
#: largest study run without confirmation, and the command-line flag that confirms
MAX_POINTS = 10_000
CONFIRM_FLAG = "--yes"


class StudyError(ValueError):
    """A malformed study file or definition (names the offending key and what is allowed)."""


def parameter_names(problem: str = "cantilever") -> tuple[str, ...]:
    """Short parameter names a study may set (:data:`runtime.problem.schema.ALIASES`);
    any dotted path of the problem file (e.g. ``material.tau``) is accepted too."""
    from runtime.problem.schema import ALIASES

    return tuple(sorted(ALIASES))


def _check_problem(problem: object) -> None:
    from runtime.problem.registry import ProblemFileError, problem_path

    if not isinstance(problem, str):
        raise StudyError(f"problem = {problem!r} must be a string: a built-in name or a "
                         "problem file")
    try:
        problem_path(problem)
    except ProblemFileError as exc:
        raise StudyError(str(exc)) from None


#: integer parameters (their values stay integers; every other number is a float, so
#: 1e6 and 1000000 give the same point)
INTEGER_PARAMETERS = ("n_elements", "elements", "rod.elements", "max_order",
                      "simulation.max_order", "load_steps", "statics.load_steps")


def _coerce(name: str, value: Any, where: str) -> Any:
    """Canonical Python value of a parameter (so 1e6 and 1000000 give the same point id)."""
    from runtime.problem.schema import ALIASES

    if name not in ALIASES and "." not in name:
        raise StudyError(f"{where}: unknown parameter {name!r}; parameters are: "
                         f"{', '.join(sorted(ALIASES))} or a dotted path of the problem "
                         "file (e.g. material.tau)")
    if isinstance(value, bool) or isinstance(value, str):
        return value
    integer = name in INTEGER_PARAMETERS
    if isinstance(value, int):
        return value if integer else float(value)
    if isinstance(value, float):
        if not math.isfinite(value):
            raise StudyError(f"{where}: {name} = {value!r} is not a finite number")
        return int(value) if integer and value.is_integer() else value
    if isinstance(value, list):
        return [_coerce(name, v, where) for v in value]
    if isinstance(value, dict):      # a whole table, e.g. an appended load (loads.1)
        return {k: _coerce(f"{name}.{k}", v, where) for k, v in value.items()}
    raise StudyError(f"{where}: {name} = {value!r} has the wrong type (a number, string, "
                     "boolean, list or table)")


def _check_params(params: Mapping[str, Any], where: str) -> dict[str, Any]:
    out = {name: _coerce(name, value, where) for name, value in params.items()}
    if "tau" in out and ({"tau_S", "tau_B"} & set(out)):
        raise StudyError(f"{where}: give either tau or tau_S/tau_B, not both")
    return out


def base_problem(problem: str) -> Any:
    """The study's problem without overrides, read once per process and file version
    (a study's points, thousands of them, share it: the registry and the problem file
    are not read again for each; an edited file is read again)."""
    try:
        path = _problem_file(problem, os.getcwd())
        st = path.stat()
    except OSError:                      # moved or deleted since: resolve it again
        _problem_file.cache_clear()
        path = _problem_file(problem, os.getcwd())
        st = path.stat()
    return _base_problem(problem, str(path), st.st_mtime_ns, st.st_size)


@lru_cache(maxsize=16)
def _problem_file(problem: str, cwd: str) -> Path:
    """The file of a problem name or path (a built-in name is looked up once per process,
    not once per point)."""
    from runtime.problem.registry import problem_path

    return problem_path(problem).resolve()


@lru_cache(maxsize=16)
def _base_problem(problem: str, path: str, mtime_ns: int, size: int) -> Any:
    from runtime.problem.registry import load_problem

    return load_problem(Path(path))


def check_point(problem: Any, params: Mapping[str, Any], where: str) -> None:
    """Build the point's problem (every value checked by the schema) without running it;
    StudyError naming the point and the parameter. ``problem``: a name or file, or the
    study's :func:`base_problem`."""
    from runtime.errors import ParameterError
    from runtime.problem.registry import load_problem

    try:
        load_problem(problem, params).check_simulable()
    except ParameterError as exc:
        raise StudyError(f"{where}: {exc}") from None


@dataclass(frozen=True)
class Study:
    """A parameter study: problem (file or built-in name), fixed parameters, varied names
    and the points.

    ``points`` (:class:`runtime.study.points.StudyPoints`) are unique by id (a point
    listed twice runs once) and ordered as written: the grid's Cartesian product first
    (last key fastest), then the explicit points; each is made when asked for.
    """

    name: str
    problem: str
    fixed: dict[str, Any]
    varied: tuple[str, ...]
    points: StudyPoints
    source: str = ""          # the TOML text the study was read from (copied to DIR)

    @property
    def param_columns(self) -> tuple[str, ...]:
        """Parameter columns of the table: varied ones first, then the fixed ones."""
        return (*self.varied, *(k for k in self.fixed if k not in self.varied))


def _viscosity_clash(fixed: Mapping[str, Any], keys: Iterable[str]) -> None:
    """Would tau_B keep the fixed tau, or not? Say it instead of guessing."""
    keys = set(keys)
    for a, b in ((("tau",), ("tau_S", "tau_B")), (("tau_S", "tau_B"), ("tau",))):
        fa = [k for k in a if k in fixed]
        pb = [k for k in b if k in keys]
        if fa and pb:
            raise StudyError(f"{fa[0]} is fixed but {pb[0]} varies: give the viscosity "
                             "one way, either tau or tau_S/tau_B, in [fixed] and the "
                             "points alike")


def _axis(name: str, values: list[Any]) -> list[Any]:
    """A grid axis's values, each checked and coerced once, repeats removed (a point
    listed twice runs once)."""
    distinct: dict[str, Any] = {}
    for v in values:
        c = _check_params({name: v}, "[grid]")[name]
        distinct.setdefault(canonical_json({"v": c}), c)
    return list(distinct.values())


def study_from_dict(data: Mapping[str, Any], name: str = "study", source: str = "",
                    max_points: int | float | None = None) -> Study:
    """Build a :class:`Study` from the parsed TOML (see the module docstring).

    ``max_points``: largest study accepted (default :data:`MAX_POINTS`; pass ``math.inf``
    once the user confirmed a larger one). The work is that of the axes and the listed
    points, never of the grid's product.
    """
    max_points = MAX_POINTS if max_points is None else max_points
    unknown = sorted(set(data) - set(STUDY_KEYS))
    if unknown:
        raise StudyError(f"unknown key(s) {', '.join(map(repr, unknown))} in the study; "
                         f"allowed: {', '.join(STUDY_KEYS)}")
    if "scenario" in data and "problem" in data:
        raise StudyError("give either problem or scenario (its earlier name), not both")
    problem = data.get("problem", data.get("scenario", "cantilever"))
    _check_problem(problem)
    name = str(data.get("name", name))
    fixed_raw = data.get("fixed", {})
    grid = data.get("grid", {})
    listed = data.get("points", [])
    if not isinstance(fixed_raw, dict) or not isinstance(grid, dict):
        raise StudyError("[fixed] and [grid] must be tables")
    if not isinstance(listed, list) or not all(isinstance(p, dict) for p in listed):
        raise StudyError("points must be an array of tables ([[points]])")
    fixed = _check_params(fixed_raw, "[fixed]")
    for k, vals in grid.items():
        if not isinstance(vals, list) or not vals:
            raise StudyError(f"[grid]: {k} must be a non-empty list of values, got {vals!r}")
    n_points = math.prod(len(v) for v in grid.values()) + len(listed)
    if n_points > max_points:
        raise StudyError(f"the study has {n_points} points, more than {max_points} (the "
                         f"grid {' x '.join(str(len(v)) for v in grid.values())}); confirm "
                         f"with {CONFIRM_FLAG} to run it anyway")
    axes = {k: _axis(k, vals) for k, vals in grid.items()}
    _check_params({k: v[0] for k, v in axes.items()}, "[grid]")  # unknown names, tau clash
    own = [_check_params(p, f"points[{i}]") for i, p in enumerate(listed)]
    if not axes and not own:
        raise StudyError("the study has no points: give a [grid] or [[points]]")
    varied: list[str] = list(axes)
    for p in own:
        varied += [k for k in p if k not in varied]
    try:
        base = base_problem(problem)        # the registry and the file: once per study
    except ValueError as exc:                # the problem file itself is bad
        raise StudyError(f"problem {problem!r}: {exc}") from None
    grid_points = StudyPoints(fixed, axes, [], varied)
    if axes:                                 # every grid value once, in a point of the grid
        _viscosity_clash(fixed, axes)
        first = grid_points.params_at(0)
        _check_params(first, "point")
        checked: set[str] = set()
        for k, vals in axes.items():
            for v in vals:
                p = grid_points.make({**first, k: v})
                if p.id not in checked:
                    checked.add(p.id)
                    check_point(base, p.params, f"point {p.id}")
    kept: list[dict[str, Any]] = []
    seen: set[str] = set()
    for p in own:                            # every listed point, unless it is a grid point
        _viscosity_clash(fixed, p)
        params = _check_params(merge(fixed, p), "point")
        key = canonical_json(params)
        if key in seen or grid_points.find(params) is not None:
            continue
        seen.add(key)
        check_point(base, params, f"point {point_id(params, varied)}")
        kept.append(p)
    return Study(name=name, problem=problem, fixed=fixed, varied=tuple(varied),
                 points=StudyPoints(fixed, axes, kept, varied), source=source)


def load_study(path: str | os.PathLike, max_points: int | float | None = None) -> Study:
    """Read a study TOML file (StudyError for a malformed file or unknown parameter)."""
    from runtime.problem.registry import read_toml

    path = Path(path)
    data, text = read_toml(path, StudyError, "study file")
    key = "problem" if "problem" in data else "scenario"
    spec = data.get(key)      # a problem file's path is relative to the study file
    if isinstance(spec, str) and (spec.endswith(".toml") or "/" in spec) \
            and not Path(spec).is_absolute():
        data = {**data, key: str((path.parent / spec).resolve())}
    return study_from_dict(data, name=path.stem, source=text, max_points=max_points)


# --------------------------------------------------------------------------------------
# the tasks: parameters in, small rows out (run on a worker; ship no compiled objects)
# --------------------------------------------------------------------------------------


@dataclass
class PointOutcome:
    """What :func:`run_point` returns: plain, picklable data.

    ``files`` maps file names of the point's folder (summary.json, series.npz,
    problem.toml) to their bytes, written by :func:`runtime.io.results.write_run` on the
    worker; the client stores them unchanged (:func:`write_point`).
    """

    point_id: str
    params: dict[str, Any]
    status: str
    message: str
    files: dict[str, bytes] = field(default_factory=dict)
    wall_time_s: float = 0.0
    host: str = ""
    pid: int = 0
    worker_lib_loads: int = -1       # compiled-library loads in this process so far


@dataclass
class PointResult:
    """What a worker hands back for one point: its table row (a few hundred bytes).

    ``files`` (the point's files as bytes, as in :class:`PointOutcome`) only when the
    worker could not write the study folder itself; ``wall_time_s`` and ``cpu_s``: the
    worker's wall and CPU time for the point, run and files together (s).
    """

    point_id: str
    status: str
    row: dict[str, Any]
    wall_time_s: float
    files: dict[str, bytes] | None = None
    cpu_s: float = 0.0


def _library_loads() -> int:
    from runtime.model import build

    return build.library_loads()


def _point_meta(problem: str, point_id: str, params: Mapping[str, Any],
                wall_time_s: float) -> dict[str, Any]:
    return {"id": point_id, "problem": problem,
            "parameters": json.loads(canonical_json(params)),
            "host": socket.gethostname(), "pid": os.getpid(), "computed_at": time.time(),
            "wall_time_s": wall_time_s}


def _simulate(problem: str, params: dict[str, Any]) -> tuple[Any, str, str]:
    """(run or None, status, message) of one point; never raises but for Ctrl-C."""
    run = None
    try:
        from runtime.problem.registry import load_problem
        from runtime.simulate.simulate import simulate

        run = simulate(load_problem(base_problem(problem), params))
        if run.interrupt is not None:      # Ctrl-C stops the study, it is no failed point
            raise run.interrupt
        return run, run.status, run.message
    except Exception as exc:  # noqa: BLE001 - a failing point must not stop the study
        return run, FAILED, f"{type(exc).__name__}: {exc}"


def _write_point_files(d: Path, problem: str, point_id: str, params: dict[str, Any],
                       run: Any, status: str, message: str, wall: float) -> dict:
    """The point's files into folder ``d`` (summary.json last); returns the summary."""
    meta = _point_meta(problem, point_id, params, wall)
    if run is not None:
        return write_run(d, run, extra={"point": meta})
    summary = {"status": status, "message": message, "parameters": params,
               "wall_time_s": wall, "point": meta}
    write_json(d / "summary.json", summary)
    return summary


def run_point(problem: str, point_id: str, params: Mapping[str, Any]) -> PointOutcome:
    """Run one point; never raises (an exception becomes status "failed" + its message).

    A parameter dict in, a :class:`PointOutcome` (the bytes of the point's files) out:
    what a worker that cannot write the study folder returns. The summary carries
    ``point`` = {id, problem, parameters, host, pid, computed_at, wall_time_s}, which the
    resume check compares against the study.
    """
    import tempfile

    t0 = time.perf_counter()
    params = dict(params)
    run, status, message = _simulate(problem, params)
    wall = time.perf_counter() - t0
    files: dict[str, bytes] = {}
    with tempfile.TemporaryDirectory(prefix="kvrod-point-") as tmp:
        summary = _write_point_files(Path(tmp), problem, point_id, params, run, status,
                                     message, wall)
        for f in sorted(Path(tmp).iterdir()):
            files[f.name] = f.read_bytes()
    return PointOutcome(point_id=point_id, params=params, status=summary["status"],
                        message=message, files=files, wall_time_s=wall,
                        host=socket.gethostname(), pid=os.getpid(),
                        worker_lib_loads=_library_loads())


def run_point_into(out: Path, problem: str, point_id: str, params: Mapping[str, Any],
                   interrupted: Callable[[], bool] | None = None) -> dict:
    """Run one point and write its folder ``DIR/points/<id>`` directly (summary.json
    last); returns the summary. Never raises but for Ctrl-C (nothing of this point is
    written then: also when ``interrupted()`` says a Ctrl-C came, whatever the run made
    of it). A series.npz of an earlier attempt is removed when this run has none."""
    t0, started = time.perf_counter(), time.time()
    params = dict(params)
    run, status, message = _simulate(problem, params)
    if interrupted is not None and interrupted():
        raise KeyboardInterrupt
    d = point_dir(out, point_id)
    d.mkdir(parents=True, exist_ok=True)
    if run is None:
        (d / "series.npz").unlink(missing_ok=True)
    try:
        return _write_point_files(d, problem, point_id, params, run, status, message,
                                  time.perf_counter() - t0)
    except KeyboardInterrupt:
        # Ctrl-C between the files (summary.json comes last): what this attempt wrote
        # goes, unless its summary made it (then the point is finished and whole)
        s = _read_summary(d / "summary.json")
        meta = s.get("point") if isinstance(s, dict) else None
        done = isinstance(meta, dict) and isinstance(meta.get("computed_at"), (int, float))
        if not (done and meta["computed_at"] >= started):
            for name in ("series.npz", "problem.toml"):
                (d / name).unlink(missing_ok=True)
        raise


#: the study folder's token file: the client writes a fresh token into it when a run
#: starts and removes it when the run ends; a worker that reads the same token there
#: writes points into the folder itself, and stops a batch when the token is gone
TOKEN_NAME = ".sweep-token"


def _folder_shared(out: str | None, token: str | None) -> bool:
    if out is None or token is None:
        return False
    try:
        return (Path(out) / TOKEN_NAME).read_text() == token
    except (OSError, UnicodeDecodeError):
        return False


def run_batch(problem: str, points: Sequence[tuple[str, Mapping[str, Any]]],
              param_columns: Sequence[str], out: str | None = None,
              token: str | None = None) -> list[PointResult]:
    """Run points one after another; the worker's task.

    ``points``: (id, parameters) pairs. Where this process sees the study folder ``out``
    (its :data:`TOKEN_NAME` file holds ``token``), each point's folder is written here
    and only its table row (:func:`runtime.study.table.row_of`) is returned; a point
    already finished there (a retried task) is not run again. Otherwise the rows come
    with the files as bytes (:func:`run_point`) for the client to write. The batch stops
    early, returning the rows so far, when the token file no longer holds ``token`` (the
    study was stopped).
    """
    shared = _folder_shared(out, token)
    results = []
    for pid, params in points:
        t0, c0 = time.perf_counter(), time.process_time()
        if shared:
            if results and not _folder_shared(out, token):
                break
            folder = Path(out)
            summary = _finished_summary(folder, pid, params)
            if summary is None:
                summary = run_point_into(folder, problem, pid, params)
            files = None
        else:
            outcome = run_point(problem, pid, params)
            files = outcome.files
            summary = json.loads(files["summary.json"])
        results.append(PointResult(pid, summary["status"],
                                   row_of(param_columns, pid, params, summary),
                                   time.perf_counter() - t0, files,
                                   time.process_time() - c0))
    return results


# --------------------------------------------------------------------------------------
# point folders
# --------------------------------------------------------------------------------------


def point_dir(out: Path, pid: str) -> Path:
    """Folder of one point."""
    return Path(out) / "points" / pid


def _read_summary(path: Path) -> dict | None:
    try:
        s = json.loads(path.read_text())
    except (OSError, ValueError):
        return None
    return s if isinstance(s, dict) else None


def _same_parameters(summary: Mapping[str, Any], params: Mapping[str, Any]) -> bool:
    meta = summary.get("point", {})
    return isinstance(meta, dict) and \
        meta.get("parameters") == json.loads(canonical_json(params))


def read_summary(out: Path, point: StudyPoint) -> dict | None:
    """The point's summary.json if it exists, is readable and belongs to these parameters."""
    s = _read_summary(point_dir(out, point.id) / "summary.json")
    return s if s is not None and _same_parameters(s, point.params) else None


def _finished_summary(out: Path, pid: str, params: Mapping[str, Any]) -> dict | None:
    s = _read_summary(point_dir(out, pid) / "summary.json")
    return s if is_finished(s) and _same_parameters(s, params) else None


def is_finished(summary: Mapping[str, Any] | None) -> bool:
    """True for a summary of a finished run (such a point is not run again)."""
    return bool(summary) and summary.get("status") == FINISHED


def write_point(out: Path, outcome: PointOutcome) -> dict:
    """Store a point's files atomically (summary.json last); returns the summary.

    A series.npz left from an earlier attempt is removed when this outcome has none.
    """
    d = point_dir(out, outcome.point_id)
    d.mkdir(parents=True, exist_ok=True)
    if "series.npz" not in outcome.files and (d / "series.npz").exists():
        (d / "series.npz").unlink()
    names = sorted(outcome.files, key=lambda n: n == "summary.json")
    for name in names:
        write_bytes(d / name, outcome.files[name])
    return json.loads(outcome.files["summary.json"])


def failure_outcome(problem: str, point: StudyPoint, message: str) -> PointOutcome:
    """Outcome recorded by the client when a task could not run (e.g. workers died)."""
    meta = _point_meta(problem, point.id, point.params, 0.0)
    summary = {"status": FAILED, "message": message, "parameters": dict(point.params),
               "wall_time_s": 0.0, "point": meta}
    return PointOutcome(point_id=point.id, params=dict(point.params), status=FAILED,
                        message=message, host=meta["host"], pid=meta["pid"],
                        files={"summary.json": (json.dumps(summary, indent=2) + "\n").encode()})


# --------------------------------------------------------------------------------------
# engine-independent bookkeeping
# --------------------------------------------------------------------------------------


@dataclass
class SweepProgress:
    """Counts reported to a progress callback after every returned point."""

    total: int              # points in the study
    skipped: int            # finished before this run (not rerun)
    done: int = 0           # finished in this run
    failed: int = 0         # failed in this run
    running: int = 0        # executing now (in-flight points, at most the worker slots)
    queued: int = 0         # to run, waiting for a free worker
    last: str = ""          # id of the point that just returned
    last_status: str = ""


@dataclass
class StudyReport:
    """What a study run did; ``computed`` lists the points run in this invocation.

    ``tasks``: tasks submitted (a task runs a batch of points); ``client_seconds``: the
    time the client spent on its own work (submitting, taking results, writing rows,
    progress), not waiting for workers (s).
    """

    out: Path
    total: int
    skipped: list[str] = field(default_factory=list)
    computed: list[str] = field(default_factory=list)
    failed: list[str] = field(default_factory=list)
    wall_time_s: float = 0.0
    engine: str = ""
    tasks: int = 0
    client_seconds: float = 0.0
    #: where the run's wall time went (s, :meth:`StudyRecorder.mark`): "engine" (the
    #: cluster and client ready; Dask only), "first_point" and "last_point" (returned),
    #: "closed" (the engine shut down, the table complete), "end"; and durations:
    #: "plots_during_run" (the client drawing summary.png while points ran),
    #: "final_plots"
    phases: dict[str, float] = field(default_factory=dict)

    def timing_line(self) -> str:
        """The phases in one line (the CLI prints it), or "" when there are none."""
        ph = self.phases
        if "end" not in ph:
            return ""
        parts = []
        if "engine" in ph:
            parts.append(f"engine ready at {ph['engine']:.2f} s")
        if "first_point" in ph:
            parts.append(f"points returned from {ph['first_point']:.2f} to "
                         f"{ph['last_point']:.2f} s")
        parts.append(f"closed at {ph['closed']:.2f} s")
        parts.append(f"plots {ph.get('final_plots', 0.0):.2f} s at the end, "
                     f"{ph.get('plots_during_run', 0.0):.2f} s during the run")
        return "timing: " + "; ".join(parts) + f"; end at {ph['end']:.2f} s"

    @property
    def ok(self) -> bool:
        """True when every point of the study is finished."""
        return not self.failed and len(self.skipped) + len(self.computed) == self.total


class ProgressFile:
    """``DIR/progress.json`` kept current by a thread: the latest counts, written at most
    every ``interval`` s and once more on :meth:`close`.

    Replacing a file (write, then rename over the old one) can take milliseconds (a
    journaling file system flushes the new data first: 4 ms a write on the machine of
    bench/results/sweeps.md); the loop that records points only hands over a dict. An
    error of a write (a full disk) is raised by the next :meth:`update` or :meth:`close`.
    """

    def __init__(self, path: Path, interval: float = 0.5) -> None:
        self.path, self.interval = Path(path), interval
        self._data: dict[str, Any] | None = None
        self._error: BaseException | None = None
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="kvrod-progress", daemon=True)
        self._thread.start()

    def update(self, data: dict[str, Any]) -> None:
        """The counts to write next."""
        self._raise()
        with self._lock:
            self._data = data

    def _raise(self) -> None:
        if self._error is not None:
            error, self._error = self._error, None
            raise error

    def _flush(self) -> None:
        with self._lock:
            data, self._data = self._data, None
        if data is not None:
            write_json(self.path, data)

    def _run(self) -> None:
        while not self._stop.wait(self.interval):
            try:
                self._flush()
            except OSError as exc:
                self._error = exc

    def close(self, data: dict[str, Any] | None = None) -> None:
        """Stop the thread and write ``data`` (else what is pending) now."""
        self._stop.set()
        self._thread.join()
        if data is not None:
            self._data = data
        self._raise()
        self._flush()


class StudyRecorder:
    """Client-side bookkeeping shared by the engines: resume scan, table, progress, plots.

    The resume scan reads the summaries in ``DIR/points`` (the folders there, not the
    study's points: a study of 10^9 points with 100 done reads 100 files). The points to
    run come from :meth:`todo`, made one by one. ``plot_interval`` (s) throttles the plot
    refresh while points return; the table grows by a row per returned point.
    """

    def __init__(self, study: Study, out: Path, rerun_failed: bool = True,
                 plot_interval: float = 10.0, plots: bool = True) -> None:
        self.study, self.out = study, Path(out)
        self.plots, self.plot_interval = plots, plot_interval
        self._last_plot = time.monotonic()   # first refresh after plot_interval
        self._plot_due = False
        self.started_at = time.time()
        self._t0 = time.perf_counter()
        self._preload: threading.Thread | None = None
        self.out.mkdir(parents=True, exist_ok=True)
        if study.source:
            write_text(self.out / "study.toml", study.source)
        self.report = StudyReport(out=self.out, total=len(study.points))
        #: table rows of the points returned (and of those kept from earlier runs), and
        #: their positions in the study (the plots draw them in study order)
        self.rows: dict[str, dict[str, Any]] = {}
        self.order: dict[str, int] = {}
        for i, p, s in self._scan(rerun_failed):
            self.report.skipped.append(p.id)
            if not is_finished(s):
                self.report.failed.append(p.id)
            self.rows[p.id] = table_row(study, p, s)
            self.order[p.id] = i
        self._keep = set(self.rows)
        self.n_todo = len(study.points) - len(self._keep)
        if plots and self.n_todo and plot_axis(study) is not None:   # points to draw
            self._preload = _preload_pyplot()
        self.progress = SweepProgress(total=len(study.points), skipped=len(self._keep))
        #: worker threads executing points (None: unknown, all in-flight count as running)
        self.slots: int | None = None
        self.in_flight: dict[str, tuple[int, StudyPoint]] = {}
        self._returned = 0
        self._table = TableAppender(self.out / TABLE_NAME,
                                    table_columns(study.param_columns), self.rows)
        self._progress_file = ProgressFile(self.out / "progress.json")

    def _scan(self, rerun_failed: bool) -> list[tuple[int, StudyPoint, dict]]:
        """(position, point, summary) of the points in DIR/points that are not run again,
        in study order."""
        folder = self.out / "points"
        try:
            names = os.listdir(folder)
        except OSError:
            return []
        found = []
        for name in names:
            s = _read_summary(folder / name / "summary.json")
            if s is None or not (is_finished(s) or not rerun_failed):
                continue
            meta = s.get("point")
            params = meta.get("parameters") if isinstance(meta, dict) else None
            if not isinstance(params, dict):
                continue
            i = self.study.points.find(params)
            if i is None:
                continue
            p = self.study.points[i]
            if p.id == name:
                found.append((i, p, s))
        found.sort(key=lambda t: t[0])
        return found

    def todo(self) -> Iterator[tuple[int, StudyPoint]]:
        """(position, point) of every point to run, in study order, made as asked for."""
        for i, p in enumerate(self.study.points):
            if p.id not in self._keep:
                yield i, p

    def mark_running(self, points: Iterable[tuple[int, StudyPoint]]) -> None:
        """Count submitted points as in flight."""
        for i, p in points:
            self.in_flight[p.id] = (i, p)
        self._count()
        self._progress_file.update(self._counts())

    def _count(self) -> None:
        pr = self.progress
        n = len(self.in_flight)
        pr.running = n if not self.slots else min(n, self.slots)
        pr.queued = max(0, self.n_todo - self._returned - pr.running)

    def _counts(self) -> dict[str, Any]:
        """What DIR/progress.json holds: the live counts."""
        pr = self.progress
        return {"total": pr.total, "skipped": pr.skipped, "done": pr.done,
                "failed": pr.failed, "running": pr.running, "queued": pr.queued,
                "last": pr.last, "last_status": pr.last_status}

    def _add(self, i: int, point: StudyPoint, status: str, row: dict[str, Any]) -> None:
        self.rows[point.id] = row
        self.order[point.id] = i
        self._table.append([row])
        self.report.computed.append(point.id)
        self._returned += 1
        pr = self.progress
        if status == FINISHED:
            pr.done += 1
        else:
            pr.failed += 1
            self.report.failed.append(point.id)
        pr.last, pr.last_status = point.id, status

    def record(self, result: PointResult) -> SweepProgress:
        """A returned point: its files (when the worker sent them), its row, the counts
        and progress.json; the plots, throttled, are only marked due here: the engine
        draws them with :meth:`refresh_plots` once its workers have work again (and
        :meth:`close` at the end)."""
        i, point = self.in_flight.pop(result.point_id)
        if result.files is not None:
            write_point(self.out, PointOutcome(point.id, point.params, result.status, "",
                                               result.files))
        self._add(i, point, result.status, result.row)
        self._count()
        self._progress_file.update(self._counts())
        self.mark("last_point")
        self.report.phases.setdefault("first_point", self.report.phases["last_point"])
        if self.plots and time.monotonic() - self._last_plot >= self.plot_interval:
            self._plot_due = True
        return self.progress

    def mark(self, phase: str) -> None:
        """``report.phases[phase]`` <- seconds since this recorder was made."""
        self.report.phases[phase] = time.perf_counter() - self._t0

    def refresh_plots(self) -> None:
        """Redraw summary.png if :meth:`record` found it due: the engines call this once
        their workers have work again (the Dask feeder after topping up its tasks), so
        that the drawing (~0.3 s; a first one also imports matplotlib) never leaves a
        worker waiting for the client."""
        if not self._plot_due:
            return
        self._plot_due = False
        t = time.perf_counter()
        self._plot()
        self._last_plot = time.monotonic()
        ph = self.report.phases
        ph["plots_during_run"] = ph.get("plots_during_run", 0.0) + time.perf_counter() - t

    def _plot(self) -> None:
        write_plots(self.out, self.study,
                    {pid: self.rows[pid] for pid in sorted(self.rows, key=self.order.get)})

    def close(self) -> StudyReport:
        """End of a run (also an interrupted one): rows of in-flight points whose summary
        a worker wrote in this run are added, then progress.json and the plots."""
        try:
            for i, p in list(self.in_flight.values()):
                s = read_summary(self.out, p)
                computed = (s or {}).get("point", {}).get("computed_at")
                if isinstance(computed, (int, float)) and computed >= self.started_at:
                    self._add(i, p, s.get("status", FAILED), table_row(self.study, p, s))
        finally:
            self.in_flight.clear()
            self._table.close()
            self._count()
            self.progress.queued = 0
            self._progress_file.close(self._counts())
        self.mark("closed")
        if self._preload is not None:
            # not left importing when the process ends (write_plots may draw nothing)
            self._preload.join(timeout=30.0)
        if self.plots:
            t = time.perf_counter()
            self._plot()
            self.report.phases["final_plots"] = time.perf_counter() - t
        self.mark("end")
        return self.report


def _preload_pyplot() -> threading.Thread | None:
    """Import matplotlib's pyplot (``runtime.io.figures.pyplot``: ~0.5 s) on a thread
    while the first points run, so that the study's plots do not import it on the
    client's critical path: at the end of the run, or in a refresh while workers wait
    for tasks. Much of an import holds the GIL, but the client mostly waits on its
    workers then (a serial study's points run in C, without it). A failed import is
    left to the plots themselves, which raise it where they always did. Returns the
    thread (:meth:`StudyRecorder.close` joins it), or None when pyplot is loaded."""
    if "matplotlib.pyplot" in sys.modules:
        return None

    def load() -> None:
        with contextlib.suppress(Exception):
            from runtime.io.figures import pyplot

            pyplot()

    thread = threading.Thread(target=load, name="kvrod-pyplot", daemon=True)
    thread.start()
    return thread


@contextlib.contextmanager
def ctrl_c_noticed() -> Iterator[Callable[[], bool]]:
    """Remember a Ctrl-C (SIGINT) that comes while points run; yields ``interrupted()``.

    Whatever the interrupted code makes of its KeyboardInterrupt, the study stops: an
    exception while cleaning up can replace it (a ``ValueError`` of a half-written NPZ,
    of a run's outputs cut short), and the point would be recorded as failed while the
    study went on. Installed only in the main thread over a Python-level handler (the
    default one raises KeyboardInterrupt; it still does)."""
    previous = signal.getsignal(signal.SIGINT)
    if threading.current_thread() is not threading.main_thread() or not callable(previous):
        yield lambda: False
        return
    seen: list[int] = []

    def remember(signum, frame):
        seen.append(signum)
        previous(signum, frame)

    signal.signal(signal.SIGINT, remember)
    try:
        yield lambda: bool(seen)
    finally:
        signal.signal(signal.SIGINT, previous)


def run_study_serial(study: Study, out: Path,
                     progress: Callable[[SweepProgress], object] | None = None,
                     rerun_failed: bool = True, plots: bool = True,
                     on_start: Callable[[SweepProgress], object] | None = None
                     ) -> StudyReport:
    """Run the study's points one after another in this process (no Dask).

    The reference the distributed engine is checked against, and the baseline of the
    speed-up measurement. ``on_start(SweepProgress)`` is called once the resume scan is
    done (the counts of points to run and skipped), ``progress`` after every point.
    Ctrl-C stops the point being run (nothing of it is written); the others stay.
    """
    t0 = time.perf_counter()
    rec = StudyRecorder(study, out, rerun_failed=rerun_failed, plots=plots)
    rec.slots = 1
    try:
        if on_start is not None:
            on_start(rec.progress)
        with ctrl_c_noticed() as interrupted:
            for i, p in rec.todo():
                rec.refresh_plots()          # due after the last point: close() draws
                rec.mark_running([(i, p)])
                t = time.perf_counter()
                try:
                    summary = run_point_into(rec.out, study.problem, p.id, p.params,
                                             interrupted)
                except Exception:
                    if interrupted():      # the Ctrl-C, not what cleaning up made of it
                        raise KeyboardInterrupt from None
                    raise
                pr = rec.record(PointResult(p.id, summary["status"],
                                            table_row(study, p, summary),
                                            time.perf_counter() - t))
                if progress is not None:
                    progress(pr)
    finally:
        report = rec.close()
    report.wall_time_s = time.perf_counter() - t0
    report.engine = "serial"
    report.tasks = len(report.computed)
    return report
