"""`kvrod plot DIR`: the pictures of any results folder, by what the folder holds.

=================  ==================================  ======================================
folder             recognised by                       draws
=================  ==================================  ======================================
run                summary.json + series.npz           ends.png, energy.png, damping_ratio.png
                                                       (with maxima), centreline.png (with
                                                       centreline frames); ``--animate``:
                                                       centreline.gif or .mp4
static result      summary.json + static.npz           shape.png
modes              modes.json (+ modes.npz)            mode_shapes.png, mode_shapes_3d.png
sweep              study.toml                          summary.png (a point: DIR/points/ID)
=================  ==================================  ======================================

An assembly's run, static result or modes (summary.json or modes.json with an
``"assembly"`` entry) get the same files with every rod and body in them, a run also
joint_forces.png, its modes mode_shapes_3d.png only (:mod:`runtime.io.assembly_plots`).

compare-damping, calibrate and calibrate --dma folders come with their figures and do
not store the series behind them; a folder of such folders (reproduce, notes-*) holds no
result itself. For those, and for anything else, :func:`plot_folder` raises
:class:`~runtime.io.folder.FolderError` with one line saying what the folder holds and what can be
plotted. Everything is checked before anything is drawn. Nothing here prints.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

from runtime.io.folder import FolderError

PREFIX = "kvrod plot"
#: what to do about a damaged file of a run or a static result
_AGAIN = "run the problem again (DIR/problem.toml) to rewrite it"
#: folders whose figures come with the command that wrote them: marker -> (command,
#: figures, why they cannot be redrawn)
FIGURES_ONLY = {
    "compare_damping.json": ("kvrod compare-damping", ("compare_signals.png",
                                                       "compare_zeta.png"),
                             "its decay series are not stored"),
    "calibration.json": ("kvrod calibrate", ("calibration.png",),
                         "the fitted curve is not stored"),
    "dma.json": ("kvrod calibrate --dma", ("dma.png",), "the fitted series is not stored"),
    "section.json": ("kvrod section", ("section.png",), "its mesh is not stored"),
}


@dataclass
class Plotted:
    """What :func:`plot_folder` did: the folder's ``kind``, the files written and notes
    for the user (what was left out and why)."""

    kind: str
    paths: list[Path] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)


def _summary(folder: Path) -> dict:
    try:
        data = json.loads((folder / "summary.json").read_text())
    except (OSError, ValueError):
        return {}
    return data if isinstance(data, dict) else {}


def folder_kind(folder: Path) -> str | None:
    """``run``, ``static``, ``modes``, ``sweep``, a FIGURES_ONLY marker, ``running`` or
    None (see the module docstring)."""
    if (folder / "summary.json").is_file():
        if (folder / "series.npz").is_file():
            return "run"
        if (folder / "static.npz").is_file():
            return "static"
    if (folder / "modes.json").is_file():
        return "modes"
    if (folder / "study.toml").is_file():
        return "sweep"
    for marker in FIGURES_ONLY:
        if (folder / marker).is_file():
            return marker
    if (folder / "summary.json").is_file():
        return "running"
    return None


def _result_subfolders(folder: Path) -> list[str]:
    try:
        subs = sorted(p for p in folder.iterdir() if p.is_dir() and not p.name.startswith("."))
    except OSError:
        return []
    return [p.name for p in subs if folder_kind(p) not in (None, "running")]


def _check(folder: Path, animate: str | None) -> str:
    """The folder's kind, after every check (FolderError naming the folder otherwise)."""
    from runtime.io.folder import LOCK_NAME, lock_holder

    where = repr(str(folder))
    if not folder.exists():
        raise FolderError(f"{PREFIX}: {where} does not exist")
    if not folder.is_dir():
        raise FolderError(f"{PREFIX}: {where} is not a folder (give a results folder)")
    holder = lock_holder(folder)
    if holder is not None:
        raise FolderError(f"{PREFIX}: {where} is in use by process {holder} (lock file "
                       f"{LOCK_NAME}): plot it when that command has finished")
    kind = folder_kind(folder)
    if kind is None:
        subs = _result_subfolders(folder)
        if subs:
            shown = ", ".join(subs[:8]) + (", ..." if len(subs) > 8 else "")
            raise FolderError(f"{PREFIX}: {where} holds no result itself; its subfolders "
                           f"{shown} do: plot one of them, e.g. kvrod plot "
                           f"{folder / subs[0]}")
        raise FolderError(f"{PREFIX}: {where} holds no kvrod result (a run: summary.json + "
                       "series.npz; a static result: static.npz; modes: modes.json; a "
                       "sweep: study.toml)")
    if kind == "running":
        status = _summary(folder).get("status", "unknown")
        raise FolderError(f"{PREFIX}: {where} holds a run without series.npz (status "
                       f"{status!r}): nothing to plot until it has stopped; an "
                       "interrupted run continues with kvrod simulate ... --resume")
    if kind in FIGURES_ONLY:
        command, figs, why = FIGURES_ONLY[kind]
        have = [f for f in figs if (folder / f).is_file()]
        raise FolderError(f"{PREFIX}: {where} is a `{command}` result: its figures "
                       f"({', '.join(have) or ', '.join(figs) + ': missing'}) are drawn by "
                       f"that command and {why}, so kvrod plot has nothing to add; it "
                       "draws runs, static results, modes and sweeps")
    if animate is not None:
        if kind != "run":
            raise FolderError(f"{PREFIX}: --animate draws a run (series.npz with centreline "
                           f"frames); {where} is a {kind} result")
        from runtime.io.shapes import animation_unavailable

        why = animation_unavailable(animate)
        if why is not None:
            raise FolderError(f"{PREFIX}: --animate {animate}: {why}")
        frames = _centreline_frames(folder)
        if frames < 2:
            raise FolderError(f"{PREFIX}: --animate: the run in {where} kept no centreline "
                           "frames (simulation.centreline_frames = 0, or written before kvrod "
                           "kept them); run it again with simulation.centreline_frames >= 2")
    return kind


def _is_assembly(folder: Path) -> bool:
    """summary.json of an assembly's result (an ``"assembly"`` entry)."""
    return isinstance(_summary(folder).get("assembly"), dict)


def _centreline_frames(folder: Path) -> int:
    """The number of centreline frames of a run (an assembly's: every rod's fewest)."""
    from runtime.io.results import read_npz

    if not _is_assembly(folder):
        series = read_npz(folder / "series.npz", ("centreline",), hint=_AGAIN)
        return series["centreline"].shape[0] if "centreline" in series else 0
    rods = _summary(folder)["assembly"].get("rods", [])
    series = read_npz(folder / "series.npz", tuple(f"{r}/centreline" for r in rods),
                      hint=_AGAIN)
    return min((a.shape[0] for a in series.values()), default=0)


def _plot_assembly_run(folder: Path, animate: str | None) -> Plotted:
    from runtime.io.assembly_plots import (
        animate_assembly,
        load_assembly_run,
        plot_assembly_run_folder,
    )

    try:
        out = Plotted("run", plot_assembly_run_folder(folder))
        run = load_assembly_run(folder)
    except ValueError as exc:
        raise FolderError(f"{PREFIX}: {exc}") from None
    if run.frames == 0:
        out.notes.append("no centreline.png: the run kept no centreline frames "
                         "(simulation.centreline_frames = 0)")
    if run.peaks_x.size < 2:
        out.notes.append("no damping_ratio.png: fewer than two maxima (analysis.maxima)")
    if animate is not None:
        out.paths.append(animate_assembly(run, folder / f"centreline.{animate}"))
    return out


def _plot_run(folder: Path, animate: str | None) -> Plotted:
    from runtime.io.plots import LoadedRun, plot_run_folder

    if _is_assembly(folder):
        return _plot_assembly_run(folder, animate)
    out = Plotted("run", plot_run_folder(folder))
    run = LoadedRun(folder)
    if run.centreline.shape[0] == 0:
        out.notes.append("no centreline.png: the run kept no centreline frames "
                         "(simulation.centreline_frames = 0, or written before kvrod kept "
                         "them)")
    if run.peaks_x.size < 2:
        out.notes.append("no damping_ratio.png: fewer than two maxima (analysis.maxima)")
    if animate is not None:
        from runtime.io.shapes import animate_run

        name = _summary(folder).get("problem", folder.name)
        out.paths.append(animate_run(run.centreline_t, run.centreline, run.reference,
                                     folder / f"centreline.{animate}", title=str(name)))
    return out


def _plot_static(folder: Path) -> Plotted:
    from runtime.io.results import DamagedFileError, read_npz
    from runtime.io.shapes import plot_static

    if _is_assembly(folder):
        from runtime.io.assembly_plots import plot_assembly_static_folder

        try:
            return Plotted("static", [plot_assembly_static_folder(folder)])
        except ValueError as exc:
            raise FolderError(f"{PREFIX}: {exc}") from None
    s = _summary(folder)
    path = folder / "static.npz"
    arrays = read_npz(path, ("positions", "reference"), hint=_AGAIN)
    pos, ref = arrays.get("positions"), arrays.get("reference")
    if (pos is None or ref is None or pos.ndim != 2 or pos.shape[0] != 3
            or pos.shape != ref.shape or pos.shape[1] < 2 or pos.dtype.kind not in "fiu"
            or ref.dtype.kind not in "fiu"):
        raise DamagedFileError(f"{path} is damaged (positions and reference must be two "
                               f"(3, n) arrays of numbers; here "
                               f"{None if pos is None else pos.shape} and "
                               f"{None if ref is None else ref.shape}); {_AGAIN}")
    status = s.get("status", "")
    title = f"{s.get('problem', folder.name)}: static equilibrium" + (
        f" ({status}: last converged load step)" if status and status != "finished" else "")
    return Plotted("static", [plot_static(pos, ref, folder / "shape.png", title)])


def _plot_assembly_modes(folder: Path) -> Plotted:
    from runtime.io.assembly_modes import read_assembly_modes
    from runtime.io.assembly_plots import plot_assembly_mode_shapes
    from runtime.io.modes import ModesFileError
    from runtime.io.shapes import MAX_MODES

    try:
        mf = read_assembly_modes(folder)
    except ModesFileError as exc:
        raise FolderError(f"{PREFIX}: {exc}") from None
    out = Plotted("modes", [plot_assembly_mode_shapes(mf, folder / "mode_shapes_3d.png")])
    if len(mf.modes) > MAX_MODES:
        out.notes.append(f"the figure shows the first {MAX_MODES} of {len(mf.modes)} modes")
    return out


def _plot_modes(folder: Path) -> Plotted:
    from runtime.io.assembly_modes import is_assembly_modes
    from runtime.io.modes import ModesFileError, read_modes
    from runtime.io.shapes import MAX_MODES, plot_mode_components, plot_mode_shapes_3d

    try:
        meta = json.loads((folder / "modes.json").read_text())
    except (OSError, ValueError):
        meta = {}
    if is_assembly_modes(meta):
        return _plot_assembly_modes(folder)
    try:
        mf = read_modes(folder)
    except ModesFileError as exc:
        raise FolderError(f"{PREFIX}: {exc}") from None
    out = Plotted("modes", [plot_mode_components(mf, folder / "mode_shapes.png"),
                            plot_mode_shapes_3d(mf, folder / "mode_shapes_3d.png")])
    if len(mf.modes) > MAX_MODES:
        out.notes.append(f"the figures show the first {MAX_MODES} of {len(mf.modes)} modes")
    if mf.equilibrium is None:
        out.notes.append("modes.json of an older kvrod (no modes.npz): the 3-D shapes are "
                         "drawn about a straight rod along z; run kvrod modes again for the "
                         "true equilibrium")
    return out


def _plot_sweep(folder: Path) -> Plotted:
    from runtime.study.sweep import (
        StudyError,
        load_study,
        read_summary,
        table_row,
        write_plots,
    )

    try:
        study = load_study(folder / "study.toml")
    except (StudyError, ValueError) as exc:
        raise FolderError(f"{PREFIX}: the study in {str(folder / 'study.toml')!r} cannot be "
                       f"read: {' '.join(str(exc).split())}") from None
    rows = {p.id: table_row(study, p, read_summary(folder, p)) for p in study.points}
    out = Plotted("sweep")
    path = write_plots(folder, study, rows)
    if path is None:
        out.notes.append("no summary.png: no finished point with damping ratios against a "
                         "numeric varied parameter yet")
    else:
        out.paths.append(path)
    out.notes.append(f"each point is a run: kvrod plot {folder / 'points'}/<point id> draws "
                     "its centreline")
    return out


def plot_folder(folder: Path, animate: str | None = None) -> Plotted:
    """Draw what results folder ``folder`` holds (module docstring); ``animate``: "gif"
    or "mp4" for an animation of a run. Raises FolderError (one line naming the folder and
    what it can plot) before drawing anything when there is nothing to draw."""
    folder = Path(folder)
    kind = _check(folder, animate)
    if kind == "run":
        return _plot_run(folder, animate)
    if kind == "static":
        return _plot_static(folder)
    if kind == "modes":
        return _plot_modes(folder)
    return _plot_sweep(folder)
