"""The one run driver: the integrator's steps with observers, breakpoints, checkpoints.

:func:`run_loop` integrates any ``ResidualProblem`` (``runtime/solvers/protocols.py``) from
consistent initial values with the variable-order BDF of :mod:`runtime.solvers.bdf`,
piece by piece between the breakpoints of its inputs (:mod:`runtime.solvers.schedule`),
and calls its observers (:class:`Observer`) on the way; it hands a checkpoint (the
solver's state plus every observer's ``state()``) to ``checkpoint`` every
``checkpoint_every`` simulated seconds. It never raises for a solver failure or an
interruption: the returned :class:`LoopResult` says ``finished``, ``stopped`` (an
observer asked for it: a terminal event), ``failed`` or ``interrupted``, why, and keeps
the last accepted state; the observers keep everything up to it.

Both ways of running a problem go through it: ``runtime.simulate.simulate`` (the rod's
observers: energy audit, output samples, maxima, snapshots, checkpoints) and
:func:`runtime.solvers.integrator.solve` (output grids, events, the dense solution:
``runtime/solvers/observers.py``).

With the compiled step loop (``runtime/solvers/native/step_loop.c``) the driver lets C
run between the times Python must see something: an observer that does not need every
step says so (``sparse = True``) and tells the driver when it must be called
(``next_time``, ``watches``) or moves its per-step work into the compiled loop
(``attach``).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np

from runtime.errors import INTERRUPTS, ParameterError
from runtime.solvers.bdf import BDF, IntegrationError
from runtime.solvers.dense import BDFDenseOutput
from runtime.solvers.schedule import Pieces, Restart


@dataclass
class RunState:
    """What observers see of the run in progress: last accepted t, y, y' and the solver;
    an observer sets ``stop_at`` (a time inside the last step) to end the run there."""

    t: float
    y: np.ndarray
    yp: np.ndarray
    solver: BDF | None = None
    stop_at: float | None = None
    #: the forward sensitivities at t, (k, n) (None without them)
    s: np.ndarray | None = None


class Observer(Protocol):
    """What the driver calls; every hook and attribute is optional (the driver looks for
    each with ``hasattr``), so an observer implements what it needs:

    * ``begin(run)``: the run starts (``run.t``, ``run.y``, ``run.yp``: initial values);
    * ``step(run, dense, t0, t1)``: a step ``[t0, t1]`` was accepted; ``dense(t)``,
      ``dense.derivative(t)`` and ``dense.values(ts)`` interpolate y and y' on it;
    * ``restart(run, restart)``: the integrator restarted at a breakpoint of the inputs
      (:class:`~runtime.solvers.schedule.Restart`);
    * ``end(run)``: the run stopped (finished, stopped, failed or interrupted);
    * ``state() -> dict`` / ``restore(dict)``: what a checkpoint keeps;
    * ``sparse = True``: ``step`` need not see every step, only those the driver stops
      at (it may be called for any step);
    * ``attach(solver) -> bool``: move the per-step work into the compiled loop (False:
      be called after every step);
    * ``next_time() -> float``: the driver stops at the step that reaches this time;
    * ``watches() -> [(index, direction)]``: it stops at a step in which ``y[index]``
      changes sign in ``direction`` (< 0: downwards);
    * ``ticks``: stop at least this many times in the run (a progress bar);
    * ``replay_times(t_end) -> array``: with the compiled loop, instead of stopping at
      each of these times (sorted in the direction of integration) the steps reaching
      them are kept and ``step`` is called for them later, in order (when the compiled
      loop's buffer is full and at every stop, before the stop's own calls), on a copy
      of their interpolant: its ``step`` must then use ``dense``, ``t0``, ``t1`` only
      (``run`` is the state of the stop);
    * ``into_core(solver) -> bool``: an observer with ``replay_times`` may take its
      times inside the compiled loop instead (True: no steps are kept for it).

    Observers are called in the order given, so one may use the results of earlier
    ones.
    """

    def begin(self, run: RunState) -> None: ...

    def step(self, run: RunState, dense: BDFDenseOutput, t0: float, t1: float) -> None: ...

    def restart(self, run: RunState, restart: Restart) -> None: ...

    def end(self, run: RunState) -> None: ...

    def state(self) -> dict[str, Any]: ...

    def restore(self, state: dict[str, Any]) -> None: ...


@dataclass
class LoopResult:
    """Outcome of :func:`run_loop`.

    status: "finished", "stopped", "failed" or "interrupted"; message: why; t_last,
    y_last: the last accepted point (or where an observer stopped the run); counters:
    solver counters (including those before a resume); wall_time_s: time spent in the
    loop; interrupt: the exception that interrupted the run (re-raised by the caller
    after saving the results); error: the integrator's failure, if it failed.
    """

    status: str
    message: str
    t_last: float
    y_last: np.ndarray
    yp_last: np.ndarray
    counters: dict[str, int] = field(default_factory=dict)
    wall_time_s: float = 0.0
    interrupt: BaseException | None = None
    error: IntegrationError | None = None


#: most steps per call of the compiled loop where a signal is seen only between calls
#: (~0.05 s at N = 50); a loop that stops on signals itself runs to its stop (a return to
#: Python costs ~0.5 ms: two in the 10 s cantilever, fifty in the pendulum)
_CHUNK = 1000


def _needs_every_step(solver: BDF, observers: Sequence[Any]) -> bool:
    """Whether some observer must see every step: always without the compiled loop; else
    an observer that is not ``sparse`` or cannot ``attach`` its per-step work to it."""
    if not solver.compiled:
        return True
    for o in observers:
        if not hasattr(o, "step"):
            continue
        if not getattr(o, "sparse", False):
            return True
        if hasattr(o, "attach") and not o.attach(solver):
            return True
    return False


def _replay(solver: BDF, run: RunState, observers: Sequence[Any], t_end: float
            ) -> Callable[[], None]:
    """Let the compiled loop keep the steps that the ``observers`` need at their
    ``replay_times`` (merged) and call their ``step`` on them; returns the flush to call
    at every stop."""
    times = np.concatenate([np.asarray(o.replay_times(t_end), dtype=float)
                            for o in observers])
    times = np.sort(times) if solver.direction > 0 else -np.sort(-times)
    hooks = [o.step for o in observers]

    def replay(t0: float, t1: float, k: int, psi: np.ndarray, phi: np.ndarray,
               sphi: np.ndarray | None = None, *, y: np.ndarray) -> None:
        dense = BDFDenseOutput(t0, t1, phi, psi, solver._c)
        if sphi is not None:
            dense.sens = BDFDenseOutput(t0, t1, sphi, psi, solver._c)
        # the run as it stood after that step: its y (the loop's, bit for bit), y' and
        # sensitivities from the step's interpolant
        at = RunState(t=t1, y=np.array(y), yp=dense.derivative(t1), solver=solver,
                      s=None if sphi is None else dense.sens(t1))
        for f in hooks:
            f(at, dense, t0, t1)

    core = solver.core
    core.enable_replay(times, replay)
    return core.flush_replay


def describe_failure(exc: IntegrationError, describe_dof: Callable[[int], str]) -> str:
    """One message naming time, step size, residual norm and the worst component."""
    return (f"integration failed at t = {exc.t:.6g} s (last accepted step), step size "
            f"{exc.h:.3g} s, residual norm {exc.residual_norm:.3g}, worst component: "
            f"{describe_dof(exc.worst_index)}: {exc}")


def _cadence_point(first: float, at_least: float, every: float, direction: float) -> float:
    """The first point ``first + k every`` (k >= 0; backwards in time for direction -1)
    at or past ``at_least``."""
    gap = direction * (at_least - first)
    if not gap > 0.0:
        return first
    return first + direction * every * math.ceil(gap / every)


def run_loop(model, t0: float, y0: np.ndarray, yp0: np.ndarray, t_end: float, *,
             rtol: float, atol: float | np.ndarray, observers: Sequence[Any] = (),
             min_step: float = 0.0, max_order: int = 5, max_steps: int = 2_000_000,
             checkpoint: Callable[[dict[str, Any]], object] | None = None,
             checkpoint_every: float = 1.0, checkpoint_wall: float = 0.0,
             counters0: dict[str, int] | None = None,
             describe_dof: Callable[[int], str] = lambda i: f"state index {i}",
             restored: bool = False, solver_options: dict[str, Any] | None = None
             ) -> LoopResult:
    """Integrate ``model`` from ``(t0, y0, yp0)`` to ``t_end`` with observers.

    The run goes piece by piece between the breakpoints of the model's inputs
    (``runtime.solvers.schedule``): the solver lands on each and restarts where an input
    jumps; observers with a ``restart(run, restart)`` hook are told.

    ``checkpoint_wall``: a checkpoint is taken at a point of the ``checkpoint_every``
    cadence only when at least this many seconds of wall time have passed since the
    previous one, the first since the loop started (0: at every point), so that
    checkpoints cost a bounded share of a run however fast it goes, and a run that ends
    within that time writes none (running it again costs less than its checkpoint); the
    loop does not even stop at points that its pace so far says come too early (then a
    checkpoint may fall after the point, at the loop's next stop, and the cadence goes on
    from there).
    ``restored``: the observers were restored from a checkpoint at ``t0`` (their ``begin``
    must not record the start again; they are called with it anyway so that they can pick
    up the state). ``counters0``: counters of the run before the resume.
    ``solver_options``: further keyword arguments of :class:`~runtime.solvers.bdf.BDF`
    (``max_step`` is combined with the pieces' own bounds). See the module docstring for
    checkpoints and failures.
    """
    if checkpoint is not None:
        if not (checkpoint_every > 0 and math.isfinite(checkpoint_every)):
            raise ParameterError("checkpoint_every", checkpoint_every,
                                 "simulated seconds > 0 (finite)")
        if not (checkpoint_wall >= 0 and math.isfinite(checkpoint_wall)):
            raise ParameterError("checkpoint_wall", checkpoint_wall,
                                 "seconds of wall time >= 0 (finite)")
    wall0 = time.perf_counter()
    counters0 = dict(counters0 or {})
    options = dict(solver_options or {})
    user_max_step = float(options.pop("max_step", math.inf))
    pieces = Pieces(model, t0, t_end)
    solver = BDF(model, t0, y0, yp0, pieces.end, rtol=rtol, atol=atol, min_step=min_step,
                 max_order=max_order, max_step=min(pieces.enter(), user_max_step),
                 **options)
    run = RunState(t=t0, y=np.array(y0, dtype=float), yp=np.array(yp0, dtype=float),
                   solver=solver, s=None if solver.sensitivities is None
                   else solver.sensitivities.copy())
    hooks = {name: [getattr(o, name) for o in observers if hasattr(o, name)]
             for name in ("begin", "step", "restart", "end")}
    for f in hooks["begin"]:
        f(run)
    direction = 1.0 if t_end >= t0 else -1.0
    next_ckpt = t0 + checkpoint_every * direction
    loop_wall0 = time.perf_counter()
    # wall time (perf_counter) of the previous checkpoint; the loop's start stands for it
    # when checkpoints keep a wall-time distance: the first, too, comes only after that
    # much of the run
    last_ckpt = loop_wall0 if checkpoint_wall > 0.0 else -math.inf

    def checkpoint_time() -> float:
        """The point of the checkpoint cadence the compiled loop must stop at next: the
        next one (``next_ckpt``) while the run has no pace yet or checkpoints keep no
        wall-time distance, else the first one that, at the run's pace so far, comes
        ``checkpoint_wall`` after the previous checkpoint (or the loop's start), where a
        checkpoint is due. The points before it would be skipped anyway, and a stop costs
        a return to Python (~0.3 ms at N = 50); stopping only at ``next_ckpt`` (as this
        did) let a fast run pass it and go on to its end without a checkpoint. A stop
        changes no step (the loop completes the step that passes it); where the pace
        changes, the checkpoint comes at a later stop."""
        if checkpoint_wall <= 0.0:
            return next_ckpt
        now, done = time.perf_counter(), abs(solver.t - t0)
        if done <= 0.0 or now <= loop_wall0:
            return next_ckpt
        pace = (now - loop_wall0) / done            # wall seconds per simulated second
        ahead = max(0.0, last_ckpt + checkpoint_wall - now) / pace   # simulated seconds
        return _cadence_point(next_ckpt, solver.t + direction * ahead, checkpoint_every,
                              direction)

    every_step = _needs_every_step(solver, observers)
    timed = [o for o in observers if hasattr(o, "next_time")]
    flush_replay = None
    replayed: list = []
    if not every_step:
        # observers that can take their times inside the compiled loop (into_core) need
        # no replayed steps
        replayed = [o for o in observers if hasattr(o, "replay_times")
                    and not (hasattr(o, "into_core") and o.into_core(solver))]
        if replayed:
            flush_replay = _replay(solver, run, replayed, t_end)
            timed = [o for o in timed if o not in replayed]
    # a replayed observer's watches (replay_watches: the maxima) keep their steps for the
    # replay instead of stopping the compiled loop
    watched = [(w, o in replayed and getattr(o, "replay_watches", False))
               for o in observers if hasattr(o, "watches") for w in o.watches()]
    watches, kept = [w for w, _ in watched], [k for _, k in watched]
    if not every_step:
        solver.watch(watches, kept)
    tick = abs(t_end - t0) / max([getattr(o, "ticks", 1) for o in observers], default=1)
    prompt = solver.core is not None and solver.core.stops_on_signals

    def total_counters() -> dict[str, int]:
        return {k: counters0.get(k, 0) + v for k, v in solver.counters.items()}

    def result(status: str, message: str, interrupt: BaseException | None = None,
               error: IntegrationError | None = None) -> LoopResult:
        if flush_replay is not None:
            flush_replay()
        for f in hooks["end"]:
            f(run)
        return LoopResult(status=status, message=message, t_last=float(run.t),
                          y_last=np.array(run.y, copy=True), yp_last=np.array(run.yp),
                          counters=total_counters(), wall_time_s=time.perf_counter() - wall0,
                          interrupt=interrupt, error=error)

    try:
        while solver.nstep < max_steps:
            if solver.status == "finished":
                if pieces.last:
                    break
                restart = pieces.next(solver)      # past the inputs' next breakpoint
                solver.set_max_step(min(solver.max_step, user_max_step))
                run.t, run.y, run.yp = solver.t, solver.y, solver.yp
                run.s = solver.sensitivities
                if restart is not None:
                    for f in hooks["restart"]:
                        f(run, restart)
                    if not every_step:
                        solver.watch(watches, kept)
                continue
            if every_step:
                solver.step()
            else:
                # let the compiled loop run to the next time someone needs to see
                stops = ([t_end, solver.t + direction * tick]
                         + [o.next_time() for o in timed]
                         + ([checkpoint_time()] if checkpoint is not None else []))
                t_stop = min(stops) if direction > 0 else max(stops)
                solver.advance(t_stop, max_steps - solver.nstep if prompt
                               else min(max_steps - solver.nstep, _CHUNK))
            t_old, t1 = solver.t_old, solver.t
            if not np.all(np.isfinite(solver.y)):
                dense = solver.dense_output()
                raise IntegrationError(f"non-finite state at t = {t1:g} s", t=t_old,
                                       y=dense(t_old), yp=dense.derivative(t_old),
                                       h=t1 - t_old, residual_norm=math.inf,
                                       worst_index=int(np.argmin(np.isfinite(solver.y))))
            dense = solver.dense_output(copy=False)   # used by the observers right away
            run.t, run.y, run.yp = t1, solver.y, solver.yp
            run.s = solver.sensitivities
            if flush_replay is not None:
                flush_replay()
            for f in hooks["step"]:
                f(run, dense, t_old, t1)
            if run.stop_at is not None:         # an observer ended the run (an event)
                run.t = run.stop_at
                run.y, run.yp = dense(run.stop_at), dense.derivative(run.stop_at)
                return result("stopped", "A termination event occurred.")
            if checkpoint is not None and direction * (t1 - next_ckpt) >= 0 \
                    and direction * (t_end - t1) > 0:
                if time.perf_counter() - last_ckpt >= checkpoint_wall:
                    state: dict[str, Any] = {"t": float(t1), "y": solver.y.copy(),
                                             "yp": solver.yp.copy(),
                                             "counters": total_counters()}
                    for o in observers:
                        if hasattr(o, "state"):
                            state.update(o.state())
                    checkpoint(state)
                    last_ckpt = time.perf_counter()
                next_ckpt = t1 + direction * checkpoint_every
    except IntegrationError as exc:
        run.t, run.y, run.yp = float(exc.t), np.array(exc.y), np.array(exc.yp)
        return result("failed", describe_failure(exc, describe_dof), error=exc)
    except INTERRUPTS as exc:
        return result("interrupted", f"interrupted at t = {run.t:.6g} s "
                      f"({type(exc).__name__}); --resume continues from the last checkpoint",
                      interrupt=exc)
    if solver.status == "finished":
        return result("finished", "ok")
    return result("failed", f"stopped after max_steps = {max_steps} steps at "
                            f"t = {solver.t:g} s")
