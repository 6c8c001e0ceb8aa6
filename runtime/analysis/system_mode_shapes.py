"""An assembly's mode shapes on its rods: from the reduced shape of
:func:`runtime.analysis.system_modal.assembly_modes` (the static reduced coordinates of
:class:`~runtime.model.system_statics.SystemStatics`) to every rod's node displacements
and segment rotations, and every body's mass-centre displacement (issue 31).

``dy = T q`` with the statics' tangent T at the equilibrium (a tied node moves with its
master, a support not at all; ``dp = 1/2 p (0, theta)`` for a segment rotated by the
material rotation vector theta), so ``theta = 2 Im(conj(p) dp)`` for a unit quaternion
p; a body's mass centre at offset e from its node moves by ``d + R (theta x e)`` (R, theta
of its segment). `kvrod modes` fixes each reduced shape's sign first
(:func:`runtime.analysis.modal.fix_sign`: its largest component positive).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from runtime.model.quaternion import quat_mul, quat_rotation
from runtime.model.system import SystemModel
from runtime.model.system_statics import SystemStatics

_CONJ = np.array([1.0, -1.0, -1.0, -1.0])


@dataclass
class RodShapes:
    """Mode shapes on one rod: ``displacement`` (k, 3, N+1) node displacements (m per unit
    modal coordinate: mass-normalised) and ``rotation`` (k, 3, N) segment rotations (rad,
    material)."""

    displacement: np.ndarray
    rotation: np.ndarray


def rod_mode_shapes(model: SystemModel, y_eq: np.ndarray, shapes: Sequence[np.ndarray],
                    t: float = 0.0) -> list[RodShapes]:
    """Every rod's :class:`RodShapes` (file order) of the reduced ``shapes`` (each
    (n_static,)) about the equilibrium ``y_eq`` (module docstring)."""
    st = SystemStatics(model, t)
    y0 = model.constrain(np.array(y_eq, dtype=float))
    T = st.tangent(y0).tocsr()
    k = len(shapes)
    dy = (np.asarray(T @ np.column_stack(shapes)) if k
          else np.zeros((model.n, 0)))                               # (n, k)
    out = []
    for r, rod in enumerate(model.rods):
        disp = dy[model.phi_index[r]]                                 # (N+1, 3, k)
        p = y0[model.p_index[r]]                                      # (N, 4)
        p = p / np.linalg.norm(p, axis=1)[:, None]
        dp = dy[model.p_index[r]]                                     # (N, 4, k)
        rot = np.zeros((k, 3, rod.N))
        for j in range(k):
            rot[j] = 2.0 * quat_mul(p * _CONJ, dp[:, :, j])[:, 1:].T
        out.append(RodShapes(np.transpose(disp, (2, 1, 0)).copy(), rot))
    return out


def body_mode_displacements(model: SystemModel, y_eq: np.ndarray, rods: Sequence[RodShapes]
                            ) -> np.ndarray:
    """The bodies' mass-centre displacements (k, nb, 3) of the shapes ``rods`` (from
    :func:`rod_mode_shapes`) about ``y_eq``."""
    k = rods[0].displacement.shape[0] if rods else 0
    out = np.zeros((k, len(model.bodies), 3))
    for b, body in enumerate(model.bodies):
        p = y_eq[model.p_index[body.rod][body.segment - 1]]
        R = quat_rotation(p / np.linalg.norm(p))
        e = np.asarray(body.offset, dtype=float)
        sh = rods[body.rod]
        for j in range(k):
            out[j, b] = (sh.displacement[j, :, body.node]
                         + R @ np.cross(sh.rotation[j, :, body.segment - 1], e))
    return out
