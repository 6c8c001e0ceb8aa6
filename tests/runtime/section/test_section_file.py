"""``section.file``: a problem's section from a section file (issue 30, item 6), and a
study's problem path relative to the study file.

The section file is what ``kvrod section`` reads; its path is relative to the problem
file; its tables and the problem's combine without ambiguity (a clash names both keys);
a problem written back (``to_mapping``, a results folder's problem.toml) holds the section
itself and loads anywhere."""

from __future__ import annotations

import shutil
import tomllib
from pathlib import Path

import pytest

from runtime.errors import ParameterError
from runtime.problem.registry import EXAMPLES_DIR, load_problem
from runtime.problem.schema import Problem
from runtime.problem.sections import Composite

ROD = """name = "cable_rod"
[rod]
length = 0.3
elements = 4
[section]
file = "{file}"
{extra}
[[loads]]
kind = "force"
at = "end"
vector = [0.02, 0.0, 0.0]
[simulation]
t_end = 0.05
"""


def _problem(tmp_path: Path, extra: str = "", file: str = "sections/cable.toml",
             tail: str = "") -> Path:
    (tmp_path / "sections").mkdir(exist_ok=True)
    shutil.copy(EXAMPLES_DIR / "cable_section.toml", tmp_path / "sections" / "cable.toml")
    p = tmp_path / "rod.toml"
    p.write_text(ROD.format(file=file, extra=extra) + tail)
    return p


def test_a_problem_takes_its_section_and_materials_from_the_file(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path.parent)            # the path is the problem file's, not cwd's
    p = load_problem(_problem(tmp_path))
    direct = tomllib.loads((EXAMPLES_DIR / "cable_section.toml").read_text())
    assert isinstance(p.section, Composite)
    assert [r.name for r in p.section.regions] == ["core", "insulation", "jacket"]
    assert p.section.materials_mapping() == direct["materials"]
    # written back: the section in full, no file; it loads from another folder
    m = p.to_mapping()
    assert "file" not in m["section"] and m["section"]["kind"] == "composite"
    other = tmp_path / "elsewhere"
    other.mkdir()
    again = Problem.from_mapping(m, base=other, name="again")
    assert again.section == p.section and again.to_mapping()["materials"] == m["materials"]


def test_damping_beside_the_file_replaces_the_files(tmp_path):
    p = load_problem(_problem(tmp_path, extra='damping = "naive"'))
    assert p.section.damping == "naive" and p.damping == "naive"
    # and an override reaches the section file's materials
    q = load_problem(_problem(tmp_path), {"materials.pvc.tau_S": 0.05})
    assert dict(q.section.materials)["pvc"].isotropic[2] == 0.05


@pytest.mark.parametrize(("extra", "tail", "names"), [
    ('kind = "circle"', "", ("section.kind", "section.file")),
    ("", "[materials.extra]\nyoungs_modulus = 1e6\npoisson_ratio = 0.3\ndensity = 1000.0\n",
     ("materials", "section.file")),
    ("", "[material]\ntau = 0.1\n", ("material", "section.file")),
])
def test_a_table_beside_the_file_that_it_gives_is_refused_naming_both(tmp_path, extra, tail,
                                                                     names):
    with pytest.raises(ParameterError) as exc:
        load_problem(_problem(tmp_path, extra=extra, tail=tail))
    assert exc.value.name == names[0] and names[1] in str(exc.value)


def test_bad_section_files_are_named(tmp_path):
    with pytest.raises(ParameterError, match=r"section\.file.*nope\.toml.*readable"):
        load_problem(_problem(tmp_path, file="nope.toml"))
    problem_as_section = tmp_path / "sections" / "a_problem.toml"
    (tmp_path / "sections").mkdir(exist_ok=True)
    shutil.copy(EXAMPLES_DIR / "cantilever.toml", problem_as_section)
    with pytest.raises(ParameterError, match=r"section\.file.*\[rod\]"):
        load_problem(_problem(tmp_path, file="sections/a_problem.toml"))
    p = _problem(tmp_path)
    bad = tmp_path / "sections" / "cable.toml"
    bad.write_text(bad.read_text().replace("tau_S = 0.01", "tau_S = -0.01"))
    with pytest.raises(ParameterError, match=r"materials\.pvc\.tau_S \(in section\.file "
                                             r"'sections/cable\.toml'\)"):
        load_problem(p)


def test_a_shape_section_file_brings_its_material(tmp_path):
    (tmp_path / "bar.toml").write_text(
        '[section]\nkind = "rectangle"\nwidth = 0.01\nheight = 0.002\n'
        "[material]\nyoungs_modulus = 2e9\npoisson_ratio = 0.3\ndensity = 1200.0\n"
        "tau = 0.01\n")
    (tmp_path / "rod.toml").write_text('[rod]\nlength = 0.3\nelements = 4\n'
                                       '[section]\nfile = "bar.toml"\n')
    p = load_problem(tmp_path / "rod.toml")
    assert p.section.kind == "rectangle" and p.material.youngs_modulus == 2e9
    # a shape without [material]: the problem's own material
    (tmp_path / "bar.toml").write_text('[section]\nkind = "circle"\nradius = 0.004\n')
    (tmp_path / "rod.toml").write_text('[rod]\nlength = 0.3\nelements = 4\n'
                                       '[section]\nfile = "bar.toml"\n'
                                       "[material]\nyoungs_modulus = 3e9\n")
    p = load_problem(tmp_path / "rod.toml")
    assert p.section.kind == "circle" and p.material.youngs_modulus == 3e9


def test_the_key_is_listed_for_problem_files():
    from runtime.problem.keys import KEYS

    assert any(k.table == "section" and k.name == "file" for k in KEYS)


def test_a_studys_problem_path_is_relative_to_the_study_file(tmp_path, monkeypatch):
    from runtime.study.sweep import load_study

    (tmp_path / "problems").mkdir()
    (tmp_path / "studies").mkdir()
    shutil.copy(EXAMPLES_DIR / "cantilever.toml", tmp_path / "problems" / "cant.toml")
    study = tmp_path / "studies" / "s.toml"
    study.write_text('problem = "../problems/cant.toml"\n[fixed]\nn_elements = 4\n'
                     "t_end = 0.1\n[grid]\ntau = [0.02, 0.04]\n")
    monkeypatch.chdir(tmp_path.parent)
    s = load_study(study)
    assert Path(s.problem) == (tmp_path / "problems" / "cant.toml").resolve()
    assert len(s.points) == 2
