"""Post-processing of cantilever runs: tip maxima, decrements, damping ratios, energy audit.

The quantities follow the paper's Sect. 5 (Linn, Lang, Tuganov 2013):

- tip amplitude ``x(t) = e1 . phi(L, t)`` (m), oscillating about 0 after release;
- logarithmic decrement between successive positive maxima ``x_k = x(t_k)``:
  ``delta_k = ln(x_k / x_{k+1})``;
- damping ratio defined implicitly by ``delta_k = 2 pi zeta_k / sqrt(1 - zeta_k^2)``
  (Craig and Kurdila 2006, ch. 3.5), i.e. ``zeta_k = delta_k / sqrt(4 pi^2 + delta_k^2)``;
- period per cycle ``T_k = t_{k+1} - t_k`` (s);
- linear stiffness-proportional Kelvin-Voigt damping: ``zeta = omega tau_E / 2``;
  Euler-Bernoulli cantilever period ``T = 2 pi / (beta_1 L)^2 L^2 sqrt(rho A / (E I))``;
- energy audit of the balance ``d/dt (T + W) = -2 D_v + P_ext`` (paper Eqs. (10), (11)):
  ``T + W + int 2 D_v dt - int P_ext dt`` must stay equal to its initial value.

Only NumPy and SciPy are used. Bad input raises :class:`ValueError` naming the parameter.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

__all__ = [
    "BETA1_L",
    "EnergyAudit",
    "BEAT_SCATTER",
    "EnvelopeFit",
    "beat_warning",
    "cumulative_integral",
    "damping_ratios",
    "energy_audit",
    "exponential_envelope",
    "find_maxima",
    "linear_damping_ratio",
    "log_decrements",
    "period_euler_bernoulli",
    "periods",
    "ratio_scatter",
    "tip_summary",
]

#: first root of ``1 + cos(x) cosh(x) = 0`` (cantilever, Euler-Bernoulli); ``BETA1_L**2 =
#: 3.5160152...`` is the paper's "3.516".
BETA1_L: float = 1.8751040687119611

ArrayLike = np.ndarray | list[float] | tuple[float, ...]
Dense = Callable[[float], float]


# ----------------------------------------------------------------------------- validation
def _as_1d(name: str, a: object, *, min_len: int = 1) -> np.ndarray:
    arr = np.asarray(a, dtype=float)
    if arr.ndim != 1:
        raise ValueError(f"{name} must be one-dimensional, got shape {arr.shape}")
    if arr.size < min_len:
        raise ValueError(f"{name} needs at least {min_len} values, got {arr.size}")
    bad = ~np.isfinite(arr)
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        raise ValueError(f"{name} contains a non-finite value {arr[i]!r} at index {i}")
    return arr


def _increasing(name: str, t: np.ndarray) -> None:
    d = np.diff(t)
    if (d <= 0).any():
        i = int(np.flatnonzero(d <= 0)[0])
        raise ValueError(
            f"{name} must be strictly increasing, but {name}[{i + 1}] = {t[i + 1]!r} "
            f"<= {name}[{i}] = {t[i]!r}"
        )


# ----------------------------------------------------------------------------- maxima
def _parabola_vertex(
    ta: float, tb: float, tc: float, xa: float, xb: float, xc: float
) -> tuple[float, float]:
    """Vertex of the parabola through three points (non-uniform spacing allowed)."""
    d1, d2 = tb - ta, tb - tc
    num = d1 * d1 * (xb - xc) - d2 * d2 * (xb - xa)
    den = d1 * (xb - xc) - d2 * (xb - xa)
    if den == 0.0:  # three collinear/flat points: keep the sample
        return tb, xb
    tv = tb - 0.5 * num / den
    tv = min(max(tv, ta), tc)
    # Lagrange form of the parabola evaluated at the vertex
    la = (tv - tb) * (tv - tc) / ((ta - tb) * (ta - tc))
    lb = (tv - ta) * (tv - tc) / ((tb - ta) * (tb - tc))
    lc = (tv - ta) * (tv - tb) / ((tc - ta) * (tc - tb))
    return tv, la * xa + lb * xb + lc * xc


def _refine_dense(sol: Dense, dsol: Dense | None, a: float, b: float, tb: float) -> float:
    """Location of the maximum of ``sol`` in ``[a, b]`` (``tb`` the best sample)."""
    if dsol is not None:
        da, db = float(dsol(a)), float(dsol(b))
        if da > 0.0 > db:
            from scipy.optimize import brentq

            return brentq(
                lambda s: float(dsol(s)),
                a,
                b,
                xtol=1e-15 * max(1.0, abs(b)),
                rtol=4 * np.finfo(float).eps,
                maxiter=200,
            )
    from scipy.optimize import minimize_scalar

    res = minimize_scalar(
        lambda s: -float(sol(s)),
        bounds=(a, b),
        method="bounded",
        options={"xatol": 1e-14 * max(1.0, abs(b)), "maxiter": 500},
    )
    ts = float(res.x)
    return ts if float(sol(ts)) >= float(sol(tb)) else tb


def find_maxima(
    t: ArrayLike,
    x: ArrayLike,
    *,
    sol: Dense | None = None,
    dsol: Dense | None = None,
    method: str = "parabolic",
    positive_only: bool = True,
    t_min: float | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Local maxima of a sampled signal, refined between samples.

    t: sample times (s), strictly increasing, at least 3. x: signal (e.g. tip ``e1``
    position, m), same length. A sample ``i`` (not the first or last) with
    ``x[i-1] < x[i] >= x[i+1]`` marks a maximum in ``[t[i-1], t[i+1]]``, which is refined:

    - ``sol`` given (dense output ``sol(t) -> x``): bounded Brent maximisation of ``sol``
      in that bracket; if also ``dsol`` (``d sol/dt``) is given and changes sign there,
      Brent's root of ``dsol`` instead. The value ``x_k = sol(t_k)`` is then as accurate as
      the interpolant (to rounding); ``t_k`` to about ``sqrt(eps)`` relative with ``sol``
      alone (a maximum is flat), to rounding with ``dsol``.
    - no ``sol``, ``method="parabolic"``: vertex of the parabola through the three samples
      (error O(h^3) in ``t_k``/``x_k`` for sample spacing h, less near symmetric samples);
    - no ``sol``, ``method="spline"``: not-a-knot cubic spline of the samples used as
      ``sol``/``dsol`` (error O(h^4)).

    positive_only: keep only maxima with ``x_k > 0`` (oscillation about 0; the maxima used
    for decrements). t_min: ignore maxima before this time (s).
    Returns arrays ``(t_k, x_k)``, possibly empty.
    """
    t = _as_1d("t", t, min_len=3)
    x = _as_1d("x", x, min_len=3)
    if t.size != x.size:
        raise ValueError(f"t and x must have the same length, got {t.size} and {x.size}")
    _increasing("t", t)
    if method not in ("parabolic", "spline"):
        raise ValueError(f"method must be 'parabolic' or 'spline', got {method!r}")
    if dsol is not None and sol is None:
        raise ValueError("dsol needs sol (the dense signal) as well")
    if sol is None and method == "spline":
        from scipy.interpolate import CubicSpline

        spline = CubicSpline(t, x)
        deriv = spline.derivative()
        sol, dsol = (lambda s: float(spline(s))), (lambda s: float(deriv(s)))

    idx = np.flatnonzero((x[1:-1] > x[:-2]) & (x[1:-1] >= x[2:])) + 1
    tk: list[float] = []
    xk: list[float] = []
    for i in idx:
        if sol is None:
            tv, xv = _parabola_vertex(t[i - 1], t[i], t[i + 1], x[i - 1], x[i], x[i + 1])
        else:
            tv = _refine_dense(sol, dsol, float(t[i - 1]), float(t[i + 1]), float(t[i]))
            xv = float(sol(tv))
        if positive_only and not xv > 0.0:
            continue
        if t_min is not None and tv < t_min:
            continue
        if tk and tv <= tk[-1]:  # plateau duplicates
            continue
        tk.append(float(tv))
        xk.append(float(xv))
    return np.asarray(tk), np.asarray(xk)


# ----------------------------------------------------------------------------- decrements
def log_decrements(x_k: ArrayLike) -> np.ndarray:
    """Logarithmic decrements ``delta_k = ln(x_k / x_{k+1})`` of successive positive maxima.

    x_k: maxima (m), at least 2, all positive. Returns ``len(x_k) - 1`` values.
    """
    x_k = _as_1d("x_k", x_k, min_len=2)
    if (x_k <= 0).any():
        i = int(np.flatnonzero(x_k <= 0)[0])
        raise ValueError(f"x_k must be positive maxima, got x_k[{i}] = {x_k[i]!r}")
    return np.log(x_k[:-1] / x_k[1:])


def damping_ratios(delta: ArrayLike) -> np.ndarray:
    """Damping ratios from decrements: invert ``delta = 2 pi zeta / sqrt(1 - zeta^2)``.

    ``zeta = delta / sqrt(4 pi^2 + delta^2)`` (dimensionless; negative for growth).
    """
    delta = _as_1d("delta", delta, min_len=1)
    return delta / np.sqrt(4.0 * math.pi**2 + delta**2)


#: successive damping ratios whose scatter about their linear trend exceeds this fraction
#: of their mean magnitude are taken for two or more modes beating in the signal
BEAT_SCATTER = 0.25
#: fewest ratios the beat test looks at (three points always lie near some trend)
BEAT_MIN_RATIOS = 4


def ratio_scatter(zeta: ArrayLike) -> float:
    """RMS deviation of successive damping ratios from their least-squares line in the
    cycle number, over their mean magnitude (NaN for fewer than ``BEAT_MIN_RATIOS``).

    One mode decaying gives ratios that lie on a smooth curve (constant in the linear
    regime, rising towards the linear value after a large release: the paper's
    cantilever, whose first ratios grow by ~40 % over five cycles with a scatter of
    ~1 %); two modes in the signal make the maxima beat and the ratios jump up and down
    about their trend."""
    z = np.asarray(zeta, dtype=float)
    z = z[np.isfinite(z)]
    if z.size < BEAT_MIN_RATIOS:
        return math.nan
    k = np.arange(z.size, dtype=float)
    slope, icpt = np.polyfit(k, z, 1)
    scale = float(np.mean(np.abs(z)))
    if scale == 0.0:
        return math.nan
    return float(np.sqrt(np.mean((z - (icpt + slope * k)) ** 2)) / scale)


def beat_warning(zeta: ArrayLike, coordinate: str | None = None) -> str | None:
    """A warning when successive damping ratios scatter by more than ``BEAT_SCATTER`` of
    their mean about their linear trend (:func:`ratio_scatter`): the maxima-based ratios
    then mix modes and say little about any one of them; else None."""
    r = ratio_scatter(zeta)
    if not (r > BEAT_SCATTER):
        return None
    z = np.asarray(zeta, dtype=float)
    where = f" of {coordinate}" if coordinate else ""
    return (f"the damping ratios of successive maxima{where} scatter by {100 * r:.0f} % about "
            f"their trend ({float(np.min(z)):.3g} ... {float(np.max(z)):.3g}; more than "
            f"{100 * BEAT_SCATTER:.0f} %): two or more modes beat in this signal, so the "
            "maxima-based ratios mix them; take the modal damping from `kvrod modes` "
            "(--deformed about a loaded equilibrium), or analyse a coordinate that one mode "
            "dominates")


def periods(t_k: ArrayLike) -> np.ndarray:
    """Periods per cycle ``T_k = t_{k+1} - t_k`` (s) from successive maxima times."""
    t_k = _as_1d("t_k", t_k, min_len=2)
    _increasing("t_k", t_k)
    return np.diff(t_k)


@dataclass(frozen=True)
class EnvelopeFit:
    """Exponential envelope ``x(t) = a exp(-b t)``: a in m, b in 1/s; fitted over
    ``t_range`` (s) from ``n`` maxima; ``rms_log`` the RMS residual of ``ln x``."""

    a: float
    b: float
    t_range: tuple[float, float]
    n: int
    rms_log: float

    def __call__(self, t: float | np.ndarray) -> float | np.ndarray:
        return self.a * np.exp(-self.b * np.asarray(t))


def exponential_envelope(
    t_k: ArrayLike,
    x_k: ArrayLike,
    *,
    t_min: float | None = None,
    t_max: float | None = None,
    first: int | None = None,
    last: int | None = None,
) -> EnvelopeFit:
    """Least-squares fit ``x_k ~ a exp(-b t_k)`` (linear regression of ``ln x_k`` on ``t_k``).

    t_k (s), x_k (m, positive): maxima, e.g. from :func:`find_maxima`. The fit range is
    selected by slice ``[first:last]`` of the maxima and then by ``t_min <= t_k <= t_max``;
    use the later cycles (linear regime) for the paper's Fig. 3 envelopes. At least two
    maxima must remain.
    """
    t_k = _as_1d("t_k", t_k, min_len=2)
    x_k = _as_1d("x_k", x_k, min_len=2)
    if t_k.size != x_k.size:
        raise ValueError(f"t_k and x_k must have the same length, got {t_k.size}, {x_k.size}")
    if (x_k <= 0).any():
        raise ValueError("x_k must be positive for an exponential envelope")
    sel = np.zeros(t_k.size, dtype=bool)
    sel[slice(first, last)] = True
    if t_min is not None:
        sel &= t_k >= t_min
    if t_max is not None:
        sel &= t_k <= t_max
    if sel.sum() < 2:
        raise ValueError(
            f"t_k: fewer than 2 maxima in the fit range (first={first}, last={last}, "
            f"t_min={t_min}, t_max={t_max}), got {int(sel.sum())}"
        )
    ts, ys = t_k[sel], np.log(x_k[sel])
    slope, intercept = np.polyfit(ts, ys, 1)
    res = ys - (intercept + slope * ts)
    return EnvelopeFit(
        a=float(math.exp(intercept)),
        b=float(-slope),
        t_range=(float(ts[0]), float(ts[-1])),
        n=int(sel.sum()),
        rms_log=float(np.sqrt(np.mean(res**2))),
    )


def tip_summary(
    t: ArrayLike,
    x: ArrayLike,
    *,
    sol: Dense | None = None,
    dsol: Dense | None = None,
    method: str = "parabolic",
) -> dict[str, list]:
    """Maxima, decrements, damping ratios and periods of a tip signal, as JSON-ready lists.

    Same arguments as :func:`find_maxima` (positive maxima only). Keys: ``peaks`` (list of
    ``{"t": s, "x": m}``), ``log_decrements``, ``damping_ratios``, ``periods`` (s). With
    fewer than two maxima (e.g. a run that failed early) the last three lists are empty
    instead of raising, so a partial run can still be summarised; invalid samples
    (non-finite, non-monotone ``t``) still raise :class:`ValueError`.
    """
    tk, xk = find_maxima(t, x, sol=sol, dsol=dsol, method=method)
    out: dict[str, list] = {
        "peaks": [{"t": float(a), "x": float(b)} for a, b in zip(tk, xk, strict=True)],
        "log_decrements": [],
        "damping_ratios": [],
        "periods": [],
    }
    if tk.size >= 2:
        delta = log_decrements(xk)
        out["log_decrements"] = delta.tolist()
        out["damping_ratios"] = damping_ratios(delta).tolist()
        out["periods"] = periods(tk).tolist()
    return out


# ----------------------------------------------------------------------------- energy
def cumulative_integral(
    t: ArrayLike,
    y: ArrayLike | None = None,
    *,
    fun: Callable[[float], float] | None = None,
    gauss_points: int = 4,
) -> np.ndarray:
    """Cumulative integral ``int_{t_0}^{t_i} y dt`` at every sample ``t_i`` (starts at 0).

    Either samples ``y`` (trapezoidal rule: error ``-h^3/12 y''`` per interval, O(h^2)
    overall) or a dense callable ``fun(t)`` (Gauss-Legendre with ``gauss_points`` nodes on
    each interval ``[t_i, t_{i+1}]``: exact for polynomials of degree ``2 n - 1``, error
    O(h^(2n)) for smooth integrands). With ``t`` the integrator's step points and ``fun``
    built on its dense output, the quadrature error is far below the integrator's own
    error, so the energy balance then measures the time-integration error alone.
    """
    t = _as_1d("t", t, min_len=2)
    _increasing("t", t)
    if (y is None) == (fun is None):
        raise ValueError("give exactly one of y (samples) and fun (dense callable)")
    if y is not None:
        y = _as_1d("y", y, min_len=2)
        if y.size != t.size:
            raise ValueError(f"y must have the length of t ({t.size}), got {y.size}")
        inc = 0.5 * np.diff(t) * (y[1:] + y[:-1])
    else:
        if gauss_points < 1:
            raise ValueError(f"gauss_points must be >= 1, got {gauss_points!r}")
        xg, wg = np.polynomial.legendre.leggauss(gauss_points)
        h = np.diff(t)
        mid = 0.5 * (t[1:] + t[:-1])
        inc = np.zeros(h.size)
        for xi, wi in zip(xg, wg, strict=True):
            vals = np.array([float(fun(s)) for s in mid + 0.5 * h * xi])
            inc += wi * vals
        inc *= 0.5 * h
        if not np.isfinite(inc).all():
            raise ValueError("fun returned a non-finite value")
    return np.concatenate(([0.0], np.cumsum(inc)))


@dataclass(frozen=True)
class EnergyAudit:
    """Energy balance of a run (paper Eqs. (10), (11)); energies in J, on the samples ``t``.

    dissipated: ``int 2 D_v dt``; external_work: ``int P_ext dt``;
    balance: ``T + W + dissipated - external_work`` (constant in exact arithmetic);
    relative_error: ``(balance - balance[0]) / E0`` with ``E0 = reference_energy`` (the
    initial ``T + W`` unless given); max_abs_error: ``max |relative_error|``.
    """

    t: np.ndarray
    dissipated: np.ndarray
    external_work: np.ndarray
    balance: np.ndarray
    reference_energy: float
    relative_error: np.ndarray
    max_abs_error: float


def energy_audit(
    t: ArrayLike,
    kinetic: ArrayLike,
    elastic: ArrayLike,
    dissipation_rate: ArrayLike | Callable[[float], float],
    external_power: ArrayLike | Callable[[float], float] | None = None,
    *,
    reference_energy: float | None = None,
    gauss_points: int = 4,
) -> EnergyAudit:
    """Relative energy-balance error ``(T + W + int 2 D_v dt - int P dt - E0) / E0``.

    t: sample times (s), strictly increasing (at least 2). kinetic ``T`` and elastic ``W``
    (J): energies at ``t``. dissipation_rate: the paper's dissipation function ``D_v`` of
    Eq. (11) in W - the mechanical power lost is ``2 D_v`` (``D_v`` is half the viscous
    stress power) - as samples at ``t`` or a dense callable ``D_v(t)``. external_power:
    power of the external loads ``P_ext`` (W), samples or callable; None for none (a dead
    load that is switched off at release does no work afterwards). Samples are integrated
    by the trapezoidal rule, callables by Gauss-Legendre per interval (see
    :func:`cumulative_integral` for the accuracy). reference_energy: the energy scale
    ``E0`` (J) the change of the balance is divided by; default ``T[0] + W[0]`` (then the
    error is exactly ``(T + W + dissipated - work - E0) / E0``), which must be positive.
    """
    t = _as_1d("t", t, min_len=2)
    _increasing("t", t)
    T = _as_1d("kinetic", kinetic, min_len=2)
    W = _as_1d("elastic", elastic, min_len=2)
    for name, arr in (("kinetic", T), ("elastic", W)):
        if arr.size != t.size:
            raise ValueError(f"{name} must have the length of t ({t.size}), got {arr.size}")

    def integrate(name: str, v: ArrayLike | Callable[[float], float] | None) -> np.ndarray:
        if v is None:
            return np.zeros(t.size)
        if callable(v):
            return cumulative_integral(t, fun=v, gauss_points=gauss_points)
        arr = _as_1d(name, v, min_len=2)
        if arr.size != t.size:
            raise ValueError(f"{name} must have the length of t ({t.size}), got {arr.size}")
        return cumulative_integral(t, arr)

    dissipated = 2.0 * integrate("dissipation_rate", dissipation_rate)
    work = integrate("external_power", external_power)
    E0 = float(T[0] + W[0]) if reference_energy is None else float(reference_energy)
    if not (math.isfinite(E0) and E0 > 0.0):
        raise ValueError(
            f"reference_energy must be positive and finite, got {E0!r}"
            + (" (T[0] + W[0]; pass reference_energy)" if reference_energy is None else "")
        )
    balance = T + W + dissipated - work
    rel = (balance - balance[0]) / E0
    return EnergyAudit(
        t=t,
        dissipated=dissipated,
        external_work=work,
        balance=balance,
        reference_energy=E0,
        relative_error=rel,
        max_abs_error=float(np.max(np.abs(rel))),
    )


# ----------------------------------------------------------------------------- linear theory
def linear_damping_ratio(omega: float | np.ndarray, tau: float) -> float | np.ndarray:
    """Modal damping ratio ``omega tau / 2`` of stiffness-proportional Kelvin-Voigt damping
    (paper Eq. (9) with ``tau_B = tau_S = tau_E = tau``). omega in rad/s, tau in s."""
    if not (math.isfinite(tau) and tau >= 0):
        raise ValueError(f"tau must be finite and >= 0, got {tau!r}")
    if np.ndim(omega):
        return 0.5 * np.asarray(omega, dtype=float) * tau
    return 0.5 * float(omega) * tau


def period_euler_bernoulli(L: float, rho: float, A: float, E: float, I: float) -> float:
    """First cantilever period ``T = 2 pi / (beta_1 L)^2 L^2 sqrt(rho A / (E I))`` in s.

    L (m), rho (kg/m^3), A (m^2), E (Pa), I (m^4); ``(beta_1 L)^2 = 3.5160152...``
    (the paper's 3.516). The paper's data give 1.76182 s.
    """
    for name, v in (("L", L), ("rho", rho), ("A", A), ("E", E), ("I", I)):
        if not (math.isfinite(v) and v > 0):
            raise ValueError(f"{name} must be positive and finite, got {v!r}")
    return 2.0 * math.pi / BETA1_L**2 * L * L * math.sqrt(rho * A / (E * I))
