"""The paper's damped large-deflection cantilever (Linn, Lang, Tuganov 2013, Sect. 5).

A scenario is data (:class:`CantileverScenario`); :func:`run_cantilever` runs it:
static equilibrium under the dead tip force F e1 by Newton with load stepping, release at
t = 0 (the force is switched off, the rod starts at rest), free Kelvin-Voigt-damped
vibration integrated by the variable-order BDF of :mod:`runtime.solvers.bdf`. Along the way it
locates the tip maxima on the step interpolants, integrates the dissipated power 2 D and
the external power by 3-point Gauss-Legendre on every step (energy audit), and samples the
tip and the energies on a uniform output grid.

Failures never lose what was computed: a failed static solve or integration returns a
:class:`CantileverRun` with ``status = "failed"``, the message and everything up to the
last accepted step.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, field

import numpy as np

from generated import rod_layout as L
from generated.constitutive import retardation_time_extension
from runtime.analysis.decay import (
    BETA1_L,
    damping_ratios,
    log_decrements,
    periods,
)
from runtime.errors import ParameterError
from runtime.model.rod import RodModel, RodParameters
from runtime.solvers.integrator import consistent_initial
from runtime.solvers.statics import StaticSolveError, solve_static

#: default absolute tolerance per field, relative to rtol x the field's scale
#: (see CantileverScenario.default_atol)
ATOL_FRACTION = 1e-3
#: accepted tolerance ranges: below them the error test works on round-off
RTOL_MIN = 100 * float(np.finfo(float).eps)
ATOL_MIN = 1e-20
#: guards against runs that cannot finish on one machine
MAX_SAMPLES = 10_000_000        # output samples t_end / output_step
MAX_ELEMENTS = 200_000          # ~1 GiB of band storage and work arrays
MAX_PERIODS = 1e6               # first-mode periods in t_end (~50 steps each)
#: lower bound of the absolute tolerances relative to the field's size (round-off: 1e4 eps)
ATOL_FLOOR = 1e4 * float(np.finfo(float).eps)

#: Gauss-Legendre nodes/weights on [0, 1] for the per-step energy quadrature
_GL_X = (np.polynomial.legendre.leggauss(3)[0] + 1.0) / 2.0
_GL_W = np.polynomial.legendre.leggauss(3)[1] / 2.0


def _in_range(name: str, value: float, low: float, high: float = math.inf,
              low_incl: bool = False) -> None:
    ok = math.isfinite(value) and (value >= low if low_incl else value > low) and value < high
    if not ok:
        lo = "[" if low_incl else "("
        hi = f"{high:g})" if math.isfinite(high) else "inf)"
        raise ParameterError(name, value, f"{lo}{low:g}, {hi}")


@dataclass(frozen=True)
class CantileverScenario:
    """Parameters of the Sect. 5 cantilever (defaults: the paper's values, SI units).

    length (m), width/height (m, section along a^(1)/a^(2)), density (kg/m^3),
    youngs_modulus (Pa), poisson_ratio (-), tau_S/tau_B (s; the paper uses
    zeta/eta = K/G, i.e. tau_B = tau_S = tau_E), tip_force (N, dead load along e1, removed
    at release), n_elements, t_end (s, simulated time after release), rtol/atol
    (integrator tolerances; atol None -> :meth:`default_atol`, scaled per field), damping
    ("consistent" eta_E or "naive" eta~_E), load_steps (static continuation),
    output_step (s, sampling of the stored series), min_step (s, smallest step the
    integrator may take before it gives up; 0 = round-off limit), max_order (highest BDF
    order, 1-5).
    """

    length: float = 0.30
    width: float = 0.01
    height: float = 0.01
    density: float = 1000.0
    youngs_modulus: float = 1.0e6
    poisson_ratio: float = 0.3
    tau_S: float = 0.04
    tau_B: float = 0.04
    tip_force: float = 0.05
    n_elements: int = 50
    t_end: float = 10.0
    rtol: float = 1e-6
    atol: float | None = None
    damping: str = "consistent"
    shear_correction: bool = True
    load_steps: int = 10
    output_step: float = 0.005
    min_step: float = 0.0
    max_order: int = 5

    def __post_init__(self) -> None:
        _in_range("t_end", self.t_end, 0.0)
        _in_range("rtol", self.rtol, RTOL_MIN, 1.0, low_incl=True)
        if self.atol is not None:
            _in_range("atol", self.atol, ATOL_MIN, 1.0, low_incl=True)
        _in_range("min_step", self.min_step, 0.0, self.t_end, low_incl=True)
        _in_range("tip_force", self.tip_force, -math.inf)
        if not isinstance(self.max_order, int) or not 1 <= self.max_order <= 5:
            raise ParameterError("max_order", self.max_order, "integer 1 ... 5")
        if not isinstance(self.load_steps, int) or not 1 <= self.load_steps <= 10_000:
            raise ParameterError("load_steps", self.load_steps, "integer 1 ... 10000")
        n = self.n_elements
        if isinstance(n, (int, np.integer)) and not isinstance(n, bool) and n > MAX_ELEMENTS:
            raise ParameterError("n_elements", n, f"integer 1 ... {MAX_ELEMENTS}")
        self.rod_parameters()  # validates the rod data (E, nu, tau, sizes, N, damping)
        periods = self.t_end / self.linear_prediction()["period_1"]
        if periods > MAX_PERIODS:
            raise ParameterError(
                "t_end", self.t_end, f"at most {MAX_PERIODS:.0e} first-mode periods "
                f"({MAX_PERIODS * self.linear_prediction()['period_1']:.3g} s for this rod: "
                f"length {self.length:g} m, E {self.youngs_modulus:g} Pa); the run would need "
                f"more than {50 * periods:.2g} steps")
        if not (math.isfinite(self.output_step) and self.output_step > 0
                and self.t_end / self.output_step <= MAX_SAMPLES):
            raise ParameterError("output_step", self.output_step,
                                 f">= t_end/{MAX_SAMPLES:.0e} = {self.t_end / MAX_SAMPLES:.3g} s "
                                 "(at most 1e7 samples)")

    @classmethod
    def with_tau(cls, tau: float, **kw) -> CantileverScenario:
        """The paper's convention tau_B = tau_S = tau (so tau_E = tau)."""
        return cls(tau_S=tau, tau_B=tau, **kw)

    def rod_parameters(self) -> RodParameters:
        return RodParameters(length=self.length, n_elements=self.n_elements,
                             density=self.density, youngs_modulus=self.youngs_modulus,
                             poisson_ratio=self.poisson_ratio, tau_S=self.tau_S,
                             tau_B=self.tau_B, width=self.width, height=self.height,
                             shear_correction=self.shear_correction, damping=self.damping)

    @property
    def tau_E(self) -> float:
        """Extensional retardation time (6) from generated/constitutive.py [s]."""
        return float(retardation_time_extension(self.tau_B, self.tau_S, self.poisson_ratio))

    def default_atol(self, y_static: np.ndarray | None = None) -> np.ndarray:
        """Absolute tolerances per state component, scaled by the motion (issue 12).

        ``atol_i = max(ATOL_FRACTION * rtol * scale_i, floor_i)`` with the scales of the
        motion: positions by the largest node displacement d of ``y_static`` from the
        straight reference (m), velocities by d omega_1 (m/s), quaternions by the largest
        segment rotation theta (rad), angular velocities by theta omega_1 (rad/s),
        omega_1 the first bending frequency. The floors (``ATOL_FLOOR`` times L, 1, L
        omega_1, omega_1) keep the tolerances above round-off of the coordinates.

        Why per field: a single atol in "the state's units" must be tiny for the
        velocities near the clamp (axial speeds ~1e-4 of the transverse ones), and with
        atol = 1e-4 rtol their round-off-sized errors pinned the tau = 0.02 s, N = 100 run
        at order 1 with h ~ 5e-5 s for a second of simulated time. Why scaled by the
        motion: with scales L and 1 regardless of the deflection, a stiff rod (E = 1e12 Pa,
        tip deflection 5e-7 m) got position tolerances 1e-3 of its amplitude and a 1 %
        energy-audit error (3e-5 with these tolerances, about three times the steps).
        Without ``y_static`` the scales are L and 1 rad.
        """
        N = self.n_elements
        omega = self.linear_prediction()["omega_1"]
        d, theta = self.length, 1.0
        if y_static is not None:
            y_ref = RodModel(self.rod_parameters()).initial_state()
            phi = [L.CELL0_OFFSETS["phi"]] + [L.cell_start(i) + L.CELL_OFFSETS["phi"]
                                             for i in range(1, N + 1)]
            d = max(float(np.linalg.norm(y_static[i:i + 3] - y_ref[i:i + 3])) for i in phi)
            p = [L.cell_start(i) + L.CELL_OFFSETS["p"] for i in range(1, N + 1)]
            theta = max(2.0 * float(np.linalg.norm(y_static[i + 1:i + 4])) for i in p)
        a = ATOL_FRACTION * self.rtol
        f = ATOL_FLOOR
        atol = np.empty(L.n_state(N))
        for i in range(N + 1):
            c = L.cell_start(i)
            off = L.CELL0_OFFSETS if i == 0 else L.CELL_OFFSETS
            atol[c + off["phi"]:c + off["phi"] + 3] = max(a * d, f * self.length)
            atol[c + off["v"]:c + off["v"] + 3] = max(a * d * omega, f * self.length * omega)
            if i > 0:
                atol[c + off["p"]:c + off["p"] + 4] = max(a * theta, f)
                atol[c + off["Omega"]:c + off["Omega"] + 3] = max(a * theta * omega,
                                                                  f * omega)
        return atol

    def linear_prediction(self) -> dict[str, float]:
        """Euler-Bernoulli first mode and the Kelvin-Voigt damping ratio omega_1 tau/2.

        tau is tau_E (bending is normal-stress damped, V_M = tau_E C_M for the bending
        entries, eq. (9)), or tau~_E for the naive route.
        """
        from generated.constitutive import retardation_time_extension_naive

        # the tip force along e1 = a^(1) bends the rod about a^(2): stiffness E I2,
        # I2 = <xi1^2> = height width^3 / 12 (width along xi1)
        A = self.width * self.height
        EI = self.youngs_modulus * self.height * self.width**3 / 12.0
        omega = BETA1_L**2 * math.sqrt(EI / (self.density * A * self.length**4))
        tau = self.tau_E if self.damping == "consistent" else float(
            retardation_time_extension_naive(self.tau_B, self.tau_S))
        zeta = omega * tau / 2.0
        return {"omega_1": omega, "period_1": 2 * math.pi / omega, "tau": tau,
                "zeta_1": zeta, "log_decrement_1": 2 * math.pi * zeta / math.sqrt(1 - zeta**2)
                if zeta < 1 else math.inf}


@dataclass
class CantileverRun:
    """Everything a run computed (also when it failed part-way)."""

    scenario: CantileverScenario
    status: str = "running"            # "finished" | "failed"
    message: str = ""
    static_tip: np.ndarray | None = None
    static_iterations: int = 0
    static_iterations_per_step: list[int] = field(default_factory=list)
    y_static: np.ndarray | None = None
    t: np.ndarray = field(default_factory=lambda: np.zeros(0))
    tip: np.ndarray = field(default_factory=lambda: np.zeros((3, 0)))
    kinetic: np.ndarray = field(default_factory=lambda: np.zeros(0))
    elastic: np.ndarray = field(default_factory=lambda: np.zeros(0))
    dissipated: np.ndarray = field(default_factory=lambda: np.zeros(0))
    external_work: np.ndarray = field(default_factory=lambda: np.zeros(0))
    peaks_t: np.ndarray = field(default_factory=lambda: np.zeros(0))
    peaks_x: np.ndarray = field(default_factory=lambda: np.zeros(0))
    counters: dict[str, int] = field(default_factory=dict)
    wall_time_s: float = 0.0
    static_wall_time_s: float = 0.0
    t_last: float = 0.0
    y_last: np.ndarray | None = None
    snapshots: list = field(default_factory=list)     # (t, y) pairs for VTK output
    model: object = None                             # the RodModel that ran
    interrupt: BaseException | None = None           # what interrupted the run, if anything
    atol_scale: object = None                        # the absolute tolerances used

    def audit(self):
        """The energy audit of the run (:func:`runtime.analysis.audit.audit_run`)."""
        from runtime.analysis.audit import audit_run

        sc = self.scenario
        EA = sc.youngs_modulus * sc.width * sc.height
        floor = EA * sc.length * ATOL_FLOOR**2    # energy of round-off-sized strains
        return audit_run(self.kinetic, self.elastic, self.dissipated, self.external_work,
                         floor)

    @property
    def energy_balance_rel(self) -> np.ndarray:
        """(T + W + int 2D - int P - E0)/E_scale on the output grid (E_scale: the run's
        energy, = the energy at release for the free decay; zeros when not applicable)."""
        return self.audit().relative

    def _noise_level(self) -> float:
        """Tip amplitude below which maxima are round-off (1e3 times the tip's atol)."""
        atol = self.atol_scale
        if atol is None:
            return 0.0
        a = np.broadcast_to(np.asarray(atol, dtype=float), (L.n_state(self.scenario.n_elements),))
        return 1e3 * float(a[_tip_indices(self.scenario.n_elements)[0][0]])

    def summary(self) -> dict:
        """JSON-ready summary: status, parameters, static result, maxima and their
        decrements, energy audit, warnings, counters (issue 4 item 4, issue 12)."""
        sc = self.scenario
        warnings: list[str] = []
        pk = {"peaks": [{"t": float(a), "x": float(b)}
                        for a, b in zip(self.peaks_t, self.peaks_x, strict=True)]}
        from runtime.analysis.audit import significant_maxima

        n_sig = significant_maxima(self.peaks_x, self._noise_level())
        if n_sig < self.peaks_x.size:
            warnings.append(f"{self.peaks_x.size - n_sig} maxima after t = "
                            f"{self.peaks_t[n_sig]:.4g} s lie below the integrator's noise "
                            f"level ({self._noise_level():.3g} m) and are left out of the "
                            "decrements")
        if n_sig >= 2:
            dl = log_decrements(self.peaks_x[:n_sig])
            pk.update(log_decrements=dl.tolist(), damping_ratios=damping_ratios(dl).tolist(),
                      periods=periods(self.peaks_t[:n_sig]).tolist())
            if np.any(dl < 0):
                warnings.append("some maxima grow in a free decay (negative decrements): the "
                                "result is doubtful; tighten --rtol")
        else:
            pk.update(log_decrements=[], damping_ratios=[], periods=[])
        audit = self.audit()
        warnings += audit.warnings
        return {
            "status": self.status,
            "message": self.message,
            "parameters": {**asdict(sc), "tau_E": sc.tau_E},
            "linear_prediction": sc.linear_prediction(),
            "static": {
                "tip": None if self.static_tip is None else [float(v) for v in self.static_tip],
                "newton_iterations": int(self.static_iterations),
                "newton_iterations_per_load_step": list(self.static_iterations_per_step),
                "wall_time_s": self.static_wall_time_s,
            },
            **pk,
            "energy_balance_max_rel": audit.max_rel,
            "energy_audit": {"applicable": audit.applicable, "max_rel": audit.max_rel,
                             "scale_J": audit.scale, "note": audit.reason},
            "warnings": warnings,
            "t_reached": float(self.t_last),
            "wall_time_s": self.wall_time_s,
            "counters": dict(self.counters),
        }


def _tip_indices(N: int) -> tuple[np.ndarray, int]:
    c = L.cell_start(N)
    return c + L.CELL_OFFSETS["phi"] + np.arange(3), c + L.CELL_OFFSETS["v"]


def describe_dof(n_elements: int, index: int) -> str:
    """Human-readable name of state/residual component ``index`` (layout of rod_layout)."""
    if index < 0:
        return "unknown component"
    if index < L.CELL0_SIZE:
        field_, off = ("phi", index) if index < 3 else ("v", index - 3)
        return f"node 0 {field_}[{off}]"
    cell, local = divmod(index - L.CELL0_SIZE, L.CELL_SIZE)
    cell += 1
    for name, start in sorted(L.CELL_OFFSETS.items(), key=lambda kv: -kv[1]):
        if local >= start:
            where = "segment" if name in ("p", "Omega") else "node"
            return f"{where} {cell} {name}[{local - start}] (state index {index})"
    return f"state index {index}"


def run_cantilever(scenario: CantileverScenario,
                   progress: Callable[[float], object] | None = None,
                   max_steps: int = 2_000_000,
                   checkpoint: Callable[[CantileverRun, dict], object] | None = None,
                   checkpoint_every: float = 1.0,
                   resume: dict | None = None,
                   snapshot_every: float | None = None,
                   snapshot_sink: Callable[[float, np.ndarray], object] | None = None
                   ) -> CantileverRun:
    """Static deflection, release and damped free vibration of the cantilever.

    progress(t) is called after every accepted step (the CLI drives a progress bar).
    checkpoint(run, state) is called every ``checkpoint_every`` simulated seconds with a
    dict that :func:`run_cantilever` accepts back as ``resume`` to continue the run (the
    multistep history restarts at order 1 there, so a resumed run agrees with an
    uninterrupted one to the integrator tolerance, not bit for bit).
    snapshot_every: also hand full states every so many seconds to ``snapshot_sink(t, y)``
    (default: keep them in ``run.snapshots``) for VTK.
    Returns a :class:`CantileverRun`; never raises for solver failure or interruption
    (status "failed" / "interrupted", message and all results up to the last accepted step
    are kept; the interrupting exception is in ``run.interrupt`` for the caller to re-raise).
    """
    from runtime.simulate.loop import run_loop
    from runtime.simulate.observers import (
        EnergyIntegrator,
        Maxima,
        Progress,
        Sampler,
        Snapshots,
    )

    sc = scenario
    run = CantileverRun(scenario=sc)
    wall0 = time.perf_counter()
    model = RodModel(sc.rod_parameters(), start="clamped", end="free",
                     tip_force=(sc.tip_force, 0.0, 0.0))
    i_tip, i_vx = _tip_indices(sc.n_elements)
    run.model = model
    t_out = np.arange(0.0, sc.t_end + 0.5 * sc.output_step, sc.output_step)
    t_out = t_out[t_out <= sc.t_end]
    energy = EnergyIntegrator(model)
    sampler = Sampler(model, energy, t_out, i_tip, np.arange(L.CELL0_OFFSETS["phi"],
                                                             L.CELL0_OFFSETS["phi"] + 3))
    maxima = Maxima(int(i_tip[0]), int(i_vx))
    observers: list = [sampler, energy, maxima]
    if snapshot_every is not None:
        sink = snapshot_sink or (lambda t, y: run.snapshots.append((t, y)))
        observers.append(Snapshots(snapshot_every, sink))
    if progress is not None:
        observers.append(Progress(progress))
    counters0: dict[str, int] = {}

    model.load_scale = 0.0 if resume is not None else 1.0
    if resume is None:
        # --- static equilibrium under the dead tip load -----------------------------
        try:
            st = solve_static(model, model.initial_state(), load_steps=sc.load_steps)
        except StaticSolveError as exc:
            run.status, run.message = "failed", f"static solve failed: {exc}"
            run.y_static = exc.y
            run.static_tip = exc.y[i_tip].copy()
            run.wall_time_s = time.perf_counter() - wall0
            return run
        run.static_wall_time_s = time.perf_counter() - wall0
        run.y_static = st.y.copy()
        run.static_tip = st.y[i_tip].copy()
        run.static_iterations = st.total_iterations
        run.static_iterations_per_step = list(st.iterations)
        # --- release: the dead load is switched off, the rod starts at rest -----------
        model.load_scale = 0.0
        t_start = 0.0
        y0, yp0 = consistent_initial(model, 0.0, st.y, np.zeros(model.n))
    else:
        t_start, y0, yp0 = float(resume["t"]), np.array(resume["y"]), np.array(resume["yp"])
        if y0.shape != (model.n,):
            raise ValueError(f"resume state has {y0.shape} entries, the scenario needs "
                             f"({model.n},): checkpoint of a different scenario")
        for o in (energy, sampler, maxima, *observers[3:]):
            if hasattr(o, "restore"):
                o.restore(resume)
        run.y_static = np.array(resume["y_static"])
        run.static_tip = np.array(resume["static_tip"])
        run.static_iterations = int(resume["static_iterations"])
        run.static_iterations_per_step = [int(v) for v in resume["static_iterations_per_step"]]
        counters0 = {k: int(v) for k, v in dict(resume["counters"]).items()}
    atol = sc.atol if sc.atol is not None else sc.default_atol(run.y_static)

    def on_checkpoint(state: dict) -> None:
        state.update(y_static=run.y_static, static_tip=run.static_tip,
                     static_iterations=run.static_iterations,
                     static_iterations_per_step=np.array(run.static_iterations_per_step))
        checkpoint(run, state)

    res = run_loop(model, t_start, y0, yp0, sc.t_end, rtol=sc.rtol, atol=atol,
                   observers=observers, min_step=sc.min_step, max_order=sc.max_order,
                   max_steps=max_steps, checkpoint=on_checkpoint if checkpoint else None,
                   checkpoint_every=checkpoint_every, counters0=counters0,
                   describe_dof=lambda i: describe_dof(sc.n_elements, i))
    run.status, run.message, run.interrupt = res.status, res.message, res.interrupt
    run.t_last, run.y_last = res.t_last, res.y_last
    run.counters = res.counters
    a = sampler.arrays()
    run.t, run.tip = a["t"], a["tip"]
    run.kinetic, run.elastic = a["kinetic"], a["elastic"]
    run.dissipated, run.external_work = a["dissipated"], a["external_work"]
    run.peaks_t, run.peaks_x = np.array(maxima.t), np.array(maxima.x)
    run.atol_scale = atol
    run.wall_time_s = time.perf_counter() - wall0
    return run
