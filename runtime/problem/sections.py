"""Cross sections: shapes whose constants come from the generated formulas, or stiffness
values given directly.

Shapes (TOML ``[section] kind = ...``; lengths in m): ``rectangle`` (``width`` along d1,
``height`` along d2), ``ellipse`` (half axis ``a`` along d2, ``b`` along d1), ``circle``
(``radius``), ``tube`` (``outer_radius``, ``inner_radius``). Their area, moments, torsion
constant and shear factors come from ``generated/constitutive.py`` (derived in
``derive/steps/sections.py``); ``shear_correction = false`` sets every factor to 1 (the
paper's eq. (2) instead of (7)).

``stiffness``: the rod's stiffnesses given directly (``EA``, ``GA1``, ``GA2`` in N;
``EI1``, ``EI2``, ``GJ`` in N m^2) with the inertia per length (``rhoA`` in kg/m and
``rhoI1``, ``rhoI2``, ``rhoI3`` in kg m), for benchmarks that prescribe them.

Taper: every dimension of a shape may be given at the far end too (``width_end``, ...):
it then varies linearly along the rod, evaluated at each segment's midpoint.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from functools import lru_cache
from typing import Any

import numpy as np

from runtime.errors import ParameterError
from runtime.problem import coerce as C

#: the constants a section provides (m^2, m^4, -)
CONSTANTS = ("A", "I1", "I2", "I3", "J_T", "kappa_1", "kappa_2", "kappa_3")
#: the stiffness values of a ``stiffness`` section
STIFFNESSES = ("EA", "GA1", "GA2", "EI1", "EI2", "GJ")
INERTIAS = ("rhoA", "rhoI1", "rhoI2", "rhoI3")


def _constitutive():
    from generated import constitutive

    return constitutive


@dataclass(frozen=True)
class Shape:
    """A section shape with per-end dimensions (taper) and the shear-correction switch."""

    kind: str = "rectangle"
    dims: tuple[tuple[str, float], ...] = ()        # (name, value at s = 0)
    dims_end: tuple[tuple[str, float], ...] = ()    # (name, value at s = L), if tapered
    shear_correction: bool = True

    DIMENSIONS = {"rectangle": ("width", "height"), "ellipse": ("a", "b"),
                  "circle": ("radius",), "tube": ("outer_radius", "inner_radius")}

    def __post_init__(self) -> None:
        names = self.DIMENSIONS[self.kind]
        got = dict(self.dims)
        for n in names:
            if n not in got:
                raise ParameterError(f"section.{n}", None, f"a length in m (> 0) for a "
                                     f"{self.kind}")
        for d, suffix in ((got, ""), (dict(self.dims_end), "_end")):
            for n, v in d.items():
                if self.kind == "tube" and n == "inner_radius":
                    C.number(f"section.{n}{suffix}", v, low=0.0, high=LENGTH_MAX)
                else:
                    C.number(f"section.{n}{suffix}", v, low=LENGTH_MIN, high=LENGTH_MAX,
                             allowed=LENGTH_RANGE)
        if self.kind == "tube":
            for d, suffix in ((got, ""), ({**got, **dict(self.dims_end)}, "_end")):
                if d["inner_radius"] >= d["outer_radius"]:
                    raise ParameterError(f"section.inner_radius{suffix}", d["inner_radius"],
                                         f"< outer_radius = {d['outer_radius']:g} m")

    @property
    def tapered(self) -> bool:
        return bool(self.dims_end)

    def dimensions_at(self, x: np.ndarray) -> dict[str, np.ndarray]:
        """Dimensions at the fractions ``x`` of the length (linear between the ends)."""
        a, b = dict(self.dims), {**dict(self.dims), **dict(self.dims_end)}
        return {n: a[n] + (b[n] - a[n]) * np.asarray(x, dtype=float) for n in a}

    def constants(self, nu: float, x: np.ndarray) -> dict[str, np.ndarray]:
        """Section constants (arrays over ``x``) from the generated formulas."""
        dims = self.dimensions_at(x)
        # once per distinct dimension set: a uniform rod evaluates the formulas once (the
        # rectangle's torsion series costs 0.5 ms, 0.5 s per run at N = 1000 before), and
        # the problems of a study (one per point) share them
        rows = [_formulas(self.kind, tuple(dims), tuple(float(v[i]) for v in dims.values()),
                          float(nu)) for i in range(np.size(x))]
        out = {k: np.array([float(r[k]) for r in rows]) for k in CONSTANTS}
        if not self.shear_correction:
            out.update(kappa_1=np.ones_like(out["A"]), kappa_2=np.ones_like(out["A"]),
                       kappa_3=np.ones_like(out["A"]))
        return out

    def to_mapping(self) -> dict[str, Any]:
        out: dict[str, Any] = {"kind": self.kind, **dict(self.dims)}
        out.update({f"{k}_end": v for k, v in self.dims_end})
        out["shear_correction"] = self.shear_correction
        return out


#: lengths of a rod and its section (m): far beyond any rod, and keeping their fourth
#: powers (second moments, L^4 of the bending frequency) normal floating-point numbers
LENGTH_MIN, LENGTH_MAX = 1e-30, 1e30
LENGTH_RANGE = (f"a length {LENGTH_MIN:g} ... {LENGTH_MAX:g} m (beyond any rod; its fourth "
                "power must stay a normal floating-point number)")


@lru_cache(maxsize=4096)
def _formulas(kind: str, names: tuple[str, ...], values: tuple[float, ...],
              nu: float) -> dict:
    """The generated section formulas of one shape (cached: pure functions of their
    arguments)."""
    c = _constitutive()
    d = dict(zip(names, values, strict=True))
    fn = {"rectangle": lambda: c.rectangle_section(d["width"], d["height"], nu),
          "ellipse": lambda: c.ellipse_section(d["a"], d["b"], nu),
          "circle": lambda: c.circle_section(d["radius"], nu),
          "tube": lambda: _tube(c, d, nu)}[kind]
    return fn()


def _tube(c, d: dict, nu: float) -> dict:
    if not hasattr(c, "tube_section"):   # pragma: no cover - before the tube is generated
        raise ParameterError("section.kind", "tube", "a generated tube_section (run "
                             "`kvrod generate`)")
    return c.tube_section(d["outer_radius"], d["inner_radius"], nu)


@dataclass(frozen=True)
class GivenStiffness:
    """Stiffnesses and inertias given directly (constant along the rod)."""

    EA: float = 1.0
    GA1: float = 1.0
    GA2: float = 1.0
    EI1: float = 1.0
    EI2: float = 1.0
    GJ: float = 1.0
    rhoA: float = 1.0
    rhoI1: float = 1.0
    rhoI2: float = 1.0
    rhoI3: float = 1.0
    kind: str = field(default="stiffness", init=False)

    def __post_init__(self) -> None:
        for f in fields(self):
            if f.name != "kind":
                C.positive(f"section.{f.name}", getattr(self, f.name))

    tapered = False

    def to_mapping(self) -> dict[str, Any]:
        return {"kind": "stiffness", **{f.name: getattr(self, f.name) for f in fields(self)
                                        if f.name != "kind"}}


Section = Shape | GivenStiffness
KINDS = ("rectangle", "ellipse", "circle", "tube", "stiffness")


def section_from_mapping(m: Mapping[str, Any] | None) -> Section:
    """A section from ``[section]`` (see the module docstring)."""
    m = dict(C.table("section", m if m is not None else {}))
    kind = C.choice("section.kind", m.pop("kind", "rectangle"), KINDS)
    if kind == "stiffness":
        C.no_unknown_keys("section", m, STIFFNESSES + INERTIAS)
        missing = [k for k in STIFFNESSES + INERTIAS if k not in m]
        if missing:
            raise ParameterError(f"section.{missing[0]}", None, "a positive value (stiffness "
                                 "sections give EA, GA1, GA2, EI1, EI2, GJ, rhoA, rhoI1..3)")
        return GivenStiffness(**{k: C.positive(f"section.{k}", v) for k, v in m.items()})
    names = Shape.DIMENSIONS[kind]
    allowed = (*names, *(f"{n}_end" for n in names), "shear_correction")
    C.no_unknown_keys("section", m, allowed)
    dims = tuple((n, C.number(f"section.{n}", m[n])) for n in names if n in m)
    ends = tuple((n, C.number(f"section.{n}_end", m[f"{n}_end"])) for n in names
                 if f"{n}_end" in m)
    sc = C.boolean("section.shear_correction", m.get("shear_correction", True))
    return Shape(kind=kind, dims=dims, dims_end=ends, shear_correction=sc)
