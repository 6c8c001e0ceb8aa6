"""The equilibrium a rod vibrates about, for the decrements of its maxima.

A free decay's logarithmic decrements ``ln(a_k / a_k+1)`` need the amplitudes ``a_k``
about the state the rod vibrates about, not about its stress-free reference: a cable
hanging under gravity and released from a pull oscillates about its sag, and its maxima
measured from the reference give decrements of the sag plus the vibration (a
copper/PVC cable printed damping ratios 0.058 ... 0.195 where its mode has 0.0327).

:func:`vibration_centre` finds that state from the loads that act while the maxima are
taken (``analysis.maxima``, docs/problem-keys):

- no load acts then and no end has moved away (a released load, the paper's cantilever):
  the stress-free reference, exactly (nothing is solved; the amplitudes are the
  displacements, as they always were for such runs);
- the loads and end positions are constant over the maxima: the static equilibrium under
  them (Newton from the run's final state, which lies close to it; load stepping from the
  reference if that fails);
- they still change over the maxima (a harmonic load, a ramp that has not ended), or no
  equilibrium is found (a rod whose loads act along a free rigid motion: a pendulum): the
  run's final state, with a warning that the centre is doubtful.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from runtime.errors import IllPosedError
from runtime.model.rod import RodModel
from runtime.model.statics import RodStatics
from runtime.problem.schema import Problem
from runtime.solvers.statics import StaticSolveError, solve_static


@dataclass(frozen=True)
class VibrationCentre:
    """The value of the maxima's coordinate (``analysis.maxima``) the rod vibrates about,
    as a displacement from the reference (m); ``source``: "reference", "static
    equilibrium" or "final state"; ``warning``: why the centre is doubtful, or None."""

    value: float
    source: str
    warning: str | None = None

    def to_dict(self) -> dict:
        return {"displacement": self.value, "source": self.source,
                **({"warning": self.warning} if self.warning else {})}


def inputs_constant(model: RodModel, t0: float, t1: float) -> bool:
    """Whether every load and end motion is constant on [t0, t1] (from the right at t0:
    a load released at t0 is off)."""
    drive = model.drive
    if drive is None or not getattr(drive, "time_dependent", False):
        return True
    lo, hi = drive.steady_interval(t0)
    return lo <= t0 and hi >= t1


def _unloaded(problem: Problem, t: float) -> bool:
    """No load acts at t and every end is at its reference position and frame."""
    if any(any(ld.vector) and ld.time.value_at(t) != 0.0 for ld in problem.loads):
        return False
    for end in (problem.start, problem.end):
        mo = end.motion
        if mo is None:
            continue
        if any(mo.translation) and mo.translation_time.value_at(t) != 0.0:
            return False
        if mo.rotation_angle and mo.rotation_time.value_at(t) != 0.0:
            return False
    return True


def equilibrium_at(problem: Problem, model: RodModel, t: float,
                   y_guess: np.ndarray) -> np.ndarray:
    """The static equilibrium (n,) under the loads and end positions at time ``t``: Newton
    from ``y_guess`` at the full load, else load stepping from the reference. Raises
    :class:`~runtime.solvers.statics.StaticSolveError` or
    :class:`~runtime.errors.IllPosedError` when there is none."""
    st = RodStatics(model, t)
    with model.statics(t):
        guess = model.constrain(np.array(y_guess, dtype=float))
        st.hold_rigid_motions(guess)
        try:
            return solve_static(st, st.at_rest(guess), first_load=1.0, max_iter=30).y.copy()
        except StaticSolveError:
            y0 = model.initial_state()
            return solve_static(st, y0, load_steps=problem.statics.load_steps).y.copy()


def vibration_centre(problem: Problem, model: RodModel, index: int, t_first: float,
                     t_last: float, y_last: np.ndarray) -> VibrationCentre:
    """The centre of the vibration of state component ``index`` (a node coordinate) over
    ``[t_first, t_last]`` (s): see the module docstring."""
    ref = float(model.reference[index])
    if not inputs_constant(model, t_first, t_last):
        return VibrationCentre(
            float(y_last[index]) - ref, "final state",
            f"loads or end motion still change after the first maximum (t = {t_first:.4g} "
            "s), so the rod vibrates about no fixed equilibrium: the decrements are taken "
            "about the run's final state and are doubtful")
    if _unloaded(problem, t_last):
        return VibrationCentre(0.0, "reference")
    try:
        y = equilibrium_at(problem, model, t_last, y_last)
    except (StaticSolveError, IllPosedError) as exc:
        why = str(exc).split("\n")[0]
        return VibrationCentre(
            float(y_last[index]) - ref, "final state",
            f"no static equilibrium under the loads that remain after t = {t_first:.4g} s "
            f"({why}): the decrements are taken about the run's final state")
    value = float(y[index]) - ref
    if not math.isfinite(value):
        return VibrationCentre(float(y_last[index]) - ref, "final state",
                               "the static equilibrium is not finite: the decrements are "
                               "taken about the run's final state")
    return VibrationCentre(value, "static equilibrium")
