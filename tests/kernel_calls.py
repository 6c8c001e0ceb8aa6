"""Calling single generated kernels in the tests: the serialised CasADi functions
(generated/rod_*.casadi) with named inputs, and the same functions in the compiled
library through ctypes (CasADi's calling convention)."""

from __future__ import annotations

import ctypes
from functools import lru_cache

import casadi as ca
import numpy as np

from runtime.model.casadi_oracle import load_kernels


@lru_cache(maxsize=1)
def kernels() -> dict[str, ca.Function]:
    """The serialised kernels of generated/, by name."""
    return load_kernels()


def call(name: str, **inputs) -> dict[str, np.ndarray]:
    """Kernel ``name`` of generated/ on named inputs: its named outputs (vectors flat,
    matrices 2-D)."""
    f = kernels()[name]
    out = f(**{k: np.asarray(v, dtype=float) for k, v in inputs.items()})
    return {k: (np.array(v).ravel() if v.shape[1] == 1 else np.array(v))
            for k, v in out.items()}


def call_compiled(lib, name: str, **inputs) -> dict[str, np.ndarray]:
    """The same kernel from the compiled library ``lib``: outputs as :func:`call`."""
    f = kernels()[name]
    args = [np.ascontiguousarray(np.asarray(inputs[f.name_in(i)], dtype=float).ravel())
            for i in range(f.n_in())]
    outs = [np.full(f.nnz_out(o), np.nan) for o in range(f.n_out())]
    P = ctypes.c_void_p
    arg = (P * max(f.sz_arg(), 1))(*[a.ctypes.data for a in args])
    res = (P * max(f.sz_res(), 1))(*[r.ctypes.data for r in outs])
    iw = (ctypes.c_longlong * max(f.sz_iw(), 1))()
    w = (ctypes.c_double * max(f.sz_w(), 1))()
    assert getattr(lib, name)(arg, res, iw, w, 0) == 0
    shaped = {}
    for o in range(f.n_out()):
        rows, cols = f.size_out(o)
        shaped[f.name_out(o)] = outs[o] if cols == 1 else outs[o].reshape((rows, cols),
                                                                         order="F")
    return shaped


def energies_through(kern, fn: int, ys: np.ndarray, yps: np.ndarray) -> np.ndarray:
    """(m, ``kern.n_energies``) of the states ``ys``, ``yps`` at t = 0 through the step
    loop's energies signature ``int f(ctx, m, ts, ys, yps, out)`` at address ``fn`` (a
    :class:`runtime.solvers.protocols.CKernels`' ``energies`` or ``audit_energies``);
    entries the function does not write stay NaN."""
    ys, yps = np.ascontiguousarray(ys, dtype=float), np.ascontiguousarray(yps, dtype=float)
    ts = np.zeros(len(ys))
    out = np.full((len(ys), kern.n_energies), np.nan)
    P = ctypes.c_void_p
    f = ctypes.CFUNCTYPE(ctypes.c_int, P, ctypes.c_int, P, P, P, P)(fn)
    assert f(kern.ctx, len(ys), ts.ctypes.data, ys.ctypes.data, yps.ctypes.data,
             out.ctypes.data) == 0
    return out
