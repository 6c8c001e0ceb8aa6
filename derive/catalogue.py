"""The catalogue of the derivation's steps, from 3-D continuum theory to the rod's damping
model, and its evaluation from scratch.

``PIPELINE`` lists the steps: name, title, the paper's equations, the earlier steps each
consumes and where its function lives. It is plain data, so listing the steps (``kvrod
derive list``) imports no SymPy and derives nothing; the title and equations of each
:class:`~derive.step.Step` record come from here (:func:`derive.step.make_step`).
:func:`derive_all` evaluates the steps in order, each once; ``derive.pipeline`` keeps the
records for the process and the derivation cache (``derive.cache``) between processes.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

#: progress(done, total, entry) is called before each step is derived (entry: the step
#: about to run) and once at the end with done == total and entry None
Progress = Callable[[int, int, "PipelineEntry | None"], None]


@dataclass(frozen=True)
class PipelineEntry:
    """One step of the catalogue.

    name: identifier (``kvrod derive show NAME``); title: one-line human title;
    equations: the paper's equation numbers (or sections) it reproduces; inputs: the
    names of the steps it takes, in argument order; target: ``"module:function"`` of the
    step function (imported only when the step is derived).
    """

    name: str
    title: str
    equations: tuple[str, ...]
    inputs: tuple[str, ...]
    target: str

    @property
    def function(self) -> Callable[..., Any]:
        """The step function (imports its module, and SymPy with it)."""
        module, _, attr = self.target.partition(":")
        return getattr(importlib.import_module(module), attr)


def _entry_of(name: str, module: str, title: str, equations: tuple[str, ...],
              inputs: tuple[str, ...] = (), function: str | None = None) -> PipelineEntry:
    return PipelineEntry(name, title, equations, inputs,
                         f"derive.steps.{module}:{function or name}")


#: the catalogue of the derivation's steps, in the order they are derived
PIPELINE: tuple[PipelineEntry, ...] = (
    _entry_of("kinematics", "kinematics",
              "Rod kinematics, deformation gradient and strain vector H",
              ("(14)", "(15)", "(16)", "(17)")),
    _entry_of("green_lagrange", "strain", "Green-Lagrange strain: exact and small-strain forms",
              ("(18)", "(19)", "(20)"), ("kinematics",)),
    _entry_of("isotropic_moduli", "material", "Isotropic moduli from a uniaxial-stress test",
              ("Sect. 3.3",)),
    _entry_of("svk_material", "material",
              "Saint-Venant-Kirchhoff energy and stress; rigid-section stresses",
              ("(21)", "(22)", "(23)"), ("isotropic_moduli", "green_lagrange")),
    _entry_of("lateral_contraction", "material",
              "Uniform lateral contraction and the modified SVK stress", ("(24)", "(25)"),
              ("isotropic_moduli", "green_lagrange")),
    _entry_of("stored_energy", "energy",
              "Stored energy: SVK density, cross-section integral, rod stiffnesses",
              ("(26)", "(27)", "(10)", "(2)", "(7)"), ("kinematics", "lateral_contraction")),
    _entry_of("dissipation", "dissipation",
              "Kelvin-Voigt dissipation function and the rod damping parameters",
              ("(28)", "(29)", "(30)", "(31)", "(32)", "(11)", "(3)", "(4)", "(5)", "(6)",
               "(8)", "(9)"),
              ("kinematics", "lateral_contraction", "isotropic_moduli", "stored_energy")),
    _entry_of("naive_resultants", "naive",
              "The naive resultant route: eta~_E and the missed in-plane dissipation",
              ("Sect. 4.2", "Sect. 4.3"),
              ("kinematics", "lateral_contraction", "isotropic_moduli", "dissipation")),
    _entry_of("cross_sections", "sections",
              "Cross sections: area, moments, torsion constants, shear correction factors",
              ("Sect. 3.1", "(7)", "footnote 1"),
              ("kinematics", "stored_energy", "dissipation")),
    _entry_of("maxwell_limit", "maxwell", "Generalised Maxwell -> Kelvin-Voigt at low frequency",
              ("Sect. 4.4",)),
    _entry_of("maxwell_material", "maxwell",
              "3-D generalized Maxwell solid: internal variables, Laplace moduli, KV limit",
              ("Sect. 4.4", "Sect. 6 (future work)"), ("maxwell_limit", "dissipation")),
    _entry_of("maxwell_rod", "maxwell_rod",
              "Generalized Maxwell rod: Laplace-domain stiffnesses and the rod's Prony series",
              ("(7)", "(24)", "Sect. 4.4", "Sect. 6 (future work)"),
              ("kinematics", "lateral_contraction", "isotropic_moduli", "stored_energy",
               "maxwell_material")),
    _entry_of("kelvin_voigt_uniaxial", "kelvin_voigt",
              "Exact uniaxial modulus of the 3-D Kelvin-Voigt solid against E (1 + s tau_E)",
              ("(6)", "(29)", "Sect. 4.2", "Sect. 4.4"),
              ("isotropic_moduli", "dissipation", "naive_resultants", "maxwell_rod")),
    _entry_of("biot_strain", "biot",
              "Biot strain: closed-form spectral decomposition of C (appendix A1)",
              ("A1", "(18)", "footnote 19"), ("green_lagrange", "lateral_contraction")),
    _entry_of("voigt_materials", "anisotropic",
              "Materials as 6x6 Voigt matrices: isotropic C and V, anisotropic classes",
              ("(23)", "(29)", "Sect. 4.3"),
              ("isotropic_moduli", "dissipation", "naive_resultants")),
    _entry_of("elastic_condensation", "anisotropic",
              "Elastic lateral response of a fibre: w = (e_33, -C_ff^-1 C_f3), E_eff = 1/S_33",
              ("(24)", "(25)", "Sect. 3.4"), ("voigt_materials", "lateral_contraction")),
    _entry_of("anisotropic_viscosity", "anisotropic",
              "Consistent w.V.w and naive e_33.V.w extensional viscosity for any C and V",
              ("(4)", "(5)", "(6)", "(32)", "Sect. 4.2"),
              ("isotropic_moduli", "dissipation", "naive_resultants", "voigt_materials",
               "elastic_condensation")),
    _entry_of("anisotropic_shear", "anisotropic",
              "Shear and torsion viscosity of a homogeneous section: when (8) carries over",
              ("(8)", "(9)", "(32)"), ("isotropic_moduli", "dissipation", "voigt_materials")),
)

STEP_NAMES: tuple[str, ...] = tuple(e.name for e in PIPELINE)


class UnknownStepError(KeyError):
    """Raised for a step name that is not in the pipeline."""

    def __init__(self, name: str):
        super().__init__(name)
        self.name = name

    def __str__(self) -> str:
        return f"unknown step {self.name!r}; steps are: {', '.join(STEP_NAMES)}"


def entry(name: str) -> PipelineEntry:
    """The catalogue entry of step ``name`` (:class:`UnknownStepError` if there is none)."""
    for e in PIPELINE:
        if e.name == name:
            return e
    raise UnknownStepError(name)


def derive_all(progress: Progress | None = None) -> dict[str, Any]:
    """Evaluate the whole pipeline in order, from scratch; returns {name: step record}
    (:class:`derive.step.Step`).

    ``progress`` (optional) is told which step starts (see ``Progress``); library code
    never prints, the command line draws the progress from it.
    """
    done: dict[str, Any] = {}
    for k, e in enumerate(PIPELINE):
        if progress is not None:
            progress(k, len(PIPELINE), e)
        rec = e.function(*(done[i] for i in e.inputs))
        if rec.name != e.name or tuple(rec.inputs) != e.inputs:
            raise AssertionError(f"step {e.name!r} declares name/inputs inconsistent "
                                 f"with the pipeline: {rec.name!r}, {rec.inputs}")
        done[e.name] = rec
    if progress is not None:
        progress(len(PIPELINE), len(PIPELINE), None)
    return done
