"""Render notes/derivation.md from the pipeline with a Jinja2 template."""

from __future__ import annotations

from pathlib import Path

import sympy as sp

from derive import symbols as S
from derive.formulas import formulas
from derive.pipeline import run
from derive.templating import render

TEMPLATE_DIR = Path(__file__).parent / "templates"
#: results larger than this many characters of LaTeX are shown abbreviated in the notes
MAX_LATEX = 1500


def _latex_names() -> dict:
    """Readable LaTeX for rate symbols (dV1 -> \\dot V_1 ...), equilibrium moduli
    (G_inf -> G_\\infty), the Maxwell branch's viscous strain (Qv11 -> Q^v_{11}) and the
    values at a zero s_k of D(s) = 3K(s) + G(s) (G_k -> G(s_k), dD_k -> D'(s_k))."""
    from derive.steps import maxwell_rod as mr

    names = {}
    for base in ("V", "U", "H"):
        for i in (1, 2, 3):
            sym = getattr(S, f"d{base}{i}", None)
            if sym is not None:
                names[sym] = rf"\dot{{{base}}}_{{{i}}}"
    for sym in (S.G_inf, S.K_inf, S.E_inf, mr.c_inf):
        names[sym] = sym.name.replace("_inf", r"_\infty")
    for i in range(1, 4):
        for k in range(i, 4):
            for prefix, tex in (("Qv", "Q^{{v}}"), ("dQv", r"\dot{{Q}}^{{v}}")):
                names[sp.Symbol(f"{prefix}{i}{k}", real=True)] = tex.format() + f"_{{{i}{k}}}"
    names.update({mr.G_k: "G(s_k)", mr.K_k: "K(s_k)", mr.dK_k: "K'(s_k)",
                  mr.dG_k: "G'(s_k)", mr.dD_k: "D'(s_k)"})
    return names


LATEX_NAMES = _latex_names()


def latex(value) -> str:
    """sp.latex with the notes' symbol names."""
    return sp.latex(value, symbol_names=LATEX_NAMES)


def _tex(value) -> str:
    tex = latex(value)
    if len(tex) > MAX_LATEX:
        return r"\text{(" + str(len(tex)) + r" characters of LaTeX; see kvrod derive show)}"
    return tex


def _text(line: str) -> str:
    """A step's plain-text line for Markdown, with ``&`` and ``<`` escaped as HTML
    entities: a section average such as <xi2 S_33> is then shown, not read as an HTML tag
    (and dropped) by the Markdown renderer. ``>`` needs no escape inside a line."""
    return line.replace("&", "&amp;").replace("<", "&lt;")


def render_derivation_notes() -> str:
    """The Markdown text of notes/derivation.md."""
    steps = run()
    f = formulas()
    naive = steps["naive_resultants"].results
    rows = []
    for s in steps.values():
        rows.append({
            "name": s.name, "title": _text(s.title), "equations": s.equations,
            "inputs": s.inputs, "assumptions": [_text(a) for a in s.assumptions],
            "symbol_assumptions": [_text(a) for a in s.symbol_assumptions],
            "notes": [_text(n) for n in s.notes], "stated": s.stated, "all_match": s.all_match,
            "rows": [(k, _tex(v), s.stated.get(k), s.matches.get(k)) for k, v in s.results.items()],
        })
    n_checks = sum(len(s.matches) for s in steps.values())
    n_match = sum(sum(s.matches.values()) for s in steps.values())
    tex = {
        "eta_E": latex(f["eta_E"]), "tau_E": latex(f["tau_E"]),
        "eta_E_naive": latex(f["eta_E_naive"]), "tau_E_naive": latex(f["tau_E_naive"]),
        "S_in_plane": latex(naive["S_viscous_in_plane"]),
        "in_plane": latex(f["in_plane_dissipation"]),
        "tau_diff": latex(naive["tau_E_minus_naive"]),
        "E_of_KG": latex(f["E_of_KG"].subs({S.K: S.K_of(S.s_lap), S.G: S.G_of(S.s_lap)})),
        "E_branch": latex(f["prony_E_branch"]),
        "E_root": latex(f["prony_E_root"]),
        "kv_tau_E": latex(f["kv_tau_E"]),
        "kv_tau_D": latex(f["kv_tau_D"]),
        "kv_remainder": latex(steps["kelvin_voigt_uniaxial"].results["remainder_in_tau_D"]),
    }
    return render(TEMPLATE_DIR, "derivation.md.jinja",
        steps=rows, n_steps=len(rows), n_checks=n_checks, n_match=n_match, latex=tex)


def write_derivation_notes(path: Path) -> Path:
    """Write the notes atomically; returns the path."""
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(render_derivation_notes())
    tmp.replace(path)
    return path
