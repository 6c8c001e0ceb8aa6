"""The problem-key catalogue (runtime/problem/keys.py) against the parsers themselves.

1. Every parser names the keys it accepts in ``coerce.no_unknown_keys``; recorded over
   problems of every kind (geometry, section, material model, end motion, load, time
   function), they must be exactly the catalogue's keys, per table and kind.
2. Each key's ``invalid`` value is refused by ``Problem.from_mapping`` with a message that
   names the key: the documented range is the enforced one.

The section layer (``runtime/section``: ``[[section.regions]]``, their shapes,
``[materials.NAME]``) has its own ``no_unknown_keys`` (it sits below the problem layer);
both are recorded.
"""

from __future__ import annotations

import copy
import re
from typing import Any

import pytest

from runtime.errors import ParameterError
from runtime.problem import coerce, keys
from runtime.problem.schema import TOP_KEYS, Problem
from runtime.section import _checks as section_checks

TABLES_AT_TOP = set(TOP_KEYS) - {"name", "description"}

GEOMETRY = {"straight": {"kind": "straight"},
            "arc": {"kind": "arc", "radius": 0.2, "angle": 90.0},
            "helix": {"kind": "helix"},
            "points": {"kind": "points", "points": [[0, 0, 0], [0, 0, 0.1], [0, 0.01, 0.2]]}}
SECTION = {"rectangle": {"width": 0.01, "height": 0.01}, "ellipse": {"a": 0.01, "b": 0.005},
           "circle": {"radius": 0.005},
           "tube": {"outer_radius": 0.01, "inner_radius": 0.005},
           "stiffness": {k: 1.0 for k in ("EA", "GA1", "GA2", "EI1", "EI2", "GJ", "rhoA",
                                          "rhoI1", "rhoI2", "rhoI3")},
           "composite": {"regions": [{"material": "a", "shape": {"kind": "circle",
                                                                 "radius": 0.004}}]}}
SHAPE = {"circle": {"kind": "circle", "radius": 0.005},
         "rectangle": {"kind": "rectangle", "width": 0.01, "height": 0.01},
         "ellipse": {"kind": "ellipse", "a": 0.01, "b": 0.005},
         "tube": {"kind": "tube", "inner_radius": 0.003, "outer_radius": 0.005},
         "polygon": {"kind": "polygon", "points": [[0, 0], [0.01, 0], [0.01, 0.01]]}}
NAMED = {"isotropic": {"youngs_modulus": 1e6, "poisson_ratio": 0.3, "density": 1000.0},
         "anisotropic": {"density": 1000.0, "stiffness_matrix":
                         [[1e9 if i == j else 0.0 for j in range(6)] for i in range(6)]}}
MATERIAL = {"kelvin_voigt": {"model": "kelvin_voigt", "density": 1000.0,
                             "youngs_modulus": 1e6, "poisson_ratio": 0.3},
            "generalized_maxwell": {"model": "generalized_maxwell", "youngs_modulus": 1e6,
                                    "poisson_ratio": 0.3,
                                    "branches": [{"youngs_modulus": 1e6,
                                                  "poisson_ratio": 0.3, "tau": 0.01}]}}
TIME = {"constant": {"kind": "constant"}, "ramp": {"kind": "ramp", "duration": 1.0},
        "smooth_ramp": {"kind": "smooth_ramp", "duration": 1.0}, "step": {"kind": "step"},
        "release": {"kind": "release"}, "harmonic": {"kind": "harmonic", "frequency": 1.0},
        "table": {"kind": "table", "points": [[0.0, 0.0], [1.0, 1.0]]}}
LOAD = {"force": {"kind": "force", "at": "end", "vector": [0.0, 0.0, 0.01]},
        "moment": {"kind": "moment", "at": "end", "vector": [0.0, 0.0, 0.001]},
        "gravity": {"kind": "gravity", "vector": [0.0, -9.81, 0.0]},
        "distributed": {"kind": "distributed", "vector": [0.0, -1.0, 0.0]}}
MOTION = {"translation": [0.0, 0.001, 0.0], "translation_time": {"kind": "smooth_ramp",
                                                                  "duration": 1.0},
          "rotation_axis": [0.0, 0.0, 1.0], "rotation_angle": 1.0,
          "rotation_time": {"kind": "harmonic", "frequency": 1.0}}


def _base() -> dict[str, Any]:
    return {"name": "keys", "description": "catalogue check",
            "rod": {"length": 0.3, "elements": 4, "geometry": {"kind": "straight"}},
            "section": {"kind": "rectangle", **SECTION["rectangle"]},
            "material": copy.deepcopy(MATERIAL["kelvin_voigt"]),
            "start": {"kind": "clamped"}, "end": {"kind": "free"}, "loads": [],
            "simulation": {"t_end": 1.0}, "statics": {"load_steps": 2},
            "analysis": {"maxima": "end.x"}}


def _variant(table: str, kind: str | None) -> tuple[dict, dict]:
    """A valid problem whose ``table`` (of ``kind``) is present; returns (problem, the
    table's mapping inside it)."""
    m = _base()
    if table == "rod.geometry":
        g = copy.deepcopy(GEOMETRY[kind or "straight"])
        m["rod"]["geometry"] = g
        if kind not in (None, "straight"):
            del m["rod"]["length"]
        return m, g
    if table == "section":
        m["section"] = {"kind": kind or "rectangle", **copy.deepcopy(SECTION[kind or
                                                                           "rectangle"])}
        if kind == "composite":
            del m["material"]
            m["materials"] = {"a": copy.deepcopy(NAMED["isotropic"])}
        return m, m["section"]
    if table.startswith("section.regions") or table.startswith("materials"):
        del m["material"]
        named = copy.deepcopy(NAMED["anisotropic" if table.endswith("orientation") else
                                    kind if table == "materials.NAME" and kind else
                                    "isotropic"])
        m["materials"] = {"a": named}
        shape = copy.deepcopy(SHAPE[kind if table == "section.regions.shape" and kind
                                    else "circle"])
        region = {"material": "a", "shape": shape}
        m["section"] = {"kind": "composite", "regions": [region]}
        if table == "section.regions":
            return m, region
        if table == "section.regions.shape":
            return m, shape
        if table == "materials.NAME.orientation":
            named["orientation"] = {"rotation": 10.0, "off_axis": 20.0}
            return m, named["orientation"]
        return m, named
    if table == "material":
        m["material"] = copy.deepcopy(MATERIAL[kind or "kelvin_voigt"])
        return m, m["material"]
    if table == "material.branches":
        m["material"] = copy.deepcopy(MATERIAL["generalized_maxwell"])
        return m, m["material"]["branches"][0]
    if table in ("start", "end"):
        m[table] = {"kind": "clamped"}
        return m, m[table]
    if table in ("start.motion", "end.motion"):
        end = table.split(".")[0]
        m[end] = {"kind": "clamped", "motion": copy.deepcopy(MOTION)}
        return m, m[end]["motion"]
    if table == "loads":
        m["loads"] = [copy.deepcopy(LOAD[kind or "force"])]
        return m, m["loads"][0]
    if table == "<time>":
        m["loads"] = [{**LOAD["force"], "time": copy.deepcopy(TIME[kind or "constant"])}]
        return m, m["loads"][0]["time"]
    if table == "zones":
        m["zones"] = [{"from": 0.1, "to": 0.2, "material": {"tau": 0.01},
                       "section": {"kind": "rectangle", "width": 0.02, "height": 0.01}}]
        return m, m["zones"][0]
    if table == "":
        return m, m
    return m, m[table]


def _variants():
    for table, kinds in (("rod.geometry", GEOMETRY), ("section", SECTION),
                         ("material", MATERIAL), ("loads", LOAD), ("<time>", TIME),
                         ("section.regions.shape", SHAPE), ("materials.NAME", NAMED)):
        for kind in kinds:
            yield table, kind
    for table in ("", "rod", "material.branches", "start", "end", "start.motion",
                  "end.motion", "simulation", "statics", "analysis", "section.regions",
                  "materials.NAME.orientation", "zones"):
        yield table, None


def _table_of(path: str) -> str:
    path = re.sub(r"\[\d+\]", "", path)
    path = re.sub(r"^materials\.[^.]+", "materials.NAME", path)
    if path.endswith(("time", "translation_time", "rotation_time")):
        return "<time>"
    return path


def _catalogued(table: str, kind: str | None) -> set[str]:
    return {k.name for k in keys.KEYS if k.table == table
            and (not k.kinds or kind is None or kind in k.kinds)}


@pytest.mark.parametrize(("table", "kind"), list(_variants()))
def test_the_catalogue_lists_exactly_the_keys_the_parser_accepts(monkeypatch, table, kind):
    seen: dict[str, set[str]] = {}
    original = coerce.no_unknown_keys

    def record(path, mapping, allowed):
        seen.setdefault(_table_of(path), set()).update(allowed)
        return original(path, mapping, allowed)

    monkeypatch.setattr(coerce, "no_unknown_keys", record)
    monkeypatch.setattr(section_checks, "no_unknown_keys", record)
    m, _ = _variant(table, kind)
    Problem.from_mapping(m)
    accepted = set(seen[table])
    if table == "":
        accepted -= TABLES_AT_TOP
    if table == "section":           # the parser pops `kind` before checking the rest
        accepted.add("kind")
    if table == "<time>" and kind is None:
        accepted.add("kind")
    assert accepted == _catalogued(table, kind), (table, kind)


def _invalid_cases():
    for k in keys.KEYS:
        if k.invalid is None:
            continue
        kind = k.kinds[0] if k.kinds else None
        if k.table == "material" and kind is None:
            kind = "kelvin_voigt"
        yield pytest.param(k, kind, id=f"{k.table or 'top'}.{k.name}[{kind}]")


@pytest.mark.parametrize(("key", "kind"), list(_invalid_cases()))
def test_each_documented_range_is_enforced_and_the_error_names_the_key(key, kind):
    m, t = _variant(key.table, kind)
    if key.name == "file":              # exclusive with inline points
        t.pop("points", None)
    if key.name == "s":                 # exclusive with `at`
        t.pop("at", None)
    if key.table == "material.branches" and key.name in ("shear_modulus", "bulk_modulus"):
        t.clear()
        t.update({"shear_modulus": 1e5, "bulk_modulus": 1e6, "tau": 0.01})
    t[key.name] = copy.deepcopy(key.invalid)
    with pytest.raises(ParameterError) as exc:
        Problem.from_mapping(m)
    assert key.name in str(exc.value), str(exc.value)


def test_every_key_has_unit_default_range_and_meaning():
    paths = [(k.table, k.name, k.kinds) for k in keys.KEYS]
    assert len(paths) == len(set(paths))
    for k in keys.KEYS:
        assert k.unit and k.default and k.allowed and k.doc, k.path
    text = keys.markdown()
    assert all(f"`{k.name}`" in text for k in keys.KEYS)
