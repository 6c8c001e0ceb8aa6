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
  than this fraction of its gap plus delta);
* ``self_contact``: the rod's contact with itself (:class:`SelfContactArrays`; None: off);
* ``tolerance_rate``: the contact's rate ``sqrt(k / rho A)`` (1/s) by which the error
  test's velocity tolerances near an obstacle follow the positions' (0: off; see
  ``kvrod_contact_error_weights`` in rod_contact.h and docs/design.md, section 14).

Like :class:`~runtime.model.arrays.RodArrays` the arrays are modified in place only (the
compiled code keeps their addresses). The problem layer fills them
(``runtime.problem.assemble.contact_arrays``).
"""

from __future__ import annotations

import ctypes
import math
from dataclasses import dataclass

import numpy as np

from generated import rod_layout as L
from runtime.solvers.native.pointers import function_address

#: the kernel kinds, in the compiled dispatch order
KINDS: tuple[str, ...] = tuple(L.OBSTACLE_KINDS)
#: values per obstacle of the compiled ``kvrod_contact_values`` (rod_contact.h, NCV)
VALUE_NAMES: tuple[str, ...] = ("force_x", "force_y", "force_z", "moment_x", "moment_y",
                                "moment_z", "energy", "dissipation", "friction_dissipation",
                                "obstacle_power", "gap_min", "segments")
N_VALUES = len(VALUE_NAMES)


def obstacle_series(values: np.ndarray) -> list[dict[str, np.ndarray]]:
    """Per obstacle, the rows ``VALUE_NAMES`` of ``values`` (``N_VALUES`` rows per obstacle,
    in file order; any trailing shape: one state or a series) by name: ``force`` and
    ``moment`` (3, ...; N, N m about the obstacle's point, on the rods, spatial),
    ``energy`` (J), ``dissipation`` and ``friction_dissipation`` (W), ``power`` (W, the
    obstacle's motion on the rods), ``gap_min`` (m) and ``segments``."""
    values = np.asarray(values)
    out = []
    for k in range(values.shape[0] // N_VALUES):
        block = values[k * N_VALUES:(k + 1) * N_VALUES]
        d = {"force": block[0:3], "moment": block[3:6]}
        d.update({name: block[j] for j, name in enumerate(VALUE_NAMES) if j >= 6})
        d["power"] = d.pop("obstacle_power")
        out.append(d)
    return out


#: the smallest share of its forces statics gives the contact (load factor 0)
MIN_FORCE_SCALE = 1e-12
#: the default step bound: half the gap plus delta per step at the approach speed
STEP_FRACTION = 0.5


#: values of the compiled ``kvrod_self_values`` (rod_contact.h, NSV)
SELF_VALUE_NAMES: tuple[str, ...] = ("energy", "dissipation", "friction_dissipation",
                                     "gap_min", "pairs", "force")
#: segments i < j closer along the rod than ``SELF_NEAR (r_i + r_j)`` of reference arc
#: length are never paired: a rod bent to its tightest (curvature 1/r) keeps stretches
#: closer than pi r along it within 2 r of each other (docs/design.md, section 14)
SELF_NEAR = math.pi / 2
#: pairs in reach the work arrays hold, per segment
SELF_PAIRS_PER_SEGMENT = 64


class SelfStruct(ctypes.Structure):
    """``kvrod_self`` of runtime/model/native/rod_contact.h."""

    _fields_ = [("seg", ctypes.c_void_p), ("s0", ctypes.c_void_p), ("near", ctypes.c_double),
                ("key", ctypes.c_void_p), ("pairs", ctypes.c_void_p),
                ("paircap", ctypes.c_int), ("ab", ctypes.c_void_p), ("ldab", ctypes.c_int),
                ("m2", ctypes.c_void_p), ("m2cap", ctypes.c_int), ("nz2cap", ctypes.c_int),
                ("srow2", ctypes.c_void_p), ("er2", ctypes.c_void_p), ("ec2", ctypes.c_void_p),
                ("ev2", ctypes.c_void_p), ("rowslot", ctypes.c_void_p),
                ("rowfill", ctypes.c_void_p), ("dropped", ctypes.c_int),
                ("nrod", ctypes.c_int), ("rods", ctypes.c_void_p), ("off", ctypes.c_void_p),
                ("sg0", ctypes.c_void_p), ("rowmap", ctypes.c_void_p),
                ("J", ctypes.c_void_p), ("ab_start", ctypes.c_void_p),
                ("ldabs", ctypes.c_void_p), ("last", ctypes.c_void_p),
                ("step_fraction", ctypes.c_double)]


class ContactStruct(ctypes.Structure):
    """``kvrod_contact`` of runtime/model/native/rod_contact.h."""

    _fields_ = [("nobs", ctypes.c_int), ("kind", ctypes.c_void_p), ("obs", ctypes.c_void_p),
                ("cnt", ctypes.c_void_p), ("step_fraction", ctypes.c_double),
                ("residual", ctypes.c_void_p), ("jacobian", ctypes.c_void_p),
                ("energies", ctypes.c_void_p), ("values", ctypes.c_void_p),
                ("max_step", ctypes.c_void_p), ("self", ctypes.c_void_p),
                ("couplings", ctypes.c_void_p), ("tolerance_rate", ctypes.c_double),
                ("energies_values", ctypes.c_void_p)]

    def bind(self, lib: ctypes.CDLL) -> None:
        """Point at the contact library's functions (``build.load_contact_library``)."""
        addr = function_address
        self.residual = addr(lib.kvrod_contact_residual)
        self.jacobian = addr(lib.kvrod_contact_jacobian)
        self.energies = addr(lib.kvrod_contact_energies)
        self.values = addr(lib.kvrod_contact_values)
        self.max_step = addr(lib.kvrod_contact_max_step)
        self.couplings = addr(lib.kvrod_self_couplings)
        self.energies_values = addr(lib.kvrod_contact_energies_values)


class SelfContactArrays:
    """The contact of a rod with itself (``kvrod_self``): ``seg`` (N, N_CNT) each
    segment's law in the ``CNT_PARAMS`` layout (k, delta, c: its normal damping per length
    on a rigid obstacle, mu: the rods' friction, v_s, r, h: its reference length; a pair
    takes the smaller k, delta and mu and ``c_1 c_2 / sqrt(c_1^2 + c_2^2)``, the damping of
    the pair's reduced mass), ``s0`` (N + 1) the reference arc length of the nodes (from
    h). The Jacobian's entries between a pair's two segments go to the dynamic couplings
    of the rod's coupled band block (:meth:`attach`)."""

    def __init__(self, seg: np.ndarray, near: float = SELF_NEAR,
                 rod_segments: tuple[int, ...] | None = None) -> None:
        self.seg = np.ascontiguousarray(seg, dtype=np.float64)
        if self.seg.ndim != 2 or self.seg.shape[1] != L.N_CNT or self.seg.shape[0] < 1:
            raise ValueError(f"self-contact law of shape {self.seg.shape}; expected "
                             f"(N, {L.N_CNT})")
        N = self.seg.shape[0]
        #: the segments of each rod (an assembly's rods one after the other in seg)
        self.rod_segments = (N,) if rod_segments is None else tuple(int(n) for n in
                                                                    rod_segments)
        if sum(self.rod_segments) != N or min(self.rod_segments) < 1:
            raise ValueError(f"rod segments {self.rod_segments} do not add up to {N}")
        h = self.seg[:, L.CNT_OFFSETS["h"]]
        cuts = np.cumsum((0,) + self.rod_segments)
        self.s0 = np.concatenate([np.concatenate([[0.0], np.cumsum(h[a:b])])
                                  for a, b in zip(cuts[:-1], cuts[1:], strict=True)])
        self.near = float(near)
        self._key = np.zeros(3 * N + 1)
        self._pairs = np.zeros(2 * SELF_PAIRS_PER_SEGMENT * N, dtype=np.int32)
        s = self._struct = SelfStruct()
        s.seg, s.s0, s.near = self.seg.ctypes.data, self.s0.ctypes.data, self.near
        s.key, s.pairs = self._key.ctypes.data, self._pairs.ctypes.data
        s.paircap = SELF_PAIRS_PER_SEGMENT * N
        #: the values of the last energies of a single rod (kvrod_energies_contact's)
        self._last = np.zeros(len(SELF_VALUE_NAMES))
        s.last = self._last.ctypes.data
        #: the step bound by the pairs' approach speed (kvrod_self.step_fraction; 0: none)
        s.step_fraction = STEP_FRACTION
        self.blocks = None

    @property
    def N(self) -> int:
        return int(self.seg.shape[0])

    def attach(self, blocks, n: int) -> None:
        """Write the Jacobian into ``blocks`` (a ``CoupledBlocks`` of one block, the rod's
        n unknowns, with dynamic coupling capacity)."""
        s = self._struct
        self.blocks = blocks
        self._rowslot = np.full(max(n, 1), -1, dtype=np.int32)
        self._rowfill = np.zeros(max(blocks.m2cap, 1), dtype=np.int32)
        s.ab, s.ldab = blocks.ab[0].ctypes.data, int(blocks.ldab[0])
        s.m2 = blocks.m2_address
        s.m2cap, s.nz2cap = blocks.m2cap, blocks.nz2cap
        s.srow2, s.er2 = blocks.srow2.ctypes.data, blocks.er2.ctypes.data
        s.ec2, s.ev2 = blocks.ec2.ctypes.data, blocks.ev2.ctypes.data
        s.rowslot, s.rowfill = self._rowslot.ctypes.data, self._rowfill.ctypes.data

    def attach_system(self, model, blocks) -> None:
        """The contact between the rods of an assembly (``model``: its ``SystemModel``,
        whose rods' segments ``rod_segments`` counts, in order): the pairs in the system's
        state, the entries within a segment into its rod's band of ``blocks``' buffer,
        those between segments into its dynamic couplings, a tied node's momentum row's
        into its master's and none of a node a joint holds at ground (``model.holds``)."""
        if tuple(r.N for r in model.rods) != self.rod_segments:
            raise ValueError(f"rods of {tuple(r.N for r in model.rods)} segments for pairs "
                             f"over {self.rod_segments}")
        self.attach(blocks, model.n)
        s = self._struct
        rowmap = np.arange(model.n, dtype=np.int32)
        for h in model.holds:
            rows = model.v_index[h.rod][h.node]
            rowmap[rows] = (-1 if h.master is None
                            else model.v_index[h.master[0]][h.master[1]])
        P = ctypes.c_void_p
        self._sys = (rowmap,
                     np.ascontiguousarray(model.offsets, dtype=np.int32),
                     np.array(np.cumsum((0,) + self.rod_segments), dtype=np.int32),
                     np.ascontiguousarray(blocks.ab_start, dtype=np.int64),
                     np.ascontiguousarray(blocks.ldab, dtype=np.int32),
                     (P * len(model.rods))(*[ctypes.addressof(r._struct)
                                             for r in model.rods]))
        s.nrod = len(model.rods)
        s.rods = ctypes.addressof(self._sys[5])
        s.off, s.sg0 = self._sys[1].ctypes.data, self._sys[2].ctypes.data
        s.rowmap = self._sys[0].ctypes.data
        s.J = blocks.buffer.ctypes.data
        s.ab_start, s.ldabs = self._sys[3].ctypes.data, self._sys[4].ctypes.data

    def set_force_scale(self, scale: float) -> None:
        """Scale the pairs' stiffness k and damping c from the values they were built
        with (statics takes the contact up with the load factor:
        :meth:`ContactArrays.set_force_scale`)."""
        kk, kc = L.CNT_OFFSETS["k"], L.CNT_OFFSETS["c"]
        base = getattr(self, "_base", None)
        if base is None:
            if scale == 1.0:
                return
            base = self._base = self.seg[:, [kk, kc]].copy()
        scale = max(float(scale), MIN_FORCE_SCALE)
        self.seg[:, kk] = scale * base[:, 0]
        self.seg[:, kc] = scale * base[:, 1]

    @property
    def dropped(self) -> int:
        """Pairs whose couplings did not fit the capacity at the last Jacobian (their
        forces are in the residual; Newton then converges more slowly)."""
        return int(self._struct.dropped)

    @property
    def struct_address(self) -> int:
        return ctypes.addressof(self._struct)

    def copy(self) -> SelfContactArrays:
        return SelfContactArrays(self.seg.copy(), self.near, self.rod_segments)


@dataclass(eq=False)
class ContactArrays:
    """The contact of one rod with its obstacles (see the module docstring)."""

    kind: np.ndarray
    obs: np.ndarray
    cnt: np.ndarray
    step_fraction: float = STEP_FRACTION
    self_contact: SelfContactArrays | None = None
    tolerance_rate: float = 0.0

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
        if self.self_contact is not None:
            self._struct.self = self.self_contact.struct_address
        if not (math.isfinite(self.tolerance_rate) and self.tolerance_rate >= 0.0):
            raise ValueError(f"tolerance_rate = {self.tolerance_rate}: finite, >= 0 (1/s)")
        self._struct.tolerance_rate = float(self.tolerance_rate)

    @property
    def n_obstacles(self) -> int:
        return int(self.kind.size)

    @property
    def active(self) -> bool:
        """Whether the rod touches anything: an obstacle, or itself."""
        return self.n_obstacles > 0 or self.self_contact is not None

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
        sc = self.self_contact
        kk, kc = L.CNT_OFFSETS["k"], L.CNT_OFFSETS["c"]
        if base is None:
            if scale == 1.0:
                return
            base = self._base = (self.cnt_field("k").copy(), self.cnt_field("c").copy(),
                                 None if sc is None else sc.seg[:, [kk, kc]].copy())
        # the kernels take k > 0 (the law's tail is k delta softplus(-g/delta)): load
        # factor 0 keeps a push of 1e-12 of the law's, far below any residual test
        scale = max(float(scale), MIN_FORCE_SCALE)
        self.cnt_field("k")[:] = scale * base[0]
        self.cnt_field("c")[:] = scale * base[1]
        if sc is not None:
            sc.seg[:, kk] = scale * base[2][:, 0]
            sc.seg[:, kc] = scale * base[2][:, 1]

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
                            self.step_fraction,
                            None if self.self_contact is None else self.self_contact.copy(),
                            self.tolerance_rate)
        if getattr(self, "lib", None) is not None:
            out.bind(self.lib)
        return out


__all__ = ["KINDS", "N_VALUES", "SELF_NEAR", "SELF_VALUE_NAMES", "STEP_FRACTION",
           "VALUE_NAMES", "ContactArrays", "ContactStruct", "SelfContactArrays", "SelfStruct"]
