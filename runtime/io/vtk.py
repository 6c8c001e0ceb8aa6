"""ParaView output: the rod centreline as VTK XML PolyData (.vtp) time series with a .pvd
collection.

Written by hand rather than through the VTK library: the XML PolyData format for a polyline
with point and cell arrays is a few dozen lines, and the ``vtk`` wheel (~140 MB) would be a
runtime dependency for that alone. The tests read the files back with the official VTK
reader (``vtk`` is in the test extra), so the format is checked by an independent parser.

Per file: points = node positions (N+1); one line cell per segment (N); cell data on
segments: directors a1, a2, a3 (frame), strains V, resultants F, dissipation rate 2D of the
segment (W); point data at nodes: curvature/twist U and moments M of the joint at the node
(zero where there is no joint), node velocity v, dissipation rate 2D of the joint (W).
"""

from __future__ import annotations

import os
from collections.abc import Iterable
from pathlib import Path
from xml.sax.saxutils import quoteattr

import numpy as np

from generated import rod_layout as L
from runtime.model.rod import RodModel, quat_rotation


def _array_xml(name: str, data: np.ndarray) -> str:
    data = np.asarray(data, dtype=float)
    comps = 1 if data.ndim == 1 else data.shape[1]
    body = " ".join(f"{v:.9g}" for v in data.ravel())
    return (f'<DataArray type="Float64" Name={quoteattr(name)} NumberOfComponents="{comps}" '
            f'format="ascii">{body}</DataArray>')


def element_fields(model: RodModel, y: np.ndarray) -> tuple[dict, dict]:
    """(cell_data, point_data) of state ``y``: see the module docstring for the fields."""
    d = model.diagnostics(0.0, y, None)
    N = model.N
    h = model.params.element_length
    mats = model.params.matrices()
    V, U = d["strains"]["V"], d["strains"]["U"]
    F, M = d["resultants"]["F"], d["resultants"]["M"]
    dV = V - np.array([[0.0], [0.0], [1.0]])

    def viscous_power(viscous, damping):            # x^T V^-1 x per column, 0 where V = 0
        inv = np.divide(1.0, damping, out=np.zeros_like(damping), where=damping > 0)
        return np.einsum("ij,i,ij->j", viscous, inv, viscous)

    Fv = F - mats["C_F"][:, None] * dV
    Mv = M - mats["C_M"][:, None] * U
    seg_2D = h * viscous_power(Fv, mats["V_F"])
    w = np.full(N + 1, h)
    w[0] = h / 2 if model.start == "clamped" else 0.0
    w[N] = h / 2 if model.end == "clamped" else 0.0
    joint_2D = w * viscous_power(Mv, mats["V_M"])
    R = np.array([quat_rotation(p) for p in model.quaternions(y).T])      # (N, 3, 3)
    pos = model.positions(y)
    v_idx = [L.CELL0_OFFSETS["v"]] + [L.cell_start(k) + L.CELL_OFFSETS["v"]
                                      for k in range(1, N + 1)]
    vel = np.array([y[i:i + 3] for i in v_idx])
    cell = {"a1": R[:, :, 0], "a2": R[:, :, 1], "a3": R[:, :, 2], "V": V.T, "F": F.T,
            "dissipation_rate_2D": seg_2D}
    point = {"U": U.T, "M": M.T, "v": vel, "dissipation_rate_2D": joint_2D}
    point["position"] = pos.T
    return cell, point


def write_vtp(path: Path, points: np.ndarray, cell_data: dict, point_data: dict) -> Path:
    """One polyline (points (n, 3)) with its arrays, written atomically."""
    pts = np.asarray(points, dtype=float)
    n = pts.shape[0]
    conn = " ".join(str(i) for j in range(n - 1) for i in (j, j + 1))
    offs = " ".join(str(2 * (j + 1)) for j in range(n - 1))
    xml = [
        '<?xml version="1.0"?>',
        '<VTKFile type="PolyData" version="0.1" byte_order="LittleEndian">',
        "<PolyData>",
        f'<Piece NumberOfPoints="{n}" NumberOfVerts="0" NumberOfLines="{n - 1}" '
        'NumberOfStrips="0" NumberOfPolys="0">',
        "<Points>", _array_xml("Points", pts), "</Points>",
        "<PointData>", *(_array_xml(k, v) for k, v in point_data.items()), "</PointData>",
        "<CellData>", *(_array_xml(k, v) for k, v in cell_data.items()), "</CellData>",
        "<Lines>",
        f'<DataArray type="Int64" Name="connectivity" format="ascii">{conn}</DataArray>',
        f'<DataArray type="Int64" Name="offsets" format="ascii">{offs}</DataArray>',
        "</Lines>", "</Piece>", "</PolyData>", "</VTKFile>",
    ]
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    tmp.write_text("\n".join(xml) + "\n")
    tmp.replace(path)
    return path


def write_series(folder: Path, model: RodModel, snapshots: Iterable[tuple[float, np.ndarray]],
                 stem: str = "rod") -> Path:
    """Write ``stem_0000.vtp ...`` and ``stem.pvd`` (the time collection) into ``folder``."""
    folder = Path(folder)
    entries = []
    for k, (t, y) in enumerate(snapshots):
        cell, point = element_fields(model, np.ascontiguousarray(y))
        pos = point.pop("position")
        name = f"{stem}_{k:05d}.vtp"
        write_vtp(folder / name, pos, cell, point)
        entries.append(f'<DataSet timestep="{t:.9g}" group="" part="0" file="{name}"/>')
    pvd = ['<?xml version="1.0"?>',
           '<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">',
           "<Collection>", *entries, "</Collection>", "</VTKFile>"]
    path = folder / f"{stem}.pvd"
    tmp = path.with_name(f".{path.name}.tmp")
    tmp.write_text("\n".join(pvd) + "\n")
    tmp.replace(path)
    return path
