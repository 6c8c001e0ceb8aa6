"""Section geometry against round-off (issue 30): edges that coincide up to round-off are
one edge, a mesh the mesher cannot make within its point budget is refused naming the
regions, and the analysis of round-off plies equals that of exactly written ones.

Two plies written with decimal centres (0.0025, 0.0075; height 0.005) overlapped by
8.7e-19 m after round-off, and Triangle refined the sliver between the two edges without
end (60 MB/s, deaf to Ctrl-C)."""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely

from runtime.errors import ParameterError
from runtime.section import analyse_section, isotropic, mesh_regions, regions_from_mapping
from runtime.section import regions as regions_module
from runtime.section.mesh import MeshBudgetError, steiner_budget
from runtime.section.regions import region_polygons


def _rect(name, width, height, centre, angle=0.0):
    return {"name": name, "material": name, "shape": {"kind": "rectangle", "width": width,
                                                      "height": height,
                                                      "centre": list(centre),
                                                      "angle": angle}}


def _rotated_pair():
    a = math.radians(30.0)
    n = (-math.sin(a), math.cos(a))
    h = 0.001
    return [_rect("lo", 0.01, h, (0.0, 0.0), 30.0),
            _rect("hi", 0.01, h, (h * n[0], h * n[1]), 30.0)]


#: sections whose regions share edges up to round-off (each of these hung, or failed, on
#: the code before issue 30, except the mm-scale plies)
SHARED_UP_TO_ROUNDOFF = {
    "decimal plies": [_rect("bottom", 0.02, 0.005, (0, 0.0025)),
                      _rect("top", 0.02, 0.005, (0, 0.0075))],
    "plies in mm": [_rect("bottom", 20.0, 5.0, (0, 2.5)), _rect("top", 20.0, 5.0, (0, 7.5))],
    "side by side along x": [_rect("left", 0.003, 0.002, (0.0015, 0)),
                             _rect("right", 0.003, 0.002, (0.0045, 0))],
    "ten 0.1 mm plies": [_rect(f"p{i}", 0.005, 0.0001, (0, (i + 0.5) * 0.0001))
                         for i in range(10)],
    "circle in a tube of equal radius": [
        {"name": "core", "material": "core", "shape": {
            "kind": "circle", "radius": 0.30000000000000004, "centre": [0.1, 0.2]}},
        {"name": "sheath", "material": "sheath", "shape": {
            "kind": "tube", "inner_radius": 0.3, "outer_radius": 0.5,
            "centre": [0.1, 0.20000000000000004]}}],
    "rectangles at 30 degrees": _rotated_pair(),
    "T-junction": [_rect("base", 0.02, 0.003, (0, 0.0015)),
                   _rect("web", 0.002, 0.007, (0.0031, 0.0065))],
    "1 km from the origin": [_rect("bottom", 0.02, 0.005, (1000.1, 0.0025)),
                             _rect("top", 0.02, 0.005, (1000.1, 0.0075))],
}


def _materials(regions):
    return {r.material: isotropic(r.material, 1e9 * (1 + i), 0.3, 1000.0, 0.01, 0.0)
            for i, r in enumerate(regions)}


@pytest.mark.parametrize("case", list(SHARED_UP_TO_ROUNDOFF))
def test_edges_equal_up_to_roundoff_are_one_edge(case):
    regions = regions_from_mapping(SHARED_UP_TO_ROUNDOFF[case])
    size = max(math.sqrt(r.shape.area) for r in regions)
    polys = region_polygons(regions, size / 8)
    union = shapely.union_all(polys)
    assert union.geom_type == "Polygon", case                  # one connected section
    for i in range(len(polys)):                                # bonded: no overlap at all
        for j in range(i + 1, len(polys)):
            assert polys[i].intersection(polys[j]).area <= 1e-15 * union.area, case
    assert abs(union.area - sum(p.area for p in polys)) <= 1e-12 * union.area, case
    mesh = mesh_regions(regions, size / 8)
    corners = mesh.nodes[mesh.elements[:, :3]]
    d1, d2 = corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]
    area = 0.5 * np.abs(d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0])
    # the mesh covers the section once, without slivers between the regions
    assert area.sum() == pytest.approx(union.area, rel=1e-3), case
    assert area.min() > 1e-9 * area.max(), case


def test_decimal_plies_analyse_as_plies_written_exactly():
    """The decimal plies against the same plies written without round-off (their shared
    edge on x2 = 0: centres -0.0025 and 0.0025): the same matrices about the elastic
    centroid, which moves with the section."""
    decimal = regions_from_mapping(SHARED_UP_TO_ROUNDOFF["decimal plies"])
    exact = regions_from_mapping([_rect("bottom", 0.02, 0.005, (0, -0.0025)),
                                  _rect("top", 0.02, 0.005, (0, 0.0025))])
    mats = _materials(decimal)
    a = analyse_section(decimal, mats, tol=1e-3)
    b = analyse_section(exact, mats, tol=1e-3)
    assert a.converged and b.converged
    assert a.elastic_centroid[1] - b.elastic_centroid[1] == pytest.approx(0.005, rel=1e-9)
    for M, N in ((a.stiffness, b.stiffness), (a.viscosity, b.viscosity)):
        scale = np.sqrt(np.outer(np.diag(N), np.diag(N)))
        assert np.max(np.abs(M - N) / scale) < 1e-6


def test_a_sliver_beyond_the_budget_is_refused_naming_the_regions(monkeypatch):
    """Without the snapping, the decimal plies' sliver of 8.7e-19 m: the mesher stops at
    its point budget and the error names both plies, instead of refining forever."""
    monkeypatch.setattr(regions_module, "SNAP_RELATIVE", 0.0)
    monkeypatch.setattr(regions_module, "SNAP_ULPS", 0.0)
    regions = regions_from_mapping(SHARED_UP_TO_ROUNDOFF["decimal plies"])
    with pytest.raises(MeshBudgetError, match=r"section\.regions.*'bottom' and 'top'.*"
                                              r"sliver") as exc:
        mesh_regions(regions, 0.01 / 8)
    assert isinstance(exc.value, ParameterError)


def test_the_budget_grows_with_the_mesh_and_has_a_ceiling():
    regions = regions_from_mapping(SHARED_UP_TO_ROUNDOFF["decimal plies"])
    polys = region_polygons(regions, 0.001)
    coarse = steiner_budget(polys, [0.001, 0.001], 20)
    fine = steiner_budget(polys, [0.0001, 0.0001], 20)
    assert coarse < fine <= 60_000
    assert steiner_budget(polys, [1e-7, 1e-7], 20) == 60_000


def test_an_outline_of_too_many_points_is_refused_naming_the_region():
    t = np.linspace(0.0, 2 * np.pi, 60_001)[:-1]
    star = np.column_stack([(1 + 0.1 * np.cos(7 * t)) * np.cos(t),
                            (1 + 0.1 * np.cos(7 * t)) * np.sin(t)])
    regions = regions_from_mapping([{"name": "star", "material": "m", "shape": {
        "kind": "polygon", "points": star.tolist()}}])
    with pytest.raises(MeshBudgetError, match=r"section\.regions\[0\]\.shape.*star.*50000"):
        mesh_regions(regions, 0.1)


def test_a_region_left_without_area_by_the_snapping_is_named():
    """A ply thinner than the section's round-off (1e-12 of its size) between two others:
    joined to both, it has no area left: named, not meshed."""
    regions = regions_from_mapping([_rect("a", 1.0, 0.5, (0, 0.25)),
                                    _rect("film", 1.0, 1e-14, (0, 0.5 + 5e-15)),
                                    _rect("b", 1.0, 0.5, (0, 0.75 + 1e-14))])
    with pytest.raises(ParameterError, match=r"section\.regions\[1\]\.shape.*film.*round-off"):
        region_polygons(regions, 0.1)
