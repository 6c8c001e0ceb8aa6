"""The results of a modal analysis: ``modes.json`` and ``modes.npz`` (one writer, one reader).

``kvrod modes``, ``kvrod notes-beyond`` and ``kvrod notes-maxwell`` all write through
:func:`write_modes`; ``kvrod plot`` reads through :func:`read_modes`.

modes.json (format 2)
    ``format`` (2), ``problem`` (name), ``parameters`` (the resolved problem),
    ``tau_E`` (s; the low-frequency equivalent for a generalized Maxwell material),
    ``deformed`` (linearised about the static equilibrium under the loads, else about the
    unloaded reference), ``static_tip`` (m, or null), ``target_omega`` (rad/s: the modes
    are those nearest this natural frequency, numbered within themselves; null or absent:
    the lowest), ``shapes`` ("modes.npz") and
    ``modes``: one object per mode, lowest first, with ``index``, ``family``
    (bending-1, bending-2, torsion, axial, shear, rigid), ``family_index``, ``omega``
    (undamped, rad/s), ``frequency_hz``, ``eigenvalues`` (the damped pair as [re, im],
    1/s), ``zeta`` (null for a rigid mode), ``omega_damped`` (rad/s), ``zeta_modal``,
    ``energy_fractions`` (V1, V2, V3, U1, U2, U3) and ``analytic_omega`` (rad/s, or null):
    see :class:`runtime.analysis.modal.Mode`. With ``kvrod modes --sensitivities``
    also ``sensitivities``: ``{parameter: {"omega": [...], "zeta": [...]}}``, the
    derivatives of every mode's omega (rad/s) and zeta per unit of the parameter, in
    the order of ``modes``, under the name asked and its unique alias
    (:mod:`runtime.analysis.modal_sensitivity`; null: a rigid mode's zeta).

modes.npz
    ``index`` (k,) the modes' indices; ``displacement`` (k, 3, N+1) node displacements
    (m) and ``rotation`` (k, 3, N) segment rotations (rad, material) of the
    mass-normalised mode shapes, their sign fixed where they are computed
    (:func:`runtime.analysis.modal.fix_sign`: the largest component positive);
    ``equilibrium`` (3, N+1) node positions (m) and ``equilibrium_frames`` (N, 3, 3;
    columns d1, d2, d3) of the state the rod was linearised about; ``reference``
    (3, N+1) the stress-free reference centreline (m).

Format 1 (before the shapes moved to modes.npz) held ``displacement`` and ``rotation``
in every mode of the JSON and no ``format``; :func:`read_modes` reads it too (without
the equilibrium, which format 1 did not store).
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from runtime.io.results import read_npz, write_json, write_npz

FORMAT = 2
JSON_NAME = "modes.json"
NPZ_NAME = "modes.npz"


def write_modes(out: Path, problem, modes: Sequence, *, model, y_eq: np.ndarray | None,
                deformed: bool, static_tip: np.ndarray | None = None,
                target: float | None = None,
                sensitivities: dict[str, dict[str, np.ndarray]] | None = None) -> list[Path]:
    """Write ``out/modes.npz`` then ``out/modes.json`` (the folder's marker, last).

    ``modes``: :class:`runtime.analysis.modal.Mode` list of ``model`` (the problem's
    rod) linearised about ``y_eq`` (None: the reference); ``static_tip``: the static
    s = L position (m) of a deformed analysis; ``target``: the natural angular frequency
    (rad/s) the modes are nearest to (``target_omega`` in the JSON; null: the lowest
    modes); ``sensitivities``: ``{parameter: {"omega": (k,), "zeta": (k,)}}``, the
    modes' derivatives (``"sensitivities"`` in the JSON, mode by mode; a rigid mode's
    d zeta null). Returns both paths.
    """
    out = Path(out)
    y = model.reference if y_eq is None else np.asarray(y_eq, dtype=float)
    n_nodes = model.N + 1
    k = len(modes)
    disp = np.stack([m.displacement for m in modes]) if k else np.zeros((0, 3, n_nodes))
    rot = np.stack([m.rotation for m in modes]) if k else np.zeros((0, 3, model.N))
    npz = write_npz(out / NPZ_NAME, index=np.array([m.index for m in modes], dtype=int),
                    displacement=disp, rotation=rot, equilibrium=model.positions(y),
                    equilibrium_frames=model.frames(y),
                    reference=model.positions(model.reference))
    js = write_json(out / JSON_NAME, {
        "format": FORMAT, "problem": problem.name, "parameters": problem.to_mapping(),
        "tau_E": problem.tau_E, "deformed": bool(deformed),
        "static_tip": None if static_tip is None else [float(v) for v in static_tip],
        "target_omega": None if target is None else float(target),
        "shapes": NPZ_NAME,
        "modes": [m.to_dict(shapes=False) for m in modes],
        **({} if sensitivities is None else {"sensitivities": {
            name: {key: [float(v) if math.isfinite(v) else None for v in values]
                   for key, values in d.items()} for name, d in sensitivities.items()}})})
    return [js, npz]


@dataclass
class ModesFile:
    """A modal analysis read back: ``meta`` (modes.json without ``modes``), ``modes``
    (its list of dicts) and the arrays of modes.npz (see the module docstring;
    ``equilibrium``, ``equilibrium_frames`` and ``reference`` are None for format 1)."""

    meta: dict[str, Any]
    modes: list[dict[str, Any]]
    displacement: np.ndarray
    rotation: np.ndarray
    equilibrium: np.ndarray | None
    equilibrium_frames: np.ndarray | None
    reference: np.ndarray | None

    @property
    def length(self) -> float:
        """Arc length of the centreline the modes were computed about (m)."""
        r = self.equilibrium if self.equilibrium is not None else self.reference
        if r is None:
            return float(self.meta.get("parameters", {}).get("rod", {}).get("length", 1.0))
        return float(np.sum(np.linalg.norm(np.diff(r, axis=1), axis=0)))


class ModesFileError(ValueError):
    """A modes result that cannot be read (the message names the file)."""


def read_modes(out: Path) -> ModesFile:
    """Read ``out/modes.json`` and its shapes (format 2: modes.npz; format 1: in the
    JSON). Raises :class:`ModesFileError` naming the file when either is missing or
    unreadable."""
    out = Path(out)
    path = out / JSON_NAME
    try:
        data = json.loads(path.read_text())
        modes = list(data.pop("modes"))
    except (OSError, ValueError, KeyError, TypeError, AttributeError) as exc:
        raise ModesFileError(f"{str(path)!r} is not a readable modes.json "
                             f"({type(exc).__name__})") from None
    if "format" not in data:      # format 1: the shapes are in the JSON
        try:
            disp = np.array([m["displacement"] for m in modes], dtype=float)
            rot = np.array([m["rotation"] for m in modes], dtype=float)
        except (KeyError, TypeError, ValueError):
            raise ModesFileError(f"{str(path)!r} holds no mode shapes") from None
        return ModesFile(data, modes, disp, rot, None, None, None)
    npz = out / str(data.get("shapes", NPZ_NAME))
    keys = ("displacement", "rotation", "equilibrium", "equilibrium_frames", "reference")
    try:
        arrays = read_npz(npz, keys)
        missing = [k for k in keys if k not in arrays]
        if missing:
            raise KeyError(", ".join(missing))
    except (OSError, ValueError, KeyError) as exc:
        raise ModesFileError(f"the mode shapes {str(npz)!r} are missing or unreadable "
                             f"({type(exc).__name__}); run kvrod modes again") from None
    if arrays["displacement"].shape[0] != len(modes):
        raise ModesFileError(f"{str(npz)!r} holds {arrays['displacement'].shape[0]} mode "
                             f"shapes, {str(path)!r} {len(modes)} modes")
    return ModesFile(data, modes, **arrays)
