"""Measurements of a notes run, written to its results folder (never into tracked notes).

The notes (``notes/*.md``) hold what a rerun reproduces: results, rounded to what the
integration error leaves stable. What changes from run to run or machine to machine (wall
times, the first C compilation, solver counters, the machine) goes to ``timings.json`` and
``run-info.md`` in the command's results folder, with the command that measured it.
"""

from __future__ import annotations

import json
import math
import platform
import time
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from runtime.io.atomic import write_text

TIMINGS = "timings.json"
RUN_INFO = "run-info.md"
#: files the notes commands write into their results folder
FILES = (TIMINGS, RUN_INFO)


def machine() -> dict[str, str]:
    """The machine facts that explain a wall time (no host name)."""
    import numpy as np

    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo", encoding="utf-8", errors="replace") as f:
            for line in f:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    import os

    return {"machine": platform.machine(), "cpu": cpu, "cpus": str(os.cpu_count()),
            "system": f"{platform.system()} {platform.release()}",
            "python": f"{platform.python_implementation()} {platform.python_version()}",
            "numpy": np.__version__}


class Timings:
    """Wall times of the phases of one notes command, its first C compilation (apart),
    and per-run solver figures."""

    def __init__(self, command: str) -> None:
        self.command = command
        self.t0 = time.perf_counter()
        self.compile_s: dict[str, float] = {}
        self.phases: dict[str, float] = {}
        self.runs: dict[str, dict[str, Any]] = {}
        #: other measured figures (e.g. the model runs of a fit), by description
        self.figures: dict[str, Any] = {}

    def compile_native(self) -> None:
        """Compile the C code now (or find it cached), so no timed run pays for it."""
        from runtime.model import build

        self.compile_s = build.compile_native()

    @contextmanager
    def phase(self, name: str) -> Iterator[None]:
        t = time.perf_counter()
        yield
        self.phases[name] = time.perf_counter() - t

    def run(self, label: str, summary: Mapping[str, Any], wall: float | None = None) -> None:
        """Solver figures of a run from its summary.json content."""
        c = summary.get("counters") or {}
        st = summary.get("static") or {}
        if wall is None:
            wall = summary.get("wall_time_s", st.get("wall_time_s"))
        row = {"wall_s": wall,
               "steps": c.get("nstep"), "lu": c.get("nlu"),
               "newton_iterations": c.get("nni"),
               "energy_audit_max_rel": summary.get("energy_balance_max_rel"),
               "static_newton_iterations": st.get("newton_iterations")}
        self.runs[label] = {k: v for k, v in row.items() if v is not None}

    def doc(self) -> dict[str, Any]:
        from runtime.version import version_text

        return {"command": self.command, "kvrod": version_text(), "machine": machine(),
                "compile_s": self.compile_s, "wall_s": self.phases,
                "total_wall_s": time.perf_counter() - self.t0, "runs": self.runs,
                "figures": self.figures}

    def write(self, out: Path) -> list[Path]:
        """``timings.json`` and ``run-info.md`` in results folder ``out``."""
        out = Path(out)
        doc = self.doc()
        paths = [write_text(out / TIMINGS, json.dumps(doc, indent=1, default=float) + "\n"),
                 write_text(out / RUN_INFO, markdown(doc))]
        return paths


def _num(x: Any, fmt: str) -> str:
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return "-"
    return format(x, fmt)


def markdown(doc: Mapping[str, Any]) -> str:
    """run-info.md: the measurements of one run of ``doc["command"]``."""
    lines = [f"# Run information: `{doc['command']}`", "",
             "Measured by that command on this machine; these numbers change from run to "
             "run and machine to machine, so they are kept here, not in the notes.", "",
             f"- {doc['kvrod']}"]
    lines += [f"- {k}: {v}" for k, v in doc["machine"].items()]
    lines += ["", "| phase | wall time [s] |", "|---|---:|"]
    for what, s in doc["compile_s"].items():
        lines.append(f"| compiling {what} (0: already compiled) | {s:.2f} |")
    for name, s in doc["wall_s"].items():
        lines.append(f"| {name} | {s:.2f} |")
    lines.append(f"| total | {doc['total_wall_s']:.2f} |")
    if doc["runs"]:
        lines += ["", "| run | wall [s] | steps | LU | Newton iterations | energy audit | "
                      "static Newton iterations |", "|---|---:|---:|---:|---:|---:|---:|"]
        for label, r in doc["runs"].items():
            lines.append(f"| {label} | {_num(r.get('wall_s'), '.2f')} | "
                         f"{_num(r.get('steps'), 'd')} | {_num(r.get('lu'), 'd')} | "
                         f"{_num(r.get('newton_iterations'), 'd')} | "
                         f"{_num(r.get('energy_audit_max_rel'), '.2e')} | "
                         f"{_num(r.get('static_newton_iterations'), 'd')} |")
    if doc.get("figures"):
        lines += [""] + [f"- {k}: {v}" for k, v in doc["figures"].items()]
    return "\n".join(lines) + "\n"


def decade(x: float) -> str:
    """The power of ten just above a small positive error: 7.6e-6 -> "1e-5".

    For the notes: integration errors (energy audits, coincidence residuals) differ in their
    digits from machine to machine; their decade does not (except at a decade's edge)."""
    if x is None or not math.isfinite(x):
        return "-"
    if x <= 0:
        return "0"
    return f"1e{math.floor(math.log10(x)) + 1}"


def bound(x: float) -> str:
    """:func:`decade` as an upper bound for a table: 7.6e-6 -> "< 1e-5"."""
    d = decade(x)
    return d if d in ("-", "0") else f"< {d}"
