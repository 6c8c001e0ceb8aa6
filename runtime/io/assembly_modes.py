"""The results of an assembly's modal analysis (issue 31): ``modes.json`` and
``modes.npz`` as `kvrod modes ASSEMBLY` writes them (one writer, one reader).

modes.json (format 2, kind "assembly")
    ``format`` (2), ``kind`` ("assembly"), ``problem`` (name), ``parameters`` (the resolved
    problem), ``assembly`` (``rods``: the rods' names in file order, ``joints``, ``bodies``:
    their numbers; as in summary.json), ``deformed`` (linearised about the static
    equilibrium under the loads, else about the unloaded reference), ``static`` (null, or
    for ``deformed`` the equilibrium's ``ends`` (each rod's ``NAME.start``/``NAME.end``
    position, m), ``newton_iterations`` and each joint's ``force``/``moment`` on the rod of
    its first point (N, N m) as in a static result's ``joints``), ``bodies``: per body (file
    order) its ``name`` and mass-centre ``position`` (m) and ``frame`` at the equilibrium,
    ``shapes`` ("modes.npz") and ``modes``: one object per mode, lowest first, with
    ``index``, ``omega`` (undamped, rad/s), ``frequency_hz``, ``zeta`` (null for a rigid
    mode), ``eigenvalue`` (the damped eigenvalue with Im >= 0 as [re, im], 1/s) and
    ``kinetic_energy_fractions`` ({rod: fraction of the mode's kinetic energy}; see
    :class:`runtime.analysis.system_modal.AssemblyMode`).

modes.npz
    ``index`` (k,); per rod ``NAME/displacement`` (k, 3, N+1) node displacements (m) and
    ``NAME/rotation`` (k, 3, N) segment rotations (rad, material) of the mass-normalised
    shapes (:mod:`runtime.analysis.system_mode_shapes`), ``NAME/equilibrium`` (3, N+1) and
    ``NAME/equilibrium_frames`` (N, 3, 3; columns d1, d2, d3) of the state linearised
    about, ``NAME/reference`` (3, N+1) the stress-free centreline; per body
    ``body{k}/position`` (3,) at the equilibrium and ``body{k}/displacement`` (k, 3).
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from runtime.io.modes import JSON_NAME, NPZ_NAME, ModesFileError
from runtime.io.results import write_json, write_npz

FORMAT = 2
KIND = "assembly"


def is_assembly_modes(meta: dict) -> bool:
    """A modes.json (its contents) of an assembly."""
    return isinstance(meta, dict) and meta.get("kind") == KIND


def write_assembly_modes(out: Path, problem, amap, modes: Sequence, *, y_eq: np.ndarray,
                         deformed: bool, static: dict | None = None) -> list[Path]:
    """Write ``out/modes.npz`` then ``out/modes.json`` (the folder's marker, last).

    ``modes``: :class:`~runtime.analysis.system_modal.AssemblyMode` list of
    ``amap.model`` linearised about ``y_eq``; ``static``: the equilibrium's summary for
    ``deformed`` (module docstring). Returns both paths."""
    from runtime.analysis.system_mode_shapes import body_mode_displacements, rod_mode_shapes
    from runtime.simulate.assembly import body_state

    out = Path(out)
    model = amap.model
    y = np.asarray(y_eq, dtype=float)
    shapes = rod_mode_shapes(model, y, [m.shape for m in modes])
    arrays: dict[str, np.ndarray] = {"index": np.array([m.index for m in modes], dtype=int)}
    for r, name in enumerate(model.names):
        rod = model.rods[r]
        ys = model.rod_state(r, y)
        arrays[f"{name}/displacement"] = shapes[r].displacement
        arrays[f"{name}/rotation"] = shapes[r].rotation
        arrays[f"{name}/equilibrium"] = rod.positions(ys)
        arrays[f"{name}/equilibrium_frames"] = rod.frames(ys)
        arrays[f"{name}/reference"] = rod.positions(rod.reference)
    body_d = body_mode_displacements(model, y, shapes)
    bodies = []
    for k, (b, body) in enumerate(zip(problem.bodies, model.bodies, strict=True)):
        state = body_state(model, body, y)
        arrays[f"body{k}/position"] = np.array(state["position"])
        arrays[f"body{k}/displacement"] = body_d[:, k]
        bodies.append({"name": b.name, **state})
    npz = write_npz(out / NPZ_NAME, **arrays)
    js = write_json(out / JSON_NAME, {
        "format": FORMAT, "kind": KIND, "problem": problem.name,
        "parameters": problem.to_mapping(),
        "assembly": {"rods": list(model.names), "joints": len(problem.joints),
                     "bodies": len(problem.bodies)},
        "deformed": bool(deformed), "static": static, "bodies": bodies,
        "shapes": NPZ_NAME, "modes": [m.to_dict() for m in modes]})
    return [js, npz]


@dataclass
class AssemblyModesFile:
    """An assembly's modal analysis read back: ``meta`` (modes.json without ``modes``),
    ``modes`` (its list of dicts), ``rods`` (names, file order), per rod name
    ``displacement``, ``rotation``, ``equilibrium``, ``reference`` (module docstring),
    ``bodies``: (name, position (3,), displacement (k, 3)) per body."""

    meta: dict[str, Any]
    modes: list[dict[str, Any]]
    rods: list[str]
    displacement: dict[str, np.ndarray]
    rotation: dict[str, np.ndarray]
    equilibrium: dict[str, np.ndarray]
    reference: dict[str, np.ndarray]
    bodies: list[tuple[str, np.ndarray, np.ndarray]]

    @property
    def size(self) -> float:
        """The largest extent (m) of the equilibrium along x, y or z (at least the longest
        rod's chord): the length a mode shape is drawn against."""
        pts = np.hstack(list(self.equilibrium.values()))
        extent = float(np.max(np.ptp(pts, axis=1))) if pts.size else 0.0
        chord = max((float(np.linalg.norm(r[:, -1] - r[:, 0]))
                     for r in self.equilibrium.values()), default=0.0)
        return max(extent, chord) or 1.0


def read_assembly_modes(out: Path) -> AssemblyModesFile:
    """Read ``out/modes.json`` of an assembly and its shapes in modes.npz. Raises
    :class:`~runtime.io.modes.ModesFileError` naming the file when either is missing,
    unreadable or not an assembly's."""
    out = Path(out)
    path = out / JSON_NAME
    try:
        data = json.loads(path.read_text())
        modes = list(data.pop("modes"))
        rods = [str(r) for r in data["assembly"]["rods"]]
        names = [str(b["name"]) for b in data.get("bodies", [])]
    except (OSError, ValueError, KeyError, TypeError, AttributeError) as exc:
        raise ModesFileError(f"{str(path)!r} is not a readable modes.json of an assembly "
                             f"({type(exc).__name__})") from None
    if not is_assembly_modes(data):
        raise ModesFileError(f"{str(path)!r} is not an assembly's modes.json (kind "
                             f"{data.get('kind')!r})")
    npz = out / str(data.get("shapes", NPZ_NAME))
    fields = ("displacement", "rotation", "equilibrium", "reference")
    try:
        with np.load(npz, allow_pickle=False) as f:
            arrays = {w: {r: np.asarray(f[f"{r}/{w}"], dtype=float) for r in rods}
                      for w in fields}
            bodies = [(n, np.asarray(f[f"body{k}/position"], dtype=float),
                       np.asarray(f[f"body{k}/displacement"], dtype=float))
                      for k, n in enumerate(names)]
    except (OSError, ValueError, KeyError, EOFError) as exc:
        raise ModesFileError(f"the mode shapes {str(npz)!r} are missing or unreadable "
                             f"({type(exc).__name__}); run kvrod modes again") from None
    for r in rods:
        if arrays["displacement"][r].shape[0] != len(modes):
            raise ModesFileError(f"{str(npz)!r} holds {arrays['displacement'][r].shape[0]} "
                                 f"mode shapes of rod {r!r}, {str(path)!r} {len(modes)} "
                                 "modes")
    return AssemblyModesFile(data, modes, rods, bodies=bodies, **arrays)
