"""Plots of runs (matplotlib, Agg backend; axes labelled with units).

:func:`plot_run` / :func:`plot_folder` draw any run (end displacements, energies, damping
ratio per cycle when maxima were tracked); the others are the paper's figures for the
cantilever reproduction. Only on request (``kvrod simulate --plots`` or ``kvrod plot
DIR``): drawing costs more than a short simulation.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from runtime.analysis.decay import damping_ratios, exponential_envelope, log_decrements


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _save(fig, path: Path) -> Path:
    from runtime.io.atomic import save_figure

    try:
        return save_figure(fig, path, dpi=120, bbox_inches="tight")
    finally:
        _plt().close(fig)


def plot_tip(runs: Sequence, labels: Sequence[str], path: Path, envelopes: bool = True) -> Path:
    """Tip x(t) like the paper's Fig. 3, with exponential envelopes fitted to the later
    (linear) maxima."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(8, 4.5))
    for run, label in zip(runs, labels, strict=True):
        line, = ax.plot(run.t, run.tip[0], lw=1.0, label=label)
        if envelopes and run.peaks_x.size >= 4:
            fit = exponential_envelope(run.peaks_t, run.peaks_x, first=max(0, run.peaks_x.size - 4))
            tt = np.linspace(0, run.t[-1], 200)
            ax.plot(tt, fit(tt), "--", color=line.get_color(), lw=0.8)
            ax.plot(tt, -fit(tt), "--", color=line.get_color(), lw=0.8)
    ax.set_xlabel("time t after release [s]")
    ax.set_ylabel("tip displacement x(t) = e1 . phi(L, t) [m]")
    ax.axhline(0, color="0.7", lw=0.5)
    ax.legend()
    ax.set_title("Damped cantilever after release (dashed: envelope fitted to the last maxima)")
    return _save(fig, path)


def plot_damping_vs_amplitude(runs: Sequence, labels: Sequence[str], predictions: Sequence[float],
                              path: Path) -> Path:
    """Damping ratio per cycle zeta_k against the cycle's first amplitude x_k, with the
    linear prediction omega_1 tau_E / 2."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(7, 4.5))
    for run, label, zlin in zip(runs, labels, predictions, strict=True):
        if run.peaks_x.size < 2:
            continue
        z = damping_ratios(log_decrements(run.peaks_x))
        line, = ax.plot(run.peaks_x[:-1], z, "o-", label=f"{label}")
        ax.axhline(zlin, color=line.get_color(), ls=":", lw=1.0)
    ax.set_xscale("log")
    ax.set_xlabel("amplitude x_k at the start of the cycle [m]")
    ax.set_ylabel("damping ratio zeta_k [-]")
    ax.set_title("Damping ratio per cycle (dotted: linear omega_1 tau_E / 2)")
    ax.legend()
    return _save(fig, path)


def plot_overlay(run_a, label_a: str, run_b, label_b: str, stretch: float, path: Path) -> Path:
    """run_b on a time axis stretched by ``stretch`` over run_a (the paper's Fig. 4)."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(8, 4.5))
    ax.plot(run_a.t, run_a.tip[0], lw=1.6, label=label_a)
    ax.plot(stretch * run_b.t, run_b.tip[0], "--", lw=1.0, label=f"{label_b}, t x {stretch:g}")
    ax.set_xlabel("time t [s]")
    ax.set_ylabel("tip displacement x [m]")
    ax.legend()
    ax.set_title("Stiffness variation with a stretched time axis")
    return _save(fig, path)


def plot_energy(run, path: Path) -> Path:
    """Kinetic, elastic, dissipated energy, external work and the relative balance error."""
    plt = _plt()
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
    a1.plot(run.t, run.kinetic, label="kinetic T")
    a1.plot(run.t, run.elastic, label="elastic W")
    a1.plot(run.t, run.dissipated, label="dissipated int 2D dt")
    if np.any(run.external_work):
        a1.plot(run.t, run.external_work, label="external work int P dt")
    a1.set_ylabel("energy [J]")
    a1.legend()
    a2.plot(run.t, run.energy_balance_rel)
    a2.set_xlabel("time t [s]")
    a2.set_ylabel("balance error [-]")
    return _save(fig, path)


def plot_ends(run, path: Path) -> Path:
    """Displacements of both ends from their initial positions over time."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(8, 4.5))
    for arr, name, style in ((run.tip, "s = L", "-"), (run.start, "s = 0", "--")):
        if arr.size == 0:
            continue
        d = arr - arr[:, :1]
        if name == "s = 0" and not np.any(d):
            continue
        for c, comp in enumerate("xyz"):
            if np.any(d[c]):
                ax.plot(run.t, d[c], style, color=f"C{c}", lw=1.0, label=f"{comp} ({name})")
    ax.set_xlabel("time t [s]")
    ax.set_ylabel("displacement from t = 0 [m]")
    ax.axhline(0, color="0.7", lw=0.5)
    ax.legend(fontsize=8)
    return _save(fig, path)


def plot_run(run, out: Path) -> list[Path]:
    """ends.png, energy.png and (with maxima) damping_ratio.png of a run into ``out``."""
    out = Path(out)
    paths = [plot_ends(run, out / "ends.png"), plot_energy(run, out / "energy.png")]
    if getattr(run, "peaks_x", np.zeros(0)).size >= 2:
        lp = run.problem.linear_prediction() if hasattr(run, "problem") else None
        paths.append(plot_damping_vs_amplitude([run], ["run"], [lp["zeta_1"] if lp else
                                                                np.nan],
                                               out / "damping_ratio.png"))
    return paths


class _Loaded:
    """A run read back from series.npz (the attributes the plots use)."""

    def __init__(self, out: Path) -> None:
        import zipfile

        path = Path(out) / "series.npz"
        try:
            with np.load(path, allow_pickle=False) as f:
                for k in ("t", "tip", "start", "kinetic", "elastic", "dissipated",
                          "external_work", "energy_balance_rel", "peaks_t", "peaks_x"):
                    setattr(self, k, np.asarray(f[k], dtype=float) if k in f.files else
                            np.zeros((3, 0) if k in ("tip", "start") else 0))
        except (OSError, ValueError, TypeError, EOFError, zipfile.BadZipFile) as exc:
            raise ValueError(f"{path} is damaged ({type(exc).__name__}: "
                             f"{' '.join(str(exc).split())[:120]}); run the problem again "
                             "(DIR/problem.toml) to rewrite it") from None
        nt = self.t.shape
        bad = [k for k in ("tip", "start") if getattr(self, k).shape[1:] != nt] + [
            k for k in ("kinetic", "elastic", "dissipated", "external_work")
            if getattr(self, k).size and getattr(self, k).shape != nt]
        if self.t.ndim != 1 or bad or self.peaks_t.shape != self.peaks_x.shape:
            raise ValueError(f"{path} is damaged (arrays {', '.join(bad) or 't/peaks'} do not "
                             f"match t of shape {nt}); run the problem again "
                             "(DIR/problem.toml) to rewrite it")


def plot_folder(out: Path) -> list[Path]:
    """The plots of :func:`plot_run` from a results folder's series.npz."""
    import json

    run = _Loaded(out)
    zlin = np.nan
    try:
        lp = json.loads((Path(out) / "summary.json").read_text()).get("linear_prediction")
        zlin = lp["zeta_1"] if lp else np.nan
    except (OSError, ValueError, KeyError, TypeError):
        pass
    out = Path(out)
    paths = [plot_ends(run, out / "ends.png"), plot_energy(run, out / "energy.png")]
    if run.peaks_x.size >= 2:
        paths.append(plot_damping_vs_amplitude([run], ["run"], [zlin],
                                               out / "damping_ratio.png"))
    return paths
