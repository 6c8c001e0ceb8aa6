"""Parameter studies: study definition, per-point runs, the study table.

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
``loads.0.time.start``); ``tau`` sets tau_S = tau_B = tau (the paper's convention). Every
point is built through the problem schema when the study is loaded, so a bad name, type or
value is a :class:`StudyError` naming the point before anything runs; a point whose run
fails is recorded as failed and the others run.

Results layout of a study folder ``DIR``::

    DIR/study.toml                       copy of the study file
    DIR/points/<point id>/summary.json   per point (status, message, figures, parameters)
    DIR/points/<point id>/series.npz     per point time series (when a run got that far)
    DIR/progress.json                    live counts: done, failed, running, queued
    DIR/study.csv                        one row per point: appended as points return,
                                         rebuilt in study order from the summaries
    DIR/summary.png                      damping ratios and periods against a varied parameter

The point id is stable: a readable slug of the varied parameters plus a hash of all of
the point's parameters, so the same point gets the same folder on every run, and a
finished point (summary.json with status "finished" and the same parameters) is not run
again. Every file is written atomically (temporary name, then rename).

This module holds everything except the distributed engine (``runtime.study.sweep_dask``): the
study, the task function :func:`run_point` that workers execute (it takes a plain
parameter dict and returns a picklable :class:`PointOutcome`), writing a point's folder,
the table, the plots and a serial engine (:func:`run_study_serial`). It does not import
Dask.
"""

from __future__ import annotations

import csv
import hashlib
import io
import itertools
import json
import math
import os
import re
import socket
import time
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path
from typing import Any

from runtime.io.atomic import write_bytes, write_text
from runtime.io.results import write_json, write_run

#: top-level keys of a study file
STUDY_KEYS = ("name", "problem", "scenario", "fixed", "grid", "points")
#: largest study run without confirmation, and the command-line flag that confirms
MAX_POINTS = 10_000
CONFIRM_FLAG = "--yes"
#: status of a point that has no finished/failed summary yet
PENDING, RUNNING, FINISHED, FAILED = "pending", "running", "finished", "failed"


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
    from runtime.problem.registry import problem_path

    path = problem_path(problem).resolve()
    st = path.stat()
    return _base_problem(problem, str(path), st.st_mtime_ns, st.st_size)


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


def canonical_json(params: Mapping[str, Any]) -> str:
    """The parameters as sorted, compact JSON (floats in shortest round-trip form)."""
    return json.dumps(dict(params), sort_keys=True, separators=(",", ":"))


def _slug_value(v: Any) -> str:
    s = f"{v:g}" if isinstance(v, float) else str(v)
    return re.sub(r"[^A-Za-z0-9.+-]", "_", s)


def point_id(params: Mapping[str, Any], varied: Sequence[str]) -> str:
    """Stable folder name: slug of the varied parameters (sorted by name, so reordering
    the study file keeps the ids) + 10 hex digits of the sha256 of all parameters."""
    digest = hashlib.sha256(canonical_json(params).encode()).hexdigest()[:10]
    slug = "_".join(f"{k}={_slug_value(params[k])}" for k in sorted(varied) if k in params)
    slug = slug[:80].rstrip("_")
    return f"{slug}-{digest}" if slug else digest


@dataclass(frozen=True)
class StudyPoint:
    """One simulation of a study: its stable id and its full parameter set (fixed + varied)."""

    id: str
    params: dict[str, Any]


@dataclass(frozen=True)
class Study:
    """A parameter study: problem (file or built-in name), fixed parameters, varied names
    and the points.

    ``points`` are unique by id (a point listed twice runs once) and ordered as written:
    the grid's Cartesian product first (last key fastest), then the explicit points.
    """

    name: str
    problem: str
    fixed: dict[str, Any]
    varied: tuple[str, ...]
    points: tuple[StudyPoint, ...]
    source: str = ""          # the TOML text the study was read from (copied to DIR)

    @property
    def param_columns(self) -> tuple[str, ...]:
        """Parameter columns of the table: varied ones first, then the fixed ones."""
        cols = list(self.varied)
        for p in self.points:
            cols += [k for k in p.params if k not in cols]
        return tuple(cols)


def study_from_dict(data: Mapping[str, Any], name: str = "study", source: str = "",
                    max_points: int | float | None = None) -> Study:
    """Build a :class:`Study` from the parsed TOML (see the module docstring).

    ``max_points``: largest study accepted (default :data:`MAX_POINTS`; pass ``math.inf``
    once the user confirmed a larger one).
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
    grid_c = {k: [_check_params({k: v}, "[grid]")[k] for v in vals] for k, vals in grid.items()}
    _check_params({k: v[0] for k, v in grid_c.items()}, "[grid]")  # unknown names, tau clash
    raw_points: list[dict[str, Any]] = []
    if grid_c:
        for combo in itertools.product(*grid_c.values()):
            raw_points.append(dict(zip(grid_c, combo, strict=True)))
    for i, p in enumerate(listed):
        raw_points.append(_check_params(p, f"points[{i}]"))
    if not raw_points:
        raise StudyError("the study has no points: give a [grid] or [[points]]")
    varied: list[str] = list(grid_c)
    for p in raw_points:
        varied += [k for k in p if k not in varied]
    try:
        base = base_problem(problem)        # the registry and the file: once per study
    except ValueError as exc:                # the problem file itself is bad
        raise StudyError(f"problem {problem!r}: {exc}") from None
    points: dict[str, StudyPoint] = {}
    for p in raw_points:
        for a, b in ((("tau",), ("tau_S", "tau_B")), (("tau_S", "tau_B"), ("tau",))):
            fa = [k for k in a if k in fixed]
            pb = [k for k in b if k in p]
            if fa and pb:     # would tau_B keep the fixed tau, or not? say it instead
                raise StudyError(f"{fa[0]} is fixed but {pb[0]} varies: give the viscosity "
                                 "one way, either tau or tau_S/tau_B, in [fixed] and the "
                                 "points alike")
        params = {**{k: v for k, v in fixed.items() if k not in p}, **p}
        _check_params(params, "point")
        pid = point_id(params, varied)
        if pid not in points:   # every value checked by the problem schema before any run
            check_point(base, params, f"point {pid}")
        points.setdefault(pid, StudyPoint(pid, params))
    return Study(name=name, problem=problem, fixed=fixed, varied=tuple(varied),
                 points=tuple(points.values()), source=source)


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
# the task: parameters in, outcome out (runs on a worker; ships no compiled objects)
# --------------------------------------------------------------------------------------


@dataclass
class PointOutcome:
    """What :func:`run_point` returns: plain, picklable data.

    ``files`` maps file names of the point's folder (summary.json, series.npz) to their
    bytes, written by :func:`runtime.io.results.write_run` on the worker; the client stores
    them unchanged (so workers need no file system shared with the client).
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


def _library_loads() -> int:
    from runtime.model import build

    return build.library_loads()


def _point_meta(problem: str, point_id: str, params: Mapping[str, Any],
                wall_time_s: float) -> dict[str, Any]:
    return {"id": point_id, "problem": problem,
            "parameters": json.loads(canonical_json(params)),
            "host": socket.gethostname(), "pid": os.getpid(), "computed_at": time.time(),
            "wall_time_s": wall_time_s}


def run_point(problem: str, point_id: str, params: Mapping[str, Any]) -> PointOutcome:
    """Run one point; never raises (an exception becomes status "failed" + its message).

    This is the function workers execute: a parameter dict in, a :class:`PointOutcome`
    (the bytes of summary.json and series.npz) out. The summary carries ``point`` =
    {id, problem, parameters, host, pid, computed_at, wall_time_s}, which the resume
    check compares against the study.
    """
    import tempfile

    t0 = time.perf_counter()
    params = dict(params)
    run = None
    try:
        from runtime.problem.registry import load_problem
        from runtime.simulate.simulate import simulate

        run = simulate(load_problem(base_problem(problem), params))
        if run.interrupt is not None:      # Ctrl-C stops the study, it is no failed point
            raise run.interrupt
        status, message = run.status, run.message
    except Exception as exc:  # noqa: BLE001 - a failing point must not stop the study
        status, message = FAILED, f"{type(exc).__name__}: {exc}"
    wall = time.perf_counter() - t0
    meta = _point_meta(problem, point_id, params, wall)
    files: dict[str, bytes] = {}
    with tempfile.TemporaryDirectory(prefix="kvrod-point-") as tmp:
        if run is not None:
            summary = write_run(Path(tmp), run, extra={"point": meta})
            status = summary["status"]
        else:
            write_json(Path(tmp) / "summary.json",
                       {"status": status, "message": message, "parameters": params,
                        "wall_time_s": wall, "point": meta})
        for f in sorted(Path(tmp).iterdir()):
            files[f.name] = f.read_bytes()
    return PointOutcome(point_id=point_id, params=params, status=status, message=message,
                        files=files, wall_time_s=wall, host=meta["host"], pid=meta["pid"],
                        worker_lib_loads=_library_loads())


# --------------------------------------------------------------------------------------
# point folders
# --------------------------------------------------------------------------------------


def point_dir(out: Path, pid: str) -> Path:
    """Folder of one point."""
    return Path(out) / "points" / pid


def read_summary(out: Path, point: StudyPoint) -> dict | None:
    """The point's summary.json if it exists, is readable and belongs to these parameters."""
    path = point_dir(out, point.id) / "summary.json"
    try:
        s = json.loads(path.read_text())
    except (OSError, ValueError):
        return None
    meta = s.get("point", {}) if isinstance(s, dict) else {}
    if meta.get("parameters") != json.loads(canonical_json(point.params)):
        return None
    return s


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


def points_to_run(study: Study, out: Path, rerun_failed: bool = True) -> list[StudyPoint]:
    """Points without a finished summary in ``out`` (and without a failed one, if not
    rerun_failed): what a (re)started study will run."""
    todo = []
    for p in study.points:
        s = read_summary(out, p)
        if not (is_finished(s) or (s is not None and not rerun_failed)):
            todo.append(p)
    return todo


def failure_outcome(problem: str, point: StudyPoint, message: str) -> PointOutcome:
    """Outcome recorded by the client when a task could not run (e.g. workers died)."""
    meta = _point_meta(problem, point.id, point.params, 0.0)
    summary = {"status": FAILED, "message": message, "parameters": dict(point.params),
               "wall_time_s": 0.0, "point": meta}
    return PointOutcome(point_id=point.id, params=dict(point.params), status=FAILED,
                        message=message, host=meta["host"], pid=meta["pid"],
                        files={"summary.json": (json.dumps(summary, indent=2) + "\n").encode()})


# --------------------------------------------------------------------------------------
# the table and plots
# --------------------------------------------------------------------------------------

FIGURE_COLUMNS = ("status", "message", "zeta_first", "zeta_last", "n_peaks", "period_mean",
                  "static_tip_x", "static_tip_z", "energy_balance_max_rel", "zeta_linear",
                  "tau_E", "wall_time_s")


def table_row(study: Study, point: StudyPoint, summary: Mapping[str, Any] | None,
              status: str | None = None) -> dict[str, Any]:
    """One table row: id, the point's parameters, status, message and key figures."""
    row: dict[str, Any] = {"point_id": point.id}
    row.update({k: point.params.get(k, "") for k in study.param_columns})
    s = summary or {}
    z = s.get("damping_ratios") or []
    per = s.get("periods") or []
    tip = (s.get("static") or {}).get("tip") or []
    row.update({
        "status": status or s.get("status", PENDING),
        "message": " ".join(str(s.get("message", "")).split()),
        "zeta_first": z[0] if z else "",
        "zeta_last": z[-1] if z else "",
        "n_peaks": len(s.get("peaks") or []) if summary else "",
        "period_mean": sum(per) / len(per) if per else "",
        "static_tip_x": tip[0] if len(tip) == 3 else "",
        "static_tip_z": tip[2] if len(tip) == 3 else "",
        "energy_balance_max_rel": s.get("energy_balance_max_rel", "")
        if s.get("energy_balance_max_rel") is not None else "",
        "zeta_linear": (s.get("linear_prediction") or {}).get("zeta_1", ""),
        "tau_E": s.get("tau_E", ""),
        "wall_time_s": s.get("wall_time_s", "") if summary else "",
    })
    return row


def _atomic_text(path: Path, text: str) -> Path:
    return write_text(path, text)


def write_table(out: Path, study: Study, rows: Mapping[str, Mapping[str, Any]]) -> Path:
    """Write ``DIR/study.csv`` atomically, one row per study point in study order."""
    cols = ["point_id", *study.param_columns, *FIGURE_COLUMNS]
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=cols, lineterminator="\n")
    w.writeheader()
    for p in study.points:
        row = rows.get(p.id) or table_row(study, p, None)
        w.writerow({c: (repr(v) if isinstance(v, float) else v) for c, v in row.items()})
    return _atomic_text(Path(out) / "study.csv", buf.getvalue())


class TableAppender:
    """``study.csv`` written incrementally while a study runs: the header, then one row per
    point as it returns (appended and flushed: O(1) per point, not a rewrite of the table).
    A crash leaves a valid CSV of the points returned so far."""

    def __init__(self, path: Path, study: Study) -> None:
        self.cols = ["point_id", *study.param_columns, *FIGURE_COLUMNS]
        path.parent.mkdir(parents=True, exist_ok=True)
        self._f = open(path, "w", newline="")
        self._w = csv.DictWriter(self._f, fieldnames=self.cols, lineterminator="\n")
        self._w.writeheader()
        self._f.flush()

    def append(self, row: Mapping[str, Any]) -> None:
        self._w.writerow({c: (repr(v) if isinstance(v, float) else v) for c, v in row.items()})
        self._f.flush()

    def close(self) -> None:
        if not self._f.closed:
            self._f.close()


def read_table(path: Path) -> list[dict[str, str]]:
    """The rows of a study.csv (strings, as written)."""
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def rebuild_table(out: Path, study: Study,
                  running: Iterable[str] = ()) -> dict[str, dict[str, Any]]:
    """Rows of every point from its summary.json (``running`` ids are marked running)."""
    running = set(running)
    rows = {}
    for p in study.points:
        s = read_summary(out, p)
        st = RUNNING if p.id in running and not is_finished(s) else None
        rows[p.id] = table_row(study, p, s, status=st)
    write_table(out, study, rows)
    return rows


#: units of the parameters, for axis labels
UNITS = {"tau": "s", "tau_S": "s", "tau_B": "s", "length": "m", "width": "m", "height": "m",
         "density": "kg/m^3", "youngs_modulus": "Pa", "poisson_ratio": "-", "tip_force": "N",
         "n_elements": "-", "t_end": "s", "rtol": "-", "atol": "-", "load_steps": "-",
         "output_step": "s"}


def _plot_axis(study: Study) -> str | None:
    numeric = [k for k in study.varied
               if all(isinstance(p.params.get(k), (int, float)) for p in study.points)]
    for k in ("tau", "tau_S", "tau_B"):
        if k in numeric:
            return k
    return numeric[0] if numeric else None


def write_plots(out: Path, study: Study, rows: Mapping[str, Mapping[str, Any]]) -> Path | None:
    """``DIR/summary.png``: first/last damping ratio and mean period against the first
    varied parameter (tau if varied), one line per combination of the other varied ones.
    Returns None when there is nothing to plot yet."""
    x = _plot_axis(study)
    if x is None:
        return None
    others = [k for k in study.varied if k != x]
    groups: dict[tuple, list[tuple[float, Mapping[str, Any]]]] = {}
    for p in study.points:
        row = rows.get(p.id)
        if row is None or row.get("status") != FINISHED or row.get("zeta_first") == "":
            continue
        key = tuple(p.params.get(k) for k in others)
        groups.setdefault(key, []).append((float(p.params[x]), row))
    if not groups:
        return None
    from runtime.io.figures import pyplot, save

    plt = pyplot()
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4.5))
    for key, pts in groups.items():
        pts.sort(key=lambda t: t[0])
        xs = [t[0] for t in pts]
        label = ", ".join(f"{k}={_slug_value(v)}" for k, v in zip(others, key, strict=True))
        line, = ax1.plot(xs, [t[1]["zeta_first"] for t in pts], "o-",
                         label=f"first {label}".strip())
        ax1.plot(xs, [t[1]["zeta_last"] for t in pts], "s--", color=line.get_color(),
                 label=f"last {label}".strip())
        per = [(a, r["period_mean"]) for a, r in pts if r.get("period_mean") != ""]
        if per:
            ax2.plot([a for a, _ in per], [b for _, b in per], "o-", color=line.get_color(),
                     label=label or None)
    xlabel = f"{x} [{UNITS.get(x, '-')}]"
    ax1.set_xlabel(xlabel)
    ax1.set_ylabel("damping ratio zeta [-] (first and last cycle)")
    ax2.set_xlabel(xlabel)
    ax2.set_ylabel("mean period of the tip maxima [s]")
    ax1.legend(fontsize=7)
    if others:
        ax2.legend(fontsize=7)
    fig.suptitle(f"study {study.name}: {sum(len(v) for v in groups.values())} finished points")
    return save(fig, Path(out) / "summary.png", dpi=120, bbox_inches="tight")


# --------------------------------------------------------------------------------------
# engine-independent bookkeeping
# --------------------------------------------------------------------------------------


@dataclass
class SweepProgress:
    """Counts reported to a progress callback after every finished point."""

    total: int              # points in the study
    skipped: int            # finished before this run (not rerun)
    done: int = 0           # finished in this run
    failed: int = 0         # failed in this run
    running: int = 0        # executing now (in-flight points, at most the worker slots)
    queued: int = 0         # submitted, waiting for a free worker
    last: str = ""          # id of the point that just returned
    last_status: str = ""


@dataclass
class StudyReport:
    """What a study run did; ``computed`` lists the points run in this invocation."""

    out: Path
    total: int
    skipped: list[str] = field(default_factory=list)
    computed: list[str] = field(default_factory=list)
    failed: list[str] = field(default_factory=list)
    wall_time_s: float = 0.0
    engine: str = ""

    @property
    def ok(self) -> bool:
        """True when every point of the study is finished."""
        return not self.failed and len(self.skipped) + len(self.computed) == self.total


class StudyRecorder:
    """Client-side bookkeeping shared by the engines: resume scan, writes, table, plots.

    ``plot_interval`` (s) throttles the plot refresh while points finish; the table is
    rewritten (atomically) after every point, the plots at least at the end.
    """

    def __init__(self, study: Study, out: Path, rerun_failed: bool = True,
                 plot_interval: float = 10.0, plots: bool = True) -> None:
        self.study, self.out = study, Path(out)
        self.plots, self.plot_interval = plots, plot_interval
        self._last_plot = time.monotonic()   # first refresh after plot_interval
        self.out.mkdir(parents=True, exist_ok=True)
        if study.source:
            _atomic_text(self.out / "study.toml", study.source)
        self.rows: dict[str, dict[str, Any]] = {}
        self.todo: list[StudyPoint] = []
        self.report = StudyReport(out=self.out, total=len(study.points))
        for p in study.points:
            s = read_summary(self.out, p)
            if is_finished(s) or (s is not None and not rerun_failed):
                self.report.skipped.append(p.id)
                if s is not None and not is_finished(s):
                    self.report.failed.append(p.id)
            else:
                self.todo.append(p)
                s = None
            self.rows[p.id] = table_row(study, p, s)
        self.progress = SweepProgress(total=len(study.points), skipped=len(self.report.skipped))
        #: worker threads executing points (None: unknown, all in-flight count as running)
        self.slots: int | None = None
        # study.csv grows by one row per returned point (rows of earlier runs first); the
        # final table in study order is written by close()
        self._table = TableAppender(self.out / "study.csv", study)
        self._last_progress = -1e9
        for p in study.points:
            if p.id in self.report.skipped:
                self._table.append(self.rows[p.id])

    def mark_running(self, ids: Iterable[str]) -> None:
        """Count submitted points as running (progress.json shows them at once)."""
        for pid in ids:
            self.rows[pid]["status"] = RUNNING
        self._count_in_flight()
        self._write_progress(force=True)

    def _write_progress(self, force: bool = False) -> None:
        """DIR/progress.json: the live counts (throttled to one write per 0.5 s)."""
        now = time.monotonic()
        if not force and now - self._last_progress < 0.5:
            return
        self._last_progress = now
        pr = self.progress
        write_json(self.out / "progress.json",
                   {"total": pr.total, "skipped": pr.skipped, "done": pr.done,
                    "failed": pr.failed, "running": pr.running, "queued": pr.queued,
                    "last": pr.last, "last_status": pr.last_status})

    def _count_in_flight(self) -> None:
        inflight = sum(r["status"] == RUNNING for r in self.rows.values())
        pr = self.progress
        pr.running = inflight if not self.slots else min(inflight, self.slots)
        pr.queued = inflight - pr.running

    def record(self, outcome: PointOutcome) -> SweepProgress:
        """Write a returned point, update the table (and, throttled, the plots)."""
        point = next(p for p in self.study.points if p.id == outcome.point_id)
        summary = write_point(self.out, outcome)
        self.rows[point.id] = table_row(self.study, point, summary)
        self._table.append(self.rows[point.id])
        self.report.computed.append(point.id)
        pr = self.progress
        if summary["status"] == FINISHED:
            pr.done += 1
        else:
            pr.failed += 1
            self.report.failed.append(point.id)
        self._count_in_flight()
        pr.last, pr.last_status = point.id, summary["status"]
        self._write_progress()
        now = time.monotonic()
        if self.plots and now - self._last_plot >= self.plot_interval:
            self._last_plot = now
            write_plots(self.out, self.study, self.rows)
        return pr

    def close(self) -> StudyReport:
        """Final table (rebuilt from the summaries on disk, in study order) and plots."""
        self._table.close()
        for row in self.rows.values():
            if row.get("status") == RUNNING:
                row["status"] = PENDING
        self._count_in_flight()
        self._write_progress(force=True)
        self.rows = rebuild_table(self.out, self.study)
        if self.plots:
            write_plots(self.out, self.study, self.rows)
        return self.report


def run_study_serial(study: Study, out: Path,
                     progress: Callable[[SweepProgress], object] | None = None,
                     rerun_failed: bool = True, plots: bool = True) -> StudyReport:
    """Run the study's points one after another in this process (no Dask).

    The reference the distributed engine is checked against, and the baseline of the
    speed-up measurement.
    """
    t0 = time.perf_counter()
    rec = StudyRecorder(study, out, rerun_failed=rerun_failed, plots=plots)
    rec.slots = 1
    try:
        for p in rec.todo:
            rec.mark_running([p.id])
            pr = rec.record(run_point(study.problem, p.id, p.params))
            if progress is not None:
                progress(pr)
    finally:
        report = rec.close()
    report.wall_time_s = time.perf_counter() - t0
    report.engine = "serial"
    return report
