"""Driver for the BDF solver: ``solve`` (outputs, dense solution, events) and
``consistent_initial`` (IDA's ``IDA_YA_YDP_INIT``).

The stepping itself lives in :mod:`runtime.solvers.bdf`; this module re-exports its public
names.

Example (``rod`` implements ``runtime.solvers.protocols.ResidualProblem``)::

    y0, yp0 = consistent_initial(rod, 0.0, y_static, np.zeros(rod.n))
    def tip_vx(t, y, yp):  # maxima of the tip x: its velocity crosses zero downwards
        return y[i_vx]
    tip_vx.direction = -1.0
    res = solve(rod, (0.0, 10.0), y0, yp0, rtol=1e-6, atol=1e-8,
                t_eval=np.linspace(0, 10, 2001), events=tip_vx, progress=bar.update_to)
    res.t_events[0], res.counters["nlu"]
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from runtime.solvers.protocols import ResidualProblem
from runtime.solvers.roots import bracketed_root

from .bdf import BDF, BDFDenseOutput, IntegrationError
from .initial import consistent_initial
from .schedule import Pieces

__all__ = [
    "BDF",
    "BDFDenseOutput",
    "BDFSolution",
    "IntegrationError",
    "SolveResult",
    "consistent_initial",
    "solve",
]


class BDFSolution:
    """Piecewise BDF interpolant over a whole run (like ``scipy``'s ``OdeSolution``).

    ``sol(t)`` gives y with shape (n,) for scalar ``t`` or (n, m) for an array of times;
    ``sol.derivative(t)`` gives y'.  Times outside the run are extrapolated from the
    first/last step.
    """

    def __init__(self, ts: Sequence[float], interpolants: Sequence[BDFDenseOutput]) -> None:
        self.ts = np.asarray(ts, dtype=float)  # step ends, including t0 first
        self.interpolants = list(interpolants)
        self.t_min = float(min(self.ts[0], self.ts[-1]))
        self.t_max = float(max(self.ts[0], self.ts[-1]))
        self._ascending = self.ts[-1] >= self.ts[0]

    def _segments(self, t: np.ndarray) -> np.ndarray:
        ts = self.ts if self._ascending else self.ts[::-1]
        idx = np.searchsorted(ts, t, side="left") - 1
        idx = np.clip(idx, 0, len(self.interpolants) - 1)
        return idx if self._ascending else len(self.interpolants) - 1 - idx

    def _eval(self, t: float | np.ndarray, deriv: bool) -> np.ndarray:
        ta = np.atleast_1d(np.asarray(t, dtype=float))
        seg = self._segments(ta)
        n = self.interpolants[0]._phi.shape[1]
        out = np.empty((n, ta.size))
        for s in np.unique(seg):
            mask = seg == s
            f = self.interpolants[s]
            out[:, mask] = f.derivative(ta[mask]) if deriv else f(ta[mask])
        return out[:, 0] if np.ndim(t) == 0 else out

    def __call__(self, t: float | np.ndarray) -> np.ndarray:
        return self._eval(t, False)

    def derivative(self, t: float | np.ndarray) -> np.ndarray:
        return self._eval(t, True)


@dataclass
class SolveResult:
    """Output of :func:`solve`.

    Attributes
    ----------
    t : ndarray
        (m,) output times.
    y, yp : ndarray
        (n, m) states and derivatives there.
    sol : BDFSolution or None
        The dense solution over the run if ``dense_output`` was requested.
    t_events : list of ndarray or None
        Per event, the event times; ``y_events``, ``yp_events``: per event, arrays of
        shape (k, n).
    status : int
        0 reached the end, 1 stopped at a terminal event, -1 failed.
    error : IntegrationError or None
        The exception on failure (its state is the last good one).
    counters : dict
        Solver counters (nstep, nfev, njev, nlu, nni, netf, ncfn).
    """

    t: np.ndarray
    y: np.ndarray
    yp: np.ndarray
    sol: BDFSolution | None
    t_events: list[np.ndarray] | None
    y_events: list[np.ndarray] | None
    yp_events: list[np.ndarray] | None
    status: int
    message: str
    counters: dict[str, int] = field(default_factory=dict)
    error: IntegrationError | None = None

    @property
    def success(self) -> bool:
        return self.status >= 0


def _event_attrs(events: Sequence[Callable[..., float]]) -> tuple[np.ndarray, np.ndarray]:
    terminal = np.array([int(getattr(e, "terminal", False)) for e in events], dtype=int)
    direction = np.array([float(getattr(e, "direction", 0.0)) for e in events])
    return terminal, direction


def _eval_events(events: Sequence[Callable[..., float]], t: float, y, yp) -> np.ndarray:
    return np.array([float(e(t, y, yp)) for e in events])


def _find_active(g_old: np.ndarray, g_new: np.ndarray, direction: np.ndarray) -> np.ndarray:
    up = (g_old <= 0) & (g_new >= 0)
    down = (g_old >= 0) & (g_new <= 0)
    either = up | down
    mask = up & (direction > 0) | down & (direction < 0) | either & (direction == 0)
    return np.nonzero(mask)[0]


def solve(
    problem: ResidualProblem,
    t_span: tuple[float, float],
    y0: np.ndarray,
    yp0: np.ndarray | None = None,
    *,
    rtol: float = 1e-6,
    atol: float | np.ndarray = 1e-8,
    t_eval: np.ndarray | None = None,
    events: Callable[..., float] | Sequence[Callable[..., float]] | None = None,
    dense_output: bool = False,
    progress: Callable[[float], Any] | None = None,
    max_steps: int = 1_000_000,
    **options: Any,
) -> SolveResult:
    """Integrate ``F(t, y, y') = 0`` over ``t_span`` with :class:`~runtime.solvers.bdf.BDF`.

    Parameters
    ----------
    problem : ResidualProblem
        The residual, its Jacobian and their layout.
    t_span : tuple of float
        ``(t0, t_end)`` in s.
    y0, yp0 : ndarray
        Initial values; if ``yp0`` is None, a consistent ``(y0, yp0)`` is computed by
        :func:`consistent_initial` from ``y' = 0``.
    rtol, atol : float or ndarray
        Tolerances (see :class:`~runtime.solvers.bdf.BDF`).
    t_eval : ndarray, optional
        Output times, sorted in the direction of integration; default: every step.
    events : callable or sequence of callables, optional
        ``g(t, y, yp) -> float`` with optional attributes ``terminal`` (bool or count)
        and ``direction`` (as in ``solve_ivp``); roots are located on the step's
        interpolant to round-off (``runtime.solvers.roots.bracketed_root``). An exact
        zero of ``g`` at ``t0`` is not reported (as in IDA).
    dense_output : bool
        Keep every step's interpolant and return ``sol``.
    progress : callable, optional
        Called as ``progress(t)`` after every accepted step, or only at output times
        when the compiled loop integrates between them (e.g. a progress bar).
    max_steps : int
        Give up (status -1) after this many steps.
    **options
        Passed to :class:`~runtime.solvers.bdf.BDF` (``max_order``, ``max_step``,
        ``first_step``, ``suppress_alg``, ``fixed_step``, ...).

    The solver stops at every breakpoint of the problem's inputs and restarts where one
    jumps (``runtime.solvers.schedule``: a pulse or a fast end motion is never stepped
    over); steps are bounded by the active inputs' time scales.

    Returns
    -------
    SolveResult
        Failures of the integrator do not raise here: the result has ``status = -1``,
        the outputs computed so far, and the exception in ``error``.
    """
    t0, tf = float(t_span[0]), float(t_span[1])
    y0 = np.asarray(y0, dtype=float)
    pieces = Pieces(problem, t0, tf) if tf >= t0 else None
    if pieces is not None:
        h_piece = pieces.enter()
        if math.isfinite(h_piece):
            options = {**options, "max_step": min(h_piece, options.get("max_step", math.inf))}
    if yp0 is None:
        y0, yp0 = consistent_initial(problem, t0, y0, np.zeros_like(y0))
    solver = BDF(problem, t0, y0, yp0, pieces.end if pieces is not None else tf, rtol=rtol,
                 atol=atol, **options)
    direction = solver.direction
    user_max_step = float(options.get("max_step", math.inf))

    if t_eval is not None:
        t_eval = np.asarray(t_eval, dtype=float)
        if t_eval.ndim != 1:
            raise ValueError(f"t_eval must be 1-D, got shape {t_eval.shape}")
        lo, hi = min(t0, tf), max(t0, tf)
        if np.any(t_eval < lo) or np.any(t_eval > hi):
            raise ValueError(f"t_eval values must lie within t_span = {t_span}")
        d = np.diff(t_eval)
        if (direction > 0 and np.any(d <= 0)) or (direction < 0 and np.any(d >= 0)):
            raise ValueError("t_eval must be strictly monotonic in the direction of t_span")
        t_eval_i = 0
        # Outputs go straight into preallocated (m, n) arrays (returned transposed):
        # no per-output arrays, no final stacking copy.
        y_rows = np.empty((t_eval.size, y0.size))
        yp_rows = np.empty((t_eval.size, y0.size))
        # An output at t0 itself comes from the initial values.
        while t_eval_i < t_eval.size and t_eval[t_eval_i] == t0:
            y_rows[t_eval_i] = y0
            yp_rows[t_eval_i] = yp0
            t_eval_i += 1
    else:
        ts_out = [t0]
        ys_out = [y0.copy()]
        yps_out = [np.asarray(yp0, dtype=float).copy()]

    if events is not None:
        if callable(events):
            events = [events]
        events = list(events)
        terminal, ev_dir = _event_attrs(events)
        max_count = np.where(terminal > 0, terminal, np.inf)
        ev_count = np.zeros(len(events))
        g = _eval_events(events, t0, solver.y, solver.yp)
        t_events: list[list[float]] | None = [[] for _ in events]
        y_events: list[list[np.ndarray]] | None = [[] for _ in events]
        yp_events: list[list[np.ndarray]] | None = [[] for _ in events]
    else:
        t_events = y_events = yp_events = None

    interpolants: list[BDFDenseOutput] = []
    ts_steps = [t0]
    status: int | None = None
    message = ""
    error: IntegrationError | None = None

    # With the compiled loop and nothing to do at every step (outputs on a grid, no
    # events, no dense solution), C integrates from one output time to the next.
    skip = solver.compiled and t_eval is not None and events is None and not dense_output
    while status is None:
        if solver.nstep >= max_steps:
            status, message = -1, f"Reached max_steps = {max_steps} at t = {solver.t:.9g}."
            break
        try:
            if skip:
                t_next = t_eval[t_eval_i] if t_eval_i < t_eval.size else tf
                solver.advance(t_next, max_steps - solver.nstep)
            else:
                solver.step()
        except IntegrationError as exc:
            status, message, error = -1, str(exc), exc
            break
        t_old, t = solver.t_old, solver.t
        interp: BDFDenseOutput | None = None
        if dense_output:
            interp = solver.dense_output()
            interpolants.append(interp)
            ts_steps.append(t)

        t_stop = t
        if events is not None:
            g_new = _eval_events(events, t, solver.y, solver.yp)
            active = _find_active(g, g_new, ev_dir)
            if t_old == t0:
                # As in IDA, an exact zero of g at t0 (e.g. a velocity event on a release
                # from rest) is not an event.
                active = active[g[active] != 0.0]
            if active.size:
                if interp is None:
                    interp = solver.dense_output()
                roots = []
                for i in active:
                    ev = events[i]

                    def gi(
                        s: float, ev: Callable[..., float] = ev, f: BDFDenseOutput = interp
                    ) -> float:
                        return float(ev(s, f(s), f.derivative(s)))

                    roots.append(_locate(gi, t_old, t, g[i], g_new[i]))
                roots = np.asarray(roots)
                order = np.argsort(direction * roots)
                active, roots = active[order], roots[order]
                stop_here = False
                for i, r in zip(active, roots, strict=True):
                    ev_count[i] += 1
                    t_events[i].append(r)
                    y_events[i].append(interp(r))
                    yp_events[i].append(interp.derivative(r))
                    if ev_count[i] >= max_count[i]:
                        stop_here = True
                        t_stop = r
                        break
                if stop_here:
                    status, message = 1, "A termination event occurred."
            g = g_new

        if t_eval is None:
            if status == 1:
                ts_out.append(t_stop)
                ys_out.append(interp(t_stop))
                yps_out.append(interp.derivative(t_stop))
            else:
                ts_out.append(t)
                ys_out.append(solver.y.copy())
                yps_out.append(solver.yp.copy())
        else:
            j0 = t_eval_i
            while t_eval_i < t_eval.size and direction * (t_eval[t_eval_i] - t_stop) <= 0:
                t_eval_i += 1
            if t_eval_i > j0:
                if interp is None:
                    interp = solver.dense_output()
                interp.values(t_eval[j0:t_eval_i], y_rows[j0:t_eval_i],
                              yp_rows[j0:t_eval_i])

        if progress is not None:
            progress(t_stop)
        if status is None and solver.status == "finished":
            if pieces is not None and not pieces.last:
                try:              # the next piece: after a breakpoint of the inputs
                    pieces.next(solver)
                except IntegrationError as exc:
                    status, message, error = -1, str(exc), exc
                    break
                solver.set_max_step(min(solver.max_step, user_max_step))
                continue
            status = 0
            message = "The solver successfully reached the end of the integration interval."

    n = y0.size
    if t_eval is not None:
        ts_out = t_eval[:t_eval_i].copy()
        y_arr, yp_arr = y_rows[:t_eval_i].T, yp_rows[:t_eval_i].T
    else:
        y_arr = np.array(ys_out).T if ys_out else np.empty((n, 0))
        yp_arr = np.array(yps_out).T if yps_out else np.empty((n, 0))
    sol = BDFSolution(ts_steps, interpolants) if dense_output and interpolants else None
    if t_events is not None:
        t_ev = [np.asarray(te) for te in t_events]
        y_ev = [np.asarray(ye).reshape(-1, n) for ye in y_events]
        yp_ev = [np.asarray(ye).reshape(-1, n) for ye in yp_events]
    else:
        t_ev = y_ev = yp_ev = None
    return SolveResult(
        t=np.asarray(ts_out),
        y=y_arr,
        yp=yp_arr,
        sol=sol,
        t_events=t_ev,
        y_events=y_ev,
        yp_events=yp_ev,
        status=status,
        message=message,
        counters=solver.counters,
        error=error,
    )


def _locate(gi: Callable[[float], float], a: float, b: float, ga: float, gb: float) -> float:
    """Root of ``gi`` in [a, b] given the sign change ga -> gb (to round-off)."""
    if ga == 0.0:
        return a
    if gb == 0.0:
        return b
    lo, hi = (a, b) if a < b else (b, a)
    xtol = 4.0 * np.finfo(float).eps * max(abs(lo), abs(hi), 1e-300)
    # Re-evaluate at the ends on the interpolant so the root finder sees a consistent bracket.
    glo, ghi = gi(lo), gi(hi)
    if glo == 0.0:
        return lo
    if ghi == 0.0:
        return hi
    if math.copysign(1.0, glo) == math.copysign(1.0, ghi):
        # The interpolant misses the sign change at round-off level: take the end with |g| min.
        return lo if abs(glo) < abs(ghi) else hi
    return bracketed_root(gi, lo, hi, glo, ghi, xtol=xtol)
