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


def test_a_maxwell_simulation_skips_numpys_lazy_submodules():
    """A generalized Maxwell rod's ``simulate`` (its Prony times' union, the integrator's
    band pattern and stiff-decay extents) imports neither ``numpy.ma`` (which NumPy 2's
    ``np.unique`` loads, 15-25 ms) nor ``numpy.random`` (7-12 ms): runtime.sorted_sets and
    the band pattern's own splitmix64 numbers instead."""
    probe = ("import sys\n"
             "from runtime.problem.registry import load_problem\n"
             "from runtime.simulate.simulate import simulate\n"
             "r = simulate(load_problem('examples/maxwell_cantilever.toml', "
             "{'n_elements': 4, 't_end': 0.02}))\n"
             "assert r.status == 'finished', r.status\n"
             "print(sorted(m for m in ('numpy.ma', 'numpy.random') if m in sys.modules))")
    r = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True,
                       cwd=ROOT, timeout=120, env={**os.environ, "PYTHONPATH": str(ROOT)})
    assert r.returncode == 0, r.stderr
    assert r.stdout.strip().splitlines()[-1] == "[]"


def test_rod_runs_let_openblas_threads_sleep():
    """kvrod simulate / sweep set OPENBLAS_THREAD_TIMEOUT before NumPy loads (its idle
    threads spin ~0.1 s of CPU otherwise); never over the user's value, never once NumPy
    is loaded (too late), never for other commands."""
    from kvrod.cli import quiet_blas_threads

    env: dict[str, str] = {}
    assert quiet_blas_threads("simulate", env, numpy_loaded=False)
    assert env == {"OPENBLAS_THREAD_TIMEOUT": "4"}
    env = {"OPENBLAS_THREAD_TIMEOUT": "28"}
    assert not quiet_blas_threads("sweep", env, numpy_loaded=False)
    assert env == {"OPENBLAS_THREAD_TIMEOUT": "28"}
    for command, loaded in (("section", False), ("modes", False), ("simulate", True)):
        env = {}
        assert not quiet_blas_threads(command, env, numpy_loaded=loaded) and env == {}
    # in a fresh process: set, and NumPy still not loaded (OpenBLAS reads it on load)
    got = subprocess.run(
        [sys.executable, "-c",
         "import os, sys\nimport kvrod.cli as c\n"
         "c.quiet_blas_threads('simulate')\n"
         "print(os.environ.get('OPENBLAS_THREAD_TIMEOUT'), 'numpy' in sys.modules)"],
        capture_output=True, text=True, cwd=ROOT, timeout=120,
        env={k: v for k, v in os.environ.items() if k != "OPENBLAS_THREAD_TIMEOUT"}
        | {"PYTHONPATH": str(ROOT)})
    assert got.stdout.split() == ["4", "False"], got.stderr
