"""The numbers the compiled contact of a rod with rigid obstacles reads (issue 32;
``runtime/model/native/rod_contact.h``; docs/design.md, section 14).

:class:`ContactArrays` holds, for a rod of N segments touching ``nobs`` obstacles:

* ``kind`` (nobs,) int32: each obstacle's kernel (:data:`KINDS`, the order of
  ``generated/rod_layout.OBSTACLE_KINDS``);
* ``obs`` (nobs, N_OBS): each obstacle's parameters (``OBS_PARAMS``: its current pose
  ``c, q, v, w`` first, written by :meth:`ContactArrays.set_pose` as it moves; then its
  shape in its own frame, whose origin is the obstacle's point);
* ``cnt`` (nobs, N, N_CNT): the contact law of each segment with each obstacle
  (``CNT_PARAMS``: k, delta, c, mu, v_s, r, h);
* ``step_fraction``: the step bound (a step moves no segment toward an obstacle by more
  than this fraction of its gap plus delta).

Like :class:`~runtime.model.arrays.RodArrays` the arrays are modified in place only (the
compiled code keeps their addresses). The problem layer fills them
(``runtime.problem.assemble.contact_arrays``).
"""

from __future__ import annotations

import ctypes
from dataclasses import dataclass

import numpy as np

from generated import rod_layout as L

#: the kernel kinds, in the compiled dispatch order
KINDS: tuple[str, ...] = tuple(L.OBSTACLE_KINDS)
#: values per obstacle of the compiled ``kvrod_contact_values`` (rod_contact.h, NCV)
VALUE_NAMES: tuple[str, ...] = ("force_x", "force_y", "force_z", "moment_x", "moment_y",
                                "moment_z", "energy", "dissipation", "friction_dissipation",
                                "obstacle_power", "gap_min", "segments")
N_VALUES = len(VALUE_NAMES)
#: the smallest share of its forces statics gives the contact (load factor 0)
MIN_FORCE_SCALE = 1e-12
#: the default step bound: half the gap plus delta per step at the approach speed
STEP_FRACTION = 0.5


class ContactStruct(ctypes.Structure):
    """``kvrod_contact`` of runtime/model/native/rod_contact.h."""

    _fields_ = [("nobs", ctypes.c_int), ("kind", ctypes.c_void_p), ("obs", ctypes.c_void_p),
                ("cnt", ctypes.c_void_p), ("step_fraction", ctypes.c_double),
                ("residual", ctypes.c_void_p), ("jacobian", ctypes.c_void_p),
                ("energies", ctypes.c_void_p), ("values", ctypes.c_void_p),
                ("max_step", ctypes.c_void_p)]

    def bind(self, lib: ctypes.CDLL) -> None:
        """Point at the contact library's functions (``build.load_contact_library``)."""
        addr = lambda fn: ctypes.cast(fn, ctypes.c_void_p).value  # noqa: E731
        self.residual = addr(lib.kvrod_contact_residual)
        self.jacobian = addr(lib.kvrod_contact_jacobian)
        self.energies = addr(lib.kvrod_contact_energies)
        self.values = addr(lib.kvrod_contact_values)
        self.max_step = addr(lib.kvrod_contact_max_step)


@dataclass(eq=False)
class ContactArrays:
    """The contact of one rod with its obstacles (see the module docstring)."""

    kind: np.ndarray
    obs: np.ndarray
    cnt: np.ndarray
    step_fraction: float = STEP_FRACTION

    def __post_init__(self) -> None:
        self.kind = np.ascontiguousarray(self.kind, dtype=np.int32)
        self.obs = np.ascontiguousarray(self.obs, dtype=np.float64)
        self.cnt = np.ascontiguousarray(self.cnt, dtype=np.float64)
        n = self.kind.size
        if self.obs.shape != (n, L.N_OBS) or self.cnt.ndim != 3 or self.cnt.shape[0] != n \
                or self.cnt.shape[2] != L.N_CNT:
            raise ValueError(f"contact arrays of shapes {self.kind.shape}, {self.obs.shape}, "
                             f"{self.cnt.shape}; expected (n,), (n, {L.N_OBS}), "
                             f"(n, N, {L.N_CNT})")
        if np.any((self.kind < 0) | (self.kind >= len(KINDS))):
            raise ValueError(f"contact kinds {self.kind.tolist()} outside 0..{len(KINDS) - 1}")
        self._struct = ContactStruct(n, self.kind.ctypes.data, self.obs.ctypes.data,
                                     self.cnt.ctypes.data, float(self.step_fraction))

    @property
    def n_obstacles(self) -> int:
        return int(self.kind.size)

    @property
    def N(self) -> int:
        """The rod's number of segments."""
        return int(self.cnt.shape[1])

    def obs_field(self, name: str) -> np.ndarray:
        """View (nobs, size) of an obstacle parameter (``OBS_PARAMS``)."""
        k = L.OBS_OFFSETS[name]
        size = dict((p[0], p[1]) for p in L.OBS_PARAMS)[name]
        return self.obs[:, k:k + size]

    def cnt_field(self, name: str) -> np.ndarray:
        """View (nobs, N) of a contact law parameter (``CNT_PARAMS``)."""
        return self.cnt[:, :, L.CNT_OFFSETS[name]]

    def set_pose(self, k: int, position, quaternion, velocity, angular_velocity) -> None:
        """Obstacle k's current pose: its point's position (m) and velocity (m/s), the
        quaternion of its rotation from the reference and its angular velocity (rad/s),
        spatial."""
        row = self.obs[k]
        for name, v in (("c", position), ("q", quaternion), ("v", velocity),
                        ("w", angular_velocity)):
            o = L.OBS_OFFSETS[name]
            v = np.asarray(v, dtype=float).ravel()
            row[o:o + v.size] = v

    def set_force_scale(self, scale: float) -> None:
        """Scale the contact's forces (its stiffness k and damping c per length) by
        ``scale`` from the values it was built with: statics takes the contact up with the
        load factor (at load factor 0 a smooth law's push at zero gap would carry nothing
        and the rod would have no equilibrium; scaled, the reference is one and the path
        ends on the full law at 1)."""
        base = getattr(self, "_base", None)
        if base is None:
            if scale == 1.0:
                return
            base = self._base = (self.cnt_field("k").copy(), self.cnt_field("c").copy())
        # the kernels take k > 0 (the law's tail is k delta softplus(-g/delta)): load
        # factor 0 keeps a push of 1e-12 of the law's, far below any residual test
        scale = max(float(scale), MIN_FORCE_SCALE)
        self.cnt_field("k")[:] = scale * base[0]
        self.cnt_field("c")[:] = scale * base[1]

    def bind(self, lib: ctypes.CDLL) -> None:
        """Let the compiled rod reach the contact library's functions (``lib``:
        ``runtime.model.build.load_contact_library()``); the rod library refuses nothing
        without it, so the model binds before its first evaluation."""
        self._struct.bind(lib)
        self.lib = lib

    @property
    def struct_address(self) -> int:
        """Address of the ``kvrod_contact`` (valid while ``self`` lives)."""
        return ctypes.addressof(self._struct)

    def copy(self) -> ContactArrays:
        out = ContactArrays(self.kind.copy(), self.obs.copy(), self.cnt.copy(),
                            self.step_fraction)
        if getattr(self, "lib", None) is not None:
            out.bind(self.lib)
        return out


__all__ = ["KINDS", "N_VALUES", "STEP_FRACTION", "VALUE_NAMES", "ContactArrays",
           "ContactStruct"]
