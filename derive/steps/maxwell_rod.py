"""Rod-level relaxation of a generalized Maxwell Cosserat rod (the paper's future work).

The cross-section reasoning of Sect. 3.4 carried into the Laplace domain: uniform lateral
contraction with a lateral ratio nu(s) chosen so that the in-plane stress vanishes, which
gives the uniaxial modulus E(s) = 9 K(s) G(s) / (3 K(s) + G(s)) for extension and bending and
G(s) for shear and torsion. For the Maxwell moduli of step maxwell_material, E(s) is a
rational function of s; its partial fractions give the rod's own Prony series

    E(s) = E_inf + sum_k E_k s theta_k / (1 + s theta_k),

with 2M relaxation times: the branch times tau_j (modulus E_j = 9 K_j G_j / (3 K_j + G_j))
and the M times theta_k = -1/s_k at the zeros s_k of D(s) = 3 K(s) + G(s), whose moduli come
from the residue formula E_k = -3 G(s_k)^2 / (s_k D'(s_k)). The zeros are real, negative and
interlace the branch poles -1/tau_j: they are the eigenvalues of a symmetric positive
semidefinite diagonal-plus-rank-one matrix (secular equation).
"""

from __future__ import annotations

from collections.abc import Sequence

import sympy as sp

from derive.moments import section_integral
from derive.step import Step, make_step
from derive.steps.energy import (
    DELTA_U,
    DELTA_V,
    SHEAR_CORRECTION_F,
    SHEAR_CORRECTION_M,
    TO_DELTAS,
    shear_correct,
    substitute_H,
)
from derive.steps.maxwell import isotropic
from derive.symbols import (
    H1,
    H2,
    H3,
    I1,
    I2,
    I3,
    A,
    E,
    G,
    G_br,
    G_inf,
    G_j,
    G_of,
    K,
    K_br,
    K_inf,
    K_j,
    K_of,
    M_br,
    e3,
    j_idx,
    kappa_1,
    kappa_2,
    kappa_3,
    nu,
    nu_of,
    s_lap,
    tau_br,
    tau_j,
    xi1,
    xi2,
)

#: symbols of the residue formulas: a zero s_k of D(s) = 3K(s) + G(s), the values K(s_k),
#: G(s_k), the derivatives K'(s_k), G'(s_k) and D'(s_k) = 3K'(s_k) + G'(s_k)
s_k = sp.Symbol("s_k", negative=True)
K_k, G_k = sp.symbols("K_k G_k", real=True)
dK_k, dG_k, dD_k = sp.symbols("dK_k dG_k dD_k", positive=True)
#: Prony term of the rod: modulus E_k [Pa], relaxation time theta_k [s]
E_k, theta_k = sp.symbols("E_k theta_k", positive=True)
#: coefficients of the secular function D(s) = c_inf + sum_j c_j s tau_j / (1 + s tau_j)
c_inf, c_j = sp.symbols("c_inf c_j", positive=True)

#: numbers of the worked M = 2 example (moduli in units of G_inf, times in units of tau_1)
M2_EXAMPLE = {"K_inf": 3, "G_inf": 1, "K": (2, 5), "G": (1, 2), "tau": (1, sp.Rational(1, 10))}


def maxwell_moduli(M: int, K_sym: Sequence | None = None, G_sym: Sequence | None = None,
                   tau_sym: Sequence | None = None) -> tuple[sp.Expr, sp.Expr]:
    """(K(s), G(s)) [Pa] of M explicit branches: step maxwell_material's sums written out with
    symbols K_1.., G_1.. [Pa], tau_1.. [s] (or the given values); s the Laplace variable [1/s]."""
    K_sym = K_sym or sp.symbols(f"K_1:{M + 1}", positive=True)
    G_sym = G_sym or sp.symbols(f"G_1:{M + 1}", positive=True)
    tau_sym = tau_sym or sp.symbols(f"tau_1:{M + 1}", positive=True)
    b = [s_lap * t / (1 + s_lap * t) for t in tau_sym]
    return (K_inf + sum(k * f for k, f in zip(K_sym, b, strict=True)),
            G_inf + sum(g * f for g, f in zip(G_sym, b, strict=True)))


def prony_terms(rational: sp.Expr) -> tuple[sp.Expr, list[tuple[sp.Expr, sp.Expr]]]:
    """(E_inf, [(E_k, theta_k), ...]) of a proper-plus-constant rational function of s with
    simple poles, read off its partial fractions (``apart``); moduli [Pa], times [s].

    Each pole term r/(s - p) of the decomposition is written as
    E_k s theta_k/(1 + s theta_k) - E_k with theta_k = -1/p and E_k = r/p (the residue of
    E_k s theta/(1 + s theta) at s = -1/theta is -E_k/theta); E_inf = E(0). A term
    r(s)/q(s) whose denominator ``apart`` leaves irreducible over the rationals (numerical
    coefficients) gives one Prony term per root p of q, with residue r(p)/q'(p).
    """
    parts = sp.Add.make_args(sp.apart(rational, s_lap))
    terms = []
    for term in parts:
        if not term.has(s_lap):
            continue
        num, den = sp.fraction(sp.together(term))
        for p in sp.solve(den, s_lap):
            r = sp.radsimp(num.subs(s_lap, p) / sp.diff(den, s_lap).subs(s_lap, p))
            terms.append((sp.factor(sp.radsimp(r / p)), sp.factor(sp.radsimp(-1 / p))))
    return sp.factor(rational.subs(s_lap, 0)), terms


def prony_sum(E0: sp.Expr, terms: list[tuple[sp.Expr, sp.Expr]]) -> sp.Expr:
    """E_inf + sum_k E_k s theta_k/(1 + s theta_k)."""
    return E0 + sum((e * s_lap * th / (1 + s_lap * th) for e, th in terms), sp.Integer(0))


def _resultant_stiffness(S: sp.Matrix, kinematics: Step) -> tuple[sp.Matrix, sp.Matrix]:
    """Laplace-domain rod stiffnesses from Simo's resultants F_i = <S_i3>, M_1 = <xi2 S_33>,
    M_2 = <-xi1 S_33>, M_3 = <xi1 S_23 - xi2 S_13> of a stress linear in H (17)."""

    def on_section(expr):
        return substitute_H(sp.expand(expr), kinematics)

    F = [section_integral(on_section(S[i, 2])) for i in range(3)]
    M = [section_integral(on_section(xi2 * S[2, 2])),
         section_integral(on_section(-xi1 * S[2, 2])),
         section_integral(on_section(xi1 * S[1, 2] - xi2 * S[0, 2]))]
    res = sp.Matrix(F + M).applyfunc(lambda c: sp.expand(c.subs(TO_DELTAS, simultaneous=True)))
    jac = res.jacobian(sp.Matrix(list(DELTA_V) + list(DELTA_U)))
    if jac[:3, 3:] != sp.zeros(3, 3) or jac[3:, :3] != sp.zeros(3, 3):
        raise AssertionError("the Laplace-domain resultants couple forces and moments")
    if res.subs({d: 0 for d in list(DELTA_V) + list(DELTA_U)}) != sp.zeros(6, 1):
        raise AssertionError("the Laplace-domain resultants have a residual part")

    def tidy(c: sp.Expr) -> sp.Expr:
        return sp.factor(c).subs(I1 + I2, I3)

    return jac[:3, :3].applyfunc(tidy), jac[3:, 3:].applyfunc(tidy)


def secular_matrix(M: int) -> tuple[sp.Matrix, sp.Expr]:
    """(T, residual) for M branches with rates lambda_j = 1/tau_j [1/s].

    T = diag(lambda_j) - z z^T / c_0 with z_j^2 = c_j lambda_j and c_0 = c_inf + sum c_j;
    residual = det(s I + T) - prod(s + lambda_j) D(s) / c_0 with
    D(s) = c_inf + sum c_j s/(s + lambda_j) (= 3K(s) + G(s)), zero for every s when the zeros
    of D are the eigenvalues of -T. The determinant is taken with z_j as symbols and
    z_j^2 = c_j lambda_j substituted afterwards (only squares occur: diagonal plus rank one).
    """
    cs = sp.symbols(f"c_1:{M + 1}", positive=True)
    lams = sp.symbols(f"lambda_1:{M + 1}", positive=True)
    zs = sp.symbols(f"z_1:{M + 1}", positive=True)
    c0 = c_inf + sum(cs)
    z = sp.Matrix(zs)
    T = sp.diag(*lams) - z * z.T / c0
    det = sp.expand((s_lap * sp.eye(M) + T).det(method="berkowitz") * c0)
    det = det.subs({zj**2: c * lam for zj, c, lam in zip(zs, cs, lams, strict=True)})
    D = c_inf + sum(c * s_lap / (s_lap + lam) for c, lam in zip(cs, lams, strict=True))
    P = sp.prod([s_lap + lam for lam in lams])
    residual = sp.cancel(det - sp.cancel(P * D)) / c0
    return T, residual


def maxwell_rod(kinematics: Step, lateral_contraction: Step, isotropic_moduli: Step,
                stored_energy: Step, maxwell_material: Step) -> Step:
    """Laplace-domain rod stiffnesses C_F(s) [N], C_M(s) [N m^2] ((7) with E(s), G(s)), the
    lateral-stress-free E(s) [Pa] ((24) with nu(s)) and the rod's Prony series of E(s)."""
    s = s_lap
    Kf, Gf, nuf = K_of(s), G_of(s), nu_of(s)
    # (a) uniform lateral contraction with lateral ratio nu(s), lateral stress free
    Ep = lateral_contraction.results["E_prime"].subs(nu, nuf)
    S = isotropic(Ep, Kf, Gf).applyfunc(sp.expand)
    (nu_s,) = sp.solve(S[0, 0], nuf)
    nu_s = sp.factor(nu_s)
    S_free = S.subs(nuf, nu_s).applyfunc(sp.factor)
    E_s = sp.factor(sp.cancel(S_free[2, 2] / H3))
    compliance = sp.expand(sp.apart(sp.cancel(1 / E_s), Kf))
    # elastic check: constant K, G of the isotropic_moduli step
    const = {Kf: isotropic_moduli.results["K"], Gf: isotropic_moduli.results["G"]}
    E_elastic = sp.factor(E_s.subs(const))
    nu_elastic = sp.factor(nu_s.subs(const))
    # (b) resultants -> C_F(s), C_M(s); geometric shear corrections of (7)
    CF_raw, CM_raw = _resultant_stiffness(S_free, kinematics)
    C_F = shear_correct(CF_raw, SHEAR_CORRECTION_F)
    C_M = shear_correct(CM_raw, SHEAR_CORRECTION_M)
    to_const = {Kf: K, Gf: G}
    E_of_KG = E_s.subs(to_const)
    elastic_vs_stored = (C_F.subs(to_const) - stored_energy.results["C_F_corrected"]
                         .subs(E, E_of_KG)).row_join(
        C_M.subs(to_const) - stored_energy.results["C_M_corrected"].subs(E, E_of_KG))
    elastic_vs_stored = elastic_vs_stored.applyfunc(sp.cancel)
    # (c) Maxwell moduli: secular function D(s) = 3K(s) + G(s), its coefficients, limits
    Gb, Kb = maxwell_material.results["G_branch"], maxwell_material.results["K_branch"]
    factor_b = sp.cancel(Gb / G_j)                                   # s tau_j/(1 + s tau_j)
    d_branch = sp.factor(3 * Kb + Gb)
    c_branch = sp.factor(sp.cancel(d_branch / factor_b))             # c_j = 3 K_j + G_j
    c_eq = sp.factor((3 * Kf + Gf).subs({Kf: K_inf, Gf: G_inf}))     # c_inf = 3 K_inf + G_inf
    to_idx = {G_j: G_br[j_idx], K_j: K_br[j_idx], tau_j: tau_br[j_idx]}
    D_s = c_eq + sp.Sum(d_branch.subs(to_idx), (j_idx, 1, M_br))
    dD_branch = sp.factor(sp.diff(d_branch, s))
    dD_s = sp.Sum(dD_branch.subs(to_idx), (j_idx, 1, M_br))
    b0, b_oo = sp.limit(factor_b, s, 0), sp.limit(factor_b, s, sp.oo)
    K_0 = K_inf + sp.Sum(K_br[j_idx] * b0, (j_idx, 1, M_br)).doit()
    G_0 = G_inf + sp.Sum(G_br[j_idx] * b0, (j_idx, 1, M_br)).doit()
    K_oo = K_inf + sp.Sum(K_br[j_idx] * b_oo, (j_idx, 1, M_br))
    G_oo = G_inf + sp.Sum(G_br[j_idx] * b_oo, (j_idx, 1, M_br))
    E_inf_ = sp.factor(E_s.subs({Kf: K_0, Gf: G_0}))
    E_inst = E_s.xreplace({Kf: K_oo, Gf: G_oo})
    # (d) residue formulas. Prony term <-> pole: residue of E_k s theta/(1 + s theta) at -1/theta
    res_term = sp.residue(E_k * s * theta_k / (1 + s * theta_k), s, -1 / theta_k)
    (E_of_res,) = sp.solve(sp.Eq(res_term, sp.Symbol("R")), E_k)
    E_of_res = E_of_res.subs(theta_k, -1 / s_k)                       # E_k = R / s_k
    # zero s_k of D: K = K_k + K'_k h, G = G_k + G'_k h with 3 K_k + G_k = 0
    h = sp.Symbol("h")
    near_zero = {Kf: K_k + dK_k * h, Gf: -3 * K_k + dG_k * h}
    R_zero = sp.factor(sp.limit(h * E_s.subs(near_zero), h, 0))
    E_root = sp.factor(E_of_res.subs(sp.Symbol("R"), R_zero))
    E_root_G = sp.factor(E_root.subs(K_k, -G_k / 3).subs(3 * dK_k + dG_k, dD_k))
    # branch pole p_j = -1/tau_j: K = a/h + k0, G = g/h + g0 (k0, g0: the other branches)
    p_j = sp.solve(sp.denom(factor_b), s)[0]
    a_j, g_j = sp.residue(Kb, s, p_j), sp.residue(Gb, s, p_j)
    k0, g0 = sp.symbols("k_0 g_0")
    R_pole = sp.factor(sp.limit(h * E_s.subs({Kf: a_j / h + k0, Gf: g_j / h + g0}), h, 0))
    E_branch = sp.factor(sp.cancel(E_of_res.subs(sp.Symbol("R"), R_pole).subs(s_k, p_j)))
    # (e) M = 1, symbolic: partial fractions against the formulas
    K1, G1 = maxwell_moduli(1)
    K_1, G_1, tau_1 = sp.symbols("K_1 G_1 tau_1", positive=True)
    E1 = sp.cancel(sp.together(E_s.subs({Kf: K1, Gf: G1})))
    E1_inf, E1_terms = prony_terms(E1)
    E1_terms.sort(key=lambda et: sp.count_ops(et[1]))                 # tau_1 first
    (s_1,) = sp.solve(sp.numer(sp.together(3 * K1 + G1)), s)
    at_root = {s_k: s_1, G_k: G1.subs(s, s_1),
               dD_k: sp.diff(3 * K1 + G1, s).subs(s, s_1)}
    formula_terms = [(E_branch.subs({K_j: K_1, G_j: G_1}), tau_1),
                     (E_root_G.subs(at_root), -1 / s_1)]
    m1_check = sp.Matrix([sp.factor(sp.factor(a) / sp.factor(b)) for t1, t2 in
                          zip(E1_terms, formula_terms, strict=True)
                          for a, b in zip(t1, t2, strict=True)])
    m1_sum = sp.cancel(prony_sum(E1_inf, E1_terms) - E1)
    # (f) M = 2 with numbers: exact partial fractions, interlacing, positivity, formulas
    ex = M2_EXAMPLE
    vals = {K_inf: ex["K_inf"], G_inf: ex["G_inf"]}
    K2, G2 = maxwell_moduli(2, ex["K"], ex["G"], ex["tau"])
    K2, G2 = K2.subs(vals), G2.subs(vals)
    E2 = sp.cancel(sp.together(E_s.subs({Kf: K2, Gf: G2})))
    E2_inf, E2_terms = prony_terms(E2)             # apart over Q, the quadratic split by roots
    E2_terms.sort(key=lambda et: float(et[1]))
    m2_sum = sp.radsimp(sp.cancel(prony_sum(E2_inf, E2_terms) - E2))
    roots2 = sp.solve(sp.numer(sp.together(3 * K2 + G2)), s)
    formula2 = [(E_branch.subs({K_j: k, G_j: g}), t)
                for k, g, t in zip(ex["K"], ex["G"], ex["tau"], strict=True)]
    formula2 += [(E_root_G.subs({s_k: r, G_k: G2.subs(s, r),
                                 dD_k: sp.diff(3 * K2 + G2, s).subs(s, r)}), -1 / r)
                 for r in roots2]
    formula2.sort(key=lambda et: float(et[1]))
    m2_check = sp.Matrix([sp.radsimp(sp.nsimplify(a - b)) for t1, t2 in
                          zip(E2_terms, formula2, strict=True)
                          for a, b in zip(t1, t2, strict=True)])
    theta2 = sp.Matrix([th for _, th in E2_terms])
    E2_k = sp.Matrix([sp.N(e, 15) for e, _ in E2_terms])
    E2_0 = E_s.subs({Kf: K2.limit(s, sp.oo), Gf: G2.limit(s, sp.oo)})
    # (g) real, negative, interlacing zeros: the secular matrix
    T2, det2 = secular_matrix(2)
    _, det3 = secular_matrix(3)
    w = sp.Matrix(sp.symbols("w_1:3", positive=True))                # w_j = sqrt(c_j)
    c0_w = c_inf + (w.T * w)[0, 0]
    psd_residual = ((sp.eye(2) - w * w.T / c0_w) * w - c_inf / c0_w * w).applyfunc(sp.cancel)
    E_lit = 9 * Kf * Gf / (3 * Kf + Gf)          # the literature's uniaxial modulus, compared
    Hv = sp.Matrix([H1, H2, H3])
    return make_step(
        name="maxwell_rod",
        assumptions=(
            "uniform lateral contraction (24) in the Laplace domain: E'_aa = -nu(s) H3, with "
            "nu(s) fixed by a stress-free lateral surface, S'_11 = S'_22 = 0",
            "Simo's resultants of the Laplace-domain stress; the same section moments and "
            "geometric shear corrections (7) as the elastic rod",
            "Maxwell moduli of step maxwell_material; distinct branch times tau_j",
        ),
        symbol_assumptions=("s complex (Laplace variable)", "G_inf, K_inf, G_j, K_j, tau_j > 0",
                            "s_k < 0 a simple zero of D(s) = 3K(s) + G(s)"),
        inputs=("kinematics", "lateral_contraction", "isotropic_moduli", "stored_energy",
                "maxwell_material"),
        results={
            "nu_of_s": nu_s,
            "S_laplace": S_free,
            "E_of_s": E_s,
            "compliance_1_over_E": compliance,
            "E_elastic": E_elastic,
            "nu_elastic": nu_elastic,
            "C_F_laplace": C_F,
            "C_M_laplace": C_M,
            "elastic_limit_minus_stored_energy": elastic_vs_stored,
            "secular_coefficient_c_j": c_branch,
            "secular_coefficient_c_inf": c_eq,
            "D_of_s": D_s,
            "dD_ds": dD_s,
            "E_inf": E_inf_,
            "E_instantaneous": E_inst,
            "prony_E_from_residue": E_of_res,
            "residue_at_zero_of_D": R_zero,
            "prony_E_root": E_root,
            "prony_E_root_in_G": E_root_G,
            "residue_at_branch_pole": R_pole,
            "prony_E_branch": E_branch,
            "M1_E_of_s": sp.factor(E1),
            "M1_E_inf": E1_inf,
            "M1_prony_terms": sp.Matrix([[e, th] for e, th in E1_terms]),
            "M1_prony_sum_minus_E": m1_sum,
            "M1_apart_over_formulas": m1_check,
            "M2_example_E_of_s": E2,
            "M2_example_theta": theta2,
            "M2_example_E_k": E2_k,
            "M2_example_E_inf": E2_inf,
            "M2_example_E_instantaneous": E2_0,
            "M2_example_prony_sum_minus_E": m2_sum,
            "M2_example_apart_minus_formulas": m2_check,
            "secular_matrix_M2": T2,
            "secular_det_identity_M2": det2,
            "secular_det_identity_M3": det3,
            "secular_psd_residual": psd_residual,
        },
        stated={
            "nu_of_s": (3 * Kf - 2 * Gf) / (2 * (3 * Kf + Gf)),
            "E_of_s": E_lit,
            "compliance_1_over_E": 1 / (3 * Gf) + 1 / (9 * Kf),
            "E_elastic": E,
            "nu_elastic": nu,
            "S_laplace": E_lit * H3 * e3 * e3.T
                         + Gf * (Hv * e3.T + e3 * Hv.T - 2 * H3 * e3 * e3.T),
            "C_F_laplace": sp.diag(kappa_1 * A * Gf, kappa_2 * A * Gf, A * E_lit),
            "C_M_laplace": sp.diag(I1 * E_lit, I2 * E_lit, kappa_3 * I3 * Gf),
            "elastic_limit_minus_stored_energy": sp.zeros(3, 6),
            "E_inf": 9 * K_inf * G_inf / (3 * K_inf + G_inf),
            "M1_prony_sum_minus_E": sp.Integer(0),
            "M1_apart_over_formulas": sp.ones(4, 1),
            "M2_example_prony_sum_minus_E": sp.Integer(0),
            "M2_example_apart_minus_formulas": sp.zeros(8, 1),
            "secular_det_identity_M2": sp.Integer(0),
            "secular_det_identity_M3": sp.Integer(0),
            "secular_psd_residual": sp.zeros(2, 1),
        },
        notes=(
            "nu(s) follows from S'_11 = 0 alone (S'_22 = S'_12 = 0 then hold too): the lateral "
            "contraction relaxes with the material. With it the in-plane stress vanishes for "
            "every s, so the resultant route and an energy route agree, and extension and "
            "bending carry the uniaxial E(s) = 9 K(s) G(s)/(3 K(s) + G(s)) "
            "(1/E = 1/(9K) + 1/(3G)), shear and torsion G(s). At constant moduli this is "
            "the stored_energy step's C_F, C_M.",
            "Prony series of E(s): poles at the branch times, E_k = 9 K_j G_j/(3 K_j + G_j) "
            "(the branch's own Young's modulus; the other branches are regular there, k_0 and "
            "g_0 drop out), and at the zeros s_k of D(s) = 3K(s) + G(s), theta_k = -1/s_k, "
            "E_k = -3 G(s_k)^2/(s_k D'(s_k)) > 0 since s_k < 0 and D' > 0. Up to 2M terms; "
            "E(0) = E_inf and E_inf + sum_k E_k = E(oo), the instantaneous modulus.",
            "The zeros of D are real, negative and interlace the branch poles: with "
            "c_j = 3K_j + G_j > 0, D(s) = c_inf + sum_j c_j s tau_j/(1 + s tau_j) increases "
            "(dD/ds > 0) between consecutive poles from -oo to +oo (one zero in each gap), from "
            "-oo to D(0) = c_inf > 0 right of the slowest pole (one zero in (-1/tau_max, 0)), and "
            "from D(-oo) = c_0 > 0 to +oo left of the fastest one (no zero): "
            "theta_1 > tau_(1) > theta_2 > tau_(2) > ... > theta_M > tau_(M) for "
            "tau_(1) > ... > tau_(M). Equivalently the -s_k are the eigenvalues of the "
            "symmetric matrix T = diag(1/tau_j) - z z^T/c_0, z_j^2 = c_j/tau_j "
            "(secular_det_identity for M = 2, 3; the matrix determinant lemma for any M), and "
            "T = L^(1/2) (I - w w^T/c_0) L^(1/2) with eigenvalues 1 and c_inf/c_0 >= 0 of the "
            "middle factor (secular_psd_residual): T is positive semidefinite.",
            "M = 1: the zero's modulus 27 (G_1 K_inf - G_inf K_1)^2 / ((3K_1 + G_1)(3K_inf + "
            "G_inf)(3K_0 + G_0)), K_0 = K_inf + K_1, G_0 = G_inf + G_1, vanishes iff branch "
            "and equilibrium part share a Poisson ratio (K_1/G_1 = K_inf/G_inf): then E(s) is "
            "proportional to G(s).",
            "M = 2 is decomposed with numbers (moduli in units of G_inf, times in units of "
            "tau_1; a symbolic apart for M = 2 takes ~45 s): thetas 1/10 < 0.19 < 1 < 1.78 "
            "interlace the branch times, all E_k > 0, and apart agrees exactly with the residue "
            "formulas.",
        ),
    )
