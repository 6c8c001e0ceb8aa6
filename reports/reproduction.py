"""`kvrod reproduce`: the paper's Sect. 5 end to end, with figures and notes/reproduction.md.

The notes hold what a rerun reproduces (rounded to what the integration error leaves
stable); wall times, the first C compilation, solver counters and the machine go to
``timings.json`` and ``run-info.md`` in the results folder (:mod:`reports.run_info`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from derive.templating import render
from runtime.io.atomic import write_text

TEMPLATE_DIR = Path(__file__).parent / "templates"
TAUS = (0.02, 0.04, 0.08)


def _reissner_reference(problem) -> dict | None:
    """Independent static reference: the references package (SciPy shooting, section
    constants from its own formulas, not kvrod's generated ones)."""
    from references import sections
    from references.reissner import elastica_tip, solve_reissner

    d = dict(problem.section.dims)
    m = problem.material
    E, nu = m.youngs_modulus, m.poisson_ratio
    sec = sections.rectangle(d["width"], d["height"], nu)
    F = float(np.linalg.norm(problem.loads[0].vector))
    EI = E * sec.I2                            # bending about a^(2) (tip force along e1)
    r = solve_reissner(F, L=problem.rod.length, EA=E * sec.A,
                       GA=E / (2 * (1 + nu)) * sec.A * sec.kappa_1, EI=EI)
    e = elastica_tip(F, EI, problem.rod.length)
    return {"reissner": [float(r.tip[0]), float(r.tip[1])],
            "elastica": [float(e.x), float(e.z)]}


def _late_zeta(summary: dict, k: int = 2) -> float:
    z = summary["damping_ratios"]
    return float(np.mean(z[-k:])) if z else float("nan")


#: written by `kvrod bench --only energy_audit` (kvrod and IDAS audited identically)
BENCH_AUDIT = Path(__file__).resolve().parents[1] / "bench" / "results" / "energy_audit.json"


def _bench_energy_audit() -> dict | None:
    """The committed kvrod-vs-IDAS energy-audit benchmark, if this checkout has it."""
    if not BENCH_AUDIT.exists():
        return None
    import json

    doc = json.loads(BENCH_AUDIT.read_text())
    rows = [r for r in doc["rows"] if r["kvrod"]["ok"] and r["idas"]["ok"]]
    return {"N": doc["N"], "rows": rows} if rows else None


def reproduce(out: Path, n_elements: int = 100, t_end: float = 10.0,
              notes: Path = Path("notes/reproduction.md"), rtol: float = 1e-7,
              derive: bool = True, overwrite: bool = False,
              command: str = "kvrod reproduce", derive_progress=None,
              progress=None) -> Path:
    """Run the three tau values, the E = 4 MPa comparison, write figures and notes.

    Every run folder under ``out`` is checked before the first run starts: one that holds
    a result is refused unless ``overwrite``. The C code is compiled first (if it is not
    yet), so that no run's wall time includes it; ``command`` is how the measurements in
    ``out/run-info.md`` were made; ``derive_progress`` is told of the derivation's steps
    when they must be derived for notes/derivation.md (:data:`derive.pipeline.Progress`);
    ``progress``: a progress display of each run (``runtime.io.runs.ProgressDisplay``).
    """
    from reports.run_info import Timings, bound, decade
    from runtime.io import folder as F
    from runtime.io import plots as P
    from runtime.io.folder import check_file_argument
    from runtime.io.runs import run_and_write
    from runtime.problem.registry import load_problem

    timings = Timings(command)
    out = Path(out)
    F.check_output_path(out)
    check_file_argument(notes, "--notes")
    labels_dirs = [f"tau_{tau:g}" for tau in TAUS] + ["E4_F0.2", "E4_F0.05"]
    for d in labels_dirs:
        F.refuse_existing(out / d, "reproduce", overwrite=overwrite)
    if derive:
        from derive.notes import write_derivation_notes
        from derive.pipeline import run

        with timings.phase("derivation notes"):
            run(progress=derive_progress)
            write_derivation_notes(notes.parent / "derivation.md")
    timings.compile_native()
    runs, summaries = {}, {}
    for tau in TAUS:
        sc = load_problem("cantilever", {"tau": tau, "n_elements": n_elements,
                                         "t_end": t_end, "rtol": rtol})
        with timings.phase(f"run tau_{tau:g}"):
            runs[tau], summaries[tau] = run_and_write(sc, out / f"tau_{tau:g}",
                                                      f"tau_E = {tau:g} s", overwrite=overwrite,
                                                      progress=progress)
        timings.run(f"tau_{tau:g}", summaries[tau])
    # E = 4 MPa: tau halved; exact coincidence needs the tip force x 4 as well
    stiff = {}
    for label, force in (("E4_F0.2", 0.2), ("E4_F0.05", 0.05)):
        sc = load_problem("cantilever", {"tau": 0.02, "youngs_modulus": 4e6,
                                         "tip_force": force, "n_elements": n_elements,
                                         "t_end": t_end / 2, "rtol": rtol})
        with timings.phase(f"run {label}"):
            stiff[label] = run_and_write(sc, out / label, f"E = 4 MPa, F = {force} N",
                                         overwrite=overwrite, progress=progress)
        timings.run(label, stiff[label][1])
    figs = out / "figures"
    with timings.phase("figures"):
        labels = [f"tau_E = {tau:g} s" for tau in TAUS]
        P.plot_tip([runs[t] for t in TAUS], labels, figs / "fig3_tip.png")
        P.plot_damping_vs_amplitude([runs[t] for t in TAUS], labels,
                                    [summaries[t]["linear_prediction"]["zeta_1"]
                                     for t in TAUS],
                                    figs / "damping_ratio_vs_amplitude.png")
        ref, (r4, s4), (r4b, s4b) = runs[0.04], stiff["E4_F0.2"], stiff["E4_F0.05"]
        P.plot_overlay(ref, "E = 1 MPa, tau_E = 0.04 s, F = 0.05 N", r4,
                       "E = 4 MPa, tau_E = 0.02 s, F = 0.2 N", 2.0, figs / "fig4_overlay.png")
        P.plot_overlay(ref, "E = 1 MPa, tau_E = 0.04 s, F = 0.05 N", r4b,
                       "E = 4 MPa, tau_E = 0.02 s, F = 0.05 N", 2.0,
                       figs / "fig4_overlay_same_force.png")
    # coincidence of the stretched time axis: x_4MPa(t/2) against x_1MPa(t)
    # both runs sample every output_step: x_4MPa(t_j) pairs with x_1MPa(2 t_j) = ref sample 2j
    n = min(r4.t.size, (ref.t.size + 1) // 2)
    dev = r4.tip[0][:n] - ref.tip[0][: 2 * n - 1 : 2]
    dev_b = r4b.tip[0][:n] - ref.tip[0][: 2 * n - 1 : 2]
    amp = float(np.max(np.abs(ref.tip[0])))
    sc0 = load_problem("cantilever", {"n_elements": n_elements})
    reference = _reissner_reference(sc0)
    ctx = {
        "n_elements": n_elements, "t_end": t_end, "rtol": rtol,
        "taus": TAUS, "s": summaries, "late_zeta": {t: _late_zeta(summaries[t]) for t in TAUS},
        "reference": reference,
        "stretch_dev": float(np.max(np.abs(dev))),
        "stretch_dev_rel": float(np.max(np.abs(dev))) / amp,
        "stretch_dev_same_force_rel": float(np.max(np.abs(dev_b))) / amp,
        "s4": s4, "s4b": s4b,
        "out": out.as_posix(),
        "bound": bound, "decade": decade,
    }
    ctx["bench_audit"] = _bench_energy_audit()
    stat = summaries[0.04]["static"]["tip"]
    if reference and reference.get("reissner"):
        rx, rz = reference["reissner"]
        ctx["static_err_rel"] = abs(stat[0] - rx) / abs(rx)
    text = render(TEMPLATE_DIR, "reproduction.md.jinja", **ctx)
    notes.parent.mkdir(parents=True, exist_ok=True)
    write_text(notes, text)
    import shutil

    dest = notes.parent / "figures"
    dest.mkdir(exist_ok=True)
    if dest.resolve() != figs.resolve():  # notes written next to the run's own figures
        for f in figs.glob("*.png"):
            shutil.copyfile(f, dest / f.name)
    timings.write(out)
    return notes
