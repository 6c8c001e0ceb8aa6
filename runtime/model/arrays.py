"""The numbers the generated assembly reads: global, per-element and load arrays.

:class:`RodArrays` holds, for a rod of N elements, the arrays whose layout
``generated/rod_layout.py`` defines (the one source of every layout):

* ``par`` (N_PARAMS,): load factor, gravity, distributed load, the ends (held, clamped,
  prescribed position/velocity/frame/angular velocity);
* ``seg`` (N, N_SEGMENT): per segment: length h, C_F, V_F, reference strain V0, rho A,
  rho I;
* ``jnt`` (N+1, N_JOINT): per joint (at node j): length, C_M, V_M, reference curvature U0;
* ``nload`` (N+1, N_NODE_LOAD): dead and follower point forces on the nodes;
* ``sload`` (N, N_SEGMENT_LOAD): dead and follower point moments on the segments;
* for a generalized Maxwell rod with B relaxation terms: ``theta`` (B,) their relaxation
  times (s), ``segb`` (N, B, 3) their moduli on the segments (the shear and extension
  stiffnesses of term b, N) and ``jntb`` (N+1, B, 3) on the joints (bending and torsion,
  N m^2); B = 0 for Kelvin-Voigt.

All are C-contiguous float64 and are modified in place only (the compiled code keeps
their addresses). Named views (``seg_field("C_F")`` -> (N, 3)) avoid index arithmetic.
"""

from __future__ import annotations

import ctypes
from dataclasses import dataclass, field

import numpy as np

from generated import rod_layout as L


class RodStruct(ctypes.Structure):
    """``kvrod_rod`` of runtime/model/native/rod_assembly.h."""

    _fields_ = [("N", ctypes.c_int), ("nb", ctypes.c_int), ("kl", ctypes.c_int),
                ("ku", ctypes.c_int), ("par", ctypes.c_void_p), ("seg", ctypes.c_void_p),
                ("jnt", ctypes.c_void_p), ("nload", ctypes.c_void_p),
                ("sload", ctypes.c_void_p), ("theta", ctypes.c_void_p),
                ("segb", ctypes.c_void_p), ("jntb", ctypes.c_void_p)]


def _view(arr: np.ndarray, offsets: dict[str, int], fields, name: str) -> np.ndarray:
    size = {f[0]: f[1] for f in fields}[name]
    k = offsets[name]
    return arr[:, k:k + size]


@dataclass
class RodArrays:
    """The assembly's input arrays for one rod (see the module docstring)."""

    N: int
    par: np.ndarray
    seg: np.ndarray
    jnt: np.ndarray
    nload: np.ndarray
    sload: np.ndarray
    theta: np.ndarray = field(default_factory=lambda: np.zeros(0))
    segb: np.ndarray = field(default_factory=lambda: np.zeros((0, 0, 3)))
    jntb: np.ndarray = field(default_factory=lambda: np.zeros((0, 0, 3)))

    @classmethod
    def zeros(cls, n_elements: int, branches: int = 0) -> RodArrays:
        N, B = int(n_elements), int(branches)
        return cls(N=N, par=np.zeros(L.N_PARAMS), seg=np.zeros((N, L.N_SEGMENT)),
                   jnt=np.zeros((N + 1, L.N_JOINT)), nload=np.zeros((N + 1, L.N_NODE_LOAD)),
                   sload=np.zeros((N, L.N_SEGMENT_LOAD)), theta=np.ones(B),
                   segb=np.zeros((N, B, 3)), jntb=np.zeros((N + 1, B, 3)))

    @property
    def branches(self) -> int:
        """Number B of relaxation terms (0: Kelvin-Voigt)."""
        return int(self.theta.size)

    def copy(self) -> RodArrays:
        return RodArrays(self.N, self.par.copy(), self.seg.copy(), self.jnt.copy(),
                         self.nload.copy(), self.sload.copy(), self.theta.copy(),
                         self.segb.copy(), self.jntb.copy())

    # -- named access ----------------------------------------------------------------
    def param(self, name: str) -> np.ndarray:
        """View of a global parameter (1-D, size of the entry)."""
        k, s = L.PARAM_OFFSETS[name], L.PARAM_SIZES[name]
        return self.par[k:k + s]

    def set_param(self, name: str, value) -> None:
        self.param(name)[:] = np.asarray(value, dtype=float).ravel()

    def seg_field(self, name: str) -> np.ndarray:
        """View (N, size) of a segment parameter."""
        return _view(self.seg, L.SEGMENT_OFFSETS, L.SEGMENT_PARAMS, name)

    def jnt_field(self, name: str) -> np.ndarray:
        """View (N+1, size) of a joint parameter."""
        return _view(self.jnt, L.JOINT_OFFSETS, L.JOINT_PARAMS, name)

    def node_load(self, name: str) -> np.ndarray:
        """View (N+1, 3) of a node load."""
        return _view(self.nload, L.NODE_LOAD_OFFSETS, L.NODE_LOADS, name)

    def segment_load(self, name: str) -> np.ndarray:
        """View (N, 3) of a segment load."""
        return _view(self.sload, L.SEGMENT_LOAD_OFFSETS, L.SEGMENT_LOADS, name)

    # -- the ends -----------------------------------------------------------------------
    def held(self, end: str) -> bool:
        """Node 0 (``end = "start"``) or node N (``"end"``) has a prescribed position."""
        return bool(self.param("fix_" + end)[0] > 0.5)

    def clamped(self, end: str) -> bool:
        """The frame at ``end`` is prescribed (half-length clamp joint)."""
        return bool(self.param("clamp_" + end)[0] > 0.5)

    # -- C view -------------------------------------------------------------------------
    def struct(self, kl: int | None = None, ku: int | None = None) -> RodStruct:
        """The ``kvrod_rod`` pointing at these arrays (keep ``self`` alive while used), for
        band storage with ``kl``, ``ku`` (default: the layout's band of this rod)."""
        for name in ("par", "seg", "jnt", "nload", "sload", "theta", "segb", "jntb"):
            a = getattr(self, name)
            if not (a.dtype == np.float64 and a.flags.c_contiguous):
                raise TypeError(f"RodArrays.{name} must be C-contiguous float64")
        B = self.branches
        if self.segb.shape != (self.N, B, 3) or self.jntb.shape != (self.N + 1, B, 3):
            raise ValueError(f"relaxation moduli of shapes {self.segb.shape}, "
                             f"{self.jntb.shape}; expected {(self.N, B, 3)}, "
                             f"{(self.N + 1, B, 3)}")
        bkl, bku = L.bandwidths(self.N, B)
        return RodStruct(self.N, B, bkl if kl is None else kl, bku if ku is None else ku,
                         self.par.ctypes.data, self.seg.ctypes.data,
                         self.jnt.ctypes.data, self.nload.ctypes.data, self.sload.ctypes.data,
                         self.theta.ctypes.data, self.segb.ctypes.data, self.jntb.ctypes.data)

    def node_masses(self) -> np.ndarray:
        """Lumped node masses (N+1,) in kg: half of each adjacent segment's rho A h."""
        ms = self.seg_field("rhoA")[:, 0] * self.seg_field("h")[:, 0]
        m = np.zeros(self.N + 1)
        m[:-1] += 0.5 * ms
        m[1:] += 0.5 * ms
        return m
