"""fit.png: the data against the fitted model and the start (matplotlib, Agg)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

#: most panels drawn (one per data column)
MAX_PANELS = 12


def plot_fit(res, path: str | Path) -> Path:
    """Draw ``res`` (a :class:`~runtime.study.fit.FitResult`): one panel per data column,
    the measurements as dots, the fitted model as a line and the start as a dashed line
    (a record and a shape: over time or arc length; modes: per measured mode). Written
    atomically; returns the path."""
    from runtime.io.atomic import save_figure
    from runtime.io.figures import pyplot

    plt = pyplot()
    data = res.data
    cols = list(data.columns)[:MAX_PANELS]
    fig, axes = plt.subplots(len(cols), 1, figsize=(8, 2.6 * len(cols) + 0.8), sharex=True,
                             squeeze=False)
    fitted = ", ".join(f"{n} = {v:.5g}" for n, v in zip(res.names, res.theta, strict=True))
    start = ", ".join(f"{n} = {v:.5g}" for n, v in zip(res.names, res.start, strict=True))
    xlabel = {"series": "t [s]", "shape": "s [m]", "modes": "mode"}[data.kind]
    for ax, col in zip(axes[:, 0], cols, strict=True):
        m = col.measured
        if data.kind == "modes":
            x = np.arange(data.rows)
            ax.plot(x[m], col.values[m], "o", color="0.3", label="data")
            ax.plot(x[m], res.fit_curves.columns[col.name][m], "x", color="C3", ms=9,
                    label=f"fit: {fitted}")
            ax.plot(x[m], res.start_curves.columns[col.name][m], "+", color="C0", ms=9,
                    label=f"start: {start}")
            ax.set_xticks(x, list(data.modes))
        else:
            ax.plot(data.abscissa[m], col.values[m], ".", ms=2.5, color="0.5", label="data")
            ax.plot(res.fit_curves.x, res.fit_curves.columns[col.name], "-", color="C3",
                    lw=1.2, label=f"fit: {fitted}")
            ax.plot(res.start_curves.x, res.start_curves.columns[col.name], "--", color="C0",
                    lw=0.9, label=f"start: {start}")
        ax.set_ylabel(f"{col.name} [{col.unit}]")
        ax.grid(alpha=0.3)
    axes[0, 0].legend(loc="best", fontsize=7)
    axes[-1, 0].set_xlabel(xlabel)
    axes[0, 0].set_title(f"kvrod fit: {Path(data.path).name}", fontsize=10)
    fig.tight_layout()
    try:
        return save_figure(fig, Path(path), dpi=110)
    finally:
        plt.close(fig)
