"""Parameter directions of a rod model for its sensitivities (issue 34).

A problem parameter theta (a modulus, a retardation time, a density, a load component,
...) enters the residual only through the rod's numbers (:class:`RodArrays`). Its
direction is the derivative of those arrays, ``dA = dA/dtheta``, in the same layout (a
:class:`RodArrays` of derivatives: ``theta`` holds d theta_b/d theta, ``segb`` the
moduli's derivatives, ...). With it the compiled tangent
(``runtime/model/native/rod_tangent.c``) gives ``F_theta = F_p dA`` and the sensitivity
residual ``F_y s + F_y' s' + F_theta`` of the integrator in one sweep.

Loads and prescribed motion change with time; their derivatives do too. A
:class:`Directions` therefore carries, besides the arrays, an optional ``drive(darrays,
t, left, scale, static)`` per parameter that writes the time-dependent entries (loads,
end motion) at time t, called by :meth:`RodModel.at` whenever the model's own drive
writes the arrays (so the compiled step loop's drive callback keeps both in step).
"""

from __future__ import annotations

import ctypes
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from runtime.model.arrays import RodArrays, RodStruct

#: ``drive(darrays, t, left, scale, static)``: the derivative of the driven entries
DirectionDrive = Callable[[RodArrays, float, bool, float, bool], None]


class SensCtx(ctypes.Structure):
    """``kvrod_sens_ctx`` of runtime/model/native/rod_tangent.c."""

    _fields_ = [("rod", ctypes.c_void_p), ("np", ctypes.c_int), ("drods", ctypes.c_void_p)]


@dataclass
class Directions:
    """The parameter directions of one model: ``names`` (as asked), ``arrays`` (one
    :class:`RodArrays` of derivatives each, the model's shapes), ``drives`` (None or a
    :data:`DirectionDrive` each, for entries that depend on time)."""

    names: tuple[str, ...]
    arrays: list[RodArrays]
    drives: list[DirectionDrive | None] = field(default_factory=list)

    def __post_init__(self) -> None:
        if len(self.names) != len(self.arrays):
            raise ValueError("one derivative array set per parameter name")
        if not self.drives:
            self.drives = [None] * len(self.arrays)

    def check(self, arrays: RodArrays) -> None:
        """Every direction has the shapes of ``arrays`` (the model's)."""
        for name, d in zip(self.names, self.arrays, strict=True):
            same = (d.N == arrays.N and d.branches == arrays.branches
                    and d.coupled == arrays.coupled
                    and all(getattr(d, k).shape == getattr(arrays, k).shape
                            for k in ("par", "seg", "jnt", "nload", "sload", "theta",
                                      "segb", "jntb")))
            if same and d.coupled:
                same = d.segc.shape == arrays.segc.shape and d.jntc.shape == arrays.jntc.shape
            if not same:
                raise ValueError(f"the direction of {name!r} has other shapes than the "
                                 "model's arrays")

    def drive(self, t: float, left: bool, scale: float, static: bool) -> None:
        """Write every time-dependent derivative at time ``t`` (as the model's drive)."""
        for d, go in zip(self.arrays, self.drives, strict=True):
            if go is not None:
                go(d, t, left, scale, static)

    def relax(self) -> list[tuple]:
        """As :meth:`RodModel.statics` relaxes a generalized Maxwell rod (C_F minus the
        terms' moduli, the terms' moduli 0), the same on the derivatives; returns what
        :meth:`restore` puts back."""
        saved = []
        for a in self.arrays:
            saved.append((a.seg_field("C_F").copy(), a.jnt_field("C_M").copy(),
                          a.segb.copy(), a.jntb.copy()))
            a.seg_field("C_F")[:] -= a.segb.sum(axis=1)
            a.jnt_field("C_M")[:] -= a.jntb.sum(axis=1)
            a.segb[:] = 0.0
            a.jntb[:] = 0.0
        return saved

    def restore(self, saved: list[tuple]) -> None:
        for a, (cf, cm, sb, jb) in zip(self.arrays, saved, strict=True):
            a.seg_field("C_F")[:], a.jnt_field("C_M")[:] = cf, cm
            a.segb[:], a.jntb[:] = sb, jb


class CSensitivities:
    """The C view of a model's directions: ``kvrod_sens_ctx`` over the model's
    ``kvrod_rod`` and one ``kvrod_rod`` of derivatives per parameter (keep this object
    alive while C uses ``ptr``)."""

    def __init__(self, rod_struct: RodStruct, directions: Directions, kl: int, ku: int):
        n = len(directions.arrays)
        self.structs = (RodStruct * max(n, 1))(*[d.struct(kl, ku)
                                                 for d in directions.arrays])
        self.ctx = SensCtx(ctypes.addressof(rod_struct), n, ctypes.addressof(self.structs))
        self.ptr = ctypes.addressof(self.ctx)
        self._keep = (rod_struct, directions)


def zeros_like(arrays: RodArrays) -> RodArrays:
    """A :class:`RodArrays` of zeros with the shapes of ``arrays`` (a direction)."""
    def z(a):
        return None if a is None else np.zeros_like(a)

    return RodArrays(arrays.N, z(arrays.par), z(arrays.seg), z(arrays.jnt), z(arrays.nload),
                     z(arrays.sload), z(arrays.theta), z(arrays.segb), z(arrays.jntb),
                     z(arrays.segc), z(arrays.jntc))


def difference(plus: RodArrays, minus: RodArrays, step: float) -> RodArrays:
    """``(plus - minus) / step`` entry by entry (a central difference of two builds)."""
    def d(a, b):
        return None if a is None else (np.asarray(a) - np.asarray(b)) / step

    return RodArrays(plus.N, d(plus.par, minus.par), d(plus.seg, minus.seg),
                     d(plus.jnt, minus.jnt), d(plus.nload, minus.nload),
                     d(plus.sload, minus.sload), d(plus.theta, minus.theta),
                     d(plus.segb, minus.segb), d(plus.jntb, minus.jntb),
                     d(plus.segc, minus.segc), d(plus.jntc, minus.jntc))


def names_of(directions: Directions | None) -> Sequence[str]:
    return () if directions is None else directions.names
