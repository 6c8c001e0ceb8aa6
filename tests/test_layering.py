"""Design section 1: derive -> generated -> runtime layering, checked by walking imports."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

FORBIDDEN = {
    "generated": {"derive", "runtime", "kvrod", "sympy", "casadi", "jinja2", "scipy"},
    "runtime": {"derive", "kvrod", "sympy", "jinja2", "references", "tests", "bench"},
    "derive": {"runtime", "kvrod", "references", "tests"},
    # independent references share no code with the simulator (they validate it)
    "references": {"derive", "generated", "runtime", "kvrod", "bench", "tests", "sympy",
                   "casadi", "jinja2"},
    "kvrod": {"tests"},
    "bench": {"tests"},
}


#: runtime/section is a floor below runtime/problem: NumPy, SciPy, shapely, cytriangle and
#: runtime.errors only (no SymPy, nothing else of runtime)
SECTION_ALLOWED = {"numpy", "scipy", "shapely", "cytriangle", "runtime", "__future__",
                   "math", "dataclasses", "collections", "typing"}


def imported_modules(path: Path) -> set[str]:
    tree = ast.parse(path.read_text(), filename=str(path))
    names: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names |= {a.name for a in node.names}
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            names.add(node.module)
    return names


def test_section_layer():
    bad = {}
    for f in sorted((ROOT / "runtime" / "section").rglob("*.py")):
        mods = imported_modules(f)
        wrong = {m for m in mods if m.split(".")[0] not in SECTION_ALLOWED
                 or (m.startswith("runtime") and not (m == "runtime.errors"
                                                      or m.startswith("runtime.section")))}
        if wrong:
            bad[str(f.relative_to(ROOT))] = sorted(wrong)
    assert not bad, f"runtime/section imports outside its floor: {bad}"


def imported_top_levels(path: Path) -> set[str]:
    tree = ast.parse(path.read_text(), filename=str(path))
    names: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names |= {a.name.split(".")[0] for a in node.names}
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            names.add(node.module.split(".")[0])
    return names


@pytest.mark.parametrize("package", sorted(FORBIDDEN))
def test_layering(package):
    files = sorted((ROOT / package).rglob("*.py"))
    assert files, package
    bad = {str(f.relative_to(ROOT)): sorted(imported_top_levels(f) & FORBIDDEN[package])
           for f in files}
    bad = {k: v for k, v in bad.items() if v}
    assert not bad, f"layering violated: {bad}"


def test_walker_detects_a_violation(tmp_path):
    f = tmp_path / "x.py"
    f.write_text("import sympy\nfrom derive.pipeline import run\n")
    assert {"sympy", "derive"} <= imported_top_levels(f)
