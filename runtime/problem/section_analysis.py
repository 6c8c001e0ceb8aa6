"""The section of a problem or section file, analysed: what ``kvrod section`` computes.

A *section file* holds only ``[section]`` with ``[materials.NAME]`` (a composite section),
or ``[section]`` (a closed-form shape) with ``[material]``, besides ``name`` and
``description``; a *problem file* (with ``[rod]``) is read as a whole (every key checked)
and its section taken. Both go through the problem's parsers
(``runtime.problem.schema.section_and_material``), so a section means the same in
either file.

:func:`analyse_problem_section` runs the finite-element section analysis
(:func:`runtime.section.analysis.analyse_section`): of the composite's regions, or of the
closed-form shape as one region of the problem's Kelvin-Voigt material. Its result carries, besides
the 6x6 stiffness and viscosities about the elastic centroid, ``info`` (merged into
``SectionResult.to_dict()``): the source, the kind, the damping route and the viscosity the
rod takes by it, the regions and materials, and for a closed-form shape the diagonal rod
model ``kvrod simulate`` takes from the generated formulas (with Cowper's or the energy
shear factors), for comparison.
"""

from __future__ import annotations

import copy
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from runtime.errors import ParameterError
from runtime.problem import coerce as C
from runtime.problem.materials import GeneralizedMaxwell, KelvinVoigt
from runtime.problem.registry import EXAMPLES_DIR, ProblemFileError, read_toml
from runtime.problem.schema import Problem, apply_override, section_and_material
from runtime.problem.section_file import SECTION_FILE_KEYS, with_section_file
from runtime.problem.sections import Composite, GivenStiffness, Shape


class SectionSpec:
    """What a section analysis needs, from a problem or a section file: ``name``,
    ``description``, ``section`` (Shape or Composite), ``material`` (the homogeneous
    section's material, else None), ``source`` (the file, or "problem")."""

    def __init__(self, name: str, description: str, section: Any, material: Any,
                 source: str) -> None:
        self.name, self.description, self.source = name, description, source
        self.section, self.material = section, material
        if isinstance(section, GivenStiffness):
            raise ParameterError("section.kind", "stiffness", "a shape (rectangle, ellipse, "
                                 "circle, tube) or a composite section: a stiffness section "
                                 "gives the rod's stiffness directly, there is no section "
                                 "to analyse")
        if isinstance(section, Shape) and section.tapered:
            ends = ", ".join(f"section.{n}_end" for n, _ in section.dims_end)
            raise ParameterError(ends.split(", ")[0], dict(section.dims_end)[
                section.dims_end[0][0]], "no taper for a section analysis (it analyses one "
                f"section; drop {ends}, or analyse each end's dimensions in turn)")
        if isinstance(material, GeneralizedMaxwell):
            raise ParameterError("material.model", "generalized_maxwell", "'kelvin_voigt' "
                                 "for a section analysis (a generalized Maxwell rod's "
                                 "section is its shape's constants times the relaxation "
                                 "functions: kvrod derive show maxwell_rod)")
        if isinstance(material, KelvinVoigt) and (material.density_end is not None
                                                  or material.youngs_modulus_end is not None):
            raise ParameterError("material.youngs_modulus_end" if material.youngs_modulus_end
                                 is not None else "material.density_end",
                                 material.youngs_modulus_end or material.density_end,
                                 "no variation along the rod for a section analysis (it "
                                 "analyses one section)")
        if isinstance(material, KelvinVoigt) and not material.poisson_ratio < 0.5:
            raise ParameterError("material.poisson_ratio", material.poisson_ratio,
                                 "-1 < nu < 1/2 for a section analysis (a nearly "
                                 "incompressible material may take nu = 0.4999)")

    @property
    def kind(self) -> str:
        return self.section.kind

    def regions_and_materials(self) -> tuple[tuple[Any, ...], dict[str, Any]]:
        """The regions and {name: SectionMaterial} of the analysis: a composite's own, or
        the shape as one region (centred at the origin) of the Kelvin-Voigt material
        (named "material")."""
        from runtime.section import Circle, Ellipse, Rectangle, Region, Tube
        from runtime.section import isotropic as iso

        if isinstance(self.section, Composite):
            return self.section.regions, self.section.used_materials()
        d = dict(self.section.dims)
        kind = self.section.kind
        if kind == "circle":
            shape: Any = Circle(d["radius"])
        elif kind == "rectangle":
            shape = Rectangle(d["width"], d["height"])
        elif kind == "ellipse":
            shape = Ellipse(d["a"], d["b"])
        elif d["inner_radius"] == 0.0:
            shape = Circle(d["outer_radius"])
        else:
            shape = Tube(d["inner_radius"], d["outer_radius"])
        m = self.material
        mat = iso("material", m.youngs_modulus, m.poisson_ratio, m.density, m.tau_S, m.tau_B,
                  path="material")
        return (Region("material", shape, "section"),), {"material": mat}


def _section_file(doc: Mapping[str, Any], where: str, name: str) -> SectionSpec:
    C.no_unknown_keys("", doc, SECTION_FILE_KEYS)
    if "section" not in doc:
        raise ParameterError("section", None, "a [section] table (kind = 'composite' with "
                             "[[section.regions]] and [materials.NAME], or a shape with "
                             "[material])")
    section, material = section_and_material(doc)
    return SectionSpec(C.string("name", doc.get("name", name)),
                       str(doc.get("description", "")), section, material, where)


def _resolve(spec: str | Path) -> Path:
    p = Path(spec)
    if p.suffix == ".toml" or p.exists() or "/" in str(spec):
        if not p.exists():
            raise ProblemFileError(f"{p}: no such problem or section file")
        return p
    f = EXAMPLES_DIR / f"{spec}.toml"
    if f.is_file():
        return f
    raise ProblemFileError(f"unknown section {str(spec)!r}: give a problem or section file "
                           "(.toml), or the name of one in examples/ (e.g. cable_section)")


def load_section(spec: str | Path | Problem | Mapping[str, Any],
                 overrides: Mapping[str, Any] | None = None) -> SectionSpec:
    """The section of a problem (object or file), a section file, a built-in example's
    name, or a table of either, with overrides (dotted paths, as ``--set``) applied and
    checked.

    Raises
    ------
    ProblemFileError
        The file is missing, unreadable or not TOML.
    ParameterError
        A key or value is wrong (the message names it and, for a file, the file).
    """
    if isinstance(spec, Problem):
        p = spec.with_overrides(overrides or {})
        return SectionSpec(p.name, p.description, p.section, p.material, "problem")
    if isinstance(spec, Mapping):
        doc, where, name = copy.deepcopy(dict(spec)), "table", "section"
    else:
        path = _resolve(spec)
        doc, _ = read_toml(path, what="problem or section file")
        where, name = str(path), path.stem
    try:
        if "rod" in doc:
            from runtime.problem.registry import load_problem

            if isinstance(spec, Mapping):
                p = Problem.from_mapping(doc, name=name).with_overrides(overrides or {})
            else:
                p = load_problem(Path(where), overrides)
            return SectionSpec(p.name, p.description, p.section, p.material, where)
        for key, value in (overrides or {}).items():
            apply_override(doc, key, value)
        base = None if where == "table" else Path(where).parent
        return _section_file(dict(with_section_file(doc, base)), where, name)
    except ParameterError as exc:
        if exc.where or where == "table":
            raise
        raise ParameterError(exc.name, exc.value, exc.allowed, where=where) from None


def analyse_problem_section(spec: str | Path | Problem | Mapping[str, Any] | SectionSpec,
                            overrides: Mapping[str, Any] | None = None, *,
                            tol: float = 1e-4) -> Any:
    """The finite-element section analysis of a problem's or a section file's section.

    Parameters
    ----------
    spec
        A :class:`~runtime.problem.schema.Problem`, a problem or section file (or the name
        of one in examples/), its table, or a :class:`SectionSpec`.
    overrides
        Dotted paths and values (``{"materials.pvc.tau_S": 0.02}``), checked.
    tol
        Relative mesh-convergence tolerance of every diagonal entry (default 1e-4).

    Returns
    -------
    runtime.section.analysis.SectionResult
        Stiffness, consistent and naive viscosity (6x6, strain order Gamma1, Gamma2,
        Gamma3, K1, K2, K3; SI) about the elastic centroid, centres, inertia, mesh and
        convergence; ``info`` holds the source, kind, damping route, the viscosity the
        rod takes (``"rod_viscosity"``: "viscosity" or "viscosity_naive"), the regions and
        materials, and for a closed-form shape ``"closed_form"``: the diagonal rod model of
        the generated formulas (``kvrod simulate``'s), with its shear factors.
    """
    from dataclasses import replace

    from runtime.section import analyse_section

    if isinstance(spec, SectionSpec) and overrides:
        raise ParameterError("overrides", dict(overrides), "none with a SectionSpec (give "
                             "them to load_section, which checks them)")
    s = spec if isinstance(spec, SectionSpec) else load_section(spec, overrides)
    regions, mats = s.regions_and_materials()
    res = analyse_section(regions, mats, tol=tol)
    info: dict[str, Any] = {
        "name": s.name, "source": s.source, "kind": s.kind,
        "damping": s.section.damping if isinstance(s.section, Composite) else
        s.material.damping,
        "regions": [{"name": r.name or f"section.regions[{i}]", "material": r.material,
                     "shape": r.shape.to_mapping(), "area": r.shape.area}
                    for i, r in enumerate(regions)],
        "materials": {k: {"kind": "isotropic" if m.isotropic else "anisotropic",
                          "density": m.density, **m.to_mapping()}
                      for k, m in mats.items()},
    }
    info["rod_viscosity"] = "viscosity" if info["damping"] == "consistent" else \
        "viscosity_naive"
    if isinstance(s.section, Shape):
        info["closed_form"] = _closed_form(s.section, s.material)
    return replace(res, info=info)


def _closed_form(section: Shape, material: KelvinVoigt) -> dict[str, Any]:
    """The diagonal rod model ``kvrod simulate`` takes for this shape and material (the
    generated formulas), in the order Gamma1, Gamma2, Gamma3, K1, K2, K3."""
    m = material.rod_matrices(section, np.array([0.0]))
    k = section.constants(material.poisson_ratio, np.array([0.0]))
    factors = ("Cowper" if section.shear_correction is True else "energy"
               if section.shear_correction == "energy" else "none (1)")
    return {"stiffness_diagonal": [*m["C_F"][0].tolist(), *m["C_M"][0].tolist()],
            "viscosity_diagonal": [*m["V_F"][0].tolist(), *m["V_M"][0].tolist()],
            "damping": material.damping,
            "shear_factors": {"kind": factors, "kappa_1": float(k["kappa_1"][0]),
                              "kappa_2": float(k["kappa_2"][0])},
            "mass_per_length": float(m["rhoA"][0]),
            "rotary_inertia": m["rhoI"][0].tolist()}
