"""Optional C helpers for :mod:`runtime.solvers.bdf` (compiled on first use, cached; else None).

Why C here (measured on the 10 s cantilever release, ``bench/integrators.py``):

- Denormals. The Newton correction of a long rod is the solution of a banded system with a
  local right-hand side; it decays exponentially along the rod and reaches subnormal
  numbers (< 2.2e-308) in far cells at N >= ~500. Subnormal arithmetic is ~100x slower on
  x86, in LAPACK's solve and in every NumPy operation on the history arrays afterwards:
  N = 1000 took 40 s instead of ~4 s. These helpers run with flush-to-zero /
  denormals-are-zero set in MXCSR *only for their own duration* (saved and restored, so
  the caller's floating-point mode is untouched); subnormal corrections become 0, which
  is far below any tolerance.
  The weighted norms of the error test are computed here for the same reason: squares
  of tiny (normal) entries underflow.
- Call overhead. One call does the band solve (``dgbtrs`` semantics on ``dgbtrf``'s
  factors), the scaling by 2/(1 + cj ratio), the weighted RMS norm and the updates of the
  correction, y and y' -- nine NumPy/f2py calls of 1-5 us each per Newton iteration
  before. ``kv_gbtrf`` calls SciPy's own LAPACK ``dgbtrf`` (the function pointer exported
  by ``scipy.linalg.cython_lapack``) into a preallocated pivot array: no f2py wrapper, no
  allocation, and flush-to-zero during the factorisation too.
- Memory traffic. At large N the solves are memory bound (the LU factors are 5.6 MB at
  N = 1000, 11 MB at N = 2000, streamed twice per Newton iteration). ``kv_gbtrf`` records
  the nonzero profile of each factor column (U rarely uses the kl rows of fill-in room
  that partial pivoting reserves) and the solve reads only that: Newton solves -22 % at
  N = 1000, -39 % at N = 2000 (LAPACK's dgbtrs reads the whole band). (Fusing the predictor and
  the history update into C as well was measured and gave nothing at N = 50: a ctypes
  call with many arguments costs about as much as the few NumPy calls it replaces.)

``load()`` returns None without a C compiler (or with ``KVROD_NO_COMPILER=1``); the BDF
then uses the NumPy/f2py path with the same results up to rounding.
"""

from __future__ import annotations

import ctypes
import hashlib
import os
import subprocess
import tempfile
from pathlib import Path

#: the C source, kept as a file beside this module
SOURCE = (Path(__file__).with_name("bdf_helpers.c")).read_text()

_CFLAGS = ("-O2", "-fPIC", "-shared", "-std=c99")
_lib: ctypes.CDLL | None = None
_tried = False
DGBTRF: int = 0


def _dgbtrf_pointer() -> int:
    import scipy.linalg.cython_lapack as cl

    cap = cl.__pyx_capi__["dgbtrf"]
    api = ctypes.pythonapi
    api.PyCapsule_GetName.restype = ctypes.c_char_p
    api.PyCapsule_GetName.argtypes = [ctypes.py_object]
    api.PyCapsule_GetPointer.restype = ctypes.c_void_p
    api.PyCapsule_GetPointer.argtypes = [ctypes.py_object, ctypes.c_char_p]
    return int(api.PyCapsule_GetPointer(cap, api.PyCapsule_GetName(cap)))


def _compile(cc: str, dest: Path) -> None:
    dest.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(dir=dest.parent) as tmp:
        src = Path(tmp) / "kvrod_bdf.c"
        src.write_text(SOURCE)
        out = Path(tmp) / dest.name
        subprocess.run([cc, *_CFLAGS, str(src), "-o", str(out), "-lm"], check=True,
                       capture_output=True)
        os.replace(out, dest)


def load() -> ctypes.CDLL | None:
    """The compiled helpers (cached per source hash), or None if they cannot be built."""
    global _lib, _tried, DGBTRF
    if _tried:
        return _lib
    _tried = True
    from runtime.model import build

    cc = build.find_compiler()
    if cc is None:
        return None
    key = hashlib.sha256((SOURCE + cc + " ".join(_CFLAGS)).encode()).hexdigest()[:16]
    path = build.cache_dir() / f"kvrod_bdf_{key}.so"
    try:
        if not path.exists():
            _compile(cc, path)
        lib = ctypes.CDLL(str(path))
        DGBTRF = _dgbtrf_pointer()
    except (OSError, subprocess.SubprocessError, KeyError, AttributeError, ValueError):
        return None
    P, I, D = ctypes.c_void_p, ctypes.c_int, ctypes.c_double
    lib.kv_gbtrf.argtypes = [P, I, I, I, P, I, P, P]
    lib.kv_gbtrf.restype = I
    lib.kv_newton.argtypes = [I, I, I, P, I, P, P, P, D, P, P, P, P, D]
    lib.kv_newton.restype = D
    lib.kv_wrms.argtypes = [I, P, P, P]
    lib.kv_wrms.restype = D
    _lib = lib
    return lib
