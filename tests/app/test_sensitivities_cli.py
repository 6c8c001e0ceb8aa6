"""`kvrod simulate / static --sensitivities` (issue 34): sensitivities.npz shaped like the
channels of series.npz and static.npz, stored under the name asked and its alias,
summary.json's record and counters, and bad names refused in one line before anything is
written."""

from __future__ import annotations

import json

import numpy as np
import pytest

from kvrod.cli import main


def test_simulate_writes_sensitivities_beside_the_series(tmp_path, capsys):
    out = tmp_path / "run"
    assert main(["simulate", "cantilever", "--t-end", "0.2", "--n-elements", "6",
                 "--sensitivities", "material.youngs_modulus,tau_S", "--out", str(out)]) == 0
    assert "sensitivities.npz" in capsys.readouterr().out
    series = np.load(out / "series.npz")
    sens = np.load(out / "sensitivities.npz")
    for name in ("material.youngs_modulus", "youngs_modulus", "tau_S"):
        assert sens[f"tip/{name}"].shape == series["tip"].shape
        assert sens[f"start/{name}"].shape == series["start"].shape
        assert sens[f"centreline/{name}"].shape == series["centreline"].shape
        assert sens[f"end_rotation/{name}"].shape == series["end_rotation"].shape
    assert np.array_equal(sens["t"], series["t"])
    assert np.array_equal(sens["tip/youngs_modulus"], sens["tip/material.youngs_modulus"])
    rec = sens["parameters"]
    assert list(rec["name"]) == ["material.youngs_modulus", "tau_S"]
    assert list(rec["value"]) == [1e6, 0.04]
    s = json.loads((out / "summary.json").read_text())
    assert s["counters"]["nfevS"] > 0 and "nsetupS" in s["counters"]
    assert s["sensitivities"]["parameters"] == {"material.youngs_modulus": 1e6, "tau_S": 0.04}


def test_static_writes_sensitivities_of_its_positions(tmp_path):
    out = tmp_path / "static"
    assert main(["static", "cantilever", "--n-elements", "6", "--sensitivities", "E,width",
                 "--out", str(out)]) == 0
    st = np.load(out / "static.npz")
    sens = np.load(out / "sensitivities.npz")
    assert sens["positions/E"].shape == st["positions"].shape
    assert sens["y/width"].shape == st["y"].shape
    assert np.array_equal(sens["tip/E"], sens["positions/E"][:, -1])
    assert sens["tip/E"][0] < 0.0 < sens["tip/width"][2]   # stiffer: less deflection


@pytest.mark.parametrize("names,words", [
    ("rod.elements", "count of elements"), ("youngs_modulos", "close: youngs_modulus"),
    ("simulation.rtol", "setting of the run"), ("E,,tau", "comma")])
def test_bad_names_one_line_nothing_written(tmp_path, capsys, names, words):
    out = tmp_path / "bad"
    assert main(["simulate", "cantilever", "--sensitivities", names, "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert words in err and len(err.strip().splitlines()) == 1
    assert not out.exists()
