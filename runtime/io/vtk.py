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

from collections.abc import Iterable
from pathlib import Path
from xml.sax.saxutils import quoteattr

import numpy as np

from runtime.io.atomic import write_text
from runtime.model.rod import RodModel


def _array_xml(name: str, data: np.ndarray) -> str:
    data = np.asarray(data, dtype=float)
    comps = 1 if data.ndim == 1 else data.shape[1]
    body = " ".join(f"{v:.9g}" for v in data.ravel())
    return (f'<DataArray type="Float64" Name={quoteattr(name)} NumberOfComponents="{comps}" '
            f'format="ascii">{body}</DataArray>')


def element_fields(model: RodModel, t: float, y: np.ndarray, yp: np.ndarray | None = None
                   ) -> tuple[dict, dict]:
    """(cell_data, point_data) of state ``y`` and its rate ``yp`` at time ``t`` (the
    prescribed end frames, the loads and the viscous resultants of that time): see the
    module docstring for the fields."""
    d = model.diagnostics(t, y, yp)
    a = model.arrays
    N = model.N
    V, U = d["strains"]["V"], d["strains"]["U"]
    F, M = d["resultants"]["F"], d["resultants"]["M"]
    dV = V - a.seg_field("V0").T
    dU = U - a.jnt_field("U0").T

    def viscous_power(viscous, damping):            # x^T V^-1 x per column, 0 where V = 0
        inv = np.divide(1.0, damping, out=np.zeros_like(damping), where=damping > 0)
        return np.einsum("ij,ij,ij->j", viscous, inv, viscous)

    w = a.jnt_field("h")[:, 0].copy()
    w[0] = w[0] if a.clamped("start") else 0.0
    w[N] = w[N] if a.clamped("end") else 0.0
    if getattr(model, "coupled", False):
        seg_2D, joint_2D = _coupled_dissipation(model, t, y, w)
    else:
        Fv = F - a.seg_field("C_F").T * dV
        Mv = M - a.jnt_field("C_M").T * dU
        seg_2D = a.seg_field("h")[:, 0] * viscous_power(Fv, a.seg_field("V_F").T)
        joint_2D = w * viscous_power(Mv, a.jnt_field("V_M").T)
    R = model.frames(y)                                                   # (N, 3, 3)
    pos = model.positions(y)
    vel = y[model.v_index]
    cell = {"a1": R[:, :, 0], "a2": R[:, :, 1], "a3": R[:, :, 2], "V": V.T, "F": F.T,
            "dissipation_rate_2D": seg_2D}
    point = {"U": U.T, "M": M.T, "v": vel, "dissipation_rate_2D": joint_2D}
    point["position"] = pos.T
    return cell, point


def _coupled_dissipation(model: RodModel, t: float, y: np.ndarray, w: np.ndarray
                         ) -> tuple[np.ndarray, np.ndarray]:
    """2D per segment and per joint of a rod with coupled sections (full viscosity
    blocks), from the exact strain rates (``RodModel.strain_rates``): a segment
    ``h Vdot^T V_FF Vdot + 2 Vdot^T V_FM (w_a Udot_a + w_b Udot_b)`` (its couplings'
    share), a joint ``h_j Udot^T V_MM Udot``; they add up to the rod's 2D."""
    a = model.arrays
    Vd, Ud = (x.T for x in model.strain_rates(t, y))                     # (N, 3), (N+1, 3)
    m = a.section_matrices()
    wc = a.segc_field("w")
    kd = wc[:, :1] * Ud[:-1] + wc[:, 1:] * Ud[1:]
    h = a.seg_field("h")[:, 0]
    seg = (h * np.einsum("ni,nij,nj->n", Vd, m["V_FF"], Vd)
           + 2 * np.einsum("ni,nij,nj->n", Vd, m["V_FM"], kd))
    jnt = w * np.einsum("ni,nij,nj->n", Ud, m["V_MM"], Ud)
    return seg, jnt


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
    return write_text(Path(path), "\n".join(xml) + "\n")


def write_points_vtp(path: Path, points: np.ndarray, point_data: dict) -> Path:
    """Points (n, 3) as vertices with their arrays (ParaView: Glyph them), atomically."""
    pts = np.asarray(points, dtype=float).reshape(-1, 3)
    n = pts.shape[0]
    xml = [
        '<?xml version="1.0"?>',
        '<VTKFile type="PolyData" version="0.1" byte_order="LittleEndian">',
        "<PolyData>",
        f'<Piece NumberOfPoints="{n}" NumberOfVerts="{n}" NumberOfLines="0" '
        'NumberOfStrips="0" NumberOfPolys="0">',
        "<Points>", _array_xml("Points", pts), "</Points>",
        "<PointData>", *(_array_xml(k, v) for k, v in point_data.items()), "</PointData>",
        "<Verts>",
        '<DataArray type="Int64" Name="connectivity" format="ascii">'
        f'{" ".join(str(i) for i in range(n))}</DataArray>',
        '<DataArray type="Int64" Name="offsets" format="ascii">'
        f'{" ".join(str(i + 1) for i in range(n))}</DataArray>',
        "</Verts>", "</Piece>", "</PolyData>", "</VTKFile>",
    ]
    return write_text(Path(path), "\n".join(xml) + "\n")


def _pvd_text(entries: list[tuple[float, str]]) -> str:
    rows = [f'<DataSet timestep="{t:.9g}" group="" part="0" file="{name}"/>'
            for t, name in entries]
    pvd = ['<?xml version="1.0"?>',
           '<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">',
           "<Collection>", *rows, "</Collection>", "</VTKFile>"]
    return "\n".join(pvd) + "\n"


def read_pvd(path: Path) -> list[tuple[float, str]]:
    """(time, file) entries of a .pvd collection written by :class:`VtkSeries`."""
    entries = []
    for line in Path(path).read_text().splitlines():
        if "<DataSet" in line and 'timestep="' in line and 'file="' in line:
            t = float(line.split('timestep="', 1)[1].split('"', 1)[0])
            entries.append((t, line.split('file="', 1)[1].split('"', 1)[0]))
    return entries


class VtkSeries:
    """A ParaView time series written frame by frame (``stem_00000.vtp`` ... + ``stem.pvd``).

    Each frame is written when it is added and the collection file is rewritten atomically
    (every ``pvd_every`` frames and on :meth:`close`), so a run that stops keeps the frames
    it produced. ``resume_from=t``: continue an earlier series in ``folder``: its frames
    before ``t`` are kept (the resumed run adds the frame at ``t`` and those after it).
    """

    def __init__(self, folder: Path, model: RodModel, stem: str = "rod",
                 resume_from: float | None = None, pvd_every: int = 20) -> None:
        self.folder, self.model, self.stem = Path(folder), model, stem
        self.path = self.folder / f"{stem}.pvd"
        self.entries: list[tuple[float, str]] = []
        if resume_from is not None and self.path.exists():
            tol = 1e-9 * max(1.0, abs(resume_from))
            self.entries = [(t, f) for t, f in read_pvd(self.path)
                            if t < resume_from - tol and (self.folder / f).exists()]
            keep = {f for _, f in self.entries}
            keep |= {f.replace(f"{stem}_", f"{stem}_contact_", 1) for f in keep}
            for stale in self.folder.glob(f"{stem}_*.vtp"):  # frames after the checkpoint
                if stale.name not in keep:
                    stale.unlink()
        self._k = len(self.entries)
        self.pvd_every = max(1, int(pvd_every))
        #: a rod touching obstacles: the contact points of each frame (quadrature points
        #: within 3 delta of an obstacle) as ``{stem}_contact_*.vtp`` / ``.pvd``
        self.contact = (None if getattr(model, "contact", None) is None else
                        VtkSeries.__new__(VtkSeries))
        if self.contact is not None:
            c = self.contact
            c.folder, c.model, c.stem = self.folder, None, f"{stem}_contact"
            c.path = self.folder / f"{c.stem}.pvd"
            c.entries = [(t, f.replace(f"{stem}_", f"{stem}_contact_", 1))
                         for t, f in self.entries]
            c._k, c.pvd_every, c.contact = self._k, self.pvd_every, None

    def add(self, t: float, y: np.ndarray, yp: np.ndarray | None = None) -> None:
        """Write the frame of state ``y`` (rate ``yp``; None: at rest) at time ``t``."""
        cell, point = element_fields(self.model, float(t), np.ascontiguousarray(y),
                                     None if yp is None else np.ascontiguousarray(yp))
        pos = point.pop("position")
        name = f"{self.stem}_{self._k:05d}.vtp"
        write_vtp(self.folder / name, pos, cell, point)
        self._k += 1
        self.entries.append((float(t), name))
        if self.contact is not None:
            self.contact.add_points(float(t), self.model.contact_points(float(t), y))
        if len(self.entries) % self.pvd_every == 0:
            self.write_collection()

    def add_points(self, t: float, rows: np.ndarray) -> None:
        """A frame of contact points (rows of ``RodModel.contact_points``: obstacle,
        segment, x (3), gap)."""
        name = f"{self.stem}_{self._k:05d}.vtp"
        write_points_vtp(self.folder / name, rows[:, 2:5],
                         {"obstacle": rows[:, 0], "segment": rows[:, 1], "gap": rows[:, 5]})
        self._k += 1
        self.entries.append((t, name))

    def write_collection(self) -> Path:
        """(Re)write ``stem.pvd`` with the frames so far (atomically)."""
        if getattr(self, "contact", None) is not None:
            self.contact.write_collection()
        return write_text(self.path, _pvd_text(self.entries))

    close = write_collection


def write_series(folder: Path, model: RodModel, snapshots: Iterable[tuple],
                 stem: str = "rod") -> Path:
    """Write ``stem_0000.vtp ...`` and ``stem.pvd`` (the time collection) into ``folder``
    from snapshots ``(t, y)`` or ``(t, y, yp)``."""
    series = VtkSeries(folder, model, stem)
    for snap in snapshots:
        series.add(*snap)
    return series.close()
