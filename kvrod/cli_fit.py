"""`kvrod fit PROBLEM --data DATA.csv --params P1,P2`: identify a rod's parameters from
measurements (computation in runtime/study/fit*.py; docs/design.md, "Identification").

Wired into `kvrod/cli.py` by ``add_commands(subparsers, parser_class)``. Building the
parser imports nothing beyond the standard library and kvrod/problem_args.py; the layers are
imported inside the command, after the flags are checked.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

#: what the command writes into its folder (replaced by --overwrite)
FIT_FILES = ("fit.json", "fit.png")


def _error(message: str) -> Exception:
    from kvrod.errors import CliError

    return CliError(f"kvrod fit: {message}")


def _names(text: str) -> list[str]:
    names = [n.strip() for n in text.split(",")]
    if not text.strip() or any(not n for n in names):
        raise _error(f"--params {text!r}: give the parameters as P1,P2 (problem keys such as "
                     "material.youngs_modulus or their short names youngs_modulus, tau, "
                     "tau_S, tau_B)")
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise _error(f"--params names {', '.join(dup)} twice")
    return names


def _cmd_fit(args) -> int:
    """Check every flag, the parameters and the data, then lock --out and fit."""
    if args.max_iterations < 1:
        raise _error(f"--max-iterations must be >= 1, got {args.max_iterations}")
    if args.sigma is not None and not (math.isfinite(args.sigma) and args.sigma > 0):
        raise _error(f"--sigma must be a noise level > 0 (the data's unit), got {args.sigma}")
    names = _names(args.params)
    from kvrod.problem_args import problem_from_args
    from runtime.io.folder import results_folder, safe_name
    from runtime.study import fit as F
    from runtime.study.fit_data import check_against_problem, read_fit_data
    from runtime.study.fit_model import check_model
    from runtime.study.fit_parameters import parse_bounds, parse_start

    problem = problem_from_args(args, "fit")
    specs = F.parameter_specs(problem, names, parse_start(args.start, names),
                              parse_bounds(args.bounds, names))
    rods = getattr(problem, "rods", None)
    rod_names = list(rods) if isinstance(rods, dict) else None
    data = read_fit_data(args.data, rod_names)
    length = None
    if data.kind == "shape":
        length = (rods[data.rod].rod.length if data.rod is not None and rod_names
                  else problem.rod.length)
    check_against_problem(data, n_parameters=len(names), t_end=problem.simulation.t_end,
                          length=length)
    check_model(problem, data)
    out = Path(args.out) if args.out else Path("results") / f"fit-{safe_name(problem.name)}"
    with results_folder(out, "fit", markers=("fit.json",), overwrite=args.overwrite,
                        names=FIT_FILES):
        return _fit_into(args, out, problem, data, specs)


def _fit_into(args, out: Path, problem, data, specs) -> int:
    from runtime.io.results import write_json
    from runtime.study import fit as F
    from runtime.study.fit_plot import plot_fit

    print(f"{problem.name}: fitting {', '.join(s.name for s in specs)} to {data.count} "
          f"values of {args.data} ({data.kind}; model: {data.model})", flush=True)
    res = F.fit(problem, data, specs, sigma=args.sigma, max_evaluations=args.max_iterations)
    doc = res.to_json(getattr(args, "command_line", ""))
    plot_fit(res, out / "fit.png")
    write_json(out / "fit.json", doc)
    for s, v, (lo, hi) in zip(res.specs, res.theta, res.stats.intervals, strict=True):
        print(f"  {s.name} = {v:.6g} {s.unit}  95 % interval [{lo:.6g}, {hi:.6g}]  "
              f"(start {s.start:.6g})")
    rms = ", ".join(f"{k} {v:.3g}" for k, v in doc["residual_rms"].items())
    print(f"residual RMS: {rms}; {doc['iterations']} iterations, {doc['model_evaluations']} "
          f"model evaluations, {res.wall_time_s:.1f} s; {res.outcome.message}")
    print(f"wrote {out}/fit.json, fit.png")
    for w in res.warnings:
        print(f"kvrod fit: warning: {w}", file=sys.stderr)
    return 0 if res.outcome.converged else 1


def add_commands(sub, parser_class) -> None:
    """Add `kvrod fit` to ``sub`` (the problem flags exactly as `kvrod simulate`'s)."""
    from kvrod.problem_args import add_problem_arguments

    f = sub.add_parser("fit", help="identify a rod's parameters from measurements (a record, "
                                   "a static shape or measured modes) by least squares with "
                                   "exact sensitivities")
    add_problem_arguments(f)
    f.add_argument("--data", required=True,
                   help="CSV with a header: t and channels end.x end.y end.z start.x ... "
                        "(assemblies: NAME.end.y, NAME.start.z; any subset) for a record; s "
                        "and x, y, z (assemblies: NAME.x ...) for a static shape; mode "
                        "(rank, or FAMILY:K such as bending-2:1) and omega [rad/s] or "
                        "frequency_hz, and/or zeta for measured modes; SI units")
    f.add_argument("--params", required=True, metavar="P1,P2",
                   help="the parameters to fit: problem keys (material.youngs_modulus, "
                        "material.tau_S, material.branches.0.tau, rods.NAME.material.tau, "
                        "...) or their unique short names (youngs_modulus, tau, tau_S, tau_B)")
    f.add_argument("--start", action="append", default=[], metavar="P=V",
                   help="start value of a fitted parameter [SI] (repeatable; default: the "
                        "problem's value)")
    f.add_argument("--bounds", action="append", default=[], metavar="P=LO:HI",
                   help="narrow a parameter's range (repeatable; LO or HI may be empty; "
                        "default: the key's range of kvrod problem-keys)")
    f.add_argument("--sigma", type=float,
                   help="the data's noise level (standard deviation, in the data's unit; "
                        "modes: relative), if known: intervals from it and a test of the fit "
                        "against it (default: estimated from the residual)")
    f.add_argument("--max-iterations", dest="max_iterations", type=int, default=40,
                   help="most model evaluations of the whole record's fit (default 40)")
    f.add_argument("--out", help="results folder (default results/fit-<problem name>)")
    f.add_argument("--overwrite", action="store_true",
                   help="replace a finished fit in --out (default: refuse)")
    f.set_defaults(func=_cmd_fit)
    _ = parser_class
