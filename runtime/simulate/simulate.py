"""``simulate(problem)``: the one way any rod problem is run.

Static equilibrium under the loads at ``t = 0-`` (Newton with load stepping; or the
stress-free reference at rest when ``simulation.initial = "reference"``), consistent
initial values, then the run loop (``runtime.solvers.driver``) with its observers:
output samples of both ends and of the energies, the running integrals of the dissipated
power and the external power (prescribed end motion included) for the energy audit,
maxima of one end coordinate (``analysis.maxima``), VTK snapshots, progress and
checkpoints. Failures never lose what was computed: a failed static solve or integration
returns a :class:`SimulationResult` with status "failed", the message and everything up to
the last accepted step; an interruption returns status "interrupted" and the exception in
``result.interrupt`` (the caller saves the results and re-raises it).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np

from runtime.analysis.audit import audit_run, significant_maxima
from runtime.analysis.decay import beat_warning, damping_ratios, log_decrements, periods
from runtime.model.quaternion import quat_log, quat_mul, quat_rotation
from runtime.model.rod import RodModel
from runtime.model.statics import RodStatics, largest_displacement
from runtime.problem.assemble import build_model
from runtime.problem.schema import Problem
from runtime.problem.timefunctions import TimeFunction
from runtime.simulate.observers import (
    Centreline,
    EnergyIntegrator,
    Maxima,
    Progress,
    Sampler,
    Snapshots,
)
from runtime.simulate.vibration_centre import (
    VibrationCentre,
    inputs_constant,
    vibration_centre,
)
from runtime.solvers.driver import run_loop
from runtime.solvers.initial import consistent_initial
from runtime.solvers.statics import StaticSolveError, solve_static

#: default absolute tolerance per field, relative to rtol x the field's motion scale
ATOL_FRACTION = 1e-3
#: lower bound of the absolute tolerances relative to the field's size (round-off)
ATOL_FLOOR = 1e4 * float(np.finfo(float).eps)


@dataclass
class StaticOutcome:
    """The static solve of a run: state, end position, Newton iterations, wall time, and
    the load path: ``path`` = [(load factor, s = L end position)] at ``statics.report``
    and at the full load."""

    y: np.ndarray
    tip: np.ndarray
    iterations: int
    per_step: list[int]
    wall_time_s: float
    path: list[tuple[float, np.ndarray]] = field(default_factory=list)
    #: per held end: the support's "force" (N) and "moment" (N m, about the node), spatial
    reactions: dict[str, dict[str, np.ndarray]] = field(default_factory=dict)
    #: director frames (3, 3) at s = 0 ("start") and s = L ("end")
    end_frames: dict[str, np.ndarray] = field(default_factory=dict)
    #: the gauge that held free rigid motions (runtime.model.rigid), in words, or None
    gauge: str | None = None
    #: for a rod held at both ends: the node that moved most (largest_displacement)
    largest: dict | None = None

    def path_table(self) -> list[dict]:
        return load_path_table(self.path)


def load_path_table(path: list[tuple[float, np.ndarray]]) -> list[dict]:
    """A static load path for JSON: [{"load_factor": f, "tip": [x, y, z] (m)}]."""
    return [{"load_factor": float(f), "tip": [float(v) for v in tip]} for f, tip in path]


@dataclass
class SimulationResult:
    """Everything a run computed (also when it failed or was interrupted part-way).

    Series on the output grid ``t`` (s): ``tip`` / ``start`` (3, n) positions of the
    s = L and s = 0 ends (m), ``kinetic``, ``elastic`` energies and the running
    ``dissipated`` energy int 2D and ``external_work`` int P (J); ``peaks_t``, ``peaks_x``:
    maxima of ``analysis.maxima`` above the equilibrium the rod vibrates about, as
    amplitudes about it (m; :attr:`centre`, the displacement of that equilibrium from the
    reference);
    ``centreline_t`` (m,) and ``centreline`` (m, 3, N+1): node positions (m) at the
    ``simulation.centreline_frames`` frame times reached.
    """

    problem: Problem
    status: str = "running"
    message: str = ""
    static: StaticOutcome | None = None
    t: np.ndarray = field(default_factory=lambda: np.zeros(0))
    tip: np.ndarray = field(default_factory=lambda: np.zeros((3, 0)))
    start: np.ndarray = field(default_factory=lambda: np.zeros((3, 0)))
    kinetic: np.ndarray = field(default_factory=lambda: np.zeros(0))
    elastic: np.ndarray = field(default_factory=lambda: np.zeros(0))
    dissipated: np.ndarray = field(default_factory=lambda: np.zeros(0))
    external_work: np.ndarray = field(default_factory=lambda: np.zeros(0))
    peaks_t: np.ndarray = field(default_factory=lambda: np.zeros(0))
    peaks_x: np.ndarray = field(default_factory=lambda: np.zeros(0))
    #: every maximum of ``analysis.maxima`` (times, s; displacements from the reference, m)
    maxima_t: np.ndarray = field(default_factory=lambda: np.zeros(0))
    maxima_x: np.ndarray = field(default_factory=lambda: np.zeros(0))
    #: the value the maxima vibrate about (``runtime.simulate.vibration_centre``)
    centre: VibrationCentre | None = None
    #: per held end ("start", "end"): the support's "force" (N) and "moment" (N m, about
    #: the held node) on the rod, spatial, (3, n) on the output grid (inertia included)
    reactions: dict[str, dict[str, np.ndarray]] = field(default_factory=dict)
    #: per obstacle (in file order): its "force" (N) and "moment" (N m, about its point)
    #: on the rod, spatial, (3, n), and the contact's "energy" (J), "dissipation" and
    #: "friction_dissipation" (W), the "power" of its motion on the rod (W), the smallest
    #: "gap_min" (m, negative: penetration) and the "segments" in reach, (n,), on the
    #: output grid (runtime.model.contact.VALUE_NAMES)
    obstacles: list[dict[str, np.ndarray]] = field(default_factory=list)
    #: with ``contact.self``: the pairs' "energy" (J), "dissipation" and
    #: "friction_dissipation" (W), smallest "gap_min" (m; inf: no pair in reach), number
    #: of "pairs" in reach and the sum of their forces' magnitudes "force" (N), (n,) on
    #: the output grid (runtime.model.contact.SELF_VALUE_NAMES); empty without
    self_contact: dict[str, np.ndarray] = field(default_factory=dict)
    #: unit quaternions (4, n) of the frames at s = 0 ("start") and s = L ("end")
    end_quaternions: dict[str, np.ndarray] = field(default_factory=dict)
    counters: dict[str, int] = field(default_factory=dict)
    wall_time_s: float = 0.0
    t_last: float = 0.0
    y_last: np.ndarray | None = None
    atol: np.ndarray | None = None
    #: what the error test controlled (``error_control``)
    control: ErrorControl | None = None
    model: RodModel | None = None
    interrupt: BaseException | None = None
    snapshots: list = field(default_factory=list)
    centreline_t: np.ndarray = field(default_factory=lambda: np.zeros(0))
    centreline: np.ndarray = field(default_factory=lambda: np.zeros((0, 3, 0)))

    def finished(self, what: str) -> SimulationResult:
        """This result if the run finished; the interrupt (Ctrl-C, SIGTERM) that stopped it
        raised again; otherwise RuntimeError("``what`` failed: ``message``"). For callers
        that need a whole run (a fit, a study of one case): an interrupted run is no failed
        one."""
        if self.interrupt is not None:
            raise self.interrupt
        if self.status != "finished":
            raise RuntimeError(f"{what} failed: {self.message}")
        return self

    @property
    def y_static(self) -> np.ndarray | None:
        return None if self.static is None else self.static.y

    @property
    def static_tip(self) -> np.ndarray | None:
        return None if self.static is None else self.static.tip

    def audit(self):
        """The energy audit (``runtime.analysis.audit.audit_run``)."""
        floor = self.model.energy_floor() if self.model is not None else 0.0
        return audit_run(self.kinetic, self.elastic, self.dissipated, self.external_work,
                         floor)

    @property
    def energy_balance_rel(self) -> np.ndarray:
        """(T + W + int 2D - int P - E0) / E_scale on the output grid (zeros when the run
        holds no energy)."""
        return self.audit().relative

    def centre_maxima(self) -> None:
        """The amplitudes of the maxima about the vibration's centre: ``peaks_t``,
        ``peaks_x`` are the maxima above the equilibrium the rod vibrates about, minus its
        value (``runtime.simulate.vibration_centre.vibration_centre``)."""
        if self.model is None or not self.problem.analysis.maxima or self.y_last is None:
            return
        if self.maxima_t.size == 0:
            self.peaks_t, self.peaks_x = np.zeros(0), np.zeros(0)
            return
        ix = _maxima_indices(self.model, self.problem.analysis.maxima)[0]
        # the start at rest (recorded as a candidate: it is a maximum when it lies above
        # the centre) does not open the vibration's window: the loads may act after it
        initial = self.maxima_t[0] == 0.0
        t_first = float(self.maxima_t[1 if initial and self.maxima_t.size > 1 else 0])
        self.centre = vibration_centre(self.problem, self.model, ix, t_first,
                                       float(self.t_last), self.y_last)
        a = self.maxima_x - self.centre.value
        keep = a > 0.0
        if initial and not inputs_constant(self.model, 0.0, t_first):
            keep[0] = False      # loads acted after the start: not a free decay from it
        self.peaks_t, self.peaks_x = self.maxima_t[keep], a[keep]

    def noise_level(self) -> float:
        """Amplitude below which maxima are the integrator's round-off (1e3 atol)."""
        if self.atol is None or self.model is None or not self.problem.analysis.maxima:
            return 0.0
        idx = _maxima_indices(self.model, self.problem.analysis.maxima)[0]
        return 1e3 * float(np.broadcast_to(self.atol, (self.model.n,))[idx])

    def end_frames(self) -> dict[str, np.ndarray]:
        """Director frames (n, 3, 3) (columns d1, d2, d3) at s = 0 and s = L."""
        return {end: quat_rotation(q.T) for end, q in self.end_quaternions.items()}

    def end_rotations(self, last: bool = False) -> dict[str, np.ndarray]:
        """Rotation vectors (3, n) (rad, spatial: angle times axis) that take each end's
        reference frame to its frame at the output times; ``last``: at the last output
        time alone, (3, 1) (the summary's; the same values, sample by sample)."""
        if self.model is None or not self.end_quaternions:
            return {}
        ref = reference_end_quaternions(self.model)
        conj = np.array([1.0, -1.0, -1.0, -1.0])
        return {end: quat_log(quat_mul((q[:, -1:] if last else q).T, ref[end] * conj)).T
                for end, q in self.end_quaternions.items()}

    def input_warnings(self) -> list[str]:
        """Doubts about how the run saw its inputs and its outputs: loads or end motion
        that acted but left no measurable energy, an output step too coarse for the first
        mode, a requested peak analysis that found no maxima (and why)."""
        out = []
        p = self.problem
        if self.t.size < 2:
            return out
        inputs = any(any(ld.vector) for ld in p.loads) or any(
            e.motion is not None and e.motion.moves for e in (p.start, p.end))
        if inputs and not self.audit().applicable:
            out.append("loads or end motion act in this problem, but the rod stored no "
                       "measurable energy: an input may be too short or too weak to "
                       "resolve; the energy audit is not applicable")
        omega = p.characteristic_frequency()
        dt = p.simulation.output_step
        if math.isfinite(omega) and omega > 0.0:
            per = 2.0 * math.pi / omega / dt
            if per < 20.0 and p.simulation.t_end > 2.0 * math.pi / omega:
                out.append(f"the output step {dt:g} s gives {per:.3g} samples per period of "
                           f"the first bending mode (about {2 * math.pi / omega:.3g} s): "
                           f"the series are coarse; set simulation.output_step <= "
                           f"{2 * math.pi / omega / 20:.3g} s for 20 (maxima and decrements "
                           "come from the integrator's interpolant and are not affected)")
        which = p.analysis.maxima
        if which and self.peaks_x.size == 0 and self.status == "finished":
            ser = self.tip if which.startswith("end") else self.start
            c = "xyz".index(which.split(".")[1])
            x0 = _reference_value(self, which)
            d = ser[c] - x0
            lo, hi = float(np.min(d)), float(np.max(d))
            centre = 0.0 if self.centre is None else self.centre.value
            turns = self.maxima_t.size - int(self.maxima_t.size > 0
                                             and self.maxima_t[0] == 0.0)
            why = (f"its maxima lie at or below the equilibrium it vibrates about "
                   f"({centre:.3g} m from the reference; it moves between {lo:.3g} and "
                   f"{hi:.3g} m) and only maxima above it are counted" if turns > 0 else
                   f"it moves between {lo:.3g} and {hi:.3g} m from the reference without "
                   "turning back (no velocity sign change from + to -)")
            out.append(f"analysis.maxima = {which!r} found no maxima: {why}; choose the "
                       "component and the sign of the vibration whose decay you want")
        return out

    def tolerance_warnings(self) -> list[str]:
        """Doubts about the tolerances: a user's atol that is not small against the
        motion's displacement scale, or a loose rtol."""
        out = []
        sim = self.problem.simulation
        if sim.atol is not None and self.model is not None and self.y_last is not None:
            y0 = self.static.y if self.static is not None else self.model.reference
            d, _ = motion_scale(self.problem, self.model, y0)
            if sim.atol > 1e-2 * d:
                out.append(f"atol = {sim.atol:g} is not small against the motion's "
                           f"displacement scale {d:.3g} m (the default scales atol by it): "
                           "the result is doubtful")
        if sim.rtol > 1e-3:
            out.append(f"rtol = {sim.rtol:g} is loose: expect errors of that order")
        return out

    def summary(self) -> dict:
        """JSON-ready summary: status, resolved parameters, static result, maxima and
        decrements, the energy audit, warnings and solver counters."""
        warnings: list[str] = []
        pk: dict = {"peaks": [{"t": float(a), "x": float(b)}
                              for a, b in zip(self.peaks_t, self.peaks_x, strict=True)]}
        n_sig = significant_maxima(self.peaks_x, self.noise_level())
        if n_sig < self.peaks_x.size:
            warnings.append(f"{self.peaks_x.size - n_sig} maxima after t = "
                            f"{self.peaks_t[n_sig]:.4g} s lie below the integrator's noise "
                            f"level ({self.noise_level():.3g} m) and are left out of the "
                            "decrements")
        if self.centre is not None and self.centre.warning:
            warnings.append(self.centre.warning)
        if n_sig >= 2:
            dl = log_decrements(self.peaks_x[:n_sig])
            zeta = damping_ratios(dl)
            pk.update(log_decrements=dl.tolist(), damping_ratios=zeta.tolist(),
                      periods=periods(self.peaks_t[:n_sig]).tolist())
            beat = beat_warning(zeta, self.problem.analysis.maxima)
            if beat:
                warnings.append(beat)
            elif np.any(dl < 0):
                warnings.append("some maxima grow in a free decay (negative decrements): the "
                                "result is doubtful; tighten --rtol")
        else:
            pk.update(log_decrements=[], damping_ratios=[], periods=[])
        audit = self.audit()
        warnings += audit.warnings
        warnings += self.tolerance_warnings()
        warnings += self.input_warnings()
        st = self.static
        return {
            "status": self.status,
            "message": self.message,
            "problem": self.problem.name,
            "parameters": self.problem.to_mapping(),
            "tau_E": self.problem.tau_E,
            "linear_prediction": self.problem.linear_prediction(),
            **({"linear_prediction_note": self.problem.linear_prediction_note()}
               if self.problem.analysis.maxima and self.problem.linear_prediction() is None
               else {}),
            "vibration_centre": None if self.centre is None else {
                "coordinate": self.problem.analysis.maxima, **self.centre.to_dict()},
            "bdf_max_order": self.problem.bdf_max_order(),
            "error_control": None if self.control is None else self.control.describe(),
            "static": {
                "tip": None if st is None else [float(v) for v in st.tip],
                "newton_iterations": 0 if st is None else int(st.iterations),
                "newton_iterations_per_load_step": [] if st is None else list(st.per_step),
                "wall_time_s": 0.0 if st is None else st.wall_time_s,
                "path": [] if st is None else st.path_table(),
                "gauge": None if st is None else st.gauge,
                "largest_displacement": None if st is None else st.largest,
            },
            **pk,
            "energy_balance_max_rel": audit.max_rel,
            "energy_audit": {"applicable": audit.applicable, "max_rel": audit.max_rel,
                             "scale_J": audit.scale, "note": audit.reason},
            "reactions": self.reaction_summary(),
            **({"obstacles": self.obstacle_summary()} if self.problem.obstacles else {}),
            **({"self_contact": self_contact_summary(self.t, self.self_contact)}
               if self.self_contact else {}),
            "end_rotation": {end: {"rotation_vector": [float(v) for v in r[:, -1]],
                                   "angle_deg": float(np.degrees(np.linalg.norm(r[:, -1])))}
                             for end, r in self.end_rotations(last=True).items() if r.size},
            "warnings": warnings,
            "t_reached": float(self.t_last),
            "wall_time_s": self.wall_time_s,
            "counters": dict(self.counters),
            "backend": None if self.model is None else self.model.backend,
        }


    def obstacle_summary(self) -> list[dict]:
        """Per obstacle: :func:`obstacle_summary` of this run."""
        return obstacle_summary(self.problem.obstacles, self.t, self.obstacles)

    def reaction_summary(self) -> dict:
        """Per held end: the support's force and moment at the last output time and their
        largest magnitudes over the run (with their times); plus the static ones."""
        out: dict = {}
        for end, r in self.reactions.items():
            e: dict = {}
            for what, v in r.items():
                if v.shape[1] == 0:
                    continue
                mag = np.linalg.norm(v, axis=0)
                k = int(np.argmax(mag))
                e[what] = {"final": [float(x) for x in v[:, -1]], "max_norm": float(mag[k]),
                           "t_of_max": float(self.t[k])}
            out[end] = e
        if self.static is not None and self.static.reactions:
            out["static"] = {end: {w: [float(x) for x in v] for w, v in r.items()}
                             for end, r in self.static.reactions.items()}
        return out


def _obstacle_series(model: RodModel, extras: np.ndarray) -> list[dict[str, np.ndarray]]:
    """The sampled per obstacle contact values (rows of ``extras`` after the reactions,
    ``model.contact_value_names()``) as :attr:`SimulationResult.obstacles`."""
    from runtime.model.contact import obstacle_series

    return obstacle_series(extras[:len(model.contact_value_names())])


def obstacle_summary(obstacles, t: np.ndarray, series: list[dict[str, np.ndarray]]
                     ) -> list[dict]:
    """Per obstacle (file order; ``obstacles`` the problem's): its kind, the force and
    moment it exerts on the rods at the last output time and their largest magnitudes
    (with their times), the smallest gap (m; negative: the deepest penetration) and its
    time, all on the output grid ``t`` (``series``: the samples by
    :func:`runtime.model.contact.obstacle_series`). An impact shorter than
    ``simulation.output_step`` can fall between two samples (the energy audit integrates
    the contact's work and dissipation over every step)."""
    out = []
    for o, v in zip(obstacles, series, strict=False):
        e: dict = {"index": o.index, "kind": o.kind}
        if t.size:
            for what in ("force", "moment"):
                mag = np.linalg.norm(v[what], axis=0)
                k = int(np.argmax(mag))
                e[what] = {"final": [float(x) for x in v[what][:, -1]],
                           "max_norm": float(mag[k]), "t_of_max": float(t[k])}
            g = v["gap_min"]
            k = int(np.argmin(g))
            e["gap_min"] = {"value": float(g[k]), "t": float(t[k])}
        out.append(e)
    return out


def static_obstacle_summary(obstacles, values: np.ndarray) -> list[dict]:
    """Per obstacle (file order) at an equilibrium: its kind, the force (N) and moment
    (N m, about its point) it exerts on the rods, the smallest gap (m) and the segments in
    reach; ``values`` the flat ``VALUE_NAMES`` rows of every obstacle."""
    from runtime.model.contact import obstacle_series

    return [{"index": o.index, "kind": o.kind,
             "force": [float(x) for x in v["force"]],
             "moment": [float(x) for x in v["moment"]],
             "gap_min": float(v["gap_min"]), "segments": int(v["segments"])}
            for o, v in zip(obstacles, obstacle_series(np.ravel(values)), strict=True)]


def _reference_value(res: SimulationResult, which: str) -> float:
    ix = _maxima_indices(res.model, which)[0]
    return float(res.model.reference[ix])


def _self_contact_series(model: RodModel, extras: np.ndarray) -> dict[str, np.ndarray]:
    """The sampled self-contact values (the last rows of ``extras``,
    ``self_contact_{value}`` of ``model.contact_value_names()``) as
    :attr:`SimulationResult.self_contact` (empty without self-contact)."""
    from runtime.model.contact import SELF_VALUE_NAMES

    if model.self_contact is None:
        return {}
    block = extras[extras.shape[0] - len(SELF_VALUE_NAMES):]
    return dict(zip(SELF_VALUE_NAMES, block, strict=True))


def self_contact_summary(t: np.ndarray, v: dict[str, np.ndarray]) -> dict:
    """summary.json's ``self_contact`` (a single rod's or an assembly's pairs, on the
    output grid ``t``): the final and the largest total pair force (N, with its time),
    the smallest gap (m; negative: the deepest penetration; None: no pair came into
    reach) and its time, the most pairs in reach, the final contact energy (J)."""
    if not t.size:
        return {}
    f, g, n = v["force"], v["gap_min"], v["pairs"]
    k = int(np.argmax(f))
    out: dict = {"force": {"final": float(f[-1]), "max": float(f[k]),
                           "t_of_max": float(t[k])},
                 "pairs_max": int(np.max(n)), "energy_final": float(v["energy"][-1])}
    j = int(np.argmin(g))
    out["gap_min"] = ({"value": float(g[j]), "t": float(t[j])} if np.isfinite(g[j])
                      else None)
    return out


def reference_end_quaternions(model: RodModel) -> dict[str, np.ndarray]:
    """Unit quaternions (4,) of the end frames of the stress-free reference (for clamped
    ends: the clamp frames without their motion)."""
    idx = model.end_segments()
    y = model.reference
    with model.statics():
        model.load_scale, scale = 0.0, model.load_scale
        try:
            model.at(0.0)
            q = model.end_quaternions(np.zeros(1), y[idx["first"]][None], y[idx["last"]][None])
        finally:
            model.load_scale = scale
    return {end: v[0] for end, v in q.items()}


def _maxima_indices(model: RodModel, which: str) -> tuple[int, int]:
    end, comp = which.split(".")
    node = model.N if end == "end" else 0
    c = "xyz".index(comp)
    return int(model.phi_index[node][c]), int(model.v_index[node][c])


def _rotation_angles(model: RodModel, y: np.ndarray, y_ref: np.ndarray) -> float:
    """Largest rotation of a segment frame between two states, measured as
    2 |Im(conj(p_ref) p)| / |p_ref| |p| (= 2 sin(angle/2), the angle for small ones)."""
    from runtime.model.quaternion import quat_mul

    p, q = y[model.p_index], y_ref[model.p_index]
    rel = quat_mul(q * np.array([1.0, -1.0, -1.0, -1.0]), p)
    norm = np.linalg.norm(p, axis=1) * np.linalg.norm(q, axis=1)
    return float(np.max(2.0 * np.linalg.norm(rel[:, 1:], axis=1) / norm)) if rel.size else 0.0


def motion_scale(problem: Problem, model: RodModel, y0: np.ndarray) -> tuple[float, float]:
    """(d, theta): the displacement (m) and rotation (rad) scale of the motion.

    The largest of: the initial state's deviation from the reference (a static
    deflection), the prescribed end motion's amplitude, and the linear static response
    to every load at its peak value (one Newton step at the reference); bounded below by
    round-off and above by the rod's length and pi.
    """
    Lr = problem.rod.length
    d = float(np.max(np.linalg.norm(y0[model.phi_index] - model.reference[model.phi_index],
                                    axis=1)))
    theta = _rotation_angles(model, y0, model.reference)
    for end in (problem.start, problem.end):
        if end.motion is not None:
            T = problem.simulation.t_end
            d = max(d, float(np.linalg.norm(end.motion.translation))
                    * end.motion.translation_time.peak(T))
            theta = max(theta, math.radians(abs(end.motion.rotation_angle))
                        * end.motion.rotation_time.peak(T))
    if problem.loads and (d < 1e-3 * Lr or problem.simulation.initial == "reference"):
        dl, tl = _linear_response(problem)
        d, theta = max(d, dl), max(theta, tl)
    if problem.obstacles:
        do, to = _obstacle_motion_scale(problem, model)
        d, theta = max(d, do), max(theta, to)
    return min(max(d, ATOL_FLOOR * Lr), Lr), min(max(theta, ATOL_FLOOR), math.pi)


def _obstacle_motion_scale(problem: Problem, model: RodModel) -> tuple[float, float]:
    """(d, theta) of the moving obstacles: the travel of their surface near the rod over
    the run (translation, plus the turn times the reference rod's farthest distance from
    the turn's centre), and, where a friction can drag the rod along, the rotation that
    travel rolls a rod of its contact radius through (the segments' spin follows the
    surface: a drum turning under a wire jerks the spin with its friction, and the spin's
    tolerance must be of that motion's size, not of the rod's bending)."""
    T = problem.simulation.t_end
    x = model.reference[model.phi_index]
    law = problem.contact_law()
    r = float(np.min(law.radius)) if law is not None else problem.rod.length
    d = theta = 0.0
    for o in problem.obstacles:
        mo = o.motion
        if mo is None:
            continue
        do = float(np.linalg.norm(mo.translation)) * mo.translation_time.peak(T)
        if mo.rotation_angle:
            reach = float(np.max(np.linalg.norm(x - o.centre, axis=1)))
            do += math.radians(abs(mo.rotation_angle)) * mo.rotation_time.peak(T) * reach
        d = max(d, do)
        if o.friction > 0.0:
            theta = max(theta, do / r)
    return d, theta


def _linear_response(problem: Problem) -> tuple[float, float]:
    """Largest node displacement and segment rotation of the linear static response to
    all loads at their peak values (held ends fixed); (L, pi) if the rod is a mechanism."""
    import scipy.sparse.linalg as spla

    T = problem.simulation.t_end
    peak = problem.with_overrides({})
    loads = tuple(replace(ld, time=TimeFunction(value=ld.time.peak(T))) for ld in peak.loads)
    model = build_model(replace(peak, loads=loads, start=replace(peak.start, motion=None),
                                end=replace(peak.end, motion=None)))
    st = RodStatics(model)
    with model.statics():
        y = model.initial_state()
        try:     # free rigid motions without load along them: held by a gauge
            st.hold_rigid_motions(y)
        except ValueError:   # loads along them, or too soft: no linear response
            return problem.rod.length, math.pi
        r = np.empty(st.n_static)
        st.static_residual(y, r)
        try:
            import warnings as _w

            with _w.catch_warnings():
                _w.simplefilter("error")
                dx = spla.spsolve(st.static_jacobian_sparse(y), -r)
        except Exception:   # singular: a mechanism (e.g. a pinned-free pendulum)
            return problem.rod.length, math.pi
    if not np.all(np.isfinite(dx)):
        return problem.rod.length, math.pi
    return (float(np.max(np.linalg.norm(dx[st.phi_cols], axis=1))),
            float(np.max(np.linalg.norm(dx[st.theta_cols], axis=1))) if st.theta_cols.size
            else 0.0)


@dataclass(frozen=True)
class ErrorControl:
    """What a run's BDF error test controls (:meth:`Problem.error_control`): ``what``
    ("state" or "configuration"), the mask of the unknowns in the test (None: all), and
    the slowest decay rate (1/s) of the rod's glassy modes (0: none), which bounds the
    BDF order on small steps (``stiff_decay_rate`` of :class:`~runtime.solvers.bdf.BDF`)."""

    what: str
    error_mask: np.ndarray | None
    stiff_decay_rate: float = 0.0

    def describe(self) -> str:
        """One line for the summary: what the error test controls."""
        if self.what == "state":
            text = "state (every unknown, velocities included)"
        else:
            text = ("configuration (positions, rotations, internal strains; the velocities "
                    "are left to the corrector)")
        if self.stiff_decay_rate > 0.0:
            text += (f"; BDF order 3-5 only on steps above D_k/sigma_g, the glassy modes' "
                     f"decay rate sigma_g = {self.stiff_decay_rate:.4g} 1/s")
        return text


def error_control(problem: Problem, model: RodModel) -> ErrorControl:
    """The error control of a run of ``problem`` on ``model``: the unknowns in the error
    test (:meth:`Problem.error_control`) and the glassy modes' decay rate
    (:meth:`RodModel.glassy_decay_rate`; a Kelvin-Voigt rod has none)."""
    sigma = model.glassy_decay_rate()
    rate = sigma if math.isfinite(sigma) else 0.0
    if problem.error_control() == "state":
        return ErrorControl("state", None, rate)
    return ErrorControl("configuration", ~model.velocity_mask, rate)


def default_atol(problem: Problem, model: RodModel, y0: np.ndarray) -> np.ndarray:
    """Absolute tolerances per state component, scaled by the motion.

    ``atol_i = max(ATOL_FRACTION * rtol * scale_i, floor_i)``: positions by the motion's
    displacement scale d (:func:`motion_scale`), velocities by d omega, quaternions by its
    rotation scale theta, angular velocities by theta omega (omega: the rod's first
    bending frequency,
    :meth:`~runtime.problem.schema.Problem.characteristic_frequency`), the internal
    strains of a generalized Maxwell rod by d/L (segments) and theta/L (joints); floors
    ``ATOL_FLOOR`` times L, 1, L omega, omega (1 and 1/L) keep the tolerances above
    round-off of the coordinates.

    Why per field: a single atol in "the state's units" must be tiny for the velocities
    near a clamp (axial speeds ~1e-4 of the transverse ones), and with atol = 1e-4 rtol
    their round-off-sized errors pinned the paper's tau = 0.02 s, N = 100 run at order 1
    with h ~ 5e-5 s for a second of simulated time. Why scaled by the motion: with scales
    L and 1 regardless of the deflection, a stiff rod (E = 1e12 Pa, tip deflection 5e-7 m)
    got position tolerances 1e-3 of its amplitude and a 1 % energy-audit error (3e-5 with
    these tolerances, about three times the steps).
    """
    omega = problem.characteristic_frequency()
    d, theta = motion_scale(problem, model, y0)
    a, f, Lr = ATOL_FRACTION * problem.simulation.rtol, ATOL_FLOOR, problem.rod.length
    atol = np.empty(model.n)
    atol[model.phi_index] = max(a * d, f * Lr)
    atol[model.v_index] = max(a * d * omega, f * Lr * omega)
    atol[model.p_index] = max(a * theta, f)
    atol[model.omega_index] = max(a * theta * omega, f * omega)
    # internal strains of the relaxation terms: strains of the motion's size
    atol[model.q_segment_index] = max(a * d / Lr, f)
    atol[model.q_joint_index] = max(a * theta / Lr, f / Lr)
    return atol


def static_equilibrium(problem: Problem, model: RodModel | None = None) -> StaticOutcome:
    """Equilibrium under the loads at t = 0- (ends at their t = 0 positions), by Newton
    with load stepping (``problem.statics``).

    Parameters
    ----------
    problem : Problem
        The rod problem.
    model : RodModel, optional
        Its model (:func:`~runtime.problem.assemble.build_model`), built from ``problem``
        when not given (pass it to reuse one model, e.g. to read positions off the state).

    Returns
    -------
    StaticOutcome
        State ``y``, end position ``tip`` (m), Newton iterations, the load path, the
        gauge, and for a rod held at both ends the largest displacement.

    Raises
    ------
    StaticSolveError
        No equilibrium found; it carries the last converged state and the load path.
    IllPosedError
        Before any work: the loads act along a rigid motion the supports leave free, or
        the rod is too soft for them (``RodStatics.hold_rigid_motions``). Free rigid
        motions without load along them are held by a gauge (``StaticOutcome.gauge``).
    """
    wall0 = time.perf_counter()
    if model is None:
        model = build_model(problem)
    st = RodStatics(model)
    path: list[tuple[float, np.ndarray]] = []
    with model.statics():
        y0 = model.initial_state()
        gauge = st.hold_rigid_motions(y0)     # IllPosedError before any work
        try:
            if model.contact is not None:
                res = _static_on_obstacles(st, y0, path)
            else:
                res = solve_static(st, y0, load_steps=problem.statics.load_steps,
                                   stations=problem.statics.report + (1.0,),
                                   on_station=lambda lam, y: path.append(
                                       (lam, model.tip_position(y))))
            doubt = None if gauge is None else gauge.doubt(st, res.y)
            if doubt is not None:
                raise StaticSolveError(f"solve_static: {doubt}", y=res.y, load_scale=1.0,
                                       iterations=res.iterations,
                                       residual_norm=res.residual_norm)
        except StaticSolveError as exc:
            exc.path = path   # the stations reached before the failure are kept
            raise
        reactions = model.reactions(0.0, res.y)
        frames = model.end_frames(0.0, res.y)
    both_held = problem.start.held and problem.end.held
    return StaticOutcome(y=res.y.copy(), tip=model.tip_position(res.y),
                         iterations=res.total_iterations, per_step=list(res.iterations),
                         wall_time_s=time.perf_counter() - wall0, path=path,
                         reactions=reactions, end_frames=frames,
                         gauge=None if gauge is None else gauge.describe(),
                         largest=largest_displacement(model, res.y) if both_held else None)


def _static_on_obstacles(st: RodStatics, y0: np.ndarray, path: list):
    """The equilibrium of a rod that obstacles support: pseudo-transient continuation
    at the full load (:func:`runtime.solvers.pseudo_transient.pseudo_transient`), then
    Newton at load factor 1. Why not load stepping: the smooth contact law is nearly a
    step on the scale of a Newton step (its width delta is the penetration under the
    rod's weight), so the set of touching segments changes under every load step and
    Newton's line search stalls; damped pseudo-dynamics settle the rod onto the
    obstacles as a real rod would. ``statics.report`` stations are not visited (the path
    is pseudo-time, not load)."""
    from runtime.solvers.pseudo_transient import pseudo_transient

    y1, ok = pseudo_transient(st, y0, first_step=1e-2, min_growth=1.5, max_iter=2000)
    if not ok:
        raise StaticSolveError(
            "statics on obstacles: pseudo-transient continuation found no equilibrium "
            "(the rod may leave the obstacles, or slide off them: a frictionless rod on "
            "an incline has none); simulate it instead", y=y1, load_scale=1.0,
            iterations=[], residual_norm=float("nan"))
    res = solve_static(st, y1, first_load=1.0, stations=(1.0,))
    path.append((1.0, st.model.tip_position(res.y)))
    return res


def simulate(problem: Problem, *, progress: Callable[[float], object] | None = None,
             checkpoint: Callable[[dict], object] | None = None,
             checkpoint_every: float = 1.0, checkpoint_wall: float = 0.0,
             resume: dict | None = None,
             snapshot_every: float | None = None,
             snapshot_sink: Callable[[float, np.ndarray, np.ndarray], object] | None = None,
             max_steps: int = 2_000_000, backend: str = "auto",
             model: RodModel | None = None, sensitivity=None) -> SimulationResult:
    """Run a problem: static equilibrium (if ``simulation.initial = "static"``), then the
    BDF integration with energy audit, outputs and maxima (see the module docstring).

    Parameters
    ----------
    problem : Problem
        The rod problem (``problem.simulation`` holds t_end, tolerances, outputs).
    progress : callable, optional
        Called as ``progress(t)`` after every accepted step.
    checkpoint : callable, optional
        Called as ``checkpoint(state)`` every ``checkpoint_every`` simulated seconds (s)
        with a dict that :func:`simulate` accepts back as ``resume``. The multistep
        history restarts at order 1 there, so a resumed run agrees with an uninterrupted
        one to the integrator tolerance, not bit for bit.
    checkpoint_every : float
        Simulated seconds between checkpoints.
    checkpoint_wall : float
        A checkpoint only once this many seconds of wall time have passed since the
        previous one, the first since the integration started (0: at every
        ``checkpoint_every``; a run that ends sooner writes none); see
        :func:`~runtime.solvers.driver.run_loop`.
    resume : dict, optional
        A checkpoint's state to continue from.
    snapshot_every : float, optional
        Full states every this many seconds, handed to ``snapshot_sink(t, y, yp)``
        (default: kept in ``result.snapshots`` as ``(t, y, yp)``).
    snapshot_sink : callable, optional
        Receives the snapshots.
    max_steps : int
        Give up after this many steps.
    backend : {"auto", "c", "casadi"}
        As in :func:`~runtime.problem.assemble.build_model`.
    model : RodModel, optional
        The problem's model when the caller built it already (e.g. for VTK output); it
        is driven by this run.
    sensitivity : optional
        Forward sensitivities to carry (a ``runtime.simulate.sensitivity.SensitivityRun``;
        :func:`~runtime.simulate.sensitivity.simulate_with_sensitivities` is the way to
        ask for them): the same steps, their channels in ``sensitivity.collected``.

    Returns
    -------
    SimulationResult
        Series, maxima, counters and status (``"finished"``, ``"failed"`` with the
        reason, or ``"interrupted"``); a failed run keeps everything computed up to the
        failure. ``result.summary()`` is what ``summary.json`` holds, energy audit
        included.
    """
    sim = problem.simulation
    res = SimulationResult(problem=problem)
    wall0 = time.perf_counter()
    if model is None:
        model = build_model(problem, backend=backend)
    res.model = model
    if sensitivity is not None:
        if resume is not None:
            raise ValueError("sensitivities of a resumed run are not kept in checkpoints: "
                             "run without --resume")
        sensitivity.prepare(model)
    t_out = np.arange(0.0, sim.t_end + 0.5 * sim.output_step, sim.output_step)
    t_out = t_out[t_out <= sim.t_end]
    energy = EnergyIntegrator(model)
    ends = model.end_segments()
    sampler = Sampler(model, energy, t_out,
                      {"tip": model.phi_index[-1], "start": model.phi_index[0],
                       "p_first": ends["first"], "p_last": ends["last"]},
                      n_extras=len(model.reaction_names) + len(model.contact_value_names()))
    observers: list = [sampler, energy]
    maxima = None
    if problem.analysis.maxima:
        ix, iv = _maxima_indices(model, problem.analysis.maxima)
        # every maximum, whatever its sign: which are maxima of the vibration is decided
        # against its centre when the run is over (vibration_centre)
        maxima = Maxima(ix, iv, offset=float(model.reference[ix]), positive_only=False)
        observers.append(maxima)
    if snapshot_every is not None:
        observers.append(Snapshots(snapshot_every, snapshot_sink or (
            lambda t, y, yp: res.snapshots.append((t, y, yp)))))
    centreline = None
    if sim.centreline_frames:
        centreline = Centreline(np.linspace(0.0, sim.t_end, sim.centreline_frames),
                                model.phi_index)
        observers.append(centreline)
    if progress is not None:
        observers.append(Progress(progress))
    counters0: dict[str, int] = {}
    if resume is None:
        if sim.initial == "static":
            try:
                res.static = static_equilibrium(problem, model)
            except StaticSolveError as exc:
                res.status, res.message = "failed", f"static solve failed: {exc}"
                res.static = StaticOutcome(exc.y, model.tip_position(exc.y), 0, [], 0.0)
                res.y_last = exc.y
                res.wall_time_s = time.perf_counter() - wall0
                return res
            y0 = model.relaxed(res.static.y)   # a held load has let every term relax
        else:
            y0 = model.initial_state(0.0)
        model.enter_piece(0.0, math.inf)          # the inputs from the right at t = 0
        model.at(0.0)
        if getattr(model.drive, "moving_ends", False):  # held ends at their t = 0 motion
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
            raise ValueError(f"the checkpoint's state has {y0.size} entries, this problem "
                             f"needs {model.n}: a checkpoint of another problem")
        for o in observers:
            if hasattr(o, "restore"):
                o.restore(resume)
        if "y_static" in resume and np.size(resume["y_static"]):
            ys = np.array(resume["y_static"])
            res.static = StaticOutcome(ys, model.tip_position(ys),
                                       int(resume["static_iterations"]),
                                       [int(v) for v in resume["static_iterations_per_step"]],
                                       0.0)
        counters0 = {k: int(v) for k, v in dict(resume["counters"]).items()}
    y_scale = res.static.y if res.static is not None else y0
    atol = sim.atol if sim.atol is not None else default_atol(problem, model, y_scale)
    res.atol = np.broadcast_to(np.asarray(atol, dtype=float), (model.n,)).copy()

    def on_checkpoint(state: dict) -> None:
        st = res.static
        state.update(y_static=np.zeros(0) if st is None else st.y,
                     static_iterations=0 if st is None else st.iterations,
                     static_iterations_per_step=np.array([] if st is None else st.per_step))
        checkpoint(state)

    control = res.control = error_control(problem, model)
    out = run_loop(model, t_start, y0, yp0, sim.t_end, rtol=sim.rtol, atol=atol,
                   observers=observers, min_step=sim.min_step, max_order=problem.bdf_max_order(),
                   max_steps=max_steps, checkpoint=on_checkpoint if checkpoint else None,
                   checkpoint_every=checkpoint_every, checkpoint_wall=checkpoint_wall,
                   counters0=counters0,
                   describe_dof=model.describe_dof,
                   solver_options={"error_mask": control.error_mask,
                                   "stiff_decay_rate": control.stiff_decay_rate,
                                   **(sens_options if resume is None else {})})
    res.status, res.message, res.interrupt = out.status, out.message, out.interrupt
    res.t_last, res.y_last, res.counters = out.t_last, out.y_last, out.counters
    a = sampler.arrays()
    res.t, res.tip, res.start = a["t"], a["tip"], a["start"]
    names = model.reaction_names
    res.obstacles = _obstacle_series(model, a["extras"][len(names):])
    res.self_contact = _self_contact_series(model, a["extras"][len(names):])
    held_at = getattr(model.drive, "held_positions", None)
    for end, i, series in (("start", 0, res.start), ("end", model.N, res.tip)):
        if i in model.held_nodes and held_at is not None and res.t.size:
            series[:] = held_at(end, res.t)        # exact: the steps hold them at r(t)
        if i in model.held_nodes:
            res.reactions[end] = {
                what: a["extras"][[names.index(f"{end}_{what}_{c}") for c in "xyz"]]
                for what in ("force", "moment")}
    if centreline is not None:
        res.centreline_t, res.centreline = centreline.arrays()
        for end, i in (("start", 0), ("end", model.N)):
            if i in model.held_nodes and held_at is not None and res.centreline_t.size:
                res.centreline[:, :, i] = held_at(end, res.centreline_t).T
    if res.t.size:
        q = model.end_quaternions(res.t, a["p_first"].T, a["p_last"].T)
        res.end_quaternions = {end: v.T for end, v in q.items()}
    res.kinetic, res.elastic = a["kinetic"], a["elastic"]
    res.dissipated, res.external_work = a["dissipated"], a["external_work"]
    if maxima is not None:
        res.maxima_t, res.maxima_x = np.array(maxima.t), np.array(maxima.x)
        res.centre_maxima()
    if sensitivity is not None:
        sensitivity.collected = sensitivity.collect(res, a, centreline, res.counters)
    res.wall_time_s = time.perf_counter() - wall0
    return res
