"""The derivation cached on disk: inspecting it takes a second, not a minute.

Deriving every step (:func:`derive.catalogue.derive_all`) takes tens of seconds of SymPy.
The records are pure functions of the code in derive/ and of the tools, so they are kept in
the user's cache folder (never in the checkout):

* folder: ``$KVROD_CACHE_DIR/derivation``, else ``<platformdirs user cache dir of
  kvrod>/derivation``, the root the compiled kernels use (``runtime.native.cache_dir``;
  derive/ may not import runtime/, so the rule is repeated here and a test checks both agree);
* key: sha256 of every file in derive/ (sources and templates, by relative path and
  bytes), the Python implementation and version and the versions of SymPy, mpmath, CasADi
  and Jinja2 (:func:`tool_versions`; pickled SymPy objects are only trusted by the version
  that wrote them). Any change is a different key, so the entry is derived afresh;
* entry: ``steps-<key>.pickle``: a magic line, the sha256 of the payload and the payload.
  A file whose magic, checksum, key or step names do not match, or that does not unpickle,
  is a miss (removed and rebuilt). Written under a temporary name and renamed, so readers
  never see half a file and concurrent writers cannot corrupt it (the last rename wins;
  both wrote the same records). A hit marks the entry as used; storing keeps the
  :data:`KEEP` most recently used entries (several checkouts may share the folder) and
  removes older ones with their companions. Beside it ``steps-<key>.json``: the per-step verdict
  against the stated forms, read by ``kvrod derive list`` without SymPy;
* :func:`memo`: other derived data (plain JSON), e.g. the band widths of the generated
  Jacobians (``derive.codegen_rod``), under the same key;
* ``KVROD_DERIVE_CACHE=0`` derives from scratch and reads and writes nothing (the test that
  regenerates generated/ from scratch uses it).

Serialisation: pickle (measured against ``srepr``/``sympify``: 0.03 s against 0.1 s to load
all steps, and exact). Plain pickling rebuilds every node through its constructor, which
re-evaluates: ``Mul(1/3, Add(...))`` as the derivation left it would come back distributed,
and ``Sum``/``Integral`` re-wrapped under ``evaluate(False)``; printed forms and the
generated code would change. So ``Add``/``Mul`` are rebuilt from their exact arguments
(``_from_args``) and ``Pow`` unevaluated; :func:`store` checks the round trip (``srepr`` of
every result and stated form) before writing and writes nothing if it is not exact.
"""

from __future__ import annotations

import contextlib
import hashlib
import io
import json
import os
import pickle
import platform
import sys
import tempfile
import warnings
from collections.abc import Callable, Mapping
from importlib import metadata
from pathlib import Path
from typing import TYPE_CHECKING, Any

from derive.catalogue import STEP_NAMES, Progress, derive_all

if TYPE_CHECKING:
    from derive.step import Step

#: bumped when the entry layout changes
FORMAT = 1
MAGIC = b"kvrod derivation cache %d\n" % FORMAT
#: tools whose version is part of the key (the derivation's SymPy objects and mpmath
#: numbers; CasADi and Jinja2 for what is generated from them)
KEY_TOOLS = ("sympy", "mpmath", "casadi", "jinja2")
DISABLE_ENV = "KVROD_DERIVE_CACHE"
#: entries kept when a new one is stored (by last use)
KEEP = 16
#: parts of derive/ that are not its content
_IGNORED_DIRS = {"__pycache__"}
_IGNORED_SUFFIXES = (".pyc", ".pyo")


class CacheEntryError(ValueError):
    """A cache entry that is not a complete, matching derivation (treated as a miss)."""


def enabled() -> bool:
    """False when ``KVROD_DERIVE_CACHE`` is 0/no/off/false (derive from scratch)."""
    return os.environ.get(DISABLE_ENV, "1").strip().lower() not in ("0", "no", "off", "false")


def cache_root() -> Path:
    """$KVROD_CACHE_DIR, else the platformdirs user cache dir of kvrod (the folder of the
    compiled kernels, ``runtime.native.cache_dir``)."""
    env = os.environ.get("KVROD_CACHE_DIR")
    if env:
        return Path(env)
    import platformdirs

    return Path(platformdirs.user_cache_dir("kvrod"))


def cache_dir() -> Path:
    """The folder of the derivation entries."""
    return cache_root() / "derivation"


def derive_dir() -> Path:
    """The derive/ package folder whose content keys the cache."""
    return Path(__file__).resolve().parent


def source_files(root: Path | None = None) -> list[Path]:
    """Every file of derive/ (sources, templates, anything else), sorted by relative path;
    byte-code caches excluded."""
    root = Path(root) if root is not None else derive_dir()
    files = [p for p in root.rglob("*") if p.is_file()
             and not _IGNORED_DIRS.intersection(p.relative_to(root).parts)
             and not p.name.endswith(_IGNORED_SUFFIXES)]
    return sorted(files, key=lambda p: p.relative_to(root).as_posix())


def _version(name: str) -> str:
    try:
        return metadata.version(name)
    except metadata.PackageNotFoundError:
        return "absent"


def tool_versions() -> dict[str, str]:
    """The Python implementation and version and the versions of :data:`KEY_TOOLS`."""
    out = {"python": f"{sys.implementation.name} {platform.python_version()}"}
    out.update({name: _version(name) for name in KEY_TOOLS})
    return out


def cache_key(root: Path | None = None, versions: Mapping[str, str] | None = None) -> str:
    """sha256 of the entry format, the tool versions and every file of derive/."""
    root = Path(root) if root is not None else derive_dir()
    h = hashlib.sha256(MAGIC)
    h.update(json.dumps(dict(versions if versions is not None else tool_versions()),
                        sort_keys=True).encode() + b"\0")
    for path in source_files(root):
        data = path.read_bytes()
        h.update(path.relative_to(root).as_posix().encode() + b"\0")
        h.update(str(len(data)).encode() + b"\0" + data + b"\0")
    return h.hexdigest()


def entry_path(key: str) -> Path:
    """The pickle of the entry with ``key``."""
    return cache_dir() / f"steps-{key[:40]}.pickle"


def summary_path(key: str) -> Path:
    """The JSON verdicts beside the entry with ``key``."""
    return cache_dir() / f"steps-{key[:40]}.json"


# --------------------------------------------------------------------------------------
# serialisation
# --------------------------------------------------------------------------------------


def _assoc(cls, args):
    return cls._from_args(args)


def _power(base, exp):
    import sympy as sp

    return sp.Pow(base, exp, evaluate=False)


def _step(state: dict) -> Step:
    from derive.step import Step, _frozen

    for key in ("results", "stated", "matches"):
        state[key] = _frozen(state[key])
    return Step(**state)


class _Pickler(pickle.Pickler):
    """Pickles SymPy trees exactly as they are (see the module docstring) and Step records
    as their fields."""

    def reducer_override(self, obj):
        import sympy as sp

        from derive.step import Step

        if isinstance(obj, (sp.Add, sp.Mul)):
            return _assoc, (type(obj), obj.args)
        if isinstance(obj, sp.Pow):
            return _power, obj.args
        if isinstance(obj, Step):
            state = {f: getattr(obj, f) for f in obj.__dataclass_fields__}
            for key in ("results", "stated", "matches"):
                state[key] = dict(state[key])
            return _step, (state,)
        return NotImplemented


def dumps(steps: Mapping[str, Step], key: str) -> bytes:
    """The entry file's bytes: magic line, sha256 of the payload, payload."""
    buf = io.BytesIO()
    _Pickler(buf, protocol=pickle.HIGHEST_PROTOCOL).dump(
        {"key": key, "names": list(steps), "steps": dict(steps)})
    payload = buf.getvalue()
    return MAGIC + hashlib.sha256(payload).hexdigest().encode() + b"\n" + payload


def loads(data: bytes, key: str) -> dict[str, Step]:
    """The records of an entry's bytes; :class:`CacheEntryError` unless complete and for
    ``key`` with exactly the pipeline's steps."""
    if not data.startswith(MAGIC):
        raise CacheEntryError("not a derivation cache entry of this format")
    digest, sep, payload = data[len(MAGIC):].partition(b"\n")
    if not sep or hashlib.sha256(payload).hexdigest().encode() != digest:
        raise CacheEntryError("checksum mismatch (truncated or corrupted)")
    try:
        doc = pickle.loads(payload)
    except Exception as exc:  # any unpickling failure is a miss
        raise CacheEntryError(f"does not unpickle ({type(exc).__name__}: {exc})") from exc
    if not isinstance(doc, dict) or doc.get("key") != key:
        raise CacheEntryError("written for another key")
    steps = doc.get("steps")
    if not isinstance(steps, dict) or tuple(steps) != STEP_NAMES:
        raise CacheEntryError("does not hold the pipeline's steps")
    return steps


def _same(a: Mapping[str, Step], b: Mapping[str, Step]) -> bool:
    """Every result and stated form identical in structure (srepr), and the same verdicts."""
    import sympy as sp

    for name, s in a.items():
        t = b[name]
        if (s.name, s.title, s.equations, s.inputs, dict(s.matches)) != \
                (t.name, t.title, t.equations, t.inputs, dict(t.matches)):
            return False
        for field in ("results", "stated"):
            x, y = getattr(s, field), getattr(t, field)
            if list(x) != list(y) or any(sp.srepr(x[k]) != sp.srepr(y[k]) for k in x):
                return False
    return True


# --------------------------------------------------------------------------------------
# reading and writing
# --------------------------------------------------------------------------------------


def _write_atomic(path: Path, data: bytes) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    finally:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)


def load(key: str | None = None) -> dict[str, Step] | None:
    """The cached records for ``key`` (default: this checkout and these tools), or None on
    a miss; a corrupt entry is removed (and so rebuilt by :func:`load_or_derive`)."""
    key = key or cache_key()
    path = entry_path(key)
    try:
        data = path.read_bytes()
    except OSError:
        return None
    try:
        steps = loads(data, key)
    except CacheEntryError:
        with contextlib.suppress(OSError):
            path.unlink()
        return None
    with contextlib.suppress(OSError):
        os.utime(path)                # last use, for pruning
    return steps


def prune(keep: int = KEEP) -> list[Path]:
    """Remove all but the ``keep`` most recently used entries (with the files that share
    their key: verdicts, memos); returns the removed files."""
    folder = cache_dir()
    entries = []
    for p in folder.glob("steps-*.pickle"):
        with contextlib.suppress(OSError):
            entries.append((p.stat().st_mtime, p))
    entries.sort(reverse=True)
    removed = []
    for _, p in entries[keep:]:
        tag = p.stem.removeprefix("steps-")
        for q in folder.glob(f"*-{tag}.*"):
            with contextlib.suppress(OSError):
                q.unlink()
                removed.append(q)
    return removed


def summary(key: str | None = None) -> dict[str, Any] | None:
    """The verdicts of the cached derivation for ``key`` without SymPy: ``{"steps": {name:
    {"all_match": bool, "checks": int}}}``, or None when there is none (or it is unreadable)."""
    if not enabled():
        return None
    key = key or cache_key()
    try:
        doc = json.loads(summary_path(key).read_text())
    except (OSError, ValueError):
        return None
    if (not isinstance(doc, dict) or doc.get("key") != key
            or tuple(doc.get("steps", ())) != STEP_NAMES):
        return None
    return doc


def store(steps: Mapping[str, Step], key: str | None = None) -> Path | None:
    """Write the entry for ``key`` (default: this checkout and these tools) atomically;
    returns its path, or None when it could not be written (the cache is an optimisation:
    a read-only cache folder is not an error) or would not read back exactly."""
    key = key or cache_key()
    data = dumps(steps, key)
    try:
        back = loads(data, key)
    except CacheEntryError:
        back = None
    if back is None or not _same(steps, back):
        warnings.warn("kvrod: the derivation does not round-trip through the cache; it is "
                      "not cached (a bug: please report)", RuntimeWarning, stacklevel=2)
        return None
    verdicts = {"key": key, "versions": tool_versions(),
                "steps": {n: {"all_match": bool(s.all_match), "checks": len(s.matches)}
                          for n, s in steps.items()}}
    path = entry_path(key)
    try:
        _write_atomic(path, data)
        _write_atomic(summary_path(key), (json.dumps(verdicts, indent=1) + "\n").encode())
        prune()
    except OSError:
        return None
    return path


def load_or_derive(progress: Progress | None = None) -> dict[str, Step]:
    """The records from the cache, else derived (``progress`` told of every step) and
    stored. With the cache disabled (:func:`enabled`) always derived, nothing written."""
    if not enabled():
        return derive_all(progress)
    key = cache_key()
    steps = load(key)
    if steps is None:
        steps = derive_all(progress)
        store(steps, key)
    return steps


def memo_path(name: str, key: str) -> Path:
    """The JSON file of :func:`memo` ``name`` for ``key``."""
    return cache_dir() / f"{name}-{key[:40]}.json"


def memo(name: str, compute: Callable[[], Any]) -> Any:
    """``compute()`` (a pure function of derive/ and the tools, returning plain JSON data:
    lists, dicts, str, int, float, bool, None) from the cache, else computed and stored
    under the current key. Tuples come back as lists."""
    if not enabled():
        return compute()
    key = cache_key()
    path = memo_path(name, key)
    try:
        doc = json.loads(path.read_text())
        if isinstance(doc, dict) and doc.get("key") == key and "value" in doc:
            return doc["value"]
    except (OSError, ValueError):
        pass
    value = compute()
    with contextlib.suppress(OSError):
        _write_atomic(path, (json.dumps({"key": key, "value": value}) + "\n").encode())
    return value
