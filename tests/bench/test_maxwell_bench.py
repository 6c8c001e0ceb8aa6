"""The Maxwell bench section (``python -m bench --only maxwell``) at a tiny size, its
error measure and rtol scan, and the IDAS script's ``--problem`` path."""

from __future__ import annotations

import json
import math
import shutil

import numpy as np
import pytest

pytest.importorskip("casadi")

from bench import maxwell as mx  # noqa: E402

TINY = mx.Size(N=6, T=2.0, ref_rtol=1e-8, ladder=(3e-6, 1e-6, 3e-7), repeats=1,
               budget=30.0)


def _need_cc():
    if shutil.which("cc") is None and shutil.which("gcc") is None:
        pytest.skip("no C compiler: the SUNDIALS opponents need one")


@pytest.fixture(scope="module")
def tiny():
    _need_cc()
    return mx.run(size=TINY, log=lambda msg: None)


def test_references_agree_and_are_independent(tiny):
    """kvrod and IDAS at rtol 1e-8 (every unknown in the error test) agree on the first
    tip maximum, far below kvrod's default error."""
    ref = tiny["reference"]
    assert ref["rtol"] == 1e-8
    assert ref["maxima_compared"] >= 1
    assert ref["kvrod"]["integrator"].startswith("kvrod")
    assert ref["idas"]["integrator"].startswith("idas")
    assert ref["max_diff_x"] < 1e-6
    assert ref["max_diff_t"] < 1e-4
    assert 0 < tiny["kvrod"]["error"] < 1e-3
    assert tiny["targets"][0]["verdict"] in ("met", "missed")


def test_matched_runs_are_at_least_as_accurate_as_kvrod(tiny):
    E = tiny["kvrod"]["error"]
    assert tiny["configs"], "no SUNDIALS configuration ran"
    assert tiny["configs"][0]["config"].startswith("idas")
    assert "velocities out of the error test" in tiny["configs"][0]["config"]
    for c in tiny["configs"]:
        assert c["scan"], c["config"]
        assert {r["rtol"] for r in c["scan"]} <= set(TINY.ladder)
        m = c["matched"]
        if m is None:
            assert c["stopped"], c["config"]
            continue
        assert m["pass"] and m["error"] <= E, c["config"]
        assert m["rtol"] in TINY.ladder
        assert c["timing"]["median"] > 0 and c["ratio_to_kvrod"] > 0
        passing = [r for r in c["scan"] if r["pass"]]
        assert m["wall"] == min(r["wall"] for r in passing)
        assert c["loosest_passing"] == max(r["rtol"] for r in passing)


def test_document_and_markdown(tiny):
    from runtime.io.results import jsonable

    doc = json.loads(json.dumps(jsonable(tiny, nonfinite="null")))
    for key in ("N", "n", "T", "reference", "kvrod", "kvrod_state", "kelvin_voigt",
                "configs", "skipped", "strongest", "ratio_strongest_over_kvrod",
                "ratio_maxwell_over_kelvin_voigt", "protocol", "walls_include",
                "targets", "meta"):
        assert key in doc, key
    assert doc["N"] == TINY.N and doc["T"] == TINY.T
    assert doc["kvrod"]["timing"]["median"] > 0
    assert doc["kelvin_voigt"]["problem"] == "cantilever"
    assert doc["kvrod"]["problem"] == "maxwell_cantilever"
    names = [c["config"] for c in doc["configs"]] + [s["config"] for s in doc["skipped"]]
    assert sum("stability limit detection" in n for n in names) == 1
    for s in doc["skipped"]:
        assert "stability_limit_detection" in s["why"]
    for t in doc["targets"]:
        assert t["verdict"] in ("met", "missed", "not measured")
    md = "\n".join(mx.markdown(doc))
    assert md.startswith("## 8. Generalized Maxwell rods")
    assert "nan" not in md and "``" not in md
    for n in names:
        assert n in md
    assert f"{doc['kvrod']['error']:.2e}" in md


def test_too_short_a_run_is_refused():
    _need_cc()
    with pytest.raises(ValueError, match="T = 0.3 s is outside the allowed range"):
        mx.run(size=mx.Size(4, 0.3, 1e-7, (1e-6,), 1, 30.0), log=lambda msg: None)
    with pytest.raises(ValueError, match="ladder"):
        mx.run(size=mx.Size(4, 0.3, 1e-7, (1e-5,), 1, 30.0), log=lambda msg: None)


def test_maxima_error():
    refs = {"a": {"peaks_t": [1.0, 2.0], "peaks_x": [0.1, 0.05]},
            "b": {"peaks_t": [1.0, 2.0001], "peaks_x": [0.1, 0.0502]}}
    run = {"peaks_t": [1.001, 2.0, 3.0], "peaks_x": [0.1001, 0.05, 0.02]}
    e = mx.maxima_error(run, refs)
    assert e["against"]["a"]["x"] == pytest.approx(1e-4)
    assert e["error"] == pytest.approx(2e-4)          # against b, the worse
    assert e["error_t"] == pytest.approx(1e-3)
    short = mx.maxima_error({"peaks_t": [1.0], "peaks_x": [0.1]}, refs)
    assert math.isinf(short["error"])
    t, x = mx.first_maxima(np.array([0.0, 1.0, 2.0]), np.array([0.2, 0.1, 0.05]), k=1)
    assert t == [1.0] and x == [0.1]                  # the release at t = 0 is no maximum


def _fake(errors: dict[float, float], walls: dict[float, float] | None = None):
    """A runner whose error at rtol is ``errors[rtol]`` (one maximum, reference 0)."""
    def runner(rtol):
        return {"ok": True, "rtol": rtol, "wall": (walls or {}).get(rtol, 1.0), "steps": 10,
                "peaks_t": [1.0], "peaks_x": [errors[rtol]]}
    return runner


REF0 = {"r": {"peaks_t": [1.0], "peaks_x": [0.0]}}
LAD = (1e-5, 3e-6, 1e-6, 3e-7, 1e-7)


def test_scan_goes_looser_from_a_pass_and_tighter_from_a_fail():
    errs = {1e-5: 9.0, 3e-6: 2.0, 1e-6: 1.0, 3e-7: 0.5, 1e-7: 0.1}
    s = mx.scan(_fake(errs), REF0, 2.0, LAD, start=1e-6)
    assert s["matched"]["rtol"] == 1e-6 and s["loosest_passing"] == 3e-6  # equal walls
    assert [r["rtol"] for r in s["scan"]] == [1e-6, 3e-6, 1e-5]
    s = mx.scan(_fake(errs, {1e-6: 2.0, 3e-6: 0.5, 1e-5: 0.7}), REF0, 2.0, LAD, start=1e-6)
    assert s["matched"]["rtol"] == 3e-6 and s["loosest_passing"] == 3e-6
    s = mx.scan(_fake(errs, {1e-6: 0.4, 3e-6: 0.5}), REF0, 2.0, LAD, start=1e-6)
    assert s["matched"]["rtol"] == 1e-6 and s["loosest_passing"] == 3e-6
    s = mx.scan(_fake(errs), REF0, 0.2, LAD, start=1e-6)
    assert s["matched"]["rtol"] == 1e-7
    assert [r["rtol"] for r in s["scan"]] == [1e-6, 3e-7, 1e-7]
    s = mx.scan(_fake(errs), REF0, 0.01, LAD, start=1e-6)
    assert s["matched"] is None and "no rtol down to 1e-07" in s["stopped"]
    s = mx.scan(_fake(errs), REF0, 0.01, LAD, start=1e-6, budget=0.5)
    assert s["matched"] is None and "budget" in s["stopped"]
    assert len(s["scan"]) == 1
    assert all("peaks_x" not in r for r in s["scan"])


def test_idas_script_refuses_a_bad_problem(capsys):
    from bench.idas_script import main

    with pytest.raises(SystemExit) as exc:
        main(["--problem", "nonesuch", "--n-elements", "4"])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert "--problem nonesuch" in err and "unknown problem" in err


def test_idas_script_maxwell_tip_agrees_with_kvrod():
    """IDAS on the Maxwell rod (relaxation terms in the kernels opponent) and kvrod, both
    at rtol 1e-8: the tip trajectories agree (the check of the --problem path)."""
    _need_cc()
    from bench.idas_script import build_function, integrate, released_rod
    from runtime.problem.registry import load_problem
    from runtime.simulate.simulate import simulate

    N, T = 6, 0.3
    p = load_problem("maxwell_cantilever", {"rod.elements": N, "simulation.t_end": T,
                                            "simulation.rtol": 1e-8})
    res = simulate(p)
    assert res.status == "finished"
    rod = released_rod(N, T, 1e-8, problem="maxwell_cantilever")
    assert rod.default_error_control() == "configuration"
    assert rod.model.q_segment_index.size > 0     # internal strains are state entries
    opp = build_function(rod, "ode", "kernels")
    for ec in ("configuration", "state"):
        run = integrate(rod, opp, T, p.simulation.output_step, 1e-8, None, "idas",
                        error_control=ec)
        assert run.ok, run.message
        np.testing.assert_allclose(run.t, res.t, atol=1e-12)
        assert np.max(np.abs(run.tip_x - res.tip[0])) < 2e-6


def test_max_order_reaches_both_solvers():
    """The BDF order cap reaches IDAS and CVODES (CasADi's CVODES ignores
    ``max_multistep_order``: integrate sets ``max_order`` too)."""
    _need_cc()
    from bench.idas_script import build_function, integrate, released_rod

    rod = released_rod(4, 0.2, 1e-6, problem="maxwell_cantilever")
    for solver in ("idas", "cvodes"):
        opp = build_function(rod, "ode", "kernels", error_control="configuration")
        steps = {}
        for order in (1, 5):
            run = integrate(rod, opp, 0.2, 0.005, 1e-6, None, solver,
                            error_control="configuration", max_order=order)
            assert run.ok, run.message
            assert f"max order {order}" in run.label
            steps[order] = run.steps
        assert steps[1] != steps[5], (solver, steps)
