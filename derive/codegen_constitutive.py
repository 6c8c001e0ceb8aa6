"""Render generated/constitutive.py from the formula table with a Jinja2 template."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import sympy as sp
from sympy.printing.numpy import NumPyPrinter

from derive.artifact import Artifact, sha256_text
from derive.formulas import formulas, in_material_parameters
from derive.pipeline import run
from derive.steps import sections as sec
from derive.steps.maxwell_rod import G_k, dD_k, s_k
from derive.symbols import (
    I1,
    I2,
    I3,
    A,
    E,
    G,
    G_br,
    G_inf,
    G_j,
    K,
    K_br,
    K_inf,
    K_j,
    j_idx,
    kappa_1,
    kappa_2,
    kappa_3,
    nu,
    s_lap,
    tau_B,
    tau_br,
    tau_j,
    tau_S,
)
from derive.templating import render

TEMPLATE_DIR = Path(__file__).parent / "templates"
TEMPLATE = "constitutive.py.jinja"
RECTANGLE_TERMS = 400


@dataclass(frozen=True)
class Range:
    low: str
    high: str
    low_incl: bool
    high_incl: bool
    unit: str


#: allowed parameter ranges (rendered into the generated module)
RANGES: dict[str, Range] = {
    "E": Range("0.0", "math.inf", False, False, "Pa"),
    "nu": Range("-1.0", "0.5", False, True, ""),
    "nu_compressible": Range("-1.0", "0.5", False, False, ""),
    "tau_S": Range("0.0", "math.inf", True, False, "s"),
    "tau_B": Range("0.0", "math.inf", True, False, "s"),
    "eta": Range("0.0", "math.inf", True, False, "Pa s"),
    "zeta": Range("0.0", "math.inf", True, False, "Pa s"),
    "length": Range("0.0", "math.inf", False, False, "m"),
    "length_or_zero": Range("0.0", "math.inf", True, False, "m"),
    "section": Range("0.0", "math.inf", False, False, "m^2 or m^4"),
    "kappa": Range("0.0", "1.0", False, True, ""),
    "modulus": Range("0.0", "math.inf", True, False, "Pa"),
    "relaxation_time": Range("0.0", "math.inf", False, False, "s"),
}


class _Printer(NumPyPrinter):
    """NumPy printer with 'numpy' as module name and plain float rationals."""

    def __init__(self):
        super().__init__({"fully_qualified_modules": True, "strict": True})


#: viscous parameters: a damping coefficient is linear in these, and is printed as a sum of
#: one term per parameter with a factored coefficient
_VISCOUS = ("tau_B", "tau_S", "zeta", "eta")


def stable_form(expr: sp.Basic) -> sp.Basic:
    """``expr`` regrouped for floating-point evaluation: one term per viscous parameter with a
    factored material coefficient.

    Why: SymPy's expanded forms write the bulk part as ``2 nu tau_B - tau_B``, which cancels
    catastrophically as nu -> 1/2 (relative error O(1) at nu = 1/2 - 1 ulp), while
    ``tau_B (1 - 2 nu)`` keeps full relative accuracy. The regrouping is an identity, checked.
    """
    names = {s.name: s for s in expr.free_symbols}
    viscous = [names[n] for n in _VISCOUS if n in names]
    if not viscous:
        return expr
    grouped = sp.collect(sp.expand(expr), viscous, sp.factor)
    if sp.simplify(grouped - expr) != 0:
        raise AssertionError(f"regrouping changed {expr} into {grouped}")
    return grouped


def code(expr: sp.Basic, allowed: set[sp.Symbol]) -> str:
    """Python source of ``expr`` in its :func:`stable_form`; refuses expressions with symbols
    outside ``allowed``."""
    extra = expr.free_symbols - allowed
    if extra:
        raise ValueError(f"expression {expr} has symbols {extra} outside {allowed}")
    return _Printer().doprint(stable_form(expr))


def code_as(expr: sp.Basic, names: dict[sp.Basic, str]) -> str:
    """Python source of ``expr`` with each key (symbol or indexed symbol) renamed to the given
    variable name of the generated function; refuses any other free symbol."""
    new = {old: sp.Symbol(name) for old, name in names.items()}
    return code(expr.xreplace(new), set(new.values()))


def _maxwell_context(f: dict) -> dict:
    """Printed formulas of the generalized Maxwell functions (steps maxwell_material,
    maxwell_rod, isotropic_moduli), in the variable names of the template."""
    branch = {s_lap: "s_b", tau_j: "tau_j"}
    indexed = {G_br[j_idx]: "G_j", K_br[j_idx]: "K_j", tau_br[j_idx]: "tau_j", s_lap: "s_b"}
    return {
        "branch_G": code_as(f["maxwell_branch_shear"], {**branch, G_j: "G_j"}),
        "branch_K": code_as(f["maxwell_branch_bulk"], {**branch, K_j: "K_j"}),
        "E_of_KG": code_as(f["E_of_KG"], {K: "K", G: "G"}),
        "c_inf": code_as(f["secular_coefficient_inf"], {K_inf: "K_inf", G_inf: "G_inf"}),
        "c_j": code_as(f["secular_coefficient"], {K_j: "K_j", G_j: "G_j"}),
        "dD_branch": code_as(f["secular_derivative_branch"], indexed),
        "E_inf": code_as(f["maxwell_E_inf"], {K_inf: "K_inf", G_inf: "G_inf"}),
        "E_branch": code_as(f["prony_E_branch"], {K_j: "K_j", G_j: "G_j"}),
        "E_root": code_as(f["prony_E_root"], {G_k: "G_k", s_k: "s_k", dD_k: "dD_k"}),
        "G_of_E": code_as(f["G_of_E"], {E: "E_j", nu: "nu_j"}),
        "K_of_E": code_as(f["K_of_E"], {E: "E_j", nu: "nu_j"}),
    }


def _fn(name, args, doc, step, eqs, arg_docs, returns, expr, checks):
    allowed = {sp.Symbol(a, **({"real": True} if a == "nu" else {"positive": True}))
               for a in args}
    return {"name": name, "args": list(args), "doc": doc, "step": step, "equations": eqs,
            "arg_docs": arg_docs, "returns": returns, "body": code(expr, allowed),
            "checks": checks}


def _context() -> dict:
    f = formulas()
    steps = run()
    cs = steps["cross_sections"].results
    nu_doc = "nu: Poisson's ratio [-]"
    functions = [
        _fn("shear_modulus", ["E", "nu"], "Shear modulus G = mu [Pa].", "isotropic_moduli",
            "Sect. 3.3", ["E: Young's modulus [Pa]", nu_doc], "G [Pa]", f["G_of_E"],
            [("E", "E"), ("nu", "nu")]),
        _fn("bulk_modulus", ["E", "nu"], "Bulk modulus K = lambda + 2 mu/3 [Pa].",
            "isotropic_moduli", "Sect. 3.3", ["E: Young's modulus [Pa]", nu_doc + " (< 1/2)"],
            "K [Pa]", f["K_of_E"], [("E", "E"), ("nu", "nu_compressible")]),
        _fn("lame_lambda", ["E", "nu"], "Lame constant lambda [Pa].", "isotropic_moduli",
            "Sect. 3.3", ["E: Young's modulus [Pa]", nu_doc + " (< 1/2)"], "lambda [Pa]",
            f["lambda_of_E"], [("E", "E"), ("nu", "nu_compressible")]),
        _fn("extensional_viscosity", ["zeta", "eta", "nu"],
            "Extensional viscosity eta_E from the dissipation function [Pa s].",
            "dissipation", "(5)", ["zeta: bulk viscosity [Pa s]", "eta: shear viscosity [Pa s]",
                                   nu_doc], "eta_E [Pa s]", f["eta_E"],
            [("zeta", "zeta"), ("eta", "eta"), ("nu", "nu")]),
        _fn("extensional_viscosity_naive", ["zeta", "eta", "nu"],
            "Extensional viscosity eta~_E of the naive resultant route [Pa s].",
            "naive_resultants", "Sect. 4.2", ["zeta: bulk viscosity [Pa s]",
                                              "eta: shear viscosity [Pa s]", nu_doc],
            "eta~_E [Pa s]", f["eta_E_naive"], [("zeta", "zeta"), ("eta", "eta"), ("nu", "nu")]),
        _fn("in_plane_dissipation", ["zeta", "eta", "nu"],
            "Coefficient of (dH3/dt)^2 the resultant route misses, eta_E - eta~_E [Pa s].",
            "naive_resultants", "Sect. 4.2", ["zeta: bulk viscosity [Pa s]",
                                              "eta: shear viscosity [Pa s]", nu_doc],
            "eta_E - eta~_E [Pa s]", f["in_plane_dissipation"],
            [("zeta", "zeta"), ("eta", "eta"), ("nu", "nu")]),
        _fn("retardation_time_extension", ["tau_B", "tau_S", "nu"],
            "Extensional retardation time tau_E = eta_E/E [s].", "dissipation", "(6)",
            ["tau_B: bulk retardation time zeta/K [s]", "tau_S: shear retardation time eta/G [s]",
             nu_doc], "tau_E [s]", f["tau_E"],
            [("tau_B", "tau_B"), ("tau_S", "tau_S"), ("nu", "nu")]),
        _fn("retardation_time_extension_naive", ["tau_B", "tau_S"],
            "Naive extensional retardation time tau~_E = eta~_E/E [s] (independent of nu).",
            "naive_resultants", "Sect. 4.2",
            ["tau_B: bulk retardation time [s]", "tau_S: shear retardation time [s]"],
            "tau~_E [s]", f["tau_E_naive"], [("tau_B", "tau_B"), ("tau_S", "tau_S")]),
    ]
    mat_args = {E, nu, A, I1, I2, I3, kappa_1, kappa_2, kappa_3}
    damp_args = mat_args | {tau_S, tau_B}
    CF = in_material_parameters(f["C_F"])
    CM = in_material_parameters(f["C_M"])
    VF, VM = in_material_parameters(f["V_F"]), in_material_parameters(f["V_M"])
    VFn, VMn = in_material_parameters(f["V_F_naive"]), in_material_parameters(f["V_M_naive"])
    b, d, a_e, b_e = sec.b, sec.d, sec.a_e, sec.b_e
    rect_args = {b, d, nu}
    ell_args = {a_e, b_e, nu}
    tube_args = {sec.r_o, sec.r_i}
    m = sec.m
    term = cs["rectangle_J_T_tanh_term"]
    return {
        "maxwell": _maxwell_context(f),
        "functions": functions,
        "ranges": list(RANGES.items()),
        "CF": [code(CF[i, i], mat_args) for i in range(3)],
        "CM": [code(CM[i, i], mat_args) for i in range(3)],
        "VF": [code(VF[i, i], damp_args) for i in range(3)],
        "VM": [code(VM[i, i], damp_args) for i in range(3)],
        "VFn": [code(VFn[i, i], damp_args) for i in range(3)],
        "VMn": [code(VMn[i, i], damp_args) for i in range(3)],
        "rect": {"A": code(cs["rectangle_A"], rect_args), "I1": code(cs["rectangle_I1"], rect_args),
                 "I2": code(cs["rectangle_I2"], rect_args),
                 "kappa": code(cs["cowper_rectangle"], rect_args)},
        "rect_power": code(cs["rectangle_J_T_power_sum"], rect_args),
        "rect_term": code(term, rect_args | {m}),
        "rect_terms": RECTANGLE_TERMS,
        "rect_terms_var": "terms",
        "rect_J_doc": "J_T = b d^3/3 - 64 d^4/pi^5 sum tanh((2m+1) pi b/(2d))/(2m+1)^5",
        "tube": {"A": code(cs["tube_A"], tube_args), "I1": code(cs["tube_I1"], tube_args),
                 "I2": code(cs["tube_I2"], tube_args), "J_T": code(cs["tube_J_T"], tube_args),
                 "kappa_3": code(cs["tube_kappa_3"], tube_args),
                 "kappa": code(cs["cowper_tube"], {sec.m_t, nu})},
        "ell": {"A": code(cs["ellipse_A"], ell_args), "I1": code(cs["ellipse_I1"], ell_args),
                "I2": code(cs["ellipse_I2"], ell_args), "J_T": code(cs["ellipse_J_T"], ell_args),
                "kappa_a": code(cs["cowper_ellipse_along_a"], ell_args),
                "kappa_b": code(cs["cowper_ellipse_along_b"], ell_args),
                # the derived J_T / I3 (exactly 1 in floating point for a circle, where
                # the quotient of the rounded J_T and I3 can exceed the bound 1 by an ulp)
                "kappa_3": code(cs["ellipse_kappa_3"], ell_args)},
    }


def render_constitutive() -> tuple[str, str]:
    """(module text, sha256 of its inputs: template text and the rendering context)."""
    ctx = _context()
    text = render(TEMPLATE_DIR, TEMPLATE, **ctx)
    template_text = (TEMPLATE_DIR / TEMPLATE).read_text()
    return text, sha256_text(template_text, repr(sorted((k, repr(v)) for k, v in ctx.items())))


def artifacts() -> list[Artifact]:
    """The generated constitutive module."""
    text, h = render_constitutive()
    return [Artifact(path="constitutive.py", text=text, source=f"derive/templates/{TEMPLATE}",
                     step="isotropic_moduli, stored_energy, dissipation, naive_resultants, "
                          "cross_sections, maxwell_material, maxwell_rod",
                     inputs_hash=h,
                     signature={"functions": ["shear_modulus", "bulk_modulus", "lame_lambda",
                                              "extensional_viscosity",
                                              "extensional_viscosity_naive",
                                              "in_plane_dissipation",
                                              "retardation_time_extension",
                                              "retardation_time_extension_naive",
                                              "rectangle_section", "ellipse_section",
                                              "circle_section", "tube_section",
                                              "maxwell_branch_moduli",
                                              "maxwell_moduli_laplace",
                                              "maxwell_rod_prony",
                                              "stiffness_matrices",
                                              "damping_matrices"]})]
