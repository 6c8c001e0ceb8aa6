"""Notes that do not churn: a notes command run twice writes the same bytes (text and
figures); measurements go to the results folder; `--out DIR` never rewrites the notes of
the checkout. notes-beyond (the cheapest) runs here with smaller settings."""

from __future__ import annotations

import argparse
import json
import re
from pathlib import Path

import pytest

from reports import damping_studies as beyond


@pytest.fixture()
def small(monkeypatch):
    """notes-beyond at smaller sizes (a few seconds instead of ten)."""
    for name, value in {"COMPARE_N": 8, "MODES_N": 12, "MODES_COUNT": 6, "DISTINCT_MODES": 3,
                        "CAL_DATA_N": 10, "CAL_MODEL_N": 6, "CAL_T_END": 2.0}.items():
        monkeypatch.setattr(beyond, name, value)


def _run_in(folder: Path, monkeypatch) -> Path:
    folder.mkdir()
    monkeypatch.chdir(folder)
    return beyond.write_beyond_notes(Path("notes/beyond.md"), Path("results/beyond"),
                                     command="kvrod notes-beyond")


def test_notes_beyond_twice_gives_the_same_bytes(tmp_path, monkeypatch, small):
    a = tmp_path / "a"
    b = tmp_path / "b"
    _run_in(a, monkeypatch)
    _run_in(b, monkeypatch)
    notes_a = (a / "notes" / "beyond.md").read_bytes()
    assert notes_a == (b / "notes" / "beyond.md").read_bytes()
    figs = sorted(p.name for p in (a / "notes" / "figures").glob("*.png"))
    assert len(figs) == 5
    for name in figs:
        assert (a / "notes" / "figures" / name).read_bytes() == \
            (b / "notes" / "figures" / name).read_bytes(), name
    # the mode shapes themselves (their signs): the same in both runs' modes.json/.npz
    from runtime.io.modes import read_modes

    for sub in ("modes", "modes-deformed"):
        ma, mb = (read_modes(x / "results/beyond" / sub) for x in (a, b))
        assert ma.modes == mb.modes
        assert ma.displacement.tobytes() == mb.displacement.tobytes()
        assert ma.rotation.tobytes() == mb.rotation.tobytes()
    text = notes_a.decode()
    assert str(tmp_path) not in text and not re.search(r"(?i)\bissue \d", text)
    import platform

    assert platform.python_version() not in text and platform.machine() not in text
    # the measurements are in the results folder instead, the C compilation apart
    info = json.loads((a / "results/beyond/timings.json").read_text())
    assert set(info["compile_s"]) == {"the rod kernels", "the BDF step loop"}
    assert {"compare-damping", "modes", "calibration"} <= set(info["wall_s"])
    assert "run-info.md" in text
    assert (a / "results/beyond/run-info.md").read_text().startswith("# Run information")


def _paths(argv: list[str]) -> tuple[Path, Path]:
    from kvrod.cli_notes import _notes_paths

    ns = argparse.Namespace(out=None, out_notes=None)
    for flag, value in zip(argv[::2], argv[1::2], strict=True):
        setattr(ns, flag.lstrip("-").replace("-", "_"), value)
    return _notes_paths(ns, "maxwell", "notes/maxwell.md", "results/maxwell")


def test_out_alone_keeps_the_notes_out_of_the_checkout(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert _paths([]) == (Path("notes/maxwell.md"), Path("results/maxwell"))
    assert _paths(["--out", "x/y"]) == (Path("x/y/maxwell.md"), Path("x/y"))
    assert _paths(["--out", "x", "--out-notes", "n.md"]) == (Path("n.md"), Path("x"))
    assert _paths(["--out-notes", "n.md"]) == (Path("n.md"), Path("results/maxwell"))


def test_decade_bounds():
    from reports.run_info import bound, decade

    assert decade(7.6e-6) == "1e-5" and bound(7.6e-6) == "< 1e-5"
    assert decade(2.4e-6) == "1e-5" and decade(1.2e-5) == "1e-4"
    assert bound(0.0) == "0" and bound(float("nan")) == "-"


def test_notes_sections_twice_gives_the_same_bytes(tmp_path, monkeypatch):
    """notes-sections (three section analyses, no simulation): the same notes, figures and
    section.json files from two runs; its wall times only in the results folder."""
    from reports.sections import RESULTS, write_sections_notes

    for name in ("a", "b"):
        (tmp_path / name).mkdir()
        monkeypatch.chdir(tmp_path / name)
        write_sections_notes(Path("notes/sections.md"), Path("results/sections"))
    a, b = tmp_path / "a", tmp_path / "b"
    files = [Path("notes/sections.md"), *sorted(p.relative_to(a) for p in
                                                (a / "notes" / "figures").glob("*.png")),
             *(Path("results/sections") / r / f for r in RESULTS
               for f in ("section.json", "section.png"))]
    assert len(files) == 1 + 4 + 6
    for f in files:
        assert (a / f).read_bytes() == (b / f).read_bytes(), f
    text = (a / "notes/sections.md").read_text()
    assert str(tmp_path) not in text and not re.search(r"(?i)\bissue \d", text)
    assert "run-info.md" in text and "wall" not in json.loads(
        (a / "results/sections/cable/section.json").read_text())
    info = json.loads((a / "results/sections/timings.json").read_text())
    assert {f"section analysis: {r}" for r in RESULTS} <= set(info["wall_s"])
