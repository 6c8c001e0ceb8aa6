"""The house's floors, checked by walking imports (docs/design.md, sections 1 and 8): the
top-level packages (derive -> generated -> runtime -> reports -> kvrod) and the floors of
runtime/ (a subpackage imports only its own floor and those below)."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

FORBIDDEN = {
    "generated": {"derive", "runtime", "kvrod", "sympy", "casadi", "jinja2", "scipy"},
    "runtime": {"derive", "kvrod", "reports", "sympy", "jinja2", "references", "tests",
                "bench"},
    "derive": {"runtime", "kvrod", "reports", "references", "tests"},
    # independent references share no code with the simulator (they validate it)
    "references": {"derive", "generated", "runtime", "kvrod", "bench", "tests", "sympy",
                   "casadi", "jinja2"},
    # the notes and reports: anything but the command line and the tests
    "reports": {"kvrod", "tests", "bench"},
    "kvrod": {"tests"},
    "bench": {"tests"},
}

#: the floors of runtime/, bottom up: a module may import its own floor and those below
RUNTIME_FLOORS: tuple[tuple[str, ...], ...] = (
    ("errors", "native", "signals", "sorted_sets", "version"),   # errors; compiling native
                                   # code; Ctrl-C and SIGTERM around C code; np.unique without
                                   # numpy.ma; the version
    ("section",),                      # cross-section analysis (NumPy/SciPy/shapely)
    ("solvers",),                      # integrator, statics, run driver: no problem known
    ("model",),                        # the rod over the generated kernels
    ("problem",),                      # problems as data, assembled into a model
    ("analysis",),                     # analyses of a model or of recorded data
    ("simulate",),                     # the rod's run: observers, energy audit
    ("io",),                           # results folders, files, plots, VTK
    ("study",),                        # studies that run simulations: sweeps, calibration
)


def _runtime_floor(module: str) -> int | None:
    """The floor of ``runtime.X...`` (None for anything else)."""
    parts = module.split(".")
    if parts[0] != "runtime" or len(parts) < 2:
        return None
    for k, names in enumerate(RUNTIME_FLOORS):
        if parts[1] in names:
            return k
    raise AssertionError(f"{module}: runtime.{parts[1]} has no floor in RUNTIME_FLOORS")


def _resolved_imports(path: Path) -> set[str]:
    """Absolute module names imported by ``path`` (relative imports resolved)."""
    rel = path.relative_to(ROOT).with_suffix("")
    package = list(rel.parts[:-1]) if rel.name != "__init__" else list(rel.parts[:-1])
    tree = ast.parse(path.read_text(), filename=str(path))
    names: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names |= {a.name for a in node.names}
        elif isinstance(node, ast.ImportFrom):
            if node.level == 0:
                base = node.module or ""
            else:
                up = package[:len(package) - (node.level - 1)]
                base = ".".join(up + ([node.module] if node.module else []))
            names.add(base)
            names |= {f"{base}.{a.name}" for a in node.names}
    return names


def test_runtime_floors():
    """No import runs up a floor of runtime/ (so no subpackage imports another in a
    circle: two packages on different floors cannot import each other)."""
    bad = []
    for f in sorted((ROOT / "runtime").rglob("*.py")):
        if f.parent == ROOT / "runtime" and f.name == "__init__.py":
            continue
        own = _runtime_floor("runtime." + ".".join(f.relative_to(ROOT / "runtime")
                                                     .with_suffix("").parts))
        if own is None:
            continue
        for mod in _resolved_imports(f):
            k = _runtime_floor(mod) if mod.startswith("runtime.") else None
            if k is not None and k > own:
                bad.append(f"{f.relative_to(ROOT)} -> {mod}")
    assert not bad, "imports up a floor of runtime/:\n" + "\n".join(sorted(set(bad)))


def test_every_runtime_package_has_a_floor():
    names = {p.name for p in (ROOT / "runtime").iterdir()
             if (p.is_dir() and (p / "__init__.py").exists()) or p.suffix == ".py"}
    names = {n.removesuffix(".py") for n in names} - {"__init__"}
    floors = {n for floor in RUNTIME_FLOORS for n in floor}
    assert names == floors, (names - floors, floors - names)


#: runtime/section is a floor below runtime/problem: NumPy, SciPy, shapely, cytriangle,
#: runtime.errors, runtime.signals and runtime.native only (no SymPy, nothing else of
#: runtime); importlib for the package's names loaded on first use
#: (runtime/section/__init__.py); ctypes and the modules of compiling and caching its C
#: numeric phase (runtime/section/multifrontal.py, through runtime.native)
SECTION_ALLOWED = {"numpy", "scipy", "shapely", "cytriangle", "runtime", "__future__",
                   "math", "dataclasses", "collections", "typing", "importlib", "ctypes",
                   "hashlib", "os", "pathlib", "subprocess", "tempfile", "threading"}
SECTION_RUNTIME = ("runtime.errors", "runtime.signals", "runtime.native")


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
                 or (m.startswith("runtime") and not (m in SECTION_RUNTIME
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
