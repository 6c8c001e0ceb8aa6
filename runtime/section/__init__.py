"""Cross-section analysis of composite, anisotropic sections (issue 25).

A floor below ``runtime/problem``: it imports NumPy, SciPy, shapely, cytriangle and
``runtime.errors`` only. ``analyse_section(regions, materials, tol=...)`` returns a
:class:`~runtime.section.analysis.SectionResult` with the 6x6 stiffness, the consistent
and the naive 6x6 viscosity about the elastic centroid, the shear centre and the inertia
per length; the parsers ``materials_from_mapping`` (``[materials.NAME]``) and
``regions_from_mapping`` (``[[section.regions]]``) turn TOML tables into its input, with
errors that name the key path.

The names below are loaded on first use (PEP 562): a problem that only checks a
material's wave speed (``runtime.section.materials``) does not import SciPy, shapely and
the mesher, which cost a third of a short ``kvrod simulate`` process (issue 33, item 5).
"""

from __future__ import annotations

import importlib
from typing import Any

#: public name -> the submodule that defines it
_WHERE = {
    "RESULTANTS": "analysis", "STRAINS": "analysis", "SectionResult": "analysis",
    "analyse_section": "analysis",
    "SectionMaterial": "materials", "anisotropic": "materials", "isotropic": "materials",
    "material_from_mapping": "materials", "materials_from_mapping": "materials",
    "Mesh": "mesh", "mesh_regions": "mesh",
    "Region": "regions", "check_regions": "regions", "regions_from_mapping": "regions",
    "Circle": "shapes", "Ellipse": "shapes", "PolygonShape": "shapes",
    "Rectangle": "shapes", "Tube": "shapes", "shape_from_mapping": "shapes",
}

__all__ = sorted(_WHERE)


def __getattr__(name: str) -> Any:
    where = _WHERE.get(name)
    if where is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(f"{__name__}.{where}"), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *_WHERE})
