"""Regions of a composite section: a material name and a shape (``[[section.regions]]``).

Regions must not overlap (touching along edges is how they are bonded); an overlap is an
error naming both regions. Together they must form one connected section (separate parts
could slide along each other: the rod would have no single stiffness); holes are allowed.
Every region's material must be one of the named materials.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from shapely.ops import unary_union

from runtime.errors import ParameterError
from runtime.section import _checks as ck
from runtime.section.materials import SectionMaterial
from runtime.section.shapes import Shape, shape_from_mapping

#: relative overlap area (of the smaller region) above which two regions overlap
OVERLAP_TOLERANCE = 1e-9


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


def check_regions(regions: Sequence[Region], materials: Mapping[str, SectionMaterial],
                  path: str = "section.regions", h: float | None = None) -> None:
    """Every material is known and no two regions overlap (errors name the regions)."""
    if not regions:
        raise ParameterError(path, [], "at least one region")
    names = [r.name or f"{path}[{i}]" for i, r in enumerate(regions)]
    for i, r in enumerate(regions):
        if r.material not in materials:
            raise ParameterError(f"{path}[{i}].material", r.material, "one of the materials "
                                 + (", ".join(map(repr, materials)) or "(none given)"))
    # the coarsest polygons (16 sides for a curve): a fixed h of 1e9 m gave a 1e20 m
    # circle 6e11 vertices (an out-of-memory error)
    size = max(r.shape.polygon(math.inf).length for r in regions)
    hh0 = h if h is not None else size / 64
    hh = hh0
    polys = [r.shape.polygon(hh) for r in regions]
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
