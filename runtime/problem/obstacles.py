"""Obstacles and the contact law of a problem (issue 32): ``[[obstacles]]`` and ``[contact]``.

Obstacles are rigid bodies the rods touch (``[[obstacles]]``, each with ``kind``):

* ``plane``: ``point`` (m) on it and ``normal`` (toward the free side);
* ``sphere``: ``centre`` (m) and ``radius`` (m);
* ``cylinder``: ``point`` (m) on the axis, ``axis``, ``radius`` (m), optional ``length``
  (m, from the point along the axis; without it the cylinder is infinite) and ``inside``
  (``true``: a pipe the rod runs inside; ``false``, the default: a solid the rod lies on).

Each may carry ``friction`` (Coulomb coefficient, default 0) and ``motion``, a prescribed
rigid motion with the keys of an end's motion (``runtime.problem.loads.
motion_from_mapping``): the obstacle's point (a sphere's centre) moves by ``translation``
times ``translation_time``, and the obstacle turns by ``rotation_angle`` (degrees) times
``rotation_time`` about ``rotation_axis`` through that moving point. A material point X
of the obstacle (reference position) is at ``c(t) + R(t) (X - c0)`` at time t, with c0
the point, ``c(t) = c0 + translation f(t)`` and R(t) the rotation (:meth:`Obstacle.pose`).

``[contact]`` sets the law (:class:`Contact`): the rod's contact ``radius``, rod-rod and
self contact (``self``), the smoothing length ``penetration``, the friction's
regularization ``slip_velocity``, the normal ``restitution`` and an optional
``stiffness``; :class:`ContactLaw` holds the numbers of one rod with the default rules
applied (:func:`contact_law`). docs/design.md, "Obstacles and the contact law", has the
reasons for the defaults.

This module knows nothing of the kernels; the signed distances here (reference pose,
positive on the free side) are the definitions the kernels implement and what the
starts-inside check and the tests use.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

from runtime.errors import ParameterError
from runtime.model.quaternion import quat_exp, quat_rotation
from runtime.problem import coerce as C
from runtime.problem.loads import Motion, motion_from_mapping
from runtime.problem.sections import LENGTH_MAX, Composite, Shape
from runtime.problem.timefunctions import TimeFunction

OBSTACLE_KINDS = ("plane", "sphere", "cylinder")
#: the keys of each kind's table, in the order to_mapping writes them
OBSTACLE_KEYS: dict[str, tuple[str, ...]] = {
    "plane": ("kind", "point", "normal", "friction", "motion"),
    "sphere": ("kind", "centre", "radius", "friction", "motion"),
    "cylinder": ("kind", "point", "axis", "radius", "length", "inside", "friction", "motion"),
}
#: the keys each kind requires
REQUIRED: dict[str, tuple[tuple[str, str], ...]] = {
    "plane": (("point", "a point on the plane: 3 finite numbers (m)"),
              ("normal", "the plane's normal, toward the free side: 3 finite numbers, "
                         "not all 0")),
    "sphere": (("centre", "the sphere's centre: 3 finite numbers (m)"),
               ("radius", "the sphere's radius in m, > 0")),
    "cylinder": (("point", "a point on the cylinder's axis: 3 finite numbers (m)"),
                 ("axis", "the cylinder's axis: 3 finite numbers, not all 0"),
                 ("radius", "the cylinder's radius in m, > 0")),
}
#: a key given to a kind that has no such key: what that kind has instead
_MISPLACED: dict[tuple[str, str], str] = {
    ("plane", "axis"): "a plane has a normal (normal = [x, y, z]), not an axis",
    ("plane", "centre"): "a plane is placed by a point on it (point = [x, y, z])",
    ("plane", "radius"): "only for a sphere or a cylinder (a plane has no radius)",
    ("plane", "inside"): "only for kind = 'cylinder' (inside = true: a pipe the rod runs "
                         "inside; a plane's free side is the side its normal points to)",
    ("plane", "length"): "only for kind = 'cylinder' (a plane is unbounded)",
    ("sphere", "point"): "a sphere is placed by its centre (centre = [x, y, z])",
    ("sphere", "normal"): "a sphere has no normal (only centre and radius)",
    ("sphere", "axis"): "a sphere has no axis (only centre and radius)",
    ("sphere", "inside"): "only for kind = 'cylinder' (a rod inside a sphere is not "
                          "supported: the sphere is a solid ball the rod touches from "
                          "outside)",
    ("sphere", "length"): "only for kind = 'cylinder' (a sphere has no length)",
    ("cylinder", "normal"): "a cylinder has an axis (axis = [x, y, z]), not a normal",
    ("cylinder", "centre"): "a cylinder is placed by a point on its axis (point = [x, y, z])",
}
#: largest Coulomb coefficient accepted (real pairs of materials stay below about 5;
#: beyond 100 a contact cannot slip at any angle a rod takes against it)
FRICTION_MAX = 100.0

#: the default ``[contact]`` settings (docs/design.md, "Obstacles and the contact law")
#: the largest default smoothing length delta of the law, as a fraction of the rod's
#: contact radius (default_penetration: below it, the penetration under the rod's weight)
PENETRATION_FRACTION = 0.002
#: m/s^2: the pressure scale rho A g of the default penetration without gravity
STANDARD_GRAVITY = 9.80665
#: the friction's regularization (m/s): a rod held by static friction creeps at about
#: slip_velocity * f_t / (mu f_n) < slip_velocity, 0.1 mm/s (under 1 mm in 10 s)
SLIP_VELOCITY = 1.0e-4
#: the coefficient of restitution of a node's mass on the contact spring (damping ratio
#: 0.59): a rod dropped flat onto a floor rebounds to 1 % of its drop height and rests
RESTITUTION = 0.1
#: k = STIFFNESS_FACTOR EI / h^4: the contact's Winkler length (4 EI / k)^(1/4) is h/2
STIFFNESS_FACTOR = 64.0
CONTACT_KEYS = ("radius", "self", "friction", "penetration", "slip_velocity", "restitution",
                "stiffness")


def _vector_array(v: tuple[float, ...]) -> np.ndarray:
    return np.asarray(v, dtype=float)


class Pose(NamedTuple):
    """An obstacle's rigid motion at one time: ``position`` (3,) m of its point (a
    sphere's centre), ``quaternion`` (4,) (scalar first) of its rotation from the
    reference, ``velocity`` (3,) m/s of its point, ``angular_velocity`` (3,) rad/s
    (spatial)."""

    position: np.ndarray
    quaternion: np.ndarray
    velocity: np.ndarray
    angular_velocity: np.ndarray


@dataclass(frozen=True)
class Obstacle:
    """One ``[[obstacles]]`` entry (``index``: its place there, from 0), checked on
    construction (every error names ``obstacles[index].KEY``).

    ``point`` (3,) m: a point of a plane, the centre of a sphere, a point on a cylinder's
    axis. ``normal`` (plane) and ``axis`` (cylinder): unit vectors (3,) (normalised here;
    None for the other kinds). ``radius`` (m; sphere, cylinder). ``length`` (m; cylinder
    only, None: infinite; else the axis runs from ``point`` to ``point + length axis``).
    ``inside`` (cylinder only): the rod runs inside the pipe. ``friction``: the Coulomb
    coefficient, 0 ... FRICTION_MAX. ``motion``: a prescribed rigid motion
    (``runtime.problem.loads.Motion``) or None.

    The free side: above a plane (where the normal points), outside a sphere, outside a
    solid cylinder (flat end caps when finite), inside a pipe (``inside``; a finite pipe
    acts between its ends only: its rim is not modelled, a point outside that stretch
    touches nothing). :meth:`signed_distance` is positive there.
    """

    index: int
    kind: str
    point: tuple[float, float, float]
    normal: tuple[float, float, float] | None = None
    axis: tuple[float, float, float] | None = None
    radius: float | None = None
    length: float | None = None
    inside: bool = False
    friction: float = 0.0
    motion: Motion | None = None

    def __post_init__(self) -> None:
        path = f"obstacles[{self.index}]"
        kind = C.choice(f"{path}.kind", self.kind, OBSTACLE_KINDS)
        where = "centre" if kind == "sphere" else "point"
        object.__setattr__(self, "point", C.vector(f"{path}.{where}", self.point))
        for key, wanted in (("normal", "plane"), ("axis", "cylinder")):
            v = getattr(self, key)
            if kind == wanted:
                if v is None:
                    raise ParameterError(f"{path}.{key}", None, dict(REQUIRED[kind])[key])
                object.__setattr__(self, key, C.unit_vector(f"{path}.{key}", v))
            elif v is not None:
                raise ParameterError(f"{path}.{key}", list(v), _MISPLACED[(kind, key)])
        if kind == "plane":
            if self.radius is not None:
                raise ParameterError(f"{path}.radius", self.radius,
                                     _MISPLACED[("plane", "radius")])
        else:
            if self.radius is None:
                raise ParameterError(f"{path}.radius", None, dict(REQUIRED[kind])["radius"])
            object.__setattr__(self, "radius", C.number(
                f"{path}.radius", self.radius, low=0.0, low_incl=False, high=LENGTH_MAX,
                allowed=f"a radius in m, > 0 (at most {LENGTH_MAX:g})"))
        if kind != "cylinder":
            if self.length is not None:
                raise ParameterError(f"{path}.length", self.length, _MISPLACED[(kind, "length")])
            if self.inside is not False:
                raise ParameterError(f"{path}.inside", self.inside, _MISPLACED[(kind, "inside")])
        else:
            if self.length is not None:
                object.__setattr__(self, "length", C.number(
                    f"{path}.length", self.length, low=0.0, low_incl=False, high=LENGTH_MAX,
                    allowed="a length in m, > 0, from the point along the axis (left out: "
                            "an infinite cylinder)"))
            object.__setattr__(self, "inside", C.boolean(f"{path}.inside", self.inside))
        object.__setattr__(self, "friction", C.number(
            f"{path}.friction", self.friction, low=0.0, high=FRICTION_MAX,
            allowed=f"a Coulomb coefficient, finite, 0 ... {FRICTION_MAX:g}"))
        if self.motion is not None and not isinstance(self.motion, Motion):
            raise ParameterError(f"{path}.motion", self.motion, "a motion table (translation, "
                                 "translation_time, rotation_axis, rotation_angle, "
                                 "rotation_time)")

    # -- geometry ----------------------------------------------------------------------
    @property
    def centre(self) -> np.ndarray:
        """The reference point (3,) m: a sphere's centre, a plane's or an axis' point."""
        return _vector_array(self.point)

    @property
    def direction(self) -> np.ndarray | None:
        """The unit normal of a plane or axis of a cylinder (3,); None for a sphere."""
        v = self.normal if self.kind == "plane" else self.axis
        return None if v is None else _vector_array(v)

    def signed_distance(self, x: Any, t: float | None = None) -> np.ndarray:
        """The signed distance (m) of the points ``x`` (..., 3) from the obstacle's
        surface, positive on the free side (see the class docstring), of the obstacle at
        its reference pose (``t`` None) or at its pose at time ``t`` (s). A rod of contact
        radius r at x touches where it is below r; a finite pipe gives +inf outside its
        stretch (no contact there). Shape (...)."""
        x = np.asarray(x, dtype=float)
        if t is not None:
            x = self.to_reference(x, t)
        d = x - self.centre
        if self.kind == "plane":
            return d @ self.direction
        if self.kind == "sphere":
            return np.linalg.norm(d, axis=-1) - self.radius
        a = self.direction
        z = d @ a
        rho = np.linalg.norm(d - z[..., None] * a, axis=-1)
        if self.inside:
            out = self.radius - rho
            if self.length is not None:
                out = np.where((z >= 0.0) & (z <= self.length), out, np.inf)
            return out
        dr = rho - self.radius
        if self.length is None:
            return dr
        dz = np.maximum(-z, z - self.length)
        return (np.minimum(np.maximum(dr, dz), 0.0)
                + np.hypot(np.maximum(dr, 0.0), np.maximum(dz, 0.0)))

    # -- motion ------------------------------------------------------------------------
    def _active(self) -> tuple[tuple[TimeFunction, str], ...]:
        mo = self.motion
        if mo is None:
            return ()
        out = []
        if any(mo.translation):
            out.append((mo.translation_time, "translation_time"))
        if mo.rotation_angle != 0.0:
            out.append((mo.rotation_time, "rotation_time"))
        return tuple(out)

    @property
    def moves(self) -> bool:
        """Whether the obstacle has a motion that displaces or turns it."""
        return bool(self._active())

    @property
    def time_dependent(self) -> bool:
        """Whether its pose changes in time (a motion with a non-constant function)."""
        return any(not f.is_constant for f, _ in self._active())

    def time_functions(self) -> tuple[TimeFunction, ...]:
        """The time functions of its motion that act (a zero translation's or angle's
        function does nothing)."""
        return tuple(f for f, _ in self._active())

    def inputs(self) -> list[tuple[TimeFunction, bool]]:
        """(time function, drives a motion = True) pairs in the form of
        ``ProblemDrive._inputs`` (runtime.problem.assemble): the drive's breakpoints and
        step bounds take them as they take an end's motion."""
        return [(f, True) for f in self.time_functions()]

    def breakpoints(self, t0: float, t1: float) -> list[tuple[float, bool]]:
        """Times in ``[t0, t1]`` where the motion is not smooth, sorted, each with whether
        the integrator must restart there: always (its position, velocity or acceleration
        jumps; the contact force depends on the position and the velocity, so an
        acceleration jump is a kink of the force, as a rate jump of a load). Equal times
        appear once; the drive merges them with its other breakpoints."""
        ts = sorted({t for f in self.time_functions() for t, order in f.breakpoints(t0, t1)
                     if order <= 2})
        return [(t, True) for t in ts]

    def time_scale(self, t: float) -> float:
        """The shortest time (s) over which the motion changes appreciably on its smooth
        piece starting at ``t`` (inf when it does not move there); the run bounds its
        steps by a fraction of it."""
        return min((f.time_scale(t) for f in self.time_functions()), default=math.inf)

    def steady_interval(self, t: float) -> tuple[float, float]:
        """``(a, b)``, ``a <= t < b``, on which the pose is constant (empty when it
        changes at ``t``)."""
        a, b = -math.inf, math.inf
        for f in self.time_functions():
            lo, hi = f.constant_interval(t)
            a, b = max(a, lo), min(b, hi)
            if not a <= t < b:
                return t, t
        return a, b

    def pose(self, t: float, left: bool = False) -> Pose:
        """The obstacle's rigid motion at time ``t`` (s; ``left``: the limits from the
        left where a rate jumps): its point's position ``c(t) = point + translation f(t)``
        (m) and velocity ``translation f'(t)`` (m/s), the quaternion ``exp(theta(t) axis /
        2)`` of its rotation from the reference (scalar first; theta = rotation_angle g(t)
        in rad) and its spatial angular velocity ``axis rotation_angle g'(t)`` (rad/s). A
        material point moves with ``v = velocity + angular_velocity x (x - position)``."""
        c, v = self.centre.copy(), np.zeros(3)
        q, om = np.array([1.0, 0.0, 0.0, 0.0]), np.zeros(3)
        mo = self.motion
        if mo is not None:
            tr = np.asarray(mo.translation, dtype=float)
            if any(mo.translation):
                c = c + tr * mo.translation_time.value_at(t, left=left)
                v = tr * mo.translation_time.rate_at(t, left=left)
            if mo.rotation_angle != 0.0:
                axis = np.asarray(mo.rotation_axis, dtype=float)
                ang = math.radians(mo.rotation_angle)
                q = quat_exp(ang * mo.rotation_time.value_at(t, left=left) * axis)
                om = axis * ang * mo.rotation_time.rate_at(t, left=left)
        return Pose(c, q, v, om)

    def to_reference(self, x: Any, t: float) -> np.ndarray:
        """The points ``x`` (..., 3) at time ``t`` carried back to the obstacle's
        reference pose, ``point + R(t)^T (x - c(t))``."""
        c, q, _, _ = self.pose(t)
        R = quat_rotation(q)
        return self.centre + (np.asarray(x, dtype=float) - c) @ R

    # -- mapping -----------------------------------------------------------------------
    def to_mapping(self) -> dict[str, Any]:
        """The ``[[obstacles]]`` table (what :func:`obstacle_from_mapping` reads back)."""
        out: dict[str, Any] = {"kind": self.kind}
        if self.kind == "sphere":
            out["centre"] = list(self.point)
        else:
            out["point"] = list(self.point)
        if self.kind == "plane":
            out["normal"] = list(self.normal)
        if self.kind == "cylinder":
            out["axis"] = list(self.axis)
        if self.radius is not None:
            out["radius"] = self.radius
        if self.kind == "cylinder":
            if self.length is not None:
                out["length"] = self.length
            out["inside"] = self.inside
        out["friction"] = self.friction
        if self.motion is not None:
            out["motion"] = self.motion.to_mapping()
        return out

    def describe(self) -> str:
        """One line for messages and reports."""
        p = ", ".join(f"{v:g}" for v in self.point)
        if self.kind == "plane":
            n = ", ".join(f"{v:g}" for v in self.normal)
            return f"plane through ({p}) m, normal ({n})"
        if self.kind == "sphere":
            return f"sphere of radius {self.radius:g} m about ({p}) m"
        a = ", ".join(f"{v:g}" for v in self.axis)
        what = "pipe" if self.inside else "cylinder"
        extent = "" if self.length is None else f", {self.length:g} m long"
        return f"{what} of radius {self.radius:g} m, axis ({a}) through ({p}) m{extent}"


def obstacle_from_mapping(k: int, m: Any, base: Path | None = None) -> Obstacle:
    """One ``[[obstacles]]`` table (``k``: its index); errors name
    ``obstacles[k].KEY``."""
    path = f"obstacles[{k}]"
    m = C.table(path, m)
    if "kind" not in m:
        raise ParameterError(f"{path}.kind", None, "one of " + ", ".join(
            repr(o) for o in OBSTACLE_KINDS))
    kind = C.choice(f"{path}.kind", m["kind"], OBSTACLE_KINDS)
    for key in m:
        if (kind, key) in _MISPLACED:
            raise ParameterError(f"{path}.{key}", m[key], _MISPLACED[(kind, key)])
    C.no_unknown_keys(path, m, OBSTACLE_KEYS[kind])
    for key, what in REQUIRED[kind]:
        if key not in m:
            raise ParameterError(f"{path}.{key}", None, what)
    kw: dict[str, Any] = {"point": m["centre" if kind == "sphere" else "point"]}
    for key in ("normal", "axis", "radius", "length", "inside", "friction"):
        if key in m:
            kw[key] = m[key]
    if "motion" in m:
        kw["motion"] = motion_from_mapping(f"{path}.motion", m["motion"], base)
    return Obstacle(k, kind, **kw)


def obstacles_from_mapping(value: Any, base: Path | None = None) -> tuple[Obstacle, ...]:
    """The ``[[obstacles]]`` array of tables (None: none)."""
    if value is None:
        return ()
    if isinstance(value, (str, bytes, Mapping)) or not isinstance(value, (list, tuple)):
        raise ParameterError("obstacles", value, "an array of tables [[obstacles]], each "
                             "with kind = 'plane', 'sphere' or 'cylinder'")
    return tuple(obstacle_from_mapping(k, o, base) for k, o in enumerate(value))


# -- the contact law --------------------------------------------------------------------
def damping_ratio(restitution: float) -> float:
    """The damping ratio zeta of a mass on a linear spring and damper that rebounds from
    a rigid wall with the coefficient of restitution e: ``zeta = -ln e / sqrt(pi^2 +
    ln^2 e)`` (e = 1: 0; e -> 0: 1)."""
    le = math.log(restitution)
    return -le / math.hypot(math.pi, le)


@dataclass(frozen=True)
class Contact:
    """The ``[contact]`` settings as given (None: the default rule).

    ``radius`` (m): the rod's contact radius (the radius of the round envelope the
    contact sees about the centreline); None: the outer radius of a circle or tube
    section (a composite section of concentric circles and tubes: the largest), required
    for other sections. In an assembly ``rod_radii`` holds a radius per rod name (the
    table form ``radius = {NAME = r}``), rods not named taking their section's.
    ``self_contact`` (key ``self``): rod-rod contact (in an assembly) and the contact of
    a rod with itself; ``friction``: their Coulomb coefficient (an obstacle has its own,
    ``Obstacle.friction``). ``penetration`` (m): the smoothing length delta of the law (the
    normal force goes from zero to the linear penalty over a gap band of that width) and
    the tolerance of the check that no rod starts inside an obstacle; None: the penetration
    under the rod's own weight, at most 0.2 % of its smallest contact radius
    (``default_penetration``). ``slip_velocity`` (m/s): the friction's
    regularization (full Coulomb friction above it; a rod held by static friction creeps
    at about slip_velocity f_t / (mu f_n)). ``restitution``: the coefficient of
    restitution e in (0, 1] of a node's mass on the contact spring, whose damping ratio
    is :func:`damping_ratio`. ``stiffness`` (N/m^2: force per length per metre of
    penetration); None: ``STIFFNESS_FACTOR EI / h^4`` of each rod (:func:`contact_law`).
    """

    radius: float | None = None
    self_contact: bool = False
    friction: float = 0.0
    penetration: float | None = None
    slip_velocity: float = SLIP_VELOCITY
    restitution: float = RESTITUTION
    stiffness: float | None = None
    rod_radii: tuple[tuple[str, float], ...] = ()

    def __post_init__(self) -> None:
        if self.radius is not None:
            object.__setattr__(self, "radius", _radius("contact.radius", self.radius))
        object.__setattr__(self, "rod_radii", tuple(
            (n, _radius(f"contact.radius.{n}", r)) for n, r in self.rod_radii))
        if self.radius is not None and self.rod_radii:
            raise ParameterError("contact.radius", self.radius, "one radius for every rod "
                                 "or a table of radii per rod, not both")
        object.__setattr__(self, "self_contact", C.boolean("contact.self", self.self_contact))
        object.__setattr__(self, "friction", C.number(
            "contact.friction", self.friction, low=0.0, high=FRICTION_MAX,
            allowed=f"a Coulomb coefficient, finite, 0 ... {FRICTION_MAX:g}"))
        if self.penetration is not None:
            object.__setattr__(self, "penetration", C.number(
                "contact.penetration", self.penetration, low=0.0, low_incl=False,
                high=LENGTH_MAX, allowed="a length in m, > 0 (and at most the contact "
                "radius)"))
        object.__setattr__(self, "slip_velocity", C.number(
            "contact.slip_velocity", self.slip_velocity, low=0.0, low_incl=False,
            allowed="a speed in m/s, finite, > 0"))
        object.__setattr__(self, "restitution", C.number(
            "contact.restitution", self.restitution, low=0.0, low_incl=False, high=1.0,
            allowed="a coefficient of restitution in (0, 1] (1: no damping; toward 0: "
                    "critical damping)"))
        if self.stiffness is not None:
            object.__setattr__(self, "stiffness", C.number(
                "contact.stiffness", self.stiffness, low=0.0, low_incl=False,
                allowed="a stiffness in N/m^2 (force per length per metre of "
                        "penetration), finite, > 0"))

    @property
    def damping_ratio(self) -> float:
        """zeta of ``restitution`` (:func:`damping_ratio`)."""
        return damping_ratio(self.restitution)

    def radius_of(self, rod: str | None = None) -> float | None:
        """The given contact radius of the rod named ``rod`` (None: its section's)."""
        if self.radius is not None:
            return self.radius
        return dict(self.rod_radii).get(rod) if rod is not None else None

    def to_mapping(self) -> dict[str, Any]:
        """The ``[contact]`` table (keys of the default rules only where given)."""
        out: dict[str, Any] = {}
        if self.radius is not None:
            out["radius"] = self.radius
        elif self.rod_radii:
            out["radius"] = dict(self.rod_radii)
        out["self"] = self.self_contact
        out["friction"] = self.friction
        if self.penetration is not None:
            out["penetration"] = self.penetration
        out["slip_velocity"] = self.slip_velocity
        out["restitution"] = self.restitution
        if self.stiffness is not None:
            out["stiffness"] = self.stiffness
        return out

    def for_rod(self, rod: str) -> Contact:
        """The settings of one rod of an assembly (its radius alone)."""
        return Contact(self.radius_of(rod), self.self_contact, self.friction,
                       self.penetration, self.slip_velocity, self.restitution,
                       self.stiffness)


def _radius(path: str, v: Any) -> float:
    return C.number(path, v, low=0.0, low_incl=False, high=LENGTH_MAX,
                    allowed="a contact radius in m, > 0 (the radius of the round envelope "
                            "the contact sees about the centreline)")


def contact_from_mapping(m: Any, rods: Sequence[str] | None = None) -> Contact | None:
    """The ``[contact]`` table (None when absent). ``rods``: the rod names of an
    assembly, whose ``radius`` may be a table {NAME = r}."""
    if m is None:
        return None
    m = C.table("contact", m)
    C.no_unknown_keys("contact", m, CONTACT_KEYS)
    kw: dict[str, Any] = {}
    if "radius" in m:
        r = m["radius"]
        if isinstance(r, Mapping):
            if rods is None:
                raise ParameterError("contact.radius", dict(r), "a contact radius in m, > 0 "
                                     "(a table of radii per rod only in an assembly)")
            for name in r:
                if name not in rods:
                    raise ParameterError(f"contact.radius.{name}", r[name], "a radius of a "
                                         "rod of the assembly: " + ", ".join(rods))
            kw["rod_radii"] = tuple((str(n), v) for n, v in r.items())
        else:
            kw["radius"] = r
    if "self" in m:
        kw["self_contact"] = m["self"]
    for key in ("friction", "penetration", "slip_velocity", "restitution", "stiffness"):
        if key in m:
            kw[key] = m[key]
    return Contact(**kw)


#: what a section without an outer radius needs
RADIUS_REQUIRED = ("the rod's contact radius in m, > 0: required for a {what} (it has no "
                   "outer radius; a circle or tube section, or a composite of concentric "
                   "circles and tubes, takes its outer radius): the radius of the round "
                   "envelope the contact sees about the centreline")


def outer_radius(section: Any, x: np.ndarray) -> np.ndarray | None:
    """The outer radius (m) of a section at the fractions ``x`` of its length (a linear
    taper), or None where the section has none: a circle's radius, a tube's outer radius,
    the largest outer radius of a composite whose regions are all circles and tubes
    about one centre (the elastic centroid, the centreline, is that centre by symmetry)."""
    x = np.asarray(x, dtype=float)
    if isinstance(section, Shape):
        if section.kind == "circle":
            return section.dimensions_at(x)["radius"]
        if section.kind == "tube":
            return section.dimensions_at(x)["outer_radius"]
        return None
    if isinstance(section, Composite):
        from runtime.section.shapes import Circle, Tube

        shapes = [r.shape for r in section.regions]
        if not all(isinstance(s, (Circle, Tube)) for s in shapes):
            return None
        centres = {tuple(float(c) for c in s.centre) for s in shapes}
        if len(centres) != 1:
            return None
        r = max(s.radius if isinstance(s, Circle) else s.outer_radius for s in shapes)
        return np.full(x.shape, float(r))
    return None


def section_label(section: Any) -> str:
    """How an error calls a section without an outer radius."""
    if isinstance(section, Composite):
        return "composite section whose regions are not concentric circles and tubes"
    return f"{getattr(section, 'kind', 'given')} section"


@dataclass(frozen=True, eq=False)
class ContactLaw:
    """The contact law of one rod with the default rules applied (what the kernels get).

    ``radius`` (N,) m: the contact radius of each segment (the outer radius at its
    midpoint, or the given one). ``penetration`` (m): the smoothing length delta.
    ``stiffness`` (N/m^2): the penalty per length and metre of penetration,
    ``STIFFNESS_FACTOR min(EI) / h_min^4`` unless given (EI: the softer bending stiffness
    of the rod's softest segment, N m^2; h_min: its shortest element, m).
    ``damping`` (N,) N s/m^2: the normal damping per length of each segment, ``2 zeta
    sqrt(stiffness rhoA)`` (zeta: ``damping_ratio``, rhoA: the segment's mass per length,
    kg/m; :func:`normal_damping`). ``slip_velocity`` (m/s), ``restitution``,
    ``self_contact`` and ``friction`` (its Coulomb coefficient) as given.
    ``self_penetration`` (m): delta of the rod's contact with itself: the given
    ``penetration``, else ``PENETRATION_FRACTION`` of the smallest contact radius (the
    weight rule of ``default_penetration`` is about a rod laid on a floor; between
    the rod's own strands it would make delta nanometres and the steps that resolve
    every touch as short)."""

    radius: np.ndarray
    penetration: float
    stiffness: float
    damping: np.ndarray
    damping_ratio: float
    slip_velocity: float
    restitution: float
    self_contact: bool
    friction: float
    self_penetration: float = 0.0


def normal_damping(stiffness: Any, damping_ratio: float, mass_per_length: Any) -> Any:
    """The normal damping per length ``c = 2 zeta sqrt(k m)`` (N s/m^2) that gives a mass
    ``m`` per length (kg/m) on the contact stiffness ``k`` (N/m^2) the damping ratio zeta:
    a segment on an obstacle takes its own rhoA; two segments in contact take their
    reduced mass ``m1 m2 / (m1 + m2)`` (the relative motion's)."""
    return 2.0 * damping_ratio * np.sqrt(np.asarray(stiffness, dtype=float)
                                         * np.asarray(mass_per_length, dtype=float))


def default_stiffness(EI: float, h: float) -> float:
    """``STIFFNESS_FACTOR EI / h^4`` (N/m^2): the Winkler length of the contact, ``(4 EI /
    k)^(1/4)``, is h/2. An Euler-Bernoulli beam of weight q per length on a tensionless
    Winkler foundation, lifted at one end by F, leaves it at ``a = 2F/q - l_W`` and its
    end rises by ``(2 x^3 - 3 x^4)`` of the height on a rigid table, ``x = l_W q / (2F)``
    (derived in docs/design.md; checked against a beam finite-element model in
    tests/runtime/test_obstacles.py): 1.7e-3 when the lifted length spans five elements,
    far below the 2 % issue 32 allows."""
    return STIFFNESS_FACTOR * EI / h**4


def default_penetration(radius: np.ndarray, k: float, rhoA: np.ndarray,
                        gravity: float = STANDARD_GRAVITY) -> float:
    """The default smoothing length delta (m): the penetration ``q / k`` under the rod's
    own weight per length q = rho A g (the lightest segment's; g the problem's gravity,
    else standard gravity as a scale of pressure), at most ``PENETRATION_FRACTION`` of the
    smallest contact radius.

    Why the weight: the smooth law carries kappa delta ln 2 at zero gap, so a rod laid
    exactly on a floor (``initial = "reference"``) starts with that force on it, and a rod
    at rest floats at ``delta ln(k delta / q)``. With delta = q / k both are the rod's own
    weight and no float (a 1 cm steel rod on a floor: delta = 1e-11 m; with 1 % of r it
    was thrown off by a force 5e5 times its weight). The radius cap keeps a soft rod's
    float a small share of its radius."""
    radius = np.asarray(radius, dtype=float)
    q = float(np.min(np.asarray(rhoA, dtype=float))) * float(gravity)
    cap = PENETRATION_FRACTION * float(np.min(radius))
    return min(cap, q / k) if q > 0.0 and k > 0.0 else cap


def contact_law(radius: np.ndarray, contact: Contact, EI_min: float, h_min: float,
                rhoA: np.ndarray, gravity: float = 0.0) -> ContactLaw:
    """The law of one rod: ``radius`` (N,) its segments' contact radii (m), ``EI_min``
    (N m^2) its softest bending stiffness, ``h_min`` (m) its shortest element, ``rhoA``
    (N,) kg/m its segments' masses per length, ``gravity`` (m/s^2) the magnitude of the
    problem's gravity (0: none; ``default_penetration`` then takes standard gravity)."""
    gravity = gravity if gravity > 0.0 else STANDARD_GRAVITY
    radius = np.asarray(radius, dtype=float)
    k = contact.stiffness if contact.stiffness is not None else default_stiffness(EI_min,
                                                                                  h_min)
    delta = (contact.penetration if contact.penetration is not None
             else default_penetration(radius, k, rhoA, gravity))
    zeta = contact.damping_ratio
    c = np.asarray(normal_damping(k, zeta, rhoA), dtype=float)
    for a in (radius, c):
        a.setflags(write=False)
    self_delta = (contact.penetration if contact.penetration is not None
                  else PENETRATION_FRACTION * float(np.min(radius)))
    return ContactLaw(radius, delta, float(k), c, zeta, contact.slip_velocity,
                      contact.restitution, contact.self_contact, contact.friction,
                      self_delta)
