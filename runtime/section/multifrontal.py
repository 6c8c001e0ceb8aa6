"""The numeric phase of the section's multifrontal Cholesky in C (``multifrontal.c``), its
solve with the factor (:func:`solve_fronts`), and its symbolic phase's supernode
amalgamation (:func:`supernodes`):
compiled on first use (cached by source, flags and host CPU, like the integrator's
library), with SciPy's own LAPACK and BLAS (``dpotrf``, ``dtrsm``, ``dsyrk``, ``dgemm``, ``dgemv``
from ``scipy.linalg.cython_lapack`` / ``cython_blas``) handed over as function pointers,
so that it factors and solves as the NumPy loops of
:func:`runtime.section.cholesky._factor_block` and
:meth:`runtime.section.cholesky.CholeskyFactor.solve` do (those loops stay the fallback
without a compiler and the tests' oracle).
"""

from __future__ import annotations

import ctypes
import hashlib
import os
import subprocess
import tempfile
import threading
from pathlib import Path

import numpy as np

import runtime.native as native

SOURCE_FILE = Path(__file__).with_name("multifrontal.c")
_lib: ctypes.CDLL | None = None
_tried = False
_lock = threading.Lock()     # the analysis runs in a worker thread; sweeps may run several


def _capsule_pointer(module, name: str) -> int:
    """The C function behind ``module.__pyx_capi__[name]`` (a Cython capsule)."""
    api = ctypes.pythonapi
    api.PyCapsule_GetName.restype = ctypes.c_char_p
    api.PyCapsule_GetName.argtypes = [ctypes.py_object]
    api.PyCapsule_GetPointer.restype = ctypes.c_void_p
    api.PyCapsule_GetPointer.argtypes = [ctypes.py_object, ctypes.c_char_p]
    cap = module.__pyx_capi__[name]
    return int(api.PyCapsule_GetPointer(cap, api.PyCapsule_GetName(cap)))


def load() -> ctypes.CDLL | None:
    """The compiled numeric phase with SciPy's routines attached, or None (no compiler,
    ``KVROD_NO_COMPILER=1``, a failed build, or a SciPy without the Cython interfaces)."""
    global _tried
    with _lock:
        if not _tried:
            _tried = True
            _load()
    return _lib


def _load() -> None:
    """Compile (or find in the cache) and load the library into ``_lib``; leave it None
    on any failure (the NumPy loop then runs)."""
    global _lib
    cc = native.find_compiler()
    if cc is None:
        return
    try:
        source = SOURCE_FILE.read_text()
        key = hashlib.sha256((source + " ".join(native.compile_command(cc))
                              + native.host_id()).encode()).hexdigest()[:16]
        path = native.cache_dir() / f"kvrod_multifrontal_{key}.so"
        from scipy.linalg import cython_blas, cython_lapack

        routines = (_capsule_pointer(cython_lapack, "dpotrf"),
                    _capsule_pointer(cython_blas, "dtrsm"),
                    _capsule_pointer(cython_blas, "dsyrk"))
        solve_routines = (_capsule_pointer(cython_blas, "dtrsm"),
                          _capsule_pointer(cython_blas, "dgemm"),
                          _capsule_pointer(cython_blas, "dgemv"))
        if not path.exists():
            path.parent.mkdir(parents=True, exist_ok=True)
            with tempfile.TemporaryDirectory(dir=path.parent) as tmp:
                out = Path(tmp) / path.name
                proc = native.run_compiler([str(SOURCE_FILE), "-o", str(out)], cc)
                if proc.returncode != 0:
                    raise subprocess.SubprocessError(proc.stderr)
                os.replace(out, path)
        lib = ctypes.CDLL(str(path))
    except (OSError, subprocess.SubprocessError, ImportError, KeyError, AttributeError):
        return
    P, I = ctypes.c_void_p, ctypes.c_int
    lib.kv_mf_factor.argtypes = [I] + [P] * 16
    lib.kv_mf_factor.restype = I
    L = ctypes.c_longlong
    lib.kv_mf_supernodes.argtypes = [L, P, P, L, I, P, P, P, P, P]
    lib.kv_mf_supernodes.restype = L
    lib.kv_mf_solve.argtypes = [L] + [P] * 8 + [L, L, P, P, P]
    lib.kv_mf_solve.restype = I
    lib.routines = routines
    lib.solve_routines = solve_routines
    _lib = lib


def factor_fronts(lib: ctypes.CDLL, bounds: np.ndarray, start: np.ndarray,
                  upd_all: np.ndarray, uptr: np.ndarray, parent: np.ndarray, Ap,
                  n: int) -> tuple[int, np.ndarray, np.ndarray, np.ndarray, tuple[int, int]]:
    """Factor every front (see multifrontal.c). Returns (code, k and off per front, the
    buffer holding each front's U11 then X at off, (front, info) of a failure)."""
    ns = len(bounds) - 1
    i64 = lambda a: np.ascontiguousarray(a, dtype=np.int64)  # noqa: E731
    bounds, start, upd_all, uptr, parent = map(i64, (bounds, start, upd_all, uptr, parent))
    k = start[bounds[1:]] - start[bounds[:-1]]
    u = np.diff(uptr)
    size = np.where(k > 0, k * k + k * u, 0)
    off = np.concatenate([[0], np.cumsum(size)[:-1]]).astype(np.int64)
    out = np.empty(max(int(size.sum()), 1))
    loc = np.empty(max(n, 1), dtype=np.int64)
    stamp = np.full(max(n, 1), -1, dtype=np.int64)
    err = np.zeros(2, dtype=np.int64)
    indptr, indices = i64(Ap.indptr), i64(Ap.indices)
    data = np.ascontiguousarray(Ap.data, dtype=float)
    ptr = lambda a: a.ctypes.data  # noqa: E731
    code = lib.kv_mf_factor(ns, ptr(bounds), ptr(start), ptr(upd_all), ptr(uptr),
                            ptr(parent), ptr(indptr), ptr(indices), ptr(data), ptr(off),
                            ptr(out), ptr(loc), ptr(stamp), *lib.routines, ptr(err))
    return int(code), k, off, out, (int(err[0]), int(err[1]))


def supernodes(lib: ctypes.CDLL, indptr: np.ndarray, indices: np.ndarray, m: int,
               small_nodes: int, zero_share: tuple[tuple[float, float], ...]
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`runtime.section.cholesky._supernodes` of the node factor L (m columns, CSC
    ``indptr``/``indices``, sorted, diagonal first) by ``kv_mf_supernodes``: the same
    (order, bounds, tops), integer for integer."""
    i64 = lambda a: np.ascontiguousarray(a, dtype=np.int64)  # noqa: E731
    indptr, indices = i64(indptr), i64(indices)
    size = np.array([s for s, _ in zero_share], dtype=float)
    limit = np.array([z for _, z in zero_share], dtype=float)
    order = np.empty(max(m, 1), dtype=np.int64)
    bounds = np.empty(m + 1, dtype=np.int64)
    tops = np.empty(max(m, 1), dtype=np.int64)
    ptr = lambda a: a.ctypes.data  # noqa: E731
    ns = lib.kv_mf_supernodes(m, ptr(indptr), ptr(indices), small_nodes, len(zero_share),
                              ptr(size), ptr(limit), ptr(order), ptr(bounds), ptr(tops))
    if ns < 0:
        raise MemoryError("the supernodes of the section's factor ran out of memory")
    return order[:m], bounds[:ns + 1].copy(), tops[:ns].copy()


def solve_fronts(lib: ctypes.CDLL, r0: np.ndarray, kf: np.ndarray, off: np.ndarray,
                 upd_all: np.ndarray, ulo: np.ndarray, un: np.ndarray, out: np.ndarray,
                 y: np.ndarray) -> None:
    """Overwrite ``y`` (n x k, Fortran order: a block's right-hand sides in its elimination
    order) with the solution of L L^T x = y by ``kv_mf_solve``; the fronts with k > 0 in
    factor order: first unknown ``r0``, ``kf`` pivots, U11 then X at ``out[off:]``, ``un``
    update unknowns at ``upd_all[ulo:]`` (int64 arrays)."""
    if not (y.flags.f_contiguous and y.dtype == np.float64 and y.ndim == 2
            and y.shape[1] >= 2):
        raise ValueError("y must be a float64 array in Fortran order with >= 2 columns")
    ptr = lambda a: a.ctypes.data  # noqa: E731
    code = lib.kv_mf_solve(r0.size, ptr(r0), ptr(kf), ptr(off), ptr(upd_all), ptr(ulo),
                           ptr(un), ptr(out), ptr(y), y.shape[0], y.shape[1],
                           *lib.solve_routines)
    if code != 0:
        raise MemoryError("the solve with the section's factor ran out of memory")
