"""`kvrod notes-examples`: run every example in examples/ and write notes/examples.md.

Each example runs exactly as ``kvrod static`` / ``kvrod simulate`` runs it (same results
folder under ``--out``), is compared with its reference from :mod:`references.examples`
(written separately, section constants from textbook formulas), and gets a figure.
The static examples also get a convergence study in N. Wall times, the first C
compilation, solver counters and the machine go to ``timings.json`` / ``run-info.md`` in
the results folder, not into the notes. Runtime about a minute.
"""

from __future__ import annotations

import math
import tomllib
from pathlib import Path
from typing import Any

import numpy as np

from derive.templating import render
from references import examples as RX
from runtime.io.atomic import write_text

TEMPLATE_DIR = Path(__file__).parent / "templates"
STATIC = ("rollup", "bathe_bolourchi", "helix", "clamped_both")
DYNAMIC = ("cantilever", "pendulum", "base_excitation")
#: meshes of the convergence studies (the documented N last)
CONVERGENCE = {"rollup": (20, 40, 80, 160), "bathe_bolourchi": (8, 16, 32, 64),
               "helix": (125, 250, 500, 1000), "clamped_both": (16, 32, 64, 128)}
#: the 8-element tip of the literature at P = 600 (Simo and Vu-Quoc 1986, Table 3)
BEND_LITERATURE_600 = (47.23, 15.79, 53.37)


def _doc(name: str) -> dict:
    from runtime.problem.registry import EXAMPLES_DIR

    return tomllib.loads((EXAMPLES_DIR / f"{name}.toml").read_text())


def _floats(x) -> list[float]:
    return [float(v) for v in x]


def _plt():
    from runtime.io.figures import pyplot

    return pyplot()


# -- the measured quantity of each static example ------------------------------------------
def rollup_errors(path: list) -> dict[float, float]:
    """|tip - circle| / L at each recorded load factor."""
    ref = RX.rollup_reference(_doc("rollup"))
    return {f: float(np.linalg.norm(tip - ref["tip"](f)) / ref["L"]) for f, tip in path}


def bend_errors(path: list) -> dict[float, float]:
    """|tip - converged tip| / |converged tip| at each recorded load (keyed by load)."""
    ref = RX.bend45_reference(_doc("bathe_bolourchi"))
    out = {}
    for f, tip in path:
        r = ref["tip"](f * ref["P"])
        out[f * ref["P"]] = float(np.linalg.norm(tip - r) / np.linalg.norm(r))
    return out


def axis_point_compliance(model, y) -> float:
    """Axial displacement of the coil-axis point carried by the end section, per unit
    force (m/N): ``(r(L) + R_end R_end,ref^T (c - r_ref(L)))_z - c_z`` over ``F``."""
    ref = RX.helix_reference(_doc("helix"))
    y0 = model.reference
    r_ref, r = model.tip_position(y0), model.tip_position(y)
    c = np.array([-ref["R"], 0.0, r_ref[2]])
    rot = model.frames(y)[-1] @ model.frames(y0)[-1].T
    return float(((r + rot @ (c - r_ref))[2] - c[2]) / ref["F"])


def midspan_deflection(model, y) -> float:
    """Downward midspan deflection (m) of the rod clamped at both ends."""
    pos, pos0 = model.positions(y), model.positions(model.reference)
    return float(-(pos - pos0)[2, pos.shape[1] // 2])


def _static_error(name: str, model, st) -> float:
    """The error of the static example that its convergence study follows."""
    if name == "rollup":
        return rollup_errors(st.path)[1.0]
    if name == "bathe_bolourchi":
        return bend_errors(st.path)[600.0]
    if name == "helix":
        return axis_point_compliance(model, st.y) / RX.helix_reference(_doc("helix"))["full"] - 1
    return (midspan_deflection(model, st.y)
            / RX.clamped_both_reference(_doc("clamped_both"))["midspan"] - 1)


def convergence(name: str) -> list[dict[str, float]]:
    """Error against N on the meshes of :data:`CONVERGENCE` (Python API, no folders)."""
    from runtime.problem.assemble import build_model
    from runtime.problem.registry import load_problem
    from runtime.simulate.simulate import static_equilibrium

    rows = []
    for n in CONVERGENCE[name]:
        problem = load_problem(name, {"rod.elements": n})
        model = build_model(problem)
        e = _static_error(name, model, static_equilibrium(problem, model))
        rows.append({"N": n, "error": e})
    for a, b in zip(rows, rows[1:], strict=False):
        b["order"] = math.log2(abs(a["error"]) / abs(b["error"]))
    if name == "helix":       # the end half segment's O(h) part, -1/(2N), removed
        for r in rows:
            r["rest"] = r["error"] + 1.0 / (2 * r["N"])
        for a, b in zip(rows, rows[1:], strict=False):
            b["order_rest"] = math.log2(abs(a["rest"]) / abs(b["rest"]))
    return rows


# -- figures ----------------------------------------------------------------------------
def _fig_rollup(model, y, path: list, out: Path) -> Path:
    plt = _plt()
    ref = RX.rollup_reference(_doc("rollup"))
    s = np.linspace(0.0, ref["L"], 400)
    fig, ax = plt.subplots(figsize=(5.2, 4.6))
    for f, style in ((0.5, "--"), (1.0, "-")):
        c = ref["curve"](f, s)
        ax.plot(c[0], c[2], "k" + style, lw=1, label=f"closed form, M = {2 * f:g} pi EI/L")
    pos = model.positions(y)
    ax.plot(pos[0], pos[2], "C0.", ms=3, label=f"kvrod nodes at M = 2 pi EI/L (N = {model.N})")
    for _, tip in path:
        ax.plot(tip[0], tip[2], "C3o", mfc="none", ms=8)
    ax.plot([], [], "C3o", mfc="none", label="kvrod end at M = pi EI/L and 2 pi EI/L")
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("z [m]")
    ax.legend(fontsize=7, loc="upper right")
    ax.set_title("Roll-up by an end moment")
    return _save(fig, out)


def _fig_bend(path: list, out: Path) -> Path:
    plt = _plt()
    ref = RX.bend45_reference(_doc("bathe_bolourchi"))
    P = np.linspace(0.0, ref["P"], 13)
    tips = np.array([ref["tip"](p) for p in P])
    fig, ax = plt.subplots(figsize=(5.6, 4.2))
    for k, name in enumerate("xyz"):
        ax.plot(P, tips[:, k], f"C{k}-", lw=1, label=f"{name}: shooting (converged)")
        ax.plot([f * ref["P"] for f, _ in path], [t[k] for _, t in path], f"C{k}o",
                label=f"{name}: kvrod")
        ax.plot(ref["P"], BEND_LITERATURE_600[k], f"C{k}x", ms=9)
    ax.plot([], [], "kx", label="8 elements (literature)")
    ax.set_xlabel("tip load P")
    ax.set_ylabel("tip coordinate")
    ax.legend(fontsize=7, ncol=2)
    ax.set_title("Bathe-Bolourchi 45-degree bend")
    return _save(fig, out)


def _fig_convergence(studies: dict[str, list[dict]], out: Path) -> Path:
    plt = _plt()
    fig, ax = plt.subplots(figsize=(5.6, 4.4))
    labels = {"rollup": "roll-up (end position / L)",
              "bathe_bolourchi": "45-degree bend at 600 (tip)",
              "helix": "helix (axial compliance)", "clamped_both": "clamped both (midspan)"}
    for k, (name, rows) in enumerate(studies.items()):
        n = np.array([r["N"] for r in rows])
        ax.loglog(n, [abs(r["error"]) for r in rows], f"C{k}o-", label=labels[name])
        if name == "helix":
            ax.loglog(n, [abs(r["rest"]) for r in rows], f"C{k}s--", mfc="none",
                      label="helix, O(h) end term -1/(2N) removed")
    n = np.array([8, 1000])
    ax.loglog(n, 0.2 * (n / 8.0) ** -2.0, "k:", lw=1, label="slope -2")
    ax.axhline(1e-3, color="0.6", lw=0.8)
    ax.set_xlabel("elements N")
    ax.set_ylabel("relative error")
    ax.legend(fontsize=7)
    ax.set_title("Static examples: convergence in N")
    return _save(fig, out)


def _fig_clamped(model, y, out: Path) -> Path:
    plt = _plt()
    ref = RX.clamped_both_reference(_doc("clamped_both"))
    pos, pos0 = model.positions(y), model.positions(model.reference)
    x = np.linspace(0.0, ref["L"], 300)
    fig, ax = plt.subplots(figsize=(5.6, 3.4))
    ax.plot(x, 1e6 * ref["curve"](x), "k-", lw=1, label="Timoshenko, closed form")
    ax.plot(pos0[0], -1e6 * (pos - pos0)[2], "C0.", ms=3, label=f"kvrod (N = {model.N})")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("sag w [um]")
    ax.invert_yaxis()
    ax.legend(fontsize=8)
    ax.set_title("Clamped at both ends, own weight")
    return _save(fig, out)


def _fig_pendulum(run, out: Path) -> Path:
    plt = _plt()
    ref = RX.pendulum_reference(_doc("pendulum"))
    theta = np.arctan2(run.tip[0], -run.tip[2])
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(5.6, 5.0), sharex=True)
    a1.plot(run.t, ref["angle"](run.t), "k-", lw=1, label="rigid pendulum (elliptic)")
    a1.plot(run.t[::8], theta[::8], "C0.", ms=3, label="kvrod: angle of the end")
    a1.set_ylabel("angle from vertical [rad]")
    a1.legend(fontsize=8)
    a2.plot(run.t, run.energy_balance_rel, "C1-", lw=1)
    a2.set_ylabel("energy audit (rel.)")
    a2.set_xlabel("t [s]")
    a1.set_title("Pinned rod falling from horizontal (undamped)")
    return _save(fig, out)


def _fig_base(run, ref: dict, out: Path) -> Path:
    plt = _plt()
    fig, ax = plt.subplots(figsize=(6.0, 3.6))
    ax.plot(run.t, 1e3 * run.tip[0], "C0-", lw=0.8, label="tip x (kvrod)")
    ax.plot(run.t, 1e3 * run.start[0], "C2-", lw=0.8, label="clamp x (prescribed)")
    for sgn in (1, -1):
        ax.axhline(sgn * 1e3 * ref["amplitude"], color="k", ls="--", lw=0.8)
    ax.plot([], [], "k--", label="X |T(omega)|, complex-modulus Timoshenko beam")
    ax.set_xlabel("t [s]")
    ax.set_ylabel("x [mm]")
    ax.legend(fontsize=7, loc="lower right")
    ax.set_title("Base excitation near the first resonance")
    return _save(fig, out)


def _save(fig, path: Path) -> Path:
    from runtime.io.figures import save

    fig.tight_layout()
    return save(fig, path, dpi=120)


# -- the notes --------------------------------------------------------------------------
def _steady_amplitude(run, omega: float, window: float = 10.0) -> float:
    keep = run.t >= run.t[-1] - window
    t, x = run.t[keep], run.tip[0][keep]
    c = np.linalg.lstsq(np.column_stack([np.sin(omega * t), np.cos(omega * t),
                                         np.ones_like(t)]), x, rcond=None)[0]
    return float(math.hypot(c[0], c[1]))


def _crossings(run) -> np.ndarray:
    x = run.tip[0]
    i = np.where(np.diff(np.sign(x)) != 0)[0]
    return run.t[i] - x[i] * (run.t[i + 1] - run.t[i]) / (x[i + 1] - x[i])


def write_examples_notes(path: Path = Path("notes/examples.md"),
                         out: Path = Path("results/examples"),
                         command: str = "kvrod notes-examples") -> Path:
    """Run every example into ``out/<name>/``, compare, draw, and render ``path``.

    Figures go to ``path.parent / "figures"`` as ``examples_*.png``; the measurements of
    this run (``command``) to ``out/run-info.md``. Raises RuntimeError when a run fails
    (its folder keeps what was computed)."""
    from reports.run_info import Timings, bound, decade
    from runtime.io.runs import run_and_write, static_and_write
    from runtime.problem.registry import load_problem

    path, out = Path(path), Path(out)
    figs = path.parent / "figures"
    timings = Timings(command)
    timings.compile_native()
    ctx: dict[str, Any] = {"out": out.as_posix(), "notes": path.as_posix(), "static": {},
                           "dynamic": {}, "bound": bound, "decade": decade}
    fig_links: dict[str, str] = {}
    static: dict[str, tuple] = {}
    for name in STATIC:
        with timings.phase(f"static {name}"):
            summary, model, y = static_and_write(load_problem(name), out / name,
                                                 overwrite=True)
        timings.run(name, summary)
        if summary["status"] != "finished":
            raise RuntimeError(f"{name}: {summary['message']}")
        pth = [(p["load_factor"], np.array(p["tip"])) for p in summary["static"]["path"]]
        static[name] = (model, y, pth, summary, timings.phases[f"static {name}"])

    model, y, pth, summary, wall = static["rollup"]
    ref = RX.rollup_reference(_doc("rollup"))
    err = rollup_errors(pth)
    ctx["static"]["rollup"] = {
        "N": model.N, "M": ref["M"], "EI": ref["EI"], "wall": wall,
        "rows": [{"f": f, "tip": _floats(tip), "ref": _floats(ref["tip"](f)), "err": err[f]}
                 for f, tip in pth]}
    fig_links["rollup"] = _fig_rollup(model, y, pth, figs / "examples_rollup.png")

    model, y, pth, summary, wall = static["bathe_bolourchi"]
    ref = RX.bend45_reference(_doc("bathe_bolourchi"))
    err = bend_errors(pth)
    ctx["static"]["bathe_bolourchi"] = {
        "N": model.N, "wall": wall, "literature": BEND_LITERATURE_600,
        "lit_err": float(np.linalg.norm(np.subtract(BEND_LITERATURE_600, ref["tip"](600.0)))
                         / np.linalg.norm(ref["tip"](600.0))),
        "rows": [{"P": f * ref["P"], "tip": _floats(tip),
                  "ref": _floats(ref["tip"](f * ref["P"])), "err": err[f * ref["P"]]}
                 for f, tip in pth]}
    fig_links["bathe_bolourchi"] = _fig_bend(pth, figs / "examples_bathe_bolourchi.png")

    model, y, pth, summary, wall = static["helix"]
    ref = RX.helix_reference(_doc("helix"))
    got = axis_point_compliance(model, y)
    ctx["static"]["helix"] = {"N": model.N, "wall": wall, "compliance": got,
                              "full": ref["full"], "classical": ref["classical"],
                              "err": got / ref["full"] - 1, "F": ref["F"],
                              "err_classical": got / ref["classical"] - 1,
                              "l": ref["wire_length"]}

    model, y, pth, summary, wall = static["clamped_both"]
    ref = RX.clamped_both_reference(_doc("clamped_both"))
    w = midspan_deflection(model, y)
    ctx["static"]["clamped_both"] = {"N": model.N, "wall": wall, "w": w, "ref": ref["midspan"],
                                     "shear": ref["shear_part"], "err": w / ref["midspan"] - 1}
    fig_links["clamped_both"] = _fig_clamped(model, y, figs / "examples_clamped_both.png")

    with timings.phase("convergence studies"):
        studies = {name: convergence(name) for name in CONVERGENCE}
    ctx["convergence"] = studies
    fig_links["convergence"] = _fig_convergence(studies, figs / "examples_convergence.png")

    runs = {}
    for name in DYNAMIC:
        with timings.phase(f"simulate {name}"):
            run, summary = run_and_write(load_problem(name), out / name, name, overwrite=True)
        timings.run(name, summary)
        if run.status != "finished":
            raise RuntimeError(f"{name}: {run.message}")
        runs[name] = (run, summary)

    run, summary = runs["cantilever"]
    lp = summary["linear_prediction"]
    ctx["dynamic"]["cantilever"] = {
        "zeta": summary["damping_ratios"], "lin": lp, "audit": summary["energy_balance_max_rel"],
        "steps": summary["counters"]["nstep"], "wall": summary["wall_time_s"],
        "N": run.problem.rod.elements}

    run, summary = runs["pendulum"]
    ref = RX.pendulum_reference(_doc("pendulum"))
    cr = _crossings(run)
    ctx["dynamic"]["pendulum"] = {
        "T": ref["period"], "quarter": cr[0], "half": float(np.mean(np.diff(cr))),
        "n_cross": len(cr), "audit": summary["energy_balance_max_rel"],
        "steps": summary["counters"]["nstep"], "wall": summary["wall_time_s"],
        "N": run.problem.rod.elements,
        "angle_err": float(np.max(np.abs(np.arctan2(run.tip[0], -run.tip[2])
                                         - ref["angle"](run.t))))}
    fig_links["pendulum"] = _fig_pendulum(run, figs / "examples_pendulum.png")

    run, summary = runs["base_excitation"]
    ref = RX.base_excitation_reference(_doc("base_excitation"))
    amp = _steady_amplitude(run, ref["omega"])
    ctx["dynamic"]["base_excitation"] = {
        **ref, "measured": amp, "err": amp / ref["amplitude"] - 1,
        "audit": summary["energy_balance_max_rel"], "steps": summary["counters"]["nstep"],
        "wall": summary["wall_time_s"], "N": run.problem.rod.elements}
    fig_links["base_excitation"] = _fig_base(run, ref, figs / "examples_base_excitation.png")

    ctx["fig"] = {k: f"figures/{Path(v).name}" for k, v in fig_links.items()}
    write_text(path, render(TEMPLATE_DIR, "examples.md.jinja", **ctx))
    timings.write(out)
    return path
