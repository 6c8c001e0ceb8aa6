"""The documentation builds from a copy of docs/ with warnings as errors (nitpicky
cross-references), every tutorial executed, and the generated references complete.

The build runs on a temporary copy of docs/ (the pages rendered from the code go to its
``_generated/``), so the checkout is left as it was."""

from __future__ import annotations

import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
TUTORIALS = ("cantilever", "problem_in_python", "consistent_vs_naive", "damped_modes",
             "calibration")

pytest.importorskip("sphinx", reason="the docs extra is not installed")
pytest.importorskip("myst_nb", reason="the docs extra is not installed")


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("docs")
    src = tmp / "docs"
    shutil.copytree(ROOT / "docs", src, ignore=shutil.ignore_patterns("_build", "_generated",
                                                                     "jupyter_execute"))
    out = tmp / "html"
    r = subprocess.run([sys.executable, "-m", "sphinx", "-W", "-n", "-E", "-q", "-b", "html",
                        str(src), str(out)], capture_output=True, text=True, cwd=tmp,
                       timeout=900)
    assert r.returncode == 0, r.stderr[-4000:]
    return src, out


def test_every_tutorial_is_executed_without_errors(built):
    _, out = built
    for name in TUTORIALS:
        html = (out / "tutorials" / f"{name}.html").read_text()
        assert "cell_output" in html, f"{name}: no executed output"
        assert "Traceback" not in html, name


def test_every_problem_key_and_cli_flag_is_in_the_reference(built):
    from kvrod.cli import build_parser
    from runtime.problem import keys

    src, out = built
    ref = (src / "_generated" / "problem_keys.md").read_text()
    for k in keys.KEYS:
        assert f"`{k.name}`" in ref, k.path
    cli = (src / "_generated" / "cli.md").read_text()
    flags = set()
    stack = [build_parser()]
    while stack:
        p = stack.pop()
        for a in p._actions:
            flags.update(a.option_strings)
            if hasattr(a, "choices") and isinstance(a.choices, dict):
                stack.extend(a.choices.values())
                for name in a.choices:
                    assert re.search(rf"kvrod( \S+)* {re.escape(name)}", cli), name
    missing = sorted(f for f in flags if f not in cli)
    assert not missing, missing
    assert (out / "_generated" / "cli.html").is_file()
    assert (out / "_generated" / "derivation.html").is_file()
