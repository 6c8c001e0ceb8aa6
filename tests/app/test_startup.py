"""Start-up (issue 33, item 5): the command line imports a layer only when a command
needs it. Structural checks, not timings (speed is measured by ``python -m bench --only
sweeps``): which packages a process has imported after building the parser, after
``kvrod --version``, and before a sweep's engine is needed."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
HEAVY = ("numpy", "scipy", "matplotlib", "casadi", "sympy", "distributed", "dask",
         "tqdm", "jinja2", "shapely", "runtime", "reports", "derive")


def _imported_after(code: str) -> list[str]:
    probe = (f"import sys, json\n{code}\n"
             f"print(json.dumps(sorted({{m.split('.')[0] for m in sys.modules}} & "
             f"set({HEAVY!r}))))")
    r = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True,
                       cwd=ROOT, timeout=120, env={**os.environ, "PYTHONPATH": str(ROOT)})
    assert r.returncode == 0, r.stderr
    return json.loads(r.stdout.strip().splitlines()[-1])


def test_the_parser_imports_no_layer():
    """`kvrod --help`, a bad flag: answered before NumPy or any layer is imported."""
    assert _imported_after("from kvrod.cli import build_parser; build_parser()") == []


def test_version_imports_only_the_version():
    got = _imported_after("from kvrod.cli import main\ntry:\n    main(['--version'])\n"
                          "except SystemExit:\n    pass")
    assert got == ["runtime"]      # runtime.version (and generated/), nothing numerical


def test_a_study_loads_without_its_engine():
    """Loading and checking a study needs the problem layer, not Dask or plotting."""
    got = _imported_after("from runtime.study.sweep import load_study\n"
                          "load_study('examples/study_tau.toml')")
    assert "distributed" not in got and "dask" not in got and "matplotlib" not in got


def test_a_problem_loads_without_scipy_or_the_mesher():
    """A rod problem's material check (runtime.section.materials) does not load the
    section solver: SciPy and shapely stay out of ``kvrod simulate`` (a third of a short
    run's process before; issue 33, item 5)."""
    got = _imported_after("from runtime.problem.registry import load_problem\n"
                          "load_problem('cantilever')\n"
                          "import runtime.section as s\n"
                          "assert s.SectionMaterial and 'runtime.section.analysis' not in "
                          "sys.modules")
    assert "scipy" not in got and "shapely" not in got
    assert "numpy" in got and "runtime" in got


def test_a_short_simulation_runs_without_scipy():
    """``simulate`` of a cantilever (static solve, integration, audit, summary): no SciPy,
    shapely or plotting imported on the way."""
    got = _imported_after("from runtime.problem.registry import load_problem\n"
                          "from runtime.simulate.simulate import simulate\n"
                          "r = simulate(load_problem('cantilever', {'n_elements': 4, "
                          "'t_end': 0.02}))\n"
                          "assert r.status == 'finished', r.status\n"
                          "r.summary()")
    assert not {"scipy", "shapely", "matplotlib", "casadi"} & set(got), got
