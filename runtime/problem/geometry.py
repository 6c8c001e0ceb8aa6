"""Reference centrelines and director frames of a rod (the stress-free configuration).

A geometry gives, at arc length ``s`` in ``[0, L]``, the position ``r(s)`` (m) and the
director frame ``D(s) = [d1, d2, d3]`` (columns; ``d3`` the tangent, ``d1`` the section's
first axis, the width direction of a rectangle). The discrete rod takes node positions
at ``s_i = i L/N``, segment frames at the segment midpoints and clamp frames at the ends
(:func:`discretize`); its intrinsic strains V0, U0 are then computed from this discrete
reference by the kernels' own strain measures (:mod:`runtime.problem.assemble`), so the
reference configuration is exactly stress-free.

Kinds (TOML ``[rod.geometry] kind = ...``): ``straight`` (direction, normal, twist),
``arc`` (radius, angle in degrees, initial direction, curving toward), ``helix`` (coil
radius, pitch, turns, handedness, axis), ``points`` (a polyline or CSV file through which
a smooth curve is drawn; frames by parallel transport). In Python, :class:`Curve` takes
any callable ``s -> position``. Every geometry may add a uniform ``twist`` (rad/m) of the
directors about the tangent, and starts at ``origin`` (default: the origin).
"""

from __future__ import annotations

import csv
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from runtime.errors import ParameterError
from runtime.problem import coerce as C


def _perp(d: np.ndarray, n: np.ndarray | None = None) -> np.ndarray:
    """A unit vector perpendicular to unit ``d`` (``n`` made orthogonal if given)."""
    if n is not None:
        v = n - np.dot(n, d) * d
        if np.linalg.norm(v) > 1e-9:
            return v / np.linalg.norm(v)
    e = np.eye(3)[int(np.argmin(np.abs(d)))]
    v = e - np.dot(e, d) * d
    return v / np.linalg.norm(v)


def _twisted(D: np.ndarray, angle: np.ndarray) -> np.ndarray:
    """Frames (..., 3, 3) rotated about their own d3 by ``angle`` (rad)."""
    c, s = np.cos(angle)[..., None], np.sin(angle)[..., None]
    d1, d2 = D[..., :, 0], D[..., :, 1]
    out = D.copy()
    out[..., :, 0] = c * d1 + s * d2
    out[..., :, 1] = -s * d1 + c * d2
    return out


@dataclass(frozen=True)
class Geometry:
    """Base: ``position(s)`` (..., 3) and ``frame(s)`` (..., 3, 3) for arrays of s."""

    twist: float = 0.0
    origin: tuple[float, float, float] = (0.0, 0.0, 0.0)

    @property
    def length(self) -> float:  # pragma: no cover - every kind overrides it
        raise NotImplementedError

    def _position(self, s: np.ndarray) -> np.ndarray:  # pragma: no cover
        raise NotImplementedError

    def _frame(self, s: np.ndarray) -> np.ndarray:  # pragma: no cover
        raise NotImplementedError

    def position(self, s) -> np.ndarray:
        s = np.asarray(s, dtype=float)
        return self._position(s) + np.asarray(self.origin)

    def frame(self, s) -> np.ndarray:
        s = np.asarray(s, dtype=float)
        D = self._frame(s)
        return _twisted(D, self.twist * s) if self.twist else D

    def to_mapping(self) -> dict[str, Any]:  # pragma: no cover
        raise NotImplementedError


@dataclass(frozen=True)
class Straight(Geometry):
    """A straight rod of ``length`` (m) along ``direction``, first director ``normal``
    (default: e1, or e2 for a rod within about 6 degrees of the x axis, see
    :func:`default_normal`)."""

    rod_length: float = 1.0
    direction: tuple[float, float, float] = (0.0, 0.0, 1.0)
    normal: tuple[float, float, float] | None = None

    def __post_init__(self) -> None:
        C.positive("rod.length", self.rod_length)
        d = np.array(C.unit_vector("rod.geometry.direction", self.direction))
        if self.normal is None:
            object.__setattr__(self, "normal", default_normal(d))
        n = np.array(C.vector("rod.geometry.normal", self.normal, nonzero=True))
        if np.linalg.norm(np.cross(d, n / np.linalg.norm(n))) < 1e-9:
            raise ParameterError("rod.geometry.normal", self.normal,
                                 "a vector not parallel to the direction")

    @property
    def length(self) -> float:
        return self.rod_length

    def _basis(self) -> np.ndarray:
        d = np.array(self.direction) / np.linalg.norm(self.direction)
        n = _perp(d, np.array(self.normal, dtype=float))
        return np.column_stack([n, np.cross(d, n), d])

    def _position(self, s):
        return s[..., None] * self._basis()[:, 2]

    def _frame(self, s):
        return np.broadcast_to(self._basis(), s.shape + (3, 3)).copy()

    def to_mapping(self) -> dict[str, Any]:
        return {"kind": "straight", "direction": list(self.direction),
                "normal": list(self.normal), "twist": self.twist, "origin": list(self.origin)}


def default_normal(direction: np.ndarray) -> tuple[float, float, float]:
    """The first director of a straight rod when none is given: e1, unless the rod runs
    within about 6 degrees of the x axis (|d x e1| < 0.1), then e2 (d1 = e2, d2 = e3 for
    a rod along +x)."""
    d = np.asarray(direction, dtype=float) / np.linalg.norm(direction)
    return (1.0, 0.0, 0.0) if np.linalg.norm(np.cross(d, [1.0, 0.0, 0.0])) >= 0.1 \
        else (0.0, 1.0, 0.0)


@dataclass(frozen=True)
class Arc(Geometry):
    """A circular arc of ``radius`` (m) through ``angle`` (degrees), starting along
    ``direction`` and curving toward ``toward``; ``first_director``: "normal" (d1 toward
    the centre, in the plane) or "binormal" (d1 out of the plane)."""

    radius: float = 1.0
    angle: float = 90.0
    direction: tuple[float, float, float] = (1.0, 0.0, 0.0)
    toward: tuple[float, float, float] = (0.0, 1.0, 0.0)
    first_director: str = "normal"

    def __post_init__(self) -> None:
        C.positive("rod.geometry.radius", self.radius)
        C.number("rod.geometry.angle", self.angle, low=0.0, high=360.0, low_incl=False)
        d = np.array(C.unit_vector("rod.geometry.direction", self.direction))
        w = np.array(C.vector("rod.geometry.toward", self.toward, nonzero=True))
        if np.linalg.norm(np.cross(d, w / np.linalg.norm(w))) < 1e-9:
            raise ParameterError("rod.geometry.toward", self.toward,
                                 "a vector not parallel to the direction")
        C.choice("rod.geometry.first_director", self.first_director, ("normal", "binormal"))

    @property
    def length(self) -> float:
        return self.radius * math.radians(self.angle)

    def _tw(self):
        t0 = np.array(self.direction) / np.linalg.norm(self.direction)
        return t0, _perp(t0, np.array(self.toward, dtype=float))

    def _position(self, s):
        t0, w = self._tw()
        a = s / self.radius
        return self.radius * (np.sin(a)[..., None] * t0 + (1 - np.cos(a))[..., None] * w)

    def _frame(self, s):
        t0, w = self._tw()
        a = s / self.radius
        T = np.cos(a)[..., None] * t0 + np.sin(a)[..., None] * w
        N = -np.sin(a)[..., None] * t0 + np.cos(a)[..., None] * w
        B = np.broadcast_to(np.cross(t0, w), T.shape)
        cols = (N, B, T) if self.first_director == "normal" else (B, -N, T)
        return np.stack(cols, axis=-1)

    def to_mapping(self) -> dict[str, Any]:
        return {"kind": "arc", "radius": self.radius, "angle": self.angle,
                "direction": list(self.direction), "toward": list(self.toward),
                "first_director": self.first_director, "twist": self.twist,
                "origin": list(self.origin)}


@dataclass(frozen=True)
class Helix(Geometry):
    """A helix of ``coil_radius`` R (m) and ``pitch`` (m per turn) about ``axis``,
    ``turns`` turns, ``handedness`` "right" or "left", starting at the origin:
    ``r(phi) = R (cos phi - 1) e1 +/- R sin phi e2 + pitch phi/(2 pi) axis`` with
    ``e1 = radial`` made normal to the axis (the axis passes through ``-R e1``). Frenet
    frame: d1 the principal normal (toward the axis), d2 the binormal, d3 the tangent."""

    coil_radius: float = 0.01
    pitch: float = 0.005
    turns: float = 5.0
    handedness: str = "right"
    axis: tuple[float, float, float] = (0.0, 0.0, 1.0)
    radial: tuple[float, float, float] = (1.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        C.positive("rod.geometry.coil_radius", self.coil_radius)
        C.nonnegative("rod.geometry.pitch", self.pitch)
        C.positive("rod.geometry.turns", self.turns)
        C.choice("rod.geometry.handedness", self.handedness, ("right", "left"))
        a = np.array(C.unit_vector("rod.geometry.axis", self.axis))
        e = np.array(C.vector("rod.geometry.radial", self.radial, nonzero=True))
        if np.linalg.norm(np.cross(a, e / np.linalg.norm(e))) < 1e-9:
            raise ParameterError("rod.geometry.radial", self.radial,
                                 "a vector not parallel to the axis")

    def _basis(self):
        a = np.array(self.axis) / np.linalg.norm(self.axis)
        e1 = _perp(a, np.array(self.radial, dtype=float))
        e2 = np.cross(a, e1) * (1.0 if self.handedness == "right" else -1.0)
        return e1, e2, a

    @property
    def _k(self) -> float:
        b = self.pitch / (2 * math.pi)
        return math.hypot(self.coil_radius, b)

    @property
    def length(self) -> float:
        return 2 * math.pi * self.turns * self._k

    @property
    def helix_angle(self) -> float:
        """Angle of the tangent with the plane normal to the axis (rad)."""
        return math.atan2(self.pitch, 2 * math.pi * self.coil_radius)

    def _position(self, s):
        e1, e2, a = self._basis()
        R, b = self.coil_radius, self.pitch / (2 * math.pi)
        ph = s / self._k
        return (R * (np.cos(ph) - 1)[..., None] * e1 + R * np.sin(ph)[..., None] * e2
                + b * ph[..., None] * a)

    def _frame(self, s):
        e1, e2, a = self._basis()
        R, b, k = self.coil_radius, self.pitch / (2 * math.pi), self._k
        ph = s / k
        T = (-R * np.sin(ph)[..., None] * e1 + R * np.cos(ph)[..., None] * e2
             + b * np.ones_like(ph)[..., None] * a) / k
        N = -np.cos(ph)[..., None] * e1 - np.sin(ph)[..., None] * e2
        B = np.cross(T, N)
        return np.stack((N, B, T), axis=-1)

    def to_mapping(self) -> dict[str, Any]:
        return {"kind": "helix", "coil_radius": self.coil_radius, "pitch": self.pitch,
                "turns": self.turns, "handedness": self.handedness, "axis": list(self.axis),
                "radial": list(self.radial), "twist": self.twist, "origin": list(self.origin)}


@dataclass(frozen=True)
class Curve(Geometry):
    """Any smooth centreline: ``function(s) -> (..., 3)`` positions for arc length ``s``
    in [0, ``curve_length``] (the caller's parametrisation must be by arc length), frames
    by parallel transport of ``normal`` (d1 at s = 0) along the tangent."""

    function: Callable[[np.ndarray], np.ndarray] | None = None
    curve_length: float = 1.0
    normal: tuple[float, float, float] | None = None
    samples: int = 4001
    _table: tuple = field(default=(), repr=False, compare=False)

    def __post_init__(self) -> None:
        C.positive("rod.length", self.curve_length)
        if not callable(self.function):
            raise ParameterError("rod.geometry.function", self.function, "a callable s -> r(s)")
        s = np.linspace(0.0, self.curve_length, int(self.samples))
        r = np.asarray(self.function(s), dtype=float)
        if r.shape != (s.size, 3) or not np.all(np.isfinite(r)):
            raise ParameterError("rod.geometry.function", self.function,
                                 "a function returning finite (len(s), 3) positions")
        t = np.gradient(r, s, axis=0, edge_order=2)
        nt = np.linalg.norm(t, axis=1)
        if np.any(nt < 1e-9):
            raise ParameterError("rod.geometry.function", self.function,
                                 "a regular curve (non-zero tangent)")
        if np.max(np.abs(nt - 1.0)) > 1e-3:
            raise ParameterError("rod.geometry.function", self.function,
                                 f"parametrised by arc length (|r'(s)| = {nt.min():.4g} ... "
                                 f"{nt.max():.4g}, must be 1)")
        t /= nt[:, None]
        n0 = np.array(self.normal, dtype=float) if self.normal is not None else None
        frames = _transport(t, _perp(t[0], n0))
        object.__setattr__(self, "_table", (s, r, frames))

    @property
    def length(self) -> float:
        return self.curve_length

    def _position(self, s):
        ss, r, _ = self._table
        return np.stack([np.interp(s, ss, r[:, k]) for k in range(3)], axis=-1) - r[0]

    def _frame(self, s):
        from scipy.spatial.transform import Rotation, Slerp

        ss, _, D = self._table
        flat = np.clip(np.atleast_1d(np.asarray(s, dtype=float)).ravel(), ss[0], ss[-1])
        # spherical linear interpolation between the transported sample frames (exact
        # at the samples, orthonormal in between)
        F = Slerp(ss, Rotation.from_matrix(D))(flat).as_matrix()
        return F.reshape(np.shape(s) + (3, 3))

    def to_mapping(self) -> dict[str, Any]:
        source = getattr(self, "_source", None)
        if source is None:
            return {"kind": "curve", "function": repr(self.function),
                    "length": self.curve_length, "note": "a Python callable (not for TOML)"}
        return {**source, **({"normal": list(self.normal)} if self.normal is not None
                             else {}), "twist": self.twist, "origin": list(self.origin)}


def _transport(t: np.ndarray, n0: np.ndarray) -> np.ndarray:
    """Rotation-minimising frames along unit tangents ``t`` (M, 3) from d1 = n0."""
    frames = np.empty((t.shape[0], 3, 3))
    d1 = n0 - np.dot(n0, t[0]) * t[0]
    d1 /= np.linalg.norm(d1)
    for k in range(t.shape[0]):
        if k:
            a, b = t[k - 1], t[k]
            v = np.cross(a, b)
            c = float(np.dot(a, b))
            if np.linalg.norm(v) > 1e-15:      # rotate d1 by the rotation taking a to b
                vx = np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])
                Rm = np.eye(3) + vx + vx @ vx / (1 + c)
                d1 = Rm @ d1
            d1 = d1 - np.dot(d1, b) * b
            d1 /= np.linalg.norm(d1)
        frames[k] = np.column_stack([d1, np.cross(t[k], d1), t[k]])
    return frames


def points_curve(points: np.ndarray, normal=None, path: str = "rod.geometry.points",
                 where: list[str] | None = None) -> Curve:
    """A :class:`Curve` through the polyline ``points`` (M, 3): a cubic spline in the chord
    length, re-parametrised by arc length (so its frames and curvature are smooth).

    ``path`` names the points in errors (``rod.geometry.points`` or ``.file``) and
    ``where[k]`` row k ("row 3 (from 0)", "pts.csv line 5"): a polyline whose spline
    folds back (its tangent reverses, so it is no regular curve) is refused naming the
    row where it does.
    """
    from scipy.interpolate import CubicSpline

    P = np.asarray(points, dtype=float)
    if P.ndim != 2 or P.shape[1] != 3 or P.shape[0] < 2 or not np.all(np.isfinite(P)):
        raise ParameterError(path, "points", "at least 2 finite [x, y, z] points")
    where = list(where or []) + [f"row {k} (from 0)" for k in range(len(where or []), len(P))]
    chord = np.linalg.norm(np.diff(P, axis=0), axis=1)
    if np.any(chord <= 0):
        k = int(np.argmax(chord <= 0)) + 1
        raise ParameterError(path, "points", f"distinct consecutive points ({where[k]} "
                             f"repeats the point before it, {list(P[k])})")
    u = np.concatenate([[0.0], np.cumsum(chord)])
    spl = CubicSpline(u, P, bc_type="natural") if P.shape[0] > 2 else None
    fine = np.linspace(0.0, u[-1], 20001)
    if spl is None:
        r_f = P[0] + np.outer(fine / u[-1], P[1] - P[0])
        ds = np.full(fine.size - 1, u[-1] / (fine.size - 1))
    else:
        r_f = spl(fine)
        ds = np.linalg.norm(np.diff(r_f, axis=0), axis=1)
    s_f = np.concatenate([[0.0], np.cumsum(ds)])
    length = float(s_f[-1])

    if spl is not None:
        # the spline in the chord parameter has speed ~1; where it drops toward 0 the
        # curve turns back on itself (a cusp or loop), which no rod reference can follow
        speed = np.linalg.norm(spl(fine, 1), axis=1)
        j = int(np.argmin(speed))
        if speed[j] < 0.5:
            k = int(np.argmin(np.abs(u - fine[j])))
            raise ParameterError(path, "points", "a polyline that does not fold back: the "
                                 f"smooth curve through it reverses near {where[k]} "
                                 f"({', '.join(f'{v:g}' for v in P[k])}); move or remove "
                                 "that point")

    def function(s: np.ndarray) -> np.ndarray:
        uu = np.interp(s, s_f, fine)
        return (spl(uu) if spl is not None else P[0] + np.outer(uu / u[-1], P[1] - P[0])) - P[0]

    try:
        return Curve(function=function, curve_length=length, normal=normal)
    except ParameterError as exc:         # name the points, not the internal callable
        raise ParameterError(path, "points", f"a smooth curve through the points: "
                             f"{exc.allowed}") from None


@dataclass(frozen=True)
class Discrete:
    """The discrete reference: nodes (N+1, 3), segment frames (N, 3, 3), clamp frames at
    s = 0 and s = L (3, 3), segment lengths h (N,) (arc length)."""

    nodes: np.ndarray
    frames: np.ndarray
    start_frame: np.ndarray
    end_frame: np.ndarray
    h: np.ndarray


#: breakpoints closer than this (relative to the rod length) to a uniform node, or to each
#: other, are that node (one breakpoint)
NODE_SNAP_RTOL = 1e-9


def node_arc_lengths(length: float, n_elements: int, breakpoints=(),
                     key: str = "rod.elements") -> np.ndarray:
    """Arc lengths (N+1,) of the nodes (m): ``i L/N`` where no breakpoint asks otherwise,
    else a node at every breakpoint (a zone boundary, a point load's ``s``, a named point
    of an assembly) with the N elements shared among the stretches between them in
    proportion to their lengths (at least one each, largest remainders; uniform inside a
    stretch). Breakpoints within ``NODE_SNAP_RTOL L`` of a uniform node keep the uniform
    grid (bit for bit the rod without them).

    Why not move the nearest node: the elements stay uniform inside each stretch, so a
    stretch keeps the second order of a uniform rod, and nothing depends on which node
    happened to be nearest."""
    N, Lr = int(n_elements), float(length)
    h = Lr / N
    tol = NODE_SNAP_RTOL * Lr
    pts: list[float] = []
    for b in sorted(float(v) for v in breakpoints):
        if tol < b < Lr - tol and (not pts or b - pts[-1] > tol):
            pts.append(b)
    if all(abs(b - round(b / h) * h) <= tol for b in pts):
        return np.arange(N + 1) * h
    edges = np.array([0.0, *pts, Lr])
    lengths = np.diff(edges)
    if lengths.size > N:
        raise ParameterError(key, N, f">= {lengths.size}: a node goes at each of the "
                             f"{lengths.size - 1} zone boundaries, point loads and named "
                             "points, and every stretch between them needs an element")
    share = N * lengths / Lr
    n = np.maximum(np.floor(share).astype(int), 1)
    while n.sum() > N:           # the minimum of one took elements from the long stretches
        k = int(np.argmax(np.where(n > 1, n - share, -np.inf)))
        n[k] -= 1
    order = np.argsort(-(share - n), kind="stable")
    for k in order[: N - int(n.sum())]:
        n[k] += 1
    s = [np.array([0.0])]
    for a, b, m in zip(edges[:-1], edges[1:], n, strict=True):
        s.append(a + (b - a) * np.arange(1, m + 1) / m)
    out = np.concatenate(s)
    out[-1] = Lr
    return out


def discretize(geom: Geometry, n_elements: int, s: np.ndarray | None = None) -> Discrete:
    """Nodes at the arc lengths ``s`` (N+1,) (default ``s_i = i h``, ``h = L/N``), segment
    frames at the midpoints, end frames at 0 and L."""
    N, Lr = int(n_elements), geom.length
    if s is None:
        h = Lr / N
        s = np.arange(N + 1) * h
        mid = (np.arange(N) + 0.5) * h
        hs = np.full(N, h)
    else:
        s = np.asarray(s, dtype=float)
        if s.shape != (N + 1,):
            raise ValueError(f"s has shape {s.shape}, expected ({N + 1},)")
        if np.array_equal(s, np.arange(N + 1) * (Lr / N)):   # uniform: its own arithmetic
            return discretize(geom, N)
        mid, hs = 0.5 * (s[:-1] + s[1:]), np.diff(s)
    return Discrete(nodes=geom.position(s), frames=geom.frame(mid),
                    start_frame=geom.frame(np.array(0.0)), end_frame=geom.frame(np.array(Lr)),
                    h=hs)


KINDS = ("straight", "arc", "helix", "points")
_KEYS = {
    "straight": ("kind", "direction", "normal", "twist", "origin"),
    "arc": ("kind", "radius", "angle", "direction", "toward", "first_director", "twist",
            "origin"),
    "helix": ("kind", "coil_radius", "pitch", "turns", "handedness", "axis", "radial", "twist",
              "origin"),
    "points": ("kind", "points", "file", "normal", "twist", "origin"),
}


def geometry_from_mapping(m: Mapping[str, Any] | None, length: float | None,
                          base: Path | None = None) -> Geometry:
    """A geometry from ``[rod.geometry]`` (``length`` from ``[rod]``: needed for straight,
    must agree with the arc/helix/points length when given)."""
    m = dict(m or {"kind": "straight"})
    path = "rod.geometry"
    kind = C.choice(f"{path}.kind", m.get("kind", "straight"), KINDS)
    C.no_unknown_keys(path, m, _KEYS[kind])
    common: dict[str, Any] = {}
    if "twist" in m:
        common["twist"] = C.number(f"{path}.twist", m["twist"])
    if "origin" in m:
        common["origin"] = C.vector(f"{path}.origin", m["origin"])
    vec = {k: C.vector(f"{path}.{k}", m[k]) for k in ("direction", "normal", "toward", "axis",
                                                       "radial") if k in m}
    if kind == "straight":
        if length is None:
            raise ParameterError("rod.length", None, "a length in m (> 0) for a straight rod")
        g: Geometry = Straight(rod_length=length, **vec, **common)
    elif kind == "arc":
        kw = {k: C.number(f"{path}.{k}", m[k]) for k in ("radius", "angle") if k in m}
        if "first_director" in m:
            kw["first_director"] = m["first_director"]
        g = Arc(**kw, **vec, **common)
    elif kind == "helix":
        kw = {k: C.number(f"{path}.{k}", m[k]) for k in ("coil_radius", "pitch", "turns")
              if k in m}
        if "handedness" in m:
            kw["handedness"] = m["handedness"]
        g = Helix(**kw, **vec, **common)
    else:
        if ("points" in m) == ("file" in m):
            raise ParameterError(f"{path}.points", m.get("points"),
                                 "either points = [[x, y, z], ...] or file = CSV")
        if "points" in m:
            pts, key = m["points"], f"{path}.points"
            where = [f"row {k} (from 0)" for k in range(len(pts))] if isinstance(
                pts, (list, tuple)) else []
        else:
            key = f"{path}.file"
            pts, where = _read_points(key, m["file"], base)
        c = points_curve(np.asarray(pts, dtype=float) if _numeric_rows(pts) else
                         _bad_points(key, pts), vec.get("normal"), key, where)
        g = Curve(function=c.function, curve_length=c.curve_length, normal=c.normal, **common)
        object.__setattr__(g, "_source", {"kind": "points", "points": [list(map(float, p))
                                                                        for p in pts]})
    if kind != "straight" and length is not None and abs(length - g.length) > 1e-9 * g.length:
        raise ParameterError("rod.length", length, f"the geometry's length {g.length:.9g} m "
                             f"(or leave rod.length out for a {kind})")
    return g


def _numeric_rows(pts: Any) -> bool:
    try:
        a = np.asarray(pts, dtype=float)
    except (TypeError, ValueError):
        return False
    return a.ndim == 2 and a.shape[1] == 3


def _bad_points(path: str, pts: Any):
    raise ParameterError(path, pts, "at least 2 finite [x, y, z] points")


def _read_points(path: str, file: Any, base: Path | None
                 ) -> tuple[list[list[float]], list[str]]:
    """(rows x, y, z, and where each row is in the file: "FILE line K") of a points CSV.

    An optional header is the first line that is not a comment ('#'); every other row
    must hold exactly three numbers (a row with a typo is refused, naming the file, line
    and column, never skipped).
    """
    name = C.string(path, file)
    f = Path(name) if Path(name).is_absolute() or base is None else base / name
    try:
        text = f.read_text()
    except OSError as exc:
        raise ParameterError(path, name, f"a readable CSV file ({exc.strerror})") from None
    except UnicodeDecodeError as exc:
        raise ParameterError(path, name, f"a UTF-8 text CSV file ({exc.reason})") from None
    rows: list[list[float]] = []
    where: list[str] = []
    first = True
    for lineno, line in enumerate(text.splitlines(), 1):
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        row = next(csv.reader([line]))
        values = []
        for col, v in enumerate(row, 1):
            try:
                values.append(float(v))
            except ValueError:
                values = None
                bad = (col, v)
                break
        if values is None and first and not rows:
            first = False
            continue                                   # the header
        first = False
        if values is None:
            col, v = bad
            raise ParameterError(path, name, f"numbers x, y, z in every row: line {lineno} "
                                 f"column {col} is {v.strip()!r}, not a number")
        if len(values) != 3 or not all(math.isfinite(v) for v in values):
            raise ParameterError(path, name, f"three finite numbers x, y, z in every row: "
                                 f"line {lineno} holds {line.strip()!r}")
        rows.append(values)
        where.append(f"{name} line {lineno}")
    return rows, where
