"""The static Newton iteration's model work in C (``statics.c``, in the integrator's
library): residual at rest, band Jacobian gathered and factorised, retraction; driven by
:class:`runtime.model.statics.RodStatics` when the rod runs on the compiled kernels."""

from __future__ import annotations

import ctypes
from dataclasses import dataclass

import numpy as np

from .loader import load
from .pointers import PointerCache

_I, _D, _P = ctypes.c_int, ctypes.c_double, ctypes.c_void_p


class StaticStruct(ctypes.Structure):
    """Mirror of ``kv_static`` in statics.c (the size is checked when built)."""

    _fields_ = ([(name, _I) for name in ("n", "ns", "ldab", "kl", "ku", "lds", "nvel",
                                         "nrow", "nfix", "nplan", "nw", "nphi", "nrot")]
                + [("t", _D)]
                + [(name, _P) for name in ("res", "jac", "ctx", "vel", "rows", "fixed", "src",
                                           "widx", "dst", "wsrc", "wsign", "phi", "phi_cols",
                                           "p_index", "theta", "y0", "zeros", "r", "w", "ab",
                                           "abs", "ipiv", "prof")])


@dataclass
class StaticLayout:
    """What :class:`NativeStatics` needs of a rod's static problem (index arrays into the
    full state y (n,) and the static unknowns (ns,); ``plan``: ``src, widx, dst`` of
    ``RodStatics._gather_plan``)."""

    n: int
    ns: int
    kl: int
    ku: int
    ldab: int
    velocities: np.ndarray
    rows: np.ndarray
    fixed: np.ndarray
    plan: tuple[np.ndarray, np.ndarray, np.ndarray]
    weight_src: np.ndarray
    weight_sign: np.ndarray
    phi: np.ndarray
    phi_cols: np.ndarray
    p_index: np.ndarray
    theta: np.ndarray


class NativeFactor:
    """The LU factors of the static band Jacobian held in the C struct (valid until the
    next :meth:`NativeStatics.factor`): ``info`` (> 0: singular) and :meth:`solve`."""

    def __init__(self, core: NativeStatics, info: int) -> None:
        self._core, self.info = core, info

    def solve(self, b: np.ndarray) -> np.ndarray:
        """``J^-1 b`` (a new array; b unchanged)."""
        if self.info != 0:
            raise ValueError(f"the static Jacobian is singular (info {self.info})")
        x = np.array(b, dtype=float)
        self._core.lib.kv_static_solve(self._core.ptr, x.ctypes.data)
        return x


class NativeStatics:
    """One rod's static problem on its compiled kernels (``residual``, ``jacobian``:
    addresses of ``kvrod_residual``, ``kvrod_jacobian_band``; ``ctx``: the rod struct).
    None from :meth:`build` without the compiled helpers."""

    @classmethod
    def build(cls, layout: StaticLayout, t: float, residual: int, jacobian: int, ctx: int,
              keep: object) -> NativeStatics | None:
        lib = load()
        if lib is None:
            return None
        return cls(lib, layout, t, residual, jacobian, ctx, keep)

    def __init__(self, lib, layout: StaticLayout, t: float, residual: int, jacobian: int,
                 ctx: int, keep: object) -> None:
        self.lib, self._keep = lib, keep

        def i32(a) -> np.ndarray:
            return np.ascontiguousarray(a, dtype=np.int32).ravel()

        def i64(a) -> np.ndarray:
            return np.ascontiguousarray(a, dtype=np.int64).ravel()

        L = layout
        lds = 2 * L.kl + L.ku + 1
        src, widx, dst = L.plan
        a = {"vel": i32(L.velocities), "rows": i32(L.rows), "fixed": i32(L.fixed),
             "src": i64(src), "widx": i64(widx), "dst": i64(dst), "wsrc": i32(L.weight_src),
             "wsign": np.ascontiguousarray(L.weight_sign, dtype=float).ravel(),
             "phi": i32(L.phi), "phi_cols": i32(L.phi_cols), "p_index": i32(L.p_index),
             "theta": i32(L.theta), "y0": np.zeros(L.n), "zeros": np.zeros(L.n),
             "r": np.zeros(L.n), "w": np.zeros(1 + np.size(L.weight_src)),
             "ab": np.zeros((L.ldab, L.n), order="F"),
             "abs": np.zeros((lds, L.ns), order="F"),
             "ipiv": np.zeros(max(L.ns, 1), dtype=np.int32),
             "prof": np.zeros(2 * max(L.ns, 1), dtype=np.int32)}
        self._arrays = a
        #: the static band (LAPACK storage, F order): the gauge's stiffness is added here
        #: between :meth:`jacobian` and :meth:`factor`
        self.band = a["abs"]
        s = self.s = StaticStruct(
            n=L.n, ns=L.ns, ldab=L.ldab, kl=L.kl, ku=L.ku, lds=lds, nvel=a["vel"].size,
            nrow=a["rows"].size, nfix=a["fixed"].size, nplan=a["src"].size,
            nw=a["wsrc"].size, nphi=a["phi"].size, nrot=a["p_index"].size // 4, t=float(t),
            res=residual, jac=jacobian, ctx=ctx)
        for name, arr in a.items():
            setattr(s, name, arr.ctypes.data)
        if lib.kv_static_sizeof() != ctypes.sizeof(StaticStruct):
            raise RuntimeError("kv_static (statics.c) and StaticStruct differ in size")
        self.ptr = ctypes.addressof(s)
        self._addr = PointerCache()

    def _data(self, a: np.ndarray, n: int) -> int:
        return self._addr(a, n)

    def residual(self, y: np.ndarray, out: np.ndarray) -> int:
        """out (ns,) <- the static residual at rest (no gauge); the kernel's code."""
        return self.lib.kv_static_residual(self.ptr, self._data(y, self.s.n),
                                           self._data(out, self.s.ns))

    def jacobian(self, y: np.ndarray) -> int:
        """:attr:`band` <- the static band Jacobian at y (no gauge); the kernel's code."""
        return self.lib.kv_static_jacobian(self.ptr, self._data(y, self.s.n))

    def factor(self) -> NativeFactor:
        """LU of :attr:`band` in place."""
        return NativeFactor(self, int(self.lib.kv_static_factor(self.ptr)))

    def trial(self, y: np.ndarray, f: np.ndarray, res: np.ndarray
              ) -> tuple[int, int, NativeFactor, np.ndarray, np.ndarray]:
        """One full Newton trial (``kv_static_trial``): ``(code, aux, factor, dx,
        y_try)`` with dx = -J(y)^-1 f, y_try = the retraction of y by dx and ``res`` (n_s)
        <- the residual at y_try (no gauge). code 0; 1: the Jacobian's kernel failed, 2:
        J singular, 3: dx not finite, 4: the residual's kernel failed (aux: the kernel's
        code or LAPACK's info)."""
        s = self.s
        dx, y1, aux = np.empty(s.ns), np.empty(s.n), np.zeros(1, dtype=np.int32)
        code = int(self.lib.kv_static_trial(self.ptr, self._data(y, s.n), self._data(f, s.ns),
                                            dx.ctypes.data, y1.ctypes.data,
                                            self._data(res, s.ns), aux.ctypes.data))
        return code, int(aux[0]), NativeFactor(self, int(aux[0]) if code == 2 else 0), dx, y1

    def retract(self, y: np.ndarray, dx: np.ndarray) -> np.ndarray:
        """A new state: positions moved by dx, quaternions rotated by its angles."""
        y1 = np.empty(self.s.n)
        self.lib.kv_static_retract(self.ptr, self._data(y, self.s.n),
                                   self._data(dx, self.s.ns), y1.ctypes.data)
        return y1
