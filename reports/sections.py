"""`kvrod notes-sections` (kvrod/cli_notes.py): composite and anisotropic cross-sections in
notes/sections.md.

Three sections, each analysed as ``kvrod section`` does (its section.json and section.png in
the results folder, under the name in :data:`RESULTS`):

1. the cable of ``examples/cable_section.toml`` (copper core, PVC insulation, rubber
   jacket): the consistent against the naive viscosity, and both against the per-layer
   sums (the layers' Poisson ratios differ);
2. the fibre-reinforced strip of ``examples/fibre_strip_section.toml`` (an antisymmetric
   angle-ply): extension-twist coupling in the stiffness and, differently, in the viscosity;
3. the same strip with a viscoelastic damping film bonded below it (``--set``): the
   viscous centroid far from the elastic centroid.

What the couplings do, from the section's matrices alone (independently of the rod
kernels, which simulate composite sections with their 6x6 matrices):
the damping ratio of the first bending mode of a cantilever of each section, from the
complex-modulus Euler-Bernoulli beam (:func:`references.viscoelastic_beam.
euler_bernoulli_eigenvalues`) whose bending modulus EI*(s) is the section's K + s V
condensed onto the bending curvature (the other resultants zero, no shear strain across
the bending plane); and the creep of a short piece of each section under a suddenly applied
axial force, K psi + V psi' = theta (the strains relax from V^-1 theta towards K^-1 theta).

Deterministic: the numbers are rounded to 4 digits, far above the analyses' round-off; wall
times go to the results folder (``run-info.md``), not into the notes.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from derive.templating import render
from runtime.io.atomic import write_text

TEMPLATE_DIR = Path(__file__).parent / "templates"
#: the results folder's subfolders, one per analysed section
RESULTS = ("cable", "fibre_strip", "fibre_strip_film")
#: cantilever lengths of the damping estimates (m)
CABLE_LENGTH = 0.5
STRIP_LENGTH = 0.3
#: the damping film of part 3: a viscoelastic polymer bonded below the strip
FILM_MATERIAL = {"youngs_modulus": 50.0e6, "poisson_ratio": 0.45, "density": 1100.0,
                 "tau_S": 0.01}
FILM_REGION = {"name": "damping film", "material": "film",
               "shape": {"kind": "rectangle", "width": 0.02, "height": 0.001,
                         "centre": [0.0, -0.0015]}}
#: strain indices: shears Gamma1, Gamma2, extension Gamma3, bending K1, K2, torsion K3
G1, G2, G3, K1, K2, K3 = range(6)
NAMES = ("Gamma1", "Gamma2", "Gamma3", "K1", "K2", "K3")


def _toml_inline(m: dict) -> str:
    """An inline TOML table for the command line (numbers, strings, lists, tables)."""
    def value(v: Any) -> str:
        if isinstance(v, str):
            return f'"{v}"'
        if isinstance(v, dict):
            return _toml_inline(v)
        if isinstance(v, (list, tuple)):
            return "[" + ", ".join(value(x) for x in v) + "]"
        return repr(v)
    return "{" + ", ".join(f"{k} = {value(v)}" for k, v in m.items()) + "}"


FILM_SETS = (f"materials.film={_toml_inline(FILM_MATERIAL)}",
             f"section.regions.2={_toml_inline(FILM_REGION)}")


def _g(x: float, digits: int = 4) -> str:
    """A number to ``digits`` significant digits (0 as 0)."""
    if x == 0 or not math.isfinite(x):
        return "0" if x == 0 else str(x)
    return f"{x:.{digits}g}"


def bending_modulus(K: np.ndarray, V: np.ndarray, keep: int = K1,
                    across: int = G2) -> Any:
    """EI*(s) [N m^2] of bending with curvature ``keep``: (K + s V) condensed onto it with
    every other resultant zero except the shear force across the bending plane, whose
    strain ``across`` is held at zero (Euler-Bernoulli)."""
    free = [keep] + [i for i in range(6) if i not in (keep, across)]

    def EI(s: complex) -> complex:
        M = (K + s * V)[np.ix_(free, free)]
        return 1.0 / complex(np.linalg.inv(M)[0, 0])

    return EI


def first_bending(res: Any, V: np.ndarray, L: float) -> dict[str, float]:
    """omega_d [rad/s] and zeta of the first bending mode (about d1) of a clamped-free
    cantilever of length L of this section (complex-modulus Euler-Bernoulli beam)."""
    from references.viscoelastic_beam import damping_ratio, euler_bernoulli_eigenvalues

    lam = euler_bernoulli_eigenvalues(1, L=L, rho=res.mass_per_length, A=1.0, I=1.0,
                                      E=bending_modulus(res.stiffness, V))[0]
    return {"omega": float(lam.imag), "zeta": float(damping_ratio(lam))}


def creep(K: np.ndarray, V: np.ndarray, theta: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Strains psi(t) (6, nt) of a piece of the section under the resultants theta applied
    at t = 0: K psi + V psi' = theta, psi(0) = 0, i.e. psi = (I - exp(-V^-1 K t)) K^-1 theta
    (V invertible)."""
    from scipy.linalg import expm

    A = np.linalg.solve(V, K)
    final = np.linalg.solve(K, theta)
    return np.column_stack([final - expm(-A * tk) @ final for tk in t])


def _norm(M: np.ndarray, i: int, j: int) -> float:
    return float(M[i, j] / math.sqrt(abs(M[i, i] * M[j, j])))


def _analyse(spec: Any, overrides: dict, out: Path, command: str, timings: Any,
             label: str) -> tuple[Any, Any]:
    from runtime.io.section_files import write_section
    from runtime.problem.section_analysis import analyse_problem_section, load_section

    s = load_section(spec, overrides)
    with timings.phase(f"section analysis: {label}"):
        res = analyse_problem_section(s)
    write_section(res, out / label, s, command)
    return s, res


def _cable(res: Any) -> dict[str, Any]:
    from references import section_analysis as ref

    mats = res.info["materials"]
    regions = res.info["regions"]
    radii = [regions[0]["shape"]["radius"], regions[1]["shape"]["outer_radius"],
             regions[2]["shape"]["outer_radius"]]
    layers = [(mats[r["material"]]["youngs_modulus"], mats[r["material"]]["poisson_ratio"],
               mats[r["material"]].get("tau_S", 0.0), mats[r["material"]].get("tau_B", 0.0))
              for r in regions]
    summed = ref.concentric_sum(radii, layers)
    rows = []
    for i in (G3, K1, K3):
        k, v, vn = (float(M[i, i]) for M in (res.stiffness, res.viscosity,
                                             res.viscosity_naive))
        rows.append({"strain": NAMES[i], "K": _g(k), "K_sum": _g(summed.K[i]),
                     "V": _g(v), "V_sum": _g(summed.V[i]), "Vn": _g(vn),
                     "Vn_sum": _g(summed.V_naive[i]), "ratio": _g(v / vn, 3),
                     "dK": _g(100 * (k / summed.K[i] - 1), 2),
                     "dV": _g(100 * (v / summed.V[i] - 1), 2)})
    shear = {"V": _g(res.viscosity[G1, G1]), "Vn": _g(res.viscosity_naive[G1, G1]),
             "ratio": _g(res.viscosity[G1, G1] / res.viscosity_naive[G1, G1], 3)}
    modes = {route: first_bending(res, V, CABLE_LENGTH) for route, V in
             (("consistent", res.viscosity), ("naive", res.viscosity_naive))}
    return {"rows": rows, "shear": shear, "modes": modes, "layers": [
        {"name": r["name"], "material": r["material"], "E": _g(lay[0]), "nu": _g(lay[1]),
         "tau_S": _g(lay[2])} for r, lay in zip(regions, layers, strict=True)]}


def _couplings(res: Any, pairs: tuple[tuple[int, int], ...]) -> list[dict[str, str]]:
    K, V, Vn = res.stiffness, res.viscosity, res.viscosity_naive
    return [{"pair": f"{NAMES[i]}-{NAMES[j]}", "K": _g(_norm(K, i, j), 3),
             "V": _g(_norm(V, i, j), 3), "Vn_row": _g(_norm(Vn, i, j), 3),
             "Vn_col": _g(_norm(Vn, j, i), 3)} for i, j in pairs]


def _strip(res: Any) -> dict[str, Any]:
    K = res.stiffness
    modes = {}
    for route, V in (("consistent", res.viscosity), ("naive", res.viscosity_naive)):
        modes[route] = first_bending(res, V, STRIP_LENGTH)
        modes[route + "_uncoupled"] = first_bending(res, np.diag(np.diag(V)), STRIP_LENGTH)
    theta = np.zeros(6)
    theta[G3] = 1.0
    final = np.linalg.solve(K, theta)
    start = {route: np.linalg.solve(V, theta) for route, V in
             (("consistent", res.viscosity), ("naive", res.viscosity_naive))}
    return {"couplings": _couplings(res, ((G3, K3), (G1, K1), (G2, K2))), "modes": modes,
            "twist_per_stretch": {"final": _g(final[K3] / final[G3], 3),
                                  **{r: _g(v[K3] / v[G3], 3) for r, v in start.items()}},
            "EI1": _g(K[K1, K1]), "EI2": _g(K[K2, K2])}


def _film(res: Any, strip: Any) -> dict[str, Any]:
    modes = {route: first_bending(res, V, STRIP_LENGTH) for route, V in
             (("consistent", res.viscosity), ("naive", res.viscosity_naive))}
    mm = 1e3
    centres = [(what, p[1] * mm) for what, p in (
        ("elastic centroid (reference point)", res.elastic_centroid),
        ("shear centre", res.shear_centre), ("mass centre", res.mass_centre),
        ("viscous centroid, consistent", res.viscous_centroid),
        ("viscous centroid, naive", res.viscous_centroid_naive))]
    return {"centres": [{"what": w, "x2": _g(y, 3)} for w, y in centres],
            "couplings": _couplings(res, ((G3, K1),)), "modes": modes,
            "EA_gain": _g(100 * (res.stiffness[G3, G3] / strip.stiffness[G3, G3] - 1), 2),
            "V_gain": _g(res.viscosity[G3, G3] / strip.viscosity[G3, G3], 3)}


def _fig_creep(strip: Any, film: Any, path: Path) -> Path:
    """Twist per stretch of the strip, and the film strip's curvature per stretch, after
    an axial force applied at t = 0 at the elastic centroid."""
    from runtime.io.figures import pyplot, save

    plt = pyplot()
    fig, axes = plt.subplots(1, 2, figsize=(9.0, 3.4), layout="constrained")
    theta = np.zeros(6)
    theta[G3] = 1.0
    for ax, res, j, what in ((axes[0], strip, K3, "twist K3 / stretch Gamma3 [1/m]"),
                             (axes[1], film, K1, "curvature K1 / stretch Gamma3 [1/m]")):
        # to 6 times the slowest retardation time of either route
        slowest = max(1.0 / float(np.min(np.linalg.eigvals(np.linalg.solve(
            V, res.stiffness)).real)) for V in (res.viscosity, res.viscosity_naive))
        t = np.linspace(0.0, 6.0 * slowest, 241)[1:]
        for route, V, style in (("consistent", res.viscosity, "C0-"),
                                ("naive", res.viscosity_naive, "C1--")):
            psi = creep(res.stiffness, V, theta, t)
            ax.plot(t * 1e3, psi[j] / psi[G3], style, lw=1.2, label=f"{route} V")
        final = np.linalg.solve(res.stiffness, theta)
        ax.axhline(final[j] / final[G3], color="k", lw=0.8, ls=":",
                   label="elastic (t -> infinity)")
        ax.set_xlabel("t [ms]")
        ax.set_ylabel(what)
        ax.legend(fontsize=7)
    axes[0].set_title("angle-ply strip: twist lags stretch", fontsize=9)
    axes[1].set_title("strip with damping film: bends while it creeps", fontsize=9)
    return save(fig, path, dpi=110)


def write_sections_notes(path: Path = Path("notes/sections.md"),
                         out: Path = Path("results/sections"),
                         command: str = "kvrod notes-sections") -> Path:
    """Analyse the three sections into ``out`` and render ``path`` (figures under
    ``path.parent / "figures"``; the wall times of this run, ``command``, in
    ``out/run-info.md``)."""
    import shutil

    from reports.run_info import Timings
    from runtime.problem.registry import EXAMPLES_DIR

    path, out = Path(path), Path(out)
    figs = path.parent / "figures"
    figs.mkdir(parents=True, exist_ok=True)
    timings = Timings(command)
    cable_file = EXAMPLES_DIR / "cable_section.toml"
    strip_file = EXAMPLES_DIR / "fibre_strip_section.toml"
    film_overrides = {"materials.film": FILM_MATERIAL, "section.regions.2": FILM_REGION}
    _, cab = _analyse(cable_file, {}, out, f"kvrod section examples/cable_section.toml "
                      f"--out {out.as_posix()}/cable", timings, "cable")
    _, strip = _analyse(strip_file, {}, out, "kvrod section examples/fibre_strip_section.toml"
                        f" --out {out.as_posix()}/fibre_strip", timings, "fibre_strip")
    _, film = _analyse(strip_file, film_overrides, out, "kvrod section "
                       "examples/fibre_strip_section.toml "
                       + " ".join(f"--set '{s}'" for s in FILM_SETS)
                       + f" --out {out.as_posix()}/fibre_strip_film", timings,
                       "fibre_strip_film")
    pictures = {}
    for label in RESULTS:
        pictures[label] = figs / f"sections_{label}.png"
        shutil.copyfile(out / label / "section.png", pictures[label])
    with timings.phase("damping estimates and creep"):
        ctx_cable, ctx_strip = _cable(cab), _strip(strip)
        ctx_film = _film(film, strip)
        pictures["creep"] = _fig_creep(strip, film, figs / "sections_creep.png")
    ctx = {
        "out": out.as_posix(), "cable": ctx_cable, "strip": ctx_strip,
        "film": ctx_film, "CABLE_LENGTH": CABLE_LENGTH, "STRIP_LENGTH": STRIP_LENGTH,
        "film_sets": FILM_SETS, "g": _g,
        "cable_mesh": {"elements": cab.n_elements, "tol": _g(cab.tolerance)},
        "figs": {k: Path(v).relative_to(path.parent).as_posix() for k, v in pictures.items()},
    }
    write_text(path, render(TEMPLATE_DIR, "sections.md.jinja", **ctx))
    timings.write(out)
    return path
