"""Validation of rods with coupled sections (issue 26) against references written
separately (references/coupled_rods.py, references/section_analysis.py): the coupled
strip pulled and twisted (stretch and twist from K^-1 f), the damped modes of a cable of one Poisson
ratio against the complex-modulus beam of its section and of the closed-form sums, the
creep of a bimetal strip whose viscous extension-bending coupling bends it, and the
energy audit of the runs."""

from __future__ import annotations

import copy
import tomllib
from pathlib import Path

import numpy as np
import pytest

from references import coupled_rods as ref
from references import section_analysis as sref
from runtime.analysis.modal import modal_analysis
from runtime.errors import ParameterError
from runtime.problem.assemble import build_model
from runtime.problem.coupled import composite_analysis
from runtime.problem.registry import EXAMPLES_DIR, load_problem
from runtime.problem.schema import Problem
from runtime.simulate.simulate import simulate, static_equilibrium

STRIP = EXAMPLES_DIR / "coupled_strip.toml"
CABLE = EXAMPLES_DIR / "cable_cantilever.toml"


def _doc(path: Path) -> dict:
    return tomllib.loads(path.read_text())


def test_coupled_strip_stretches_and_twists_as_the_inverse_stiffness_says():
    doc = _doc(STRIP)
    K = np.array(doc["section"]["stiffness_matrix"])
    F = doc["loads"][0]["vector"][2]
    L = doc["rod"]["length"]
    want = ref.uniform_strain(K, [0.0, 0.0, F, 0.0, 0.0, 0.0])
    problem = load_problem(STRIP)
    st = static_equilibrium(problem)
    model = build_model(problem)
    d = model.diagnostics(0.0, st.y)
    G3 = d["strains"]["V"][2] - 1.0
    K3 = d["strains"]["U"][2, :-1]                # joints 0 (clamp) .. N-1
    assert np.abs(G3 / want[2] - 1).max() < 1e-3
    assert np.abs(K3 / want[5] - 1).max() < 1e-3
    stretch = st.tip[2] - L
    assert stretch == pytest.approx(L * want[2], rel=1e-3)
    R = model.end_frames(0.0, st.y)["end"]
    twist = np.arctan2(R[1, 0], R[0, 0])          # d1 turned about the axis e3
    assert twist == pytest.approx(L * want[5], rel=1e-3)


def _strip_with(loads: list, **rod) -> Problem:
    doc = copy.deepcopy(_doc(STRIP))
    doc["loads"] = loads
    doc["rod"].update(rod)
    return Problem.from_mapping(doc)


@pytest.mark.parametrize("frame", ["dead", "follower"])
def test_coupled_strip_under_an_end_torque_stretches_as_the_inverse_stiffness_says(frame):
    """The strip twisted by a torque at its free end stretches through its extension-twist
    coupling, by K^-1 (0, 0, 0, 0, 0, M) in every segment and joint, the end segment's
    included (the free end's condensation carries the moment; it assumed none, and the
    end segment stretched about half as much: the tip stretch was 1.6 % short at
    N = 32), and the tip by L times that."""
    Mz = 0.01
    K = np.array(_doc(STRIP)["section"]["stiffness_matrix"])
    want = ref.uniform_strain(K, [0.0, 0.0, 0.0, 0.0, 0.0, Mz])
    p = _strip_with([{"kind": "moment", "at": "end", "frame": frame,
                      "vector": [0.0, 0.0, Mz]}], elements=32)
    st = static_equilibrium(p)
    d = build_model(p).diagnostics(0.0, st.y)
    assert np.abs(d["strains"]["V"][2] - 1.0 - want[2]).max() < 1e-6 * abs(want[2])
    assert np.abs(d["strains"]["U"][2, :-1] - want[5]).max() < 1e-6 * abs(want[5])
    L = p.rod.length
    assert st.tip[2] - L == pytest.approx(L * want[2], rel=1e-6)


def test_coupled_strip_twisted_and_pulled_transient_energy_audit():
    """A step of an end torque (follower) and an axial force (dead) on the strip: the
    energy audit closes with the power of the moment through the free end's condensed
    joint, and the run settles towards the static uniform strain."""
    loads = [{"kind": "moment", "at": "end", "frame": "follower", "vector": [0, 0, 0.01]},
             {"kind": "force", "at": "end", "vector": [0.0, 0.0, 50.0]}]
    p = _strip_with(loads)
    res = simulate(p)
    assert res.status == "finished", res.message
    assert res.audit().max_rel < 1e-4
    K = np.array(_doc(STRIP)["section"]["stiffness_matrix"])
    want = ref.uniform_strain(K, [0.0, 0.0, 50.0, 0.0, 0.0, 0.01])
    assert res.tip[2, -1] - p.rod.length == pytest.approx(p.rod.length * want[2], rel=1e-3)


@pytest.mark.parametrize("key,value", [("material.tau", 0.1), ("material.tau_S", 0.02),
                                       ("material.eta", 3.0)])
def test_a_material_viscosity_beside_a_given_viscosity_matrix_is_refused(key, value):
    """The section's viscosity_matrix is the rod's whole viscosity: --tau 0.1 was taken,
    reported (tau_E = 0.1 s, the modes header) and acted nowhere."""
    with pytest.raises(ParameterError, match=key.replace(".", r"\.")
                       + r".*section\.viscosity_matrix"):
        load_problem(STRIP, {key: value})


def test_the_naive_route_beside_a_given_viscosity_matrix_is_refused():
    """--damping naive was taken and reported, and acted nowhere."""
    with pytest.raises(ParameterError, match=r"section\.damping.*viscosity_matrix"):
        load_problem(STRIP, {"damping": "naive"})


def test_tau_e_of_a_given_viscosity_matrix_is_its_own():
    doc = _doc(STRIP)
    p = load_problem(STRIP)
    want = doc["section"]["viscosity_matrix"][2][2] / doc["section"]["stiffness_matrix"][2][2]
    assert p.tau_E == pytest.approx(want, rel=1e-12)          # was the material's 0
    assert "viscosity matrices" in p.describe_material()
    assert load_problem(STRIP, {"material.tau": 0.0}).tau_E == pytest.approx(want)


def test_a_viscosity_beyond_the_inertia_is_named_for_composites_and_given_matrices():
    """A composite's viscous rate was not checked (materials.pvc.tau_S = 1e12: kvrod
    simulate ended in an 'internal error' of the initial Newton); a given viscosity_matrix
    too stiff was named material.tau = 0 (a key not written)."""
    p = load_problem(CABLE, {"rod.elements": 20, "materials.pvc.tau_S": 1e12})
    with pytest.raises(ParameterError, match=r"'materials\.pvc'.*tau \* omega_max\^2"):
        p.check_simulable()
    V = _doc(STRIP)["section"]["viscosity_matrix"]
    V[2][2] = 1e12
    with pytest.raises(ParameterError, match=r"'section\.viscosity_matrix'.*omega_max"):
        load_problem(STRIP, {"rod.elements": 6, "section.viscosity_matrix": V})


def test_a_composite_run_shorter_than_round_off_is_refused_as_a_homogeneous_one():
    """t_end = 1e-20 s: refused for a homogeneous rod, taken for a composite one (the
    check was skipped, and its message would have printed the missing material's nan)."""
    p = load_problem(CABLE, {"rod.elements": 6, "simulation.t_end": 1e-20})
    with pytest.raises(ParameterError, match=r"simulation\.t_end.*section's matrices") as e:
        p.check_simulable()
    assert "nan" not in str(e.value)


def test_coupled_strip_transient_energy_audit():
    """The strip pulled by a step load: a damped transient of the coupled extension and
    twist, whose energy audit closes, and which settles to the static stretch."""
    res = simulate(load_problem(STRIP, {"simulation.t_end": 0.05}))
    assert res.status == "finished", res.message
    audit = res.audit()
    assert audit.max_rel < 1e-4
    doc = _doc(STRIP)
    want = ref.uniform_strain(np.array(doc["section"]["stiffness_matrix"]),
                              [0.0, 0.0, doc["loads"][0]["vector"][2], 0, 0, 0])
    assert res.tip[2, -1] - doc["rod"]["length"] == pytest.approx(
        doc["rod"]["length"] * want[2], rel=1e-3)


def _one_nu_cable(tau_S: float = 0.2) -> tuple[Problem, list]:
    """The cable cantilever with one Poisson ratio (0.34) in both layers and a viscous
    sheath: the closed-form sums over the layers hold exactly."""
    doc = _doc(CABLE)
    doc = copy.deepcopy(doc)
    doc["materials"]["pvc"].update(poisson_ratio=0.34, tau_S=tau_S)
    doc["loads"] = []                                # the modes of the straight rod
    doc["simulation"]["initial"] = "reference"
    p = Problem.from_mapping(doc)
    m = doc["materials"]
    layers = [(m["copper"]["youngs_modulus"], 0.34, 0.0, 0.0),
              (m["pvc"]["youngs_modulus"], 0.34, tau_S, 0.0)]
    return p, layers


def test_cable_of_one_poisson_ratio_has_the_damped_mode_of_its_summed_section():
    p, layers = _one_nu_cable()
    radii = [0.001, 0.0016]
    sums = sref.concentric_sum(radii, layers)
    rho = [8960.0, 1350.0]
    rhoA = rho[0] * np.pi * radii[0] ** 2 + rho[1] * np.pi * (radii[1] ** 2 - radii[0] ** 2)
    L = p.rod.length
    closed = ref.kelvin_voigt_cantilever(sums.K[3], sums.V[3], rhoA, L)
    sec = composite_analysis(p.section)        # the section's own matrices
    own = ref.kelvin_voigt_cantilever(sec.stiffness[3, 3], sec.viscosity[3, 3],
                                      sec.mass_per_length, L)
    model = build_model(p)
    modes = modal_analysis(model, count=2)
    m1 = modes[0]
    assert m1.family.startswith("bending")
    for want in (closed, own):
        assert m1.omega == pytest.approx(want["omega"], rel=5e-3)
        assert m1.zeta == pytest.approx(want["zeta"], rel=1e-2)
    assert closed["zeta"] > 0.005                # the damping is not negligible


def _bimetal(tau: float = 1.0, F: float = 20.0, N: int = 16) -> dict:
    """A bimetal strip (10 mm wide, 1 + 1 mm thick layers stacked along d2, one Poisson
    ratio): an elastic layer under a viscous one, clamped at s = 0 and stretched by an
    axial force at its free end that is released at t = 0."""
    return {
        "name": "bimetal_creep",
        "rod": {"length": 0.05, "elements": N,
                "geometry": {"kind": "straight", "direction": [0, 0, 1],
                             "normal": [1, 0, 0]}},
        "section": {"kind": "composite", "regions": [
            {"name": "bottom", "material": "stiff", "shape": {
                "kind": "rectangle", "width": 0.01, "height": 0.001, "centre": [0, -5e-4]}},
            {"name": "top", "material": "soft", "shape": {
                "kind": "rectangle", "width": 0.01, "height": 0.001, "centre": [0, 5e-4]}}]},
        "materials": {"stiff": {"youngs_modulus": 2e9, "poisson_ratio": 0.3,
                                "density": 1000.0},
                      "soft": {"youngs_modulus": 1e9, "poisson_ratio": 0.3,
                               "density": 1000.0, "tau": tau}},
        "start": {"kind": "clamped"}, "end": {"kind": "free"},
        "loads": [{"kind": "force", "at": "end", "vector": [0, 0, F],
                   "time": {"kind": "release", "start": 0.0}}],
        "simulation": {"t_end": 1.0, "rtol": 1e-7, "output_step": 0.05,
                       "initial": "static"},
    }


def test_bimetal_strip_bends_while_it_creeps_back_as_the_two_dof_model_says():
    """After the release the stretch creeps back through the viscous layer; the viscous
    extension-bending coupling (the viscous centroid off the elastic one) bends the
    strip meanwhile, though its elastic section has no coupling. The mid-rod strains
    follow V x' + K x = 0 with the transformed-section K, V of (Gamma3, K1)."""
    tau, F = 1.0, 20.0
    p = Problem.from_mapping(_bimetal(tau, F))
    b = sref.bimetal(0.01, (0.001, 0.001), ((2e9, 0.3, 0.0, 0.0), (1e9, 0.3, tau, tau)))
    K = np.diag([b["EA"], b["EI1"]])
    V = np.array([[b["V_Gamma3"], b["V_Gamma3_K1"]], [b["V_Gamma3_K1"], b["V_K1"]]])
    ts = np.array([0.1, 0.3, 0.6, 1.0])
    want = ref.creep(K, V, [F / b["EA"], 0.0], ts)
    seen = []
    model = build_model(p)
    mid_s, mid_j = p.rod.elements // 2 - 1, p.rod.elements // 2

    def sink(t, y, yp):
        d = model.diagnostics(t, y)
        seen.append((t, d["strains"]["V"][2, mid_s] - 1.0, d["strains"]["U"][0, mid_j]))

    res = simulate(p, model=model, snapshot_every=0.1, snapshot_sink=sink)
    assert res.status == "finished", res.message
    assert res.audit().max_rel < 1e-4
    got = {round(t, 6): (g, k) for t, g, k in seen}
    peak = np.abs(want[:, 1]).max()
    assert peak > 0.05 * F / b["EA"] * 100       # the bending is not a round-off effect
    for t, (g_want, k_want) in zip(ts, want, strict=True):
        g, k = got[round(float(t), 6)]
        assert g == pytest.approx(g_want, rel=2e-3, abs=2e-3 * F / b["EA"])
        assert abs(k - k_want) < 1e-2 * peak


def test_cable_cantilever_example_decays_as_its_section_says_and_its_audit_closes():
    """The cable example (copper core, lossy PVC sheath of another Poisson ratio) released
    from its static deflection: the damping ratio of its free decay (log decrements of
    the tip, after the first cycle) is the complex-modulus beam's of its section's own
    K44, V44, and the energy audit closes."""
    from runtime.analysis.decay import damping_ratios, log_decrements

    p = load_problem(CABLE, {"simulation.t_end": 0.6})
    res = simulate(p)
    assert res.status == "finished", res.message
    assert res.audit().max_rel < 1e-4
    sec = composite_analysis(p.section)
    want = ref.kelvin_voigt_cantilever(sec.stiffness[4, 4], sec.viscosity[4, 4],
                                       sec.mass_per_length, p.rod.length)
    zeta = damping_ratios(log_decrements(res.peaks_x))[1:]
    assert zeta.size >= 3
    assert np.median(zeta) == pytest.approx(want["zeta"], rel=2e-2)
