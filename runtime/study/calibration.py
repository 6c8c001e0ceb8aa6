"""Calibration of the retardation time tau of the cantilever from measured decay.

Paper convention tau_S = tau_B = tau, hence tau_E = tau (eq. (6)). Two kinds of data:

* ``"signal"``: a measured tip signal ``x(t)`` (m) after release at ``t = 0`` of the
  problem's static tip load. Model: a simulation of the problem
  (:func:`runtime.simulate.simulate.simulate`, coarse ``n_elements`` and ``t_end`` = the end
  of the data), the displacement of its ``analysis.maxima`` coordinate (the cantilever: the
  tip's x) interpolated (cubic spline) at the data times.
  Residuals ``r_i(tau) = x_model(t_i; tau) - x_i``.
* ``"decrements"``: logarithmic decrements ``delta_k`` (-) of successive maxima. Model: the
  linear (small-amplitude) prediction of damped modal analysis (:mod:`runtime.analysis.modal`),
  ``delta(tau) = 2 pi zeta_1 / sqrt(1 - zeta_1^2)`` with ``zeta_1`` the damping ratio of the
  first in-plane bending mode of the straight cantilever. Residuals ``delta(tau) -
  delta_k``. Large-amplitude decrements (the paper's release from 0.22 m) lie below the
  linear value, so this mode underestimates tau there; use the signal mode for them.

The fit is nonlinear least squares (``scipy.optimize.least_squares``, trust region) in
``tau`` with forward-difference sensitivities. With ``J = dr/dtau`` at the optimum, ``n``
residuals and ``p = 1`` parameter, the residual variance is ``s^2 = |r|^2 / (n - p)``, the
standard error ``SE = s / |J|`` and the 95 % confidence interval ``tau +- t_{0.975, n-p} SE``
(Student t), valid for independent, equal-variance measurement errors.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from scipy.interpolate import CubicSpline
from scipy.optimize import least_squares
from scipy.stats import t as student_t

from runtime.analysis.decay import damping_ratios, find_maxima, log_decrements
from runtime.analysis.records import load_csv

__all__ = [
    "CalibrationResult",
    "calibrate_decrements",
    "calibrate_signal",
    "check_tau0",
    "decrement_model",
    "dominant_period",
    "load_csv",
    "plot_calibration",
    "signal_maxima",
    "tau_range",
    "validate_decrements",
    "validate_signal",
]

#: fewest samples of a signal accepted
MIN_SAMPLES = 20
#: lower bound of the fitted tau (s)
TAU_MIN = 1e-9


@dataclass
class CalibrationResult:
    """Outcome of a calibration (SI units: tau in s, signal in m).

    mode: "signal" or "decrements"; tau: estimate; std_error: standard error of tau;
    ci95: 95 % confidence interval; tau0: starting value; residual_rms: RMS residual
    (m or -); n_data: residual count; nfev: model evaluations (excluding the
    sensitivity evaluations of ``least_squares``' own counter ``njev``); data_t/data_y:
    the data (t in s, x in m; for decrements t = k); fit_t/fit_y: the fitted model
    (dense for plotting); success/message: of least_squares.
    """

    mode: str
    tau: float
    std_error: float
    ci95: tuple[float, float]
    tau0: float
    residual_rms: float
    n_data: int
    nfev: int
    njev: int
    success: bool
    message: str
    data_t: np.ndarray = field(repr=False)
    data_y: np.ndarray = field(repr=False)
    fit_t: np.ndarray = field(repr=False)
    fit_y: np.ndarray = field(repr=False)
    doubts: list[str] = field(default_factory=list)

    @property
    def accepted(self) -> bool:
        """The fit converged and passed its self-checks (``fit_doubts``)."""
        return self.success and not self.doubts

    def summary(self) -> dict:
        """JSON-ready summary without the arrays."""
        return {"status": "ok" if self.accepted else "rejected", "mode": self.mode,
                "tau": self.tau, "std_error": self.std_error,
                "ci95": list(self.ci95), "tau0": self.tau0, "residual_rms": self.residual_rms,
                "n_data": self.n_data, "nfev": self.nfev, "njev": self.njev,
                "success": self.success, "message": self.message, "doubts": list(self.doubts)}


# --------------------------------------------------------------------------------------
# Data
# --------------------------------------------------------------------------------------


def _finite(name: str, a: np.ndarray) -> None:
    bad = np.flatnonzero(~np.isfinite(a))
    if bad.size:
        raise ValueError(f"{name} contains NaN or inf (first at row {int(bad[0])}); "
                         "remove or fill the missing values")


def validate_signal(t: Sequence[float], x: Sequence[float],
                    min_samples: int = MIN_SAMPLES) -> tuple[np.ndarray, np.ndarray]:
    """Check a measured tip signal; returns float arrays (t, x) or raises ValueError.

    Needs: equal lengths, at least ``min_samples`` samples, finite values, strictly
    increasing time, t >= 0 (time since release), and at least two positive maxima
    (``signal_maxima``; the start counts when the signal starts at a maximum).
    """
    t, x = np.asarray(t, dtype=float).ravel(), np.asarray(x, dtype=float).ravel()
    if t.size != x.size:
        raise ValueError(f"t and x differ in length ({t.size} and {x.size})")
    if t.size < min_samples:
        raise ValueError(f"signal too short: {t.size} samples, at least {min_samples} needed")
    _finite("t", t)
    _finite("x", x)
    dt = np.diff(t)
    if np.any(dt <= 0):
        i = int(np.flatnonzero(dt <= 0)[0])
        raise ValueError(f"time is not strictly increasing (non-monotone): t[{i}] = {t[i]!r} "
                         f">= t[{i + 1}] = {t[i + 1]!r}")
    if t[0] < 0:
        raise ValueError(f"t must start at the release, t >= 0; got t[0] = {float(t[0]):g} s "
                         "(is t offset? subtract the release time from it)")
    tk, _ = signal_maxima(t, x)
    if tk.size == 0:
        raise ValueError("no maxima in the signal: it must contain oscillation peaks x > 0")
    if tk.size < 2:
        raise ValueError(f"too few maxima in the signal ({tk.size}); at least 2 are needed "
                         "(record longer, over two periods)")
    return t, x


def signal_maxima(t: np.ndarray, x: np.ndarray, prominence: float = 0.05,
                  start_at_rest: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """Positive maxima (t_k, x_k) of a noisy signal (t in s, x in m).

    Peaks whose prominence exceeds ``prominence`` times the signal range
    (``scipy.signal.find_peaks``; noise wiggles are not peaks), refined by the parabola
    through the peak sample and its neighbours. start_at_rest: the record starts at the
    release from rest, so ``x(-t) = x(t)`` near 0 and a start value above the following
    samples counts as the first maximum.
    """
    from scipy.signal import find_peaks

    n = x.size
    xe = np.concatenate([x[:0:-1], x]) if start_at_rest else x  # even extension about t0
    idx, _ = find_peaks(xe, prominence=prominence * float(np.ptp(x)))
    if start_at_rest:
        idx = np.unique(np.abs(idx - (n - 1)))
    tk, xk = [], []
    for i in idx:
        if x[i] <= 0 or i == x.size - 1:
            continue
        if i == 0:
            tk.append(float(t[0]))
            xk.append(float(x[0]))
            continue
        a, b = find_maxima(t[i - 1:i + 2], x[i - 1:i + 2], positive_only=True)
        if a.size:
            tk.append(a[0])
            xk.append(b[0])
    return np.asarray(tk), np.asarray(xk)


def dominant_period(t: np.ndarray, x: np.ndarray) -> float:
    """The period (s) of the strongest oscillation of a record (t in s, x in m): the peak
    of its amplitude spectrum.

    Robust to measurement noise, unlike the spacing of maxima (white noise spreads over
    all frequencies, while the decay concentrates at its own). The record is resampled
    onto a uniform grid of as many points (linear interpolation; NumPy's FFT needs one),
    its mean removed, zero-padded eightfold for a fine frequency grid, and the spectrum's
    largest value above the lowest resolvable frequency 1/span is refined by a parabola
    through it and its neighbours.
    """
    t = np.asarray(t, dtype=float)
    x = np.asarray(x, dtype=float)
    n = min(t.size, 1 << 20)
    span = float(t[-1] - t[0])
    tu = np.linspace(float(t[0]), float(t[-1]), n)
    xu = np.interp(tu, t, x)
    xu = xu - xu.mean()
    m = 8 * n
    spec = np.abs(np.fft.rfft(xu, m))
    freq = np.fft.rfftfreq(m, d=span / (n - 1))
    ok = np.flatnonzero(freq >= 1.0 / span)
    if ok.size < 3 or not np.any(spec[ok] > 0):
        return math.inf
    k = int(ok[np.argmax(spec[ok])])
    if 0 < k < spec.size - 1:
        a, b, c = spec[k - 1], spec[k], spec[k + 1]
        den = a - 2 * b + c
        shift = 0.5 * (a - c) / den if den != 0 else 0.0
        f = freq[k] + float(np.clip(shift, -1, 1)) * (freq[1] - freq[0])
    else:
        f = freq[k]
    return 1.0 / f if f > 0 else math.inf


def record_centre(t: np.ndarray, x: np.ndarray) -> float:
    """The value a decaying record oscillates about (m): the mean over its last
    :func:`dominant_period` (of the whole record when it is shorter than a period or has
    none); 0 for a vibration about the reference, the sag for a rod left under load."""
    from scipy.integrate import trapezoid

    T = dominant_period(t, x)
    sel = t >= t[-1] - T if math.isfinite(T) and T < t[-1] - t[0] else np.ones(t.size, bool)
    if np.count_nonzero(sel) < 2:
        return float(np.mean(x))
    return float(trapezoid(x[sel], t[sel]) / (t[sel][-1] - t[sel][0]))


def smoothed_maxima(t: np.ndarray, x: np.ndarray, start_at_rest: bool = True
                    ) -> tuple[np.ndarray, np.ndarray]:
    """:func:`signal_maxima` of the record smoothed over a tenth of its
    :func:`dominant_period` (a moving average on a uniform grid): the maxima of the
    oscillation, not of the noise on it."""
    T = dominant_period(t, x)
    n = t.size
    tu = np.linspace(float(t[0]), float(t[-1]), n)
    xu = np.interp(tu, t, x)
    w = int(round(0.1 * T / (tu[1] - tu[0]))) if math.isfinite(T) else 1
    if w >= 3:
        # a centred moving average; the ends keep their own (shorter) windows
        c = np.concatenate([[0.0], np.cumsum(xu)])
        lo = np.clip(np.arange(n) - w // 2, 0, n)
        hi = np.clip(np.arange(n) + w // 2 + 1, 0, n)
        xu = (c[hi] - c[lo]) / (hi - lo)
    return signal_maxima(tu, xu, start_at_rest=start_at_rest)


def release_offset(t: np.ndarray, x: np.ndarray) -> tuple[float, float]:
    """(delta, T) [s]: how far the record's maxima lie from the multiples of their period
    T. A linear oscillator released from rest at t = 0 has its maxima at exactly k T_d
    (x = x0 e^(-zeta w t) (cos w_d t + zeta w / w_d sin w_d t), whose velocity is
    proportional to sin w_d t), with damping too, so delta ~ 0; a record whose time does
    not count from the release (a logger's clock, a still start before the release) has
    delta = its offset modulo T. The interior maxima t_k of :func:`smoothed_maxima` are
    numbered by whole periods n_k of the :func:`dominant_period` and fitted by
    t_k = a + T n_k (once more without those off the fit by over a quarter period: maxima
    of noise); delta = a - T round(a / T), in (-T/2, T/2]; (nan, nan) with fewer than two
    maxima."""
    tk, _ = smoothed_maxima(t, x, start_at_rest=False)
    T = dominant_period(t, x)
    if tk.size < 2 or not math.isfinite(T):
        return math.nan, math.nan
    n = np.round((tk - tk[0]) / T)
    a = float(tk[0])
    for _ in range(2):
        if np.ptp(n) == 0:
            break
        T, a = (float(v) for v in np.polyfit(n, tk, 1))
        keep = np.abs(tk - (a + T * n)) <= 0.25 * T
        if keep.all() or keep.sum() < 2:
            break
        tk, n = tk[keep], n[keep]
    return a - T * round(a / T), T


#: a record whose scale differs from the model's by more than this factor is rejected
SCALE_FACTOR = 3.0
#: longest record accepted, in first-mode periods of the model
MAX_RECORD_PERIODS = 200.0
#: a fit whose residual RMS exceeds this fraction of the signal's RMS is rejected, unless
#: the residual is the record's own noise (at most NOISE_FACTOR times its estimate)
MAX_RESIDUAL_FRACTION = 0.3
NOISE_FACTOR = 1.5
#: the record must start within this many periods of the release (t = 0), and its
#: maxima lie within RELEASE_PHASE periods of whole periods after it (a time offset)
RELEASE_START = 0.25
RELEASE_PHASE = 0.1
#: a record whose noise is this fraction of its RMS or more holds no measurable decay
MAX_NOISE_FRACTION = 0.7


class RecordSignError(ValueError):
    """The record's first maximum and the model's release lie on opposite sides (x m)."""

    def __init__(self, message: str, first: float, release_x: float) -> None:
        super().__init__(message)
        self.first, self.release_x = first, release_x


def check_signal_against_model(t: np.ndarray, x: np.ndarray, release_x: float,
                               period: float) -> None:
    """Reject a record that cannot come from the model before fitting (ValueError).

    ``release_x`` (m): the model's tip x at release (its first maximum); ``period`` (s):
    its first bending period. Checked: the sign of the first maximum (a flipped record),
    its size against ``release_x`` (units: mm instead of m), the period of the record's
    maxima against ``period`` (units: ms instead of s) and the record's length (at most
    ``MAX_RECORD_PERIODS`` periods).
    """
    i0 = int(np.argmax(np.abs(x[: max(3, x.size // 10)])))
    first = float(x[i0])
    if first < 0 < release_x or first > 0 > release_x:
        raise RecordSignError(f"the record starts at x = {first:.4g} m but the model is "
                              f"released from x = {release_x:.4g} m: is the sign of the "
                              "record flipped?", first, release_x)
    if release_x == 0.0:
        raise ValueError("the model is not deflected before the release (its tip force is "
                         "zero): give the static tip force of the experiment (--tip-force)")
    ratio = abs(first) / abs(release_x)
    if not 1 / SCALE_FACTOR <= ratio <= SCALE_FACTOR:
        unit = (" (is the record in mm? x must be in m)" if 300 < ratio < 3000 else
                " (is the record in cm? x must be in m)" if 30 < ratio < 300 else
                " (check the units and the problem's tip force)")
        raise ValueError(f"the record's first maximum {first:.4g} m is {ratio:.3g} times the "
                         f"model's release deflection {release_x:.4g} m{unit}")
    T = dominant_period(t, x)
    if math.isfinite(T):
        r = T / period
        if not 1 / SCALE_FACTOR <= r <= SCALE_FACTOR:
            unit = (" (is time in ms? t must be in s)" if 300 < r < 3000 else
                    " (check the units of t and the problem's geometry and material)")
            raise ValueError(f"the signal's period {T:.4g} s is {r:.3g} times the model's "
                             f"first period {period:.4g} s{unit}")
    _check_release_time(t, x, T if math.isfinite(T) else period)
    span = float(t[-1] - t[0])
    if span > MAX_RECORD_PERIODS * period:
        raise ValueError(f"the record spans {span:.4g} s = {span / period:.3g} periods of the "
                         f"model (at most {MAX_RECORD_PERIODS:g}); cut it to the decay")


def _check_release_time(t: np.ndarray, x: np.ndarray, period: float) -> None:
    """t must count from the release: the record starts within RELEASE_START periods of
    t = 0 and its maxima lie within RELEASE_PHASE periods (or two samples) of the
    multiples of their period (:func:`release_offset`); ValueError naming the offset."""
    if t[0] > RELEASE_START * period:
        raise ValueError(f"the record starts at t = {float(t[0]):.6g} s, "
                         f"{float(t[0]) / period:.3g} periods of {period:.4g} s after t = 0: t "
                         "must be the time since the release (is t offset? subtract the "
                         "release time from it)")
    delta, T = release_offset(t, x)
    if not math.isfinite(delta):
        return
    dt = float(np.median(np.diff(t)))
    if abs(delta) > max(RELEASE_PHASE * T, 2.0 * dt):
        raise ValueError(f"the record's maxima lie {delta:+.4g} s ({delta / T:+.2f} periods) "
                         f"off the multiples of its period {T:.4g} s: t = 0 must be the "
                         "release from rest, whose maxima fall at whole periods (is t offset "
                         f"by {delta:.4g} s, or does the record begin before the release?)")


def noise_rms(x: np.ndarray) -> float:
    """RMS of white measurement noise on a finely sampled record (m): second differences
    of white noise of variance s^2 have variance 6 s^2, while a smooth oscillation
    sampled many times per period contributes little to them (an upper estimate)."""
    x = np.asarray(x, dtype=float)
    return float(np.std(np.diff(x, 2)) / math.sqrt(6.0)) if x.size > 3 else 0.0


def fit_doubts(tau: float, ci: tuple[float, float], residual_rms: float,
               signal_rms: float, lower_bound: float, noise: float = 0.0) -> list[str]:
    """Why a converged fit is still not believable (empty when it is). ``noise``: the
    record's own noise level (:func:`noise_rms`); a residual at that level is no misfit."""
    doubts = []
    lo, hi = ci
    if not (math.isfinite(lo) and math.isfinite(hi)):
        doubts.append("no confidence interval (too few data or a flat residual)")
    elif lo <= 0.0:
        doubts.append(f"the 95 % confidence interval [{lo:.4g}, {hi:.4g}] s contains zero: "
                      "the data do not determine tau")
    if tau <= 1.01 * lower_bound:
        doubts.append(f"tau = {tau:.3g} s sits at its lower bound: the model cannot match "
                      "the data (units? sign?)")
    if (signal_rms > 0 and residual_rms > MAX_RESIDUAL_FRACTION * signal_rms
            and residual_rms > NOISE_FACTOR * noise):
        doubts.append(f"the residual RMS {residual_rms:.4g} is {residual_rms / signal_rms:.2f} "
                      f"of the signal's RMS {signal_rms:.4g} and above the record's noise "
                      f"{noise:.3g}: the model does not fit the data (units, sign, problem?)")
    if noise > 0 and noise >= MAX_NOISE_FRACTION * signal_rms:
        doubts.append(f"the record's noise {noise:.3g} is {noise / signal_rms:.2f} of its RMS "
                      f"{signal_rms:.4g}: no decay can be told from that noise")
    return doubts


def validate_decrements(delta: Sequence[float]) -> np.ndarray:
    """Check log decrements (finite, > 0, at least 2); returns a float array."""
    d = np.asarray(delta, dtype=float).ravel()
    if d.size < 2:
        raise ValueError(f"too few decrements ({d.size}); at least 2 are needed for a "
                         "confidence interval")
    _finite("delta", d)
    if np.any(d <= 0):
        i = int(np.flatnonzero(d <= 0)[0])
        raise ValueError(f"decrements must be > 0 (decaying maxima); delta[{i}] = {d[i]!r}")
    return d


# --------------------------------------------------------------------------------------
# Models
# --------------------------------------------------------------------------------------


def _problem(problem=None, **overrides):
    """The calibrated problem: ``problem`` (default: the built-in cantilever at N = 16)
    with ``overrides`` (aliases or dotted paths)."""
    from runtime.problem.registry import load_problem

    base = problem if problem is not None else load_problem("cantilever", {"n_elements": 16})
    return base.with_overrides(overrides) if overrides else base


def _bending_family(problem) -> str:
    """The modal family that moves the maxima coordinate: a displacement along d1 is
    bending about d2 ("bending-2"), along d2 about d1 ("bending-1")."""
    comp = (problem.analysis.maxima or "end.x")[-1]
    d = problem.rod.geometry.frame(np.array(0.0))
    e = np.eye(3)["xyz".index(comp)]
    return "bending-2" if abs(e @ d[:, 0]) >= abs(e @ d[:, 1]) else "bending-1"


def decrement_model(problem=None) -> Callable[[float], float]:
    """delta(tau) (-) of the first bending mode in the direction of the maxima, from damped
    modal analysis of the unloaded rod of ``problem`` (default: the paper's cantilever,
    N = 16) with tau_S = tau_B = tau. Returns a function of tau (s)."""
    from dataclasses import replace as dc_replace

    from runtime.analysis.modal import modal_analysis
    from runtime.problem.assemble import build_model

    base = _problem(problem)
    family = _bending_family(base)

    def delta(tau: float) -> float:
        p = dc_replace(base.with_overrides({"tau": float(tau)}), loads=())
        modes = modal_analysis(build_model(p), count=2)
        m = next((m for m in modes if m.family == family), modes[0])
        z = m.zeta
        return 2 * math.pi * z / math.sqrt(1 - z * z) if z < 1 else math.inf

    return delta


def _component(problem) -> tuple[int, float]:
    """(coordinate index, reference value) of the maxima coordinate of the s = L end."""
    comp = "xyz".index((problem.analysis.maxima or "end.x")[-1])
    ref = problem.rod.geometry.position(np.array(problem.rod.length))[comp]
    return comp, float(ref)


def _simulate_tip(problem, tau: float, t_end: float) -> tuple[np.ndarray, np.ndarray]:
    from runtime.simulate.simulate import simulate

    run = simulate(problem.with_overrides({"tau": float(tau), "t_end": float(t_end)}))
    run.finished(f"simulation at tau = {tau!r} s")
    c, ref = _component(problem)
    return run.t, run.tip[c] - ref


def _ci(tau: float, J: np.ndarray, r: np.ndarray) -> tuple[float, tuple[float, float]]:
    n = r.size
    dof = n - 1
    jtj = float(J.ravel() @ J.ravel())
    if dof < 1 or jtj <= 0:
        return math.nan, (math.nan, math.nan)
    s2 = float(r @ r) / dof
    se = math.sqrt(s2 / jtj)
    q = float(student_t.ppf(0.975, dof))
    return se, (tau - q * se, tau + q * se)


def tau_range(problem=None) -> tuple[float, float]:
    """(lowest, highest) tau (s) a fit may try on ``problem``: ``TAU_MIN``, and the
    largest retardation time the rod accepts (``schema.VISCOUS_RATE_MAX`` over the
    stiffest element mode's omega_max^2; see ``Problem.element_rates``)."""
    from runtime.problem.schema import VISCOUS_RATE_MAX

    w2, _ = _problem(problem).element_rates()
    return TAU_MIN, VISCOUS_RATE_MAX / w2


def check_tau0(tau0: float | None, problem=None) -> None:
    """ParameterError (naming tau0 and its range) unless tau0 is None or a time within
    :func:`tau_range`."""
    if tau0 is None:
        return
    from runtime.errors import ParameterError

    lo, hi = tau_range(problem)
    if not (isinstance(tau0, (int, float)) and math.isfinite(tau0) and lo <= tau0 <= hi):
        raise ParameterError("tau0", tau0, f"a starting retardation time {lo:g} ... {hi:.3g} s "
                             "(above it the rod's viscous forces swamp its inertia)")


def _fit(res: Callable[[float], np.ndarray], tau0: float, diff_step: float,
         xtol: float = 1e-10, ftol: float = 1e-12, tau_max: float = np.inf):
    nfev = [0]

    def fun(p: np.ndarray) -> np.ndarray:
        nfev[0] += 1
        return res(float(p[0]))

    x = min(max(tau0, TAU_MIN), tau_max)
    # restarted from its own result until it stays put: a trust region that collapsed
    # after an overshoot meets xtol far from the minimum (measured: the paper's record
    # from tau0 = 42.8 ms stopped at 51.3 ms with a 95 % interval of +-0.15 ms, three
    # times the residual of tau = 50 ms; the restart reaches 50.0 ms)
    for _ in range(4):
        sol = least_squares(fun, x0=[x], bounds=([TAU_MIN], [tau_max]), method="trf",
                            jac="2-point", diff_step=diff_step, x_scale=[x], xtol=xtol,
                            ftol=ftol, gtol=1e-12, max_nfev=50)
        moved = abs(float(sol.x[0]) - x) > 10 * xtol * x
        x = float(sol.x[0])
        if not moved:
            break
    return sol, nfev[0]


def calibrate_decrements(delta: Sequence[float], problem=None,
                         tau0: float | None = None) -> CalibrationResult:
    """Fit tau (s) to measured log decrements with the linear modal prediction.

    Parameters
    ----------
    delta : sequence of float
        Logarithmic decrements (-), at least 2.
    problem : Problem, optional
        The rod (geometry, material, elements of the modal model); default the
        paper's at N = 16.
    tau0 : float, optional
        Starting value (s); default from the mean decrement and the modal frequency.

    Returns
    -------
    CalibrationResult
    """
    d = validate_decrements(delta)
    check_tau0(tau0, problem)
    model = decrement_model(problem)
    if tau0 is None:
        d1 = model(0.04)
        z1 = float(damping_ratios([d1])[0])
        zm = float(damping_ratios([float(np.mean(d))])[0])
        tau0 = 0.04 * zm / z1
    sol, nfev = _fit(lambda tau: np.full(d.size, model(tau)) - d, tau0, 1e-6,
                     tau_max=tau_range(problem)[1])
    tau = float(sol.x[0])
    se, ci = _ci(tau, sol.jac, sol.fun)
    k = np.arange(1, d.size + 1, dtype=float)
    rms = float(np.sqrt(np.mean(sol.fun**2)))
    return CalibrationResult(mode="decrements", tau=tau, std_error=se, ci95=ci, tau0=tau0,
                             residual_rms=rms, n_data=d.size,
                             nfev=nfev, njev=int(sol.njev or 0), success=bool(sol.success),
                             message=str(sol.message), data_t=k, data_y=d, fit_t=k,
                             fit_y=np.full(d.size, model(tau)),
                             doubts=fit_doubts(tau, ci, rms, float(np.sqrt(np.mean(d**2))),
                                               TAU_MIN))


def calibrate_signal(t: Sequence[float], x: Sequence[float], problem=None,
                     tau0: float | None = None, n_elements: int = 16,
                     output_step: float = 0.002) -> CalibrationResult:
    """Fit tau (s) to a measured tip signal x(t) (m) by simulations of the cantilever.

    Parameters
    ----------
    t, x : sequence of float
        Time since release (s) and tip x (m); checked (finite, increasing, sampled
        finely enough for the rod's first period).
    problem : Problem, optional
        The rod that was released (geometry, material, tip force); default the paper's.
        Its ``rod.elements`` is replaced by ``n_elements`` (coarse, for speed) and its
        t_end by the end of the data.
    tau0 : float, optional
        Starting value (s); default from the first log decrement of the data and the
        linear prediction of the problem.
    n_elements : int
        Elements of the model simulated in the fit.
    output_step : float
        Sampling (s) of the model's signal.

    Returns
    -------
    CalibrationResult
        tau with its standard error and 95 % interval, residual, fit curve, and
        ``accepted`` (False with the reasons when the fit is doubtful).
    """
    t, x = validate_signal(t, x)
    sc = _problem(problem, n_elements=n_elements, output_step=output_step)
    check_tau0(tau0, sc)
    check_record(t, x, sc)
    lp = sc.linear_prediction()
    if tau0 is None:
        # maxima about the centre the record decays to (a loaded rod vibrates about its
        # equilibrium, not about the reference): the mean of its last period
        _, xk = smoothed_maxima(t, x - record_centre(t, x))
        z = float(np.mean(damping_ratios(log_decrements(xk)))) if xk.size >= 2 else 0.0
        tau0 = min(max(2 * z / lp["omega_1"], 1e-4), tau_range(sc)[1])
    t_end = float(t[-1]) + 2 * output_step

    def model_at(tau: float, tq: np.ndarray) -> np.ndarray:
        ts, xs = _simulate_tip(sc, tau, t_end)
        return CubicSpline(ts, xs)(tq)

    sol, nfev = _fit(lambda tau: model_at(tau, t) - x, tau0, 1e-4, xtol=1e-4,
                     ftol=1e-6, tau_max=tau_range(sc)[1])
    tau = float(sol.x[0])
    se, ci = _ci(tau, sol.jac, sol.fun)
    tf = np.linspace(float(t[0]), float(t[-1]), 2000)
    rms = float(np.sqrt(np.mean(sol.fun**2)))
    return CalibrationResult(mode="signal", tau=tau, std_error=se, ci95=ci, tau0=tau0,
                             residual_rms=rms, n_data=t.size,
                             nfev=nfev, njev=int(sol.njev or 0), success=bool(sol.success),
                             message=str(sol.message), data_t=t, data_y=x, fit_t=tf,
                             fit_y=model_at(tau, tf),
                             doubts=fit_doubts(tau, ci, rms, float(np.sqrt(np.mean(x**2))),
                                               TAU_MIN, noise_rms(x)))


def check_record(t: np.ndarray, x: np.ndarray, problem) -> None:
    """Reject a signal the problem's model cannot produce (see
    :func:`check_signal_against_model`), before any fitting."""
    lp = problem.linear_prediction()
    if lp is None:
        raise ValueError(f"problem {problem.name!r}: the signal calibration needs a straight "
                         "clamped-free rod whose end maxima are analysed (analysis.maxima)")
    check_signal_against_model(t, x, _release_x(problem), lp["period_1"])


def _release_x(problem) -> float:
    """The static displacement (m) of the maxima coordinate under the problem's loads at
    t = 0-: the release deflection."""
    from runtime.problem.assemble import build_model
    from runtime.simulate.simulate import static_equilibrium

    model = build_model(problem)
    st = static_equilibrium(problem, model)
    c, ref = _component(problem)
    return float(st.tip[c] - ref)


# --------------------------------------------------------------------------------------
# Plot
# --------------------------------------------------------------------------------------


def plot_calibration(res: CalibrationResult, path: str | Path) -> Path:
    """The fitted curve over the data (PNG, matplotlib Agg), written atomically."""
    from runtime.io.figures import pyplot

    plt = pyplot()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig, ax = plt.subplots(figsize=(8, 4.5))
    label = (f"fit: tau = {res.tau * 1e3:.3f} ms, 95 % CI [{res.ci95[0] * 1e3:.3f}, "
             f"{res.ci95[1] * 1e3:.3f}] ms")
    if res.mode == "signal":
        ax.plot(res.data_t, res.data_y, ".", ms=2, color="0.5", label="data")
        ax.plot(res.fit_t, res.fit_y, "-", color="C3", lw=1.2, label=label)
        ax.set_xlabel("t [s]")
        ax.set_ylabel("tip x [m]")
    else:
        ax.plot(res.data_t, res.data_y, "o", color="0.3", label="measured decrements")
        ax.plot(res.fit_t, res.fit_y, "-", color="C3", label=label + " (linear modal)")
        ax.set_xlabel("cycle k")
        ax.set_ylabel("log decrement delta_k [-]")
    ax.legend(loc="best", fontsize=8)
    ax.grid(alpha=0.3)
    from runtime.io.atomic import save_figure

    try:
        return save_figure(fig, path, dpi=120, bbox_inches="tight")
    finally:
        plt.close(fig)
