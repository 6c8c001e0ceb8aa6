"""Calibration of tau from measured decay (issue 7 item 3) and the `modes`/`calibrate` CLI."""

from __future__ import annotations

import json

import numpy as np
import pytest

from kvrod import cli_analysis
from kvrod.cli import CliError, _Parser
from runtime.analysis.decay import damping_ratios
from runtime.analysis.records import load_csv
from runtime.problem.registry import load_problem
from runtime.simulate.simulate import simulate
from runtime.study import calibration as cal


def parse(argv):
    p = _Parser(prog="kvrod")
    sub = p.add_subparsers(dest="command", required=True, parser_class=_Parser)
    cli_analysis.add_commands(sub, _Parser)
    return p.parse_args(argv)


@pytest.fixture(scope="module")
def synthetic_signal():
    """Tip x after release, tau = 0.05 s (N = 16, as the calibration model), 1 mm noise."""
    tau = 0.05
    sc = load_problem("cantilever", {"tau": tau, "n_elements": 16, "t_end": 4.0,
                                     "output_step": 0.01})
    run = simulate(sc)
    assert run.status == "finished"
    rng = np.random.default_rng(7)
    return tau, run.t, run.tip[0] + 1e-3 * rng.standard_normal(run.t.size)


def test_signal_fit_recovers_tau(synthetic_signal, tmp_path):
    """Measured: tau = 0.04995 s (-0.1 %), SE 4.4e-5 s; the CI contains the true value."""
    tau, t, x = synthetic_signal
    res = cal.calibrate_signal(t, x)
    assert res.success
    assert res.ci95[0] < tau < res.ci95[1]
    assert res.tau == pytest.approx(tau, rel=1e-2)
    assert 0 < res.std_error < 1e-3
    assert res.residual_rms == pytest.approx(1e-3, rel=0.2)  # the noise level
    assert res.fit_y.shape == res.fit_t.shape
    path = cal.plot_calibration(res, tmp_path / "fit.png")
    assert path.stat().st_size > 1000


def test_decrement_fit_recovers_tau():
    tau = 0.03
    problem = load_problem("cantilever", {"n_elements": 8})
    model = cal.decrement_model(problem)
    rng = np.random.default_rng(3)
    d = model(tau) + 0.01 * rng.standard_normal(8)
    res = cal.calibrate_decrements(d, problem=problem)
    assert res.ci95[0] < tau < res.ci95[1]
    assert res.tau == pytest.approx(tau, rel=0.05)
    # proportional damping: the modal decrement is linear in zeta = omega_1 tau / 2
    z = damping_ratios([model(0.02)])[0]
    assert z == pytest.approx(2 * damping_ratios([model(0.01)])[0], rel=1e-6)


@pytest.mark.parametrize(
    "t, x, match",
    [
        (np.linspace(0, 1, 5), np.cos(np.linspace(0, 1, 5)), "too short"),
        (np.linspace(0, 4, 200), np.where(np.arange(200) == 50, np.nan,
                                          np.cos(6 * np.linspace(0, 4, 200))), "NaN"),
        (np.r_[np.linspace(0, 2, 100), np.linspace(1.9, 4, 100)],
         np.cos(6 * np.r_[np.linspace(0, 2, 100), np.linspace(1.9, 4, 100)]), "monotone"),
        (np.linspace(0, 4, 200), -np.exp(-np.linspace(0, 4, 200)), "no maxima"),
        (np.linspace(0, 1.2, 200), np.sin(6 * np.linspace(0, 1.2, 200)), "too few maxima"),
        (np.linspace(0, 4, 200), np.ones(199), "differ in length"),
    ],
)
def test_bad_signal(t, x, match):
    with pytest.raises(ValueError, match=match):
        cal.validate_signal(t, x)
    with pytest.raises(ValueError, match=match):
        cal.calibrate_signal(t, x)


def test_signal_maxima_ignore_noise():
    t = np.linspace(0, 4, 801)
    rng = np.random.default_rng(0)
    x = 0.2 * np.exp(-0.3 * t) * np.cos(2 * np.pi * t) + 1e-3 * rng.standard_normal(t.size)
    tk, xk = cal.signal_maxima(t, x)
    assert tk == pytest.approx([0, 1, 2, 3, 4][: tk.size], abs=0.03)
    assert tk.size in (4, 5)


@pytest.mark.parametrize("d, match", [([0.3], "too few"), ([0.3, np.nan], "NaN"),
                                      ([0.3, -0.1], "> 0")])
def test_bad_decrements(d, match):
    with pytest.raises(ValueError, match=match):
        cal.calibrate_decrements(d)


def test_load_csv(tmp_path):
    f = tmp_path / "d.csv"
    f.write_text("# measured\nT,X\n0,0.2\n0.1,0.19\n0.2,0.18\n")
    t, x = load_csv(f, ("t", "x"))
    assert t.tolist() == [0, 0.1, 0.2] and x.tolist() == [0.2, 0.19, 0.18]
    # a gap or a typo is refused naming the file's line and column (issue 22)
    f.write_text("# measured\nT,X\n0,0.2\n0.1,0.19\n0.2,\n")
    with pytest.raises(ValueError, match="line 5, column 'x': the cell is empty"):
        load_csv(f, ("t", "x"))
    f.write_text("T,X\n0,0.2\n0.1,O.19\n")
    with pytest.raises(ValueError, match="line 3, column 'x': 'O.19' is not a finite"):
        load_csv(f, ("t", "x"))
    g = tmp_path / "delta.csv"
    g.write_text("0.4\n0.42\n")
    (d,) = load_csv(g, ("delta",))
    assert d.tolist() == [0.4, 0.42]
    with pytest.raises(ValueError, match="no column 'x'"):
        load_csv(_write(tmp_path, "t,y\n0,1\n"), ("t", "x"))
    with pytest.raises(ValueError, match="does not exist"):
        load_csv(tmp_path / "missing.csv", ("t", "x"))
    with pytest.raises(ValueError, match="empty"):
        load_csv(_write(tmp_path, "# nothing\n"), ("t", "x"))


def _write(tmp_path, text: str):
    p = tmp_path / f"f{abs(hash(text))}.csv"
    p.write_text(text)
    return p


# ----------------------------------------------------------------------------- CLI
def test_cli_calibrate_decrements(tmp_path, capsys):
    model = cal.decrement_model(load_problem("cantilever", {"n_elements": 8}))
    data = tmp_path / "delta.csv"
    data.write_text("delta\n" + "\n".join(f"{model(0.04) * (1 + e):.6f}"
                                          for e in (0.01, -0.01, 0.005, -0.004)))
    args = parse(["calibrate", "--data", str(data), "--mode", "decrements",
                  "--n-elements", "8", "--out", str(tmp_path / "out")])
    assert args.func(args) == 0
    out = capsys.readouterr().out
    assert "95 % CI" in out
    js = json.loads((tmp_path / "out" / "calibration.json").read_text())
    assert js["tau"] == pytest.approx(0.04, rel=0.01)
    assert js["ci95"][0] < 0.04 < js["ci95"][1]
    assert (tmp_path / "out" / "calibration.png").exists()


def test_cli_calibrate_bad_data(tmp_path):
    data = tmp_path / "bad.csv"
    data.write_text("t,x\n0,0.1\n0.1,0.2\n0.05,0.1\n")
    args = parse(["calibrate", "--data", str(data), "--out", str(tmp_path / "o")])
    with pytest.raises(CliError, match="bad.csv: signal too short"):
        args.func(args)
    assert not (tmp_path / "o").exists()          # rejected before anything is written


def test_cli_modes(tmp_path, capsys):
    args = parse(["modes", "cantilever", "--n-elements", "8", "--count", "4", "--plots",
                  "--out", str(tmp_path / "m")])
    assert args.func(args) == 0
    out = capsys.readouterr().out
    assert "bending-2" in out and "analytic omega" in out
    js = json.loads((tmp_path / "m" / "modes.json").read_text())
    assert len(js["modes"]) == 4 and js["modes"][0]["zeta"] == pytest.approx(0.0712, abs=2e-3)
    assert (tmp_path / "m" / "mode_shapes.png").stat().st_size > 1000
    args = parse(["modes", "cantilever", "--n-elements", "8", "--count", "2", "--deformed",
                  "--tau", "0.02", "--out", str(tmp_path / "d")])
    assert args.func(args) == 0
    js = json.loads((tmp_path / "d" / "modes.json").read_text())
    assert js["deformed"] and js["static_tip"][0] > 0.2


def test_cli_modes_errors():
    from runtime.problem.registry import ProblemFileError

    with pytest.raises(ProblemFileError, match="unknown problem"):
        a = parse(["modes", "beam"])
        a.func(a)
    with pytest.raises(CliError, match="count"):
        a = parse(["modes", "cantilever", "--count", "0"])
        a.func(a)
    with pytest.raises(CliError):
        parse(["calibrate"])  # --data is required
