"""Observers of the run driver for :func:`runtime.solvers.integrator.solve`: outputs on a
grid or at every step, events located on the steps' interpolants, the dense solution,
progress (see :class:`runtime.solvers.driver.Observer` for the hooks)."""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np

from runtime.solvers.dense import BDFDenseOutput
from runtime.solvers.roots import bracketed_root


class OutputGrid:
    """y and y' at the times ``t_eval`` (sorted in the direction of integration), in
    preallocated (m, n) arrays.

    With the compiled step loop the outputs are interpolated there, after each step that
    reaches them (``attach``: ``CoreLink.enable_grid``, the same interpolant and
    arithmetic as ``BDFDenseOutput.values``), so the loop does not return at each; with
    ``in_loop=False`` (a progress callback that expects to be called at the outputs), or
    without the compiled loop, the driver stops at each (``next_time``) and they are
    interpolated here."""

    sparse = True

    def __init__(self, t_eval: np.ndarray, n: int, direction: float,
                 in_loop: bool = True) -> None:
        self.t_eval = np.asarray(t_eval, dtype=float)
        self.direction = direction
        self.y = np.empty((self.t_eval.size, n))
        self.yp = np.empty((self.t_eval.size, n))
        self.k = 0
        self.in_loop = in_loop
        self._core = None

    def attach(self, solver) -> bool:
        """Interpolate the outputs in the compiled loop (with ``in_loop``); True: the
        driver need not call ``step`` after every step either way."""
        core = getattr(solver, "core", None)
        if self._core is None and self.in_loop and core is not None:
            core.enable_grid(self.t_eval, self.k, self.y, self.yp)
            self._core = core
        return True

    def begin(self, run) -> None:
        # an output at t0 itself comes from the initial values
        while self.k < self.t_eval.size and self.t_eval[self.k] == run.t:
            self.y[self.k], self.yp[self.k] = run.y, run.yp
            self.k += 1

    def next_time(self) -> float:
        if self.k < self.t_eval.size and self._core is None:
            return float(self.t_eval[self.k])
        return math.inf if self.direction > 0 else -math.inf

    def step(self, run, dense: BDFDenseOutput, t0: float, t1: float) -> None:
        t_stop = run.stop_at if run.stop_at is not None else t1
        if self._core is not None:     # filled in the loop, up to the last step
            self.k = self._core.grid_done
            while self.k > 0 and self.direction * (self.t_eval[self.k - 1] - t_stop) > 0:
                self.k -= 1            # past a terminal event's time: not reached
        j0 = self.k
        while (self.k < self.t_eval.size
               and self.direction * (self.t_eval[self.k] - t_stop) <= 0):
            self.k += 1
        if self.k > j0:
            dense.values(self.t_eval[j0:self.k], self.y[j0:self.k], self.yp[j0:self.k])

    def arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(t (m,), y (n, m), y' (n, m)) of the outputs reached."""
        return self.t_eval[:self.k].copy(), self.y[:self.k].T, self.yp[:self.k].T


class StepOutputs:
    """y and y' at every accepted step (and at the start; at a terminal event's time
    instead of the step's end)."""

    def __init__(self) -> None:
        self.t: list[float] = []
        self.y: list[np.ndarray] = []
        self.yp: list[np.ndarray] = []

    def begin(self, run) -> None:
        self.t.append(run.t)
        self.y.append(np.array(run.y, dtype=float))
        self.yp.append(np.array(run.yp, dtype=float))

    def step(self, run, dense: BDFDenseOutput, t0: float, t1: float) -> None:
        if run.stop_at is not None:
            self.t.append(run.stop_at)
            self.y.append(dense(run.stop_at))
            self.yp.append(dense.derivative(run.stop_at))
        else:
            self.t.append(t1)
            self.y.append(run.y.copy())
            self.yp.append(run.yp.copy())

    def arrays(self, n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        y = np.array(self.y).T if self.y else np.empty((n, 0))
        yp = np.array(self.yp).T if self.yp else np.empty((n, 0))
        return np.asarray(self.t), y, yp


class DenseSolution:
    """Every step's interpolant (for ``BDFSolution``)."""

    def __init__(self) -> None:
        self.ts: list[float] = []
        self.interpolants: list[BDFDenseOutput] = []

    def begin(self, run) -> None:
        self.ts.append(run.t)

    def step(self, run, dense: BDFDenseOutput, t0: float, t1: float) -> None:
        self.interpolants.append(run.solver.dense_output())     # a copy: it is kept
        self.ts.append(t1)


def event_attributes(events: Sequence[Callable]) -> tuple[np.ndarray, np.ndarray]:
    """(terminal counts, directions) of event functions (``solve_ivp``'s attributes)."""
    terminal = np.array([int(getattr(ev, "terminal", False)) for ev in events], dtype=int)
    direction = np.array([float(getattr(ev, "direction", 0.0)) for ev in events])
    return terminal, direction


class Events:
    """Roots of ``g(t, y, y')`` located on each step's interpolant to round-off (as in
    ``solve_ivp``: attributes ``terminal`` (bool or count) and ``direction``); an exact
    zero of g at t0 is not an event (as in IDA). A terminal event stops the run there
    (``run.stop_at``)."""

    def __init__(self, events: Sequence[Callable], direction: float) -> None:
        self.events = list(events)
        terminal, self.ev_dir = event_attributes(self.events)
        self.max_count = np.where(terminal > 0, terminal, np.inf)
        self.count = np.zeros(len(self.events))
        self.direction = direction
        self.t: list[list[float]] = [[] for _ in self.events]
        self.y: list[list[np.ndarray]] = [[] for _ in self.events]
        self.yp: list[list[np.ndarray]] = [[] for _ in self.events]
        self.g = np.zeros(len(self.events))
        self.t0 = math.nan

    def _values(self, t: float, y: np.ndarray, yp: np.ndarray) -> np.ndarray:
        return np.array([float(ev(t, y, yp)) for ev in self.events])

    def begin(self, run) -> None:
        self.t0 = run.t
        self.g = self._values(run.t, run.y, run.yp)

    def step(self, run, dense: BDFDenseOutput, t0: float, t1: float) -> None:
        g_new = self._values(t1, run.y, run.yp)
        up = (self.g <= 0) & (g_new >= 0)
        down = (self.g >= 0) & (g_new <= 0)
        d = self.ev_dir
        active = np.flatnonzero(up & (d > 0) | down & (d < 0) | (up | down) & (d == 0))
        if t0 == self.t0:       # an exact zero at t0 (a velocity event at rest) is none
            active = active[self.g[active] != 0.0]
        if active.size:
            interp = run.solver.dense_output()
            roots = np.array([locate_root(lambda s, ev=self.events[i]: float(
                ev(s, interp(s), interp.derivative(s))), t0, t1, self.g[i], g_new[i])
                for i in active])
            order = np.argsort(self.direction * roots)
            for i, r in zip(active[order], roots[order], strict=True):
                self.count[i] += 1
                self.t[i].append(r)
                self.y[i].append(interp(r))
                self.yp[i].append(interp.derivative(r))
                if self.count[i] >= self.max_count[i]:
                    run.stop_at = r
                    break
        self.g = g_new

    def arrays(self, n: int):
        """Per event: times (k,), states (k, n), rates (k, n)."""
        return ([np.asarray(t) for t in self.t],
                [np.asarray(y).reshape(-1, n) for y in self.y],
                [np.asarray(y).reshape(-1, n) for y in self.yp])


class ProgressCallback:
    """``callback(t)`` after every step the driver stops at (every step without the
    compiled loop; else at the outputs)."""

    sparse = True

    def __init__(self, callback: Callable[[float], object]) -> None:
        self.callback = callback

    def step(self, run, dense, t0: float, t1: float) -> None:
        self.callback(run.stop_at if run.stop_at is not None else t1)


def locate_root(gi: Callable[[float], float], a: float, b: float, ga: float,
                gb: float) -> float:
    """Root of ``gi`` in [a, b] given the sign change ga -> gb (to round-off)."""
    if ga == 0.0:
        return a
    if gb == 0.0:
        return b
    lo, hi = (a, b) if a < b else (b, a)
    xtol = 4.0 * np.finfo(float).eps * max(abs(lo), abs(hi), 1e-300)
    # re-evaluate at the ends on the interpolant so the root finder sees a consistent
    # bracket
    glo, ghi = gi(lo), gi(hi)
    if glo == 0.0:
        return lo
    if ghi == 0.0:
        return hi
    if math.copysign(1.0, glo) == math.copysign(1.0, ghi):
        # the interpolant misses the sign change at round-off level: the end with |g| min
        return lo if abs(glo) < abs(ghi) else hi
    return bracketed_root(gi, lo, hi, glo, ghi, xtol=xtol)
