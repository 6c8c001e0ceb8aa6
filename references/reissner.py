"""Static planar large deflection of a clamped-free rod under a dead tip force.

Independent reference for kvrod's static solver (written from scratch with NumPy/SciPy).

Geometry and conventions (the paper's Sect. 5 cantilever): the undeformed rod lies along
``e3`` (coordinate ``z``), clamped at ``s = 0``; the load acts in the ``e1``-``e3`` plane
(coordinates ``x``, ``z``), so the motion is planar bending about ``e2``. ``theta(s)`` is the
rotation of the cross section about ``e2``, measured from ``e3`` towards ``e1``; the directors
are::

    a3 = ( sin theta, cos theta)      (section normal)
    a1 = ( cos theta, -sin theta)     (= e2 x a3, as in the paper's footnote 16)

Simo-Reissner rod (extensible, shearable; the paper's Eqs. (2), (7), (10), (12), (13)):

- strains: ``phi' = V1 a1 + V3 a3``, shear ``V1``, dilatation ``V3`` (``= 1`` unstretched),
  curvature ``U2 = theta'``;
- linear elastic law: ``n . a1 = GA_s V1``, ``n . a3 = EA (V3 - 1)``, ``M = EI theta'``;
- balance without distributed loads: ``n' = 0`` so the force resultant equals the dead tip
  force everywhere, ``n = F``; moment balance ``M' + (phi' x n) . e2 = 0``, i.e.
  ``M' = -(z' F_x - x' F_z)``;
- boundary conditions: ``x = z = theta = 0`` at ``s = 0``; ``M(L) = 0`` (no tip couple).

The two-point problem is solved by shooting on the base moment ``M(0)`` with
:func:`scipy.integrate.solve_ivp` (DOP853, rtol 1e-12) and a secant iteration, with load
continuation from the unloaded state (so the principal, non-inflectional branch is
followed). :func:`solve_reissner_bvp` solves the same problem by collocation
(:func:`scipy.integrate.solve_bvp`) as a cross-check.

:func:`elastica_tip` is the closed form of the inextensible, unshearable Euler elastica under
a tip force perpendicular to the undeformed axis (Love 1927, ch. XIX, Sect. 260-263):
with ``1 + sin theta = 2 k^2 sin^2 phi``, ``phi_0 = arcsin(1/(sqrt(2) k))``::

    sqrt(F L^2 / EI)  = K(k) - F(phi_0, k)
    x_tip             = L - 2 sqrt(EI/F) (E(k) - E(phi_0, k))
    z_tip             = sqrt(2 EI sin(theta_L) / F),   sin(theta_L) = 2 k^2 - 1

Run ``python -m references.reissner`` to print the numbers for the paper's data.
SI units throughout.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_bvp, solve_ivp
from scipy.optimize import brentq, root_scalar
from scipy.special import ellipeinc, ellipk, ellipkinc

from .sections import cowper_rectangle  # re-exported (moved to .sections)

__all__ = [
    "ElasticaTip",
    "ReissnerSolution",
    "cowper_rectangle",
    "elastica_tip",
    "paper_cantilever",
    "solve_reissner",
    "solve_reissner_bvp",
]


@dataclass(frozen=True)
class ElasticaTip:
    """Tip of the inextensible elastica: position ``(x, z)`` in m, rotation ``theta`` in rad."""

    x: float
    z: float
    theta: float
    k: float  # elliptic modulus k (not the parameter m = k^2)


def elastica_tip(F: float, EI: float, L: float) -> ElasticaTip:
    """Closed-form tip of the clamped inextensible Euler elastica under a perpendicular force.

    F: dead tip force along ``e1`` in N (either sign); EI: bending stiffness in N m^2;
    L: length in m. The rod lies along ``e3`` unloaded. Returns the principal
    (non-inflectional) solution; tip position ``x`` (along the load), ``z`` (along the
    undeformed axis) and tip rotation ``theta`` (from e3 towards e1).
    """
    if not (EI > 0 and L > 0):
        raise ValueError(f"EI and L must be positive, got EI={EI!r}, L={L!r}")
    if F == 0:
        return ElasticaTip(0.0, float(L), 0.0, math.sqrt(0.5))
    sign = 1.0 if F > 0 else -1.0
    F = abs(F)
    target = math.sqrt(F * L * L / EI)

    def g(m: float) -> float:
        phi0 = math.asin(min(1.0, 1.0 / math.sqrt(2.0 * m)))
        return float(ellipk(m) - ellipkinc(phi0, m)) - target

    m = brentq(
        g, 0.5, np.nextafter(1.0, 0.0), xtol=1e-17, rtol=4 * np.finfo(float).eps, maxiter=500
    )
    phi0 = math.asin(min(1.0, 1.0 / math.sqrt(2.0 * m)))
    x = L - 2.0 * math.sqrt(EI / F) * float(ellipeinc(math.pi / 2, m) - ellipeinc(phi0, m))
    sin_theta = 2.0 * m - 1.0
    z = math.sqrt(2.0 * EI * sin_theta / F)
    return ElasticaTip(sign * x, z, sign * math.asin(sin_theta), math.sqrt(m))


@dataclass(frozen=True)
class ReissnerSolution:
    """Equilibrium of the clamped Simo-Reissner rod under a dead tip force.

    Arrays are sampled on ``s`` (m, ``n_points`` values from 0 to L).
    ``tip = (x, z)`` in m; ``tip_rotation`` in rad; ``base_moment = M(0)`` in N m;
    ``elastic_energy`` (J) is the stored energy (10); ``potential = elastic_energy - F . tip``
    the total potential energy of the dead load; ``residual = M(L)`` in N m.
    """

    F: tuple[float, float]
    L: float
    EA: float
    GA: float
    EI: float
    tip: tuple[float, float]
    tip_rotation: float
    base_moment: float
    elastic_energy: float
    potential: float
    residual: float
    s: np.ndarray
    x: np.ndarray
    z: np.ndarray
    theta: np.ndarray
    moment: np.ndarray
    axial_strain: np.ndarray
    shear_strain: np.ndarray


def _compliances(EA: float, GA: float, EI: float) -> tuple[float, float]:
    for name, val in (("EA", EA), ("GA", GA), ("EI", EI)):
        if not val > 0:
            raise ValueError(f"{name} must be positive (math.inf allowed for EA, GA), got {val!r}")
    if not math.isfinite(EI):
        raise ValueError(f"EI must be finite, got {EI!r}")
    return 1.0 / EA, 1.0 / GA  # 1/inf = 0: inextensible / unshearable


def _rhs(Fx: float, Fz: float, cEA: float, cGA: float, EI: float):
    """Right-hand side for y = (x, z, theta, M, W) with W the accumulated elastic energy."""

    def f(s, y):
        th, M = y[2], y[3]
        c, sn = np.cos(th), np.sin(th)
        Q = Fx * c - Fz * sn  # n . a1
        N = Fx * sn + Fz * c  # n . a3
        V1 = Q * cGA
        eps = N * cEA
        V3 = 1.0 + eps
        xp = V1 * c + V3 * sn
        zp = -V1 * sn + V3 * c
        Mp = -(zp * Fx - xp * Fz)
        w = 0.5 * (Q * V1 + N * eps + M * M / EI)
        return (
            np.array([xp, zp, M / EI, Mp, w])
            if np.ndim(th) == 0
            else np.vstack([xp, zp, M / EI, Mp, w])
        )

    return f


def solve_reissner(
    F: float,
    *,
    L: float,
    EA: float,
    GA: float,
    EI: float,
    angle: float = 0.0,
    n_points: int = 201,
    rtol: float = 1e-12,
    load_steps: int = 10,
) -> ReissnerSolution:
    """Shooting solution of the clamped-free Simo-Reissner rod under a dead tip force.

    F: force magnitude in N. angle: direction of the force in rad, measured from ``e1``
    towards ``e3`` (0: perpendicular to the undeformed axis, pi/2: axial tension).
    L: length (m); EA, GA (shear-corrected ``kappa G A``), EI: stiffnesses (N, N, N m^2);
    ``math.inf`` for EA/GA makes the rod inextensible/unshearable. n_points: samples of
    the returned centerline. rtol: solve_ivp tolerance. load_steps: continuation steps from
    zero load (the principal branch is followed).
    """
    cEA, cGA = _compliances(EA, GA, EI)
    if not (L > 0 and math.isfinite(L)):
        raise ValueError(f"L must be positive and finite, got {L!r}")
    if n_points < 2:
        raise ValueError(f"n_points must be >= 2, got {n_points!r}")
    Fx_full, Fz_full = F * math.cos(angle), F * math.sin(angle)
    atol = 1e-15 * max(1.0, L)

    def shoot(M0: float, Fx: float, Fz: float, dense: bool = False):
        sol = solve_ivp(
            _rhs(Fx, Fz, cEA, cGA, EI),
            (0.0, L),
            np.array([0.0, 0.0, 0.0, M0, 0.0]),
            method="DOP853",
            rtol=rtol,
            atol=atol,
            dense_output=dense,
        )
        if sol.status != 0:  # pragma: no cover - integrator failure
            raise RuntimeError(f"solve_ivp failed: {sol.message}")
        return sol

    M0 = 0.0
    scale = max(abs(F) * L, 1e-300)
    for j in range(1, load_steps + 1):
        lam = j / load_steps
        Fx, Fz = lam * Fx_full, lam * Fz_full
        guess = M0 * lam / ((j - 1) / load_steps) if j > 1 else Fx * L

        def resid(m0: float, Fx: float = Fx, Fz: float = Fz) -> float:
            return float(shoot(m0, Fx, Fz).y[3, -1])

        if F == 0:
            M0 = 0.0
            break
        r = root_scalar(
            resid,
            method="secant",
            x0=guess,
            x1=guess * (1 + 1e-3) + 1e-6 * scale,
            xtol=1e-15 * scale,
            rtol=1e-15,
            maxiter=100,
        )
        if not r.converged:  # pragma: no cover
            raise RuntimeError(f"shooting did not converge at load factor {lam}: {r.flag}")
        M0 = float(r.root)

    sol = shoot(M0, Fx_full, Fz_full, dense=True)
    s = np.linspace(0.0, L, n_points)
    Y = sol.sol(s)
    Y[:, -1] = sol.y[:, -1]
    th = Y[2]
    c, sn = np.cos(th), np.sin(th)
    Q = Fx_full * c - Fz_full * sn
    N = Fx_full * sn + Fz_full * c
    tip = (float(sol.y[0, -1]), float(sol.y[1, -1]))
    W = float(sol.y[4, -1])
    return ReissnerSolution(
        F=(Fx_full, Fz_full),
        L=L,
        EA=EA,
        GA=GA,
        EI=EI,
        tip=tip,
        tip_rotation=float(sol.y[2, -1]),
        base_moment=M0,
        elastic_energy=W,
        potential=W - (Fx_full * tip[0] + Fz_full * (tip[1] - L)),
        residual=float(sol.y[3, -1]),
        s=s,
        x=Y[0],
        z=Y[1],
        theta=th,
        moment=Y[3],
        axial_strain=N * cEA,
        shear_strain=Q * cGA,
    )


def solve_reissner_bvp(
    F: float,
    *,
    L: float,
    EA: float,
    GA: float,
    EI: float,
    angle: float = 0.0,
    tol: float = 1e-10,
    n_mesh: int = 101,
) -> tuple[float, float, float]:
    """Collocation cross-check (:func:`scipy.integrate.solve_bvp`) of :func:`solve_reissner`.

    Same arguments; returns ``(x_tip, z_tip, tip_rotation)`` in m, m, rad. The initial
    guess is the linear (small-deflection) solution, so use moderate loads or expect the
    principal branch only where it is the nearest.
    """
    cEA, cGA = _compliances(EA, GA, EI)
    Fx, Fz = F * math.cos(angle), F * math.sin(angle)
    f5 = _rhs(Fx, Fz, cEA, cGA, EI)

    def fun(s, y):
        return f5(s, np.vstack([y, np.zeros_like(y[0])]))[:4]

    def bc(ya, yb):
        return np.array([ya[0], ya[1], ya[2], yb[3]])

    s = np.linspace(0.0, L, n_mesh)
    # linear-beam initial guess at a quarter of the load, then load continuation
    y = np.zeros((4, n_mesh))
    y[1] = s
    for lam in (0.25, 0.5, 0.75, 1.0):
        Fxl, Fzl = lam * Fx, lam * Fz
        f5 = _rhs(Fxl, Fzl, cEA, cGA, EI)
        if lam == 0.25:
            y[3] = Fxl * (L - s)
            y[2] = Fxl * (L * s - 0.5 * s * s) / EI
            y[0] = Fxl * (0.5 * L * s * s - s**3 / 6) / EI
        res = solve_bvp(fun, bc, s, y, tol=tol, max_nodes=200000)
        if not res.success:  # pragma: no cover
            raise RuntimeError(f"solve_bvp failed: {res.message}")
        s, y = res.x, res.y
    return float(y[0, -1]), float(y[1, -1]), float(y[2, -1])


def paper_cantilever() -> dict[str, float]:
    """The paper's Sect. 5 data (SI): L = 0.3 m, 1 cm square, rho = 1000, E = 1 MPa, nu = 0.3,
    F = 0.05 N; with derived A, I, G, Cowper factor kappa and the stiffnesses EA, GA_s, EI."""
    L, a, rho, E, nu, F = 0.3, 0.01, 1000.0, 1.0e6, 0.3, 0.05
    A = a * a
    I = a**4 / 12.0
    G = E / (2.0 * (1.0 + nu))
    kappa = cowper_rectangle(nu)
    return {
        "L": L,
        "a": a,
        "rho": rho,
        "E": E,
        "nu": nu,
        "F": F,
        "A": A,
        "I": I,
        "G": G,
        "kappa": kappa,
        "EA": E * A,
        "GA_s": kappa * G * A,
        "GA": G * A,
        "EI": E * I,
        "load_parameter": F * L * L / (E * I),
    }


def _main() -> None:  # pragma: no cover - report helper
    p = paper_cantilever()
    L, EI = p["L"], p["EI"]
    el = elastica_tip(p["F"], EI, L)
    print(f"load parameter F L^2/EI = {p['load_parameter']:.6f}")
    print(f"elastica:          x = {el.x:.12f}  z = {el.z:.12f}  theta = {el.theta:.12f}")
    cases = [
        ("inextensible (inf)", math.inf, math.inf),
        ("extensible only", p["EA"], math.inf),
        ("shear only (kGA)", math.inf, p["GA_s"]),
        ("Reissner EA, kGA", p["EA"], p["GA_s"]),
        ("Reissner EA, GA", p["EA"], p["GA"]),
    ]
    for name, EA, GA in cases:
        r = solve_reissner(p["F"], L=L, EA=EA, GA=GA, EI=EI)
        print(
            f"{name:20s} x = {r.tip[0]:.12f}  z = {r.tip[1]:.12f}  "
            f"w = z - L = {r.tip[1] - L:+.12f}  theta = {r.tip_rotation:.12f}  "
            f"|tip - base| displ = {math.hypot(r.tip[0], r.tip[1] - L):.12f}"
        )


if __name__ == "__main__":  # pragma: no cover
    _main()
