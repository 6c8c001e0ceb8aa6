"""Results that check themselves: the energy audit of a run and the doubts it raises.

The discrete rod satisfies ``d/dt (T + W) = -2D + P`` exactly along its flow (paper eqs.
(10), (11); ``P`` the power of external loads and prescribed motion), so the balance
``T + W + int 2D dt - int P dt`` is constant; its drift measures the integration error.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

#: an energy audit error above this (relative) makes a result doubtful
AUDIT_DOUBTFUL = 1e-3


@dataclass(frozen=True)
class RunAudit:
    """Energy audit of a run on its output samples.

    relative: ``(balance - balance[0]) / scale`` per sample; max_rel: its largest magnitude
    (None when not applicable); scale: the run's energy scale (J): the largest of the
    initial balance and ``|T + W|``, ``int 2D``, ``|int P|`` over the run; applicable:
    False when the run holds no energy above round-off (nothing moved), with the reason.
    """

    relative: np.ndarray
    max_rel: float | None
    scale: float
    applicable: bool
    reason: str = ""
    warnings: list[str] = field(default_factory=list)


def audit_run(kinetic: np.ndarray, elastic: np.ndarray, dissipated: np.ndarray,
              external_work: np.ndarray, floor: float) -> RunAudit:
    """Audit the energy balance of sampled energies (J); ``floor`` (J): the energy of
    round-off-sized strains, below which the audit is not applicable."""
    T, W = np.asarray(kinetic, float), np.asarray(elastic, float)
    D, P = np.asarray(dissipated, float), np.asarray(external_work, float)
    if T.size == 0:
        return RunAudit(np.zeros(0), None, 0.0, False, "no samples")
    total = T + W + D - P
    scale = float(max(abs(total[0]), np.max(np.abs(T + W)), np.max(np.abs(D)),
                      np.max(np.abs(P))))
    if not math.isfinite(scale):
        return RunAudit(np.full(T.size, math.nan), math.inf, scale, True, "",
                        ["the energies are not finite: the result is invalid"])
    if scale <= floor:
        return RunAudit(np.zeros(T.size), None, scale, False,
                        f"no energy in the run (largest term {scale:.3g} J is below the "
                        f"round-off floor {floor:.3g} J): nothing to audit")
    rel = (total - total[0]) / scale
    worst = float(np.max(np.abs(rel)))
    warns = []
    if worst > AUDIT_DOUBTFUL:
        warns.append(f"energy audit error {worst:.3g} exceeds {AUDIT_DOUBTFUL:g} of the run's "
                     "energy: the result is doubtful (tighten --rtol, or check atol against "
                     "the motion's scale)")
    return RunAudit(rel, worst, scale, True, "", warns)


def significant_maxima(x: np.ndarray, noise: float) -> int:
    """Number of leading maxima above the noise level ``noise`` (m): later ones are the
    integrator's round-off, not the decay, and their decrements mean nothing."""
    x = np.asarray(x, float)
    below = np.flatnonzero(np.abs(x) <= noise)
    return int(below[0]) if below.size else int(x.size)
