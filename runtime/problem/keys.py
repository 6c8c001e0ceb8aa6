"""Every key of a problem file: table, meaning, unit, default and allowed range.

This catalogue is what ``kvrod problem-keys`` prints and what the documentation's problem
file reference is rendered from. It cannot drift from the parsers unnoticed:
``tests/runtime/test_problem_keys.py`` records the keys every parser accepts
(``coerce.no_unknown_keys``) over problems of every kind and requires the catalogue to
list exactly those, and feeds each key's ``invalid`` value to the parser, which must
refuse it naming the key. Time-function keys are listed once under ``<time>``: they apply
to every ``time`` of a load and to ``translation_time``/``rotation_time`` of a motion.
``ASSEMBLY_KEYS`` and ``CONTACT_KEYS`` (obstacles, the contact law) are checked the
same way (``tests/runtime/test_assembly_problem.py``, ``test_obstacles.py``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any


@dataclass(frozen=True)
class Key:
    """One key: ``table`` (dotted, ``[[loads]]`` as ``loads``), ``name``, the ``kinds``
    of its table it applies to (empty: all), its ``unit``, ``default`` (a string; "required"
    or "-" for none), ``allowed`` range or choices, ``doc``, and an ``invalid`` value the
    parser must refuse (None: no value is out of range, e.g. a free text)."""

    table: str
    name: str
    kinds: tuple[str, ...]
    unit: str
    default: str
    allowed: str
    doc: str
    invalid: Any = None

    @property
    def path(self) -> str:
        return f"{self.table}.{self.name}" if self.table else self.name


def _k(table: str, name: str, unit: str, default: str, allowed: str, doc: str,
       invalid: Any = None, kinds: tuple[str, ...] = ()) -> Key:
    return Key(table, name, kinds, unit, default, allowed, doc, invalid)


_SHAPES = {"rectangle": (("width", "along d1"), ("height", "along d2")),
           "ellipse": (("a", "half axis along d2"), ("b", "half axis along d1")),
           "circle": (("radius", "radius"),),
           "tube": (("outer_radius", "outer radius"), ("inner_radius", "inner radius (>= 0)"))}
_STIFF = {"EA": ("N", "axial stiffness"), "GA1": ("N", "shear stiffness along d1"),
          "GA2": ("N", "shear stiffness along d2"), "EI1": ("N m^2", "bending stiffness about d1"),
          "EI2": ("N m^2", "bending stiffness about d2"), "GJ": ("N m^2", "torsional stiffness"),
          "rhoA": ("kg/m", "mass per length"), "rhoI1": ("kg m", "rotary inertia about d1"),
          "rhoI2": ("kg m", "rotary inertia about d2"),
          "rhoI3": ("kg m", "polar rotary inertia")}
_VEC = "3 numbers"
_UNIT_VEC = "3 numbers, not all 0"

KEYS: tuple[Key, ...] = (
    # -- top level ----------------------------------------------------------------------
    _k("", "name", "-", "file name", "text", "the problem's name (results folder default)"),
    _k("", "description", "-", '""', "text", "one line shown in reports"),
    # -- [rod] --------------------------------------------------------------------------
    _k("rod", "length", "m", "required (straight)", "1e-30 ... 1e30; for other "
       "geometries their length, or left out", "arc length L of the rod", invalid=-1.0),
    _k("rod", "elements", "-", "50", "1 ... 200000", "number of elements N", invalid=0),
    _k("rod", "geometry", "-", "straight", "a table", "the reference centreline and frames "
       "(below)"),
    # -- [rod.geometry] -----------------------------------------------------------------
    _k("rod.geometry", "kind", "-", '"straight"', "straight, arc, helix, points",
       "shape of the stress-free centreline", invalid="spiral"),
    _k("rod.geometry", "direction", "-", "[0, 0, 1] (arc: [1, 0, 0])", _UNIT_VEC,
       "initial tangent", invalid=[0, 0, 0], kinds=("straight", "arc")),
    _k("rod.geometry", "normal", "-", "[1, 0, 0] (e2 along x)",
       _UNIT_VEC + ", not along the tangent",
       "first director d1 (the width direction of a rectangle)", invalid=[0, 0, 0],
       kinds=("straight", "points")),
    _k("rod.geometry", "twist", "rad/m", "0", "a number", "uniform twist of the directors "
       "about the tangent", invalid="fast"),
    _k("rod.geometry", "origin", "m", "[0, 0, 0]", _VEC + ", |origin| <= 1e-8 (L/N)/eps",
       "position of the start s = 0",
       invalid=[0, 0]),
    _k("rod.geometry", "radius", "m", "1.0", "> 0", "radius of the arc", invalid=0.0,
       kinds=("arc",)),
    _k("rod.geometry", "angle", "deg", "90", "0 < angle <= 360", "angle the arc subtends",
       invalid=400.0, kinds=("arc",)),
    _k("rod.geometry", "toward", "-", "[0, 1, 0]", _UNIT_VEC + ", not along direction",
       "the arc curves toward this direction", invalid=[0, 0, 0], kinds=("arc",)),
    _k("rod.geometry", "first_director", "-", '"normal"', "normal, binormal",
       "d1 toward the centre of curvature or out of the plane", invalid="up",
       kinds=("arc",)),
    _k("rod.geometry", "coil_radius", "m", "0.01", "> 0", "radius of the helix",
       invalid=0.0, kinds=("helix",)),
    _k("rod.geometry", "pitch", "m", "0.005", ">= 0", "rise per turn", invalid=-1.0,
       kinds=("helix",)),
    _k("rod.geometry", "turns", "-", "5", "> 0", "number of turns", invalid=0.0,
       kinds=("helix",)),
    _k("rod.geometry", "handedness", "-", '"right"', "right, left", "sense of the helix",
       invalid="up", kinds=("helix",)),
    _k("rod.geometry", "axis", "-", "[0, 0, 1]", _UNIT_VEC, "axis of the helix",
       invalid=[0, 0, 0], kinds=("helix",)),
    _k("rod.geometry", "radial", "-", "[1, 0, 0]", _UNIT_VEC + ", not along the axis",
       "direction from the axis to the start", invalid=[0, 0, 0], kinds=("helix",)),
    _k("rod.geometry", "points", "m", "required (or file)", "at least 2 [x, y, z] rows",
       "polyline through which a smooth curve is drawn", invalid=[[0, 0, 0]],
       kinds=("points",)),
    _k("rod.geometry", "file", "-", "-", "a CSV file with columns x, y, z (relative to "
       "the problem file)", "the points from a file", invalid="missing.csv",
       kinds=("points",)),
    # -- [section] ----------------------------------------------------------------------
    _k("section", "kind", "-", '"rectangle"', "rectangle, ellipse, circle, tube, stiffness, "
       "composite", "shape of the cross-section, stiffnesses given directly, or a composite "
       "section of named materials ([[section.regions]], [materials.NAME]; its 6x6 "
       "matrices from the finite-element section analysis, as kvrod section reports them)",
       invalid="hexagon"),
    _k("section", "file", "-", "-", "a section file (the TOML kvrod section reads: "
       "[section] with [materials.NAME], or a shape with [material]), relative to the "
       "problem file", "the section (and its materials) from a section file; beside it "
       "[section] gives only damping and shear_correction, and the problem no [materials] "
       "(nor [material] where the file has one); a problem written back holds the section "
       "itself", invalid="missing_section.toml"),
    _k("section", "damping", "-", '"consistent"', "consistent, naive; with "
       "material.damping (its earlier place, still read) the same route",
       "the rod viscosity: from the dissipation on the section's elastic deformation "
       "(eta_E, eq. (5); for a composite the consistent 6x6 V) or the naive traction route "
       "(eta~_E; the naive V~); one key for every section kind", invalid="viscous"),
    *(_k("section", n, "m", "required", "1e-30 ... 1e30" if n != "inner_radius" else
         ">= 0, < outer_radius", f"{kind}: {what}", invalid=-0.01, kinds=(kind,))
      for kind, dims in _SHAPES.items() for n, what in dims),
    *(_k("section", f"{n}_end", "m", "= the start value", "as the start value",
         f"{kind}: {what} at s = L (linear taper)", invalid=-0.01, kinds=(kind,))
      for kind, dims in _SHAPES.items() for n, what in dims),
    _k("section", "shear_correction", "-", "true", 'true, false, "energy"', "transverse shear "
       "factors of the shape (eq. (7)): true Cowper's (the paper's reference, the default, so "
       "the reproduction of the paper is unchanged); \"energy\" the energy-consistent "
       "factors of Saint-Venant flexure (what BECAS and VABS give and composite sections "
       "use), computed by the section analysis of the shape at the material's nu (< 1/2) "
       "and cached per aspect ratio (0.2 ... 2 s the first time): lower than Cowper's for "
       "nu > 0 (circle, nu = 0.3: 0.851 against 0.886; far lower for a wide section "
       "sheared across its depth: a 20:1 strip 0.049); false all factors 1 (eq. (2))",
       invalid="yes", kinds=tuple(_SHAPES)),
    *(_k("section", n, u, "required" if n.startswith("rho") else "required (or "
         "stiffness_matrix)", "> 0", what, invalid=0.0, kinds=("stiffness",))
      for n, (u, what) in _STIFF.items()),
    _k("section", "stiffness_matrix", "N, N m, N m^2", "- (instead of EA ... GJ)",
       "6x6, symmetric positive definite", "the section's 6x6 stiffness about the "
       "centreline, strain order Gamma1, Gamma2, Gamma3, K1, K2, K3 (as kvrod section "
       "reports it; blocks in N, N m, N m^2); off-diagonal entries couple shear, extension, "
       "bending and torsion (the coupled kernels)", invalid=[[1.0]], kinds=("stiffness",)),
    _k("section", "viscosity_matrix", "N s, N m s, N m^2 s", "from the material",
       "6x6, symmetric positive semi-definite; with stiffness_matrix; the material's "
       "retardation times then 0", "the section's 6x6 "
       "viscosity, order as stiffness_matrix; without it V_ij = sqrt(t_i t_j) K_ij with "
       "t = (tau_S, tau_S, tau_E, tau_E, tau_E, tau_S) of the material", invalid=[[1.0]],
       kinds=("stiffness",)),
    _k("section", "rhoI12", "kg m", "0", "|rhoI12| < sqrt(rhoI1 rhoI2)", "product of "
       "inertia <rho x1 x2> per length about the mass centre", invalid="x",
       kinds=("stiffness",)),
    _k("section", "mass_centre", "m", "[0, 0]", "2 numbers (x1, x2)", "the mass centre in "
       "the section (along d1, d2) relative to the centreline (the stiffness's reference "
       "point); rhoI1 ... rhoI12 are about it", invalid=[1.0], kinds=("stiffness",)),
    _k("section", "regions", "-", "required", "at least one table [[section.regions]]; "
       "no two overlap, together one connected section", "the regions of a composite "
       "section (below)", invalid=[], kinds=("composite",)),
    # -- [[section.regions]] ------------------------------------------------------------
    _k("section.regions", "material", "-", "required", "the NAME of a [materials.NAME] "
       "table", "the region's material", invalid="unobtainium"),
    _k("section.regions", "shape", "-", "required", "a table { kind = ..., ... } (below)",
       "the region's shape in the section's (x1, x2) along (d1, d2)",
       invalid={"kind": "hexagon"}),
    _k("section.regions", "name", "-", "section.regions[i]", "a non-empty text", "how "
       "errors, reports and pictures call the region", invalid=""),
    # -- shape = {...} of a region ------------------------------------------------------
    _k("section.regions.shape", "kind", "-", "required", "circle, rectangle, ellipse, "
       "tube, polygon", "the shape", invalid="hexagon"),
    _k("section.regions.shape", "centre", "m", "[0, 0]", "[x1, x2], finite", "centre of "
       "the shape", invalid=[0.0], kinds=("circle", "rectangle", "ellipse", "tube")),
    _k("section.regions.shape", "radius", "m", "required", "> 0", "circle: radius",
       invalid=-1.0, kinds=("circle",)),
    _k("section.regions.shape", "width", "m", "required", "> 0", "rectangle: width along "
       "d1 (before the angle)", invalid=-1.0, kinds=("rectangle",)),
    _k("section.regions.shape", "height", "m", "required", "> 0", "rectangle: height "
       "along d2 (before the angle)", invalid=0.0, kinds=("rectangle",)),
    _k("section.regions.shape", "angle", "deg", "0", "a number", "rotation "
       "counterclockwise from d1", invalid="steep", kinds=("rectangle", "ellipse")),
    _k("section.regions.shape", "a", "m", "required", "> 0", "ellipse: half axis along d2 "
       "(before the angle)", invalid=-1.0, kinds=("ellipse",)),
    _k("section.regions.shape", "b", "m", "required", "> 0", "ellipse: half axis along d1",
       invalid=0.0, kinds=("ellipse",)),
    _k("section.regions.shape", "outer_radius", "m", "required", "> 0", "tube: outer "
       "radius", invalid=-1.0, kinds=("tube",)),
    _k("section.regions.shape", "inner_radius", "m", "required", "0 < inner_radius < "
       "outer_radius", "tube: inner radius", invalid=0.0, kinds=("tube",)),
    _k("section.regions.shape", "points", "m", "required", "at least 3 points [[x1, x2], "
       "...], a simple polygon of positive area", "polygon: its outline",
       invalid=[[0.0, 0.0], [1.0, 0.0]], kinds=("polygon",)),
    _k("section.regions.shape", "holes", "m", "[]", "point lists inside the outline",
       "polygon: its holes", invalid="none", kinds=("polygon",)),
    # -- [materials.NAME] ---------------------------------------------------------------
    _k("materials.NAME", "model", "-", '"kelvin_voigt"', "kelvin_voigt (generalized "
       "Maxwell regions are not supported yet)", "constitutive model of the region's 3-D "
       "material", invalid="generalized_maxwell"),
    _k("materials.NAME", "density", "kg/m^3", "required", "> 0", "mass density",
       invalid=0.0),
    _k("materials.NAME", "youngs_modulus", "Pa", "required", "> 0", "isotropic: Young's "
       "modulus E", invalid=-1.0, kinds=("isotropic",)),
    _k("materials.NAME", "poisson_ratio", "-", "required", "-1 < nu < 1/2 (rubber: e.g. "
       "0.4999; nearly incompressible regions are integrated without locking)",
       "isotropic: Poisson's ratio", invalid=0.5, kinds=("isotropic",)),
    _k("materials.NAME", "tau", "s", "0 (elastic)", ">= 0; not with tau_S/tau_B or "
       "eta/zeta", "isotropic: tau_S = tau_B = tau", invalid=-0.01, kinds=("isotropic",)),
    _k("materials.NAME", "tau_S", "s", "0", ">= 0", "isotropic: shear retardation time "
       "(eta = G tau_S)", invalid=-0.01, kinds=("isotropic",)),
    _k("materials.NAME", "tau_B", "s", "0", ">= 0", "isotropic: bulk retardation time "
       "(zeta = K tau_B)", invalid=-0.01, kinds=("isotropic",)),
    _k("materials.NAME", "eta", "Pa s", "0", ">= 0; not with tau, tau_S, tau_B",
       "isotropic: shear viscosity", invalid=-1.0, kinds=("isotropic",)),
    _k("materials.NAME", "zeta", "Pa s", "0", ">= 0", "isotropic: bulk viscosity",
       invalid=-1.0, kinds=("isotropic",)),
    _k("materials.NAME", "stiffness_matrix", "Pa", "required (anisotropic)", "6x6, "
       "symmetric positive definite", "anisotropic: Voigt stiffness C in the material's "
       "axes, order 11, 22, 33, 23, 13, 12 (axis 3 along the rod before the orientation), "
       "engineering shear strains (C44 = G when isotropic)",
       invalid=[[1.0e9 if i == j else 0.0 for j in range(6)] for i in range(5)]
       + [[0.0] * 5 + [-1.0e9]], kinds=("anisotropic",)),
    _k("materials.NAME", "viscosity_matrix", "Pa s", "0 (elastic)", "6x6, symmetric "
       "positive semi-definite", "anisotropic: Voigt viscosity V (viscous stress V "
       "d(eps)/dt), order and axes as stiffness_matrix", invalid=[[-1.0] * 6] * 6,
       kinds=("anisotropic",)),
    _k("materials.NAME", "orientation", "deg", "{ rotation = 0, off_axis = 0 }", "a table "
       "(below)", "anisotropic: the material's axes in the section", invalid="along",
       kinds=("anisotropic",)),
    _k("materials.NAME.orientation", "off_axis", "deg", "0", "-90 ... 90", "the material's "
       "axis 3 (e.g. its fibre) tilts from the rod axis towards d1 by this angle (turned "
       "about d2)", invalid=120.0),
    _k("materials.NAME.orientation", "rotation", "deg", "0", "a number", "then the tilt "
       "turns about the rod axis towards cos(rotation) d1 + sin(rotation) d2 (a fibre wound "
       "in a wall: the angle of the wall's tangent from d1)", invalid="north"),
    # -- [material] ---------------------------------------------------------------------
    _k("material", "model", "-", '"kelvin_voigt"', "kelvin_voigt, generalized_maxwell",
       "constitutive model", invalid="elastic"),
    _k("material", "density", "kg/m^3", "1000", "> 0", "mass density rho", invalid=0.0),
    _k("material", "density_end", "kg/m^3", "= density", "> 0", "density at s = L "
       "(linear variation)", invalid=0.0),
    _k("material", "youngs_modulus", "Pa", "1e6", "> 0 (Maxwell: >= 0, the equilibrium "
       "spring E_inf; 0 needs simulation.initial = reference under loads; glassy moduli at "
       "most 1e10 times the equilibrium ones)", "Young's modulus E", invalid=-1.0),
    _k("material", "youngs_modulus_end", "Pa", "= youngs_modulus", "> 0", "E at s = L "
       "(linear variation)", invalid=0.0, kinds=("kelvin_voigt",)),
    _k("material", "poisson_ratio", "-", "0.3", "-1 < nu <= 1/2 (Maxwell: < 1/2)",
       "Poisson's ratio nu", invalid=0.7),
    _k("material", "tau", "s", "0", ">= 0, tau omega_max^2 <= 0.1/eps (omega_max: the "
       "stiffest element mode); not with tau_S/tau_B or eta/zeta",
       "retardation time tau_S = tau_B = tau (the paper's choice, tau_E = tau)",
       invalid=-0.01, kinds=("kelvin_voigt",)),
    _k("material", "tau_S", "s", "0", ">= 0, as tau", "shear retardation time (eta = G "
       "tau_S)",
       invalid=-0.01, kinds=("kelvin_voigt",)),
    _k("material", "tau_B", "s", "0", ">= 0, as tau", "bulk retardation time (zeta = K "
       "tau_B)",
       invalid=-0.01, kinds=("kelvin_voigt",)),
    _k("material", "eta", "Pa s", "0", ">= 0; not with tau, tau_S, tau_B",
       "shear viscosity (instead of tau_S)", invalid=-1.0, kinds=("kelvin_voigt",)),
    _k("material", "zeta", "Pa s", "0", ">= 0 (0 if nu = 1/2)", "bulk viscosity (instead "
       "of tau_B)", invalid=-1.0, kinds=("kelvin_voigt",)),
    _k("material", "damping", "-", '"consistent"', "consistent, naive", "the earlier place "
       "of section.damping, still read (both given must agree): extensional viscosity eta_E "
       "from the dissipation function (eq. (5)) or the naive eta~_E",
       invalid="viscous", kinds=("kelvin_voigt",)),
    _k("material", "branches", "-", "required", "1 ... 12 tables [[material.branches]]",
       "the Maxwell branches (below)", invalid=[], kinds=("generalized_maxwell",)),
    # -- [[material.branches]] ----------------------------------------------------------
    _k("material.branches", "tau", "s", "required", ">= 1e-12", "relaxation time of the "
       "branch", invalid=0.0),
    _k("material.branches", "youngs_modulus", "Pa", "-", ">= 0; with poisson_ratio, not "
       "with shear/bulk_modulus", "the branch's spring as E", invalid=-1.0),
    _k("material.branches", "poisson_ratio", "-", "-", "-1 < nu < 1/2", "the branch's "
       "spring's nu", invalid=0.5),
    _k("material.branches", "shear_modulus", "Pa", "-", ">= 0; with bulk_modulus",
       "the branch's spring as G", invalid=-1.0),
    _k("material.branches", "bulk_modulus", "Pa", "-", ">= 0; with shear_modulus",
       "the branch's spring as K", invalid=-1.0),
    # -- [[zones]] ----------------------------------------------------------------------
    _k("zones", "from", "m", "required", "0 ... L", "where the zone starts (arc length): a "
       "stretch of the rod with its own section and/or material; zones may not overlap, "
       "the problem's [section] and [material] hold elsewhere; place the ends on nodes "
       "(multiples of L/N): a segment belongs to the zone of its midpoint (a zone that holds "
       "no segment midpoint is refused)", invalid=-1.0),
    _k("zones", "to", "m", "required", "from < to <= L", "where the zone ends",
       invalid=-1.0),
    _k("zones", "section", "-", "the problem's [section]", "a [section] table (every "
       "kind; a composite names [materials.NAME]; tapers run over the zone)", "the zone's "
       "section: without a kind, its keys override the problem's [section] (the others "
       "kept, tapers not); with a kind, given whole; joints across a sharp change take the "
       "mean of their two segments (first order in h there)", invalid={"kind": "hexagon"}),
    _k("zones", "material", "-", "the problem's [material]", "a Kelvin-Voigt [material] "
       "table", "the zone's material: its keys override the problem's [material] (the "
       "others kept; naming tau, tau_S/tau_B or eta/zeta drops the problem's other damping "
       "keys); generalized Maxwell materials are the same along the rod",
       invalid={"density": -1.0}),
    # -- [start], [end] -----------------------------------------------------------------
    *(_k(end, "kind", "-", '"clamped"' if end == "start" else '"free"', "free, clamped, "
         "pinned", "what holds the end: nothing, position and frame, position",
         invalid="welded") for end in ("start", "end")),
    *(_k(end, "motion", "-", "none", "a table (held ends)", "prescribed motion of a held "
         "end (below)", invalid=3) for end in ("start", "end")),
    *(k for end in ("start", "end") for k in (
        _k(f"{end}.motion", "translation", "m", "[0, 0, 0]", _VEC + ", at most 1e-8 "
           "(L/N)/eps", "displacement of the end (spatial), times translation_time",
           invalid=[1, 2]),
        _k(f"{end}.motion", "translation_time", "-", "constant 1", "a time function "
           "(<time>), continuous", "scales translation", invalid={"kind": "step"}),
        _k(f"{end}.motion", "rotation_axis", "-", "[0, 0, 1]", _UNIT_VEC, "fixed spatial "
           "axis of the clamp's rotation", invalid=[0, 0, 0]),
        _k(f"{end}.motion", "rotation_angle", "deg", "0", "a number (clamped ends)",
           "rotation of the clamp frame, times rotation_time", invalid="quarter"),
        _k(f"{end}.motion", "rotation_time", "-", "constant 1", "a time function "
           "(<time>), continuous", "scales rotation_angle", invalid={"kind": "release"}))),
    # -- [[loads]] ----------------------------------------------------------------------
    _k("loads", "kind", "-", '"force"', "gravity, distributed, force, moment",
       "gravity (m/s^2), dead force per length (N/m), point force (N), point moment (N m)",
       invalid="torque"),
    _k("loads", "vector", "see kind", "required", _VEC + "; times the time function's peak "
       "at most a strain of 1e6 (|F| / min(EA, GA), |q| L / ..., rho A |g| L / ..., "
       "rotation |M| L / min(EI, GJ))", "the load's vector (spatial, or in the node's "
       "reference frame for a follower)", invalid=[1, 0]),
    _k("loads", "time", "-", "constant 1", "a time function (<time>)", "scales the load "
       "in time", invalid={"kind": "sometimes"}),
    _k("loads", "at", "-", '"end"', 'start, end, or a node 0 ... N', "where a point load "
       "acts", invalid="middle", kinds=("force", "moment")),
    _k("loads", "s", "m", "-", "0 ... L", "where a point load acts, as an arc length "
       "(nearest node)", invalid=-1.0, kinds=("force", "moment")),
    _k("loads", "frame", "-", '"dead"', "dead, follower", "fixed in space or turning with "
       "the node's frame", invalid="moving", kinds=("force", "moment")),
    # -- time functions -----------------------------------------------------------------
    _k("<time>", "kind", "-", '"constant"', "constant, ramp, smooth_ramp, step, release, "
       "harmonic, table", "the function's shape (a number instead of a table: constant)",
       invalid="sawtooth"),
    _k("<time>", "value", "-", "1", "a number", "the constant value", invalid="one",
       kinds=("constant",)),
    _k("<time>", "start", "s", "0", "a number", "ramp, step: 0 before start; release: 1 "
       "before start, 0 after", invalid="now",
       kinds=("ramp", "smooth_ramp", "step", "release")),
    _k("<time>", "duration", "s", "required", "> 0", "duration of the (smooth) ramp to 1",
       invalid=0.0, kinds=("ramp", "smooth_ramp")),
    _k("<time>", "amplitude", "-", "1", "a number", "offset + amplitude sin(2 pi f t + "
       "phase)", invalid="big", kinds=("harmonic",)),
    _k("<time>", "frequency", "Hz", "0", ">= 0, at most 1e6 periods in t_end",
       "frequency f of the harmonic",
       invalid=-1.0, kinds=("harmonic",)),
    _k("<time>", "phase", "rad", "0", "a number", "phase of the harmonic", invalid="late",
       kinds=("harmonic",)),
    _k("<time>", "offset", "-", "0", "a number", "offset of the harmonic", invalid="x",
       kinds=("harmonic",)),
    _k("<time>", "points", "s, -", "required (or file)", ">= 2 [t, value] pairs, t "
       "increasing", "piecewise linear, held constant outside", invalid=[[0, 1]],
       kinds=("table",)),
    _k("<time>", "file", "-", "-", "a CSV file with columns t, value", "the points from a "
       "file", invalid="missing.csv", kinds=("table",)),
    # -- [simulation] -------------------------------------------------------------------
    _k("simulation", "t_end", "s", "10", ">= sqrt(eps)/omega_max (omega_max: the stiffest "
       "element mode), at most 1e6 first-mode periods",
       "end time of the run", invalid=0.0),
    _k("simulation", "rtol", "-", "1e-6", "2.2e-14 ... < 1", "relative tolerance of the "
       "BDF integrator", invalid=1e-16),
    _k("simulation", "atol", "state units", "scaled to the rod (see kvrod simulate "
       "--help)", "1e-20 ... < 1", "absolute tolerance", invalid=0.0),
    _k("simulation", "output_step", "s", "0.005", "> 0, at most 1e7 samples",
       "sampling of the series", invalid=0.0),
    _k("simulation", "max_order", "-", "5", "1 ... 5", "highest BDF order (3-5 only on "
       "steps that damp a Maxwell rod's glassy modes)", invalid=6),
    _k("simulation", "error_control", "-", '"auto"', "auto, state, configuration",
       "what the BDF error test controls: every unknown (state), or positions, rotations "
       "and internal strains with the velocities left to the corrector (configuration); "
       "auto: configuration for a generalized Maxwell rod, state otherwise",
       invalid="velocity"),
    _k("simulation", "min_step", "s", "0", "0 ... t_end", "smallest step before the run "
       "is declared failed", invalid=-1.0),
    _k("simulation", "initial", "-", '"static"', "static, reference", "start from the "
       "static equilibrium under the loads at t = 0-, or from the reference at rest",
       invalid="rest"),
    _k("simulation", "centreline_frames", "-", "101", "0 or 2 ... 10000", "node "
       "positions kept at this many equally spaced times from 0 to t_end (the deformed "
       "centreline that kvrod plot draws and animates; 0: none)", invalid=1),
    # -- [statics], [analysis] ----------------------------------------------------------
    _k("statics", "load_steps", "-", "10", "1 ... 10000", "initial load increments of "
       "the Newton continuation", invalid=0),
    _k("statics", "report", "-", "[]", "load factors in (0, 1)", "load factors at which "
       "the end positions are recorded on the way", invalid=[1.5]),
    _k("analysis", "maxima", "-", "none", "end.x, end.y, end.z, start.x, start.y, start.z",
       "the coordinate whose maxima give log decrements and damping ratios. A maximum is "
       "where its velocity turns from + to -; the amplitudes are taken about the "
       "equilibrium the rod vibrates about (the stress-free reference when no load is left "
       "on the rod and no end has moved; else the static equilibrium under the loads that "
       "remain after the first maximum; the run's final state, with a warning, when they "
       "still change or no equilibrium exists: summary.json vibration_centre), and only "
       "maxima above it count. A warning flags successive damping ratios that scatter by "
       "more than 25 % about their linear trend (two modes beating)",
       invalid="tip"),
)


#: what an assembly file is (shown by both renderings)
ASSEMBLY_INTRO = (
    "A problem file with `[rods.NAME]` tables is an assembly of rods. Each rod's table "
    "holds what a single-rod file holds: `[rods.NAME.rod]` (its `geometry.origin` places "
    "the rod), `[rods.NAME.section]`, `[rods.NAME.material]`, `[[rods.NAME.zones]]`, "
    "`[rods.NAME.start]`, `[rods.NAME.end]` (the ends default to free: joints hold the "
    "rods). `[simulation]`, `[statics]`, `[analysis]` and `[[loads]]` stay at the top; "
    "gravity and distributed loads act on every rod unless `rods = [...]` names some; a "
    "point force or moment acts at a point, `at = \"NAME.end\"`. Points: `NAME.start`, "
    "`NAME.end`, `NAME@S` (arc length S in m from the rod's start); the rod has a node at "
    "every named point (its elements need not be equal). A weld of one rod's end to the "
    "next rod's start is the one rod made of both. Rigid bodies feel every gravity load. "
    "Examples: `examples/assembly_*.toml`.")

#: how the command line and the Python API change keys (shown by both renderings)
OVERRIDES = (
    "Any key can be changed without editing the file: on the command line with `--set "
    "PATH=VALUE` (repeatable, TOML values: `--set material.tau=0.02`, `--set "
    "loads.0.vector=[0,0,1]`), in Python with `load_problem(path, {PATH: value})` or "
    "`Problem.with_overrides({PATH: value})`. PATH is the table path and key below; an "
    "array of tables (`[[loads]]`, `[[material.branches]]`) is indexed from 0 "
    "(`loads.0.time.start`). A whole table or entry is given as an inline table (a "
    "dict in Python): `--set 'material={youngs_modulus=2e6, tau=0.01}'` replaces the "
    "material. To append an entry, give the whole entry at the index one past the "
    "last: `--set 'loads.1={kind=\"force\", vector=[0,0,1]}'` adds a second load to a "
    "problem with one (a larger index is refused, naming the allowed range). Every "
    "value is checked as in a problem file.")


_POINT = ('a point: NAME.start, NAME.end or NAME@S (S: arc length in m from the rod\'s '
          'start, 0 ... its length)')
_MATRIX6 = ("6x6, symmetric (to 1e-9 of its largest entry) positive semi-definite; "
            "translation then rotation, as a section's matrices")

#: the keys of an assembly file (``[rods.NAME]`` tables; :mod:`runtime.problem.assembly`),
#: beside those of a single rod (:data:`KEYS`), which each rod's table holds
ASSEMBLY_KEYS: tuple[Key, ...] = (
    # -- top level ----------------------------------------------------------------------
    _k("", "name", "-", "file name", "text", "the assembly's name (results folder "
       "default)"),
    _k("", "description", "-", '""', "text", "one line shown in reports"),
    _k("", "rods", "-", "required", "at least one table [rods.NAME]; NAME: letters, "
       "digits, _ and -, starting with a letter or _, not ground", "the rods, in file "
       "order (an assembly file is one with [rods]; [rod], [section], [material], "
       "[start], [end], [[zones]] beside it are refused: they go into rods.NAME)",
       invalid={}),
    _k("", "materials", "-", "-", "tables [materials.NAME] as in a single-rod file; "
       "only beside a composite section in some rod", "named materials shared by every "
       "rod's composite sections (a rod may add its own, rods.NAME.materials.X; a name "
       "in both places must hold the same material)", invalid={"a": {"density": -1.0}}),
    _k("", "joints", "-", "[]", "an array of tables [[joints]]", "the joints (below)",
       invalid={"kind": "weld"}),
    _k("", "bodies", "-", "[]", "an array of tables [[bodies]]", "the rigid bodies "
       "(below)", invalid={"mass": 1.0}),
    _k("", "loads", "-", "[]", "an array of tables [[loads]]", "as in a single-rod file, "
       "with the placement below", invalid={"kind": "gravity"}),
    _k("", "simulation", "-", "defaults", "the [simulation] table of a single rod",
       "the run's settings, for the whole assembly", invalid={"t_end": 0.0}),
    _k("", "statics", "-", "defaults", "the [statics] table of a single rod",
       "the static solve's settings, for the whole assembly", invalid={"load_steps": 0}),
    _k("", "analysis", "-", "none", "a table with maxima (below)", "what to analyse",
       invalid={"maxima": "end.x"}),
    _k("", "obstacles", "-", "[]", "an array of tables [[obstacles]] as in a single-rod "
       "file", "the obstacles every rod touches (contact: below)",
       invalid={"kind": "plane"}),
    _k("", "contact", "-", "defaults", "the [contact] table of a single rod; its radius "
       "may be a table {NAME = r} of radii per rod", "the contact law of every rod; self = "
       "true: the rods' contact with each other and themselves (refused when an "
       "assembly runs, in this version)", invalid={"self": "yes"}),
    # -- [rods.NAME] --------------------------------------------------------------------
    _k("rods.NAME", "rod", "-", "required", "the [rod] table of a single rod (length, "
       "elements, geometry)", "the rod's length, elements and reference geometry; "
       "rods.NAME.rod.geometry.origin (m) places its start", invalid={"length": -1.0}),
    _k("rods.NAME", "section", "-", "a 1 cm square", "the [section] table of a single rod",
       "the rod's cross-section", invalid={"kind": "hexagon"}),
    _k("rods.NAME", "material", "-", "the default material", "the [material] table of a "
       "single rod", "the rod's material", invalid={"youngs_modulus": -1.0}),
    _k("rods.NAME", "materials", "-", "-", "tables as [materials.NAME]", "named "
       "materials of this rod's composite sections, beside the shared ones",
       invalid={"a": {"density": -1.0}}),
    _k("rods.NAME", "zones", "-", "[]", "[[zones]] of a single rod (from, to on this rod)",
       "stretches of the rod with their own section or material",
       invalid=[{"from": 0.0, "to": 99.0, "material": {"tau": 0.0}}]),
    _k("rods.NAME", "start", "-", '"free" (not "clamped" as in a single-rod file)',
       "the [start] table of a single rod (kind free, clamped, pinned; motion)",
       "the rod's end at s = 0 (free: joints hold the rods)", invalid="glued"),
    _k("rods.NAME", "end", "-", '"free"', "the [end] table of a single rod", "the rod's "
       "end at s = L", invalid="glued"),
    # -- [[joints]] ---------------------------------------------------------------------
    _k("joints", "kind", "-", "required", "weld, ball, hinge, spring", "weld: all "
       "relative motion held; ball: the relative position held, rotation free; hinge: "
       "the position held, relative rotation only about axis; spring: the 6x6 matrices "
       "on the relative displacement and rotation", invalid="glue"),
    _k("joints", "between", "-", "required", "two points [P, Q] at the same place in the "
       "reference configuration (to 1e-9 of the longest rod), or a point and \"ground\" "
       "(a support or clip at the point's place); " + _POINT.replace("a point: ", "points: "),
       "what the joint joins; no two joints may join the same points (or the same point "
       "to ground); a spring's matrices act in P's frame (the point's, when the other is "
       "ground)", invalid=["nowhere.end", "ground"]),
    _k("joints", "axis", "-", "required (hinge)", _UNIT_VEC, "the hinge's axis, a "
       "spatial direction in the reference configuration", invalid=[0, 0, 0],
       kinds=("hinge",)),
    _k("joints", "rotational_stiffness", "N m/rad", "0", ">= 0", "a torsion spring on "
       "the free relative rotation (about the axis of a hinge)", invalid=-1.0,
       kinds=("ball", "hinge")),
    _k("joints", "rotational_viscosity", "N m s/rad", "0", ">= 0", "a rotational "
       "damper on the free relative rotation", invalid=-1.0, kinds=("ball", "hinge")),
    _k("joints", "stiffness_matrix", "N/m, N/rad, N m/rad", "required (spring)", _MATRIX6,
       "the spring's stiffness on the relative displacement (m) and rotation (rad) of "
       "Q against P in P's frame", invalid=[[1.0]], kinds=("spring",)),
    _k("joints", "viscosity_matrix", "N s/m, N s/rad, N m s/rad", "zeros", _MATRIX6,
       "the spring's viscosity on the rates of the same", invalid=[[1.0]],
       kinds=("spring",)),
    # -- [[bodies]] ---------------------------------------------------------------------
    _k("bodies", "name", "-", '"bodyK" (K: its index)', "text, distinct", "the body's "
       "name", invalid=""),
    _k("bodies", "at", "-", "required", _POINT, "the point the body is welded at",
       invalid="nowhere.end"),
    _k("bodies", "mass", "kg", "required", ">= 0", "the body's mass", invalid=-1.0),
    _k("bodies", "inertia", "kg m^2", "zeros (a point mass)", "3x3 symmetric positive "
       "semi-definite, or 3 numbers (its diagonal)", "the rotary inertia about the mass "
       "centre, in the rod's reference frame at the point (the frame of its segment)",
       invalid=[-1.0, 1.0, 1.0]),
    _k("bodies", "offset", "m", "[0, 0, 0]", _VEC, "the mass centre from the point, in "
       "the same frame", invalid=[0, 0]),
    # -- [[loads]] in an assembly -------------------------------------------------------
    _k("loads", "at", "-", "required (force, moment)", _POINT + " (not s, not a node "
       "index)", "where a point load acts", invalid="nowhere.end",
       kinds=("force", "moment")),
    _k("loads", "rods", "-", "every rod", "a non-empty list of rod names",
       "the rods a gravity or distributed load acts on (a body feels every gravity "
       "load, whatever its rods)", invalid=["nowhere"], kinds=("gravity", "distributed")),
    # -- [analysis] in an assembly ------------------------------------------------------
    _k("analysis", "maxima", "-", "none", "NAME.end.x, NAME.start.y, NAME@S.z, ...: a "
       "point and a coordinate", "the coordinate whose maxima give log decrements and "
       "damping ratios (as for a single rod)", invalid="end.x"),
)

#: what obstacles and the contact law are (shown by both renderings)
CONTACT_INTRO = (
    "Rods touch rigid obstacles, `[[obstacles]]` (a plane, a sphere, a cylinder or a "
    "pipe, fixed or moving with a prescribed rigid motion), and, with `[contact] self = "
    "true`, each other and themselves. The contact is a smoothed penalty with normal "
    "damping and regularized Coulomb friction, on the rod's contact radius (a circle's "
    "radius, a tube's outer radius, or `contact.radius`) about the centreline. Defaults: "
    "the stiffness 64 EI/h^4 per rod (EI its softer bending stiffness, h its shortest "
    "element: the contact's Winkler length is h/2, stiff enough that a heavy rod lifted "
    "off a table changes by about 2 (h/2a)^3 of its lift height, a its lifted length), "
    "a restitution of 0.1 (a rod dropped flat rebounds to 1 % of its drop height and rests "
    "within about half a second), a smoothing length "
    "`penetration` of the rod's own weight's (q/k, at most 0.2 % of the contact radius: a "
    "rod laid on a floor starts and rests at zero gap), a slip velocity of 1e-4 m/s (a rod held "
    "by static friction creeps below 0.1 mm/s). A rod may not start inside an obstacle "
    "by more than the penetration. `[contact]` without obstacles and without self = true "
    "is refused (it would change nothing). In an assembly both stay at the top and act "
    "on every rod. Paths for --set: `obstacles.0.friction`, `contact.restitution`; "
    "`--set 'obstacles.1={kind=\"sphere\", centre=[0,0,0.5], radius=0.1}'` appends an "
    "obstacle. Examples: `examples/contact_*.toml`.")

_MOTION = "3 numbers, |translation| x its function's peak at most 1e-8 (L/N)/eps"

#: the keys of obstacles and the contact law (:mod:`runtime.problem.obstacles`), in a
#: single-rod file and at the top of an assembly file
CONTACT_KEYS: tuple[Key, ...] = (
    # -- [[obstacles]] ------------------------------------------------------------------
    _k("obstacles", "kind", "-", "required", "plane, sphere, cylinder", "the obstacle's "
       "shape: a plane (a half space), a solid ball, a solid cylinder or, with inside = "
       "true, a pipe", invalid="cube"),
    _k("obstacles", "point", "m", "required", _VEC + ", at most 1e-8 (L/N)/eps from the "
       "origin", "plane: a point on it; cylinder: a point on its axis (where a finite one "
       "starts); a motion's rotation turns about it", invalid=[0, 0],
       kinds=("plane", "cylinder")),
    _k("obstacles", "normal", "-", "required", _UNIT_VEC, "the plane's normal, toward the "
       "free side (where the rod may be)", invalid=[0, 0, 0], kinds=("plane",)),
    _k("obstacles", "centre", "m", "required", _VEC + ", as point", "the sphere's centre "
       "(a motion's rotation turns about it)", invalid=[0, 0], kinds=("sphere",)),
    _k("obstacles", "radius", "m", "required", "> 0", "the radius of the sphere or "
       "cylinder (the pipe's bore)", invalid=-0.1, kinds=("sphere", "cylinder")),
    _k("obstacles", "axis", "-", "required", _UNIT_VEC, "the cylinder's axis",
       invalid=[0, 0, 0], kinds=("cylinder",)),
    _k("obstacles", "length", "m", "infinite", "> 0", "the cylinder's length from point "
       "along axis: a solid with flat end caps, or a pipe acting between its ends only "
       "(its rim is not modelled)", invalid=0.0, kinds=("cylinder",)),
    _k("obstacles", "inside", "-", "false", "true, false (cylinders only; refused on a "
       "plane or sphere)", "true: a pipe the rod runs inside (the free side is the bore); "
       "false: a solid the rod touches from outside", invalid="yes",
       kinds=("cylinder",)),
    _k("obstacles", "friction", "-", "0", "0 ... 100", "the Coulomb coefficient of "
       "friction between the rod and the obstacle (static = kinetic)", invalid=-0.1),
    _k("obstacles", "motion", "-", "none", "a table (below)", "a prescribed rigid motion "
       "of the obstacle, keys as an end's motion; it turns about the obstacle's point "
       "(centre) as that point moves", invalid=3),
    # -- motion = {...} of an obstacle --------------------------------------------------
    _k("obstacles.motion", "translation", "m", "[0, 0, 0]", _MOTION, "displacement of "
       "the obstacle's point (centre), times translation_time", invalid=[1, 2]),
    _k("obstacles.motion", "translation_time", "-", "constant 1", "a time function "
       "(<time>), continuous", "scales translation", invalid={"kind": "step"}),
    _k("obstacles.motion", "rotation_axis", "-", "[0, 0, 1]", _UNIT_VEC, "the fixed "
       "spatial direction of the rotation's axis (through the moving point)",
       invalid=[0, 0, 0]),
    _k("obstacles.motion", "rotation_angle", "deg", "0", "a number", "rotation of the "
       "obstacle, times rotation_time (a drum turning: a cylinder about its own axis)",
       invalid="quarter"),
    _k("obstacles.motion", "rotation_time", "-", "constant 1", "a time function "
       "(<time>), continuous", "scales rotation_angle", invalid={"kind": "release"}),
    # -- [contact] ----------------------------------------------------------------------
    _k("contact", "radius", "m", "the section's outer radius (circle: radius, tube: "
       "outer_radius, a composite of concentric circles and tubes: the largest); "
       "required for other sections", "> 0; in an assembly also a table {NAME = r} "
       "(rods not named: their section's)", "the rod's contact radius: the round "
       "envelope about the centreline the contact sees", invalid=-0.01),
    _k("contact", "self", "-", "false", "true, false", "contact of a rod with "
       "itself (a plectoneme); in an assembly also of its rods with each other (and "
       "each with itself); not with sensitivities or kvrod modes",
       invalid="yes"),
    _k("contact", "friction", "-", "0", "0 ... 100", "the Coulomb coefficient of the "
       "rods' contact with each other and themselves (self = true; an obstacle has its "
       "own friction)", invalid=-0.5),
    _k("contact", "penetration", "m", "rho A g / k (at most 0.2 % of the smallest contact "
       "radius)", "> 0, at "
       "most the contact radius", "the smoothing length of the law (the normal force "
       "rises from zero to the linear penalty over a gap band this wide) and the "
       "tolerance of the check that no rod starts inside an obstacle", invalid=0.0),
    _k("contact", "slip_velocity", "m/s", "1e-4", "> 0", "the regularization of the "
       "friction: full Coulomb friction above this sliding speed; a rod held by static "
       "friction creeps at about slip_velocity f_t / (mu f_n)", invalid=0.0),
    _k("contact", "restitution", "-", "0.1", "(0, 1]", "the coefficient of restitution "
       "e of a node's mass on the contact spring (normal damping ratio -ln e / sqrt(pi^2 "
       "+ ln^2 e): 0.59 at 0.1; 1: no damping)", invalid=1.5),
    _k("contact", "stiffness", "N/m^2", "64 EI/h^4 per rod (EI: its softer bending "
       "stiffness, smallest along the rod; h: its shortest element)", "> 0", "the "
       "penalty: normal force per length per metre of penetration", invalid=-1.0),
)

#: which command-line aliases an assembly takes and how
ASSEMBLY_OVERRIDES = (
    "In an assembly, PATH runs through the file's tables: `rods.NAME.material."
    "youngs_modulus`, `rods.NAME.rod.elements`, `joints.0.rotational_stiffness`, "
    "`bodies.0.mass`, `loads.1.vector`, `materials.NAME.tau_S` (a shared material), "
    "`simulation.t_end`; the index one past the last entry of `joints`, `bodies` or "
    "`loads` appends one. The short aliases (`--tau`, `--tau-S`, `--tau-B`, `--E`, "
    "`--nu`, `--n-elements` and the names tau, E, nu, density, damping, n_elements, "
    "width, height, radius, shear_correction of sweeps) are broadcast: they set their "
    "key on every rod (`--n-elements 20` gives each rod 20 elements). The simulation "
    "and statics aliases (`--t-end`, `--rtol`, `--atol`, `--max-order`, "
    "`--error-control`, min_step, output_step, load_steps) set the one top-level key. "
    "`length` and `--tip-force` are refused in an assembly: set rods.NAME.rod.length or "
    "loads.K.vector.")


def by_table(keys: tuple[Key, ...] = KEYS) -> dict[str, list[Key]]:
    """The catalogue (or ``keys``) grouped by table, in file order."""
    out: dict[str, list[Key]] = {}
    for k in keys:
        out.setdefault(k.table, []).append(k)
    return out


def _table_rows(keys: list[Key]) -> list[str]:
    lines = ["| key | kinds | unit | default | allowed | meaning |", "|---|---|---|---|---|---|"]
    for k in keys:
        cells = (f"`{k.name}`", ", ".join(k.kinds) or "all", k.unit, k.default,
                 k.allowed, k.doc)
        lines.append("| " + " | ".join(c.replace("|", "\\|") for c in cells) + " |")
    return lines + [""]


#: the assembly part's headings, by table
_ASSEMBLY_HEADS = {"": "assembly file: top level", "rods.NAME": "`[rods.NAME]` (each rod)",
                   "joints": "`[[joints]]`", "bodies": "`[[bodies]]`",
                   "loads": "`[[loads]]` in an assembly",
                   "analysis": "`[analysis]` in an assembly"}


#: the contact part's headings, by table
_CONTACT_HEADS = {"obstacles": "`[[obstacles]]`",
                  "obstacles.motion": "`motion = {...}` of an obstacle",
                  "contact": "`[contact]`"}


def markdown() -> str:
    """The reference as Markdown tables, one per table (what the documentation shows)."""
    lines = ["### Changing keys: `--set` and overrides", "", OVERRIDES, ""]
    for table, keys in by_table().items():
        head = ("top level" if not table else "time functions (`time = {...}` of a load, "
                "`translation_time`/`rotation_time` of a motion)" if table == "<time>"
                else "`shape = {...}` of a region" if table == "section.regions.shape"
                else f"`[[{table}]]`" if table in ("loads", "material.branches",
                                                   "section.regions")
                else f"`[{table}]`")
        lines += [f"### {head}", ""] + _table_rows(keys)
    lines += ["### Assemblies: several rods, joints, bodies", "", ASSEMBLY_INTRO, "",
              ASSEMBLY_OVERRIDES, ""]
    for table, keys in by_table(ASSEMBLY_KEYS).items():
        lines += [f"### {_ASSEMBLY_HEADS[table]}", ""] + _table_rows(keys)
    lines += ["### Contact: obstacles and the contact law", "", CONTACT_INTRO, ""]
    for table, keys in by_table(CONTACT_KEYS).items():
        lines += [f"### {_CONTACT_HEADS[table]}", ""] + _table_rows(keys)
    return "\n".join(lines)


def text() -> str:
    """The reference as plain text (``kvrod problem-keys``): one key per entry."""
    import textwrap

    def entries(keys: tuple[Key, ...], prefix: str = "") -> list[str]:
        out = []
        for k in keys:
            path = f"<time>.{k.name}" if k.table == "<time>" else prefix + k.path
            kinds = f" [{', '.join(k.kinds)}]" if k.kinds else ""
            out.append(f"{path}{kinds}  unit: {k.unit}; default: {k.default}; allowed: "
                       f"{k.allowed}\n    {k.doc}")
        return out

    def para(text: str) -> str:
        return textwrap.fill(text.replace("`", ""), 88, initial_indent="    ",
                             subsequent_indent="    ")

    out = entries(KEYS)
    out += ["", "changing keys (--set, overrides):", para(OVERRIDES)]
    out += ["", "assemblies (a file with [rods.NAME] tables):", para(ASSEMBLY_INTRO),
            para(ASSEMBLY_OVERRIDES), ""]
    out += entries(ASSEMBLY_KEYS, prefix="assembly: ")
    out += ["", "contact (obstacles and the contact law, single rods and assemblies):",
            para(CONTACT_INTRO), ""]
    out += entries(CONTACT_KEYS)
    return "\n".join(out)
