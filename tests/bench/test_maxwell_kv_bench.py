"""The Maxwell-over-Kelvin-Voigt bench section (``python -m bench --only maxwell_kv``) at a
tiny size: both problems' accuracy against their own tight runs, the in-process rounds and
the whole ``kvrod simulate`` processes in pairs, and its Markdown."""

from __future__ import annotations

import pytest

from bench import maxwell_kv as mk
from runtime.solvers.native.loader import load


@pytest.fixture(scope="module")
def tiny():
    if load() is None:
        pytest.skip("no C compiler")
    return mk.run(N=6, T=2.0, pairs=2, rounds=1, log=lambda msg: None)


def test_both_problems_are_checked_against_their_own_tight_runs(tiny):
    for name in mk.PROBLEMS:
        a = tiny["accuracy"][name]
        assert a["maxima_compared"] >= 1
        assert 0 < a["error"] < mk.ACCURACY_MAX
        assert a["ref_steps"] > a["steps"] > 0         # rtol 1e-8 takes more steps
        assert len(a["peaks_x"]) >= a["maxima_compared"]
    (t_mx, t_kv, t_ratio) = tiny["targets"]
    assert t_mx["verdict"] == t_kv["verdict"] == "met"
    assert t_ratio["verdict"] in ("met", "missed")


def test_whole_processes_ran_in_pairs(tiny):
    wp = tiny["whole_process"]
    assert not wp["failed"]
    for name in mk.PROBLEMS:
        assert len(wp[name]["walls"]) == len(wp[name]["cpu"]) == 2
        assert min(wp[name]["walls"]) > 0 and min(wp[name]["cpu"]) > 0
    assert len(wp["ratios"]) == 2 and wp["median_ratio"] > 0
    least = min(wp[mk.MAXWELL]["cpu"]) / min(wp[mk.KV]["cpu"])
    assert wp["min_cpu_ratio"] == pytest.approx(least, rel=1e-12)
    assert tiny["in_process"]["median_ratio"] > 0
    assert tiny["machine"]["cores"] >= 1 and tiny["machine"]["cpu"]


def test_markdown_has_every_row(tiny):
    md = "\n".join(mk.markdown(tiny))
    assert md.startswith("## 11. Generalized Maxwell over Kelvin-Voigt")
    assert "| Maxwell cantilever |" in md and "| Kelvin-Voigt cantilever |" in md
    assert "paired median" in md and "least CPU over least CPU" in md


def test_bad_sizes_are_refused():
    with pytest.raises(ValueError, match="outside the allowed range"):
        mk.run(N=6, T=2.0, pairs=0, rounds=1, log=lambda msg: None)
