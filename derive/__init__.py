"""derive: the Kelvin-Voigt Cosserat rod model re-derived from 3-D theory with SymPy.

>>> from derive import formulas, steps
>>> formulas()["eta_E"]          # extensional viscosity (5), derived
>>> steps()["dissipation"]       # a frozen Step record (LaTeX in Jupyter)

Layering: derive may import SymPy, CasADi, Jinja2 and generated/, never runtime/.
"""

from __future__ import annotations

from derive.formulas import formulas
from derive.pipeline import PIPELINE, STEP_NAMES, UnknownStepError, run, step
from derive.step import Step


def steps() -> dict[str, Step]:
    """All step records by name, in pipeline order.

    Returns
    -------
    dict of str to Step
        Each :class:`~derive.step.Step` with its assumptions, derived results and the
        comparison with the paper's stated forms (``kvrod derive list``).
    """
    return run()


__all__ = ["PIPELINE", "STEP_NAMES", "Step", "UnknownStepError", "formulas", "run", "step",
           "steps"]
