"""Measured records as CSV tables: the named columns of a file, every cell checked (a
decay record for a calibration, the storage and loss moduli of a DMA sweep)."""

from __future__ import annotations

import csv
import math
from collections.abc import Sequence
from pathlib import Path

import numpy as np


def csv_rows(path: Path, error: type[ValueError] = ValueError, encoding: str = "utf-8"
             ) -> list[tuple[int, list[str]]]:
    """(file line, cells) of the rows of a CSV file that hold something, '#' comment lines
    skipped; a one-line ``error`` naming the file when it is missing, a directory, not
    UTF-8 text, not a readable CSV table or unreadable (an empty result is the caller's
    to refuse)."""
    if not path.is_file():
        raise error(f"data file {str(path)!r} "
                    + ("is a directory, not a CSV file" if path.is_dir() else "does not exist"))
    try:
        with path.open(newline="", encoding=encoding) as fh:
            return [(i, r) for i, r in enumerate(csv.reader(fh), 1)
                    if r and not r[0].lstrip().startswith("#") and any(c.strip() for c in r)]
    except UnicodeDecodeError as exc:
        raise error(f"data file {str(path)!r} is not UTF-8 text ({exc.reason} at byte "
                    f"{exc.start}): save it as a plain CSV") from None
    except csv.Error as exc:
        raise error(f"data file {str(path)!r} is not a readable CSV table ({exc})") from None
    except OSError as exc:
        raise error(f"data file {str(path)!r} cannot be read ({exc.strerror})") from None


def load_csv(path: str | Path, columns: Sequence[str]) -> list[np.ndarray]:
    """Read the named columns (case-insensitive header names) of a CSV file as floats.

    Lines starting with '#' are comments. A file with one unnamed numeric column is
    accepted when one column is asked for. An empty cell, text or a non-finite number in
    an asked column is refused naming the file's line and the column (never skipped).
    """
    path = Path(path)
    numbered = csv_rows(path)
    lines = [i for i, _ in numbered]
    rows = [r for _, r in numbered]
    if not rows:
        raise ValueError(f"data file {str(path)!r} is empty")
    header = [c.strip().lower() for c in rows[0]]
    if all(_is_number(c) for c in header):
        if len(columns) == 1:
            header, body = [columns[0]], rows
        else:
            raise ValueError(f"data file {str(path)!r} has no header; expected columns "
                             f"{', '.join(columns)}")
    else:
        body, lines = rows[1:], lines[1:]
    idx = []
    for name in columns:
        if name.lower() not in header:
            raise ValueError(f"data file {str(path)!r} has no column {name!r} "
                             f"(columns: {', '.join(header)})")
        idx.append(header.index(name.lower()))
    out = [np.full(len(body), np.nan) for _ in columns]
    for i, r in enumerate(body):
        for c, j in enumerate(idx):
            cell = r[j].strip() if j < len(r) else ""
            if not (_is_number(cell) and math.isfinite(float(cell))):
                what = f"{cell!r} is not a finite number" if cell else "the cell is empty"
                raise ValueError(f"data file {str(path)!r}: line {lines[i]}, column "
                                 f"{columns[c]!r}: {what}; correct or remove that row")
            out[c][i] = float(cell)
    return out


def _is_number(s: str) -> bool:
    try:
        float(s)
    except ValueError:
        return False
    return True
