"""Every derivation step reproduces the paper's stated forms; pipeline structure."""

from __future__ import annotations

import dataclasses

import pytest
import sympy as sp
from sympy.core.function import AppliedUndef

from derive import STEP_NAMES, run, step
from derive.pipeline import PIPELINE, UnknownStepError

STATED = [(name, key) for name in STEP_NAMES for key in run()[name].stated]


@pytest.mark.parametrize(("name", "key"), STATED, ids=[f"{n}:{k}" for n, k in STATED])
def test_derived_equals_stated(name, key):
    s = step(name)
    derived, stated = s.results[key], s.stated[key]
    diff = (sp.Matrix(derived) - sp.Matrix(stated)) if isinstance(stated, sp.MatrixBase) \
        else derived - stated
    assert s.matches[key], f"{name}.{key}: derived {derived} != paper {stated}"
    # recheck independently of the record's own comparison, numerically at a random point
    # (undetermined functions such as K(s), G(s) of the Laplace-domain steps get values too)
    free = sorted(diff.free_symbols, key=str)
    if free and not diff.has(sp.Sum, sp.Integral):
        funcs = sorted(diff.atoms(AppliedUndef), key=str)
        vals = {sym: sp.Rational(3 + 7 * i % 11, 10 + i) for i, sym in enumerate(funcs + free)}
        num = diff.xreplace({f: vals[f] for f in funcs}).subs(vals)
        num = num.evalf() if not isinstance(num, sp.MatrixBase) else num.evalf()
        assert sp.Abs(sp.N(sp.Matrix(num).norm() if isinstance(num, sp.MatrixBase) else num)) < 1e-9


def test_every_step_has_stated_forms_and_equations():
    for s in run().values():
        assert s.equations, s.name
        assert s.stated, f"{s.name} is compared against nothing"
        assert s.all_match


def test_pipeline_order_respects_inputs():
    seen: set[str] = set()
    for e in PIPELINE:
        assert set(e.inputs) <= seen, e.name
        seen.add(e.name)


def test_records_are_frozen():
    s = step("dissipation")
    with pytest.raises(dataclasses.FrozenInstanceError):
        s.name = "x"  # type: ignore[misc]
    with pytest.raises(TypeError):
        s.results["eta_E"] = 0  # type: ignore[index]


def test_unknown_step():
    with pytest.raises(UnknownStepError, match="steps are"):
        step("no_such_step")


def test_repr_latex():
    tex = step("dissipation")._repr_latex_()
    assert tex.startswith("$") and r"\eta" in tex


def test_stated_forms_would_catch_a_wrong_derivation():
    """The comparison machinery fails on a wrong result (e.g. the OCR's eta_E without 4/3)."""
    from derive.step import make_step
    from derive.symbols import eta, nu, zeta

    wrong = zeta * (1 - 2 * nu) ** 2 + eta * (1 + nu) ** 2
    s = step("dissipation")
    rec = make_step(name="x", title="x", equations=("(5)",), assumptions=(),
                    results={"eta_E": wrong}, stated={"eta_E": s.stated["eta_E"]})
    assert not rec.all_match
