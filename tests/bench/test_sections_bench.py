"""The section-analysis bench section (``python -m bench --only sections``) at a tiny size:
every child process runs, each mesh of the refinement loop is timed, and kvrod and
sectionproperties agree on the mesh they share (the same quadratic elements: the peer is
the independent reference here). Nothing about speed is asserted."""

from __future__ import annotations

import pytest

pytest.importorskip("sectionproperties")

from bench import sections  # noqa: E402

TINY = {"plies": 2, "ply": 0.0005, "width": 0.006}


@pytest.fixture(scope="module")
def tiny():
    return sections.run(size=TINY, rounds=1, log=lambda msg: None)


def test_every_child_ran_and_each_mesh_is_timed(tiny):
    (row,) = tiny["rounds"]
    assert row["kvrod"]["ok"], row["kvrod"].get("error")
    assert row["sectionproperties"]["ok"], row["sectionproperties"].get("error")
    assert row["whole_process"]["ok"], row["whole_process"].get("error")
    levels = row["kvrod"]["levels"]
    assert levels and all(lev["elements"] > 0 and lev["cpu"] > 0 for lev in levels)
    assert levels[-1]["elements"] == tiny["composite"]["elements"]
    assert tiny["sectionproperties_solver"] in ("direct", "cgs")
    m = tiny["median"]
    for key in ("analysis_cpu", "finest_mesh_cpu", "sectionproperties_cpu",
                "whole_process_cpu", "ratio_cpu"):
        assert m[key] > 0, key


def test_kvrod_and_sectionproperties_agree_on_the_shared_mesh(tiny):
    cross = tiny["cross_check"]
    for key in ("EA", "EI1", "EI2"):
        assert cross[key]["relative_difference"] < 1e-9, (key, cross[key])
    assert cross["GJ"]["relative_difference"] < 1e-6, cross["GJ"]


def test_targets_and_markdown(tiny):
    assert [t["verdict"] in ("met", "missed") for t in tiny["targets"]] == [True] * 3
    md = "\n".join(sections.markdown(tiny))
    assert "kvrod section beside sectionproperties" in md
    assert "| 1 |" in md                     # the per-mesh table


def test_laminate_file_is_a_valid_section():
    """The bench's laminate is a section the analysis accepts (plies bonded, one part)."""
    from runtime.section.materials import materials_from_mapping
    from runtime.section.regions import check_regions, regions_from_mapping

    spec = sections.laminate(**sections.FULL)
    regions = regions_from_mapping(spec["section"]["regions"])
    assert len(regions) == 16
    check_regions(regions, materials_from_mapping(spec["materials"]))
