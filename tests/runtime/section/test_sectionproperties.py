"""An isotropic composite against the peer code sectionproperties (in the test extra):
EA, EI about the centroid (with the product term), the torsional stiffness and the shear
centre of a two-material L section of one Poisson ratio."""

from __future__ import annotations

import pytest

from runtime.section import Rectangle, Region, analyse_section, isotropic

sp_pre = pytest.importorskip("sectionproperties.pre.pre")
sp_lib = pytest.importorskip("sectionproperties.pre.library")
sp_analysis = pytest.importorskip("sectionproperties.analysis")

NU = 0.3


def test_composite_l_section_against_sectionproperties():
    steel = sp_pre.Material("steel", 200e9, NU, 1.0, 7800.0, "grey")
    alu = sp_pre.Material("alu", 70e9, NU, 1.0, 2700.0, "silver")
    leg1 = sp_lib.rectangular_section(d=0.03, b=0.004, material=steel)
    leg2 = sp_lib.rectangular_section(d=0.004, b=0.016, material=alu).shift_section(
        x_offset=0.004)
    geom = leg1 + leg2
    geom.create_mesh(mesh_sizes=[2e-7, 2e-7])
    sec = sp_analysis.Section(geom)
    sec.calculate_geometric_properties()
    sec.calculate_warping_properties()
    eixx, eiyy, eixy = sec.get_eic()
    mats = {"steel": isotropic("steel", 200e9, NU, 7800.0),
            "alu": isotropic("alu", 70e9, NU, 2700.0)}
    regions = [Region("steel", Rectangle(0.004, 0.03, (0.002, 0.015))),
               Region("alu", Rectangle(0.016, 0.004, (0.012, 0.002)))]
    r = analyse_section(regions, mats, tol=1e-4)
    K = r.stiffness
    assert K[2, 2] == pytest.approx(sec.get_ea(), rel=1e-9)
    assert K[3, 3] == pytest.approx(eixx, rel=1e-9)          # I1 = <x2^2> about d1
    assert K[4, 4] == pytest.approx(eiyy, rel=1e-9)
    assert -K[3, 4] == pytest.approx(eixy, rel=1e-9)         # K2 strains -x1
    assert r.elastic_centroid == pytest.approx(sec.get_c(), abs=1e-12)
    # sectionproperties' composite torsion constant is modulus weighted: E J / (2 (1 + nu))
    assert r.torsional_stiffness == pytest.approx(sec.get_ej() / (2 * (1 + NU)), rel=5e-4)
    sc = sec.get_sc()
    assert abs(r.shear_centre[0] - sc[0]) < 1e-3 * 0.03
    assert abs(r.shear_centre[1] - sc[1]) < 1e-3 * 0.03
