"""The work behind `kvrod modes`, `kvrod compare-damping` and `kvrod calibrate --dma`
(modal analysis with continuum references, its files and mode-shape plots, the
comparison tables and files, the DMA fit's files), shared by those commands and the notes
commands. Nothing here prints."""

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


def write_modes(res: dict, out: Path, figures: bool = True) -> list[Path]:
    """The results of :func:`run_modes` as every command writes them: modes.json and
    modes.npz (:func:`runtime.io.modes.write_modes`, the one format) and, read back
    from them, mode_shapes.png (components along s) and mode_shapes_3d.png (the
    centreline in 3-D) when ``figures``. Returns the paths in that order."""
    from runtime.io.modes import read_modes
    from runtime.io.modes import write_modes as write_files

    out = Path(out)
    paths = write_files(out, res["problem"], res["modes"], model=res["model"],
                        y_eq=res.get("y_eq"), deformed=res["deformed"],
                        static_tip=res["static_tip"], target=res.get("target"),
                        sensitivities=res.get("sensitivities"))
    if figures:
        from runtime.io.shapes import plot_mode_components, plot_mode_shapes_3d

        mf = read_modes(out)
        paths += [plot_mode_components(mf, out / "mode_shapes.png"),
                  plot_mode_shapes_3d(mf, out / "mode_shapes_3d.png")]
    return paths


def run_modes(problem, count: int = 10, deformed: bool = False,
              target: float | None = None, sensitivities: list[str] | None = None) -> dict:
    """Modal analysis of a problem; returns {"modes", "model", "y_eq", "static_tip", ...}.

    Straight (default): about the stress-free reference without loads; deformed: about
    the static equilibrium under the problem's loads at t = 0-. ``target`` (rad/s): the
    ``count`` modes nearest that natural frequency instead of the lowest. Continuum
    reference frequencies (the independent ``references`` package) are attached where
    they apply (not with a target: the modes' family_index then counts within the modes
    returned, not from the family's first). ``sensitivities``: parameter names whose
    derivatives of every mode's omega and zeta go to ``res["sensitivities"]``
    (:func:`runtime.analysis.modal_sensitivity.modal_sensitivities`; under the name
    asked and its unique alias).
    """
    from dataclasses import replace

    from reports import continuum
    from runtime.analysis.modal import modal_analysis
    from runtime.problem.assemble import build_model
    from runtime.simulate.simulate import static_equilibrium

    p = problem if deformed else replace(problem, loads=())
    model = build_model(p)
    y_eq, tip = None, None
    if deformed:
        st = static_equilibrium(p, model)
        y_eq, tip = st.y, st.tip
    modes = modal_analysis(model, y_eq, count=count, target=target)
    if not deformed and target is None:
        continuum.attach(problem, modes)
    sens = None
    if sensitivities is not None:
        from runtime.analysis.modal_sensitivity import modal_sensitivities
        from runtime.problem.parameters import resolve_parameters
        from runtime.simulate.sensitivity import _labels

        resolved = resolve_parameters(problem, sensitivities)
        d = modal_sensitivities(problem, resolved, modes, model, y_eq, deformed)
        sens = {label: d[r.name] for r, labels in zip(resolved, _labels(resolved), strict=True)
                for label in labels}
    return {"problem": problem, "model": model, "modes": modes, "deformed": deformed,
            "y_eq": y_eq, "static_tip": tip, "target": target, "sensitivities": sens}


def assembly_modes_table(modes, shares: int = 3) -> str:
    """The table `kvrod modes` prints for an assembly (one line per mode): the rods that
    hold most of the mode's kinetic energy (at most ``shares``, each >= 5 %) last."""
    head = (f"{'mode':>4} {'f [Hz]':>11} {'omega [rad/s]':>14} {'zeta [-]':>9} "
            f"{'lambda [1/s]':>28}  kinetic energy in")
    lines = [head, "-" * (len(head) + 12)]
    for m in modes:
        lam = m.eigenvalue
        lam_s = (f"{lam.real:.4g} +- {abs(lam.imag):.4g}i" if lam.imag != 0
                 else f"{lam.real:.4g}")
        zeta = f"{m.zeta:9.5f}" if math.isfinite(m.zeta) else f"{'-':>9}"
        top = sorted(m.rods.items(), key=lambda kv: -kv[1])
        where = ", ".join(f"{n} {100 * f:.0f}%" for n, f in top[:shares] if f >= 0.05)
        lines.append(f"{m.index:>4} {m.frequency_hz:11.5f} {m.omega:14.5f} {zeta} "
                     f"{lam_s:>28}  {where or '-'}")
    return "\n".join(lines)


def assembly_reduced_size(amap) -> int:
    """The number of unknowns (and so of modes) of an assembly's linearised problem."""
    from runtime.model.system_statics import SystemStatics

    return SystemStatics(amap.model).n_static


def run_assembly_modes(problem, count: int = 10, deformed: bool = False,
                       amap=None) -> dict:
    """Modal analysis of an assembly; returns {"problem", "amap", "modes", "deformed",
    "y_eq", "static"}.

    About the reference (default): the loads scaled to zero (gravity on the bodies
    included), so the rods' discretisation is the one of the loaded problem (a point
    load's point keeps its node); deformed: about the static equilibrium under the loads
    at t = 0- (:func:`runtime.simulate.assembly.static_equilibrium`), the loads' stiffness
    included (a hanging pendulum's gravity). ``static``: for ``deformed`` the
    equilibrium's ends, Newton iterations and joints' forces and moments."""
    from runtime.analysis.modal import fix_sign
    from runtime.analysis.system_modal import assembly_modes
    from runtime.io.assembly_results import static_joint_values
    from runtime.problem.assemble_system import build_system
    from runtime.simulate.assembly import static_ends, static_equilibrium

    amap = build_system(problem) if amap is None else amap
    model = amap.model
    static = None
    if deformed:
        st = static_equilibrium(problem, amap)
        y_eq = st.y
        joints = static_joint_values(amap, y_eq)
        static = {"ends": static_ends(amap, y_eq), "newton_iterations": int(st.iterations),
                  "joints": [{"index": k, "kind": jt.kind,
                              "between": [jt.first.label, "ground" if jt.second is None
                                          else jt.second.label], **joints[k]}
                             for k, jt in enumerate(problem.joints)]}
        with model.statics():
            modes = assembly_modes(model, y_eq, count=count)
    else:
        with model.statics():
            saved = model.load_scale
            model.load_scale = 0.0
            try:
                y_eq = model.initial_state()
                modes = assembly_modes(model, y_eq, count=count)
            finally:
                model.load_scale = saved
    for m in modes:                       # one sign on every machine
        m.shape = fix_sign(m.shape)
    return {"problem": problem, "amap": amap, "modes": modes, "deformed": deformed,
            "y_eq": y_eq, "static": static}


def write_assembly_modes(res: dict, out: Path, figures: bool = True) -> list[Path]:
    """The results of :func:`run_assembly_modes`: modes.json and modes.npz
    (:mod:`runtime.io.assembly_modes`) and, read back from them, mode_shapes_3d.png (every
    rod in 3-D) when ``figures``. Returns the paths in that order."""
    from runtime.io.assembly_modes import read_assembly_modes, write_assembly_modes

    out = Path(out)
    paths = write_assembly_modes(out, res["problem"], res["amap"], res["modes"],
                                 y_eq=res["y_eq"], deformed=res["deformed"],
                                 static=res["static"])
    if figures:
        from runtime.io.assembly_plots import plot_assembly_mode_shapes

        paths.append(plot_assembly_mode_shapes(read_assembly_modes(out),
                                               out / "mode_shapes_3d.png"))
    return paths


def compare_table(result) -> str:
    """The table printed by `kvrod compare-damping` (plain text, one line per route)."""
    head = (f"{'case':<8} {'route':<11} {'tau_E [s]':>11} {'zeta meas.':>11} "
            f"{'w1 tau/2':>9} {'w1c tau/2':>9} {'zeta mod.':>9} {'meas/pred':>10}")
    lines = [head, "-" * len(head)]
    for case, res in result["cases"].items():
        for route, r in res["routes"].items():
            lines.append(f"{case:<8} {route:<11} {r['tau_E']:11.5g} {r['measured_zeta']:11.5f} "
                         f"{r['predicted_zeta']:9.5f} {r['predicted_zeta_continuum']:9.5f} "
                         f"{r['modal_zeta']:9.5f} "
                         f"{r['measured_zeta'] / r['predicted_zeta']:10.4f}")
        lines.append(f"{case:<8} ratio consistent/naive: measured {res['measured_ratio']:.4f}, "
                     f"predicted tau_E/tau~_E = {res['predicted_ratio']:.4f}")
    lines.append("w1: the discrete rod's first mode, w1c: the continuum's; zeta mod.: damped "
                 "modal analysis; meas/pred: zeta meas. / (w1 tau/2)")
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
    from runtime.io.results import write_json
    from runtime.study.compare_damping import plot_compare, summary

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

    from runtime.io.atomic import write_text
    from runtime.io.plots import plot_dma
    from runtime.io.results import write_json

    write_json(out / "dma.json", {"command": command, **fit.summary(), "material": table})
    write_text(out / "material.toml", f"# {command}: paste into a problem file\n"
               + tomli_w.dumps({"material": table}))
    return [out / "dma.json", out / "material.toml", plot_dma(fit, out / "dma.png")]
