"""The committed generated/ tree equals a fresh generation, byte for byte."""

from __future__ import annotations

import json

from derive.artifacts import MANIFEST_NAME, check_tree, generated_dir, sha256_text, write_tree


def test_generated_tree_is_up_to_date():
    problems = check_tree()
    assert not problems, "generated/ is stale; run `kvrod generate`:\n" + "\n".join(problems)


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
