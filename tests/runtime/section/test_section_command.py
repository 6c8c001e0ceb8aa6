"""`kvrod section` end to end: TOML files through the real entry point (``kvrod.cli.main``)
against the references written separately (references/section_analysis.py), as the
issue's "done when" list asks: a homogeneous circle, a concentric composite of one Poisson
ratio, the bimetal strip, a transversely isotropic circle and the published VABS box beam.
The Python function (``analyse_problem_section``) gives what section.json holds."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
import tomli_w

from kvrod.cli import main
from references import section_analysis as ref
from runtime.problem.section_analysis import analyse_problem_section


def rel(a: float, b: float) -> float:
    return abs(a - b) / abs(b)


def run_section(tmp_path: Path, doc: dict, *flags: str) -> dict:
    """Write ``doc`` as a TOML file, run `kvrod section` on it, return section.json."""
    f = tmp_path / f"{doc.get('name', 'section')}.toml"
    f.write_text(tomli_w.dumps(doc))
    out = tmp_path / "out"
    assert main(["section", str(f), "--out", str(out), *flags]) == 0
    assert (out / "section.png").stat().st_size > 0
    return json.loads((out / "section.json").read_text())


def diag(d: dict, key: str) -> np.ndarray:
    return np.diag(np.array(d[key]))


def test_homogeneous_circle_from_a_section_file(tmp_path, capsys):
    """A circle of one Kelvin-Voigt material ([material], the FE analysis of the shape):
    EA, EI, GJ, the energy shear stiffness and the consistent (eta_E) and naive (eta~_E)
    viscosities to 2e-4; the closed-form rod model beside it (Cowper's shear factors)."""
    E, nu, tS, tB, r = 2.0e9, 0.35, 0.03, 0.004, 0.004
    d = run_section(tmp_path, {"name": "circle", "section": {"kind": "circle", "radius": r},
                               "material": {"youngs_modulus": E, "poisson_ratio": nu,
                                            "density": 1200.0, "tau_S": tS, "tau_B": tB}})
    want = ref.circle(r, E, nu, tS, tB)
    for key, w in (("stiffness", want.K), ("viscosity", want.V),
                   ("viscosity_naive", want.V_naive)):
        for i, v in enumerate(diag(d, key)):
            assert rel(v, w[i]) < 2e-4, (key, i, v, w[i])
    assert d["mesh"]["converged"] and d["kind"] == "circle" and d["damping"] == "consistent"
    assert d["reference_point"] == d["elastic_centroid"]
    assert d["mass_per_length"] == pytest.approx(1200.0 * math.pi * r * r, rel=1e-6)
    cf = d["closed_form"]
    assert cf["shear_factors"]["kind"] == "Cowper"
    # the rod model differs from the FE only in the shear entries (Cowper's factor)
    assert np.allclose(cf["stiffness_diagonal"][2:], diag(d, "stiffness")[2:], rtol=2e-4)
    assert cf["stiffness_diagonal"][0] > 1.03 * diag(d, "stiffness")[0]
    text = capsys.readouterr().out
    assert "stiffness K about the elastic centroid" in text and "Gamma3" in text


def test_concentric_composite_of_one_poisson_ratio_is_the_sum(tmp_path):
    """Core, insulation and jacket of one nu: EA, EI, GJ and the extension, bending and
    torsion viscosities (both routes) are the per-region sums, to 2e-4."""
    layers = [(110e9, 0.33, 0.0, 0.0), (3e9, 0.33, 0.05, 0.01), (20e6, 0.33, 0.1, 0.02)]
    radii = [0.002, 0.003, 0.0035]
    doc = {"name": "cable", "section": {"kind": "composite", "regions": [
        {"material": "l0", "shape": {"kind": "circle", "radius": radii[0]}},
        {"material": "l1", "shape": {"kind": "tube", "inner_radius": radii[0],
                                     "outer_radius": radii[1]}},
        {"material": "l2", "shape": {"kind": "tube", "inner_radius": radii[1],
                                     "outer_radius": radii[2]}}]},
        "materials": {f"l{i}": {"youngs_modulus": E, "poisson_ratio": nu, "density": 1000.0,
                                "tau_S": tS, "tau_B": tB}
                      for i, (E, nu, tS, tB) in enumerate(layers)}}
    d = run_section(tmp_path, doc)
    s = ref.concentric_sum(radii, layers)
    for key, w in (("stiffness", s.K), ("viscosity", s.V), ("viscosity_naive", s.V_naive)):
        for i in range(2, 6):
            assert rel(diag(d, key)[i], w[i]) < 2e-4, (key, i)


def test_bimetal_strip(tmp_path):
    """Two bonded layers of one nu stacked along d2: the transformed EI about the elastic
    centroid, no elastic extension-bending coupling there (< 1e-6 of the geometric mean),
    and the viscous Gamma3-K1 coupling sum eta_E,i A_i (y_i - y_c), both routes; the
    viscous centroid is where the viscous axial force acts."""
    w, h0, h1 = 0.01, 0.002, 0.003
    layers = ((200e9, 0.3, 0.001, 0.002), (70e9, 0.3, 0.02, 0.005))
    doc = {"name": "bimetal", "section": {"kind": "composite", "regions": [
        {"material": "steel", "shape": {"kind": "rectangle", "width": w, "height": h0,
                                        "centre": [0.0, -h0 / 2]}},
        {"material": "alu", "shape": {"kind": "rectangle", "width": w, "height": h1,
                                      "centre": [0.0, h1 / 2]}}]},
        "materials": {n: {"youngs_modulus": E, "poisson_ratio": nu, "density": 5000.0,
                          "tau_S": tS, "tau_B": tB}
                      for n, (E, nu, tS, tB) in zip(("steel", "alu"), layers, strict=True)}}
    d = run_section(tmp_path, doc)
    b = ref.bimetal(w, (h0, h1), layers)
    K, V, Vn = (np.array(d[k]) for k in ("stiffness", "viscosity", "viscosity_naive"))
    assert d["elastic_centroid"][1] == pytest.approx(b["y_c"], abs=1e-9)
    assert rel(K[3, 3], b["EI1"]) < 1e-4
    for j in (3, 4):
        assert abs(K[2, j]) < 1e-6 * math.sqrt(K[2, 2] * K[j, j])
    assert rel(V[2, 3], b["V_Gamma3_K1"]) < 1e-4
    assert rel(Vn[2, 3], b["V_Gamma3_K1_naive"]) < 1e-4
    assert d["viscous_centroid"][1] == pytest.approx(
        b["y_c"] + b["V_Gamma3_K1"] / b["V_Gamma3"], rel=1e-4)


def test_transversely_isotropic_circle_from_voigt_matrices(tmp_path):
    """A circle of a fibre material given by its 6x6 Voigt matrices (symmetry axis along
    the rod): EA, EI, GJ and the extension, bending and torsion viscosities, to 2e-4."""
    C = ref.box_material_stiffness()
    V = 0.01 * np.diag([1.0, 1.0, 5.0, 2.0, 2.0, 1.0]) * 1e9
    V[0, 1] = V[1, 0] = 0.2e9 * 0.01
    V[0, 2] = V[2, 0] = V[1, 2] = V[2, 1] = 0.3e9 * 0.01
    doc = {"name": "fibre", "section": {"kind": "composite", "regions": [
        {"material": "f", "shape": {"kind": "circle", "radius": 0.005}}]},
        "materials": {"f": {"stiffness_matrix": C.tolist(), "viscosity_matrix": V.tolist(),
                            "density": 1600.0}}}
    d = run_section(tmp_path, doc)
    t = ref.transversely_isotropic_circle(0.005, C, V)
    K, Vc, Vn = (diag(d, k) for k in ("stiffness", "viscosity", "viscosity_naive"))
    for got, want in ((K[2], t["EA"]), (K[3], t["EI"]), (K[4], t["EI"]), (K[5], t["GJ"]),
                      (Vc[2], t["V_ext"]), (Vc[3], t["V_bend"]), (Vn[2], t["V_ext_naive"]),
                      (Vn[3], t["V_bend_naive"]), (Vc[5], t["V_tors"]), (Vn[5], t["V_tors"])):
        assert rel(got, want) < 2e-4, (got, want)


def test_published_vabs_box_beam_from_a_toml_file(tmp_path):
    """The CUS box beam (Yu, Hodges, Ho 2012) written as a section file (four walls as
    polygons, the ply by its Voigt matrix, fibres at 15 degrees wound along each wall):
    every published entry of the VABS matrix to 1 % (off-diagonal ones relative to the
    geometric mean of their diagonals), the extension-twist coupling included."""
    C = ref.box_material_stiffness()
    g = ref.BOX_GEOMETRY
    X, Y = g["width"] * ref.INCH / 2, g["height"] * ref.INCH / 2
    t = g["wall"] * ref.INCH
    x, y = X - t, Y - t
    walls = {"top": ([(-x, y), (x, y), (X, Y), (-X, Y)], 180.0),
             "left": ([(-X, -Y), (-x, -y), (-x, y), (-X, Y)], 270.0),
             "bottom": ([(-X, -Y), (X, -Y), (x, -y), (-x, -y)], 0.0),
             "right": ([(x, -y), (X, -Y), (X, Y), (x, y)], 90.0)}
    doc = {"name": "box", "section": {"kind": "composite", "regions": [
        {"name": k, "material": k, "shape": {"kind": "polygon", "points": [list(q) for q in p]}}
        for k, (p, _) in walls.items()]},
        "materials": {k: {"stiffness_matrix": C.tolist(), "density": 1.0,
                          "orientation": {"rotation": beta, "off_axis": g["ply_angle"]}}
                      for k, (_, beta) in walls.items()}}
    d = run_section(tmp_path, doc, "--tol", "1e-3")
    K = np.array(d["stiffness"])
    pub = ref.box_vabs_in_kvrod_units()
    for (i, j), v in pub.items():
        scale = abs(v) if i == j else math.sqrt(pub[(i, i)] * pub[(j, j)])
        assert abs(K[i, j] - v) / scale < 0.01, (i, j, K[i, j], v)


def test_the_python_function_gives_what_the_command_writes(tmp_path):
    """analyse_problem_section on the example file: the same numbers as section.json (one
    computation, two doors), and the example's cable has its centres at the axis."""
    from runtime.problem.registry import EXAMPLES_DIR

    f = EXAMPLES_DIR / "cable_section.toml"
    out = tmp_path / "cable"
    assert main(["section", str(f), "--out", str(out)]) == 0
    d = json.loads((out / "section.json").read_text())
    res = analyse_problem_section(f)
    assert np.allclose(np.array(d["stiffness"]), res.stiffness, rtol=1e-12, atol=0.0)
    assert np.allclose(np.array(d["viscosity"]), res.viscosity, rtol=1e-12, atol=0.0)
    assert d["regions"][0]["name"] == "core" and d["materials"]["copper"]["kind"] == "isotropic"
    for key in ("mass_per_length", "mass_centre", "rotary_inertia", "elastic_centroid",
                "shear_centre", "reference_point", "viscous_centroid"):
        assert key in d
    assert np.allclose(d["elastic_centroid"], 0.0, atol=1e-12)
    # copper carries the stiffness, the polymers all of the viscosity
    assert d["materials"]["copper"]["youngs_modulus"] > 1e3 * d["materials"]["pvc"][
        "youngs_modulus"]


def test_energy_shear_factors_make_a_shape_and_its_one_region_composite_agree(tmp_path):
    """shear_correction = "energy": the closed-form rod model of a rectangle takes the
    section analysis's shear factors, so its diagonal equals the one-region composite's;
    with Cowper's (the default) the shear entries differ by a few per cent."""
    from runtime.problem.registry import load_problem

    E, nu = 1.0e9, 0.3
    mat = {"youngs_modulus": E, "poisson_ratio": nu, "density": 1000.0, "tau": 0.01}
    shape = {"width": 0.02, "height": 0.008}
    comp = analyse_problem_section({"section": {"kind": "composite", "regions": [
        {"material": "m", "shape": {"kind": "rectangle", **shape}}]}, "materials": {"m": mat}})
    K = np.diag(comp.stiffness)
    for sc, close in (("energy", True), (True, False)):
        p = load_problem("cantilever", {"section": {"kind": "rectangle", **shape,
                                                    "shear_correction": sc},
                                        "material": mat})
        m = p.segment_matrices()
        rod = np.concatenate([m["C_F"][0], m["C_M"][0]])
        assert np.allclose(rod[2:5], K[2:5], rtol=2e-4)
        assert np.allclose(rod[:2], K[:2], rtol=2e-4) == close, (sc, rod[:2], K[:2])
    assert p.to_mapping()["section"]["shear_correction"] is True
