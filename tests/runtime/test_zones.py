"""Zones of a rod with their own section or material (issue 26): parsing and checks, the
matrices per segment, writing back, a two-zone cantilever against the closed form of the
stepped beam (second order in h at the sharp change: a node at every boundary, the joint's
half cells in series), a coupled
clip zone on a diagonal rod."""

from __future__ import annotations

import numpy as np
import pytest

from references import coupled_rods as ref
from runtime.errors import ParameterError
from runtime.problem.schema import Problem
from runtime.simulate.simulate import simulate, static_equilibrium

EI1, EI2, GA, EA, P, L = 1.0, 4.0, 1e6, 1e6, 1e-4, 1.0


def stiff(EI: float) -> dict:
    return {"kind": "stiffness", "EA": EA, "GA1": GA, "GA2": GA, "EI1": EI, "EI2": EI,
            "GJ": EI, "rhoA": 1.0, "rhoI1": 1e-4, "rhoI2": 1e-4, "rhoI3": 2e-4}


def two_zones(N: int, **zone) -> dict:
    return {"name": "stepped", "rod": {"length": L, "elements": N},
            "section": stiff(EI1), "material": {"tau": 0.01},
            "zones": [{"from": L / 2, "to": L, "section": stiff(EI2), **zone}],
            "start": {"kind": "clamped"}, "end": {"kind": "free"},
            "loads": [{"kind": "force", "at": "end", "vector": [P, 0.0, 0.0]}],
            "simulation": {"t_end": 0.1}}


def test_zones_give_their_segments_their_section_and_write_back():
    p = Problem.from_mapping(two_zones(8))
    m = p.segment_matrices()
    assert np.allclose(m["C_M"][:4, 0], EI1) and np.allclose(m["C_M"][4:, 0], EI2)
    back = Problem.from_mapping(p.to_mapping())
    assert np.allclose(back.segment_matrices()["C_M"], m["C_M"])


@pytest.mark.parametrize("change,needle", [
    ({"from": -0.1}, r"zones\[0\]\.from"),
    ({"to": 2.0}, r"zones\[0\]\.to"),
    ({"from": 0.6, "to": 0.6}, r"zones\[0\]\.to.*> from"),
    ({"section": {**stiff(EI2), "EA": -1.0}}, r"zones\[0\]\.section\.EA"),
    ({"colour": "red"}, r"zones\[0\]"),
])
def test_zone_errors_name_the_key(change, needle):
    m = two_zones(8)
    m["zones"][0].update(change)
    with pytest.raises(ParameterError, match=needle):
        Problem.from_mapping(m)


def test_overlapping_zones_are_refused():
    m = two_zones(8)
    m["zones"].append({"from": 0.25, "to": 0.75, "material": {"tau": 0.02}})
    with pytest.raises(ParameterError, match=r"zones\[0\]\.from.*zones\[1\].*overlap"):
        Problem.from_mapping(m)


@pytest.mark.parametrize("span", [(0.0, 0.05), (0.3, 0.33), (0.26, 0.374)])
def test_a_zone_between_nodes_gets_nodes_at_its_boundaries(span):
    """At N = 4 (nodes 0, 0.25, ...) these zones hold no uniform segment's midpoint: they
    used to change nothing, silently, or (a step between nodes) were moved to the nearest
    node. Now the rod has a node at each boundary and the zone's segments carry its
    section, the others the rod's."""
    m = two_zones(4)
    m["zones"][0].update({"from": span[0], "to": span[1]})
    p = Problem.from_mapping(m)
    s = p.node_arc_lengths()
    assert s.size == 5 and s[0] == 0.0 and s[-1] == L
    for b in span:
        assert np.min(np.abs(s - b)) <= 1e-12
    inside = (0.5 * (s[:-1] + s[1:]) > span[0]) & (0.5 * (s[:-1] + s[1:]) < span[1])
    C = p.segment_matrices()["C_M"][:, 0]
    assert inside.any() and np.all(C[inside] == EI2) and np.all(C[~inside] == EI1)


def test_more_stretches_than_elements_are_refused_naming_rod_elements():
    m = two_zones(2)
    m["zones"] = [{"from": 0.1, "to": 0.2, "section": stiff(EI2)},
                  {"from": 0.5, "to": 0.6, "section": stiff(EI2)}]
    with pytest.raises(ParameterError, match=r"rod\.elements.*>= 5"):
        Problem.from_mapping(m)


def test_a_point_load_by_arc_length_acts_at_its_own_node():
    """A force at s = 0.3 L on a rod of 4 elements: a node is put there (it was moved to
    the nearest uniform node, 0.25 L, without a word)."""
    from runtime.problem.assemble import build_model

    m = two_zones(4)
    m["loads"] = [{"kind": "force", "s": 0.3, "vector": [P, 0.0, 0.0]}]
    p = Problem.from_mapping(m)
    model = build_model(p)
    s = p.node_arc_lengths()
    k = int(np.argmin(np.abs(s - 0.3)))
    assert abs(s[k] - 0.3) < 1e-12
    f = model.arrays.node_load("f_dead")
    assert f[k, 0] == P and np.count_nonzero(f) == 1


@pytest.mark.parametrize("s0", [L / 2, L / 3, 0.3])
def test_two_zone_cantilever_converges_at_second_order(s0):
    """Tip deflection under a small tip force against the moment-area closed form of a
    cantilever with EI1 on [0, s0] and EI2 = 4 EI1 on [s0, L], the step on a uniform node
    (L/2), between nodes (L/3, 0.3 L: a node is put there). The joint on the step takes
    the two half cells in series, so the error falls like h^2 (with the arithmetic mean
    of the two EIs it fell like h: 0.28 % at N = 64)."""
    want = ref.stepped_cantilever(EI1, EI2, s0, L, P)
    errs = []
    for N in (8, 16, 32):
        m = two_zones(N)
        m["zones"][0]["from"] = s0
        st = static_equilibrium(Problem.from_mapping(m))
        errs.append(abs(st.tip[0] / want["deflection"] - 1))
    rates = [errs[k] / errs[k + 1] for k in range(2)]
    assert errs[-1] < 5e-4, errs
    assert all(3.0 < r < 5.5 for r in rates), (errs, rates)


def test_joint_series_rule():
    """Equal neighbours keep their value exactly; a common retardation time is kept; a
    damped half beside an undamped one damps the joint; the compliance of the two halves
    adds (unequal lengths)."""
    from runtime.problem.materials import joint_series

    C = np.array([[2.0, 3.0, 5.0], [2.0, 12.0, 1.0]])
    V = 0.1 * C
    h = np.array([0.2, 0.6])
    Cj, Vj = joint_series(C, V, h)
    assert np.array_equal(Cj[0], C[0]) and np.array_equal(Cj[-1], C[-1])
    assert Cj[1, 0] == 2.0 and Vj[1, 0] == 0.2
    assert np.allclose(0.4 / Cj[1], 0.1 / C[0] + 0.3 / C[1])
    assert np.allclose(Vj[1], 0.1 * Cj[1])
    _, Vu = joint_series(C, np.array([[0.0] * 3, [1.0] * 3]), h)
    assert np.all(Vu[1] > 0)


def test_a_coupled_clip_zone_on_a_diagonal_rod():
    """A stiffer coupled clip (stiffness matrix with an extension-twist entry, a mass
    centre off the centreline) on [0.2, 0.8] of a diagonal rod: the whole rod takes the
    coupled kernels, its other segments keep their diagonal matrices; pulled, only the
    clip twists, by K^-1 f inside (its boundary layers, where a joint straddles the
    change, decay within a few elements) and in total to first order in h; the
    transient's energy audit closes."""
    from runtime.problem.assemble import build_model

    K = np.diag([GA, GA, EA, EI1, EI1, EI1]) * 3.0
    K[2, 5] = K[5, 2] = 0.5 * np.sqrt(K[2, 2] * K[5, 5])
    clip = {"kind": "stiffness", "stiffness_matrix": K.tolist(), "rhoA": 2.0,
            "rhoI1": 1e-4, "rhoI2": 1e-4, "rhoI3": 2e-4, "mass_centre": [0.002, 0.0]}
    want = ref.uniform_strain(K, [0, 0, 100.0, 0, 0, 0])[5]
    errs = []
    for N in (10, 20):
        m = two_zones(N)
        m["zones"] = [{"from": 0.2, "to": 0.8, "section": clip}]
        m["loads"] = [{"kind": "force", "at": "end", "vector": [0.0, 0.0, 100.0]}]
        p = Problem.from_mapping(m)
        mats = p.segment_matrices()
        assert mats["K6"][N // 2, 2, 5] != 0 and mats["K6"][0, 2, 5] == 0
        model = build_model(p)
        assert model.coupled
        st = static_equilibrium(p, model)
        K3 = model.diagnostics(0.0, st.y)["strains"]["U"][2]
        assert abs(K3[1]) < 1e-9 * abs(want) and abs(K3[N - 1]) < 1e-9 * abs(want)
        R = model.end_frames(0.0, st.y)["end"]
        errs.append(abs(np.arctan2(R[1, 0], R[0, 0]) / (0.6 * want) - 1))
    assert K3[N // 2] == pytest.approx(want, rel=1e-5)
    assert 1.7 < errs[0] / errs[1] < 2.3 and errs[1] < 0.05
    m["simulation"] = {"t_end": 0.02, "initial": "reference"}
    res = simulate(Problem.from_mapping(m))
    assert res.status == "finished" and res.audit().max_rel < 1e-4


@pytest.mark.parametrize("zone", [
    {"section": {"kind": "rectangle", "width": 0.02, "height": 0.01}},
    {"material": {"youngs_modulus": 2e6}},
])
def test_zones_on_a_maxwell_rod_are_refused_naming_the_material_model(zone):
    """A section-only zone was refused as zones[0].material.model (a key not written),
    a material zone as 'zones' = 'given' only when the matrices were built."""
    from runtime.problem.registry import load_problem

    with pytest.raises(ParameterError, match=r"'zones'.*generalized Maxwell.*material\.model"):
        load_problem("maxwell_cantilever", {"zones": [{"from": 0.0, "to": 0.15, **zone}]})


def test_a_zone_overrides_the_problem_material_and_section_key_by_key():
    """A zone giving only youngs_modulus keeps the problem's density, Poisson ratio and
    damping (it took the defaults: undamped, density 1000, nu 0.3, silently); a zone's
    tau_S beside the problem's tau keeps tau_B = tau; a zone section without a kind
    changes only the keys it names, one with its kind is given whole."""
    base = {"name": "z", "rod": {"length": 1.0, "elements": 10},
            "section": {"kind": "rectangle", "width": 0.02, "height": 0.01},
            "material": {"youngs_modulus": 5e6, "poisson_ratio": 0.4, "density": 1300.0,
                         "tau": 0.03},
            "start": {"kind": "clamped"}, "end": {"kind": "free"},
            "simulation": {"t_end": 0.1}}
    m = {**base, "zones": [{"from": 0.5, "to": 1.0, "material": {"youngs_modulus": 2e6}}]}
    z = Problem.from_mapping(m).zones[0].material
    assert (z.youngs_modulus, z.poisson_ratio, z.density) == (2e6, 0.4, 1300.0)
    assert z.tau_S == z.tau_B == 0.03
    m["zones"][0]["material"] = {"tau_S": 0.1}
    z = Problem.from_mapping(m).zones[0].material
    assert (z.tau_S, z.tau_B, z.youngs_modulus) == (0.1, 0.03, 5e6)
    m["zones"][0]["material"] = {"eta": 1e3}
    z = Problem.from_mapping(m).zones[0].material
    assert z.tau_B == 0.0 and z.tau_S > 0       # eta alone: no bulk viscosity
    m = {**base, "zones": [{"from": 0.5, "to": 1.0, "section": {"height": 0.005}}]}
    p = Problem.from_mapping(m)
    sec = p.zones[0].section
    assert dict(sec.dims) == {"width": 0.02, "height": 0.005}
    assert p.to_mapping()["zones"][0]["section"] == {"height": 0.005}   # written as given
    m["zones"][0]["section"] = {"kind": "circle", "radius": 0.004}
    assert dict(Problem.from_mapping(m).zones[0].section.dims) == {"radius": 0.004}
