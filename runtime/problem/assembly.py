"""Rod assemblies: problem files of several rods, joints and rigid bodies (issue 31).

A problem file with ``[rods.NAME]`` tables is an :class:`Assembly`. Each rod's table holds
what a single-rod problem holds (``[rods.NAME.rod]`` with its ``geometry``, whose
``origin`` places the rod, ``[rods.NAME.section]``, ``[rods.NAME.material]``,
``[[rods.NAME.zones]]``, ``[rods.NAME.start]``, ``[rods.NAME.end]``; the ends default
to ``free``: joints hold the rods), and becomes a
:class:`~runtime.problem.schema.Problem` with the loads that act on it. ``simulation``,
``statics``, ``analysis`` and ``[[loads]]`` stay at the top; ``[materials.NAME]`` at the
top is shared by the rods' composite sections (a rod may add its own,
``[rods.NAME.materials.X]``; a name given in both places must be the same material).

Points: ``NAME.start``, ``NAME.end``, ``NAME@S`` (arc length S in m from the rod's
start). Every named point gets a node of its rod (``Problem.points``).

* ``[[joints]]``: ``between = [P, Q]`` (two points at the same place in the reference
  configuration, or a point and ``"ground"``), ``kind`` = ``weld`` (all relative motion
  held), ``ball`` (position held), ``hinge`` (position held, relative rotation only about
  ``axis``, a spatial vector of the reference configuration) or ``spring`` (the 6x6
  ``stiffness_matrix`` and ``viscosity_matrix`` on the relative displacement and rotation
  in P's frame). ``ball`` and ``hinge`` take ``rotational_stiffness`` [N m/rad] and
  ``rotational_viscosity`` [N m s/rad] on their free rotation.
* ``[[bodies]]``: ``name``, ``at`` (welded at a point), ``mass`` [kg], ``inertia`` [kg
  m^2] (3x3 about the mass centre, or its diagonal), ``offset`` [m] (mass centre from the
  point), both in the rod's reference frame at the point (``Geometry.frame``). A body
  feels every gravity load (:meth:`Assembly.gravity_loads`).
* ``[[loads]]``: gravity and distributed loads act on every rod, or on those named in
  ``rods = [...]``; a point force or moment acts at ``at = POINT``.
* ``[[obstacles]]`` and ``[contact]`` (:mod:`runtime.problem.obstacles`) stay at the top
  and act on every rod; ``contact.self`` switches on the contact of the rods with each
  other and with themselves; ``contact.radius`` may be a table ``{NAME = r}`` of radii
  per rod (rods not named: their section's outer radius).

The lead's system model (``runtime.model``) consumes these objects; nothing here knows
of it. ``kvrod problem-keys`` lists every key (``runtime.problem.keys.ASSEMBLY_KEYS``).
"""

from __future__ import annotations

import copy
import math
import re
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from runtime.errors import ParameterError
from runtime.problem import coerce as C
from runtime.problem.geometry import NODE_SNAP_RTOL, Geometry, geometry_from_mapping
from runtime.problem.loads import LOAD_KINDS, Load, load_from_mapping
from runtime.problem.obstacles import (
    Contact,
    Obstacle,
    contact_from_mapping,
    obstacles_from_mapping,
)
from runtime.problem.schema import (
    ALIASES,
    MAX_ELEMENTS,
    Problem,
    Simulation,
    Statics,
    _settings,
    apply_override,
)

#: keys at the top of an assembly file
ASSEMBLY_TOP_KEYS = ("name", "description", "rods", "materials", "joints", "bodies", "loads",
                     "simulation", "statics", "analysis", "obstacles", "contact")
#: keys of a rod's table ``[rods.NAME]``
ROD_KEYS = ("rod", "section", "material", "materials", "zones", "start", "end")
#: the single-rod tables that go into each rod's table in an assembly
PER_ROD = ("rod", "section", "material", "zones", "start", "end")
JOINT_KINDS = ("weld", "ball", "hinge", "spring")
_ROTATIONAL = ("rotational_stiffness", "rotational_viscosity")
JOINT_KEYS: dict[str, tuple[str, ...]] = {
    "weld": ("kind", "between"),
    "ball": ("kind", "between") + _ROTATIONAL,
    "hinge": ("kind", "between", "axis") + _ROTATIONAL,
    "spring": ("kind", "between", "stiffness_matrix", "viscosity_matrix"),
}
BODY_KEYS = ("name", "at", "mass", "inertia", "offset")
GROUND = "ground"
#: a rod's name: letters, digits, _ and -, not starting with a digit or - (a point label
#: ``NAME.end``, ``NAME@S`` must parse back)
NAME_RE = re.compile(r"[A-Za-z_][A-Za-z0-9_-]*\Z")
#: two joined points coincide within this fraction of the longest rod
COINCIDE_RTOL = 1e-9
#: a 6x6 or 3x3 matrix is symmetric within this fraction of its largest entry
SYMMETRY_RTOL = 1e-9
#: a positive semi-definite matrix may have eigenvalues down to -this times its largest
#: (round-off of the symmetric part)
PSD_RTOL = 1e-12
#: units of a spring joint's matrices (relative displacement, m; relative rotation, rad)
SPRING_UNITS = ("N/m (translation), N/rad and N (coupling), N m/rad (rotation); viscosity "
                "the same per second: N s/m, N s/rad, N m s/rad")
#: the command line's aliases that an assembly refuses (what each would mean is unclear)
REFUSED_ALIASES = {
    "length": "rods.NAME.rod.length for one rod (one length for every rod would move the "
              "joints' points apart)",
    "tip_force": "loads.K.vector (an assembly has no single tip: set the force's vector)",
}
#: the aliases that set a key at the top of an assembly (not per rod)
TOP_ALIAS_TABLES = ("simulation", "statics")


# -- points ---------------------------------------------------------------------------------
@dataclass(frozen=True)
class Point:
    """A named point of an assembly: arc length ``s`` (m) on rod ``rod``; ``label`` as
    written (``"arm.end"``, ``"trunk@0.2"``)."""

    rod: str
    s: float
    label: str

    @property
    def end(self) -> str | None:
        """``"start"`` or ``"end"`` for a point named by its rod's end, else None."""
        for e in ("start", "end"):
            if self.label.endswith("." + e):
                return e
        return None

    def __str__(self) -> str:
        return self.label


def _rod_list(lengths: Mapping[str, float]) -> str:
    return ", ".join(f"{n} ({L:g} m)" for n, L in lengths.items())


def parse_point(path: str, label: Any, lengths: Mapping[str, float]) -> Point:
    """The point ``label`` (``NAME.start``, ``NAME.end`` or ``NAME@S``) of the rods of
    ``lengths`` ({name: length in m}); a ParameterError naming ``path`` otherwise."""
    form = ("a point: NAME.start, NAME.end or NAME@S (S: arc length in m from the rod's "
            f"start) of a rod: {_rod_list(lengths)}")
    if not isinstance(label, str):
        raise ParameterError(path, label, form)
    if "@" in label:
        name, _, s_text = label.partition("@")
        try:
            s = float(s_text)
        except ValueError:
            raise ParameterError(path, label, form) from None
    elif label.endswith(".start"):
        name, s = label[:-len(".start")], 0.0
    elif label.endswith(".end"):
        name, s = label[:-len(".end")], None
    else:
        raise ParameterError(path, label, form)
    if name not in lengths:
        raise ParameterError(path, label, f"a point of a known rod; unknown rod {name!r}: "
                             f"the rods are {_rod_list(lengths)}")
    L = lengths[name]
    if s is None:
        s = L
    if not (math.isfinite(s) and 0.0 <= s <= L * (1 + 1e-12)):
        raise ParameterError(path, label, f"{name}@S with 0 <= S <= {L:g} m (the length of "
                             f"rod {name})")
    return Point(name, min(s, L), label)


# -- joints ---------------------------------------------------------------------------------
def _frozen(a: np.ndarray) -> np.ndarray:
    a = np.array(a, dtype=float)
    a.setflags(write=False)
    return a


def _same(a: Any, b: Any) -> bool:
    if a is None or b is None:
        return a is None and b is None
    return bool(np.array_equal(a, b))


def check_psd(path: str, value: Any, size: int, units: str,
              diagonal_ok: bool = False) -> np.ndarray:
    """A ``size`` x ``size`` symmetric positive semi-definite matrix of finite numbers
    (``diagonal_ok``: ``size`` numbers are its diagonal); returns its symmetric part.
    Symmetric within ``SYMMETRY_RTOL`` of its largest entry; eigenvalues >=
    ``-PSD_RTOL`` times the largest."""
    shape = f"a {size}x{size} matrix" + (f" (or {size} numbers: its diagonal)"
                                          if diagonal_ok else "")
    try:
        M = np.array(value, dtype=float)
    except (TypeError, ValueError):
        M = np.zeros(0)
    if isinstance(value, (str, bytes)) or not np.all(np.isfinite(M)):
        raise ParameterError(path, value, f"{shape} of finite numbers ({units})")
    if diagonal_ok and M.shape == (size,):
        M = np.diag(M)
    if M.shape != (size, size):
        raise ParameterError(path, value, f"{shape} of finite numbers ({units})")
    big = float(np.max(np.abs(M))) if M.size else 0.0
    asym = np.abs(M - M.T)
    if float(np.max(asym)) > SYMMETRY_RTOL * big:
        i, j = np.unravel_index(int(np.argmax(asym)), M.shape)
        raise ParameterError(path, M.tolist(), f"a symmetric matrix ({units}): entries "
                             f"[{i}][{j}] = {M[i, j]:.6g} and [{j}][{i}] = {M[j, i]:.6g} "
                             f"differ by more than {SYMMETRY_RTOL:g} of the largest entry")
    S = 0.5 * (M + M.T)
    ev = np.linalg.eigvalsh(S)
    if ev.min() < -PSD_RTOL * max(float(np.max(np.abs(ev))), 0.0):
        raise ParameterError(path, M.tolist(), f"a positive semi-definite matrix ({units}); "
                             f"its most negative eigenvalue is {ev.min():.6g}")
    return S


@dataclass(frozen=True, eq=False)
class Joint:
    """One ``[[joints]]`` entry (``index``: its place there, from 0).

    ``first`` (P) and ``second`` (Q; None: ground, the place of P in the reference
    configuration) coincide in the reference configuration. ``kind``: ``weld`` (all
    relative motion held), ``ball`` (relative position held), ``hinge`` (relative
    position held, relative rotation only about ``axis``: a spatial unit vector (3,) of
    the reference configuration), ``spring`` (``stiffness_matrix`` K and
    ``viscosity_matrix`` V, (6, 6), symmetric positive semi-definite, on the relative
    displacement (m) and rotation (rad) of Q against P in P's frame, the order of a
    section's matrices: translation 1, 2, 3 then rotation 1, 2, 3; V zeros when not
    given). ``ball`` and ``hinge`` carry ``rotational_stiffness`` [N m/rad] and
    ``rotational_viscosity`` [N m s/rad] on their free relative rotation (0: free).
    """

    index: int
    kind: str
    first: Point
    second: Point | None = None
    axis: np.ndarray | None = None
    rotational_stiffness: float = 0.0
    rotational_viscosity: float = 0.0
    stiffness_matrix: np.ndarray | None = None
    viscosity_matrix: np.ndarray | None = None

    def __post_init__(self) -> None:
        path = f"joints[{self.index}]"
        C.choice(f"{path}.kind", self.kind, JOINT_KINDS)
        if self.kind == "hinge":
            if self.axis is None:
                raise ParameterError(f"{path}.axis", None, "the hinge's axis: 3 finite "
                                     "numbers, not all 0 (a spatial direction in the "
                                     "reference configuration)")
            object.__setattr__(self, "axis", _frozen(C.unit_vector(f"{path}.axis",
                                                                   list(self.axis))))
        elif self.axis is not None:
            raise ParameterError(f"{path}.axis", list(self.axis), "only for kind = 'hinge' "
                                 f"(a {self.kind} has no axis)")
        for key in _ROTATIONAL:
            v = getattr(self, key)
            if self.kind in ("ball", "hinge"):
                object.__setattr__(self, key, C.nonnegative(f"{path}.{key}", v))
            elif v:
                raise ParameterError(f"{path}.{key}", v, "only for kind = 'ball' or 'hinge' "
                                     f"(a {self.kind} holds or springs every rotation)")
        if self.kind == "spring":
            if self.stiffness_matrix is None:
                raise ParameterError(f"{path}.stiffness_matrix", None, "a spring's 6x6 "
                                     f"stiffness, symmetric positive semi-definite "
                                     f"({SPRING_UNITS})")
            K = check_psd(f"{path}.stiffness_matrix", self.stiffness_matrix, 6, SPRING_UNITS)
            V = (np.zeros((6, 6)) if self.viscosity_matrix is None else
                 check_psd(f"{path}.viscosity_matrix", self.viscosity_matrix, 6,
                           SPRING_UNITS))
            object.__setattr__(self, "stiffness_matrix", _frozen(K))
            object.__setattr__(self, "viscosity_matrix", _frozen(V))
        else:
            for key in ("stiffness_matrix", "viscosity_matrix"):
                if getattr(self, key) is not None:
                    raise ParameterError(f"{path}.{key}", "given", "only for kind = 'spring'")

    @property
    def grounded(self) -> bool:
        """A joint of one point to ground (a support or clip)."""
        return self.second is None

    def to_mapping(self) -> dict[str, Any]:
        out: dict[str, Any] = {"kind": self.kind, "between": [
            self.first.label, self.second.label if self.second is not None else GROUND]}
        if self.kind == "hinge":
            out["axis"] = [float(v) for v in self.axis]
        if self.kind in ("ball", "hinge"):
            out["rotational_stiffness"] = self.rotational_stiffness
            out["rotational_viscosity"] = self.rotational_viscosity
        if self.kind == "spring":
            out["stiffness_matrix"] = self.stiffness_matrix.tolist()
            out["viscosity_matrix"] = self.viscosity_matrix.tolist()
        return out

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Joint):
            return NotImplemented
        return ((self.index, self.kind, self.first, self.second, self.rotational_stiffness,
                 self.rotational_viscosity) == (other.index, other.kind, other.first,
                                                other.second, other.rotational_stiffness,
                                                other.rotational_viscosity)
                and all(_same(getattr(self, k), getattr(other, k)) for k in
                        ("axis", "stiffness_matrix", "viscosity_matrix")))

    __hash__ = None  # type: ignore[assignment]


def _joint(k: int, m: Any, lengths: Mapping[str, float]) -> Joint:
    """One ``[[joints]]`` table (the points' coincidence is checked by the caller)."""
    path = f"joints[{k}]"
    m = C.table(path, m)
    if "kind" not in m:
        raise ParameterError(f"{path}.kind", None, "one of " + ", ".join(
            repr(j) for j in JOINT_KINDS))
    kind = C.choice(f"{path}.kind", m["kind"], JOINT_KINDS)
    if "axis" in m and kind != "hinge":
        raise ParameterError(f"{path}.axis", m["axis"], f"only for kind = 'hinge' (a {kind} "
                             "has no axis)")
    for key in _ROTATIONAL:
        if key in m and kind not in ("ball", "hinge"):
            raise ParameterError(f"{path}.{key}", m[key], "only for kind = 'ball' or "
                                 f"'hinge' (a {kind} holds or springs every rotation)")
    for key in ("stiffness_matrix", "viscosity_matrix"):
        if key in m and kind != "spring":
            raise ParameterError(f"{path}.{key}", "given", "only for kind = 'spring'")
    C.no_unknown_keys(path, m, JOINT_KEYS[kind])
    between = m.get("between")
    form = ('two points [P, Q] (NAME.start, NAME.end, NAME@S) or a point and "ground"; '
            f"the rods: {_rod_list(lengths)}")
    if (isinstance(between, (str, bytes, Mapping)) or not isinstance(between, (list, tuple))
            or len(between) != 2):
        raise ParameterError(f"{path}.between", between, form)
    if between[0] == GROUND and between[1] == GROUND:
        raise ParameterError(f"{path}.between[1]", GROUND, "a point (a joint of ground with "
                             "ground holds nothing)")
    pts = [None if b == GROUND else parse_point(f"{path}.between[{i}]", b, lengths)
           for i, b in enumerate(between)]
    if pts[0] is None:                 # ground first: the point is P, ground Q
        pts = [pts[1], None]
    kw: dict[str, Any] = {}
    if "axis" in m:
        kw["axis"] = C.unit_vector(f"{path}.axis", m["axis"])
    for key in _ROTATIONAL:
        if key in m:
            kw[key] = C.nonnegative(f"{path}.{key}", m[key])
    for key in ("stiffness_matrix", "viscosity_matrix"):
        if key in m:
            kw[key] = m[key]
    return Joint(k, kind, pts[0], pts[1], **kw)


# -- bodies ---------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class Body:
    """A rigid body welded at a point (``[[bodies]]``, ``index`` its place there): its
    ``mass`` [kg], ``inertia`` (3, 3) [kg m^2] about its mass centre and ``offset`` (3,)
    [m] of the mass centre from the point, both in the rod's reference frame at the point
    (the frame of the point's segment). Zero inertia: a point mass."""

    name: str
    at: Point
    mass: float
    inertia: np.ndarray = field(default_factory=lambda: np.zeros((3, 3)))
    offset: np.ndarray = field(default_factory=lambda: np.zeros(3))
    index: int = 0

    def __post_init__(self) -> None:
        path = f"bodies[{self.index}]"
        C.string(f"{path}.name", self.name)
        object.__setattr__(self, "mass", C.nonnegative(f"{path}.mass", self.mass))
        J = check_psd(f"{path}.inertia", self.inertia, 3, "kg m^2, about the mass centre",
                      diagonal_ok=True)
        object.__setattr__(self, "inertia", _frozen(J))
        object.__setattr__(self, "offset", _frozen(C.vector(f"{path}.offset", self.offset)))

    def to_mapping(self) -> dict[str, Any]:
        return {"name": self.name, "at": self.at.label, "mass": self.mass,
                "inertia": self.inertia.tolist(), "offset": self.offset.tolist()}

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Body):
            return NotImplemented
        return ((self.name, self.at, self.mass, self.index)
                == (other.name, other.at, other.mass, other.index)
                and _same(self.inertia, other.inertia) and _same(self.offset, other.offset))

    __hash__ = None  # type: ignore[assignment]


def _body(k: int, m: Any, lengths: Mapping[str, float]) -> Body:
    path = f"bodies[{k}]"
    m = C.table(path, m)
    C.no_unknown_keys(path, m, BODY_KEYS)
    for key, what in (("at", "the point the body is welded at (NAME.start, NAME.end, "
                             "NAME@S)"), ("mass", "the body's mass in kg, >= 0")):
        if key not in m:
            raise ParameterError(f"{path}.{key}", None, what)
    at = parse_point(f"{path}.at", m["at"], lengths)
    kw: dict[str, Any] = {}
    if "inertia" in m:
        kw["inertia"] = m["inertia"]
    if "offset" in m:
        kw["offset"] = m["offset"]
    return Body(C.string(f"{path}.name", m.get("name", f"body{k}")), at, m["mass"],
                index=k, **kw)


# -- loads ----------------------------------------------------------------------------------
@dataclass(frozen=True)
class AssemblyLoad:
    """One ``[[loads]]`` entry of an assembly (``index``: its place there).

    ``load``: the load in the single-rod form (a point load's ``at`` = "start"/"end" or
    its ``s`` on the rod of ``point``); ``point``: where a force or moment acts (None for
    gravity and distributed loads); ``rods``: the rods a gravity or distributed load acts
    on (None: every rod; bodies feel every gravity load whatever its ``rods``)."""

    index: int
    load: Load
    point: Point | None = None
    rods: tuple[str, ...] | None = None

    @property
    def kind(self) -> str:
        return self.load.kind

    def acts_on(self, rod: str) -> bool:
        """Whether the load acts on the rod named ``rod``."""
        if self.point is not None:
            return self.point.rod == rod
        return self.rods is None or rod in self.rods

    def to_mapping(self) -> dict[str, Any]:
        out = self.load.to_mapping()
        if self.point is not None:
            out.pop("s", None)
            out["at"] = self.point.label
        elif self.rods is not None:
            out["rods"] = list(self.rods)
        return out


def _load(k: int, m: Any, lengths: Mapping[str, float], base: Path | None) -> AssemblyLoad:
    path = f"loads[{k}]"
    m = C.table(path, m)
    kind = C.choice(f"{path}.kind", m.get("kind", "force"), LOAD_KINDS)
    point = kind in ("force", "moment")
    if point and "s" in m:
        raise ParameterError(f"{path}.s", m["s"], "at = \"NAME@S\" in an assembly (a point "
                             "names its rod and its arc length)")
    if point and "rods" in m:
        raise ParameterError(f"{path}.rods", m["rods"], "only for gravity and distributed "
                             "loads (a point load acts at its point, `at`)")
    C.no_unknown_keys(path, m, ("kind", "vector", "time")
                      + (("at", "frame") if point else ("rods",)))
    single = {key: v for key, v in m.items() if key not in ("at", "rods")}
    pt: Point | None = None
    if point:
        if "at" not in m:
            raise ParameterError(f"{path}.at", None, "the point the load acts at: "
                                 f"NAME.start, NAME.end or NAME@S of a rod: "
                                 f"{_rod_list(lengths)}")
        pt = parse_point(f"{path}.at", m["at"], lengths)
        if pt.end is not None:
            single["at"] = pt.end
        else:
            single["s"] = pt.s
    rods: tuple[str, ...] | None = None
    if "rods" in m:
        r = m["rods"]
        if isinstance(r, (str, bytes, Mapping)) or not isinstance(r, (list, tuple)) or not r:
            raise ParameterError(f"{path}.rods", r, "a non-empty list of rod names: "
                                 + ", ".join(lengths))
        for i, name in enumerate(r):
            if name not in lengths:
                raise ParameterError(f"{path}.rods[{i}]", name, "a rod of the assembly: "
                                     + ", ".join(lengths))
        rods = tuple(dict.fromkeys(r))
    return AssemblyLoad(k, load_from_mapping(path, single, base), pt, rods)


# -- analysis -------------------------------------------------------------------------------
@dataclass(frozen=True)
class AssemblyAnalysis:
    """``analysis.maxima`` of an assembly: a point's coordinate (``"arm.end.x"``,
    ``"trunk@0.2.z"``) as written, its ``point`` and ``component`` ("x", "y" or "z");
    None: no maxima."""

    maxima: str | None = None
    point: Point | None = None
    component: str | None = None

    @property
    def axis(self) -> int | None:
        """The component as an index 0, 1, 2 (None without maxima)."""
        return None if self.component is None else "xyz".index(self.component)

    def to_mapping(self) -> dict[str, Any]:
        return {} if self.maxima is None else {"maxima": self.maxima}


def _analysis(m: Any, lengths: Mapping[str, float]) -> AssemblyAnalysis:
    m = C.table("analysis", m if m is not None else {})
    C.no_unknown_keys("analysis", m, ("maxima",))
    if m.get("maxima") is None:
        return AssemblyAnalysis()
    v = m["maxima"]
    form = ("a coordinate of a point: NAME.end.x, NAME.start.y or NAME@S.z of a rod: "
            + _rod_list(lengths))
    if not isinstance(v, str) or "." not in v:
        raise ParameterError("analysis.maxima", v, form)
    label, _, comp = v.rpartition(".")
    if comp not in ("x", "y", "z"):
        raise ParameterError("analysis.maxima", v, form)
    try:
        point = parse_point("analysis.maxima", label, lengths)
    except ParameterError as exc:
        hint = (" (a single rod's end.x names no rod in an assembly: NAME.end.x)"
                if label in ("start", "end") else "")
        raise ParameterError("analysis.maxima", v, exc.allowed + hint) from None
    return AssemblyAnalysis(v, point, comp)


# -- errors inside a rod's table ------------------------------------------------------------
_LOAD_NAME = re.compile(r"loads(?:\[(\d+)\]|\.(\d+))(.*)\Z", re.S)


def _rod_error(exc: ParameterError, rod: str, loads: tuple[int, ...] = (),
               shared: tuple[str, ...] = ()) -> ParameterError:
    """A rod problem's error as the assembly names it: the rod's own keys prefixed with
    ``rods.NAME.``; its loads by their index in the assembly's ``[[loads]]``; the top-level
    settings and shared materials by their own names (the rod said in the range)."""
    name = exc.name
    m = _LOAD_NAME.match(name)
    note = f" [rod {rod}]"
    if m:
        i = int(m.group(1) or m.group(2))
        k = loads[i] if i < len(loads) else i
        new = (f"loads[{k}]" if m.group(1) is not None else f"loads.{k}") + m.group(3)
        return ParameterError(new, exc.value, exc.allowed + note, exc.where)
    top = name.split(".")[0].split("[")[0]
    if top in ("loads", "simulation", "statics", "analysis", "obstacles", "contact"):
        return ParameterError(name, exc.value, exc.allowed + note, exc.where)
    if top == "materials" and len(name.split(".")) > 1 and name.split(".")[1] in shared:
        return ParameterError(name, exc.value, exc.allowed + note, exc.where)
    return ParameterError(f"rods.{rod}.{name}" if name else f"rods.{rod}", exc.value,
                          exc.allowed, exc.where)


@contextmanager
def _in_rod(rod: str, loads: tuple[int, ...] = (),
            shared: tuple[str, ...] = ()) -> Iterator[None]:
    try:
        yield
    except ParameterError as exc:
        raise _rod_error(exc, rod, loads, shared) from None


def _rod_geometry(name: str, t: Mapping[str, Any], base: Path | None) -> Geometry:
    """The reference geometry of a rod's table (``[rods.NAME.rod]``), checked as in a
    single-rod file."""
    with _in_rod(name):
        rod_m = dict(C.table("rod", t.get("rod", {})))
        C.no_unknown_keys("rod", rod_m, ("length", "elements", "geometry"))
        length = C.positive("rod.length", rod_m["length"]) if "length" in rod_m else None
        C.integer("rod.elements", rod_m.get("elements", 50), low=1, high=MAX_ELEMENTS)
        return geometry_from_mapping(rod_m.get("geometry"), length, base)


def _uses_composite(t: Mapping[str, Any]) -> bool:
    """A rod table whose section or a zone's section is composite (names materials)."""
    sec = t.get("section")
    if isinstance(sec, Mapping) and sec.get("kind") == "composite":
        return True
    zones = t.get("zones")
    return isinstance(zones, list) and any(
        isinstance(z, Mapping) and isinstance(z.get("section"), Mapping)
        and z["section"].get("kind") == "composite" for z in zones)


def _resolved_materials(m: Any, path: str) -> dict[str, Any]:
    from runtime.section import materials_from_mapping

    return {k: v.to_mapping() for k, v in materials_from_mapping(m, path).items()}


# -- the assembly ---------------------------------------------------------------------------
@dataclass(frozen=True)
class Assembly:
    """Several rods joined by joints, carrying rigid bodies (see the module docstring).

    ``rods``: {name: :class:`~runtime.problem.schema.Problem`} in file order, each with
    its own rod, section, material, zones and ends, the loads that act on it (a point
    load at one of its points in the single-rod form), the assembly's simulation and
    statics settings, no ``analysis.maxima``, and a node at every named point
    (``Problem.points``). ``joints``, ``bodies``, ``loads``: tuples of :class:`Joint`,
    :class:`Body`, :class:`AssemblyLoad` in file order; ``materials``: the shared
    ``[materials.NAME]`` tables (resolved), ``analysis``: :class:`AssemblyAnalysis`.
    ``obstacles``: the :class:`~runtime.problem.obstacles.Obstacle` tuple, ``contact``:
    the :class:`~runtime.problem.obstacles.Contact` as given (None: not given); each
    rod's problem holds the same obstacles and its own contact settings
    (``Contact.for_rod``: its radius), so ``rods[NAME].contact_law()`` gives its numbers.
    """

    name: str
    description: str
    rods: dict[str, Problem]
    joints: tuple[Joint, ...] = ()
    bodies: tuple[Body, ...] = ()
    loads: tuple[AssemblyLoad, ...] = ()
    simulation: Simulation = field(default_factory=Simulation)
    statics: Statics = field(default_factory=Statics)
    analysis: AssemblyAnalysis = field(default_factory=AssemblyAnalysis)
    materials: dict[str, Any] = field(default_factory=dict)
    base: Path | None = field(default=None, compare=False, repr=False)
    obstacles: tuple[Obstacle, ...] = ()
    contact: Contact | None = None

    def __post_init__(self) -> None:
        if not self.rods:
            raise ParameterError("rods", {}, "at least one rod: a [rods.NAME] table")

    # -- names and points ---------------------------------------------------------------
    @property
    def rod_names(self) -> tuple[str, ...]:
        """The rods' names in file order."""
        return tuple(self.rods)

    def rod_index(self, name: str) -> int:
        """The place (from 0) of the rod ``name`` in file order."""
        try:
            return self.rod_names.index(name)
        except ValueError:
            raise ParameterError("rods", name, "a rod of the assembly: "
                                 + ", ".join(self.rods)) from None

    def lengths(self) -> dict[str, float]:
        """{rod name: length in m}."""
        return {n: p.rod.length for n, p in self.rods.items()}

    def point(self, label: str) -> Point:
        """The point named ``label`` (``NAME.start``, ``NAME.end``, ``NAME@S``)."""
        return parse_point("point", label, self.lengths())

    def named_points(self) -> tuple[Point, ...]:
        """Every point the file names: the joints', bodies' and point loads' points and
        the point of ``analysis.maxima``, in that order (repeats kept)."""
        return _named(self.joints, self.bodies, self.loads, self.analysis)

    def points_on(self, rod: str) -> tuple[float, ...]:
        """The arc lengths (m, increasing, distinct) of the named points on rod ``rod``
        (the rod problem's ``points``: each has a node)."""
        self.rod_index(rod)
        return _points_on(self.named_points(), rod)

    def reference_position(self, point: Point) -> np.ndarray:
        """The point's position (3,) in m in the reference configuration."""
        return np.asarray(self.rods[point.rod].rod.geometry.position(point.s), dtype=float)

    def reference_frame(self, point: Point) -> np.ndarray:
        """The rod's reference director frame (3, 3) at the point (columns d1, d2, d3)."""
        return np.asarray(self.rods[point.rod].rod.geometry.frame(point.s), dtype=float)

    def gravity_loads(self) -> tuple[Load, ...]:
        """Every gravity load (vector in m/s^2 and time function), whatever rods it is
        limited to: the bodies feel all of them."""
        return tuple(ld.load for ld in self.loads if ld.kind == "gravity")

    # -- checks and reports -------------------------------------------------------------
    def check_simulable(self) -> None:
        """Each rod's :meth:`~runtime.problem.schema.Problem.check_simulable` (a composite
        section's analysis and the checks that need it), errors named by the rod."""
        shared = tuple(self.materials)
        for name, p in self.rods.items():
            with _in_rod(name, _rod_load_indices(self.loads, name), shared):
                p.check_simulable()

    def describe_material(self) -> str:
        """One line for reports: the rods' materials (one description when all agree)."""
        d = {n: p.describe_material() for n, p in self.rods.items()}
        one = set(d.values())
        if len(one) == 1:
            return one.pop() + (f" (all {len(d)} rods)" if len(d) > 1 else "")
        return "; ".join(f"{n}: {v}" for n, v in d.items())

    # -- mappings -----------------------------------------------------------------------
    def to_mapping(self) -> dict[str, Any]:
        """The resolved assembly as a TOML-ready table (:meth:`from_mapping` reads it back
        to an equal assembly)."""
        rods: dict[str, Any] = {}
        for name, p in self.rods.items():
            t = p.to_mapping()
            for key in ("name", "description", "loads", "simulation", "statics", "analysis",
                        "obstacles", "contact"):
                t.pop(key, None)
            own = {k: v for k, v in t.pop("materials", {}).items()
                   if self.materials.get(k) != v}
            if own:
                t["materials"] = own
            rods[name] = t
        out: dict[str, Any] = {"name": self.name, "description": self.description,
                               "rods": rods}
        if self.materials:
            out["materials"] = copy.deepcopy(dict(self.materials))
        out["joints"] = [j.to_mapping() for j in self.joints]
        out["bodies"] = [b.to_mapping() for b in self.bodies]
        out["loads"] = [ld.to_mapping() for ld in self.loads]
        out["simulation"] = {k: v for k, v in vars(self.simulation).items() if v is not None}
        out["statics"] = {"load_steps": self.statics.load_steps,
                          **({"report": list(self.statics.report)}
                             if self.statics.report else {})}
        out["analysis"] = self.analysis.to_mapping()
        if self.obstacles:              # an assembly without contact writes what it did
            out["obstacles"] = [o.to_mapping() for o in self.obstacles]
        if self.contact is not None:
            out["contact"] = self.contact.to_mapping()
        return out

    @classmethod
    def from_mapping(cls, m: Mapping[str, Any], base: Path | None = None,
                     name: str = "assembly") -> Assembly:
        """Build and check an assembly from a TOML table (see the module docstring);
        every error names its key path (``joints[1].between[0]``, ``rods.arm.rod.length``)."""
        m = C.table("", m)
        rods_m = m.get("rods")
        first = next(iter(rods_m), "NAME") if isinstance(rods_m, Mapping) else "NAME"
        for key in PER_ROD:
            if key in m:
                table = f"[[{key}]]" if key == "zones" else f"[{key}]"
                where = f"[[rods.{first}.zones]]" if key == "zones" else f"[rods.{first}.{key}]"
                raise ParameterError(key, m[key], f"no {table} beside [rods]: in an assembly "
                                     f"it goes into each rod's table, rods.NAME.{key} (here "
                                     f"{where})")
        C.no_unknown_keys("", m, ASSEMBLY_TOP_KEYS)
        rods_m = C.table("rods", rods_m)
        if not rods_m:
            raise ParameterError("rods", {}, "at least one rod: a [rods.NAME] table")
        tables: dict[str, Mapping[str, Any]] = {}
        geometry: dict[str, Geometry] = {}
        for rod, t in rods_m.items():
            if not isinstance(rod, str) or not NAME_RE.match(rod) or rod == GROUND:
                raise ParameterError(f"rods.{rod}", rod, "a rod name of letters, digits, _ "
                                     "and - starting with a letter or _, not 'ground'")
            t = C.table(f"rods.{rod}", t)
            for key in ("obstacles", "contact"):
                if key in t:
                    raise ParameterError(f"rods.{rod}.{key}", t[key], f"no {key} in a rod's "
                                         f"table: [{key}] stays at the top of an assembly file "
                                         "and acts on every rod (contact.radius = {"
                                         f"{rod} = ...}} sets one rod's contact radius)")
            for key in ("loads", "simulation", "statics", "analysis", "joints", "bodies"):
                if key in t:
                    raise ParameterError(f"rods.{rod}.{key}", t[key], f"no {key} in a rod's "
                                         f"table: [{key}] stays at the top of an assembly "
                                         "file (a load acts on every rod, on those of rods "
                                         f"= [...], or at a point: at = \"{rod}.end\")")
            C.no_unknown_keys(f"rods.{rod}", t, ROD_KEYS)
            tables[rod] = t
            geometry[rod] = _rod_geometry(rod, t, base)
        lengths = {rod: g.length for rod, g in geometry.items()}

        simulation = _settings(Simulation, "simulation", m.get("simulation"))
        statics = _settings(Statics, "statics", m.get("statics"))
        joints = _list_of(m, "joints", "joints", lambda k, j: _joint(k, j, lengths))
        _check_joints(joints, geometry)
        bodies = _list_of(m, "bodies", "bodies", lambda k, b: _body(k, b, lengths))
        seen: dict[str, int] = {}
        for b in bodies:
            if b.name in seen:
                raise ParameterError(f"bodies[{b.index}].name", b.name, "a name not used by "
                                     f"another body (bodies[{seen[b.name]}] has it)")
            seen[b.name] = b.index
        loads = _list_of(m, "loads", "loads", lambda k, ld: _load(k, ld, lengths, base))
        analysis = _analysis(m.get("analysis"), lengths)
        obstacles = obstacles_from_mapping(m.get("obstacles"), base)
        contact = contact_from_mapping(m.get("contact"), rods=tuple(tables))
        if contact is not None and not obstacles and not contact.self_contact:
            raise ParameterError("contact", contact.to_mapping(), "[contact] only beside "
                                 "[[obstacles]] or with self = true (the rods' contact with "
                                 "each other and themselves): without either it changes "
                                 "nothing (add an obstacle, set contact.self = true, or "
                                 "remove [contact])")

        shared_m = m.get("materials")
        shared: dict[str, Any] = {}
        if shared_m is not None:
            if not any(_uses_composite(t) for t in tables.values()):
                raise ParameterError("materials", shared_m, "[materials.NAME] tables only "
                                     "with a composite section in a rod (rods.NAME.section "
                                     "kind = 'composite', or a zone's), whose regions name "
                                     "them; a homogeneous rod takes its material from "
                                     "rods.NAME.material")
            shared = _resolved_materials(shared_m, "materials")

        named = _named(joints, bodies, loads, analysis)
        rods: dict[str, Problem] = {}
        for rod, t in tables.items():
            doc: dict[str, Any] = {key: v for key, v in t.items() if key != "materials"}
            doc["start"] = t.get("start", "free")
            doc["end"] = t.get("end", "free")
            mine = [ld for ld in loads if ld.acts_on(rod)]
            doc["loads"] = [ld.load.to_mapping() for ld in mine]
            for key in ("simulation", "statics"):
                if m.get(key) is not None:
                    doc[key] = m[key]
            if obstacles:
                doc["obstacles"] = [o.to_mapping() for o in obstacles]
            if contact is not None:
                doc["contact"] = contact.for_rod(rod).to_mapping()
            own = t.get("materials")
            if _uses_composite(t):
                pool = copy.deepcopy(dict(shared_m or {}))
                if own is not None:
                    own = C.table(f"rods.{rod}.materials", own)
                    for k, v in own.items():
                        if k in shared and _resolved_materials(
                                {k: v}, f"rods.{rod}.materials")[k] != shared[k]:
                            raise ParameterError(
                                f"rods.{rod}.materials.{k}", v, f"the table of materials.{k} "
                                "(a material name is defined once: this rod's differs from "
                                "the shared one; give it another name)")
                        pool[k] = v
                doc["materials"] = pool
            elif own is not None:
                doc["materials"] = own
            with _in_rod(rod, tuple(ld.index for ld in mine), tuple(shared)):
                rods[rod] = Problem.from_mapping(doc, base=base, name=rod,
                                                 points=_points_on(named, rod))
        return cls(name=C.string("name", m.get("name", name)),
                   description=str(m.get("description", "")), rods=rods, joints=joints,
                   bodies=bodies, loads=loads, simulation=simulation, statics=statics,
                   analysis=analysis, materials=shared, base=base, obstacles=obstacles,
                   contact=contact)

    def with_overrides(self, overrides: Mapping[str, Any]) -> Assembly:
        """A new assembly with values replaced, all checked as in a file.

        Keys (applied in order): dotted paths through the file's tables
        (``rods.arm.material.youngs_modulus``, ``joints.0.rotational_stiffness``,
        ``bodies.0.mass``, ``loads.1.vector``, ``materials.pvc.tau_S``,
        ``simulation.t_end``); the index one past an array's last entry appends a whole
        entry (``{"joints.2": {"kind": "weld", "between": ["a.end", "ground"]}}``). The
        short aliases of the command line (:data:`~runtime.problem.schema.ALIASES`) set
        their key on every rod (``tau``, ``E``, ``n_elements``, ``width``, ...: each
        rod's ``rods.NAME.material.tau``, ...) or, for the simulation and statics
        settings, once at the top; ``length`` and ``tip_force`` are refused (naming the
        key to set instead)."""
        if not overrides:
            return self
        base_m = self.__dict__.get("_mapping")
        if base_m is None:
            base_m = self.to_mapping()
            object.__setattr__(self, "_mapping", base_m)
        m = copy.deepcopy(base_m)
        used: dict[str, str] = {}
        for key, value in overrides.items():
            for path in apply_assembly_override(m, key, value):
                used[path] = key
        try:
            return Assembly.from_mapping(m, base=self.base, name=self.name)
        except ParameterError as exc:   # name the value as the caller wrote it
            if exc.name in used and used[exc.name] != exc.name:
                raise ParameterError(f"{used[exc.name]} ({exc.name})", exc.value,
                                     exc.allowed, exc.where) from None
            raise


def _list_of(m: Mapping[str, Any], key: str, what: str, parse) -> tuple:
    v = m.get(key, [])
    if not isinstance(v, list):
        raise ParameterError(key, v, f"an array of tables [[{what}]]")
    return tuple(parse(k, x) for k, x in enumerate(v))


def _named(joints, bodies, loads, analysis) -> tuple[Point, ...]:
    out: list[Point] = []
    for j in joints:
        out += [j.first] + ([j.second] if j.second is not None else [])
    out += [b.at for b in bodies]
    out += [ld.point for ld in loads if ld.point is not None]
    if analysis.point is not None:
        out.append(analysis.point)
    return tuple(out)


def _points_on(points: tuple[Point, ...], rod: str) -> tuple[float, ...]:
    return tuple(sorted({p.s for p in points if p.rod == rod}))


def _rod_load_indices(loads: tuple[AssemblyLoad, ...], rod: str) -> tuple[int, ...]:
    return tuple(ld.index for ld in loads if ld.acts_on(rod))


def _same_place(p: Point, q: Point, lengths: Mapping[str, float]) -> bool:
    return p.rod == q.rod and abs(p.s - q.s) <= NODE_SNAP_RTOL * lengths[p.rod]


def _check_joints(joints: tuple[Joint, ...], geometry: Mapping[str, Geometry]) -> None:
    """Each joint's points coincide in the reference configuration (within
    ``COINCIDE_RTOL`` of the longest rod), differ, and no two joints hold the same
    pair of points or the same point to ground."""
    lengths = {n: g.length for n, g in geometry.items()}
    tol = COINCIDE_RTOL * max(lengths.values())
    for j in joints:
        path = f"joints[{j.index}].between"
        if j.second is None:
            continue
        if _same_place(j.first, j.second, lengths):
            raise ParameterError(f"{path}[1]", j.second.label, f"a point other than "
                                 f"between[0] = {j.first.label!r} (a joint of a point with "
                                 "itself holds nothing)")
        a = geometry[j.first.rod].position(j.first.s)
        b = geometry[j.second.rod].position(j.second.s)
        d = float(np.linalg.norm(a - b))
        if d > tol:
            fmt = lambda r: "(" + ", ".join(f"{v:.6g}" for v in r) + ")"  # noqa: E731
            raise ParameterError(path, [j.first.label, j.second.label], "two points at the "
                                 "same place in the reference configuration: "
                                 f"{j.first.label} is at {fmt(a)} m, {j.second.label} at "
                                 f"{fmt(b)} m, {d:.6g} m apart (tolerance {tol:.3g} m); "
                                 "place the rods with rods.NAME.rod.geometry.origin")
    for n, j in enumerate(joints):
        for i in joints[:n]:
            if j.second is None and i.second is None:
                same = _same_place(i.first, j.first, lengths)
            elif j.second is not None and i.second is not None:
                same = ((_same_place(i.first, j.first, lengths)
                         and _same_place(i.second, j.second, lengths))
                        or (_same_place(i.first, j.second, lengths)
                            and _same_place(i.second, j.first, lengths)))
            else:
                same = False
            if same:
                what = ("the same point to ground" if j.second is None
                        else "the same two points")
                raise ParameterError(f"joints[{j.index}].between", j.to_mapping()["between"],
                                     f"points not joined already: joints[{i.index}] "
                                     f"({i.kind}) holds {what} (a second joint is redundant; "
                                     "give one joint, or a spring for both)")


# -- overrides ------------------------------------------------------------------------------
def apply_assembly_override(m: dict[str, Any], key: str, value: Any) -> list[str]:
    """Set ``key`` in the assembly mapping ``m`` in place (see
    :meth:`Assembly.with_overrides`); returns the dotted paths set (one per rod for a
    broadcast alias), the names a refused value is reported under."""
    rods = m.setdefault("rods", {})
    if key in ALIASES:
        if key in REFUSED_ALIASES:
            raise ParameterError(key, value, "not for an assembly: set "
                                 + REFUSED_ALIASES[key])
        path = ALIASES[key]
        if path.split(".")[0] in TOP_ALIAS_TABLES:
            return [apply_override(m, path, value)]
        out = []
        for rod, t in rods.items():
            if not isinstance(t, dict):
                continue
            out.append(f"rods.{rod}.{apply_override(t, path, value)}")
        return out
    parts = key.split(".")
    if not all(parts):
        raise ParameterError(key, value, "a dotted path without empty parts (e.g. "
                             "rods.arm.material.tau)")
    if parts[0] == "rods" and len(parts) >= 3:
        rod, rest = parts[1], ".".join(parts[2:])
        if rod not in rods or not isinstance(rods[rod], dict):
            raise ParameterError(key, value, "a path through a rod of the assembly: "
                                 + ", ".join(rods))
        if parts[2] not in ROD_KEYS:
            raise ParameterError(key, value, f"rods.{rod}.KEY... with KEY one of "
                                 + ", ".join(ROD_KEYS))
        return [f"rods.{rod}.{apply_override(rods[rod], rest, value)}"]
    if parts[0] not in ASSEMBLY_TOP_KEYS:
        raise ParameterError(key, value, "a dotted path (e.g. rods.arm.material.tau, "
                             "joints.0.rotational_stiffness), a top-level key ("
                             + ", ".join(ASSEMBLY_TOP_KEYS) + ") or one of the aliases "
                             "set on every rod: " + ", ".join(sorted(
                                 k for k in ALIASES if k not in REFUSED_ALIASES)))
    if len(parts) == 1:
        m[key] = copy.deepcopy(value)
        return [key]
    if parts[0] == "rods":                       # rods.NAME: a whole rod (new or replaced)
        rods[parts[1]] = copy.deepcopy(value)
        return [key]
    return [apply_override(m, key, value)]
