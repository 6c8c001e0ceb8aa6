"""Independent references for the cross-section analysis (runtime/section), NumPy/SciPy only.

Rod strains (Gamma1, Gamma2, Gamma3, K1, K2, K3) and resultants (T1, T2, T3, M1, M2, M3) as in
kvrod's kernels: axial strain Gamma3 + x2 K1 - x1 K2, I1 = <x2^2>, I2 = <x1^2>. SI units.

Contents (each from a textbook or a published table, none from the solver):

- Kelvin-Voigt scalars of an isotropic material (paper eqs. (4)-(6) and Sect. 4.2):
  eta_E = zeta (1 - 2 nu)^2 + 4/3 eta (1 + nu)^2 (consistent), eta~_E = (1 - 2 nu) zeta
  + 4/3 (1 + nu) eta (naive); a homogeneous section has V = diag(eta k1 A, eta k2 A,
  eta_E A, eta_E I1, eta_E I2, eta J_T) (consistent) and eta~_E in place of eta_E (naive).
- Energy-consistent shear factors: kappa = T^2 / (A <tau13^2 + tau23^2>) with the shear
  stresses of Saint-Venant's flexure solution (Timoshenko and Goodier, Theory of
  Elasticity, 3rd ed. 1970, Sects. 119-124; the definition of Renton 1991 and Pilkey,
  Analysis and Design of Elastic Beams, 2002, Sect. 6.4, which the Timoshenko stiffness of
  BECAS and VABS reduces to for a homogeneous isotropic section): the circle in closed form
  6 (1 + nu)^2 / (7 + 14 nu + 8 nu^2), the rectangle and the tube by quadrature of the
  series / closed-form stress functions below.
- Concentric composites (sums over regions; exact for one Poisson ratio) and the Lame
  solution of concentric cylinders in axial extension for different Poisson ratios.
- A bimetal strip (transformed section) and a transversely isotropic circle.
- The published VABS Timoshenko matrix of the circumferentially uniform stiffness (CUS)
  box beam: W. Yu, D. H. Hodges, J. C. Ho, "Variational asymptotic beam sectional analysis
  - An updated version", Int. J. Engineering Science 59 (2012) 40-64, as tabulated in the
  PreVABS documentation (example "Box beam", Table "Results", column "Reference [YU2012]").
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.polynomial.legendre import leggauss

from references.sections import rectangle_torsion_constant

# --------------------------------------------------------------------------- materials


def moduli(E: float, nu: float) -> tuple[float, float]:
    """(G, K) [Pa]."""
    return E / (2 * (1 + nu)), E / (3 * (1 - 2 * nu))


def viscosities(E: float, nu: float, tau_S: float, tau_B: float) -> tuple[float, float]:
    """(eta, zeta) [Pa s] = (G tau_S, K tau_B)."""
    G, K = moduli(E, nu)
    return G * tau_S, K * tau_B


def eta_E(E: float, nu: float, tau_S: float, tau_B: float) -> float:
    """Consistent extensional viscosity (5) [Pa s]."""
    eta, zeta = viscosities(E, nu, tau_S, tau_B)
    return zeta * (1 - 2 * nu) ** 2 + 4.0 / 3.0 * eta * (1 + nu) ** 2


def eta_E_naive(E: float, nu: float, tau_S: float, tau_B: float) -> float:
    """Naive (traction route) extensional viscosity eta~_E [Pa s]."""
    eta, zeta = viscosities(E, nu, tau_S, tau_B)
    return (1 - 2 * nu) * zeta + 4.0 / 3.0 * (1 + nu) * eta


# --------------------------------------------------------- energy-consistent shear factors


def shear_factor_circle(nu: float) -> float:
    """Energy-consistent shear factor of a solid circle from Love's flexure stresses
    (Timoshenko and Goodier Sect. 121: tau_xz = (3 + 2 nu)/(8 (1 + nu)) P/I (a^2 - x^2
    - (1 - 2 nu)/(3 + 2 nu) y^2), tau_yz = -(1 + 2 nu)/(4 (1 + nu)) P x y / I), integrated
    in closed form: 6 (1 + nu)^2 / (7 + 14 nu + 8 nu^2)."""
    return 6 * (1 + nu) ** 2 / (7 + 14 * nu + 8 * nu**2)


def _flexure_energy_rectangle(a: float, b: float, nu: float, n_terms: int = 400,
                              n_quad: int = 160) -> float:
    """<tau_xz^2 + tau_yz^2> for a unit shear force along x on |x| <= a, |y| <= b.

    Timoshenko and Goodier Sect. 124: with f(y) = P a^2 / (2I) the stress function phi
    vanishes on the boundary and Laplace phi = nu/(1 + nu) P y / I; phi = c psi with
    psi = (y^3 - b^2 y)/6 + sum_n c_n cosh(n pi x / b) sin(n pi y / b), whose sine
    coefficients follow from psi(+-a, y) = 0: the sine series of (y^3 - b^2 y)/6 on (-b, b)
    has coefficients 2 (-1)^n b^3 / (n pi)^3. tau_xz = P (a^2 - x^2)/(2I) + d phi/dy,
    tau_yz = -d phi/dx.
    """
    I = 4 * b * a**3 / 3
    c = nu / (1 + nu) / I
    n = np.arange(1, n_terms + 1)[:, None, None]
    gx, gw = leggauss(n_quad)
    x = a * gx[None, :, None]
    y = b * gx[None, None, :]
    k = n * np.pi / b
    gn = 2 * (-1.0) ** n * b**3 / (n * np.pi) ** 3
    # cosh(k x)/cosh(k a) and sinh(k x)/cosh(k a) without overflow
    e1 = np.exp(k * (np.abs(x) - a))
    e2 = np.exp(-k * (np.abs(x) + a))
    den = 1 + np.exp(-2 * k * a)
    ch, sh = (e1 + e2) / den, np.sign(x) * (e1 - e2) / den
    dpsi_dy = (3 * y[0] ** 2 - b**2) / 6 - np.sum(gn * k * ch * np.cos(k * y), axis=0)
    dpsi_dx = -np.sum(gn * k * sh * np.sin(k * y), axis=0)
    txz = (a**2 - x[0] ** 2) / (2 * I) + c * dpsi_dy
    tyz = -c * dpsi_dx
    w = np.outer(gw * a, gw * b)
    return float(np.sum(w * (txz**2 + tyz**2)))


def shear_factor_rectangle(depth: float, width: float, nu: float) -> float:
    """Energy-consistent shear factor of a rectangle sheared along its side ``depth``
    (the other side ``width``); 5/6 at nu = 0 for every aspect ratio."""
    a, b = depth / 2, width / 2
    return 1.0 / (4 * a * b * _flexure_energy_rectangle(a, b, nu))


def shear_factor_tube(r_o: float, r_i: float, nu: float, n_quad: int = 200) -> float:
    """Energy-consistent shear factor of a tube (outer radius r_o, inner r_i).

    Timoshenko and Goodier's flexure formulation (Sect. 119) with f(y) = P (r_o^2 - y^2)/(2I):
    Laplace phi = (1 + 2 nu)/(1 + nu) P y / I, phi = 0 on the outer circle and, on the inner
    one, d phi / ds = P (r_i^2 - r_o^2)/(2I) dy/ds, i.e. phi = P (r_i^2 - r_o^2)/(2I) y
    (the constant vanishes by the symmetry in y). phi = (k r^3 + A r + B / r) sin(theta)
    with k = (1 + 2 nu)/(8 (1 + nu)) P / I. r_i = 0 gives Love's solid circle.
    """
    I = math.pi * (r_o**4 - r_i**4) / 4
    k = (1 + 2 * nu) / (8 * (1 + nu)) / I
    Dv = (r_i**2 - r_o**2) / (2 * I)
    if r_i > 0:
        M = np.array([[r_o, 1 / r_o], [r_i, 1 / r_i]])
        A_, B_ = np.linalg.solve(M, [-k * r_o**3, Dv * r_i - k * r_i**3])
    else:
        A_, B_ = -k * r_o**2, 0.0
    gr, wr = leggauss(n_quad)
    r = 0.5 * (r_o - r_i) * gr + 0.5 * (r_o + r_i)
    wr = 0.5 * (r_o - r_i) * wr
    t = 2 * np.pi * (np.arange(2 * n_quad) + 0.5) / (2 * n_quad)
    R, T = np.meshgrid(r, t, indexing="ij")
    x, y = R * np.cos(T), R * np.sin(T)
    # phi = (k r^2 + A + B / r^2) y ; derivatives in Cartesian form
    g = k * R**2 + A_ + B_ / R**2
    dg_dr = 2 * k * R - 2 * B_ / R**3
    dphi_dx = dg_dr * (x / R) * y
    dphi_dy = dg_dr * (y / R) * y + g
    txz = dphi_dy - x**2 / (2 * I) + (r_o**2 - y**2) / (2 * I)
    tyz = -dphi_dx
    w = (wr * r)[:, None] * (2 * np.pi / t.size)
    energy = float(np.sum(w * (txz**2 + tyz**2)))
    return 1.0 / (math.pi * (r_o**2 - r_i**2) * energy)


# ------------------------------------------------------------- homogeneous closed forms


@dataclass(frozen=True)
class Homogeneous:
    """Diagonals (6,) of K, V (consistent) and V_naive of a homogeneous isotropic section;
    ``None`` entries where no closed form is given."""

    K: tuple
    V: tuple
    V_naive: tuple


def homogeneous(A: float, I1: float, I2: float, J: float, k1: float | None,
                k2: float | None, E: float, nu: float, tau_S: float, tau_B: float
                ) -> Homogeneous:
    G, _ = moduli(E, nu)
    eta, _ = viscosities(E, nu, tau_S, tau_B)
    eE, eN = eta_E(E, nu, tau_S, tau_B), eta_E_naive(E, nu, tau_S, tau_B)
    sh = tuple(None if k is None else k * A for k in (k1, k2))
    K = tuple(None if s is None else G * s for s in sh) + (E * A, E * I1, E * I2, G * J)
    V = tuple(None if s is None else eta * s for s in sh) + (eE * A, eE * I1, eE * I2,
                                                             eta * J)
    Vn = tuple(None if s is None else eta * s for s in sh) + (eN * A, eN * I1, eN * I2,
                                                              eta * J)
    return Homogeneous(K, V, Vn)


def circle(r: float, E: float, nu: float, tau_S: float, tau_B: float) -> Homogeneous:
    I = math.pi * r**4 / 4
    k = shear_factor_circle(nu)
    return homogeneous(math.pi * r * r, I, I, 2 * I, k, k, E, nu, tau_S, tau_B)


def tube(r_o: float, r_i: float, E: float, nu: float, tau_S: float, tau_B: float
         ) -> Homogeneous:
    I = math.pi * (r_o**4 - r_i**4) / 4
    k = shear_factor_tube(r_o, r_i, nu)
    return homogeneous(math.pi * (r_o**2 - r_i**2), I, I, 2 * I, k, k, E, nu, tau_S, tau_B)


def rectangle(width: float, height: float, E: float, nu: float, tau_S: float, tau_B: float
              ) -> Homogeneous:
    """Width along d1, height along d2; J_T by Saint-Venant's series."""
    A = width * height
    return homogeneous(A, width * height**3 / 12, height * width**3 / 12,
                       rectangle_torsion_constant(width, height),
                       shear_factor_rectangle(width, height, nu),
                       shear_factor_rectangle(height, width, nu), E, nu, tau_S, tau_B)


def ellipse(a: float, b: float, E: float, nu: float, tau_S: float, tau_B: float
            ) -> Homogeneous:
    """Half axis a along d2, b along d1; J_T = pi a^3 b^3 / (a^2 + b^2) (no shear factor)."""
    return homogeneous(math.pi * a * b, math.pi * b * a**3 / 4, math.pi * a * b**3 / 4,
                       math.pi * a**3 * b**3 / (a * a + b * b), None, None, E, nu, tau_S,
                       tau_B)


# ------------------------------------------------------------- concentric composites


def concentric_sum(radii: list[float], layers: list[tuple[float, float, float, float]]
                   ) -> Homogeneous:
    """Concentric circle and tubes (radii r_1 < r_2 < ..., layer i between r_{i-1} and
    r_i with r_0 = 0), layers (E, nu, tau_S, tau_B): the per-region sums of EA, EI, GJ and
    of the extension, bending and torsion viscosities (exact when every layer has the same
    nu: the lateral contraction is then compatible and the interfaces carry no in-plane
    stress). Shear entries are not given (None)."""
    K = np.zeros(6)
    V = np.zeros(6)
    Vn = np.zeros(6)
    r_in = 0.0
    for r_out, (E, nu, tS, tB) in zip(radii, layers, strict=True):
        A = math.pi * (r_out**2 - r_in**2)
        I = math.pi * (r_out**4 - r_in**4) / 4
        G, _ = moduli(E, nu)
        eta, _ = viscosities(E, nu, tS, tB)
        K[2:] += [E * A, E * I, E * I, 2 * G * I]
        V[2:] += [eta_E(E, nu, tS, tB) * A, eta_E(E, nu, tS, tB) * I,
                  eta_E(E, nu, tS, tB) * I, 2 * eta * I]
        Vn[2:] += [eta_E_naive(E, nu, tS, tB) * A, eta_E_naive(E, nu, tS, tB) * I,
                   eta_E_naive(E, nu, tS, tB) * I, 2 * eta * I]
        r_in = r_out
    none2 = (None, None)
    return Homogeneous(none2 + tuple(K[2:]), none2 + tuple(V[2:]), none2 + tuple(Vn[2:]))


def lame_extension(radii: list[float], layers: list[tuple[float, float, float, float]]
                   ) -> dict[str, float]:
    """Concentric cylinders under a unit axial strain (generalized plane strain, Lame).

    In layer i: u_r = a_i r + b_i / r (b_1 = 0 in a solid core), eps_rr = a - b/r^2,
    eps_tt = a + b/r^2, eps_zz = 1; sigma_rr = 2 (lam + mu) a - 2 mu b / r^2 + lam,
    sigma_zz = 2 lam a + lam + 2 mu. u_r and sigma_rr continuous at the interfaces,
    sigma_rr = 0 outside. Returns EA = <sigma_zz>, the consistent viscosity
    <eps . V eps> and the naive <(V eps)_zz> [N s], and the per-layer (a_i, b_i).
    """
    n = len(radii)
    lam_mu = []
    for E, nu, _, _ in layers:
        G, K = moduli(E, nu)
        lam_mu.append((K - 2 * G / 3, G))
    # unknowns a_1, (a_i, b_i) for i >= 2
    idx = {}
    m = 0
    for i in range(n):
        idx[(i, "a")] = m
        m += 1
        if i > 0:
            idx[(i, "b")] = m
            m += 1
    M = np.zeros((m, m))
    rhs = np.zeros(m)
    row = 0

    def coef_u(i, r):
        c = {idx[(i, "a")]: r}
        if i > 0:
            c[idx[(i, "b")]] = 1 / r
        return c

    def coef_s(i, r):
        lam, mu = lam_mu[i]
        c = {idx[(i, "a")]: 2 * (lam + mu)}
        if i > 0:
            c[idx[(i, "b")]] = -2 * mu / r**2
        return c, lam

    for i in range(n - 1):
        r = radii[i]
        for k, v in coef_u(i, r).items():
            M[row, k] += v
        for k, v in coef_u(i + 1, r).items():
            M[row, k] -= v
        row += 1
        (c1, l1), (c2, l2) = coef_s(i, r), coef_s(i + 1, r)
        for k, v in c1.items():
            M[row, k] += v
        for k, v in c2.items():
            M[row, k] -= v
        rhs[row] = -(l1 - l2)
        row += 1
    c, lam = coef_s(n - 1, radii[-1])
    for k, v in c.items():
        M[row, k] += v
    rhs[row] = -lam
    sol = np.linalg.solve(M, rhs)
    EA = Vc = Vn = 0.0
    coeffs = []
    r_in = 0.0
    for i, (E, nu, tS, tB) in enumerate(layers):
        r_out = radii[i]
        a = sol[idx[(i, "a")]]
        b = sol[idx[(i, "b")]] if i > 0 else 0.0
        lam, mu = lam_mu[i]
        A = math.pi * (r_out**2 - r_in**2)
        EA += (2 * lam * a + lam + 2 * mu) * A
        eta, zeta = viscosities(E, nu, tS, tB)
        lv, mv = zeta - 2 * eta / 3, eta
        inv_r2 = math.pi * (1 / r_in**2 - 1 / r_out**2) if r_in > 0 else 0.0
        # <tr^2> = (2a + 1)^2 A; <eps_rr^2 + eps_tt^2 + 1> = (2 a^2 + 1) A + 2 b^2 <r^-4>
        Vc += lv * (2 * a + 1) ** 2 * A + 2 * mv * ((2 * a * a + 1) * A + 2 * b * b * inv_r2)
        Vn += (lv * (2 * a + 1) + 2 * mv) * A
        coeffs.append((a, b))
        r_in = r_out
    return {"EA": EA, "V": Vc, "V_naive": Vn, "coefficients": coeffs}


# ---------------------------------------------------------------------- bimetal strip


def bimetal(width: float, heights: tuple[float, float],
            layers: tuple[tuple[float, float, float, float], ...]) -> dict[str, float]:
    """Two layers of one width stacked along d2 (layer 0 below x2 = 0, layer 1 above), both
    of the same Poisson ratio: transformed section. Returns the elastic centroid y_c,
    EA, EI1 about y_c (bending about d1, strain varying along d2), the consistent and
    naive extension and bending viscosities and the viscous Gamma3-K1 coupling
    sum eta_E,i A_i (y_i - y_c) (and its naive counterpart)."""
    (h0, h1) = heights
    ys = (-h0 / 2, h1 / 2)
    As = (width * h0, width * h1)
    Is = (width * h0**3 / 12, width * h1**3 / 12)
    Es = [ly[0] for ly in layers]
    yc = sum(E * A * y for E, A, y in zip(Es, As, ys, strict=True)) / \
        sum(E * A for E, A in zip(Es, As, strict=True))
    out = {"y_c": yc, "EA": sum(E * A for E, A in zip(Es, As, strict=True))}
    out["EI1"] = sum(E * (I + A * (y - yc) ** 2) for E, A, I, y in zip(Es, As, Is, ys,
                                                                     strict=True))
    for key, fn in (("", eta_E), ("_naive", eta_E_naive)):
        e = [fn(*ly) for ly in layers]
        out["V_Gamma3" + key] = sum(ei * A for ei, A in zip(e, As, strict=True))
        out["V_K1" + key] = sum(ei * (I + A * (y - yc) ** 2)
                                for ei, A, I, y in zip(e, As, Is, ys, strict=True))
        out["V_Gamma3_K1" + key] = sum(ei * A * (y - yc) for ei, A, y in zip(e, As, ys,
                                                                          strict=True))
    return out


# ------------------------------------------------------ transversely isotropic circle


def transversely_isotropic_circle(r: float, C: np.ndarray, V: np.ndarray) -> dict[str, float]:
    """Circle of a material transversely isotropic about the rod axis (Voigt C [Pa], V
    [Pa s], axis 3 the symmetry axis). Extension and bending: uniaxial stress along 3 with
    the compatible lateral contraction eps11 = eps22 = -nu_31 eps33 (in-plane stress free),
    E_3 = 1/S33, nu_31 = -S13/S33 (S = C^-1); torsion: no warping, G_L = C44 = C55."""
    S = np.linalg.inv(C)
    E3 = 1 / S[2, 2]
    n31 = -S[0, 2] / S[2, 2]
    w = np.array([-n31, -n31, 1, 0, 0, 0])
    A, I = math.pi * r * r, math.pi * r**4 / 4
    vE, vN = float(w @ V @ w), float((V @ w)[2])
    return {"EA": E3 * A, "EI": E3 * I, "GJ": C[3, 3] * 2 * I, "V_ext": vE * A,
            "V_bend": vE * I, "V_ext_naive": vN * A, "V_bend_naive": vN * I,
            "V_tors": V[3, 3] * 2 * I}


# ---------------------------------------------------- published VABS box (CUS) beam

PSI = 6894.757293168361      # Pa
INCH = 0.0254                # m
LBF = 4.4482216152605        # N

#: ply material of the box (Table "Material properties"): E1 along the fibre [psi]
BOX_MATERIAL = {"E1": 20.59e6, "E2": 1.42e6, "E3": 1.42e6, "G12": 0.87e6, "G13": 0.87e6,
                "G23": 0.696e6, "nu12": 0.30, "nu13": 0.30, "nu23": 0.34}
#: outer width (VABS x2), outer height (x3), wall thickness (6 plies) [in]; the fibres at
#: 15 degrees to the axis in every wall (circumferentially uniform stiffness)
BOX_GEOMETRY = {"width": 0.953, "height": 0.530, "wall": 0.030, "ply_angle": 15.0}
#: Yu, Hodges, Ho (2012), VABS Timoshenko stiffness (1-based, VABS order: extension,
#: shear along x2, shear along x3, twist, bending kappa2, kappa3); lb, lb in, lb in^2
BOX_VABS = {(1, 1): 1.437e6, (2, 2): 9.027e4, (3, 3): 3.943e4, (1, 4): 1.074e5,
            (2, 5): -5.201e4, (3, 6): -5.635e4, (4, 4): 1.679e4, (5, 5): 6.621e4,
            (6, 6): 1.725e5}
#: VABS index (0-based) -> kvrod index: the VABS beam axis x1 is kvrod's d3, its section
#: axes (x2, x3) are (d1, d2) (a cyclic relabelling, right-handed either way); its strains
#: (gamma11, 2 gamma12, 2 gamma13, kappa1, kappa2, kappa3) are kvrod's (Gamma3, Gamma1,
#: Gamma2, K3, K1, K2): VABS's axial strain gamma11 + x3 kappa2 - x2 kappa3 is
#: Gamma3 + x2 K1 - x1 K2.
VABS_TO_KVROD = (2, 0, 1, 5, 3, 4)


def box_material_stiffness() -> np.ndarray:
    """Voigt C [Pa] of the box's ply in kvrod's material axes: the fibre (VABS material
    axis 1) is the material axis 3, the in-plane transverse axes are 1 and 2."""
    m = BOX_MATERIAL
    E_f, E_t = m["E1"] * PSI, m["E2"] * PSI
    G_ft, G_tt = m["G12"] * PSI, m["G23"] * PSI
    S = np.zeros((6, 6))
    S[0, 0] = S[1, 1] = 1 / E_t
    S[2, 2] = 1 / E_f
    S[0, 1] = S[1, 0] = -m["nu23"] / E_t
    S[0, 2] = S[2, 0] = S[1, 2] = S[2, 1] = -m["nu12"] / E_f
    S[3, 3] = S[4, 4] = 1 / G_ft
    S[5, 5] = 1 / G_tt
    return np.linalg.inv(S)


def box_vabs_in_kvrod_units() -> dict[tuple[int, int], float]:
    """The published entries mapped to kvrod's order (0-based) and SI units (N, N m,
    N m^2)."""
    out = {}
    for (i, j), v in BOX_VABS.items():
        a, b = VABS_TO_KVROD[i - 1], VABS_TO_KVROD[j - 1]
        lengths = (a >= 3) + (b >= 3)
        out[(a, b)] = v * LBF * INCH**lengths
    return out
