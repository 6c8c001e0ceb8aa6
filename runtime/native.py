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
import json
import os
import shutil
import subprocess
import sys
import tempfile
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
    # platformdirs' rule on Linux without importing it (3-4 ms of every command's start;
    # tests/runtime/test_rod_build.py checks the two agree): $XDG_CACHE_HOME when it is
    # an absolute path, else ~/.cache; anything unusual (a relative HOME) asks it
    if sys.platform.startswith("linux"):
        for root, tail in ((os.environ.get("XDG_CACHE_HOME", ""), ()),
                           (os.environ.get("HOME", ""), (".cache",))):
            if os.path.isabs(root):
                return Path(root, *tail, "kvrod")
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


#: the digests that :func:`file_sha256` remembers across processes, in the cache folder
DIGESTS_FILE = "file-digests.json"
#: a file whose modification or change time is less than this many seconds old when it is
#: hashed is remembered in this process only: a second edit within the file system's
#: timestamp resolution could leave its stat signature as it was (git's "racily clean"
#: index entries), and across processes nothing else would notice
RACY_SECONDS = 2.0
#: (trailer hex, absolute path) -> (stat signature, digest); None: not read yet
_digests: dict[str, tuple[tuple[int, ...], str]] | None = None


def _stat_signature(st: os.stat_result) -> tuple[int, ...]:
    # the change time too: ``cp -p``, ``rsync -t`` or ``tar x`` restore an edited file's
    # modification time, never its change time
    return (st.st_dev, st.st_ino, st.st_size, st.st_mtime_ns, st.st_ctime_ns)


def _remembered() -> dict[str, tuple[tuple[int, ...], str]]:
    global _digests
    if _digests is None:
        _digests = {}
        try:
            data = json.loads((cache_dir() / DIGESTS_FILE).read_text())
            for key, (sig, digest) in data.items():
                if isinstance(digest, str) and len(digest) == 64:
                    _digests[key] = (tuple(int(v) for v in sig), digest)
        except (OSError, ValueError, TypeError, AttributeError):
            pass                    # none yet, unreadable or foreign: hash again
    return _digests


def _remember(key: str, sig: tuple[int, ...], digest: str) -> None:
    """Keep the digest in the cache folder (atomically; a folder that cannot be written
    only costs the next process the hashing)."""
    folder = cache_dir()
    try:
        folder.mkdir(parents=True, exist_ok=True)
        try:
            kept = json.loads((folder / DIGESTS_FILE).read_text())
            if not isinstance(kept, dict):
                kept = {}
        except (OSError, ValueError):
            kept = {}
        kept[key] = [list(sig), digest]
        fd, tmp = tempfile.mkstemp(prefix=DIGESTS_FILE + ".", suffix=".tmp", dir=folder)
        with os.fdopen(fd, "w") as f:
            json.dump(kept, f)
        os.replace(tmp, folder / DIGESTS_FILE)
    except OSError:
        pass


def file_sha256(path: Path | str, trailer: bytes = b"") -> str:
    """sha256 (hex) of a file's bytes followed by ``trailer``, computed once while the
    file stays the same file (device, inode, size, modification and change times): in
    this process, and in later ones through :data:`DIGESTS_FILE` in the cache folder
    (files older than :data:`RACY_SECONDS`). Every command checks the generated tree
    against its manifest and each library against its recorded hash: 2.5 MB hashed,
    ~8 ms a process, before this memo (an edit changes the signature, so it is hashed
    again)."""
    memo = _remembered()
    key = trailer.hex() + ":" + os.path.abspath(path)
    st = os.stat(path)          # before reading: a file changed meanwhile is hashed again
    sig = _stat_signature(st)
    seen = memo.get(key)
    if seen is not None and seen[0] == sig:
        return seen[1]
    digest = hashlib.sha256(Path(path).read_bytes() + trailer).hexdigest()
    memo[key] = (sig, digest)
    if time.time() - max(st.st_mtime, st.st_ctime) > RACY_SECONDS:
        _remember(key, sig, digest)
    return digest


def file_hash(path: Path) -> str:
    """sha256 of a file's bytes (hex), as :func:`file_sha256` remembers it."""
    return file_sha256(path)
