"""``DIR/summary.png`` of a study: damping ratios and periods against a varied parameter."""

from __future__ import annotations

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


def write_plots(out: Path, study, rows: Mapping[str, Mapping[str, Any]]) -> Path | None:
    """``DIR/summary.png``: first/last damping ratio and mean period against the first
    varied parameter (tau if varied), one line per combination of the other varied ones.

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
    for key, pts in groups.items():
        pts.sort(key=lambda t: t[0])
        xs = [t[0] for t in pts]
        label = ", ".join(f"{k}={slug_value(v)}" for k, v in zip(others, key, strict=True))
        line, = ax1.plot(xs, [t[1]["zeta_first"] for t in pts], "o-",
                         label=f"first {label}".strip())
        ax1.plot(xs, [t[1]["zeta_last"] for t in pts], "s--", color=line.get_color(),
                 label=f"last {label}".strip())
        per = [(a, r["period_mean"]) for a, r in pts if r.get("period_mean") != ""]
        if per:
            ax2.plot([a for a, _ in per], [b for _, b in per], "o-", color=line.get_color(),
                     label=label or None)
    xlabel = f"{x} [{UNITS.get(x, '-')}]"
    ax1.set_xlabel(xlabel)
    ax1.set_ylabel("damping ratio zeta [-] (first and last cycle)")
    ax2.set_xlabel(xlabel)
    ax2.set_ylabel("mean period of the tip maxima [s]")
    ax1.legend(fontsize=7)
    if others:
        ax2.legend(fontsize=7)
    fig.suptitle(f"study {study.name}: {sum(len(v) for v in groups.values())} finished points")
    return save(fig, Path(out) / "summary.png", dpi=120, bbox_inches="tight")
