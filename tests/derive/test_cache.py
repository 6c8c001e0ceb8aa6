"""The derivation cache (derive/cache.py): exact round trip, hit, miss, invalidation by
content and tool versions, corrupt entries, concurrent writers, and `derive list` without
SymPy. Every test uses a temporary cache folder (KVROD_CACHE_DIR), never the user's."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import threading
from pathlib import Path

import pytest

from derive import cache, pipeline
from derive.pipeline import STEP_NAMES

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def real_steps(tmp_path_factory):
    """The real step records: this process's, else derived once into a temporary cache."""
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("KVROD_CACHE_DIR", str(tmp_path_factory.mktemp("derive-cache")))
        return pipeline.run()


@pytest.fixture()
def tmp_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("KVROD_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.delenv(cache.DISABLE_ENV, raising=False)
    return tmp_path / "cache" / "derivation"


@pytest.fixture()
def counting_derive(monkeypatch, real_steps):
    """derive_all replaced by a counter returning the real records (no SymPy work)."""
    calls = []

    def fake(progress=None):
        calls.append(progress)
        return dict(real_steps)

    monkeypatch.setattr(cache, "derive_all", fake)
    return calls


def test_round_trip_is_exact(real_steps):
    """Every result and stated form comes back with the same tree (srepr), including the
    unevaluated products that plain pickling would distribute."""
    back = cache.loads(cache.dumps(real_steps, "k" * 64), "k" * 64)
    assert list(back) == list(STEP_NAMES)
    assert cache._same(real_steps, back)
    eta_e = real_steps["dissipation"].results["eta_E"]
    assert back["dissipation"].results["eta_E"].args == eta_e.args
    s = back["dissipation"]
    assert s.all_match and s.title == pipeline.entry("dissipation").title
    with pytest.raises(TypeError):       # still a frozen record
        s.results["eta_E"] = 0  # type: ignore[index]


def test_same_detects_a_changed_tree(real_steps):
    import sympy as sp

    other = dict(real_steps)
    s = other["dissipation"]
    results = dict(s.results)
    results["eta_E"] = sp.expand(results["eta_E"])       # equal value, other tree
    other["dissipation"] = type(s)(**{**{f: getattr(s, f) for f in s.__dataclass_fields__},
                                      "results": results})
    assert not cache._same(real_steps, other)


def test_hit_miss_and_other_key(tmp_cache, real_steps):
    key = cache.cache_key()
    assert cache.load(key) is None                      # empty folder: a miss
    path = cache.store(real_steps, key)
    assert path == cache.entry_path(key) and path.parent == tmp_cache
    assert cache._same(real_steps, cache.load(key))     # a hit
    assert cache.load("0" * 64) is None                 # another key: a miss
    doc = cache.summary(key)
    assert doc and tuple(doc["steps"]) == STEP_NAMES
    assert all(v["all_match"] for v in doc["steps"].values())


def test_invalidated_by_a_tool_version(tmp_cache, counting_derive, monkeypatch):
    cache.load_or_derive()
    cache.load_or_derive()
    assert len(counting_derive) == 1                    # derived once, then read
    versions = {**cache.tool_versions(), "sympy": "0.0.test"}
    monkeypatch.setattr(cache, "tool_versions", lambda: versions)
    cache.load_or_derive()
    assert len(counting_derive) == 2                    # a new SymPy: derived again
    assert len(list(tmp_cache.glob("steps-*.pickle"))) == 2


def test_invalidated_by_any_file_of_derive(tmp_cache, counting_derive, monkeypatch, tmp_path):
    copy = tmp_path / "derive"
    shutil.copytree(ROOT / "derive", copy, ignore=shutil.ignore_patterns("__pycache__"))
    monkeypatch.setattr(cache, "derive_dir", lambda: copy)
    cache.load_or_derive()
    cache.load_or_derive()
    assert len(counting_derive) == 1
    template = copy / "templates" / "derivation.md.jinja"
    template.write_text(template.read_text() + " ")      # a template, not only sources
    cache.load_or_derive()
    assert len(counting_derive) == 2
    (copy / "__pycache__").mkdir(exist_ok=True)
    (copy / "__pycache__" / "x.cpython-311.pyc").write_bytes(b"\0")   # not content
    cache.load_or_derive()
    assert len(counting_derive) == 2


def test_key_inputs():
    base = cache.tool_versions()
    assert set(base) == {"python", *cache.KEY_TOOLS}
    import sympy

    assert base["sympy"] == sympy.__version__
    k = cache.cache_key(versions=base)
    assert k == cache.cache_key(versions=dict(base))
    assert k != cache.cache_key(versions={**base, "sympy": base["sympy"] + ".post1"})
    assert k != cache.cache_key(versions={**base, "python": "cpython 3.99.0"})
    assert k != cache.cache_key(versions={**base, "casadi": "0.0"})


def test_cache_root_is_the_compiled_kernels_root(monkeypatch, tmp_path):
    from runtime import native

    monkeypatch.setenv("KVROD_CACHE_DIR", str(tmp_path))
    assert cache.cache_root() == native.cache_dir() == tmp_path
    monkeypatch.delenv("KVROD_CACHE_DIR")
    assert cache.cache_root() == native.cache_dir()
    assert ROOT not in cache.cache_root().parents        # never in the checkout


@pytest.mark.parametrize("damage", ["truncate", "flip", "garbage", "empty", "other-key"])
def test_corrupt_entry_is_detected_and_rebuilt(tmp_cache, counting_derive, real_steps,
                                               damage):
    key = cache.cache_key()
    path = cache.store(real_steps, key)
    data = path.read_bytes()
    damaged = {"truncate": data[: len(data) // 2],
               "flip": data[:-100] + bytes([data[-100] ^ 0xFF]) + data[-99:],
               "garbage": b"\x80\x05not a pickle",
               "empty": b"",
               "other-key": cache.dumps(real_steps, "f" * 64)}[damage]
    path.write_bytes(damaged)
    with pytest.raises(cache.CacheEntryError):
        cache.loads(damaged, key)
    assert cache.load(key) is None and not path.exists()     # a miss; the file is gone
    steps = cache.load_or_derive()
    assert len(counting_derive) == 1 and list(steps) == list(STEP_NAMES)
    assert cache._same(real_steps, cache.load(key))          # rebuilt and readable


def test_concurrent_writers_never_expose_a_partial_entry(tmp_cache, real_steps):
    key = cache.cache_key()
    cache.store(real_steps, key)
    path, errors, stop = cache.entry_path(key), [], threading.Event()

    def write():
        for _ in range(4):
            cache.store(real_steps, key)

    def read():
        while not stop.is_set():
            try:
                cache.loads(path.read_bytes(), key)
            except FileNotFoundError:
                pass
            except cache.CacheEntryError as exc:
                errors.append(exc)

    reader = threading.Thread(target=read)
    reader.start()
    writers = [threading.Thread(target=write) for _ in range(3)]
    for w in writers:
        w.start()
    for w in writers:
        w.join()
    stop.set()
    reader.join()
    assert not errors
    assert cache._same(real_steps, cache.load(key))
    assert not list(tmp_cache.glob(".*.tmp"))                 # no temporary left behind


def test_disabled_cache_derives_and_writes_nothing(tmp_cache, counting_derive, monkeypatch):
    monkeypatch.setenv(cache.DISABLE_ENV, "0")
    cache.load_or_derive()
    cache.load_or_derive()
    assert len(counting_derive) == 2
    assert not tmp_cache.exists()
    assert cache.summary() is None


def test_prune_keeps_the_recent_entries(tmp_cache, real_steps):
    data_keys = [f"{i:02d}" * 32 for i in range(5)]
    for i, key in enumerate(data_keys):
        cache.store(real_steps, key)
        os.utime(cache.entry_path(key), (1000 + i, 1000 + i))
    cache.memo_path("rod-bands", data_keys[0]).write_text("{}")
    removed = cache.prune(keep=2)
    left = sorted(p.name for p in tmp_cache.glob("steps-*.pickle"))
    assert left == sorted(cache.entry_path(k).name for k in data_keys[3:])
    assert cache.memo_path("rod-bands", data_keys[0]) in removed


def test_memo(tmp_cache):
    calls = []

    def compute():
        calls.append(1)
        return {"bands": [[1, 2]], "n": 3}

    assert cache.memo("test-memo", compute) == {"bands": [[1, 2]], "n": 3}
    assert cache.memo("test-memo", compute) == {"bands": [[1, 2]], "n": 3}
    assert len(calls) == 1
    cache.memo_path("test-memo", cache.cache_key()).write_text('{"key": "x"')   # corrupt
    assert cache.memo("test-memo", compute)["n"] == 3
    assert len(calls) == 2


def _run_list(env_cache: Path) -> subprocess.CompletedProcess:
    code = ("import sys\nfrom kvrod.cli import main\nrc = main(['derive', 'list'])\n"
            "assert 'sympy' not in sys.modules, 'derive list imported SymPy'\n"
            "sys.exit(rc)\n")
    env = {**os.environ, "KVROD_CACHE_DIR": str(env_cache)}
    env.pop(cache.DISABLE_ENV, None)
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          cwd=ROOT, env=env, timeout=120)


def test_derive_list_does_no_sympy_work(tmp_path, real_steps, monkeypatch):
    r = _run_list(tmp_path / "empty")
    assert r.returncode == 0, r.stderr
    lines = r.stdout.splitlines()
    assert [line.split()[0] for line in lines] == list(STEP_NAMES)
    assert all(line.split()[1] == "-" for line in lines)      # nothing derived: unknown
    assert "not derived yet" in r.stderr
    assert not (tmp_path / "empty").exists()                  # and nothing written
    # with a cached derivation the verdicts are shown, still without SymPy
    monkeypatch.setenv("KVROD_CACHE_DIR", str(tmp_path / "full"))
    cache.store(real_steps)
    r = _run_list(tmp_path / "full")
    assert r.returncode == 0, r.stderr
    assert all(line.split()[1] == "ok" for line in r.stdout.splitlines())
    assert r.stderr == ""


def test_derive_list_json_has_the_catalogue(capsys, tmp_cache):
    from kvrod.cli import main

    assert main(["derive", "list", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert [d["name"] for d in doc] == list(STEP_NAMES)
    for d, e in zip(doc, pipeline.PIPELINE, strict=True):
        assert d["title"] == e.title and d["equations"] == list(e.equations)
        assert d["all_match"] is None                          # empty cache: not known


def test_progress_is_reported_step_by_step(capsys):
    from kvrod.notices import DerivationProgress

    p = DerivationProgress("kvrod derive show")
    for k, e in enumerate(pipeline.PIPELINE):
        p(k, len(pipeline.PIPELINE), e)
    p(len(pipeline.PIPELINE), len(pipeline.PIPELINE), None)
    err = capsys.readouterr().err.splitlines()
    assert err[0].startswith("kvrod derive show: deriving the model")
    assert err[1:] == [f"  step {k + 1}/{len(STEP_NAMES)}: {n}"
                       for k, n in enumerate(STEP_NAMES)]


def test_catalogue_titles_are_the_records(real_steps):
    for e in pipeline.PIPELINE:
        s = real_steps[e.name]
        assert (s.title, s.equations, s.inputs) == (e.title, e.equations, e.inputs)
