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


def _maxwell_solid(m):
    """The reference's 3-D generalized Maxwell solid of a material's plain numbers."""
    from references.viscoelastic_material import GeneralizedMaxwell, shear_bulk_from_E_nu

    G, K = (float(np.real(x)) for x in shear_bulk_from_E_nu(m.youngs_modulus,
                                                            m.poisson_ratio))
    return GeneralizedMaxwell(G, K, [b.shear_modulus for b in m.branches],
                              [b.bulk_modulus for b in m.branches],
                              [b.tau for b in m.branches])


def _maxwell_frequencies(problem, sec, family: str, n: int) -> np.ndarray:
    """|lambda| of the first n complex eigenvalues of the continuum with the complex
    moduli E(s), G(s) of the generalized Maxwell solid (correspondence principle)."""
    from references import viscoelastic_beam as vb

    solid = _maxwell_solid(problem.material)
    L, rho = problem.rod.length, problem.material.density
    if family in ("bending-1", "bending-2"):
        I, kappa = (sec.I1, sec.kappa_2) if family == "bending-1" else (sec.I2, sec.kappa_1)
        lam = vb.timoshenko_eigenvalues(n, L=L, rho=rho, A=sec.A, I=I, kappa=kappa,
                                        E=solid.E, G=solid.G_s)
    elif family == "axial":
        lam = vb.axial_eigenvalues(n, L=L, rho=rho, E=solid.E)
    elif family == "torsion":
        lam = vb.torsion_eigenvalues(n, L=L, rho=rho, G=solid.G_s, J_T=sec.J_T, I3=sec.I3)
    else:
        return np.full(n, math.nan)
    return np.abs(np.asarray(lam))


def frequencies(problem, family: str, n: int) -> np.ndarray:
    """First n continuum angular frequencies (rad/s) of a family (NaN where unknown); for
    a generalized Maxwell material the natural frequencies |lambda| of the complex-modulus
    continuum."""
    sec = _section(problem)
    if sec is None or n < 1:
        return np.full(max(n, 0), math.nan)
    m = problem.material
    if getattr(m, "model", "") == "generalized_maxwell":
        return _maxwell_frequencies(problem, sec, family, n)
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
