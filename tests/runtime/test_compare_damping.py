"""eta_E against eta~_E in simulation (issue 7 item 1): runtime/study/compare_damping.py.

No bulk viscosity (tau_B = 0, tau_S = 0.04 s, nu = 0.3): tau_E / tau~_E = 1 + nu = 1.3
(eq. (6) over Sect. 4.2). Measured at N = 12: ratio consistent/naive 1.2995 (bending) and
1.2993 (axial); each route within 0.1 % of omega tau / 2.
"""

from __future__ import annotations

import json
import math
import re

import numpy as np
import pytest

from runtime.io.results import write_json
from runtime.study.compare_damping import (
    compare_damping,
    measured_zeta,
    plot_compare,
    predicted_ratio,
    summary,
)


@pytest.fixture(scope="module")
def no_bulk():
    return compare_damping(n_elements=12)


@pytest.mark.parametrize("case", ["bending", "axial"])
def test_ratio_consistent_over_naive(no_bulk, case):
    c = no_bulk["cases"][case]
    assert c["predicted_ratio"] == pytest.approx(1.3, rel=1e-12)
    assert c["measured_ratio"] == pytest.approx(c["predicted_ratio"], rel=1e-2)
    for route, r in c["routes"].items():
        assert r["measured_zeta"] == pytest.approx(r["predicted_zeta"], rel=1e-2), route
        # the discrete omega is close to the continuum one (Euler-Bernoulli, bar)
        assert r["omega"] == pytest.approx(r["omega_continuum"], rel=1e-2)
        # modal pair vs omega tau / 2: equal up to the shear strain energy (damped by tau_S)
        assert r["modal_zeta"] == pytest.approx(r["predicted_zeta"], rel=1e-3)
        assert len(r["measured_zeta_per_cycle"]) >= 3
    naive = c["routes"]["naive"]
    assert naive["tau_E"] == pytest.approx((c["tau_B"] + 2 * c["tau_S"]) / 3, rel=1e-12)


def test_axial_case_is_underdamped_at_the_requested_zeta(no_bulk):
    p = no_bulk["parameters"]
    naive = no_bulk["cases"]["axial"]["routes"]["naive"]
    assert naive["predicted_zeta_continuum"] == pytest.approx(p["axial_zeta"], rel=1e-12)
    assert no_bulk["cases"]["axial"]["tau_B"] == 0.0


def test_routes_coincide_when_tau_B_equals_tau_S():
    """tau_B = tau_S: both routes give the same damping matrices (to round-off: the
    consistent one is printed as tau_B (1 - 2 nu)/3 + 2 tau_S (1 + nu)/3), hence the same
    motion to the integrator's tolerance (an ulp in a parameter changes the adaptive steps)."""
    res = compare_damping(n_elements=8, tau_S=0.04, tau_B=0.04, bending_cycles=3,
                          axial_cycles=4)
    for case, c in res["cases"].items():
        con, nai = c["routes"]["consistent"], c["routes"]["naive"]
        assert c["predicted_ratio"] == pytest.approx(1.0, rel=1e-12)
        assert con["tau_E"] == pytest.approx(nai["tau_E"], rel=1e-12)
        assert con["measured_zeta"] == pytest.approx(nai["measured_zeta"], rel=1e-5), case
        assert c["measured_ratio"] == pytest.approx(1.0, rel=1e-5)
        t1, x1 = res["series"][(case, "consistent")]
        t2, x2 = res["series"][(case, "naive")]
        np.testing.assert_allclose(x1, x2, rtol=0, atol=1e-5 * np.abs(x1).max())


@pytest.mark.parametrize("tau_B, tau_S, nu", [(0.0, 0.04, 0.3), (0.02, 0.04, 0.25),
                                               (0.04, 0.0, 0.3), (0.05, 0.05, 0.1)])
def test_predicted_ratio_formula(tau_B, tau_S, nu):
    expect = ((1 - 2 * nu) * tau_B + 2 * (1 + nu) * tau_S) / (tau_B + 2 * tau_S)
    assert predicted_ratio(tau_B, tau_S, nu) == pytest.approx(expect, rel=1e-12)


def test_measured_zeta():
    zeta = 0.05
    delta = 2 * math.pi * zeta / math.sqrt(1 - zeta**2)
    per_cycle, mean = measured_zeta(np.exp(-delta * np.arange(6)))
    assert per_cycle == pytest.approx([zeta] * 5, rel=1e-12)
    assert mean == pytest.approx(zeta, rel=1e-12)
    assert measured_zeta([1.0]) == ([], pytest.approx(math.nan, nan_ok=True))


@pytest.mark.parametrize("kw, match", [
    ({"tau_S": 0.0, "tau_B": 0.0}, "tau_B \\+ 2 tau_S"),
    ({"tau_S": -0.1}, "tau_S"),
    ({"n_elements": 1}, "n_elements"),
    ({"cases": ("torsion",)}, "cases"),
    ({"axial_zeta": 1.5}, "axial_zeta"),
    ({"bending_cycles": 1}, "bending_cycles"),
])
def test_bad_input(kw, match):
    with pytest.raises(ValueError, match=match):
        compare_damping(**kw)


def test_outputs(no_bulk, tmp_path):
    paths = plot_compare(no_bulk, tmp_path)
    assert [p.name for p in paths] == ["compare_signals.png", "compare_zeta.png"]
    assert all(p.stat().st_size > 1000 for p in paths)
    js = json.loads(write_json(tmp_path / "c.json", summary(no_bulk)).read_text())
    assert js["cases"]["bending"]["predicted_ratio"] == pytest.approx(1.3)


def test_cli_compare_damping(no_bulk, tmp_path, monkeypatch, capsys):
    """`kvrod compare-damping` formats and writes the library's result (JSON, MD, PNG)."""
    from kvrod import cli_analysis
    from kvrod.cli import _Parser

    seen = {}

    def fake(**kw):
        seen.update(kw)
        return no_bulk

    monkeypatch.setattr("runtime.study.compare_damping.compare_damping", fake)
    p = _Parser(prog="kvrod")
    sub = p.add_subparsers(dest="command", required=True, parser_class=_Parser)
    cli_analysis.add_commands(sub, _Parser)
    args = p.parse_args(["compare-damping", "--n-elements", "12", "--out", str(tmp_path)])
    assert args.func(args) == 0
    assert seen["n_elements"] == 12 and seen["tau_B"] == 0.0 and seen["poisson_ratio"] == 0.3
    out = capsys.readouterr().out
    assert "ratio consistent/naive" in out
    for name in ("compare_damping.json", "compare_damping.md", "compare_signals.png",
                 "compare_zeta.png"):
        assert (tmp_path / name).exists(), name
    md = (tmp_path / "compare_damping.md").read_text()
    assert "| bending |" in md and "predicted tau_E/tau~_E" in md


def test_notes_beyond_small(no_bulk, tmp_path, monkeypatch):
    """`kvrod notes-beyond` end to end with small settings (the template renders strictly)."""
    from reports import damping_studies as beyond

    monkeypatch.setattr("runtime.study.compare_damping.compare_damping", lambda **kw: no_bulk)
    for name, value in (("MODES_N", 8), ("CAL_DATA_N", 8), ("CAL_MODEL_N", 8),
                        ("CAL_T_END", 2.0)):
        monkeypatch.setattr(beyond, name, value)
    notes = beyond.write_beyond_notes(tmp_path / "notes" / "beyond.md", tmp_path / "res")
    text = notes.read_text()
    # the table's numbers, compared as numbers (a golden string would sit on a rounding edge)
    m = re.search(r"\| bending \| \*\*([0-9.]+)\*\* \| ([0-9.]+) \|", text)
    assert m, text
    measured = no_bulk["cases"]["bending"]["measured_ratio"]
    assert float(m.group(1)) == pytest.approx(measured, abs=6e-5)
    assert float(m.group(2)) == pytest.approx(no_bulk["cases"]["bending"]["predicted_ratio"],
                                              abs=6e-5)
    assert "kvrod modes cantilever --n-elements 8 --count 12" in text
    data = (tmp_path / "res" / "calibration" / "synthetic.csv").as_posix()
    assert f"kvrod calibrate --data {data}" in text
    for link in ("compare_signals", "compare_zeta", "mode_shapes", "mode_shapes_deformed",
                 "calibration"):
        assert f"(figures/beyond_{link}.png)" in text
        assert (tmp_path / "notes" / "figures" / f"beyond_{link}.png").exists()
