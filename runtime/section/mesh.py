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

from runtime.errors import ParameterError
from runtime.section.element import shape_functions
from runtime.section.regions import Region, region_names, region_polygons

#: minimum angle of the triangles (degrees; Triangle guarantees termination below 20.7)
MIN_ANGLE = 30.0
#: mesh grading at corners and material junctions (where stresses are singular): points on
#: circles of radius h q^k, k = 1..GRADING_LEVELS, around every such vertex
GRADING_RATIO = 0.3
GRADING_LEVELS = 4
#: most points Triangle may add to one mesh (a mesh of the analysis' largest size,
#: MAX_NODES = 120 000 six-node nodes, has about 30 000 corners); about a second of
#: meshing at worst (measured on a sliver between two plies)
MAX_STEINER = 60_000
#: most points of the regions' outlines (with the grading rings) given to the mesher
MAX_INPUT_POINTS = 50_000


class MeshBudgetError(ParameterError):
    """A mesh of the regions that Triangle could not make within the point budget; names
    ``section.regions`` and the regions where it got stuck."""


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
    polys = region_polygons(regions, h)
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


def _grading_points(vertices: np.ndarray, segments: np.ndarray, polys, h: float,
                    curves) -> np.ndarray:
    """Extra mesh vertices around the corners of the graph (a vertex whose segments are not
    two collinear ones): rings of 8 points at radii h q^k, kept where they lie inside a region
    and clear of every segment, so that Triangle grades the mesh towards the corner. The
    warping and stresses are singular there; without grading a uniform refinement converges
    slowly (e.g. at a box section's inner corners)."""
    nv = vertices.shape[0]
    nbr: list[list[int]] = [[] for _ in range(nv)]
    for a, b in segments:
        nbr[a].append(b)
        nbr[b].append(a)
    on_curve = np.zeros(nv, dtype=bool)
    for c in curves:
        r = np.hypot(*c.scaled(vertices).T)
        on_curve |= np.abs(r - 1.0) < 1e-9
    corners = []
    for i, nb in enumerate(nbr):
        if on_curve[i]:
            continue                       # a vertex of a polygonised circle or ellipse
        if len(nb) == 2:
            d1, d2 = vertices[nb[0]] - vertices[i], vertices[nb[1]] - vertices[i]
            cross = d1[0] * d2[1] - d1[1] * d2[0]
            if abs(cross) <= 1e-3 * np.linalg.norm(d1) * np.linalg.norm(d2):
                continue                   # a straight run or a polygonised curve
        corners.append(i)
    if not corners:
        return np.zeros((0, 2))
    union = unary_union(polys)
    edges = shapely.MultiLineString([vertices[[a, b]] for a, b in segments])
    t = 2 * np.pi * (np.arange(8) + 0.5) / 8
    ring = np.column_stack([np.cos(t), np.sin(t)])
    pts = []
    for i in corners:
        for k in range(1, GRADING_LEVELS + 1):
            r = h * GRADING_RATIO**k
            pts.append(vertices[i] + r * ring)
    pts = np.concatenate(pts)
    geo = shapely.points(pts)
    keep = shapely.contains(union, geo)
    dist = shapely.distance(edges, geo)
    radius = np.repeat([h * GRADING_RATIO**k for _ in corners
                        for k in range(1, GRADING_LEVELS + 1)], 8)
    keep &= dist > 0.3 * radius
    return pts[keep]


def _inverted(nodes: np.ndarray, elements: np.ndarray) -> np.ndarray:
    """Elements whose isoparametric Jacobian is not positive at a corner or midside node."""

    L = np.array([[1, 0, 0], [0, 1, 0], [0, 0, 1], [.5, .5, 0], [0, .5, .5], [.5, 0, .5]])
    _, dN = shape_functions(L.astype(float))
    J = np.einsum("qab,eac->eqcb", dN, nodes[elements])
    det = J[..., 0, 0] * J[..., 1, 1] - J[..., 0, 1] * J[..., 1, 0]
    return np.any(det <= 0, axis=1)


def steiner_budget(polys: Sequence[Polygon], sizes: Sequence[float], n_input: int) -> int:
    """The most points Triangle may add to a mesh of ``polys`` with elements of edge
    ``sizes[i]`` [m] in region i from ``n_input`` given points: four times the number of
    elements their areas take, 20 per given point (the grading at corners takes about
    100 per corner, 32 of them given) and 1000, at most ``MAX_STEINER``. Measured: the
    meshes of the examples add 0.3 ... 3 times the elements' number."""
    elements = sum(p.area / (hi * hi * math.sqrt(3.0) / 4.0)
                   for p, hi in zip(polys, sizes, strict=True))
    return int(min(MAX_STEINER, 4.0 * elements + 20.0 * n_input + 1000.0))


def _stuck(regions: Sequence[Region], polys: Sequence[Polygon], corners: np.ndarray,
           triangles: np.ndarray, budget: int, h: float) -> MeshBudgetError:
    """The error of a mesh that ran out of points: where its smallest triangles are, and
    the regions whose edges pass there."""
    p = corners[triangles[:, :3]]
    area = 0.5 * np.abs((p[:, 1, 0] - p[:, 0, 0]) * (p[:, 2, 1] - p[:, 0, 1])
                        - (p[:, 2, 0] - p[:, 0, 0]) * (p[:, 1, 1] - p[:, 0, 1]))
    longest = np.max(np.linalg.norm(p - np.roll(p, 1, axis=1), axis=2), axis=1)
    height = 2.0 * area / np.maximum(longest, 1e-300)     # across the thinnest direction
    small = np.argsort(height)[:20]
    where = p[small].mean(axis=1)
    size = float(height[small].max())
    edges = shapely.boundary(np.array(polys, dtype=object))
    dist = np.array([[shapely.distance(e, shapely.points(w)) for w in where] for e in edges])
    near = [i for i in range(len(polys))
            if np.any(dist[i] <= 10.0 * size + 1e-9 * h)] or [int(np.argmin(dist.min(1)))]
    names = region_names(regions)
    x = where[0]
    return MeshBudgetError(
        "section.regions", ", ".join(names[i] for i in near),
        f"regions the mesher can fill with at most {budget} points; near ({x[0]:.6g}, "
        f"{x[1]:.6g}) m the edges of {' and '.join(repr(names[i]) for i in near)} nearly "
        f"meet along a length and need elements {size:.2g} m thin against the section's "
        f"{h:.3g} m (a sliver of gap or overlap): make such edges coincide (points closer "
        f"than 1e-12 of the section's size are joined) or keep them further apart")


def mesh_regions(regions: Sequence[Region], h: float,
                 factors: Sequence[float] | None = None) -> Mesh:
    """Mesh the regions with six-node triangles of edge length about ``h`` [m] (times
    ``factors[i]`` <= 1 in region i: thin regions take smaller elements without refining
    the whole section).

    Raises :class:`MeshBudgetError` when the mesh needs more than
    :func:`steiner_budget` points or its outlines more than ``MAX_INPUT_POINTS``."""
    polys, vertices, segments, holes = _pslg(regions, h)
    curves = [c for r in regions for c in r.shape.curves(h)]
    extra = _grading_points(vertices, segments, polys, h, curves)
    if extra.size:
        vertices = np.vstack([vertices, extra])
    sizes = [h * (1.0 if factors is None else factors[i]) for i in range(len(polys))]
    if vertices.shape[0] > MAX_INPUT_POINTS:
        counts = [len(shapely.get_coordinates(p)) for p in polys]
        i = int(np.argmax(counts))
        raise MeshBudgetError(f"section.regions[{i}].shape", region_names(regions)[i],
                              f"outlines of at most {MAX_INPUT_POINTS} points in all (with "
                              f"the mesh grading at corners; here {vertices.shape[0]}, "
                              f"{counts[i]} of them this region's)")
    budget = steiner_budget(polys, sizes, vertices.shape[0])
    control = []
    for i, p in enumerate(polys):
        q = shapely.get_coordinates(p.representative_point())[0]
        control.append([q[0], q[1], float(i), sizes[i] * sizes[i] * math.sqrt(3.0) / 4.0])
    tri = {"vertices": vertices, "segments": segments, "regions": control}
    if holes:
        tri["holes"] = holes
    out = cytriangle.triangulate(tri, f"pq{MIN_ANGLE:.1f}Aao2QS{budget}")
    nodes = np.asarray(out["vertices"], dtype=float)
    elements = np.asarray(out["triangles"], dtype=np.int64)
    added = np.unique(elements[:, :3])
    if np.count_nonzero(added >= vertices.shape[0]) >= budget:
        raise _stuck(regions, polys, nodes, elements, budget, h)
    # Triangle's midside order is (1-2, 2-0, 0-1); ours is (0-1, 1-2, 2-0)
    elements = elements[:, [0, 1, 2, 5, 3, 4]]
    region = np.asarray(out["triangle_attributes"], dtype=float)[:, 0].round().astype(int)
    chord = nodes
    for curve in curves:
        nodes = curve.snap(nodes)
    # a node put on a curve must not turn an element inside out (a region's corner close
    # to a curved interface): such elements keep their nodes on the chords
    for _ in range(3):
        bad = _inverted(nodes, elements)
        if not bad.any():
            break
        idx = np.unique(elements[bad])
        nodes = nodes.copy()
        nodes[idx] = chord[idx]
    used = np.unique(elements)
    if used.size != nodes.shape[0]:           # drop vertices outside every element
        remap = -np.ones(nodes.shape[0], dtype=np.int64)
        remap[used] = np.arange(used.size)
        nodes, elements = nodes[used], remap[elements]
    return Mesh(nodes=nodes, elements=elements, region=region, h=h)
