"""Results folders: atomic JSON/NPZ writes of a run (docs/design.md, section 4, I/O).

Every file is written under a temporary name in the same folder and renamed, so a
reader never sees half a file, and a run that dies leaves the previous complete file.
"""

from __future__ import annotations

import json
import math
import zipfile
from pathlib import Path
from typing import Any

import numpy as np

from runtime.io.atomic import atomic_path, write_text


def jsonable(obj: Any, nonfinite: str = "string") -> Any:
    """``obj`` with NumPy scalars/arrays as plain Python; non-finite floats as strings
    (``nonfinite="string"``: "nan", "inf") or as None (``"null"``), since JSON has neither."""
    if isinstance(obj, dict):
        return {str(k): jsonable(v, nonfinite) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [jsonable(v, nonfinite) for v in obj]
    if isinstance(obj, np.ndarray):
        return jsonable(obj.tolist(), nonfinite)
    if isinstance(obj, (np.floating, float)):
        v = float(obj)
        if math.isfinite(v):
            return v
        return str(v) if nonfinite == "string" else None
    if isinstance(obj, np.integer):
        return int(obj)
    return obj


def write_json(path: Path, data: dict) -> Path:
    """Write ``data`` as indented JSON atomically (non-finite floats become strings)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    return write_text(path, json.dumps(jsonable(data), indent=2) + "\n")


#: zlib level of the NPZ files (``np.savez_compressed`` uses zlib's default, 6): level 1
#: wrote the N = 50 cantilever's series.npz (0.81 MB of arrays) in ~60 % of the time for
#: a 1 % larger file (0.289 vs 0.285 MB); floating-point series hardly compress further
NPZ_COMPRESSLEVEL = 1


def write_npz(path: Path, **arrays: np.ndarray) -> Path:
    """Write arrays to a compressed NPZ atomically: what ``np.savez_compressed`` writes
    (an entry ``<key>.npy`` per array, read back by ``np.load``), at
    :data:`NPZ_COMPRESSLEVEL`."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(path, suffix=".npz") as tmp:
        _write_archive(tmp, arrays)
    return path


def _write_archive(tmp: Path, arrays: dict[str, Any]) -> None:
    # a function of its own: the ZipFile is released (its __del__ runs) before
    # atomic_path delivers a held signal, not after, where an interrupt is lost
    with zipfile.ZipFile(tmp, "w", compression=zipfile.ZIP_DEFLATED,
                         compresslevel=NPZ_COMPRESSLEVEL) as archive:
        for key, value in arrays.items():
            with archive.open(f"{key}.npy", "w", force_zip64=True) as entry:
                np.lib.format.write_array(entry, np.asanyarray(value), allow_pickle=True)


class DamagedFileError(ValueError):
    """A results file that cannot be read back (truncated, not what it should hold); the
    message names the file."""


def read_npz(path: Path, keys: tuple[str, ...] | None = None, *,
             hint: str = "") -> dict[str, np.ndarray]:
    """The arrays of an NPZ file (all, or those of ``keys`` it holds), read at once.

    Anything that goes wrong reading the bytes of an existing file (a truncated archive,
    a damaged member, a header claiming an impossible shape) is the file's damage:
    :class:`DamagedFileError` naming it, ``hint`` (what to do) appended. A missing file
    is a FileNotFoundError.
    """
    path = Path(path)
    try:
        with np.load(path, allow_pickle=False) as f:
            names = f.files if keys is None else [k for k in keys if k in f.files]
            return {k: np.asarray(f[k]) for k in names}
    except FileNotFoundError:
        raise
    except Exception as exc:  # noqa: BLE001 - any failure to decode the bytes
        what = " ".join(str(exc).split())[:120]
        raise DamagedFileError(f"{path} is damaged ({type(exc).__name__}: {what})"
                               + (f"; {hint}" if hint else "")) from None


def write_run(out_dir: Path, run, extra: dict | None = None) -> dict:
    """summary.json, series.npz and problem.toml of a
    :class:`runtime.simulate.simulate.SimulationResult`.

    series.npz: ``t`` (n,), ``tip`` and ``start`` (3, n) end positions (m), the energies
    ``kinetic``, ``elastic``, ``dissipated``, ``external_work`` (J) and
    ``energy_balance_rel`` on the output grid, ``peaks_t``/``peaks_x``, and the static and
    last states ``y_static``, ``y_last``; the end frames ``start_frame``, ``end_frame``
    (n, 3, 3; columns d1, d2, d3) and their rotations from the reference,
    ``start_rotation``, ``end_rotation`` (3, n; rad, spatial rotation vectors); for each
    held end the support's ``start_reaction_force`` / ``_moment`` (3, n; N, N m about the
    node, spatial, inertia included), likewise ``end_reaction_*``; the deformed
    centreline ``centreline`` (m, 3, N+1; m) at the frame times ``centreline_t`` (m,; s;
    ``simulation.centreline_frames``) and the stress-free ``reference`` centreline
    (3, N+1; m); per obstacle k ``obstacle{k}_force`` / ``_moment`` (3, n; N, N m about
    its point, on the rod, spatial), ``obstacle{k}_energy`` (J), ``_dissipation``,
    ``_friction_dissipation``, ``_power`` (W), ``_gap_min`` (m) and ``_segments`` (n,);
    with ``contact.self`` the pairs' ``self_contact_energy`` (J), ``_dissipation``,
    ``_friction_dissipation`` (W), ``_gap_min`` (m; inf: no pair), ``_pairs`` and
    ``_force`` (N: the sum of the pairs' force magnitudes), (n,).
    problem.toml: the resolved problem (rerun it with ``kvrod simulate
    DIR/problem.toml``).
    """
    out_dir = Path(out_dir)
    summary = run.summary()
    if extra:
        summary.update(extra)
    ends = {}
    for end, f in run.end_frames().items():
        ends[f"{end}_frame"] = f
    for end, r in run.end_rotations().items():
        ends[f"{end}_rotation"] = r
    for end, r in run.reactions.items():
        for what, v in r.items():
            ends[f"{end}_reaction_{what}"] = v
    for k, r in enumerate(getattr(run, "obstacles", ())):
        for what, v in r.items():
            ends[f"obstacle{k}_{what}"] = v
    for what, v in getattr(run, "self_contact", {}).items():
        ends[f"self_contact_{what}"] = v
    write_npz(out_dir / "series.npz", t=run.t, tip=run.tip, start=run.start,
              kinetic=run.kinetic, elastic=run.elastic, dissipated=run.dissipated,
              external_work=run.external_work, energy_balance_rel=run.energy_balance_rel,
              peaks_t=run.peaks_t, peaks_x=run.peaks_x,
              y_static=run.y_static if run.y_static is not None else np.zeros(0),
              y_last=run.y_last if run.y_last is not None else np.zeros(0),
              centreline_t=run.centreline_t, centreline=run.centreline,
              reference=(run.model.positions(run.model.reference) if run.model is not None
                         else np.zeros((3, 0))), **ends)
    write_problem(out_dir / "problem.toml", summary["parameters"])
    write_json(out_dir / "summary.json", summary)
    return summary


def write_problem(path: Path, mapping: dict) -> Path | None:
    """The resolved problem as TOML (atomically); None when it holds a Python callable."""
    import tomli_w

    doc = jsonable(mapping, nonfinite="null")
    if doc.get("rod", {}).get("geometry", {}).get("kind") == "curve":
        return None
    return write_text(path, "# the resolved problem of this run: kvrod simulate " + path.name
                      + "\n" + tomli_w.dumps(_drop_none(doc)))


def _drop_none(obj):
    if isinstance(obj, dict):
        return {k: _drop_none(v) for k, v in obj.items() if v is not None}
    if isinstance(obj, list):
        return [_drop_none(v) for v in obj]
    return obj


CHECKPOINT = "checkpoint.npz"


def write_status(out_dir: Path, parameters: dict, status: str, t_reached: float = 0.0,
                 message: str = "") -> Path:
    """A minimal summary.json for a run in progress (status "running")."""
    return write_json(Path(out_dir) / "summary.json",
                      {"status": status, "message": message, "parameters": parameters,
                       "t_reached": t_reached})


def write_checkpoint(out_dir: Path, parameters: dict, state: dict) -> Path:
    """Everything :func:`runtime.simulate.simulate.simulate` needs to continue (its
    ``resume=``), plus the resolved parameters (a resume with others is refused)."""
    arrays = {k: np.asarray(v) for k, v in state.items() if k != "counters"}
    arrays["counters_json"] = np.array(json.dumps(state["counters"]))
    arrays["parameters_json"] = np.array(json.dumps(jsonable(parameters), sort_keys=True))
    path = Path(out_dir) / CHECKPOINT
    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(path, suffix=".npz") as tmp:
        # not compressed: written many times during a run and read at most once (zlib
        # took half of a checkpoint's time)
        np.savez(tmp, **arrays)
    return path


def _flatten(obj, prefix: str = "") -> dict:
    """{dotted.path: value} of nested tables (lists by index)."""
    if isinstance(obj, dict):
        out: dict = {}
        for k, v in obj.items():
            out.update(_flatten(v, f"{prefix}{k}."))
        return out
    if isinstance(obj, list) and obj and all(isinstance(v, dict) for v in obj):
        out = {}
        for i, v in enumerate(obj):
            out.update(_flatten(v, f"{prefix}{i}."))
        return out
    return {prefix[:-1]: obj}


def _named(path: str) -> str:
    """A dotted path with its command-line alias, e.g. 'rod.elements (n_elements)'."""
    from runtime.problem.schema import ALIASES

    alias = next((a for a, p in ALIASES.items() if p == path and "_" in a), None)
    return f"{path} ({alias})" if alias else path


class CheckpointError(ValueError):
    """A checkpoint that cannot be used for --resume (message names the file)."""


def load_checkpoint(out_dir: Path, parameters: dict,
                    required: tuple[str, ...] = ("t", "y", "yp")) -> dict:
    """The state saved by :func:`write_checkpoint`.

    Raises :class:`CheckpointError` if there is none, it is unreadable (truncated,
    corrupted, not an NPZ archive), lacks a ``required`` entry, or was written for other
    parameters (names the first differing parameter).
    """
    path = Path(out_dir) / CHECKPOINT
    if not path.exists():
        raise CheckpointError(f"--resume: no checkpoint in {str(out_dir)!r} (nothing to "
                              "resume: a run writes its first checkpoint after a second of "
                              "wall time, KVROD_CHECKPOINT_WALL; run it again with "
                              "--overwrite)")
    try:
        data = read_npz(path)
        saved = json.loads(str(data.pop("parameters_json")))
        counters = json.loads(str(data.pop("counters_json")))
    except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile) as exc:
        raise CheckpointError(f"--resume: checkpoint {str(path)!r} is unreadable or "
                              f"truncated ({type(exc).__name__}); start again with "
                              "--overwrite") from exc
    missing = [k for k in required if k not in data]
    if missing or not isinstance(saved, dict) or not isinstance(counters, dict):
        raise CheckpointError(f"--resume: checkpoint {str(path)!r} is incomplete (missing "
                              f"{', '.join(missing) or 'metadata'}); start again with "
                              "--overwrite")
    a, b = _flatten(saved), _flatten(jsonable(parameters))
    for key in sorted(set(a) | set(b)):
        if a.get(key) != b.get(key):
            raise CheckpointError(f"--resume: checkpoint in {str(out_dir)!r} was written with "
                                  f"{_named(key)} = {a.get(key)!r}, this run has "
                                  f"{b.get(key)!r}")
    data["counters"] = counters
    return data
