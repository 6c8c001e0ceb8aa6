"""Rigid motions the supports leave free (issue 22 item 2): detection, the statics gauge,
refusals before any work, and the simply supported beam against references/supported.py.

The detection (from the geometry: rigid motions that keep held nodes and clamped frames in
place) is checked against the null space of the static stiffness at the reference; the
gauge against a solve that removes the free spin by elimination (a "clamped rotation"
model written here); the equilibria against closed forms written separately.
"""

from __future__ import annotations

import tomllib

import numpy as np
import pytest
import scipy.linalg as la
import scipy.sparse.linalg as spla

from references import examples as RX
from references import sections, supported
from runtime.errors import IllPosedError
from runtime.model.statics import RodStatics
from runtime.problem.assemble import build_model
from runtime.problem.registry import EXAMPLES_DIR, load_problem
from runtime.simulate.simulate import static_equilibrium
from runtime.solvers.statics import StaticSolveError
from tests.rods import rod_problem

GRAVITY_Z = [{"kind": "gravity", "vector": [0.0, 0.0, -9.81]}]


def _doc(name: str) -> dict:
    return tomllib.loads((EXAMPLES_DIR / f"{name}.toml").read_text())


def _stiffness_null_dim(model) -> int:
    """Dimension of the null space of the unloaded static stiffness at the reference."""
    st = RodStatics(model)
    with model.statics():
        J = st.static_jacobian_sparse(model.initial_state()).toarray()
    s = la.svdvals(J)
    return int(np.sum(s <= 1e-10 * s[0]))


def _motions(model):
    st = RodStatics(model)
    with model.statics():
        y = model.initial_state()
        return st, y, st.rigid_motions(y)


ARC = {"kind": "arc", "radius": 0.2, "angle": 120.0}


@pytest.mark.parametrize("start,end,geometry,k", [
    ("pinned", "pinned", None, 1), ("pinned", "pinned", ARC, 1), ("pinned", "free", None, 3),
    ("free", "free", None, 6), ("free", "free", ARC, 6), ("pinned", "clamped", None, 0),
    ("clamped", "free", None, 0), ("free", "pinned", ARC, 3)])
def test_free_rigid_motions_are_the_null_space_of_the_static_stiffness(start, end, geometry, k):
    model = build_model(rod_problem(8, start, end, loads=False, geometry=geometry))
    st, y, mot = _motions(model)
    assert mot.k == k
    assert _stiffness_null_dim(model) == k
    if k:
        with model.statics():
            J = st.static_jacobian_sparse(y)
        Z = mot.basis
        assert np.linalg.norm(J @ Z) <= 1e-12 * abs(J).max() * np.linalg.norm(Z)
        assert np.linalg.matrix_rank(Z) == k
        assert np.all(Z[st.fixed_cols] == 0.0)


def test_pinned_pinned_straight_spin_and_arc_chord():
    straight = build_model(rod_problem(8, "pinned", "pinned", loads=False))
    _, y, mot = _motions(straight)
    axis = straight.positions(y)[:, -1] - straight.positions(y)[:, 0]
    assert abs(abs(mot.axis @ axis) / np.linalg.norm(axis) - 1) < 1e-12
    assert "spin about the rod's own axis" in mot.what
    assert np.abs(mot.basis[RodStatics(straight).phi_cols]).max() < 1e-14  # nodes stay
    arc = build_model(rod_problem(8, "pinned", "pinned", loads=False, geometry=ARC))
    _, y, mot = _motions(arc)
    chord = arc.positions(y)[:, -1] - arc.positions(y)[:, 0]
    assert abs(abs(mot.axis @ chord) / np.linalg.norm(chord) - 1) < 1e-12
    assert "chord" in mot.what


def _eliminated_spin_solve(problem, model):
    """Newton on the static residual with the spin held by elimination: the rotation
    increment of segment 1 about the rod's axis (its material d3, a coordinate of the
    static layout for a straight rod) is removed from the unknowns, as a support that
    holds that rotation would; load stepping as in the gauged solve."""
    st = RodStatics(model)
    keep = np.setdiff1d(np.arange(st.n_static), [st.theta_cols[0][2]])
    r = np.empty(st.n_static)
    with model.statics():
        y = model.initial_state()
        for lam in np.linspace(0.1, 1.0, 10):
            st.load_scale = lam
            for _ in range(30):
                st.static_residual(y, r)
                J = st.jacobian_csr(y)[keep][:, keep].tocsc()
                dx = np.zeros(st.n_static)
                dx[keep] = -spla.spsolve(J, r[keep])
                y = st.static_retract(y, dx)
                if np.linalg.norm(dx) < 1e-15:
                    break
    return y


def test_gauge_gives_the_equilibrium_of_a_rod_whose_spin_is_held_by_a_support():
    """Straight pinned-pinned beam under transverse gravity (no load work on the spin):
    the gauged equilibrium is the one with the spin eliminated."""
    problem = rod_problem(16, "pinned", "pinned", loads=GRAVITY_Z, tau=0.0)
    model = build_model(problem)
    out = static_equilibrium(problem, model)
    assert out.gauge is not None and "spin" in out.gauge
    y_ref = _eliminated_spin_solve(problem, model)
    pos, pos_ref = model.positions(out.y), model.positions(y_ref)
    sag = np.abs(pos_ref - model.positions(model.reference)).max()
    assert sag > 1e-4
    assert np.abs(pos - pos_ref).max() <= 1e-8 * sag
    assert np.allclose(model.frames(out.y), model.frames(y_ref), atol=1e-9)
    st = RodStatics(model)
    with model.statics():
        g = st.hold_rigid_motions(model.initial_state())
        mom, force, Ms, Fs = g.reaction(st, out.y)
    assert mom <= 1e-9 * Ms and force == 0.0


def test_simply_supported_example_sag_against_timoshenko():
    ref = RX.simply_supported_reference(_doc("simply_supported"))
    problem = load_problem("simply_supported")
    model = build_model(problem)
    out = static_equilibrium(problem, model)
    d = model.positions(out.y) - model.positions(model.reference)
    N = model.N
    err = -d[2, N // 2] / ref["midspan"] - 1.0
    assert abs(err) < 1e-2                    # the bound; measured 1.6e-4 at N = 64
    assert abs(err) < 5e-4
    assert np.abs(d[:, [0, N]]).max() <= 1e-15  # the pins hold
    # the shape: w(x) of the reference, to the same accuracy
    x = model.positions(model.reference)[0]
    np.testing.assert_allclose(-d[2], ref["curve"](x), atol=5e-4 * ref["midspan"])
    big = out.largest
    assert big["node"] == N // 2 and big["s"] == pytest.approx(0.25, rel=1e-12)
    assert big["magnitude"] == pytest.approx(-d[2, N // 2], rel=1e-12)
    assert big["position"] == pytest.approx(model.positions(out.y)[:, N // 2].tolist())


def test_largest_displacement_only_for_rods_held_at_both_ends():
    problem = rod_problem(6, loads=GRAVITY_Z)
    model = build_model(problem)
    assert static_equilibrium(problem, model).largest is None


def test_free_free_bar_under_balanced_end_forces_stretches_by_FL_over_EA():
    """Equal and opposite axial forces at the two free ends: no net load on the six free
    motions, so the gauge holds them and the bar stretches by F L / (E A)."""
    F = 0.2
    problem = rod_problem(10, "free", "free", tau=0.0, loads=[
        {"kind": "force", "at": "start", "vector": [0.0, 0.0, -F]},
        {"kind": "force", "at": "end", "vector": [0.0, 0.0, F]}])
    model = build_model(problem)
    out = static_equilibrium(problem, model)
    assert "free-free" in out.gauge
    pos = model.positions(out.y)
    sec = sections.rectangle(0.01, 0.012, 0.3)
    stretch = pos[2, -1] - pos[2, 0] - 0.3
    assert stretch == pytest.approx(F * 0.3 / (1e6 * sec.A), rel=1e-6)  # linear: F/EA tiny
    assert np.abs(pos[:2]).max() < 1e-12


@pytest.mark.parametrize("start,end,geometry,loads,words", [
    ("free", "free", None, GRAVITY_Z, ("free-free", "net force", 'start.kind (or end.kind)')),
    ("pinned", "free", None, [{"kind": "gravity", "vector": [9.81, 0.0, 0.0]}],
     ("rotations about its pinned start", 'start.kind = "clamped"')),
    ("pinned", "pinned", ARC, [{"kind": "gravity", "vector": [0.0, 0.0, -9.81]}],
     ("chord", "moment", "clamped")),
])
def test_loads_along_a_free_motion_are_refused_before_any_work(start, end, geometry, loads,
                                                                 words, monkeypatch):
    import runtime.simulate.simulate as S

    def no_solve(*a, **k):
        raise AssertionError("solve_static ran")

    monkeypatch.setattr(S, "solve_static", no_solve)
    problem = rod_problem(8, start, end, loads=loads, geometry=geometry)
    with pytest.raises(IllPosedError) as exc:
        static_equilibrium(problem, build_model(problem))
    for w in words:
        assert w in str(exc.value), (w, str(exc.value))
    assert isinstance(exc.value, ValueError)


def test_arc_pinned_pinned_under_in_plane_gravity_solves_with_the_chord_gauged():
    geometry = {"kind": "arc", "radius": 0.2, "angle": 120.0}
    problem = rod_problem(16, "pinned", "pinned", geometry=geometry, tau=0.0,
                          loads=[{"kind": "gravity", "vector": [0.0, -9.81 * 1e-3, 0.0]}])
    model = build_model(problem)
    ref = model.positions(model.reference)
    normal = np.cross(ref[:, 4] - ref[:, 0], ref[:, 8] - ref[:, 0])
    assert abs(normal[1]) < 1e-12 * np.linalg.norm(normal)   # gravity in the arc's plane
    out = static_equilibrium(problem, model)
    assert "chord" in out.gauge
    d = model.positions(out.y) - ref
    assert np.abs(d).max() > 1e-6
    assert np.abs(normal @ d).max() < 1e-9 * np.linalg.norm(normal) * np.abs(d).max()


def test_a_gauge_that_would_hold_a_load_is_a_failed_solve():
    """A rectangle whose principal axes are not along gravity sags sideways as well; its
    weight then turns it about the line through the pins (it would swing until its centre
    of mass hangs below it): the gauge reacts, and the solve fails naming the motion."""
    problem = rod_problem(8, "pinned", "pinned", tau=0.0, loads=[     # rod along e3
        {"kind": "gravity", "vector": [-6.0, -8.0, 0.0]}],
        section={"kind": "rectangle", "width": 0.01, "height": 0.02})
    with pytest.raises(StaticSolveError, match="gauge holding them reacts") as exc:
        static_equilibrium(problem, build_model(problem))
    assert 'start.kind (or end.kind) = "clamped"' in str(exc.value)
    assert exc.value.y is not None


def test_too_soft_for_double_precision_is_refused():
    problem = rod_problem(6, "clamped", "free", loads=GRAVITY_Z, youngs_modulus=1e-300)
    with pytest.raises(IllPosedError, match="double precision") as exc:
        static_equilibrium(problem, build_model(problem))
    assert "material.youngs_modulus" in str(exc.value)
    problem = rod_problem(6, "clamped", "free", loads=GRAVITY_Z, youngs_modulus=1e-12)
    with pytest.raises(IllPosedError, match="would strain it by"):
        static_equilibrium(problem, build_model(problem))


def test_simply_supported_reference_limits():
    """references/supported.py against its own limits: Euler-Bernoulli for a rigid shear
    and no rotary inertia, the free-free roots of cos x cosh x = 1."""
    kw = {"L": 0.5, "rho": 7850.0, "A": 1e-4, "E": 2.1e11, "I": 1e-8 / 12}
    eb = supported.simply_supported_euler_bernoulli_frequencies(3, **kw)
    tim = supported.simply_supported_timoshenko_frequencies(3, kGA=1e30, rotary_inertia=False,
                                                            **kw)
    np.testing.assert_allclose(tim, eb, rtol=1e-12)
    assert np.all(supported.simply_supported_timoshenko_frequencies(3, kGA=6.9e6, **kw) < eb)
    roots = supported.free_free_euler_bernoulli_roots(3)
    np.testing.assert_allclose(roots, [4.730040744862704, 7.853204624095838,
                                       10.995607838001671], rtol=1e-12)
    # free-free Timoshenko -> Euler-Bernoulli for a slender beam (rotary inertia ~ (r/L)^2)
    slender = dict(kw, I=1e-12 / 12, A=1e-6)
    w = supported.free_free_timoshenko_frequencies(2, kGA=1e30, rotary_inertia=False,
                                                   **slender)
    w_eb = roots[:2] ** 2 * np.sqrt(slender["E"] * slender["I"]
                                    / (slender["rho"] * slender["A"] * 0.5**4))
    np.testing.assert_allclose(w, w_eb, rtol=1e-10)
    w_ri = supported.free_free_timoshenko_frequencies(2, kGA=1e30, **slender)
    assert np.all(w_ri < w) and np.all(w_ri > (1 - 1e-4) * w)
    # the sag's curve integrates to the midspan value and vanishes at the supports
    c = supported.simply_supported_uniform_load_curve(np.array([0.0, 0.25, 0.5]), 7.7,
                                                      L=0.5, EI=175.0, kGA=6.9e6)
    assert c[0] == 0.0 and abs(c[2]) < 1e-20
    assert c[1] == pytest.approx(supported.simply_supported_uniform_load_deflection(
        7.7, L=0.5, EI=175.0, kGA=6.9e6), rel=1e-14)
