"""The cross-section solver (runtime/section) against independent references
(references/section_analysis.py, references/sections.py) and a published VABS matrix."""

from __future__ import annotations

import math

import numpy as np
import pytest

from references import section_analysis as ref
from runtime.errors import ParameterError
from runtime.section import (
    Circle,
    Ellipse,
    PolygonShape,
    Rectangle,
    Region,
    Tube,
    analyse_section,
    anisotropic,
    isotropic,
    materials_from_mapping,
    regions_from_mapping,
)

E, NU, RHO, TS, TB = 70e9, 0.3, 2700.0, 0.02, 0.005


def rel(a, b):
    return abs(a - b) / abs(b)


def assert_diagonals(result, reference, tol):
    for M, R in ((result.stiffness, reference.K), (result.viscosity, reference.V),
                 (result.viscosity_naive, reference.V_naive)):
        for i in range(6):
            if R[i] is not None:
                assert rel(M[i, i], R[i]) < tol, (i, M[i, i], R[i])


@pytest.fixture(scope="module")
def metal():
    return {"m": isotropic("m", E, NU, RHO, TS, TB)}


@pytest.fixture(scope="module")
def circle_result(metal):
    return analyse_section([Region("m", Circle(0.01, (0.003, -0.002)))], metal, tol=1e-5)


def test_homogeneous_circle(circle_result):
    """EA, EI, GJ, the energy-consistent shear stiffness and both viscosities (eta_E, eta~_E)
    of a homogeneous circle, about its centroid, to 1e-5."""
    r = circle_result
    assert_diagonals(r, ref.circle(0.01, E, NU, TS, TB), 2e-5)
    assert r.converged and r.achieved_change < 1e-5
    assert np.allclose(r.elastic_centroid, (0.003, -0.002), atol=1e-9)
    assert np.allclose(r.shear_centre, (0.003, -0.002), atol=1e-9)
    K = r.stiffness
    off = K - np.diag(np.diag(K))
    assert np.max(np.abs(off) / np.sqrt(np.outer(np.diag(K), np.diag(K)))) < 1e-6
    assert r.mass_per_length == pytest.approx(RHO * math.pi * 1e-4, rel=1e-5)
    assert r.rotary_inertia["I11"] == pytest.approx(RHO * math.pi * 1e-8 / 4, rel=1e-5)
    assert r.rotary_inertia["polar"] == pytest.approx(RHO * math.pi * 1e-8 / 2, rel=1e-5)
    assert np.allclose(r.mass_centre, (0.003, -0.002), atol=1e-9)


@pytest.mark.parametrize("shape, reference", [
    (Rectangle(0.02, 0.01), lambda: ref.rectangle(0.02, 0.01, E, NU, TS, TB)),
    (Tube(0.006, 0.01), lambda: ref.tube(0.01, 0.006, E, NU, TS, TB)),
    (Ellipse(0.01, 0.004), lambda: ref.ellipse(0.01, 0.004, E, NU, TS, TB)),
])
def test_homogeneous_closed_forms(metal, shape, reference):
    """Rectangle (Saint-Venant torsion series, energy shear factors from the flexure
    series), tube and ellipse: every closed-form diagonal entry and both viscosities to
    1e-4."""
    r = analyse_section([Region("m", shape)], metal, tol=1e-4)
    assert_diagonals(r, reference(), 1e-4)


def test_energy_shear_factors_differ_from_cowper():
    """What the FE analysis gives (the energy-consistent factor) is not Cowper's."""
    from references.sections import cowper_circle
    assert ref.shear_factor_circle(0.0) == pytest.approx(cowper_circle(0.0))
    assert ref.shear_factor_circle(0.3) < 0.96 * cowper_circle(0.3)
    assert ref.shear_factor_rectangle(1.0, 3.0, 0.0) == pytest.approx(5 / 6, rel=1e-9)
    assert ref.shear_factor_tube(1.0, 1e-9, 0.3) == pytest.approx(ref.shear_factor_circle(0.3),
                                                                  rel=1e-9)


def test_viscosity_proportional_to_stiffness():
    """V3 = tau C (tau_S = tau_B) gives V = tau K for both routes, also for a composite
    with an anisotropic region and a nearly incompressible one."""
    tau = 0.03
    Cf = ref.box_material_stiffness()
    mats = {"core": anisotropic("core", Cf, tau * Cf, 1500.0, (30.0, 20.0)),
            "jacket": isotropic("jacket", 5e6, 0.4995, 1100.0, tau, tau),
            "ring": isotropic("ring", 3e9, 0.38, 1300.0, tau, tau)}
    regions = [Region("core", Circle(0.003)),
               Region("ring", Tube(0.003, 0.004)), Region("jacket", Tube(0.004, 0.005))]
    r = analyse_section(regions, mats, tol=1e-3)
    K = r.stiffness
    scale = np.sqrt(np.outer(np.diag(K), np.diag(K)))
    assert np.max(np.abs(r.viscosity - tau * K) / scale) < 1e-10 * tau
    assert np.max(np.abs(r.viscosity_naive - tau * K) / scale) < 1e-10 * tau


def test_concentric_composite_one_poisson_ratio():
    """Core, insulation, jacket of one Poisson ratio: EA, EI, GJ and the extension, bending
    and torsion viscosities (both routes) are the sums over the regions."""
    layers = [(110e9, 0.33, 0.0, 0.0), (3e9, 0.33, 0.05, 0.01), (20e6, 0.33, 0.1, 0.02)]
    radii = [0.002, 0.003, 0.0035]
    mats = {f"l{i}": isotropic(f"l{i}", *ly[:2], 1000.0, *ly[2:]) for i, ly in enumerate(layers)}
    regions = [Region("l0", Circle(radii[0])), Region("l1", Tube(radii[0], radii[1])),
               Region("l2", Tube(radii[1], radii[2]))]
    r = analyse_section(regions, mats, tol=1e-4)
    assert_diagonals(r, ref.concentric_sum(radii, layers), 2e-4)


@pytest.mark.parametrize("nu_jacket", [0.3, 0.45, 0.4999])
def test_lame_poisson_mismatch(nu_jacket):
    """Concentric cylinders of different Poisson ratios (a nearly incompressible jacket
    included): EA and the consistent and naive extension viscosities against the Lame
    solution. The consistent viscosity departs from the per-region sum at first order in
    the difference of nu, the stiffness only at second order."""
    layers = [(110e9, 0.34, 0.001, 0.0), (10e6, nu_jacket, 0.05, 0.05)]
    radii = [0.002, 0.0035]
    mats = {"cu": isotropic("cu", 110e9, 0.34, 8900.0, 0.001, 0.0),
            "jk": isotropic("jk", 10e6, nu_jacket, 1200.0, 0.05, 0.05)}
    regions = [Region("cu", Circle(radii[0])), Region("jk", Tube(*radii))]
    r = analyse_section(regions, mats, tol=1e-5)
    lame = ref.lame_extension(radii, layers)
    assert rel(r.stiffness[2, 2], lame["EA"]) < 1e-5
    assert rel(r.viscosity[2, 2], lame["V"]) < 1e-4
    assert rel(r.viscosity_naive[2, 2], lame["V_naive"]) < 1e-4
    summed = ref.concentric_sum(radii, layers)
    dv = rel(lame["V"], summed.V[2])
    dk = rel(lame["EA"], summed.K[2])
    if nu_jacket != 0.34:
        assert dv > 10 * dk      # first order against second order in the mismatch


def test_poisson_mismatch_orders():
    """The Lame reference itself: the departure from the summed values scales like
    d nu (viscosity) and d nu^2 (stiffness)."""
    radii = [0.002, 0.004]
    out = []
    for d in (0.002, 0.001):
        layers = [(200e9, 0.3, 0.01, 0.02), (1e9, 0.3 + d, 0.05, 0.01)]
        lame, s = ref.lame_extension(radii, layers), ref.concentric_sum(radii, layers)
        out.append((abs(lame["V"] / s.V[2] - 1), abs(lame["EA"] / s.K[2] - 1)))
    assert out[0][0] / out[1][0] == pytest.approx(2.0, rel=0.05)
    assert out[0][1] / out[1][1] == pytest.approx(4.0, rel=0.05)


def test_bimetal_strip():
    """Two bonded layers of one Poisson ratio stacked along d2: the transformed EI about the
    elastic centroid, no elastic extension-bending coupling there, and the viscous
    Gamma3-K1 coupling sum eta_E,i A_i (y_i - y_c) (consistent and naive)."""
    w, h0, h1 = 0.01, 0.002, 0.003
    layers = ((200e9, 0.3, 0.001, 0.002), (70e9, 0.3, 0.02, 0.005))
    mats = {"steel": isotropic("steel", 200e9, 0.3, 7800.0, 0.001, 0.002),
            "alu": isotropic("alu", 70e9, 0.3, 2700.0, 0.02, 0.005)}
    regions = [Region("steel", Rectangle(w, h0, (0.0, -h0 / 2))),
               Region("alu", Rectangle(w, h1, (0.0, h1 / 2)))]
    r = analyse_section(regions, mats, tol=1e-4)
    b = ref.bimetal(w, (h0, h1), layers)
    K, V, Vn = r.stiffness, r.viscosity, r.viscosity_naive
    assert r.elastic_centroid[1] == pytest.approx(b["y_c"], abs=1e-9)
    assert abs(r.elastic_centroid[0]) < 1e-12
    assert rel(K[2, 2], b["EA"]) < 1e-6
    assert rel(K[3, 3], b["EI1"]) < 1e-5
    assert abs(K[2, 3]) < 1e-6 * math.sqrt(K[2, 2] * K[3, 3])
    assert abs(K[2, 4]) < 1e-6 * math.sqrt(K[2, 2] * K[4, 4])
    assert rel(V[2, 2], b["V_Gamma3"]) < 1e-6
    assert rel(V[3, 3], b["V_K1"]) < 1e-5
    assert rel(V[2, 3], b["V_Gamma3_K1"]) < 1e-4
    assert rel(Vn[2, 3], b["V_Gamma3_K1_naive"]) < 1e-4
    assert abs(V[2, 3]) > 1e-2 * math.sqrt(V[2, 2] * V[3, 3])     # the coupling is real


def test_transversely_isotropic_circle():
    """A circle of a fibre material (symmetry axis along the rod) given by Voigt matrices:
    EA, EI, GJ and the extension, bending and torsion viscosities."""
    C = ref.box_material_stiffness()
    V = 0.01 * np.diag([1.0, 1.0, 5.0, 2.0, 2.0, 1.0]) * 1e9
    V[0, 1] = V[1, 0] = 0.2e9 * 0.01
    V[0, 2] = V[2, 0] = V[1, 2] = V[2, 1] = 0.3e9 * 0.01
    mats = {"f": anisotropic("f", C, V, 1600.0)}
    r = analyse_section([Region("f", Circle(0.005))], mats, tol=1e-5)
    t = ref.transversely_isotropic_circle(0.005, C, V)
    K, Vc, Vn = r.stiffness, r.viscosity, r.viscosity_naive
    for got, want in ((K[2, 2], t["EA"]), (K[3, 3], t["EI"]), (K[4, 4], t["EI"]),
                      (K[5, 5], t["GJ"]), (Vc[2, 2], t["V_ext"]), (Vc[3, 3], t["V_bend"]),
                      (Vn[2, 2], t["V_ext_naive"]), (Vn[3, 3], t["V_bend_naive"]),
                      (Vc[5, 5], t["V_tors"]), (Vn[5, 5], t["V_tors"])):
        assert rel(got, want) < 2e-5, (got, want)


def box_section(angle: float):
    C = ref.box_material_stiffness()
    g = ref.BOX_GEOMETRY
    X, Y = g["width"] * ref.INCH / 2, g["height"] * ref.INCH / 2
    t = g["wall"] * ref.INCH
    x, y = X - t, Y - t
    # mitred walls; the fibre tilts towards the counterclockwise wall tangent
    walls = {"top": ([(-x, y), (x, y), (X, Y), (-X, Y)], 180.0),
             "left": ([(-X, -Y), (-x, -y), (-x, y), (-X, Y)], 270.0),
             "bottom": ([(-X, -Y), (X, -Y), (x, -y), (-x, -y)], 0.0),
             "right": ([(x, -y), (X, -Y), (X, Y), (x, y)], 90.0)}
    mats = {k: anisotropic(k, C, None, 1.0, (beta, angle)) for k, (_, beta) in walls.items()}
    return [Region(k, PolygonShape(tuple(p))) for k, (p, _) in walls.items()], mats


def test_published_vabs_box_beam():
    """The CUS box beam of Yu, Hodges and Ho (2012) against its published VABS Timoshenko
    matrix: every published entry to 1 % (off-diagonal ones relative to the geometric mean
    of their diagonals), extension-twist coupling included."""
    regions, mats = box_section(15.0)
    r = analyse_section(regions, mats, tol=1e-3)
    K = r.stiffness
    pub = ref.box_vabs_in_kvrod_units()
    for (i, j), v in pub.items():
        scale = abs(v) if i == j else math.sqrt(pub[(i, i)] * pub[(j, j)])
        assert abs(K[i, j] - v) / scale < 0.01, (i, j, K[i, j], v)
    assert K[2, 5] > 0.5 * math.sqrt(K[2, 2] * K[5, 5])       # strong extension-twist


def test_parsers_and_errors():
    mats = materials_from_mapping({
        "cu": {"youngs_modulus": 110e9, "poisson_ratio": 0.34, "density": 8900.0},
        "pvc": {"youngs_modulus": 3e9, "poisson_ratio": 0.4, "density": 1400.0,
                "eta": 1e7, "zeta": 2e7}})
    regions = regions_from_mapping([
        {"material": "cu", "shape": {"kind": "circle", "radius": 0.001}},
        {"material": "pvc", "shape": {"kind": "tube", "inner_radius": 0.001,
                                      "outer_radius": 0.002}}])
    assert mats["pvc"].isotropic[2] == pytest.approx(1e7 / (3e9 / 2.8))
    assert len(regions) == 2
    with pytest.raises(ParameterError, match=r"section\.regions\[1\]\.shape\.radius"):
        regions_from_mapping([{"material": "cu", "shape": {"kind": "circle", "radius": 1}},
                              {"material": "cu", "shape": {"kind": "circle",
                                                           "radius": -1.0}}])
    with pytest.raises(ParameterError, match=r"regions\[1\].*overlap.*regions\[0\]"):
        analyse_section(regions_from_mapping([
            {"material": "cu", "shape": {"kind": "circle", "radius": 0.002}},
            {"material": "cu", "shape": {"kind": "rectangle", "width": 0.002,
                                         "height": 0.002, "centre": [0.002, 0.0]}}]), mats)
    with pytest.raises(ParameterError, match=r"one connected section.*2 separate parts"):
        analyse_section(regions_from_mapping([
            {"material": "cu", "shape": {"kind": "circle", "radius": 0.001}},
            {"material": "cu", "shape": {"kind": "tube", "inner_radius": 0.0015,
                                         "outer_radius": 0.002}}]), mats)
    with pytest.raises(ParameterError, match=r"regions\[0\]\.material"):
        analyse_section(regions_from_mapping([
            {"material": "steel", "shape": {"kind": "circle", "radius": 0.002}}]), mats)
    bad_C = np.eye(6) * 1e9
    bad_C[2, 2] = -1e9
    with pytest.raises(ParameterError, match=r"materials\.x\.stiffness_matrix.*Pa"):
        materials_from_mapping({"x": {"stiffness_matrix": bad_C.tolist(), "density": 1.0}})
    bad_V = np.eye(6)
    bad_V[0, 0] = -1.0
    with pytest.raises(ParameterError, match=r"materials\.x\.viscosity_matrix.*Pa s"):
        materials_from_mapping({"x": {"stiffness_matrix": (np.eye(6) * 1e9).tolist(),
                                      "viscosity_matrix": bad_V.tolist(), "density": 1.0}})
    asym = np.eye(6) * 1e9
    asym[0, 1] = 1e8
    with pytest.raises(ParameterError, match=r"stiffness_matrix.*symmetric"):
        materials_from_mapping({"x": {"stiffness_matrix": asym.tolist(), "density": 1.0}})
    with pytest.raises(ParameterError, match=r"materials\.p\.poisson_ratio"):
        materials_from_mapping({"p": {"youngs_modulus": 1e6, "poisson_ratio": 0.5,
                                      "density": 1.0}})
    with pytest.raises(ParameterError, match=r"materials\.p\.tau_S"):
        materials_from_mapping({"p": {"youngs_modulus": 1e6, "poisson_ratio": 0.3,
                                      "density": 1.0, "tau": 0.1, "tau_S": 0.1}})
    with pytest.raises(ParameterError, match=r"materials\.p\.model"):
        materials_from_mapping({"p": {"model": "generalized_maxwell"}})


def test_orientation_transforms():
    """The Voigt rotation: an isotropic C is invariant, strains transform with T^-T, a
    quarter turn about the rod axis swaps the in-plane axes, and the orientation table
    parses with its key path in errors."""
    from runtime.section.materials import isotropic_stiffness, rotation, stress_transform
    R = rotation(37.0, 21.0)
    assert np.allclose(R.T @ R, np.eye(3), atol=1e-15)
    T = stress_transform(R)
    C = isotropic_stiffness(1e9, 0.3)
    assert np.allclose(T @ C @ T.T, C, rtol=1e-12, atol=1e-3)
    # strain: eps_s = R eps_m R^T; in engineering Voigt that is T^-T
    eps = np.array([[1e-3, 2e-4, -3e-4], [2e-4, -5e-4, 1e-4], [-3e-4, 1e-4, 7e-4]])
    voigt = [(0, 0), (1, 1), (2, 2), (1, 2), (0, 2), (0, 1)]

    def v(e):
        return np.array([e[i, j] * (1 if i == j else 2) for i, j in voigt])

    assert np.allclose(np.linalg.solve(T.T, v(eps)), v(R @ eps @ R.T), atol=1e-15)
    Cf = ref.box_material_stiffness()
    m = materials_from_mapping({"f": {"stiffness_matrix": Cf.tolist(), "density": 1.0,
                                      "orientation": {"rotation": 90.0}}})["f"]
    assert m.stiffness[0, 0] == pytest.approx(Cf[1, 1])
    assert m.stiffness[4, 4] == pytest.approx(Cf[3, 3])
    # the tilted fibre (off-axis 90) lies along d1
    m = materials_from_mapping({"f": {"stiffness_matrix": Cf.tolist(), "density": 1.0,
                                      "orientation": {"off_axis": 90.0}}})["f"]
    assert m.stiffness[0, 0] == pytest.approx(Cf[2, 2])
    with pytest.raises(ParameterError, match=r"materials\.f\.orientation\.off_axis"):
        materials_from_mapping({"f": {"stiffness_matrix": Cf.tolist(), "density": 1.0,
                                      "orientation": {"off_axis": 120.0}}})
    with pytest.raises(ParameterError, match=r"materials\.f\.orientation\.twist"):
        materials_from_mapping({"f": {"stiffness_matrix": Cf.tolist(), "density": 1.0,
                                      "orientation": {"twist": 1.0}}})


def test_poisson_mismatch_visible():
    """A viscous core in an elastic jacket of equal modulus, nu 0.3 against 0.45: the
    jacket holds the core's contraction back, and the consistent extension viscosity comes
    out 2.5 % below the per-region sum (first order in d nu) while EA moves by 0.45 %
    (second order); the FE matches the Lame solution."""
    layers = [(1e9, 0.3, 0.1, 0.05), (1e9, 0.45, 0.0, 0.0)]
    radii = [0.002, 0.004]
    mats = {"core": isotropic("core", 1e9, 0.3, 1000.0, 0.1, 0.05),
            "jacket": isotropic("jacket", 1e9, 0.45, 1000.0)}
    r = analyse_section([Region("core", Circle(radii[0])), Region("jacket", Tube(*radii))],
                        mats, tol=1e-5)
    lame, summed = ref.lame_extension(radii, layers), ref.concentric_sum(radii, layers)
    assert rel(r.stiffness[2, 2], lame["EA"]) < 1e-5
    assert rel(r.viscosity[2, 2], lame["V"]) < 1e-5
    assert rel(r.viscosity_naive[2, 2], lame["V_naive"]) < 1e-5
    assert r.viscosity[2, 2] / summed.V[2] - 1 == pytest.approx(0.0245, abs=0.001)
    assert r.stiffness[2, 2] / summed.K[2] - 1 == pytest.approx(0.0045, abs=0.0003)


@pytest.mark.parametrize("shape", [
    {"kind": "rectangle", "width": 1e-9, "height": 0.001, "centre": [0.0, 0.0015]},
    {"kind": "tube", "inner_radius": 0.001, "outer_radius": 0.001 * (1 + 1e-7)},
])
def test_a_region_too_thin_for_any_mesh_is_refused_before_meshing(shape):
    """A 1e-9 m wide ply on a 2 x 2 mm square asked for ~1e6 six-node triangles in its
    first mesh (elements of 1.5 times a region's thickness): `kvrod section` took all the
    memory and was killed (exit 137). Now refused at once, naming the region."""
    mats = {"m": isotropic("m", E, NU, RHO, TS, TB)}
    first = ({"kind": "rectangle", "width": 0.002, "height": 0.002}
             if shape["kind"] == "rectangle" else {"kind": "circle", "radius": 0.001})
    regions = regions_from_mapping([{"material": "m", "shape": first},
                                    {"material": "m", "shape": shape}])
    with pytest.raises(ParameterError, match=r"section\.regions\[1\]\.shape.*thick.*nodes"):
        analyse_section(regions, mats)


@pytest.mark.parametrize("shape,key", [
    ({"kind": "circle", "radius": 1e-300}, "radius"),     # was an internal ZeroDivisionError
    ({"kind": "circle", "radius": 1e31}, "radius"),
    ({"kind": "rectangle", "width": 1e300, "height": 1.0}, "width"),
    ({"kind": "polygon", "points": [[0, 0], [1e300, 0], [0, 1e300]]}, r"points\[1\]"),
    ({"kind": "circle", "radius": 1.0, "centre": [1e300, 0.0]}, "centre"),
])
def test_section_lengths_out_of_range_are_named(shape, key):
    with pytest.raises(ParameterError, match=r"section\.regions\[0\]\.shape\." + key):
        regions = regions_from_mapping([{"material": "m", "shape": shape}])
        analyse_section(regions, {"m": isotropic("m", E, NU, RHO, TS, TB)})


def test_a_huge_section_is_checked_without_a_fine_polygon():
    """check_regions polygonised every curve at h = 1e9 m: a 1e25 m circle (a length
    within the allowed 1e30 m) asked for 6e16 vertices, a MemoryError ("out of memory")."""
    from runtime.section.regions import check_regions

    mats = {"m": isotropic("m", E, NU, RHO, TS, TB)}
    check_regions(regions_from_mapping([{"material": "m", "shape": {
        "kind": "circle", "radius": 1e25}}]), mats)
