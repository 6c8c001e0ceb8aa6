"""Command-line access to problems: the PROBLEM argument, ``--set`` and the short flags.

Every command that runs a problem (simulate, static, modes, sweep points) takes it the same
way: a problem file or built-in name, then overrides from ``--config`` (the earlier
format), the short flags (``--tau``, ``--E``, ``--n-elements``, ...) and ``--set
path=value`` (any key of the problem file, e.g. ``--set loads.0.time.start=0.5``), in
that order. A value may be an inline TOML table or array (``--set
'loads.1={kind="force", vector=[0,0,1]}'``); the index one past an array's last entry
appends an entry (:data:`SET_HELP`). The values go through the problem schema's checks
(one line naming the key, value and range).
"""

from __future__ import annotations

import argparse
import tomllib
from typing import Any

#: short flags: (flag, dest, type, help) -> alias of runtime.problem.schema.ALIASES
FLAGS: tuple[tuple[str, str, type, str], ...] = (
    ("--tau", "tau", float, "tau_S = tau_B = tau [s] (the paper's convention)"),
    ("--tau-S", "tau_S", float, "shear retardation time [s]"),
    ("--tau-B", "tau_B", float, "bulk retardation time [s]"),
    ("--E", "youngs_modulus", float, "Young's modulus [Pa]"),
    ("--nu", "poisson_ratio", float, "Poisson's ratio [-]"),
    ("--tip-force", "tip_force", float, "magnitude of the force at the s = L end [N]"),
    ("--n-elements", "n_elements", int, "number of elements"),
    ("--t-end", "t_end", float, "simulated time [s]"),
    ("--rtol", "rtol", float, "relative tolerance"),
    ("--atol", "atol", float, "absolute tolerance (default: scaled per field by the motion)"),
    ("--max-order", "max_order", int, "highest BDF order 1-5"),
    ("--error-control", "error_control", str, "what the BDF error test controls: auto "
     "(default), state (every unknown, velocities included) or configuration (positions, "
     "rotations, internal strains)"),
)


#: what --set does (its --help, and `kvrod problem-keys`)
SET_HELP = ("set any key of the problem (repeatable; TOML values, in order): "
            "--set material.tau=0.02, --set loads.0.vector=[0.1,0,0]; a whole table "
            "or entry as an inline table: --set 'material={youngs_modulus=2e6, tau=0.01}' "
            "replaces the material; an array of tables ([[loads]], "
            "[[material.branches]]) is indexed from 0 and the index one past its last "
            "entry appends one: --set 'loads.1={kind=\"force\", vector=[0,0,1]}' adds "
            "a second load; in an assembly: --set rods.NAME.material.tau=0.02, --set "
            "joints.0.rotational_stiffness=1, and the short flags set every rod")


def add_problem_arguments(p: argparse.ArgumentParser, required: bool = False) -> None:
    """PROBLEM, --config, the short flags, --set and --damping."""
    p.add_argument("problem", nargs=None if required else "?",
                   help="problem file (.toml) or built-in name (e.g. cantilever)")
    p.add_argument("--config", help="configuration file: a problem file, or the earlier "
                                    "format (scenario = NAME, [parameters])")
    for flag, dest, typ, text in FLAGS:
        p.add_argument(flag, dest=dest, type=typ, help=text)
    p.add_argument("--damping", choices=("consistent", "naive"),
                   help="extensional viscosity eta_E (consistent) or eta~_E (naive)")
    p.add_argument("--set", dest="sets", action="append", default=[], metavar="PATH=VALUE",
                   help=SET_HELP.replace("%", "%%"))


#: what --sensitivities does (its --help)
SENSITIVITIES_HELP = ("forward sensitivities of the outputs to these parameters, "
                      "comma-separated: any numeric key --set takes (material.youngs_modulus, "
                      "material.tau_S, section.width, material.branches.0.tau, "
                      "loads.0.vector.x, rods.NAME.material.E, ...), an alias (E, tau, "
                      "tip_force) or the last word of a key when unique (youngs_modulus, "
                      "tau_S); written to sensitivities.npz as <channel>/<parameter>")


def add_sensitivity_arguments(p: argparse.ArgumentParser, errcon: bool = True,
                              help_text: str = SENSITIVITIES_HELP) -> None:
    """--sensitivities (and, for runs, --sensitivity-error-control)."""
    p.add_argument("--sensitivities", metavar="P1,P2", help=help_text)
    if errcon:
        p.add_argument("--sensitivity-error-control", dest="sens_errcon",
                       action="store_true",
                       help="the sensitivities in the integrator's error test too (IDAS's "
                            "errconS; default: the steps are the plain run's)")


def sensitivity_names(args, problem, command: str) -> list[str] | None:
    """The parameters of --sensitivities, validated against ``problem`` (None: none
    asked); one line naming a bad name and why, before anything is written."""
    from kvrod.errors import CliError
    from runtime.problem.parameters import resolve_parameters

    text = getattr(args, "sensitivities", None)
    if text is None:
        return None
    names = [n.strip() for n in text.split(",")]
    if not names or any(not n for n in names):
        raise CliError(f"kvrod {command}: --sensitivities {text!r}: parameter names "
                       "separated by commas (e.g. material.youngs_modulus,tau_S)")
    resolve_parameters(problem, names)          # ParameterError: one line, the name
    return names


def parse_set(item: str) -> tuple[str, Any]:
    """``path=value`` with a TOML value (a bare word is a string)."""
    from kvrod.errors import CliError

    if "=" not in item:
        raise CliError(f"kvrod: --set {item!r} must be PATH=VALUE (e.g. material.tau=0.02)")
    key, text = item.split("=", 1)
    key = key.strip()
    try:
        value = tomllib.loads(f"v = {text}")["v"]
    except tomllib.TOMLDecodeError:
        value = text.strip()
    return key, value


def problem_from_args(args, command: str):
    """The problem named on the command line with all overrides applied (checked), one the
    rod kernels can run (simulate, static, modes)."""
    from kvrod.errors import CliError
    from runtime.problem.registry import load_config, load_problem

    spec = args.problem
    overrides: dict[str, Any] = {}
    if getattr(args, "config", None):
        name, kw = load_config(args.config)
        if spec is not None and spec != name:
            raise CliError(f"kvrod {command}: problem {spec!r} on the command line but "
                           f"{name!r} in {args.config}")
        spec = name
        overrides.update(kw)
    if spec is None:
        raise CliError(f"kvrod {command}: name a problem (a .toml file or a built-in name "
                       "such as cantilever) or give --config FILE")
    if args.tau is not None and (args.tau_S is not None or args.tau_B is not None):
        raise CliError(f"kvrod {command}: --tau sets tau_S = tau_B; do not combine it with "
                       "--tau-S/--tau-B")
    if args.tau is not None:
        for k in ("tau_S", "tau_B"):
            overrides.pop(k, None)
    elif args.tau_S is not None or args.tau_B is not None:
        overrides.pop("tau", None)
    for _, dest, _, _ in FLAGS:
        v = getattr(args, dest)
        if v is not None:
            overrides[dest] = v
    if args.damping is not None:
        overrides["damping"] = args.damping
    for item in args.sets:
        k, v = parse_set(item)
        overrides[k] = v
    problem = load_problem(spec, overrides)
    problem.check_simulable()          # a composite section: before anything is written
    return problem
