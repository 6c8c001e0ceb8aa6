"""The pieces of a run between the breakpoints of its inputs (IDA's ``tstop`` and
``IDAReInit``, for both run drivers).

A load or a prescribed end motion that starts, stops or kinks (a ramp's ends, a pulse
given as a table, a step, a release) is not smooth there. An integrator that steps over
such a time interpolates its history across it: from a rod at rest the error test has
nothing to control, so the step grows over a short pulse or a fast end motion, which
is then skipped without a word. So the drivers integrate piece by piece: the solver
lands exactly on every breakpoint (its ``t_bound``) and, where an input or its rate
jumps, restarts from there (order 1, a new history, consistent ``y'``), the inputs
then evaluated from the right; inside a piece the steps are bounded by the active
inputs' own time scales.

The problem says what its inputs do (all optional; a problem without them is one
piece):

* ``breakpoints(t0, t1) -> [(t, restart), ...]``, sorted, inside ``(t0, t1)``;
* ``enter_piece(t0, t1) -> max_step``: evaluate the inputs for the piece (from the
  left at ``t1``), and the largest step on it;
* ``prescribed_rates(t, yp) -> yp``: the exact ``y'`` of the algebraic unknowns whose
  motion is prescribed (the restart's history starts from them).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .bdf import BDF
from .initial import consistent_initial, consistent_sensitivities


@dataclass
class Restart:
    """A restart at a breakpoint: its time and the states just before and after it (the
    prescribed velocities jump there; the run's energy audit books the work of that
    impulse)."""

    t: float
    y_before: np.ndarray
    y_after: np.ndarray
    yp_after: np.ndarray


class Pieces:
    """The pieces ``[t_k, t_k+1]`` of ``[t0, t_end]`` cut at the problem's breakpoints."""

    def __init__(self, problem, t0: float, t_end: float) -> None:
        get = getattr(problem, "breakpoints", None)
        bps = get(t0, t_end) if get is not None else []
        self.problem = problem
        self.times = [float(t0)] + [float(t) for t, _ in bps] + [float(t_end)]
        self.restarts = [False] + [bool(r) for _, r in bps] + [False]
        self.k = 0

    @property
    def end(self) -> float:
        """End of the current piece (the solver's ``t_bound``)."""
        return self.times[self.k + 1]

    @property
    def last(self) -> bool:
        """The current piece ends at ``t_end``."""
        return self.k + 2 >= len(self.times)

    def enter(self) -> float:
        """Prepare the problem for the current piece; its largest step (s)."""
        get = getattr(self.problem, "enter_piece", None)
        h = get(self.times[self.k], self.end) if get is not None else math.inf
        return h if h > 0.0 else math.inf

    def next(self, solver: BDF) -> Restart | None:
        """The solver has landed on the end of the current piece: go on with the next one,
        restarting where an input jumps. Returns the restart (or None: the steps go on
        with their history)."""
        t = solver.t
        self.k += 1
        max_step = self.enter()
        solver.extend(self.end)
        restart = None
        if self.restarts[self.k]:
            y_before = solver.y.copy()
            y, yp = consistent_initial(self.problem, t, y_before, solver.yp.copy())
            rates = getattr(self.problem, "prescribed_rates", None)
            if rates is not None:
                yp = rates(t, yp)
            s = sp = None
            if solver.n_sensitivities:       # consistent with the inputs after the jump
                s, sp = consistent_sensitivities(self.problem, t, y, yp,
                                                 solver.sensitivities.copy())
            solver.set_max_step(max_step)
            solver.restart(y, yp, s=s, sp=sp)
            restart = Restart(t, y_before, y.copy(), yp.copy())
        else:
            solver.set_max_step(max_step)
        return restart
