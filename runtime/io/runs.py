"""Run a problem into a results folder (the results-folder protocol of a run): the work
behind `kvrod simulate` and `kvrod static`, shared by those commands and the notes."""

from __future__ import annotations

import contextlib
from collections.abc import Callable
from pathlib import Path
from typing import Any


def already_finished(problem, out: Path) -> bool:
    """True when DIR holds a finished run of exactly this problem (and no checkpoint)."""
    import json

    from runtime.io.results import CHECKPOINT, jsonable

    path = out / "summary.json"
    if (out / CHECKPOINT).exists() or not path.exists():
        return False
    try:
        data = json.loads(path.read_text())
    except (OSError, ValueError):
        return False
    return (isinstance(data, dict) and data.get("status") == "finished"
            and data.get("parameters") == jsonable(problem.to_mapping()))


#: seconds of wall time at least between a run's checkpoints, and before its first (the
#: loop's start stands for the previous one): a checkpoint writes the run's samples so far
#: and its status (~2.5 ms of CPU at N = 50, and two files on disk while the loop runs:
#: on a virtual machine's disk the 10 s cantilever's whole run took ~6 ms longer with its
#: one checkpoint, docs/design.md section 13), and one every simulated second was a third
#: of the CPU time of a 10 s cantilever run; a run shorter than this writes none (running
#: it again costs less). ``KVROD_CHECKPOINT_WALL`` (seconds >= 0) sets another; 0: a
#: checkpoint at every ``checkpoint_every`` of simulated time, the first at the first
CHECKPOINT_WALL = 1.0
CHECKPOINT_WALL_ENV = "KVROD_CHECKPOINT_WALL"


def checkpoint_wall() -> float:
    """:data:`CHECKPOINT_WALL`, or the seconds ``KVROD_CHECKPOINT_WALL`` gives (a finite
    number >= 0; anything else is refused, naming the variable)."""
    import math
    import os

    from runtime.errors import ParameterError

    text = os.environ.get(CHECKPOINT_WALL_ENV, "").strip()
    if not text:
        return CHECKPOINT_WALL
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and value >= 0.0):
        raise ParameterError(CHECKPOINT_WALL_ENV, text,
                             "seconds of wall time >= 0 (0: a checkpoint every simulated "
                             "second)", where="the environment")
    return value

class CheckpointWriter:
    """A run's checkpoints written on a thread while its loop goes on: a checkpoint
    (``write(state)``: the npz and the status file) costs ~2.5-3.5 ms at N = 50, which
    the compiled loop, holding no GIL, need not wait for. One at a time and in order:
    :meth:`submit` waits for the previous one, and :meth:`wait` must be called before
    anything else writes the folder (the final summary.json must not be overtaken by a
    "running" one). The state is copied first (the run goes on changing its arrays). An
    error of the writer is raised by the next :meth:`submit` or :meth:`wait`, so it is
    never lost."""

    def __init__(self, write: Callable[[dict], object]) -> None:
        self._write = write
        self._thread = None
        self._error: BaseException | None = None

    def __enter__(self) -> CheckpointWriter:
        return self

    def __exit__(self, kind, exc, tb) -> bool:
        """Wait for the checkpoint in flight; on an exception already on its way, the
        checkpoint's own failure (if any) is added to it as a note, not lost."""
        if exc is None:
            self.wait()
        else:
            note = self.wait_noting("")
            if note:
                exc.add_note(note.removeprefix("; "))
        return False

    def submit(self, state: dict) -> None:
        import copy
        import threading

        import numpy as np

        self.wait()
        state = {k: np.array(v) if isinstance(v, np.ndarray) else copy.deepcopy(v)
                 for k, v in state.items()}
        self._thread = threading.Thread(target=self._run, args=(state,),
                                        name="kvrod-checkpoint")
        self._thread.start()

    def _run(self, state: dict) -> None:
        try:
            self._write(state)
        except BaseException as exc:          # handed to the run's thread by wait()
            self._error = exc

    def wait(self) -> None:
        """Until the checkpoint in flight is written; raises its error, if it failed."""
        if self._thread is not None:
            self._thread.join()
            self._thread = None
        if self._error is not None:
            exc, self._error = self._error, None
            raise exc

    def wait_noting(self, message: str) -> str:
        """:meth:`wait` for a run that is failing anyway: ``message``, with the
        checkpoint's own error added if it failed too."""
        try:
            self.wait()
        except Exception as exc:
            return f"{message}; the last checkpoint could not be written: {exc}"
        return message


def _folder_checkpoints(out: Path, params: dict) -> CheckpointWriter:
    """The writer of a run's checkpoints into results folder ``out``: the checkpoint,
    then the "running" status at its time."""
    from runtime.io.results import write_checkpoint, write_status

    def write(state: dict) -> None:
        write_checkpoint(out, params, state)
        write_status(out, params, "running", state["t"])

    return CheckpointWriter(write)


def _write_results(out: Path, params: dict, run, writer: CheckpointWriter, sens_run,
                   write: Callable[[], dict]) -> dict:
    """After the checkpoint in flight: the sensitivities (if any), then ``write()`` (the
    run's files; its summary returned). On any failure summary.json says "failed" and
    why (e.g. a full disk: never "running" left behind), and the error is raised."""
    try:
        writer.wait()
        if sens_run is not None and sens_run.collected is not None:
            write_sensitivities(out, sens_run.collected)
        return write()
    except BaseException as exc:
        from runtime.io.results import write_status

        with contextlib.suppress(Exception):
            # (a signal inside the wait for the checkpoint: finish waiting first, so that
            # its "running" status cannot land after this one)
            write_status(out, params, "failed", run.t_last, writer.wait_noting(
                f"the results could not be written: {exc}"))
        raise


#: a progress display of a run: ``progress(t_end, label) -> (callback(t), close())`` (the
#: callback None: nothing to show, e.g. not on a terminal)
ProgressDisplay = Callable[[float, str], tuple[Callable[[float], object], Callable[[], object]]]


def _check_resume_state(state: dict, n: int, out: Path, what: str) -> None:
    """Refuse (CheckpointError) a checkpoint whose y or y' is not n finite values (the
    state of this ``what``, "problem" or "assembly")."""
    import numpy as np

    from runtime.io.results import CHECKPOINT, CheckpointError

    for key in ("y", "yp"):
        if np.shape(state[key]) != (n,) or not np.all(np.isfinite(state[key])):
            raise CheckpointError(f"--resume: checkpoint {str(out / CHECKPOINT)!r} holds a "
                                  f"state {key} of shape {np.shape(state[key])}, this "
                                  f"{what} needs ({n},) finite values; start again with "
                                  "--overwrite")


def _run_in_folder(out: Path, params: dict, state: dict | None, overwrite: bool, problem,
                   label: str, progress: ProgressDisplay | None, sens_run,
                   frames: Callable[[float | None], Any] | None,
                   run_it: Callable[[Any, Callable, Any], Any],
                   write: Callable[[Any, dict | None], dict],
                   plot: Callable[[Any], None] | None) -> tuple:
    """The folder's part of a run, the same for a rod and an assembly (everything is
    checked before): the folder claimed and locked, "running" in summary.json, the VTK
    series from ``frames(resume_from)`` (None: none), ``run_it(progress callback,
    on_checkpoint, series)``, checkpoints written on a thread, "failed" with the reason on
    any error (the checkpoint kept), then the results by ``write(run, extra)``, the
    checkpoint removed when finished, an interrupt raised again, ``plot(run)``. Returns
    (run, summary)."""
    from runtime.io import folder as F
    from runtime.io.results import CHECKPOINT, write_status

    with F.claim(out, "simulate", overwrite=overwrite) as claimed:
        t_start = float(state["t"]) if state else 0.0
        write_status(out, params, "running", t_start)
        claimed.keep()

        # the folder (and its lock) is never left with a checkpoint in flight
        with _folder_checkpoints(out, params) as writer:

            def on_checkpoint(st):
                if series is not None:       # the frames so far survive a kill after this
                    series.write_collection()
                writer.submit(st)

            series = None
            if frames is not None:
                series = frames(t_start if state else None)
            cb, close = (progress(problem.simulation.t_end, label) if progress is not None
                         else (None, lambda: None))
            try:
                run = run_it(cb, on_checkpoint, series)
            except BaseException as exc:   # a bug or resource error: say so, keep the checkpoint
                write_status(out, params, "failed", t_start,
                             writer.wait_noting(f"{type(exc).__name__}: {exc}"))
                raise
            finally:
                close()
                if series is not None:
                    series.close()
            extra = {"resumed_from_t": t_start} if state else None
            if sens_run is not None and sens_run.collected is not None:
                extra = {**(extra or {}), "sensitivities": sens_run.collected.summary()}
            summary = _write_results(out, params, run, writer, sens_run,
                                     lambda: write(run, extra))
            if run.status == "finished":
                (out / CHECKPOINT).unlink(missing_ok=True)
            if run.interrupt is not None:
                raise run.interrupt
            if plot is not None and run.t.size > 1:
                plot(run)
    return run, summary


def load_compiled(problem=None) -> None:
    """Load the compiled rod kernels and the solver's C helpers, and the contact kernels
    where ``problem`` (a rod's or an assembly's) touches obstacles or itself (compiling
    them on a machine's first run: tens of seconds), with the checks before a run,
    before its folder is locked and its clock starts: the summary's ``wall_time_s`` is
    the run's, not a one-off compilation's, and a first run says "compiling" before its
    progress starts. Each library is loaded once per process
    (:func:`runtime.model.build.load_library`, :func:`runtime.solvers.native.loader.
    load`, :func:`runtime.model.build.load_contact_library`); without a compiler the
    CasADi fallback's warning comes here, and contact's
    :class:`~runtime.errors.GeneratedCodeError` (it has no fallback) before anything is
    written."""
    from runtime.model import build
    from runtime.solvers.native import loader

    build.load_library()
    loader.load()
    contact = getattr(problem, "contact", None)
    if getattr(problem, "obstacles", ()) or (contact is not None and contact.self_contact):
        build.load_contact_library()


def run_and_write(problem, out: Path, label: str, plots: bool = False, resume: bool = False,
                  vtk_every: float | None = None, checkpoint_every: float = 1.0,
                  overwrite: bool = False, progress: ProgressDisplay | None = None,
                  sensitivities: list[str] | None = None, sens_errcon: bool = False) -> tuple:
    """Run one problem into results folder ``out`` and write its results.

    Everything that can be checked is checked before anything is written (parameters, the
    folder, an existing result, the checkpoint to resume, the generated code). Then the
    folder is locked (``.kvrod.lock``), ``summary.json`` says "running" (with t_reached)
    while the run goes and a checkpoint is written every ``checkpoint_every`` simulated
    seconds, at most one per :func:`checkpoint_wall` seconds of wall time, the first
    after that much of the run (a shorter run writes none);
    when the run stops, ``summary.json`` says "finished", "failed" or
    "interrupted" (never "running", except after SIGKILL). ``resume`` continues from
    DIR/checkpoint.npz (VTK frames before the checkpoint are kept); ``overwrite`` replaces
    a finished result. ``sensitivities``: parameter names (validated here, before
    anything is written) whose forward sensitivities go to ``sensitivities.npz``
    (:func:`write_sensitivities`; summary.json's ``sensitivities``); ``sens_errcon``: in
    the error test too. Returns (result, summary).
    """
    from runtime.io import folder as F
    from runtime.io.assembly_results import is_assembly
    from runtime.io.results import jsonable, load_checkpoint, write_run
    from runtime.model import build
    from runtime.simulate.simulate import simulate

    sens_run = None
    if sensitivities is not None:
        from runtime.problem.parameters import resolve_parameters

        if resume:
            raise ValueError("sensitivities are not kept in checkpoints: a run with them "
                             "cannot resume")
        resolved = resolve_parameters(problem, sensitivities)
    if is_assembly(problem):
        return run_assembly_and_write(problem, out, label, plots=plots, resume=resume,
                                      vtk_every=vtk_every, checkpoint_every=checkpoint_every,
                                      overwrite=overwrite, progress=progress,
                                      sensitivities=sensitivities, sens_errcon=sens_errcon)
    if sensitivities is not None:
        from runtime.simulate.sensitivity import SensitivityRun

        sens_run = SensitivityRun(problem, resolved, sens_errcon)
    out = Path(out)
    params = jsonable(problem.to_mapping())
    wall = checkpoint_wall()
    F.check_output_path(out)
    if not resume:
        F.refuse_existing(out, "simulate", overwrite=overwrite, resumable=True)
    state = load_checkpoint(out, params) if resume else None
    if state is not None:
        from generated import rod_layout

        # the state holds the internal strains of a generalized Maxwell rod's relaxation
        # terms too (as many as runtime.problem.assemble gives the rod's arrays)
        n = rod_layout.n_state(problem.rod.elements, problem.relaxation_terms())
        _check_resume_state(state, n, out, "problem")
    build.require_generated()
    load_compiled(problem)
    if (state is None and problem.simulation.initial == "static"
            and not (problem.start.clamped or problem.end.clamped)):
        # rigid motions may be free: a static start under loads along them is refused
        # before the folder is touched (the model is built twice only for such rods)
        from runtime.problem.assemble import build_model

        check_statics(build_model(problem))
    model = None

    def frames(resume_from: float | None):
        nonlocal model
        from runtime.io.vtk import VtkSeries
        from runtime.problem.assemble import build_model

        model = build_model(problem)          # one model: the run's and the frames'
        return VtkSeries(out / "vtk", model, resume_from=resume_from)

    def run_it(cb, on_checkpoint, series):
        return simulate(problem, progress=cb, checkpoint=on_checkpoint,
                        checkpoint_every=checkpoint_every, checkpoint_wall=wall,
                        resume=state, snapshot_every=vtk_every,
                        snapshot_sink=series.add if series else None, model=model,
                        sensitivity=sens_run)

    def plot(run) -> None:
        from runtime.io.plots import plot_run

        plot_run(run, out)

    return _run_in_folder(out, params, state, overwrite and not resume, problem, label,
                          progress, sens_run, frames if vtk_every is not None else None,
                          run_it, lambda run, extra: write_run(out, run, extra=extra),
                          plot if plots else None)


def write_sensitivities(out: Path, sens) -> Path:
    """``sensitivities.npz`` of a run or a static result: every channel
    ``"<channel>/<parameter>"``, ``t`` and the ``parameters`` record
    (:meth:`runtime.simulate.sensitivity.Sensitivities.arrays`), atomically."""
    from runtime.io.results import write_npz

    return write_npz(Path(out) / "sensitivities.npz", **sens.arrays())


def run_assembly_and_write(problem, out: Path, label: str, plots: bool = False,
                           resume: bool = False, vtk_every: float | None = None,
                           checkpoint_every: float = 1.0, overwrite: bool = False,
                           progress: ProgressDisplay | None = None,
                           sensitivities: list[str] | None = None,
                           sens_errcon: bool = False) -> tuple:
    """:func:`run_and_write` for an assembly of rods (results: ``runtime.io.
    assembly_results``): the same checks, lock, status, checkpoints and resume."""
    from runtime.io import folder as F
    from runtime.io.assembly_results import write_assembly_run
    from runtime.io.results import (
        jsonable,
        load_checkpoint,
    )
    from runtime.model import build
    from runtime.problem.assemble_system import build_system
    from runtime.simulate.assembly import simulate_assembly

    sens_run = None
    if sensitivities is not None:
        from runtime.problem.parameters import resolve_parameters
        from runtime.simulate.assembly_sensitivity import AssemblySensitivityRun

        if resume:
            raise ValueError("sensitivities are not kept in checkpoints: a run with them "
                             "cannot resume")
        sens_run = AssemblySensitivityRun(problem, resolve_parameters(problem, sensitivities),
                                          sens_errcon)
    out = Path(out)
    params = jsonable(problem.to_mapping())
    wall = checkpoint_wall()
    F.check_output_path(out)
    if not resume:
        F.refuse_existing(out, "simulate", overwrite=overwrite, resumable=True)
    state = load_checkpoint(out, params) if resume else None
    build.require_generated()
    load_compiled(problem)
    amap = build_system(problem)
    if vtk_every is not None:
        from runtime.io.assembly_vtk import check_rod_names

        check_rod_names(amap.rod_names)
    if state is not None:
        _check_resume_state(state, amap.model.n, out, "assembly")
    def frames(resume_from: float | None):
        from runtime.io.assembly_vtk import AssemblyVtk

        return AssemblyVtk(out / "vtk", amap.model, resume_from=resume_from)

    def run_it(cb, on_checkpoint, series):
        return simulate_assembly(problem, progress=cb, checkpoint=on_checkpoint,
                                 checkpoint_every=checkpoint_every, checkpoint_wall=wall,
                                 resume=state, amap=amap,
                                 sensitivity=sens_run, snapshot_every=vtk_every,
                                 snapshot_sink=series.add if series else None)

    def plot(run) -> None:
        from runtime.io.assembly_plots import plot_assembly_run_folder

        plot_assembly_run_folder(out)

    return _run_in_folder(out, params, state, overwrite and not resume, problem, label,
                          progress, sens_run, frames if vtk_every is not None else None,
                          run_it, lambda run, extra: write_assembly_run(out, run, extra=extra),
                          plot if plots else None)


def check_statics(model) -> None:
    """Refuse (:class:`runtime.errors.IllPosedError`) a static problem that has no
    equilibrium to compute as posed: loads along a rigid motion its supports leave free, a
    rod too soft for its loads (``RodStatics.hold_rigid_motions``, in statics at load
    factor 1; nothing is written)."""
    from runtime.model.statics import RodStatics

    with model.statics():
        RodStatics(model).hold_rigid_motions(model.initial_state())


def static_and_write(problem, out: Path, overwrite: bool = False,
                     sensitivities: list[str] | None = None) -> tuple[dict, object, object]:
    """Static equilibrium of ``problem`` under its loads at t = 0- into results folder
    ``out`` (checked and locked like :func:`run_and_write`; a problem statics cannot solve
    as posed is refused before, see :func:`check_statics`): summary.json with the end
    positions (for a rod held at both ends also the largest displacement and where), the
    gauge holding free rigid motions, the load path and Newton iterations; static.npz with
    the state ``y``, node
    ``positions`` (3, N+1) and segment ``frames`` (N, 3, 3; columns d1, d2, d3) of the
    equilibrium and of the ``reference``, the segment ``quaternions`` (4, N), the end
    frames ``start_frame``, ``end_frame`` (3, 3) and, per held end, the support's
    ``start_reaction_force`` / ``_moment`` (N, N m about the node; also in summary.json),
    per obstacle ``obstacle{k}_force`` / ``_moment`` (N, N m about its point, on the rod;
    summary.json's ``obstacles`` also has the smallest gap and the segments in reach);
    problem.toml; with ``sensitivities`` (parameter names, validated before anything is
    written) also ``sensitivities.npz`` (the derivatives of static.npz's ``y`` and
    ``positions`` and of the summary's ``tip`` and ``start``, by the implicit function
    theorem: :func:`runtime.simulate.sensitivity.static_sensitivity_channels`). Returns
    (summary, model, y); a failed solve keeps its last converged state (status
    "failed") and writes no sensitivities."""
    import time

    import numpy as np

    from runtime.io.assembly_results import is_assembly, static_assembly_and_write
    from runtime.io.folder import RUN_FILES, results_folder
    from runtime.io.results import jsonable, write_json, write_npz, write_problem
    from runtime.model import build
    from runtime.model.statics import largest_displacement
    from runtime.problem.assemble import build_model
    from runtime.simulate.simulate import (
        load_path_table,
        static_equilibrium,
        static_obstacle_summary,
    )
    from runtime.solvers.statics import StaticSolveError

    sens_run = None
    if sensitivities is not None:
        from runtime.problem.parameters import resolve_parameters

        resolved = resolve_parameters(problem, sensitivities)
    build.require_generated()
    load_compiled(problem)              # before the clock of either kind of statics
    if is_assembly(problem):
        return static_assembly_and_write(problem, out, overwrite=overwrite,
                                         sensitivities=sensitivities)
    wall0 = time.perf_counter()
    model = build_model(problem)
    check_statics(model)            # an ill-posed problem is refused before the folder
    if sensitivities is not None:
        from runtime.simulate.sensitivity import SensitivityRun

        sens_run = SensitivityRun(problem, resolved)
        sens_run.prepare(model)
    with results_folder(out, "static", markers=("summary.json",), overwrite=overwrite,
                        names=RUN_FILES):   # a run's files too: the same marker
        params = jsonable(problem.to_mapping())
        gauge = None
        try:
            st = static_equilibrium(problem, model)
            status, message, y, its, per = "finished", "ok", st.y, st.iterations, st.per_step
            path, gauge = st.path_table(), st.gauge
        except StaticSolveError as exc:
            status, message, y, its, per = ("failed", f"static solve failed: {exc}", exc.y,
                                            sum(exc.iterations), list(exc.iterations))
            path = load_path_table(getattr(exc, "path", []))
        pos = model.positions(y)
        with model.statics():
            reactions = model.reactions(0.0, y)
            ends = model.end_frames(0.0, y)
            contact = model.contact_values(0.0, y)
        both_held = problem.start.held and problem.end.held
        summary = {"status": status, "message": message, "problem": problem.name,
                   "parameters": params,
                   "static": {"tip": pos[:, -1].tolist(), "start": pos[:, 0].tolist(),
                              "largest_displacement": (largest_displacement(model, y)
                                                       if both_held else None),
                              "gauge": gauge,
                              "reactions": {end: {w: v.tolist() for w, v in r.items()}
                                            for end, r in reactions.items()},
                              "newton_iterations": int(its),
                              "newton_iterations_per_load_step": per,
                              "path": path,
                              "wall_time_s": time.perf_counter() - wall0},
                   **({"obstacles": static_obstacle_summary(problem.obstacles, contact)}
                      if problem.obstacles else {}),
                   "backend": model.backend}
        extra = {f"{end}_frame": f for end, f in ends.items()}
        for k, o in enumerate(summary.get("obstacles", ())):
            extra.update({f"obstacle{k}_{w}": np.array(o[w]) for w in ("force", "moment")})
        for end, r in reactions.items():
            extra.update({f"{end}_reaction_{w}": v for w, v in r.items()})
        write_npz(out / "static.npz", y=y, positions=pos, quaternions=model.quaternions(y),
                  frames=model.frames(y), reference=model.positions(model.reference),
                  reference_frames=model.frames(model.reference), **extra)
        if sens_run is not None and status == "finished":
            from runtime.simulate.sensitivity import static_sensitivity_channels

            sens = static_sensitivity_channels(model, y, sens_run)
            write_sensitivities(out, sens)
            summary["sensitivities"] = sens.summary()
        write_problem(out / "problem.toml", params)
        write_json(out / "summary.json", summary)
    return summary, model, y
