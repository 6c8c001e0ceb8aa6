"""The formula table: the derivation's end results under stable names.

Every entry is taken from a derived step result (never typed in). Symbols are those of
:mod:`derive.symbols`: ``E, nu, G, K, eta, zeta, tau_S, tau_B, A, I1, I2, I3, kappa_1,
kappa_2, kappa_3`` and, for the densities, ``V1..U3``, ``U01..U03``, ``dV1..dU3``; for the
generalized Maxwell entries the Laplace variable ``s``, ``G_inf, K_inf``, one branch's
``G_j, K_j, tau_j`` (or the indexed ``G[j], K[j], tau[j]`` of a sum over j = 1..M), the functions
``G(s), K(s)``, and at a zero ``s_k`` of D(s) = 3K(s) + G(s) the values ``G_k`` = G(s_k) and
``dD_k`` = D'(s_k).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from derive.pipeline import run

# SymPy and the step modules are imported by the functions: importing the derive package
# (e.g. for ``kvrod derive list``) must not pay for them.
if TYPE_CHECKING:
    import sympy as sp

FORMULA_DOCS: dict[str, str] = {
    "eta_E": "extensional viscosity from the dissipation function (5) [Pa s]",
    "eta_E_naive": "extensional viscosity of the naive resultant route eta~_E [Pa s]",
    "tau_E": "extensional retardation time eta_E/E (6) [s]",
    "tau_E_naive": "naive extensional retardation time eta~_E/E [s]",
    "in_plane_dissipation": "coefficient of (dH3)^2 in the in-plane dissipation missed by "
                            "the resultant route, eta_E - eta~_E [Pa s]",
    "C_F": "force stiffness matrix, shear-corrected (7) [N]",
    "C_M": "moment stiffness matrix, torsion-corrected (7) [N m^2]",
    "V_F": "force damping matrix, shear-corrected (8)-(9) [N s]",
    "V_M": "moment damping matrix, torsion-corrected (8)-(9) [N m^2 s]",
    "V_F_naive": "force damping matrix of the naive resultant route, shear-corrected [N s]",
    "V_M_naive": "moment damping matrix of the naive resultant route [N m^2 s]",
    "stored_energy_density_2x": "2 <Psi_SVK>_A, the integrand of (10) with (2) [N]",
    "dissipation_density_2x": "2 <Psi_KV>_A, the integrand of (11) with (3)-(4) [N/s]",
    "G_of_E": "shear modulus E/(2(1+nu)) [Pa]",
    "K_of_E": "bulk modulus E/(3(1-2nu)) [Pa]",
    "lambda_of_E": "Lame constant [Pa]",
    "eta_of_tau": "shear viscosity G tau_S [Pa s]",
    "zeta_of_tau": "bulk viscosity K tau_B [Pa s]",
    # generalized Maxwell solid and rod (steps maxwell_material, maxwell_rod)
    "maxwell_branch_shear": "one Maxwell branch's share of G(s): G_j s tau_j/(1 + s tau_j) [Pa]",
    "maxwell_branch_bulk": "one Maxwell branch's share of K(s): K_j s tau_j/(1 + s tau_j) [Pa]",
    "maxwell_G_of_s": "Laplace-domain shear modulus G_inf + sum_j G_j s tau_j/(1 + s tau_j) [Pa]",
    "maxwell_K_of_s": "Laplace-domain bulk modulus K_inf + sum_j K_j s tau_j/(1 + s tau_j) [Pa]",
    "E_of_KG": "lateral-stress-free uniaxial modulus 9 K G/(3 K + G) [Pa] (K, G may be K(s), "
               "G(s))",
    "nu_of_KG": "lateral contraction ratio (3 K - 2 G)/(2 (3 K + G)) [-]",
    "C_F_laplace": "Laplace-domain force stiffness diag(kappa_1 A G(s), kappa_2 A G(s), "
                   "A E(s)) [N]",
    "C_M_laplace": "Laplace-domain moment stiffness diag(I1 E(s), I2 E(s), kappa_3 I3 G(s)) "
                   "[N m^2]",
    "maxwell_E_inf": "equilibrium uniaxial modulus E(0) = 9 K_inf G_inf/(3 K_inf + G_inf) [Pa]",
    "maxwell_E_instantaneous": "instantaneous uniaxial modulus E(s -> oo) [Pa]",
    "secular_coefficient_inf": "c_inf = 3 K_inf + G_inf, D(0) of D(s) = 3 K(s) + G(s) [Pa]",
    "secular_coefficient": "c_j = 3 K_j + G_j, branch j's weight in D(s) [Pa]",
    "secular_derivative_branch": "branch j's share of D'(s): c_j tau_j/(1 + s tau_j)^2 [Pa s]",
    "prony_E_branch": "rod Prony modulus at the branch time tau_j: 9 K_j G_j/(3 K_j + G_j) [Pa]",
    "prony_E_root": "rod Prony modulus at theta_k = -1/s_k, D(s_k) = 0: "
                    "-3 G(s_k)^2/(s_k D'(s_k)) [Pa]",
    # the 3-D Kelvin-Voigt solid's exact uniaxial modulus (step kelvin_voigt_uniaxial)
    "kv_E_of_s": "exact uniaxial modulus of the 3-D Kelvin-Voigt solid E(s) [Pa]",
    "kv_tau_E": "first-order retardation time of kv_E_of_s, equal to tau_E (6) [s]",
    "kv_tau_D": "pole time of kv_E_of_s: E(s) has its pole at -1/tau_D [s]",
    "kv_remainder": "E(s) - E (1 + s tau_E), O(s^2), zero iff tau_B = tau_S [Pa]",
}


def tidy(expr: sp.Basic) -> sp.Basic:
    """Readable normal form: collect in the viscosities/retardation times, factor the rest."""
    import sympy as sp

    from derive.symbols import eta, tau_B, tau_S, zeta

    if isinstance(expr, sp.MatrixBase):
        return expr.applyfunc(tidy)
    present = [v for v in (zeta, eta, tau_B, tau_S) if expr.has(v)]
    if not present:
        return sp.factor(expr)
    return sp.collect(sp.expand(expr), present, sp.factor)


def formulas() -> dict[str, sp.Basic]:
    """The derived results the generated code is rendered from (computed once per process
    from the step records).

    Returns
    -------
    dict of str to sympy.Basic
        Name -> SymPy expression (a 3x3 Matrix for C_F, C_M, V_F, V_M and their
        variants), e.g. ``"eta_E"`` (eq. (5)), ``"tau_E"`` (eq. (6)), ``"eta_E_naive"``.
    """
    global _table
    if _table is None:
        _table = _formulas()
    return dict(_table)


_table: dict | None = None


def forget() -> None:
    """Drop the table kept for this process (:func:`derive.pipeline.forget` drops the
    records it is computed from)."""
    global _table
    _table = None


def _formulas() -> dict[str, sp.Basic]:
    import sympy as sp

    from derive.steps.energy import SHEAR_CORRECTION_F, SHEAR_CORRECTION_M, shear_correct
    from derive.symbols import G, G_of, K, K_of, s_lap, tau_B, tau_S

    steps = run()
    moduli, energy = steps["isotropic_moduli"], steps["stored_energy"]
    diss, naive = steps["dissipation"], steps["naive_resultants"]
    mat, rod, kvu = steps["maxwell_material"], steps["maxwell_rod"], steps["kelvin_voigt_uniaxial"]
    laplace_to_constant = {K_of(s_lap): K, G_of(s_lap): G}
    res = naive.results["resultants"]
    rates = sp.symbols("dV1 dV2 dV3 dU1 dU2 dU3", real=True)
    V_naive = res.jacobian(sp.Matrix(rates)).applyfunc(
        lambda c: sp.factor(c).subs(sp.Symbol("I1", positive=True)
                                    + sp.Symbol("I2", positive=True),
                                    sp.Symbol("I3", positive=True)))
    table = {
        "eta_E": diss.results["eta_E"],
        "eta_E_naive": naive.results["eta_E_naive"],
        "tau_E": diss.results["tau_E"],
        "tau_E_naive": naive.results["tau_E_naive"],
        "in_plane_dissipation": naive.results["in_plane_dissipation"],
        "C_F": energy.results["C_F_corrected"],
        "C_M": energy.results["C_M_corrected"],
        "V_F": diss.results["V_F_corrected"],
        "V_M": diss.results["V_M_corrected"],
        "V_F_naive": shear_correct(V_naive[:3, :3], SHEAR_CORRECTION_F),
        "V_M_naive": shear_correct(V_naive[3:, 3:], SHEAR_CORRECTION_M),
        "stored_energy_density_2x": energy.results["stored_energy_density_2x"],
        "dissipation_density_2x": diss.results["dissipation_density_2x"],
        "G_of_E": moduli.results["G"],
        "K_of_E": moduli.results["K"],
        "lambda_of_E": moduli.results["lambda"],
        "eta_of_tau": G * tau_S,
        "zeta_of_tau": K * tau_B,
        "maxwell_branch_shear": mat.results["G_branch"],
        "maxwell_branch_bulk": mat.results["K_branch"],
        "maxwell_G_of_s": mat.results["G_of_s"],
        "maxwell_K_of_s": mat.results["K_of_s"],
        "E_of_KG": rod.results["E_of_s"].subs(laplace_to_constant),
        "nu_of_KG": rod.results["nu_of_s"].subs(laplace_to_constant),
        "C_F_laplace": rod.results["C_F_laplace"],
        "C_M_laplace": rod.results["C_M_laplace"],
        "maxwell_E_inf": rod.results["E_inf"],
        "maxwell_E_instantaneous": rod.results["E_instantaneous"],
        "secular_coefficient_inf": rod.results["secular_coefficient_c_inf"],
        "secular_coefficient": rod.results["secular_coefficient_c_j"],
        "secular_derivative_branch": rod.results["dD_ds"].function,
        "prony_E_branch": rod.results["prony_E_branch"],
        "prony_E_root": rod.results["prony_E_root_in_G"],
        "kv_E_of_s": kvu.results["E_of_s"],
        "kv_tau_E": kvu.results["tau_E_exact"],
        "kv_tau_D": kvu.results["tau_D"],
        "kv_remainder": kvu.results["remainder"],
    }
    keep = ("stored_energy_density_2x", "dissipation_density_2x", "maxwell_G_of_s",
            "maxwell_K_of_s", "maxwell_E_instantaneous", "C_F_laplace", "C_M_laplace",
            "secular_derivative_branch", "kv_E_of_s", "kv_remainder")
    return {k: (v if k in keep else tidy(v)) for k, v in table.items()}


def in_material_parameters(expr: sp.Basic) -> sp.Basic:
    """Rewrite an expression in E, nu, tau_S, tau_B (eta = G tau_S, zeta = K tau_B,
    G and K from the isotropic moduli), cancelling (1 - 2 nu) where it divides."""
    import sympy as sp

    from derive.symbols import G, K, eta, tau_B, tau_S, zeta

    f = formulas()
    sub = {eta: G * tau_S, zeta: K * tau_B}
    moduli = {G: f["G_of_E"], K: f["K_of_E"]}
    out = expr.subs(sub).subs(moduli)
    if isinstance(out, sp.MatrixBase):
        return out.applyfunc(lambda c: sp.factor(sp.cancel(c)))
    return sp.factor(sp.cancel(out))
