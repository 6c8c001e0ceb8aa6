"""Generalised Maxwell (Prony series) -> Kelvin-Voigt low-frequency limit (Sect. 4.4)."""

from __future__ import annotations

import sympy as sp

from derive.step import Step, make_step

N_PRONY = 3  # terms of the Prony series used to carry out the derivation


def maxwell_limit() -> Step:
    """Complex modulus, its first-order match with Kelvin-Voigt, and the error term."""
    w = sp.Symbol("omega", positive=True)
    G_inf, eta_kv = sp.symbols("G_inf eta", positive=True)
    Gj = sp.symbols(f"G_1:{N_PRONY + 1}", positive=True)
    tj = sp.symbols(f"tau_1:{N_PRONY + 1}", positive=True)
    G_hat = G_inf + sum(g * sp.I * w * t / (1 + sp.I * w * t) for g, t in zip(Gj, tj, strict=True))
    # relaxation kernel G(s) = G_inf + sum G_j exp(-s/tau_j), sigma = int G(s) eps'(t-s) ds:
    # sigma_hat = i omega [int_0^oo G(s) exp(-i omega s) ds] eps_hat, one exponential at a time;
    # the constant G_inf is the limit tau -> oo of an exponential term
    s_, T = sp.symbols("s T", positive=True)

    def kernel_term(g, t):
        return sp.simplify(sp.I * w * sp.integrate(g * sp.exp(-s_ / t) * sp.exp(-sp.I * w * s_),
                                                    (s_, 0, sp.oo), conds="none"))

    G_hat_from_kernel = sp.limit(kernel_term(G_inf, T), T, sp.oo) + sum(
        kernel_term(g, t) for g, t in zip(Gj, tj, strict=True))
    series = sp.series(G_hat, w, 0, 2).removeO()
    G_kv = sp.expand(series.coeff(w, 0))
    eta_match = sp.expand(sp.simplify(series.coeff(w, 1) / sp.I))
    diff = sp.simplify(G_hat - (G_kv + sp.I * eta_match * w))
    first = Gj[0] * sp.I * w * tj[0] / (1 + sp.I * w * tj[0]) - sp.I * w * Gj[0] * tj[0]
    term_abs = sp.simplify(sp.Abs(sp.simplify(first)))
    return make_step(
        name="maxwell_limit",
        title="Generalised Maxwell -> Kelvin-Voigt at low frequency",
        equations=("Sect. 4.4",),
        assumptions=("1-D linear viscoelastic law with a Prony-series relaxation function",
                     f"derivation carried out with N = {N_PRONY} Maxwell elements"),
        symbol_assumptions=("omega, G_j, tau_j > 0",),
        results={
            "G_hat": G_hat,
            "G_hat_from_kernel": G_hat_from_kernel,
            "G": G_kv,
            "eta": eta_match,
            "G_hat_minus_KV": diff,
            "error_term_abs_j1": term_abs,
            "error_order_omega": sp.Integer(sp.Poly(sp.series(diff, w, 0, 3).removeO(), w)
                                            .monoms()[-1][0]),
        },
        stated={
            "G_hat_from_kernel": G_hat,
            "G": G_inf,
            "eta": sum(g * t for g, t in zip(Gj, tj, strict=True)),
            "G_hat_minus_KV": sum(g * (w * t) ** 2 / (1 + sp.I * w * t)
                                  for g, t in zip(Gj, tj, strict=True)),
            "error_term_abs_j1": Gj[0] * (w * tj[0]) ** 2 / sp.sqrt(1 + (w * tj[0]) ** 2),
            "error_order_omega": sp.Integer(2),
        },
        notes=("Kelvin-Voigt (G + i eta omega) is the first-order Taylor polynomial of the "
               "complex modulus: the error is O(omega^2 tau_j^2), so the model holds well "
               f"below 1/tau_j. {eta_kv} = sum G_j tau_j.",),
    )
