"""Continuum reference frequencies for the modes table, from the independent references.

For a straight, uniform, unloaded rod clamped at s = 0 and free at s = L, the
``references`` package (written without kvrod code) gives the Timoshenko bending, axial
and torsional frequencies; the section constants come from ``references.sections`` too,
so the column ``analytic omega`` of ``kvrod modes`` is an independent check of the
discrete rod, not a copy of it.
"""

from __future__ import annotations

import math

import numpy as np

from references import beams
from references import sections as ref_sections


def _section(problem):
    s = problem.section
    nu = problem.material.poisson_ratio
    if getattr(s, "kind", "") == "stiffness":
        return None
    d = dict(s.dims)
    return {"rectangle": lambda: ref_sections.rectangle(d["width"], d["height"], nu),
            "circle": lambda: ref_sections.circle(d["radius"], nu),
            "ellipse": lambda: ref_sections.ellipse(d["a"], d["b"], nu),
            "tube": lambda: ref_sections.tube(d["outer_radius"], d["inner_radius"], nu),
            }[s.kind]()


def applies(problem) -> bool:
    """Straight, uniform, clamped-free, no end motion: the continuum references apply."""
    from runtime.problem.geometry import Straight

    return (isinstance(problem.rod.geometry, Straight) and problem.rod.geometry.twist == 0
            and problem.start.kind == "clamped" and problem.start.motion is None
            and problem.end.kind == "free" and not getattr(problem.section, "tapered", False)
            and problem.material.density_end is None
            and problem.material.youngs_modulus_end is None)


def frequencies(problem, family: str, n: int) -> np.ndarray:
    """First n continuum angular frequencies (rad/s) of a family (NaN where unknown)."""
    sec = _section(problem)
    if sec is None or n < 1:
        return np.full(max(n, 0), math.nan)
    m = problem.material
    E, rho = m.youngs_modulus, m.density
    G = E / (2 * (1 + m.poisson_ratio))
    L = problem.rod.length
    if family == "bending-1":      # about d1: E I1, shear along d2
        return beams.timoshenko_frequencies(n, L=L, rho=rho, A=sec.A, E=E, I=sec.I1,
                                            kGA=sec.kappa_2 * G * sec.A)
    if family == "bending-2":      # about d2: E I2, shear along d1
        return beams.timoshenko_frequencies(n, L=L, rho=rho, A=sec.A, E=E, I=sec.I2,
                                            kGA=sec.kappa_1 * G * sec.A)
    if family == "torsion":
        return beams.torsional_frequencies(n, L=L, rho=rho, G=G, J_T=sec.J_T, I3=sec.I3)
    if family == "axial":
        return beams.axial_frequencies(n, L=L, rho=rho, E=E)
    return np.full(n, math.nan)


def attach(problem, modes) -> None:
    """Set ``analytic_omega`` of each mode where the references apply."""
    if not applies(problem):
        return
    counts: dict[str, int] = {}
    for md in modes:
        counts[md.family] = max(counts.get(md.family, 0), md.family_index)
    ref = {f: frequencies(problem, f, k) for f, k in counts.items()}
    for md in modes:
        w = float(ref[md.family][md.family_index - 1])
        md.analytic_omega = w if math.isfinite(w) else None
