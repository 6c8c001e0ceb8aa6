"""Composite sections and named materials in problem files (runtime/problem): parsing,
errors naming the key, the damping key for every section kind, writing a problem back,
composite sections in every command (their rod matrices from the section analysis), and
the energy shear factors of the closed-form shapes."""

from __future__ import annotations

import copy
import math
from pathlib import Path

import numpy as np
import pytest

from kvrod.cli import main
from references import section_analysis as ref
from references.sections import cowper_circle
from runtime.errors import ParameterError
from runtime.problem.registry import load_problem
from runtime.problem.schema import Problem
from runtime.problem.sections import Composite, energy_shear_factors

CABLE = {
    "name": "cable_rod",
    "rod": {"length": 0.5, "elements": 8},
    "section": {"kind": "composite", "regions": [
        {"name": "core", "material": "cu", "shape": {"kind": "circle", "radius": 0.001}},
        {"material": "pvc", "shape": {"kind": "tube", "inner_radius": 0.001,
                                      "outer_radius": 0.002}}]},
    "materials": {"cu": {"youngs_modulus": 117e9, "poisson_ratio": 0.34, "density": 8960.0},
                  "pvc": {"youngs_modulus": 30e6, "poisson_ratio": 0.45, "density": 1350.0,
                          "tau_S": 0.01}},
    "loads": [{"kind": "gravity", "vector": [-9.81, 0.0, 0.0]}],
}


def cable(**changes) -> dict:
    m = copy.deepcopy(CABLE)
    for path, value in changes.items():
        node = m
        *head, last = path.split(".")
        for part in head:
            node = node[int(part)] if isinstance(node, list) else node[part]
        if value is None:
            del node[last]
        else:
            node[last] = value
    return m


def test_a_composite_problem_reads_and_writes_back():
    p = Problem.from_mapping(cable())
    assert isinstance(p.section, Composite) and p.material is None
    assert p.damping == "consistent"
    assert [r.material for r in p.section.regions] == ["cu", "pvc"]
    m = p.to_mapping()
    assert "material" not in m and set(m["materials"]) == {"cu", "pvc"}
    assert m["section"]["regions"][0]["name"] == "core"
    assert "name" not in m["section"]["regions"][1]           # not given: not written
    assert Problem.from_mapping(m) == p
    q = p.with_overrides({"materials.pvc.tau": 0.02, "damping": "naive"})
    mats = q.section.material_map()
    assert mats["pvc"].isotropic[2:] == (0.02, 0.02)          # tau replaced tau_S
    assert q.damping == "naive" and q != p
    r = p.with_overrides({"section.regions.1.shape.outer_radius": 0.003})
    assert r.section.regions[1].shape.outer_radius == 0.003


@pytest.mark.parametrize("changes, needle", [
    ({"material": {"tau": 0.1}}, r"'material'.*no \[material\] beside .*composite"),
    ({"materials": None}, r"'materials'.*\[materials\.NAME\]"),
    ({"section.regions.1.material": "steel"}, r"section\.regions\[1\]\.material.*'cu', 'pvc'"),
    ({"section.regions.1.shape.inner_radius": 0.0005},
     r"section\.regions\[1\]\.shape.*overlap.*'core'"),
    ({"materials.pvc.poisson_ratio": 0.5}, r"materials\.pvc\.poisson_ratio.*1/2"),
    ({"materials.pvc.model": "generalized_maxwell"},
     r"materials\.pvc\.model.*generalized Maxwell regions are not supported"),
    ({"materials.pvc.density": -1.0}, r"materials\.pvc\.density.*kg/m\^3"),
    ({"section.damping": "viscous"}, r"section\.damping"),
    ({"section.shear_correction": "energy"}, r"section\.shear_correction.*known key"),
])
def test_composite_errors_name_the_key(changes, needle):
    with pytest.raises(ParameterError, match=needle):
        Problem.from_mapping(cable(**changes))


def test_materials_only_with_a_composite_section():
    m = load_problem("cantilever").to_mapping()
    m["materials"] = CABLE["materials"]
    with pytest.raises(ParameterError, match=r"'materials'.*only with \[section\] kind = "
                                             r"'composite'"):
        Problem.from_mapping(m)


def test_non_spd_and_asymmetric_matrices_are_named_with_their_unit():
    C = np.eye(6) * 1e9
    C[2, 2] = -1e9
    bad = cable(**{"materials.pvc": {"stiffness_matrix": C.tolist(), "density": 1.0}})
    with pytest.raises(ParameterError, match=r"materials\.pvc\.stiffness_matrix.*positive "
                                             r"definite.*Pa"):
        Problem.from_mapping(bad)
    V = np.ones((6, 6)) * 1e3
    V[0, 1] = 0.0
    bad = cable(**{"materials.pvc": {"stiffness_matrix": (np.eye(6) * 1e9).tolist(),
                                     "viscosity_matrix": V.tolist(), "density": 1.0}})
    with pytest.raises(ParameterError, match=r"materials\.pvc\.viscosity_matrix.*symmetric"
                                             r".*Pa s"):
        Problem.from_mapping(bad)


@pytest.mark.parametrize("command", ["simulate", "static", "modes"])
def test_a_composite_problem_runs_in_every_command(tmp_path, capsys, command):
    """Composite sections are simulated with the coupled kernels (issue 26; the 6x6
    matrices of the section analysis)."""
    import tomli_w

    f = tmp_path / "cable.toml"
    f.write_text(tomli_w.dumps(cable(**{"simulation": {"t_end": 0.02, "initial": "static"}})))
    out = tmp_path / "out"
    assert main([command, str(f), "--out", str(out)]) == 0, capsys.readouterr().err
    assert (out / ("modes.json" if command == "modes" else "summary.json")).exists()


def test_the_rod_matrices_of_a_composite_are_its_section_analysis():
    from runtime.problem.coupled import composite_analysis

    p = Problem.from_mapping(cable())
    m = p.segment_matrices()
    res = composite_analysis(p.section)
    assert composite_analysis(p.section) is res               # cached per section
    K = 0.5 * (res.stiffness + res.stiffness.T)
    assert np.allclose(m["K6"], K) and m["K6"].shape == (8, 6, 6)
    assert np.allclose(m["V6"], 0.5 * (res.viscosity + res.viscosity.T))
    assert np.allclose(m["rhoA"], res.mass_per_length)
    assert np.allclose(m["mass_centre"], np.subtract(res.mass_centre, res.elastic_centroid))
    assert p.characteristic_frequency() > 0.0
    p.check_simulable()


def test_a_study_of_a_composite_problem_checks_its_points(tmp_path):
    import tomli_w

    from runtime.study.sweep import check_point

    f = tmp_path / "cable.toml"
    f.write_text(tomli_w.dumps(cable()))
    check_point(str(f), {"materials.pvc.tau_S": 0.02}, "point 1")


def test_a_non_symmetric_naive_viscosity_is_refused_naming_the_damping_key():
    import tomllib

    from runtime.problem.registry import EXAMPLES_DIR

    doc = tomllib.loads((EXAMPLES_DIR / "fibre_strip_section.toml").read_text())
    doc.update(rod={"length": 0.2, "elements": 4})
    doc["section"]["damping"] = "naive"
    doc.pop("description", None)
    p = Problem.from_mapping(doc)
    with pytest.raises(ParameterError, match=r"section\.damping.*'consistent'.*not symmetric"):
        p.check_simulable()


def test_the_damping_key_lives_in_section_and_the_old_key_is_still_read():
    base = load_problem("cantilever").to_mapping()
    assert base["section"]["damping"] == "consistent" and "damping" not in base["material"]
    for sec, mat, want in ((None, "naive", "naive"), ("naive", None, "naive"),
                           ("naive", "naive", "naive"), (None, None, "consistent")):
        m = copy.deepcopy(base)
        m["section"].pop("damping")
        if sec:
            m["section"]["damping"] = sec
        if mat:
            m["material"]["damping"] = mat
        p = Problem.from_mapping(m)
        assert p.damping == want == p.material.damping
    m = copy.deepcopy(base)
    m["material"]["damping"] = "naive"
    with pytest.raises(ParameterError, match=r"section\.damping.*material\.damping = "
                                             r"'naive'"):
        Problem.from_mapping(m)
    with pytest.raises(ParameterError, match=r"material\.damping"):
        load_problem("cantilever", {"material.damping": "magic"})
    # an override of either key replaces the other
    p = load_problem("cantilever", {"material.damping": "naive"})
    assert p.with_overrides({"section.damping": "consistent"}).damping == "consistent"
    # a Maxwell material has no naive route
    with pytest.raises(ParameterError, match=r"section\.damping.*generalized Maxwell"):
        load_problem("maxwell_cantilever", {"section.damping": "naive"})
    assert load_problem("maxwell_cantilever", {"section.damping": "consistent"})


def test_energy_shear_factors_of_the_closed_form_shapes():
    """The circle's energy factor against its closed form 6 (1 + nu)^2 / (7 + 14 nu +
    8 nu^2) (Renton; Love's flexure stresses) and the tube's against its quadrature,
    both below Cowper's; Cowper's stays the default."""
    for nu in (0.0, 0.3, 0.45):
        k1, k2 = energy_shear_factors("circle", {"radius": np.array([0.01])}, nu)
        assert k1[0] == pytest.approx(ref.shear_factor_circle(nu), rel=1e-5)
        assert k1[0] == k2[0]
    k1, _ = energy_shear_factors("tube", {"inner_radius": np.array([0.006]),
                                          "outer_radius": np.array([0.01])}, 0.3)
    assert k1[0] == pytest.approx(ref.shear_factor_tube(0.01, 0.006, 0.3), rel=1e-4)
    assert ref.shear_factor_circle(0.3) < cowper_circle(0.3)
    p = load_problem("cantilever", {"section": {"kind": "circle", "radius": 0.005}})
    assert p.section.shear_correction is True
    k = p.section.constants(0.3, np.array([0.5]))
    assert k["kappa_1"][0] == pytest.approx(cowper_circle(0.3), rel=1e-12)
    with pytest.raises(ParameterError, match=r"section\.shear_correction.*nu < 1/2"):
        load_problem("cantilever", {"section.shear_correction": "energy",
                                    "material.poisson_ratio": 0.5})


def test_energy_factors_of_a_taper_interpolate_the_analyses():
    """A rectangle whose width triples along the rod: its energy factors come from nine
    analyses over the aspect-ratio range; at points between them they agree with a direct
    analysis to 1e-5."""
    w = 0.01 + 0.02 * np.linspace(0.0, 1.0, 40)
    dims = {"width": w, "height": np.full(40, 0.01)}
    k1, k2 = energy_shear_factors("rectangle", dims, 0.3)
    for i in (3, 17, 31):
        d1, d2 = energy_shear_factors("rectangle", {"width": w[i:i + 1],
                                                    "height": np.array([0.01])}, 0.3)
        assert k1[i] == pytest.approx(d1[0], rel=1e-5)
        assert k2[i] == pytest.approx(d2[0], rel=1e-5)
    assert np.all(np.diff(k2) < 0)            # sheared across a widening strip: smaller


def test_section_file_rules(tmp_path):
    """A section file holds [section] with [materials.NAME] or [material]; a stiffness
    section, a taper and a Maxwell material are refused with the key named."""
    from runtime.problem.section_analysis import load_section

    def spec(doc):
        return load_section(doc)

    ok = spec({"section": {"kind": "circle", "radius": 0.01},
               "material": {"youngs_modulus": 1e6, "tau": 0.01}})
    regions, mats = ok.regions_and_materials()
    assert regions[0].shape.radius == 0.01 and mats["material"].isotropic[2] == 0.01
    with pytest.raises(ParameterError, match=r"section\.kind.*stiffness"):
        spec({"section": {"kind": "stiffness", **{k: 1.0 for k in (
            "EA", "GA1", "GA2", "EI1", "EI2", "GJ", "rhoA", "rhoI1", "rhoI2", "rhoI3")}}})
    with pytest.raises(ParameterError, match=r"section\.radius_end.*no taper"):
        spec({"section": {"kind": "circle", "radius": 0.01, "radius_end": 0.02}})
    with pytest.raises(ParameterError, match=r"material\.model.*kelvin_voigt"):
        spec({"section": {"kind": "circle", "radius": 0.01},
              "material": load_problem("maxwell_cantilever").to_mapping()["material"]})
    with pytest.raises(ParameterError, match=r"'loads'.*known key"):
        spec({"section": {"kind": "circle", "radius": 0.01}, "loads": []})
    f = tmp_path / "s.toml"
    f.write_text('[section]\nkind = "circle"\nradius = -1.0\n')
    with pytest.raises(ParameterError, match=r"s\.toml.*section\.radius"):
        load_section(f)
    assert Path(ok.source) == Path("table")
    assert math.isfinite(ok.material.youngs_modulus)
