"""Measurements for ``kvrod fit``: the three kinds of data file, read and checked before any
simulation (docs/design.md, "Identification (kvrod fit)").

Every file is a CSV table with a header row; lines starting with ``#`` are comments. The
columns say what kind of measurement it is, and so which model the fit runs:

* **a record** (``kind = "series"``, model: a simulation): a column ``t`` (s, time since
  the start of the simulation, t = 0 the release) and columns named like the channels of
  ``series.npz``: ``end.x end.y end.z start.x start.y start.z`` (positions of the rod's
  ends, m) for a single rod, ``NAME.end.x``, ``NAME.start.z`` for the rods of an assembly.
  Any subset of the columns will do.
* **a static shape** (``kind = "shape"``, model: the static equilibrium): a column ``s``
  (m, arc length of the reference centreline from the rod's start, 0 ... L) and any of
  ``x y z`` (m, the deformed centreline's position there); for an assembly the columns
  ``NAME.x`` ... of one rod NAME (one rod per file).
* **measured modes** (``kind = "modes"``, model: damped modal analysis): a column
  ``mode`` naming each mode, either by its rank in ``kvrod modes``' table (``1``, ``2``,
  ...) or by family and rank within it (``bending-2:1``, ``torsion:1``: robust where modes
  are close and may swap order), and ``omega`` (rad/s, the undamped natural angular
  frequency) or ``frequency_hz`` (Hz), and/or ``zeta`` (-, the damping ratio). An empty
  cell of a modes file means "not measured" (e.g. a zeta only for the first mode).

Refused in one line naming the file, the line and the column: a missing header, a column
that names no channel (the allowed ones listed), a repeated column, an empty cell, text or
a non-finite number (NaN, inf), a time that does not increase (unsorted or repeated), a
time before 0, a record longer than the simulation's t_end (both numbers and the flag that
changes it), arc lengths outside the rod, too few data for the parameters.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from runtime.analysis.records import csv_rows

#: the kinds of data and the model each is compared with
KINDS = {"series": "simulate", "shape": "static", "modes": "modes"}
COMPONENTS = "xyz"
#: mode families of runtime.analysis.modal (a ``mode`` cell FAMILY:K names one of them)
MODE_FAMILIES = ("bending-1", "bending-2", "torsion", "axial", "shear")
MODE_QUANTITIES = ("omega", "frequency_hz", "zeta")


class DataError(ValueError):
    """A data file kvrod fit cannot use (one line naming the file, line and column)."""


@dataclass(frozen=True)
class Column:
    """One measured column: ``name`` as in the file, the model ``channel`` it is compared
    with (a record: ``"tip"``, ``"start"``, ``"NAME.end"``, ``"NAME.start"``, the names of
    the sensitivity channels; a shape: ``"positions"`` or ``"NAME.positions"``; modes:
    ``"omega"`` or ``"zeta"``), the ``component`` (0, 1, 2 for x, y, z; 0 for modes), the
    ``values`` (SI: m, rad/s, -; NaN where a modes file leaves a cell empty) and its
    ``unit``."""

    name: str
    channel: str
    component: int
    values: np.ndarray = field(repr=False)
    unit: str = "m"

    @property
    def measured(self) -> np.ndarray:
        """Rows of this column that hold a value (all but a modes file's empty cells)."""
        return np.isfinite(self.values)


@dataclass(frozen=True)
class FitData:
    """A checked data file (see the module docstring).

    ``kind``: "series", "shape" or "modes"; ``abscissa``: t (s) of a record, s (m) of a
    shape, the row number (1, 2, ...) of modes; ``modes``: the ``mode`` cells of a modes
    file (a rank "3" or "FAMILY:K"); ``rod``: the assembly rod a shape belongs to (None for
    a single rod); ``lines``: the file line of each row (for messages)."""

    path: str
    kind: str
    abscissa: np.ndarray = field(repr=False)
    columns: tuple[Column, ...]
    lines: np.ndarray = field(repr=False)
    modes: tuple[str, ...] = ()
    rod: str | None = None

    @property
    def model(self) -> str:
        """The model the data are compared with: "simulate", "static" or "modes"."""
        return KINDS[self.kind]

    @property
    def rows(self) -> int:
        return int(self.abscissa.size)

    @property
    def count(self) -> int:
        """Number of measured values (residuals of the fit)."""
        return int(sum(np.count_nonzero(c.measured) for c in self.columns))

    @property
    def t_end(self) -> float:
        """The record's last time (s); 0 for data without time."""
        return float(self.abscissa[-1]) if self.kind == "series" else 0.0

    def window(self, t_end: float) -> FitData:
        """The record up to time ``t_end`` (s), a prefix of its rows."""
        keep = self.abscissa <= t_end * (1 + 1e-12)
        return FitData(self.path, self.kind, self.abscissa[keep],
                       tuple(Column(c.name, c.channel, c.component, c.values[keep], c.unit)
                             for c in self.columns), self.lines[keep], self.modes, self.rod)


def series_channels(rod_names: Sequence[str] | None) -> dict[str, tuple[str, int]]:
    """The columns a record may have: column name -> (sensitivity channel, component).
    ``rod_names`` None: a single rod (``end.x`` -> ("tip", 0), ``start.z`` -> ("start",
    2)); else an assembly (``NAME.end.y`` -> ("NAME.end", 1))."""
    out: dict[str, tuple[str, int]] = {}
    if rod_names is None:
        for end, channel in (("end", "tip"), ("start", "start")):
            for c, comp in enumerate(COMPONENTS):
                out[f"{end}.{comp}"] = (channel, c)
        return out
    for name in rod_names:
        for end in ("end", "start"):
            for c, comp in enumerate(COMPONENTS):
                out[f"{name}.{end}.{comp}"] = (f"{name}.{end}", c)
    return out


def shape_channels(rod_names: Sequence[str] | None) -> dict[str, tuple[str, int]]:
    """The position columns a static shape may have (beside ``s``): ``x`` -> ("positions",
    0) for a single rod, ``NAME.x`` -> ("NAME.positions", 0) for an assembly."""
    if rod_names is None:
        return {comp: ("positions", c) for c, comp in enumerate(COMPONENTS)}
    return {f"{name}.{comp}": (f"{name}.positions", c) for name in rod_names
            for c, comp in enumerate(COMPONENTS)}


# --------------------------------------------------------------------------------------
# reading
# --------------------------------------------------------------------------------------


def _rows(path: Path) -> tuple[list[str], list[list[str]], list[int]]:
    """(header, body rows, file line of each body row) of a CSV file; comments and blank
    lines skipped."""
    numbered = csv_rows(path, DataError, encoding="utf-8-sig")
    if not numbered:
        raise DataError(f"data file {str(path)!r} is empty")
    header = [c.strip() for c in numbered[0][1]]
    return header, [r for _, r in numbered[1:]], [i for i, _ in numbered[1:]]


def _is_number(s: str) -> bool:
    try:
        float(s)
    except ValueError:
        return False
    return True


def _match(header: list[str], allowed: Sequence[str], fixed: Sequence[str]) -> list[str]:
    """The canonical name of each header cell: ``fixed`` names (t, s, mode) and the
    ``allowed`` channel columns, matched exactly or, where that is unique, ignoring case;
    cells that match nothing are kept as they are (refused by the caller)."""
    names = list(fixed) + list(allowed)
    lower: dict[str, list[str]] = {}
    for n in names:
        lower.setdefault(n.lower(), []).append(n)
    out = []
    for h in header:
        if h in names:
            out.append(h)
        elif len(lower.get(h.lower(), [])) == 1:
            out.append(lower[h.lower()][0])
        else:
            out.append(h)
    return out


def _cell(path: Path, line: int, column: str, text: str, empty_ok: bool = False) -> float:
    cell = text.strip()
    if not cell:
        if empty_ok:
            return math.nan
        raise DataError(f"data file {str(path)!r}: line {line}, column {column!r}: the cell "
                        "is empty; fill in the value or remove that row")
    if not _is_number(cell):
        raise DataError(f"data file {str(path)!r}: line {line}, column {column!r}: {cell!r} "
                        "is not a number; correct or remove that row")
    v = float(cell)
    if not math.isfinite(v):
        raise DataError(f"data file {str(path)!r}: line {line}, column {column!r}: {cell!r} "
                        "is not a finite number (NaN or inf); remove that row or fill in "
                        "the value")
    return v


def _kind(path: Path, header: list[str], series: Sequence[str], shape: Sequence[str]) -> str:
    cols = set(header)
    if "t" in cols:
        return "series"
    if "s" in cols:
        return "shape"
    if "mode" in cols:
        return "modes"
    example = ", ".join(list(series)[:3])
    if cols & set(series):
        raise DataError(f"data file {str(path)!r} has no column 't' (time since the start of "
                        f"the simulation, s) beside its channels ({', '.join(header)}); a "
                        "record needs it")
    raise DataError(f"data file {str(path)!r} has no column 't', 's' or 'mode' (columns: "
                    f"{', '.join(header) or 'none'}): a record needs t (s) and channels such "
                    f"as {example}; a static shape s (m) and {', '.join(list(shape)[:3])}; "
                    "measured modes mode and omega, frequency_hz and/or zeta")


def read_fit_data(path: str | Path, rod_names: Sequence[str] | None = None) -> FitData:
    """Read and check a data file for ``kvrod fit`` (see the module docstring).

    Parameters
    ----------
    path : str or Path
        The CSV file.
    rod_names : sequence of str, optional
        The rods of an assembly (their names prefix the columns); None for a single rod.

    Returns
    -------
    FitData
        The measurements, checked for everything that does not need the problem's
        numbers (:func:`check_against_problem` does the rest).

    Raises
    ------
    DataError
        One line naming the file, and the line and column where one is at fault.
    """
    path = Path(path)
    header_raw, body, lines = _rows(path)
    if all(_is_number(c) for c in header_raw if c):
        raise DataError(f"data file {str(path)!r} has no header row (its first line holds "
                        "numbers): name the columns, e.g. t,end.x")
    series, shape = series_channels(rod_names), shape_channels(rod_names)
    header = _match(header_raw, list(series) + list(shape) + list(MODE_QUANTITIES),
                    ("t", "s", "mode"))
    kind = _kind(path, header, series, shape)
    allowed = {"series": series, "shape": shape,
               "modes": {q: (q if q != "frequency_hz" else "omega", 0)
                         for q in MODE_QUANTITIES}}[kind]
    first = {"series": "t", "shape": "s", "modes": "mode"}[kind]
    seen: set[str] = set()
    for h, raw in zip(header, header_raw, strict=True):
        if h in seen:
            raise DataError(f"data file {str(path)!r}: column {raw!r} appears twice")
        seen.add(h)
        if h != first and h not in allowed:
            what = {"series": "a record", "shape": "a static shape",
                    "modes": "measured modes"}[kind]
            raise DataError(f"data file {str(path)!r}: column {raw!r} names no channel of "
                            f"this {'assembly' if rod_names is not None else 'rod'} for "
                            f"{what}; allowed: {first}, {', '.join(allowed)}")
    data_cols = [h for h in header if h != first]
    if not data_cols:
        raise DataError(f"data file {str(path)!r} has only the column {first!r}; add the "
                        f"measured columns ({', '.join(list(allowed)[:6])}, ...)")
    if kind == "modes" and "omega" in data_cols and "frequency_hz" in data_cols:
        raise DataError(f"data file {str(path)!r}: give omega (rad/s) or frequency_hz (Hz), "
                        "not both")
    if not body:
        raise DataError(f"data file {str(path)!r} has a header but no data rows")
    width = len(header)
    for r, line in zip(body, lines, strict=True):
        if len(r) > width and any(c.strip() for c in r[width:]):
            raise DataError(f"data file {str(path)!r}: line {line} has {len(r)} cells, the "
                            f"header names {width} columns")
    j0 = header.index(first)
    values = {h: np.array([_cell(path, line, h_raw, r[j] if j < len(r) else "",
                                 empty_ok=kind == "modes")
                           for r, line in zip(body, lines, strict=True)])
              for j, (h, h_raw) in enumerate(zip(header, header_raw, strict=True))
              if j != j0}
    line_arr = np.asarray(lines)
    if kind == "modes":
        labels = tuple(_mode_label(path, line, r[j0] if j0 < len(r) else "")
                       for r, line in zip(body, lines, strict=True))
        dup = _first_repeat(labels)
        if dup is not None:
            raise DataError(f"data file {str(path)!r}: mode {labels[dup]!r} appears twice "
                            f"(line {lines[dup]})")
        cols = []
        for h in data_cols:
            v = values[h]
            if h == "frequency_hz":
                v = 2 * math.pi * v
            if h != "zeta" and np.any(v[np.isfinite(v)] <= 0):
                i = int(np.flatnonzero(np.isfinite(v) & (v <= 0))[0])
                raise DataError(f"data file {str(path)!r}: line {lines[i]}, column {h!r}: a "
                                "natural frequency must be > 0")
            if h == "zeta" and np.any(v[np.isfinite(v)] <= 0):
                i = int(np.flatnonzero(np.isfinite(v) & (v <= 0))[0])
                raise DataError(f"data file {str(path)!r}: line {lines[i]}, column 'zeta': a "
                                "damping ratio must be > 0")
            cols.append(Column(h, "zeta" if h == "zeta" else "omega", 0, v,
                               "-" if h == "zeta" else "rad/s"))
        if not any(np.any(c.measured) for c in cols):
            raise DataError(f"data file {str(path)!r}: no mode has a measured value")
        return FitData(str(path), kind, np.arange(1.0, len(body) + 1), tuple(cols),
                       line_arr, modes=labels)
    x = np.array([_cell(path, line, header_raw[j0], r[j0] if j0 < len(r) else "")
                  for r, line in zip(body, lines, strict=True)])
    _check_increasing(path, first, x, lines)
    if kind == "series" and x[0] < 0:
        raise DataError(f"data file {str(path)!r}: line {lines[0]}, column 't': t = "
                        f"{x[0]:g} s is before the start of the simulation (t = 0, the "
                        "release): shift the record's time so that it counts from there")
    if kind == "series" and x[-1] <= 0:
        raise DataError(f"data file {str(path)!r}: the record holds only t = 0 (the state "
                        "before the motion); a record needs times after it")
    rod = None
    if kind == "shape" and rod_names is not None:
        rods = sorted({allowed[h][0].rsplit(".", 1)[0] for h in data_cols})
        if len(rods) > 1:
            raise DataError(f"data file {str(path)!r}: a static shape holds the centreline of "
                            f"one rod, its columns name {', '.join(rods)}; one file per rod")
        rod = rods[0]
    cols = [Column(h, allowed[h][0], allowed[h][1], values[h]) for h in data_cols]
    return FitData(str(path), kind, x, tuple(cols), line_arr, rod=rod)


def _first_repeat(items: Sequence[str]) -> int | None:
    seen = set()
    for i, v in enumerate(items):
        if v in seen:
            return i
        seen.add(v)
    return None


def _mode_label(path: Path, line: int, text: str) -> str:
    """A ``mode`` cell: a rank ("3") or FAMILY:K ("bending-2:1"), checked."""
    cell = text.strip()
    if cell.isdigit() and int(cell) >= 1:
        return str(int(cell))
    fam, _, k = cell.partition(":")
    if fam in MODE_FAMILIES and k.isdigit() and int(k) >= 1:
        return f"{fam}:{int(k)}"
    raise DataError(f"data file {str(path)!r}: line {line}, column 'mode': {cell!r} names no "
                    "mode; give its rank in kvrod modes' table (1, 2, ...) or FAMILY:K with "
                    f"FAMILY one of {', '.join(MODE_FAMILIES)} (e.g. bending-2:1)")


def _check_increasing(path: Path, name: str, x: np.ndarray, lines: list[int]) -> None:
    d = np.diff(x)
    bad = np.flatnonzero(d <= 0)
    if not bad.size:
        return
    i = int(bad[0])
    unit = "s" if name == "t" else "m"
    if d[i] == 0:
        raise DataError(f"data file {str(path)!r}: line {lines[i + 1]}, column {name!r}: "
                        f"{name} = {x[i + 1]:.10g} {unit} repeats line {lines[i]}; remove "
                        "the repeated row")
    raise DataError(f"data file {str(path)!r}: line {lines[i + 1]}, column {name!r}: "
                    f"{name} = {x[i + 1]:.10g} {unit} comes after {x[i]:.10g} {unit} (line "
                    f"{lines[i]}): the rows must be sorted by {name} (increasing)")


# --------------------------------------------------------------------------------------
# against the problem
# --------------------------------------------------------------------------------------


def check_against_problem(data: FitData, *, n_parameters: int, t_end: float,
                          length: float | None = None) -> None:
    """The checks that need the problem's numbers (DataError, one line).

    ``t_end`` (s): the problem's ``simulation.t_end``; a record may not last longer (the
    message names both and the flag that changes t_end). ``length`` (m): the length of
    the rod a shape belongs to (its s lies in 0 ... L). At least ``n_parameters`` + 1
    measured values are needed (one residual degree of freedom for an interval).
    """
    if data.kind == "series" and data.t_end > t_end * (1 + 1e-12):
        raise DataError(f"data file {data.path!r}: the record ends at t = {data.t_end:.10g} s, "
                        f"after the simulation's t_end = {t_end:.10g} s "
                        f"(simulation.t_end): give --t-end {data.t_end:.10g} (or --set "
                        f"simulation.t_end={data.t_end:.10g}), or cut the record")
    if data.kind == "shape" and length is not None:
        s = data.abscissa
        tol = 1e-9 * length
        if s[0] < -tol or s[-1] > length + tol:
            i = 0 if s[0] < -tol else s.size - 1
            raise DataError(f"data file {data.path!r}: line {int(data.lines[i])}, column 's': "
                            f"s = {s[i]:.10g} m lies outside the rod (0 ... {length:.10g} m, "
                            "the arc length of its reference centreline)")
    need = n_parameters + 1
    if data.count < need:
        raise DataError(f"data file {data.path!r} holds {data.count} measured value"
                        f"{'s' if data.count != 1 else ''} ({data.rows} row"
                        f"{'s' if data.rows != 1 else ''}); fitting {n_parameters} "
                        f"parameter{'s' if n_parameters != 1 else ''} needs at least {need} "
                        "(more than the parameters, for the residual's variance)")
