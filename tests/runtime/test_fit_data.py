"""`kvrod fit`'s data files: every refusal is one line naming the file, the line and the
column; records, static shapes and measured modes are told apart by their columns; the
model is sampled on the record's own times where they form a grid."""

from __future__ import annotations

import math

import numpy as np
import pytest

from runtime.study.fit_data import (
    DataError,
    check_against_problem,
    read_fit_data,
    series_channels,
)
from runtime.study.fit_sampling import OUTPUTS_PER_PERIOD, sampling


def csv(tmp_path, text, name="data.csv"):
    p = tmp_path / name
    p.write_text(text)
    return p


def one_line(exc) -> str:
    msg = str(exc.value)
    assert "\n" not in msg
    return msg


def test_record_subset_of_channels(tmp_path):
    p = csv(tmp_path, "# a comment\nt,end.x,end.z\n0,0.1,0.3\n0.01,0.09,0.3\n0.02,0.08,0.29\n")
    d = read_fit_data(p)
    assert d.kind == "series" and d.model == "simulate"
    assert [(c.name, c.channel, c.component) for c in d.columns] == [
        ("end.x", "tip", 0), ("end.z", "tip", 2)]
    assert d.count == 6 and d.rows == 3 and d.t_end == pytest.approx(0.02)
    assert d.lines.tolist() == [3, 4, 5]
    w = d.window(0.01)
    assert w.rows == 2 and w.columns[0].values.tolist() == [0.1, 0.09]


@pytest.mark.parametrize("text, needles", [
    ("t,end.x\n0,0.1\n0.01,nan\n", ("line 3", "'end.x'", "nan", "finite")),
    ("t,end.x\n0,0.1\n0.01,inf\n", ("line 3", "'end.x'", "inf")),
    ("t,end.x\n0,0.1\n0.01,\n", ("line 3", "'end.x'", "empty")),
    ("t,end.x\n0,0.1\nNaN,0.2\n", ("line 3", "'t'", "NaN")),
    ("t,end.x\n0,0.1\n0.02,0.2\n0.01,0.3\n", ("line 4", "'t'", "sorted")),
    ("t,end.x\n0,0.1\n0.01,0.2\n0.01,0.3\n", ("line 4", "repeats line 3")),
    ("t,end.x,tip.y\n0,0.1,0\n", ("'tip.y'", "allowed", "end.x", "start.z")),
    ("end.x,end.y\n0.1,0\n0.2,0\n", ("no column 't'",)),
    ("0,0.1\n0.01,0.2\n", ("no header",)),
    ("t,end.x\n-0.1,0.1\n0,0.2\n", ("line 2", "before the start")),
    ("t,end.x,end.x\n0,0.1,0.1\n", ("'end.x' appears twice",)),
    ("t\n0\n0.1\n", ("only the column 't'",)),
    ("", ("is empty",)),
    ("x,y,z\n1,2,3\n", ("no column 't', 's' or 'mode'",)),
])
def test_bad_records_refused_in_one_line(tmp_path, text, needles):
    with pytest.raises(DataError) as exc:
        read_fit_data(csv(tmp_path, text))
    msg = one_line(exc)
    assert "data.csv" in msg
    for n in needles:
        assert n in msg, msg


def test_missing_file_and_folder(tmp_path):
    with pytest.raises(DataError, match="does not exist"):
        read_fit_data(tmp_path / "nope.csv")
    with pytest.raises(DataError, match="directory"):
        read_fit_data(tmp_path)


def test_record_checked_against_the_problem(tmp_path):
    d = read_fit_data(csv(tmp_path, "t,end.x\n0,0.1\n2.5,0.2\n5.0,0.1\n"))
    with pytest.raises(DataError) as exc:
        check_against_problem(d, n_parameters=1, t_end=4.0)
    msg = one_line(exc)
    assert "t = 5 s" in msg and "t_end = 4 s" in msg and "--t-end 5" in msg
    with pytest.raises(DataError) as exc:
        check_against_problem(d, n_parameters=3, t_end=10.0)
    assert "3 measured values" in one_line(exc) and "at least 4" in str(exc.value)
    check_against_problem(d, n_parameters=2, t_end=5.0)


def test_assembly_channels(tmp_path):
    ch = series_channels(["left", "right"])
    assert ch["left.end.y"] == ("left.end", 1) and ch["right.start.z"] == ("right.start", 2)
    d = read_fit_data(csv(tmp_path, "t,right.end.y\n0,0\n0.1,0.01\n"), ["left", "right"])
    assert d.columns[0].channel == "right.end"
    with pytest.raises(DataError, match="'end.y' names no channel of this assembly"):
        read_fit_data(csv(tmp_path, "t,end.y\n0,0\n"), ["left", "right"])


def test_static_shape(tmp_path):
    d = read_fit_data(csv(tmp_path, "s,x,z\n0,0,0\n0.15,0.01,0.149\n0.3,0.04,0.296\n"))
    assert d.kind == "shape" and d.model == "static"
    assert [c.channel for c in d.columns] == ["positions", "positions"]
    with pytest.raises(DataError) as exc:
        check_against_problem(d, n_parameters=1, t_end=1.0, length=0.2)
    assert "s = 0.3 m lies outside the rod" in one_line(exc)
    with pytest.raises(DataError, match="one rod"):
        read_fit_data(csv(tmp_path, "s,a.x,b.x\n0,0,0\n"), ["a", "b"])
    d = read_fit_data(csv(tmp_path, "s,b.x\n0,0\n0.1,0.01\n"), ["a", "b"])
    assert d.rod == "b" and d.columns[0].channel == "b.positions"


def test_measured_modes(tmp_path):
    d = read_fit_data(csv(tmp_path, "mode,frequency_hz,zeta\n1,0.5659,0.0711\n"
                                    "bending-1:2,3.498,\n"))
    assert d.kind == "modes" and d.model == "modes"
    assert d.modes == ("1", "bending-1:2")
    omega, zeta = d.columns
    assert omega.channel == "omega" and omega.values[0] == pytest.approx(2 * math.pi * 0.5659)
    assert zeta.measured.tolist() == [True, False] and d.count == 3
    for text, needle in [("mode,omega\nbending-3:1,2\n", "names no mode"),
                         ("mode,omega\n1,2\n1,3\n", "appears twice"),
                         ("mode,omega\n1,-2\n", "must be > 0"),
                         ("mode,omega,frequency_hz\n1,2,3\n", "not both")]:
        with pytest.raises(DataError, match=needle):
            read_fit_data(csv(tmp_path, text))


def test_sampling_on_the_records_grid():
    """A logger at 5 ms with gaps and a late start: the simulation's outputs are its times."""
    t = np.array([0.2, 0.205, 0.21, 0.225, 0.23])
    s = sampling(t)
    assert s.on_grid and s.output_step == pytest.approx(0.005)
    assert s.index.tolist() == [40, 41, 42, 45, 46]
    assert s.t_end == pytest.approx(0.23)
    grid = np.arange(0.0, s.t_end + 0.5 * s.output_step, s.output_step)
    assert np.allclose(grid[s.index], t, atol=1e-12)


def test_sampling_interpolated_between_outputs():
    """Irregular times: outputs at most a hundredth of a period apart, ending on the
    record's last time; the spline error on a decaying oscillation is below 1e-6 of it."""
    rng = np.random.default_rng(1)
    t = np.sort(rng.uniform(0.0, 3.0, 300))
    period = 1.7
    s = sampling(t, period)
    assert not s.on_grid
    assert s.output_step <= period / OUTPUTS_PER_PERIOD and s.t_end == pytest.approx(t[-1])
    grid = np.arange(0.0, s.t_end + 0.5 * s.output_step, s.output_step)
    grid = grid[grid <= s.t_end]
    w = 2 * math.pi / period

    def f(x):
        return np.exp(-0.2 * x) * np.cos(w * x)

    assert np.max(np.abs(s.values(grid, f(grid), t) - f(t))) < 1e-6
