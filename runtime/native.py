"""Compiling native code on first use: the compiler, its flags, the cache folder and the
compile observers (one module below the rod's kernels, ``runtime/model/build.py``, and the
integrator's step loop, ``runtime/solvers/native``, which both build shared libraries
with it).

The cache folder is ``$KVROD_CACHE_DIR`` when set, else the platformdirs user cache dir
of ``kvrod``; a library's cache key carries its sources, the flags, the compiler and the
host CPU (:func:`host_id`), since the code is compiled for the machine that runs it
(``-march=native``) and a cache folder may be shared by the machines of a cluster.

A first compilation takes seconds to tens of seconds. Library code never prints: whoever
wants to say so registers an observer (:func:`add_compile_observer`; the command line
prints one line on stderr).
"""

from __future__ import annotations

import contextlib
import hashlib
import os
import shutil
import subprocess
import time
from collections.abc import Callable, Iterator
from functools import lru_cache
from pathlib import Path

# -O3 -march=native: the kernels and the step loop are compiled on the machine that runs
# them (measured at N = 1000 against -O2: residual -8 %, Jacobian -9 %, energies -23 %).
# -ffp-contract=off: no fused multiply-adds (the rounding stays that of -O2 and of the
# NumPy fallback, which the tests compare step by step).
# -fno-semantic-interposition: a function of the library may be inlined into its callers
# in the same file although it is exported (GCC otherwise calls even CasADi's casadi_sq
# through the PLT); no change to the arithmetic (same results bit for bit); measured on
# the N = 50 cantilever: energies -10 %, a whole simulate -10 %. Dropped with
# -march=native by a compiler that refuses them (NATIVE: retried without).
CFLAGS = ("-O3", "-fPIC", "-shared", "-std=c99", "-ffp-contract=off")
NATIVE = ("-march=native", "-fno-semantic-interposition")
LIBS = ("-lm",)

#: what is compiled, as the observers are told
ROD_KERNELS = "the rod kernels"
STEP_LOOP = "the BDF step loop"
CONTACT_KERNELS = "the contact kernels"
#: rough first-build wall times (s) for the observers' messages (measured on 2 shared
#: cores: 6 s and 9.5 s with GCC; the contact kernels, compiled on the first problem with
#: obstacles, about 1.6 times the rod kernels)
TYPICAL_SECONDS = {ROD_KERNELS: 10, STEP_LOOP: 10, CONTACT_KERNELS: 15}

CompileObserver = Callable[[str, "float | None"], None]
_observers: list[CompileObserver] = []


def add_compile_observer(observer: CompileObserver) -> None:
    """Call ``observer(what, None)`` when a compilation of ``what`` (:data:`ROD_KERNELS`,
    :data:`STEP_LOOP`) starts and ``observer(what, seconds)`` when it ends (wall time)."""
    if observer not in _observers:
        _observers.append(observer)


def remove_compile_observer(observer: CompileObserver) -> None:
    """Stop calling ``observer`` (no error if it was not registered)."""
    with contextlib.suppress(ValueError):
        _observers.remove(observer)


@contextlib.contextmanager
def compiling(what: str) -> Iterator[None]:
    """Tell the observers that ``what`` is being compiled, and how long it took."""
    for obs in list(_observers):
        obs(what, None)
    t0 = time.perf_counter()
    yield
    seconds = time.perf_counter() - t0
    for obs in list(_observers):
        obs(what, seconds)


def cache_dir() -> Path:
    """Cache folder for compiled libraries ($KVROD_CACHE_DIR or the user cache dir)."""
    env = os.environ.get("KVROD_CACHE_DIR")
    if env:
        return Path(env)
    import platformdirs

    return Path(platformdirs.user_cache_dir("kvrod"))


def find_compiler() -> str | None:
    """Path of the C compiler ($CC, cc, gcc, clang) or None; None if KVROD_NO_COMPILER=1."""
    if os.environ.get("KVROD_NO_COMPILER", "") not in ("", "0"):
        return None
    for cand in (os.environ.get("CC"), "cc", "gcc", "clang"):
        if cand and (path := shutil.which(cand)):
            return path
    return None


@lru_cache(maxsize=1)
def host_id() -> str:
    """The CPU that native code is compiled for: the machine type and, on Linux, the
    model name and instruction-set flags of /proc/cpuinfo (part of every cache key)."""
    import platform

    parts = [platform.machine(), platform.system()]
    try:
        with open("/proc/cpuinfo", encoding="utf-8", errors="replace") as f:
            for line in f:
                key = line.split(":", 1)[0].strip()
                if key in ("model name", "flags", "Features", "CPU part"):
                    parts.append(line.strip())
                elif not line.strip() and len(parts) > 2:
                    break                      # the first processor is enough
    except OSError:
        pass
    return hashlib.sha256("\n".join(parts).encode()).hexdigest()[:16]


def compile_command(compiler: str, native: bool = True) -> list[str]:
    """The compiler and flags (with -march=native unless ``native`` is False)."""
    return [compiler, *CFLAGS, *(NATIVE if native else ())]


def run_compiler(cmd_tail: list[str], compiler: str) -> subprocess.CompletedProcess:
    """Compile with the native flags, or without them if the compiler rejects them."""
    proc = subprocess.run(compile_command(compiler) + cmd_tail, capture_output=True,
                          text=True)
    if proc.returncode != 0:
        retry = subprocess.run(compile_command(compiler, native=False) + cmd_tail,
                               capture_output=True, text=True)
        if retry.returncode == 0:
            return retry
    return proc


def file_hash(path: Path) -> str:
    """sha256 of a file's bytes (hex)."""
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()
