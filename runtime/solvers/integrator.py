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

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from runtime.solvers.protocols import ResidualProblem

from .bdf import BDF, IntegrationError
from .dense import BDFDenseOutput
from .driver import run_loop
from .initial import consistent_initial
from .observers import DenseSolution, Events, OutputGrid, ProgressCallback, StepOutputs

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
        :func:`~runtime.solvers.initial.consistent_initial` from ``y' = 0``.
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

    Returns
    -------
    SolveResult
        Failures of the integrator do not raise here: the result has ``status = -1``,
        the outputs computed so far, and the exception in ``error``.

    Notes
    -----
    The solver stops at every breakpoint of the problem's inputs and restarts where one
    jumps (``runtime.solvers.schedule``: a pulse or a fast end motion is never stepped
    over); steps are bounded by the active inputs' time scales.
    """
    t0, tf = float(t_span[0]), float(t_span[1])
    y0 = np.asarray(y0, dtype=float)
    if yp0 is None:
        y0, yp0 = consistent_initial(problem, t0, y0, np.zeros_like(y0))
    yp0 = np.asarray(yp0, dtype=float)
    direction = 1.0 if tf >= t0 else -1.0
    n = y0.size
    observers: list = []
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
        # a progress callback is called at the outputs: the loop stops at each for it
        outputs: OutputGrid | StepOutputs = OutputGrid(t_eval, n, direction,
                                                       in_loop=progress is None)
    else:
        outputs = StepOutputs()
    ev = None
    if events is not None:
        ev = Events([events] if callable(events) else list(events), direction)
        observers.append(ev)               # first: a terminal event cuts the outputs
    observers.append(outputs)
    dense = DenseSolution() if dense_output else None
    if dense is not None:
        observers.append(dense)
    if progress is not None:
        observers.append(ProgressCallback(progress))
    options = dict(options)
    out = run_loop(problem, t0, y0, yp0, tf, rtol=rtol, atol=atol, observers=observers,
                   max_steps=max_steps, min_step=options.pop("min_step", 0.0),
                   max_order=options.pop("max_order", 5), solver_options=options)
    if out.status == "finished":
        status, message = 0, "The solver successfully reached the end of the integration " \
                             "interval."
    elif out.status == "stopped":
        status, message = 1, out.message
    elif out.error is not None:
        status, message = -1, str(out.error)
    else:
        status, message = -1, (f"Reached max_steps = {max_steps} at t = {out.t_last:.9g}."
                               if out.interrupt is None else out.message)
        if out.interrupt is not None:
            raise out.interrupt
    ts, y_arr, yp_arr = (outputs.arrays() if isinstance(outputs, OutputGrid)
                         else outputs.arrays(n))
    sol = (BDFSolution(dense.ts, dense.interpolants) if dense is not None
           and dense.interpolants else None)
    t_ev, y_ev, yp_ev = ev.arrays(n) if ev is not None else (None, None, None)
    return SolveResult(t=np.asarray(ts), y=y_arr, yp=yp_arr, sol=sol, t_events=t_ev,
                       y_events=y_ev, yp_events=yp_ev, status=status, message=message,
                       counters=out.counters, error=out.error)
