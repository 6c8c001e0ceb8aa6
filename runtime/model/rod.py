"""The discrete Cosserat rod in IDA form on the generated assembly.

:class:`RodModel` is what the integrator and the analyses see: the residual
``F(t, y, y') = 0`` of the discrete rod (``derive/discrete_rod.py``; layout in
``generated/rod_layout.py``), its banded iteration matrix ``cy dF/dy + cj dF/dy'`` in
LAPACK band storage, energies and powers, strains and stress resultants. It evaluates
the compiled C assembly through ctypes (``runtime.model.build``) or, without a C
compiler, the CasADi MX assembly (``runtime.model.casadi_oracle``) with the same numbers
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
from runtime.model.contact import N_VALUES, SELF_VALUE_NAMES, VALUE_NAMES
from runtime.model.layout_tables import layout_blocks, layout_table
from runtime.model.quaternion import end_quaternion, quat_mul, quat_rotation
from runtime.solvers.native.pointers import PointerCache as _PointerCache
from runtime.solvers.native.pointers import data_address as _ptr
from runtime.solvers.native.pointers import function_address
from runtime.solvers.native.relaxation import RelaxationBlock

#: the self-contact couplings' capacity: at most this many doubles of the Woodbury
#: columns Z (rows x n; beyond, a rod's pairs are left out of the Jacobian) and the
#: entries per coupling row (19 per pair a row's segment is in: 32 pairs)
SELF_COUPLING_DOUBLES = 1 << 23
SELF_COUPLING_ENTRIES_PER_ROW = 19 * 32


class Drive(Protocol):
    """What changes the rod's arrays with time: loads with time functions, moving ends.

    ``apply(arrays, t, left, scale)`` writes the values at time ``t`` (``left``: the limit
    from the left, for statics at ``t = 0-``) into ``arrays``; ``scale`` is the load
    factor, which also scales prescribed end displacements and rotations in statics;
    ``static``: velocities of the ends are zero (statics). ``time_dependent``: False when
    the values never change with t (then ``apply`` runs once). Optional:
    ``rotates(end) -> bool``, whether the frame of a held end (``"start"``, ``"end"``)
    turns with time (without it, any end may).
    """

    time_dependent: bool

    def apply(self, arrays: RodArrays, t: float, *, left: bool = False, scale: float = 1.0,
              static: bool = False) -> None:
        ...


class _Scatter:
    """Deterministic pseudo-random numbers for :meth:`RodModel.band_pattern`: splitmix64
    of a counter (Steele, Lea and Flood 2014), vectorised in NumPy's wrapping uint64
    arithmetic. Why not ``numpy.random``: importing it costs 7-12 ms of every process
    that builds an integrator, for ~1e3 numbers whose only job is to be generic (no
    Jacobian entry vanishes at them by accident)."""

    def __init__(self, seed: int) -> None:
        self._next = np.uint64(seed)

    def uniform(self, low: float, high: float, size) -> np.ndarray:
        """Numbers in [low, high), shaped ``size``."""
        count = int(np.prod(size))
        z = (np.arange(1, count + 1, dtype=np.uint64) + self._next) \
            * np.uint64(0x9E3779B97F4A7C15)
        self._next += np.uint64(count)
        z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
        z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
        z ^= z >> np.uint64(31)
        u = (z >> np.uint64(11)).astype(float) * 2.0**-53
        return (low + (high - low) * u).reshape(size)


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
        #: a rod with coupled sections (docs/design.md, section 10)
        self.coupled = arrays.coupled
        self.kl, self.ku = L.bandwidths(N, B, self.coupled)
        self.ldab = 2 * self.kl + self.ku + 1
        self.drive = drive
        self._key: tuple = ()       # (time, left?, load factor) the arrays were driven to
        self._steady = (0.0, 0.0)   # times on which those arrays hold (empty: none known)
        self._static = False
        self._piece_end = math.inf  # inputs are evaluated from the left here (enter_piece)
        build.require_generated()
        lib = None if backend == "casadi" else build.load_library()
        if backend == "c" and lib is None:
            raise GeneratedCodeError("compiled backend requested but no library could be "
                                     "built (see the warning above)")
        self._lib = lib
        #: the rigid obstacles the rod touches (runtime.model.contact; None: none)
        self.contact = arrays.contact if (arrays.contact is not None
                                          and arrays.contact.active) else None
        #: the rod's contact with itself (runtime.model.contact; None: off)
        self.self_contact = None if self.contact is None else self.contact.self_contact
        if self.contact is not None:
            if lib is None:
                raise GeneratedCodeError("contact runs on the compiled backend only (a C "
                                         "compiler is needed: see the warning above)")
            self._clib = build.load_contact_library()
            self.contact.bind(self._clib)
        self._blocks = None
        if self.self_contact is not None:
            # a self-contact pair couples two segments far apart along the rod: its
            # Jacobian leaves the band, and the Newton system is the rod's band block
            # with the pairs as dynamic couplings (runtime/solvers/native/blocks.c)
            self.newton_system = self._self_contact_newton_system
        #: the state's bound on the next step (contact; the BDF reads it), None without
        self.state_max_step = None if self.contact is None else self._contact_max_step
        #: the error test's weights near obstacles (contact; the BDF applies them), None
        #: without: a rod without obstacles keeps its tolerances everywhere
        self.state_error_weights = (self._contact_error_weights
                                    if self.contact is not None
                                    and self.contact.n_obstacles > 0
                                    and self.contact.tolerance_rate > 0.0 else None)
        self._struct = arrays.struct(self.kl, self.ku)
        self._sp = None
        self._casadi = None
        if lib is None and arrays.coupled:
            raise GeneratedCodeError(
                "a rod with coupled sections (full 6x6 matrices, a mass centre off the "
                "centreline, a product of inertia) runs on the compiled backend only; the "
                "CasADi fallback takes diagonal sections (a C compiler is needed: see the "
                "warning above, or backend='c')")
        if lib is None:
            from runtime.model.casadi_oracle import CasadiOracle

            self._casadi = CasadiOracle(arrays)
        self._ptrs = _PointerCache()
        self._zeros = np.zeros(self.n)
        self._ab = np.zeros((self.ldab, self.n), order="F")
        self._diag = np.zeros(L.diagnostics_size(N))
        #: values per state of :meth:`energies`: the DIAG_SCALARS, then per obstacle the
        #: contact's values (runtime.model.contact.VALUE_NAMES), then with self-contact
        #: the pairs' (SELF_VALUE_NAMES)
        self.n_energies = len(L.DIAG_SCALARS) + len(self.contact_value_names())
        self._energy = np.zeros(self.n_energies)
        self.phi_index = layout_blocks(lambda i: L.node_phi(i, B), 0, N, 3)
        self.v_index = layout_blocks(lambda i: L.node_v(i, B), 0, N, 3)
        self.p_index = layout_blocks(lambda i: L.segment_p(i, B), 1, N, 4)
        self.omega_index = layout_blocks(lambda i: L.segment_omega(i, B), 1, N, 3)
        #: state indices of the internal strains of the relaxation terms, (N, B, 3) and (N+1, B, 3)
        self.q_segment_index = (layout_table(lambda i: L.segment_q(i, B), 1, N)
                                .reshape(N, 1, 1) + np.arange(3 * B).reshape(1, B, 3))
        self.q_joint_index = (layout_table(lambda j: L.joint_q(j, B), 0, N)
                              .reshape(N + 1, 1, 1) + np.arange(3 * B).reshape(1, B, 3))
        self.velocity_mask = np.zeros(self.n, dtype=bool)
        self.velocity_mask[self.v_index.ravel()] = True
        self.velocity_mask[self.omega_index.ravel()] = True
        self.differential = np.ones(self.n, dtype=bool)
        #: the held nodes (0 and/or N): position and velocity prescribed (algebraic rows)
        self.held_nodes = tuple(i for end, i in (("start", 0), ("end", N)) if arrays.held(end))
        for i in self.held_nodes:
            self.differential[self.phi_index[i]] = False
            self.differential[self.v_index[i]] = False
        #: their rows phi - r(t), v - v(t): the integrator solves them exactly
        self.exact_rows = np.array(sorted(int(k) for i in self.held_nodes
                                          for k in (*self.phi_index[i], *self.v_index[i])),
                                   dtype=np.int32)
        self._pattern: sp.csc_matrix | None = None
        self._band_pattern: np.ndarray | None = None
        self._pattern_flat = np.zeros(0, dtype=np.intp)
        self._directions = None     # parameter directions of the sensitivities
        self._csens = None
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
        """Drive the arrays to time ``t`` (in statics: to ``t-`` with the ends at rest; at
        the end of the current piece, :meth:`enter_piece`, also to ``t-``); no-op when
        nothing changed since the last call."""
        if self.drive is None:
            return
        left = self._static or t >= self._piece_end
        lo, hi = self._steady
        if self.drive.time_dependent and not left and lo <= t < hi:
            tk = self._key[0] if self._key else None   # arrays of an earlier t still hold
        else:
            tk = t if self.drive.time_dependent else None
        key = (tk, left, self._scale_key())
        if key != self._key:
            self.drive.apply(self.arrays, t, left=left, scale=self.load_scale,
                             static=self._static)
            if self._directions is not None:
                self._directions.drive(t, left, self.load_scale, self._static)
            self._key = key
            if self._static or not self.drive.time_dependent:
                self._steady = (-math.inf, -math.inf)
            elif left:                    # the end of a piece: these values hold at t only
                self._steady = (t, t)
            else:
                lo, hi = self.drive.steady_interval(t)
                self._steady = (lo, min(hi, self._piece_end))

    # -- the inputs' breakpoints (the run drivers stop the integrator at each) ------------
    def breakpoints(self, t0: float, t1: float) -> list[tuple[float, bool]]:
        """Times in ``(t0, t1)`` where a load or a prescribed motion is not smooth, with
        whether the integrator must restart there (``ProblemDrive.breakpoints``)."""
        get = getattr(self.drive, "breakpoints", None)
        return [] if get is None else get(t0, t1)

    def enter_piece(self, t0: float, t1: float) -> float:
        """Integrate next over ``[t0, t1]`` (between two breakpoints): the inputs are
        evaluated from the right at t0 and from the left at t1, the implicit steps that
        end on t1 seeing the inputs before their jump. Returns the largest step on the
        piece (``ProblemDrive.max_step``; inf without a bound)."""
        self._piece_end = float(t1)
        self._key = ()
        get = getattr(self.drive, "max_step", None)
        return math.inf if get is None else float(get(t0, t1))

    def prescribed_rates(self, t: float, yp: np.ndarray) -> np.ndarray:
        """``yp`` with the derivatives of the algebraic unknowns set exactly: a held node's
        phi' = v(t) and v' = a(t) (the integrator's history starts from them, so its first
        predictor follows the prescribed motion)."""
        self.at(t)
        yp = np.array(yp, dtype=float)
        for end, i in (("start", 0), ("end", self.N)):
            if i in self.held_nodes:
                yp[self.phi_index[i]] = self.arrays.param("v_" + end)
                yp[self.v_index[i]] = self.arrays.param("a_" + end)
        return yp

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

    def _scale_key(self) -> float | None:
        """The load factor where the driven arrays depend on it, else None: only in
        statics, where it scales prescribed end motion and the obstacles' forces
        (``ProblemDrive.apply``), or with sensitivities (their directions are driven
        too); external loads read it from the arrays, so a load step of a rod without
        either need not drive the arrays again (16 calls per static solve of the
        cantilever)."""
        if self._static and (self._directions is not None or self.arrays.contact is not None
                             or getattr(self.drive, "scaled_in_statics", True)):
            return self.load_scale
        return None

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
        saved = dsaved = None
        if self.branches and relaxed and not previous:
            saved = (a.seg_field("C_F").copy(), a.jnt_field("C_M").copy(), a.segb.copy(),
                     a.jntb.copy())
            a.seg_field("C_F")[:] -= a.segb.sum(axis=1)
            a.jnt_field("C_M")[:] -= a.jntb.sum(axis=1)
            a.segb[:] = 0.0
            a.jntb[:] = 0.0
            if self._directions is not None:       # the derivatives relaxed alike
                dsaved = self._directions.relax()
        try:
            self.at(t)
            yield
        finally:
            if saved is not None:
                a.seg_field("C_F")[:], a.jnt_field("C_M")[:] = saved[0], saved[1]
                a.segb[:], a.jntb[:] = saved[2], saved[3]
            if dsaved is not None:
                self._directions.restore(dsaved)
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

    def relaxed_sensitivities(self, t: float, y: np.ndarray, s: np.ndarray) -> np.ndarray:
        """The sensitivities (k, n) of :meth:`relaxed`'s state ``y`` (every relaxation
        term at its element's strain) given those ``s`` of its configuration (their
        internal strains ignored): the terms' ``dq = d(strain)``, exactly, from the
        tangent of their rows ``q' - (strain - q)/theta`` (at q = strain, with dq = 0 and
        no rates, the row's tangent is ``-d(strain)/theta``); ``s`` itself for a
        Kelvin-Voigt rod."""
        if not self.branches:
            return s
        out = np.array(s, dtype=float)
        zero = np.zeros(self.n)
        qs, qj = self.q_segment_index, self.q_joint_index       # (N, B, 3), (N+1, B, 3)
        theta = self.arrays.theta
        for i, d in enumerate(self._directions.arrays):
            si = out[i]
            si[qs] = 0.0
            si[qj] = 0.0
            r = self.residual_tangent(t, y, zero, si, zero, d)
            si[qs] = -theta[None, :, None] * r[qs]
            si[qj] = -theta[None, :, None] * r[qj]
        return out

    def glassy_decay_rate(self) -> float:
        """Slowest decay rate sigma_g (1/s) of the rod's glassy modes (math.inf for a
        Kelvin-Voigt rod).

        A mode whose frequency is far above every 1/theta_b sees each relaxation term as
        a spring k_b (the instantaneous stiffness k_g = C_F) with a small loss:
        k*(omega) = k_g + i sum_b k_b / (omega theta_b) + O((omega theta)^-2), a loss factor
        sum_b k_b/(omega theta_b k_g) and a damping ratio half of it, so its amplitude
        decays like exp(-sigma t) with sigma = sum_b (k_b/theta_b) / (2 k_g), whatever the
        frequency. The slowest over the stiffnesses that relax (shear, extension, bending,
        torsion; every segment and joint) is returned: after ln(1/rtol)/sigma_g a
        ringing the start or a restart excited has decayed below the tolerance."""
        if not self.branches:
            return math.inf
        a = self.arrays
        rates = []
        for glassy, moduli in ((a.seg_field("C_F"), a.segb), (a.jnt_field("C_M"), a.jntb)):
            relax = np.tensordot(moduli, 1.0 / a.theta, axes=([1], [0]))   # sum_b k_b/theta_b
            live = (glassy > 0.0) & (relax > 0.0)
            if live.any():
                rates.append(float(np.min(relax[live] / (2.0 * glassy[live]))))
        return min(rates) if rates else math.inf

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

    # -- end frames ---------------------------------------------------------------------
    def end_segments(self) -> dict[str, np.ndarray]:
        """State indices of the quaternions that give the end frames: ``"first"`` of
        segments 1, 2 and ``"last"`` of segments N-1, N (one segment when N = 1)."""
        k = min(2, self.N)
        return {"first": self.p_index[:k].ravel(), "last": self.p_index[self.N - k:].ravel()}

    def end_quaternions(self, ts: np.ndarray, first: np.ndarray, last: np.ndarray
                        ) -> dict[str, np.ndarray]:
        """Unit quaternions (m, 4) of the frames at s = 0 (``"start"``) and s = L
        (``"end"``) at times ``ts`` (m,), from the quaternions of :meth:`end_segments`
        (``first``, ``last``: (m, 4k)). A clamped end has its clamp frame (prescribed: of
        its time); a free or pinned end the frame half a segment beyond its segment's
        centre, continued with the curvature of the neighbouring joint (second order)."""
        ts = np.atleast_1d(np.asarray(ts, dtype=float))
        m, k = ts.size, min(2, self.N)
        first = np.asarray(first, dtype=float).reshape(m, k, 4)
        last = np.asarray(last, dtype=float).reshape(m, k, 4)
        h = self.arrays.seg_field("h")[:, 0]
        hj = self.arrays.jnt_field("h")[:, 0]
        out = {}
        for end, segs, h_end, h_joint, inner, outer in (
                ("start", first, h[0], hj[1] if self.N > 1 else h[0], 1, 0),
                ("end", last, h[-1], hj[-2] if self.N > 1 else h[-1], 0, k - 1)):
            if self.arrays.clamped(end):
                varies = self.drive is not None and self.drive.time_dependent
                rotates = getattr(self.drive, "rotates", None)
                timed = varies and (rotates is None or rotates(end))
                q = np.empty((m, 4))
                if timed:
                    for j in range(m):
                        self.at(float(ts[j]))
                        q[j] = self.arrays.param("p_" + end)
                elif m:                      # one clamp frame for every time
                    self.at(float(ts[0]))
                    q[:] = self.arrays.param("p_" + end)
                    if varies:               # the arrays where a loop over ts leaves them
                        self.at(float(ts[-1]))
            elif k == 1:
                q = segs[:, 0]
            else:
                q = end_quaternion(segs[:, inner], segs[:, outer], h_end, h_joint)
            out[end] = q / np.linalg.norm(q, axis=1, keepdims=True)
        return out

    def end_frames(self, t: float, y: np.ndarray) -> dict[str, np.ndarray]:
        """Director frames (3, 3) (columns d1, d2, d3) at s = 0 and s = L of one state
        (:meth:`end_quaternions`)."""
        idx = self.end_segments()
        q = self.end_quaternions(np.array([t]), y[idx["first"]][None], y[idx["last"]][None])
        return {end: quat_rotation(v[0]) for end, v in q.items()}

    def condensation_blocks(self) -> list[tuple[int, int, int, int, int]]:
        """The kinematic blocks a Newton solve may eliminate (``runtime.solvers.native.
        condensed.CondensedNewton``): per node, the rows phi' = v eliminate v (kept: phi; at a held
        node the rows v = v(t)); per segment, the rows p' = 1/2 p*(0, Omega) eliminate p
        (kept: Omega). Each as
        ``(e_off, e_size, r_off, k_off, k_size)`` of contiguous state ranges."""
        blocks = []
        for i in range(self.N + 1):
            phi, v = self.phi_index[i], self.v_index[i]
            # a held node: its rows are phi - r(t), v - v(t); v goes with its own rows
            rows = v if i in self.held_nodes else phi
            blocks.append((int(v[0]), 3, int(rows[0]), int(phi[0]), 3))
        for i in range(self.N):
            p, om = self.p_index[i], self.omega_index[i]
            blocks.append((int(p[0]), 4, int(p[0]), int(om[0]), 3))
        for e0, es, r0, k0, ks in blocks:    # the layout keeps each field contiguous
            assert e0 >= 0 and r0 >= 0 and k0 >= 0 and es <= 4 and ks <= 4
        return blocks

    def condensation_relaxation_blocks(self) -> list[RelaxationBlock]:
        """The internal strains of a generalized Maxwell rod as relaxation blocks of the
        condensed Newton systems (``runtime.solvers.native.relaxation``): per segment and
        per joint, its 3B strains (term-major, as the state), whose rows ``q_b' -
        (strain - q_b)/theta_b`` are diagonal in them, with the rates 1/theta_b and the
        moduli of its terms (``segb``, ``jntb``); none for B = 0."""
        if not self.branches:
            return []
        a = self.arrays
        rates = np.repeat(1.0 / np.asarray(a.theta, float), 3)
        return ([RelaxationBlock(int(i), 3, rates, a.segb[s].ravel().copy())
                 for s, i in enumerate(self.q_segment_index[:, 0, 0])]
                + [RelaxationBlock(int(j), 3, rates, a.jntb[s].ravel().copy())
                   for s, j in enumerate(self.q_joint_index[:, 0, 0])])

    def condensation_cells(self) -> list[int]:
        """First state index of each cell of the layout (cell 0: node 0 and joint 0; cell
        i: segment i, node i, joint i). Couplings are nearest-neighbour, so the Newton
        systems condensed by :meth:`condensation_blocks` are block tridiagonal in these
        cells (``CondensedNewton`` checks it on :meth:`band_pattern`)."""
        starts = [0] + [int(self.p_index[i][0]) for i in range(self.N)]
        if self.coupled:
            # a coupled segment reaches cells i-1..i+1 (its nodes and its neighbours'
            # frames): nearest-neighbour in pairs of cells
            return starts[::2]
        return starts

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

    # -- sensitivities (issue 34; runtime/model/sensitivity.py) ------------------------
    def residual_tangent(self, t: float, y: np.ndarray, yp: np.ndarray, dy: np.ndarray,
                         dyp: np.ndarray, darrays: RodArrays | None = None,
                         out: np.ndarray | None = None) -> np.ndarray:
        """``dF = F_y dy + F_y' dy' + F_p dA`` (n,): the directional derivative of the
        residual at (t, y, y') along the state direction (dy, dy') and the direction
        ``darrays`` of the rod's numbers (the derivatives of its arrays with respect to
        one parameter, ``RodArrays`` of the model's shapes; None: none). Exact
        (the generated tangent kernels, ``native/rod_tangent.c``; on the CasADi
        backend the oracle's forward derivative)."""
        self._time(t)
        n = self.n
        out = np.empty(n) if out is None else out
        dy = np.ascontiguousarray(dy, dtype=float)
        dyp = np.ascontiguousarray(dyp, dtype=float)
        if self._lib is not None:
            import ctypes

            P = self._ptrs
            dptr = None
            if darrays is not None:
                ds = darrays.struct(self.kl, self.ku)
                dptr = ctypes.byref(ds)
            rc = self._lib.kvrod_residual_tangent(self._struct_ptr(), dptr, t, P(y, n),
                                                  P(yp, n), _ptr(dy, n), _ptr(dyp, n),
                                                  _ptr(out, n))
            if rc:
                raise GeneratedCodeError(f"kvrod_residual_tangent failed (code {rc})")
            return out
        from runtime.model.casadi_oracle import CasadiOracle

        if getattr(self, "_casadi_fwd", None) is None:
            self._casadi_fwd = self._casadi.residual.forward(1)
        args = self._cargs(t, y, yp)
        dargs = ([0.0, dy, dyp] + (CasadiOracle.args(darrays) if darrays is not None
                                   else [np.zeros_like(a) for a in args[3:]]))
        nominal = self._casadi.residual(*args)
        out[:] = np.asarray(self._casadi_fwd(*args, nominal, *dargs)).ravel()
        return out

    @property
    def directions(self):
        """The parameter directions of the sensitivities
        (``runtime.model.sensitivity.Directions``), or None."""
        return self._directions

    def set_directions(self, directions) -> None:
        """Give the model its parameters' directions (None: none): the sensitivity
        residual of parameter ``ip`` is then :meth:`sensitivity_residual`, driven in
        time with the model's arrays (:meth:`at`)."""
        if directions is not None:
            directions.check(self.arrays)
        self._directions = directions
        self._csens = None
        self._key = ()                      # drive both at the next at()

    @property
    def n_sensitivities(self) -> int:
        return 0 if self._directions is None else len(self._directions.arrays)

    def sensitivity_residual(self, t: float, y: np.ndarray, yp: np.ndarray, ip: int,
                             s: np.ndarray, sp: np.ndarray, out: np.ndarray) -> None:
        """out <- F_y s + F_y' s' + F_theta of parameter ``ip`` (its direction,
        :meth:`set_directions`; ip < 0: without the parameter's term)."""
        d = None if ip < 0 else self._directions.arrays[ip]
        self.residual_tangent(t, y, yp, s, sp, d, out)

    def sensitivity_prescribed_rates(self, t: float, ip: int, sp: np.ndarray) -> np.ndarray:
        """``sp`` with the rates of the held nodes' sensitivities set exactly: the
        derivatives of their prescribed velocity and acceleration with respect to
        parameter ``ip`` (as :meth:`prescribed_rates` for the state)."""
        self.at(t)
        sp = np.array(sp, dtype=float)
        d = self._directions.arrays[ip]
        for end, i in (("start", 0), ("end", self.N)):
            if i in self.held_nodes:
                sp[self.phi_index[i]] = d.param("v_" + end)
                sp[self.v_index[i]] = d.param("a_" + end)
        return sp

    def c_sensitivities(self) -> tuple[int, int, object] | None:
        """(address of ``kvrod_sens_residual``, its context, what must stay alive) for
        the compiled step loop; None on the CasADi backend or without directions."""
        if self._lib is None or self._directions is None:
            return None

        from runtime.model.sensitivity import CSensitivities

        if self._csens is None:
            self._csens = CSensitivities(self._struct, self._directions, self.kl, self.ku)
        fn = function_address(self._lib.kvrod_sens_residual)
        return fn, self._csens.ptr, self._csens

    def c_kernels(self):
        """The compiled residual, Jacobian and energies for the C step loop
        (:class:`runtime.solvers.protocols.CKernels`), with the drive as a callback that
        reports the interval on which the loads stay constant; None on the CasADi
        backend."""
        if self._lib is None:
            return None
        import ctypes

        from runtime.solvers.protocols import CKernels

        drive = None
        if self.drive is not None:
            def drive(t: float) -> tuple[float, float]:
                self.at(t)
                if not self.drive.time_dependent:
                    return -math.inf, math.inf
                lo, hi = self._steady
                if hi == self._piece_end > lo:
                    # the piece's end, evaluated from the left, has the arrays of the
                    # constant stretch before it: the interval covers it (so the
                    # compiled loop never calls back for a release, nor holds signals)
                    hi = math.nextafter(hi, math.inf)
                return lo, hi

        lib = self._lib
        energies = lib.kvrod_energies if self.contact is None else lib.kvrod_energies_contact
        kern = CKernels(function_address(lib.kvrod_residual),
                        function_address(lib.kvrod_jacobian_band),
                        function_address(energies), ctypes.addressof(self._struct),
                        drive=drive, keep=self,
                        jacobian_cells=(0 if self.coupled else
                                        function_address(lib.kvrod_jacobian_band_cells)),
                        drive_constant=drive is not None and not self.drive.time_dependent,
                        n_energies=self.n_energies)
        if self.contact is not None:
            kern.max_step = function_address(self._clib.kvrod_max_step)
        if self.branches and not self.coupled:
            kern.jacobian_cells_relaxed = (
                function_address(lib.kvrod_jacobian_band_cells_relaxed),
                self._set_relaxation_need)
        if self.self_contact is None:
            kern.audit_energies = function_address(lib.kvrod_audit_powers)
        # without obstacles the energies only read the rod's struct and the state (the
        # contact library keeps per-call values of the gaps): safe beside the residual
        kern.energies_reentrant = self.contact is None and self.self_contact is None
        # energies_one reads y' only for coupled sections (rod_assembly.c); the contact
        # energies are not looked at here
        kern.energies_read_rates = self.coupled or not kern.energies_reentrant
        if self.state_error_weights is not None:
            kern.error_weights = function_address(self._clib.kvrod_error_weights)
        if self.self_contact is not None:
            self.blocks  # noqa: B018 (attached before the first Jacobian)
            kern.system_jacobian = function_address(lib.kvrod_jacobian_system)
        return kern

    def _set_relaxation_need(self, need: np.ndarray) -> None:
        """The relaxation rows and columns ``kvrod_jacobian_band_cells_relaxed`` forms in
        full (``kvrod_rod.relax_need``; CKernels.jacobian_cells_relaxed)."""
        need = np.ascontiguousarray(need, dtype=np.uint8)
        if need.shape != (self.n,):
            raise ValueError(f"relaxation need of shape {need.shape}; expected ({self.n},)")
        self._relax_need = need
        self._struct.relax_need = need.ctypes.data

    # -- self-contact: the coupled band block (runtime/solvers/native/blocks.py) --------------
    @property
    def blocks(self):
        """The rod's Newton matrix with self-contact: one band block (condensed as the
        rod's own Newton system is, where it can be) and the self-contact pairs' entries
        between their segments as dynamic coupling rows (``CoupledBlocks``; None without
        self-contact). Capacity: every momentum row of the rod, within
        ``SELF_COUPLING_DOUBLES`` of Z (pairs beyond it are left out of the Jacobian,
        not of the residual)."""
        if self.self_contact is None:
            return None
        if self._blocks is None:
            from runtime.solvers.native.blocks import Block, CoupledBlocks
            from runtime.solvers.native.condensed import CondensedNewton

            cond = CondensedNewton.build(self, self.n, self.kl, self.ku, self.ldab)
            rows = min(6 * self.N + 3, max(SELF_COUPLING_DOUBLES // max(self.n, 1), 36))
            cb = CoupledBlocks([Block(0, self.n, self.kl, self.ku, cond)], {},
                               dynamic_rows=rows,
                               dynamic_entries=rows * SELF_COUPLING_ENTRIES_PER_ROW)
            self.self_contact.attach(cb, self.n)
            self._blocks = cb
        return self._blocks

    def system_jacobian(self, t: float, y: np.ndarray, yp: np.ndarray, cj: float) -> None:
        """J = dF/dy + cj dF/dy' into the coupled block ``blocks`` (self-contact only)."""
        self._time(t)
        self.blocks  # noqa: B018
        rc = self._lib.kvrod_jacobian_system(self._struct_ptr(), t, _ptr(y, self.n),
                                             _ptr(yp, self.n), cj, None)
        if rc:
            raise GeneratedCodeError(f"kvrod_jacobian_system failed (code {rc})")

    def _self_contact_newton_system(self):
        """The integrator's Newton system with self-contact: the coupled block."""
        from runtime.solvers.newton import BlocksSystem

        return BlocksSystem(self)

    def _self_couplings(self, t: float, y: np.ndarray) -> sp.csc_matrix:
        """dF/dy's self-contact entries between the segments of each pair (CSC)."""
        import ctypes

        import scipy.sparse as sp

        cb = self.blocks
        self._time(t)
        rc = self._clib.kvrod_self_couplings(self._struct_ptr(), _ptr(y, self.n))
        if rc:
            raise GeneratedCodeError(f"kvrod_self_couplings failed (code {rc})")
        m = int(ctypes.c_int.from_address(cb.m2_address).value)
        nz = int(cb.er2[m])
        rows = np.repeat(cb.srow2[:m], np.diff(cb.er2[:m + 1]))
        return sp.csc_matrix((cb.ev2[:nz].copy(), (rows, cb.ec2[:nz].copy())),
                             shape=(self.n, self.n))

    def self_contact_values(self, t: float, y: np.ndarray) -> dict[str, float]:
        """The self-contact's energy (J), dissipated power (W) and its friction part,
        the smallest gap between paired segments' surfaces (m; inf: no pair in reach) and
        the number of pairs in reach (``contact.SELF_VALUE_NAMES``)."""
        if self.self_contact is None:
            raise ValueError("the rod has no self-contact (contact.self = false)")
        self._time(t)
        out = np.zeros(len(SELF_VALUE_NAMES))
        rc = self._clib.kvrod_self_values(self._struct_ptr(), _ptr(y, self.n),
                                          out.ctypes.data)
        if rc:
            raise GeneratedCodeError(f"kvrod_self_values failed (code {rc})")
        return dict(zip(SELF_VALUE_NAMES, out.tolist(), strict=True))

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

        Found by evaluating the banded Jacobian at two pseudo-random states (loads with
        follower parts present keep their entries), so no entry vanishes by accident. No
        SciPy (unlike :meth:`sparsity`) and no ``numpy.random`` (``_Scatter`` instead): the
        integrator's setup uses it.
        """
        if self._band_pattern is None:
            rng = _Scatter(12345)
            pat = np.zeros((self.ldab, self.n), dtype=bool, order="F")
            ab = np.zeros((self.ldab, self.n), order="F")
            saved = self.arrays.copy()
            driven = (self._key, self._steady)   # what the restored arrays hold
            a = self.arrays
            for name in ("f_follower",):
                a.node_load(name)[:] = rng.uniform(0.5, 1.5, a.node_load(name).shape)
            for name in ("m_dead",):
                a.segment_load(name)[:] = rng.uniform(0.5, 1.5, a.segment_load(name).shape)
            a.set_param("load_scale", 1.0)
            # self-contact's pairs within a segment have the segment's own entries; at
            # random states the pair search would only cost
            struct = None if self.contact is None else self.contact._struct
            self_ptr = None if struct is None else struct.self
            if struct is not None:
                struct.self = None
            try:
                for _ in range(2):
                    y = self.reference + 0.1 * rng.uniform(-1.0, 1.0, self.n)
                    self.jacobian_band2(0.0, y, rng.uniform(-1.0, 1.0, self.n), 1.0, 1.0, ab)
                    # whole (contiguous) arrays: rows 0..kl-1 are never written
                    np.logical_or(pat, ab != 0.0, out=pat)
            finally:
                if struct is not None:
                    struct.self = self_ptr
                for name in ("par", "seg", "jnt", "nload", "sload"):
                    getattr(a, name)[...] = getattr(saved, name)
                self._key, self._steady = driven
            pat[:self.kl] = False
            self._band_pattern = pat
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
        if self.self_contact is not None and cy != 0.0:
            # the pairs' entries within a segment are in the band (its pattern: the
            # segment's own forces'), those between the segments are the couplings
            return (pat + cy * self._self_couplings(t, y)).tocsc()
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
            return tuple(float(v) for v in out[:len(L.DIAG_ENERGIES)])
        vals = self._casadi.energies(*self._cargs(t, y, yp_))
        return tuple(float(v) for v in vals[:len(L.DIAG_ENERGIES)])

    #: names of the energies' columns after the first five: the supports' reactions
    reaction_names: tuple[str, ...] = tuple(L.DIAG_REACTIONS)

    # -- contact with obstacles (runtime/model/native/rod_contact.h) ----------------------
    def _contact_max_step(self, t: float, y: np.ndarray) -> float:
        """The largest next step (s) that moves no segment toward an obstacle by more than
        ``step_fraction`` of its gap plus delta (inf: no bound)."""
        self._time(t)
        return float(self._clib.kvrod_contact_max_step(self._struct_ptr(), _ptr(y, self.n)))

    def _contact_error_weights(self, y: np.ndarray, rtol: float, atol: np.ndarray,
                               w: np.ndarray) -> None:
        """The error test's weights ``w`` (``1/(rtol |y| + atol)``, changed in place) near
        obstacles: the velocities of segments within their length of an obstacle at the
        positions' tolerance times the contact's rate (``kvrod_contact_error_weights``)."""
        rc = self._clib.kvrod_contact_error_weights(self._struct_ptr(), _ptr(y, self.n),
                                                    float(rtol), _ptr(atol, self.n),
                                                    _ptr(w, self.n))
        if rc:
            raise RuntimeError(f"kvrod_contact_error_weights failed ({rc})")

    def contact_values(self, t: float, y: np.ndarray) -> np.ndarray:
        """(nobs, N_VALUES): per obstacle the force (N) and moment (N m, about its point)
        it exerts on the rod (spatial), the contact energy (J), the dissipated power
        (W) and its friction part, the power of its motion on the rod (W), the smallest
        gap (m) and the number of segments in reach (``contact.VALUE_NAMES``); (0, ...)
        without obstacles."""
        if self.contact is None:
            return np.zeros((0, N_VALUES))
        self._time(t)
        out = np.zeros((self.contact.n_obstacles, N_VALUES))
        rc = self._clib.kvrod_contact_values(self._struct_ptr(), _ptr(y, self.n),
                                            out.ctypes.data)
        if rc:
            raise GeneratedCodeError(f"kvrod_contact_values failed (code {rc})")
        return out

    def contact_points(self, t: float, y: np.ndarray) -> np.ndarray:
        """(k, 6): the quadrature points touching an obstacle (gap below 3 delta): obstacle
        index, segment (1..N), position (3, m), gap (m)."""
        if self.contact is None:
            return np.zeros((0, 6))
        self._time(t)
        cap = 256
        while True:
            out = np.zeros((cap, 6))
            k = self._clib.kvrod_contact_points(self._struct_ptr(), _ptr(y, self.n),
                                               out.ctypes.data, cap)
            if k < 0:
                raise GeneratedCodeError(f"kvrod_contact_points failed (code {k})")
            if k <= cap:
                return out[:k]
            cap = k

    def contact_value_names(self) -> tuple[str, ...]:
        """Names of the columns of :meth:`energies` after the DIAG_SCALARS:
        ``obstacle{k}_{value}``, then ``self_contact_{value}`` with self-contact."""
        if self.contact is None:
            return ()
        return (tuple(f"obstacle{k}_{v}" for k in range(self.contact.n_obstacles)
                      for v in VALUE_NAMES)
                + tuple(f"self_contact_{v}" for v in SELF_VALUE_NAMES
                        if self.self_contact is not None))

    def reactions(self, t: float, y: np.ndarray) -> dict[str, dict[str, np.ndarray]]:
        """The force (N) and moment (N m, about the node) that each held end's support
        exerts on the rod in state ``y`` at time ``t``, spatial: ``{"start": {"force",
        "moment"}, "end": {...}}`` for the held ends (the moment of a pinned end is 0).
        In a dynamic state the held node's inertia is included (``m a - f_ext - f_int``
        with the prescribed acceleration a); velocities enter through the viscous
        forces. The last columns of :meth:`energies` hold the same numbers."""
        d = self.diagnostics(t, y)
        out = {}
        for end, i in (("start", 0), ("end", self.N)):
            if i in self.held_nodes:
                out[end] = {what: np.array([d[f"{end}_{what}_{c}"] for c in "xyz"])
                            for what in ("force", "moment")}
        return out

    def energies(self, ts: np.ndarray, ys: np.ndarray, yps: np.ndarray) -> np.ndarray:
        """(m, k) energies and powers of m states (rows of ``ys``, ``yps``) in one call
        (the per-step energy quadrature): the columns of ``DIAG_SCALARS`` (layout), the
        five of :meth:`energy_scalars` then the supports' reactions. Loads must not
        depend on time within ``ts`` beyond what :meth:`at` of each time gives;
        time-dependent problems evaluate per state."""
        ys = np.ascontiguousarray(ys, dtype=float)
        yps = np.ascontiguousarray(yps, dtype=float)
        ts = np.ascontiguousarray(ts, dtype=float)
        m = ys.shape[0]
        out = np.empty((m, self.n_energies))
        if self.contact is not None:
            for k in range(m):
                self._time(float(ts[k]))
                rc = self._lib.kvrod_energies_contact(
                    self._struct_ptr(), 1, ts[k:k + 1].ctypes.data, ys[k].ctypes.data,
                    yps[k].ctypes.data, out[k].ctypes.data)
                if rc:
                    raise GeneratedCodeError(f"kvrod_energies_contact failed (code {rc})")
            return out
        if self._lib is not None and self._steady_for(ts):
            rc = self._lib.kvrod_energies(self._struct_ptr(), m, ts.ctypes.data, ys.ctypes.data,
                                          yps.ctypes.data, out.ctypes.data)
            if rc:
                raise GeneratedCodeError(f"kvrod_energies failed (code {rc})")
            return out
        for k in range(m):
            d = self.diagnostics(float(ts[k]), ys[k], yps[k])
            out[k] = [d[name] for name in L.DIAG_SCALARS]
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

    def strain_rates(self, t: float, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The exact rates of the discrete strains along the flow of state ``y``:
        ``Vdot`` (3, N) = R^T (v_b - v_a)/h + V x Omega on segments and ``Udot`` (3, N+1) =
        A w / h_j at joints (``w = Omega_b - R(r)^T Omega_a``, ``A = I + [u]x + u u^T``,
        u = Im(r)/Re(r), r = conj(p_a) p_b; zero where a clamp joint is absent), the
        rates whose viscous resultants the kernels form (``derive/discrete_rod.py``)."""
        self._time(t)
        a = self.arrays
        N = self.N
        h = a.seg_field("h")[:, 0]
        p = y[self.p_index]
        om = y[self.omega_index]
        R = quat_rotation(p)                                            # (N, 3, 3)
        phi, v = y[self.phi_index], y[self.v_index]
        V = np.einsum("nji,nj->ni", R, np.diff(phi, axis=0)) / h[:, None]
        Vd = np.einsum("nji,nj->ni", R, np.diff(v, axis=0)) / h[:, None] + np.cross(V, om)
        pa, pb, oa, ob, on = [], [], [], [], []
        for j in range(N + 1):
            has_a, has_b = j >= 1, j + 1 <= N
            if not ((has_a and has_b) or (j == 0 and a.clamped("start"))
                    or (j == N and a.clamped("end"))):
                on.append(False)
                pa.append(p[0]), pb.append(p[0]), oa.append(om[0]), ob.append(om[0])
                continue
            on.append(True)
            pa.append(p[j - 1] if has_a else a.param("p_start"))
            pb.append(p[j] if has_b else a.param("p_end"))
            oa.append(om[j - 1] if has_a else a.param("Omega_start"))
            ob.append(om[j] if has_b else a.param("Omega_end"))
        pa, pb, oa, ob = (np.array(x, dtype=float) for x in (pa, pb, oa, ob))
        r = quat_mul(pa * np.array([1.0, -1.0, -1.0, -1.0]), pb)
        u = r[:, 1:] / r[:, :1]
        w = ob - np.einsum("nji,nj->ni", quat_rotation(r), oa)
        Aw = w + np.cross(u, w) + u * np.sum(u * w, axis=1, keepdims=True)
        Ud = np.where(np.array(on)[:, None], Aw / a.jnt_field("h"), 0.0)
        return Vd.T, Ud.T

    def energy_floor(self) -> float:
        """Energy (J) of round-off-sized strains of this rod: below it there is nothing to
        audit (``max EA L`` times ``(1e4 eps)^2``)."""
        h = self.arrays.seg_field("h")[:, 0]
        EA = self.arrays.seg_field("C_F")[:, 2]
        return float(np.sum(EA * h)) * (1e4 * np.finfo(float).eps) ** 2
