"""Assemblies of rods against references written separately (issue 31): two rods welded
end to end against one rod, a cantilever with a tip body against the frequency equation,
an L-frame against Castigliano, a propped cantilever and a two-span beam against their
reactions, a hinged double pendulum against the rigid-bar frequencies, a closed ring
against its in-plane frequencies, energy audits of the harness and the tip body
(references/assemblies.py: no kvrod code)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from references import assemblies as ref
from runtime.analysis.system_modal import assembly_modes
from runtime.problem.assemble_system import build_system
from runtime.problem.assembly import Assembly
from runtime.problem.registry import load_problem
from runtime.simulate.assembly import simulate_assembly, static_equilibrium

E, NU, RHO, R = 2.1e11, 0.3, 7850.0, 0.005
G = E / (2 * (1 + NU))
A, I = math.pi * R**2, math.pi * R**4 / 4
KAPPA = 6 * (1 + NU) / (7 + 6 * NU)          # Cowper's circle: the default shear factor


def steel_rod(length: float, n: int, direction, origin=(0.0, 0.0, 0.0), normal=None,
              **ends) -> dict:
    d = np.asarray(direction, dtype=float)
    if normal is None:
        normal = [0.0, 1.0, 0.0] if abs(d[1]) < 0.9 else [1.0, 0.0, 0.0]
    return {"rod": {"length": length, "elements": n,
                    "geometry": {"kind": "straight", "direction": list(direction),
                                 "normal": list(normal), "origin": list(origin)}},
            "section": {"kind": "circle", "radius": R},
            "material": {"density": RHO, "youngs_modulus": E, "poisson_ratio": NU,
                         "tau": 1e-4}, **ends}


def assembly(rods: dict, joints=(), loads=(), bodies=(), **top) -> Assembly:
    return Assembly.from_mapping({"name": "test", "rods": rods, "joints": list(joints),
                                  "loads": list(loads), "bodies": list(bodies),
                                  "simulation": {"t_end": 0.1}, **top})


def modes_of(problem, count: int, loaded: bool = False) -> list:
    amap = build_system(problem)
    y = static_equilibrium(problem, amap).y if loaded else amap.model.initial_state()
    with amap.model.statics():
        return assembly_modes(amap.model, y, count=count)


def distinct(omegas, rtol=1e-6) -> list[float]:
    out = []
    for w in sorted(omegas):
        if not out or w > out[-1] * (1 + rtol):
            out.append(w)
    return out


def test_two_rods_welded_end_to_end_are_one_rod():
    """The paper's cantilever as two rods of 0.15 m welded end to end: static tip under
    its 0.05 N load (a large deflection, 0.22 m) and four frequencies equal one rod's of
    the same elements to 1e-6 (the weld is the rod's own interior joint)."""
    from runtime.analysis.modal import modal_analysis
    from runtime.problem.assemble import build_model
    from runtime.simulate.simulate import static_equilibrium as single_static

    two = load_problem("examples/assembly_two_rod_cantilever.toml",
                       {"rods.root.rod.elements": 8, "rods.tip.rod.elements": 8})
    one = load_problem("cantilever", {"rod.elements": 16})
    one_free = one.with_overrides({"loads.0.vector": [0.0, 0.0, 0.0]})
    amap = build_system(two)
    st = static_equilibrium(two, amap)
    tip = st.y[amap.model.phi_index[1][-1]]
    want = single_static(one).tip
    assert np.max(np.abs(tip - want)) <= 1e-6 * np.linalg.norm(want)
    free = two.with_overrides({"loads.0.vector": [0.0, 0.0, 0.0]})
    w2 = distinct(m.omega for m in modes_of(free, 8))[:4]
    w1 = distinct(m.omega for m in modal_analysis(build_model(one_free), count=8))[:4]
    assert np.allclose(w2, w1, rtol=1e-6, atol=0)


def test_tip_body_first_frequency():
    """A steel cantilever (0.5 m, r = 5 mm) carrying a 0.2 kg ball (rotary inertia
    2.68e-5 kg m^2) at its tip: omega_1 against the Euler-Bernoulli frequency equation with
    a tip mass and rotary inertia within 0.5 % at N = 64 (measured -2.4e-4; against the
    Timoshenko one -1.0e-4, second order in h)."""
    p = load_problem("examples/assembly_tip_body.toml",
                     {"loads": [], "rods.beam.rod.elements": 64})
    w = distinct(m.omega for m in modes_of(p, 4))
    eb = ref.tip_mass_cantilever_frequencies(1, L=0.5, EI=E * I, m=RHO * A, M=0.2,
                                             J=2.68e-5)[0]
    assert w[0] == pytest.approx(eb, rel=5e-3)
    timo = ref.tip_mass_timoshenko_frequencies(1, L=0.5, EI=E * I, kGA=KAPPA * G * A,
                                               m=RHO * A, rhoI=RHO * I, M=0.2, J=2.68e-5)[0]
    assert w[0] == pytest.approx(timo, rel=5e-4)


@pytest.mark.parametrize("force", [[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])
def test_l_frame_tip_against_castigliano(force):
    """Column (0.4 m, up from a clamp) and beam (0.3 m, along +x) welded at a right-angled
    corner, a small tip force out of and in the plane: the tip displacement within 0.5 %
    of the unit-load method with bending, torsion, shear and extension at N = 32 + 32."""
    scale = 1e-3                                       # N: the linear range
    rods = {"column": steel_rod(0.4, 32, [0, 0, 1], start={"kind": "clamped"}),
            "beam": steel_rod(0.3, 32, [1, 0, 0], origin=[0, 0, 0.4], normal=[0, 0, 1])}
    p = assembly(rods, joints=[{"kind": "weld", "between": ["column.end", "beam.start"]}],
                 loads=[{"kind": "force", "at": "beam.end",
                         "vector": [scale * f for f in force]}])
    amap = build_system(p)
    y = static_equilibrium(p, amap).y
    u = y[amap.model.phi_index[1][-1]] - amap.model.reference[amap.model.phi_index[1][-1]]
    want = ref.l_frame_tip(np.asarray(force) * scale, L1=0.4, L2=0.3, EI=E * I,
                           GJ=G * math.pi * R**4 / 2, EA=E * A,
                           GA=KAPPA * G * A)["displacement"]
    k = int(np.argmax(np.abs(want)))
    assert u[k] == pytest.approx(want[k], rel=5e-3)
    assert np.linalg.norm(u - want) <= 5e-3 * np.linalg.norm(want)


def _support_reactions(p) -> list[np.ndarray]:
    from runtime.io.assembly_results import static_joint_values

    amap = build_system(p)
    st = static_equilibrium(p, amap)
    return [np.array(j["force"]) for j in static_joint_values(amap, st.y)]


def test_propped_cantilever_reactions():
    """examples/assembly_propped_cantilever.toml: a cantilever (1 m) propped at its end (a
    ball joint to ground) under its own weight: the prop and clamp carry 3qL/8 and 5qL/8
    (Timoshenko-exact) within 0.5 %."""
    L = 1.0
    p = load_problem("examples/assembly_propped_cantilever.toml")
    q = RHO * A * 9.81
    want = ref.propped_cantilever(q, L=L, EI=E * I, kGA=KAPPA * G * A)
    prop = _support_reactions(p)[0]
    assert prop[2] == pytest.approx(want["R_prop"], rel=5e-3)
    assert q * L - prop[2] == pytest.approx(want["R_clamp"], rel=5e-3)


def test_two_span_beam_reactions():
    """examples/assembly_two_span.toml: a beam over three supports (pinned at both ends,
    a ball joint to ground in the middle) under its own weight: 3qL/8, 10qL/8, 3qL/8."""
    p = load_problem("examples/assembly_two_span.toml")
    q = RHO * A * 9.81
    want = ref.two_span_beam(q, L1=0.5, EI=E * I, kGA=KAPPA * G * A)
    middle = _support_reactions(p)[0]
    assert middle[2] == pytest.approx(want["R_B"], rel=5e-3)


def test_double_pendulum_frequencies():
    """Two stiff steel rods hanging from a hinge and hinged to each other: the two lowest
    modes about the hanging equilibrium against the rigid-bar double pendulum within 1 %."""
    l1 = l2 = 0.5
    rods = {"upper": steel_rod(l1, 16, [0, 0, -1], normal=[0, 1, 0]),
            "lower": steel_rod(l2, 16, [0, 0, -1], origin=[0, 0, -l1], normal=[0, 1, 0])}
    p = assembly(rods, joints=[
        {"kind": "hinge", "between": ["upper.start", "ground"], "axis": [0, 1, 0]},
        {"kind": "hinge", "between": ["upper.end", "lower.start"], "axis": [0, 1, 0]}],
        loads=[{"kind": "gravity", "vector": [0.0, 0.0, -9.81]}])
    w = distinct(m.omega for m in modes_of(p, 4, loaded=True) if m.omega > 1e-3)
    m = RHO * A * l1
    want = ref.double_pendulum_frequencies(m1=m, l1=l1, m2=m, l2=l2, g=9.81)
    assert w[:2] == pytest.approx(list(want), rel=1e-2)


def test_closed_ring_in_plane_frequencies():
    """examples/assembly_ring.toml: a full circle (R = 0.2 m, 360 degrees) welded to
    itself, free: its flexural frequencies n = 2, 3, in and out of plane, within 1 % of
    Hoppe's and Michell's (the rigid motions come out at 0)."""
    Rr = 0.2
    p = load_problem("examples/assembly_ring.toml")
    w = distinct(md.omega for md in modes_of(p, 16) if md.omega > 1.0)
    ip = ref.ring_inplane_frequencies(np.array([2, 3]), R=Rr, EI=E * I, m=RHO * A)
    op = ref.ring_out_of_plane_frequencies(np.array([2, 3]), R=Rr, EI=E * I,
                                           GJ=G * math.pi * R**4 / 2, m=RHO * A)
    for want in (*ip, *op):
        assert min(abs(x / want - 1) for x in w) < 1e-2, (want, w[:8])


@pytest.mark.slow
@pytest.mark.parametrize("name", ["harness", "tip_body", "l_frame", "soft_arm"])
def test_assembly_examples_close_their_energy_audit(name):
    p = load_problem(f"examples/assembly_{name}.toml", {"simulation.t_end": 0.3})
    res = simulate_assembly(p)
    assert res.status == "finished", res.message
    assert res.audit().max_rel < 1e-4
