"""The committed generated/ tree equals a fresh generation, byte for byte."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

from derive.artifacts import MANIFEST_NAME, check_tree, generated_dir, sha256_text, write_tree
from derive.pipeline import STEP_NAMES

ROOT = Path(__file__).resolve().parents[2]


def test_generated_tree_is_up_to_date():
    """From this process's derivation (the derivation cache, when it has the entry)."""
    problems = check_tree()
    assert not problems, "generated/ is stale; run `kvrod generate`:\n" + "\n".join(problems)


def test_generated_tree_regenerates_from_scratch(tmp_path):
    """Without any cache (KVROD_DERIVE_CACHE=0: every step derived again, nothing read or
    written), `kvrod generate --out` into a temporary folder gives the committed tree byte
    for byte."""
    env = {**os.environ, "KVROD_DERIVE_CACHE": "0", "KVROD_CACHE_DIR": str(tmp_path / "c")}
    out = tmp_path / "generated"
    r = subprocess.run([sys.executable, "-m", "kvrod", "generate", "--out", str(out)],
                       capture_output=True, text=True, cwd=tmp_path, env=env, timeout=900)
    assert r.returncode == 0, r.stderr[-2000:]
    n = len(STEP_NAMES)
    assert f"step {n}/{n}" in r.stderr                   # derived, step by step
    assert not (tmp_path / "c").exists()                # no cache written
    fresh = {p.name: p.read_bytes() for p in out.iterdir()}
    committed = {p.name: p.read_bytes() for p in generated_dir().iterdir()
                 if p.is_file() and p.name in fresh}
    assert set(fresh) == set(committed)
    differ = sorted(n for n in fresh if fresh[n] != committed[n])
    assert not differ, f"differ from a generation from scratch: {differ}"


def test_stale_tree_is_detected(tmp_path):
    write_tree(tmp_path)
    target = tmp_path / "constitutive.py"
    target.write_text(target.read_text().replace("numpy.diag", "numpy.diagflat", 1))
    problems = check_tree(tmp_path)
    assert any(p.startswith("constitutive.py") for p in problems)


def test_every_file_has_provenance():
    manifest = json.loads((generated_dir() / MANIFEST_NAME).read_text())
    assert set(manifest["tools"]) == {"sympy", "casadi", "jinja2"}
    for rel, entry in manifest["files"].items():
        text = (generated_dir() / rel).read_text()
        assert sha256_text(text) == entry["sha256"], rel
        if rel.endswith((".py", ".c", ".h")):
            assert "GENERATED FILE - do not edit; regenerate with `kvrod generate`." in text[:200]
            assert entry["inputs_sha256"] in text[:600]
