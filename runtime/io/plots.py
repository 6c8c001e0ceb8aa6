"""Plots of runs (matplotlib through :mod:`runtime.io.figures`; axes labelled with units).

:func:`plot_run` / :func:`plot_run_folder` draw any run: end displacements (ends.png),
energies (energy.png), the damping ratio per cycle when maxima were tracked
(damping_ratio.png) and the deformed centreline at a few frame times in 3-D
(centreline.png, :mod:`runtime.io.shapes`); the others are the paper's figures for the
cantilever reproduction. Only on request (``kvrod simulate --plots`` or ``kvrod plot
DIR``): drawing costs more than a short simulation. Each ``figure_*`` function returns
the matplotlib figure (for inspection), each ``plot_*`` function saves it.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from runtime.analysis.decay import damping_ratios, exponential_envelope, log_decrements
from runtime.io.figures import pyplot as _plt
from runtime.io.figures import save


def _save(fig, path: Path) -> Path:
    return save(fig, path, dpi=120, bbox_inches="tight")


def padded_limits(values: Sequence[float] | np.ndarray, margin: float = 0.08
                  ) -> tuple[float, float] | None:
    """(low, high) around the finite ``values`` with ``margin`` of their range on each
    side (of their size where they are all equal), or None if there is none."""
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v)]
    if v.size == 0:
        return None
    lo, hi = float(v.min()), float(v.max())
    pad = margin * (hi - lo) if hi > lo else margin * max(abs(hi), 1e-300)
    return lo - pad, hi + pad


def _centre_x(run) -> float:
    """The tip x the maxima of a run decay towards (its vibration centre: the reference
    plus the centre's displacement, ``SimulationResult.centre``), 0 where unknown."""
    centre, model = getattr(run, "centre", None), getattr(run, "model", None)
    if centre is None or model is None or run.problem.analysis.maxima != "end.x":
        return 0.0
    return float(model.reference[model.phi_index[-1][0]]) + centre.value


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
            c = _centre_x(run)          # the envelope about the equilibrium it decays to
            ax.plot(tt, c + fit(tt), "--", color=line.get_color(), lw=0.8)
            ax.plot(tt, c - fit(tt), "--", color=line.get_color(), lw=0.8)
    ax.set_xlabel("time t after release [s]")
    ax.set_ylabel("tip displacement x(t) = e1 . phi(L, t) [m]")
    ax.axhline(0, color="0.7", lw=0.5)
    ax.legend()
    ax.set_title("Damped cantilever after release (dashed: envelope fitted to the last maxima)")
    return _save(fig, path)


def figure_damping_vs_amplitude(runs: Sequence, labels: Sequence[str],
                                predictions: Sequence[float]):
    """Damping ratio per cycle zeta_k against the cycle's first amplitude x_k, with the
    linear prediction (e.g. omega_1 tau_E / 2) as a dotted line; y-limits hold the data
    and the predictions with margins, the amplitude axis is logarithmic where it spans
    more than a factor 4."""
    from matplotlib.ticker import FormatStrFormatter, LogLocator, NullFormatter

    plt = _plt()
    fig, ax = plt.subplots(figsize=(7, 4.5))
    ys: list[float] = []
    xs: list[float] = []
    for run, label, zlin in zip(runs, labels, predictions, strict=True):
        if run.peaks_x.size < 2:
            continue
        z = damping_ratios(log_decrements(run.peaks_x))
        line, = ax.plot(run.peaks_x[:-1], z, "o-", label=f"{label}")
        ys += list(z)
        xs += list(run.peaks_x[:-1])
        if math.isfinite(zlin):
            ax.axhline(zlin, color=line.get_color(), ls=":", lw=1.2,
                       label=f"{label}: linear {zlin:.4g}")
            ys.append(zlin)
    lim = padded_limits(ys, 0.12)
    if lim is not None:
        ax.set_ylim(*lim)
    x = np.asarray(xs, dtype=float)
    x = x[np.isfinite(x) & (x > 0)]
    if x.size and x.max() > 4 * x.min():
        ax.set_xscale("log")
        ax.xaxis.set_major_locator(LogLocator(subs=(1.0, 2.0, 5.0)))
        ax.xaxis.set_major_formatter(FormatStrFormatter("%g"))
        ax.xaxis.set_minor_formatter(NullFormatter())
    ax.set_xlabel("amplitude x_k at the start of the cycle [m]")
    ax.set_ylabel("damping ratio zeta_k [-]")
    ax.set_title("Damping ratio per cycle (dotted: linear omega_1 tau_E / 2)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="best")
    return fig


def plot_damping_vs_amplitude(runs: Sequence, labels: Sequence[str], predictions: Sequence[float],
                              path: Path) -> Path:
    """:func:`figure_damping_vs_amplitude` as PNG."""
    return _save(figure_damping_vs_amplitude(runs, labels, predictions), path)


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


def figure_energy(run):
    """Kinetic, elastic, dissipated energy, external work and the relative balance error
    (legend outside the axes, right of the data)."""
    plt = _plt()
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
    a1.plot(run.t, run.kinetic, label="kinetic T")
    a1.plot(run.t, run.elastic, label="elastic W")
    a1.plot(run.t, run.dissipated, label="dissipated int 2D dt")
    if np.any(run.external_work):
        a1.plot(run.t, run.external_work, label="external work int P dt")
    a1.set_ylabel("energy [J]")
    a1.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, frameon=False)
    a2.plot(run.t, run.energy_balance_rel)
    a2.set_xlabel("time t [s]")
    a2.set_ylabel("balance error [-]")
    return fig


def plot_energy(run, path: Path) -> Path:
    """:func:`figure_energy` as PNG."""
    return _save(figure_energy(run), path)


def figure_ends(run):
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
    if ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False)
    return fig


def plot_ends(run, path: Path) -> Path:
    """:func:`figure_ends` as PNG."""
    return _save(figure_ends(run), path)


def figure_contact(t: np.ndarray, obstacles: Sequence[dict], kinds: Sequence[str]):
    """Per obstacle the force it exerts on the rod (components and magnitude, N) and the
    smallest gap (m; below zero: penetration) over time."""
    plt = _plt()
    fig, (ax, axg) = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
    for k, (o, kind) in enumerate(zip(obstacles, kinds, strict=True)):
        f = np.asarray(o["force"])
        ax.plot(t, np.linalg.norm(f, axis=0), color=f"C{k}", lw=1.2,
                label=f"|F| obstacle {k} ({kind})")
        for c, comp in enumerate("xyz"):
            if np.any(f[c]):
                ax.plot(t, f[c], color=f"C{k}", lw=0.6, ls=(":", "--", "-.")[c],
                        label=f"F{comp} obstacle {k}")
        axg.plot(t, o["gap_min"], color=f"C{k}", lw=1.0, label=f"obstacle {k}")
    ax.set_ylabel("force on the rod [N]")
    axg.set_ylabel("smallest gap [m]")
    axg.axhline(0, color="0.6", lw=0.5)
    axg.set_xlabel("time t [s]")
    for a in (ax, axg):
        if a.get_legend_handles_labels()[0]:
            a.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False)
    return fig


def plot_contact(t: np.ndarray, obstacles: Sequence[dict], kinds: Sequence[str],
                 path: Path) -> Path:
    """:func:`figure_contact` as PNG."""
    return _save(figure_contact(t, obstacles, kinds), path)


def _zeta_prediction(run) -> float:
    lp = run.problem.linear_prediction() if hasattr(run, "problem") else None
    return lp["zeta_1"] if lp else math.nan


def plot_run(run, out: Path) -> list[Path]:
    """ends.png, energy.png, (with maxima) damping_ratio.png and (with centreline frames)
    centreline.png of a run into ``out``."""
    out = Path(out)
    paths = [plot_ends(run, out / "ends.png"), plot_energy(run, out / "energy.png")]
    if getattr(run, "peaks_x", np.zeros(0)).size >= 2:
        paths.append(plot_damping_vs_amplitude([run], ["run"], [_zeta_prediction(run)],
                                               out / "damping_ratio.png"))
    if getattr(run, "obstacles", None):
        paths.append(plot_contact(run.t, run.obstacles,
                                  [o.kind for o in run.problem.obstacles], out / "contact.png"))
    frames = getattr(run, "centreline", np.zeros((0, 3, 0)))
    if frames.shape[0] and run.model is not None:
        from runtime.io.shapes import plot_run_centreline

        paths.append(plot_run_centreline(run.centreline_t, frames,
                                         run.model.positions(run.model.reference),
                                         out / "centreline.png", title=run.problem.name))
    return paths


class LoadedRun:
    """A run read back from series.npz (the attributes the plots use; ``centreline``
    (m, 3, N+1) and ``reference`` (3, N+1) are empty for a run written before kvrod kept
    centreline frames)."""

    KEYS = ("t", "tip", "start", "kinetic", "elastic", "dissipated", "external_work",
            "energy_balance_rel", "peaks_t", "peaks_x", "centreline_t", "centreline",
            "reference")
    EMPTY = {"tip": (3, 0), "start": (3, 0), "centreline": (0, 3, 0), "reference": (3, 0)}

    def __init__(self, out: Path) -> None:
        from runtime.io.results import DamagedFileError, read_npz

        path = Path(out) / "series.npz"
        hint = "run the problem again (DIR/problem.toml) to rewrite it"
        arrays = read_npz(path, self.KEYS, hint=hint)
        try:
            for k in self.KEYS:
                setattr(self, k, np.asarray(arrays[k], dtype=float) if k in arrays else
                        np.zeros(self.EMPTY.get(k, 0)))
        except (TypeError, ValueError) as exc:
            raise DamagedFileError(f"{path} is damaged ({type(exc).__name__}: "
                                   f"{' '.join(str(exc).split())[:120]}); {hint}") from None
        nt = self.t.shape
        bad = [k for k in ("tip", "start") if getattr(self, k).shape[1:] != nt] + [
            k for k in ("kinetic", "elastic", "dissipated", "external_work")
            if getattr(self, k).size and getattr(self, k).shape != nt]
        if self.t.ndim != 1 or bad or self.peaks_t.shape != self.peaks_x.shape:
            raise ValueError(f"{path} is damaged (arrays {', '.join(bad) or 't/peaks'} do not "
                             f"match t of shape {nt}); run the problem again "
                             "(DIR/problem.toml) to rewrite it")


def plot_run_folder(out: Path) -> list[Path]:
    """The plots of :func:`plot_run` from a results folder's series.npz (centreline.png
    only when the run kept centreline frames)."""
    import json

    out = Path(out)
    run = LoadedRun(out)
    zlin, name = math.nan, out.name
    s: dict = {}
    try:
        s = json.loads((out / "summary.json").read_text())
        lp = s.get("linear_prediction")
        zlin = lp["zeta_1"] if lp else math.nan
        name = s.get("problem", name)
    except (OSError, ValueError, KeyError, TypeError):
        pass
    paths = [plot_ends(run, out / "ends.png"), plot_energy(run, out / "energy.png")]
    if run.peaks_x.size >= 2:
        paths.append(plot_damping_vs_amplitude([run], ["run"], [zlin],
                                               out / "damping_ratio.png"))
    if run.centreline.shape[0] and run.reference.size:
        from runtime.io.shapes import plot_run_centreline

        paths.append(plot_run_centreline(run.centreline_t, run.centreline, run.reference,
                                         out / "centreline.png", title=name))
    contact = plot_contact_of_folder(out, run.t, s)
    return paths + ([contact] if contact is not None else [])


def plot_contact_of_folder(out: Path, t: np.ndarray, summary) -> Path | None:
    """contact.png of a run folder (a single rod's or an assembly's) whose series.npz has
    per obstacle values on the output grid ``t``; ``summary`` (summary.json) names the
    obstacles' kinds. None without obstacles."""
    obstacles = _loaded_obstacles(Path(out) / "series.npz", t.size)
    if not obstacles:
        return None
    listed = summary.get("obstacles") if isinstance(summary, dict) else None
    kinds = [str(o.get("kind", "?")) if isinstance(o, dict) else "?"
             for o in (listed if isinstance(listed, list) else [])]
    kinds = (kinds + ["?"] * len(obstacles))[:len(obstacles)]
    return plot_contact(t, obstacles, kinds, Path(out) / "contact.png")


def _loaded_obstacles(path: Path, nt: int) -> list[dict]:
    """The per obstacle ``force`` and ``gap_min`` of a run's series.npz (none: [])."""
    out = []
    with np.load(path) as z:
        k = 0
        while f"obstacle{k}_force" in z.files and f"obstacle{k}_gap_min" in z.files:
            f, g = np.asarray(z[f"obstacle{k}_force"]), np.asarray(z[f"obstacle{k}_gap_min"])
            if f.shape != (3, nt) or g.shape != (nt,):
                break
            out.append({"force": f, "gap_min": g})
            k += 1
    return out


def plot_dma(fit, path: Path) -> Path:
    """E' and E'' of a DMA fit (``runtime.analysis.dma.DmaFit``) against frequency: data
    and fitted series (log-log)."""
    plt = _plt()
    w = np.logspace(math.log10(fit.omega.min()) - 0.3, math.log10(fit.omega.max()) + 0.3, 200)
    Ep, Epp = fit.moduli(w)
    fig, ax = plt.subplots(figsize=(5.6, 4.0))
    ax.loglog(fit.omega, fit.storage, "C0o", ms=4, label="E' (data)")
    ax.loglog(fit.omega, np.maximum(fit.loss, 1e-300), "C1s", ms=4, label="E'' (data)")
    ax.loglog(w, Ep, "C0-", lw=1, label=f"E' (Prony, {fit.theta.size} terms)")
    ax.loglog(w, Epp, "C1-", lw=1, label="E'' (Prony)")
    ax.set_xlabel("omega [rad/s]")
    ax.set_ylabel("modulus [Pa]")
    ax.legend(fontsize=7)
    ax.set_title(f"DMA fit (relative RMS {fit.rel_rms:.2g})")
    fig.tight_layout()
    return save(fig, path, dpi=110)
