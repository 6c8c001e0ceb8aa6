"""derive: the Kelvin-Voigt Cosserat rod model re-derived from 3-D theory with SymPy.

>>> from derive import formulas, steps
>>> formulas()["eta_E"]          # extensional viscosity (5), derived
>>> steps()["dissipation"]       # a frozen Step record (LaTeX in Jupyter)

Layering: derive may import SymPy, CasADi, Jinja2 and generated/, never runtime/.
Importing this package imports no SymPy (it comes with the first derivation or cache read).
"""

from __future__ import annotations

# Order matters: the submodules derive.step and derive.formulas are imported before the
# functions of the same names are bound here (importing a submodule the first time sets
# the package attribute to the module). None of these imports SymPy.
from derive.step import Step  # isort: skip
from derive.formulas import formulas  # isort: skip
from derive.pipeline import PIPELINE, STEP_NAMES, UnknownStepError, run, step  # isort: skip


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
