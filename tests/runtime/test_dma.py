"""`kvrod calibrate --dma`: a Prony series fitted to storage and loss moduli.

Synthetic DMA data come from the independent reference solid
(``references.viscoelastic_material``: a 3-branch generalized Maxwell material, uniaxial
complex modulus ``E(i omega)``) with 1 % noise; the fit must reproduce the noise-free
moduli, the material table it writes must be one kvrod accepts, and that material's
complex modulus (through the derived rod-level series) must be the fitted one."""

from __future__ import annotations

import subprocess
import sys
import tomllib

import numpy as np
import pytest

from references import viscoelastic_material as vm
from runtime.analysis import dma
from runtime.problem.materials import material_from_mapping


def _solid(nu: float = 0.45) -> vm.GeneralizedMaxwell:
    def gk(E):
        return tuple(float(np.real(x)) for x in vm.shear_bulk_from_E_nu(E, nu))

    G, K = gk(1e6)
    br = [gk(E) for E in (3e6, 1e6, 5e5)]
    return vm.GeneralizedMaxwell(G, K, [b[0] for b in br], [b[1] for b in br],
                                 [1e-3, 1e-2, 1e-1])


def _write_data(path, noise=0.01, seed=1):
    f = np.logspace(-1, 3, 25)
    Es = _solid().E(1j * 2 * np.pi * f)
    rng = np.random.default_rng(seed)
    n = 1 + noise * rng.standard_normal((2, f.size))
    rows = ["frequency_hz,storage,loss"] + [f"{float(a)!r},{float(b)!r},{float(c)!r}" for a, b, c in
                                            zip(f, Es.real * n[0], Es.imag * n[1],
                                                strict=True)]
    path.write_text("\n".join(rows) + "\n")
    return 2 * np.pi * f, Es


def test_fit_reproduces_the_moduli_and_gives_a_usable_material(tmp_path):
    omega, Es = _write_data(tmp_path / "dma.csv")
    fit = dma.fit_prony(*dma.load_dma(tmp_path / "dma.csv"), poisson_ratio=0.45)
    assert fit.accepted and fit.rel_rms < 0.03
    Ep, Epp = fit.moduli(omega)
    np.testing.assert_allclose(Ep, Es.real, rtol=0.03)
    np.testing.assert_allclose(Epp, Es.imag, rtol=0.05)
    assert fit.E_inf == pytest.approx(1e6, rel=0.05)
    mat = material_from_mapping(fit.material(1100.0))
    E_rod, _ = mat.complex_moduli(omega)
    np.testing.assert_allclose(E_rod.real, Ep, rtol=1e-8)    # the same series, derived
    np.testing.assert_allclose(E_rod.imag, Epp, rtol=1e-8)
    assert all(t["std_E"] > 0 for t in fit.summary()["terms"])


def test_noise_free_data_within_one_percent_and_a_coarse_grid_is_flagged():
    """Noise-free data of three Debye terms: the default grid (3 per decade, none on the
    true times) matches both moduli within 1 %; one time per decade cannot, and the fit
    says so instead of returning it as good."""
    f = np.logspace(-1, 3, 25)
    omega, Es = 2 * np.pi * f, _solid().E(1j * 2 * np.pi * f)
    fit = dma.fit_prony(omega, Es.real, Es.imag, poisson_ratio=0.45)
    Ep, Epp = fit.moduli(omega)
    assert fit.accepted
    np.testing.assert_allclose(Ep, Es.real, rtol=0.01)
    np.testing.assert_allclose(Epp, Es.imag, rtol=0.02)
    coarse = dma.fit_prony(omega, Es.real, Es.imag, poisson_ratio=0.45, per_decade=1.0)
    assert not coarse.accepted and "relative RMS residual" in coarse.doubts[0]


def test_cli_writes_material_and_refuses_bad_input(tmp_path):
    _write_data(tmp_path / "dma.csv")
    out = tmp_path / "fit"
    run = [sys.executable, "-m", "kvrod", "calibrate", "--dma", str(tmp_path / "dma.csv")]
    r = subprocess.run(run + ["--nu", "0.45", "--out", str(out)], capture_output=True,
                       text=True)
    assert r.returncode == 0, r.stderr
    table = tomllib.loads((out / "material.toml").read_text())["material"]
    assert table["model"] == "generalized_maxwell" and len(table["branches"]) >= 3
    material_from_mapping(table)
    r = subprocess.run(run + ["--out", str(tmp_path / "x")], capture_output=True, text=True)
    assert r.returncode == 2 and "--nu" in r.stderr
    bad = tmp_path / "bad.csv"
    bad.write_text("frequency_hz,storage,loss\n1,1e6,1e5\n2,-1e6,1e5\n3,1e6,1e5\n")
    r = subprocess.run([sys.executable, "-m", "kvrod", "calibrate", "--dma", str(bad),
                        "--nu", "0.4", "--out", str(tmp_path / "y")], capture_output=True,
                       text=True)
    assert r.returncode == 2 and "line 3" in r.stderr and "storage" in r.stderr
    assert not (tmp_path / "y").exists()
