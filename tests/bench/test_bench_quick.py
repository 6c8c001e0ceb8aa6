"""The benchmark package's quick smoke run (``python -m bench --quick``) into a temporary
folder: it finishes, and every JSON document it writes records its metadata and its
targets with a verdict."""

from __future__ import annotations

import json
import shutil

import pytest

pytest.importorskip("casadi")

REQUIRED_META = ("date", "platform", "python", "numpy", "scipy", "casadi", "command")
#: the sections run here; maxwell, maxwell_kv, sections, assembly and sweeps have test
#: modules of their own that run them at smaller sizes still (running them twice cost the
#: suite minutes)
QUICK_SECTIONS = ("integrators", "scaling", "modes", "sensitivities", "fit")


@pytest.fixture(scope="module")
def quick_run(tmp_path_factory):
    if shutil.which("cc") is None and shutil.which("gcc") is None:
        pytest.skip("no C compiler: the SUNDIALS opponents need one")
    from bench.__main__ import run_all

    out = tmp_path_factory.mktemp("bench_quick")
    docs = run_all(quick=True, out_dir=out, only=QUICK_SECTIONS)
    return out, docs


def test_quick_writes_the_documents(quick_run):
    out, _ = quick_run
    for name in ("integrators.json", "scaling.json", "README.md"):
        assert (out / name).is_file(), name
    readme = (out / "README.md").read_text()
    assert "matched accuracy" in readme
    assert "us/step" in readme


@pytest.mark.parametrize("name", QUICK_SECTIONS)
def test_json_has_metadata_and_verdicts(quick_run, name):
    out, _ = quick_run
    doc = json.loads((out / f"{name}.json").read_text())
    meta = doc["meta"]
    for key in REQUIRED_META:
        assert meta.get(key), f"{name}.json: meta.{key} missing"
    assert "bench" in meta["command"]
    assert doc["targets"], f"{name}.json has no targets"
    for t in doc["targets"]:
        assert t["verdict"] in ("met", "missed", "not measured"), t
        assert t["met"] in (True, False, None)
        assert (t["met"] is None) == (t["verdict"] == "not measured")
        assert isinstance(t["target"], str) and t["limit"] > 0


def test_integrators_compares_at_matched_accuracy(quick_run):
    out, _ = quick_run
    doc = json.loads((out / "integrators.json").read_text())
    (run,) = doc["runs"]
    assert run["kvrod"]["matched"]["tip_error"] <= 1e-5
    assert run["cross_check"]["max_tip_diff"] < 1e-6   # kvrod and IDAS agree at 1e-9
    assert run["duel"]["kvrod"]["us_per_step"] > 0
    for name, res in run["opponents"].items():
        if name.startswith(("idas", "cvodes")):
            assert res["matched"] is not None, name
            assert res["matched"]["tip_error"] <= 1e-5
            assert run["duel"][name]["us_per_step"] > 0
    assert run["strongest"] in run["duel"]
    assert doc["targets"][0]["verdict"] in ("met", "missed")


def test_modes_rows_ran_and_twins_agree(quick_run):
    """The modes section: every whole-process row ran (kvrod modes of the Kelvin-Voigt and
    the Maxwell cantilever, the simulation beside them), the first damping ratios are
    those of the cantilever (zeta = omega tau / 2 for Kelvin-Voigt, tau = 0.04 s), and the
    twin bending modes of its square section agree."""
    out, _ = quick_run
    doc = json.loads((out / "modes.json").read_text())
    assert [r["kind"] for r in doc["rows"]] == ["modes", "modes", "simulate"]
    for r in doc["rows"]:
        assert r["ok"] and r["walls"] and r["median"] > 0, r
    kv = doc["rows"][0]
    assert kv["first_zeta"] == pytest.approx(kv["first_omega"] * 0.04 / 2, rel=1e-6)
    assert 0 < doc["rows"][1]["first_zeta"] < 1
    twin = doc["targets"][2]
    assert twin["verdict"] == "met", twin
    assert "Damped modes at any size" in (out / "README.md").read_text()
