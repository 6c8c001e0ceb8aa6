"""Contact between the rods of an assembly (``contact.self`` in an assembly, issue 32;
runtime/model/native/rod_self_contact.c's ``kvsys_pairs_*`` through system.c): the forces
are the pairs' energy gradient, the system Jacobian (bands plus couplings, with a weld
and a ground joint at the crossing) against central differences of the residual, the
coupled blocks' solve against a dense one, the crossing example's contact force and
deflections against linear cantilevers (computed here from the beam formulas), and a rod
dropped onto another held above it with the energy audit closed."""

from __future__ import annotations

import math

import numpy as np
import pytest

from runtime.errors import ParameterError
from runtime.problem.assemble_system import build_system
from runtime.problem.assembly import Assembly
from runtime.problem.registry import load_problem
from runtime.simulate.assembly import simulate_assembly, static_equilibrium
from tests.rods import central_difference_jacobian

R = 0.01                  # m, the rods' radius (= contact radius) in the small cases
RUBBER = {"density": 1100.0, "youngs_modulus": 1e6, "poisson_ratio": 0.45, "tau": 0.01}


def _rod(origin, direction, length, n, r=R, material=RUBBER, **ends) -> dict:
    d = np.asarray(direction, dtype=float)
    normal = [0.0, 0.0, 1.0] if abs(d[2]) < 0.9 else [1.0, 0.0, 0.0]
    return {"rod": {"length": length, "elements": n,
                    "geometry": {"kind": "straight", "direction": list(direction),
                                 "normal": normal, "origin": list(origin)}},
            "section": {"kind": "circle", "radius": r}, "material": dict(material), **ends}


def _crossing(contact=True, joints=False, gap=-1e-3) -> dict:
    """Rod b along y crossing over rod a along x (their surfaces ``gap`` apart: < 0
    pressed into each other). ``joints``: a welded to a third rod c at the crossing (a's
    end, c's start) and b held at ground there by a ball joint, so that the pairs act on
    a tied node and on a held one."""
    z = 2 * R + gap
    if joints:
        rods = {"a": _rod((-0.15, 0.0, 0.0), (1, 0, 0), 0.15, 5),
                "c": _rod((0.0, 0.0, 0.0), (1, 0, 0), 0.15, 5),
                "b": _rod((0.0, -0.15, z), (0, 1, 0), 0.3, 6)}
        jts = [{"kind": "weld", "between": ["a.end", "c.start"]},
               {"kind": "ball", "between": ["b@0.15", "ground"]}]
    else:
        rods = {"a": _rod((-0.1, 0.0, 0.0), (1, 0, 0), 0.2, 5),
                "b": _rod((0.0, -0.1, z), (0, 1, 0), 0.2, 5)}
        jts = []
    m = {"name": "crossing", "rods": rods, "joints": jts,
         "loads": [{"kind": "gravity", "vector": [0.0, 0.0, -9.81]}],
         "simulation": {"t_end": 0.1, "initial": "reference"}}
    if contact:
        m["contact"] = {"self": True, "friction": 0.3, "penetration": 1e-3}
    return m


def _model(m):
    return build_system(Assembly.from_mapping(m)).model


def _state(model, rng, speed=0.05, spin=0.5, jitter=1e-4):
    y = model.initial_state()
    for k in range(len(model.rods)):
        ph, v, om = model.phi_index[k], model.v_index[k], model.omega_index[k]
        y[ph] += jitter * rng.standard_normal(ph.shape)
        y[v] = speed * rng.standard_normal(v.shape)
        y[om] = spin * rng.standard_normal(om.shape)
    return model.constrain(y)


def _residual(model, y):
    out = np.zeros(model.n)
    model.residual(0.0, y, np.zeros(model.n), out)
    return out


def test_the_pairs_act_between_the_rods():
    on, off = _model(_crossing()), _model(_crossing(contact=False))
    assert on.pairs is not None and off.pairs is None
    assert all(r.self_contact is None for r in on.rods)     # the system holds the pairs
    y = _state(on, np.random.default_rng(0))
    v = on.pair_contact_values(0.0, y)
    assert v["pairs"] > 0 and v["gap_min"] < 0.0 and v["energy"] > 0.0
    diff = _residual(on, y) - _residual(off, y)
    for k in range(2):                                     # on both rods
        assert np.abs(diff[on.v_index[k]]).max() > 1e-3
    # apart (by 20 delta): no energy to speak of (each straight rod's own segments two
    # apart are in reach by the bound, 20 delta apart too)
    far = _model(_crossing(gap=0.02))
    assert far.pair_contact_values(0.0, far.initial_state())["energy"] < 1e-12 * v["energy"]


def test_forces_are_the_pair_energy_gradient_at_rest():
    """Without velocities the force on every node is -dE/dphi (E: the pairs' energy) and
    no torque acts; action and reaction balance between the rods."""
    on, off = _model(_crossing()), _model(_crossing(contact=False))
    y = _state(on, np.random.default_rng(1), speed=0.0, spin=0.0)
    f = _residual(on, y) - _residual(off, y)             # res -= Q: +dE/dphi on the v rows
    E = lambda z: on.pair_contact_values(0.0, z)["energy"]  # noqa: E731
    h = 1e-7
    worst, scale = 0.0, 0.0
    total = np.zeros(3)
    for k in range(2):
        grad = np.zeros(on.phi_index[k].shape)
        for i in range(grad.shape[0]):
            for c in range(3):
                e = np.zeros(on.n)
                e[on.phi_index[k][i, c]] = h
                grad[i, c] = (E(y + e) - E(y - e)) / (2 * h)
        scale = max(scale, np.abs(grad).max())
        worst = max(worst, np.abs(f[on.v_index[k]] - grad).max())
        total += f[on.v_index[k]].sum(axis=0)
        assert np.abs(f[on.omega_index[k]]).max() < 1e-9 * max(scale, 1.0)
    assert scale > 1e-2
    assert worst < 1e-6 * scale
    assert np.abs(total).max() < 1e-9 * scale


@pytest.mark.parametrize("joints", [False, True])
def test_system_jacobian_against_central_differences(joints):
    """With damping and friction; with ``joints`` the crossing is on a node tied to
    another rod's (its entries move to the master's row) and on one held at ground."""
    model = _model(_crossing(joints=joints))
    y = _state(model, np.random.default_rng(2))
    yp = np.zeros(model.n)
    assert model.pair_contact_values(0.0, y)["pairs"] >= 2
    J = model.jacobian_sparse(0.0, y, yp, 1.0, 0.0).toarray()
    Jfd = central_difference_jacobian(lambda x: _residual(model, x), y)
    scale = np.abs(J).max()
    assert np.abs(J - Jfd).max() < 1e-7 * scale
    # entries between the two rods: the pairs' couplings (no joint couples a and b)
    a, b = model.rod_slice(0), model.rod_slice(model.names.index("b"))
    assert np.abs(J[a, b]).max() > 0.0 and np.abs(J[b, a]).max() > 0.0
    assert model.pairs.dropped == 0


def test_the_coupled_blocks_solve_the_newton_system():
    model = _model(_crossing(joints=True))
    y, yp, cj = _state(model, np.random.default_rng(3)), np.zeros(model.n), 250.0
    model.system_jacobian(0.0, y, yp, cj)
    cb = model.blocks
    D = cb.dense()
    assert cb.factor() == 0
    b = np.random.default_rng(4).standard_normal(model.n)
    np.testing.assert_allclose(cb.solve(b.copy()), np.linalg.solve(D, b), rtol=1e-8,
                               atol=1e-10 * np.abs(np.linalg.solve(D, b)).max())


def test_each_rod_takes_its_own_contact_radius():
    """``contact.radius`` as a table per rod (the format an assembly takes): each rod's
    segments carry their radius into the pairs."""
    from generated import rod_layout as L
    from tests.runtime.test_assembly_problem import _base

    m = _base()
    m["contact"] = {"radius": {"a": 0.008}, "self": True}
    model = build_system(Assembly.from_mapping(m)).model
    r = model.pairs.seg[:, L.CNT_OFFSETS["r"]]
    na = model.rods[0].N
    assert model.pairs.rod_segments == (na, model.rods[1].N)
    np.testing.assert_array_equal(r[:na], 0.008)
    np.testing.assert_array_equal(r[na:], 0.005)            # b's circle radius


def test_sensitivities_with_contact_between_the_rods_are_refused():
    model = _model(_crossing())
    with pytest.raises(ParameterError) as exc:
        model.set_directions(object())
    assert exc.value.name == "contact.self" and "\n" not in str(exc.value)


def test_kvrod_simulate_refuses_those_sensitivities_before_writing(tmp_path):
    """The command's path refuses them with the problem, before the results folder."""
    from runtime.io.runs import run_and_write

    with pytest.raises(ParameterError) as exc:
        run_and_write(load_problem("contact_crossing"), tmp_path / "out", "test",
                      sensitivities=["E"])
    assert exc.value.name == "contact.self"
    assert not (tmp_path / "out").exists()


# -- the crossing example against linear cantilevers ----------------------------------------
def _cantilever(doc_rod: dict, g: float) -> tuple[float, float, float]:
    """(q N/m, EI N m^2, L m) of a round steel wire of the example."""
    r = doc_rod["section"]["radius"]
    mat = doc_rod["material"]
    return (mat["density"] * math.pi * r**2 * g, mat["youngs_modulus"] * math.pi * r**4 / 4,
            doc_rod["rod"]["length"])


def crossing_reference(doc: dict, a: float = 0.5) -> dict[str, float]:
    """Euler-Bernoulli cantilevers under their weight crossing at ``a`` from both
    clamps, the thin one's centreline ``clear`` above its place on the thick one (the
    reference gap between the surfaces): the contact force P from compatibility, and
    both crossing points' deflections (m, downward)."""
    g = -doc["loads"][0]["vector"][2]
    qs, EIs, L = _cantilever(doc["rods"]["thin"], g)
    qk, EIk, Lk = _cantilever(doc["rods"]["thick"], g)
    assert L == Lk
    clear = (doc["rods"]["thin"]["rod"]["geometry"]["origin"][2]
             - doc["rods"]["thin"]["section"]["radius"]
             - doc["rods"]["thick"]["section"]["radius"])
    w = lambda q, EI: q * a**2 * (6 * L**2 - 4 * L * a + a**2) / (24 * EI)  # noqa: E731
    c = lambda EI: a**3 / (3 * EI)                                         # noqa: E731
    P = (w(qs, EIs) - w(qk, EIk) - clear) / (c(EIs) + c(EIk))
    return {"P": P, "thin": w(qs, EIs) - P * c(EIs), "thick": w(qk, EIk) + P * c(EIk)}


def test_the_crossing_example_against_linear_cantilevers():
    """examples/contact_crossing.toml (kvrod static): the contact force and the
    crossing points' deflections within 1 % of linear beam theory (its slope 0.05 makes
    it good to ~1e-3; shear ~1e-4; the law's compliance, about delta, ~1e-3 of the 2 mm
    closed; measured 1.5e-4 to 3.8e-4)."""
    import tomllib

    from runtime.problem.registry import EXAMPLES_DIR

    doc = tomllib.loads((EXAMPLES_DIR / "contact_crossing.toml").read_text())
    ref = crossing_reference(doc)
    assert ref["P"] == pytest.approx(0.05644, rel=1e-3)       # the header's numbers
    p = load_problem("contact_crossing")
    amap = build_system(p)
    model = amap.model
    y = static_equilibrium(p, amap).y
    # the contact force on the thick wire: the pairs' part of its residual
    m = p.to_mapping()
    del m["contact"]
    off = build_system(Assembly.from_mapping(m, base=p.base)).model
    zero = np.zeros(model.n)
    r_on, r_off = np.zeros(model.n), np.zeros(model.n)
    with model.statics(), off.statics():
        model.residual(0.0, y, zero, r_on)
        off.residual(0.0, y, zero, r_off)
    thick, thin = model.names.index("thick"), model.names.index("thin")
    f = -(r_on - r_off)                                  # the force on each node
    P = -f[model.v_index[thick]][:, 2].sum()
    assert P == pytest.approx(ref["P"], rel=0.01)
    assert f[model.v_index[thin]][:, 2].sum() == pytest.approx(P, rel=1e-9)
    for name, k in (("thin", thin), ("thick", thick)):
        node = int(round(0.5 / p.rods[name].rod.length * p.rods[name].rod.elements))
        dz = y[model.phi_index[k][node, 2]] - model.reference[model.phi_index[k][node, 2]]
        assert -dz == pytest.approx(ref[name], rel=0.01), name


# -- a rod dropped onto another --------------------------------------------------------------
def test_a_rod_dropped_onto_another_is_held_above_it_and_the_audit_closes(tmp_path):
    """A free rod falls 2 mm onto a rod clamped at both ends across it: it never sinks
    into it by more than a tenth of the radius, ends resting on it (its centreline 2 r
    above the other's at the crossing, within the law's compliance) and the energy audit
    closes; without the contact it falls through."""
    rods = {"beam": _rod((-0.1, 0.0, 0.0), (1, 0, 0), 0.2, 8, start={"kind": "clamped"},
                         end={"kind": "clamped"}),
            "drop": _rod((0.0, -0.1, 2 * R + 2e-3), (0, 1, 0), 0.2, 8)}
    m = {"name": "drop", "rods": rods,
         "loads": [{"kind": "gravity", "vector": [0.0, 0.0, -9.81]}],
         "simulation": {"t_end": 0.25, "initial": "reference", "output_step": 0.005},
         "contact": {"self": True, "restitution": 0.2}}
    p = Assembly.from_mapping(m)
    amap = build_system(p)
    model = amap.model
    gaps = []
    res = simulate_assembly(p, amap=amap, snapshot_every=0.0025, snapshot_sink=lambda t, y, yp:
                            gaps.append(model.pair_contact_values(t, y)["gap_min"]))
    assert res.status == "finished", res.message
    assert res.audit().max_rel < 1e-3
    assert len(gaps) > 50 and min(gaps) > -0.1 * R
    y = res.y_last
    beam, drop = model.names.index("beam"), model.names.index("drop")
    z_drop = y[model.phi_index[drop][4, 2]]
    z_beam = y[model.phi_index[beam][4, 2]]
    assert z_drop - z_beam == pytest.approx(2 * R, abs=0.05 * R)
    # the pairs' values on the output grid: series.npz and summary.json
    from runtime.io.assembly_results import write_assembly_run

    summary = write_assembly_run(tmp_path, res)
    with np.load(tmp_path / "series.npz") as z:
        force, gap = z["self_contact_force"], z["self_contact_gap_min"]
        assert force.shape == z["t"].shape == (51,)
    assert force[0] == pytest.approx(0.0, abs=1e-12) and force.max() > 0.0
    assert np.all(gap >= min(gaps))                      # the output grid is coarser
    sc = summary["self_contact"]
    assert sc["gap_min"]["value"] == pytest.approx(gap.min())
    assert 0.02 < sc["gap_min"]["t"] < 0.25 and sc["pairs_max"] >= 1
    weight = 1100.0 * math.pi * R**2 * 0.2 * 9.81         # the impact exceeds it
    assert sc["force"]["max"] > weight and sc["force"]["final"] > 0.0
    m_off = dict(m)
    del m_off["contact"]
    m_off["simulation"] = {**m["simulation"], "t_end": 0.1}
    free = simulate_assembly(Assembly.from_mapping(m_off))
    assert free.status == "finished", free.message
    yf = free.y_last
    assert yf[model.phi_index[drop][4, 2]] - yf[model.phi_index[beam][4, 2]] < 0.0


# -- the step bound by the approach speed ---------------------------------------------------
STEEL = {"density": 7850.0, "youngs_modulus": 2.1e11, "poisson_ratio": 0.3, "tau": 1e-4}


def _fall(height: float, rtol: float | None = None) -> Assembly:
    """A steel wire (2 mm radius) dropped from ``height`` (m, between the surfaces) across
    one clamped at both ends, until 20 ms after the free fall's impact."""
    r = 0.002
    rods = {"beam": _rod((-0.1, 0.0, 0.0), (1, 0, 0), 0.2, 8, r=r, material=STEEL,
                         start={"kind": "clamped"}, end={"kind": "clamped"}),
            "drop": _rod((0.0, -0.1, 2 * r + height), (0, 1, 0), 0.2, 8, r=r,
                         material=STEEL)}
    sim = {"t_end": math.sqrt(2 * height / 9.81) + 0.02, "initial": "reference",
           "output_step": 0.005}
    if rtol is not None:
        sim["rtol"] = rtol
    return Assembly.from_mapping({"name": "fall", "rods": rods,
                                  "loads": [{"kind": "gravity", "vector": [0, 0, -9.81]}],
                                  "simulation": sim,
                                  "contact": {"self": True, "restitution": 0.5}})


def _lowest(p: Assembly, bound: bool) -> tuple[float, object]:
    """The smallest height (m) of the dropped wire's middle node above the beam's over
    the run (sampled every 0.5 ms), and the result."""
    amap = build_system(p)
    model = amap.model
    if not bound:
        model.pairs._struct.step_fraction = 0.0
    dz = []
    res = simulate_assembly(p, amap=amap, snapshot_every=5e-4, snapshot_sink=lambda t, y, yp:
                            dz.append(y[model.phi_index[1][4, 2]]
                                      - y[model.phi_index[0][4, 2]]))
    assert res.status == "finished", res.message
    return min(dz), res


@pytest.mark.parametrize("height, rtol", [(0.3, None), (1.0, 1e-3), (3.0, 1e-3)])
def test_a_wire_dropped_from_any_height_never_steps_through_another(height, rtol):
    """Without the bound the free fall's steps carry the wire through the other one (its
    BDF error is nil in free fall); with it the step closes at most half the gap."""
    r = 0.002
    low, res = _lowest(_fall(height, rtol), bound=True)
    assert low > 1.9 * r                                  # 2 r: touching
    assert res.audit().max_rel < 1e-3
    if height == 0.3:
        low, res = _lowest(_fall(height, rtol), bound=False)
        assert low < -r


def test_the_step_bound_of_a_single_rods_own_pairs():
    """A single rod's self-contact bounds the step too (kvrod_contact_max_step): finite
    while two turns of a coil approach each other, shorter the faster; none in a rigid
    translation (nothing closes)."""
    from runtime.problem.assemble import build_model
    from runtime.problem.schema import Problem
    from tests.runtime.test_self_contact import _helix

    model = build_model(Problem.from_mapping(_helix(gap=5e-3)))
    y = model.reference.copy()
    z = y[model.phi_index][:, 2]
    y[model.v_index] = 0.0
    y[model.v_index[:, 2]] = np.where(z > np.median(z), -1.0, 0.0)  # the top turn falls
    h1 = model.state_max_step(0.0, y)
    y[model.v_index[:, 2]] *= 2.0
    h2 = model.state_max_step(0.0, y)
    assert 0.0 < h2 < h1 < math.inf
    assert h2 == pytest.approx(h1 / 2, rel=0.2)
    y[model.v_index] = [0.3, -0.2, 1.0]
    assert model.state_max_step(0.0, y) > 1e6               # rounding of the mean only
