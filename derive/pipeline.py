"""The ordered derivation pipeline: from 3-D continuum theory to the rod's damping model.

``PIPELINE`` lists every step with the earlier steps it consumes; :func:`run` evaluates them
in order (each once) and returns the records by name. Steps are pure, so the result is cached.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

from derive.step import Step, StepFunction
from derive.steps.anisotropic import (
    anisotropic_shear,
    anisotropic_viscosity,
    elastic_condensation,
    voigt_materials,
)
from derive.steps.biot import biot_strain
from derive.steps.dissipation import dissipation
from derive.steps.energy import stored_energy
from derive.steps.kelvin_voigt import kelvin_voigt_uniaxial
from derive.steps.kinematics import kinematics
from derive.steps.material import isotropic_moduli, lateral_contraction, svk_material
from derive.steps.maxwell import maxwell_limit, maxwell_material
from derive.steps.maxwell_rod import maxwell_rod
from derive.steps.naive import naive_resultants
from derive.steps.sections import cross_sections
from derive.steps.strain import green_lagrange


@dataclass(frozen=True)
class PipelineEntry:
    """A step function and the names of the steps it takes, in argument order."""

    name: str
    function: StepFunction
    inputs: tuple[str, ...]


PIPELINE: tuple[PipelineEntry, ...] = (
    PipelineEntry("kinematics", kinematics, ()),
    PipelineEntry("green_lagrange", green_lagrange, ("kinematics",)),
    PipelineEntry("isotropic_moduli", isotropic_moduli, ()),
    PipelineEntry("svk_material", svk_material, ("isotropic_moduli", "green_lagrange")),
    PipelineEntry("lateral_contraction", lateral_contraction,
                  ("isotropic_moduli", "green_lagrange")),
    PipelineEntry("stored_energy", stored_energy, ("kinematics", "lateral_contraction")),
    PipelineEntry("dissipation", dissipation,
                  ("kinematics", "lateral_contraction", "isotropic_moduli", "stored_energy")),
    PipelineEntry("naive_resultants", naive_resultants,
                  ("kinematics", "lateral_contraction", "isotropic_moduli", "dissipation")),
    PipelineEntry("cross_sections", cross_sections,
                  ("kinematics", "stored_energy", "dissipation")),
    PipelineEntry("maxwell_limit", maxwell_limit, ()),
    PipelineEntry("maxwell_material", maxwell_material, ("maxwell_limit", "dissipation")),
    PipelineEntry("maxwell_rod", maxwell_rod,
                  ("kinematics", "lateral_contraction", "isotropic_moduli", "stored_energy",
                   "maxwell_material")),
    PipelineEntry("kelvin_voigt_uniaxial", kelvin_voigt_uniaxial,
                  ("isotropic_moduli", "dissipation", "naive_resultants", "maxwell_rod")),
    PipelineEntry("biot_strain", biot_strain, ("green_lagrange", "lateral_contraction")),
    # issue 25: any homogeneous C and V (Voigt), consistent and naive viscosity
    PipelineEntry("voigt_materials", voigt_materials,
                  ("isotropic_moduli", "dissipation", "naive_resultants")),
    PipelineEntry("elastic_condensation", elastic_condensation,
                  ("voigt_materials", "lateral_contraction")),
    PipelineEntry("anisotropic_viscosity", anisotropic_viscosity,
                  ("isotropic_moduli", "dissipation", "naive_resultants", "voigt_materials",
                   "elastic_condensation")),
    PipelineEntry("anisotropic_shear", anisotropic_shear,
                  ("isotropic_moduli", "dissipation", "voigt_materials")),
)

STEP_NAMES: tuple[str, ...] = tuple(e.name for e in PIPELINE)


class UnknownStepError(KeyError):
    """Raised for a step name that is not in the pipeline."""

    def __init__(self, name: str):
        super().__init__(name)
        self.name = name

    def __str__(self) -> str:
        return f"unknown step {self.name!r}; steps are: {', '.join(STEP_NAMES)}"


def _entry(name: str) -> PipelineEntry:
    for e in PIPELINE:
        if e.name == name:
            return e
    raise UnknownStepError(name)


@lru_cache(maxsize=1)
def run() -> dict[str, Step]:
    """Evaluate the whole pipeline in order; returns {name: Step}."""
    done: dict[str, Step] = {}
    for e in PIPELINE:
        rec = e.function(*(done[i] for i in e.inputs))
        if rec.name != e.name or tuple(rec.inputs) != e.inputs:
            raise AssertionError(f"step {e.name!r} declares name/inputs inconsistent "
                                 f"with the pipeline: {rec.name!r}, {rec.inputs}")
        done[e.name] = rec
    return done


def step(name: str) -> Step:
    """The record of one step (evaluates the pipeline up to it, cached)."""
    _entry(name)
    return run()[name]
