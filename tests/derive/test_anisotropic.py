"""Steps voigt_materials, elastic_condensation, anisotropic_viscosity, anisotropic_shear
(issue 25, item 3): the symbolic reductions, V = tau C, positivity, the (missing) order of
consistent and naive, and the closed forms against a direct NumPy computation."""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

from derive import step
from derive.symbols import E, eta, nu, tau_B, tau_S, zeta

#: Voigt order 11, 22, 33, 23, 13, 12 (NumPy side, written here independently of derive/)
PAIRS = ((0, 0), (1, 1), (2, 2), (1, 2), (0, 2), (0, 1))
FREE = [0, 1, 3, 4, 5]


def numeric(expr: sp.Basic, values: dict[str, float]) -> np.ndarray:
    """Evaluate a step result at values given by symbol name."""
    syms = sorted(expr.free_symbols, key=str)
    f = sp.lambdify(syms, expr, "numpy")
    return np.array(f(*(values[s.name] for s in syms)), dtype=float)


def matrix_values(prefix: str, M: np.ndarray) -> dict[str, float]:
    """{'C11': M[0, 0], 'C12': M[0, 1], ...} for the symbols of a Voigt matrix."""
    return {f"{prefix}{i + 1}{j + 1}": M[i, j] for i in range(6) for j in range(i, 6)}


def random_spd(rng: np.random.Generator, scale: float = 1.0) -> np.ndarray:
    B = rng.normal(size=(6, 6))
    return scale * (B @ B.T + 0.3 * np.eye(6))


def random_psd(rng: np.random.Generator, rank: int) -> np.ndarray:
    B = rng.normal(size=(6, rank))
    return B @ B.T


def uniaxial_response(C: np.ndarray) -> tuple[np.ndarray, float]:
    """(w, E_eff) from the compliance: the strain of a unit axial stress, scaled to a unit
    axial strain (the lateral surface of a fibre free: sigma = sigma_33 e_33 only)."""
    eps = np.linalg.solve(C, np.eye(6)[2])
    return eps / eps[2], 1.0 / eps[2]


def plane_response(C: np.ndarray) -> np.ndarray:
    """w with 11, 22, 12 stress free and 23, 13 held at zero (the in-plane model)."""
    p = [0, 1, 5]
    w = np.zeros(6)
    w[2] = 1.0
    w[p] = np.linalg.solve(C[np.ix_(p, p)], -C[p, 2])
    return w


def rotated(C6: np.ndarray, R: np.ndarray) -> np.ndarray:
    """Voigt matrix of the law turned by R (through the 4th-order tensor; engineering shear
    strains, so C_ijkl = C6[I(ij), J(kl)])."""
    C4 = np.empty((3, 3, 3, 3))
    for a, (i, j) in enumerate(PAIRS):
        for b, (k, m) in enumerate(PAIRS):
            for ii, jj in {(i, j), (j, i)}:
                for kk, mm in {(k, m), (m, k)}:
                    C4[ii, jj, kk, mm] = C6[a, b]
    C4r = np.einsum("ia,jb,kc,ld,abcd->ijkl", R, R, R, R, C4)
    return np.array([[C4r[i, j, k, m] for k, m in PAIRS] for i, j in PAIRS])


def rotation(axis: int, degrees: float) -> np.ndarray:
    c, s = np.cos(np.radians(degrees)), np.sin(np.radians(degrees))
    a, b = [k for k in range(3) if k != axis]
    R = np.eye(3)
    R[a, a], R[a, b], R[b, a], R[b, b] = c, -s, s, c
    return R


# --- symbolic reductions -------------------------------------------------------------------

@pytest.mark.parametrize("key", [
    "eta_E_isotropic", "eta_E_naive_isotropic", "tau_E_isotropic", "tau_E_naive_isotropic",
    "eta_cons_minus_naive_isotropic", "eta_cons_transversely_isotropic_at_isotropic",
    "rod_normal_viscosity_isotropic", "rod_normal_naive_isotropic",
    "eta_cons_V_tau_C", "eta_naive_V_tau_C", "eta_cons_orthotropic_V_tau_C",
    "eta_cons_transversely_isotropic_V_tau_C", "eta_naive_transversely_isotropic_V_tau_C"])
def test_reductions_hold(key):
    s = step("anisotropic_viscosity")
    assert s.matches[key], key


def test_isotropic_reduces_to_the_earlier_steps_results():
    """The general w.V.w on the isotropic C, V is the dissipation step's eta_E (5), whose
    own record matches the paper's printed form; likewise the naive route."""
    s = step("anisotropic_viscosity").results
    diss, naive = step("dissipation"), step("naive_resultants")
    assert sp.simplify(s["eta_E_isotropic"] - diss.stated["eta_E"]) == 0
    assert sp.simplify(s["eta_E_naive_isotropic"] - naive.stated["eta_E_naive"]) == 0
    assert sp.simplify(s["tau_E_isotropic"] - diss.stated["tau_E"]) == 0
    c = step("elastic_condensation").results
    assert c["E_eff_isotropic"] == E
    assert list(c["w_isotropic"]) == [-nu, -nu, 1, 0, 0, 0]


def test_general_V_tau_C_with_all_21_entries():
    """Independent of the step's lateral-response parametrization: the general symmetric C
    with its 21 entries, w_f = -adj(C_ff) C_f3 / det(C_ff) explicitly; with V = tau C the
    naive e33.V.w equals the consistent w.V.w (so both are tau E_eff): w.C.w - e33.C.w =
    w_f.(C w)_f = 0 identically (a polynomial identity after clearing det(C_ff)^2)."""
    C = sp.Matrix(6, 6, lambda i, j: sp.Symbol(f"c{min(i, j)}{max(i, j)}"))
    Cff = C.extract(FREE, FREE)
    det = Cff.det(method="berkowitz")
    wf = -Cff.adjugate() * C.extract(FREE, [2])
    w = sp.zeros(6, 1)
    w[2] = det
    for k, i in enumerate(FREE):
        w[i] = wf[k]
    Cw = C * w
    assert sp.expand((w.T * Cw)[0, 0] - det * Cw[2]) == 0
    # the free stresses vanish, so det * E_eff = (C w)_33: E_eff is the Schur complement
    assert all(sp.expand(Cw[i]) == 0 for i in FREE)


# --- positivity, order of consistent and naive ---------------------------------------------

def general_values(C: np.ndarray, V: np.ndarray) -> dict[str, float]:
    w, _ = uniaxial_response(C)
    vals = {**matrix_values("C", C), **matrix_values("V", V)}
    vals.update({f"w{i + 1}": w[i] for i in FREE})
    return vals


@pytest.mark.parametrize("rank", [0, 1, 3, 6])
def test_consistent_viscosity_nonnegative_for_psd_V(rank):
    rng = np.random.default_rng(250 + rank)
    s = step("anisotropic_viscosity").results
    for _ in range(20):
        C = random_spd(rng)
        V = random_psd(rng, rank) if rank else np.zeros((6, 6))
        cons = float(numeric(s["eta_cons"], general_values(C, V)))
        assert cons >= -1e-12 * max(1.0, np.abs(V).max())
        if rank == 0:
            assert cons == 0.0


def test_consistent_is_not_always_above_naive():
    """eta_cons - eta_naive = w_f.(V w)_f has no sign: isotropic with tau_B > tau_S gives
    eta_E < eta~_E, tau_B < tau_S the opposite (Sect. 4.2 note), and random PSD V give both."""
    s = step("anisotropic_viscosity").results
    diff = s["eta_cons_minus_naive_isotropic"]
    G, K = 1.0 / (2 * 1.3), 1.0 / (3 * 0.4)      # E = 1, nu = 0.3
    lo = float(diff.subs({nu: 0.3, eta: G * 0.01, zeta: K * 0.05}))   # tau_B > tau_S
    hi = float(diff.subs({nu: 0.3, eta: G * 0.05, zeta: K * 0.01}))   # tau_B < tau_S
    assert lo < 0 < hi
    rng = np.random.default_rng(2525)
    signs = set()
    for _ in range(200):
        vals = general_values(random_spd(rng), random_psd(rng, 6))
        signs.add(np.sign(float(numeric(s["eta_cons"] - s["eta_naive"], vals))))
    assert {-1.0, 1.0} <= signs


# --- closed forms against a direct NumPy computation ---------------------------------------

@pytest.mark.parametrize("seed", range(5))
def test_general_closed_form_against_numpy(seed):
    """Random SPD C, PSD V: E_eff, eta_cons, eta_naive of the step (w from the stress-free
    block solve) against the compliance route (uniaxial stress) in plain NumPy."""
    rng = np.random.default_rng(seed)
    C, V = random_spd(rng), random_psd(rng, 6)
    c = step("elastic_condensation").results
    s = step("anisotropic_viscosity").results
    Cff, Cf3 = C[np.ix_(FREE, FREE)], C[FREE, 2]
    wf = np.linalg.solve(Cff, -Cf3)                                   # -C_ff^-1 C_f3
    vals = {**matrix_values("C", C), **matrix_values("V", V)}
    vals.update({f"w{i + 1}": wf[k] for k, i in enumerate(FREE)})
    w, E_eff = uniaxial_response(C)
    assert np.allclose(numeric(c["C_f3_of_w"], vals).ravel(), Cf3, rtol=1e-10)
    assert np.isclose(float(numeric(c["E_eff"], vals)), E_eff, rtol=1e-9)
    assert np.isclose(float(numeric(s["eta_cons"], vals)), w @ V @ w, rtol=1e-9)
    assert np.isclose(float(numeric(s["eta_naive"], vals)), (V @ w)[2], rtol=1e-9)
    # the lateral stresses of the elastic mode vanish, the viscous ones in general do not
    assert np.allclose((C @ w)[FREE], 0.0, atol=1e-9 * np.abs(C).max())


def transversely_isotropic_compliance(E_L, E_T, nu_T, nu_L, G_L) -> np.ndarray:
    """Textbook compliance of a transversely isotropic solid, axis 3 (engineering constants:
    S33 = 1/E_L, S13 = -nu_L/E_L, S11 = 1/E_T, S12 = -nu_T/E_T, S44 = 1/G_L,
    S66 = 2 (1 + nu_T)/E_T)."""
    S = np.zeros((6, 6))
    S[0, 0] = S[1, 1] = 1 / E_T
    S[0, 1] = S[1, 0] = -nu_T / E_T
    S[0, 2] = S[2, 0] = S[1, 2] = S[2, 1] = -nu_L / E_L
    S[2, 2] = 1 / E_L
    S[3, 3] = S[4, 4] = 1 / G_L
    S[5, 5] = 2 * (1 + nu_T) / E_T
    return S


@pytest.mark.parametrize("constants", [
    (120e9, 8e9, 0.4, 0.3, 5e9),      # carbon fibre / epoxy like
    (40e9, 10e9, 0.35, 0.25, 4e9),    # glass fibre / epoxy like
    (5e6, 1e6, 0.45, 0.49, 0.3e6),    # a fibre-reinforced elastomer
])
def test_transversely_isotropic_closed_forms(constants):
    E_L, E_T, nu_T, nu_L, G_L = constants
    C = np.linalg.inv(transversely_isotropic_compliance(*constants))
    # a transversely isotropic V: the compliance form with other constants, and a dashpot
    # proportional to C on top (PSD by construction)
    V = np.linalg.inv(transversely_isotropic_compliance(3.0, 1.0, 0.2, 0.1, 0.7)) + 0.01 * C
    c = step("elastic_condensation").results
    s = step("anisotropic_viscosity").results
    vals = {**matrix_values("C", C), **matrix_values("V", V)}
    assert np.isclose(float(numeric(c["nu_L"], vals)), nu_L, rtol=1e-9)
    assert np.isclose(float(numeric(c["E_L"], vals)), E_L, rtol=1e-9)
    w, E_eff = uniaxial_response(C)
    cons, naive = w @ V @ w, (V @ w)[2]
    assert np.isclose(float(numeric(s["eta_cons_transversely_isotropic"], vals)), cons,
                      rtol=1e-9)
    assert np.isclose(float(numeric(s["eta_naive_transversely_isotropic"], vals)), naive,
                      rtol=1e-9)
    assert np.isclose(float(numeric(s["tau_E_transversely_isotropic"], vals)), cons / E_eff,
                      rtol=1e-9)
    in_nu = {**vals, "nu_L": nu_L}
    assert np.isclose(float(numeric(s["eta_cons_transversely_isotropic_in_nu_L"], in_nu)),
                      cons, rtol=1e-9)


def test_orthotropic_lateral_response_against_numpy():
    rng = np.random.default_rng(7)
    B = rng.normal(size=(3, 3))
    C = np.zeros((6, 6))
    C[:3, :3] = B @ B.T + 0.3 * np.eye(3)
    C[3, 3], C[4, 4], C[5, 5] = rng.uniform(0.5, 2.0, size=3)
    w_step = numeric(step("elastic_condensation").results["w_orthotropic"],
                     matrix_values("C", C)).ravel()
    w, _ = uniaxial_response(C)
    assert np.allclose(w_step, w, rtol=1e-10, atol=1e-12)
    assert np.allclose(plane_response(C), w, rtol=1e-10, atol=1e-12)


def test_fibre_and_plane_models_agree_in_plane_and_differ_off_axis():
    """A transversely isotropic material with its fibre in the section plane (monoclinic
    about the section plane): fibre mode = plane mode. Its fibre tilted 30 degrees out of
    the rod axis: the plane mode leaves sigma_23, sigma_13 (step result evaluated), the
    fibre mode shears, and E_fibre < E_plane (more freedom, less stiffness)."""
    C0 = np.linalg.inv(transversely_isotropic_compliance(120e9, 8e9, 0.4, 0.3, 5e9))
    expr = step("elastic_condensation").results["shear_stress_of_plane_mode"]
    fibre_in_section = rotated(C0, rotation(2, 25) @ rotation(1, 90))
    tilted = rotated(C0, rotation(0, 30))
    for Cm, agree in ((fibre_in_section, True), (tilted, False)):
        wp = plane_response(Cm)
        vals = {**matrix_values("C", Cm), **{f"wbar_{i + 1}": wp[i] for i in (0, 1, 5)}}
        shear = numeric(expr, vals).ravel()
        wf, E_f = uniaxial_response(Cm)
        E_p = wp @ Cm @ wp
        scale = np.abs(Cm).max()
        if agree:
            assert np.allclose(shear, 0.0, atol=1e-12 * scale)
            assert np.allclose(wf, wp, atol=1e-10)
            assert np.isclose(E_f, E_p, rtol=1e-10)
        else:
            assert np.abs(shear).max() > 1e-3 * scale
            assert np.abs(wf[[3, 4]]).max() > 1e-3
            assert E_f < E_p * (1 - 1e-6)


# --- shear and torsion ---------------------------------------------------------------------

def test_shear_step_reduces_to_tau_S_and_names_the_section_solver():
    s = step("anisotropic_shear")
    assert s.all_match
    assert s.results["shear_viscosity_over_stiffness_isotropic"] == tau_S
    assert any("section solver" in a for a in s.assumptions)
    # the general C couples the shear mode to the lateral stresses: not zero
    assert any(e != 0 for e in s.results["lateral_stress_of_shear_mode"])
    assert tau_B not in s.results["shear_viscosity_over_stiffness_isotropic"].free_symbols
