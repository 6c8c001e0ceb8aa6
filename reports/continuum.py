"""Continuum reference frequencies for the modes table, from the independent references.

For a straight, uniform rod with no end motion, clamped at s = 0 and free at s = L, pinned
at both ends (simply supported) or free at both ends, the ``references`` package (written
without kvrod code) gives the Timoshenko bending, axial and torsional frequencies
(``references.beams`` and, for generalized Maxwell materials, the complex-modulus
cantilever of ``references.viscoelastic_beam``; ``references.supported`` for the other two
supports); the section constants come from ``references.sections`` too, so the column
``analytic omega`` of ``kvrod modes`` is an independent check of the discrete rod, not a
copy of it. Where no reference exists (rigid and shear modes, a Maxwell rod that is not a
cantilever, a root the reference cannot track, zones that make the rod vary; a zone over
the whole rod is the rod's section and material) the column stays empty.
"""

from __future__ import annotations

import math

import numpy as np

from references import beams, supported
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


def support(problem) -> str | None:
    """"clamped-free", "pinned-pinned" or "free-free" for a straight, untwisted, uniform
    rod without end motion whose ends are those; else None (no continuum reference)."""
    from runtime.problem.geometry import Straight

    if problem.material is None or getattr(problem.section, "coupled", False):
        return None                     # a composite or coupled section: no closed form here
    if problem.zones:                   # see uniform_equivalent (attach folds a whole-rod zone)
        return None
    if not (isinstance(problem.rod.geometry, Straight) and problem.rod.geometry.twist == 0
            and problem.start.motion is None and problem.end.motion is None
            and not getattr(problem.section, "tapered", False)
            and problem.material.density_end is None
            and problem.material.youngs_modulus_end is None):
        return None
    ends = (problem.start.kind, problem.end.kind)
    return {("clamped", "free"): "clamped-free", ("pinned", "pinned"): "pinned-pinned",
            ("free", "free"): "free-free"}.get(ends)


def applies(problem) -> bool:
    """Straight, uniform, no end motion, and clamped-free, pinned-pinned or free-free: the
    continuum references apply."""
    return support(problem) is not None


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
    a generalized Maxwell material (cantilevers only) the natural frequencies |lambda| of
    the complex-modulus continuum."""
    sec = _section(problem)
    kind = support(problem)
    if sec is None or n < 1 or kind is None:
        return np.full(max(n, 0), math.nan)
    m = problem.material
    if getattr(m, "model", "") == "generalized_maxwell":
        if kind != "clamped-free":
            return np.full(n, math.nan)
        return _maxwell_frequencies(problem, sec, family, n)
    E, rho = m.youngs_modulus, m.density
    G = E / (2 * (1 + m.poisson_ratio))
    L = problem.rod.length
    if family in ("bending-1", "bending-2"):   # about d1: E I1, shear along d2 (and v.v.)
        I, kappa = (sec.I1, sec.kappa_2) if family == "bending-1" else (sec.I2, sec.kappa_1)
        kw = {"L": L, "rho": rho, "A": sec.A, "E": E, "I": I, "kGA": kappa * G * sec.A}
        return {"clamped-free": beams.timoshenko_frequencies,
                "pinned-pinned": supported.simply_supported_timoshenko_frequencies,
                "free-free": supported.free_free_timoshenko_frequencies}[kind](n, **kw)
    if family == "torsion":
        kw = {"L": L, "rho": rho, "G": G, "J_T": sec.J_T, "I3": sec.I3}
        if kind == "clamped-free":
            return beams.torsional_frequencies(n, **kw)
        return supported.shaft_free_free_frequencies(n, **kw)   # a pin leaves the twist free
    if family == "axial":
        if kind == "clamped-free":
            return beams.axial_frequencies(n, L=L, rho=rho, E=E)
        return supported.bar_frequencies(n, L=L, rho=rho, E=E)
    return np.full(n, math.nan)


def attach(problem, modes) -> None:
    """Set ``analytic_omega`` of each mode where the references apply: the k-th mode of a
    family gets the family's k-th continuum frequency; None where there is none (or the
    reference cannot compute it)."""
    problem = problem.uniform_equivalent()     # zones: the rod's own, or none at all
    if problem is None or not applies(problem):
        return
    counts: dict[str, int] = {}
    for md in modes:
        counts[md.family] = max(counts.get(md.family, 0), md.family_index)
    ref: dict[str, np.ndarray] = {}
    for f, k in counts.items():
        try:
            ref[f] = np.asarray(frequencies(problem, f, k), dtype=float)
        except RuntimeError:      # a root the reference could not find or track
            ref[f] = np.full(k, math.nan)
    for md in modes:
        w = float(ref[md.family][md.family_index - 1])
        md.analytic_omega = w if math.isfinite(w) else None
