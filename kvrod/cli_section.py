"""`kvrod section FILE.toml --out DIR`: the cross-section analysis (section.json,
section.png, a table on the terminal).

Wired into `kvrod/cli.py` by ``add_commands(subparsers, parser_class)``. Heavy imports
happen inside the commands; library code never prints, these commands do.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    import numpy as np

_ROWS = ("T1", "T2", "T3", "M1", "M2", "M3")
_COLS = ("Gamma1", "Gamma2", "Gamma3", "K1", "K2", "K3")


#: entries below this fraction of the geometric mean of their diagonal entries are printed
#: as 0 (round-off of the analysis; section.json keeps them)
SHOWN_ZERO = 1e-10


def _matrix(title: str, M: np.ndarray) -> list[str]:
    import numpy as np

    d = np.sqrt(np.abs(np.outer(np.diag(M), np.diag(M))))
    lines = [title, "      " + "".join(f"{c:>12}" for c in _COLS)]
    for r, row, drow in zip(_ROWS, M, d, strict=True):
        lines.append(f"  {r:<4}" + "".join(
            f"{0 if abs(v) <= SHOWN_ZERO * dd else v:>12.4g}" for v, dd in
            zip(row, drow, strict=True)))
    return lines


def _point(p: Any) -> str:
    return "-" if p is None else f"({p[0]:.6g}, {p[1]:.6g})"


def section_table(res: Any) -> str:
    """What `kvrod section` prints: the matrices, centres, inertia and the mesh."""
    import numpy as np

    info = res.info
    kinds = ", ".join(f"{r['name']} ({r['material']}, {r['shape']['kind']})"
                      for r in info.get("regions", []))
    lines = [f"section {info.get('name', '')}: {info.get('kind', '')}; regions: {kinds}",
             f"(matrix entries below {SHOWN_ZERO:g} of the geometric mean of their diagonal "
             "entries are shown as 0; section.json has them all)"]
    lines += _matrix("stiffness K about the elastic centroid [N; N m; N m^2] (rows: "
                     "resultants, columns: strains):", res.stiffness)
    lines += _matrix("consistent viscosity V [the same units times s]:", res.viscosity)
    lines += _matrix("naive viscosity V~ (traction route; not symmetric in general):",
                     res.viscosity_naive)
    damping = info.get("damping", "consistent")
    lines.append(f"damping = {damping!r} (section.damping): the rod takes "
                 f"{'V' if damping == 'consistent' else 'V~'}")
    lines.append(f"elastic centroid = reference point [m]: {_point(res.elastic_centroid)}; "
                 f"shear centre: {_point(res.shear_centre)}")
    lines.append(f"viscous centroid [m]: consistent {_point(res.viscous_centroid)}, naive "
                 f"{_point(res.viscous_centroid_naive)}")
    ri = res.rotary_inertia
    lines.append(f"mass per length {res.mass_per_length:.6g} kg/m, mass centre "
                 f"{_point(res.mass_centre)} m; rotary inertia about it [kg m]: I11 "
                 f"{ri['I11']:.6g}, I22 {ri['I22']:.6g}, I12 {ri['I12']:.4g}, polar "
                 f"{ri['polar']:.6g}")
    lines.append(f"torsional stiffness 1/F66 = {res.torsional_stiffness:.6g} N m^2; area "
                 f"{res.area:.6g} m^2")
    change = "-" if not math.isfinite(res.achieved_change) else f"{res.achieved_change:.2g}"
    lines.append(f"mesh: {res.n_elements} six-node triangles, {res.n_nodes} nodes, h = "
                 f"{res.mesh_size:.4g} m; {'converged' if res.converged else 'NOT converged'}"
                 f" to {res.tolerance:g} (last change of a diagonal entry {change})")
    cf = info.get("closed_form")
    if cf:
        k = np.diag(res.stiffness)
        sf = cf["shear_factors"]
        lines.append(f"the rod model of the closed-form formulas (kvrod simulate's; shear "
                     f"factors {sf['kind']}: kappa_1 {sf['kappa_1']:.4g}, kappa_2 "
                     f"{sf['kappa_2']:.4g}):")
        lines.append("  stiffness diagonal " + " ".join(f"{v:.6g}" for v in
                                                        cf["stiffness_diagonal"]))
        lines.append("  viscosity diagonal " + " ".join(f"{v:.6g}" for v in
                                                        cf["viscosity_diagonal"]))
        dev = [abs(a / b - 1) for a, b in zip(cf["stiffness_diagonal"], k, strict=True)]
        lines.append("  relative difference of the stiffness from the section analysis: "
                     + " ".join(f"{d:.2g}" for d in dev) + " (the shear entries differ by "
                     "the shear factors unless section.shear_correction = \"energy\")")
    return "\n".join(lines)


def _cmd_section(args) -> int:
    from kvrod.errors import CliError
    from kvrod.problem_args import parse_set
    from runtime.io.folder import results_folder, safe_name
    from runtime.io.section_files import SECTION_FILES, write_section
    from runtime.problem.section_analysis import analyse_problem_section, load_section

    if not (math.isfinite(args.tol) and 1e-9 <= args.tol <= 0.1):
        raise CliError(f"kvrod section: --tol = {args.tol} is outside the allowed range: "
                       "1e-9 ... 0.1 (relative change of the diagonal entries)")
    overrides = dict(parse_set(item) for item in args.sets)
    spec = load_section(args.file, overrides)            # everything checked here
    out = Path(args.out) if args.out else Path("results") / f"section-{safe_name(spec.name)}"
    with results_folder(out, "section", markers=("section.json",), overwrite=args.overwrite,
                        names=SECTION_FILES):
        res = analyse_problem_section(spec, tol=args.tol)
        write_section(res, out, spec, getattr(args, "command_line", "kvrod section"))
    print(section_table(res))
    print(f"wrote {out}/{', '.join(SECTION_FILES)}")
    for w in res.warnings:
        print(f"kvrod: warning: {w}", file=sys.stderr)
    return 0


def add_commands(sub, parser_class) -> None:
    """Add `section` to ``sub`` (parser_class: kept for symmetry with the other command
    modules)."""
    _ = parser_class
    s = sub.add_parser("section", help="cross-section analysis: 6x6 stiffness, consistent and "
                                       "naive viscosity, centres, inertia of a section")
    s.add_argument("file", help="a problem file, or a section file ([section] with "
                                "[materials.NAME], or a shape with [material]); or the name "
                                "of one in examples/ (e.g. cable_section)")
    s.add_argument("--out", help="results folder (default results/section-NAME): "
                                 "section.json, section.png")
    s.add_argument("--tol", type=float, default=1e-4,
                   help="mesh refinement stops when every diagonal entry of the stiffness "
                        "and both viscosities changes by less than this (default 1e-4)")
    s.add_argument("--set", dest="sets", action="append", default=[], metavar="PATH=VALUE",
                   help="set any key of the file (repeatable; TOML values): --set "
                        "materials.pvc.tau_S=0.02, --set section.damping=naive")
    s.add_argument("--overwrite", action="store_true",
                   help="replace a result already in --out (default: refuse)")
    s.set_defaults(func=_cmd_section)
