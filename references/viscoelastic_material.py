"""Isotropic linear viscoelastic 3-D materials: generalized Maxwell and Kelvin-Voigt.

Independent of kvrod (NumPy/SciPy only). SI units: moduli in Pa, times in s, angular
frequencies in rad/s, strains dimensionless.

Tensors are handled in Mandel notation, ``eps = (e11, e22, e33, r2 e23, r2 e13, r2 e12)``
with ``r2 = sqrt(2)`` (likewise for the stress), so that ``sigma . eps`` is the double
contraction and an isotropic stiffness is the symmetric 6x6 matrix
``C(G, K) = 3 K P_vol + 2 G P_dev`` with ``P_vol = m m^T / 3``, ``m = (1, 1, 1, 0, 0, 0)``,
``P_dev = 1 - P_vol``.

Generalized Maxwell (Prony series) solid
----------------------------------------
An equilibrium spring ``C_inf = C(G_inf, K_inf)`` in parallel with ``M`` Maxwell branches
``j``, each an isotropic spring ``C_j = C(G_j, K_j)`` in series with a dashpot of one
relaxation time ``tau_j`` acting on the whole (deviatoric and volumetric) branch strain.
With the branch viscous strains ``q_j`` as internal variables::

    sigma     = C_inf eps + sum_j C_j (eps - q_j)
    dq_j / dt = (eps - q_j) / tau_j,          q_j(0) = 0.

In the Laplace domain this gives ``G(s) = G_inf + sum_j G_j s tau_j / (1 + s tau_j)`` and the
same for ``K(s)``; the uniaxial (lateral stress free) modulus is
``E(s) = 9 K(s) G(s) / (3 K(s) + G(s))`` (:meth:`GeneralizedMaxwell.E`).

Two independent routes to the relaxation moduli:

- :func:`maxwell_step_stress` (time domain, no Laplace algebra): the strain component(s)
  of the test are prescribed (a step ``eps0`` held for ``t > 0``), the remaining stress
  components are zero (mixed control). The free strains are eliminated from the linear
  algebraic condition ``sigma_f = 0`` at every instant, which leaves the linear ODE system
  ``dz/dt = A z`` for ``z = (q_1, ..., q_M, eps_p)``; it is solved exactly by
  ``z(t) = expm(A t) z(0)`` (or, as a check, by Radau with tight tolerances).
- :func:`relaxation_modulus_laplace`: numerical inverse Laplace transform of ``E(s)/s``
  (or ``G(s)/s``) by the fixed-Talbot method (Abate and Valko 2004).

Kelvin-Voigt solid
------------------
``sigma = C(G, K) eps + C(G tau_S, K tau_B) deps/dt``, i.e. ``G(s) = G (1 + s tau_S)``,
``K(s) = K (1 + s tau_B)``. :func:`kelvin_voigt_uniaxial` integrates the uniaxial stress
state exactly (piecewise linear axial strain history, lateral stresses zero: the lateral
strains obey a linear ODE, solved by the matrix exponential on every segment).
:func:`kelvin_voigt_complex_modulus` is the harmonic steady state of the same 3-D equations
(Schur complement of ``C + i omega V`` on the stress-free components).
:func:`fit_first_order` fits ``E*(i w)/E = 1 + i w tau_E + c2 (i w)^2 + ...`` numerically.
For reference (derived by hand, *not* used by the code)::

    E(s) / E = (1 + s tau_B)(1 + s tau_S) / (1 + s tau_m)
             = 1 + s tau_E + s^2 (tau_B - tau_m)(tau_S - tau_m) / (1 + s tau_m),
    tau_m = (3 K tau_B + G tau_S) / (3 K + G) = (2 (1 + nu) tau_B + (1 - 2 nu) tau_S) / 3,
    tau_E = tau_B + tau_S - tau_m = ((1 - 2 nu) tau_B + 2 (1 + nu) tau_S) / 3,

exactly Kelvin-Voigt ``E (1 + s tau)`` when ``tau_B = tau_S = tau``.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy.integrate import solve_ivp
from scipy.linalg import expm

__all__ = [
    "GeneralizedMaxwell",
    "KelvinVoigtUniaxial",
    "example_two_branch",
    "fit_first_order",
    "isotropic_mandel",
    "kelvin_voigt_complex_modulus",
    "kelvin_voigt_uniaxial",
    "maxwell_step_stress",
    "relaxation_modulus_laplace",
    "shear_bulk_from_E_nu",
    "talbot_inverse",
]

_R2 = math.sqrt(2.0)
_M = np.array([1.0, 1.0, 1.0, 0.0, 0.0, 0.0])
_P_VOL = np.outer(_M, _M) / 3.0
_P_DEV = np.eye(6) - _P_VOL

#: Mandel index of the prescribed strain component of each test
_MODES = {"uniaxial": 0, "shear": 5}


def shear_bulk_from_E_nu(E: complex, nu: float) -> tuple[complex, complex]:
    """``G = E / (2 (1 + nu))`` and ``K = E / (3 (1 - 2 nu))`` (Pa)."""
    return E / (2.0 * (1.0 + nu)), E / (3.0 * (1.0 - 2.0 * nu))


def isotropic_mandel(G: complex, K: complex) -> np.ndarray:
    """Isotropic stiffness ``3 K P_vol + 2 G P_dev`` as a 6x6 Mandel matrix."""
    return 3.0 * K * _P_VOL + 2.0 * G * _P_DEV


@dataclass(frozen=True)
class GeneralizedMaxwell:
    """Isotropic generalized Maxwell solid (Pa, s).

    G_inf, K_inf: equilibrium shear and bulk moduli; G, K, tau: per-branch shear modulus,
    bulk modulus and relaxation time (sequences of equal length ``M``).
    """

    G_inf: float
    K_inf: float
    G: Sequence[float] = field(default_factory=tuple)
    K: Sequence[float] = field(default_factory=tuple)
    tau: Sequence[float] = field(default_factory=tuple)

    def __post_init__(self) -> None:
        if not len(self.G) == len(self.K) == len(self.tau):
            raise ValueError("G, K and tau need one entry per branch")
        if any(t <= 0 for t in self.tau):
            raise ValueError(f"relaxation times must be positive, got {self.tau!r}")

    # Laplace-domain moduli (s complex, scalar or array)
    def G_s(self, s: complex | np.ndarray) -> complex | np.ndarray:
        """``G(s) = G_inf + sum_j G_j s tau_j / (1 + s tau_j)`` (Pa)."""
        branches = zip(self.G, self.tau, strict=True)
        return self.G_inf + sum(g * s * t / (1.0 + s * t) for g, t in branches)

    def K_s(self, s: complex | np.ndarray) -> complex | np.ndarray:
        """``K(s) = K_inf + sum_j K_j s tau_j / (1 + s tau_j)`` (Pa)."""
        branches = zip(self.K, self.tau, strict=True)
        return self.K_inf + sum(k * s * t / (1.0 + s * t) for k, t in branches)

    def E(self, s: complex | np.ndarray) -> complex | np.ndarray:
        """Uniaxial modulus ``E(s) = 9 K(s) G(s) / (3 K(s) + G(s))`` (Pa)."""
        g, k = self.G_s(s), self.K_s(s)
        return 9.0 * k * g / (3.0 * k + g)

    @property
    def glassy(self) -> tuple[float, float]:
        """Instantaneous ``(G_0, K_0) = (G_inf + sum G_j, K_inf + sum K_j)``."""
        return self.G_inf + sum(self.G), self.K_inf + sum(self.K)

    def E_glassy(self) -> float:
        """Instantaneous uniaxial modulus ``9 K_0 G_0 / (3 K_0 + G_0)``."""
        g, k = self.glassy
        return 9.0 * k * g / (3.0 * k + g)

    def E_relaxed(self) -> float:
        """Long-time uniaxial modulus ``9 K_inf G_inf / (3 K_inf + G_inf)``."""
        g, k = self.G_inf, self.K_inf
        return 9.0 * k * g / (3.0 * k + g)


def _maxwell_system(mat: GeneralizedMaxwell, p: int) -> tuple[np.ndarray, np.ndarray]:
    """Linear system of the mixed-control test with prescribed Mandel component ``p``.

    Returns ``(A, S)``: ``dz/dt = A z`` for ``z = (q_1, ..., q_M, eps_p)`` (``eps_p`` held
    constant, so its row is zero) and the row ``S`` with ``sigma_p = S z``.
    """
    M = len(mat.tau)
    C_inf = isotropic_mandel(mat.G_inf, mat.K_inf)
    C_br = [isotropic_mandel(g, k) for g, k in zip(mat.G, mat.K, strict=True)]
    C_tot = C_inf + sum(C_br, np.zeros((6, 6)))
    f = [i for i in range(6) if i != p]
    n = 6 * M + 1
    # eps = E_map z: eps_p from the last state, eps_f from sigma_f = 0:
    # C_tot[f, f] eps_f = sum_j C_j[f, :] q_j - C_tot[f, p] eps_p
    rhs = np.zeros((5, n))
    for j, C in enumerate(C_br):
        rhs[:, 6 * j : 6 * j + 6] = C[f, :]
    rhs[:, -1] = -C_tot[f, p]
    E_map = np.zeros((6, n))
    E_map[p, -1] = 1.0
    E_map[f, :] = np.linalg.solve(C_tot[np.ix_(f, f)], rhs)
    A = np.zeros((n, n))
    for j, t in enumerate(mat.tau):
        blk = slice(6 * j, 6 * j + 6)
        A[blk, :] = E_map / t
        A[blk, blk] -= np.eye(6) / t
    # sigma_p = C_tot[p, :] eps - sum_j C_j[p, :] q_j
    S = C_tot[p, :] @ E_map
    for j, C in enumerate(C_br):
        S[6 * j : 6 * j + 6] -= C[p, :]
    return A, S


def maxwell_step_stress(
    mat: GeneralizedMaxwell,
    t: float | np.ndarray,
    eps0: float = 1.0,
    *,
    mode: str = "uniaxial",
    method: str = "expm",
) -> np.ndarray:
    """Stress history after a strain step held for ``t > 0`` (time domain, Pa).

    mode ``"uniaxial"``: ``e11 = eps0`` prescribed, all other stresses zero; returns
    ``sigma_11(t) = E_relax(t) eps0``. mode ``"shear"``: engineering shear ``gamma_12 =
    eps0`` prescribed, all other stresses zero; returns ``sigma_12(t) = G_relax(t) eps0``.
    ``t = 0`` is the instant just after the step (internal variables still zero, glassy
    response). method ``"expm"``: exact ``z(t) = expm(A t) z(0)``; ``"ode"``: Radau with
    ``rtol = 1e-12`` (independent check).
    """
    if mode not in _MODES:
        raise ValueError(f"unknown mode {mode!r}")
    p = _MODES[mode]
    t_arr = np.atleast_1d(np.asarray(t, dtype=float))
    if np.any(t_arr < 0):
        raise ValueError("times must be >= 0")
    A, S = _maxwell_system(mat, p)
    z0 = np.zeros(A.shape[0])
    # prescribed Mandel strain: eps0 (uniaxial) or r2 * eps_12 = gamma / r2 (shear)
    z0[-1] = eps0 if mode == "uniaxial" else eps0 / _R2
    if method == "expm":
        z = np.array([expm(A * ti) @ z0 for ti in t_arr])
    elif method == "ode":
        order = np.argsort(t_arr)
        sol = solve_ivp(
            lambda _t, y: A @ y,
            (0.0, float(t_arr.max())),
            z0,
            method="Radau",
            jac=A,
            t_eval=t_arr[order],
            rtol=1e-12,
            atol=1e-14 * max(abs(eps0), 1e-300),
        )
        if not sol.success:  # pragma: no cover
            raise RuntimeError(sol.message)
        z = np.empty((t_arr.size, A.shape[0]))
        z[order] = sol.y.T
    else:
        raise ValueError(f"unknown method {method!r}")
    sig_p = z @ S
    if mode == "uniaxial":
        return sig_p
    return sig_p / _R2  # shear: sigma_12 = (Mandel stress 5) / r2


def talbot_inverse(F: Callable[[np.ndarray], np.ndarray], t: float | np.ndarray, M: int = 24):
    """Fixed-Talbot numerical inverse Laplace transform (Abate and Valko 2004).

    ``f(t) ~ r/M [ F(r) e^{r t} / 2 + sum_{k=1}^{M-1} Re( e^{t d_k} F(d_k) (1 + i s_k) ) ]``,
    ``r = 2 M / (5 t)``, ``theta_k = k pi / M``, ``d_k = r theta_k (cot theta_k + i)``,
    ``s_k = theta_k + (theta_k cot theta_k - 1) cot theta_k``. ``F`` must be vectorized and
    analytic to the right of, and around, the negative real axis (poles on ``(-inf, 0]``).
    In double precision ``M = 24`` gives about 12 significant digits for Prony-type
    moduli.
    """
    t_arr = np.atleast_1d(np.asarray(t, dtype=float))
    if np.any(t_arr <= 0):
        raise ValueError("Talbot inversion needs t > 0")
    k = np.arange(1, M)
    th = k * math.pi / M
    cot = 1.0 / np.tan(th)
    sig = th + (th * cot - 1.0) * cot
    out = np.empty_like(t_arr)
    for i, ti in enumerate(t_arr):
        r = 2.0 * M / (5.0 * ti)
        d = r * th * (cot + 1j)
        acc = 0.5 * math.exp(r * ti) * complex(F(np.array([r + 0j]))[0]).real
        acc += float(np.sum((np.exp(ti * d) * F(d) * (1.0 + 1j * sig)).real))
        out[i] = r / M * acc
    return out


def relaxation_modulus_laplace(
    mat: GeneralizedMaxwell, t: float | np.ndarray, *, mode: str = "uniaxial", M: int = 24
) -> np.ndarray:
    """``E_relax(t) = L^-1[E(s)/s](t)`` (or ``G_relax`` for mode ``"shear"``) by Talbot (Pa)."""
    if mode == "uniaxial":
        return talbot_inverse(lambda s: mat.E(s) / s, t, M)
    if mode == "shear":
        return talbot_inverse(lambda s: mat.G_s(s) / s, t, M)
    raise ValueError(f"unknown mode {mode!r}")


def example_two_branch() -> GeneralizedMaxwell:
    """A 2-branch example: equilibrium part ``E = 1 MPa, nu = 0.3``; branch 1
    ``G_1 = 0.2 MPa, K_1 = 0.1 MPa, tau_1 = 0.01 s``; branch 2 ``G_2 = 0.1 MPa,
    K_2 = 0.3 MPa, tau_2 = 0.1 s`` (shear and bulk branches deliberately not proportional,
    so ``E_relax(t)`` is not a combination of ``exp(-t/tau_j)``)."""
    G_inf, K_inf = shear_bulk_from_E_nu(1.0e6, 0.3)
    return GeneralizedMaxwell(
        G_inf=G_inf, K_inf=K_inf, G=(2.0e5, 1.0e5), K=(1.0e5, 3.0e5), tau=(0.01, 0.1)
    )


# ----------------------------------------------------------------------------- Kelvin-Voigt
@dataclass(frozen=True)
class KelvinVoigtUniaxial:
    """Uniaxial Kelvin-Voigt response: times (s), axial strain, axial stress (Pa) and the
    lateral strain ``e22 = e33`` (the other components stay zero)."""

    t: np.ndarray
    strain: np.ndarray
    stress: np.ndarray
    lateral_strain: np.ndarray


def kelvin_voigt_uniaxial(
    t: float | np.ndarray,
    knots_t: Sequence[float],
    knots_eps: Sequence[float],
    *,
    E: float,
    nu: float,
    tau_S: float,
    tau_B: float,
) -> KelvinVoigtUniaxial:
    """Exact uniaxial response of the 3-D Kelvin-Voigt solid to a piecewise-linear ``e11``.

    ``sigma = C eps + V deps/dt`` with ``C = C(G, K)``, ``V = C(G tau_S, K tau_B)``; ``e11``
    is prescribed by the knots (linear between them, constant after the last knot; the first
    knot is the initial state, with zero lateral strain), all other stresses vanish. With
    ``p`` the axial and ``f`` the five other Mandel components::

        V_ff deps_f/dt = -C_ff eps_f - C_fp e11 - V_fp de11/dt

    On a segment with rate ``r`` the state ``(eps_f, e11, 1)`` obeys a constant linear ODE and
    is advanced by the matrix exponential. At a knot where the rate jumps the stress jumps
    (viscous part); the value returned at a knot time is the right limit (the rate of the
    segment that starts there). Needs ``tau_S > 0`` (then ``V_ff`` is invertible).
    """
    if tau_S <= 0 or tau_B < 0:
        raise ValueError("need tau_S > 0 and tau_B >= 0")
    kt = np.asarray(knots_t, dtype=float)
    ke = np.asarray(knots_eps, dtype=float)
    if kt.ndim != 1 or kt.shape != ke.shape or kt.size < 1 or np.any(np.diff(kt) <= 0):
        raise ValueError("knots_t must be increasing and match knots_eps")
    t_arr = np.atleast_1d(np.asarray(t, dtype=float))
    if np.any(t_arr < kt[0]):
        raise ValueError("query times must not precede the first knot")
    G, K = shear_bulk_from_E_nu(E, nu)
    C = isotropic_mandel(G, K)
    V = isotropic_mandel(G * tau_S, K * tau_B)
    f = [1, 2, 3, 4, 5]
    Vff_inv = np.linalg.inv(V[np.ix_(f, f)])
    Cff, Cfp, Vfp = C[np.ix_(f, f)], C[f, 0], V[f, 0]
    rates = np.append(np.diff(ke) / np.diff(kt), 0.0)

    def segment_matrix(r: float) -> np.ndarray:
        A = np.zeros((7, 7))
        A[:5, :5] = -Vff_inv @ Cff
        A[:5, 5] = -Vff_inv @ Cfp
        A[:5, 6] = -Vff_inv @ Vfp * r
        A[5, 6] = r
        return A

    # states at the knots
    states = [np.concatenate([np.zeros(5), [ke[0], 1.0]])]
    for i in range(kt.size - 1):
        states.append(expm(segment_matrix(rates[i]) * (kt[i + 1] - kt[i])) @ states[-1])
    seg = np.searchsorted(kt, t_arr, side="right") - 1
    stress = np.empty_like(t_arr)
    eps = np.empty_like(t_arr)
    lat = np.empty_like(t_arr)
    for n, (ti, i) in enumerate(zip(t_arr, seg, strict=True)):
        r = rates[i]
        y = expm(segment_matrix(r) * (ti - kt[i])) @ states[i]
        eps_full = np.concatenate([[y[5]], y[:5]])
        deps_f = Vff_inv @ (-Cff @ y[:5] - Cfp * y[5] - Vfp * r)
        deps_full = np.concatenate([[r], deps_f])
        stress[n] = C[0] @ eps_full + V[0] @ deps_full
        eps[n], lat[n] = y[5], y[0]
    return KelvinVoigtUniaxial(t=t_arr, strain=eps, stress=stress, lateral_strain=lat)


def kelvin_voigt_complex_modulus(
    omega: float | np.ndarray, *, E: float, nu: float, tau_S: float, tau_B: float
) -> np.ndarray:
    """Uniaxial complex modulus ``E*(i omega)`` of the 3-D Kelvin-Voigt solid (Pa).

    Harmonic steady state ``eps = eps_hat e^{i omega t}`` of the 3-D law with all stresses but
    ``sigma_11`` zero: the Schur complement ``C*_pp - C*_pf C*_ff^{-1} C*_fp`` of
    ``C* = C + i omega V`` (no use of ``9 K G / (3 K + G)``).
    """
    G, K = shear_bulk_from_E_nu(E, nu)
    C = isotropic_mandel(G, K)
    V = isotropic_mandel(G * tau_S, K * tau_B)
    w_arr = np.atleast_1d(np.asarray(omega, dtype=float))
    out = np.empty(w_arr.shape, dtype=complex)
    f = [1, 2, 3, 4, 5]
    for n, w in enumerate(w_arr):
        Cs = C + 1j * w * V
        out[n] = Cs[0, 0] - Cs[0, f] @ np.linalg.solve(Cs[np.ix_(f, f)], Cs[f, 0])
    return out


def fit_first_order(
    omega: np.ndarray, Estar: np.ndarray, E0: float, order: int = 6
) -> np.ndarray:
    """Least-squares coefficients ``c_1..c_order`` of ``E*(i w)/E0 - 1 = sum_k c_k (i w)^k``.

    ``c_1`` is the first-order (Kelvin-Voigt) relaxation time ``tau_E`` (s), ``c_2`` the
    ``O(omega^2)`` coefficient (s^2). Real and imaginary parts are fitted jointly with real
    coefficients.
    """
    w = np.asarray(omega, dtype=float)
    s = 1j * w
    X = np.stack([s**k for k in range(1, order + 1)], axis=1)
    y = np.asarray(Estar) / E0 - 1.0
    Xr = np.concatenate([X.real, X.imag])
    yr = np.concatenate([y.real, y.imag])
    scale = np.max(np.abs(Xr), axis=0)
    c, *_ = np.linalg.lstsq(Xr / scale, yr, rcond=None)
    return c / scale


def _main() -> None:  # pragma: no cover - report helper
    mat = example_two_branch()
    t1 = mat.tau[0]
    ts = np.array([0.0, t1, 10 * t1])
    td = maxwell_step_stress(mat, ts)
    tl = np.concatenate([[np.nan], relaxation_modulus_laplace(mat, ts[1:])])
    print(f"E_glassy = {mat.E_glassy():.10e}  E_relaxed = {mat.E_relaxed():.10e}")
    for ti, a, b in zip(ts, td, tl, strict=True):
        print(f"E_relax({ti:g}) time domain = {a:.12e}   Talbot = {b:.12e}")
    E, nu = 1.0e6, 0.3
    w = np.geomspace(1e-3, 0.3, 30)
    for tau_S, tau_B in ((0.04, 0.04), (0.04, 0.0), (0.04, 0.12), (0.0 + 0.02, 0.08)):
        Es = kelvin_voigt_complex_modulus(w, E=E, nu=nu, tau_S=tau_S, tau_B=tau_B)
        c = fit_first_order(w, Es, E)
        kv = E * (1 + 1j * w * c[0])
        print(
            f"tau_S = {tau_S}, tau_B = {tau_B}: tau_E fit = {c[0]:.12f}  c2 = {c[1]:.6e}  "
            f"max |E* - E(1 + i w tau_E)|/(E w^2) = {np.max(np.abs(Es - kv) / (E * w**2)):.6e}"
        )


if __name__ == "__main__":  # pragma: no cover
    _main()
