"""Compile and load the generated rod C code.

On first use the generated kernels (``generated/rod_kernels.c``, ``rod_kernels_x4.c``,
``rod_tangent_kernels.c``, with the layout header ``rod_layout.h``) and the assembly
written by hand (``runtime/model/native/rod_assembly.c``, its tangent ``rod_tangent.c``,
the assemblies' ``system.c``) are compiled with the system C compiler into a
shared library in a cache folder keyed by the sha256 of the sources, the flags and the
compiler path. The cache folder is
``$KVROD_CACHE_DIR`` when set, else the platformdirs user cache dir of ``kvrod``.
The library is built under a unique temporary name in the cache folder and moved into
place with :func:`os.replace`, so concurrent first uses from several processes cannot
corrupt it (the last rename wins; both files are complete and identical).

If no compiler is found, compilation fails, or ``KVROD_NO_COMPILER=1``, :func:`load_library`
returns ``None`` after ONE ``warnings.warn``; callers then evaluate the serialised CasADi
kernels (``generated/rod_*.casadi``) in-process instead.

The compiler, its flags, the cache folder and the compile observers are
``runtime/native.py``'s; :func:`compile_native` compiles (or finds) this library and the
integrator's step loop up front, so a timed run does not pay for it (the notes report
compile and run times apart).
"""

from __future__ import annotations

import ctypes
import hashlib
import json
import os
import sys
import tempfile
import warnings
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import generated
from generated import rod_layout as L
from runtime.errors import GeneratedCodeError
from runtime.native import (
    CONTACT_KERNELS,
    LIBS,
    ROD_KERNELS,
    STEP_LOOP,
    add_compile_observer,
    cache_dir,
    compile_command,
    compiling,
    file_hash,
    file_sha256,
    find_compiler,
    host_id,
    remove_compile_observer,
    run_compiler,
)

#: the generated C (checked against generated/MANIFEST.json before it is compiled)
SOURCES = ("rod_kernels.c", "rod_kernels_x4.c", "rod_tangent_kernels.c")
HEADERS = ("rod_kernels.h", "rod_kernels_x4.h", "rod_tangent_kernels.h", "rod_layout.h")
#: the assembly, written by hand, compiled with them
NATIVE_DIR = Path(__file__).resolve().parent / "native"
#: the contact library (issue 32): the generated contact kernels and the loops around
#: them, compiled apart on the first problem with obstacles (the kernels' Jacobians are
#: long straight-line code: compiling them with the rod library would double every first
#: use); the rod library calls it through kvrod_contact's function pointers
CONTACT_SOURCES = ("rod_contact_kernels.c",)
CONTACT_HEADERS = ("rod_contact_kernels.h", "rod_layout.h")
CONTACT_NATIVE_SOURCES = ("rod_contact.c", "rod_self_contact.c")
CONTACT_NATIVE_HEADERS = ("rod_assembly.h", "rod_access.h", "rod_contact.h")
ASSEMBLY_SOURCES = ("rod_assembly.c", "rod_tangent.c", "system.c", "system_tangent.c")
ASSEMBLY_HEADERS = ("rod_assembly.h", "rod_access.h", "rod_contact.h", "rod_tangent.h",
                    "system.h", "system_tangent.h")


@dataclass(frozen=True)
class LibrarySpec:
    """One shared library built from generated and hand-written C: its name's prefix,
    what the compile observers are told, its sources and headers (generated/, native/)."""

    prefix: str
    what: str
    sources: tuple[str, ...]
    headers: tuple[str, ...]
    native_sources: tuple[str, ...]
    native_headers: tuple[str, ...]


ROD_LIBRARY = LibrarySpec("kvrod_rod", ROD_KERNELS, SOURCES, HEADERS, ASSEMBLY_SOURCES,
                          ASSEMBLY_HEADERS)
CONTACT_LIBRARY = LibrarySpec("kvrod_contact", CONTACT_KERNELS, CONTACT_SOURCES,
                              CONTACT_HEADERS, CONTACT_NATIVE_SOURCES,
                              CONTACT_NATIVE_HEADERS)


def source_paths(gdir: Path | None = None, spec: LibrarySpec = ROD_LIBRARY) -> list[Path]:
    """Every C source of a library (default the rod's): the generated kernels and the
    hand-written loops."""
    gdir = gdir or generated_dir()
    return [gdir / s for s in spec.sources] + [NATIVE_DIR / s for s in spec.native_sources]


def header_paths(gdir: Path | None = None, spec: LibrarySpec = ROD_LIBRARY) -> list[Path]:
    """Every header a library (default the rod's) is compiled with."""
    gdir = gdir or generated_dir()
    return [gdir / s for s in spec.headers] + [NATIVE_DIR / s for s in spec.native_headers]


def include_flags(gdir: Path | None = None) -> list[str]:
    """``-I`` flags for the generated and the hand-written headers."""
    return ["-I", str(gdir or generated_dir()), "-I", str(NATIVE_DIR)]

_warned = False


def compile_native() -> dict[str, float]:
    """Compile (or find in the cache) the rod kernels and the BDF step loop now.

    Returns the wall time (s) spent compiling each (0.0 when it came from the cache or
    cannot be built: then the in-process fallbacks are used, with their warning).
    """
    from runtime.solvers.native import loader

    spent = {ROD_KERNELS: 0.0, STEP_LOOP: 0.0}

    def record(what: str, seconds: float | None) -> None:
        if seconds is not None:
            spent[what] += seconds

    add_compile_observer(record)
    try:
        load_library()
        loader.load()
    finally:
        remove_compile_observer(record)
    return spent


def generated_dir() -> Path:
    """The ``generated/`` package folder."""
    return Path(generated.__file__).resolve().parent


def _manifest_hash(text: str) -> str:
    # same convention as derive.artifacts.sha256_text (content followed by NUL)
    return hashlib.sha256(text.encode() + b"\0").hexdigest()


def verify_manifest(gdir: Path | None = None, names: tuple[str, ...] | None = None, *,
                    exclude: tuple[str, ...] = ()) -> None:
    """Check generated files against generated/MANIFEST.json before anything uses them.

    ``names``: the files to check (default: every file the manifest lists, the Python
    formula modules ``constitutive.py`` and ``rod_layout.py`` as well as the C sources,
    headers and serialised CasADi kernels, and the C sources and headers even if the
    manifest lost their entries; less those whose names end in one of ``exclude``).
    Raises :class:`GeneratedCodeError` naming the file when the manifest is missing,
    unreadable or truncated, lacks an entry, or a file is missing or does not match its
    recorded hash (an edited ``constitutive.py`` would otherwise change every material
    silently).
    """
    gdir = gdir or generated_dir()
    mpath = gdir / "MANIFEST.json"
    regen = "run `kvrod generate` to regenerate generated/"
    try:
        manifest = json.loads(mpath.read_text())
        files = manifest["files"]
        if not isinstance(files, dict):
            raise TypeError("'files' is not a table")
    except FileNotFoundError:
        raise GeneratedCodeError(f"{mpath} is missing: the generated code cannot be checked; "
                                 f"{regen}") from None
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise GeneratedCodeError(f"{mpath} is unreadable or truncated ({type(exc).__name__}); "
                                 f"{regen}") from None
    if names is None:
        names = SOURCES + HEADERS + tuple(sorted(n for n in files
                                                 if n not in SOURCES + HEADERS
                                                 and not n.endswith(exclude)))
    for name in names:
        entry = files.get(name)
        if not isinstance(entry, dict) or "sha256" not in entry:
            raise GeneratedCodeError(f"generated/{name} has no entry in {mpath.name}; {regen}")
        try:
            # the bytes as written (LF, UTF-8) match without decoding (half the time of
            # this check, which every command runs); else the text as read (CRLF
            # checkouts) decides
            if file_digest(gdir / name) == entry.get("sha256"):
                continue
            text = (gdir / name).read_text()
        except OSError:
            raise GeneratedCodeError(f"generated/{name} is missing or unreadable; "
                                     f"{regen}") from None
        if _manifest_hash(text) != entry.get("sha256"):
            raise GeneratedCodeError(
                f"generated/{name} does not match generated/MANIFEST.json (edited by hand or "
                f"stale); {regen} (or restore the file from version control)")


@lru_cache(maxsize=1)
def require_generated() -> None:
    """Verify the generated tree once per process (see :func:`verify_manifest`), but for
    the serialised CasADi kernels (three quarters of its bytes), which
    :func:`require_casadi_kernels` checks when they are loaded."""
    verify_manifest(exclude=(".casadi",))


@lru_cache(maxsize=1)
def require_casadi_kernels() -> None:
    """Verify the serialised CasADi kernels (generated/rod_*.casadi) once per process."""
    verify_manifest(names=tuple(f"{name}.casadi" for name in L.KERNELS))


def file_digest(path: Path) -> str:
    """sha256 (hex) of a file's bytes followed by a NUL byte (the manifest's hash of a file
    as written), remembered while the file stays the same (:func:`runtime.native.file_sha256`):
    the manifest check and the libraries' cache keys read the same 2.5 MB of generated C."""
    return file_sha256(path, b"\0")


def library_key(compiler: str, gdir: Path | None = None,
                spec: LibrarySpec = ROD_LIBRARY) -> str:
    """sha256 of the sources' and headers' digests (:func:`file_digest`), flags, compiler
    path and host CPU (the cache key)."""
    h = hashlib.sha256()
    for path in (*source_paths(gdir, spec), *header_paths(gdir, spec)):
        h.update(path.name.encode() + b"\0" + file_digest(path).encode() + b"\0")
    h.update(" ".join((*compile_command(compiler), *LIBS, host_id())).encode())
    return h.hexdigest()


def compile_library(compiler: str, gdir: Path | None = None, outdir: Path | None = None,
                    spec: LibrarySpec = ROD_LIBRARY) -> Path:
    """Compile (or reuse) a shared library (default the rod's); returns its path. Atomic
    under concurrency."""
    gdir = gdir or generated_dir()
    outdir = outdir or cache_dir()
    outdir.mkdir(parents=True, exist_ok=True)
    target = _library_path(compiler, gdir, outdir, spec)
    sidecar = target.with_name(target.name + ".sha256")
    if _is_built(target):
        return target
    # missing, or a library whose bytes do not match the hash recorded when it was built
    # (corrupted or replaced): rebuild, never load it
    fd, tmp = tempfile.mkstemp(prefix=target.name + ".", suffix=".tmp", dir=outdir)
    os.close(fd)
    try:
        tail = [*include_flags(gdir), "-o", tmp,
                *(str(p) for p in source_paths(gdir, spec)), *LIBS]
        with compiling(spec.what):
            proc = run_compiler(tail, compiler)
        if proc.returncode != 0:
            raise RuntimeError(f"C compilation failed ({' '.join(proc.args)}):\n"
                               f"{proc.stderr}")
        side_tmp = Path(tmp + ".sha256")
        side_tmp.write_text(file_hash(Path(tmp)) + "\n")
        os.replace(side_tmp, sidecar)
        os.replace(tmp, target)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)
    return target


def _library_path(compiler: str, gdir: Path, outdir: Path, spec: LibrarySpec) -> Path:
    suffix = ".dll" if sys.platform == "win32" else ".so"
    return outdir / f"{spec.prefix}_{library_key(compiler, gdir, spec)[:32]}{suffix}"


def _is_built(target: Path) -> bool:
    """The library is there, with the hash recorded when it was built."""
    sidecar = target.with_name(target.name + ".sha256")
    try:
        return sidecar.read_text().strip() == file_hash(target)
    except OSError:
        return False


def library_built() -> bool:
    """Whether :func:`load_library` would load the rod library without compiling it (a
    compiler is found and the cache holds the library of these sources, intact)."""
    compiler = find_compiler()
    if compiler is None or not generated_dir().is_dir():
        return False
    return _is_built(_library_path(compiler, generated_dir(), cache_dir(), ROD_LIBRARY))


def _declare(lib: ctypes.CDLL) -> ctypes.CDLL:
    """Argument and result types of the C API (runtime/model/native/rod_assembly.h and
    system.h)."""
    i, d, p = ctypes.c_int, ctypes.c_double, ctypes.c_void_p
    lib.kvrod_residual.argtypes = [p, d, p, p, p]
    lib.kvrod_jacobian_band.argtypes = [p, d, p, p, d, d, i, p]
    lib.kvrod_jacobian_band_cells.argtypes = [p, d, p, p, d, d, i, p, i, i, i]
    lib.kvrod_diagnostics.argtypes = [p, d, p, p, p]
    lib.kvrod_energies.argtypes = [p, i, p, p, p, p]
    for name in ("kvrod_residual", "kvrod_jacobian_band", "kvrod_jacobian_band_cells",
                 "kvrod_diagnostics",
                 "kvrod_energies", "kvrod_n_state"):
        getattr(lib, name).restype = i
    lib.kvrod_n_state.argtypes = [i, i]
    lib.kvrod_energies_contact.argtypes = [p, i, p, p, p, p]
    lib.kvrod_energies_contact.restype = i
    # the residual's tangent (runtime/model/native/rod_tangent.h)
    lib.kvrod_residual_tangent.argtypes = [p, p, d, p, p, p, p, p]
    lib.kvrod_residual_tangent.restype = i
    lib.kvrod_sens_residual.argtypes = [p, d, p, p, i, p, p, p]
    lib.kvrod_sens_residual.restype = i
    lib.kvrod_jacobian_system.argtypes = [p, d, p, p, d, p]
    lib.kvrod_jacobian_system.restype = i
    # an assembly of rods (runtime/model/native/system.h)
    lib.kvsys_residual.argtypes = [p, d, p, p, p]
    lib.kvsys_jacobian.argtypes = [p, d, p, p, d, p]
    lib.kvsys_energies.argtypes = [p, i, p, p, p, p]
    lib.kvsys_link_values.argtypes = [p, i, p, p, p]
    lib.kvsys_max_step.argtypes = [p, d, p, p]
    lib.kvsys_max_step.restype = d
    for name in ("kvsys_residual", "kvsys_jacobian", "kvsys_energies", "kvsys_link_values"):
        getattr(lib, name).restype = i
    lib.kvsys_residual_tangent.argtypes = [p, p, d, p, p, p, p, p]
    lib.kvsys_residual_tangent.restype = i
    lib.kvsys_sens_residual.argtypes = [p, d, p, p, i, p, p, p]
    lib.kvsys_sens_residual.restype = i
    return lib


@lru_cache(maxsize=1)
def _load_cached() -> ctypes.CDLL | None:
    global _warned
    require_generated()
    compiler = find_compiler()
    reason = None
    if compiler is None:
        reason = ("no C compiler found" if not os.environ.get("KVROD_NO_COMPILER")
                  else "KVROD_NO_COMPILER is set")
    else:
        try:
            return _declare(ctypes.CDLL(str(compile_library(compiler))))
        except (RuntimeError, OSError) as exc:
            reason = f"compiling the generated C code failed: {exc}"
    if not _warned:
        warnings.warn(f"kvrod: {reason}; evaluating the CasADi kernels in-process instead "
                      "(same results, much slower)", RuntimeWarning, stacklevel=3)
        _warned = True
    return None


def library_loads() -> int:
    """How many times this process has loaded (or tried to load) the rod library: 1 after
    the first use, more only after :func:`clear_cache` (a sweep's workers report it: each
    loads once, however many points it runs)."""
    return _load_cached.cache_info().misses


def load_library() -> ctypes.CDLL | None:
    """The compiled rod library (ctypes), or None for the in-process CasADi fallback."""
    return _load_cached()


def _declare_contact(lib: ctypes.CDLL) -> ctypes.CDLL:
    """Argument and result types of the contact library (rod_contact.h)."""
    i, d, p = ctypes.c_int, ctypes.c_double, ctypes.c_void_p
    lib.kvrod_contact_values.argtypes = [p, p, p]
    lib.kvrod_contact_points.argtypes = [p, p, p, i]
    for name in ("kvrod_contact_values", "kvrod_contact_points"):
        getattr(lib, name).restype = i
    lib.kvrod_contact_max_step.argtypes = [p, p]
    lib.kvrod_contact_max_step.restype = d
    lib.kvrod_contact_error_weights.argtypes = [p, p, d, p, p]
    lib.kvrod_contact_error_weights.restype = i
    lib.kvrod_self_values.argtypes = [p, p, p]
    lib.kvrod_self_values.restype = i
    lib.kvrod_self_couplings.argtypes = [p, p]
    lib.kvrod_self_couplings.restype = i
    lib.kvsys_pairs_values.argtypes = [p, p, p]
    lib.kvsys_pairs_values.restype = i
    return lib


@lru_cache(maxsize=1)
def load_contact_library() -> ctypes.CDLL:
    """The compiled contact library (ctypes; compiled on first use, cached like the rod
    library). Contact has no in-process fallback: raises :class:`GeneratedCodeError`
    saying why when it cannot be built."""
    require_generated()
    compiler = find_compiler()
    if compiler is None:
        raise GeneratedCodeError("contact with obstacles needs a C compiler (none found, or "
                                 "KVROD_NO_COMPILER is set)")
    try:
        return _declare_contact(ctypes.CDLL(str(compile_library(compiler,
                                                                spec=CONTACT_LIBRARY))))
    except (RuntimeError, OSError) as exc:
        raise GeneratedCodeError(f"compiling {CONTACT_KERNELS} failed: {exc}") from None


def clear_cache() -> None:
    """Forget the loaded library (tests switch KVROD_NO_COMPILER / KVROD_CACHE_DIR)."""
    global _warned
    _load_cached.cache_clear()
    load_contact_library.cache_clear()
    require_generated.cache_clear()
    require_casadi_kernels.cache_clear()
    _warned = False
