"""What every benchmark document records: when, where, with what, how it was started,
and its targets with a verdict."""

from __future__ import annotations

import datetime
import os
import platform
import shlex
import sys
from typing import Any

#: the bench command being run, set by :func:`bench.__main__.run_all` (a programmatic call,
#: e.g. from the tests, records the equivalent command, not the caller's command line)
COMMAND: str | None = None


def metadata() -> dict[str, Any]:
    """Date (UTC), platform, CPUs, load average, Python/NumPy/SciPy/CasADi versions, the
    bench command (:data:`COMMAND`, else this process's command line) and the process's
    command line."""
    import casadi
    import numpy
    import scipy

    try:
        load = [round(v, 2) for v in os.getloadavg()]
    except OSError:
        load = None
    return {"date": datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%d %H:%M UTC"),
            "platform": platform.platform(), "cpus": os.cpu_count(),
            "load_average_at_end": load, "python": platform.python_version(),
            "numpy": numpy.__version__, "scipy": scipy.__version__,
            "casadi": casadi.__version__,
            "command": COMMAND or shlex.join(getattr(sys, "orig_argv", sys.argv)),
            "process": shlex.join(getattr(sys, "orig_argv", sys.argv))}


def target(text: str, value: float | None, limit: float, *, below: bool = True,
           strict: bool = False, note: str = "") -> dict[str, Any]:
    """A target with its measured value and verdict ("met", "missed", or "not measured"
    when value is None): value <= limit (``below``; < with ``strict``) or >= limit."""
    if value is None:
        met = None
    elif below:
        met = bool(value < limit) if strict else bool(value <= limit)
    else:
        met = bool(value > limit) if strict else bool(value >= limit)
    verdict = "not measured" if met is None else ("met" if met else "missed")
    out = {"target": text, "value": value, "limit": limit, "met": met, "verdict": verdict}
    if note:
        out["note"] = note
    return out


def targets_md(targets: list[dict]) -> list[str]:
    """Markdown lines: one bullet per target with its value and verdict."""
    out = []
    for t in targets:
        v = t["value"]
        val = "-" if v is None else (f"{v:.3g}" if isinstance(v, float) else str(v))
        note = f" ({t['note']})" if t.get("note") else ""
        out.append(f"- {t['target']}: {val} -> **{t['verdict']}**{note}")
    return out
