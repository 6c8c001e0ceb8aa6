"""``DIR/summary.png`` of a study: damping ratios and periods against a varied parameter."""

from __future__ import annotations

import json
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from runtime.study.points import FINISHED, slug_value

#: units of the parameters, for axis labels
UNITS = {"tau": "s", "tau_S": "s", "tau_B": "s", "length": "m", "width": "m", "height": "m",
         "density": "kg/m^3", "youngs_modulus": "Pa", "poisson_ratio": "-", "tip_force": "N",
         "n_elements": "-", "t_end": "s", "rtol": "-", "atol": "-", "load_steps": "-",
         "output_step": "s"}


def plot_axis(study) -> str | None:
    """The parameter on the x axis: tau (or tau_S, tau_B) if varied, else the first
    varied parameter that is a number at every point; None when there is none."""
    numeric = [k for k in study.varied
               if all(isinstance(v, (int, float)) for v in study.points.column_values(k))]
    for k in ("tau", "tau_S", "tau_B"):
        if k in numeric:
            return k
    return numeric[0] if numeric else None


#: up to this many lines (combinations of the other varied parameters) get a legend
#: entry each; more are coloured along a colour scale, with a colour bar
LEGEND_MAX = 8


def write_plots(out: Path, study, rows: Mapping[str, Mapping[str, Any]]) -> Path | None:
    """``DIR/summary.png``: first/last damping ratio and mean period against the first
    varied parameter (tau if varied), one line per combination of the other varied ones.

    Up to :data:`LEGEND_MAX` lines are named in a legend; more (a 16 x 16 grid has 16) are
    coloured along a colour scale in study order, its colour bar labelled with the other
    parameter's values where there is one, so that the figure stays readable (and is
    drawn in a third of the time: a 48-entry legend was half of the drawing).

    ``rows``: table rows (:func:`runtime.study.table.row_of`) by point id, in study order
    (the order of the legend). Returns None when there is nothing to plot yet.
    """
    x = plot_axis(study)
    if x is None:
        return None
    others = [k for k in study.varied if k != x]
    groups: dict[tuple, list[tuple[float, Mapping[str, Any]]]] = {}
    for row in rows.values():
        if row.get("status") != FINISHED or row.get("zeta_first") == "":
            continue
        key = tuple(None if row.get(k, "") == "" else row[k] for k in others)
        groups.setdefault(key, []).append((float(row[x]), row))
    if not groups:
        return None
    from runtime.io.figures import pyplot, save

    plt = pyplot()
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4.5))
    scale = _ColourScale(study, others, list(groups)) if len(groups) > LEGEND_MAX else None
    order = list(groups) if scale is None else scale.keys
    for key in order:
        pts = groups[key]
        pts.sort(key=lambda t: t[0])
        xs = [t[0] for t in pts]
        label = ", ".join(f"{k}={slug_value(v)}" for k, v in zip(others, key, strict=True))
        colour = None if scale is None else scale.colour(key)
        line, = ax1.plot(xs, [t[1]["zeta_first"] for t in pts], "o-", color=colour,
                         ms=4 if scale else 6, label=f"first {label}".strip())
        ax1.plot(xs, [t[1]["zeta_last"] for t in pts], "s--", color=line.get_color(),
                 ms=3 if scale else 6, label=f"last {label}".strip())
        per = [(a, r["period_mean"]) for a, r in pts if r.get("period_mean") != ""]
        if per:
            ax2.plot([a for a, _ in per], [b for _, b in per], "o-", color=line.get_color(),
                     ms=4 if scale else 6, label=label or None)
    xlabel = f"{x} [{UNITS.get(x, '-')}]"
    ax1.set_xlabel(xlabel)
    ax1.set_ylabel("damping ratio zeta [-] (first and last cycle)")
    ax2.set_xlabel(xlabel)
    ax2.set_ylabel("mean period of the tip maxima [s]")
    if scale is None:
        ax1.legend(fontsize=7)
        if others:
            ax2.legend(fontsize=7)
    else:
        ax1.legend(handles=[ax1.lines[0], ax1.lines[1]], labels=["first cycle", "last cycle"],
                   fontsize=7)
        scale.colour_bar(fig, (ax1, ax2))
    fig.suptitle(f"study {study.name}: {sum(len(v) for v in groups.values())} finished points")
    return save(fig, Path(out) / "summary.png", dpi=120, bbox_inches="tight")


class _ColourScale:
    """Colours of many lines along viridis, and the colour bar that says what they stand
    for. With one other varied parameter, a number at every point: the colour is a
    function of its value over the study's range of it (logarithmic where its values are
    positive and span a decade or more), the same at every refresh, and the colour bar
    is that parameter's axis. Otherwise: the combination's rank in sorted order."""

    def __init__(self, study, others: list[str], keys: list[tuple]) -> None:
        import matplotlib as mpl

        self._cmap = mpl.colormaps["viridis"]
        self.label = "combination of the other varied parameters (sorted)"
        values = (list(study.points.column_values(others[0])) if len(others) == 1
                  else [])
        if values and all(isinstance(v, (int, float)) and not isinstance(v, bool)
                          for v in values):
            lo, hi = min(values), max(values)
            log = lo > 0 and hi >= 10 * lo
            norm = (mpl.colors.LogNorm if log else mpl.colors.Normalize)(
                vmin=lo, vmax=hi if hi > lo else lo + (abs(lo) or 1.0))
            self.keys = sorted(keys, key=lambda k: k[0])
            self._value = lambda key: key[0]
            self.label = f"{others[0]} [{UNITS.get(others[0], '-')}]"
            self._ticks = None
        else:
            self.keys = sorted(keys, key=lambda k: json.dumps(k, default=str))
            rank = {k: i for i, k in enumerate(self.keys)}
            self._value = rank.__getitem__
            norm = mpl.colors.Normalize(vmin=0, vmax=max(len(keys) - 1, 1))
            n = len(keys)
            self._ticks = sorted({0, n - 1, *range(0, n, max(1, n // 5))})
        self._norm = norm

    def colour(self, key: tuple):
        return self._cmap(self._norm(self._value(key)))

    def colour_bar(self, fig, axes) -> None:
        import matplotlib as mpl

        sm = mpl.cm.ScalarMappable(cmap=self._cmap, norm=self._norm)
        bar = fig.colorbar(sm, ax=list(axes), pad=0.02, fraction=0.03)
        if self._ticks is not None:
            bar.set_ticks(self._ticks)
            bar.set_ticklabels([str(t + 1) for t in self._ticks])
        bar.set_label(self.label, fontsize=8)
