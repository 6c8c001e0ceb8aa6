"""Transient response of a Kelvin-Voigt Euler-Bernoulli cantilever to a tip force history,
by modal superposition (a reference written apart from kvrod: closed-form mode shapes and
one damped oscillator per mode).

A uniform cantilever (clamped at x = 0, free at x = L) with bending stiffness EI, mass per
length rhoA and Kelvin-Voigt damping EI tau_E (so each mode has the damping ratio
zeta_k = omega_k tau_E / 2) under a transverse tip force F(t): with the modes normalised to
int_0^L phi_k^2 dx = L (then phi_k(L) = 2 (-1)^(k+1)) the modal coordinates obey

    q_k'' + tau_E omega_k^2 q_k' + omega_k^2 q_k = phi_k(L) F(t) / (rhoA L),

and the tip displacement is w(L, t) = sum_k phi_k(L) q_k(t). The forcing is piecewise
linear (a table), and each oscillator is integrated piece by piece in closed form over
the pieces (the exact response of a linear oscillator to a linear force), so the reference
has no time-step error.
"""

from __future__ import annotations

import math

import numpy as np

from references.beams import euler_bernoulli_roots


def _piece(q: float, v: float, w: float, z: float, f0: float, f1: float, T: float,
           t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Exact (q, q') at times t in [0, T] of q'' + 2 z w q' + w^2 q = f0 + (f1 - f0) t / T
    from (q, v) at t = 0 (underdamped, z < 1)."""
    s = (f1 - f0) / T if T > 0 else 0.0
    # particular solution of the linear force: a + b t
    b = s / w**2
    a = (f0 - 2 * z * w * b) / w**2
    wd = w * math.sqrt(1.0 - z * z)
    c1 = q - a
    c2 = (v - b + z * w * c1) / wd
    e = np.exp(-z * w * t)
    cs, sn = np.cos(wd * t), np.sin(wd * t)
    qt = a + b * t + e * (c1 * cs + c2 * sn)
    vt = b + e * ((-z * w * c1 + wd * c2) * cs + (-z * w * c2 - wd * c1) * sn)
    return qt, vt


def cantilever_tip_response(t: np.ndarray, force_table: list[tuple[float, float]], *,
                            L: float, EI: float, rhoA: float, tau_E: float,
                            modes: int = 8) -> np.ndarray:
    """Tip displacement w(L, t) (m) at times ``t`` (s, ascending, >= 0) of a cantilever at
    rest at t = 0 under the tip force ``force_table`` = [(t_i, F_i), ...] (N, piecewise
    linear, held at its last value after the last point, 0 before the first), by
    superposing ``modes`` Euler-Bernoulli modes (see the module docstring). Modes that
    are overdamped (zeta_k >= 1) are skipped: a short pulse hardly excites them."""
    t = np.asarray(t, dtype=float)
    ts = np.array([p[0] for p in force_table], dtype=float)
    fs = np.array([p[1] for p in force_table], dtype=float)
    knots = np.unique(np.concatenate([[0.0], ts[ts > 0.0], [max(t.max(), ts.max()) + 1.0]]))
    force = np.interp(knots, ts, fs, left=0.0, right=fs[-1])
    beta = euler_bernoulli_roots(modes) / L
    out = np.zeros_like(t)
    for k in range(modes):
        w = beta[k] ** 2 * math.sqrt(EI / rhoA)
        z = 0.5 * w * tau_E
        if z >= 1.0:
            continue
        phiL = 2.0 * (-1) ** k
        scale = phiL / (rhoA * L)
        q = v = 0.0
        for j in range(knots.size - 1):
            a, b = knots[j], knots[j + 1]
            inside = (t >= a) & (t < b) if j < knots.size - 2 else (t >= a)
            if inside.any():
                qt, _ = _piece(q, v, w, z, scale * force[j], scale * force[j + 1], b - a,
                               t[inside] - a)
                out[inside] += phiL * qt
            qe, ve = _piece(q, v, w, z, scale * force[j], scale * force[j + 1], b - a,
                            np.array([b - a]))
            q, v = float(qe[0]), float(ve[0])
    return out
