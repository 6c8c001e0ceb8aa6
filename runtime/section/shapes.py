"""Shapes of section regions, in the section's (x1, x2) along (d1, d2); lengths in m.

``circle`` (``radius``, ``centre``), ``rectangle`` (``width`` along d1, ``height`` along
d2, ``centre``, ``angle`` in degrees, counterclockwise from d1), ``ellipse`` (half axis
``a`` along d2, ``b`` along d1, as kvrod's ellipse section; ``centre``, ``angle``),
``tube`` (``inner_radius``, ``outer_radius``, ``centre``), ``polygon`` (``points``
[[x1, x2], ...] and optional ``holes`` [[[x1, x2], ...], ...]). ``centre`` defaults to
[0, 0].

A shape gives a shapely polygon at a mesh size h (curves as polygons with about one vertex
per h) and its curved boundaries, on which the mesh's nodes are then put exactly
(isoparametric quadratic elements).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import shapely
from shapely.geometry import Polygon

from runtime.errors import ParameterError
from runtime.section import _checks as ck


@dataclass(frozen=True)
class Curve:
    """An ellipse (circle when a = b) x = c + b cos(t) e_b + a sin(t) e_a, with
    e_b = (cos angle, sin angle) and e_a = (-sin angle, cos angle), drawn with n straight
    segments at t = 2 pi k / n."""

    centre: tuple[float, float]
    b: float
    a: float
    angle: float
    n: int

    def scaled(self, xy: np.ndarray) -> np.ndarray:
        """Coordinates in the frame where the curve is the unit circle (n, 2)."""
        c, s = math.cos(self.angle), math.sin(self.angle)
        d = xy - np.asarray(self.centre)
        return np.column_stack([(c * d[:, 0] + s * d[:, 1]) / self.b,
                                (-s * d[:, 0] + c * d[:, 1]) / self.a])

    def unscaled(self, uv: np.ndarray) -> np.ndarray:
        c, s = math.cos(self.angle), math.sin(self.angle)
        u, v = uv[:, 0] * self.b, uv[:, 1] * self.a
        return np.column_stack([self.centre[0] + c * u - s * v, self.centre[1] + s * u + c * v])

    def vertices(self) -> np.ndarray:
        t = 2.0 * np.pi * np.arange(self.n) / self.n
        return self.unscaled(np.column_stack([np.cos(t), np.sin(t)]))

    def snap(self, xy: np.ndarray) -> np.ndarray:
        """Move the points lying on the polygon of this curve (between its chords and the
        curve) onto the curve; others are returned unchanged."""
        uv = self.scaled(xy)
        r = np.hypot(uv[:, 0], uv[:, 1])
        inner = math.cos(math.pi / self.n)
        on = (r > inner * (1.0 - 1e-9)) & (r < 1.0 + 1e-9)
        out = xy.copy()
        if np.any(on):
            out[on] = self.unscaled(uv[on] / r[on, None])
        return out


def _segments(length: float, h: float, minimum: int = 16) -> int:
    n = max(minimum, int(math.ceil(length / h)))
    return 4 * int(math.ceil(n / 4))


def _ellipse_perimeter(a: float, b: float) -> float:
    h = ((a - b) / (a + b)) ** 2
    return math.pi * (a + b) * (1 + 3 * h / (10 + math.sqrt(4 - 3 * h)))   # Ramanujan


@dataclass(frozen=True)
class Circle:
    radius: float
    centre: tuple[float, float] = (0.0, 0.0)
    kind: str = "circle"

    def curves(self, h: float) -> tuple[Curve, ...]:
        return (Curve(self.centre, self.radius, self.radius, 0.0,
                      _segments(2 * math.pi * self.radius, h)),)

    def polygon(self, h: float) -> Polygon:
        return Polygon(self.curves(h)[0].vertices())

    @property
    def area(self) -> float:
        return math.pi * self.radius**2

    def to_mapping(self) -> dict[str, Any]:
        return {"kind": self.kind, "radius": self.radius, "centre": list(self.centre)}


@dataclass(frozen=True)
class Ellipse:
    a: float            # half axis along d2 (before the angle)
    b: float            # half axis along d1
    centre: tuple[float, float] = (0.0, 0.0)
    angle: float = 0.0  # degrees
    kind: str = "ellipse"

    def curves(self, h: float) -> tuple[Curve, ...]:
        return (Curve(self.centre, self.b, self.a, math.radians(self.angle),
                      _segments(_ellipse_perimeter(self.a, self.b), h)),)

    def polygon(self, h: float) -> Polygon:
        return Polygon(self.curves(h)[0].vertices())

    @property
    def area(self) -> float:
        return math.pi * self.a * self.b

    def to_mapping(self) -> dict[str, Any]:
        return {"kind": self.kind, "a": self.a, "b": self.b, "centre": list(self.centre),
                "angle": self.angle}


@dataclass(frozen=True)
class Tube:
    inner_radius: float
    outer_radius: float
    centre: tuple[float, float] = (0.0, 0.0)
    kind: str = "tube"

    def curves(self, h: float) -> tuple[Curve, ...]:
        return tuple(Curve(self.centre, r, r, 0.0, _segments(2 * math.pi * r, h))
                     for r in (self.outer_radius, self.inner_radius))

    def polygon(self, h: float) -> Polygon:
        outer, inner = self.curves(h)
        return Polygon(outer.vertices(), [inner.vertices()[::-1]])

    @property
    def area(self) -> float:
        return math.pi * (self.outer_radius**2 - self.inner_radius**2)

    def to_mapping(self) -> dict[str, Any]:
        return {"kind": self.kind, "inner_radius": self.inner_radius,
                "outer_radius": self.outer_radius, "centre": list(self.centre)}


@dataclass(frozen=True)
class Rectangle:
    width: float        # along d1 (before the angle)
    height: float       # along d2
    centre: tuple[float, float] = (0.0, 0.0)
    angle: float = 0.0  # degrees
    kind: str = "rectangle"

    def curves(self, h: float) -> tuple[Curve, ...]:
        return ()

    def polygon(self, h: float) -> Polygon:
        w, t = self.width / 2, self.height / 2
        c, s = math.cos(math.radians(self.angle)), math.sin(math.radians(self.angle))
        pts = [(x * c - y * s + self.centre[0], x * s + y * c + self.centre[1])
               for x, y in ((-w, -t), (w, -t), (w, t), (-w, t))]
        return Polygon(pts)

    @property
    def area(self) -> float:
        return self.width * self.height

    def to_mapping(self) -> dict[str, Any]:
        return {"kind": self.kind, "width": self.width, "height": self.height,
                "centre": list(self.centre), "angle": self.angle}


@dataclass(frozen=True)
class PolygonShape:
    points: tuple[tuple[float, float], ...]
    holes: tuple[tuple[tuple[float, float], ...], ...] = ()
    kind: str = "polygon"

    def curves(self, h: float) -> tuple[Curve, ...]:
        return ()

    def polygon(self, h: float) -> Polygon:
        return shapely.orient_polygons(Polygon(self.points, list(self.holes)))

    @property
    def area(self) -> float:
        return float(Polygon(self.points, list(self.holes)).area)

    def to_mapping(self) -> dict[str, Any]:
        out: dict[str, Any] = {"kind": self.kind, "points": [list(p) for p in self.points]}
        if self.holes:
            out["holes"] = [[list(p) for p in h] for h in self.holes]
        return out


Shape = Circle | Ellipse | Tube | Rectangle | PolygonShape
KINDS = ("circle", "rectangle", "ellipse", "tube", "polygon")
_KEYS = {"circle": ("kind", "radius", "centre"),
         "rectangle": ("kind", "width", "height", "centre", "angle"),
         "ellipse": ("kind", "a", "b", "centre", "angle"),
         "tube": ("kind", "inner_radius", "outer_radius", "centre"),
         "polygon": ("kind", "points", "holes")}


def shape_from_mapping(m: Any, path: str = "shape") -> Shape:
    """A shape from a table ``{ kind = ..., ... }`` (see the module docstring); errors name
    the key path, e.g. ``section.regions[1].shape.radius``."""
    m = ck.table(path, m)
    kind = m.get("kind")
    if kind not in KINDS:
        raise ParameterError(f"{path}.kind", kind, "one of " + ", ".join(map(repr, KINDS)))
    ck.no_unknown_keys(path, m, _KEYS[kind])
    centre = ck.point(f"{path}.centre", m.get("centre", (0.0, 0.0)))

    def length(key: str) -> float:
        ck.required(path, m, key, f"a length in m (> 0) for a {kind}")
        return ck.length(f"{path}.{key}", m[key])

    angle = ck.number(f"{path}.angle", m.get("angle", 0.0), "an angle in degrees")
    if kind == "circle":
        return Circle(length("radius"), centre)
    if kind == "rectangle":
        return Rectangle(length("width"), length("height"), centre, angle)
    if kind == "ellipse":
        return Ellipse(length("a"), length("b"), centre, angle)
    if kind == "tube":
        ro = length("outer_radius")
        ck.required(path, m, "inner_radius", "a length in m, 0 < inner_radius < outer_radius")
        ri = ck.number(f"{path}.inner_radius", m["inner_radius"],
                       f"a length in m, 0 < inner_radius < outer_radius = {ro:g} m",
                       low=0.0, high=ro, low_incl=False, high_incl=False)
        return Tube(ri, ro, centre)
    pts = ck.points(f"{path}.points", ck.required(path, m, "points",
                                                  "a list of at least 3 points [[x1, x2], ...]"))
    holes_in = m.get("holes", [])
    if isinstance(holes_in, (str, bytes)) or not hasattr(holes_in, "__len__"):
        raise ParameterError(f"{path}.holes", holes_in, "a list of point lists")
    holes = tuple(ck.points(f"{path}.holes[{i}]", hh) for i, hh in enumerate(holes_in))
    poly = Polygon(pts, list(holes))
    if not poly.is_valid or poly.area <= 0.0:
        reason = shapely.is_valid_reason(poly)
        raise ParameterError(f"{path}.points", [list(p) for p in pts], "a simple polygon of "
                             f"positive area with its holes inside ({reason})")
    return PolygonShape(pts, holes)
