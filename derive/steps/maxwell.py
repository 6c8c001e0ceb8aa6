"""Generalised Maxwell (Prony series) -> Kelvin-Voigt low-frequency limit (Sect. 4.4), and
the 3-D isotropic generalized Maxwell solid (the paper's future work, Sect. 6)."""

from __future__ import annotations

import sympy as sp

from derive.step import Step, make_step
from derive.steps.dissipation import viscous_stress
from derive.symbols import (
    G_br,
    G_inf,
    G_j,
    K_br,
    K_inf,
    K_j,
    M_br,
    eta,
    eta_br,
    eta_j,
    j_idx,
    omega,
    s_lap,
    tau_br,
    tau_j,
    zeta,
    zeta_br,
    zeta_j,
)

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
    # the error bound: sigma - sigma_KV = 1/(2 pi) int (G_hat - G_KV) eps_hat e^{i w t} dw
    # (convention eps(t) = 1/(2 pi) int eps_hat e^{i w t} dw); |int f| <= int |f|,
    # |e^{i w t}| = 1 and the triangle inequality over the branches give the paper's bound
    terms = [g * sp.I * w * t / (1 + sp.I * w * t) - sp.I * w * g * t
             for g, t in zip(Gj, tj, strict=True)]
    terms_abs = [sp.simplify(sp.Abs(sp.simplify(x))) for x in terms]
    term_abs = terms_abs[0]
    w_r, t_r = sp.Symbol("omega", real=True), sp.Symbol("t", real=True)
    eps_hat = sp.Function("epsilonhat")             # prints as a hatted epsilon
    stress_diff = sp.Integral(diff.subs(w, w_r) * eps_hat(w_r) * sp.exp(sp.I * w_r * t_r),
                              (w_r, -sp.oo, sp.oo)) / (2 * sp.pi)
    unimodular = sp.Abs(sp.exp(sp.I * w_r * t_r))                      # = 1 for real w, t
    # |terms_j| is even in omega: the omega > 0 form holds on the whole real axis
    bound = sum((sp.Integral(a.subs(w, w_r) * unimodular * sp.Abs(eps_hat(w_r)),
                             (w_r, -sp.oo, sp.oo)) for a in terms_abs), sp.Integer(0)) / (2 * sp.pi)
    return make_step(
        name="maxwell_limit",
        assumptions=("1-D linear viscoelastic law with a Prony-series relaxation function",
                     "Fourier convention eps(t) = 1/(2 pi) int eps_hat(omega) e^{i omega t} "
                     "d omega",
                     f"derivation carried out with N = {N_PRONY} Maxwell elements"),
        symbol_assumptions=("omega, G_j, tau_j > 0",),
        results={
            "G_hat": G_hat,
            "G_hat_from_kernel": G_hat_from_kernel,
            "G": G_kv,
            "eta": eta_match,
            "G_hat_minus_KV": diff,
            "error_term_abs_j1": term_abs,
            "error_integrand": sum(terms_abs, sp.Integer(0)),
            "stress_difference": stress_diff,
            "error_bound": bound,
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
            "error_integrand": sum(g * (t * w) ** 2 / sp.sqrt(1 + (t * w) ** 2)
                                   for g, t in zip(Gj, tj, strict=True)),
            "error_bound": sum(sp.Integral(g * (t * w_r) ** 2 / sp.sqrt(1 + (t * w_r) ** 2)
                                           * sp.Abs(eps_hat(w_r)), (w_r, -sp.oo, sp.oo))
                               for g, t in zip(Gj, tj, strict=True)) / (2 * sp.pi),
            "error_order_omega": sp.Integer(2),
        },
        notes=("Kelvin-Voigt (G + i eta omega) is the first-order Taylor polynomial of the "
               "complex modulus: the error is O(omega^2 tau_j^2), so the model holds well "
               f"below 1/tau_j. {eta_kv} = sum G_j tau_j.",
               "The paper's error bound (Sect. 4.4): |sigma(t) - sigma_KV(t)| <= "
               "1/(2 pi) sum_j G_j int dw (tau_j w)^2/sqrt(1 + (tau_j w)^2) |eps_hat(w)| "
               "(error_bound), from |int f| <= int |f|, |exp(i w t)| = 1 and the triangle "
               "inequality over the branches; the 1/(2 pi) belongs to the convention "
               "eps(t) = 1/(2 pi) int eps_hat(w) exp(i w t) dw.",
               "Each summand G_j (w tau_j)^2/sqrt(1 + (w tau_j)^2) <= G_j (w tau_j)^2: the bound "
               "is small when the strain spectrum lies well below 1/tau_j (second order).",),
    )


# ------------------------------------------------------------------------------------------
# 3-D generalized Maxwell solid
# ------------------------------------------------------------------------------------------

#: a symmetric strain tensor (the same symbols as the dissipation step's Q)
_Q = sp.Matrix(3, 3, lambda i, k: sp.Symbol(f"Q{min(i, k) + 1}{max(i, k) + 1}", real=True))
#: the branch's viscous strain and its rate (symmetric)
_Qv = sp.Matrix(3, 3, lambda i, k: sp.Symbol(f"Qv{min(i, k) + 1}{max(i, k) + 1}", real=True))
_dQv = sp.Matrix(3, 3, lambda i, k: sp.Symbol(f"dQv{min(i, k) + 1}{max(i, k) + 1}", real=True))


def _sym_entries(Q: sp.Matrix) -> list[sp.Basic]:
    return [Q[i, k] for i in range(3) for k in range(i, 3)]


def isotropic(Q: sp.Matrix, bulk: sp.Expr, shear: sp.Expr) -> sp.Matrix:
    """bulk tr(Q) I + 2 shear dev(Q): the isotropic operator of the dissipation step's (29)
    (moduli [Pa] give a stress from a strain, viscosities [Pa s] from a strain rate)."""
    return viscous_stress(Q, bulk, shear)


def maxwell_material(maxwell_limit_: Step, dissipation: Step) -> Step:
    """3-D isotropic generalized Maxwell solid: internal variables, Laplace moduli, KV limit.

    Equilibrium spring (K_inf, G_inf) in parallel with M branches j; branch j is a spring
    (K_j, G_j) in series with a dashpot (zeta_j, eta_j) = (K_j tau_j, G_j tau_j), i.e. one
    relaxation time tau_j for its bulk and shear parts. Internal variable: the branch's
    viscous strain Qv_j. Moduli [Pa], times [s], s the Laplace variable [1/s].
    """
    s, t = s_lap, sp.Symbol("t", positive=True)
    # (a) series connection: spring stress = dashpot stress, solved for the viscous strain rate
    spring = isotropic(_Q - _Qv, K_j, G_j)
    dashpot = isotropic(_dQv, K_j * tau_j, G_j * tau_j)
    rate = sp.solve(_sym_entries(spring - dashpot), _sym_entries(_dQv), dict=True)[0]
    dQv = _dQv.subs(rate).applyfunc(sp.factor)
    # (b) correspondence principle: Laplace transform of the scalar evolution law (zero history)
    q, qv = sp.Function("q"), sp.Function("q_v")
    ode = sp.diff(qv(t), t) - (q(t) - qv(t)) / tau_j
    lt = sp.laplace_transform(ode, t, s, noconds=True)
    q_hat, qv_hat = sp.symbols("qhat qhat_v")
    lt = lt.subs({sp.LaplaceTransform(q(t), t, s): q_hat,
                  sp.LaplaceTransform(qv(t), t, s): qv_hat, qv(0): 0})
    qv_of_q = sp.solve(lt, qv_hat)[0]                                 # qhat_v / qhat
    ratio = sp.factor(qv_of_q / q_hat)
    Qv_hat = (_Q * ratio)
    sigma_hat = isotropic(_Q - Qv_hat, K_j, G_j).applyfunc(sp.factor)
    K_branch = sp.factor(sp.cancel(sigma_hat.trace() / (3 * _Q.trace())))
    G_branch = sp.factor(sp.cancel(sigma_hat[0, 1] / (2 * _Q[0, 1])))
    isotropy = (sigma_hat - isotropic(_Q, K_branch, G_branch)).applyfunc(sp.cancel)
    # (c) relaxation test: step strain q0 at t = 0 -> branch stress ~ q0 exp(-t/tau_j)
    q0 = sp.Symbol("q_0", positive=True)
    qv_t = sp.dsolve(sp.Eq(sp.diff(qv(t), t), (q0 - qv(t)) / tau_j), qv(t), ics={qv(0): 0}).rhs
    relax = sp.simplify((q0 - qv_t) / q0)                               # spring strain / q0
    shear_relax_branch = G_j * relax
    correspondence = sp.simplify(
        s * sp.laplace_transform(shear_relax_branch, t, s, noconds=True) - G_branch)
    # (d) sum of branches
    to_idx = {G_j: G_br[j_idx], K_j: K_br[j_idx], tau_j: tau_br[j_idx]}
    G_s = G_inf + sp.Sum(G_branch.subs(to_idx), (j_idx, 1, M_br))
    K_s = K_inf + sp.Sum(K_branch.subs(to_idx), (j_idx, 1, M_br))
    G_t = G_inf + sp.Sum(shear_relax_branch.subs(to_idx), (j_idx, 1, M_br))
    # 1-D link: G(i omega) for the maxwell_limit step's N branches is its complex modulus
    n = N_PRONY
    G_1d = G_s.subs(M_br, n).doit().subs(s, sp.I * omega)
    G_1d = G_1d.subs({G_br[i]: sp.Symbol(f"G_{i}", positive=True) for i in range(1, n + 1)})
    G_1d = G_1d.subs({tau_br[i]: sp.Symbol(f"tau_{i}", positive=True) for i in range(1, n + 1)})
    link_1d = sp.cancel(sp.together(G_1d - maxwell_limit_.results["G_hat"]))
    # (e) Kelvin-Voigt limit: stiff, fast branches with eta_j = G_j tau_j, zeta_j = K_j tau_j fixed
    kv_shear = sp.limit(G_branch.subs(G_j, eta_j / tau_j), tau_j, 0)
    kv_bulk = sp.limit(K_branch.subs(K_j, zeta_j / tau_j), tau_j, 0)
    to_kv = {eta_j: eta_br[j_idx], zeta_j: zeta_br[j_idx]}
    G_kv = G_inf + sp.Sum(kv_shear.subs(to_kv), (j_idx, 1, M_br))
    K_kv = K_inf + sp.Sum(kv_bulk.subs(to_kv), (j_idx, 1, M_br))
    # the limit stress against the dissipation step: elastic part + s V_KV : Q
    zeta_tot, eta_tot = zeta, eta
    sigma_kv = isotropic(_Q, K_inf + s * zeta_tot, G_inf + s * eta_tot)
    kv_vs_dissipation = (sigma_kv - isotropic(_Q, K_inf, G_inf)
                         - s * dissipation.results["V_KV_Q"]).applyfunc(sp.expand)
    return make_step(
        name="maxwell_material",
        assumptions=(
            "isotropic linear viscoelastic solid: equilibrium spring (K_inf, G_inf) in parallel "
            "with M Maxwell branches j",
            "branch j: spring (K_j, G_j) in series with a dashpot (K_j tau_j, G_j tau_j): one "
            "relaxation time tau_j for its bulk and deviatoric parts",
            "internal variable: the branch's viscous strain Qv_j, zero before t = 0 "
            "(correspondence principle: d/dt -> s)",
            "Kelvin-Voigt limit: G_j, K_j -> oo, tau_j -> 0 with eta_j = G_j tau_j and "
            "zeta_j = K_j tau_j fixed",
        ),
        symbol_assumptions=("G_inf, K_inf, G_j, K_j, tau_j > 0", "s complex (Laplace variable)"),
        inputs=("maxwell_limit", "dissipation"),
        results={
            "branch_viscous_strain_rate": dQv,
            "evolution_laplace": sp.Eq(qv_hat, qv_of_q),
            "branch_stress_laplace": sigma_hat,
            "G_branch": G_branch,
            "K_branch": K_branch,
            "branch_isotropy_residual": isotropy,
            "branch_relaxation": relax,
            "correspondence_residual": correspondence,
            "G_of_t": G_t,
            "G_of_s": G_s,
            "K_of_s": K_s,
            "G_of_i_omega_minus_G_hat": link_1d,
            "kv_limit_G_branch": kv_shear,
            "kv_limit_K_branch": kv_bulk,
            "G_of_s_kv_limit": G_kv,
            "K_of_s_kv_limit": K_kv,
            "kv_limit_stress_minus_dissipation": kv_vs_dissipation,
        },
        stated={
            "branch_viscous_strain_rate": (_Q - _Qv) / tau_j,
            "G_branch": G_j * s * tau_j / (1 + s * tau_j),
            "K_branch": K_j * s * tau_j / (1 + s * tau_j),
            "branch_isotropy_residual": sp.zeros(3, 3),
            "branch_relaxation": sp.exp(-t / tau_j),
            "correspondence_residual": sp.Integer(0),
            "G_of_s": G_inf + sp.Sum(G_br[j_idx] * s * tau_br[j_idx] / (1 + s * tau_br[j_idx]),
                                     (j_idx, 1, M_br)),
            "G_of_t": G_inf + sp.Sum(G_br[j_idx] * sp.exp(-t / tau_br[j_idx]), (j_idx, 1, M_br)),
            "G_of_i_omega_minus_G_hat": sp.Integer(0),
            "kv_limit_G_branch": eta_j * s,
            "kv_limit_K_branch": zeta_j * s,
            "kv_limit_stress_minus_dissipation": sp.zeros(3, 3),
        },
        notes=(
            "Each branch relaxes as dQv/dt = (Q - Qv)/tau_j; in the Laplace domain "
            "Qv = Q/(1 + s tau_j), so the branch adds G_j s tau_j/(1 + s tau_j) to G(s) and "
            "K_j s tau_j/(1 + s tau_j) to K(s): G(s) = s times the Laplace transform of "
            "G(t), with the Prony relaxation function "
            "G(t) = G_inf + sum_j G_j exp(-t/tau_j) of Sect. 4.4.",
            "On the imaginary axis G(i omega) is the paper's complex modulus (step maxwell_limit).",
            "Kelvin-Voigt limit: G_j s tau_j/(1 + s tau_j) = eta_j s/(1 + s tau_j) -> eta_j s, "
            "so G(s) -> G_inf + s eta and K(s) -> K_inf + s zeta with eta = sum eta_j, "
            "zeta = sum zeta_j: the stress S = H:E + V_KV:dE/dt of the dissipation step (29).",
        ),
    )
