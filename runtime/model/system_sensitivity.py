"""Parameter directions of an assembly of rods for its sensitivities (issue 34), the
system's counterpart of ``runtime.model.sensitivity``.

A parameter of an assembly moves the numbers of its rods (each rod's
``RodArrays``), of its links (``LINK_PARAMS`` and the 40
constants of a link's ground side), of its bodies (``BODY_PARAMS``), the supports'
positions and the bodies' gravity. A ``SystemDirection`` holds their derivatives;
the rods' parts are given to the rods themselves (``RodModel.set_directions``), so
each rod drives its loads' derivatives in time as a single rod does, and the system's
compiled tangent (``native/system_tangent.c``) adds the links', the bodies' and the
holds'.
"""

from __future__ import annotations

import ctypes
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from generated import rod_layout as L
from runtime.model.arrays import RodArrays
from runtime.model.sensitivity import DirectionDrive, Directions

#: constants per link (the kernel's inputs where a side is the ground; system.h)
LINK_CONSTANTS = 40


class KvsysDir(ctypes.Structure):
    """``kvsys_dir`` of runtime/model/native/system_tangent.h."""

    _fields_ = [("drod", ctypes.c_void_p), ("dlpar", ctypes.c_void_p),
                ("dlconst", ctypes.c_void_p), ("dbpar", ctypes.c_void_p),
                ("dhold_r", ctypes.c_void_p), ("dgravity", ctypes.c_double * 3)]


class SysSensCtx(ctypes.Structure):
    """``kvsys_sens_ctx`` of runtime/model/native/system_tangent.h."""

    _fields_ = [("sys", ctypes.c_void_p), ("np", ctypes.c_int), ("dirs", ctypes.c_void_p)]


def system_tables(model) -> dict[str, np.ndarray]:
    """The parameter tables of a ``SystemModel`` as its
    compiled struct holds them: ``lpar`` (links, N_LINK), ``lconst`` (links, 40), ``bpar``
    (bodies, N_BODY), ``hold_r`` (holds, 3: a support's position, 0 for a tie)."""
    from runtime.model.system import _body_params, _link_params

    lconst = [model._link_tables(lk)[2] for lk in model.links]
    return {"lpar": np.array([_link_params(lk) for lk in model.links]).reshape(-1, L.N_LINK),
            "lconst": np.array(lconst, dtype=float).reshape(-1, LINK_CONSTANTS),
            "bpar": np.array([_body_params(b) for b in model.bodies]).reshape(-1, L.N_BODY),
            "hold_r": np.array([h.position if h.master is None else (0.0, 0.0, 0.0)
                                for h in model.holds], dtype=float).reshape(-1, 3)}


@dataclass
class SystemDirection:
    """The derivatives of an assembly's numbers along one parameter: ``rods`` (one
    RodArrays of derivatives per rod), ``rod_drives`` (their time-dependent entries, or
    None), ``tables`` (``system_tables``' derivatives), ``reference`` (the reference
    state's, (n,)), ``gravity`` (``(t, left, scale) -> dg``, the bodies' gravity's, or
    None)."""

    rods: list[RodArrays]
    rod_drives: list[DirectionDrive | None]
    tables: dict[str, np.ndarray]
    reference: np.ndarray
    gravity: Callable[[float, bool, float], np.ndarray] | None = None
    error: float = 0.0


@dataclass
class SystemDirections:
    """The directions of an assembly's parameters (``names`` as asked)."""

    names: tuple[str, ...]
    dirs: list[SystemDirection]
    _dgravity: list[np.ndarray] = field(default_factory=list)

    def install(self, model) -> None:
        """Give every rod its part (``RodModel.set_directions``)."""
        for r, rod in enumerate(model.rods):
            rod.set_directions(Directions(self.names, [d.rods[r] for d in self.dirs],
                                          [d.rod_drives[r] for d in self.dirs]))
        self._dgravity = [np.zeros(3) for _ in self.dirs]

    def set_gravity(self, t: float, left: bool, scale: float) -> None:
        """The bodies' gravity's derivatives at time t (as the system sets its gravity)."""
        for k, d in enumerate(self.dirs):
            g = np.zeros(3) if d.gravity is None else np.asarray(d.gravity(t, left, scale))
            self._dgravity[k][:] = g


class CSystemSensitivities:
    """The C view: ``kvsys_sens_ctx`` over the system's ``kvsys`` and one ``kvsys_dir``
    per parameter, each pointing at the rods' derivative structs (keep alive while C
    uses ``ptr``)."""

    def __init__(self, model, directions: SystemDirections) -> None:
        n = len(directions.dirs)
        self._keep: list = [directions]
        rod_ctx = [rod.c_sensitivities() for rod in model.rods]    # (fn, ctx, keep) each
        self._keep += rod_ctx
        self.dirs = (KvsysDir * max(n, 1))()
        for k, d in enumerate(directions.dirs):
            drods = (ctypes.c_void_p * len(model.rods))(*[
                ctypes.addressof(c[2].structs[k]) for c in rod_ctx])
            arrays = [np.ascontiguousarray(d.tables[key], dtype=float).reshape(-1)
                      for key in ("lpar", "lconst", "bpar", "hold_r")]
            arrays = [a if a.size else np.zeros(1) for a in arrays]
            self._keep += [drods, *arrays]
            self.dirs[k].drod = ctypes.addressof(drods)
            self.dirs[k].dlpar, self.dirs[k].dlconst = arrays[0].ctypes.data, arrays[1].ctypes.data
            self.dirs[k].dbpar, self.dirs[k].dhold_r = arrays[2].ctypes.data, arrays[3].ctypes.data
        self.ctx = SysSensCtx(model._ptr(), n, ctypes.addressof(self.dirs))
        self.ptr = ctypes.addressof(self.ctx)
        self._directions = directions
        self.refresh_gravity()

    def refresh_gravity(self) -> None:
        for k, g in enumerate(self._directions._dgravity):
            for q in range(3):
                self.dirs[k].dgravity[q] = float(g[q])


def held_sensitivities(model, ip: int, s: np.ndarray) -> np.ndarray:
    """``s`` (n,) with the held nodes' entries set to their prescribed derivatives: a
    rod's own held end's (``d r``), a support's (``d hold_r``), a tied node's its
    master's (a copy)."""
    s = np.array(s, dtype=float)
    d = model.directions.dirs[ip]
    for r, rod in enumerate(model.rods):
        o = int(model.offsets[r])
        for end, i in (("start", 0), ("end", rod.N)):
            if i in rod.held_nodes:
                s[rod.phi_index[i] + o] = d.rods[r].param("r_" + end)
                s[rod.v_index[i] + o] = d.rods[r].param("v_" + end)
    hr = d.tables["hold_r"]
    for k, h in enumerate(model.holds):
        ph, v = model.phi_index[h.rod][h.node], model.v_index[h.rod][h.node]
        if h.master is None:
            s[ph] = hr[k]
            s[v] = 0.0
    for h in model.holds:
        if h.master is not None:
            ph, v = model.phi_index[h.rod][h.node], model.v_index[h.rod][h.node]
            s[ph] = s[model.phi_index[h.master[0]][h.master[1]]]
            s[v] = s[model.v_index[h.master[0]][h.master[1]]]
    return s


def static_sensitivities(model, y: np.ndarray, statics=None) -> np.ndarray:
    """dy/dtheta (k, n) at the assembly's static equilibrium ``y`` for its parameters'
    directions, by the implicit function theorem in the reduced coordinates of
    ``SystemStatics`` (a support's position, a rod's
    held end and a tied node's master move with the parameter: their derivatives enter
    the right-hand side; the gauge holding free rigid motions is kept). Call inside
    ``with model.statics():``. One sparse factorisation serves every parameter."""
    from runtime.model.system_statics import SystemStatics

    st = statics if statics is not None else SystemStatics(model)
    if statics is None:
        st.hold_rigid_motions(y)
    y0 = st.at_rest(y)
    lu = st.static_factor(y0)
    if lu.info != 0:
        raise ValueError("static_sensitivities: the assembly's static Jacobian is singular "
                         "at the equilibrium (a mechanism): no sensitivity")
    T = st.tangent(y0)
    zero = np.zeros(model.n)
    out = np.zeros((model.n_sensitivities, model.n))
    model.at(st.time)
    for i in range(model.n_sensitivities):
        held = held_sensitivities(model, i, zero)
        r = model.residual_tangent(st.time, y0, zero, held, zero, i)
        dx = lu.solve(-r[st.static_rows])
        out[i] = held + T @ dx
        out[i][model.velocity_mask] = 0.0
    return out
