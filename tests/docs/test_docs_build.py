"""The documentation builds from a copy of docs/ with warnings as errors (nitpicky
cross-references), every tutorial executed, and the generated pages complete.

The build runs on a temporary copy of docs/ (the pages rendered from the code go to its
``_generated/``) into a temporary output folder, so the checkout is left as it was and the
notebook cache (``<output>/../.jupyter_cache``) starts empty: every tutorial is executed
against the current code, and a broken tutorial fails here whatever a developer's own
cache holds. Building the same copy again after touching the tutorials (Sphinx reads them
again) must take every notebook from that cache."""

from __future__ import annotations

import re
import shutil
import subprocess
import sys
from collections import Counter
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
TUTORIALS = ("cantilever", "problem_in_python", "assemblies", "consistent_vs_naive",
             "damped_modes", "calibration", "fit", "your_section")

pytest.importorskip("sphinx", reason="the docs extra is not installed")
pytest.importorskip("myst_nb", reason="the docs extra is not installed")


def _sphinx(src: Path, out: Path, *extra: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "sphinx", "-W", "-n", *extra, "-b", "html",
                           str(src), str(out)], capture_output=True, text=True,
                          cwd=out.parent, timeout=900)


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("docs")
    src = tmp / "docs"
    shutil.copytree(ROOT / "docs", src, ignore=shutil.ignore_patterns("_build", "_generated",
                                                                     "jupyter_execute"))
    out = tmp / "html"
    r = _sphinx(src, out, "-E", "-q")
    assert r.returncode == 0, r.stderr[-4000:]
    return src, out


@pytest.fixture(scope="module")
def kvrod_docs():
    sys.path.insert(0, str(ROOT / "docs" / "_ext"))
    try:
        import kvrod_docs
    finally:
        sys.path.remove(str(ROOT / "docs" / "_ext"))
    return kvrod_docs


def _pages(out: Path) -> list[Path]:
    return [p for p in out.rglob("*.html") if "_static" not in p.parts]


def test_every_tutorial_is_executed_without_errors(built):
    _, out = built
    for name in TUTORIALS:
        html = (out / "tutorials" / f"{name}.html").read_text()
        assert "cell_output" in html, f"{name}: no executed output"
        assert "Traceback" not in html, name


def test_a_rebuild_takes_every_notebook_from_the_cache(built, kvrod_docs):
    src, out = built
    cache = out.parent / ".jupyter_cache"
    # one cache folder, named by the hash of kvrod's sources and library versions
    assert [p.name for p in cache.iterdir()] == [kvrod_docs.source_key()[:20]]
    for name in TUTORIALS:
        (src / "tutorials" / f"{name}.md").touch()      # same content, newer: read again
    r = _sphinx(src, out)
    assert r.returncode == 0, r.stderr[-4000:]
    log = r.stdout + r.stderr
    assert "Executing notebook" not in log
    assert log.count("Using cached notebook") == len(TUTORIALS), log[-3000:]


def test_the_cache_key_follows_kvrod_sources(tmp_path, kvrod_docs):
    (tmp_path / "runtime").mkdir()
    module = tmp_path / "runtime" / "m.py"
    module.write_text("x = 1\n")
    key = kvrod_docs.source_key(("runtime",), ("numpy",), root=tmp_path)
    (tmp_path / "runtime" / "__pycache__").mkdir()
    (tmp_path / "runtime" / "__pycache__" / "m.cpython.pyc").write_bytes(b"\0")
    assert kvrod_docs.source_key(("runtime",), ("numpy",), root=tmp_path) == key
    module.write_text("x = 2\n")
    assert kvrod_docs.source_key(("runtime",), ("numpy",), root=tmp_path) != key
    module.write_text("x = 1\n")
    assert kvrod_docs.source_key(("runtime",), ("scipy",), root=tmp_path) != key


def test_math_is_served_locally(built):
    _, out = built
    scripts = Counter()
    for page in _pages(out):
        html = page.read_text()
        for src in re.findall(r'<script[^>]*\ssrc="([^"]+)"', html):
            scripts[src] += 1
            assert not re.match(r"(https?:)?//", src), f"{page.name} loads {src}"
        for href in re.findall(r'<link[^>]*rel="stylesheet"[^>]*href="([^"]+)"', html):
            assert not re.match(r"(https?:)?//", href), f"{page.name} loads {href}"
    mathjax = [s for s in scripts if "mathjax" in s]
    assert mathjax, "no page loads MathJax"
    for src in mathjax:
        assert src.split("?")[0].endswith("_static/mathjax/tex-chtml.js"), src
    assert (out / "_static" / "mathjax" / "tex-chtml.js").stat().st_size > 100_000
    assert (out / "_static" / "mathjax" / "output" / "chtml" / "fonts" / "woff-v2").is_dir()


def test_section_averages_on_the_derivation_page_are_text(built):
    _, out = built
    html = (out / "_generated" / "derivation.html").read_text()
    assert "M_1 = &lt;xi2 S_33&gt;" in html
    assert "&lt;xi1 xi2&gt; = 0" in html
    assert "<xi2" not in html and "<xi1" not in html


def test_every_api_object_is_documented_once(built):
    _, out = built
    ids = Counter()
    for page in (out / "api").glob("*.html"):
        html = page.read_text()
        ids.update(re.findall(r'<dt class="sig sig-object py" id="([^"]+)"', html))
        # an attribute without a docstring would be an empty entry
        assert "<dd></dd>" not in html, page.name
    assert ids, "the API pages document nothing"
    assert [k for k, n in ids.items() if n > 1] == []
    assert [k for k in ids if k.endswith(".BDF")] == ["runtime.solvers.bdf.BDF"]
    for name in ("runtime.simulate.simulate.simulate", "runtime.problem.schema.Problem",
                 "runtime.analysis.modal.modal_analysis", "derive.formulas"):
        assert name in ids, name


def test_getting_started_shows_what_each_command_prints(built, kvrod_docs):
    _, out = built
    html = (out / "getting-started.html").read_text()
    text = re.sub(r"<[^>]+>", "", html)
    for cmd in kvrod_docs.FIRST_ROD:
        assert f"$ .venv/bin/kvrod {cmd}" in text, cmd
    assert text.count("wrote results/") == len(kvrod_docs.FIRST_ROD)
    assert "energy balance max rel. error" in text
    assert "bending-2" in text                   # the modes table


def test_the_validation_page_shows_the_notes_figures_and_tables(built):
    _, out = built
    html = (out / "validation.html").read_text()
    for name in ("reproduction", "examples", "beyond", "maxwell", "sections"):
        note = (ROOT / "notes" / f"{name}.md").read_text()
        for fig in re.findall(r"!\[[^\]]*\]\(figures/([^)]+)\)", note):
            assert f'src="_images/{fig}"' in html, (name, fig)
            assert (out / "_images" / fig).is_file(), fig
        assert f"_generated/notes/{name}.html" in html
    assert html.count("<table") >= 10
    assert "Regenerated by" in html and "Regenerate:" in html
    # the checks are tables of kvrod against a reference with the error
    assert re.search(r"kvrod.{0,200}reference|reference.{0,200}kvrod", html, re.S)


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
