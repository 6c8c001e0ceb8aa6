"""The work behind `kvrod modes`, `kvrod compare-damping` and `kvrod calibrate --dma`
(modal analysis with continuum references, mode-shape plots, the comparison tables and
files, the DMA fit's files), shared by those commands and the notes commands. Nothing
here prints."""

from __future__ import annotations

import math
from pathlib import Path


def modes_table(modes) -> str:
    """The table printed by `kvrod modes` (one line per mode)."""
    head = (f"{'mode':>4}  {'family':<10} {'f [Hz]':>10} {'omega [rad/s]':>14} "
            f"{'zeta [-]':>9} {'lambda [1/s]':>30} {'analytic omega':>15} {'diff':>8}")
    lines = [head, "-" * len(head)]
    for m in modes:
        l1, l2 = m.eigenvalues
        lam = (f"{l1.real:.4g} +- {abs(l1.imag):.4g}i" if l1.imag != 0
               else f"{l1.real:.4g}, {l2.real:.4g}")
        ref = f"{m.analytic_omega:15.5f}" if m.analytic_omega else f"{'-':>15}"
        diff = (f"{(m.omega / m.analytic_omega - 1) * 100:+7.3f}%" if m.analytic_omega
                else f"{'':>8}")
        zeta = f"{m.zeta:9.5f}" if math.isfinite(m.zeta) else f"{'-':>9}"
        lines.append(f"{m.index:>4}  {m.family:<10} {m.frequency_hz:10.5f} {m.omega:14.5f} "
                     f"{zeta} {lam:>30} {ref} {diff}")
    return "\n".join(lines)


def plot_mode_shapes(modes, length: float, path: Path) -> Path:
    """Mode shapes as PNG: displacements (solid) and rotations times L (dashed), scaled
    together to max 1; components below 1e-6 of the largest are left out."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    n = len(modes)
    cols = min(3, n)
    rows = math.ceil(n / cols)
    fig, axes = plt.subplots(rows, cols, figsize=(4.2 * cols, 2.8 * rows), squeeze=False)
    for ax, m in zip(axes.ravel(), modes, strict=False):
        N = m.rotation.shape[1]
        s_n = np.linspace(0.0, length, N + 1)
        s_s = (s_n[:-1] + s_n[1:]) / 2
        d, r = m.displacement, m.rotation * length  # rotations as theta L (m)
        scale = max(np.abs(d).max(), np.abs(r).max()) or 1.0
        for c, lab in enumerate(("x", "y", "z")):
            if np.abs(d[c]).max() > 1e-6 * scale:
                ax.plot(s_n, d[c] / scale, "-", color=f"C{c}", label=f"u_{lab}")
            if np.abs(r[c]).max() > 1e-6 * scale:
                ax.plot(s_s, r[c] / scale, "--", color=f"C{c}", label=f"theta_{c + 1} L")
        ax.set_title(f"{m.index}: {m.family}, f = {m.frequency_hz:.4g} Hz, "
                     f"zeta = {m.zeta:.3g}", fontsize=8)
        ax.set_xlabel("s [m]", fontsize=8)
        ax.tick_params(labelsize=7)
        ax.legend(fontsize=6, loc="best")
        ax.grid(alpha=0.3)
    for ax in axes.ravel()[n:]:
        ax.set_visible(False)
    fig.tight_layout()
    from runtime.io.atomic import save_figure

    try:
        return save_figure(fig, path, dpi=110)
    finally:
        plt.close(fig)


def run_modes(problem, count: int = 10, deformed: bool = False) -> dict:
    """Modal analysis of a problem; returns {"modes", "model", "static_tip", ...}.

    Straight (default): about the stress-free reference without loads; deformed: about
    the static equilibrium under the problem's loads at t = 0-. Continuum reference
    frequencies (the independent ``references`` package) are attached where they apply.
    """
    from dataclasses import replace

    from kvrod import continuum
    from runtime.analysis.modal import modal_analysis
    from runtime.problem.assemble import build_model
    from runtime.simulate.simulate import static_equilibrium

    p = problem if deformed else replace(problem, loads=())
    model = build_model(p)
    y_eq, tip = None, None
    if deformed:
        st = static_equilibrium(p, model)
        y_eq, tip = st.y, st.tip
    modes = modal_analysis(model, y_eq, count=count)
    if not deformed:
        continuum.attach(problem, modes)
    return {"problem": problem, "model": model, "modes": modes, "deformed": deformed,
            "static_tip": tip}


def compare_table(result) -> str:
    """The table printed by `kvrod compare-damping` (plain text, one line per route)."""
    head = (f"{'case':<8} {'route':<11} {'tau_E [s]':>11} {'zeta meas.':>11} "
            f"{'w tau/2':>9} {'(contin.)':>9} {'modal':>9} {'meas/pred':>10}")
    lines = [head, "-" * len(head)]
    for case, res in result["cases"].items():
        for route, r in res["routes"].items():
            lines.append(f"{case:<8} {route:<11} {r['tau_E']:11.5g} {r['measured_zeta']:11.5f} "
                         f"{r['predicted_zeta']:9.5f} {r['predicted_zeta_continuum']:9.5f} "
                         f"{r['modal_zeta']:9.5f} "
                         f"{r['measured_zeta'] / r['predicted_zeta']:10.4f}")
        lines.append(f"{case:<8} ratio consistent/naive: measured {res['measured_ratio']:.4f}, "
                     f"predicted tau_E/tau~_E = {res['predicted_ratio']:.4f}")
    return "\n".join(lines)


def compare_markdown(result) -> str:
    """The same table as Markdown (written to compare_damping.md)."""
    p = result["parameters"]
    lines = [
        "# eta_E (consistent) against eta~_E (naive): measured damping ratios",
        "",
        f"N = {p['n_elements']}, tau_S = {p['tau_S']:g} s, tau_B = {p['tau_B']:g} s, "
        f"nu = {p['poisson_ratio']:g}; bending: release from F = {p['tip_force']:g} N; "
        f"axial: release from F_z = {p['axial_force']:g} N with tau_S, tau_B scaled to "
        f"{p['axial_tau_S']:.4g} s, {p['axial_tau_B']:.4g} s (naive zeta = "
        f"{p['axial_zeta']:g}).",
        "",
        "| case | route | tau [s] | zeta measured | omega tau/2 (modal omega) | "
        "omega tau/2 (continuum) | measured/predicted |",
        "|---|---|---|---|---|---|---|",
    ]
    for case, res in result["cases"].items():
        for route, r in res["routes"].items():
            lines.append(f"| {case} | {route} | {r['tau_E']:.5g} | {r['measured_zeta']:.5f} | "
                         f"{r['predicted_zeta']:.5f} | {r['predicted_zeta_continuum']:.5f} | "
                         f"{r['measured_zeta'] / r['predicted_zeta']:.4f} |")
    lines += ["", "| case | ratio consistent/naive measured | predicted tau_E/tau~_E | "
              "difference |", "|---|---|---|---|"]
    for case, res in result["cases"].items():
        lines.append(f"| {case} | {res['measured_ratio']:.4f} | {res['predicted_ratio']:.4f} | "
                     f"{(res['measured_ratio'] / res['predicted_ratio'] - 1) * 100:+.3f} % |")
    return "\n".join(lines) + "\n"


def write_compare(result, out: Path) -> list[Path]:
    """compare_damping.json, compare_damping.md, compare_signals.png, compare_zeta.png."""
    from runtime.analysis.compare_damping import plot_compare, summary
    from runtime.io.results import write_json

    out = Path(out)
    paths = [write_json(out / "compare_damping.json", summary(result))]
    from runtime.io.atomic import write_text

    paths.append(write_text(out / "compare_damping.md", compare_markdown(result)))
    return paths + plot_compare(result, out)


def write_dma_fit(fit, table: dict, out: Path, command: str) -> list[Path]:
    """Write a DMA fit as `kvrod calibrate --dma` does: ``dma.json`` (series, uncertainty,
    doubts), ``material.toml`` (``table``, a ``[material]`` for a problem file, headed by
    ``command``) and ``dma.png``."""
    import tomli_w

    from runtime.analysis import dma
    from runtime.io.atomic import write_text
    from runtime.io.results import write_json

    write_json(out / "dma.json", {"command": command, **fit.summary(), "material": table})
    write_text(out / "material.toml", f"# {command}: paste into a problem file\n"
               + tomli_w.dumps({"material": table}))
    return [out / "dma.json", out / "material.toml", dma.plot_dma(fit, out / "dma.png")]
