"""Zones of a rod with their own section or material (issue 26; docs/design.md, section 10).

``[[zones]]`` tables, each with ``from`` and ``to`` (arc length, m, 0 <= from < to <= L)
and a ``section`` and/or a ``material`` table that override the problem's ``[section]`` /
``[material]`` on that stretch key by key (:func:`overlay`: a zone that gives only
``youngs_modulus`` keeps the problem's density, Poisson ratio and damping, not the
defaults; a section that names its ``kind`` is given whole; a ``composite`` zone
section names ``[materials.NAME]`` tables as the top-level one does). Zones may not
overlap; where no zone lies the problem's own section and material hold (a cable with a
stiffer clip region is one zone). A zone's tapers (``*_end``) run over the zone. The rod
has a node at every zone boundary (``Problem.node_arc_lengths``: the elements are shared
among the stretches between boundaries, uniform inside each), so a segment lies wholly in
one zone.

Joints between segments of different zones take the two half cells in series
(``materials.joint_series``; for coupled sections ``arrays.coupled_joint_series``): the
compliance of the joint's cell is that of its two halves, which keeps a sharp change
second order in h (the arithmetic mean of the joints' matrices, used before, made it first
order: 0.75 % at N = 64 for an EI step 4 -> 1).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from runtime.errors import ParameterError
from runtime.problem import coerce as C

ZONE_KEYS = ("from", "to", "section", "material")


@dataclass(frozen=True)
class Zone:
    """``start`` .. ``end`` (m) of the rod with its own ``section`` and ``material`` (the
    problem's where the zone gives none); ``index`` its place in ``[[zones]]``."""

    index: int
    start: float
    end: float
    section: Any
    material: Any
    section_mapping: Mapping[str, Any] | None = None
    material_mapping: Mapping[str, Any] | None = None

    def to_mapping(self) -> dict[str, Any]:
        out: dict[str, Any] = {"from": self.start, "to": self.end}
        if self.section_mapping is not None:
            out["section"] = dict(self.section_mapping)
        if self.material_mapping is not None:
            out["material"] = dict(self.material_mapping)
        return out


#: mutually exclusive ways of giving a Kelvin-Voigt material's damping
#: (``materials.material_from_mapping``): a zone naming one drops the problem's others
_DAMPING_ALTERNATIVES = (("tau",), ("tau_S", "tau_B"), ("eta", "zeta"))


def overlay(base: Mapping[str, Any] | None, own: Mapping[str, Any],
            material: bool = False) -> dict[str, Any]:
    """A zone's ``section`` or ``material`` table ``own`` over the problem's ``base``, key
    by key: the zone's keys win; a section that names its ``kind`` is given whole (its
    kind's keys may exclude the problem's: ``stiffness_matrix`` beside ``EA``); the
    problem's tapers (``*_end``, over the whole rod) are not inherited (a
    zone's own run over the zone). For a material, naming one way of giving the damping
    (``tau``; ``tau_S``/``tau_B``; ``eta``/``zeta``) drops the problem's others, and a
    problem's ``tau`` counts as ``tau_S = tau_B = tau`` beside a zone's ``tau_S`` or
    ``tau_B``.

    Why not replace: a zone table that gives one key silently took the defaults for the
    others (``material = {youngs_modulus = 2e6}`` made the stretch undamped, density 1000,
    nu 0.3, whatever the problem's material)."""
    if not isinstance(base, Mapping) or not isinstance(own, Mapping):
        return dict(own) if isinstance(own, Mapping) else own
    if "kind" in own:       # a section given with its kind is given whole
        return dict(own)
    out = {k: v for k, v in base.items() if not str(k).endswith("_end")}
    if material:
        named = [alt for alt in _DAMPING_ALTERNATIVES if any(k in own for k in alt)]
        if named:
            if named[0] == ("tau_S", "tau_B") and "tau" in out:
                out["tau_S"] = out["tau_B"] = out.pop("tau")
            for alt in _DAMPING_ALTERNATIVES:
                if alt not in named:
                    for k in alt:
                        out.pop(k, None)
    out.update(own)
    return out


def zones_from_mapping(value: Any, top: Mapping[str, Any],
                       length: float) -> tuple[Zone, ...]:
    """The ``[[zones]]`` of a problem table ``top`` (its ``section``, ``material`` and
    ``materials`` are what a zone replaces or names), checked against the rod length (the
    rod puts a node at every boundary: ``Problem.node_arc_lengths``)."""
    from runtime.problem.schema import section_and_material

    if value is None:
        return ()
    if not isinstance(value, list):
        raise ParameterError("zones", value, "an array of tables [[zones]], each with from, "
                             "to (m) and a section and/or material table")
    top_material = top.get("material")
    if value and isinstance(top_material, Mapping) and top_material.get(
            "model") == "generalized_maxwell":
        # said here, before a zone's own tables are read: a zone with a section only
        # inherits the Maxwell material and was refused as zones[k].material.model
        raise ParameterError("zones", f"{len(value)} zone(s)", "no [[zones]] with a "
                             "generalized Maxwell [material] (material.model): its "
                             "relaxation terms are the same along the rod; zones are for "
                             "Kelvin-Voigt rods")
    out = []
    for k, z in enumerate(value):
        path = f"zones[{k}]"
        z = C.table(path, z)
        C.no_unknown_keys(path, z, ZONE_KEYS)
        for key in ("from", "to"):
            if key not in z:
                raise ParameterError(f"{path}.{key}", None, f"an arc length in m, 0 ... "
                                     f"{length:g} (the rod length)")
        a = C.number(f"{path}.from", z["from"], low=0.0, high=length,
                     allowed=f"0 ... {length:g} m (the rod length)")
        b = C.number(f"{path}.to", z["to"], low=0.0, high=length * (1 + 1e-12),
                     allowed=f"{a:g} < to <= {length:g} m (the rod length)")
        if not b > a:
            raise ParameterError(f"{path}.to", b, f"> from = {a:g} m")
        if "section" not in z and "material" not in z:
            raise ParameterError(path, dict(z), "a section and/or a material table for the "
                                 "zone (else it changes nothing)")
        sec_m = (overlay(top.get("section"), z["section"]) if "section" in z
                 else top.get("section"))
        mat_m = (overlay(top.get("material"), z["material"], material=True)
                 if "material" in z else top.get("material"))
        doc: dict[str, Any] = {"section": sec_m}
        if C.table("section", sec_m or {}).get("kind") == "composite":
            if "materials" in top:
                doc["materials"] = top["materials"]
        elif mat_m is not None:
            doc["material"] = mat_m
        try:
            section, material = section_and_material(doc)
        except ParameterError as exc:
            raise ParameterError(f"{path}.{exc.name}", exc.value, exc.allowed,
                                 exc.where) from None
        if getattr(material, "model", "kelvin_voigt") != "kelvin_voigt":
            raise ParameterError(f"{path}.material.model", material.model, "'kelvin_voigt' "
                                 "in zones (a generalized Maxwell rod's relaxation terms "
                                 "are the same along the rod)")
        out.append(Zone(k, a, b, section, material,
                        dict(z["section"]) if "section" in z else None,
                        dict(z["material"]) if "material" in z else None))
    order = sorted(out, key=lambda zz: zz.start)
    for z0, z1 in zip(order, order[1:], strict=False):
        if z1.start < z0.end:
            raise ParameterError(f"zones[{z1.index}].from", z1.start, f">= {z0.end:g} m, "
                                 f"the end of zones[{z0.index}] (zones may not overlap)")
    return tuple(out)


def full_form(m: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """Rod matrices (``Problem.segment_matrices``) with the coupled entries K6, V6, rhoJ,
    mass_centre, made from the diagonals where a section has none."""
    if "K6" in m:
        return m
    n = m["rhoA"].shape[0]
    out = dict(m)
    out["K6"] = np.zeros((n, 6, 6))
    out["V6"] = np.zeros((n, 6, 6))
    idx = np.arange(3)
    out["K6"][:, idx, idx] = m["C_F"]
    out["K6"][:, idx + 3, idx + 3] = m["C_M"]
    out["V6"][:, idx, idx] = m["V_F"]
    out["V6"][:, idx + 3, idx + 3] = m["V_M"]
    out["rhoJ"] = m["rhoI"][:, :, None] * np.eye(3)
    out["mass_centre"] = np.zeros((n, 2))
    return out


def apply_zones(base: dict[str, np.ndarray], s_mid: np.ndarray, zones: tuple[Zone, ...],
                matrices_of) -> dict[str, np.ndarray]:
    """The rod matrices of segments with midpoints ``s_mid`` (m): ``base``, replaced in
    each zone by ``matrices_of(zone, x)`` at the zone's fractions x; in the coupled form
    (:func:`full_form`) for all when any part is coupled."""
    parts = []
    for z in zones:
        sel = (s_mid >= z.start) & (s_mid < z.end)
        if np.any(sel):
            x = (s_mid[sel] - z.start) / (z.end - z.start)
            parts.append((sel, matrices_of(z, x)))
    if not parts:
        return base
    if "theta" in base:
        raise ParameterError("zones", "given", "a Kelvin-Voigt [material] with zones (a "
                             "generalized Maxwell rod's relaxation terms are the same along "
                             "the rod)")
    coupled = "K6" in base or any("K6" in m for _, m in parts)
    out = {k: np.array(v, dtype=float) for k, v in
           (full_form(base) if coupled else base).items()}
    for sel, m in parts:
        m = full_form(m) if coupled else m
        for k in out:
            out[k][sel] = m[k]
    return out
