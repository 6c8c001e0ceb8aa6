"""Energy-consistent eta_E against the naive eta~_E in simulation.

The extensional viscosity of the rod follows from the 3-D Kelvin-Voigt dissipation as
``eta_E`` (paper eq. (5)), i.e. the retardation time ``tau_E = eta_E / E`` (eq. (6))

    tau_E  = ((1 - 2 nu) tau_B + 2 (1 + nu) tau_S) / 3,

while the naive resultant route (Sect. 4.2) gives ``tau~_E = (tau_B + 2 tau_S) / 3``. The
two coincide when ``tau_B = tau_S`` (the paper's example); with no bulk viscosity
(``tau_B = 0``) and ``nu = 0.3`` they differ by ``tau_E / tau~_E = 1 + nu = 1.3``.

Bending and extension are damped by ``tau_E`` (``V = diag(tau) C``, eq. (9): ``V_M[0:2] =
tau_E C_M[0:2]``, ``V_F[2] = tau_E C_F[2]``), so the linear (small-amplitude) damping ratio of
a bending or axial mode of angular frequency ``omega`` is ``zeta = omega tau_E / 2`` on the
consistent route and ``omega tau~_E / 2`` on the naive one, and the ratio of the measured
damping ratios is predicted as

    zeta_consistent / zeta_naive = tau_E / tau~_E
        = ((1 - 2 nu) tau_B + 2 (1 + nu) tau_S) / (tau_B + 2 tau_S).

:func:`compare_damping` checks this by simulation, each decay run with both routes:

* **bending**: the cantilever of Sect. 5 (the built-in problem ``cantilever``, run by
  :func:`runtime.simulate.simulate.simulate`) released from a small static tip force
  along ``e1`` (linear regime); signal: tip ``x``;
* **axial**: the same rod, clamped-free, stretched by a dead axial tip force along ``e3``
  and released at rest; signal: tip axial displacement ``u = z_tip - L`` about the
  unloaded equilibrium ``z = L``. With the paper's retardation times the first axial
  mode (``omega = pi/(2L) sqrt(E/rho) = 165.6 rad/s``) is overdamped, so the axial case
  scales ``tau_S`` and ``tau_B`` by a common factor that puts its naive damping ratio at
  ``axial_zeta`` (default 0.05); the predicted ratio does not depend on that factor.

Damping ratios are measured from the log decrements of successive maxima,
``zeta_k = delta_k / sqrt(4 pi^2 + delta_k^2)``, averaged over the later half of the cycles
(the first cycles still carry the faster-decaying higher modes of the release).
Predictions use ``omega`` of the same discrete rod from damped modal analysis
(:mod:`runtime.analysis.modal`) and, for reference, the continuum formulas (Euler-Bernoulli
``omega_1 = 1.8751^2 sqrt(E I/(rho A L^4))``, bar ``omega = pi/(2L) sqrt(E/rho)``).

Library code: nothing here prints; the CLI ``kvrod compare-damping`` formats the result.
"""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path
from typing import TypedDict

import numpy as np

from generated.constitutive import (
    retardation_time_extension,
    retardation_time_extension_naive,
)
from runtime.analysis.decay import damping_ratios, log_decrements
from runtime.analysis.modal import modal_analysis
from runtime.problem.assemble import build_model
from runtime.problem.registry import load_problem
from runtime.problem.schema import Problem
from runtime.simulate.simulate import simulate

__all__ = [
    "CASES",
    "ROUTES",
    "CaseResult",
    "ComparisonResult",
    "DecaySignal",
    "RouteResult",
    "axial_release",
    "check_inputs",
    "compare_damping",
    "measured_zeta",
    "plot_compare",
    "predicted_ratio",
    "summary",
]

#: the two decays
CASES = ("bending", "axial")
#: the two extensional viscosities: eta_E (eq. (5)) and eta~_E (Sect. 4.2)
ROUTES = ("consistent", "naive")
#: modal family governing each case (bending-2: in-plane, moves along e1)
_FAMILY = {"bending": "bending-2", "axial": "axial"}


class RouteResult(TypedDict):
    """One decay on one route (SI units; damping ratios dimensionless).

    tau_E: tau_E (eq. (6)) or tau~_E (Sect. 4.2), s; measured_zeta: mean of the later half
    of measured_zeta_per_cycle; predicted_zeta: omega tau / 2 with omega of the discrete
    rod (modal analysis); predicted_zeta_continuum: the same with the continuum omega;
    modal_zeta: damping ratio of the damped eigenvalue pair; omega, omega_continuum:
    rad/s; peaks_t (s) and peaks_x (m): the maxima of the signal.
    """

    tau_E: float
    measured_zeta: float
    measured_zeta_per_cycle: list[float]
    predicted_zeta: float
    predicted_zeta_continuum: float
    modal_zeta: float
    omega: float
    omega_continuum: float
    peaks_t: list[float]
    peaks_x: list[float]


class CaseResult(TypedDict):
    """Both routes of one decay: tau_S, tau_B (s) used, the routes, and the ratios."""

    tau_S: float
    tau_B: float
    routes: dict[str, RouteResult]
    measured_ratio: float
    predicted_ratio: float


class ComparisonResult(TypedDict):
    """Result of :func:`compare_damping`: parameters, cases and the decay time series.

    series[(case, route)] = (t in s, signal in m) on a uniform grid, for plotting.
    """

    parameters: dict[str, float | int]
    cases: dict[str, CaseResult]
    series: dict[tuple[str, str], tuple[np.ndarray, np.ndarray]]


class DecaySignal(TypedDict):
    """A free decay: t (s), signal (m), its maxima peaks_t (s), peaks_x (m)."""

    t: np.ndarray
    x: np.ndarray
    peaks_t: np.ndarray
    peaks_x: np.ndarray


def predicted_ratio(tau_B: float, tau_S: float, poisson_ratio: float) -> float:
    """tau_E / tau~_E = ((1-2nu) tau_B + 2(1+nu) tau_S) / (tau_B + 2 tau_S) (-).

    Eq. (6) over the naive resultant value of Sect. 4.2 (from generated/constitutive.py).
    """
    return float(retardation_time_extension(tau_B, tau_S, poisson_ratio)
                 / retardation_time_extension_naive(tau_B, tau_S))


def measured_zeta(peaks_x: np.ndarray | list[float]) -> tuple[list[float], float]:
    """Per-cycle damping ratios of successive maxima (m) and their later-half mean (-).

    ``zeta_k = delta_k / sqrt(4 pi^2 + delta_k^2)`` with ``delta_k = ln(x_k / x_{k+1})``;
    the mean skips the first half of the cycles (higher modes of the release still
    decaying). Fewer than two maxima give ``([], nan)``.
    """
    if len(peaks_x) < 2:
        return [], math.nan
    z = damping_ratios(log_decrements(np.asarray(peaks_x, dtype=float)))
    return [float(v) for v in z], float(np.mean(z[len(z) // 2:]))


def unloaded(problem: Problem) -> Problem:
    """The problem without its loads (the straight reference is then an equilibrium)."""
    return replace(problem, loads=())


def axial_release(problem: Problem, force: float, t_end: float,
                  samples: int = 2001) -> DecaySignal:
    """The rod of ``problem`` stretched by a dead axial tip force (N), released at t = 0.

    The static stretch is solved under ``force`` along ``e3`` (one load step); the load is
    then switched off and the free vibration run over ``[0, t_end]`` (s). Returns the tip
    axial displacement ``u = z_tip - L`` (m) on ``samples`` uniform times and its maxima
    refined on the dense output (the start, at rest, counts as the first). Raises
    RuntimeError if the run fails.
    """
    p = problem.with_overrides({"loads.0.vector": [0.0, 0.0, float(force)],
                                "statics.load_steps": 1, "analysis.maxima": "end.z",
                                "simulation.t_end": t_end,
                                "simulation.output_step": t_end / (samples - 1)})
    run = simulate(p).finished("axial release")
    u = run.tip[2] - problem.rod.length
    return DecaySignal(t=run.t, x=u, peaks_t=run.peaks_t, peaks_x=run.peaks_x)


def _check_inputs(n_elements: int, tau_S: float, tau_B: float, cases: tuple[str, ...],
                  bending_cycles: float, axial_cycles: float, axial_zeta: float) -> None:
    if isinstance(n_elements, bool) or not isinstance(n_elements, int) or n_elements < 2:
        raise ValueError(f"n_elements = {n_elements!r} must be an integer >= 2")
    for name, v in (("tau_S", tau_S), ("tau_B", tau_B)):
        if not (math.isfinite(v) and v >= 0):
            raise ValueError(f"{name} = {v!r} must be finite and >= 0 (s)")
    if tau_B + 2 * tau_S <= 0:
        raise ValueError("tau_B + 2 tau_S must be > 0: without damping there is nothing "
                         "to compare")
    bad = [c for c in cases if c not in CASES]
    if bad or not cases:
        raise ValueError(f"cases must be a non-empty subset of {CASES}, got {cases!r}")
    for name, v in (("bending_cycles", bending_cycles), ("axial_cycles", axial_cycles)):
        if not (math.isfinite(v) and v >= 2):
            raise ValueError(f"{name} = {v!r} must be >= 2 (two maxima per decrement)")
    if not (0 < axial_zeta < 1):
        raise ValueError(f"axial_zeta = {axial_zeta!r} must be in (0, 1) (underdamped)")


#: damping ratios of the first bending mode (either route) whose ratio the bending decay
#: resolves: below ZETA_MIN the release's higher modes, barely damped, still beat in the
#: later maxima (measured at N = 4 and 20: tau_S = 3e-3 s, zeta 0.004, is 3 to 12 % off the
#: predicted ratio, tau_S = 1e-3 s up to 90 %; tau_S = 0.01 s, zeta 0.012, within 0.3 %);
#: above ZETA_MAX the maxima of the 5 periods fall toward the integrator's tolerance
ZETA_MIN, ZETA_MAX = 0.01, 0.5
#: static tip deflection of the bending release, as a fraction of L: above
#: DEFLECTION_MIN the decay is resolved above the integrator's tolerance (measured: the
#: ratio is within 0.3 % down to 4e-8 L and off by 16 % at 4e-10 L), below DEFLECTION_MAX
#: it is linear (measured: 0.3 % off at 0.36 L, 3 % at 1.8 L)
DEFLECTION_MIN, DEFLECTION_MAX = 1e-6, 0.1


def _check_ranges(base: Problem, tau_S: float, tau_B: float, poisson_ratio: float,
                  tip_force: float, axial_zeta: float) -> None:
    """The decays must be resolvable and linear (ValueError naming the parameter and its
    range for this rod)."""
    lp = base.linear_prediction()
    omega = lp["omega_1"]
    taus = {"consistent": float(retardation_time_extension(tau_B, tau_S, poisson_ratio)),
            "naive": float(retardation_time_extension_naive(tau_B, tau_S))}
    for route, tau in sorted(taus.items(), key=lambda kv: kv[0] != "naive"):
        zeta = omega * tau / 2
        if not ZETA_MIN <= zeta <= ZETA_MAX:
            # the naive tau~_E depends on the retardation times only, tau_E on nu as well
            name = ("tau_S" if tau_S >= tau_B else "tau_B") if route == "naive" else "nu"
            value = {"tau_S": tau_S, "tau_B": tau_B, "nu": poisson_ratio}[name]
            raise ValueError(
                f"{name} = {value:g}{' s' if name != 'nu' else ''} is outside the allowed "
                f"range (with tau_S = {tau_S:g} s, tau_B = {tau_B:g} s, nu = "
                f"{poisson_ratio:g}): the first bending mode's "
                f"damping ratio omega_1 tau_E / 2 must lie in [{ZETA_MIN}, {ZETA_MAX}] on both "
                f"routes for a resolvable decay over the run (here {route}: tau_E = "
                f"{tau:.3g} s, zeta = {zeta:.3g}; omega_1 = {omega:.4g} rad/s: tau_E = "
                f"{2 * ZETA_MIN / omega:.3g} ... {2 * ZETA_MAX / omega:.3g} s)")
    ratio = taus["consistent"] / taus["naive"]
    if not ZETA_MIN <= axial_zeta * ratio <= ZETA_MAX:
        raise ValueError(
            f"tau_B = {tau_B:g} s with tau_S = {tau_S:g} s and nu = {poisson_ratio:g} give "
            f"tau_E / tau~_E = {ratio:.3g}: the axial decay (naive zeta {axial_zeta}) needs "
            f"a ratio in [{ZETA_MIN / axial_zeta:.3g}, {ZETA_MAX / axial_zeta:.3g}] to be "
            "resolvable on both routes")
    m = base._uniform_matrices()
    EI = float(m["C_M"][0, 1])            # tip x along d1 bends about d2
    L = base.rod.length
    per_newton = L**3 / (3 * EI)          # Euler-Bernoulli tip deflection per N (m/N)
    lo, hi = DEFLECTION_MIN * L / per_newton, DEFLECTION_MAX * L / per_newton
    if not (math.isfinite(tip_force) and lo <= abs(tip_force) <= hi):
        raise ValueError(
            f"tip_force = {tip_force:g} N is outside the allowed range: {lo:.3g} ... "
            f"{hi:.3g} N in magnitude for this rod (a static tip deflection F L^3 / (3 E I) "
            f"of {DEFLECTION_MIN:g} ... {DEFLECTION_MAX:g} L: resolvable above the "
            "integrator's tolerance and within the linear range the comparison assumes)")


def check_inputs(n_elements: int = 20, tau_S: float = 0.04, tau_B: float = 0.0,
                 poisson_ratio: float = 0.3, tip_force: float = 0.001,
                 rtol: float = 1e-7) -> None:
    """Validate the parameters of :func:`compare_damping` (ValueError naming the first bad
    one and its range) without running anything."""
    _check_inputs(n_elements, tau_S, tau_B, CASES, 5.0, 6.0, 0.05)
    if not (math.isfinite(rtol) and 0 < rtol <= 1e-4):
        raise ValueError(f"rtol = {rtol!r} is outside the allowed range: 0 < rtol <= 1e-4 "
                         "(the measured damping ratios need an accurate decay)")
    _check_ranges(_base(n_elements, tau_S, tau_B, poisson_ratio, tip_force, rtol),
                  tau_S, tau_B, poisson_ratio, tip_force, 0.05)


def _base(n_elements, tau_S, tau_B, poisson_ratio, tip_force, rtol) -> Problem:
    return load_problem("cantilever", {"n_elements": n_elements, "tau_S": tau_S,
                                       "tau_B": tau_B, "poisson_ratio": poisson_ratio,
                                       "tip_force": tip_force, "rtol": rtol})


def compare_damping(n_elements: int = 20, tau_S: float = 0.04, tau_B: float = 0.0,
                    poisson_ratio: float = 0.3, tip_force: float = 0.001,
                    bending_cycles: float = 5.0, axial_force: float = 0.1,
                    axial_zeta: float = 0.05, axial_cycles: float = 6.0,
                    rtol: float = 1e-7,
                    cases: tuple[str, ...] = CASES) -> ComparisonResult:
    """Measured damping ratios of both extensional viscosities against omega tau / 2.

    n_elements: elements of the rod (the paper's cantilever otherwise: L = 0.3 m, 1 cm
    square, rho = 1000 kg/m^3, E = 1 MPa); tau_S, tau_B: shear and bulk retardation times
    (s; default: no bulk viscosity, where the routes differ); poisson_ratio: nu (-);
    tip_force: static tip force of the bending release (N, along e1; small, so the decay is
    linear); bending_cycles: simulated time of the bending decay in periods of the
    Euler-Bernoulli first mode; axial_force: dead axial tip force of the stretch (N);
    axial_zeta: naive damping ratio the axial case is scaled to (see module docstring);
    axial_cycles: simulated axial periods; rtol: integrator tolerance; cases: a subset of
    :data:`CASES`.

    Returns a :class:`ComparisonResult`; ``cases[c]["measured_ratio"]`` is the measured
    zeta_consistent / zeta_naive, ``cases[c]["predicted_ratio"]`` = tau_E / tau~_E.
    Raises ValueError for bad parameters and RuntimeError if a simulation fails.
    """
    cases = tuple(cases)
    _check_inputs(n_elements, tau_S, tau_B, cases, bending_cycles, axial_cycles, axial_zeta)
    base = _base(n_elements, tau_S, tau_B, poisson_ratio, tip_force, rtol)
    _check_ranges(base, tau_S, tau_B, poisson_ratio, tip_force, axial_zeta)
    omega_eb = base.linear_prediction()["omega_1"]
    t_bend = bending_cycles * 2 * math.pi / omega_eb
    L, E, rho = base.rod.length, base.material.youngs_modulus, base.material.density
    omega_ax = math.pi / (2 * L) * math.sqrt(E / rho)
    k = axial_zeta * 2 / (omega_ax * float(retardation_time_extension_naive(tau_B, tau_S)))
    ax_tau_S, ax_tau_B = tau_S * k, tau_B * k
    result = ComparisonResult(
        parameters={"n_elements": n_elements, "tau_S": tau_S, "tau_B": tau_B,
                    "poisson_ratio": poisson_ratio, "tip_force": tip_force,
                    "bending_cycles": bending_cycles, "axial_force": axial_force,
                    "axial_zeta": axial_zeta, "axial_cycles": axial_cycles,
                    "axial_tau_S": ax_tau_S, "axial_tau_B": ax_tau_B, "rtol": rtol},
        cases={}, series={})
    for case in cases:
        ts, tb = (tau_S, tau_B) if case == "bending" else (ax_tau_S, ax_tau_B)
        taus = {"consistent": float(retardation_time_extension(tb, ts, poisson_ratio)),
                "naive": float(retardation_time_extension_naive(tb, ts))}
        w_cont = omega_eb if case == "bending" else omega_ax
        routes: dict[str, RouteResult] = {}
        for route in ROUTES:
            sc = base.with_overrides({"tau_S": ts, "tau_B": tb, "damping": route})
            modes = modal_analysis(build_model(unloaded(sc)), count=12)
            mode = next(m for m in modes if m.family == _FAMILY[case])
            if case == "bending":
                run = simulate(sc.with_overrides({"t_end": t_bend})).finished(
                    f"cantilever ({route})")
                sig = DecaySignal(t=run.t, x=run.tip[0], peaks_t=run.peaks_t,
                                  peaks_x=run.peaks_x)
            else:
                sig = axial_release(sc, axial_force, axial_cycles * 2 * math.pi / omega_ax)
            per_cycle, zeta = measured_zeta(sig["peaks_x"])
            routes[route] = RouteResult(
                tau_E=taus[route], measured_zeta=zeta, measured_zeta_per_cycle=per_cycle,
                predicted_zeta=mode.omega * taus[route] / 2,
                predicted_zeta_continuum=w_cont * taus[route] / 2,
                modal_zeta=mode.zeta, omega=mode.omega, omega_continuum=w_cont,
                peaks_t=[float(v) for v in sig["peaks_t"]],
                peaks_x=[float(v) for v in sig["peaks_x"]])
            result["series"][(case, route)] = (np.asarray(sig["t"]), np.asarray(sig["x"]))
        c, n = routes["consistent"], routes["naive"]
        result["cases"][case] = CaseResult(
            tau_S=ts, tau_B=tb, routes=routes,
            measured_ratio=c["measured_zeta"] / n["measured_zeta"],
            predicted_ratio=predicted_ratio(tb, ts, poisson_ratio))
    return result


def summary(result: ComparisonResult) -> dict:
    """JSON-ready copy of a :class:`ComparisonResult` without the time series."""
    return {"parameters": dict(result["parameters"]), "cases": result["cases"]}


# --------------------------------------------------------------------------------------
# Plots
# --------------------------------------------------------------------------------------


def _save_fig(fig, path: Path) -> Path:
    from runtime.io.figures import save

    fig.tight_layout()
    return save(fig, path, dpi=110)


def plot_compare(result: ComparisonResult, out: Path | str) -> list[Path]:
    """Two PNGs in ``out`` (matplotlib Agg), written atomically; returns their paths.

    compare_signals.png: the decays of both routes (tip x for bending, tip u_z for axial,
    m, against t in s); compare_zeta.png: the measured per-cycle damping ratios against
    the linear predictions omega tau_E / 2 and omega tau~_E / 2.
    """
    from runtime.io.figures import pyplot

    plt = pyplot()
    cases = [c for c in CASES if c in result["cases"]]
    ylabel = {"bending": "tip x [m]", "axial": "tip u_z = z - L [m]"}
    paths = []
    fig, axes = plt.subplots(1, len(cases), figsize=(5.5 * len(cases), 3.8), squeeze=False)
    for ax, case in zip(axes[0], cases, strict=True):
        for c, route in enumerate(ROUTES):
            t, x = result["series"][(case, route)]
            ax.plot(t, x, color=f"C{c}", lw=1, label=route)
        ax.set_title(f"{case} decay", fontsize=9)
        ax.set_xlabel("t [s]")
        ax.set_ylabel(ylabel[case])
        ax.legend(fontsize=8)
        ax.grid(alpha=0.3)
    paths.append(_save_fig(fig, Path(out) / "compare_signals.png"))
    fig, axes = plt.subplots(1, len(cases), figsize=(5.5 * len(cases), 3.8), squeeze=False)
    for ax, case in zip(axes[0], cases, strict=True):
        res = result["cases"][case]
        for c, route in enumerate(ROUTES):
            r = res["routes"][route]
            k = range(1, len(r["measured_zeta_per_cycle"]) + 1)
            ax.plot(list(k), r["measured_zeta_per_cycle"], "o", color=f"C{c}",
                    label=f"{route}: measured")
            tau = "tau_E" if route == "consistent" else "tau~_E"
            ax.axhline(r["predicted_zeta"], color=f"C{c}", ls="--",
                       label=f"{route}: omega {tau}/2 = {r['predicted_zeta']:.4f}")
        ax.set_title(f"{case}: ratio measured {res['measured_ratio']:.4f}, predicted "
                     f"{res['predicted_ratio']:.4f}", fontsize=9)
        ax.set_xlabel("cycle k")
        ax.set_ylabel("damping ratio zeta_k [-]")
        ax.legend(fontsize=7)
        ax.grid(alpha=0.3)
    paths.append(_save_fig(fig, Path(out) / "compare_zeta.png"))
    return paths
