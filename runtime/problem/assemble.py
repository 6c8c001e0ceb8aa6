"""From a problem to the numbers of its discrete rod: arrays, reference state and drive.

:func:`build_model` discretizes the reference geometry (nodes at ``s_i``, segment frames
at the midpoints, clamp frames at the ends), fills the per-element arrays (lengths,
stiffness and damping from the material and section, inertia, and the intrinsic strains
V0, U0 computed from the discrete reference with the kernels' own strain measures, so
the reference configuration is exactly stress-free), sets the ends, and returns a
:class:`~runtime.model.rod.RodModel` with a :class:`ProblemDrive` that writes the loads and
the prescribed end motion at any time.
"""

from __future__ import annotations

import math

import numpy as np

from runtime.model.arrays import RodArrays, coupled_arrays
from runtime.model.contact import ContactArrays, SelfContactArrays
from runtime.model.layout_tables import layout_blocks
from runtime.model.quaternion import (
    cayley_curvature,
    quat_exp,
    quat_from_matrix,
    quat_mul,
    quat_rotation,
)
from runtime.model.rod import RodModel
from runtime.problem.geometry import Straight, discretize
from runtime.problem.materials import joint_average, joint_series
from runtime.problem.obstacles import Obstacle
from runtime.problem.schema import Problem
from runtime.problem.timefunctions import TimeFunction


class ProblemDrive:
    """Loads with time functions and prescribed end motion, written into the arrays.

    The ends' reference positions and frames are those of the discrete reference; a
    motion adds ``translation * f(t)`` and rotates the clamp frame about the fixed spatial
    axis by ``angle * g(t)``. In statics (``static``) the velocities are zero and the
    displacement and rotation are scaled by the load factor (they are load-stepped).
    """

    def __init__(self, problem: Problem, N: int, r_ends: np.ndarray, p_ends: np.ndarray):
        self.problem = problem
        self.N = N
        self.length = problem.rod.length
        self.r_ends, self.p_ends = r_ends, p_ends        # (2, 3), (2, 4)
        self.loads = problem.loads
        self.ends = (problem.start, problem.end)
        #: the obstacles whose pose the drive writes (runtime.model.contact)
        self.obstacles = problem.obstacles
        self.time_dependent = any(not ld.time.is_constant for ld in self.loads) or any(
            e.motion is not None and e.motion.time_dependent for e in self.ends) or any(
            o.time_dependent for o in self.obstacles)
        s_nodes = problem.node_arc_lengths()
        self._nodes = [ld.node(N, self.length, s_nodes) for ld in self.loads]
        #: an end has prescribed motion (statics must move the held nodes)
        self.moving_ends = any(e.motion is not None and e.motion.moves for e in self.ends)
        #: :meth:`apply` in statics reads its ``scale`` (the load factor): prescribed end
        #: motion is scaled by it (obstacles' forces too: RodModel._scale_key checks those)
        self.scaled_in_statics = any(e.held and e.motion is not None for e in self.ends)

    #: steps per time scale of an active input at most (a ramp's duration, a harmonic's
    #: period, a table piece): the error test sees nothing to control in a rod at rest
    STEPS_PER_TIME_SCALE = 10
    #: breakpoints closer than this (relative to ``max(1, |t|)``) are one
    MERGE_RTOL = 1e-10

    def _inputs(self) -> list[tuple[TimeFunction, bool]]:
        """(time function, drives a motion) of every input that acts (nonzero)."""
        out = [(ld.time, False) for ld in self.loads if any(ld.vector)]
        for e in self.ends:
            mo = e.motion
            if mo is not None:
                if any(mo.translation):
                    out.append((mo.translation_time, True))
                if mo.rotation_angle:
                    out.append((mo.rotation_time, True))
        for o in self.obstacles:
            out += o.inputs()
        return out

    def breakpoints(self, t0: float, t1: float) -> list[tuple[float, bool]]:
        """The inputs' breakpoints in ``(t0, t1)``, sorted, each with whether the integrator
        must restart there: where a load or its rate jumps, or a prescribed motion, its
        rate or its acceleration (the held node's velocity is an algebraic unknown, so an
        acceleration jump is a kink of an unknown, as a rate jump of a load is of the
        accelerations). Breakpoints closer than ``MERGE_RTOL`` are one."""
        raw: list[tuple[float, bool]] = []
        for f, motion in self._inputs():
            for t, order in f.breakpoints(t0, t1):
                raw.append((t, order <= (2 if motion else 1)))
        out: list[tuple[float, bool]] = []
        for t, restart in sorted(raw):
            tol = self.MERGE_RTOL * max(1.0, abs(t))
            if not t0 + tol < t < t1 - tol:
                continue
            if out and t - out[-1][0] <= tol:
                out[-1] = (out[-1][0], out[-1][1] or restart)
            else:
                out.append((t, restart))
        return out

    def max_step(self, t0: float, t1: float) -> float:
        """Largest step (s) on the piece ``[t0, t1]`` between two breakpoints: a fraction
        ``1 / STEPS_PER_TIME_SCALE`` of the shortest time scale of the inputs active on
        it (inf when none is)."""
        tm = 0.5 * (t0 + t1) if math.isfinite(t1) else t0
        scale = min((f.time_scale(tm) for f, _ in self._inputs()), default=math.inf)
        return scale / self.STEPS_PER_TIME_SCALE

    def held_positions(self, end: str, ts: np.ndarray) -> np.ndarray:
        """Prescribed positions (3, m) of a held end (``"start"``, ``"end"``) at times
        ``ts`` (m), as :meth:`apply` writes them (the outputs report these: a held end is
        where its motion puts it, not where an interpolant of the steps does)."""
        k = 0 if end == "start" else 1
        ts = np.atleast_1d(np.asarray(ts, dtype=float))
        r = np.repeat(self.r_ends[k][:, None], ts.size, axis=1)
        mo = self.ends[k].motion
        if mo is not None and any(mo.translation):
            f = mo.translation_time
            tr = np.asarray(mo.translation)
            for j, t in enumerate(ts):
                r[:, j] = self.r_ends[k] + 1.0 * tr * f.value_at(float(t))
        return r

    def rotates(self, end: str) -> bool:
        """Whether the frame of held end ``end`` (``"start"``, ``"end"``) turns with time
        (a prescribed rotation; :meth:`apply` writes the same frame at every t otherwise)."""
        mo = self.ends[0 if end == "start" else 1].motion
        return mo is not None and mo.rotation_angle != 0.0

    def steady_interval(self, t: float) -> tuple[float, float]:
        """``(a, b)``, ``a <= t < b``: an interval on which every load and end motion is
        constant (the arrays written at ``t`` hold on all of it); empty when something
        varies at ``t``."""
        a, b = -np.inf, np.inf
        funcs = [ld.time for ld in self.loads]
        funcs += [f for e in self.ends if e.motion is not None
                  for f, on in ((e.motion.translation_time, any(e.motion.translation)),
                                (e.motion.rotation_time, e.motion.rotation_angle != 0.0)) if on]
        funcs += [f for o in self.obstacles for f in o.time_functions()]
        for f in funcs:
            lo, hi = f.constant_interval(t)
            a, b = max(a, lo), min(b, hi)
            if not a <= t < b:
                return t, t
        return a, b

    def apply(self, a: RodArrays, t: float, *, left: bool = False, scale: float = 1.0,
              static: bool = False) -> None:
        grav, dist = np.zeros(3), np.zeros(3)
        N = self.N
        fd, ff = a.node_load("f_dead"), a.node_load("f_follower")
        md, mf = a.segment_load("m_dead"), a.segment_load("m_follower")
        # the moments applied at the end nodes once more on their own (a coupled rod's
        # free-end condensation carries them: docs/design.md, section 10)
        ends = {(0, "dead"): a.param("m_dead_start"),
                (0, "follower"): a.param("m_follower_start"),
                (N, "dead"): a.param("m_dead_end"), (N, "follower"): a.param("m_follower_end")}
        for arr in (fd, ff, md, mf, *ends.values()):
            arr[:] = 0.0
        for ld, node in zip(self.loads, self._nodes, strict=True):
            v = np.asarray(ld.vector) * ld.time.value_at(t, left=left)
            if ld.kind == "gravity":
                grav += v
            elif ld.kind == "distributed":
                dist += v
            elif ld.kind == "force":
                (ff if ld.frame == "follower" else fd)[node] += v
            else:
                target = mf if ld.frame == "follower" else md
                if node in (0, N):
                    ends[node, "follower" if ld.frame == "follower" else "dead"][:] += v
                if node == 0:
                    target[0] += v
                elif node == N:
                    target[N - 1] += v
                else:                 # an interior node: half on each adjacent segment
                    target[node - 1] += 0.5 * v
                    target[node] += 0.5 * v
        a.set_param("gravity", grav)
        a.set_param("f_dist", dist)
        for k, (end, name) in enumerate(zip(self.ends, ("start", "end"), strict=True)):
            if not end.held:
                continue
            r, v, acc = self.r_ends[k].copy(), np.zeros(3), np.zeros(3)
            p, om = self.p_ends[k].copy(), np.zeros(3)
            mo = end.motion
            if mo is not None:
                s = scale if static else 1.0
                tr = np.asarray(mo.translation)
                f = mo.translation_time
                r = r + s * tr * f.value_at(t, left=left)
                if not static:
                    v = tr * f.rate_at(t, left=left)
                    acc = tr * f.accel_at(t, left=left)
                if mo.rotation_angle:
                    ang = np.radians(mo.rotation_angle)
                    axis = np.asarray(mo.rotation_axis)
                    g = mo.rotation_time
                    theta = s * ang * g.value_at(t, left=left)
                    p = quat_mul(quat_exp(theta * axis), p)       # spatial rotation first
                    if not static:
                        om = quat_rotation(p).T @ (axis * ang * g.rate_at(t, left=left))
            a.set_param("r_" + name, r)
            a.set_param("v_" + name, v)
            a.set_param("a_" + name, acc)
            a.set_param("p_" + name, p)
            a.set_param("Omega_" + name, om)
        if a.contact is not None:
            a.contact.set_force_scale(scale if static else 1.0)
            for k, o in enumerate(self.obstacles):
                if o.moves:
                    c, q, v, w = o.pose(t, left=left)
                    if static:
                        v, w = np.zeros(3), np.zeros(3)
                    a.contact.set_pose(k, c, q, v, w)


def reference_arrays(problem: Problem) -> tuple[RodArrays, np.ndarray, np.ndarray, np.ndarray]:
    """(arrays, reference state, end positions (2, 3), end quaternions (2, 4))."""
    from generated import rod_layout as L

    N = problem.rod.elements
    disc = discretize(problem.rod.geometry, N, problem.node_arc_lengths())
    mats = problem.segment_matrices()
    a = RodArrays.zeros(N, len(mats.get("theta", ())))
    h = disc.h
    p_seg = quat_from_matrix(disc.frames)                        # (N, 4)
    p_start = quat_from_matrix(disc.start_frame)
    p_end = quat_from_matrix(disc.end_frame)
    # keep neighbouring quaternions in the same hemisphere (Cayley curvature is sign-safe,
    # but continuity makes the reference readable and the initial guesses smooth)
    for i in range(1, N):
        if np.dot(p_seg[i], p_seg[i - 1]) < 0:
            p_seg[i] = -p_seg[i]
    if np.dot(p_start, p_seg[0]) < 0:
        p_start = -p_start
    if np.dot(p_end, p_seg[-1]) < 0:
        p_end = -p_end
    a.seg_field("h")[:, 0] = h
    a.seg_field("C_F")[:] = mats["C_F"]
    a.seg_field("V_F")[:] = mats["V_F"]
    a.seg_field("rhoA")[:, 0] = mats["rhoA"]
    a.seg_field("rhoI")[:] = mats["rhoI"]
    R = quat_rotation(p_seg)
    chord = np.diff(disc.nodes, axis=0)
    V0 = np.einsum("nji,nj->ni", R, chord) / h[:, None]
    if isinstance(problem.rod.geometry, Straight):
        # the chords of a straight rod are its tangent: V0 = e3 exactly (the rounding of
        # the node coordinates would otherwise leave a round-off prestress)
        V0 = np.tile([0.0, 0.0, 1.0], (N, 1))
    a.seg_field("V0")[:] = V0
    hj = np.empty(N + 1)
    hj[1:-1] = 0.5 * (h[:-1] + h[1:])
    hj[0], hj[-1] = 0.5 * h[0], 0.5 * h[-1]
    a.jnt_field("h")[:, 0] = hj
    a.jnt_field("C_M")[:], a.jnt_field("V_M")[:] = joint_series(mats["C_M"], mats["V_M"], h)
    if a.branches:            # generalized Maxwell: the rod's relaxation terms
        a.theta[:] = mats["theta"]
        a.segb[:] = mats["segb"]
        a.jntb[:] = joint_average(mats["jntb"])
    U0 = np.zeros((N + 1, 3))
    if N > 1:
        U0[1:-1] = cayley_curvature(p_seg[:-1], p_seg[1:], hj[1:-1])
    U0[0] = cayley_curvature(p_start, p_seg[0], hj[0])
    U0[-1] = cayley_curvature(p_seg[-1], p_end, hj[-1])
    a.jnt_field("U0")[:] = U0
    a.set_param("load_scale", 1.0)
    for name, end in (("start", problem.start), ("end", problem.end)):
        a.set_param("fix_" + name, float(end.held))
        a.set_param("clamp_" + name, float(end.clamped))
    a.set_param("r_start", disc.nodes[0])
    a.set_param("r_end", disc.nodes[-1])
    a.set_param("p_start", p_start)
    a.set_param("p_end", p_end)
    if "K6" in mats:          # coupled sections: the coupled kernels (docs/design.md, 10)
        a = coupled_arrays(a, mats["K6"], mats["V6"], mats["rhoJ"], mats["mass_centre"])
    if problem.has_contact:
        a.contact = contact_arrays(problem, h)
    B = a.branches
    y = np.zeros(L.n_state(N, B))         # at rest, stress free: internal strains 0
    y[layout_blocks(lambda i: L.node_phi(i, B), 0, N, 3)] = disc.nodes
    y[layout_blocks(lambda i: L.segment_p(i, B), 1, N, 4)] = p_seg
    return a, y, np.array([disc.nodes[0], disc.nodes[-1]]), np.array([p_start, p_end])


def obstacle_parameters(o: Obstacle, radius: float, delta: float) -> tuple[int, np.ndarray]:
    """(kernel kind, parameters ``OBS_PARAMS``) of an obstacle at its reference pose: its
    frame's origin at its point (a sphere's centre), its shape in that frame; ``radius``
    (m): the largest contact radius of the rods that touch it, ``delta`` (m) the smallest
    smoothing length: a capped cylinder's rims are rounded over ``sqrt(radius delta)``
    (their error at the rod's surface then stays below delta: derive.contact), a pipe's
    open end switches the contact off over one rod radius."""
    from generated import rod_layout as L
    from runtime.model.contact import KINDS

    kind = "pipe" if o.kind == "cylinder" and o.inside else o.kind
    par = np.zeros(L.N_OBS)
    put = lambda name, v: par.__setitem__(  # noqa: E731
        slice(L.OBS_OFFSETS[name], L.OBS_OFFSETS[name] + np.size(v)), np.ravel(v))
    put("c", o.centre)
    put("q", (1.0, 0.0, 0.0, 0.0))
    if o.direction is not None:
        put("axis", o.direction)
    if o.radius is not None:
        put("radius", o.radius)
    if o.kind == "cylinder":
        put("length", o.length if o.length is not None else 0.0)
        if o.length is not None:
            put("edge", radius if o.inside else math.sqrt(radius * delta))
    return KINDS.index(kind), par


def contact_arrays(problem: Problem, h: np.ndarray) -> ContactArrays:
    """The contact of a rod with its problem's obstacles (``runtime.model.contact``): per
    obstacle its kernel and parameters (:func:`obstacle_parameters`; the pose of t = 0),
    per obstacle and segment the law of :meth:`Problem.contact_law` (k, delta, the
    segment's normal damping, the obstacle's friction, the slip velocity, the segment's
    contact radius and length ``h`` (N,), m), the contact's rate ``sqrt(k / rho A)``
    (the slowest segment's) for the error test's tolerances near obstacles; with
    ``contact.self`` the same per segment
    for the rod's contact with itself
    (``runtime.model.contact.SelfContactArrays``, with the rods' friction)."""
    from generated import rod_layout as L

    law = problem.contact_law()
    N = h.size
    kinds, obs = [], []
    for o in problem.obstacles:
        kind, par = obstacle_parameters(o, float(np.max(law.radius)), law.penetration)
        kinds.append(kind)
        obs.append(par)
    cnt = np.zeros((len(kinds), N, L.N_CNT))
    for k, o in enumerate(problem.obstacles):
        for name, value in (("k", law.stiffness), ("delta", law.penetration),
                            ("c", law.damping), ("mu", o.friction),
                            ("v_s", law.slip_velocity), ("r", law.radius), ("h", h)):
            cnt[k, :, L.CNT_OFFSETS[name]] = value
    self_contact = None
    if law.self_contact:
        seg = np.zeros((N, L.N_CNT))
        for name, v in (("k", law.stiffness), ("delta", law.self_penetration),
                        ("c", law.damping),
                        ("mu", law.friction), ("v_s", law.slip_velocity),
                        ("r", law.radius), ("h", h)):
            seg[:, L.CNT_OFFSETS[name]] = v
        self_contact = SelfContactArrays(seg)
    # the contact's rate sqrt(k / rho A), the slowest over the segments: the error
    # test's velocity tolerances near an obstacle (rod_contact.h)
    rate = 0.0
    if kinds:
        rhoA = np.asarray(problem.segment_matrices()["rhoA"], dtype=float)
        rate = float(np.min(np.sqrt(np.broadcast_to(law.stiffness, rhoA.shape) / rhoA)))
    arrays = ContactArrays(np.array(kinds, dtype=np.int32).reshape(-1),
                           np.array(obs, dtype=float).reshape(-1, L.N_OBS), cnt,
                           self_contact=self_contact, tolerance_rate=rate)
    for k, o in enumerate(problem.obstacles):
        c, q, v, w = o.pose(0.0)
        arrays.set_pose(k, c, q, v, w)
    return arrays


def build_model(problem: Problem, backend: str = "auto") -> RodModel:
    """The discrete rod of a problem, over the compiled kernels (see the module docstring).

    Parameters
    ----------
    problem : Problem
        The rod problem.
    backend : {"auto", "c", "casadi"}
        ``"c"``: the generated C assembly through ctypes (compiled on first use, cached);
        ``"casadi"``: the CasADi MX assembly (no compiler needed); ``"auto"``: C when a
        compiler is available.

    Returns
    -------
    RodModel
        Residual, band Jacobian, energies and diagnostics of the rod, driven by the
        problem's loads and end motion.
    """
    arrays, y_ref, r_ends, p_ends = reference_arrays(problem)
    drive = ProblemDrive(problem, arrays.N, r_ends, p_ends)
    return RodModel(arrays, y_ref, drive=drive, backend=backend)


def build_assembly_rod(problem: Problem, backend: str = "auto"
                       ) -> tuple[RodModel, SelfContactArrays | None]:
    """A rod of an assembly (:func:`build_model`) and, with ``contact.self``, its law for
    the contact between the assembly's rods (``SelfContactArrays`` of its segments),
    taken out of the rod: the system pairs every rod's segments with every other's and
    its own (``runtime.model.system.SystemModel``'s ``pairs``)."""
    arrays, y_ref, r_ends, p_ends = reference_arrays(problem)
    law = None
    c = arrays.contact
    if c is not None and c.self_contact is not None:
        law = c.self_contact
        arrays.contact = ContactArrays(c.kind, c.obs, c.cnt, c.step_fraction)
    drive = ProblemDrive(problem, arrays.N, r_ends, p_ends)
    return RodModel(arrays, y_ref, drive=drive, backend=backend), law
