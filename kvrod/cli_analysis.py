"""`kvrod modes`, `kvrod calibrate` and `kvrod compare-damping`: the analyses of a rod
beyond a single run (computations in runtime/analysis and runtime/study; tables and files
in reports/analyses.py).

Wired into `kvrod/cli.py` by ``add_commands(subparsers, parser_class)``. Heavy imports
happen inside the commands; library code never prints, these commands do.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path


def _cli_error(message: str) -> Exception:
    from kvrod.errors import CliError

    return CliError(message)


# --------------------------------------------------------------------------------------
# kvrod modes
# --------------------------------------------------------------------------------------


def _cmd_modes(args) -> int:
    from kvrod.problem_args import problem_from_args, sensitivity_names

    if args.count < 1:
        raise _cli_error(f"kvrod modes: --count must be >= 1, got {args.count}")
    if args.near is not None and not (math.isfinite(args.near) and args.near >= 0):
        raise _cli_error(f"kvrod modes: --near must be a frequency >= 0 Hz, got {args.near}")
    problem = problem_from_args(args, "modes")
    if getattr(problem, "obstacles", ()):
        raise _cli_error(
            "kvrod modes: modes about a contact equilibrium are not available in this "
            "version (they need the contact linearised with its sticking contacts held): "
            "without [[obstacles]] kvrod modes gives the free rod's modes; kvrod simulate "
            "gives the damped motion on the obstacles")
    contact = getattr(problem, "contact", None)
    if contact is not None and contact.self_contact:
        raise _cli_error(
            "kvrod modes: contact.self = true: modes about a self-contact equilibrium are "
            "not available in this version (they need the contact linearised with its "
            "sticking contacts held): with contact.self = false kvrod modes gives the "
            "free rod's modes; kvrod simulate gives the damped motion")
    from runtime.io.assembly_results import is_assembly

    if is_assembly(problem):
        if getattr(args, "sensitivities", None):
            raise _cli_error("kvrod modes: --sensitivities of an assembly's modes are not "
                             "available in this version (a single rod's are; kvrod simulate "
                             "and kvrod static give an assembly's sensitivities)")
        return _assembly_modes(args, problem)
    sens = sensitivity_names(args, problem, "modes")
    nq = 6 * problem.rod.elements
    if args.count > nq:
        raise _cli_error(f"kvrod modes: --count {args.count} exceeds the {nq} degrees of "
                         f"freedom of {problem.rod.elements} elements")
    out = _modes_folder(args, problem)
    from runtime.io.folder import results_folder

    with results_folder(out, "modes", markers=("modes.json",), overwrite=args.overwrite,
                        names=("modes.json", "modes.npz", "mode_shapes.png",
                               "mode_shapes_3d.png")):
        return _modes_into(args, problem, out, sens)


def _modes_into(args, problem, out: Path, sensitivities: list[str] | None = None) -> int:
    from reports.analyses import modes_table, run_modes, write_modes

    target = None if args.near is None else 2 * math.pi * args.near
    res = run_modes(problem, args.count, args.deformed, target=target,
                    sensitivities=sensitivities)
    modes = res["modes"]
    state = "pre-deformed by its static loads" if args.deformed else "straight, unloaded"
    near = "" if args.near is None else f"; the {args.count} modes nearest {args.near:g} Hz"
    print(f"{problem.name}: N = {problem.rod.elements}, {problem.describe_material()}, "
          f"{state}{near}")
    if res["static_tip"] is not None:
        print(f"static tip [m]: {[round(float(v), 6) for v in res['static_tip']]}")
    print(modes_table(modes))
    for m in modes:
        if m.doubt:
            print(f"kvrod modes: warning: mode {m.index} ({m.family}): {m.doubt}",
                  file=sys.stderr)
    paths = write_modes(res, out, figures=args.plots)
    print(f"wrote {out}/{', '.join(p.name for p in paths)}")
    return 0


def _modes_folder(args, problem) -> Path:
    from runtime.io.folder import safe_name

    return Path(args.out) if args.out else Path("results") / (
        f"modes-{safe_name(problem.name)}" + ("-deformed" if args.deformed else ""))


def _assembly_modes(args, problem) -> int:
    """`kvrod modes ASSEMBLY`: the lowest --count modes of the whole assembly about its
    reference or (--deformed) its static equilibrium; checked before the folder is
    locked."""
    from reports.analyses import (
        assembly_modes_table,
        assembly_reduced_size,
        run_assembly_modes,
        write_assembly_modes,
    )
    from runtime.io.folder import results_folder
    from runtime.model import build
    from runtime.problem.assemble_system import build_system

    if args.near is not None:
        raise _cli_error("kvrod modes: --near is for a single rod; an assembly's modes are "
                         "its --count lowest")
    build.require_generated()
    amap = build_system(problem)
    nq = assembly_reduced_size(amap)
    if args.count > nq:
        raise _cli_error(f"kvrod modes: --count {args.count} exceeds the {nq} degrees of "
                         f"freedom of this assembly (its rods' free nodes and segments)")
    out = _modes_folder(args, problem)
    from runtime.solvers.statics import StaticSolveError

    with results_folder(out, "modes", markers=("modes.json",), overwrite=args.overwrite,
                        names=("modes.json", "modes.npz", "mode_shapes_3d.png")):
        try:
            res = run_assembly_modes(problem, args.count, args.deformed, amap=amap)
        except StaticSolveError as exc:
            raise _cli_error(f"kvrod modes: --deformed: no static equilibrium to linearise "
                             f"about ({' '.join(str(exc).split())}); kvrod static "
                             f"{args.problem} shows the load path, or drop --deformed"
                             ) from None
        state = ("about its static equilibrium under the loads" if args.deformed
                 else "about its unloaded reference")
        print(f"{problem.name}: an assembly of {len(problem.rods)} rods "
              f"({', '.join(problem.rods)}), {len(problem.joints)} joints, "
              f"{len(problem.bodies)} bodies; {state}")
        if res["static"] is not None:
            for k, v in res["static"]["ends"].items():
                print(f"  static {k} [m]: {[round(x, 9) for x in v]}")
        print(assembly_modes_table(res["modes"]))
        paths = write_assembly_modes(res, out, figures=args.plots)
    print(f"wrote {out}/{', '.join(p.name for p in paths)}")
    return 0


# --------------------------------------------------------------------------------------
# kvrod calibrate
# --------------------------------------------------------------------------------------


def _cmd_calibrate_dma(args) -> int:
    """`kvrod calibrate --dma FILE --nu NU`: a Prony series from storage and loss moduli;
    everything is checked before the folder is locked."""
    from reports.analyses import write_dma_fit
    from runtime.analysis import dma
    from runtime.io.folder import results_folder
    from runtime.problem.materials import material_from_mapping

    if args.nu is None:
        raise _cli_error("kvrod calibrate: --dma needs --nu (Poisson's ratio of the "
                         "material: a uniaxial DMA test does not measure it)")
    if not (-1.0 < args.nu < 0.5):
        raise _cli_error(f"kvrod calibrate: --nu = {args.nu} is outside the allowed range: "
                         "-1 < nu < 1/2")
    if not (math.isfinite(args.per_decade) and 0 < args.per_decade <= 8):
        raise _cli_error(f"kvrod calibrate: --per-decade = {args.per_decade} is outside the "
                         "allowed range: 0 < per-decade <= 8")
    if not (math.isfinite(args.density) and args.density > 0):
        raise _cli_error(f"kvrod calibrate: --density = {args.density} must be > 0 kg/m^3")
    try:
        data = dma.load_dma(args.dma)
    except ValueError as exc:
        raise _cli_error(f"kvrod calibrate: {exc}") from None
    fit = dma.fit_prony(*data, poisson_ratio=args.nu, per_decade=args.per_decade)
    table = fit.material(args.density)
    try:
        material_from_mapping(table)      # a material kvrod accepts, before writing it
    except ValueError as exc:             # the data's moduli, with --density
        raise _cli_error(f"kvrod calibrate: {args.dma}: the fitted material is not one "
                         f"kvrod accepts (with --density {args.density:g} kg/m^3): "
                         f"{exc}") from None
    out = Path(args.out)
    with results_folder(out, "calibrate", markers=("dma.json",), overwrite=args.overwrite,
                        names=("dma.json", "dma.png", "material.toml")):
        write_dma_fit(fit, table, out, f"kvrod calibrate --dma {args.dma} --nu {args.nu}")
    print(f"{fit.omega.size} frequencies, {fit.theta_grid.size} relaxation times tried, "
          f"{fit.theta.size} kept; E_inf = {fit.E_inf:.6g} Pa (+- {fit.std_E_inf:.2g})")
    for t, e, sd in zip(fit.theta, fit.E, fit.std_E, strict=True):
        print(f"  tau = {t:.4g} s: E = {e:.6g} Pa (+- {sd:.2g})")
    print(f"relative RMS residual {fit.rel_rms:.3g}; wrote {out}/dma.json, material.toml, "
          "dma.png")
    if not fit.accepted:
        print(f"kvrod calibrate: fit rejected: {'; '.join(fit.doubts)}", file=sys.stderr)
        return 1
    return 0


def _cmd_calibrate(args) -> int:
    """Validate the data and the model first, then lock the folder and fit."""
    from runtime.io.folder import results_folder
    from runtime.problem.registry import load_problem
    from runtime.study import calibration as cal

    if args.dma is not None:
        return _cmd_calibrate_dma(args)

    if args.tau0 is not None and not (math.isfinite(args.tau0) and args.tau0 > 0):
        raise _cli_error(f"kvrod calibrate: --tau0 = {args.tau0} must be a finite time > 0 s")
    kw: dict = {}
    if args.tip_force is not None:
        kw["tip_force"] = args.tip_force
    n = 16 if args.n_elements is None else args.n_elements
    # the model is checked before the data, so a bad flag is named as such
    problem = load_problem(args.problem, {"n_elements": n, **kw})
    if problem.material.model != "kelvin_voigt":
        raise _cli_error(f"kvrod calibrate: --problem {args.problem}: the fit is of the "
                         f"Kelvin-Voigt tau, but this rod's material is "
                         f"{problem.material.model}; give a Kelvin-Voigt rod, or fit a "
                         "generalized Maxwell material to DMA data with --dma")
    if args.tau0 is not None:
        lo, hi = cal.tau_range(problem)
        if not lo <= args.tau0 <= hi:
            raise _cli_error(f"kvrod calibrate: --tau0 = {args.tau0:g} s is outside the "
                             f"allowed range: {lo:g} ... {hi:.3g} s for this rod (below: no "
                             "measurable damping; above: the viscous forces swamp the "
                             "inertia)")
    from runtime.analysis.records import load_csv

    try:
        if args.mode == "signal":
            data = cal.validate_signal(*load_csv(args.data, ("t", "x")))
            cal.check_record(data[0], data[1], problem)
        else:
            data = (cal.validate_decrements(*load_csv(args.data, ("delta",))),)
    except ValueError as exc:
        from runtime.errors import ParameterError

        if isinstance(exc, ParameterError):
            raise
        if (isinstance(exc, cal.RecordSignError) and args.tip_force is not None
                and args.tip_force < 0):
            raise _cli_error(f"kvrod calibrate: --tip-force = {args.tip_force:g} N is "
                             f"negative: it releases the model from x = {exc.release_x:.4g} "
                             f"m, the other side of the record's first maximum "
                             f"{exc.first:.4g} m; give the magnitude of the static tip force "
                             "(> 0; its direction is the problem's end load)") from None
        raise _cli_error(f"kvrod calibrate: {args.data}: {exc}") from None
    with results_folder(Path(args.out), "calibrate", markers=("calibration.json",),
                        overwrite=args.overwrite,
                        names=("calibration.json", "calibration.png")):
        return _calibrate_into(args, Path(args.out), data, problem)


def _calibrate_into(args, out: Path, data: tuple, problem) -> int:
    from runtime.io.results import write_json
    from runtime.study import calibration as cal

    if args.mode == "signal":
        res = cal.calibrate_signal(*data, problem=problem, tau0=args.tau0,
                                   n_elements=problem.rod.elements)
    else:
        res = cal.calibrate_decrements(data[0], problem=problem, tau0=args.tau0)
    write_json(out / "calibration.json", {"data": str(args.data), **res.summary()})
    cal.plot_calibration(res, out / "calibration.png")
    lo, hi = res.ci95
    print(f"mode: {res.mode}, {res.n_data} data, start tau0 = {res.tau0 * 1e3:.4f} ms")
    print(f"tau = {res.tau * 1e3:.4f} ms  (standard error {res.std_error * 1e3:.4f} ms; "
          f"95 % CI [{lo * 1e3:.4f}, {hi * 1e3:.4f}] ms)")
    print(f"residual RMS {res.residual_rms:.4g}{' m' if res.mode == 'signal' else ''}, "
          f"{res.nfev} model evaluations; {res.message}")
    print(f"wrote {out}/calibration.json, calibration.png")
    if not res.accepted:
        why = "; ".join(res.doubts) or f"the fit did not converge: {res.message}"
        print(f"kvrod calibrate: fit rejected: {why}", file=sys.stderr)
        return 1
    return 0


# --------------------------------------------------------------------------------------
# kvrod compare-damping (computation: runtime/study/compare_damping.py)
# --------------------------------------------------------------------------------------


def _cmd_compare(args) -> int:
    if args.n_elements < 2:
        raise _cli_error(f"kvrod compare-damping: --n-elements must be >= 2, got "
                         f"{args.n_elements}")
    from reports.analyses import compare_table, write_compare
    from runtime.io.folder import results_folder
    from runtime.study import compare_damping as cd

    cd.check_inputs(args.n_elements, args.tau_S, args.tau_B, args.nu, args.tip_force,
                    args.rtol)
    with results_folder(Path(args.out), "compare-damping", markers=("compare_damping.json",),
                        overwrite=args.overwrite,
                        names=("compare_damping.json", "compare_damping.md",
                               "compare_signals.png", "compare_zeta.png")):
        res = cd.compare_damping(n_elements=args.n_elements, tau_S=args.tau_S,
                                 tau_B=args.tau_B, poisson_ratio=args.nu,
                                 tip_force=args.tip_force, rtol=args.rtol)
        print(compare_table(res))
        paths = write_compare(res, Path(args.out))
    print(f"wrote {Path(args.out)}/{', '.join(p.name for p in paths)}")
    return 0


# --------------------------------------------------------------------------------------
# wiring
# --------------------------------------------------------------------------------------


def add_commands(sub, parser_class) -> None:
    """Add `modes`, `calibrate` and `compare-damping` to ``sub``.

    parser_class is the one-line-error parser the caller created ``sub`` with (kept for
    symmetry with the other command modules; argparse passes it on to the subparsers).
    """
    _ = parser_class
    m = sub.add_parser("modes", help="damped modal analysis (frequencies, damping ratios, "
                                     "mode shapes)")
    from kvrod.problem_args import add_problem_arguments, add_sensitivity_arguments

    add_problem_arguments(m)
    add_sensitivity_arguments(
        m, errcon=False,
        help_text="derivatives of every mode's omega and zeta with respect to these "
                  "parameters (names as for kvrod simulate --sensitivities: "
                  "material.youngs_modulus, tau_S, section.width, ...), written to "
                  "modes.json as sensitivities: {parameter: {omega: [...], zeta: [...]}}")
    m.add_argument("--count", type=int, default=10, help="number of modes (default 10)")
    m.add_argument("--near", type=float, metavar="HZ",
                   help="the --count modes whose natural frequency is nearest HZ (Hz) "
                        "instead of the lowest (numbered within those shown; no continuum "
                        "column; a single rod only)")
    m.add_argument("--deformed", action="store_true",
                   help="linearise about the static state under the problem's loads "
                        "(an assembly's: its static equilibrium, joints and bodies "
                        "included)")
    m.add_argument("--plots", action="store_true",
                   help="also draw mode_shapes.png and mode_shapes_3d.png (an "
                        "assembly: mode_shapes_3d.png; or later: kvrod plot DIR)")
    m.add_argument("--out", help="results folder (default results/modes-SCENARIO[-deformed])")
    m.add_argument("--overwrite", action="store_true",
                   help="replace a result already in --out (default: refuse)")
    m.set_defaults(func=_cmd_modes)

    c = sub.add_parser("calibrate", help="fit tau (= tau_S = tau_B) of the cantilever to "
                                         "measured decay, or a Prony series to DMA data")
    src = c.add_mutually_exclusive_group(required=True)
    src.add_argument("--data",
                     help="CSV: columns t, x (signal: time [s] since release, tip x [m]) "
                          "or a column delta (log decrements)")
    src.add_argument("--dma",
                     help="CSV of a DMA test: columns frequency_hz (Hz) or omega (rad/s), "
                          "storage and loss (Pa): fits a generalized Maxwell (Prony) series "
                          "and writes material.toml for a problem file")
    c.add_argument("--nu", type=float, default=None,
                   help="with --dma: Poisson's ratio of the material (every branch; "
                        "uniaxial DMA does not measure it)")
    c.add_argument("--per-decade", dest="per_decade", type=float, default=3.0,
                   help="with --dma: relaxation times per decade of frequency (default 3; "
                        "two leave a few %% of error on a single Debye peak)")
    c.add_argument("--density", type=float, default=1000.0,
                   help="with --dma: density [kg/m^3] written into material.toml")
    c.add_argument("--mode", choices=("signal", "decrements"), default="signal",
                   help="signal: simulate the problem; decrements: linear modal model")
    c.add_argument("--problem", default="cantilever",
                   help="the rod that was measured (problem file or built-in name)")
    c.add_argument("--n-elements", dest="n_elements", type=int,
                   help="elements of the model (default 16)")
    c.add_argument("--tip-force", dest="tip_force", type=float,
                   help="static tip force before release [N] (paper: 0.05)")
    c.add_argument("--tau0", type=float, help="starting value [s] (default: from the data)")
    c.add_argument("--out", default="results/calibration", help="results folder")
    c.add_argument("--overwrite", action="store_true",
                   help="replace a result already in --out (default: refuse)")
    c.set_defaults(func=_cmd_calibrate)

    d = sub.add_parser("compare-damping", help="consistent eta_E vs naive eta~_E in "
                                               "simulation (bending and axial decay)")
    d.add_argument("--n-elements", dest="n_elements", type=int, default=20,
                   help="elements (default 20)")
    d.add_argument("--tau-S", dest="tau_S", type=float, default=0.04,
                   help="shear retardation time [s] (default 0.04)")
    d.add_argument("--tau-B", dest="tau_B", type=float, default=0.0,
                   help="bulk retardation time [s] (default 0: no bulk viscosity)")
    d.add_argument("--nu", type=float, default=0.3, help="Poisson's ratio (default 0.3)")
    d.add_argument("--tip-force", dest="tip_force", type=float, default=0.001,
                   help="static tip force of the bending release [N] (default 0.001: "
                        "small amplitude, linear regime)")
    d.add_argument("--rtol", type=float, default=1e-7, help="integrator tolerance")
    d.add_argument("--out", default="results/compare-damping", help="results folder")
    d.add_argument("--overwrite", action="store_true",
                   help="replace a result already in --out (default: refuse)")
    d.set_defaults(func=_cmd_compare)
