"""Named problems and problem files: the one registry every command uses.

A problem is named by a TOML file (``kvrod simulate my_rod.toml``) or by the name of a
built-in example (``kvrod simulate cantilever`` reads ``examples/cantilever.toml``).
Overrides (command-line flags, sweep points) are dotted paths or the short aliases of
:data:`runtime.problem.schema.ALIASES`, checked like the file's own values.

The earlier configuration format (``scenario = "cantilever"`` plus a ``[parameters]``
table of aliases) is still read by :func:`load_config`.
"""

from __future__ import annotations

import tomllib
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from runtime.errors import ParameterError
from runtime.problem.assembly import Assembly
from runtime.problem.schema import ALIASES, Problem

#: the built-in examples (a source checkout's examples/ folder)
EXAMPLES_DIR = Path(__file__).resolve().parents[2] / "examples"


class ProblemFileError(ValueError):
    """A problem or configuration file that cannot be read (message names the file)."""


def read_toml(path: Path, error: type[ValueError] = ProblemFileError,
              what: str = "problem file") -> tuple[dict, str]:
    """(parsed document, text) of a TOML file; ``error`` (one line naming the file) when
    it cannot be read or parsed."""
    path = Path(path)
    try:
        text = path.read_text()
    except OSError as exc:
        raise error(f"{path}: cannot read the {what} ({exc.strerror or exc})") from exc
    except UnicodeDecodeError as exc:
        raise error(f"{path}: the {what} is not UTF-8 text ({exc.reason})") from exc
    try:
        return tomllib.loads(text), text
    except tomllib.TOMLDecodeError as exc:
        raise error(f"{path}: malformed TOML: {exc}") from exc


def _is_problem(doc: Mapping[str, Any]) -> bool:
    """A problem file: one rod (``[rod]``) or an assembly of rods (``[rods.NAME]``)."""
    return "rod" in doc or "rods" in doc


def _is_assembly(doc: Mapping[str, Any]) -> bool:
    return "rods" in doc


def builtin_names() -> list[str]:
    """Names of the built-in example problems (single rods and assemblies)."""
    if not EXAMPLES_DIR.is_dir():
        return []
    names = []
    for f in sorted(EXAMPLES_DIR.glob("*.toml")):
        try:
            doc = tomllib.loads(f.read_text())
        except (OSError, tomllib.TOMLDecodeError):
            continue
        if _is_problem(doc):
            names.append(f.stem)
    return names


def problem_path(spec: str | Path) -> Path:
    """The file of a problem named by path or built-in name (ProblemFileError if none)."""
    p = Path(spec)
    if p.suffix == ".toml" or p.exists() or "/" in str(spec):
        if not p.exists():
            raise ProblemFileError(f"{p}: no such problem file")
        return p
    # a built-in name is its own file: read that one (not every example, which a study
    # of many points would otherwise parse once per point)
    f = EXAMPLES_DIR / f"{spec}.toml"
    if f.is_file():
        try:
            if _is_problem(tomllib.loads(f.read_text())):
                return f
        except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError):
            pass
    names = ", ".join(builtin_names()) or "(none found)"
    raise ProblemFileError(f"unknown problem {str(spec)!r}; built-in problems: {names}; or "
                           "give a problem file (.toml)")


def load_problem(spec: str | Path | Problem | Assembly,
                 overrides: Mapping[str, Any] | None = None) -> Problem | Assembly:
    """A problem by file, built-in name or object, with overrides applied (all checked).

    Parameters
    ----------
    spec : str, Path, Problem or Assembly
        A problem file (TOML), the name of a built-in problem (``examples/NAME.toml``,
        e.g. ``"cantilever"``), a :class:`~runtime.problem.schema.Problem` or an
        :class:`~runtime.problem.assembly.Assembly`. A file with ``[rods.NAME]`` tables
        is an assembly of rods.
    overrides : mapping, optional
        ``{"material.tau": 0.02, "rod.elements": 30}``: dotted paths or the command
        line's short names (:data:`~runtime.problem.schema.ALIASES`), applied in order.
        A value may be a whole table or array of tables, as a dict or a list of dicts:
        ``{"material": {"density": 7800.0, "youngs_modulus": 2.1e11, "tau": 1e-4}}``
        replaces the material, ``{"loads": [{"kind": "gravity", "vector": [0, 0, -9.81]}]}``
        all loads; an array entry is named by its index (``"loads.0.vector"``), and the
        index one past the last entry appends a whole entry
        (``{"loads.1": {"kind": "force", "vector": [0, 0, 1.0]}}`` to a problem with one
        load; the same for ``material.branches``). Every value is checked exactly as in
        a problem file. For an assembly: paths through ``rods.NAME``, ``joints``,
        ``bodies``, ``loads``; the short names set their key on every rod
        (:meth:`~runtime.problem.assembly.Assembly.with_overrides`).

    Returns
    -------
    Problem or Assembly

    Raises
    ------
    ProblemFileError
        The file is missing, unreadable, not TOML or not a problem.
    ParameterError
        A value is outside its allowed range (the message names the key and the file).
    """
    if isinstance(spec, (Problem, Assembly)):
        return spec.with_overrides(overrides or {})
    path = problem_path(spec)
    doc, _ = read_toml(path)
    if not _is_problem(doc):
        hint = (" (a study: run it with `kvrod sweep`)" if "grid" in doc or "points" in doc
                else " (no [rod] or [rods.NAME] table)")
        raise ProblemFileError(f"{path}: not a problem file{hint}")
    kind = Assembly if _is_assembly(doc) else Problem
    try:
        problem = kind.from_mapping(doc, base=path.parent.resolve(), name=path.stem)
    except ParameterError as exc:
        raise ParameterError(exc.name, exc.value, exc.allowed, where=str(path)) from None
    return problem.with_overrides(overrides or {})


def load_config(path: Path) -> tuple[str, dict[str, Any]]:
    """(problem name, overrides) of a configuration file in the earlier format::

        scenario = "cantilever"
        [parameters]          # aliases: tau, n_elements, youngs_modulus, ...
        tau = 0.04

    A problem file (with ``[rod]`` or ``[rods.NAME]``) is returned as (its path, {}).
    """
    path = Path(path)
    doc, _ = read_toml(path, what="config file")
    if _is_problem(doc):
        return str(path), {}
    name = doc.pop("scenario", "cantilever")
    if not isinstance(name, str):
        raise ProblemFileError(f"{path}: scenario = {name!r} must be a string, one of: "
                               + ", ".join(builtin_names()))
    params = doc.pop("parameters", {})
    if not isinstance(params, dict):
        raise ProblemFileError(f"{path}: [parameters] must be a table")
    tables = [k for k, v in doc.items() if isinstance(v, dict)]
    if tables:
        raise ProblemFileError(f"{path}: unknown table(s) {tables}; use [parameters]")
    twice = sorted(set(doc) & set(params))
    if twice:
        raise ProblemFileError(f"{path}: {', '.join(twice)} given both at the top level and "
                               "in [parameters]; give each once")
    flat = {**doc, **params}
    both = [k for k in ("tau_S", "tau_B") if k in flat]
    if "tau" in flat and both:
        raise ProblemFileError(f"{path}: tau and {' and '.join(both)} are both given; tau "
                               "sets tau_S = tau_B, so give either tau or tau_S/tau_B")
    for key in flat:
        if key not in ALIASES:
            raise ProblemFileError(f"{path}: unknown parameter {key!r}; allowed: "
                                   + ", ".join(sorted(ALIASES)))
    return name, flat
