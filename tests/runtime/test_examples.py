"""The examples in examples/ against references written separately (references/).

Each example is read as shipped; the references take their section constants from
:mod:`references.sections` (textbook formulas), never from the generated code. Static
cases are checked at the documented number of elements to 1e-3 relative, and their
convergence order in N is checked on coarser meshes.
"""

from __future__ import annotations

import math
import tomllib

import numpy as np
import pytest

from references import examples as RX
from runtime.problem.assemble import build_model
from runtime.problem.registry import EXAMPLES_DIR, load_problem
from runtime.simulate.simulate import simulate, static_equilibrium


def _toml(name: str) -> dict:
    return tomllib.loads((EXAMPLES_DIR / f"{name}.toml").read_text())


def _static(name: str, **overrides):
    problem = load_problem(name, overrides)
    model = build_model(problem)
    return problem, model, static_equilibrium(problem, model)


def _order(e_coarse: float, e_fine: float) -> float:
    return math.log2(abs(e_coarse) / abs(e_fine))


def test_every_example_puts_its_start_at_the_origin():
    for f in sorted(EXAMPLES_DIR.glob("*.toml")):
        if "rod" not in tomllib.loads(f.read_text()):
            continue                       # a study, not a problem
        model = build_model(load_problem(f))
        assert np.allclose(model.start_position(model.reference), 0.0, atol=1e-12), f.name


# -- roll-up ---------------------------------------------------------------------------
def test_rollup_file_applies_the_closing_moment():
    ref = RX.rollup_reference(_toml("rollup"))
    assert ref["M"] == pytest.approx(ref["closing_moment"], rel=1e-14)


def _rollup_errors(st) -> dict[float, float]:
    ref = RX.rollup_reference(_toml("rollup"))
    return {f: np.linalg.norm(tip - ref["tip"](f)) / ref["L"] for f, tip in st.path}


def test_rollup_closes_the_circle_and_passes_the_half_circle():
    _, _, st = _static("rollup")
    assert [f for f, _ in st.path] == [0.5, 1.0]
    err = _rollup_errors(st)
    assert err[0.5] < 1e-3 and err[1.0] < 1e-3, err
    assert np.linalg.norm(dict(st.path)[1.0]) < 1e-3 * 1.0   # back at the clamp (L = 1 m)


def test_rollup_converges_at_second_order():
    e = [_rollup_errors(_static("rollup", **{"rod.elements": n})[2])[1.0] for n in (40, 80)]
    assert 1.8 < _order(*e) < 2.2, e


# -- Bathe-Bolourchi 45-degree bend ------------------------------------------------------
def _bend_errors(st) -> dict[float, float]:
    ref = RX.bend45_reference(_toml("bathe_bolourchi"))
    out = {}
    for f, tip in st.path:
        r = ref["tip"](f * ref["P"])
        out[f * ref["P"]] = np.linalg.norm(tip - r) / np.linalg.norm(r)
    return out


def test_bathe_bolourchi_matches_the_converged_bend():
    doc = _toml("bathe_bolourchi")
    stiff = RX.bend45_reference(doc)["stiffness"]
    for key, value in (("EA", stiff.EA), ("GA1", stiff.GA1), ("EI1", stiff.EI1),
                       ("GJ", stiff.GJ)):
        assert doc["section"][key] == pytest.approx(value, rel=1e-15), key
    _, _, st = _static("bathe_bolourchi")
    err = _bend_errors(st)
    assert sorted(err) == [300.0, 450.0, 600.0]
    assert max(err.values()) < 1e-3, err


def test_bathe_bolourchi_converges_at_second_order():
    e = [_bend_errors(_static("bathe_bolourchi", **{"rod.elements": n})[2])[600.0]
         for n in (16, 32)]
    assert 1.8 < _order(*e) < 2.2, e


# -- helical spring ----------------------------------------------------------------------
def _axis_point_compliance(n: int | None = None) -> float:
    """Central difference of the axis point's displacement under +-F (both loads scaled),
    the arm carried by the end section's rotation."""
    ref = RX.helix_reference(_toml("helix"))
    R, F = ref["R"], ref["F"]
    assert _toml("helix")["loads"][1]["vector"] == [0.0, R * F, 0.0]   # the arm's moment
    deltas = []
    for sign in (1.0, -1.0):
        over = {"loads.0.vector": [0.0, 0.0, sign * F],
                "loads.1.vector": [0.0, sign * R * F, 0.0]}
        if n is not None:
            over["rod.elements"] = n
        _, model, st = _static("helix", **over)
        ref_y = model.reference
        r_ref, r = model.tip_position(ref_y), model.tip_position(st.y)
        c = np.array([-R, 0.0, r_ref[2]])                 # the coil axis at the end height
        rot = model.frames(st.y)[-1] @ model.frames(ref_y)[-1].T
        deltas.append((r + rot @ (c - r_ref))[2] - c[2])
    return (deltas[0] - deltas[1]) / (2.0 * F)


def test_helix_axial_stiffness_matches_the_spring_formula():
    ref = RX.helix_reference(_toml("helix"))
    got = _axis_point_compliance()
    assert got / ref["full"] - 1.0 == pytest.approx(0.0, abs=1e-3)
    # the classical formula (no extension or shear of the wire) is 0.6 % stiffer here
    gap = ref["full"] / ref["classical"] - 1.0
    assert gap > 3e-3
    assert got / ref["classical"] - 1.0 == pytest.approx(gap, abs=1e-3)


def test_helix_error_is_the_unbent_end_half_segment_plus_second_order():
    """The end moment meets a last half segment without joint: -1/(2N) relative (O(h)),
    the rest converges at second order."""
    full = RX.helix_reference(_toml("helix"))["full"]
    rest = [_axis_point_compliance(n) / full - 1.0 + 1.0 / (2 * n) for n in (200, 400)]
    assert 1.8 < _order(*rest) < 2.2, rest


# -- rod clamped at both ends ------------------------------------------------------------
def _midspan_error(n: int | None = None) -> float:
    ref = RX.clamped_both_reference(_toml("clamped_both"))
    _, model, st = _static("clamped_both", **({"rod.elements": n} if n else {}))
    pos, pos0 = model.positions(st.y), model.positions(model.reference)
    assert np.allclose(pos[:, [0, -1]], pos0[:, [0, -1]], atol=1e-15)
    return -(pos - pos0)[2, pos.shape[1] // 2] / ref["midspan"] - 1.0


def test_clamped_both_midspan_deflection():
    assert abs(_midspan_error()) < 1e-3


def test_clamped_both_converges_at_second_order():
    e = [_midspan_error(n) for n in (32, 64)]
    assert 1.8 < _order(*e) < 2.2, e


# -- pendulum ----------------------------------------------------------------------------
def test_undamped_pendulum_conserves_energy_and_swings_like_the_rigid_one():
    res = simulate(load_problem("pendulum", {"simulation.t_end": 1.5}))
    assert res.status == "finished", res.message
    audit = res.audit()
    assert audit.applicable and audit.max_rel < 1e-4, audit
    # the swing: zero crossings of the tip x (theta = 0) are a half period apart
    x = res.tip[0]
    i = np.where(np.diff(np.sign(x)) != 0)[0][:2]
    crossings = res.t[i] - x[i] * (res.t[i + 1] - res.t[i]) / (x[i + 1] - x[i])
    T = RX.pendulum_reference(_toml("pendulum"))["period"]
    assert crossings[0] == pytest.approx(T / 4, rel=3e-3)
    assert crossings[1] - crossings[0] == pytest.approx(T / 2, rel=3e-3)


def test_damped_pendulum_dissipates_and_balances_its_energy():
    """With tau = 1 ms the flexural vibrations excited by the fall decay (zeta = 0.2 for
    the first); the audit balances the dissipated energy (0.1 mJ of 12 J)."""
    res = simulate(load_problem("pendulum", {"simulation.t_end": 0.5, "material.tau": 1e-3,
                                             "simulation.rtol": 1e-8}))
    assert res.status == "finished", res.message
    audit = res.audit()
    assert audit.applicable and audit.max_rel < 1e-5, audit
    assert 5e-5 < res.dissipated[-1] < 2e-4


# -- base excitation ---------------------------------------------------------------------
def test_base_excitation_amplitude_matches_the_complex_modulus_beam():
    ref = RX.base_excitation_reference(_toml("base_excitation"))
    assert ref["T"] > 10.0                                  # near resonance indeed
    res = simulate(load_problem("base_excitation"))
    assert res.status == "finished", res.message
    # steady state: the last ten seconds, fitted by a sine at the drive frequency
    keep = res.t >= res.t[-1] - 10.0
    t, x = res.t[keep], res.tip[0][keep]
    w = ref["omega"]
    c = np.linalg.lstsq(np.column_stack([np.sin(w * t), np.cos(w * t), np.ones_like(t)]), x,
                        rcond=None)[0]
    assert math.hypot(c[0], c[1]) / ref["amplitude"] - 1.0 == pytest.approx(0.0, abs=5e-3)
