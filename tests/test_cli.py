"""CLI behaviour: listing, showing, one-line errors with non-zero exit codes."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

from kvrod.cli import main


def run_cli(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "kvrod.cli", *args], capture_output=True,
                          text=True, timeout=300)


def test_derive_list_json(capsys):
    assert main(["derive", "list", "--json"]) == 0
    assert '"dissipation"' in capsys.readouterr().out


def test_derive_show_latex(capsys):
    assert main(["derive", "show", "naive_resultants", "--latex"]) == 0
    out = capsys.readouterr().out
    assert r"\begin{align}" in out and r"\eta" in out


@pytest.mark.parametrize("argv", [
    ["derive", "show", "no_such_step"],
    ["derive", "--bogus"],
    ["derive", "show"],
    ["frobnicate"],
    ["generate", "--chek"],
])
def test_bad_input_one_line_nonzero(argv):
    r = run_cli(*argv)
    assert r.returncode == 2
    assert len(r.stderr.strip().splitlines()) == 1, r.stderr
    assert "Traceback" not in r.stderr


def test_derive_notes(tmp_path):
    out = tmp_path / "derivation.md"
    assert main(["derive", "notes", "--out", str(out)]) == 0
    text = out.read_text()
    assert "eta_E" in text and "(\\eta_E - \\tilde\\eta_E)" in text
    assert "**DIFFERS**" not in text


def test_reproduce_coarse_notes_beside_the_runs(tmp_path):
    """A coarse `kvrod reproduce` whose notes sit in its own results folder (the figures are
    already there: nothing to copy) writes the report with the three tau rows."""
    out = tmp_path / "rep"
    r = run_cli("reproduce", "--n-elements", "8", "--t-end", "4", "--out", str(out),
                "--notes", str(out / "reproduction.md"), "--skip-derive")
    assert r.returncode == 0, r.stderr[-2000:]
    text = (out / "reproduction.md").read_text()
    for tau in ("0.02", "0.04", "0.08"):
        assert f"\n| {tau} |" in text
    assert (out / "figures" / "fig3_tip.png").stat().st_size > 0


def test_kvrod_warnings_reach_the_user(tmp_path):
    """A degraded path is said on stderr as one line, not swallowed with NumPy's
    floating-point RuntimeWarnings: without a C compiler the run falls back to the CasADi
    kernels in-process (same results, slower), and says so."""
    env = {**os.environ, "KVROD_NO_COMPILER": "1"}
    r = subprocess.run([sys.executable, "-m", "kvrod.cli", "simulate", "cantilever",
                        "--n-elements", "2", "--t-end", "0.01", "--out", str(tmp_path / "r")],
                       capture_output=True, text=True, env=env, timeout=600)
    assert r.returncode == 0, r.stderr
    lines = [ln for ln in r.stderr.splitlines() if "in-process instead" in ln]
    assert len(lines) == 1 and lines[0].startswith("kvrod: ")
    assert "Warning" not in r.stderr          # the message, not Python's file:line format


def test_the_program_leaves_its_heap_to_the_os(monkeypatch, capsys):
    """As the program (argv None) a command ends by freezing the heap (the interpreter's
    last full collection then skips it: 0.1-0.5 s of a command's exit); called with its
    arguments (tests, scripts), main leaves the collector alone."""
    import gc

    gc.unfreeze()
    try:
        assert main(["problem-keys"]) == 0
        assert gc.get_freeze_count() == 0
        monkeypatch.setattr(sys, "argv", ["kvrod", "problem-keys"])
        assert main() == 0
        assert gc.get_freeze_count() > 0
    finally:
        gc.unfreeze()
    assert "youngs_modulus" in capsys.readouterr().out
