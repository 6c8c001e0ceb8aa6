"""`kvrod notes-maxwell`: the generalized Maxwell rod in notes/maxwell.md.

1. the derivation (steps ``maxwell_material``, ``maxwell_rod``, ``kelvin_voigt_uniaxial``,
   ``maxwell_limit``), rendered from the same step records as ``kvrod derive show``;
2. the paper's Kelvin-Voigt cantilever against ``examples/maxwell_cantilever.toml`` (the
   same low-frequency viscosity in three Maxwell branches): damped modes of both
   (``kvrod modes``) and the release simulated (``kvrod simulate``), with wall times;
3. a DMA fit (``kvrod calibrate --dma``) of synthetic storage and loss moduli made by the
   independent reference solid (:mod:`references.viscoelastic_material`) from the example's
   3-D material, with 1 % noise: the series found against the one that made the data.

Each part is written to a results folder in the form of the command quoted next to it.
Wall times (the cost of a Maxwell run against a Kelvin-Voigt one), the first C compilation,
solver counters and the machine go to ``timings.json`` / ``run-info.md`` there, not into the
notes. Runtime about half a minute.
"""

from __future__ import annotations

import math
import time
from pathlib import Path
from typing import Any

import numpy as np

from derive.templating import render
from runtime.io.atomic import save_figure, write_text

TEMPLATE_DIR = Path(__file__).parent / "templates"
EXAMPLE = "maxwell_cantilever"
MODES_N = 30            # elements of the modal comparison
MODES_COUNT = 12        # modes computed (both bending planes: 6 distinct pairs)
SIM_N = 20              # elements of the simulated release (modest: the Maxwell run is slow)
SIM_T_END = 4.0         # s simulated
DMA_NOISE = 0.01        # relative noise of the synthetic DMA data
DMA_SEED = 1
DMA_FREQUENCIES = np.logspace(-1, 3, 25)      # Hz

#: the results of the derivation shown, by step: (key, what it is)
DERIVATION = {
    "maxwell_material": [("G_of_s", "shear modulus of the 3-D solid in the Laplace domain"),
                         ("K_of_s", "bulk modulus")],
    "maxwell_rod": [("nu_of_s", "Poisson ratio of the laterally stress-free section"),
                    ("E_of_s", "extension/bending modulus E(s) = 9 K G / (3 K + G)"),
                    ("D_of_s", "its denominator: the zeros are the rod's extra times"),
                    ("prony_E_root", "Prony modulus at a zero s_k of D"),
                    ("prony_E_branch", "Prony modulus at a branch pole s = -1/tau_j")],
    "kelvin_voigt_uniaxial": [("E_of_s", "exact uniaxial modulus of the 3-D Kelvin-Voigt "
                                         "solid"),
                              ("tau_E_exact", "its first-order time: the paper's tau_E (6)"),
                              ("remainder_in_tau_D", "E(s) - E (1 + s tau_E): zero only for "
                                                     "tau_B = tau_S")],
    "maxwell_limit": [("G_hat_minus_KV", "Maxwell minus Kelvin-Voigt complex modulus"),
                      ("error_bound", "the paper's Kelvin-Voigt error bound")],
}


def _plt():
    from runtime.io.figures import pyplot

    return pyplot()


def _derivation() -> list[dict]:
    from derive import steps
    from derive.notes import latex

    st = steps()
    return [{"name": name, "title": st[name].title, "equations": " ".join(st[name].equations),
             "rows": [{"key": k, "what": what, "tex": latex(st[name].results[k]),
                       "checked": st[name].matches.get(k)} for k, what in rows]}
            for name, rows in DERIVATION.items()]


def _problems() -> tuple[Any, Any]:
    from runtime.problem.registry import load_problem

    return load_problem("cantilever"), load_problem(EXAMPLE)


def _modes(kv, mx, out: Path) -> list[dict]:
    """Damped modes of both rods at N = MODES_N (one row per distinct bending pair)."""
    from reports.analyses import run_modes, write_modes

    rows: dict[int, dict] = {}
    for label, problem in (("kv", kv), ("mx", mx)):
        p = problem.with_overrides({"rod.elements": MODES_N})
        res = run_modes(p, MODES_COUNT)
        modes = res["modes"]
        write_modes(res, out / f"modes-{label}", figures=False)
        for md in modes:
            if md.family == "bending-1":
                rows.setdefault(md.family_index, {"k": md.family_index})[label] = md
    table = []
    for k in sorted(rows):
        r = rows[k]
        if "kv" not in r or "mx" not in r:
            continue
        w = r["mx"].omega
        E = complex(mx.material.complex_moduli(w)[0])
        table.append({"k": k, "omega_kv": r["kv"].omega, "zeta_kv": r["kv"].zeta,
                      "omega_mx": w, "zeta_mx": r["mx"].zeta,
                      "zeta_cm": E.imag / (2 * E.real)})
    return table


def _simulate(kv, mx, out: Path) -> dict:
    from runtime.io.runs import run_and_write

    res = {}
    for label, problem in (("kv", kv), ("mx", mx)):
        p = problem.with_overrides({"rod.elements": SIM_N, "simulation.t_end": SIM_T_END})
        t0 = time.perf_counter()
        result, summary = run_and_write(p, out / f"simulate-{label}", p.name,
                                        overwrite=True)
        wall = time.perf_counter() - t0
        if summary["status"] != "finished":
            raise RuntimeError(f"{p.name}: {summary['message']}")
        d = np.load(out / f"simulate-{label}" / "series.npz")
        res[label] = {"name": p.name, "wall": wall, "summary": summary,
                      "t": d["t"], "x": d["tip"][0],
                      "nstep": summary["counters"]["nstep"],
                      "zeta": summary["damping_ratios"][:3],
                      "audit": summary["energy_balance_max_rel"]}
    return res


def _dma(mx, out: Path) -> dict:
    from references import viscoelastic_material as vm
    from reports.analyses import write_dma_fit
    from runtime.analysis import dma

    G, K, Gj, Kj, tj = mx.material.moduli
    solid = vm.GeneralizedMaxwell(G, K, list(Gj), list(Kj), list(tj))
    omega = 2 * np.pi * DMA_FREQUENCIES
    Es = solid.E(1j * omega)
    rng = np.random.default_rng(DMA_SEED)
    noise = 1 + DMA_NOISE * rng.standard_normal((2, omega.size))
    out.mkdir(parents=True, exist_ok=True)
    csv = out / "dma.csv"
    write_text(csv, "frequency_hz,storage,loss\n" + "".join(
        f"{f!r},{a!r},{b!r}\n" for f, a, b in zip(DMA_FREQUENCIES.tolist(),
                                                 (Es.real * noise[0]).tolist(),
                                                 (Es.imag * noise[1]).tolist(), strict=True)))
    fit = dma.fit_prony(*dma.load_dma(csv), poisson_ratio=mx.material.poisson_ratio)
    table = fit.material(mx.material.density)
    write_dma_fit(fit, table, out / "fit",
                  f"kvrod calibrate --dma {csv.as_posix()} --nu {mx.material.poisson_ratio}")
    Ep, Epp = fit.moduli(omega)
    return {"csv": csv.as_posix(), "fit": fit, "terms": fit.summary()["terms"],
            "true": [{"tau": float(t), "E": float(e)} for t, e in
                     zip(mx.material.rod_relaxation().theta, mx.material.rod_relaxation().E,
                         strict=True)],
            "max_err_storage": float(np.max(np.abs(Ep / Es.real - 1))),
            "max_err_loss": float(np.max(np.abs(Epp / Es.imag - 1))),
            "E_inf_true": solid.E_relaxed(), "png": (out / "fit" / "dma.png")}


def _finish(plt, fig, ax, xlabel: str, ylabel: str, path: Path) -> Path:
    """Label, legend and save a figure (closed afterwards)."""
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.legend(fontsize=7)
    fig.tight_layout()
    try:
        return save_figure(fig, path, dpi=110)
    finally:
        plt.close(fig)


def _fig_modes(rows: list[dict], mx, path: Path) -> Path:
    plt = _plt()
    fig, ax = plt.subplots(figsize=(5.6, 3.8))
    w = np.logspace(0, math.log10(max(r["omega_kv"] for r in rows) * 2), 200)
    E = mx.material.complex_moduli(w)[0]
    ax.loglog(w, w * 0.04 / 2, "C0-", lw=1, label="Kelvin-Voigt omega tau / 2")
    ax.loglog(w, E.imag / (2 * E.real), "C1-", lw=1, label="Maxwell Im E* / (2 Re E*)")
    ax.loglog([r["omega_kv"] for r in rows], [r["zeta_kv"] for r in rows], "C0o",
              label="Kelvin-Voigt rod modes")
    ax.loglog([r["omega_mx"] for r in rows], [r["zeta_mx"] for r in rows], "C1s",
              label="Maxwell rod modes")
    return _finish(plt, fig, ax, "omega [rad/s]", "damping ratio zeta [-]", path)


def _fig_release(sim: dict, path: Path) -> Path:
    plt = _plt()
    fig, ax = plt.subplots(figsize=(6.4, 3.4))
    for label, style, text in (("kv", "C0-", "Kelvin-Voigt"), ("mx", "C1--", "Maxwell")):
        ax.plot(sim[label]["t"], sim[label]["x"], style, lw=1, label=text)
    return _finish(plt, fig, ax, "t [s]", "tip x [m]", path)


def write_maxwell_notes(path: Path = Path("notes/maxwell.md"),
                        out: Path = Path("results/maxwell"),
                        command: str = "kvrod notes-maxwell") -> Path:
    """Run the three parts into ``out`` and render ``path`` (figures under
    ``path.parent / "figures"``; the measurements of this run, ``command``, in
    ``out/run-info.md``)."""
    import shutil

    from reports.run_info import Timings, decade

    path, out = Path(path), Path(out)
    figs = path.parent / "figures"
    timings = Timings(command)
    timings.compile_native()
    kv, mx = _problems()
    with timings.phase("modes"):
        rows = _modes(kv, mx, out)
    with timings.phase("release simulations"):
        sim = _simulate(kv, mx, out)
    for label in ("kv", "mx"):
        timings.run(f"simulate-{label}", sim[label]["summary"], sim[label]["wall"])
    ratio = sim["mx"]["wall"] / sim["kv"]["wall"]
    timings.figures["Maxwell release against Kelvin-Voigt release, wall time"] = \
        f"{ratio:.1f}x"
    timings.figures["Maxwell release against Kelvin-Voigt release, steps"] = \
        f"{sim['mx']['nstep'] / sim['kv']['nstep']:.1f}x"
    with timings.phase("DMA fit"):
        dm = _dma(mx, out / "dma")
    fig_modes = _fig_modes(rows, mx, figs / "maxwell_modes.png")
    fig_release = _fig_release(sim, figs / "maxwell_release.png")
    fig_dma = figs / "maxwell_dma.png"
    figs.mkdir(parents=True, exist_ok=True)
    shutil.copyfile(dm["png"], fig_dma)
    r = mx.material.rod_relaxation()
    ctx = {
        "out": out.as_posix(), "notes": path.as_posix(), "example": EXAMPLE,
        "derivation": _derivation(), "modes": rows, "MODES_N": MODES_N,
        "SIM_N": SIM_N, "SIM_T_END": SIM_T_END, "sim": sim, "decade": decade,
        "step_ratio": sim["mx"]["nstep"] / sim["kv"]["nstep"],
        "eta_kv": kv.material.youngs_modulus * kv.material.tau_E,
        "eta_mx": float(np.sum(r.E * r.theta)), "tau_E_mx": mx.material.tau_E,
        "rod": r,
        "dma": dm, "noise": DMA_NOISE,
        "figs": {k: Path(v).relative_to(path.parent).as_posix() for k, v in
                 (("modes", fig_modes), ("release", fig_release), ("dma", fig_dma))},
    }
    write_text(path, render(TEMPLATE_DIR, "maxwell.md.jinja", **ctx))
    timings.write(out)
    return path
