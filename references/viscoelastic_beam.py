"""Linear viscoelastic cantilever, bar and shaft: complex eigenvalues and base excitation.

Independent of kvrod (NumPy/SciPy only). SI units; ``s`` is the (complex) Laplace variable
in 1/s, ``omega`` an angular frequency in rad/s. Moduli are passed as callables of ``s``:
``E(s)`` (uniaxial, Pa) and ``G(s)`` (shear, Pa), e.g. Kelvin-Voigt
``E(s) = E (1 + s tau_E)``, ``G(s) = G (1 + s tau_S)`` (:func:`kelvin_voigt_moduli`) or a
generalized Maxwell solid. By the correspondence principle the undamped equations hold with
``E -> E(s)``, ``G -> G(s)``; a free vibration ``~ e^{lambda t}`` has ``s = lambda``, a
harmonic steady state ``~ e^{i omega t}`` has ``s = i omega``.

Complex eigenvalues (``lambda = -zeta |lambda| + i omega_d``; damping ratio
``zeta = -Re(lambda)/|lambda|``, damped frequency ``omega_d = Im(lambda)``):

- Euler-Bernoulli clamped-free bending, ``rho A lambda^2 + (beta_n/L)^4 E(lambda) I = 0``
  with ``beta_n L`` the roots of ``1 + cos x cosh x = 0``;
- axial modes of a clamped-free bar, ``rho lambda^2 + (k_n/L)^2 E(lambda) = 0``, and torsion
  ``rho I_3 lambda^2 + (k_n/L)^2 G(lambda) J_T = 0``, ``k_n = (2n - 1) pi / 2``;
- Timoshenko clamped-free bending (shear ``kappa A G(s)``, rotary inertia ``rho I``): zeros
  of the complex transfer determinant ``det P(s)[2:, 2:]`` (see :func:`timoshenko_matrix`).

All are solved by a complex secant iteration, continued in the moduli from the undamped
problem (reference moduli ``|E(0)|``, ``|G(0)|``, whose roots are real): the moduli are
blended ``M_h(s) = M_ref + h (M(s) - M_ref)``, ``h = 0 -> 1``, following the root.
Overdamped (real) modes are not targeted.

Base excitation (clamp translating transversely, ``u_b(t) = X sin(omega t)``): in absolute
coordinates ``w(0) = X``, ``w'(0) = 0`` (resp. ``psi(0) = 0``) and a free tip. The steady
state is ``w(x, t) = Im(W(x) e^{i omega t})``; the transmissibility is ``T = W(L)/X`` and the
tip amplitude ``X |T|``.

- Euler-Bernoulli: ``W'''' = beta^4 W``, ``beta^4 = rho A omega^2 / (E(i omega) I)`` and
  ``W = a cosh + b sinh + c cos + d sin`` (of ``beta x``); the 4x4 boundary system is solved
  (:func:`euler_bernoulli_transmissibility`); its solution is the closed form
  ``T = (cos bL + cosh bL) / (1 + cos bL cosh bL)``
  (:func:`euler_bernoulli_transmissibility_closed`).
- Timoshenko: the transfer matrix of :func:`timoshenko_matrix` at ``s = i omega`` with
  ``(w, psi)(0) = (X, 0)`` and ``M(L) = Q(L) = 0``.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.linalg import expm
from scipy.optimize import brentq, minimize_scalar

from references.beams import euler_bernoulli_roots

__all__ = [
    "Modulus",
    "Resonance",
    "axial_eigenvalues",
    "damping_ratio",
    "euler_bernoulli_eigenvalues",
    "euler_bernoulli_transmissibility",
    "euler_bernoulli_transmissibility_closed",
    "kelvin_voigt_moduli",
    "paper_beam",
    "paper_base_excitation",
    "resonance",
    "timoshenko_determinant",
    "timoshenko_eigenvalues",
    "timoshenko_matrix",
    "timoshenko_transmissibility",
    "torsion_eigenvalues",
]

#: a modulus as a function of the complex Laplace variable ``s`` (Pa)
Modulus = Callable[[complex], complex]


def kelvin_voigt_moduli(
    E: float, nu: float, tau_E: float, tau_S: float
) -> tuple[Modulus, Modulus]:
    """``E(s) = E (1 + s tau_E)`` and ``G(s) = G (1 + s tau_S)``, ``G = E / (2 (1 + nu))``."""
    G = E / (2.0 * (1.0 + nu))
    return (lambda s: E * (1.0 + s * tau_E)), (lambda s: G * (1.0 + s * tau_S))


def damping_ratio(lam: complex | np.ndarray) -> float | np.ndarray:
    """``zeta = -Re(lambda) / |lambda|`` (dimensionless)."""
    return -np.real(lam) / np.abs(lam)


def _secant(
    f: Callable[[complex], complex],
    z0: complex,
    z1: complex,
    *,
    tol: float = 1e-14,
    maxiter: int = 100,
) -> complex:
    """Complex secant iteration for an analytic ``f``; stops when the step is below
    ``tol |z|``."""
    f0, f1 = f(z0), f(z1)
    for _ in range(maxiter):
        if f1 == 0:
            return z1
        if f1 == f0:
            break
        z2 = z1 - f1 * (z1 - z0) / (f1 - f0)
        if abs(z2 - z1) <= tol * abs(z2):
            return z2
        z0, f0, z1, f1 = z1, f1, z2, f(z2)
    if abs(z1 - z0) <= 1e3 * tol * abs(z1):  # stagnated at round-off level
        return z1
    raise RuntimeError(f"complex secant did not converge (last {z1!r}, step {z1 - z0!r})")


def _follow(
    residual: Callable[[complex, float], complex], lam0: complex, steps: int,
    *, max_move: float = 0.1, min_step: float = 1e-7,
) -> complex:
    """Track the root of ``residual(lambda, h)`` from ``h = 0`` (root ``lam0``) to ``h = 1``.

    Steps in ``h`` start at ``1/steps``; a step is accepted when the secant converges and
    the root moved by at most ``max_move |lambda|`` (from the last root and from the
    linear extrapolation), else it is halved. Why adaptive: with fixed steps the secant of
    a strongly damped high mode (a generalized Maxwell beam's 4th bending mode, whose
    moduli triple between relaxed and glassy) landed on the branch of mode 1.
    """
    lam, h, dh = lam0, 0.0, 1.0 / steps
    prev: tuple[complex, float] | None = None
    while h < 1.0:
        dh = min(dh, 1.0 - h)
        guess = lam if prev is None else lam + (lam - prev[0]) * dh / prev[1]
        if guess == lam:
            guess = lam * (1.0 + 1e-6j) + 1e-12
        h_new = 1.0 if dh >= 1.0 - h else h + dh
        try:
            new = _secant(lambda z, h=h_new: residual(z, h), lam, guess)
            ok = (abs(new - lam) <= max_move * abs(lam)
                  and abs(new - guess) <= max_move * abs(lam))
        except RuntimeError:
            ok = False
        if not ok:
            dh *= 0.5
            if dh < min_step:
                raise RuntimeError(f"root tracking lost the root near {lam!r} at h = {h:.3g}")
            continue
        prev, lam, h = (lam, dh), new, h_new
        dh = min(2.0 * dh, 1.0 / steps)
    return lam


def _blend(M: Modulus, M_ref: float, h: float) -> Modulus:
    return lambda s: M_ref + h * (M(s) - M_ref)


def _scalar_modal(c: float, M: Modulus, steps: int) -> complex:
    """Root near ``i sqrt(c |M(0)|)`` of ``lambda^2 + c M(lambda) = 0``."""
    M_ref = abs(M(0.0))
    if M_ref == 0:
        raise ValueError("modulus vanishes at s = 0: give a solid (E(0) != 0)")
    lam0 = 1j * math.sqrt(c * M_ref)

    def residual(z: complex, h: float) -> complex:
        return z * z / (c * M_ref) + _blend(M, M_ref, h)(z) / M_ref

    return _follow(residual, lam0, steps)


def euler_bernoulli_eigenvalues(
    n: int, *, L: float, rho: float, A: float, I: float, E: Modulus, steps: int = 8
) -> np.ndarray:
    """First ``n`` complex eigenvalues (1/s, ``Im > 0``) of the viscoelastic E-B cantilever:
    ``rho A lambda^2 + (beta_k / L)^4 E(lambda) I = 0``."""
    b = euler_bernoulli_roots(n) / L
    return np.array([_scalar_modal(bk**4 * I / (rho * A), E, steps) for bk in b])


def axial_eigenvalues(
    n: int, *, L: float, rho: float, E: Modulus, steps: int = 8
) -> np.ndarray:
    """Clamped-free (free-clamped) bar: ``rho lambda^2 + (k_n/L)^2 E(lambda) = 0``,
    ``k_n = (2n - 1) pi / 2`` (1/s)."""
    k = (2 * np.arange(1, n + 1) - 1) * math.pi / 2 / L
    return np.array([_scalar_modal(kk**2 / rho, E, steps) for kk in k])


def torsion_eigenvalues(
    n: int, *, L: float, rho: float, J_T: float, I3: float, G: Modulus, steps: int = 8
) -> np.ndarray:
    """Clamped-free shaft: ``rho I3 lambda^2 + (k_n/L)^2 G(lambda) J_T = 0`` (1/s).

    J_T: Saint-Venant torsion constant (m^4); I3: polar moment of area (m^4)."""
    k = (2 * np.arange(1, n + 1) - 1) * math.pi / 2 / L
    return np.array([_scalar_modal(kk**2 * J_T / (rho * I3), G, steps) for kk in k])


# ----------------------------------------------------------------------------- Timoshenko
def timoshenko_matrix(
    s: complex, *, L: float, rhoA: float, rhoI: float, EI: complex, kGA: complex
) -> np.ndarray:
    """First-order system ``y' = A y`` (``' = d/d(x/L)``) for ``y = (w/L, psi, M L/EI,
    Q L^2/EI)`` of the Laplace-transformed Timoshenko beam::

        w'   = psi + Q / kGA          psi' = M / EI
        M'   = -Q + rho I s^2 psi     Q'   = rho A s^2 w

    (``Q = kGA (w' - psi)``, ``M = EI psi'``; for ``s = i omega`` the inertia terms are
    ``-rho omega^2 (.)``). ``EI``, ``kGA`` are the complex section stiffnesses at ``s``.
    """
    return np.array(
        [
            [0.0, 1.0, 0.0, EI / (kGA * L * L)],
            [0.0, 0.0, 1.0, 0.0],
            [0.0, rhoI * s * s * L * L / EI, 0.0, -1.0],
            [rhoA * s * s * L**4 / EI, 0.0, 0.0, 0.0],
        ],
        dtype=complex,
    )


def timoshenko_determinant(
    s: complex, *, L: float, rhoA: float, rhoI: float, EI: complex, kGA: complex
) -> complex:
    """Clamped-free frequency function ``det P[2:, 2:]``, ``P = expm(A(s))`` (zero at the
    eigenvalues): the clamp leaves ``(0, 0, M0, Q0)``, the free end needs ``M = Q = 0``."""
    P = expm(timoshenko_matrix(s, L=L, rhoA=rhoA, rhoI=rhoI, EI=EI, kGA=kGA))
    return P[2, 2] * P[3, 3] - P[2, 3] * P[3, 2]


def _timoshenko_real_roots(
    n: int, *, L: float, rhoA: float, rhoI: float, EI: float, kGA: float
) -> np.ndarray:
    """Undamped (real-moduli) frequencies: sign changes of the real determinant on a grid
    below the E-B frequencies, refined with Brent's method (rad/s)."""
    b = euler_bernoulli_roots(n + 1)
    w_eb = b**2 * math.sqrt(EI / (rhoA * L**4))
    w_max = 0.5 * (w_eb[n - 1] + w_eb[n])
    grid = np.linspace(1e-3 * w_eb[0], w_max, 200 * n + 1)

    def f(w: float) -> float:
        d = timoshenko_determinant(1j * w, L=L, rhoA=rhoA, rhoI=rhoI, EI=EI, kGA=kGA)
        return float(d.real)

    vals = [f(w) for w in grid]
    roots: list[float] = []
    for i in range(len(grid) - 1):
        if vals[i] * vals[i + 1] < 0:
            roots.append(brentq(f, grid[i], grid[i + 1], xtol=1e-14 * w_max, rtol=1e-15))
            if len(roots) == n:
                return np.array(roots)
    raise RuntimeError(f"found only {len(roots)} Timoshenko roots")  # pragma: no cover


def timoshenko_eigenvalues(
    n: int,
    *,
    L: float,
    rho: float,
    A: float,
    I: float,
    kappa: float,
    E: Modulus,
    G: Modulus,
    rotary_inertia: bool = True,
    steps: int = 8,
) -> np.ndarray:
    """First ``n`` complex eigenvalues (1/s) of the viscoelastic Timoshenko cantilever.

    ``EI(s) = E(s) I``, ``kGA(s) = kappa A G(s)``; rotary inertia ``rho I`` unless
    ``rotary_inertia=False``. Starts from the real roots with moduli ``|E(0)|, |G(0)|``.
    """
    rhoA, rhoI = rho * A, (rho * I if rotary_inertia else 0.0)
    E_ref, G_ref = abs(E(0.0)), abs(G(0.0))
    w0 = _timoshenko_real_roots(
        n, L=L, rhoA=rhoA, rhoI=rhoI, EI=E_ref * I, kGA=kappa * A * G_ref
    )
    out = []
    for w in w0:

        def residual(z: complex, h: float) -> complex:
            Ez = E_ref + h * (E(z) - E_ref)
            Gz = G_ref + h * (G(z) - G_ref)
            return timoshenko_determinant(
                z, L=L, rhoA=rhoA, rhoI=rhoI, EI=Ez * I, kGA=kappa * A * Gz
            )

        out.append(_follow(residual, 1j * w, steps))
    out_arr = np.array(out)
    _check_distinct(out_arr)
    return out_arr


def _check_distinct(lam: np.ndarray) -> None:
    """RuntimeError when two tracked roots coincide (a root tracking jumped branches)."""
    for i in range(lam.size):
        for j in range(i):
            if abs(lam[i] - lam[j]) <= 1e-8 * max(abs(lam[i]), abs(lam[j])):
                raise RuntimeError(f"roots {j + 1} and {i + 1} coincide ({lam[i]!r}): the "
                                   "root tracking jumped between modes")


# ----------------------------------------------------------------------------- base excitation
def euler_bernoulli_transmissibility(
    omega: float | np.ndarray, *, L: float, rho: float, A: float, I: float, E: Modulus
) -> np.ndarray:
    """Complex ``T = W(L)/X`` of the E-B cantilever with a harmonically translating clamp.

    ``W(x) = a cosh(bx) + b sinh(bx) + c cos(bx) + d sin(bx)``,
    ``beta^4 = rho A omega^2 / (E(i omega) I)``, conditions ``W(0) = X``, ``W'(0) = 0``,
    ``W''(L) = W'''(L) = 0`` solved as a 4x4 linear system.
    """
    w_arr = np.atleast_1d(np.asarray(omega, dtype=float))
    out = np.empty(w_arr.shape, dtype=complex)
    for n, w in enumerate(w_arr):
        beta = (rho * A * w * w / (E(1j * w) * I) + 0j) ** 0.25
        x = beta * L
        ch, sh, c, s = np.cosh(x), np.sinh(x), np.cos(x), np.sin(x)
        Mtx = np.array(
            [
                [1.0, 0.0, 1.0, 0.0],  # W(0) = 1
                [0.0, 1.0, 0.0, 1.0],  # W'(0) / beta = 0
                [ch, sh, -c, -s],  # W''(L) / beta^2 = 0
                [sh, ch, s, -c],  # W'''(L) / beta^3 = 0
            ],
            dtype=complex,
        )
        a, b, cc, d = np.linalg.solve(Mtx, np.array([1.0, 0.0, 0.0, 0.0], dtype=complex))
        out[n] = a * ch + b * sh + cc * c + d * s
    return out


def euler_bernoulli_transmissibility_closed(
    omega: float | np.ndarray, *, L: float, rho: float, A: float, I: float, E: Modulus
) -> np.ndarray:
    """Closed form of the 4x4 system: ``T = (cos bL + cosh bL) / (1 + cos bL cosh bL)``."""
    w = np.atleast_1d(np.asarray(omega, dtype=float))
    Ew = np.array([E(1j * wi) for wi in w], dtype=complex)
    x = (rho * A * w * w / (Ew * I) + 0j) ** 0.25 * L
    return (np.cos(x) + np.cosh(x)) / (1.0 + np.cos(x) * np.cosh(x))


def timoshenko_transmissibility(
    omega: float | np.ndarray,
    *,
    L: float,
    rho: float,
    A: float,
    I: float,
    kappa: float,
    E: Modulus,
    G: Modulus,
    rotary_inertia: bool = True,
) -> np.ndarray:
    """Complex ``T = W(L)/X`` of the Timoshenko cantilever with a translating clamp.

    Transfer matrix ``P = expm(A(i omega))`` of :func:`timoshenko_matrix`; the clamp state is
    ``(X/L, 0, m0, q0)``, and ``M(L) = Q(L) = 0`` fixes ``(m0, q0)``.
    """
    rhoA, rhoI = rho * A, (rho * I if rotary_inertia else 0.0)
    w_arr = np.atleast_1d(np.asarray(omega, dtype=float))
    out = np.empty(w_arr.shape, dtype=complex)
    for n, w in enumerate(w_arr):
        s = 1j * w
        P = expm(
            timoshenko_matrix(s, L=L, rhoA=rhoA, rhoI=rhoI, EI=E(s) * I, kGA=kappa * A * G(s))
        )
        mq = np.linalg.solve(P[2:, 2:], -P[2:, 0])  # per unit X/L
        out[n] = P[0, 0] + P[0, 2:] @ mq
    return out


@dataclass(frozen=True)
class Resonance:
    """Peak of ``|T(omega)|``: frequency (rad/s) and modulus."""

    omega: float
    gain: float


def resonance(T: Callable[[float], complex], lo: float, hi: float) -> Resonance:
    """Maximum of ``|T(omega)|`` on ``[lo, hi]`` (bounded Brent, ``xatol`` 1e-10 ``hi``)."""
    res = minimize_scalar(
        lambda w: -abs(complex(np.asarray(T(w)).ravel()[0])),
        bounds=(lo, hi),
        method="bounded",
        options={"xatol": 1e-10 * hi},
    )
    return Resonance(omega=float(res.x), gain=float(-res.fun))


def paper_beam() -> dict[str, float]:
    """The paper's cantilever (SI): L = 0.3, 1 cm square, rho = 1000, E = 1 MPa, nu = 0.3,
    Cowper's ``kappa = 10 (1 + nu) / (12 + 11 nu)``."""
    L, a, rho, E, nu = 0.3, 0.01, 1000.0, 1.0e6, 0.3
    return {
        "L": L,
        "rho": rho,
        "A": a * a,
        "I": a**4 / 12.0,
        "E": E,
        "nu": nu,
        "kappa": 10.0 * (1.0 + nu) / (12.0 + 11.0 * nu),
    }


def paper_base_excitation(tau: float, X: float = 1e-3) -> dict[str, dict[str, float]]:
    """Base-excitation numbers of the paper's cantilever with ``tau_E = tau_S = tau``.

    For E-B and Timoshenko: first eigenvalue, damping ratio, damped frequency ``omega_d``,
    resonance (peak ``|T|`` and its frequency), and tip amplitudes ``X |T|`` (m) at
    ``omega_d``, ``0.9 omega_d``, ``1.1 omega_d``.
    """
    p = paper_beam()
    E, G = kelvin_voigt_moduli(p["E"], p["nu"], tau, tau)
    geo = {k: p[k] for k in ("L", "rho", "A", "I")}
    out: dict[str, dict[str, float]] = {}
    for name in ("euler_bernoulli", "timoshenko"):
        if name == "euler_bernoulli":
            lam = euler_bernoulli_eigenvalues(1, E=E, **geo)[0]

            def T(w, E=E):
                return euler_bernoulli_transmissibility(w, E=E, **geo)
        else:
            lam = timoshenko_eigenvalues(1, kappa=p["kappa"], E=E, G=G, **geo)[0]

            def T(w, E=E, G=G):
                return timoshenko_transmissibility(w, kappa=p["kappa"], E=E, G=G, **geo)

        wd = float(lam.imag)
        pk = resonance(T, 0.5 * wd, 1.5 * wd)
        amps = X * np.abs(T(np.array([0.9 * wd, wd, 1.1 * wd])))
        out[name] = {
            "lambda_re": float(lam.real),
            "lambda_im": float(lam.imag),
            "zeta": float(damping_ratio(lam)),
            "omega_d": wd,
            "omega_peak": pk.omega,
            "T_peak": pk.gain,
            "amp_0.9": float(amps[0]),
            "amp_1.0": float(amps[1]),
            "amp_1.1": float(amps[2]),
        }
    return out


if __name__ == "__main__":  # pragma: no cover
    for tau in (0.02, 0.04, 0.08):
        res = paper_base_excitation(tau)
        for name, d in res.items():
            print(f"tau = {tau} {name}:")
            for k, v in d.items():
                print(f"    {k:11s} = {v:.10g}")
