"""Cross-section analysis of composite, anisotropic sections (issue 25).

A floor below ``runtime/problem``: it imports NumPy, SciPy, shapely, cytriangle and
``runtime.errors`` only. ``analyse_section(regions, materials, tol=...)`` returns a
:class:`~runtime.section.analysis.SectionResult` with the 6x6 stiffness, the consistent
and the naive 6x6 viscosity about the elastic centroid, the shear centre and the inertia
per length; the parsers ``materials_from_mapping`` (``[materials.NAME]``) and
``regions_from_mapping`` (``[[section.regions]]``) turn TOML tables into its input, with
errors that name the key path.
"""

from runtime.section.analysis import RESULTANTS, STRAINS, SectionResult, analyse_section
from runtime.section.materials import (
    SectionMaterial,
    anisotropic,
    isotropic,
    material_from_mapping,
    materials_from_mapping,
)
from runtime.section.mesh import Mesh, mesh_regions
from runtime.section.regions import Region, check_regions, regions_from_mapping
from runtime.section.shapes import (
    Circle,
    Ellipse,
    PolygonShape,
    Rectangle,
    Tube,
    shape_from_mapping,
)

__all__ = [
    "RESULTANTS", "STRAINS", "Circle", "Ellipse", "Mesh", "PolygonShape", "Rectangle",
    "Region", "SectionMaterial", "SectionResult", "Tube", "analyse_section", "anisotropic",
    "check_regions", "isotropic", "material_from_mapping", "materials_from_mapping",
    "mesh_regions", "regions_from_mapping", "shape_from_mapping",
]
