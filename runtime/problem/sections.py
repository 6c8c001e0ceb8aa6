"""Cross sections: shapes whose constants come from the generated formulas, stiffness
values given directly, or composite sections of named materials.

Shapes (TOML ``[section] kind = ...``; lengths in m): ``rectangle`` (``width`` along d1,
``height`` along d2), ``ellipse`` (half axis ``a`` along d2, ``b`` along d1), ``circle``
(``radius``), ``tube`` (``outer_radius``, ``inner_radius``). Their area, moments and torsion
constant come from ``generated/constitutive.py`` (derived in ``derive/steps/sections.py``).
Their transverse shear factors (eq. (7)), ``shear_correction``:

- ``true`` (default): Cowper's (1966), cited in the derivation; the paper's reference, so
  the reproduction of the paper is unchanged;
- ``"energy"``: the energy-consistent factors of Saint-Venant flexure (Renton; Pilkey;
  what BECAS and VABS give, and what a composite section uses), computed by the
  finite-element section analysis (``runtime/section``) of the shape with the material's
  Poisson ratio; they depend only on the shape's aspect ratio and nu, and are cached per
  (shape, aspect, nu): the first costs 0.2 ... 2 s. Equal to Cowper's at nu = 0 and below
  them for nu > 0 (circle at nu = 0.3: 0.851 against 0.886; a strip 20 times wider than
  deep, sheared across its depth: 0.049 against 0.850);
- ``false``: every factor 1 (the paper's eq. (2) instead of (7)).

The torsion factor kappa_3 = J_T / I3 is exact either way.

``stiffness``: the rod's stiffnesses given directly (``EA``, ``GA1``, ``GA2`` in N;
``EI1``, ``EI2``, ``GJ`` in N m^2), or its 6x6 ``stiffness_matrix`` (and optionally
``viscosity_matrix``) about the centreline, with the inertia per length (``rhoA`` in kg/m
and ``rhoI1``, ``rhoI2``, ``rhoI3`` in kg m; optionally ``rhoI12`` and ``mass_centre``),
for benchmarks that prescribe them and sections known from elsewhere (BECAS, VABS, a
test rig).

``composite``: ``[[section.regions]]`` (each a ``material`` named in ``[materials.NAME]``
and a ``shape``: circle, rectangle, ellipse, tube, polygon with holes; see
:mod:`runtime.section`). Its 6x6 stiffness and viscosity come from the finite-element
section analysis (``kvrod section``) and the rod simulates them with its coupled kernels
(:mod:`runtime.problem.coupled`; docs/design.md, section 10).

``damping`` (every kind): which rod viscosity the section gives, ``"consistent"`` (the
dissipation on the section's elastic deformation, eta_E of eq. (5)) or ``"naive"`` (the
traction route, eta~_E). The key was ``material.damping`` before composite sections came;
that key is still read (:mod:`runtime.problem.schema`).

Taper: every dimension of a shape may be given at the far end too (``width_end``, ...):
it then varies linearly along the rod, evaluated at each segment's midpoint.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from functools import lru_cache
from typing import Any

import numpy as np

from runtime.errors import ParameterError
from runtime.problem import coerce as C
from runtime.sorted_sets import sorted_unique

#: the constants a section provides (m^2, m^4, -)
CONSTANTS = ("A", "I1", "I2", "I3", "J_T", "kappa_1", "kappa_2", "kappa_3")
#: the stiffness values of a ``stiffness`` section
STIFFNESSES = ("EA", "GA1", "GA2", "EI1", "EI2", "GJ")
INERTIAS = ("rhoA", "rhoI1", "rhoI2", "rhoI3")
#: the coupled section's keys of a ``stiffness`` section (issue 26)
MATRIX_KEYS = ("stiffness_matrix", "viscosity_matrix", "rhoI12", "mass_centre")


def _constitutive():
    from generated import constitutive

    return constitutive


@dataclass(frozen=True)
class Shape:
    """A section shape with per-end dimensions (taper) and the shear-correction switch."""

    kind: str = "rectangle"
    dims: tuple[tuple[str, float], ...] = ()        # (name, value at s = 0)
    dims_end: tuple[tuple[str, float], ...] = ()    # (name, value at s = L), if tapered
    shear_correction: bool | str = True             # True (Cowper), False, "energy"

    DIMENSIONS = {"rectangle": ("width", "height"), "ellipse": ("a", "b"),
                  "circle": ("radius",), "tube": ("outer_radius", "inner_radius")}

    def __post_init__(self) -> None:
        if not (isinstance(self.shear_correction, bool) or self.shear_correction == "energy"):
            raise ParameterError("section.shear_correction", self.shear_correction,
                                 SHEAR_CORRECTION_ALLOWED)
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
        if self.shear_correction is False:
            out.update(kappa_1=np.ones_like(out["A"]), kappa_2=np.ones_like(out["A"]),
                       kappa_3=np.ones_like(out["A"]))
        elif self.shear_correction == "energy":
            out["kappa_1"], out["kappa_2"] = energy_shear_factors(self.kind, dims, nu)
        return out

    def to_mapping(self) -> dict[str, Any]:
        out: dict[str, Any] = {"kind": self.kind, **dict(self.dims)}
        out.update({f"{k}_end": v for k, v in self.dims_end})
        out["shear_correction"] = self.shear_correction
        return out


SHEAR_CORRECTION_ALLOWED = ('true (Cowper\'s factors), "energy" (the energy-consistent '
                            'factors of the section analysis) or false (no correction)')
#: mesh tolerance of the section analyses that give the energy shear factors (their
#: factors then agree with finer meshes to ~1e-6)
ENERGY_TOL = 1e-4
#: a tapered shape whose aspect ratio takes more distinct values than this along the rod
#: gets its energy factors by interpolation between ENERGY_NODES analyses
ENERGY_DIRECT = 5
ENERGY_NODES = 9


def _aspect(kind: str, dims: dict[str, np.ndarray]) -> np.ndarray | None:
    """The one number the energy shear factors of a shape depend on besides nu (they are
    scale-free): width/height, b/a, inner/outer radius; None for a circle."""
    if kind == "rectangle":
        return np.asarray(dims["width"] / dims["height"], dtype=float)
    if kind == "ellipse":
        return np.asarray(dims["b"] / dims["a"], dtype=float)
    if kind == "tube":
        return np.asarray(dims["inner_radius"] / dims["outer_radius"], dtype=float)
    return None


@lru_cache(maxsize=256)
def _energy_factors_at(kind: str, aspect: float, nu: float) -> tuple[float, float]:
    """(kappa_1, kappa_2) of the shape with this aspect ratio: the finite-element section
    analysis's shear stiffnesses K11, K22 over G A (the energy-consistent factors)."""
    from runtime.section import Circle, Ellipse, Rectangle, Region, Tube, analyse_section
    from runtime.section import isotropic as iso

    if kind == "circle" or (kind == "tube" and aspect == 0.0):
        shape: Any = Circle(1.0)
    elif kind == "rectangle":
        shape = Rectangle(aspect, 1.0)
    elif kind == "ellipse":
        shape = Ellipse(1.0, aspect)
    else:
        shape = Tube(aspect, 1.0)
    res = analyse_section([Region("m", shape)], {"m": iso("m", 1.0, nu, 1.0)}, tol=ENERGY_TOL)
    if not res.converged:
        raise ParameterError("section.shear_correction", "energy", "true or false for this "
                             f"shape: its section analysis did not converge to {ENERGY_TOL:g} "
                             f"({'; '.join(res.warnings)})")
    GA = res.area / (2.0 * (1.0 + nu))
    k1, k2 = float(res.stiffness[0, 0] / GA), float(res.stiffness[1, 1] / GA)
    if kind in ("circle", "tube"):      # equal by symmetry; the mesh is not quite symmetric
        k1 = k2 = 0.5 * (k1 + k2)
    return k1, k2


def energy_shear_factors(kind: str, dims: dict[str, np.ndarray], nu: float
                         ) -> tuple[np.ndarray, np.ndarray]:
    """Energy-consistent shear factors (kappa_1, kappa_2) of a shape at every point of
    ``dims`` (arrays of its dimensions in m), from the section analysis (see the module
    docstring). A taper whose aspect ratio takes more than ENERGY_DIRECT values is
    interpolated between ENERGY_NODES analyses at Chebyshev points of the aspect ratio's
    range (in its logarithm for a rectangle or ellipse; log kappa is interpolated: a wide
    section's factor falls like a power of the ratio): the factors are smooth in it, and
    an analysis per segment would cost seconds each. Measured against direct analyses:
    1e-5 over ratios 1 ... 3, 1e-4 over 1 ... 20."""
    if not nu < 0.5:
        raise ParameterError("section.shear_correction", "energy", "true or false for an "
                             f"incompressible material (poisson_ratio = {nu:g}): the "
                             "section analysis that gives the energy factors takes nu < 1/2")
    n = np.size(next(iter(dims.values())))
    aspect = _aspect(kind, dims)
    if aspect is None:
        k1, k2 = _energy_factors_at(kind, 0.0, float(nu))
        return np.full(n, k1), np.full(n, k2)
    aspect = np.broadcast_to(aspect, (n,))
    keys = np.array([float(f"{a:.12g}") for a in aspect])
    distinct = sorted_unique(keys)
    if distinct.size <= ENERGY_DIRECT:
        rows = {a: _energy_factors_at(kind, float(a), float(nu)) for a in distinct}
        return (np.array([rows[a][0] for a in keys]), np.array([rows[a][1] for a in keys]))
    log = kind in ("rectangle", "ellipse")
    u = np.log(keys) if log else keys
    lo, hi = float(u.min()), float(u.max())
    t = np.cos(np.pi * (np.arange(ENERGY_NODES) + 0.5) / ENERGY_NODES)   # Chebyshev points
    nodes = 0.5 * (lo + hi) + 0.5 * (hi - lo) * t
    vals = np.array([_energy_factors_at(kind, float(f"{(np.exp(v) if log else v):.12g}"),
                                        float(nu)) for v in nodes])
    out = []
    for j in range(2):           # log kappa: a wide section's factor falls like a power
        cheb = np.polynomial.Chebyshev.fit(nodes, np.log(vals[:, j]), ENERGY_NODES - 1,
                                           domain=[lo, hi])
        out.append(np.exp(cheb(u)))
    return out[0], out[1]


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


#: units of the 6x6 blocks (strain order Gamma1, Gamma2, Gamma3, K1, K2, K3)
MATRIX_UNITS = "N (Gamma, Gamma), N m (Gamma, K), N m^2 (K, K)"


def _matrix6(name: str, value: Any) -> np.ndarray:
    """A 6x6 matrix of finite numbers (nested lists), or a ParameterError naming it."""
    try:
        M = np.array(value, dtype=float)
    except (TypeError, ValueError):
        M = np.zeros(0)
    if M.shape != (6, 6) or not np.all(np.isfinite(M)):
        raise ParameterError(name, value, f"a 6x6 matrix of finite numbers ({MATRIX_UNITS}; "
                             "strain order Gamma1, Gamma2, Gamma3, K1, K2, K3 about the "
                             "centreline, as `kvrod section` reports)")
    return M


def check_section_matrix(name: str, M: np.ndarray, definite: bool, units: str,
                         symmetric_tol: float = 1e-9) -> np.ndarray:
    """M symmetric (to ``symmetric_tol`` of the geometric mean of the diagonals) and
    positive definite (``definite``) or semi-definite; returns its symmetric part.
    Semi-definite allows -1e-12 of the largest eigenvalue (round-off)."""
    d = np.sqrt(np.abs(np.outer(np.diag(M), np.diag(M))))
    with np.errstate(invalid="ignore", divide="ignore"):
        asym = np.where(d > 0, np.abs(M - M.T) / np.where(d > 0, d, 1.0), np.abs(M - M.T))
    if np.max(asym) > symmetric_tol:
        i, j = np.unravel_index(int(np.argmax(asym)), M.shape)
        raise ParameterError(name, M.tolist(), f"a symmetric matrix ({units}): entries "
                             f"[{i}][{j}] = {M[i, j]:.6g} and [{j}][{i}] = {M[j, i]:.6g} differ")
    S = 0.5 * (M + M.T)
    ev = np.linalg.eigvalsh(S)
    ok = ev.min() > 0 if definite else ev.min() >= -1e-12 * max(ev.max(), 0.0)
    if not ok:
        raise ParameterError(name, M.tolist(), f"a symmetric positive {'' if definite else 'semi-'}"
                             f"definite matrix ({units}); its smallest eigenvalue is "
                             f"{ev.min():.6g}")
    return S


@dataclass(frozen=True)
class GivenStiffness:
    """Stiffnesses and inertias given directly (constant along the rod).

    Either the six diagonal stiffnesses (EA ... GJ) or ``stiffness_matrix``, the section's
    symmetric positive definite 6x6 stiffness about the centreline (strain order Gamma1,
    Gamma2, Gamma3, K1, K2, K3, as ``kvrod section`` reports), with optionally
    ``viscosity_matrix`` (symmetric positive semi-definite, N s ...; else the material's
    retardation times make it: :func:`runtime.problem.coupled.given_matrices`); ``rhoA``,
    ``rhoI1..3`` as before (the rotary inertia about the mass centre), ``rhoI12`` (kg m, the
    product <rho x1 x2>) and ``mass_centre`` (m, in the section's (x1, x2) along (d1, d2))
    optional. With a matrix the diagonal fields hold its diagonal.
    """

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
    stiffness_matrix: tuple[tuple[float, ...], ...] | None = None
    viscosity_matrix: tuple[tuple[float, ...], ...] | None = None
    rhoI12: float = 0.0
    mass_centre: tuple[float, float] = (0.0, 0.0)
    kind: str = field(default="stiffness", init=False)

    def __post_init__(self) -> None:
        for f in fields(self):
            if f.name in STIFFNESSES + INERTIAS:
                C.positive(f"section.{f.name}", getattr(self, f.name))
        if self.stiffness_matrix is not None:
            K = check_section_matrix("section.stiffness_matrix",
                                     _matrix6("section.stiffness_matrix",
                                              self.stiffness_matrix), True, MATRIX_UNITS)
            object.__setattr__(self, "stiffness_matrix", _tuple6(K))
            for n, v in zip(STIFFNESSES, np.diag(K)[[2, 0, 1, 3, 4, 5]], strict=True):
                object.__setattr__(self, n, float(v))
        if self.viscosity_matrix is not None:
            if self.stiffness_matrix is None:
                raise ParameterError("section.viscosity_matrix", "given", "with "
                                     "section.stiffness_matrix (the diagonal stiffnesses "
                                     "take their viscosity from the material)")
            V = check_section_matrix("section.viscosity_matrix",
                                     _matrix6("section.viscosity_matrix",
                                              self.viscosity_matrix), False,
                                     "N s (Gamma, Gamma), N m s (Gamma, K), N m^2 s (K, K)")
            object.__setattr__(self, "viscosity_matrix", _tuple6(V))
        C.number("section.rhoI12", self.rhoI12)
        if not self.rhoI12**2 < self.rhoI1 * self.rhoI2:
            raise ParameterError("section.rhoI12", self.rhoI12, f"|rhoI12| < sqrt(rhoI1 "
                                 f"rhoI2) = {math.sqrt(self.rhoI1 * self.rhoI2):.6g} kg m (a "
                                 "positive definite rotary inertia)")
        e = self.mass_centre
        if not (isinstance(e, (tuple, list)) and len(e) == 2):
            raise ParameterError("section.mass_centre", e, "2 numbers (x1, x2) in m")
        object.__setattr__(self, "mass_centre", (C.number("section.mass_centre", e[0]),
                                                 C.number("section.mass_centre", e[1])))

    tapered = False

    @property
    def coupled(self) -> bool:
        """Couplings the diagonal kernels do not have: a stiffness or viscosity matrix
        with off-diagonal entries, a product of inertia, a mass centre off the
        centreline."""
        off = lambda M: M is not None and bool(np.any(  # noqa: E731
            np.asarray(M) - np.diag(np.diag(np.asarray(M)))))
        return (off(self.stiffness_matrix) or off(self.viscosity_matrix)
                or self.rhoI12 != 0.0 or self.mass_centre != (0.0, 0.0))

    def matrix(self) -> np.ndarray:
        """The 6x6 stiffness (the diagonal one from EA ... GJ without a matrix)."""
        if self.stiffness_matrix is not None:
            return np.array(self.stiffness_matrix)
        return np.diag([self.GA1, self.GA2, self.EA, self.EI1, self.EI2, self.GJ])

    def to_mapping(self) -> dict[str, Any]:
        out: dict[str, Any] = {"kind": "stiffness"}
        if self.stiffness_matrix is None:
            out.update({n: getattr(self, n) for n in STIFFNESSES})
        else:
            out["stiffness_matrix"] = [list(r) for r in self.stiffness_matrix]
            if self.viscosity_matrix is not None:
                out["viscosity_matrix"] = [list(r) for r in self.viscosity_matrix]
        out.update({n: getattr(self, n) for n in INERTIAS})
        if self.rhoI12 != 0.0:
            out["rhoI12"] = self.rhoI12
        if self.mass_centre != (0.0, 0.0):
            out["mass_centre"] = list(self.mass_centre)
        return out


def _tuple6(M: np.ndarray) -> tuple[tuple[float, ...], ...]:
    return tuple(tuple(float(v) for v in r) for r in M)


#: the rod viscosity a section gives: the dissipation route (eta_E) or the traction route
DAMPING_ROUTES = ("consistent", "naive")
#: a composite section's rod matrices come from its section analysis, not a material
COMPOSITE_REFUSAL = (
    "a shape or stiffness section for a material's rod matrices: a composite section's "
    "come from its finite-element analysis (runtime.problem.coupled.composite_matrices)")


@dataclass(frozen=True, eq=False)
class Composite:
    """A composite section: ``regions`` (:class:`runtime.section.regions.Region`: a material name
    and a shape each) of the named ``materials`` ({name: SectionMaterial} as pairs), and
    the rod viscosity route ``damping``. Checked on construction: every region's material
    is named, no two regions overlap, together they are one connected section.

    Its properties come from the finite-element section analysis
    (:func:`runtime.problem.section_analysis.analyse_problem_section`, ``kvrod section``),
    about the elastic centroid, the rod's centreline (:mod:`runtime.problem.coupled`).
    """

    regions: tuple[Any, ...]
    materials: tuple[tuple[str, Any], ...]
    damping: str = "consistent"
    kind: str = field(default="composite", init=False)

    tapered = False

    def __post_init__(self) -> None:
        from runtime.section import check_regions

        C.choice("section.damping", self.damping, DAMPING_ROUTES)
        check_regions(self.regions, self.material_map())

    def material_map(self) -> dict[str, Any]:
        return dict(self.materials)

    def used_materials(self) -> dict[str, Any]:
        """The materials the regions use, in the order of first use."""
        mats = self.material_map()
        return {r.material: mats[r.material] for r in self.regions}

    def to_mapping(self) -> dict[str, Any]:
        return {"kind": "composite", "damping": self.damping,
                "regions": [r.to_mapping() for r in self.regions]}

    def materials_mapping(self) -> dict[str, Any]:
        """The ``[materials]`` table: {name: table}."""
        return {name: m.to_mapping() for name, m in self.materials}

    def _key(self) -> str:
        import json

        return json.dumps([self.to_mapping(), self.materials_mapping()], sort_keys=True)

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Composite) and self._key() == other._key()

    def __hash__(self) -> int:
        return hash(self._key())


Section = Shape | GivenStiffness | Composite
KINDS = ("rectangle", "ellipse", "circle", "tube", "stiffness", "composite")


def section_from_mapping(m: Mapping[str, Any] | None,
                         materials: Mapping[str, Any] | None = None) -> Section:
    """A section from ``[section]`` (see the module docstring); ``materials``: the
    ``[materials]`` table, which a composite section's regions name. ``damping`` is
    checked here; for a shape or stiffness section the problem keeps it with the material
    (:mod:`runtime.problem.schema`)."""
    m = dict(C.table("section", m if m is not None else {}))
    kind = C.choice("section.kind", m.pop("kind", "rectangle"), KINDS)
    if "damping" in m:
        C.choice("section.damping", m["damping"], DAMPING_ROUTES)
    if kind == "composite":
        from runtime.section import materials_from_mapping, regions_from_mapping

        C.no_unknown_keys("section", m, ("regions", "damping"))
        if "regions" not in m:
            raise ParameterError("section.regions", None, "an array of tables "
                                 "[[section.regions]], each with a material (named in "
                                 "[materials.NAME]) and a shape")
        if materials is None:
            raise ParameterError("materials", None, "[materials.NAME] tables for the "
                                 "regions of section.kind = 'composite' (each isotropic: "
                                 "youngs_modulus, poisson_ratio, density, tau; or "
                                 "anisotropic: stiffness_matrix [Pa], viscosity_matrix "
                                 "[Pa s], density)")
        mats = materials_from_mapping(materials)
        regions = regions_from_mapping(m["regions"])
        return Composite(regions=regions, materials=tuple(mats.items()),
                         damping=m.get("damping", "consistent"))
    damping = {"damping": m.pop("damping")} if "damping" in m else {}
    if kind == "stiffness":
        C.no_unknown_keys("section", {**m, **damping}, STIFFNESSES + INERTIAS + MATRIX_KEYS
                          + ("damping",))
        matrix = "stiffness_matrix" in m
        kw: dict[str, Any] = {}
        for k in ("stiffness_matrix", "viscosity_matrix"):
            if k in m:
                kw[k] = _tuple6(_matrix6(f"section.{k}", m[k]))
        if matrix and any(k in m for k in STIFFNESSES):
            k = next(k for k in STIFFNESSES if k in m)
            raise ParameterError(f"section.{k}", m[k], "absent beside section."
                                 "stiffness_matrix (its diagonal gives the stiffnesses)")
        need = INERTIAS if matrix else STIFFNESSES + INERTIAS
        missing = [k for k in need if k not in m]
        if missing:
            raise ParameterError(f"section.{missing[0]}", None, "a positive value (stiffness "
                                 "sections give EA, GA1, GA2, EI1, EI2, GJ or "
                                 "stiffness_matrix, and rhoA, rhoI1..3)")
        kw.update({k: C.positive(f"section.{k}", m[k]) for k in STIFFNESSES + INERTIAS
                   if k in m})
        if "rhoI12" in m:
            kw["rhoI12"] = C.number("section.rhoI12", m["rhoI12"])
        if "mass_centre" in m:
            e = m["mass_centre"]
            if not (isinstance(e, (list, tuple)) and len(e) == 2):
                raise ParameterError("section.mass_centre", e, "2 numbers (x1, x2) in m")
            kw["mass_centre"] = (C.number("section.mass_centre", e[0]),
                                 C.number("section.mass_centre", e[1]))
        return GivenStiffness(**kw)
    names = Shape.DIMENSIONS[kind]
    allowed = (*names, *(f"{n}_end" for n in names), "shear_correction", "damping")
    C.no_unknown_keys("section", {**m, **damping}, allowed)
    dims = tuple((n, C.number(f"section.{n}", m[n])) for n in names if n in m)
    ends = tuple((n, C.number(f"section.{n}_end", m[f"{n}_end"])) for n in names
                 if f"{n}_end" in m)
    sc = m.get("shear_correction", True)
    if not (isinstance(sc, bool) or sc == "energy"):
        raise ParameterError("section.shear_correction", sc, SHEAR_CORRECTION_ALLOWED)
    return Shape(kind=kind, dims=dims, dims_end=ends, shear_correction=sc)
