"""The study table ``DIR/study.csv``: one row per returned point, appended as points return.

A row is the point's id, its parameters and the key figures of its summary. Rows are
made where the summary is (on the worker that ran the point) and only they travel to
the client, which appends them: the table is never rewritten while a study runs, and
a crash leaves a valid CSV of the rows appended so far. A restarted study keeps the
rows of the points it will not run again; it rewrites the table once, at the start,
only when the table on disk does not hold exactly those (a failed point about to run
again, a table lost or deleted).
"""

from __future__ import annotations

import csv
import io
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any

from runtime.io.atomic import write_text
from runtime.study.points import PENDING

#: figures of a row, after its point id and parameters
FIGURE_COLUMNS = ("status", "message", "zeta_first", "zeta_last", "n_peaks", "period_mean",
                  "static_tip_x", "static_tip_z", "energy_balance_max_rel", "zeta_linear",
                  "tau_E", "wall_time_s")
TABLE_NAME = "study.csv"


def table_columns(param_columns: Sequence[str]) -> list[str]:
    """Columns of the table: point id, the parameters, the figures."""
    return ["point_id", *param_columns, *FIGURE_COLUMNS]


def row_of(param_columns: Sequence[str], point_id: str, params: Mapping[str, Any],
           summary: Mapping[str, Any] | None, status: str | None = None) -> dict[str, Any]:
    """One table row: id, the point's parameters, status, message and key figures of its
    summary (``summary`` None: a point without one, status pending)."""
    row: dict[str, Any] = {"point_id": point_id}
    row.update({k: params.get(k, "") for k in param_columns})
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


def table_row(study, point, summary: Mapping[str, Any] | None,
              status: str | None = None) -> dict[str, Any]:
    """:func:`row_of` for a point of ``study`` (:class:`runtime.study.sweep.Study`)."""
    return row_of(study.param_columns, point.id, point.params, summary, status)


def _cells(row: Mapping[str, Any]) -> dict[str, Any]:
    return {c: (repr(v) if isinstance(v, float) else v) for c, v in row.items()}


def _csv_text(columns: Sequence[str], rows: Iterable[Mapping[str, Any]]) -> str:
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=list(columns), lineterminator="\n")
    w.writeheader()
    for row in rows:
        w.writerow(_cells(row))
    return buf.getvalue()


def read_table(path: Path) -> list[dict[str, str]]:
    """The rows of a study.csv (strings, as written)."""
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


class TableAppender:
    """``DIR/study.csv`` opened for appending rows (each call flushed: O(rows) per call,
    never a rewrite).

    ``keep``: the rows of the points a (re)started study will not run again, by id, in
    the order they should appear when the table has to be written anew. The table on
    disk is kept as it is when it has this header and exactly these points, each once;
    otherwise it is replaced (atomically) by the header and ``keep``.
    """

    def __init__(self, path: Path, columns: Sequence[str],
                 keep: Mapping[str, Mapping[str, Any]]) -> None:
        self.path = Path(path)
        self.columns = list(columns)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        if not self._matches(keep):
            old = self._old_order()
            order = [pid for pid in old if pid in keep]
            order += [pid for pid in keep if pid not in set(order)]
            write_text(self.path, _csv_text(self.columns, (keep[pid] for pid in order)))
        self._f = open(self.path, "a", newline="")
        self._w = csv.DictWriter(self._f, fieldnames=self.columns, lineterminator="\n")

    def _old_order(self) -> list[str]:
        try:
            rows = read_table(self.path)
        except (OSError, csv.Error, UnicodeDecodeError):
            return []
        seen: dict[str, None] = {}
        for r in rows:
            seen.setdefault(r.get("point_id") or "", None)
        return list(seen)

    def _matches(self, keep: Mapping[str, Any]) -> bool:
        try:
            with open(self.path, newline="") as f:
                text = f.read()
        except (OSError, UnicodeDecodeError):
            return False
        if not text.endswith("\n"):        # a row cut short by a crash
            return False
        try:
            rows = list(csv.reader(io.StringIO(text)))
        except csv.Error:
            return False
        if not rows or rows[0] != self.columns:
            return False
        if any(len(r) != len(self.columns) for r in rows[1:]):
            return False
        ids = [r[0] for r in rows[1:]]
        return len(ids) == len(set(ids)) == len(keep) and set(ids) == set(keep)

    def append(self, rows: Iterable[Mapping[str, Any]]) -> None:
        """Append rows and flush (a crash keeps every row appended)."""
        for row in rows:
            self._w.writerow(_cells(row))
        self._f.flush()

    def close(self) -> None:
        if not self._f.closed:
            self._f.close()
