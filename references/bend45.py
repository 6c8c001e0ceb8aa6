"""Bathe-Bolourchi 45-degree bend: converged tip positions by 3-D shooting.

The classical benchmark of Bathe and Bolourchi (1979), "Large displacement analysis of
three-dimensional beam structures", Int. J. Numer. Meth. Engng 14, 961-986; repeated by
Simo and Vu-Quoc (1986), "A three-dimensional finite-strain rod model. Part II", Comput.
Meth. Appl. Mech. Engng 58, 79-116 (Example 7.5), Cardona and Geradin (1988) and Crisfield
(1990). Data (consistent units, no SI scaling)::

    radius R = 100, arc angle 45 deg (L = 25 pi), unit square section
    A = 1, I1 = I2 = 1/12, J = 1/6 (given, not the Saint-Venant 0.1406)
    E = 1e7, G = 5e6, shear factor 1:  GA1 = GA2 = 5e6, EA = 1e7,
    EI1 = EI2 = 833333.33..., GJ = 833333.33...

Placement (this module): the arc lies in the x-y plane, starts at the origin with tangent
``+x`` and curves toward ``+y`` (centre of curvature ``(0, R, 0)``, unloaded tip
``(R sin 45, R (1 - cos 45), 0) = (70.7107, 29.2893, 0)``); clamped at ``s = 0``; dead
tip force ``(0, 0, P)`` for ``P = 300, 450, 600``.

Director choice: ``d3`` is the tangent; ``director="in_plane"`` takes ``d1`` in the plane of
the arc pointing to the centre (``d1 = e_y``, ``d2 = e_z`` at the clamp, intrinsic curvature
``K0 = (0, 1/R, 0)``); ``director="out_of_plane"`` takes ``d1 = e_z``, ``d2 = -e_y``,
``K0 = (1/R, 0, 0)``. With the square section (equal ``EI``, equal ``GA``) the two give the
same solution to the last digit (checked in the tests); for unequal stiffnesses they
would not.

Converged tip positions (shooting, DOP853; the same to 1e-11 for integrator rtol 1e-12 and
1e-13, and for 1, 2, 3 or 12 continuation steps; see :func:`bend45_convergence`)::

    P = 300:  (58.7791224897, 22.2447809454, 40.1918916702)
    P = 450:  (52.2385580112, 18.5081789254, 48.5029273441)
    P = 600:  (47.1504385736, 15.6848005340, 53.4748587918)

(full digits: :data:`BEND45_TIPS`; we trust about 10 significant digits.)

Literature (8 elements, *not* mesh-converged), mapped to this placement (Simo and Vu-Quoc
list the components in the order (y, x, z) of this placement, e.g. (15.79, 47.23, 53.37)):

- Bathe and Bolourchi (1979), P = 600: (47.2, 15.9, 53.4); P = 300: (59.2, 22.5, 39.5).
- Simo and Vu-Quoc (1986), 8 linear elements: P = 300: (58.84, 22.33, 40.08);
  P = 450: (52.32, 18.62, 48.39); P = 600: (47.23, 15.79, 53.37).

Converged values in the later literature are reported near (47.1, 15.7, 53.5) for
P = 600 with refined meshes; I could not verify exact published digits for this data set
here, so the reference is the shooting number above.

A third-party converged number for a *variant* that cross-checks the 3-D solver: the
Kynema code's regression test (Static_CurvedCompositeBeamBending, a 15-node spectral
element) uses shear factor 5/6, stiffnesses rounded to 8.333e5, and a reference axis that
is the parabola ``y(x)`` through three points of the arc (tip curving to ``-y``, length
78.566 instead of 78.540, tangent not along ``x`` at the root), and reports the tip
displacement (-23.6459716009047, 13.7208006040058, 53.5776450626987) at P = 600. Given
that parabola, the shooting solver reproduces all these digits to about 1e-12
(``tests/references/test_bend45.py``); for the true circular arc with shear factor 5/6 it
gives (-23.5606, -13.6046, 53.4755). So Kynema's number is not the Bathe-Bolourchi bend,
but it validates the solver.
"""

from __future__ import annotations

import math

import numpy as np

from .cosserat_bvp import RodSolution, RodStiffness, solve_rod

__all__ = [
    "BEND45",
    "BEND45_TIPS",
    "bend45_convergence",
    "bend45_frame",
    "bend45_solve",
    "bend45_stiffness",
    "bend45_table",
    "bend45_tip",
]

BEND45 = {"R": 100.0, "angle": math.pi / 4, "E": 1.0e7, "G": 5.0e6, "A": 1.0,
          "I": 1.0 / 12.0, "J": 1.0 / 6.0}
"""Benchmark data (consistent units)."""

BEND45_TIPS = {
    300.0: (58.779122489683, 22.244780945368, 40.191891670150),
    450.0: (52.238558011155, 18.508178925370, 48.502927344141),
    600.0: (47.150438573629, 15.684800534039, 53.474858791825),
}
"""Converged tip positions ``(x, y, z)`` by shooting (rtol 1e-13), placement as above."""


def bend45_stiffness(shear_factor: float = 1.0) -> RodStiffness:
    """``(GA1, GA2, EA, EI1, EI2, GJ)`` of the benchmark; ``GA = shear_factor G A``."""
    d = BEND45
    GA = shear_factor * d["G"] * d["A"]
    EI = d["E"] * d["I"]
    return RodStiffness(GA, GA, d["E"] * d["A"], EI, EI, d["G"] * d["J"])


def bend45_frame(director: str = "in_plane") -> tuple[np.ndarray, tuple[float, float, float]]:
    """Clamp frame ``R0`` (columns ``d1, d2, d3``) and intrinsic curvature ``K0``."""
    k = 1.0 / BEND45["R"]
    if director == "in_plane":
        return np.column_stack([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]]), (0.0, k, 0.0)
    if director == "out_of_plane":
        return np.column_stack([[0.0, 0.0, 1.0], [0.0, -1.0, 0.0], [1.0, 0.0, 0.0]]), (k, 0.0, 0.0)
    raise ValueError(f"director must be 'in_plane' or 'out_of_plane', got {director!r}")


def bend45_solve(
    P: float,
    *,
    director: str = "in_plane",
    shear_factor: float = 1.0,
    load_steps: int | list[float] = 3,
    rtol: float = 1e-12,
    guess: np.ndarray | None = None,
    n_points: int = 41,
) -> RodSolution:
    """Shooting solution of the bend under the dead tip load ``(0, 0, P)``."""
    R0, K0 = bend45_frame(director)
    L = BEND45["R"] * BEND45["angle"]
    return solve_rod(
        L,
        bend45_stiffness(shear_factor),
        R0=R0,
        K0=K0,
        tip_force=(0.0, 0.0, P),
        load_steps=load_steps,
        rtol=rtol,
        guess=guess,
        n_points=n_points,
    )


def bend45_tip(P: float, **kw) -> np.ndarray:
    """Tip position ``(x, y, z)`` under the load ``P`` (keywords of :func:`bend45_solve`)."""
    return bend45_solve(P, **kw).tip.copy()


def bend45_table(
    loads: tuple[float, ...] = (300.0, 450.0, 600.0), **kw
) -> dict[float, np.ndarray]:
    """Tip positions for increasing loads; each solution warm-starts the next.

    The first load is reached in three continuation steps; the scaled base resultants
    ``(n(0)/P, m(0)/(P L))`` of one load are the Newton start of the next.
    """
    L = BEND45["R"] * BEND45["angle"]
    out: dict[float, np.ndarray] = {}
    guess = None
    for P in loads:
        if guess is None:
            sol = bend45_solve(P, **kw)
        else:
            sol = bend45_solve(P, load_steps=[1.0], guess=guess, **kw)
        out[P] = sol.tip.copy()
        guess = np.r_[sol.base_force / P, sol.base_moment / (P * L)]
    return out


def bend45_convergence(
    P: float = 600.0, rtols: tuple[float, ...] = (1e-7, 1e-8, 1e-10, 1e-12, 1e-13)
) -> dict[float, np.ndarray]:
    """Tolerance study: tip position for each integrator ``rtol``."""
    return {rtol: bend45_tip(P, rtol=rtol) for rtol in rtols}


if __name__ == "__main__":  # pragma: no cover - report helper
    for P, tip in bend45_table(rtol=1e-13).items():
        print(f"P = {P:5.0f}: tip = ({tip[0]:.12f}, {tip[1]:.12f}, {tip[2]:.12f})")
    for rtol, tip in bend45_convergence().items():
        print(f"rtol = {rtol:.0e}: tip = ({tip[0]:.12f}, {tip[1]:.12f}, {tip[2]:.12f})")
