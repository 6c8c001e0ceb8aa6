"""A study's points made on demand (issue 30): a grid is never expanded, each grid value
is checked once, a bad combination is a failed point named when reached.

The reference for the order and the ids is the plain expansion written here
(itertools.product, repeats dropped by parameters), on grids small enough for it.
"""

from __future__ import annotations

import itertools
import json
import math
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from runtime.study import sweep
from runtime.study.points import canonical_json, point_id
from runtime.study.sweep import FAILED, FINISHED, read_table, run_study_serial, study_from_dict

ROOT = Path(__file__).resolve().parents[2]
TINY = {"length": 0.1, "n_elements": 4, "rtol": 1e-4}


def _expanded(fixed: dict, grid: dict, listed: list[dict], varied: list[str]) -> list[tuple]:
    """(id, params) of every point by the plain expansion: product, then listed points,
    a repeat (same parameters) dropped."""
    out: dict[str, dict] = {}
    combos = itertools.product(*grid.values()) if grid else ()
    own = [dict(zip(grid, c, strict=True)) for c in combos] + listed
    for p in own:
        params = {**{k: v for k, v in fixed.items() if k not in p}, **p}
        out.setdefault(canonical_json(params), params)
    return [(point_id(p, varied), p) for p in out.values()]


def test_points_are_the_product_in_order_with_repeats_dropped():
    data = {"fixed": {**TINY, "t_end": 0.2},
            "grid": {"tau": [0.01, 0.02, 0.01, 0.03], "youngs_modulus": [1e6, 2000000, 2e6],
                     "n_elements": [4, 6]},
            "points": [{"tau": 0.02, "youngs_modulus": 2e6, "n_elements": 4},   # a grid point
                       {"tau": 0.05, "poisson_ratio": 0.4},
                       {"poisson_ratio": 0.4, "tau": 0.05}]}                    # listed twice
    s = study_from_dict(data)
    grid = {"tau": [0.01, 0.02, 0.01, 0.03], "youngs_modulus": [1e6, 2e6, 2e6],
            "n_elements": [4, 6]}
    want = _expanded(s.fixed, grid, [{"tau": 0.05, "poisson_ratio": 0.4}], list(s.varied))
    got = [(p.id, p.params) for p in s.points]
    assert got == want and len(s.points) == len(want) == 3 * 2 * 2 + 1
    assert [(p.id, p.params) for p in s.points[2:9:3]] == want[2:9:3]
    assert s.points[-1].params == want[-1][1]
    for i, (pid, params) in enumerate(want):
        assert s.points[i].id == pid
        assert s.points.find(json.loads(canonical_json(params))) == i   # as a summary has it
    assert s.points.find({**want[0][1], "tau": 0.07}) is None
    assert s.points[0] in s.points
    with pytest.raises(IndexError):
        s.points[len(want)]
    # the table's columns: varied first (grid order, then the listed points' own), fixed
    assert s.param_columns == ("tau", "youngs_modulus", "n_elements", "poisson_ratio",
                               "length", "rtol", "t_end")


def test_each_grid_value_is_checked_once_not_the_product(monkeypatch):
    calls = []
    real = sweep.check_point

    def counted(problem, params, where):
        calls.append(dict(params))
        return real(problem, params, where)

    monkeypatch.setattr(sweep, "check_point", counted)
    axes = {"tau": [0.01 + 1e-3 * i for i in range(30)],
            "youngs_modulus": [1e6 + i for i in range(40)], "t_end": [0.1, 0.2, 0.3]}
    s = study_from_dict({"fixed": TINY, "grid": axes}, max_points=math.inf)
    assert len(s.points) == 30 * 40 * 3
    assert len(calls) == 30 + 40 + 3 - 2       # the first point serves every axis
    for k, vals in axes.items():                # every value of every axis was checked
        assert sorted({c[k] for c in calls}) == sorted(vals)


def test_a_bad_combination_is_a_failed_point_and_the_others_run(tmp_path):
    """min_step <= t_end: each value is fine with the other axis's first value, the
    combination t_end = 0.02 with min_step = 0.03 is not; it is found when reached, named
    in its row, and the points before and after it are run."""
    s = study_from_dict({"fixed": {**TINY, "tau": 0.02},
                         "grid": {"t_end": [0.05, 0.02], "min_step": [0.0, 0.03]}})
    report = run_study_serial(s, tmp_path, plots=False)
    rows = {r["point_id"]: r for r in read_table(tmp_path / "study.csv")}
    assert len(rows) == 4 == len(report.computed)
    bad = [p.id for p in s.points if p.params["t_end"] == 0.02 and p.params["min_step"] == 0.03]
    assert rows[bad[0]]["status"] == FAILED
    assert "simulation.min_step" in rows[bad[0]]["message"], rows[bad[0]]["message"]
    ok = [p.id for p in s.points if p.params["min_step"] == 0.0]
    assert all(rows[pid]["status"] == FINISHED for pid in ok)


BILLION = """
import json, resource, sys
from pathlib import Path

def vm_bytes():
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmSize:"):
            return int(line.split()[1]) * 1024

from runtime.study.sweep import read_table, run_study_serial, study_from_dict
import runtime.simulate.simulate  # noqa: F401  (imports before the limit)

# room for a few hundred MiB more: a list of 10^9 points would need hundreds of GiB
resource.setrlimit(resource.RLIMIT_AS, (vm_bytes() + (768 << 20), resource.RLIM_INFINITY))
grid = {k: [v * (1 + 0.01 * i) for i in range(10)] for k, v in
        (("tau", 0.02), ("youngs_modulus", 1e6), ("density", 1000.0), ("poisson_ratio", 0.3),
         ("tip_force", 0.05), ("length", 0.1), ("width", 0.01), ("height", 0.01),
         ("rtol", 1e-4))}
study = study_from_dict({"fixed": {"n_elements": 4, "t_end": 0.05}, "grid": grid},
                        max_points=float("inf"))
seen = []

def stop(pr):
    seen.append((pr.total, pr.done, pr.failed, pr.running, pr.queued))
    raise KeyboardInterrupt

try:
    run_study_serial(study, Path(sys.argv[1]), progress=stop, plots=False)
except KeyboardInterrupt:
    pass
rows = read_table(Path(sys.argv[1]) / "study.csv")
print(json.dumps({"n": len(study.points), "seen": seen, "rows": rows,
                  "last": study.points[-1].params}))
"""


@pytest.mark.skipif(not Path("/proc/self/status").exists(), reason="Linux /proc")
def test_a_billion_point_grid_runs_its_first_point_without_expanding(tmp_path):
    """10^9 points could not be listed in the memory this child may use: the study is
    loaded, its first point run and kept when Ctrl-C comes, its last point named."""
    script = tmp_path / "billion.py"
    script.write_text(textwrap.dedent(BILLION))
    out = tmp_path / "study"
    p = subprocess.run([sys.executable, str(script), str(out)], capture_output=True,
                       text=True, cwd=tmp_path, timeout=600,
                       env={**os.environ, "PYTHONPATH": str(ROOT)})
    assert p.returncode == 0, p.stderr[-2000:]
    doc = json.loads(p.stdout.strip().splitlines()[-1])
    assert doc["n"] == 10 ** 9
    total, done, failed, running, queued = doc["seen"][0]
    assert (total, done + failed) == (10 ** 9, 1) and running + queued == 10 ** 9 - 1
    assert len(doc["rows"]) == 1 and doc["rows"][0]["status"] == FINISHED
    assert doc["last"]["tau"] == pytest.approx(0.02 * 1.09)
