"""Scenario configuration files (TOML) -> validated scenario parameters.

Format (``kvrod simulate --config run.toml``)::

    scenario = "cantilever"
    [parameters]            # any CantileverScenario field, plus tau = tau_S = tau_B
    tau = 0.04
    youngs_modulus = 1.0e6
    n_elements = 50

Every problem (missing file, malformed TOML, unknown scenario or key, wrong type) raises
:class:`ConfigError` (a ValueError) with one line naming the file and the key.
"""

from __future__ import annotations

import dataclasses
import tomllib
from pathlib import Path
from typing import Any

from runtime.scenarios import CantileverScenario

SCENARIOS = {"cantilever": CantileverScenario}


class ConfigError(ValueError):
    """A configuration file that cannot be used (message names file and key)."""


def scenario_fields(name: str = "cantilever") -> dict[str, type]:
    cls = SCENARIOS[name]
    return {f.name: f.type for f in dataclasses.fields(cls)}


def _coerce(path: Path, key: str, value: Any, annotation: str) -> Any:
    ann = str(annotation)
    if ann in ("int",):
        if isinstance(value, bool) or not isinstance(value, int):
            raise ConfigError(f"{path}: {key} = {value!r} must be an integer")
        return value
    if ann in ("bool",):
        if not isinstance(value, bool):
            raise ConfigError(f"{path}: {key} = {value!r} must be true or false")
        return value
    if ann in ("str",):
        if not isinstance(value, str):
            raise ConfigError(f"{path}: {key} = {value!r} must be a string")
        return value
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ConfigError(f"{path}: {key} = {value!r} must be a number")
    return float(value)


def parameters_from_mapping(path: Path, params: dict, scenario: str = "cantilever") -> dict:
    """Validated keyword arguments for the scenario dataclass (``tau`` expanded)."""
    fields = scenario_fields(scenario)
    both = [k for k in ("tau_S", "tau_B") if k in params]
    if "tau" in params and both:
        raise ConfigError(f"{path}: tau and {' and '.join(both)} are both given; tau sets "
                          "tau_S = tau_B, so give either tau or tau_S/tau_B")
    out: dict[str, Any] = {}
    for key, value in params.items():
        if key == "tau":
            v = _coerce(path, key, value, "float")
            out["tau_S"] = out["tau_B"] = v
            continue
        if key not in fields:
            raise ConfigError(f"{path}: unknown parameter {key!r}; allowed: tau, "
                              + ", ".join(sorted(fields)))
        ann = fields[key]
        out[key] = None if value is None else _coerce(
            path, key, value, "float" if "float" in str(ann) else str(ann))
    return out


def read_toml(path: Path, error: type[ValueError] = ValueError,
              what: str = "config file") -> tuple[dict, str]:
    """(parsed document, text) of a TOML file; ``error`` (one line naming the file) when it
    cannot be read or parsed."""
    path = Path(path)
    try:
        text = path.read_text()
    except OSError as exc:
        raise error(f"{path}: cannot read the {what} ({exc.strerror})") from exc
    try:
        return tomllib.loads(text), text
    except tomllib.TOMLDecodeError as exc:
        raise error(f"{path}: malformed TOML: {exc}") from exc


def load_config(path: Path) -> tuple[str, dict]:
    """(scenario name, scenario keyword arguments) from a TOML file."""
    path = Path(path)
    doc, _ = read_toml(path, ConfigError)
    name = doc.pop("scenario", "cantilever")
    if not isinstance(name, str):
        raise ConfigError(f"{path}: scenario = {name!r} must be a string, one of: "
                          + ", ".join(SCENARIOS))
    if name not in SCENARIOS:
        raise ConfigError(f"{path}: unknown scenario {name!r}; scenarios are: "
                          + ", ".join(SCENARIOS))
    params = doc.pop("parameters", {})
    if not isinstance(params, dict):
        raise ConfigError(f"{path}: [parameters] must be a table")
    flat = {k: v for k, v in doc.items() if not isinstance(v, dict)}
    extra_tables = [k for k, v in doc.items() if isinstance(v, dict)]
    if extra_tables:
        raise ConfigError(f"{path}: unknown table(s) {extra_tables}; use [parameters]")
    twice = sorted(set(flat) & set(params))
    if twice:
        raise ConfigError(f"{path}: {', '.join(twice)} given both at the top level and in "
                          "[parameters]; give each once")
    return name, parameters_from_mapping(path, {**flat, **params}, name)
