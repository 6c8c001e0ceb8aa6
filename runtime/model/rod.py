"""The discrete Cosserat rod in IDA form on the generated assembly.

:class:`RodModel` is what the integrator and the analyses see: the residual
``F(t, y, y') = 0`` of the discrete rod (``derive/discrete_rod.py``; layout in
``generated/rod_layout.py``), its banded iteration matrix ``cy dF/dy + cj dF/dy'`` in
LAPACK band storage, energies and powers, strains and stress resultants. It evaluates
the compiled C assembly through ctypes (``runtime.model.build``) or, without a C
compiler, the CasADi MX assembly (``runtime.model.casadi_rod``) with the same numbers
up to rounding. The rod's numbers live in a ``runtime.model.arrays.RodArrays``;
a :class:`Drive` (loads with time functions, moving ends) updates them when the time or
the load factor changes, so the model knows nothing about any particular problem.
"""

from __future__ import annotations

import contextlib
import math
from collections.abc import Iterator
from typing import TYPE_CHECKING, Protocol

import numpy as np

if TYPE_CHECKING:
    import scipy.sparse as sp

from generated import rod_layout as L
from runtime.errors import GeneratedCodeError, ParameterError
from runtime.model import build
from runtime.model.arrays import RodArrays
from runtime.model.quaternion import quat_rotation


class Drive(Protocol):
    """What changes the rod's arrays with time: loads with time functions, moving ends.

    ``apply(arrays, t, left, scale)`` writes the values at time ``t`` (``left``: the limit
    from the left, for statics at ``t = 0-``) into ``arrays``; ``scale`` is the load
    factor, which also scales prescribed end displacements and rotations in statics;
    ``static``: velocities of the ends are zero (statics). ``time_dependent``: False when
    the values never change with t (then :meth:`apply` runs once).
    """

    time_dependent: bool

    def apply(self, arrays: RodArrays, t: float, *, left: bool = False, scale: float = 1.0,
              static: bool = False) -> None:
        ...


def _ptr(a: np.ndarray, n: int, fortran: bool = False) -> int:
    """Data address of a contiguous (C, or Fortran if asked) float64 array of size >= n."""
    ok = isinstance(a, np.ndarray) and a.dtype == np.float64 and a.size >= n and (
        a.flags.f_contiguous if fortran else a.flags.c_contiguous)
    if not ok:
        order = "Fortran" if fortran else "C"
        raise TypeError(f"expected a {order}-contiguous float64 numpy array of size >= {n}")
    return a.ctypes.data


class _PointerCache:
    """Data addresses of the last few arrays seen (``ndarray.ctypes.data`` costs ~3 us).

    Holding a reference keeps an array alive and its buffer fixed (numpy refuses to
    resize referenced arrays), so an identity hit always returns the right address.
    """

    def __init__(self, size: int = 8) -> None:
        self._arrays: list[np.ndarray] = []
        self._ptrs: list[int] = []
        self._size = size

    def __call__(self, a: np.ndarray, n: int, fortran: bool = False) -> int:
        for k, b in enumerate(self._arrays):
            if b is a:
                return self._ptrs[k]
        ptr = _ptr(a, n, fortran)
        self._arrays.insert(0, a)
        self._ptrs.insert(0, ptr)
        del self._arrays[self._size:], self._ptrs[self._size:]
        return ptr


class RodModel:
    """Discrete Kelvin-Voigt Cosserat rod in IDA form (see the module docstring).

    arrays: the rod's numbers (owned by the model from now on; edit in place only);
    reference: the reference configuration as a state (n,) (node positions and segment
    quaternions of the stress-free rod, at rest); drive: time-dependent loads and end
    motion (None: constant); backend: "auto", "c" or "casadi".
    """

    def __init__(self, arrays: RodArrays, reference: np.ndarray, drive: Drive | None = None,
                 backend: str = "auto") -> None:

        if backend not in ("auto", "c", "casadi"):
            raise ParameterError("backend", backend, "'auto', 'c' or 'casadi'")
        N = self.N = arrays.N
        if N < 1:
            raise ParameterError("n_elements", N, "integer >= 1")
        self.arrays = arrays
        self.branches = B = arrays.branches
        self.n = L.n_state(N, B)
        self.reference = np.array(reference, dtype=float)
        if self.reference.shape != (self.n,):
            raise ValueError(f"reference state has shape {self.reference.shape}, "
                             f"expected ({self.n},)")
        self.kl, self.ku = L.bandwidths(N, B)
        self.ldab = 2 * self.kl + self.ku + 1
        self.drive = drive
        self._key: tuple = ()       # (time, statics?, load factor) the arrays were driven to
        self._steady = (0.0, 0.0)   # times on which those arrays hold (empty: none known)
        self._static = False
        build.require_generated()
        lib = None if backend == "casadi" else build.load_library()
        if backend == "c" and lib is None:
            raise GeneratedCodeError("compiled backend requested but no library could be "
                                     "built (see the warning above)")
        self._lib = lib
        self._struct = arrays.struct(self.kl, self.ku)
        self._sp = None
        self._casadi = None
        if lib is None:
            from runtime.model.casadi_rod import CasadiRod

            self._casadi = CasadiRod(arrays)
        self._ptrs = _PointerCache()
        self._zeros = np.zeros(self.n)
        self._ab = np.zeros((self.ldab, self.n), order="F")
        self._diag = np.zeros(L.diagnostics_size(N))
        self._energy = np.zeros(len(L.DIAG_SCALARS))
        nodes, segs = np.arange(N + 1), np.arange(1, N + 1)
        self.phi_index = np.array([L.node_phi(i, B) for i in nodes])[:, None] + np.arange(3)
        self.v_index = np.array([L.node_v(i, B) for i in nodes])[:, None] + np.arange(3)
        self.p_index = np.array([L.segment_p(i, B) for i in segs])[:, None] + np.arange(4)
        self.omega_index = (np.array([L.segment_omega(i, B) for i in segs])[:, None]
                            + np.arange(3))
        #: state indices of the internal strains of the relaxation terms, (N, B, 3) and (N+1, B, 3)
        self.q_segment_index = (np.array([L.segment_q(i, B) for i in segs], dtype=int)
                                .reshape(N, 1, 1) + np.arange(3 * B).reshape(1, B, 3))
        self.q_joint_index = (np.array([L.joint_q(j, B) for j in nodes], dtype=int)
                              .reshape(N + 1, 1, 1) + np.arange(3 * B).reshape(1, B, 3))
        self.velocity_mask = np.zeros(self.n, dtype=bool)
        self.velocity_mask[self.v_index.ravel()] = True
        self.velocity_mask[self.omega_index.ravel()] = True
        self.differential = np.ones(self.n, dtype=bool)
        for end, i in (("start", 0), ("end", N)):
            if arrays.held(end):     # the velocity is prescribed (algebraic row)
                self.differential[self.v_index[i]] = False
        self._pattern: sp.csc_matrix | None = None
        self._band_pattern: np.ndarray | None = None
        self._pattern_flat = np.zeros(0, dtype=np.intp)
        self.at(0.0)

    # -- time, loads, ends --------------------------------------------------------------
    @property
    def load_scale(self) -> float:
        """Factor on all external loads and, in statics, on prescribed end motion."""
        return float(self.arrays.param("load_scale")[0])

    @load_scale.setter
    def load_scale(self, value: float) -> None:
        if not math.isfinite(value):
            raise ParameterError("load_scale", value, "finite")
        self.arrays.set_param("load_scale", value)

    def at(self, t: float) -> None:
        """Drive the arrays to time ``t`` (in statics: to ``t-`` with the ends at rest);
        no-op when nothing changed since the last call."""
        if self.drive is None:
            return
        lo, hi = self._steady
        if self.drive.time_dependent and not self._static and lo <= t < hi:
            tk = self._key[0] if self._key else None   # arrays of an earlier t still hold
        else:
            tk = t if self.drive.time_dependent else None
        key = (tk, self._static, self.load_scale)
        if key != self._key:
            self.drive.apply(self.arrays, t, left=self._static, scale=self.load_scale,
                             static=self._static)
            self._key = key
            self._steady = ((-math.inf, -math.inf) if self._static or not
                            self.drive.time_dependent else self.drive.steady_interval(t))

    def _steady_for(self, ts: np.ndarray) -> bool:
        """Drive the arrays to ``ts[0]`` and say whether they hold for every time of ``ts``
        (the interval cached by :meth:`at` first: this runs for every step)."""
        t0 = float(ts[0])
        self._time(t0)
        if self.drive is None or not self.drive.time_dependent:
            return True
        lo, hi = self._steady
        t_lo, t_hi = (t0, t0) if ts.size == 1 else (float(ts.min()), float(ts.max()))
        if lo <= t_lo and t_hi < hi:
            return True
        return self.steady_over(t_lo, t_hi)

    def steady_over(self, t0: float, t1: float) -> bool:
        """True when the loads and end motion are constant on [t0, t1] (so one set of
        arrays serves every time in it)."""
        if self.drive is None or not self.drive.time_dependent:
            return True
        lo, hi = self.drive.steady_interval(t0)
        return lo <= t0 and t1 < hi

    _time = at

    @contextlib.contextmanager
    def statics(self, t: float = 0.0, relaxed: bool = True) -> Iterator[None]:
        """Within this block the rod is driven as in statics: loads at ``t-`` (their limit
        from the left, e.g. a load released at t = 0 is on), ends at rest, prescribed end
        displacements and rotations scaled by the load factor. A generalized Maxwell rod
        is in its relaxed state: a load held long enough has let every relaxation term
        relax (q_b = strain), so statics sees the equilibrium stiffness C_inf (the
        instantaneous C_F minus the terms' moduli, which are set to zero meanwhile);
        ``relaxed=False`` keeps the terms (linearised dynamics about a static state)."""
        previous = self._static
        self._static = True
        self._key = ()
        a = self.arrays
        saved = None
        if self.branches and relaxed and not previous:
            saved = (a.seg_field("C_F").copy(), a.jnt_field("C_M").copy(), a.segb.copy(),
                     a.jntb.copy())
            a.seg_field("C_F")[:] -= a.segb.sum(axis=1)
            a.jnt_field("C_M")[:] -= a.jntb.sum(axis=1)
            a.segb[:] = 0.0
            a.jntb[:] = 0.0
        try:
            self.at(t)
            yield
        finally:
            if saved is not None:
                a.seg_field("C_F")[:], a.jnt_field("C_M")[:] = saved[0], saved[1]
                a.segb[:], a.jntb[:] = saved[2], saved[3]
            self._static = previous
            self._key = ()

    def relaxed(self, y: np.ndarray, t: float = 0.0) -> np.ndarray:
        """y with every relaxation term relaxed to its element's strain (q_b = V - V0 on
        segments, U - U0 on joints; absent clamp joints keep 0): the state after a load
        held long enough (a copy; y itself for a Kelvin-Voigt rod)."""
        if not self.branches:
            return y
        y = np.array(y, dtype=float)
        d = self.diagnostics(t, y)
        a = self.arrays
        dV = (d["strains"]["V"].T - a.seg_field("V0"))[:, None, :]
        active = np.ones(self.N + 1, dtype=bool)     # joints 0 and N exist at a clamp only
        active[0], active[-1] = a.clamped("start"), a.clamped("end")
        dU = np.where(active[:, None], d["strains"]["U"].T - a.jnt_field("U0"), 0.0)
        y[self.q_segment_index] = np.broadcast_to(dV, self.q_segment_index.shape)
        y[self.q_joint_index] = np.broadcast_to(dU[:, None, :], self.q_joint_index.shape)
        return y

    # -- states -------------------------------------------------------------------------
    def initial_state(self, t: float = 0.0) -> np.ndarray:
        """The reference configuration at rest, with held nodes at their targets at t."""
        self.at(t)
        y = self.reference.copy()
        return self.constrain(y)

    def constrain(self, y: np.ndarray) -> np.ndarray:
        """y with the held nodes at their prescribed positions and velocities (copy)."""
        y = np.array(y, dtype=float)
        a = self.arrays
        for end, i in (("start", 0), ("end", self.N)):
            if a.held(end):
                y[self.phi_index[i]] = a.param("r_" + end)
                y[self.v_index[i]] = a.param("v_" + end)
        return y

    def positions(self, y: np.ndarray) -> np.ndarray:
        """Node positions phi (3, N+1) in m."""
        return y[self.phi_index].T.copy()

    def quaternions(self, y: np.ndarray) -> np.ndarray:
        """Segment quaternions p (4, N), scalar part first."""
        return y[self.p_index].T.copy()

    def frames(self, y: np.ndarray) -> np.ndarray:
        """Director frames R(p) (N, 3, 3): columns d1, d2, d3 of each segment."""
        return quat_rotation(y[self.p_index])

    def tip_position(self, y: np.ndarray) -> np.ndarray:
        """Position of node N, the s = L end (3,) in m."""
        return y[self.phi_index[-1]].copy()

    def start_position(self, y: np.ndarray) -> np.ndarray:
        """Position of node 0, the s = 0 end (3,) in m."""
        return y[self.phi_index[0]].copy()

    def condensation_blocks(self) -> list[tuple[int, int, int, int, int]]:
        """The kinematic blocks a Newton solve may eliminate (``runtime.solvers._bdf_c.
        CondensedNewton``): per node, the rows phi' = v eliminate v (kept: phi); per
        segment, the rows p' = 1/2 p*(0, Omega) eliminate p (kept: Omega). Each as
        ``(e_off, e_size, r_off, k_off, k_size)`` of contiguous state ranges."""
        blocks = []
        for i in range(self.N + 1):
            phi, v = self.phi_index[i], self.v_index[i]
            blocks.append((int(v[0]), 3, int(phi[0]), int(phi[0]), 3))
        for i in range(self.N):
            p, om = self.p_index[i], self.omega_index[i]
            blocks.append((int(p[0]), 4, int(p[0]), int(om[0]), 3))
        for e0, es, r0, k0, ks in blocks:    # the layout keeps each field contiguous
            assert e0 >= 0 and r0 >= 0 and k0 >= 0 and es <= 4 and ks <= 4
        return blocks

    def condensation_cells(self) -> list[int]:
        """First state index of each cell of the layout (cell 0: node 0 and joint 0; cell
        i: segment i, node i, joint i). Couplings are nearest-neighbour, so the Newton
        systems condensed by :meth:`condensation_blocks` are block tridiagonal in these
        cells (``CondensedNewton`` checks it on :meth:`band_pattern`)."""
        return [0] + [int(self.p_index[i][0]) for i in range(self.N)]

    def describe_dof(self, index: int) -> str:
        """Human-readable name of state/residual component ``index``."""
        return L.describe_index(self.N, index, self.branches)

    # -- IDA residual and Jacobian ------------------------------------------------------
    @property
    def backend(self) -> str:
        """'c' (compiled, ctypes) or 'casadi' (in-process fallback)."""
        return "c" if self._lib is not None else "casadi"

    def _cargs(self, t, y, yp) -> list:
        return [t, y, yp, *self._casadi.args(self.arrays)]

    def residual(self, t: float, y: np.ndarray, yp: np.ndarray, out: np.ndarray) -> None:
        """out <- F(t, y, y') (n,)."""
        self._time(t)
        if self._lib is not None:
            n = self.n
            P = self._ptrs
            rc = self._lib.kvrod_residual(self._struct_ptr(), t, P(y, n), P(yp, n), P(out, n))
            if rc:
                raise GeneratedCodeError(f"kvrod_residual failed (code {rc})")
        else:
            out[:] = np.asarray(self._casadi.residual(*self._cargs(t, y, yp))).ravel()

    def c_kernels(self):
        """The compiled residual, Jacobian and energies for the C step loop
        (:class:`runtime.solvers.protocols.CKernels`), with the drive as a callback that
        reports the interval on which the loads stay constant; None on the CasADi
        backend."""
        if self._lib is None:
            return None
        import ctypes

        from runtime.solvers.protocols import CKernels

        def address(fn) -> int:
            return ctypes.cast(fn, ctypes.c_void_p).value

        drive = None
        if self.drive is not None:
            def drive(t: float) -> tuple[float, float]:
                self.at(t)
                if not self.drive.time_dependent:
                    return -math.inf, math.inf
                return self._steady

        lib = self._lib
        return CKernels(address(lib.kvrod_residual), address(lib.kvrod_jacobian_band),
                        address(lib.kvrod_energies), ctypes.addressof(self._struct),
                        drive=drive, keep=self,
                        jacobian_cells=address(lib.kvrod_jacobian_band_cells),
                        drive_constant=drive is not None and not self.drive.time_dependent)

    def _struct_ptr(self):
        import ctypes

        if self._sp is None:
            self._sp = ctypes.byref(self._struct)
        return self._sp

    def jacobian_band2(self, t: float, y: np.ndarray, yp: np.ndarray, cy: float, cj: float,
                       out_ab: np.ndarray) -> None:
        """out_ab <- cy dF/dy + cj dF/dy' in LAPACK band storage (2 kl + ku + 1, n), 'F'."""
        self._time(t)
        if out_ab.shape != (self.ldab, self.n) or not out_ab.flags.f_contiguous:
            raise TypeError(f"out_ab must be a Fortran-ordered array of shape "
                            f"{(self.ldab, self.n)}")
        if self._lib is not None:
            n = self.n
            P = self._ptrs
            rc = self._lib.kvrod_jacobian_band(self._struct_ptr(), t, P(y, n), P(yp, n), cy, cj,
                                               self.ldab, P(out_ab, self.ldab * n, True))
            if rc:
                raise GeneratedCodeError(f"kvrod_jacobian_band failed (code {rc})")
        else:
            import scipy.sparse as sp  # on use: it costs 0.15 s of import

            J = sp.csc_matrix(self._casadi.jacobian(*self._cargs(t, y, yp), cy, cj))
            out_ab[self.kl:] = 0.0
            c = J.tocoo()
            np.add.at(out_ab, (self.kl + self.ku + c.row - c.col, c.col), c.data)

    def jacobian_band(self, t: float, y: np.ndarray, yp: np.ndarray, cj: float,
                      out_ab: np.ndarray) -> None:
        """out_ab <- dF/dy + cj dF/dy' in LAPACK band storage (the integrator's matrix)."""
        self.jacobian_band2(t, y, yp, 1.0, cj, out_ab)

    def band_to_csc(self, ab: np.ndarray, kl: int, ku: int) -> sp.csc_matrix:
        """The matrix held in rows kl: of LAPACK band storage, as CSC (zeros dropped)."""
        import scipy.sparse as sp

        n = ab.shape[1]
        offsets = ku - np.arange(kl + ku + 1)
        m = sp.dia_matrix((ab[kl:], offsets), shape=(n, n)).tocsc()
        m.eliminate_zeros()
        return m

    def band_pattern(self) -> np.ndarray:
        """Structural pattern of dF/dy + c dF/dy' in LAPACK band storage ((ldab, n) bool,
        Fortran order; rows 0..kl-1, the LU's fill-in room, False), fixed for this model.

        Found by evaluating the banded Jacobian at two random states (loads with follower
        parts present keep their entries), so no entry vanishes by accident. No SciPy
        (unlike :meth:`sparsity`): the integrator's setup uses it.
        """
        if self._band_pattern is None:
            rng = np.random.default_rng(12345)
            acc = np.zeros((self.ldab, self.n), order="F")
            ab = np.zeros((self.ldab, self.n), order="F")
            saved = self.arrays.copy()
            driven = (self._key, self._steady)   # what the restored arrays hold
            a = self.arrays
            for name in ("f_follower",):
                a.node_load(name)[:] = rng.uniform(0.5, 1.5, a.node_load(name).shape)
            for name in ("m_dead",):
                a.segment_load(name)[:] = rng.uniform(0.5, 1.5, a.segment_load(name).shape)
            a.set_param("load_scale", 1.0)
            try:
                for _ in range(2):
                    y = self.reference + 0.1 * rng.standard_normal(self.n)
                    self.jacobian_band2(0.0, y, rng.standard_normal(self.n), 1.0, 1.0, ab)
                    acc[self.kl:] += np.abs(ab[self.kl:])
            finally:
                for name in ("par", "seg", "jnt", "nload", "sload"):
                    getattr(a, name)[...] = getattr(saved, name)
                self._key, self._steady = driven
            self._band_pattern = acc != 0.0
        return self._band_pattern.copy(order="F")

    def sparsity(self) -> sp.csc_matrix:
        """Structural pattern of dF/dy + c dF/dy' (CSC of ones), fixed for this model
        (that of :meth:`band_pattern`)."""
        if self._pattern is None:
            m = self.band_to_csc(self.band_pattern().astype(float), self.kl, self.ku)
            m.sort_indices()
            m.data[:] = 1.0
            cols = np.repeat(np.arange(self.n), np.diff(m.indptr))
            self._pattern = m
            self._pattern_flat = (self.kl + self.ku + m.indices - cols) + cols * self.ldab
        return self._pattern.copy()

    def _sparse(self, t, y, yp, cy, cj) -> sp.csc_matrix:
        pat = self.sparsity()
        ab = self._ab
        self.jacobian_band2(t, y, yp, cy, cj, ab)
        pat.data = ab.ravel(order="F")[self._pattern_flat].copy()
        return pat

    def jacobian_sparse(self, t: float, y: np.ndarray, yp: np.ndarray,
                        cj: float) -> sp.csc_matrix:
        """dF/dy + cj dF/dy' as CSC with the fixed pattern of :meth:`sparsity`."""

        return self._sparse(t, y, yp, 1.0, cj)

    def dF_dy_sparse(self, t: float, y: np.ndarray, yp: np.ndarray) -> sp.csc_matrix:
        """dF/dy (CSC, fixed pattern of :meth:`sparsity`)."""
        return self._sparse(t, y, yp, 1.0, 0.0)

    def dF_dyp_sparse(self, t: float, y: np.ndarray, yp: np.ndarray) -> sp.csc_matrix:
        """dF/dy' (CSC, fixed pattern of :meth:`sparsity`)."""
        return self._sparse(t, y, yp, 0.0, 1.0)

    # -- energies and diagnostics -------------------------------------------------------
    def energy_scalars(self, t: float, y: np.ndarray, yp: np.ndarray | None = None
                       ) -> tuple[float, float, float, float, float]:
        """(T, W, 2D, P_ext, P_bc) of a state in J, J, W, W, W: kinetic and elastic
        energy, dissipation rate, power of the external loads and of prescribed end
        motion (the balance is d/dt (T + W) = -2D + P_ext + P_bc)."""
        self._time(t)
        yp_ = self._zeros if yp is None else yp
        if self._lib is not None:
            out = self._energy
            n = self.n
            P = self._ptrs
            tt = np.array([t])
            rc = self._lib.kvrod_energies(self._struct_ptr(), 1, tt.ctypes.data, P(y, n),
                                          P(yp_, n), out.ctypes.data)
            if rc:
                raise GeneratedCodeError(f"kvrod_energies failed (code {rc})")
            return tuple(float(v) for v in out)
        vals = self._casadi.energies(*self._cargs(t, y, yp_))
        return tuple(float(v) for v in vals)

    def energies(self, ts: np.ndarray, ys: np.ndarray, yps: np.ndarray) -> np.ndarray:
        """(m, 5) energies and powers of m states (rows of ``ys``, ``yps``) in one call
        (the per-step energy quadrature). Loads must not depend on time within ``ts``
        beyond what :meth:`at` of each time gives; time-dependent problems evaluate per
        state."""
        ys = np.ascontiguousarray(ys, dtype=float)
        yps = np.ascontiguousarray(yps, dtype=float)
        ts = np.ascontiguousarray(ts, dtype=float)
        m = ys.shape[0]
        out = np.empty((m, len(L.DIAG_SCALARS)))
        if self._lib is not None and self._steady_for(ts):
            rc = self._lib.kvrod_energies(self._struct_ptr(), m, ts.ctypes.data, ys.ctypes.data,
                                          yps.ctypes.data, out.ctypes.data)
            if rc:
                raise GeneratedCodeError(f"kvrod_energies failed (code {rc})")
            return out
        for k in range(m):
            out[k] = self.energy_scalars(float(ts[k]), ys[k], yps[k])
        return out

    def diagnostics(self, t: float, y: np.ndarray, yp: np.ndarray | None = None) -> dict:
        """Energies and resultants of state y.

        Returns the scalars of :meth:`energy_scalars` by name (kinetic, elastic,
        dissipation_rate, external_power, boundary_power), strains V (3, N) on segments
        and U (3, N+1) at joints (joint j at node j; the clamp joints j = 0, N are zero
        when absent), material resultants F (3, N) (N) and M (3, N+1) (N m), each elastic
        + viscous (eq. (1)).
        """
        self._time(t)
        N, ns = self.N, len(L.DIAG_SCALARS)
        yp_ = self._zeros if yp is None else yp
        if self._lib is not None:
            out = self._diag
            rc = self._lib.kvrod_diagnostics(self._struct_ptr(), t, _ptr(y, self.n),
                                             _ptr(yp_, self.n), _ptr(out, out.size))
            if rc:
                raise GeneratedCodeError(f"kvrod_diagnostics failed (code {rc})")
            res = {name: float(out[k]) for k, name in enumerate(L.DIAG_SCALARS)}
            V = out[ns:ns + 3 * N].reshape(N, 3).T.copy()
            F = out[ns + 3 * N:ns + 6 * N].reshape(N, 3).T.copy()
            U = out[ns + 6 * N:ns + 6 * N + 3 * (N + 1)].reshape(N + 1, 3).T.copy()
            M = out[ns + 6 * N + 3 * (N + 1):].reshape(N + 1, 3).T.copy()
        else:
            args = self._cargs(t, y, yp_)
            res = {name: float(v) for name, v in
                   zip(L.DIAG_SCALARS, self._casadi.energies(*args), strict=True)}
            V, F, U, M = (np.array(a) for a in self._casadi.elements(*args))
        res["strains"] = {"V": V, "U": U}
        res["resultants"] = {"F": F, "M": M}
        return res

    def energy_floor(self) -> float:
        """Energy (J) of round-off-sized strains of this rod: below it there is nothing to
        audit (``max EA L`` times ``(1e4 eps)^2``)."""
        h = self.arrays.seg_field("h")[:, 0]
        EA = self.arrays.seg_field("C_F")[:, 2]
        return float(np.sum(EA * h)) * (1e4 * np.finfo(float).eps) ** 2
