"""Regions of a composite section: a material name and a shape (``[[section.regions]]``).

Regions must not overlap (touching along edges is how they are bonded); an overlap is an
error naming both regions. Together they must form one connected section (separate parts
could slide along each other: the rod would have no single stiffness); holes are allowed.
Every region's material must be one of the named materials.

Edges that coincide up to round-off are one edge: :func:`region_polygons` snaps every
region's vertices to its neighbours' within :data:`SNAP_RELATIVE` of the section's size
(two plies written with decimal centres, ``centre = [0, 0.0025]`` and ``[0, 0.0075]``
with height 0.005, overlap by 8.7e-19 m after round-off; unsnapped, the mesher refined
the sliver between the two edges without end).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import shapely
from shapely.geometry import Polygon
from shapely.ops import unary_union

from runtime.errors import ParameterError
from runtime.section import _checks as ck
from runtime.section.materials import SectionMaterial
from runtime.section.shapes import Shape, shape_from_mapping

#: relative overlap area (of the smaller region) above which two regions overlap
OVERLAP_TOLERANCE = 1e-9
#: points of two regions closer than this fraction of the section's size are one point,
#: and a point this close to another region's edge lies on it (the regions are bonded there)
SNAP_RELATIVE = 1e-12
#: ... and at least this many units in the last place of the largest coordinate (a section
#: far from the origin carries the round-off of its coordinates' size)
SNAP_ULPS = 16.0


@dataclass(frozen=True)
class Region:
    """One region: ``material`` (a name in the materials map) and ``shape``; ``name`` is
    how errors and reports call it (empty: its key path, ``section.regions[i]``)."""

    material: str
    shape: Shape
    name: str = ""

    def to_mapping(self) -> dict[str, Any]:
        """The ``[[section.regions]]`` table of this region."""
        out: dict[str, Any] = {"material": self.material, "shape": self.shape.to_mapping()}
        if self.name:
            out["name"] = self.name
        return out


def region_from_mapping(m: Any, path: str) -> Region:
    """A region from a ``[[section.regions]]`` table."""
    m = ck.table(path, m)
    ck.no_unknown_keys(path, m, ("material", "shape", "name"))
    mat = ck.string(f"{path}.material", ck.required(path, m, "material",
                                                   "the name of a [materials.NAME] table"))
    shape = shape_from_mapping(ck.required(path, m, "shape", "a shape table { kind = ... }"),
                               f"{path}.shape")
    name = ck.string(f"{path}.name", m["name"]) if "name" in m else ""
    return Region(mat, shape, name)


def regions_from_mapping(items: Any, path: str = "section.regions") -> tuple[Region, ...]:
    """The regions of ``[[section.regions]]`` (an array of tables)."""
    if isinstance(items, (str, bytes, Mapping)) or not isinstance(items, Sequence) or not items:
        raise ParameterError(path, items, "an array of at least one table "
                             "[[section.regions]] with material and shape")
    return tuple(region_from_mapping(r, f"{path}[{i}]") for i, r in enumerate(items))


def region_names(regions: Sequence[Region], path: str = "section.regions") -> list[str]:
    """How errors call each region: its name, or its key path ``section.regions[i]``."""
    return [r.name or f"{path}[{i}]" for i, r in enumerate(regions)]


def snap_tolerance(polys: Sequence[Polygon]) -> float:
    """The distance [m] below which points of different regions are joined:
    :data:`SNAP_RELATIVE` of the section's size (the larger side of the regions' bounding
    box), at least :data:`SNAP_ULPS` units in the last place of its largest coordinate."""
    b = np.array([p.bounds for p in polys], dtype=float)
    size = max(b[:, 2].max() - b[:, 0].min(), b[:, 3].max() - b[:, 1].min())
    far = float(np.abs(b).max())
    return max(SNAP_RELATIVE * size, SNAP_ULPS * float(np.finfo(float).eps) * far)


def bonded(polys: Sequence[Polygon], tol: float, names: Sequence[str] | None = None,
           path: str = "section.regions") -> list[Polygon]:
    """The polygons with every vertex closer than ``tol`` to a vertex of another polygon
    moved onto it, and every vertex of another polygon closer than ``tol`` to an edge put
    into that edge (shapely's snapping, in two passes: first each polygon onto the ones
    before it, then each onto all others), so that edges that coincide up to round-off
    coincide exactly and are noded as one."""
    out = list(polys)
    n = len(out)
    names = list(names) if names is not None else [f"{path}[{i}]" for i in range(n)]
    for i, p in enumerate(out):
        thick = 2.0 * p.area / p.length if p.length > 0 else 0.0
        if n > 1 and thick < 4.0 * tol:
            raise ParameterError(f"{path}[{i}].shape", names[i], f"a region thicker than "
                                 f"the section's round-off, {tol:.3g} m ({SNAP_RELATIVE:g} "
                                 f"of its size; here about {thick:.3g} m thick, 2 area / "
                                 "perimeter): thinner, its edges are one with its "
                                 "neighbours'")
    if n < 2:
        return out

    def vertices(idx) -> shapely.Geometry:
        return shapely.multipoints(np.concatenate([shapely.get_coordinates(out[j])
                                                   for j in idx]))

    for i in range(1, n):
        out[i] = shapely.snap(out[i], vertices(range(i)), tol)
    for i in range(n):
        out[i] = shapely.snap(out[i], vertices([j for j in range(n) if j != i]), tol)
    for i, p in enumerate(out):
        if not isinstance(p, Polygon) or not p.is_valid or not p.area > 0.0:
            raise ParameterError(f"{path}[{i}].shape", names[i],
                                 f"a region whose edges lie more than {tol:.3g} m (the "
                                 f"section's round-off, {SNAP_RELATIVE:g} of its size) from "
                                 "each other's and from the other regions' points: joined "
                                 "to its neighbours there, it is left without area ("
                                 + shapely.is_valid_reason(p) + ")")
    return out


def region_polygons(regions: Sequence[Region], h: float,
                    path: str = "section.regions") -> list[Polygon]:
    """The regions' polygons at mesh size ``h`` [m] (curves with about one vertex per h),
    bonded along the edges they share up to round-off (``bonded``)."""
    polys = [r.shape.polygon(h) for r in regions]
    return bonded(polys, snap_tolerance(polys), region_names(regions, path), path)


def check_regions(regions: Sequence[Region], materials: Mapping[str, SectionMaterial],
                  path: str = "section.regions", h: float | None = None) -> None:
    """Every material is known and no two regions overlap (errors name the regions)."""
    if not regions:
        raise ParameterError(path, [], "at least one region")
    names = region_names(regions, path)
    for i, r in enumerate(regions):
        if r.material not in materials:
            raise ParameterError(f"{path}[{i}].material", r.material, "one of the materials "
                                 + (", ".join(map(repr, materials)) or "(none given)"))
    # the coarsest polygons (16 sides for a curve): a fixed h of 1e9 m gave a 1e20 m
    # circle 6e11 vertices (an out-of-memory error)
    size = max(r.shape.polygon(math.inf).length for r in regions)
    hh0 = h if h is not None else size / 64
    hh = hh0
    polys = region_polygons(regions, hh, path)
    for i in range(len(polys)):
        for j in range(i + 1, len(polys)):
            if not polys[i].intersects(polys[j]):
                continue
            ov = polys[i].intersection(polys[j]).area
            if ov > OVERLAP_TOLERANCE * min(polys[i].area, polys[j].area) and ov > 0:
                raise ParameterError(f"{path}[{j}].shape", regions[j].shape.kind,
                                     f"a shape that does not overlap region {names[i]!r} "
                                     f"(region {names[j]!r} overlaps it by {ov:.4g} m^2)")
    union = unary_union(polys)
    parts = list(getattr(union, "geoms", [union]))
    if len(parts) > 1:
        groups = [[names[i] for i, p in enumerate(polys) if part.intersects(p)
                   and part.intersection(p).area > 0] for part in parts]
        raise ParameterError(path, " | ".join(", ".join(g) for g in groups),
                             f"regions that form one connected section, bonded along "
                             f"their edges (they form {len(parts)} separate parts: "
                             + "; ".join("[" + ", ".join(g) + "]" for g in groups) + ")")
