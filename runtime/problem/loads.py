"""Ends and loads of a rod problem.

Ends (``[start]`` at s = 0, ``[end]`` at s = L): ``kind`` = ``free``, ``clamped`` (position
and frame held), ``pinned`` (position held, rotation free); a held end may move:
``[start.motion]`` with ``translation`` (m, spatial) times ``translation_time`` and a
rotation of the clamp frame by ``rotation_angle`` (degrees) times ``rotation_time`` about
the fixed spatial ``rotation_axis`` (clamped ends only). Time functions:
:mod:`runtime.problem.timefunctions` (a motion must be continuous: no step/release).

Loads (``[[loads]]``, each with an optional ``time`` function):

* ``gravity``: ``vector`` (m/s^2) on the lumped masses;
* ``distributed``: dead force per length ``vector`` (N/m), lumped to the nodes;
* ``force``: point force ``vector`` (N) at a node, ``frame = "dead"`` (fixed in space) or
  ``"follower"`` (fixed in the frame of the node's segment; the vector is given in the
  reference frame there);
* ``moment``: point moment ``vector`` (N m), dead or follower, on the segments at a node
  (split between the two segments at an interior node).

A node is chosen with ``at`` = ``"start"``, ``"end"`` or a node index 0..N, or with ``s``
= an arc length (m; the nearest node).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from runtime.errors import ParameterError
from runtime.problem import coerce as C
from runtime.problem.timefunctions import TimeFunction

END_KINDS = ("free", "clamped", "pinned")
LOAD_KINDS = ("gravity", "distributed", "force", "moment")
FRAMES = ("dead", "follower")


@dataclass(frozen=True)
class Motion:
    """Prescribed motion of a held end (see the module docstring)."""

    translation: tuple[float, float, float] = (0.0, 0.0, 0.0)
    translation_time: TimeFunction = field(default_factory=TimeFunction)
    rotation_axis: tuple[float, float, float] = (0.0, 0.0, 1.0)
    rotation_angle: float = 0.0
    rotation_time: TimeFunction = field(default_factory=TimeFunction)

    @property
    def moves(self) -> bool:
        return any(self.translation) or self.rotation_angle != 0.0

    @property
    def time_dependent(self) -> bool:
        return (any(self.translation) and not self.translation_time.is_constant) or (
            self.rotation_angle != 0.0 and not self.rotation_time.is_constant)

    def to_mapping(self) -> dict[str, Any]:
        return {"translation": list(self.translation),
                "translation_time": self.translation_time.to_mapping(),
                "rotation_axis": list(self.rotation_axis), "rotation_angle": self.rotation_angle,
                "rotation_time": self.rotation_time.to_mapping()}


@dataclass(frozen=True)
class End:
    """One end of the rod: free, clamped or pinned, possibly moving."""

    kind: str = "free"
    motion: Motion | None = None

    @property
    def held(self) -> bool:
        return self.kind != "free"

    @property
    def clamped(self) -> bool:
        return self.kind == "clamped"

    def to_mapping(self) -> dict[str, Any]:
        out: dict[str, Any] = {"kind": self.kind}
        if self.motion is not None:
            out["motion"] = self.motion.to_mapping()
        return out


def end_from_mapping(path: str, m: Any, base: Path | None = None) -> End:
    """An end from ``[start]`` / ``[end]`` (a bare string is its kind)."""
    if m is None:
        return End()
    if isinstance(m, str):
        m = {"kind": m}
    m = C.table(path, m)
    C.no_unknown_keys(path, m, ("kind", "motion"))
    kind = C.choice(f"{path}.kind", m.get("kind", "free"), END_KINDS)
    if "motion" not in m:
        return End(kind)
    if kind == "free":
        raise ParameterError(f"{path}.motion", m["motion"], "only for a clamped or pinned end")
    return End(kind, motion_from_mapping(f"{path}.motion", m["motion"], base,
                                         rotates=kind == "clamped",
                                         fixed="a pinned end (its rotation is free)"))


MOTION_KEYS = ("translation", "translation_time", "rotation_axis", "rotation_angle",
               "rotation_time")


def motion_from_mapping(path: str, m: Any, base: Path | None = None, *, rotates: bool = True,
                        fixed: str = "") -> Motion:
    """A prescribed rigid motion from its table (``[start.motion]``, an obstacle's
    ``motion``): ``translation`` (m) times ``translation_time``, a rotation by
    ``rotation_angle`` (degrees) times ``rotation_time`` about ``rotation_axis``; the time
    functions continuous (a position cannot jump). ``rotates`` False: the angle must be 0
    (``fixed`` says for what)."""
    mm = C.table(path, m)
    C.no_unknown_keys(path, mm, MOTION_KEYS)
    kw: dict[str, Any] = {}
    if "translation" in mm:
        kw["translation"] = C.vector(f"{path}.translation", mm["translation"])
    if "rotation_axis" in mm:
        kw["rotation_axis"] = C.unit_vector(f"{path}.rotation_axis", mm["rotation_axis"])
    if "rotation_angle" in mm:
        kw["rotation_angle"] = C.number(f"{path}.rotation_angle", mm["rotation_angle"])
        if not rotates and kw["rotation_angle"] != 0:
            raise ParameterError(f"{path}.rotation_angle", kw["rotation_angle"],
                                 f"0 for {fixed}")
    for key in ("translation_time", "rotation_time"):
        if key in mm:
            tf = TimeFunction.from_mapping(mm[key], f"{path}.{key}", base)
            if not tf.continuous:
                raise ParameterError(f"{path}.{key}.kind", tf.kind, "a continuous function for a "
                                     "prescribed position (ramp, smooth_ramp, harmonic, table, "
                                     "constant)")
            kw[key] = tf
    return Motion(**kw)


@dataclass(frozen=True)
class Load:
    """One external load (see the module docstring)."""

    kind: str = "force"
    vector: tuple[float, float, float] = (0.0, 0.0, 0.0)
    at: str | int | None = "end"
    s: float | None = None
    frame: str = "dead"
    time: TimeFunction = field(default_factory=TimeFunction)

    def __post_init__(self) -> None:
        C.choice("loads.kind", self.kind, LOAD_KINDS)
        C.vector("loads.vector", self.vector)
        C.choice("loads.frame", self.frame, FRAMES)
        if self.kind in ("gravity", "distributed") and self.frame != "dead":
            raise ParameterError("loads.frame", self.frame, "'dead' for gravity and "
                                 "distributed loads")

    def node(self, n_elements: int, length: float,
             s_nodes: np.ndarray | None = None) -> int:
        """The node index (0..N) the load acts at; ``s_nodes``: the nodes' arc lengths
        (m), which hold a node at the load's ``s`` (``Problem.node_arc_lengths``)."""
        if self.s is not None:
            if s_nodes is None:
                return int(round(self.s / length * n_elements))
            return int(np.argmin(np.abs(np.asarray(s_nodes) - self.s)))
        if self.at == "start":
            return 0
        if self.at == "end" or self.at is None:
            return n_elements
        if isinstance(self.at, int) and 0 <= self.at <= n_elements:
            return self.at
        raise ParameterError("loads.at", self.at, f"'start', 'end' or a node 0 ... {n_elements}")

    def to_mapping(self) -> dict[str, Any]:
        out: dict[str, Any] = {"kind": self.kind, "vector": list(self.vector)}
        if self.kind in ("force", "moment"):
            out.update({"s": self.s} if self.s is not None else {"at": self.at})
            out["frame"] = self.frame
        out["time"] = self.time.to_mapping()
        return out


def load_from_mapping(path: str, m: Any, base: Path | None = None) -> Load:
    """A load from one ``[[loads]]`` table."""
    m = C.table(path, m)
    kind = C.choice(f"{path}.kind", m.get("kind", "force"), LOAD_KINDS)
    point = kind in ("force", "moment")
    C.no_unknown_keys(path, m, ("kind", "vector", "time") + (("at", "s", "frame") if point
                                                            else ()))
    if "vector" not in m:
        raise ParameterError(f"{path}.vector", None, "3 finite numbers")
    kw: dict[str, Any] = {"kind": kind, "vector": C.vector(f"{path}.vector", m["vector"])}
    if point:
        if "at" in m and "s" in m:
            raise ParameterError(f"{path}.s", m["s"], "not together with 'at': give one")
        if "s" in m:
            kw["s"] = C.nonnegative(f"{path}.s", m["s"])
            kw["at"] = None
        elif "at" in m:
            at = m["at"]
            if isinstance(at, str):
                C.choice(f"{path}.at", at, ("start", "end"))
            else:
                at = C.integer(f"{path}.at", at, low=0)
            kw["at"] = at
        if "frame" in m:
            kw["frame"] = C.choice(f"{path}.frame", m["frame"], FRAMES)
    if "time" in m:
        kw["time"] = TimeFunction.from_mapping(m["time"], f"{path}.time", base)
    return Load(**kw)
