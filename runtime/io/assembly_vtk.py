"""ParaView output of an assembly of rods (issue 31): one time series per rod and one of
the bodies, written frame by frame as the run goes (``kvrod simulate ASSEMBLY --vtk DT``).

In the results folder's ``vtk/``:

* ``NAME.pvd`` + ``NAME_00000.vtp`` ...: rod NAME's centreline with its element fields,
  exactly as a single rod's ``rod.pvd`` (:func:`runtime.io.vtk.element_fields` of the
  rod's own model and its slice of the state);
* ``bodies.pvd`` + ``bodies_00000.vtp`` ... (when the assembly has bodies): one vertex per
  body (file order) at its mass centre, with point data ``d1``, ``d2``, ``d3`` (the
  directors of its frame, the columns of R), ``v`` (mass-centre velocity, m/s),
  ``omega`` (angular velocity, spatial, rad/s), ``mass`` (kg) and ``index``;
* ``assembly.pvd``: every rod and the bodies as the parts of one dataset (ParaView opens
  it as one multiblock with a part per rod).

The frames are at the run's own times (``Snapshots`` every DT s); a resumed run keeps
the frames before its checkpoint (:class:`runtime.io.vtk.FrameSeries`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from runtime.errors import ParameterError
from runtime.io.atomic import write_text
from runtime.io.vtk import FrameSeries, VtkSeries, pvd_text
from runtime.model.quaternion import quat_rotation

#: file stems of the series that are not a rod's
BODIES_STEM = "bodies"
COLLECTION_STEM = "assembly"


def check_rod_names(names: list[str]) -> None:
    """Refuse (:class:`~runtime.errors.ParameterError`) a rod whose name is taken by the
    bodies' series or the collection (``vtk/bodies.pvd``, ``vtk/assembly.pvd``)."""
    for name in names:
        if name in (BODIES_STEM, COLLECTION_STEM):
            raise ParameterError(f"rods.{name}", name, "a rod name other than "
                                 f"{BODIES_STEM!r} and {COLLECTION_STEM!r} for --vtk (those "
                                 "name the bodies' series and the whole assembly's in vtk/)")


def body_fields(model, y: np.ndarray, yp: np.ndarray | None = None
                ) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """(points (nb, 3), point data) of the bodies of a
    :class:`~runtime.model.system.SystemModel` at state ``y`` (see the module docstring);
    ``yp`` is unused (a body's velocities are in y) and accepted for symmetry."""
    _ = yp
    nb = len(model.bodies)
    pts, vel, om = np.zeros((nb, 3)), np.zeros((nb, 3)), np.zeros((nb, 3))
    d = np.zeros((3, nb, 3))
    for j, b in enumerate(model.bodies):
        phi = y[model.phi_index[b.rod][b.node]]
        v = y[model.v_index[b.rod][b.node]]
        p = y[model.p_index[b.rod][b.segment - 1]]
        Om = y[model.omega_index[b.rod][b.segment - 1]]
        R = quat_rotation(p / np.linalg.norm(p))
        e = np.asarray(b.offset, dtype=float)
        pts[j] = phi + R @ e
        vel[j] = v + R @ np.cross(Om, e)
        om[j] = R @ Om
        d[:, j] = R.T
    return pts, {"d1": d[0], "d2": d[1], "d3": d[2], "v": vel, "omega": om,
                 "mass": np.array([b.mass for b in model.bodies], dtype=float),
                 "index": np.arange(nb, dtype=float)}


class AssemblyVtk:
    """The ParaView series of an assembly's run (module docstring): ``add(t, y, yp)`` is a
    snapshot sink of :func:`runtime.simulate.assembly.simulate_assembly`.

    ``model``: the run's :class:`~runtime.model.system.SystemModel`; ``resume_from``: the
    checkpoint's time of a resumed run (frames before it are kept)."""

    def __init__(self, folder: Path, model, resume_from: float | None = None,
                 pvd_every: int = 20) -> None:
        check_rod_names(list(model.names))
        self.folder, self.model = Path(folder), model
        self.rods = [VtkSeries(self.folder, rod, stem=name, resume_from=resume_from,
                               pvd_every=pvd_every)
                     for rod, name in zip(model.rods, model.names, strict=True)]
        self.bodies = (FrameSeries(self.folder, BODIES_STEM, resume_from, pvd_every)
                       if model.bodies else None)

    @property
    def series(self) -> list[FrameSeries]:
        """Every series: the rods' in file order, then the bodies'."""
        return [*self.rods, *([self.bodies] if self.bodies is not None else [])]

    def add(self, t: float, y: np.ndarray, yp: np.ndarray | None = None) -> None:
        """Write the frames of state ``y`` (rate ``yp``; None: at rest) at time ``t``."""
        m = self.model
        for k, s in enumerate(self.rods):
            s.add(t, m.rod_state(k, y), None if yp is None else m.rod_state(k, yp))
        if self.bodies is not None:
            pts, point = body_fields(m, y, yp)
            self.bodies.add_frame(t, pts, {}, point, cells="vertex")

    def write_collection(self) -> Path:
        """(Re)write every series' .pvd and ``assembly.pvd`` (atomically); returns the
        latter."""
        entries = []
        for part, s in enumerate(self.series):
            s.write_collection()
            entries += [(t, f, part) for t, f in s.entries]
        entries.sort(key=lambda e: (e[0], e[2]))
        return write_text(self.folder / f"{COLLECTION_STEM}.pvd", pvd_text(entries))

    close = write_collection
