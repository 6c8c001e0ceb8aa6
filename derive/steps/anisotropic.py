"""Anisotropic homogeneous materials in Voigt notation and the rod viscosity they give (issue
25, item 3): the elastic lateral condensation of C, the consistent (dissipation) and naive
(traction) viscosity of extension and bending, and what carries over to shear and torsion.

Voigt order 11, 22, 33, 23, 13, 12 (Voigt indices 1..6; the symbol ``C34`` is the entry of
row 33, column 23), axis 3 along the rod, engineering shear strains (gamma_23 = 2 eps_23, ...):
sigma = C eps + V d(eps)/dt with symmetric 6x6 C [Pa] and V [Pa s]; C44 = G when isotropic.

The paper's assumption carried over: the section deforms with the *elastic* lateral
response. A unit axial strain comes with the lateral strains that leave the lateral
components of the elastic stress zero, w = (e_33, -C_ff^{-1} C_f3); then E_eff = w.C.w,
eta_cons = w.V.w (the dissipation on the elastic mode) and eta_naive = e_33.V.w (the 33-row
of V on the elastic strain rate: the traction route).
"""

from __future__ import annotations

from collections.abc import Sequence

import sympy as sp

from derive.moments import quadratic_form_matrix, section_integral
from derive.step import Step, make_step
from derive.symbols import E, dU1, dU2, dV3, eta, tau_B, tau_S, xi1, xi2, zeta

#: tensor index pairs of the Voigt components, in the order 11, 22, 33, 23, 13, 12
VOIGT_PAIRS = ((0, 0), (1, 1), (2, 2), (1, 2), (0, 2), (0, 1))
#: Voigt position of the axial component 33
AXIAL = 2
#: the general fibre model: 11, 22, 23, 13, 12 stress free (uniaxial stress sigma_33 only)
FIBRE_FREE = (0, 1, 3, 4, 5)
#: the in-plane model: 11, 22, 12 stress free, the out-of-plane shears 23, 13 held
PLANE_FREE = (0, 1, 5)
#: the out-of-plane shears 23, 13 (rod shear and torsion, warping included)
SHEAR = (3, 4)

#: engineering strain vector (Voigt) and a stress vector, for building Voigt matrices
_g = sp.Matrix(sp.symbols("g1:7", real=True))
_s = sp.Matrix(sp.symbols("s1:7", real=True))
#: the symmetric tensor symbols Q11, Q12, ... of steps isotropic_moduli and dissipation
_Q = {(i, j): sp.Symbol(f"Q{i + 1}{j + 1}", real=True) for i in range(3) for j in range(i, 3)}

#: lateral response per unit axial strain (fibre model): w = (w1, w2, 1, w4, w5, w6)
W_FREE = sp.Matrix([sp.Symbol(f"w{i + 1}", real=True) for i in FIBRE_FREE])
#: retardation time of a viscosity proportional to the stiffness, V = tau C [s]
tau = sp.Symbol("tau", positive=True)
#: axial Poisson ratio of a transversely isotropic material (lateral strain per axial strain)
nu_L = sp.Symbol("nu_L", real=True)
#: out-of-plane shear strains of a shear or torsion mode, warping included (any values)
g23, g13 = sp.symbols("gamma_23 gamma_13", real=True)
#: the fibre-wise coefficients eta_cons = w.V.w, eta_naive = e_33.V.w as symbols [Pa s]
ETA_CONS, ETA_NAIVE = sp.symbols("eta_cons eta_naive", real=True)
_e33 = sp.Matrix([0, 0, 1, 0, 0, 0])


def symmetric_voigt(prefix: str) -> sp.Matrix:
    """A general symmetric 6x6 Voigt matrix of symbols ``prefix11`` ... ``prefix66`` (21
    independent entries; diagonal positive, off-diagonal real)."""
    def entry(i: int, j: int) -> sp.Symbol:
        a, b = min(i, j), max(i, j)
        return sp.Symbol(f"{prefix}{a + 1}{b + 1}", **({"positive": True} if a == b
                                                       else {"real": True}))
    return sp.Matrix(6, 6, entry)


def strain_tensor(g: sp.Matrix) -> sp.Matrix:
    """Symmetric strain tensor of an engineering-strain Voigt vector (eps_23 = gamma_23/2)."""
    Q = sp.zeros(3, 3)
    for k, (i, j) in enumerate(VOIGT_PAIRS):
        Q[i, j] = Q[j, i] = g[k] if i == j else g[k] / 2
    return Q


def stress_tensor(s: sp.Matrix) -> sp.Matrix:
    """Symmetric stress tensor of a Voigt stress vector (sigma_23 = s_4, no factor)."""
    S = sp.zeros(3, 3)
    for k, (i, j) in enumerate(VOIGT_PAIRS):
        S[i, j] = S[j, i] = s[k]
    return S


def stress_vector(S: sp.Matrix) -> sp.Matrix:
    """Voigt stress vector of a symmetric tensor."""
    return sp.Matrix([S[i, j] for i, j in VOIGT_PAIRS])


def strain_vector(Q: sp.Matrix) -> sp.Matrix:
    """Engineering-strain Voigt vector of a symmetric tensor (gamma_ij = 2 eps_ij)."""
    return sp.Matrix([Q[i, j] if i == j else 2 * Q[i, j] for i, j in VOIGT_PAIRS])


def voigt_matrix(tensor_law: sp.Matrix) -> sp.Matrix:
    """The 6x6 Voigt matrix of a linear tensor law written in the symbols Q11, Q12, ...

    The law is evaluated on the strain tensor of an engineering-strain vector g and
    differentiated: C = d sigma_Voigt / d g.
    """
    Qg = strain_tensor(_g)
    on_g = tensor_law.subs({q: Qg[i, j] for (i, j), q in _Q.items()}, simultaneous=True)
    return stress_vector(on_g).jacobian(_g).applyfunc(sp.factor)


def voigt_transformations(R: sp.Matrix) -> tuple[sp.Matrix, sp.Matrix]:
    """(T_strain, T_stress): the Voigt images of Q -> R Q R^T for strains and stresses."""
    T_e = strain_vector(R * strain_tensor(_g) * R.T).jacobian(_g)
    T_s = stress_vector(R * stress_tensor(_s) * R.T).jacobian(_s)
    return T_e.applyfunc(sp.nsimplify), T_s.applyfunc(sp.nsimplify)


def invariance_residual(C: sp.Matrix, R: sp.Matrix) -> sp.Matrix:
    """C T_strain - T_stress C: zero iff the law sigma = C eps commutes with the orthogonal
    map R (sigma(R eps R^T) = R sigma(eps) R^T)."""
    T_e, T_s = voigt_transformations(R)
    return (C * T_e - T_s * C).applyfunc(sp.cancel)


def symmetry_class(C: sp.Matrix, maps: Sequence[sp.Matrix],
                   eliminate_first: Sequence[sp.Symbol]) -> sp.Matrix:
    """The general C restricted to the laws invariant under every map in ``maps``.

    The invariance conditions are linear in the entries; they are solved for the entries in
    ``eliminate_first`` order (so the remaining, independent ones are the conventional
    constants).
    """
    eqs = [e for R in maps for e in invariance_residual(C, R) if e != 0]
    rest = [x for x in sorted(C.free_symbols, key=str) if x not in eliminate_first]
    sol = sp.solve(eqs, list(eliminate_first) + rest, dict=True)[0]
    return C.subs(sol).applyfunc(sp.factor)


def lateral_response(C: sp.Matrix, free: Sequence[int]) -> sp.Matrix:
    """3-D strain w of a unit axial strain whose ``free`` components leave the stress
    (C w)_free zero: solves the stress-free lateral conditions, w = (e_33, -C_ff^-1 C_f3)."""
    unknowns = [sp.Dummy(f"w{i + 1}") for i in free]
    w = sp.zeros(6, 1)
    w[AXIAL] = 1
    for k, i in enumerate(free):
        w[i] = unknowns[k]
    sigma = C * w
    sol = sp.solve([sigma[i] for i in free], unknowns, dict=True)[0]
    return w.subs(sol).applyfunc(sp.factor)


def quadratic(w: sp.Matrix, M: sp.Matrix, u: sp.Matrix | None = None) -> sp.Expr:
    """w^T M u (u = w by default), expanded."""
    return sp.expand((w.T * M * (w if u is None else u))[0, 0])


def compliance_column(C: sp.Matrix) -> sp.Matrix:
    """S e_33 = C^-1 e_33 (the strain of a unit axial stress), by solving C x = e_33."""
    x = sp.Matrix(sp.symbols("x1:7"))
    sol = sp.solve(list(C * x - _e33), list(x), dict=True)[0]
    return x.subs(sol).applyfunc(sp.factor)


def _tidy(expr: sp.Expr, keys: Sequence[sp.Symbol] = (zeta, eta, tau_B, tau_S)) -> sp.Expr:
    """Readable form: collected in the viscosities (retardation times), factored otherwise."""
    present = [k for k in keys if expr.has(k)]
    return sp.collect(sp.expand(expr), present, sp.factor) if present else sp.factor(expr)


def _mirror(k: int) -> sp.Matrix:
    R = sp.eye(3)
    R[k, k] = -1
    return R


#: rotation about the rod axis by an angle with cos = 3/5, sin = 4/5: an irrational multiple
#: of pi (Niven), so invariance under it means invariance under every rotation about axis 3
#: (the closed subgroup of SO(2) it generates is infinite, hence all of SO(2))
_ROT3 = sp.Matrix([[sp.Rational(3, 5), -sp.Rational(4, 5), 0],
                   [sp.Rational(4, 5), sp.Rational(3, 5), 0], [0, 0, 1]])


def _renamed(M: sp.Matrix, old: str, new: str) -> sp.Matrix:
    """M with its entry symbols ``old``ij renamed ``new``ij (same assumptions)."""
    return M.xreplace({x: sp.Symbol(new + x.name[len(old):], **x.assumptions0)
                       for x in M.free_symbols if x.name.startswith(old)})


def _class_constants(M: sp.Matrix) -> sp.Integer:
    return sp.Integer(len(M.free_symbols))


def _classes(prefix: str) -> dict[str, sp.Matrix]:
    """Monoclinic about the section plane, orthotropic and transversely isotropic (axis 3)
    Voigt matrices, each the general one restricted by its symmetry maps."""
    M = symmetric_voigt(prefix)

    def s(i, j):
        return M[i - 1, j - 1]
    couplings = [s(i, j) for i in range(1, 7) for j in range(i + 1, 7)
                 if (i, j) not in ((1, 2), (1, 3), (2, 3))]
    # conventional constants kept: C11, C12, C13, C33, C44 (and C22, C23, C55, C66 for the
    # lower symmetries); the rest is eliminated first
    order = couplings + [s(6, 6), s(5, 5), s(2, 3), s(2, 2)]
    return {
        "monoclinic": symmetry_class(M, [_mirror(2)], order),
        "orthotropic": symmetry_class(M, [_mirror(0), _mirror(1), _mirror(2)], order),
        "transversely_isotropic": symmetry_class(M, [_mirror(0), _mirror(1), _mirror(2),
                                                     _ROT3], order),
    }


def voigt_materials(isotropic_moduli: Step, dissipation: Step, naive_resultants: Step) -> Step:
    """Voigt matrices: isotropic C, V from the SVK and Kelvin-Voigt laws; symmetry classes."""
    lame = {sp.Symbol("lambda", positive=True): isotropic_moduli.results["lambda"],
            sp.Symbol("mu", positive=True): isotropic_moduli.results["mu"]}
    C_lame = voigt_matrix(isotropic_moduli.results["S_SVK"])
    C_iso = C_lame.subs(lame).applyfunc(sp.factor)
    V_iso = voigt_matrix(dissipation.results["V_KV_Q"])
    S33_iso = compliance_column(C_iso)[AXIAL]
    C_cls = _classes("C")
    V_cls = {k: _renamed(M, "C", "V") for k, M in C_cls.items()}
    C_ti = C_cls["transversely_isotropic"]
    # the Lame form of V: lambda_v J + mu_v diag(2, 2, 2, 1, 1, 1) with the ANCF constants
    lam_v, mu_v = naive_resultants.results["ancf_lambda_v"], naive_resultants.results["ancf_mu_v"]
    J = sp.zeros(6, 6)
    J[:3, :3] = sp.ones(3, 3)
    V_ancf = lam_v * J + mu_v * sp.diag(2, 2, 2, 1, 1, 1)
    return make_step(
        name="voigt_materials",
        assumptions=(
            "Voigt order 11, 22, 33, 23, 13, 12 (indices 1..6), axis 3 along the rod, "
            "engineering shear strains gamma_ij = 2 eps_ij; stress sigma = C eps + V deps/dt",
            "isotropic C: the SVK law (23) with the moduli of isotropic_moduli; isotropic V: "
            "the Kelvin-Voigt law (29)",
            "a symmetry class is the general symmetric C restricted by invariance "
            "sigma(R eps R^T) = R sigma(eps) R^T under its maps: monoclinic = mirror "
            "x3 -> -x3 (symmetric about the section plane: e.g. an orthotropic material "
            "turned about the rod axis, or fibres lying in the section plane); orthotropic = "
            "the three mirrors; transversely isotropic (fibres along the axis) = orthotropic "
            "and every rotation about axis 3",
        ),
        symbol_assumptions=("C_ii, V_ii > 0; C_ij, V_ij real (i != j)",
                            "C symmetric positive definite, V symmetric positive semidefinite"),
        inputs=("isotropic_moduli", "dissipation", "naive_resultants"),
        results={
            "C_isotropic": C_iso,
            "V_isotropic": V_iso,
            "C_isotropic_shear_entries": sp.Matrix([C_iso[3, 3], C_iso[4, 4], C_iso[5, 5]]),
            "V_isotropic_shear_entries": sp.Matrix([V_iso[3, 3], V_iso[4, 4], V_iso[5, 5]]),
            "S33_isotropic": S33_iso,
            "C_monoclinic": C_cls["monoclinic"],
            "C_orthotropic": C_cls["orthotropic"],
            "C_transversely_isotropic": C_ti,
            "V_transversely_isotropic": V_cls["transversely_isotropic"],
            "constants_monoclinic": _class_constants(C_cls["monoclinic"]),
            "constants_orthotropic": _class_constants(C_cls["orthotropic"]),
            "constants_transversely_isotropic": _class_constants(C_ti),
            "isotropic_rotation_residual": invariance_residual(C_iso, _ROT3),
        },
        stated={
            "C_isotropic_shear_entries": sp.Matrix([isotropic_moduli.results["G"]] * 3),
            "V_isotropic_shear_entries": sp.Matrix([eta] * 3),
            "S33_isotropic": 1 / E,
            "V_isotropic": V_ancf,
            "constants_monoclinic": sp.Integer(13),
            "constants_orthotropic": sp.Integer(9),
            "constants_transversely_isotropic": sp.Integer(5),
            "isotropic_rotation_residual": sp.zeros(6, 6),
        },
        notes=(
            "C44 = C55 = C66 = G: the engineering-shear convention (the brief of issue 25).",
            "V_isotropic is the Lame form lambda_v J + mu_v diag(2, 2, 2, 1, 1, 1) with the "
            "ANCF constants lambda_v = zeta - 2 eta/3, mu_v = eta of step naive_resultants.",
            "Transversely isotropic: C66 = (C11 - C12)/2, C22 = C11, C23 = C13, C55 = C44; "
            "5 constants. The isotropic C is in the class (rotation residual zero).",
        ),
    )


def _general_in_lateral_response() -> tuple[sp.Matrix, sp.Matrix, sp.Matrix, dict]:
    """(C, C_param, w, C_f3 solution): the general C, the same C with its coupling column
    C_f3 written through the lateral response w_f (C_f3 = -C_ff w_f, the stress-free
    conditions solved for C_f3 instead of w_f), and w = (w1, w2, 1, w4, w5, w6).

    Every C with C_ff invertible (every positive definite C) is of this form, with
    w_f = -C_ff^-1 C_f3; the rod quantities are then polynomials, not rational functions of
    21 entries.
    """
    C = symmetric_voigt("C")
    w = sp.zeros(6, 1)
    w[AXIAL] = 1
    for k, i in enumerate(FIBRE_FREE):
        w[i] = W_FREE[k]
    sigma = C * w
    coupling = [C[i, AXIAL] for i in FIBRE_FREE]
    sol = sp.solve([sigma[i] for i in FIBRE_FREE], coupling, dict=True)[0]
    return C, C.subs(sol), w, sol


def _substitution(general: sp.Matrix, special: sp.Matrix) -> dict:
    """{entry symbol of the general matrix: the special matrix's entry} (for xreplace; the
    entries of ``general`` that are not symbols are left out)."""
    return {general[i, j]: special[i, j] for i in range(6) for j in range(i, 6)
            if general[i, j].is_Symbol}


def _w_substitution(w_special: sp.Matrix) -> dict:
    return {W_FREE[k]: w_special[i] for k, i in enumerate(FIBRE_FREE)}


def elastic_condensation(voigt_materials: Step, lateral_contraction: Step) -> Step:
    """w = (e_33, -C_ff^-1 C_f3), E_eff = w.C.w = 1/S_33; isotropic, transversely isotropic,
    orthotropic and monoclinic cases; the in-plane model against the fibre model."""
    C, C_par, w, sol = _general_in_lateral_response()
    E_eff = quadratic(w, C_par)
    compliance_residual = (C_par * w - E_eff * _e33).applyfunc(sp.expand)
    C_iso = voigt_materials.results["C_isotropic"]
    w_iso = lateral_response(C_iso, FIBRE_FREE)
    iso = {**_substitution(C, C_iso), **_w_substitution(w_iso)}
    E_iso = sp.factor(E_eff.xreplace(iso))
    H1, H2, H3 = sp.symbols("H1 H2 H3", real=True)
    E_ulc = lateral_contraction.results["E_prime"].subs({H1: 0, H2: 0, H3: 1})
    C_ti = voigt_materials.results["C_transversely_isotropic"]
    w_ti = lateral_response(C_ti, FIBRE_FREE)
    S_ti = compliance_column(C_ti)
    E_L = sp.factor(E_eff.xreplace({**_substitution(C, C_ti), **_w_substitution(w_ti)}))
    C_o = voigt_materials.results["C_orthotropic"]
    w_o = lateral_response(C_o, FIBRE_FREE)
    C_m = voigt_materials.results["C_monoclinic"]
    w_m_plane = lateral_response(C_m, PLANE_FREE)
    # the in-plane mode of the general C, its lateral strains kept as symbols wbar_i (they
    # solve the in-plane conditions); what it leaves in sigma_23, sigma_13
    w_plane = sp.zeros(6, 1)
    w_plane[AXIAL] = 1
    for i in PLANE_FREE:
        w_plane[i] = sp.Symbol(f"wbar_{i + 1}", real=True)
    return make_step(
        name="elastic_condensation",
        assumptions=(
            "homogeneous material, small strain; a fibre (a point of the section) strained "
            "axially by eps_33 takes the lateral strains of the elastic response",
            "fibre model (uniaxial stress; Saint-Venant extension and pure bending of a "
            "homogeneous anisotropic prism): the free components 11, 22, 23, 13, 12 are "
            "stress free, sigma_11 = sigma_22 = sigma_12 = sigma_23 = sigma_13 = 0; "
            "eps_f = -C_ff^-1 C_f3 eps_33",
            "in-plane model: only 11, 22, 12 free (sigma_11 = sigma_22 = sigma_12 = 0), the "
            "out-of-plane shears 23, 13 (the rod's shear and twist strains) held; the two "
            "agree iff the in-plane mode leaves sigma_23 = sigma_13 = 0, e.g. for every "
            "material symmetric about the section plane",
            "isotropic: the uniform lateral contraction (24) of the paper",
        ),
        symbol_assumptions=("C symmetric positive definite, so C_ff is invertible",
                            "w1, w2, w4, w5, w6 real: w_f = -C_ff^-1 C_f3"),
        inputs=("voigt_materials", "lateral_contraction"),
        results={
            "w_fibre": w,
            "stress_free_conditions": (C * w).extract(list(FIBRE_FREE), [0]),
            "C_f3_of_w": sp.Matrix([sol[C[i, AXIAL]] for i in FIBRE_FREE]),
            "E_eff": E_eff,
            "compliance_residual": compliance_residual,
            "w_isotropic": w_iso,
            "E_eff_isotropic": E_iso,
            "w_plane_isotropic": lateral_response(C_iso, PLANE_FREE),
            "w_transversely_isotropic": w_ti,
            "nu_L": sp.factor(-w_ti[0]),
            "E_L": E_L,
            "w_orthotropic": w_o,
            "fibre_minus_plane_orthotropic": (w_o - lateral_response(C_o, PLANE_FREE))
            .applyfunc(sp.cancel),
            "shear_stress_of_plane_mode_monoclinic": (C_m * w_m_plane).extract(
                list(SHEAR), [0]).applyfunc(sp.cancel),
            "w_plane": w_plane,
            "plane_conditions": (C * w_plane).extract(list(PLANE_FREE), [0]),
            "shear_stress_of_plane_mode": (C * w_plane).extract(list(SHEAR), [0]),
        },
        stated={
            "compliance_residual": sp.zeros(6, 1),
            "w_isotropic": strain_vector(E_ulc),
            "E_eff_isotropic": E,
            "w_plane_isotropic": strain_vector(E_ulc),
            "nu_L": -S_ti[0] / S_ti[AXIAL],
            "E_L": 1 / S_ti[AXIAL],
            "fibre_minus_plane_orthotropic": sp.zeros(6, 1),
            "shear_stress_of_plane_mode_monoclinic": sp.zeros(2, 1),
        },
        notes=(
            "C_f3_of_w: the stress-free conditions solved for the coupling column, "
            "C_f3 = -C_ff w_f. Every positive definite C is of this form with "
            "w_f = -C_ff^-1 C_f3, so E_eff, and the viscosities of the next step, are "
            "polynomials in (C_ff, C33, w_f) for the fully general C (21 entries).",
            "compliance_residual = C w - E_eff e_33 = 0: C^-1 e_33 = w / E_eff, i.e. "
            "S_33 = 1/E_eff and w = S e_33 / S_33 (the strain of a uniaxial stress).",
            "Isotropic: w = (-nu, -nu, 1, 0, 0, 0), the uniform lateral contraction (24), "
            "and E_eff = E. Transversely isotropic (fibres along the axis): "
            "nu_L = C13/(C11 + C12), E_L = C33 - 2 C13^2/(C11 + C12) = 1/S33.",
            "shear_stress_of_plane_mode: sigma_23, sigma_13 of the in-plane mode w_plane "
            "(wbar_1, wbar_2, wbar_6 solve plane_conditions = 0) for the general C; where they are "
            "non-zero (e.g. a fibre tilted out of the section plane: C34, C35 != 0) the fibre and "
            "in-plane models then differ, and the in-plane mode is the rod's Gamma_3 entry at "
            "held shear strains (the section solver's stiffness entry), the fibre mode its "
            "condensation at zero shear force and torque.",
        ),
    )


def _rod_rows(density_2x: sp.Expr, traction_33: sp.Expr) -> tuple[sp.Matrix, sp.Matrix]:
    """Consistent and naive rod rows (extension Gamma_3, bending K_1, K_2) of a fibre-wise
    density ``density_2x`` = 2 Psi and axial viscous stress ``traction_33`` on the section
    fields, both written in dH3 = dV3 + xi2 dU1 - xi1 dU2 (31).

    Consistent: the quadratic form of <2 Psi> in (dV3, dU1, dU2); naive: d(F3, M1, M2)/d
    (dV3, dU1, dU2) with F3 = <S33>, M1 = <xi2 S33>, M2 = <-xi1 S33> (Sect. 4.2).
    """
    rates = [dV3, dU1, dU2]
    consistent = quadratic_form_matrix(section_integral(density_2x), rates)
    resultants = sp.Matrix([section_integral(traction_33), section_integral(xi2 * traction_33),
                            section_integral(-xi1 * traction_33)])
    return consistent, resultants.jacobian(rates)


def anisotropic_viscosity(isotropic_moduli: Step, dissipation: Step, naive_resultants: Step,
                          voigt_materials: Step, elastic_condensation: Step) -> Step:
    """eta_cons = w.V.w and eta_naive = e_33.V.w for a general C and V; their reduction to
    eta_E (5), tau_E (6), eta~_E; V = tau C; transversely isotropic closed forms; the rod's
    extension and bending rows."""
    C, C_par, w, _ = _general_in_lateral_response()
    V = symmetric_voigt("V")
    E_eff = elastic_condensation.results["E_eff"]
    Vw = (V * w).applyfunc(sp.expand)
    cons = quadratic(w, V)
    naive = Vw[AXIAL]
    lateral_stress = Vw.extract(list(FIBRE_FREE), [0])
    power = sp.expand(sum(W_FREE[k] * lateral_stress[k] for k in range(len(FIBRE_FREE))))
    # V = tau C, C any positive definite matrix (in the lateral-response form)
    tauC = {V[i, j]: tau * C_par[i, j] for i in range(6) for j in range(i, 6)}
    # isotropic: C, V and w of the earlier steps
    C_iso, V_iso = voigt_materials.results["C_isotropic"], voigt_materials.results["V_isotropic"]
    w_iso = elastic_condensation.results["w_isotropic"]
    iso = {**_substitution(V, V_iso), **_w_substitution(w_iso)}
    cons_iso, naive_iso = _tidy(cons.xreplace(iso)), _tidy(naive.xreplace(iso))
    E_iso = elastic_condensation.results["E_eff_isotropic"]
    in_taus = {eta: isotropic_moduli.results["G"] * tau_S, zeta: isotropic_moduli.results["K"]
               * tau_B}
    # transversely isotropic (fibres along the axis), with nu_L = C13/(C11 + C12)
    C_ti, V_ti = (voigt_materials.results["C_transversely_isotropic"],
                  voigt_materials.results["V_transversely_isotropic"])
    w_ti = elastic_condensation.results["w_transversely_isotropic"]
    ti = {**_substitution(V, V_ti), **_w_substitution(w_ti)}
    cons_ti, naive_ti = sp.factor(cons.xreplace(ti)), sp.factor(naive.xreplace(ti))
    E_L = elastic_condensation.results["E_L"]
    C13 = C_ti[0, 2]
    V11, V12, V13, V33 = V_ti[0, 0], V_ti[0, 1], V_ti[0, 2], V_ti[2, 2]
    C13_of_nuL = sp.solve(sp.Eq(elastic_condensation.results["nu_L"], nu_L), C13)[0]
    viscous_terms = [V33, V13, V11, V12]

    def in_nu_L(expr):
        poly = sp.Poly(sp.cancel(expr.xreplace({C13: C13_of_nuL})), *viscous_terms)
        return sum((sp.factor(c) * sp.prod(v**k for v, k in zip(viscous_terms, m, strict=True))
                    for m, c in poly.terms()), sp.Integer(0))
    ti_at_iso = {**_substitution(C_ti, C_iso), **_substitution(V_ti, V_iso)}
    ti_tauC = _substitution(V_ti, tau * C_ti)
    # orthotropic with explicit entries: V = tau C
    C_o = voigt_materials.results["C_orthotropic"]
    w_o = elastic_condensation.results["w_orthotropic"]
    E_o = sp.factor(quadratic(w_o, C_o))
    cons_o_tauC = quadratic(w_o, tau * C_o)
    # the rod's extension and bending rows: the fibre mode's strain rate w dH3 on the
    # section field dH3 (31); per unit coefficient, and for the isotropic material
    # (the general coefficients enter as the symbols eta_cons, eta_naive: they are constants
    # over a homogeneous section, and factoring the 21-term polynomials is slow)
    dH3 = dissipation.results["dH"][2]
    rows_c, rows_n = _rod_rows(sp.expand(ETA_CONS * dH3**2), sp.expand(ETA_NAIVE * dH3))
    rows_c_iso, rows_n_iso = _rod_rows(sp.expand(cons_iso * dH3**2),
                                       sp.expand(naive_iso * dH3))
    V_F, V_M = dissipation.results["V_F"], dissipation.results["V_M"]
    naive_rows = naive_resultants.results["resultants"].extract([2, 3, 4], [0]).jacobian(
        [dV3, dU1, dU2])
    return make_step(
        name="anisotropic_viscosity",
        assumptions=(
            "homogeneous Kelvin-Voigt material sigma = C eps + V deps/dt, C symmetric "
            "positive definite, V symmetric positive semidefinite (21 entries each)",
            "the section deforms with the ELASTIC lateral response (step "
            "elastic_condensation, fibre model): the 3-D strain rate of an axial strain "
            "rate dH3 is w dH3, w = (e_33, -C_ff^-1 C_f3)",
            "consistent: the dissipation on that mode, 2 Psi = eta_cons dH3^2 with "
            "eta_cons = w.V.w; naive (traction route): S33 = eta_naive dH3 with "
            "eta_naive = e_33.V.w",
            "extension and bending: dH3 = dV3 + xi2 dU1 - xi1 dU2 (31) is linear over the "
            "section, so the fibre-wise coefficients carry over with the section moments "
            "(centroid at the origin, principal axes: <xi_a> = <xi1 xi2> = 0)",
        ),
        symbol_assumptions=("C_ff invertible: w_f = -C_ff^-1 C_f3, C_f3 = -C_ff w_f",
                            "tau > 0: V = tau C", "tau_S = eta/G, tau_B = zeta/K"),
        inputs=("isotropic_moduli", "dissipation", "naive_resultants", "voigt_materials",
                "elastic_condensation"),
        results={
            "eta_cons": cons,
            "eta_naive": naive,
            "lateral_viscous_stress": lateral_stress,
            "eta_cons_minus_naive": sp.expand(cons - naive),
            "eta_cons_V_tau_C": sp.factor_terms(sp.expand(cons.xreplace(tauC))),
            "eta_naive_V_tau_C": sp.factor_terms(sp.expand(naive.xreplace(tauC))),
            "lateral_viscous_stress_V_tau_C": lateral_stress.xreplace(tauC).applyfunc(sp.expand),
            "eta_E_isotropic": cons_iso,
            "eta_E_naive_isotropic": naive_iso,
            "eta_cons_minus_naive_isotropic": sp.factor(cons_iso - naive_iso),
            "tau_E_isotropic": _tidy(cons_iso.subs(in_taus) / E_iso),
            "tau_E_naive_isotropic": _tidy(naive_iso.subs(in_taus) / E_iso),
            "eta_cons_transversely_isotropic": cons_ti,
            "eta_naive_transversely_isotropic": naive_ti,
            "eta_cons_transversely_isotropic_in_nu_L": in_nu_L(cons_ti),
            "eta_naive_transversely_isotropic_in_nu_L": in_nu_L(naive_ti),
            "eta_cons_minus_naive_transversely_isotropic_in_nu_L": sp.factor(
                in_nu_L(cons_ti - naive_ti)),
            "tau_E_transversely_isotropic": sp.factor(cons_ti / E_L),
            "eta_cons_transversely_isotropic_at_isotropic": _tidy(
                cons_ti.xreplace(ti_at_iso)),
            "eta_naive_transversely_isotropic_at_isotropic": _tidy(
                naive_ti.xreplace(ti_at_iso)),
            "eta_cons_transversely_isotropic_V_tau_C": sp.factor(cons_ti.xreplace(ti_tauC)),
            "eta_naive_transversely_isotropic_V_tau_C": sp.factor(naive_ti.xreplace(ti_tauC)),
            "eta_cons_orthotropic_V_tau_C": sp.factor(cons_o_tauC),
            "rod_normal_viscosity": rows_c,
            "rod_normal_naive": rows_n,
            "rod_normal_viscosity_isotropic": rows_c_iso,
            "rod_normal_naive_isotropic": rows_n_iso,
        },
        stated={
            "eta_cons_minus_naive": power,
            "eta_cons_V_tau_C": tau * E_eff,
            "eta_naive_V_tau_C": tau * E_eff,
            "lateral_viscous_stress_V_tau_C": sp.zeros(len(FIBRE_FREE), 1),
            "eta_E_isotropic": dissipation.results["eta_E"],
            "eta_E_naive_isotropic": naive_resultants.results["eta_E_naive"],
            "eta_cons_minus_naive_isotropic": naive_resultants.results["eta_E_minus_naive"],
            "tau_E_isotropic": dissipation.results["tau_E"],
            "tau_E_naive_isotropic": naive_resultants.results["tau_E_naive"],
            "eta_cons_transversely_isotropic_in_nu_L": V33 - 4 * nu_L * V13
                                                       + 2 * nu_L**2 * (V11 + V12),
            "eta_naive_transversely_isotropic_in_nu_L": V33 - 2 * nu_L * V13,
            "eta_cons_transversely_isotropic_at_isotropic": dissipation.results["eta_E"],
            "eta_naive_transversely_isotropic_at_isotropic":
                naive_resultants.results["eta_E_naive"],
            "eta_cons_transversely_isotropic_V_tau_C": tau * E_L,
            "eta_naive_transversely_isotropic_V_tau_C": tau * E_L,
            "eta_cons_orthotropic_V_tau_C": tau * E_o,
            "rod_normal_viscosity_isotropic": sp.diag(V_F[2, 2], V_M[0, 0], V_M[1, 1]),
            "rod_normal_naive_isotropic": naive_rows,
        },
        notes=(
            "eta_cons - eta_naive = w_f . (V w)_f: the power of the viscous lateral stresses "
            "of the elastic mode on its lateral strain rates, which no traction integral "
            "sees (Sect. 4.2, for any C and V). The elastic lateral stresses (C w)_f vanish "
            "by construction, so the stiffnesses of both routes agree.",
            "V = tau C, C fully general (21 entries, in the lateral-response form of step "
            "elastic_condensation): the lateral viscous stresses vanish and "
            "eta_cons = eta_naive = tau E_eff = tau / S_33.",
            "eta_cons = w.V.w >= 0 for V positive semidefinite. eta_cons >= eta_naive does NOT "
            "hold in general: isotropic, eta_E - eta~_E = -2 nu ((1 - 2 nu) zeta - "
            "2 (1 + nu) eta / 3), negative when tau_B > tau_S and 0 < nu < 1/2.",
            "Transversely isotropic (fibres along the axis), nu_L = C13/(C11 + C12): "
            "eta_cons = V33 - 4 nu_L V13 + 2 nu_L^2 (V11 + V12), "
            "eta_naive = V33 - 2 nu_L V13, tau_E = eta_cons / E_L.",
            "Rod rows (Gamma_3, K_1, K_2): consistent diag(A, I1, I2) eta_cons, naive "
            "diag(A, I1, I2) eta_naive, as (4) with eta_E and eta~_E. For a general "
            "anisotropic C the fibre mode also strains 23, 13 (w4, w5 != 0): those are the "
            "rod's shear and twist rates following the elastic response (zero shear force "
            "and torque); at held shear strains use the in-plane mode of step "
            "elastic_condensation (the section solver's entries).",
        ),
    )


def _shear_mode() -> sp.Matrix:
    """3-D strain of a shear or torsion mode at a point: out-of-plane shears only
    (gamma_23, gamma_13 any values, the Saint-Venant warping included)."""
    g = sp.zeros(6, 1)
    g[SHEAR[0]], g[SHEAR[1]] = g23, g13
    return g


#: the components a shear mode must leave stress free laterally (and axially: no sigma_33)
_NOT_SHEAR = tuple(i for i in range(6) if i not in SHEAR)


def anisotropic_shear(isotropic_moduli: Step, dissipation: Step, voigt_materials: Step) -> Step:
    """Shear and torsion: when the out-of-plane shear block of V is tau times that of C and
    decoupled from the rest, any warping dissipates tau times its energy, so (8) follows;
    otherwise the warping solution (the section solver) is needed."""
    g = _shear_mode()
    C_iso, V_iso = voigt_materials.results["C_isotropic"], voigt_materials.results["V_isotropic"]
    C_ti, V_ti = (voigt_materials.results["C_transversely_isotropic"],
                  voigt_materials.results["V_transversely_isotropic"])
    C_o = voigt_materials.results["C_orthotropic"]
    V_o = _renamed(C_o, "C", "V")
    C = symmetric_voigt("C")
    in_tau_S = {eta: isotropic_moduli.results["G"] * tau_S}

    def ratio(V_: sp.Matrix, C_: sp.Matrix) -> sp.Expr:
        return sp.factor(sp.cancel(quadratic(g, V_) / quadratic(g, C_)))
    ratio_o = ratio(V_o, C_o)
    # the ratio is the same for every shear field iff its derivative along the field vanishes
    condition = sp.factor(sp.numer(sp.together(sp.diff(ratio_o, g13))))
    V55 = V_o[4, 4]
    (V55_free,) = sp.solve(condition, V55)
    tau_F, tau_M = dissipation.results["tau_matrix_F"], dissipation.results["tau_matrix_M"]
    return make_step(
        name="anisotropic_shear",
        assumptions=(
            "the shear and torsion modes strain a point only in the out-of-plane shears "
            "gamma_23, gamma_13 (rod shear V_a, twist U_3 and the Saint-Venant warping w_3 "
            "of the ELASTIC solution); these must leave 11, 22, 33, 12 stress free, else the "
            "mode carries its own lateral condensation and in-plane warping",
            "isotropic and transversely isotropic (fibres along the axis): that holds, and "
            "the shear block of V is tau times that of C, so every warping field (whatever "
            "the shape) dissipates tau times its elastic energy: gamma_S = tau GA_a, "
            "gamma_T = tau GJ_T with the corrected stiffnesses (7), (8)",
            "general anisotropic C or V (shear block not proportional, e.g. orthotropic with "
            "V44/C44 != V55/C55, or coupled to 11, 22, 33, 12: C14, C15, ... != 0): the "
            "shear and torsion viscosities need the warping solution of the section "
            "(runtime/section, the section solver); no closed form is claimed here",
        ),
        symbol_assumptions=("gamma_23, gamma_13 real: any shear field, warping included",
                            "tau_S = eta/G"),
        inputs=("isotropic_moduli", "dissipation", "voigt_materials"),
        results={
            "shear_mode": g,
            "lateral_stress_of_shear_mode_isotropic": (C_iso * g).extract(list(_NOT_SHEAR),
                                                                         [0]),
            "viscous_minus_tau_S_elastic_stress_isotropic": (V_iso * g - tau_S * C_iso * g)
            .xreplace(in_tau_S).applyfunc(sp.cancel),
            "shear_viscosity_over_stiffness_isotropic": ratio(V_iso, C_iso).subs(in_tau_S),
            "torsion_viscosity_over_stiffness_isotropic": ratio(V_iso, C_iso).subs(in_tau_S),
            "lateral_stress_of_shear_mode_transversely_isotropic": (C_ti * g).extract(
                list(_NOT_SHEAR), [0]),
            "shear_viscosity_over_stiffness_transversely_isotropic": ratio(V_ti, C_ti),
            "shear_viscosity_over_stiffness_orthotropic": ratio_o,
            "field_independence_condition_orthotropic": condition,
            "V55_for_field_independence_orthotropic": V55_free,
            "lateral_stress_of_shear_mode": (C * g).extract(list(_NOT_SHEAR), [0]),
        },
        stated={
            "lateral_stress_of_shear_mode_isotropic": sp.zeros(4, 1),
            "viscous_minus_tau_S_elastic_stress_isotropic": sp.zeros(6, 1),
            "shear_viscosity_over_stiffness_isotropic": tau_F[0, 0],
            "torsion_viscosity_over_stiffness_isotropic": tau_M[2, 2],
            "lateral_stress_of_shear_mode_transversely_isotropic": sp.zeros(4, 1),
            "shear_viscosity_over_stiffness_transversely_isotropic": V_ti[3, 3] / C_ti[3, 3],
            "V55_for_field_independence_orthotropic": V_o[3, 3] * C_o[4, 4] / C_o[3, 3],
        },
        notes=(
            "Isotropic: the viscous stress of any shear field is tau_S times its elastic "
            "stress, pointwise, so the dissipation of the (elastic) warping field is tau_S "
            "times its energy for every section shape: gamma_S,a = tau_S GA kappa_a, "
            "gamma_T = tau_S GJ_T, the paper's (8). The traction route agrees: with V = tau C "
            "on the mode, <Z.V.W> = tau <Z.C.W> = tau <W.C.W> since the elastic warping is "
            "self-equilibrated (C-orthogonal to W - Z); consistent = naive for shear, torsion.",
            "Transversely isotropic (fibres along the axis): the same with "
            "tau_L = V44/C44 (the axial shear retardation time); the torsion warping is the "
            "isotropic one (only C44 = C55 enters), so gamma_T = tau_L C44 J_T.",
            "Orthotropic: the ratio depends on the field (the warping) unless "
            "V44/C44 = V55/C55; general anisotropy couples the shear mode to 11, 22, 33, 12 "
            "(lateral_stress_of_shear_mode): the section solver's warping solution decides.",
            "The transverse-shear factor kappa_a in (7)-(8) is the paper's geometric "
            "correction; the energy-based factor of Saint-Venant flexure also contains the "
            "in-plane (Poisson) part of the flexure warping, which this pointwise argument "
            "does not cover (the section solver computes it).",
        ),
    )
