"""Problem parameters by name, for sensitivities and fits (issue 34).

A parameter is any numeric key of a problem file that a sweep or ``--set`` can set,
named the same way: a dotted path (``material.youngs_modulus``, ``material.tau_S``,
``section.width``, ``material.branches.0.tau``, ``loads.0.vector.0`` (or ``.x``),
``loads.0.time.frequency``, ``zones.0.material.youngs_modulus``,
``rods.arm.material.youngs_modulus`` in an assembly, ``joints.0.rotational_stiffness``,
``bodies.0.mass``), a short alias of the command line
(:data:`~runtime.problem.schema.ALIASES`: ``E``, ``tau``, ``tip_force``; in an assembly
they stand for the key of every rod, whose values must then agree), or the last word of
a path when no other parameter
of the problem ends in it (``youngs_modulus``, ``tau_S``, ``frequency``).

Keys given one way and asked another are derived: ``tau`` of a material written with
``tau_S = tau_B`` (its value; the derivative moves both), ``tau_S`` of a material written
with ``tau`` (the derivative with tau_B held: the material is split first, as
``--set material.tau_S`` does), ``eta`` and ``zeta`` (G tau_S, K tau_B), a Maxwell
branch's ``youngs_modulus`` and ``poisson_ratio`` written as shear and bulk moduli.

Refused, in one line naming the key and why: keys that are not continuous numbers
(element counts, kinds, names, flags), the run's settings (``simulation``,
``statics``, ``analysis``), and numbers that move where the mesh's nodes or the inputs'
breakpoints are (a point load's ``s``, a zone's ``from``/``to``, a time function's
``start``, ``duration`` or table times): the discrete solution is not differentiable in
them. An unknown name lists the close matches.

``array_directions`` gives the derivative of the rod's numbers with respect to each
parameter (the direction of its sensitivity, ``runtime.model.sensitivity``) by
differencing the build of the arrays with the mesh fixed (N, the node placement rule):
where the build is linear in the key (moduli, densities, retardation times, loads) the
central difference is exact to round-off (checked: two step sizes agree to 1e-9), else
(section dimensions, analysed sections, time-function frequencies) Richardson's
extrapolation of two central differences, its error estimated from their difference
(``ArrayDirection.error``).
"""

from __future__ import annotations

import difflib
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from runtime.errors import ParameterError
from runtime.model.arrays import RodArrays
from runtime.model.sensitivity import Directions
from runtime.problem.schema import ALIASES, Problem

#: tables of the run's settings: not parameters of the model
SETTINGS = ("simulation", "statics", "analysis")
#: leaves that move nodes of the mesh or breakpoints of the inputs
_MOVES = {"s": "moves a node of the mesh (the point load's place)",
          "from": "moves a node of the mesh (the zone's boundary)",
          "to": "moves a node of the mesh (the zone's boundary)",
          "start": "moves a breakpoint of the input (a jump in time)",
          "duration": "moves a breakpoint of the input (a jump in time)",
          "points": "moves breakpoints of the input (the table's times)",
          "elements": "is a count of elements (an integer)"}
_XYZ = {"x": "0", "y": "1", "z": "2"}


@dataclass(frozen=True)
class ResolvedParameter:
    """One parameter: ``name`` as asked, ``key`` what ``with_overrides`` is given to set
    it (a dotted path, or an alias that sets every rod's), ``paths`` the dotted paths it
    sets, ``alias`` its unique short name (the last word of its path; None when another
    parameter ends in it too), ``value`` its value (SI)."""

    name: str
    key: str
    paths: tuple[str, ...]
    alias: str | None
    value: float

    @property
    def labels(self) -> tuple[str, ...]:
        """The names its results are stored under: as asked, and its alias."""
        return (self.name,) + ((self.alias,) if self.alias and self.alias != self.name
                               else ())


def _is_number(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def _leaves(m: Any, prefix: str = "") -> dict[str, Any]:
    """Every leaf of a problem mapping by dotted path (lists by index)."""
    out: dict[str, Any] = {}
    items = m.items() if isinstance(m, Mapping) else enumerate(m) if isinstance(m, list) \
        else None
    if items is None:
        return {prefix: m}
    for k, v in items:
        path = f"{prefix}.{k}" if prefix else str(k)
        if isinstance(v, (Mapping, list)) and not (isinstance(v, list) and not v):
            out.update(_leaves(v, path))
        else:
            out[path] = v
    return out


def _material_derived(mat: Mapping[str, Any], prefix: str) -> dict[str, float]:
    """Keys of a material given another way: tau, eta, zeta of a Kelvin-Voigt material,
    a Maxwell branch's youngs_modulus and poisson_ratio."""
    out: dict[str, float] = {}
    if mat.get("model", "kelvin_voigt") == "kelvin_voigt" and "tau_S" in mat:
        E, nu = float(mat.get("youngs_modulus", 1e6)), float(mat.get("poisson_ratio", 0.3))
        tS, tB = float(mat["tau_S"]), float(mat.get("tau_B", mat["tau_S"]))
        if tS == tB:
            out[prefix + "tau"] = tS
        out[prefix + "eta"] = E / (2 * (1 + nu)) * tS
        if nu < 0.5:
            out[prefix + "zeta"] = E / (3 * (1 - 2 * nu)) * tB
    for k, b in enumerate(mat.get("branches", []) or []):
        if isinstance(b, Mapping) and "shear_modulus" in b and "bulk_modulus" in b:
            G, K = float(b["shear_modulus"]), float(b["bulk_modulus"])
            if 3 * K + G > 0:
                out[f"{prefix}branches.{k}.youngs_modulus"] = 9 * K * G / (3 * K + G)
                out[f"{prefix}branches.{k}.poisson_ratio"] = (3 * K - 2 * G) / (2 * (3 * K + G))
    return out


def _rod_tables(m: Mapping[str, Any]) -> dict[str, Mapping[str, Any]]:
    """prefix -> the tables of each rod (one rod: prefix ""; assembly: "rods.NAME.")."""
    if "rods" in m:
        return {f"rods.{name}.": t for name, t in m["rods"].items()}
    return {"": m}


def _catalogue(problem) -> dict[str, Any]:
    """Every leaf of the problem by dotted path, with the derived keys."""
    m = problem.to_mapping()
    leaves = _leaves(m)
    for prefix, t in _rod_tables(m).items():
        if isinstance(t.get("material"), Mapping):
            leaves.update(_material_derived(t["material"], prefix + "material."))
        for z, zone in enumerate(t.get("zones", []) or []):
            if isinstance(zone, Mapping) and isinstance(zone.get("material"), Mapping):
                leaves.update(_material_derived(zone["material"],
                                                f"{prefix}zones.{z}.material."))
    for name, mat in (m.get("materials") or {}).items():
        if isinstance(mat, Mapping):
            leaves.update(_material_derived(mat, f"materials.{name}."))
    if "rods" not in m:
        tip = _tip_force_path(m)
        if tip is not None:
            leaves["tip_force"] = float(np.linalg.norm(leaves_vector(leaves, tip)))
    return leaves


def leaves_vector(leaves: Mapping[str, Any], path: str) -> np.ndarray:
    out, k = [], 0
    while f"{path}.{k}" in leaves:
        out.append(float(leaves[f"{path}.{k}"]))
        k += 1
    return np.array(out)


def _tip_force_path(m: Mapping[str, Any]) -> str | None:
    """The vector of the load ``tip_force`` sets (schema._set_tip_force's rule)."""
    for k, ld in enumerate(m.get("loads", [])):
        if ld.get("kind", "force") == "force" and ld.get("at", "end") == "end" and "s" not in ld:
            return f"loads.{k}.vector"
    return None


def _why_not(path: str, value: Any) -> str | None:
    """Why a key cannot be a parameter (None: it can)."""
    parts = path.split(".")
    if parts[0] in SETTINGS:
        return "is a setting of the run, not a parameter of the model"
    for p in reversed(parts):
        if not p.isdigit():
            leaf = p
            break
    else:
        leaf = parts[-1]
    if leaf in _MOVES:
        return _MOVES[leaf]
    if "points" in parts and "time" in parts:
        return _MOVES["points"]
    if isinstance(value, bool):
        return "is a flag (true/false), not a continuous number"
    if isinstance(value, str):
        return f"is a name or kind ({value!r}), not a continuous number"
    if isinstance(value, int) and leaf in ("elements", "load_steps", "centreline_frames"):
        return "is a count (an integer)"
    if not _is_number(value):
        return "is not a number"
    return None


def _candidates(leaves: Mapping[str, Any]) -> dict[str, float]:
    return {p: float(v) for p, v in leaves.items() if _why_not(p, v) is None}


def _aliases(cands: Mapping[str, float]) -> dict[str, list[str]]:
    """Last word -> the parameter paths ending in it (words only, not indices)."""
    out: dict[str, list[str]] = {}
    for p in cands:
        leaf = p.rsplit(".", 1)[-1]
        if not leaf.isdigit() and p != leaf:
            out.setdefault(leaf, []).append(p)
    return out


def _normalise(path: str) -> str:
    """``loads.0.vector.x`` -> ``loads.0.vector.0``."""
    parts = path.split(".")
    if len(parts) > 1 and parts[-1] in _XYZ and parts[-2] == "vector":
        parts[-1] = _XYZ[parts[-1]]
    return ".".join(parts)


def resolve_parameters(problem, names: Sequence[str]) -> list[ResolvedParameter]:
    """The parameters ``names`` of ``problem`` (a Problem or an Assembly), validated
    (see the module docstring); raises ParameterError naming the first bad name."""
    leaves = _catalogue(problem)
    cands = _candidates(leaves)
    by_leaf = _aliases(cands)
    assembly = "rods" in problem.to_mapping()
    out: list[ResolvedParameter] = []
    seen: set[str] = set()
    for raw in names:
        name = str(raw).strip()
        if not name:
            raise ParameterError("--sensitivities", raw, "parameter names, comma-separated "
                                 "(e.g. material.youngs_modulus,tau_S)")
        res = _resolve_one(problem, name, leaves, cands, by_leaf, assembly)
        if name in seen:
            raise ParameterError(name, None, "each parameter once")
        seen.add(name)
        out.append(res)
    return out


def _alias_of(path: str, by_leaf: Mapping[str, list[str]]) -> str | None:
    leaf = path.rsplit(".", 1)[-1]
    return leaf if len(by_leaf.get(leaf, [])) == 1 else None


def _resolve_one(problem, name: str, leaves, cands, by_leaf, assembly: bool
                 ) -> ResolvedParameter:
    path = _normalise(name)
    if name in ALIASES and name != "tip_force":
        target = ALIASES[name]
        if assembly:
            paths = tuple(p for p in cands if p.startswith("rods.")
                          and p.split(".", 2)[2] == target)
            if not paths:
                _refuse(name, target, leaves, cands)
            vals = {cands[p] for p in paths}
            if len(vals) > 1:
                raise ParameterError(name, sorted(vals), "one value on every rod (the alias "
                                     "sets every rod's " + target + "): ask for "
                                     + ", ".join(paths) + " one by one")
            return ResolvedParameter(name, name, paths, target.rsplit(".", 1)[-1],
                                     vals.pop())
        path = target
    if path in cands:
        alias = _alias_of(path, by_leaf) if "." in path else None
        return ResolvedParameter(name, path, (path,), alias, cands[path])
    if "." not in path and path in by_leaf:
        hits = by_leaf[path]
        if len(hits) == 1:
            return ResolvedParameter(name, hits[0], (hits[0],), path, cands[hits[0]])
        raise ParameterError(name, None, "a unique key: several parameters end in it ("
                             + ", ".join(sorted(hits)) + "); give the dotted path")
    _refuse(name, path, leaves, cands)
    raise AssertionError  # pragma: no cover


def _refuse(name: str, path: str, leaves: Mapping[str, Any], cands: Mapping[str, float]):
    if path in leaves:
        raise ParameterError(name, leaves[path], "a continuous number of the model: "
                             f"{path} {_why_not(path, leaves[path])}")
    parent = path.rsplit(".", 1)[0] if "." in path else ""
    if path.rsplit(".", 1)[-1] == "tau" and f"{parent}.tau_S" in leaves:
        raise ParameterError(name, None, f"tau of a material whose tau_S and tau_B agree "
                             f"({parent}.tau_S = {leaves[parent + '.tau_S']}, tau_B = "
                             f"{leaves.get(parent + '.tau_B')}); ask for tau_S and tau_B")
    words = sorted(set(cands) | {p.rsplit(".", 1)[-1] for p in cands}
                   | {a for a in ALIASES if ALIASES[a] in cands or a == "tip_force"})
    close = difflib.get_close_matches(name, words, n=5, cutoff=0.6)
    hint = ("; close: " + ", ".join(close)) if close else ""
    raise ParameterError(name, None, "a numeric key of this problem (a dotted path such as "
                         "material.youngs_modulus, an alias, or the last word of one)" + hint)


def with_parameters(problem, values: Mapping[str, float]):
    """The same problem (mesh included) with the parameters ``values`` (names as
    :func:`resolve_parameters` takes them) set; everything else kept."""
    if not values:
        return problem
    resolved = resolve_parameters(problem, list(values))
    overrides: dict[str, Any] = {}
    for r in resolved:
        v = values[r.name]
        if not (_is_number(v) and math.isfinite(float(v))):
            raise ParameterError(r.name, v, "a finite number")
        overrides[r.key] = float(v)
    return problem.with_overrides(overrides)


# -- directions: d(arrays)/d theta ---------------------------------------------------------

#: relative difference step of the arrays' build
STEP = 1e-3
#: two step sizes agreeing to this (relative) mean the build is linear in the key
LINEAR_RTOL = 1e-9


@dataclass
class ArrayDirection:
    """The derivative of one rod's numbers with respect to a parameter: ``arrays``
    (RodArrays of derivatives), ``reference`` (the reference state's derivative, (n,)),
    ``drive`` (None, or the derivative of the driven entries at a time: the loads' and
    end motion's), ``error`` (estimated relative error of the difference; 0: the build is
    linear in the key, the difference exact to round-off), ``step`` (the step used)."""

    arrays: RodArrays
    reference: np.ndarray
    drive: Any
    error: float
    step: float


def _at(problem, r: ResolvedParameter, value: float):
    return with_parameters(problem, {r.name: value})


def _stencils(problem, r: ResolvedParameter
              ) -> tuple[list[tuple[float, Any]], list[tuple[float, Any]] | None, float]:
    """Two difference formulas of the derivative at theta, as [(coefficient, problem at
    theta + k delta)]: central with steps delta and 2 delta, or (where a side is out of
    range) second-order one-sided and first-order one-sided; and delta."""
    theta = r.value
    delta = STEP * (abs(theta) if theta != 0.0 else _zero_scale(problem, r))
    try:
        pm = [_at(problem, r, theta + k * delta) for k in (1.0, -1.0, 2.0, -2.0)]
        h = 0.5 / delta
        return ([(h, pm[0]), (-h, pm[1])], [(0.5 * h, pm[2]), (-0.5 * h, pm[3])], delta)
    except ParameterError:
        pass
    for s in (1.0, -1.0):
        try:
            p1, p2 = _at(problem, r, theta + s * delta), _at(problem, r, theta + 2 * s * delta)
        except ParameterError:
            continue
        h = 1.0 / (s * delta)         # (-3 A0 + 4 A1 - A2) / (2 s delta); (A1 - A0) / (s delta)
        return ([(-1.5 * h, problem), (2.0 * h, p1), (-0.5 * h, p2)],
                [(-h, problem), (h, p1)], delta)
    raise ParameterError(r.name, theta, "a value with valid neighbours (the derivative is "
                         f"formed at {theta:g} +- {2 * delta:.3g})")


def _zero_scale(problem, r: ResolvedParameter) -> float:
    """A scale for the step of a parameter whose value is 0: the size of its vector, or
    of its siblings, else 1 in its units."""
    leaves = _catalogue(problem)
    parent = r.paths[0].rsplit(".", 1)[0]
    sib = [abs(float(v)) for p, v in leaves.items()
           if p.rsplit(".", 1)[0] == parent and _is_number(v) and v]
    return max(sib) if sib else 1.0


_TABLES = ("par", "seg", "jnt", "nload", "sload", "theta", "segb", "jntb")
#: entries of par that are flags or the load factor: no derivative
_FLAGS = ("load_scale", "fix_start", "clamp_start", "fix_end", "clamp_end")


def _combine(terms: Sequence[tuple[float, RodArrays]]) -> RodArrays:
    from runtime.model.sensitivity import zeros_like

    out = zeros_like(terms[0][1])
    for c, a in terms:
        for k in _TABLES:
            getattr(out, k)[...] += c * getattr(a, k)
        if a.coupled:
            out.segc[...] += c * a.segc
            out.jntc[...] += c * a.jntc
    _clear_flags(out)
    return out


def _clear_flags(d: RodArrays) -> None:
    for name in _FLAGS:
        d.param(name)[:] = 0.0


class _DriveDirection:
    """The derivative of the driven entries (loads, end motion) at time t: the same
    difference formula over the perturbed problems' drives, each writing into a copy of
    its own arrays (whose entries the drive does not write keep their build's values)."""

    def __init__(self, terms: list[tuple[float, Any, RodArrays]]) -> None:
        self.terms = terms

    def __call__(self, d: RodArrays, t: float, left: bool, scale: float, static: bool
                 ) -> None:
        d.par[:] = 0.0
        d.nload[:] = 0.0
        d.sload[:] = 0.0
        for c, drive, scratch in self.terms:
            drive.apply(scratch, t, left=left, scale=scale, static=static)
            d.par += c * scratch.par
            d.nload += c * scratch.nload
            d.sload += c * scratch.sload
        _clear_flags(d)


def _builds(stencil):
    from runtime.problem.assemble import ProblemDrive, reference_arrays

    out = []
    for c, p in stencil:
        arrays, y_ref, r_ends, p_ends = reference_arrays(p)
        out.append((c, arrays, y_ref, ProblemDrive(p, arrays.N, r_ends, p_ends)))
    return out


def _direction(problem, r: ResolvedParameter, ref: RodArrays) -> ArrayDirection:
    main, check, delta = _stencils(problem, r)
    b1, b2 = _builds(main), _builds(check)
    for _, a, _, _ in b1 + b2:
        if a.N != ref.N or a.branches != ref.branches or a.coupled != ref.coupled:
            raise ParameterError(r.name, r.value, "a key that keeps the rod's structure "
                                 "(elements, relaxation terms, coupled sections) when it "
                                 "changes a little")
    d1 = _combine([(c, a) for c, a, _, _ in b1])
    d2 = _combine([(c, a) for c, a, _, _ in b2])
    diff = _relative_difference(d1, d2)
    final = b1
    error = 0.0
    if diff > LINEAR_RTOL:
        if len(main) == 2:            # central at delta and 2 delta: Richardson, O(delta^4)
            final = ([(4.0 / 3.0 * c, a, y, dr) for c, a, y, dr in b1]
                     + [(-1.0 / 3.0 * c, a, y, dr) for c, a, y, dr in b2])
            error = diff / 3.0        # the central difference's error: a bound
        else:                         # one-sided second order against first order
            error = diff
    d = _combine([(c, a) for c, a, _, _ in final])
    dref = np.sum([c * y for c, _, y, _ in final], axis=0)
    drive = None
    if _drives(r):
        drive = _DriveDirection([(c, dr, a.copy()) for c, a, _, dr in final])
    return ArrayDirection(d, np.asarray(dref, dtype=float), drive, error, delta)


def _relative_difference(a: RodArrays, b: RodArrays) -> float:
    """Largest difference of two derivative estimates, entry by entry relative to the
    entry (entries below 1e-12 of their table's largest taken at that size)."""
    worst = 0.0
    for k in _TABLES + (("segc", "jntc") if a.coupled else ()):
        x, y = np.abs(getattr(a, k)), np.abs(getattr(a, k) - getattr(b, k))
        if x.size == 0:
            continue
        floor = max(1e-12 * float(x.max()), 1e-300)
        worst = max(worst, float(np.max(y / np.maximum(x, floor))))
    return worst


def _drives(r: ResolvedParameter) -> bool:
    """Whether the parameter enters what the drive writes (loads, end motion, the ends'
    reference positions and frames)."""
    return any(p.split(".")[0] in ("loads", "start", "end", "rod", "tip_force")
               or ".start." in p or ".end." in p or ".rod." in p for p in r.paths)


def array_directions(problem: Problem, resolved: Sequence[ResolvedParameter],
                     arrays: RodArrays) -> tuple[Directions, list[ArrayDirection]]:
    """The directions of a single rod's parameters (see the module docstring), for a
    model whose arrays are ``arrays`` (the problem's build: the shapes are checked)."""
    dirs = [_direction(problem, r, arrays) for r in resolved]
    return (Directions(tuple(r.name for r in resolved), [d.arrays for d in dirs],
                       [d.drive for d in dirs]), dirs)


# -- assemblies ----------------------------------------------------------------------------

def _system_builds(stencil):
    from runtime.problem.assemble_system import build_system

    return [(c, build_system(p).model) for c, p in stencil]


def _combine_system(terms, ref_model):
    """The derivative of an assembly's numbers from builds (coefficient, SystemModel)."""
    from runtime.model.system_sensitivity import system_tables

    rods = [_combine([(c, m.rods[r].arrays) for c, m in terms])
            for r in range(len(ref_model.rods))]
    tabs = [(c, system_tables(m)) for c, m in terms]
    tables = {k: sum(c * t[k] for c, t in tabs) for k in tabs[0][1]}
    return rods, tables


def _system_difference(a, b) -> float:
    rods_a, tab_a = a
    rods_b, tab_b = b
    worst = max((_relative_difference(x, y) for x, y in zip(rods_a, rods_b, strict=True)),
                default=0.0)
    for k, v in tab_a.items():
        x, y = np.abs(v), np.abs(v - tab_b[k])
        if x.size:
            floor = max(1e-12 * float(x.max()), 1e-300)
            worst = max(worst, float(np.max(y / np.maximum(x, floor))))
    return worst


def _system_direction(problem, r: ResolvedParameter, model):
    """The derivative of an assembly's numbers (``SystemDirection``) along one
    parameter, as ``array_directions`` for one rod."""
    from runtime.model.system_sensitivity import SystemDirection

    main, check, delta = _stencils(problem, r)
    b1, b2 = _system_builds(main), _system_builds(check)
    for _, m in b1 + b2:
        same = (len(m.rods) == len(model.rods) and m.n == model.n
                and len(m.links) == len(model.links) and len(m.bodies) == len(model.bodies)
                and len(m.holds) == len(model.holds)
                and all(x.arrays.coupled == y.arrays.coupled for x, y in
                        zip(m.rods, model.rods, strict=True)))
        if not same:
            raise ParameterError(r.name, r.value, "a key that keeps the assembly's "
                                 "structure (rods, elements, joints, bodies) when it "
                                 "changes a little")
    d1, d2 = _combine_system(b1, model), _combine_system(b2, model)
    diff = _system_difference(d1, d2)
    final, error = b1, 0.0
    if diff > LINEAR_RTOL:
        if len(main) == 2:
            final = ([(4.0 / 3.0 * c, m) for c, m in b1] + [(-1.0 / 3.0 * c, m) for c, m in b2])
            error = diff / 3.0
        else:
            error = diff
    rods, tables = _combine_system(final, model)
    reference = np.sum([c * m.reference for c, m in final], axis=0)
    rod_drives = []
    for k in range(len(model.rods)):
        if _drives(r) or any(p.split(".")[0] == "loads" for p in r.paths):
            rod_drives.append(_DriveDirection([(c, m.rods[k].drive, m.rods[k].arrays.copy())
                                               for c, m in final]))
        else:
            rod_drives.append(None)
    gravs = [(c, m._gravity) for c, m in final if m._gravity is not None]

    def gravity(t: float, left: bool, scale: float) -> np.ndarray:
        return sum((c * np.asarray(g(t, left, scale)) for c, g in gravs), np.zeros(3))

    return SystemDirection(rods, rod_drives, tables, np.asarray(reference, dtype=float),
                           gravity if gravs else None, error)


def system_directions(problem, resolved: Sequence[ResolvedParameter], model):
    """The directions of an assembly's parameters (``SystemDirections``) for its
    system ``model`` (the build of ``problem``)."""
    from runtime.model.system_sensitivity import SystemDirections

    return SystemDirections(tuple(r.name for r in resolved),
                            [_system_direction(problem, r, model) for r in resolved])
