"""The derivation step record and the registry of steps (docs/design.md, section 2).

A step is a pure function from earlier steps' records to a frozen :class:`Step`. Its
``results`` are SymPy objects computed from the inputs; ``stated`` holds the paper's
printed form of some results, typed in only to be *compared against*; ``matches`` records
for every stated result whether ``derived - stated`` simplifies to zero.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import TYPE_CHECKING, Any

# SymPy is imported inside the functions that use it: the catalogue of steps (titles,
# equations, ``kvrod derive list``) must not pay for importing it.
if TYPE_CHECKING:
    import sympy as sp

    Expr = sp.Basic
else:
    Expr = Any


def _frozen(d: Mapping | None) -> Mapping:
    return MappingProxyType(dict(d or {}))


def is_zero(expr: Expr) -> bool:
    """True when ``expr`` (scalar or matrix) simplifies to zero.

    Cheap normal forms first (expand, cancel), full ``simplify`` only when they fail: the
    derivation is polynomial/rational almost everywhere and this keeps it fast.
    """
    import sympy as sp

    if isinstance(expr, sp.MatrixBase):
        return all(is_zero(e) for e in expr)
    if isinstance(expr, (tuple, list)):
        return all(is_zero(e) for e in expr)
    for normal in (sp.expand, lambda e: sp.cancel(sp.together(e)), sp.simplify):
        if normal(expr) == 0:
            return True
    return False


@dataclass(frozen=True)
class Step:
    """One derivation step: what it assumes, what it derives, and how that compares.

    name: identifier used by ``kvrod derive show NAME``.
    title: one-line human title.
    equations: the paper's equation numbers this step reproduces, e.g. ("(14)", "(17)").
    assumptions: modelling assumptions in words.
    symbol_assumptions: SymPy assumptions in force (e.g. "E > 0", "-1 < nu < 1/2").
    inputs: names of the earlier steps whose results this step uses.
    results: derived SymPy objects by name.
    stated: the paper's stated form of some results (compared against, never used).
    matches: per stated result, whether derived - stated simplifies to zero.
    notes: short remarks shown with the step (e.g. where the OCR copy was reconstructed).
    """

    name: str
    title: str
    equations: tuple[str, ...]
    assumptions: tuple[str, ...]
    symbol_assumptions: tuple[str, ...]
    inputs: tuple[str, ...]
    results: Mapping[str, Expr] = field(default_factory=lambda: _frozen(None))
    stated: Mapping[str, Expr] = field(default_factory=lambda: _frozen(None))
    matches: Mapping[str, bool] = field(default_factory=lambda: _frozen(None))
    notes: tuple[str, ...] = ()

    @property
    def all_match(self) -> bool:
        """True when every stated form equals its derived counterpart."""
        return all(self.matches.values())

    def latex(self) -> str:
        """The step as LaTeX: every result, with its stated counterpart where one exists."""
        import sympy as sp

        lines = [rf"\textbf{{{self.title}}}\ {' '.join(self.equations)}"]
        for key, value in self.results.items():
            lines.append(rf"{latex_name(key)} = {sp.latex(value)}")
        return r"\\ ".join(lines)

    def _repr_latex_(self) -> str:  # Jupyter
        import sympy as sp

        body = r"\\ ".join(rf"{latex_name(k)} &= {sp.latex(v)}" for k, v in self.results.items())
        return rf"$\begin{{aligned}}{body}\end{{aligned}}$"


def latex_name(key: str) -> str:
    """Readable LaTeX for a result key such as ``eta_E_naive`` -> ``\\mathrm{eta\\_E\\_naive}``."""
    return r"\mathrm{" + key.replace("_", r"\_") + "}"


def make_step(
    *,
    name: str,
    title: str | None = None,
    equations: tuple[str, ...] | None = None,
    assumptions: tuple[str, ...],
    symbol_assumptions: tuple[str, ...] = (),
    inputs: tuple[str, ...] = (),
    results: Mapping[str, Expr],
    stated: Mapping[str, Expr] | None = None,
    notes: tuple[str, ...] = (),
) -> Step:
    """Build a :class:`Step`, comparing each stated form with the derived result.

    ``title`` and ``equations`` default to the step's entry in the pipeline catalogue
    (:data:`derive.catalogue.PIPELINE`, where every step of the pipeline has them).
    """
    import sympy as sp

    if title is None or equations is None:
        from derive.catalogue import entry

        e = entry(name)
        title = e.title if title is None else title
        equations = e.equations if equations is None else equations
    stated = dict(stated or {})
    missing = set(stated) - set(results)
    if missing:
        raise KeyError(f"step {name!r}: stated forms without a derived result: {sorted(missing)}")
    matches = {k: is_zero(sp.Matrix(results[k]) - sp.Matrix(v))
               if isinstance(v, sp.MatrixBase) else is_zero(results[k] - v)
               for k, v in stated.items()}
    return Step(name=name, title=title, equations=equations, assumptions=assumptions,
                symbol_assumptions=symbol_assumptions, inputs=inputs,
                results=_frozen(results), stated=_frozen(stated), matches=_frozen(matches),
                notes=notes)


StepFunction = Callable[..., Step]
