"""An assembly of rods as one implicit system (issue 31; docs/design.md, section 12).

:class:`SystemModel` is what the integrator, statics and the analyses see of an assembly:
the rods' states one after the other (rod r's unknowns from ``offsets[r]``, each in its
own layout), the residual and iteration matrix of the whole, energies and the forces in
the joints. The rods stay :class:`~runtime.model.rod.RodModel` objects and are computed
exactly as single rods (their own residuals and band Jacobians, compiled); the system
adds three kinds of coupling, all in ``native/system.c``:

* :class:`Hold` -- a node held by a support (its rows ``phi - r``, ``v``) or tied to
  another node, its group's master (rows ``phi - phi_m``, ``v - v_m``; its momentum row,
  computed as if it were free, is added to the master's: the joint force cancels, an
  index reduction without a multiplier, as the rod's held ends are);
* :class:`Link` -- elastic and viscous coupling of two sides (a node and one or two
  segment frames each, or the ground) through the generated ``rod_link_*`` kernels:
  welds, hinges, rotational and 6x6 springs;
* :class:`Body` -- a rigid body welded at a node, its frame the node's segment's
  (``rod_body_*`` kernels).

Linear algebra: each rod is a band block (condensed and factored as a single rod is,
with its held nodes' rows as a held end's), the couplings are the few rows they touch
(:class:`~runtime.solvers.native.blocks.CoupledBlocks`: Woodbury on those rows).
"""

from __future__ import annotations

import contextlib
import ctypes
import math
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass

import numpy as np

from generated import rod_layout as L
from runtime.errors import GeneratedCodeError
from runtime.model import build
from runtime.model.contact import N_VALUES, SELF_VALUE_NAMES, VALUE_NAMES, SelfContactArrays
from runtime.model.rod import SELF_COUPLING_DOUBLES, SELF_COUPLING_ENTRIES_PER_ROW, RodModel
from runtime.solvers.native.pointers import function_address


@dataclass(frozen=True)
class Hold:
    """Node ``node`` of rod ``rod`` held at ``position`` (m, a support: master None) or tied
    to the node ``master`` = (rod, node) (a joint's shared position)."""

    rod: int
    node: int
    master: tuple[int, int] | None = None
    position: tuple[float, float, float] | None = None


@dataclass(frozen=True)
class Side:
    """One side of a link: the node whose position and velocity it uses (``node`` =
    (rod, node), or None: the fixed ``point``), and its frame: the sum of the quaternions
    of one or two segments (``frames`` = ((rod, segment 1..N), ...); two adjacent segments
    give the frame at their common node) or the fixed ``frame`` (a unit quaternion, the
    ground)."""

    node: tuple[int, int] | None = None
    frames: tuple[tuple[int, int], ...] = ()
    point: tuple[float, float, float] = (0.0, 0.0, 0.0)
    frame: tuple[float, float, float, float] = (1.0, 0.0, 0.0, 0.0)


@dataclass(frozen=True)
class Link:
    """Stiffness ``K`` and viscosity ``V`` (6x6, in side a's frame, order translation then
    rotation) between sides ``a`` and ``b``; ``d0`` (m) and ``r0`` (quaternion) their
    relative position and rotation in the reference (the link is stress free there)."""

    a: Side
    b: Side
    K: np.ndarray
    V: np.ndarray
    d0: tuple[float, float, float] = (0.0, 0.0, 0.0)
    r0: tuple[float, float, float, float] = (1.0, 0.0, 0.0, 0.0)


@dataclass(frozen=True)
class Body:
    """A rigid body welded at node ``node`` of rod ``rod``, its frame that of ``segment``:
    ``mass`` (kg), ``inertia`` (3x3 about its mass centre, kg m^2) and ``offset`` (m, mass
    centre from the node), both in the segment's material frame."""

    rod: int
    node: int
    segment: int
    mass: float
    inertia: np.ndarray
    offset: tuple[float, float, float] = (0.0, 0.0, 0.0)


class SysStruct(ctypes.Structure):
    """``kvsys`` of runtime/model/native/system.h."""

    _P, _I, _D, _L = ctypes.c_void_p, ctypes.c_int, ctypes.c_double, ctypes.c_longlong
    _fields_ = [("n", _I), ("nrod", _I), ("rod", _P), ("off", _P), ("J", _P),
                ("ab_start", _P), ("ldab", _P), ("nhold", _I), ("hold", _P),
                ("hold_r", _P), ("hold_e", _P), ("ncopy", _I), ("copy_src", _P),
                ("copy_dst", _P), ("nzero", _I), ("zero", _P), ("ev_start", _L),
                ("nev", _I), ("nlink", _I), ("lidx", _P), ("lrow", _P), ("lpar", _P),
                ("lconst", _P), ("ldst", _P), ("nbody", _I), ("bidx", _P), ("brow", _P),
                ("bpar", _P), ("bdst", _P), ("gravity", _D * 3), ("nextra", _I),
                ("scratch", _P), ("pairs", _P), ("pair_residual", _P),
                ("pair_jacobian", _P), ("pair_couplings", _P), ("pair_values", _P),
                ("pair_max_step", _P)]


#: the link kernel's inputs in order (name, size): its Jacobian's columns follow them
LINK_INPUTS = (("phi_a", 3), ("phi_b", 3), ("v_a", 3), ("v_b", 3), ("p_a1", 4), ("p_a2", 4),
               ("p_b1", 4), ("p_b2", 4), ("Omega_a1", 3), ("Omega_a2", 3), ("Omega_b1", 3),
               ("Omega_b2", 3))
#: the link kernel's outputs (rows): forces on the nodes, torques on the four frames
LINK_OUTPUTS = (("f_a", 3), ("f_b", 3), ("T_a1", 3), ("T_a2", 3), ("T_b1", 3), ("T_b2", 3))
#: the order of the link Jacobian's columns (the kernel's: positions and frames first)
LINK_JAC_COLUMNS = ("phi_a", "phi_b", "p_a1", "p_a2", "p_b1", "p_b2", "v_a", "v_b",
                    "Omega_a1", "Omega_a2", "Omega_b1", "Omega_b2")


class SystemModel:
    """An assembly of rods as one residual problem (see the module docstring).

    rods: the rods' models (built as single rods; a rod whose node is held or tied by
    the system is built free there); names: their names; holds, links, bodies: the
    couplings; gravity: ``gravity(t, left, scale)`` the scaled gravity (m/s^2) on the
    bodies at time t (the rods' own loads are in their drives); pairs: the contact
    between the rods' segments and of each rod with itself (``contact.self``;
    :class:`~runtime.model.contact.SelfContactArrays` over every rod's segments in
    order; None: none; the rods themselves then carry no self-contact).
    """

    def __init__(self, rods: Sequence[RodModel], names: Sequence[str],
                 holds: Sequence[Hold] = (), links: Sequence[Link] = (),
                 bodies: Sequence[Body] = (),
                 gravity: Callable[[float, bool, float], np.ndarray] | None = None,
                 pairs: SelfContactArrays | None = None) -> None:
        if not rods:
            raise ValueError("an assembly needs at least one rod")
        if pairs is not None and any(r.self_contact is not None for r in rods):
            raise ValueError("an assembly's contact between its rods takes every rod's "
                             "self-contact: build the rods without it")
        self.rods = list(rods)
        #: the contact between the rods' segments (None: off)
        self.pairs = pairs
        self._pair_scale = 1.0
        self._plib = None if pairs is None else build.load_contact_library()
        #: the step bound of rods touching obstacles and of the pairs (BDF's
        #: state_max_step), None without contact
        self.state_max_step = (self._contact_max_step
                               if pairs is not None
                               or any(r.contact is not None for r in self.rods) else None)
        self.names = list(names)
        self.holds, self.links, self.bodies = list(holds), list(links), list(bodies)
        self._gravity = gravity
        lib = build.load_library()
        if lib is None or any(r.backend != "c" for r in self.rods):
            raise GeneratedCodeError("an assembly of rods runs on the compiled backend only "
                                     "(a C compiler is needed: see the warning above)")
        if not hasattr(lib, "kvsys_residual"):
            raise GeneratedCodeError("the compiled rod library has no assembly functions")
        self._lib = lib
        off = [0]
        for r in self.rods:
            off.append(off[-1] + r.n)
        self.offsets = np.array(off, dtype=np.int32)
        self.n = int(off[-1])
        #: the integrator's own band storage is unused (the blocks hold J): a 1-wide band
        self.kl = self.ku = 0
        self.branches = max(r.branches for r in self.rods)
        self.coupled = any(r.coupled for r in self.rods)
        self.reference = np.concatenate([r.reference for r in self.rods])
        g = self.global_index
        self.phi_index = [g(k, r.phi_index) for k, r in enumerate(self.rods)]
        self.v_index = [g(k, r.v_index) for k, r in enumerate(self.rods)]
        self.p_index = [g(k, r.p_index) for k, r in enumerate(self.rods)]
        self.omega_index = [g(k, r.omega_index) for k, r in enumerate(self.rods)]
        self.velocity_mask = np.concatenate([r.velocity_mask for r in self.rods])
        self.differential = np.concatenate([r.differential for r in self.rods])
        held_rows = []
        for h in self.holds:
            self._check_node(h.rod, h.node)
            if h.node in self.rods[h.rod].held_nodes:
                raise ValueError(f"rod {self.names[h.rod]!r}: node {h.node} is held by its "
                                 "own end condition and by a joint")
            rows = [*self.phi_index[h.rod][h.node], *self.v_index[h.rod][h.node]]
            held_rows += rows
            self.differential[rows] = False
        self.exact_rows = np.array(sorted(
            [int(k) for r_, rod in enumerate(self.rods) for k in rod.exact_rows + off[r_]]
            + [int(k) for k in held_rows]), dtype=np.int32)
        self._held = {(h.rod, h.node) for h in self.holds}
        self._zeros = np.zeros(self.n)
        self._scratch = np.zeros(self.n)
        self._blocks = None          # CoupledBlocks, built with the Newton system
        self._struct: SysStruct | None = None
        self._keep: list = []
        self.drive = self
        self.time_dependent = any(r.drive is not None and r.drive.time_dependent
                                  for r in self.rods)
        self._static = False
        self._load_scale = 1.0
        self._t = math.nan
        #: obstacles the rods touch (every rod with contact sees all of the problem's)
        self.n_obstacles = max((r.contact.n_obstacles for r in self.rods
                                if r.contact is not None), default=0)
        self.nextra = (12 * len(self.rods) + 3 * len(self.holds) + 6 * len(self.links)
                       + N_VALUES * self.n_obstacles
                       + (0 if pairs is None else len(SELF_VALUE_NAMES)))
        self._sdirs = None            # parameter directions (runtime/model/system_sensitivity)
        self._csys_sens = None
        self.at(0.0)

    # -- indices --------------------------------------------------------------------------
    def global_index(self, rod: int, local: np.ndarray) -> np.ndarray:
        """Global state indices of rod ``rod``'s local indices."""
        return np.asarray(local) + int(self.offsets[rod])

    def _check_node(self, rod: int, node: int) -> None:
        if not 0 <= rod < len(self.rods) or not 0 <= node <= self.rods[rod].N:
            raise ValueError(f"no node {node} on rod {rod}")

    def rod_slice(self, rod: int) -> slice:
        """The state range of rod ``rod``."""
        return slice(int(self.offsets[rod]), int(self.offsets[rod + 1]))

    def describe_dof(self, index: int) -> str:
        """Human-readable name of state/residual component ``index``."""
        r = int(np.searchsorted(self.offsets, index, side="right") - 1)
        return f"rod {self.names[r]!r}: {self.rods[r].describe_dof(index - self.offsets[r])}"

    # -- time, loads ----------------------------------------------------------------------
    @property
    def load_scale(self) -> float:
        return self._load_scale

    @load_scale.setter
    def load_scale(self, value: float) -> None:
        self._load_scale = float(value)
        for r in self.rods:
            r.load_scale = value
        self._t = math.nan

    def at(self, t: float) -> None:
        """Drive every rod and the bodies' gravity to time ``t``."""
        for r in self.rods:
            r.at(t)
        if self.pairs is not None:
            # statics takes the pairs' contact up with the load factor, as a rod's drive
            # does its obstacles' (runtime.problem.assemble.ProblemDrive)
            scale = self._load_scale if self._static else 1.0
            if scale != self._pair_scale:
                self.pairs.set_force_scale(scale)
                self._pair_scale = scale
        if t != self._t and self._struct is not None:
            self._set_gravity(t)
        self._t = t

    def _set_gravity(self, t: float) -> None:
        g = (np.zeros(3) if self._gravity is None else
             np.asarray(self._gravity(t, self._static or t >= self._piece_end,
                                      self._load_scale), dtype=float))
        for k in range(3):
            self._struct.gravity[k] = float(g[k])
        if self._sdirs is not None:          # the sensitivities' gravity, alike
            self._sdirs.set_gravity(t, self._static or t >= self._piece_end, self._load_scale)
            if self._csys_sens is not None:
                self._csys_sens.refresh_gravity()

    _piece_end = math.inf

    def steady_interval(self, t: float | None = None) -> tuple[float, float]:
        """The interval on which every rod's inputs hold (intersection): at ``t`` (the
        drives' own answer), else the one each rod's arrays were last driven on."""
        lo, hi = -math.inf, math.inf
        for r in self.rods:
            if r.drive is not None and r.drive.time_dependent:
                a, b = r.drive.steady_interval(t) if t is not None else r._steady
                lo, hi = max(lo, a), min(hi, b)
        return lo, hi

    def breakpoints(self, t0: float, t1: float) -> list[tuple[float, bool]]:
        """The rods' input breakpoints in (t0, t1), merged (restart where any asks)."""
        out: dict[float, bool] = {}
        for r in self.rods:
            for t, restart in r.breakpoints(t0, t1):
                out[t] = out.get(t, False) or restart
        return sorted(out.items())

    def enter_piece(self, t0: float, t1: float) -> float:
        self._piece_end = float(t1)
        self._t = math.nan
        return min(r.enter_piece(t0, t1) for r in self.rods)

    def prescribed_rates(self, t: float, yp: np.ndarray) -> np.ndarray:
        yp = np.array(yp, dtype=float)
        for k, r in enumerate(self.rods):
            s = self.rod_slice(k)
            yp[s] = r.prescribed_rates(t, yp[s])
        for h in self.holds:
            ph, v = self.phi_index[h.rod][h.node], self.v_index[h.rod][h.node]
            if h.master is None:
                yp[ph] = 0.0
                yp[v] = 0.0
            else:
                yp[ph] = yp[self.phi_index[h.master[0]][h.master[1]]]
                yp[v] = yp[self.v_index[h.master[0]][h.master[1]]]
        return yp

    def steady_over(self, t0: float, t1: float) -> bool:
        return all(r.steady_over(t0, t1) for r in self.rods)

    @contextlib.contextmanager
    def statics(self, t: float = 0.0, relaxed: bool = True) -> Iterator[None]:
        """Every rod driven as in statics (``RodModel.statics``)."""
        with contextlib.ExitStack() as stack:
            for r in self.rods:
                stack.enter_context(r.statics(t, relaxed))
            previous, self._static = self._static, True
            self._t = math.nan
            try:
                self.at(t)
                yield
            finally:
                self._static = previous
                self._t = math.nan

    # -- states ---------------------------------------------------------------------------
    def constrain(self, y: np.ndarray) -> np.ndarray:
        """y with every held node at its support or its master (copy), the rods' own held
        ends at their targets."""
        y = np.array(y, dtype=float)
        for k, r in enumerate(self.rods):
            s = self.rod_slice(k)
            y[s] = r.constrain(y[s])
        for h in self.holds:
            ph, v = self.phi_index[h.rod][h.node], self.v_index[h.rod][h.node]
            if h.master is None:
                y[ph] = h.position
                y[v] = 0.0
            else:
                y[ph] = y[self.phi_index[h.master[0]][h.master[1]]]
                y[v] = y[self.v_index[h.master[0]][h.master[1]]]
        return y

    def initial_state(self, t: float = 0.0) -> np.ndarray:
        self.at(t)
        return self.constrain(self.reference.copy())

    def relaxed(self, y: np.ndarray, t: float = 0.0) -> np.ndarray:
        y = np.array(y, dtype=float)
        for k, r in enumerate(self.rods):
            s = self.rod_slice(k)
            y[s] = r.relaxed(y[s], t)
        return y

    def rod_state(self, rod: int, y: np.ndarray) -> np.ndarray:
        """Rod ``rod``'s part of the state (a view)."""
        return y[self.rod_slice(rod)]

    # -- the compiled tables ----------------------------------------------------------------
    def _build(self) -> None:
        """The Jacobian's blocks and couplings, then the kvsys struct."""
        from runtime.solvers.native.blocks import Block, CoupledBlocks
        from runtime.solvers.native.condensed import CondensedNewton

        rods, off = self.rods, self.offsets
        patterns = [self._block_pattern(k) for k in range(len(rods))]
        # the structural entries of every coupling, as (row, col) pairs (global)
        link_entries = [self._link_entries(lk) for lk in self.links]
        body_entries = [self._body_entries(b) for b in self.bodies]
        coupling: dict[int, set[int]] = {}

        def in_band(r: int, c: int) -> bool:
            k = int(np.searchsorted(off, r, side="right") - 1)
            if not off[k] <= c < off[k + 1]:
                return False
            d = c - r
            return -rods[k].kl <= d <= rods[k].ku

        def add(r: int, c: int) -> None:
            if not in_band(r, c):
                coupling.setdefault(r, set()).add(c)
            else:
                k = int(np.searchsorted(off, r, side="right") - 1)
                i, j = r - off[k], c - off[k]
                patterns[k][rods[k].kl + rods[k].ku + i - j, j] = True

        for ent in link_entries + body_entries:
            for (r, c) in ent:
                add(r, c)
        # the slaves' momentum rows move to their masters' rows: every structural entry
        # of a slave's v row (its band row and its couplings) gets a place in the master's
        copies: list[tuple[int, int, int]] = []          # (slave row, master row, column)
        for h in self.holds:
            if h.master is None:
                continue
            k = h.rod
            for q in range(3):
                rs = int(self.v_index[k][h.node][q])
                rm = int(self.v_index[h.master[0]][h.master[1]][q])
                cols = set(self._band_row_columns(k, rs, patterns[k]))
                cols |= coupling.get(rs, set())
                for c in sorted(cols):
                    copies.append((rs, rm, c))
                    add(rm, c)
            for q in range(3):               # the -1 of the tie rows on the master's columns
                for rows, cols in ((self.phi_index, self.phi_index),
                                   (self.v_index, self.v_index)):
                    r_ = int(rows[k][h.node][q])
                    c_ = int(cols[h.master[0]][h.master[1]][q])
                    coupling.setdefault(r_, set()).add(c_)
        # the held rows are identities in their blocks (the condensation sees held ends)
        for h in self.holds:
            pat = patterns[h.rod]
            rod = rods[h.rod]
            for idx in (*self.phi_index[h.rod][h.node], *self.v_index[h.rod][h.node]):
                i = int(idx) - int(off[h.rod])
                for j in range(max(0, i - rod.kl), min(rod.n, i + rod.ku + 1)):
                    pat[rod.kl + rod.ku + i - j, j] = False
                pat[rod.kl + rod.ku, i] = True
        blocks = []
        for k, rod in enumerate(rods):
            held = set(rod.held_nodes) | {h.node for h in self.holds if h.rod == k}
            cond = CondensedNewton(build_lib_solvers(), rod.n, rod.kl, rod.ku,
                                   2 * rod.kl + rod.ku + 1,
                                   _condensation_blocks(rod, held),
                                   cells=rod.condensation_cells(), pattern=patterns[k])
            blocks.append(Block(int(off[k]), rod.n, rod.kl, rod.ku, cond))
        rows = entries = 0
        if self.pairs is not None:
            # the pairs' entries between two segments: dynamic couplings, at most every
            # momentum row of every rod within SELF_COUPLING_DOUBLES of Z (as a single
            # rod's self-contact) and of the capacitance matrix (m + rows)^2 (many small
            # rods: Z is small, C is not); pairs beyond stay in the residual only
            biggest = max(r.n for r in rods)
            rows = min(sum(6 * r.N + 3 for r in rods),
                       max(SELF_COUPLING_DOUBLES // max(biggest, 1), 36),
                       max(math.isqrt(SELF_COUPLING_DOUBLES) - len(coupling), 36))
            entries = rows * SELF_COUPLING_ENTRIES_PER_ROW
        cb = self._blocks = CoupledBlocks(blocks, {r: sorted(c) for r, c in coupling.items()},
                                          dynamic_rows=rows, dynamic_entries=entries)
        dest = cb.destination
        s = SysStruct()
        keep = self._keep
        arr = lambda a, dt: keep.append(np.ascontiguousarray(a, dtype=dt)) or keep[-1]  # noqa: E731
        ptr = lambda a: a.ctypes.data if a.size else None  # noqa: E731
        s.n, s.nrod = self.n, len(rods)
        rodp = (ctypes.c_void_p * len(rods))(*[ctypes.addressof(r._struct) for r in rods])
        keep.append(rodp)
        s.rod = ctypes.addressof(rodp)
        s.off = ptr(arr(off, np.int32))
        s.J = cb.buffer.ctypes.data
        s.ab_start = ptr(arr(cb.ab_start, np.int64))
        s.ldab = ptr(arr(cb.ldab, np.int32))
        s.nhold = len(self.holds)
        hold, hold_r, hold_e = [], [], []
        for h in self.holds:
            ph, v = int(self.phi_index[h.rod][h.node][0]), int(self.v_index[h.rod][h.node][0])
            if h.master is None:
                hold += [ph, v, -1, -1]
                hold_r += list(h.position)
                hold_e += [-1] * 6
            else:
                mph = int(self.phi_index[h.master[0]][h.master[1]][0])
                mv = int(self.v_index[h.master[0]][h.master[1]][0])
                hold += [ph, v, mph, mv]
                hold_r += [0.0, 0.0, 0.0]
                hold_e += [dest(ph + q, mph + q) for q in range(3)]
                hold_e += [dest(v + q, mv + q) for q in range(3)]
        s.hold = ptr(arr(hold or [0], np.int32))
        s.hold_r = ptr(arr(hold_r or [0.0], np.float64))
        s.hold_e = ptr(arr(hold_e or [0], np.int64))
        s.ncopy = len(copies)
        s.copy_src = ptr(arr([dest(a, c) for a, _, c in copies] or [0], np.int64))
        s.copy_dst = ptr(arr([dest(b, c) for _, b, c in copies] or [0], np.int64))
        zero = [int(cb.ev_start + k) for k, (r, c) in enumerate(cb.entries)
                if any(r in (int(i) for i in (*self.phi_index[h.rod][h.node],
                                              *self.v_index[h.rod][h.node]))
                       for h in self.holds)]
        s.nzero = len(zero)
        s.zero = ptr(arr(zero or [0], np.int64))
        s.ev_start, s.nev = int(cb.ev_start), len(cb.entries)
        s.nlink = len(self.links)
        lidx, lrow, lpar, lconst, ldst = [], [], [], [], []
        for lk in self.links:
            ix, rows, const = self._link_tables(lk)
            lidx += ix
            lrow += rows
            lconst += const
            lpar += list(_link_params(lk))
            cols = self._link_columns(ix)
            for q in range(18):
                for x in range(40):
                    r_, c_ = rows[q], cols[x]
                    ldst.append(dest(r_, c_) if r_ >= 0 and c_ >= 0 else -1)
        s.lidx = ptr(arr(lidx or [0], np.int32))
        s.lrow = ptr(arr(lrow or [0], np.int32))
        s.lpar = ptr(arr(lpar or [0.0], np.float64))
        s.lconst = ptr(arr(lconst or [0.0], np.float64))
        s.ldst = ptr(arr(ldst or [0], np.int64))
        s.nbody = len(self.bodies)
        bidx, brow, bpar, bdst = [], [], [], []
        for b in self.bodies:
            v = int(self.v_index[b.rod][b.node][0])
            p = int(self.p_index[b.rod][b.segment - 1][0])
            om = int(self.omega_index[b.rod][b.segment - 1][0])
            bidx += [v, p, om]
            rows = [v, v + 1, v + 2, om, om + 1, om + 2]
            brow += rows
            bpar += list(_body_params(b))
            cols = [v, v + 1, v + 2, p, p + 1, p + 2, p + 3, om, om + 1, om + 2]
            for r_ in rows:
                for c_ in cols:
                    bdst.append(dest(r_, c_))
        s.bidx = ptr(arr(bidx or [0], np.int32))
        s.brow = ptr(arr(brow or [0], np.int32))
        s.bpar = ptr(arr(bpar or [0.0], np.float64))
        s.bdst = ptr(arr(bdst or [0], np.int64))
        s.nextra = self.nextra
        s.scratch = self._scratch.ctypes.data
        if self.pairs is not None:
            self.pairs.attach_system(self, cb)
            addr = function_address
            s.pairs = self.pairs.struct_address
            s.pair_residual = addr(self._plib.kvsys_pairs_residual)
            s.pair_jacobian = addr(self._plib.kvsys_pairs_jacobian)
            s.pair_couplings = addr(self._plib.kvsys_pairs_couplings)
            s.pair_values = addr(self._plib.kvsys_pairs_values)
            s.pair_max_step = addr(self._plib.kvsys_pairs_max_step)
        self._struct = s
        self._t = math.nan

    # (the helpers of _build)
    def _block_pattern(self, k: int) -> np.ndarray:
        return self.rods[k].band_pattern()

    def _band_row_columns(self, k: int, row: int, pattern: np.ndarray) -> list[int]:
        rod, o = self.rods[k], int(self.offsets[k])
        i = row - o
        out = []
        for j in range(max(0, i - rod.kl), min(rod.n, i + rod.ku + 1)):
            if pattern[rod.kl + rod.ku + i - j, j]:
                out.append(j + o)
        return out

    def _side_indices(self, side: Side) -> dict[str, int]:
        out = {"phi": -1, "v": -1, "p1": -1, "p2": -1, "om1": -1, "om2": -1}
        if side.node is not None:
            r, i = side.node
            self._check_node(r, i)
            out["phi"] = int(self.phi_index[r][i][0])
            out["v"] = int(self.v_index[r][i][0])
        for q, (r, sgm) in enumerate(side.frames[:2]):
            if not 1 <= sgm <= self.rods[r].N:
                raise ValueError(f"no segment {sgm} on rod {self.names[r]!r}")
            out[f"p{q + 1}"] = int(self.p_index[r][sgm - 1][0])
            out[f"om{q + 1}"] = int(self.omega_index[r][sgm - 1][0])
        return out

    def _link_tables(self, lk: Link) -> tuple[list[int], list[int], list[float]]:
        """(12 input indices, 18 residual rows, 40 constants) of a link."""
        a, b = self._side_indices(lk.a), self._side_indices(lk.b)
        ix = [a["phi"], b["phi"], a["v"], b["v"], a["p1"], a["p2"], b["p1"], b["p2"],
              a["om1"], a["om2"], b["om1"], b["om2"]]
        zero4 = [0.0] * 4
        const = (list(lk.a.point) + list(lk.b.point) + [0.0] * 6
                 + (list(lk.a.frame) if not lk.a.frames else zero4) + zero4
                 + (list(lk.b.frame) if not lk.b.frames else zero4) + zero4 + [0.0] * 12)
        rows = []
        for base in (a["v"], b["v"], a["om1"], a["om2"], b["om1"], b["om2"]):
            rows += [base + q if base >= 0 else -1 for q in range(3)]
        return ix, rows, const

    @staticmethod
    def _link_columns(ix: list[int]) -> list[int]:
        """The 40 Jacobian columns of a link (kernel order: phi_a, phi_b, p_a1, p_a2, p_b1,
        p_b2, v_a, v_b, Omega_a1, Omega_a2, Omega_b1, Omega_b2), -1 where constant."""
        size = dict(LINK_INPUTS)
        where = dict(zip((n for n, _ in LINK_INPUTS), ix, strict=True))
        out = []
        for name in LINK_JAC_COLUMNS:
            base = where[name]
            out += [base + q if base >= 0 else -1 for q in range(size[name])]
        return out

    def _link_entries(self, lk: Link) -> list[tuple[int, int]]:
        ix, rows, _ = self._link_tables(lk)
        cols = self._link_columns(ix)
        return [(r, c) for r in rows if r >= 0 for c in cols if c >= 0]

    def _body_entries(self, b: Body) -> list[tuple[int, int]]:
        v = int(self.v_index[b.rod][b.node][0])
        p = int(self.p_index[b.rod][b.segment - 1][0])
        om = int(self.omega_index[b.rod][b.segment - 1][0])
        rows = [v, v + 1, v + 2, om, om + 1, om + 2]
        cols = [v, v + 1, v + 2, p, p + 1, p + 2, p + 3, om, om + 1, om + 2]
        return [(r, c) for r in rows for c in cols]

    def _ptr(self) -> int:
        if self._struct is None:
            self._build()
            self._set_gravity(0.0 if math.isnan(self._t) else self._t)
        return ctypes.addressof(self._struct)

    # -- residual, Jacobian, Newton -----------------------------------------------------------
    def residual(self, t: float, y: np.ndarray, yp: np.ndarray, out: np.ndarray) -> None:
        """out <- F(t, y, y') (n,) of the whole assembly."""
        p = self._ptr()
        self.at(t)
        rc = self._lib.kvsys_residual(p, t, y.ctypes.data, yp.ctypes.data, out.ctypes.data)
        if rc:
            raise RuntimeError(f"kvsys_residual failed ({rc})")

    def system_jacobian(self, t: float, y: np.ndarray, yp: np.ndarray, cj: float) -> None:
        """J = dF/dy + cj dF/dy' into the coupled blocks (:attr:`blocks`)."""
        p = self._ptr()
        self.at(t)
        rc = self._lib.kvsys_jacobian(p, t, y.ctypes.data, yp.ctypes.data, cj, None)
        if rc:
            raise RuntimeError(f"kvsys_jacobian failed ({rc})")

    # -- sensitivities (issue 34; runtime/model/system_sensitivity.py) -----------------------
    @property
    def directions(self):
        """The parameter directions (:class:`SystemDirections`), or None."""
        return self._sdirs

    def set_directions(self, directions) -> None:
        """Give the assembly (and its rods) its parameters' directions (None: none)."""
        if directions is not None and self.pairs is not None:
            refuse_pair_sensitivities()
        self._sdirs = directions
        self._csys_sens = None
        if directions is not None:
            directions.install(self)
        self._t = math.nan

    @property
    def n_sensitivities(self) -> int:
        return 0 if self._sdirs is None else len(self._sdirs.dirs)

    def residual_tangent(self, t: float, y: np.ndarray, yp: np.ndarray, dy: np.ndarray,
                         dyp: np.ndarray, ip: int | None = None,
                         out: np.ndarray | None = None) -> np.ndarray:
        """``F_y dy + F_y' dy' + F_p dp`` of the whole assembly along parameter ``ip``'s
        direction (:meth:`set_directions`; None: the state direction only)."""
        p = self._ptr()
        self.at(t)
        if ip is not None:
            self._c_sensitivity_context()
        out = np.empty(self.n) if out is None else out
        d = None if ip is None else ctypes.addressof(self._csys_sens.dirs[ip])
        c = np.ascontiguousarray
        dy, dyp = c(dy, dtype=float), c(dyp, dtype=float)
        rc = self._lib.kvsys_residual_tangent(p, d, t, y.ctypes.data, yp.ctypes.data,
                                              dy.ctypes.data, dyp.ctypes.data,
                                              out.ctypes.data)
        if rc:
            raise RuntimeError(f"kvsys_residual_tangent failed ({rc})")
        return out

    def sensitivity_residual(self, t, y, yp, ip, s, sp, out) -> None:
        """out <- F_y s + F_y' s' + F_theta of parameter ``ip`` (ip < 0: without it)."""
        self.residual_tangent(t, y, yp, s, sp, None if ip < 0 else ip, out)

    def sensitivity_prescribed_rates(self, t: float, ip: int, sp: np.ndarray) -> np.ndarray:
        """sp with the held nodes' rates set exactly (the rods' own held ends by their
        prescribed motion's derivatives; supports at rest; ties as their masters)."""
        sp = np.array(sp, dtype=float)
        for k, r in enumerate(self.rods):
            sl = self.rod_slice(k)
            sp[sl] = r.sensitivity_prescribed_rates(t, ip, sp[sl])
        for h in self.holds:
            ph, v = self.phi_index[h.rod][h.node], self.v_index[h.rod][h.node]
            if h.master is None:
                sp[ph] = 0.0
                sp[v] = 0.0
            else:
                sp[ph] = sp[self.phi_index[h.master[0]][h.master[1]]]
                sp[v] = sp[self.v_index[h.master[0]][h.master[1]]]
        return sp

    def _c_sensitivity_context(self):
        from runtime.model.system_sensitivity import CSystemSensitivities

        if self._csys_sens is None:
            self._csys_sens = CSystemSensitivities(self, self._sdirs)
        return self._csys_sens

    def c_sensitivities(self) -> tuple[int, int, object] | None:
        """(address of ``kvsys_sens_residual``, its context, what must stay alive) for the
        compiled step loop; None without directions."""
        if self._sdirs is None:
            return None
        ctx = self._c_sensitivity_context()
        fn = function_address(self._lib.kvsys_sens_residual)
        return fn, ctx.ptr, ctx

    @property
    def blocks(self):
        """The coupled band blocks that hold J (:class:`CoupledBlocks`)."""
        self._ptr()
        return self._blocks

    def jacobian_band(self, t, y, yp, cj, out_ab) -> None:
        raise NotImplementedError("an assembly's Jacobian is not banded: its Newton system "
                                  "is newton_system()'s coupled blocks")

    def newton_system(self):
        """The integrator's Newton system: the coupled blocks (see the module docstring)."""
        from runtime.solvers.newton import BlocksSystem

        return BlocksSystem(self)

    def jacobian_sparse(self, t: float, y: np.ndarray, yp: np.ndarray, cy: float = 1.0,
                        cj: float = 0.0):
        """cy dF/dy + cj dF/dy' (scipy.sparse CSC), from the blocks (cy = 1 or 0)."""
        import scipy.sparse as sp

        if cy == 0.0:
            return self.dF_dyp_sparse(t, y, yp) * cj
        self.system_jacobian(t, y, yp, cj)
        rows, cols, flat = self._coo_pattern()
        vals = self._blocks.buffer[flat]
        nz = vals != 0.0
        rows, cols, vals = rows[nz], cols[nz], vals[nz]
        if self.pairs is not None:            # the pairs' couplings (dynamic rows)
            cb = self._blocks
            m = int(ctypes.c_int.from_address(cb.m2_address).value)
            k = int(cb.er2[m])
            rows = np.concatenate([rows, np.repeat(cb.srow2[:m], np.diff(cb.er2[:m + 1]))])
            cols = np.concatenate([cols, cb.ec2[:k]])
            vals = np.concatenate([vals, cb.ev2[:k]])
        return sp.csc_matrix((vals, (rows, cols)), shape=(self.n, self.n))

    def _coo_pattern(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(rows, cols, flat index into the blocks' buffer) of every entry J may hold:
        every band position of every block, then the couplings (built once)."""
        pat = getattr(self, "_coo", None)
        if pat is None:
            cb = self.blocks
            rows, cols, flat = [], [], []
            for b, a0, ld in zip(cb.blocks, cb.ab_start, cb.ldab, strict=True):
                j = np.arange(b.n)
                for d in range(-b.kl, b.ku + 1):          # d = col - row
                    i = j - d
                    ok = (i >= 0) & (i < b.n)
                    rows.append(b.offset + i[ok])
                    cols.append(b.offset + j[ok])
                    flat.append(a0 + (b.kl + b.ku - d) + j[ok] * int(ld))
            if cb.entries:
                e = np.array(cb.entries)
                rows.append(e[:, 0])
                cols.append(e[:, 1])
                flat.append(cb.ev_start + np.arange(len(cb.entries)))
            pat = self._coo = tuple(np.concatenate(x).astype(np.int64)
                                    for x in (rows, cols, flat))
        return pat

    def dF_dy_sparse(self, t, y, yp):
        return self.jacobian_sparse(t, y, yp, 1.0, 0.0)

    def dF_dyp_sparse(self, t, y, yp):
        """dF/dy' from two Jacobians (it is linear in cj)."""
        J1 = self.jacobian_sparse(t, y, yp, 1.0, 1.0)
        J0 = self.jacobian_sparse(t, y, yp, 1.0, 0.0)
        return (J1 - J0).tocsc()

    # -- energies and the joints' forces ------------------------------------------------------
    @property
    def n_energies(self) -> int:
        return 5 + self.nextra

    def energy_values(self, t: float, y: np.ndarray, yp: np.ndarray | None = None
                      ) -> np.ndarray:
        """The values of one state: T, W, 2D, P_ext, P_bc, then the extras (the rods'
        supports, the holds' free rows, the links' force and moment on side a, each
        obstacle's ``runtime.model.contact.VALUE_NAMES`` summed over the rods, the pairs'
        values with ``contact.self``)."""
        p = self._ptr()
        self.at(t)
        yp = self._zeros if yp is None else yp
        out = np.zeros(self.n_energies)
        ts = np.array([t])
        rc = self._lib.kvsys_energies(p, 1, ts.ctypes.data, np.ascontiguousarray(y).ctypes.data,
                                      np.ascontiguousarray(yp).ctypes.data, out.ctypes.data)
        if rc:
            raise RuntimeError(f"kvsys_energies failed ({rc})")
        return out

    def energies(self, ts: np.ndarray, ys: np.ndarray, yps: np.ndarray) -> np.ndarray:
        """(m, 5 + extras) of m states (:meth:`energy_values`)."""
        return np.array([self.energy_values(float(t), y, yp)
                         for t, y, yp in zip(ts, ys, yps, strict=True)])

    def energy_scalars(self, t: float, y: np.ndarray, yp: np.ndarray | None = None
                       ) -> tuple[float, float, float, float, float]:
        """(T, W, 2D, P_ext, P_bc) of a state (J, J, W, W, W)."""
        return tuple(float(v) for v in self.energy_values(t, y, yp)[:5])

    def pair_contact_values(self, t: float, y: np.ndarray) -> dict[str, float]:
        """The contact between the rods (``contact.self``): energy (J), dissipated power
        (W) and its friction part, the smallest gap between paired segments' surfaces (m;
        inf: no pair in reach) and the number of pairs in reach
        (``contact.SELF_VALUE_NAMES``)."""
        if self.pairs is None:
            raise ValueError("the assembly has no contact between its rods "
                             "(contact.self = false)")
        self._ptr()                  # the pairs attached to the system
        self.at(t)
        out = np.zeros(len(SELF_VALUE_NAMES))
        y = np.ascontiguousarray(y, dtype=float)
        rc = self._plib.kvsys_pairs_values(self.pairs.struct_address, y.ctypes.data,
                                           out.ctypes.data)
        if rc:
            raise RuntimeError(f"kvsys_pairs_values failed ({rc})")
        return dict(zip(SELF_VALUE_NAMES, out.tolist(), strict=True))

    @property
    def reaction_names(self) -> tuple[str, ...]:
        """Names of the extras of :meth:`energy_values` (after the five energies)."""
        out = []
        for name in self.names:
            out += [f"{name}/{r}" for r in L.DIAG_REACTIONS]
        for i in range(len(self.holds)):
            out += [f"hold{i}_force_{c}" for c in "xyz"]
        for i in range(len(self.links)):
            out += [f"link{i}_{w}_{c}" for w in ("force", "moment") for c in "xyz"]
        for i in range(self.n_obstacles):
            out += [f"obstacle{i}_{v}" for v in VALUE_NAMES]
        if self.pairs is not None:                # the last extras (kvsys_energies)
            out += [f"self_contact_{v}" for v in SELF_VALUE_NAMES]
        return tuple(out)

    def energy_floor(self) -> float:
        return sum(r.energy_floor() for r in self.rods)

    def extras_layout(self) -> dict[str, slice]:
        """Where the extras of :meth:`energy_values` are (after the five energies)."""
        k = 5
        out = {}
        for name in self.names:
            out[f"rod:{name}"] = slice(k, k + 12)
            k += 12
        for i in range(len(self.holds)):
            out[f"hold:{i}"] = slice(k, k + 3)
            k += 3
        for i in range(len(self.links)):
            out[f"link:{i}"] = slice(k, k + 6)
            k += 6
        for i in range(self.n_obstacles):
            out[f"obstacle:{i}"] = slice(k, k + N_VALUES)
            k += N_VALUES
        if self.pairs is not None:                # the last extras (kvsys_energies)
            out["self_contact"] = slice(5 + self.nextra - len(SELF_VALUE_NAMES),
                                        5 + self.nextra)
        return out

    def c_kernels(self):
        """The compiled residual, system Jacobian and energies for the C step loop."""
        from runtime.solvers.protocols import CKernels

        p = self._ptr()
        addr = function_address
        lib = self._lib

        def drive(t: float) -> tuple[float, float]:
            self.at(t)
            if not self.time_dependent:
                return -math.inf, math.inf
            return self.steady_interval()

        k = CKernels(addr(lib.kvsys_residual), 0, addr(lib.kvsys_energies), p, drive=drive,
                     keep=self, drive_constant=not self.time_dependent,
                     n_energies=self.n_energies)
        k.system_jacobian = addr(lib.kvsys_jacobian)
        if self.state_max_step is not None:
            k.max_step = addr(lib.kvsys_max_step)
        return k

    def _contact_max_step(self, t: float, y: np.ndarray) -> float:
        """The largest next step (s) that moves no segment of any rod toward an obstacle
        or another segment by more than its share of the gap (the rods'
        ``kvrod_contact_max_step``, the pairs' ``kvsys_pairs_max_step``)."""
        self.at(t)
        y = np.ascontiguousarray(y, dtype=float)
        return float(self._lib.kvsys_max_step(self._ptr(), t, y.ctypes.data, None))


def refuse_pair_sensitivities() -> None:
    """Sensitivities of an assembly whose rods touch each other (``contact.self``) are not
    available: a one-line :class:`~runtime.errors.ParameterError` naming the key."""
    from runtime.errors import ParameterError

    raise ParameterError("contact.self", True, "false for sensitivities: the contact "
                         "between an assembly's rods has no parameter derivatives in this "
                         "version")


def _condensation_blocks(rod: RodModel, held: set[int]) -> list[tuple[int, int, int, int, int]]:
    """The rod's kinematic blocks with the nodes in ``held`` as held nodes (their v by
    their own rows: ``RodModel.condensation_blocks``)."""
    blocks = []
    for i in range(rod.N + 1):
        phi, v = rod.phi_index[i], rod.v_index[i]
        rows = v if i in held else phi
        blocks.append((int(v[0]), 3, int(rows[0]), int(phi[0]), 3))
    for i in range(rod.N):
        p, om = rod.p_index[i], rod.omega_index[i]
        blocks.append((int(p[0]), 4, int(p[0]), int(om[0]), 3))
    return blocks


def build_lib_solvers():
    """The integrator's compiled helpers (``runtime.solvers.native.loader.load``)."""
    from runtime.solvers.native.loader import load

    lib = load()
    if lib is None:
        raise GeneratedCodeError("an assembly of rods needs the compiled integrator helpers")
    return lib


def _link_params(lk: Link) -> np.ndarray:
    """A link's parameter vector (``LINK_PARAMS`` of generated/rod_layout.py)."""
    out = np.zeros(L.N_LINK)
    put = lambda name, v: out.__setitem__(  # noqa: E731
        slice(L.LINK_OFFSETS[name], L.LINK_OFFSETS[name] + np.size(v)), np.ravel(v))
    put("K", np.asarray(lk.K, dtype=float).reshape(6, 6))
    put("V", np.asarray(lk.V, dtype=float).reshape(6, 6))
    put("d0", lk.d0)
    put("r0", lk.r0)
    return out


def _body_params(b: Body) -> np.ndarray:
    """A body's parameter vector (``BODY_PARAMS`` of generated/rod_layout.py)."""
    out = np.zeros(L.N_BODY)
    put = lambda name, v: out.__setitem__(  # noqa: E731
        slice(L.BODY_OFFSETS[name], L.BODY_OFFSETS[name] + np.size(v)), np.ravel(v))
    put("M", b.mass)
    put("J", np.asarray(b.inertia, dtype=float).reshape(3, 3))
    put("e", b.offset)
    return out


__all__ = ["Body", "Hold", "Link", "Side", "SystemModel"]
