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
from scipy.optimize import brentq

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
from runtime.solvers.bdf import BDF, IntegrationError
from runtime.solvers.integrator import consistent_initial
from runtime.solvers.statics import StaticSolveError, solve_static

#: default absolute tolerance per field, relative to rtol x the field's scale
#: (see CantileverScenario.default_atol)
ATOL_FRACTION = 1e-3

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
        _in_range("rtol", self.rtol, 0.0, 1.0)
        if self.atol is not None:
            _in_range("atol", self.atol, 0.0)
        _in_range("output_step", self.output_step, 0.0)
        _in_range("min_step", self.min_step, 0.0, low_incl=True)
        _in_range("tip_force", self.tip_force, -math.inf)
        if not isinstance(self.max_order, int) or not 1 <= self.max_order <= 5:
            raise ParameterError("max_order", self.max_order, "integer 1 ... 5")
        if not isinstance(self.load_steps, int) or self.load_steps < 1:
            raise ParameterError("load_steps", self.load_steps, "integer >= 1")
        self.rod_parameters()  # validates the rod data (E, nu, tau, sizes, N, damping)

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

    def default_atol(self) -> np.ndarray:
        """Absolute tolerances per state component: ATOL_FRACTION * rtol * the field's scale.

        Scales: positions L (m), quaternions 1, velocities L omega_1 (m/s), angular
        velocities omega_1 (rad/s), omega_1 the first bending frequency. Why per field: a
        single atol in "the state's units" must be tiny for the velocities near the clamp
        (axial speeds ~1e-4 of the transverse ones), and with atol = 1e-4 rtol their
        round-off-sized errors pinned the tau = 0.02 s, N = 100 run at order 1 with
        h ~ 5e-5 s for a second of simulated time (3027 error-test failures, 6244 LU at
        rtol = 1e-7; 74 and 374 with these tolerances, same damping ratios).
        """
        N = self.n_elements
        omega = self.linear_prediction()["omega_1"]
        scale = np.empty(L.n_state(N))
        for i in range(N + 1):
            c = L.cell_start(i)
            off = L.CELL0_OFFSETS if i == 0 else L.CELL_OFFSETS
            scale[c + off["phi"]:c + off["phi"] + 3] = self.length
            scale[c + off["v"]:c + off["v"] + 3] = self.length * omega
            if i > 0:
                scale[c + off["p"]:c + off["p"] + 4] = 1.0
                scale[c + off["Omega"]:c + off["Omega"] + 3] = omega
        return ATOL_FRACTION * self.rtol * scale

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

    @property
    def energy_balance_rel(self) -> np.ndarray:
        """(T + W + int 2D - int P - E0)/E0 on the output grid (E0 = energy at release)."""
        if self.t.size == 0:
            return np.zeros(0)
        total = self.kinetic + self.elastic + self.dissipated - self.external_work
        e0 = total[0]
        return (total - e0) / e0 if e0 > 0 else np.zeros_like(total)

    def summary(self) -> dict:
        """JSON-ready summary (issue 4 item 4 keys)."""
        sc = self.scenario
        pk = {"peaks": [{"t": float(a), "x": float(b)}
                        for a, b in zip(self.peaks_t, self.peaks_x, strict=True)]}
        if self.peaks_x.size >= 2:
            dl = log_decrements(self.peaks_x)
            pk.update(log_decrements=dl.tolist(), damping_ratios=damping_ratios(dl).tolist(),
                      periods=periods(self.peaks_t).tolist())
        else:
            pk.update(log_decrements=[], damping_ratios=[], periods=[])
        eb = self.energy_balance_rel
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
            "energy_balance_max_rel": float(np.max(np.abs(eb))) if eb.size else None,
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


def _checkpoint_state(run: CantileverRun, solver: BDF, rec: dict, pk: tuple, diss: float,
                      work: float, k_out: int, counters0: dict) -> dict:
    counters = {k: counters0.get(k, 0) + v for k, v in solver.counters.items()}
    return {"t": float(solver.t), "y": solver.y.copy(), "yp": solver.yp.copy(),
            "k_out": k_out, "diss": diss, "work": work,
            "rec_t": np.array(rec["t"]), "rec_tip": np.array(rec["tip"]),
            "rec_T": np.array(rec["T"]), "rec_W": np.array(rec["W"]),
            "rec_D": np.array(rec["D"]), "rec_P": np.array(rec["P"]),
            "peaks_t": np.array(pk[0]), "peaks_x": np.array(pk[1]),
            "y_static": run.y_static, "static_tip": run.static_tip,
            "static_iterations": run.static_iterations,
            "static_iterations_per_step": np.array(run.static_iterations_per_step),
            "counters": counters}


def run_cantilever(scenario: CantileverScenario,
                   progress: Callable[[float], object] | None = None,
                   max_steps: int = 2_000_000,
                   checkpoint: Callable[[CantileverRun, dict], object] | None = None,
                   checkpoint_every: float = 1.0,
                   resume: dict | None = None,
                   snapshot_every: float | None = None) -> CantileverRun:
    """Static deflection, release and damped free vibration of the cantilever.

    progress(t) is called after every accepted step (the CLI drives a progress bar).
    checkpoint(run, state) is called every ``checkpoint_every`` simulated seconds with a
    dict that :func:`run_cantilever` accepts back as ``resume`` to continue the run (the
    multistep history restarts at order 1 there, so a resumed run agrees with an
    uninterrupted one to the integrator tolerance, not bit for bit).
    snapshot_every: also keep full states every so many seconds (``run.snapshots``) for VTK.
    Returns a :class:`CantileverRun`; never raises for solver failure (status "failed",
    message and all results up to the last accepted step are kept).
    """
    sc = scenario
    run = CantileverRun(scenario=sc)
    wall0 = time.perf_counter()
    model = RodModel(sc.rod_parameters(), start="clamped", end="free",
                     tip_force=(sc.tip_force, 0.0, 0.0))
    i_tip, i_vx = _tip_indices(sc.n_elements)
    run.model = model
    rec = {"t": [], "tip": [], "T": [], "W": [], "D": [], "P": []}
    pk_t: list[float] = []
    pk_x: list[float] = []
    t_out = np.arange(0.0, sc.t_end + 0.5 * sc.output_step, sc.output_step)
    t_out = t_out[t_out <= sc.t_end]
    counters0: dict[str, int] = {}

    def energies(y, yp):
        return model.energy_scalars(0.0, y, yp)

    def record(tq, y, yp, diss_q, work_q):
        T, W, _, _ = energies(y, yp)
        rec["t"].append(tq)
        rec["tip"].append(y[i_tip].copy())
        rec["T"].append(T)
        rec["W"].append(W)
        rec["D"].append(diss_q)
        rec["P"].append(work_q)

    def power_integrals(dense, a: float, b: float) -> tuple[float, float]:
        """int_a^b 2D dt and int_a^b P dt on the step interpolant (3-point Gauss)."""
        tq = a + (b - a) * _GL_X
        ys = np.ascontiguousarray(dense(tq).T)
        yps = np.ascontiguousarray(dense.derivative(tq).T)
        dsum = wsum = 0.0
        for j in range(tq.size):
            _, _, twoD, P = energies(ys[j], yps[j])
            dsum += _GL_W[j] * twoD
            wsum += _GL_W[j] * P
        return dsum * (b - a), wsum * (b - a)

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
        diss = work = 0.0          # integrals up to the last accepted step
        record(0.0, y0, yp0, 0.0, 0.0)
        k_out = 1
        if y0[i_tip[0]] > 0:       # released from rest at a deflected state: a maximum
            pk_t.append(0.0)
            pk_x.append(float(y0[i_tip[0]]))
    else:
        t_start, y0, yp0 = float(resume["t"]), np.array(resume["y"]), np.array(resume["yp"])
        if y0.shape != (model.n,):
            raise ValueError(f"resume state has {y0.shape} entries, the scenario needs "
                             f"({model.n},): checkpoint of a different scenario")
        diss, work, k_out = float(resume["diss"]), float(resume["work"]), int(resume["k_out"])
        for key, src in (("t", "rec_t"), ("T", "rec_T"), ("W", "rec_W"), ("D", "rec_D"),
                         ("P", "rec_P")):
            rec[key] = [float(v) for v in resume[src]]
        rec["tip"] = [np.array(v) for v in resume["rec_tip"]]
        pk_t, pk_x = list(map(float, resume["peaks_t"])), list(map(float, resume["peaks_x"]))
        run.y_static = np.array(resume["y_static"])
        run.static_tip = np.array(resume["static_tip"])
        run.static_iterations = int(resume["static_iterations"])
        run.static_iterations_per_step = [int(v) for v in resume["static_iterations_per_step"]]
        counters0 = {k: int(v) for k, v in dict(resume["counters"]).items()}
    atol = sc.atol if sc.atol is not None else sc.default_atol()
    solver = BDF(model, t_start, y0, yp0, sc.t_end, rtol=sc.rtol, atol=atol,
                 min_step=sc.min_step, max_order=sc.max_order)
    next_ckpt = t_start + checkpoint_every
    next_snap = t_start
    if snapshot_every is not None:
        run.snapshots = [(t_start, y0.copy())]
        next_snap = t_start + snapshot_every
    try:
        while solver.status == "running" and solver.nstep < max_steps:
            vx_old = solver.y[i_vx]
            solver.step()
            dense = solver.dense_output()
            t0, t1 = solver.t_old, solver.t
            h = t1 - t0
            if not np.all(np.isfinite(solver.y)):
                raise IntegrationError(f"non-finite state at t = {t1:g} s", t=t0,
                                       y=dense(t0), yp=dense.derivative(t0), h=h,
                                       residual_norm=math.inf,
                                       worst_index=int(np.argmin(np.isfinite(solver.y))))
            while k_out < t_out.size and t_out[k_out] <= t1 + 1e-12 * max(1.0, t1):
                tq = min(t_out[k_out], t1)
                dd, ww = power_integrals(dense, t0, tq)
                record(tq, dense(tq), dense.derivative(tq), diss + dd, work + ww)
                k_out += 1
            dd, ww = power_integrals(dense, t0, t1)
            diss += dd
            work += ww
            vx_new = solver.y[i_vx]
            if vx_old > 0.0 >= vx_new and h > 0:      # tip x velocity turns negative: maximum
                tk = t1 if vx_new == 0.0 else brentq(
                    lambda s, d=dense: d(s)[i_vx], t0, t1, xtol=1e-14, rtol=1e-13)
                xk = float(dense(tk)[i_tip[0]])
                if xk > 0:
                    pk_t.append(tk)
                    pk_x.append(xk)
            if snapshot_every is not None:
                while next_snap <= t1:
                    run.snapshots.append((next_snap, np.array(dense(next_snap))))
                    next_snap += snapshot_every
            if progress is not None:
                progress(t1)
            if checkpoint is not None and t1 >= next_ckpt and solver.status == "running":
                checkpoint(run, _checkpoint_state(run, solver, rec, (pk_t, pk_x), diss, work,
                                                  k_out, counters0))
                next_ckpt = t1 + checkpoint_every
        run.status = "finished" if solver.status == "finished" else "failed"
        if run.status == "failed":
            run.message = f"stopped after max_steps = {max_steps} steps at t = {solver.t:g} s"
        else:
            run.message = "ok"
        run.t_last, run.y_last = solver.t, solver.y.copy()
    except IntegrationError as exc:
        run.status = "failed"
        run.message = (f"integration failed at t = {exc.t:.6g} s (last accepted step), "
                       f"step size {exc.h:.3g} s, residual norm {exc.residual_norm:.3g}, "
                       f"worst component: {describe_dof(sc.n_elements, exc.worst_index)}: "
                       f"{exc}")
        run.t_last, run.y_last = float(exc.t), np.array(exc.y, copy=True)
    run.counters = {k: counters0.get(k, 0) + v for k, v in solver.counters.items()}
    run.t = np.array(rec["t"])
    run.tip = np.array(rec["tip"]).T if rec["tip"] else np.zeros((3, 0))
    run.kinetic, run.elastic = np.array(rec["T"]), np.array(rec["W"])
    run.dissipated, run.external_work = np.array(rec["D"]), np.array(rec["P"])
    run.peaks_t, run.peaks_x = np.array(pk_t), np.array(pk_x)
    run.wall_time_s = time.perf_counter() - wall0
    return run
