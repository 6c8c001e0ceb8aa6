"""Rough edges a new user met: `kvrod --version`, the Python API without boilerplate
(static_equilibrium without a model, built-in problems from any folder), and a line on
stderr while the C code compiles."""

from __future__ import annotations

import hashlib
import re
import shutil
import subprocess
import sys
from importlib import metadata
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]


def test_version(capsys):
    from kvrod.cli import main

    with pytest.raises(SystemExit) as exc:
        main(["--version"])
    assert exc.value.code == 0
    out = capsys.readouterr().out.strip()
    m = re.fullmatch(r"kvrod (\S+) \(generated/ ([0-9a-f]{12})\)", out)
    assert m, out
    assert m.group(1) == metadata.version("kvrod")
    manifest = (ROOT / "generated" / "MANIFEST.json").read_bytes()
    assert m.group(2) == hashlib.sha256(manifest).hexdigest()[:12]


def test_version_says_when_the_tree_differs_from_its_manifest(tmp_path, monkeypatch):
    import generated
    from runtime.version import version_text

    copy = tmp_path / "generated"
    shutil.copytree(ROOT / "generated", copy, ignore=shutil.ignore_patterns("__pycache__"))
    monkeypatch.setattr(generated, "__file__", str(copy / "__init__.py"))
    assert "differ" not in version_text()
    (copy / "rod_kernels.c").write_text((copy / "rod_kernels.c").read_text() + "\n")
    assert "1 file(s) differ from it" in version_text()


def test_version_as_a_command_line():
    r = subprocess.run([sys.executable, "-m", "kvrod", "--version"], capture_output=True,
                       text=True, timeout=120)
    assert r.returncode == 0 and r.stdout.startswith("kvrod "), r.stderr


def test_static_equilibrium_without_a_model():
    from runtime.problem.assemble import build_model
    from runtime.problem.registry import load_problem
    from runtime.simulate.simulate import static_equilibrium

    problem = load_problem("clamped_both", {"rod.elements": 16})
    alone = static_equilibrium(problem)
    given = static_equilibrium(problem, build_model(problem))
    assert alone.iterations > 0
    np.testing.assert_allclose(alone.tip, given.tip, rtol=0, atol=1e-12)
    np.testing.assert_allclose(alone.y, given.y, rtol=0, atol=1e-12)


def test_builtin_problem_from_any_folder(tmp_path, monkeypatch):
    from runtime.problem.registry import ProblemFileError, load_problem

    monkeypatch.chdir(tmp_path)
    p = load_problem("pendulum", {"simulation.t_end": 1.0})
    assert p.name == "pendulum" and p.simulation.t_end == 1.0
    with pytest.raises(ProblemFileError, match="no such problem file"):
        load_problem("examples/pendulum.toml")      # a path is relative to the cwd


def test_compile_is_announced(tmp_path, monkeypatch, capsys):
    """A compilation of the rod kernels tells the observers when it starts and how long it
    took; the command line prints both on stderr (library code prints nothing)."""
    from kvrod.notices import install_compile_notices, remove_compile_notices
    from runtime import native
    from runtime.model import build

    def fake_compiler(tail, compiler):     # writes a "library" where -o points
        out = Path(tail[tail.index("-o") + 1])
        out.write_bytes(b"not really a library")
        return subprocess.CompletedProcess(tail, 0, "", "")

    monkeypatch.setattr(build, "run_compiler", fake_compiler)
    events = []
    native.add_compile_observer(lambda what, s: events.append((what, s)))
    try:
        build.compile_library("cc", outdir=tmp_path)
        assert capsys.readouterr().err == ""            # no observer that prints
        install_compile_notices()
        (tmp_path / "again").mkdir()
        build.compile_library("cc", outdir=tmp_path / "again")
        err = capsys.readouterr().err.splitlines()
    finally:
        remove_compile_notices()
        native._observers.clear()
    assert events[0] == (native.ROD_KERNELS, None) and events[1][1] >= 0
    assert err[0] == "kvrod: compiling the rod kernels (first use, ~10 s; cached afterwards)..."
    assert re.fullmatch(r"kvrod: compiled the rod kernels in \d+\.\d s", err[1])


def test_compile_native_reports_zero_when_cached():
    from runtime import native
    from runtime.model import build

    build.compile_native()                              # whatever it takes the first time
    spent = build.compile_native()
    assert spent == {native.ROD_KERNELS: 0.0, native.STEP_LOOP: 0.0}


def test_a_missing_package_is_named_with_its_install_command(monkeypatch, capsys, tmp_path):
    """A package that is not installed (here Dask's distributed, hidden) gives one line
    naming it and the command that installs it, exit 2, never an internal error."""
    import builtins

    from kvrod.cli import main

    real = builtins.__import__

    def hide(name, *args, **kw):
        if name == "distributed" or name.startswith("distributed."):
            raise ModuleNotFoundError(f"No module named {name!r}", name=name)
        return real(name, *args, **kw)

    monkeypatch.setattr(builtins, "__import__", hide)
    for mod in [m for m in sys.modules if m == "distributed" or m.startswith(
            ("distributed.", "runtime.study.sweep_dask"))]:
        monkeypatch.delitem(sys.modules, mod)
    code = main(["sweep", str(ROOT / "examples" / "study_tau.toml"), "--out",
                 str(tmp_path / "never-written")])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2, err
    assert len(err) == 1 and "'distributed'" in err[0] and "pip install" in err[0]
    assert "internal error" not in err[0]
    assert not (tmp_path / "never-written").exists()


def test_optional_packages_name_their_extras():
    import tomllib

    from kvrod.cli import OPTIONAL_PACKAGES, missing_package_line

    extras = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"][
        "optional-dependencies"]
    for module, extra in OPTIONAL_PACKAGES.items():
        assert extra in extras, (module, extra)
        assert f"[{extra}]" in missing_package_line("kvrod x", module)
    assert "core dependency" in missing_package_line("kvrod x", "scipy.sparse")


def test_a_rod_along_x_needs_no_normal():
    """The default first director is e1, which a rod along x cannot take: then e2."""
    from runtime.problem.assemble import build_model
    from runtime.problem.schema import Problem

    base = {"rod": {"length": 0.3, "elements": 4, "geometry": {"kind": "straight"}},
            "section": {"kind": "circle", "radius": 0.005},
            "material": {"density": 1000.0, "youngs_modulus": 1e6, "poisson_ratio": 0.3,
                         "tau": 0.01},
            "start": "clamped"}
    for d, n in (([1.0, 0.0, 0.0], (0.0, 1.0, 0.0)), ([-1.0, 0.02, 0.0], (0.0, 1.0, 0.0)),
                 ([0.0, 0.0, 1.0], (1.0, 0.0, 0.0)), ([0.0, 1.0, 0.0], (1.0, 0.0, 0.0))):
        base["rod"]["geometry"]["direction"] = d
        p = Problem.from_mapping(base)
        assert p.rod.geometry.normal == n
        R = build_model(p).frames(build_model(p).reference)[0]
        assert np.allclose(R.T @ R, np.eye(3)) and np.linalg.det(R) == pytest.approx(1.0)
        assert R[:, 2] == pytest.approx(np.asarray(d) / np.linalg.norm(d))
        assert Problem.from_mapping(p.to_mapping()) == p         # the resolved normal


def test_compare_damping_table_has_a_label_per_column():
    from reports.analyses import compare_table

    r = {"tau_E": 0.04, "measured_zeta": 0.07, "predicted_zeta": 0.071,
         "predicted_zeta_continuum": 0.0713, "modal_zeta": 0.0712}
    result = {"cases": {"bending": {"routes": {"consistent": r, "naive": r},
                                    "measured_ratio": 1.0, "predicted_ratio": 1.0}}}
    lines = compare_table(result).splitlines()
    assert len(lines[0].split()) - lines[0].count("[s]") - lines[0].count(" tau/2") \
        - lines[0].count(" meas.") - lines[0].count(" mod.") == len(lines[2].split())


def test_documented_sag_of_clamped_both_is_the_reference():
    """The numbers in examples/clamped_both.toml's comment are the reference's."""
    import tomllib

    from references.examples import clamped_both_reference

    text = (ROOT / "examples" / "clamped_both.toml").read_text()
    m = re.search(r"([0-9.]+) um of bending plus ([0-9.]+) um of shear", text)
    ref = clamped_both_reference(tomllib.loads(text))
    assert float(m.group(1)) == pytest.approx((ref["midspan"] - ref["shear_part"]) * 1e6,
                                              abs=0.006)
    assert float(m.group(2)) == pytest.approx(ref["shear_part"] * 1e6, abs=0.0006)


def test_simulate_off_a_terminal_does_not_stop_for_progress(tmp_path, monkeypatch):
    """Without a terminal there is no progress bar, and the run does not return from the
    compiled loop for its ticks (100 stops on the way otherwise)."""
    from kvrod.cli import main
    from kvrod.progress import progress_bar
    from runtime.solvers.native.step_loop import CoreLink

    assert not sys.stderr.isatty() and progress_bar(1.0, "x")[0] is None
    runs: list[int] = []
    advance = CoreLink.advance
    monkeypatch.setattr(CoreLink, "advance",
                        lambda self, *a: runs.append(1) or advance(self, *a))
    assert main(["simulate", "cantilever", "--n-elements", "6", "--t-end", "2",
                 "--out", str(tmp_path / "run")]) == 0
    assert 0 < len(runs) < 20
