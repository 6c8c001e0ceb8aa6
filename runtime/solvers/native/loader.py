"""Compile (on first use, cached by source, flags and host CPU) and load the integrator's
C library: ``step_loop.c``, which includes ``band.c`` and ``condensed.c`` (one translation
unit, so that the kernels inline across them); declare its functions. ``load()`` is None
without a C compiler (or with ``KVROD_NO_COMPILER=1``)."""

from __future__ import annotations

import ctypes
import hashlib
import os
import platform
import subprocess
import tempfile
from pathlib import Path

from runtime import native

from .step_loop import CoreStruct

#: the C sources, kept as files beside this module: step_loop.c includes band.c,
#: condensed.c, blocks.c and statics.c (one unit; the first is the one compiled)
FILES = ("step_loop.c", "band.c", "condensed.c", "blocks.c", "statics.c")
SOURCES = {name: Path(__file__).with_name(name).read_text() for name in FILES}
SOURCE = "".join(SOURCES.values())

# Flags as for the rod kernels (runtime/native.py: -O3, -march=native with the host
# CPU in the cache key, plain flags if the compiler rejects them); -ffp-contract=off
# matters here too: no fused multiply-adds, so the C step loop rounds like the NumPy
# path of bdf.py (compared step by step in the tests). Measured at N = 1000
# (kv_cond_factor / kv_cond_newton timed in C, us; GCC 12, AMD EPYC Zen 4): -O2 711 /
# 112; -O3 477 / 88 (complete unrolling and vectorisation of the fixed-size 6 x 6
# kernels of the block path); -O3 -march=native 537 / 70 (AVX2: fewer vector
# instructions in the products, but GCC's AVX-512 code of the pivoting and gathering
# kernels is slower here), so -mno-avx512f on x86-64: 468 / 72.
_EXTRA = ("-mno-avx512f",) if platform.machine().lower() in ("x86_64", "amd64") else ()
# POSIX threads for the energy audit's second thread (step_loop.c: KV_THREADS); on
# Windows the audit stays in the loop
_THREADS = () if os.name == "nt" else ("-pthread",)
_lib: ctypes.CDLL | None = None
_tried = False


def _compile(cc: str, dest: Path) -> None:
    dest.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(dir=dest.parent) as tmp:
        for name, text in SOURCES.items():
            (Path(tmp) / name).write_text(text)
        out = Path(tmp) / dest.name
        with native.compiling(native.STEP_LOOP):
            proc = native.run_compiler([*_EXTRA, str(Path(tmp) / FILES[0]), "-o", str(out),
                                       *_THREADS, "-lm"], cc)
        if proc.returncode != 0:
            raise subprocess.SubprocessError(proc.stderr)
        os.replace(out, dest)


def _library_path(cc: str) -> Path:
    key = hashlib.sha256((SOURCE + " ".join((*native.compile_command(cc), *_EXTRA, *_THREADS))
                          + native.host_id()).encode()).hexdigest()[:16]
    return native.cache_dir() / f"kvrod_bdf_{key}.so"


def built() -> bool:
    """Whether :func:`load` would load the helpers without compiling them."""
    cc = native.find_compiler()
    return cc is not None and _library_path(cc).exists()


def load() -> ctypes.CDLL | None:
    """The compiled helpers (cached per source hash), or None if they cannot be built."""
    global _lib, _tried
    if _tried:
        return _lib
    _tried = True
    cc = native.find_compiler()
    if cc is None:
        return None
    path = _library_path(cc)
    try:
        if not path.exists():
            _compile(cc, path)
        lib = ctypes.CDLL(str(path))
    except (OSError, subprocess.SubprocessError):
        return None
    return _declare(lib)


def _declare(lib: ctypes.CDLL) -> ctypes.CDLL:
    global _lib
    P, I, D = ctypes.c_void_p, ctypes.c_int, ctypes.c_double
    lib.kv_gbtrf.argtypes = [I, I, I, P, I, P, P]
    lib.kv_gbtrf.restype = I
    lib.kv_gbtrs.argtypes = [I, I, I, P, I, P, P, P]
    lib.kv_gbtrs.restype = None
    lib.kv_newton.argtypes = [I, I, I, P, I, P, P, P, D, P, P, P, P, D]
    lib.kv_newton.restype = D
    lib.kv_interp.argtypes = [I, I, I, D, P, P, P, P, P]
    lib.kv_interp.restype = None
    lib.kv_interp_at_tn.argtypes = [I, I, P, P, P]
    lib.kv_interp_at_tn.restype = None
    lib.kv_cond_factor.argtypes = [P, P, D]
    lib.kv_cond_factor.restype = I
    lib.kv_cond_solve.argtypes = [P, P, P]
    lib.kv_cond_solve.restype = None
    lib.kv_cond_newton.argtypes = [P, P, P, D, P, P, P, P, D]
    lib.kv_cond_newton.restype = D
    lib.kv_blocks_factor.argtypes = [P]
    lib.kv_blocks_factor.restype = I
    lib.kv_blocks_solve.argtypes = [P, P]
    lib.kv_blocks_solve.restype = None
    lib.kv_blocks_newton.argtypes = [P, P, D, P, P, P, P, D]
    lib.kv_blocks_newton.restype = D
    lib.kv_wrms.argtypes = [I, P, P, P]
    lib.kv_wrms.restype = D
    lib.kv_static_sizeof.argtypes = []
    lib.kv_static_sizeof.restype = ctypes.c_size_t
    for name in ("kv_static_residual", "kv_static_jacobian"):
        getattr(lib, name).argtypes = [P, P] + ([P] if name.endswith("residual") else [])
        getattr(lib, name).restype = I
    lib.kv_static_factor.argtypes = [P]
    lib.kv_static_factor.restype = I
    lib.kv_static_solve.argtypes = [P, P]
    lib.kv_static_solve.restype = None
    lib.kv_static_retract.argtypes = [P, P, P, P]
    lib.kv_static_retract.restype = None
    lib.kv_static_trial.argtypes = [P, P, P, P, P, P, P]
    lib.kv_static_trial.restype = I
    lib.kv_ida_sizeof.argtypes = []
    lib.kv_ida_sizeof.restype = ctypes.c_size_t
    lib.kv_ida_advance.argtypes = [P, D, ctypes.c_longlong]
    lib.kv_ida_advance.restype = I
    lib.kv_ida_watch_reset.argtypes = [P]
    lib.kv_ida_watch_reset.restype = None
    if lib.kv_ida_sizeof() != ctypes.sizeof(CoreStruct):
        raise RuntimeError("kv_ida (step_loop.c) and CoreStruct (step_loop.py) differ in "
                           "size: the mirror is out of date")
    _lib = lib
    return lib
