"""The numbers the generated assembly reads: global, per-element and load arrays.

:class:`RodArrays` holds, for a rod of N elements, the arrays whose layout
``generated/rod_layout.py`` defines (the one source of every layout):

* ``par`` (N_PARAMS,): load factor, gravity, distributed load, the ends (held, clamped,
  prescribed position/velocity/frame/angular velocity, the moments applied at them);
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
from runtime.model.contact import ContactArrays


class RodStruct(ctypes.Structure):
    """``kvrod_rod`` of runtime/model/native/rod_assembly.h."""

    _fields_ = [("N", ctypes.c_int), ("nb", ctypes.c_int), ("kl", ctypes.c_int),
                ("ku", ctypes.c_int), ("par", ctypes.c_void_p), ("seg", ctypes.c_void_p),
                ("jnt", ctypes.c_void_p), ("nload", ctypes.c_void_p),
                ("sload", ctypes.c_void_p), ("theta", ctypes.c_void_p),
                ("segb", ctypes.c_void_p), ("jntb", ctypes.c_void_p),
                ("coupled", ctypes.c_int), ("segc", ctypes.c_void_p),
                ("jntc", ctypes.c_void_p), ("contact", ctypes.c_void_p),
                ("relax_need", ctypes.c_void_p)]


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
    segc: np.ndarray | None = None
    jntc: np.ndarray | None = None
    #: the rigid obstacles the rod touches (runtime.model.contact; None: none)
    contact: ContactArrays | None = None

    @classmethod
    def zeros(cls, n_elements: int, branches: int = 0, coupled: bool = False) -> RodArrays:
        N, B = int(n_elements), int(branches)
        if coupled and B:
            raise ValueError("coupled sections with relaxation terms are not supported")
        return cls(N=N, par=np.zeros(L.N_PARAMS), seg=np.zeros((N, L.N_SEGMENT)),
                   jnt=np.zeros((N + 1, L.N_JOINT)), nload=np.zeros((N + 1, L.N_NODE_LOAD)),
                   sload=np.zeros((N, L.N_SEGMENT_LOAD)), theta=np.ones(B),
                   segb=np.zeros((N, B, 3)), jntb=np.zeros((N + 1, B, 3)),
                   segc=np.zeros((N, L.N_COUPLED_SEGMENT)) if coupled else None,
                   jntc=np.zeros((N + 1, L.N_COUPLED_JOINT)) if coupled else None)

    @property
    def coupled(self) -> bool:
        """A rod with coupled sections (``segc``, ``jntc``: full 6x6 stiffness and
        viscosity, mass centre, product of inertia; docs/design.md, section 10)."""
        return self.segc is not None

    @property
    def branches(self) -> int:
        """Number B of relaxation terms (0: Kelvin-Voigt)."""
        return int(self.theta.size)

    def copy(self) -> RodArrays:
        return RodArrays(self.N, self.par.copy(), self.seg.copy(), self.jnt.copy(),
                         self.nload.copy(), self.sload.copy(), self.theta.copy(),
                         self.segb.copy(), self.jntb.copy(),
                         None if self.segc is None else self.segc.copy(),
                         None if self.jntc is None else self.jntc.copy(),
                         None if self.contact is None else self.contact.copy())

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

    def segc_field(self, name: str) -> np.ndarray:
        """View (N, size) of a coupled segment parameter (a coupled rod only)."""
        return _view(self.segc, L.COUPLED_SEGMENT_OFFSETS, L.COUPLED_SEGMENT_PARAMS, name)

    def jntc_field(self, name: str) -> np.ndarray:
        """View (N+1, size) of a coupled joint parameter (a coupled rod only)."""
        return _view(self.jntc, L.COUPLED_JOINT_OFFSETS, L.COUPLED_JOINT_PARAMS, name)

    def section_matrices(self) -> dict[str, np.ndarray]:
        """The full matrices of the rod whether coupled or not: per segment ``C_FF``,
        ``V_FF``, ``C_FM``, ``V_FM`` (N, 3, 3), per joint ``C_MM``, ``V_MM`` (N+1, 3, 3)
        (a diagonal rod: its diagonals, zero couplings)."""
        N = self.N
        if self.coupled:
            out = {k: self.segc_field(k).reshape(N, 3, 3) for k in ("C_FF", "V_FF", "C_FM",
                                                                  "V_FM")}
            out.update({k: self.jntc_field(k).reshape(N + 1, 3, 3) for k in ("C_MM", "V_MM")})
            return {k: v.copy() for k, v in out.items()}
        diag = lambda d: d[:, :, None] * np.eye(3)  # noqa: E731
        return {"C_FF": diag(self.seg_field("C_F")), "V_FF": diag(self.seg_field("V_F")),
                "C_FM": np.zeros((N, 3, 3)), "V_FM": np.zeros((N, 3, 3)),
                "C_MM": diag(self.jnt_field("C_M")), "V_MM": diag(self.jnt_field("V_M"))}

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
        names = ("par", "seg", "jnt", "nload", "sload", "theta", "segb", "jntb")
        for name in names + (("segc", "jntc") if self.coupled else ()):
            a = getattr(self, name)
            if not (a.dtype == np.float64 and a.flags.c_contiguous):
                raise TypeError(f"RodArrays.{name} must be C-contiguous float64")
        B = self.branches
        if self.segb.shape != (self.N, B, 3) or self.jntb.shape != (self.N + 1, B, 3):
            raise ValueError(f"relaxation moduli of shapes {self.segb.shape}, "
                             f"{self.jntb.shape}; expected {(self.N, B, 3)}, "
                             f"{(self.N + 1, B, 3)}")
        c = self.coupled
        if c and (self.segc.shape != (self.N, L.N_COUPLED_SEGMENT)
                  or self.jntc.shape != (self.N + 1, L.N_COUPLED_JOINT)):
            raise ValueError(f"coupled parameters of shapes {self.segc.shape}, "
                             f"{self.jntc.shape}")
        bkl, bku = L.bandwidths(self.N, B, c)
        return RodStruct(self.N, B, bkl if kl is None else kl, bku if ku is None else ku,
                         self.par.ctypes.data, self.seg.ctypes.data,
                         self.jnt.ctypes.data, self.nload.ctypes.data, self.sload.ctypes.data,
                         self.theta.ctypes.data, self.segb.ctypes.data, self.jntb.ctypes.data,
                         int(c), self.segc.ctypes.data if c else None,
                         self.jntc.ctypes.data if c else None,
                         None if self.contact is None else self.contact.struct_address)

    def node_masses(self) -> np.ndarray:
        """Lumped node masses (N+1,) in kg: half of each adjacent segment's rho A h."""
        ms = self.seg_field("rhoA")[:, 0] * self.seg_field("h")[:, 0]
        m = np.zeros(self.N + 1)
        m[:-1] += 0.5 * ms
        m[1:] += 0.5 * ms
        return m


def _positive_sides(F: np.ndarray, B: np.ndarray, M: np.ndarray, strict: bool) -> bool:
    """Whether the 6x6 ``[[F, B], [B^T, M]]`` is positive definite (``strict``) or semi-
    definite to round-off: the form a segment holds with one of its joints."""
    S = np.block([[F, B], [B.T, M]])
    S = 0.5 * (S + S.T)
    w = np.linalg.eigvalsh(S)
    tol = 1e-12 * max(float(np.max(np.abs(w))), 1e-300)
    return bool(w[0] > tol) if strict else bool(w[0] >= -tol)


def coupled_joint_series(stiffness: np.ndarray, viscosity: np.ndarray,
                         h: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Joint blocks C_MM, V_MM (N+1, 3, 3) of a rod with coupled sections from its
    segments' 6x6 matrices (N, 6, 6) and lengths h (N,): the two half cells in series
    (``runtime.problem.materials.joint_series`` in matrix form:
    ``h_j C_j^-1 = w_a C_a^-1 + w_b C_b^-1``,
    ``h_j C_j^-1 V_j C_j^-1 = w_a C_a^-1 V_a C_a^-1 + w_b C_b^-1 V_b C_b^-1``, w = h/2),
    equal neighbours their own blocks, the ends the end segment's.

    Where a neighbour has force-moment couplings (C_FM or V_FM), the joint keeps the
    length-weighted mean: in series, the coupling's moment C_FM^T dG of that half cell
    would need the weight ``C_j C_a^-1 w_a / h_j`` instead of the kernels' scalar w/h_j
    (each half's curvature is ``C_a^-1 (m - C_FM^T dG)``); with the scalar weight the
    series block doubles the curvature that the coupling drives in the joint (a coupled
    clip's total twist went from 0.5 to 1 element's worth of error). A change between
    coupled sections therefore stays first order at the joint (docs/design.md, 10).

    Positive definiteness (docs/design.md, section 10): segment i's share of the energy is
    ``h/4 ([dG; U_a]^T K_a [dG; U_a] + [dG; U_b]^T K_b [dG; U_b])`` with
    ``K_x = [[C_FF, C_FM], [C_FM^T, C_x]]``, C_x its joint's block; the series block is
    softer than the mean, so next to a strongly coupled segment K_x could lose
    definiteness. Such a joint keeps the length-weighted mean, whose split gives each
    segment its own C_MM (positive by the section's K); the same for V (semi-definite)."""
    K = np.asarray(stiffness, dtype=float)
    V = np.asarray(viscosity, dtype=float)
    h = np.asarray(h, dtype=float).reshape(-1)
    N = K.shape[0]
    CMM, VMM = K[:, 3:, 3:], V[:, 3:, 3:]
    jC, jV = np.empty((N + 1, 3, 3)), np.empty((N + 1, 3, 3))
    jC[0], jC[-1], jV[0], jV[-1] = CMM[0], CMM[-1], VMM[0], VMM[-1]
    for j in range(1, N):
        a, b = j - 1, j
        wa, wb = 0.5 * h[a], 0.5 * h[b]
        hj = wa + wb
        mean_C = (h[a] * CMM[a] + h[b] * CMM[b]) / (h[a] + h[b])
        mean_V = (h[a] * VMM[a] + h[b] * VMM[b]) / (h[a] + h[b])
        if np.array_equal(K[a], K[b]) and np.array_equal(V[a], V[b]):
            jC[j], jV[j] = mean_C, mean_V       # equal neighbours (to round-off, as before)
            continue
        Fa, Fb = np.linalg.inv(CMM[a]), np.linalg.inv(CMM[b])
        Cs = hj * np.linalg.inv(wa * Fa + wb * Fb)
        Cs = 0.5 * (Cs + Cs.T)
        Vs = Cs @ (wa * Fa @ VMM[a] @ Fa + wb * Fb @ VMM[b] @ Fb) @ Cs / hj
        Vs = 0.5 * (Vs + Vs.T)
        uncoupled = not (np.any(K[a, :3, 3:]) or np.any(K[b, :3, 3:])
                         or np.any(V[a, :3, 3:]) or np.any(V[b, :3, 3:]))
        ok_C = uncoupled and all(_positive_sides(K[k, :3, :3], K[k, :3, 3:], Cs, True)
                                 for k in (a, b))
        ok_V = uncoupled and all(_positive_sides(V[k, :3, :3], V[k, :3, 3:], Vs, False)
                                 for k in (a, b))
        jC[j] = Cs if ok_C else mean_C
        jV[j] = Vs if ok_V else mean_V
    return jC, jV


def coupled_arrays(base: RodArrays, stiffness: np.ndarray, viscosity: np.ndarray,
                   rotary_inertia: np.ndarray | None = None,
                   mass_centre: np.ndarray | None = None) -> RodArrays:
    """A rod with coupled sections: ``base`` (lengths, reference strains, masses, loads and
    ends already set) with the per-segment 6x6 matrices (docs/design.md, section 10).

    stiffness, viscosity: (N, 6, 6) in the strain order (Gamma1, Gamma2, Gamma3, K1, K2, K3)
    about the centreline (N, N m, N m^2 and N s, ...), symmetric (checked by the callers;
    symmetrised here to round-off); rotary_inertia: (N, 3, 3) rho times the section's
    inertia about its mass centre per length (kg m; default: ``diag(rhoI)`` of ``base``);
    mass_centre: (N, 2) in the material frame (m; default 0).

    Segments carry C_FF, V_FF and the coupling blocks C_FM, V_FM, with the weights h/2 of
    their couplings with the two joints (0 where a joint is absent: a free end, where
    C_FF, V_FF take the free end's condensation ``- 1/2 C_FM C_MM^-1 C_FM^T``, and V with
    the pseudo-inverse, and ``C_FE = 1/2 C_FM C_MM^-1`` carries the moment applied
    there into the resultant; the viscous condensation carries none); joints their
    segments' C_MM, V_MM in series (``coupled_joint_series``; the end segment's at a
    clamp). ``base``'s diagonal fields C_F, V_F, C_M, V_M, rhoI receive the diagonals
    (read by what reports on them; the kernels of a coupled rod read the coupled tables
    only).
    """
    N = base.N
    if base.branches:
        raise ValueError("coupled sections with relaxation terms are not supported")
    K = np.asarray(stiffness, dtype=float).reshape(N, 6, 6)
    V = np.asarray(viscosity, dtype=float).reshape(N, 6, 6)
    K = 0.5 * (K + K.transpose(0, 2, 1))
    V = 0.5 * (V + V.transpose(0, 2, 1))
    a = RodArrays(N, base.par.copy(), base.seg.copy(), base.jnt.copy(), base.nload.copy(),
                  base.sload.copy(), base.theta.copy(), base.segb.copy(), base.jntb.copy(),
                  np.zeros((N, L.N_COUPLED_SEGMENT)), np.zeros((N + 1, L.N_COUPLED_JOINT)))
    h = a.seg_field("h")[:, 0]
    if rotary_inertia is None:
        J = a.seg_field("rhoI")[:, :, None] * np.eye(3)
    else:
        J = np.asarray(rotary_inertia, dtype=float).reshape(N, 3, 3)
    e = np.zeros((N, 3))
    if mass_centre is not None:
        e[:, :2] = np.asarray(mass_centre, dtype=float).reshape(N, 2)
    CFF, VFF = K[:, :3, :3].copy(), V[:, :3, :3].copy()
    CFM, VFM = K[:, :3, 3:], V[:, :3, 3:]
    CMM, VMM = K[:, 3:, 3:], V[:, 3:, 3:]
    w = np.tile(0.5 * h[:, None], (1, 2))
    CFE = np.zeros((N, 3, 3))
    for end, seg, col in (("start", 0, 0), ("end", N - 1, 1)):
        if not a.clamped(end):        # no joint beyond the end segment: its condensation
            w[seg, col] = 0.0
            CFF[seg] -= 0.5 * CFM[seg] @ np.linalg.solve(CMM[seg], CFM[seg].T)
            VFF[seg] -= 0.5 * VFM[seg] @ np.linalg.pinv(VMM[seg], hermitian=True) @ VFM[seg].T
            CFE[seg] = 0.5 * np.linalg.solve(CMM[seg], CFM[seg].T).T   # C_MM symmetric
    for name, val in (("C_FF", CFF), ("V_FF", VFF), ("C_FM", CFM), ("V_FM", VFM),
                      ("rhoJ", J), ("C_FE", CFE)):
        a.segc_field(name)[:] = val.reshape(N, 9)
    a.segc_field("w")[:] = w
    a.segc_field("e")[:] = e
    jC, jV = coupled_joint_series(K, V, h)
    a.jntc_field("C_MM")[:] = jC.reshape(N + 1, 9)
    a.jntc_field("V_MM")[:] = jV.reshape(N + 1, 9)
    d = lambda M: np.diagonal(M, axis1=1, axis2=2)  # noqa: E731
    a.seg_field("C_F")[:], a.seg_field("V_F")[:] = d(K[:, :3, :3]), d(V[:, :3, :3])
    a.seg_field("rhoI")[:] = d(J)
    a.jnt_field("C_M")[:] = d(a.jntc_field("C_MM").reshape(N + 1, 3, 3))
    a.jnt_field("V_M")[:] = d(a.jntc_field("V_MM").reshape(N + 1, 3, 3))
    return a
