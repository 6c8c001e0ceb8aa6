"""The picture of an analysed cross-section (``kvrod section``, notes/sections.md): the
regions coloured by material, the finite-element mesh, and the centres (elastic centroid =
the reference point, shear centre, mass centre, the viscous centroids of both routes)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

#: a six-node triangle drawn as its four corner-and-midside sub-triangles (curved edges)
_SUB = ((0, 3, 5), (3, 1, 4), (5, 4, 2), (3, 4, 5))


def _scale(extent: float) -> tuple[float, str]:
    return (1e3, "mm") if extent < 0.5 else (1.0, "m")


def _polygons(polys: np.ndarray):
    """One compound matplotlib Path of the closed polygons ``polys`` (m, k, 2)."""
    from matplotlib.path import Path as MplPath

    m, k, _ = polys.shape
    verts = np.concatenate([polys, polys[:, :1]], axis=1).reshape(-1, 2)
    codes = np.full((m, k + 1), MplPath.LINETO, dtype=MplPath.code_type)
    codes[:, 0], codes[:, -1] = MplPath.MOVETO, MplPath.CLOSEPOLY
    return MplPath(verts, codes.ravel())


def draw_section(result: Any, regions: Sequence[Any], path: Path, title: str = "",
                 dpi: int = 110) -> Path:
    """Draw ``result`` (a :class:`runtime.section.SectionResult` with its mesh) of the
    ``regions`` it was computed from into the PNG ``path``; returns the path."""
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch, PathPatch

    from runtime.io.figures import pyplot, save

    plt = pyplot()
    mesh = result.mesh
    nodes, el = mesh.nodes, mesh.elements
    extent = float(np.max(np.ptp(nodes, axis=0)))
    f, unit = _scale(extent)
    materials = list(dict.fromkeys(r.material for r in regions))
    colours = plt.get_cmap("tab10")
    face = np.array([materials.index(regions[i].material) for i in mesh.region])
    tris = np.concatenate([nodes[el[:, list(s)]] for s in _SUB]) * f
    span = np.ptp(nodes, axis=0)
    height = float(np.clip(4.4 * span[1] / max(span[0], 1e-300) + 1.6, 2.6, 5.6))
    fig, ax = plt.subplots(figsize=(7.6, height), layout="constrained")
    # one compound path per material and one polyline for all edges: a collection of
    # tens of thousands of paths costs seconds in matplotlib (a Path object and extents
    # each); the compound paths draw the same pixels in a fraction of that
    # (add_artist: add_patch would walk the path's segments in Python for the limits)
    sub_face = np.tile(face, len(_SUB))
    for k in range(len(materials)):
        ax.add_artist(PathPatch(_polygons(tris[sub_face == k]), facecolor=colours(k % 10),
                                edgecolor="none", alpha=0.55, transform=ax.transData))
    ax.update_datalim(nodes * f)
    # element edges: corner-midside-corner polylines (curved where the element is)
    edges = np.concatenate([nodes[el[:, [0, 3, 1]]], nodes[el[:, [1, 4, 2]]],
                            nodes[el[:, [2, 5, 0]]]]) * f
    gaps = np.full((edges.shape[0], 1, 2), np.nan)
    xy = np.concatenate([edges, gaps], axis=1).reshape(-1, 2)
    ax.plot(xy[:, 0], xy[:, 1], color="k", lw=0.15, alpha=0.6)
    marks = [("elastic centroid (reference point)", result.elastic_centroid, "k", "+", 14),
             ("shear centre", result.shear_centre, "C3", "x", 10),
             ("mass centre", result.mass_centre, "C0", "o", 6),
             ("viscous centroid (consistent)", result.viscous_centroid, "C2", "D", 6),
             ("viscous centroid (naive)", result.viscous_centroid_naive, "C1", "^", 6)]
    handles: list[Any] = [Patch(facecolor=colours(k % 10), alpha=0.55, label=m)
                          for k, m in enumerate(materials)]
    for label, pt, colour, marker, size in marks:
        if pt is None:
            continue
        ax.plot([pt[0] * f], [pt[1] * f], marker=marker, color=colour, ms=size,
                mfc="none" if marker in "oD^" else colour, mew=1.4, ls="none")
        handles.append(Line2D([], [], marker=marker, color=colour, ms=size, ls="none",
                              mfc="none" if marker in "oD^" else colour, label=label))
    ax.set_aspect("equal")
    ax.autoscale_view()
    ax.set_xlabel(f"x1 along d1 [{unit}]")
    ax.set_ylabel(f"x2 along d2 [{unit}]")
    ax.set_title(title or f"{result.n_elements} six-node triangles, h = "
                 f"{result.mesh_size * f:.3g} {unit}", fontsize=9)
    ax.legend(handles=handles, fontsize=7, loc="center left", bbox_to_anchor=(1.02, 0.5),
              frameon=False)
    return save(fig, Path(path), dpi=dpi)
