"""Quadratic triangle mesh of the regions, conforming at their interfaces.

The regions' boundaries are noded together with shapely (shared edges become one segment,
T-junctions are split) into a planar straight-line graph; Shewchuk's Triangle (through
``cytriangle``, as ``sectionproperties`` uses it) meshes it with six-node triangles, one
region attribute per triangle and a maximum area per region. Nodes on a curved boundary or
interface (circle, ellipse, tube) are then put on the exact curve, so the elements there
are curved (isoparametric): the geometry error falls far below the discretisation error.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import cytriangle
import numpy as np
import shapely
from shapely.geometry import LineString, Polygon
from shapely.ops import unary_union

from runtime.section.regions import Region

#: minimum angle of the triangles (degrees; Triangle guarantees termination below 20.7)
MIN_ANGLE = 30.0


@dataclass(frozen=True)
class Mesh:
    """``nodes`` (n, 2) in m; ``elements`` (ne, 6) node indices, corners counterclockwise
    then the midside nodes of edges 0-1, 1-2, 2-0; ``region`` (ne,) region index; ``h``
    the target edge length in m."""

    nodes: np.ndarray
    elements: np.ndarray
    region: np.ndarray
    h: float


def _pslg(regions: Sequence[Region], h: float):
    polys = [r.shape.polygon(h) for r in regions]
    boundaries = unary_union([p.boundary for p in polys])       # noded: shared edges once
    lines = list(getattr(boundaries, "geoms", [boundaries]))
    index: dict[tuple[float, float], int] = {}
    vertices: list[tuple[float, float]] = []
    segments: list[tuple[int, int]] = []

    def vid(pt) -> int:
        key = (float(pt[0]), float(pt[1]))
        if key not in index:
            index[key] = len(vertices)
            vertices.append(key)
        return index[key]

    for line in lines:
        if not isinstance(line, LineString):
            continue
        coords = list(line.coords)
        for a, b in zip(coords[:-1], coords[1:], strict=True):
            ia, ib = vid(a), vid(b)
            if ia != ib:
                segments.append((ia, ib))
    # holes: faces enclosed by the regions that no region covers
    union = unary_union(polys)
    holes = []
    for part in getattr(union, "geoms", [union]):
        for ring in part.interiors:
            empty = Polygon(ring).difference(union)
            for face in getattr(empty, "geoms", [empty]):
                if face.area > 0:
                    p = face.representative_point()
                    holes.append((p.x, p.y))
    return polys, np.array(vertices), np.array(segments, dtype=np.int32), holes


def mesh_regions(regions: Sequence[Region], h: float) -> Mesh:
    """Mesh the regions with six-node triangles of edge length about ``h`` [m]."""
    polys, vertices, segments, holes = _pslg(regions, h)
    area = h * h * math.sqrt(3.0) / 4.0
    control = []
    for i, p in enumerate(polys):
        q = shapely.get_coordinates(p.representative_point())[0]
        control.append([q[0], q[1], float(i), area])
    tri = {"vertices": vertices, "segments": segments, "regions": control}
    if holes:
        tri["holes"] = holes
    out = cytriangle.triangulate(tri, f"pq{MIN_ANGLE:.1f}Aao2Q")
    nodes = np.asarray(out["vertices"], dtype=float)
    elements = np.asarray(out["triangles"], dtype=np.int64)
    # Triangle's midside order is (1-2, 2-0, 0-1); ours is (0-1, 1-2, 2-0)
    elements = elements[:, [0, 1, 2, 5, 3, 4]]
    region = np.asarray(out["triangle_attributes"], dtype=float)[:, 0].round().astype(int)
    for r in regions:
        for curve in r.shape.curves(h):
            nodes = curve.snap(nodes)
    used = np.unique(elements)
    if used.size != nodes.shape[0]:           # drop vertices outside every element
        remap = -np.ones(nodes.shape[0], dtype=np.int64)
        remap[used] = np.arange(used.size)
        nodes, elements = nodes[used], remap[elements]
    return Mesh(nodes=nodes, elements=elements, region=region, h=h)
