"""Self-contact of a single rod (``contact.self``, issue 32; runtime/model/native/
rod_self_contact.c): the forces are the contact energy's gradient, the Jacobian (band
plus the pairs' couplings) against central differences of the residual, the coupled
block's solve against a dense one, the broad phase against a brute-force search written
here, pairs near along the rod never paired, a closing coil held apart in a simulation
(with the energy audit) where without self-contact its turns pass through each other,
statics with self-contact (an assembly's rods: tests/runtime/test_rod_rod_contact.py)."""

from __future__ import annotations

import math

import numpy as np

from runtime.problem.assemble import build_model
from runtime.problem.schema import Problem
from tests.rods import central_difference_jacobian

R_ROD = 0.01           # m, contact radius of the helices below
CUTOFF = 40.0          # generated/rod_layout.CONTACT_CUTOFF, written here on purpose


def _helix(N=24, turns=1.4, coil=0.06, gap=-5e-4, r=R_ROD, contact=None, **extra) -> dict:
    """A free rubber helix whose turns touch: pitch 2 r + gap (gap < 0: overlapping)."""
    pitch = 2 * r + gap
    length = turns * math.hypot(2 * math.pi * coil, pitch)
    m = {"name": "selfcontact",
         "rod": {"length": length, "elements": N,
                 "geometry": {"kind": "helix", "coil_radius": coil, "pitch": pitch,
                              "turns": turns}},
         "section": {"kind": "circle", "radius": r},
         "material": {"density": 1100.0, "youngs_modulus": 1e6, "poisson_ratio": 0.45,
                      "tau": 0.01},
         "start": {"kind": "free"}, "end": {"kind": "free"},
         "simulation": {"t_end": 0.1, "initial": "reference"}}
    if contact is not False:
        m["contact"] = {"self": True, "friction": 0.3, "penetration": 1e-3,
                        **(contact or {})}
    m.update(extra)
    return m


def _model(m):
    return build_model(Problem.from_mapping(m))


def _state(model, rng, speed=0.05, spin=0.5, jitter=1e-4):
    y = model.reference.copy()
    y[model.phi_index] += jitter * rng.standard_normal(model.phi_index.shape)
    y[model.v_index] = speed * rng.standard_normal(model.v_index.shape)
    y[model.omega_index] = spin * rng.standard_normal(model.omega_index.shape)
    return y


def _residual(model, y, yp=None):
    out = np.zeros(model.n)
    model.residual(0.0, y, np.zeros(model.n) if yp is None else yp, out)
    return out


def test_self_contact_is_on_and_changes_the_residual():
    rng = np.random.default_rng(0)
    on, off = _model(_helix()), _model(_helix(contact=False))
    assert on.self_contact is not None and off.self_contact is None
    y = _state(on, rng)
    v = on.self_contact_values(0.0, y)
    assert v["pairs"] > 0 and v["gap_min"] < 0.0 and v["energy"] > 0.0
    diff = _residual(on, y) - _residual(off, y)
    assert np.abs(diff[on.v_index]).max() > 1e-3


def test_forces_are_the_energy_gradient_at_rest():
    """Without velocities (no damping, no friction) the force on node i is -dE/dphi_i and
    no torque acts (the pair energy does not depend on the frames)."""
    rng = np.random.default_rng(1)
    on, off = _model(_helix()), _model(_helix(contact=False))
    y = _state(on, rng, speed=0.0, spin=0.0)
    f = _residual(on, y) - _residual(off, y)          # res -= Q: +dE/dphi on the v rows
    E = lambda z: on.self_contact_values(0.0, z)["energy"]  # noqa: E731
    grad = np.zeros(on.phi_index.shape)
    h = 1e-7
    for i in range(on.N + 1):
        for k in range(3):
            e = np.zeros(on.n)
            e[on.phi_index[i, k]] = h
            grad[i, k] = (E(y + e) - E(y - e)) / (2 * h)
    scale = np.abs(grad).max()
    assert scale > 1.0
    np.testing.assert_allclose(f[on.v_index], grad, atol=1e-6 * scale)
    assert np.abs(f[on.omega_index]).max() < 1e-9 * scale


def test_jacobian_against_central_differences_with_friction_and_damping():
    rng = np.random.default_rng(2)
    model = _model(_helix())
    y = _state(model, rng)
    yp = np.zeros(model.n)
    J = model.dF_dy_sparse(0.0, y, yp).toarray()
    Jfd = central_difference_jacobian(lambda x: _residual(model, x), y)
    scale = np.abs(J).max()
    assert np.abs(J - Jfd).max() < 1e-7 * scale
    # the couplings hold entries far outside the band (segments a turn apart)
    rows, cols = np.nonzero(model._self_couplings(0.0, y).toarray())
    assert rows.size and np.abs(rows - cols).max() > 3 * (model.kl + model.ku)
    assert model.self_contact.dropped == 0


def test_the_coupled_block_solves_the_newton_system():
    rng = np.random.default_rng(3)
    model = _model(_helix())
    y, yp, cj = _state(model, rng), np.zeros(model.n), 250.0
    model.system_jacobian(0.0, y, yp, cj)
    cb = model.blocks
    D = cb.dense()
    np.testing.assert_allclose(D, model.jacobian_sparse(0.0, y, yp, cj).toarray(),
                               atol=1e-12 * np.abs(D).max())
    assert cb.factor() == 0
    b = rng.standard_normal(model.n)
    x = cb.solve(b.copy())
    ref = np.linalg.solve(D, b)
    assert np.abs(x - ref).max() < 1e-8 * np.abs(ref).max()


def _brute_pairs(model, y, law, s) -> set[tuple[int, int]]:
    """Every pair in reach by the definition: segments i < j, not neighbours, more than
    pi/2 (r_i + r_j) apart along the rod (s: the nodes' arc lengths), midpoints' distance
    minus half lengths and radii at most CUTOFF delta."""
    x = y[model.phi_index]
    r = np.asarray(law.radius)
    out = set()
    for i in range(1, model.N + 1):
        for j in range(i + 2, model.N + 1):
            if s[j - 1] - s[i] < math.pi / 2 * (r[i - 1] + r[j - 1]):
                continue
            mi, mj = (x[i - 1] + x[i]) / 2, (x[j - 1] + x[j]) / 2
            g = (np.linalg.norm(mi - mj) - np.linalg.norm(x[i] - x[i - 1]) / 2
                 - np.linalg.norm(x[j] - x[j - 1]) / 2 - r[i - 1] - r[j - 1])
            if g <= CUTOFF * law.self_penetration:
                out.add((i, j))
    return out


def test_the_broad_phase_finds_every_pair_in_reach():
    """A crumpled rod (a random walk folded into a small box): the sweep's pairs equal
    the brute-force search's, in a state where the sweep's axis matters."""
    rng = np.random.default_rng(4)
    m = _helix(N=60, turns=3.0, coil=0.03, gap=0.0, contact={"penetration": 2e-3})
    p = Problem.from_mapping(m)
    model = build_model(p)
    for trial in range(3):
        y = model.reference.copy()
        y[model.phi_index] += 0.01 * rng.standard_normal(model.phi_index.shape)
        y[model.phi_index[:, trial]] *= 0.2            # flatten along one axis
        expected = _brute_pairs(model, y, p.contact_law(), np.asarray(p.node_arc_lengths()))
        assert len(expected) > 20
        assert model.self_contact_values(0.0, y)["pairs"] == len(expected)


def test_stretches_near_along_the_rod_are_not_paired():
    """A straight rod whose contact radius is twice its element: its segments up to
    pi r apart along it overlap in space, yet none is paired (the exclusion goes by
    arc length, not by a count of elements); beyond that they are apart."""
    m = {"name": "thick", "rod": {"length": 0.2, "elements": 40,
                                  "geometry": {"kind": "straight"}},
         "section": {"kind": "circle", "radius": 0.01},
         "material": {"density": 1100.0, "youngs_modulus": 1e6, "poisson_ratio": 0.45},
         "start": {"kind": "free"}, "end": {"kind": "free"},
         "simulation": {"t_end": 0.1, "initial": "reference"},
         "contact": {"self": True}}
    model = _model(m)
    v = model.self_contact_values(0.0, model.reference)
    assert v["pairs"] == 0 and v["energy"] == 0.0
    off = _model({k: w for k, w in m.items() if k != "contact"})
    np.testing.assert_array_equal(_residual(model, model.reference),
                                  _residual(off, model.reference))
    # with the exclusion by a count of two elements they would be deep in contact
    x = model.reference[model.phi_index]
    assert np.linalg.norm((x[3] + x[4] - x[0] - x[1]) / 2) - 2 * 0.01 < -0.004


def _coil(self_contact: bool, N=30) -> dict:
    """A soft coil spring (2 turns, 2 mm clear between the turns' surfaces) clamped at its
    start and pushed along its axis at its free end: its turns close onto each other."""
    r, coil, turns = 0.002, 0.015, 2
    pitch = 2 * r + 0.002
    m = {"name": "coil",
         "rod": {"length": turns * math.hypot(2 * math.pi * coil, pitch), "elements": N,
                 "geometry": {"kind": "helix", "coil_radius": coil, "pitch": pitch,
                              "turns": turns, "axis": [0.0, 0.0, 1.0]}},
         "section": {"kind": "circle", "radius": r},
         "material": {"density": 1100.0, "youngs_modulus": 5e6, "poisson_ratio": 0.45,
                      "tau": 0.01},
         "start": {"kind": "clamped"}, "end": {"kind": "free"},
         "loads": [{"kind": "force", "vector": [0.0, 0.0, -0.02], "at": "end",
                    "time": {"kind": "smooth_ramp", "start": 0.0, "duration": 0.1}}],
         "simulation": {"t_end": 0.15, "output_step": 0.01, "initial": "reference"}}
    if self_contact:
        m["contact"] = {"self": True}
    return m


def _worst_gap(model, states, r, ends=True) -> float:
    """The smallest surface gap (m) over every state of pairs of segments more than pi r
    apart along the rod (sampled segment distance: an upper bound of the exact one), or
    r when none comes closer; ``ends=False``: without the rod's first and last
    segments."""
    u = np.linspace(0.0, 1.0, 41)
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(model.reference[
        model.phi_index], axis=0), axis=1))])
    i, j = np.triu_indices(model.N, 2)
    keep = s[j] - s[i + 1] >= math.pi * r
    if not ends:
        keep &= (i > 0) & (j < model.N - 1)
    i, j = i[keep], j[keep]
    worst = r
    for y in states:
        x = y[model.phi_index]
        mid, half = (x[1:] + x[:-1]) / 2, np.linalg.norm(x[1:] - x[:-1], axis=1) / 2
        bound = np.linalg.norm(mid[i] - mid[j], axis=1) - half[i] - half[j] - 2 * r
        near = bound < worst            # the others cannot come closer
        P = x[:-1, None, :] + u[None, :, None] * (x[1:] - x[:-1])[:, None, :]   # (N, 41, 3)
        for a, b in zip(i[near], j[near], strict=True):
            d = np.linalg.norm(P[a][:, None] - P[b][None], axis=2).min()
            worst = min(worst, d - 2 * r)
    return worst


def test_a_closing_coil_is_held_apart_and_audited():
    from runtime.simulate.simulate import simulate

    states = {}
    for on in (True, False):
        p = Problem.from_mapping(_coil(on))
        snaps = []
        res = simulate(p, snapshot_every=0.005,
                       snapshot_sink=lambda t, y, yp, s=snaps: s.append(y.copy()))
        assert res.status == "finished", res.message
        states[on] = (build_model(p), snaps, res.summary(), res.self_contact)
    r = 0.002
    passed = _worst_gap(states[False][0], states[False][1], r)
    assert passed < -r                    # without self-contact the turns pass through
    # with it they touch and stay apart: between inner segments within the law's
    # compliance; where the rod's end (here its clamped start) presses on the next turn
    # the pair kernel's smooth clamp of the closest points to the segment's inside
    # (derive/contact_pair.py) lets it sink further (0.15 r in this run)
    held = _worst_gap(states[True][0], states[True][1], r, ends=False)
    assert -0.05 * r < held < 0.1 * r
    assert _worst_gap(states[True][0], states[True][1], r) > -0.25 * r
    assert states[True][2]["energy_balance_max_rel"] < 1e-4
    # the pairs' values on the output grid (series.npz) and in the summary
    series, summary = states[True][3], states[True][2]["self_contact"]
    assert set(series) == {"energy", "dissipation", "friction_dissipation", "gap_min",
                           "pairs", "force"}
    assert all(v.shape == (16,) for v in series.values())      # t = 0, 0.01, ... 0.15
    assert -0.25 * r < summary["gap_min"]["value"] < 0.1 * r
    assert summary["pairs_max"] > 0 and summary["force"]["max"] > 0.0
    assert np.all(series["energy"] >= 0.0) and np.all(series["dissipation"] >= 0.0)
    assert not states[False][3] and "self_contact" not in states[False][2]


def test_statics_with_self_contact_uses_the_sparse_jacobian():
    """The static Jacobian with self-contact includes the pairs' couplings: it equals
    the central differences of the static residual (a coil pressed into itself)."""
    from runtime.model.statics import RodStatics

    rng = np.random.default_rng(5)
    model = _model(_helix(contact={"friction": 0.0}))
    st = RodStatics(model)
    assert st.static_factor is not None
    with model.statics():
        y = model.reference.copy()
        y[model.phi_index] += 1e-4 * rng.standard_normal(model.phi_index.shape)
        J = st.jacobian_csr(y).toarray()
        n = st.n_static
        Jfd = np.zeros((n, n))
        r0, r1 = np.zeros(n), np.zeros(n)
        for k in range(n):
            dx = np.zeros(n)
            dx[k] = 1e-7
            st.static_residual(st.static_retract(y, dx), r1)
            st.static_residual(st.static_retract(y, -dx), r0)
            Jfd[:, k] = (r1 - r0) / 2e-7
    scale = np.abs(J).max()
    assert np.abs(J - Jfd).max() < 1e-5 * scale


def test_the_plectoneme_example_holds_its_strands_apart():
    """examples/contact_plectoneme.toml as shipped: the strands touch (a plectoneme
    forms) and never come closer than 2 r - delta; the energy audit closes."""
    from runtime.problem.registry import load_problem
    from runtime.simulate.simulate import simulate

    p = load_problem("contact_plectoneme")
    res = simulate(p)
    assert res.status == "finished", res.message
    assert res.summary()["energy_balance_max_rel"] < 1e-5
    model = build_model(p)
    r = float(np.min(p.contact_law().radius))
    delta = p.contact_law().self_penetration
    frames = [np.zeros(model.n) for _ in res.centreline]
    for y, c in zip(frames, res.centreline, strict=True):
        y[model.phi_index] = c.T
    touching = [f for f in frames[::4] if _worst_gap(model, [f], r) < 0.1 * r]
    assert len(touching) >= 3                      # from t = 5.6 s on (of 8 s)
    assert _worst_gap(model, touching, r) > -delta


def test_pairs_beyond_the_coupling_capacity_slow_newton_but_not_the_result(monkeypatch):
    """With room for 36 coupling rows the closing coil's Jacobian leaves pairs out (their
    forces stay in the residual): the run ends where the full one does, within the
    integrator's tolerance."""
    import runtime.model.rod as rod_module
    from runtime.simulate.simulate import simulate

    p = Problem.from_mapping(_coil(True))
    full = simulate(p)
    monkeypatch.setattr(rod_module, "SELF_COUPLING_DOUBLES", 1)
    model = build_model(p)
    assert model.blocks.m2cap == 36
    y = full.centreline[-1].T
    state = model.reference.copy()
    state[model.phi_index] = y
    model.system_jacobian(0.0, state, np.zeros(model.n), 1e3)
    assert model.self_contact.dropped > 0
    part = simulate(p, model=model)
    assert part.status == "finished", part.message
    np.testing.assert_allclose(part.tip[:, -1], full.tip[:, -1], atol=1e-4 * 0.1)
