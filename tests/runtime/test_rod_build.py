"""Build and load of the generated C (runtime/model/build.py): cache, concurrency, manifest check,
fallback to in-process CasADi with one warning."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

from runtime import native
from runtime.errors import GeneratedCodeError
from runtime.model import build
from tests.rods import rod_model

ROOT = Path(__file__).resolve().parents[2]
needs_cc = pytest.mark.skipif(native.find_compiler() is None, reason="no C compiler")


@pytest.fixture
def fresh_build(monkeypatch, tmp_path):
    monkeypatch.setenv("KVROD_CACHE_DIR", str(tmp_path / "cache"))
    build.clear_cache()
    yield tmp_path / "cache"
    monkeypatch.undo()
    build.clear_cache()


@needs_cc
def test_compiles_into_content_keyed_cache(fresh_build):
    m = rod_model(3)
    assert m.backend == "c"
    libs = list(fresh_build.glob("kvrod_rod_*.so"))
    assert len(libs) == 1
    assert build.library_key(native.find_compiler())[:32] in libs[0].name
    assert not list(fresh_build.glob("*.tmp"))


#: a one-function library: the cache's rules (content key, atomic publication, the hash
#: sidecar) are the same for every LibrarySpec, and compiling the rod library three more
#: times would cost minutes of the suite
TINY_C = "int kvrod_n_state(int N, int nb) { return 6 * N + 3 * nb; }\n"


def tiny_spec(gdir: Path):
    gdir.mkdir(parents=True, exist_ok=True)
    (gdir / "tiny.c").write_text(TINY_C)
    return build.LibrarySpec("kvrod_tiny", "a test library", ("tiny.c",), (), (), ())


@needs_cc
def test_concurrent_first_use_does_not_corrupt_the_cache(tmp_path):
    tiny_spec(tmp_path / "src")
    code = "\n".join([
        f"import sys; sys.path.insert(0, {str(ROOT)!r})",
        "import ctypes, pathlib",
        "from runtime import native",
        "from runtime.model import build",
        f"g = pathlib.Path({str(tmp_path / 'src')!r})",
        'spec = build.LibrarySpec("kvrod_tiny", "a test library", ("tiny.c",), (), (), ())',
        f"p = build.compile_library(native.find_compiler(), gdir=g, "
        f"outdir=pathlib.Path({str(tmp_path / 'out')!r}), spec=spec)",
        "assert ctypes.CDLL(str(p)).kvrod_n_state(2, 1) == 15",
    ])
    procs = [subprocess.Popen([sys.executable, "-c", code]) for _ in range(3)]
    assert all(p.wait(timeout=120) == 0 for p in procs)
    assert len(list((tmp_path / "out").glob("kvrod_tiny_*.so"))) == 1
    assert not list((tmp_path / "out").glob("*.tmp"))


def test_manifest_mismatch_tells_the_user_to_regenerate(tmp_path):
    gdir = build.generated_dir()
    for name in build.SOURCES + build.HEADERS:
        shutil.copy(gdir / name, tmp_path / name)
    good = {
        name: build._manifest_hash((gdir / name).read_text())
        for name in build.SOURCES + build.HEADERS
    }
    man = {"files": {k: {"sha256": v} for k, v in good.items()}}
    (tmp_path / "MANIFEST.json").write_text(json.dumps(man))
    names = build.SOURCES + build.HEADERS
    build.verify_manifest(tmp_path, names)  # consistent: no error
    with open(tmp_path / "rod_kernels.c", "a") as fh:
        fh.write("/* hand edit */\n")
    with pytest.raises(GeneratedCodeError, match="kvrod generate"):
        build.verify_manifest(tmp_path, names)


def test_a_crlf_checkout_of_the_generated_files_still_verifies(tmp_path):
    """The manifest hashes the text: files checked out with CRLF line ends verify (their
    bytes differ), an edit in them does not."""
    gdir = build.generated_dir()
    names = build.SOURCES + build.HEADERS
    for name in names:
        (tmp_path / name).write_bytes((gdir / name).read_bytes().replace(b"\n", b"\r\n"))
    shutil.copy(gdir / "MANIFEST.json", tmp_path / "MANIFEST.json")
    build.verify_manifest(tmp_path, names)
    with open(tmp_path / "rod_kernels.h", "ab") as fh:
        fh.write(b"/* hand edit */\r\n")
    with pytest.raises(GeneratedCodeError, match="rod_kernels.h"):
        build.verify_manifest(tmp_path, names)


@pytest.mark.parametrize("damage", ["missing", "truncated", "not_json", "no_entry",
                                    "source_missing"])
def test_manifest_problems_are_errors_naming_the_file(tmp_path, damage):
    """Issue 12: without a usable MANIFEST.json the generated code is never compiled."""
    gdir = build.generated_dir()
    names = build.SOURCES + build.HEADERS
    for name in names:
        shutil.copy(gdir / name, tmp_path / name)
    text = (gdir / "MANIFEST.json").read_text()
    man = tmp_path / "MANIFEST.json"
    if damage == "truncated":
        man.write_text(text[: len(text) // 2])
    elif damage == "not_json":
        man.write_text("[1, 2, 3]")
    elif damage == "no_entry":
        doc = json.loads(text)
        del doc["files"]["rod_kernels.c"]
        man.write_text(json.dumps(doc))
    elif damage == "source_missing":
        man.write_text(text)
        (tmp_path / "rod_kernels.h").unlink()
    with pytest.raises(GeneratedCodeError) as exc:
        build.verify_manifest(tmp_path, names)
    msg = str(exc.value)
    assert "MANIFEST.json" in msg or "rod_kernels" in msg
    assert "kvrod generate" in msg


@pytest.fixture
def cache_cleared_after():
    """The library caches dropped after the test (and after monkeypatch restored the
    environment: requested before it, torn down after it)."""
    yield
    build.clear_cache()


def test_fallback_without_compiler_warns_once_and_gives_same_numbers(cache_cleared_after,
                                                                    monkeypatch, tmp_path):
    ref = None
    if native.find_compiler() is not None:
        ref = rod_model(3)                  # compiled in the suite's own cache
    monkeypatch.setenv("KVROD_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.setenv("KVROD_NO_COMPILER", "1")
    build.clear_cache()
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        m1 = rod_model(3)
        rod_model(4)
    msgs = [w for w in rec if "in-process" in str(w.message)]
    assert len(msgs) == 1
    assert m1.backend == "casadi"
    if ref is not None:
        rng = np.random.default_rng(0)
        y = ref.initial_state() + 0.03 * rng.standard_normal(ref.n)
        yp = rng.standard_normal(ref.n)
        r1, r2 = np.empty(ref.n), np.empty(ref.n)
        ref.residual(0.0, y, yp, r1)
        m1.residual(0.0, y, yp, r2)
        assert np.abs(r1 - r2).max() <= 1e-12 * np.abs(r1).max()


def test_tampered_library_is_rebuilt_not_loaded(tmp_path):
    """A cached library whose bytes no longer match the hash recorded at build time is
    compiled again (issue 6, item 4)."""
    compiler = native.find_compiler()
    if compiler is None:
        pytest.skip("no C compiler")
    spec, gdir, out = tiny_spec(tmp_path / "src"), tmp_path / "src", tmp_path / "out"
    lib = build.compile_library(compiler, gdir=gdir, outdir=out, spec=spec)
    good = lib.read_bytes()
    lib.write_bytes(good[:-64] + b"\0" * 64)           # corrupt it in place
    again = build.compile_library(compiler, gdir=gdir, outdir=out, spec=spec)
    assert again == lib and again.read_bytes() == good
    (out / (lib.name + ".sha256")).unlink()            # no record of its hash: rebuilt too
    mtime = lib.stat().st_mtime_ns
    build.compile_library(compiler, gdir=gdir, outdir=out, spec=spec)
    assert lib.stat().st_mtime_ns != mtime


def test_edited_casadi_kernels_are_refused_when_loaded(tmp_path):
    """The compiled path checks the C sources, headers and formula modules; the serialised
    CasADi kernels (three quarters of the bytes) are checked when they are loaded."""
    from runtime.model.casadi_oracle import load_kernels

    gdir = tmp_path / "generated"
    shutil.copytree(build.generated_dir(), gdir, ignore=shutil.ignore_patterns("__pycache__"))
    path = gdir / "rod_segment_forces.casadi"
    path.write_text(path.read_text() + "\n")
    build.verify_manifest(gdir, exclude=(".casadi",))
    with pytest.raises(GeneratedCodeError, match="rod_segment_forces.casadi"):
        load_kernels(gdir)


@pytest.fixture
def digest_memo(monkeypatch, tmp_path):
    """A cache folder of its own and a memo not read yet (a fresh process)."""
    monkeypatch.setenv("KVROD_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.setattr(native, "_digests", None)
    return tmp_path / "cache" / native.DIGESTS_FILE


def test_file_digests_are_remembered_across_processes_until_the_file_changes(
        digest_memo, tmp_path, monkeypatch):
    import hashlib

    monkeypatch.setattr(native, "RACY_SECONDS", -1.0)      # the file counts as old
    path = tmp_path / "kernels.c"
    path.write_bytes(b"int f(void) { return 1; }\n")
    want = hashlib.sha256(path.read_bytes() + b"\0").hexdigest()
    assert native.file_sha256(path, b"\0") == want
    assert native.file_sha256(path) == hashlib.sha256(path.read_bytes()).hexdigest()
    assert digest_memo.is_file()
    # a later process: the same signature is not read again
    monkeypatch.setattr(native, "_digests", None)
    reads = []
    real = Path.read_bytes
    monkeypatch.setattr(Path, "read_bytes", lambda p: reads.append(p) or real(p))
    assert native.file_sha256(path, b"\0") == want
    assert reads == []
    # an edit (same size) changes the signature: hashed again
    path.write_bytes(b"int f(void) { return 2; }\n")
    monkeypatch.setattr(native, "_digests", None)
    assert native.file_sha256(path, b"\0") == hashlib.sha256(
        b"int f(void) { return 2; }\n\0").hexdigest()
    assert reads == [path]


def test_a_file_changed_just_now_is_not_remembered_across_processes(digest_memo, tmp_path):
    path = tmp_path / "fresh.c"
    path.write_bytes(b"x")
    native.file_sha256(path)
    assert not digest_memo.exists()        # within RACY_SECONDS of its change: this process only


@pytest.mark.parametrize("content", ["{", "[1, 2]", '{"00:/x": [[1, 2], "short"]}', ""])
def test_an_unreadable_digest_memo_is_ignored(digest_memo, tmp_path, monkeypatch, content):
    import hashlib

    monkeypatch.setattr(native, "RACY_SECONDS", -1.0)
    digest_memo.parent.mkdir(parents=True)
    digest_memo.write_text(content)
    path = tmp_path / "a.c"
    path.write_bytes(b"abc")
    assert native.file_sha256(path) == hashlib.sha256(b"abc").hexdigest()
    kept = json.loads(digest_memo.read_text())
    assert kept[":" + str(path)][1] == hashlib.sha256(b"abc").hexdigest()


@pytest.mark.parametrize("xdg, home", [(None, "/home/u"), ("/var/xdg", "/home/u"),
                                       ("relative/xdg", "/home/u"), ("", "/home/u"),
                                       ("/var/xdg", None)])
def test_the_user_cache_folder_is_platformdirs_own(monkeypatch, xdg, home):
    """cache_dir's shortcut (no platformdirs import on Linux) gives platformdirs' folder."""
    import sys

    import platformdirs

    monkeypatch.delenv("KVROD_CACHE_DIR", raising=False)
    for name, value in (("XDG_CACHE_HOME", xdg), ("HOME", home)):
        if value is None:
            monkeypatch.delenv(name, raising=False)
        else:
            monkeypatch.setenv(name, value)
    if not sys.platform.startswith("linux") or (home is None and xdg is None):
        pytest.skip("the shortcut is Linux's")
    assert native.cache_dir() == Path(platformdirs.user_cache_dir("kvrod"))


@pytest.mark.parametrize("command, name, over", [
    ("simulate", "examples/contact_flat_drop.toml", {"simulation.t_end": 0.002}),
    ("static", "examples/assembly_l_frame.toml", {"rods.column.rod.elements": 4,
                                                  "rods.beam.rod.elements": 3}),
    ("simulate", "cantilever", {"n_elements": 4, "t_end": 0.01})])
def test_the_libraries_load_before_the_folder_and_the_clock(tmp_path, monkeypatch, command,
                                                            name, over):
    """runs.load_compiled: the rod kernels, the solver's helpers and (where the problem
    touches something) the contact kernels are loaded, compiling on a first run, with
    the checks: before the results folder exists and before any model is built (the
    model build starts the run's clock), so that no compilation counts in the run's
    wall_time_s and a failure to build comes before anything is written."""
    from runtime.io import runs
    from runtime.model.rod import RodModel
    from runtime.problem.registry import load_problem
    from runtime.solvers.native import loader

    out = tmp_path / "out"
    events: list[tuple[str, bool]] = []

    def watch(owner, fn):
        original = getattr(owner, fn)

        def called(*a, **k):
            events.append((fn, out.exists()))
            return original(*a, **k)
        monkeypatch.setattr(owner, fn, called)

    watch(build, "load_library")
    watch(build, "load_contact_library")
    watch(loader, "load")
    watch(RodModel, "__init__")
    problem = load_problem(name, over)
    if command == "static":
        runs.static_and_write(problem, out)
    else:
        runs.run_and_write(problem, out, "t")
    touches = name.endswith("contact_flat_drop.toml")
    libs = {"load_library", "load"} | ({"load_contact_library"} if touches else set())
    first_model = next(k for k, (fn, _) in enumerate(events) if fn == "__init__")
    before = events[:first_model]
    assert {fn for fn, _ in before} == libs and not any(seen for _, seen in before)
    assert (out / "summary.json").exists()


@needs_cc
def test_library_built_says_whether_loading_would_compile(tmp_path, monkeypatch):
    """What a sweep's fork server asks before it loads the kernels (it never compiles):
    true for the cache's intact library of these sources, false for an empty cache or a
    library whose recorded hash no longer matches."""
    from runtime.solvers.native import loader

    build.load_library()
    loader.load()
    assert build.library_built() and loader.built()
    target = build._library_path(native.find_compiler(), build.generated_dir(),
                                 native.cache_dir(), build.ROD_LIBRARY)
    monkeypatch.setenv("KVROD_CACHE_DIR", str(tmp_path))
    assert not build.library_built() and not loader.built()
    copy = tmp_path / target.name
    shutil.copy(target, copy)
    shutil.copy(target.with_name(target.name + ".sha256"), tmp_path)
    assert build.library_built()
    copy.write_bytes(copy.read_bytes()[:-64] + b"\0" * 64)       # damaged: would rebuild
    assert not build.library_built()
