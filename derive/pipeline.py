"""The ordered derivation pipeline: from 3-D continuum theory to the rod's damping model.

``PIPELINE`` is the catalogue of the steps: name, title, the paper's equations, the earlier
steps each consumes and where its function lives. It is plain data, so listing the steps
(``kvrod derive list``) imports no SymPy and derives nothing; the title and equations of
each :class:`~derive.step.Step` record come from here (:func:`derive.step.make_step`).

:func:`run` evaluates the steps in order (each once) and returns the records by name. Steps
are pure, so the result is kept for the process and, between processes, in the derivation
cache (:mod:`derive.cache`: the user's cache folder, keyed by the content of derive/ and the
tool versions, never the checkout).
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # derive.step imports SymPy lazily; the type is for annotations only
    from derive.step import Step, StepFunction

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
    def function(self) -> StepFunction:
        """The step function (imports its module, and SymPy with it)."""
        module, _, attr = self.target.partition(":")
        return getattr(importlib.import_module(module), attr)


def _entry_of(name: str, module: str, title: str, equations: tuple[str, ...],
              inputs: tuple[str, ...] = (), function: str | None = None) -> PipelineEntry:
    return PipelineEntry(name, title, equations, inputs,
                         f"derive.steps.{module}:{function or name}")


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


def derive_all(progress: Progress | None = None) -> dict[str, Step]:
    """Evaluate the whole pipeline in order, from scratch; returns {name: Step}.

    ``progress`` (optional) is told which step starts (see :data:`Progress`); library code
    never prints, the command line draws the progress from it.
    """
    done: dict[str, Step] = {}
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


_memo: dict[str, Step] | None = None


def run(progress: Progress | None = None) -> dict[str, Step]:
    """All step records by name, in pipeline order.

    Derived once per process; between processes they come from the derivation cache
    (:func:`derive.cache.load_or_derive`: rebuilt when anything in derive/ or a tool
    version changed; ``KVROD_DERIVE_CACHE=0`` derives from scratch and writes nothing).
    ``progress`` is called only when the steps are actually derived.
    """
    global _memo
    if _memo is None:
        from derive import cache

        _memo = cache.load_or_derive(progress)
    return dict(_memo)


def forget() -> None:
    """Drop the records (and the formula table) kept for this process; the disk cache is
    left alone."""
    global _memo
    _memo = None
    # the module (``derive.formulas`` as an attribute of the package is the function)
    importlib.import_module("derive.formulas").forget()


def step(name: str) -> Step:
    """The record of one step (see :func:`run`)."""
    entry(name)
    return run()[name]
