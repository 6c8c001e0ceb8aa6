"""Statics and runs of an assembly of rods (issue 31; docs/design.md, section 12).

The same run as a single rod's (:mod:`runtime.simulate.simulate`): the static equilibrium
under the loads at ``t = 0-`` (or the reference at rest), consistent initial values, the
run loop with the energy audit, output samples, maxima, centreline frames (with the
bodies' mass centres) and full-state snapshots (VTK), on the assembly's
:class:`~runtime.model.system.SystemModel`. Outputs name the rods: each rod's end
positions (``NAME/start``, ``NAME/end``), node positions (``NAME/positions``), and every
joint's force and moment on the rod of its first point, every body's position.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from runtime.analysis.audit import audit_run, significant_maxima
from runtime.analysis.decay import beat_warning, damping_ratios, log_decrements, periods
from runtime.errors import IllPosedError
from runtime.model.contact import N_VALUES, obstacle_series
from runtime.model.quaternion import quat_rotation
from runtime.model.system_statics import SystemStatics
from runtime.problem.assemble_system import AssemblyMap, build_system, frames_of
from runtime.simulate.observers import (
    Centreline,
    EnergyIntegrator,
    Maxima,
    Progress,
    Sampler,
    Snapshots,
)
from runtime.simulate.simulate import (
    ATOL_FLOOR,
    ATOL_FRACTION,
    ErrorControl,
    obstacle_summary,
    self_contact_summary,
)
from runtime.simulate.vibration_centre import VibrationCentre, inputs_constant
from runtime.solvers.driver import run_loop
from runtime.solvers.initial import consistent_initial
from runtime.solvers.statics import StaticSolveError, solve_static


@dataclass
class AssemblyStatic:
    """An assembly's static equilibrium: state, Newton iterations, wall time."""

    y: np.ndarray
    iterations: int
    per_step: list[int]
    wall_time_s: float


@dataclass
class AssemblyResult:
    """Everything a run of an assembly computed (also when it failed part-way)."""

    problem: Any
    status: str = "running"
    message: str = ""
    amap: AssemblyMap | None = None
    static: AssemblyStatic | None = None
    t: np.ndarray = field(default_factory=lambda: np.zeros(0))
    #: "NAME/start", "NAME/end": (3, n) positions (m) on the output grid
    ends: dict[str, np.ndarray] = field(default_factory=dict)
    kinetic: np.ndarray = field(default_factory=lambda: np.zeros(0))
    elastic: np.ndarray = field(default_factory=lambda: np.zeros(0))
    dissipated: np.ndarray = field(default_factory=lambda: np.zeros(0))
    external_work: np.ndarray = field(default_factory=lambda: np.zeros(0))
    extras: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    maxima_t: np.ndarray = field(default_factory=lambda: np.zeros(0))
    maxima_x: np.ndarray = field(default_factory=lambda: np.zeros(0))
    peaks_t: np.ndarray = field(default_factory=lambda: np.zeros(0))
    peaks_x: np.ndarray = field(default_factory=lambda: np.zeros(0))
    centre: VibrationCentre | None = None
    counters: dict[str, int] = field(default_factory=dict)
    wall_time_s: float = 0.0
    t_last: float = 0.0
    y_last: np.ndarray | None = None
    atol: np.ndarray | None = None
    interrupt: BaseException | None = None
    centreline_t: np.ndarray = field(default_factory=lambda: np.zeros(0))
    #: per rod: (m, 3, N+1) node positions at the centreline frame times
    centreline: dict[str, np.ndarray] = field(default_factory=dict)
    #: per body (file order): (m, 3) mass-centre positions at the centreline frame times
    body_centreline: list[np.ndarray] = field(default_factory=list)
    #: ``(t, y, yp)`` every ``snapshot_every`` seconds when no sink took them
    snapshots: list = field(default_factory=list)

    @property
    def model(self):
        return None if self.amap is None else self.amap.model

    def audit(self):
        floor = self.model.energy_floor() if self.model is not None else 0.0
        return audit_run(self.kinetic, self.elastic, self.dissipated, self.external_work,
                         floor)

    # -- joints and bodies ------------------------------------------------------------------
    def joint_series(self) -> list[dict[str, np.ndarray]]:
        """Per joint (file order): ``force`` and ``moment`` (3, n) that it exerts on the rod
        of its first point (N, N m about that point, spatial)."""
        return joint_forces(self.amap, self.extras)

    def obstacle_series(self) -> list[dict[str, np.ndarray]]:
        """Per obstacle (file order): its values on the output grid, summed over the rods
        (:func:`runtime.model.contact.obstacle_series`: ``force``, ``moment`` (3, n; N,
        N m about its point, on the rods, spatial), ``energy``, ``dissipation``,
        ``friction_dissipation``, ``power``, ``gap_min``, ``segments`` (n,))."""
        model = self.model
        if model is None or not model.n_obstacles or self.extras.shape[0] == 0:
            return []
        first = model.extras_layout()["obstacle:0"].start - 5
        return obstacle_series(self.extras[first:first + N_VALUES * model.n_obstacles])

    def self_contact_series(self) -> dict[str, np.ndarray]:
        """With ``contact.self``: the pairs' values (n,) on the output grid
        (``runtime.model.contact.SELF_VALUE_NAMES``: energy, dissipation, its friction
        part, smallest gap, pairs in reach, the sum of their forces' magnitudes); empty
        without."""
        from runtime.model.contact import SELF_VALUE_NAMES

        lay = None if self.model is None else self.model.extras_layout()
        if lay is None or "self_contact" not in lay or self.extras.ndim != 2:
            return {}
        s = lay["self_contact"]
        block = self.extras[s.start - 5:s.stop - 5]
        return dict(zip(SELF_VALUE_NAMES, block, strict=True))

    def summary(self) -> dict:
        """JSON-ready summary: status, static result, maxima and decrements, energy audit,
        joints, bodies, obstacles, contact between the rods, warnings, counters."""
        p = self.problem
        warnings: list[str] = []
        pk: dict = {"peaks": [{"t": float(a), "x": float(b)}
                              for a, b in zip(self.peaks_t, self.peaks_x, strict=True)]}
        if self.centre is not None and self.centre.warning:
            warnings.append(self.centre.warning)
        if self.peaks_x.size >= 2:
            n_sig = significant_maxima(self.peaks_x, self.noise_level())
            dl = log_decrements(self.peaks_x[:max(n_sig, 2)])
            z = damping_ratios(dl)
            pk.update(log_decrements=dl.tolist(), damping_ratios=z.tolist(),
                      periods=periods(self.peaks_t[:max(n_sig, 2)]).tolist())
            beat = beat_warning(z, p.analysis.maxima)
            if beat:
                warnings.append(beat)
        else:
            pk.update(log_decrements=[], damping_ratios=[], periods=[])
        audit = self.audit()
        warnings += audit.warnings
        if p.simulation.rtol > 1e-3:
            warnings.append(f"rtol = {p.simulation.rtol:g} is loose: expect errors of that "
                            "order")
        joints = []
        series = self.joint_series() if self.t.size else []
        for k, jt in enumerate(p.joints):
            entry: dict[str, Any] = {"index": k, "kind": jt.kind,
                                     "between": [jt.first.label, "ground" if jt.second is None
                                                 else jt.second.label]}
            if series:
                for what in ("force", "moment"):
                    v = series[k][what]
                    mag = np.linalg.norm(v, axis=0)
                    i = int(np.nanargmax(mag)) if np.any(np.isfinite(mag)) else 0
                    entry[what] = {"final": [float(x) for x in v[:, -1]],
                                   "max_norm": float(mag[i]), "t_of_max": float(self.t[i])}
            note = self.amap.joints[k].note if self.amap is not None else ""
            if note:
                entry["note"] = note
            joints.append(entry)
        bodies = {}
        if self.amap is not None and self.y_last is not None:
            for b, body in zip(p.bodies, self.model.bodies, strict=True):
                bodies[b.name] = body_state(self.model, body, self.y_last)
        return {
            "status": self.status,
            "message": self.message,
            "problem": p.name,
            "assembly": {"rods": list(p.rods), "joints": len(p.joints),
                         "bodies": len(p.bodies)},
            "parameters": p.to_mapping(),
            "static": None if self.static is None else {
                "newton_iterations": int(self.static.iterations),
                "newton_iterations_per_load_step": list(self.static.per_step),
                "wall_time_s": self.static.wall_time_s,
                "ends": static_ends(self.amap, self.static.y)},
            **pk,
            "vibration_centre": None if self.centre is None else {
                "coordinate": p.analysis.maxima, **self.centre.to_dict()},
            "energy_balance_max_rel": audit.max_rel,
            "energy_audit": {"applicable": audit.applicable, "max_rel": audit.max_rel,
                             "scale_J": audit.scale, "note": audit.reason},
            "joints": joints,
            "bodies": bodies,
            **({"obstacles": obstacle_summary(p.obstacles, self.t, self.obstacle_series())}
               if p.obstacles else {}),
            **({"self_contact": self_contact_summary(self.t, sc)}
               if (sc := self.self_contact_series()) else {}),
            "ends": {k: [float(x) for x in v[:, -1]] for k, v in self.ends.items()
                     if v.shape[1]},
            "warnings": warnings,
            "t_reached": float(self.t_last),
            "wall_time_s": self.wall_time_s,
            "counters": dict(self.counters),
            "backend": "c",
        }

    def noise_level(self) -> float:
        if self.atol is None or self.amap is None or not self.problem.analysis.maxima:
            return 0.0
        ix, _ = maxima_indices(self.amap, self.problem.analysis.maxima)
        return 1e3 * float(self.atol[ix])


def joint_forces(amap: AssemblyMap | None, extras: np.ndarray) -> list[dict[str, np.ndarray]]:
    """Per joint: the force and moment (3, n) it exerts on the rod of its first point, from
    the sampled extras (the holds' free rows, the links' force and moment on side a)."""
    if amap is None:
        return []
    model = amap.model
    lay = model.extras_layout()
    n = extras.shape[1] if extras.ndim == 2 else 0
    out = []
    for part in amap.joints:
        f, m = np.zeros((3, n)), np.zeros((3, n))
        first = part.first
        for h in part.holds:
            hold = model.holds[h]
            v = extras[lay[f"hold:{h}"].start - 5:lay[f"hold:{h}"].stop - 5]
            if hold.master is None:
                if (hold.rod, hold.node) == (first.rod, first.node):
                    f += v                                 # the support's force on P's rod
            elif (hold.rod, hold.node) == (first.rod, first.node):
                f += v                                     # P is the tied node
            elif tuple(hold.master) == (first.rod, first.node):
                f -= v                                     # the tied node's rod pushes back
        for li in part.links:
            s = lay[f"link:{li}"]
            v = extras[s.start - 5:s.stop - 5]
            f += v[:3]
            m += v[3:]
        out.append({"force": f, "moment": m})
    return out


def body_state(model, body, y: np.ndarray) -> dict:
    """A body's mass-centre position (m) and frame (3x3) at state y."""
    rod = model.rods[body.rod]
    ys = model.rod_state(body.rod, y)
    phi = ys[rod.phi_index[body.node]]
    p = ys[rod.p_index[body.segment - 1]]
    R = quat_rotation(p / np.linalg.norm(p))
    c = phi + R @ np.asarray(body.offset, dtype=float)
    return {"position": [float(v) for v in c],
            "frame": [[float(v) for v in row] for row in R]}


def body_pose_index(model, body) -> np.ndarray:
    """The state indices (7,) of a body's node position (3) and its segment's quaternion
    (4): what :func:`body_centres` needs."""
    return np.concatenate([model.phi_index[body.rod][body.node],
                           model.p_index[body.rod][body.segment - 1]])


def body_centres(model, poses: np.ndarray) -> np.ndarray:
    """Mass-centre positions (m, nb, 3) in m from poses (m, 7, nb) recorded at
    :func:`body_pose_index`: node position + R(p) offset."""
    poses = np.asarray(poses, dtype=float)
    out = np.zeros((poses.shape[0], len(model.bodies), 3))
    for j, body in enumerate(model.bodies):
        e = np.asarray(body.offset, dtype=float)
        for i in range(poses.shape[0]):
            p = poses[i, 3:, j]
            R = quat_rotation(p / np.linalg.norm(p)) if np.all(np.isfinite(p)) else np.eye(3)
            out[i, j] = poses[i, :3, j] + R @ e
    return out


def static_ends(amap: AssemblyMap | None, y: np.ndarray) -> dict[str, list[float]]:
    """Each rod's end positions (m) at state y."""
    if amap is None:
        return {}
    out = {}
    for k, name in enumerate(amap.rod_names):
        rod = amap.model.rods[k]
        ys = amap.model.rod_state(k, y)
        out[f"{name}.start"] = [float(v) for v in ys[rod.phi_index[0]]]
        out[f"{name}.end"] = [float(v) for v in ys[rod.phi_index[-1]]]
    return out


def maxima_indices(amap: AssemblyMap, which: str) -> tuple[int, int]:
    """State indices (position, velocity) of ``NAME.end.x``, ``NAME.start.y`` or
    ``NAME@S.z``."""
    point, comp = which.rsplit(".", 1)
    c = "xyz".index(comp)
    if "@" in point:
        name, s = point.split("@", 1)
        r = amap.rod(name)
        rod = amap.model.rods[r]
        h = rod.arrays.seg_field("h")[:, 0]
        node = int(np.argmin(np.abs(np.concatenate([[0.0], np.cumsum(h)]) - float(s))))
    else:
        name, end = point.rsplit(".", 1)
        r = amap.rod(name)
        node = 0 if end == "start" else amap.model.rods[r].N
    return int(amap.model.phi_index[r][node][c]), int(amap.model.v_index[r][node][c])


def static_equilibrium(problem, amap: AssemblyMap, t: float = 0.0,
                       y_guess: np.ndarray | None = None) -> AssemblyStatic:
    """The assembly's equilibrium under the loads at ``t-`` (by load stepping from the
    reference, or Newton from ``y_guess`` at the full load)."""
    wall0 = time.perf_counter()
    model = amap.model
    st = SystemStatics(model, t)
    with model.statics(t):
        if y_guess is not None:          # Newton at the full load from a nearby state
            res = solve_static(st, st.at_rest(model.constrain(y_guess)), first_load=1.0)
        else:
            y0 = model.initial_state(t)
            try:
                first = st.hold_rigid_motions(y0)
            except IllPosedError:
                # singular where it starts, also loaded: a mechanism its loads hold only
                # once they have moved or stressed it (a pendulum released at an angle, or
                # hanging unstretched): pseudo-transient continuation reaches that state,
                # Newton finishes
                y0 = pseudo_transient(st, y0)
                first = 1.0
            try:
                res = solve_static(st, y0, load_steps=problem.statics.load_steps,
                                   first_load=first)
            except StaticSolveError as exc:
                if any(r.contact is not None for r in model.rods):
                    exc.args = (f"{exc.args[0]}; statics of an assembly on obstacles is "
                                "load stepping only in this version (a single rod on "
                                "obstacles settles by pseudo-transient continuation): "
                                "simulate it to rest instead (simulation.initial = "
                                "\"reference\")",) + exc.args[1:]
                raise
    return AssemblyStatic(res.y.copy(), res.total_iterations, list(res.iterations),
                          time.perf_counter() - wall0)


def pseudo_transient(st: SystemStatics, y0: np.ndarray, tol: float = 1e-8,
                     max_iter: int = 400) -> np.ndarray:
    """A state near the loaded equilibrium of a mechanism whose static stiffness is
    singular at ``y0``, by pseudo-transient continuation with the reduced mass matrix
    (:func:`runtime.solvers.pseudo_transient.pseudo_transient`). Raises
    :class:`~runtime.errors.IllPosedError` when it does not converge."""
    from runtime.analysis.system_modal import linear_matrices
    from runtime.solvers.pseudo_transient import pseudo_transient as ptc

    st.load_scale = 1.0
    M, _, _, _ = linear_matrices(st.model, y0, st.time)
    y, ok = ptc(st, y0, M, tol=tol, max_iter=max_iter)
    if ok:
        return y
    raise IllPosedError(
        "statics of this assembly: its supports leave a rigid motion free that its loads "
        "do not hold (pseudo-transient continuation found no equilibrium); hold it with "
        "a joint to \"ground\" or a clamped or pinned end, or simulate it "
        "(simulation.initial = \"reference\")")


def default_atol(problem, amap: AssemblyMap, y0: np.ndarray) -> np.ndarray:
    """Absolute tolerances per component, as a single rod's
    (:func:`runtime.simulate.simulate.default_atol`): positions by the motion's
    displacement scale d, velocities by d omega, rotations by its rotation scale, angular
    velocities by that times omega, with omega the highest of the rods' first bending
    frequencies and d the largest node displacement of the initial state or of the
    linear static response to the loads (the assembly's length scale if none)."""
    model = amap.model
    Lr = max(p.rod.length for p in problem.rods.values())
    omega = max(p.characteristic_frequency() for p in problem.rods.values())
    d = max(float(np.max(np.linalg.norm(y0[ix] - model.reference[ix], axis=1)))
            for ix in model.phi_index)
    theta = 0.0
    if any(any(ld.load.vector) for ld in problem.loads) and (
            d < 1e-3 * Lr or problem.simulation.initial == "reference"):
        dl = _linear_response(problem)
        d = max(d, dl if dl is not None else Lr)
    theta = max(theta, d / Lr)
    a, f = ATOL_FRACTION * problem.simulation.rtol, ATOL_FLOOR
    d = min(max(d, f * Lr), Lr)
    theta = min(max(theta, f), math.pi)
    atol = np.empty(model.n)
    for k in range(len(model.rods)):
        atol[model.phi_index[k]] = max(a * d, f * Lr)
        atol[model.v_index[k]] = max(a * d * omega, f * Lr * omega)
        atol[model.p_index[k]] = max(a * theta, f)
        atol[model.omega_index[k]] = max(a * theta * omega, f * omega)
        rod = model.rods[k]
        o = int(model.offsets[k])
        atol[rod.q_segment_index.ravel() + o] = max(a * d / Lr, f)
        atol[rod.q_joint_index.ravel() + o] = max(a * theta / Lr, f / Lr)
    return atol


def _linear_response(problem) -> float | None:
    """The largest node displacement (m) of the assembly's linear static response to every
    load at its peak value (one Newton step at the reference); None for a mechanism."""
    T = problem.simulation.t_end
    peak = problem.with_overrides({
        f"loads.{k}.time": {"kind": "constant", "value": float(ld.load.time.peak(T))}
        for k, ld in enumerate(problem.loads)})
    amap = build_system(peak)
    model = amap.model
    st = SystemStatics(model)
    with model.statics():
        y = model.initial_state()
        r = np.empty(st.n_static)
        st.static_residual(y, r)
        lu = st.static_factor(y)
        if lu.info != 0:
            return None
        dx = -lu.solve(r)
    if not np.all(np.isfinite(dx)):
        return None
    y1 = st.static_retract(y, dx)
    return max(float(np.max(np.linalg.norm(y1[ix] - model.reference[ix], axis=1)))
               for ix in model.phi_index)


def error_control(problem, amap: AssemblyMap) -> ErrorControl:
    """The whole state in the error test (Kelvin-Voigt rods); a generalized Maxwell rod in
    the assembly puts the configuration in it and bounds the order by its glassy modes
    (the slowest rate over the rods), as for a single rod."""
    model = amap.model
    rates = [r.glassy_decay_rate() for r in model.rods]
    rate = min((s for s in rates if math.isfinite(s)), default=0.0)
    if rate == 0.0:
        return ErrorControl("state", None, 0.0)
    return ErrorControl("configuration", ~model.velocity_mask, rate)


def simulate_assembly(problem, *, progress=None, checkpoint=None,
                      checkpoint_every: float = 1.0, checkpoint_wall: float = 0.0,
                      resume: dict | None = None,
                      max_steps: int = 2_000_000, amap: AssemblyMap | None = None,
                      sensitivity=None,
                      snapshot_every: float | None = None,
                      snapshot_sink: Callable[[float, np.ndarray, np.ndarray], object]
                      | None = None) -> AssemblyResult:
    """Run an assembly problem (see the module docstring); never raises for a failed
    solve: the result says why and keeps what was computed. ``sensitivity``: forward
    sensitivities to carry (``runtime.simulate.assembly_sensitivity``), their channels in
    ``sensitivity.collected``.

    ``snapshot_every`` (s): the whole state and its rate every this many seconds, handed
    to ``snapshot_sink(t, y, yp)`` as the run reaches them (for VTK:
    :class:`runtime.io.assembly_vtk.AssemblyVtk`; default: kept in
    ``result.snapshots``); a resumed run continues where the checkpoint's left off.

    ``checkpoint(state)`` is called every ``checkpoint_every`` simulated seconds, but only
    once ``checkpoint_wall`` seconds of wall time have passed since the previous one (the
    first since the integration started; 0: at every ``checkpoint_every``), as in
    :func:`runtime.simulate.simulate.simulate` (:func:`~runtime.solvers.driver.run_loop`)."""
    sim = problem.simulation
    res = AssemblyResult(problem=problem)
    wall0 = time.perf_counter()
    if amap is None:
        amap = build_system(problem)
    res.amap = amap
    model = amap.model
    if sensitivity is not None:
        if resume is not None:
            raise ValueError("sensitivities of a resumed run are not kept in checkpoints")
        sensitivity.prepare(model)
    t_out = np.arange(0.0, sim.t_end + 0.5 * sim.output_step, sim.output_step)
    t_out = t_out[t_out <= sim.t_end]
    energy = EnergyIntegrator(model)
    channels = {}
    for k, name in enumerate(amap.rod_names):
        channels[f"{name}/start"] = model.phi_index[k][0]
        channels[f"{name}/end"] = model.phi_index[k][-1]
    sampler = Sampler(model, energy, t_out, channels, n_extras=model.nextra)
    observers: list = [sampler, energy]
    maxima = None
    if problem.analysis.maxima:
        ix, iv = maxima_indices(amap, problem.analysis.maxima)
        maxima = Maxima(ix, iv, offset=float(model.reference[ix]), positive_only=False)
        observers.append(maxima)
    if snapshot_every is not None:
        observers.append(Snapshots(snapshot_every, snapshot_sink or (
            lambda t, y, yp: res.snapshots.append((t, y, yp)))))
    centreline = poses = None
    if sim.centreline_frames:
        t_frames = np.linspace(0.0, sim.t_end, sim.centreline_frames)
        centreline = Centreline(t_frames, np.concatenate(model.phi_index))
        observers.append(centreline)
        if model.bodies:
            poses = Centreline(t_frames, np.stack([body_pose_index(model, b)
                                                   for b in model.bodies]), key="body_poses")
            observers.append(poses)
    if progress is not None:
        observers.append(Progress(progress))
    counters0: dict[str, int] = {}
    if resume is None:
        if sim.initial == "static":
            try:
                res.static = static_equilibrium(problem, amap)
            except (StaticSolveError, ValueError) as exc:
                res.status, res.message = "failed", f"static solve failed: {exc}"
                res.y_last = getattr(exc, "y", None)
                res.wall_time_s = time.perf_counter() - wall0
                return res
            y0 = model.relaxed(res.static.y)
        else:
            y0 = model.initial_state(0.0)
        model.enter_piece(0.0, math.inf)
        model.at(0.0)
        y0 = model.constrain(y0)
        y0, yp0 = consistent_initial(model, 0.0, y0, np.zeros(model.n))
        yp0 = model.prescribed_rates(0.0, yp0)
        t_start = 0.0
        sens_options = {}
        if sensitivity is not None:
            s0 = sensitivity.initial(model, res.static.y if res.static is not None else None)
            model.at(0.0)
            sens_options = sensitivity.options(model, 0.0, y0, yp0, s0)
    else:
        t_start, y0, yp0 = float(resume["t"]), np.array(resume["y"]), np.array(resume["yp"])
        if y0.shape != (model.n,):
            raise ValueError(f"the checkpoint's state has {y0.size} entries, this assembly "
                             f"needs {model.n}: a checkpoint of another problem")
        for o in observers:
            if hasattr(o, "restore"):
                o.restore(resume)
        counters0 = {k: int(v) for k, v in dict(resume["counters"]).items()}
    atol = sim.atol if sim.atol is not None else default_atol(
        problem, amap, res.static.y if res.static is not None else y0)
    res.atol = np.broadcast_to(np.asarray(atol, dtype=float), (model.n,)).copy()
    control = error_control(problem, amap)
    out = run_loop(model, t_start, y0, yp0, sim.t_end, rtol=sim.rtol, atol=atol,
                   observers=observers, min_step=sim.min_step,
                   max_order=sim.max_order or 5, max_steps=max_steps,
                   checkpoint=checkpoint, checkpoint_every=checkpoint_every,
                   checkpoint_wall=checkpoint_wall,
                   counters0=counters0, describe_dof=model.describe_dof,
                   solver_options={"error_mask": control.error_mask,
                                   "stiff_decay_rate": control.stiff_decay_rate,
                                   **(sens_options if resume is None else {})})
    res.status, res.message, res.interrupt = out.status, out.message, out.interrupt
    res.t_last, res.y_last, res.counters = out.t_last, out.y_last, out.counters
    a = sampler.arrays()
    res.t = a["t"]
    res.ends = {k: a[k] for k in channels}
    res.kinetic, res.elastic = a["kinetic"], a["elastic"]
    res.dissipated, res.external_work = a["dissipated"], a["external_work"]
    res.extras = a["extras"]
    if centreline is not None:
        t_c, pos = centreline.arrays()
        res.centreline_t = t_c
        k0 = 0
        for k, name in enumerate(amap.rod_names):
            n_nodes = model.rods[k].N + 1
            res.centreline[name] = pos[:, :, k0:k0 + n_nodes]
            k0 += n_nodes
    if poses is not None:
        c = body_centres(model, poses.arrays()[1])
        res.body_centreline = [c[:, j] for j in range(c.shape[1])]
    if maxima is not None and res.y_last is not None:
        res.maxima_t, res.maxima_x = np.array(maxima.t), np.array(maxima.x)
        _centre_maxima(res, problem, amap)
    if sensitivity is not None:
        sensitivity.collected = sensitivity.collect(res, a, centreline, res.counters, amap)
    res.wall_time_s = time.perf_counter() - wall0
    return res


def _centre_maxima(res: AssemblyResult, problem, amap: AssemblyMap) -> None:
    """The maxima as amplitudes about the equilibrium the assembly vibrates about (as
    :meth:`SimulationResult.centre_maxima`)."""
    if res.maxima_t.size == 0:
        return
    model = amap.model
    ix, _ = maxima_indices(amap, problem.analysis.maxima)
    initial = res.maxima_t[0] == 0.0
    t_first = float(res.maxima_t[1 if initial and res.maxima_t.size > 1 else 0])
    ref = float(model.reference[ix])
    if _unloaded(problem, res.t_last):
        res.centre = VibrationCentre(0.0, "reference")
    elif not inputs_constant(model, t_first, res.t_last):
        res.centre = VibrationCentre(float(res.y_last[ix]) - ref, "final state",
                                     f"loads still change after the first maximum (t = "
                                     f"{t_first:.4g} s): the decrements are taken about the "
                                     "run's final state and are doubtful")
    else:
        try:
            st = static_equilibrium(problem, amap, res.t_last, res.y_last)
            res.centre = VibrationCentre(float(st.y[ix]) - ref, "static equilibrium")
        except (StaticSolveError, ValueError) as exc:
            res.centre = VibrationCentre(float(res.y_last[ix]) - ref, "final state",
                                         f"no static equilibrium under the loads left "
                                         f"({str(exc).splitlines()[0]}): the decrements are "
                                         "taken about the run's final state")
    a = res.maxima_x - res.centre.value
    keep = a > 0.0
    if initial and not inputs_constant(model, 0.0, t_first):
        keep[0] = False
    res.peaks_t, res.peaks_x = res.maxima_t[keep], a[keep]


def _unloaded(problem, t: float) -> bool:
    """No load acts at t and no rod's end moves away (the reference is the equilibrium)."""
    if any(any(ld.load.vector) and ld.load.time.value_at(t) != 0.0 for ld in problem.loads):
        return False
    for rod in problem.rods.values():
        for end in (rod.start, rod.end):
            mo = end.motion
            if mo is not None and ((any(mo.translation) and mo.translation_time.value_at(t))
                                   or (mo.rotation_angle and mo.rotation_time.value_at(t))):
                return False
    return True


def frame_at(amap: AssemblyMap, label: str, y: np.ndarray) -> np.ndarray:
    """The frame (3x3) at a named point."""
    p = amap.points[label]
    return frames_of(amap.model, p.rod, p.segments, y)
