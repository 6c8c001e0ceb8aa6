"""The assembly bench section (``python -m bench --only assembly``, issue 31 item 3) at a
tiny size: the problems it builds from the cantilever, the paired whole processes, the
paired in-process rounds and its Markdown."""

from __future__ import annotations

import pytest

from bench import assembly as ab
from runtime.problem.registry import load_problem
from runtime.solvers.native.loader import load


def test_independent_cantilevers_are_copies_of_the_example(tmp_path):
    """k rods, each the cantilever's rod, section, material and clamp, apart along y,
    each with the cantilever's released tip load at its own end; no joints."""
    single = load_problem("cantilever", {"n_elements": 8, "t_end": 1.0})
    a = load_problem(ab.write_toml(tmp_path / "a.toml", ab.independent_cantilevers(3, 8, 1.0)))
    assert list(a.rods) == ["c0", "c1", "c2"] and not a.joints
    for i, rod in enumerate(a.rods.values()):
        assert rod.rod.elements == 8 and rod.rod.length == single.rod.length
        assert rod.material == single.material and rod.section == single.section
        assert rod.start.kind == "clamped" and rod.end.kind == "free"
        assert rod.rod.geometry.origin == pytest.approx([0.0, ab.SPACING * i, 0.0])
    assert [ld.point.label for ld in a.loads] == ["c0.end", "c1.end", "c2.end"]
    assert all(ld.load.vector == single.loads[0].vector for ld in a.loads)
    assert a.simulation.t_end == 1.0 and a.simulation.rtol == single.simulation.rtol


def test_welded_chain_is_the_cantilever_cut_into_pieces(tmp_path):
    """k rods of N elements end to end along the cantilever's axis, welded, clamped at the
    first start, the tip load at the last end: the reference end is the cantilever's."""
    a = load_problem(ab.write_toml(tmp_path / "w.toml", ab.welded_chain(3, 4, 1.0)))
    single = load_problem("cantilever")
    assert [j.kind for j in a.joints] == ["weld", "weld"]
    assert [r.start.kind for r in a.rods.values()] == ["clamped", "free", "free"]
    assert sum(r.rod.length for r in a.rods.values()) == pytest.approx(single.rod.length)
    end = a.reference_position(a.loads[0].point)
    assert end == pytest.approx([0.0, 0.0, single.rod.length])


@pytest.fixture(scope="module")
def tiny():
    if load() is None:
        pytest.skip("no C compiler")
    return ab.run(k=2, n_elements=4, t_end=0.2, pairs=1, log=lambda msg: None)


def test_the_sides_ran_in_pairs_and_the_target_has_a_verdict(tiny):
    for case, runs in (("independent", 2), ("welded", 1)):
        c = tiny[case]
        (r,) = c["rounds"]
        assert len(r["B"]["steps"]) == runs and r["A"]["steps"][0] > 0
        assert r["A"]["summary_wall"] < r["A"]["wall"]          # start-up outside
        assert c["median_command_ratio"] > 0 and c["median_process_ratio"] > 0
        assert c["median_same_steps_ratio"] == pytest.approx(
            c["median_command_ratio"] * sum(r["B"]["steps"]) / runs / r["A"]["steps"][0])
    for t in tiny["targets"]:
        assert t["verdict"] in ("met", "missed") and t["limit"] == ab.RATIO_MAX
    for case in ("independent", "welded"):
        ip = tiny["in_process"][case]
        (r,) = ip["rounds"]
        for side in ("A", "B"):
            assert 0 < r[side]["static_s"] < r[side]["total_s"]
            assert r[side]["run_s"] == pytest.approx(r[side]["total_s"] - r[side]["static_s"])
        assert ip["steps_A"] == r["A"]["counters"]["nstep"] > 0
        assert ip["median_same_steps_ratio"] == pytest.approx(
            ip["median_ratio"] * ip["steps_B"] / ip["steps_A"])
    assert tiny["in_process"]["independent"]["k_single"] == 2


def test_markdown_has_both_rows(tiny):
    md = "\n".join(ab.markdown(tiny))
    assert md.startswith("## 13. Rod assemblies beside their rods run one by one")
    assert "| 2 cantilevers N = 4 in one assembly / 2 runs |" in md
    assert "| 2 welded rods of N = 4 / one rod of N = 8 |" in md
    assert "| 2 cantilevers N = 4 / 2 runs |" in md


def test_bad_sizes_are_refused():
    with pytest.raises(ValueError, match="outside the allowed range"):
        ab.run(k=1, n_elements=4, t_end=0.2, pairs=1, log=lambda msg: None)
