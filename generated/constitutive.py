# GENERATED FILE - do not edit; regenerate with `kvrod generate`.
# source: derive/templates/constitutive.py.jinja
# derivation step: isotropic_moduli, stored_energy, dissipation, naive_resultants, cross_sections, maxwell_material, maxwell_rod
# inputs sha256: 27d9ec4ba9fe97c123622c57752ce90d590a7ad02572dab2fb1e821ff0ba913a
# tools: sympy 1.14.0, casadi 3.8.2, jinja2 3.1.6

"""Rod stiffness and damping parameters of the Kelvin-Voigt Cosserat rod.

Rendered by `kvrod generate` from the SymPy derivation in derive/ (Linn, Lang, Tuganov
2013): every formula below is a derived result of the step named in its docstring.
Plain Python/NumPy; SI units throughout. Functions accept floats or NumPy arrays.
"""

from __future__ import annotations

import math

import numpy

__all__ = [
    "ParameterError",
    "shear_modulus",
    "bulk_modulus",
    "lame_lambda",
    "extensional_viscosity",
    "extensional_viscosity_naive",
    "in_plane_dissipation",
    "retardation_time_extension",
    "retardation_time_extension_naive",
    "rectangle_section",
    "ellipse_section",
    "circle_section",
    "tube_section",
    "maxwell_branch_moduli",
    "maxwell_moduli_laplace",
    "maxwell_rod_prony",
    "stiffness_matrices",
    "damping_matrices",
]


class ParameterError(ValueError):
    """A physical parameter outside its allowed range (names parameter, value, range)."""


#: allowed ranges: name -> (low, high, low inclusive, high inclusive, unit)
PARAMETER_RANGES = {
    "E": (0.0, math.inf, False, False, "Pa"),
    "nu": (-1.0, 0.5, False, True, ""),
    "nu_compressible": (-1.0, 0.5, False, False, ""),
    "tau_S": (0.0, math.inf, True, False, "s"),
    "tau_B": (0.0, math.inf, True, False, "s"),
    "eta": (0.0, math.inf, True, False, "Pa s"),
    "zeta": (0.0, math.inf, True, False, "Pa s"),
    "length": (0.0, math.inf, False, False, "m"),
    "length_or_zero": (0.0, math.inf, True, False, "m"),
    "section": (0.0, math.inf, False, False, "m^2 or m^4"),
    "kappa": (0.0, 1.0, False, True, ""),
    "modulus": (0.0, math.inf, True, False, "Pa"),
    "relaxation_time": (0.0, math.inf, False, False, "s"),
}


def _check(name: str, value, key: str | None = None) -> None:
    """Raise ParameterError unless every entry of ``value`` is finite and in range."""
    low, high, low_incl, high_incl, unit = PARAMETER_RANGES[key or name]
    arr = numpy.asarray(value, dtype=float)
    ok = numpy.isfinite(arr)
    ok &= (arr >= low) if low_incl else (arr > low)
    ok &= (arr <= high) if high_incl else (arr < high)
    if not numpy.all(ok):
        bad = float(arr[~ok][0]) if arr.ndim else float(arr)   # a plain float in the message
        lo = "[" if low_incl else "("
        hi = "]" if high_incl else ")"
        rng = f"{lo}{low:g}, {high:g}{hi}" if math.isfinite(high) else f"{lo}{low:g}, inf)"
        raise ParameterError(f"parameter {name!r} = {bad!r} is outside the allowed range: "
                             f"{rng} {unit}".rstrip())



def shear_modulus(E, nu):
    """Shear modulus G = mu [Pa].

    Derivation step: isotropic_moduli; paper: Sect. 3.3.
    E: Young's modulus [Pa]
    nu: Poisson's ratio [-]
    Returns: G [Pa]
    """
    _check("E", E)
    _check("nu", nu)
    return (1/2)*E/(nu + 1)



def bulk_modulus(E, nu):
    """Bulk modulus K = lambda + 2 mu/3 [Pa].

    Derivation step: isotropic_moduli; paper: Sect. 3.3.
    E: Young's modulus [Pa]
    nu: Poisson's ratio [-] (< 1/2)
    Returns: K [Pa]
    """
    _check("E", E)
    _check("nu", nu, "nu_compressible")
    return -1/3*E/(2*nu - 1)



def lame_lambda(E, nu):
    """Lame constant lambda [Pa].

    Derivation step: isotropic_moduli; paper: Sect. 3.3.
    E: Young's modulus [Pa]
    nu: Poisson's ratio [-] (< 1/2)
    Returns: lambda [Pa]
    """
    _check("E", E)
    _check("nu", nu, "nu_compressible")
    return -E*nu/((nu + 1)*(2*nu - 1))



def extensional_viscosity(zeta, eta, nu):
    """Extensional viscosity eta_E from the dissipation function [Pa s].

    Derivation step: dissipation; paper: (5).
    zeta: bulk viscosity [Pa s]
    eta: shear viscosity [Pa s]
    nu: Poisson's ratio [-]
    Returns: eta_E [Pa s]
    """
    _check("zeta", zeta)
    _check("eta", eta)
    _check("nu", nu)
    return (4/3)*eta*(nu + 1)**2 + zeta*(2*nu - 1)**2



def extensional_viscosity_naive(zeta, eta, nu):
    """Extensional viscosity eta~_E of the naive resultant route [Pa s].

    Derivation step: naive_resultants; paper: Sect. 4.2.
    zeta: bulk viscosity [Pa s]
    eta: shear viscosity [Pa s]
    nu: Poisson's ratio [-]
    Returns: eta~_E [Pa s]
    """
    _check("zeta", zeta)
    _check("eta", eta)
    _check("nu", nu)
    return (4/3)*eta*(nu + 1) + zeta*(1 - 2*nu)



def in_plane_dissipation(zeta, eta, nu):
    """Coefficient of (dH3/dt)^2 the resultant route misses, eta_E - eta~_E [Pa s].

    Derivation step: naive_resultants; paper: Sect. 4.2.
    zeta: bulk viscosity [Pa s]
    eta: shear viscosity [Pa s]
    nu: Poisson's ratio [-]
    Returns: eta_E - eta~_E [Pa s]
    """
    _check("zeta", zeta)
    _check("eta", eta)
    _check("nu", nu)
    return (4/3)*eta*nu*(nu + 1) + 2*nu*zeta*(2*nu - 1)



def retardation_time_extension(tau_B, tau_S, nu):
    """Extensional retardation time tau_E = eta_E/E [s].

    Derivation step: dissipation; paper: (6).
    tau_B: bulk retardation time zeta/K [s]
    tau_S: shear retardation time eta/G [s]
    nu: Poisson's ratio [-]
    Returns: tau_E [s]
    """
    _check("tau_B", tau_B)
    _check("tau_S", tau_S)
    _check("nu", nu)
    return -1/3*tau_B*(2*nu - 1) + (2/3)*tau_S*(nu + 1)



def retardation_time_extension_naive(tau_B, tau_S):
    """Naive extensional retardation time tau~_E = eta~_E/E [s] (independent of nu).

    Derivation step: naive_resultants; paper: Sect. 4.2.
    tau_B: bulk retardation time [s]
    tau_S: shear retardation time [s]
    Returns: tau~_E [s]
    """
    _check("tau_B", tau_B)
    _check("tau_S", tau_S)
    return (1/3)*tau_B + (2/3)*tau_S



def _rectangle_torsion_constant(b, d, terms: int = 400):
    """Saint-Venant torsion constant of a b x d rectangle [m^4] (series truncated after
    ``terms`` odd terms; the neglected tail is below 1e-11 relative for any aspect ratio).

    Derivation step: cross_sections (J_T = b d^3/3 - 64 d^4/pi^5 sum tanh((2m+1) pi b/(2d))/(2m+1)^5).
    """
    b, d = numpy.maximum(b, d), numpy.minimum(b, d)   # series along the thin side
    total = (1/3)*b*d**3
    for m in range(terms):
        total = total + -64*d**4*numpy.tanh((1/2)*numpy.pi*b*(2*m + 1)/d)/(numpy.pi**5*(32*m**5 + 80*m**4 + 80*m**3 + 40*m**2 + 10*m + 1))
    return total


def rectangle_section(width, height, nu):
    """Section constants of a width x height rectangle (width along xi1 / a^(1)).

    Derivation step: cross_sections. Shear factors: Cowper (1966), cited.
    width, height: side lengths [m]; nu: Poisson's ratio [-].
    Returns dict with A [m^2], I1 = <xi2^2>, I2 = <xi1^2>, I3 [m^4], J_T [m^4], kappa_1,
    kappa_2, kappa_3 = J_T/I3 [-].
    """
    _check("width", width, "length")
    _check("height", height, "length")
    _check("nu", nu)
    b, d = width, height
    A = b*d
    I1 = (1/12)*b*d**3
    I2 = (1/12)*b**3*d
    J_T = _rectangle_torsion_constant(b, d)
    kappa = (10*nu + 10)/(11*nu + 12)
    return {"A": A, "I1": I1, "I2": I2, "I3": I1 + I2, "J_T": J_T,
            "kappa_1": kappa, "kappa_2": kappa, "kappa_3": J_T / (I1 + I2)}


def ellipse_section(a, b, nu):
    """Section constants of an ellipse with half axis a along xi2 and b along xi1.

    Derivation step: cross_sections (footnote 1). Shear factors: Cowper (1966), cited.
    a, b: half axes [m]; nu: Poisson's ratio [-].
    Returns dict with A, I1, I2, I3, J_T, kappa_1 (shear along b), kappa_2 (along a), kappa_3.
    """
    _check("a", a, "length")
    _check("b", b, "length")
    _check("nu", nu)
    A = numpy.pi*a*b
    I1 = (1/4)*numpy.pi*a**3*b
    I2 = (1/4)*numpy.pi*a*b**3
    J_T = numpy.pi*a**3*b**3/(a**2 + b**2)
    return {"A": A, "I1": I1, "I2": I2, "I3": I1 + I2, "J_T": J_T,
            "kappa_1": b**2*(a**2 + 3*b**2)*(12*nu + 12)/(a**4*nu + a**2*b**2*(10*nu + 16) + b**4*(37*nu + 40)), "kappa_2": a**2*(3*a**2 + b**2)*(12*nu + 12)/(a**4*(37*nu + 40) + a**2*b**2*(10*nu + 16) + b**4*nu),
            "kappa_3": 4*a**2*b**2/(a**2 + b**2)**2}


def circle_section(radius, nu):
    """Section constants of a solid circle (ellipse with a = b = radius).

    radius [m]; nu: Poisson's ratio [-]. Returns the dict of :func:`ellipse_section`.
    """
    _check("radius", radius, "length")
    return ellipse_section(radius, radius, nu)


def tube_section(r_outer, r_inner, nu):
    """Section constants of a tube (hollow circle, annulus r_inner <= |xi| <= r_outer).

    Derivation step: cross_sections (explicit integration in polar coordinates; Prandtl
    stress function constant on the inner boundary, single-valued warping: the annulus does
    not warp, J_T = I3 = pi/2 (r_outer^4 - r_inner^4), kappa_3 = 1). Shear factor: Cowper
    (1966) for the hollow circle, cited; r_inner = 0 gives :func:`circle_section`.
    r_outer: outer radius [m] (> 0); r_inner: inner radius [m] (0 <= r_inner < r_outer);
    nu: Poisson's ratio [-].
    Returns dict with A [m^2], I1 = I2, I3, J_T [m^4], kappa_1 = kappa_2, kappa_3 [-].
    """
    _check("r_outer", r_outer, "length")
    _check("r_inner", r_inner, "length_or_zero")
    _check("nu", nu)
    r_o, r_i = numpy.broadcast_arrays(numpy.asarray(r_outer, dtype=float),
                                      numpy.asarray(r_inner, dtype=float))
    if not numpy.all(r_i < r_o):
        bad, top = float(r_i[r_i >= r_o].flat[0]), float(r_o[r_i >= r_o].flat[0])
        raise ParameterError(f"parameter 'r_inner' = {bad!r} is outside the allowed range: "
                             f"[0, r_outer) = [0, {top:g}) m")
    if numpy.ndim(r_outer) == 0 and numpy.ndim(r_inner) == 0:
        r_o, r_i = float(r_o), float(r_i)
    m = r_i / r_o
    A = -numpy.pi*(r_i - r_o)*(r_i + r_o)
    I1 = -1/4*numpy.pi*(r_i - r_o)*(r_i + r_o)*(r_i**2 + r_o**2)
    I2 = -1/4*numpy.pi*(r_i - r_o)*(r_i + r_o)*(r_i**2 + r_o**2)
    J_T = -1/2*numpy.pi*(r_i - r_o)*(r_i + r_o)*(r_i**2 + r_o**2)
    kappa = (m**2 + 1)**2*(6*nu + 6)/(m**2*(12*nu + 20) + (m**2 + 1)**2*(6*nu + 7))
    return {"A": A, "I1": I1, "I2": I2, "I3": I1 + I2, "J_T": J_T,
            "kappa_1": kappa, "kappa_2": kappa, "kappa_3": 1 + 0.0 * A}


def maxwell_branch_moduli(E_j, nu_j):
    """(G_j, K_j) [Pa] of Maxwell branches given by Young's modulus and Poisson's ratio.

    Derivation step: isotropic_moduli (G = E/(2(1+nu)), K = E/(3(1-2nu))), applied branch by
    branch. E_j: branch Young's moduli [Pa] (>= 0); nu_j: branch Poisson's ratios [-]
    (-1 < nu_j < 1/2; an incompressible branch has no finite K_j). Scalars or arrays that
    broadcast; returns two float arrays of the broadcast shape.
    """
    _check("E_j", E_j, "modulus")
    _check("nu_j", nu_j, "nu_compressible")
    E_j, nu_j = numpy.broadcast_arrays(numpy.asarray(E_j, dtype=float),
                                       numpy.asarray(nu_j, dtype=float))
    return (1/2)*E_j/(nu_j + 1), -1/3*E_j/(2*nu_j - 1)


def _maxwell_branches(G_inf, K_inf, G_j, K_j, tau_j):
    """Validated (G_inf, K_inf, G_j, K_j, tau_j): two scalars and three 1-D float arrays of
    one length M >= 0 (a scalar branch parameter is one branch)."""
    for name, value in (("G_inf", G_inf), ("K_inf", K_inf)):
        if numpy.ndim(value) != 0:
            raise ParameterError(f"parameter {name!r} = {value!r} is outside the allowed "
                                 "range: a scalar [Pa]")
        _check(name, value, "modulus")
    arrays = {}
    for name, value in (("G_j", G_j), ("K_j", K_j), ("tau_j", tau_j)):
        arr = numpy.atleast_1d(numpy.asarray(value, dtype=float))
        if arr.ndim != 1:
            raise ParameterError(f"parameter {name!r} has shape {arr.shape}, outside the "
                                 "allowed range: one value per branch (a 1-D array)")
        _check(name, arr, "relaxation_time" if name == "tau_j" else "modulus")
        arrays[name] = arr
    M = arrays["G_j"].size
    for name in ("K_j", "tau_j"):
        if arrays[name].size != M:
            raise ParameterError(f"parameter {name!r} has {arrays[name].size} entries, outside "
                                 f"the allowed range: one per branch ({M}, like 'G_j')")
    return float(G_inf), float(K_inf), arrays["G_j"], arrays["K_j"], arrays["tau_j"]


def maxwell_moduli_laplace(s, G_inf, K_inf, G_j, K_j, tau_j):
    """Laplace-domain moduli (G(s), K(s), E(s)) [Pa] of the 3-D generalized Maxwell solid.

    G(s) = G_inf + sum_j G_j s tau_j/(1 + s tau_j), K(s) likewise (step maxwell_material) and
    the lateral-stress-free uniaxial modulus E(s) = 9 K(s) G(s)/(3 K(s) + G(s)) that extension
    and bending carry (step maxwell_rod); shear and torsion carry G(s).
    s: Laplace variable [1/s], scalar or array, real or complex (s = i omega gives the complex
    moduli); G_inf, K_inf: equilibrium moduli [Pa] (>= 0); G_j, K_j: branch moduli [Pa]
    (>= 0) and tau_j: branch relaxation times [s] (> 0), 1-D arrays of one length M >= 0.
    Returns three complex arrays of the shape of s (poles at s = -1/tau_j and, for E, at the
    zeros of 3 K(s) + G(s)).
    """
    G_inf, K_inf, G_j, K_j, tau_j = _maxwell_branches(G_inf, K_inf, G_j, K_j, tau_j)
    s_b = numpy.asarray(s, dtype=complex)[..., numpy.newaxis]      # branch axis last
    G = G_inf + numpy.sum(G_j*s_b*tau_j/(s_b*tau_j + 1), axis=-1)
    K = K_inf + numpy.sum(K_j*s_b*tau_j/(s_b*tau_j + 1), axis=-1)
    E = 9*G*K/(G + 3*K)
    return G, K, E


def _secular_zeros(c_inf, c, lam):
    """Decay rates x_k = -s_k > 0 at the zeros s_k of D(s) = c_inf + sum_j c_j s/(s + lam_j).

    lam: branch rates 1/tau_j [1/s], strictly increasing; c: weights c_j > 0 [Pa]; c_inf >= 0.
    D(-x) = 0 is the secular equation of the symmetric positive semidefinite matrix
    T = diag(lam) - z z^T/c_0, z_j = sqrt(c_j lam_j), c_0 = c_inf + sum c_j (step maxwell_rod):
    its eigenvalues are the x_k, one in each of (0, lam_1), (lam_1, lam_2), ...,
    (lam_{M-1}, lam_M). numpy.linalg.eigvalsh gives them to an absolute error ~ eps lam_M; a
    bracketed Newton iteration on f(x) = c_inf - sum_j c_j x/(lam_j - x) (decreasing in each
    bracket) then refines each to full relative precision. With c_inf = 0 the first zero is
    x = 0 and is not returned (E(s) has no pole there).
    """
    M = lam.size
    if M == 0:
        return numpy.empty(0)
    c0 = c_inf + numpy.sum(c)
    z = numpy.sqrt(c * lam)
    x = numpy.linalg.eigvalsh(numpy.diag(lam) - numpy.outer(z, z) / c0)
    lo = numpy.concatenate(([0.0], lam[:-1]))
    hi = lam.copy()
    if c_inf == 0.0:
        x, lo, hi = x[1:], lo[1:], hi[1:]
    eps = numpy.finfo(float).eps
    mid = numpy.where(lo > 0.0, numpy.sqrt(lo * hi), 0.5 * hi)
    x = numpy.where((x > lo) & (x < hi), x, mid)
    for _ in range(200):
        d = lam[numpy.newaxis, :] - x[:, numpy.newaxis]
        f = c_inf - numpy.sum(c * x[:, numpy.newaxis] / d, axis=1)
        fp = -numpy.sum(c * lam / d**2, axis=1)
        lo = numpy.where(f > 0.0, x, lo)
        hi = numpy.where(f < 0.0, x, hi)
        step = numpy.where(f == 0.0, x, x - f / fp)
        mid = numpy.where(lo > 0.0, numpy.sqrt(lo * hi), 0.5 * hi)
        x_new = numpy.where((step > lo) & (step < hi), step, mid)
        x_new = numpy.where(f == 0.0, x, x_new)
        done = (numpy.abs(x_new - x) <= 4.0 * eps * x_new) | (hi - lo <= 4.0 * eps * hi)
        x = x_new
        if numpy.all(done):
            break
    return x


def maxwell_rod_prony(G_inf, K_inf, G_j, K_j, tau_j):
    """The rod's Prony series for extension/bending and for shear/torsion.

    Derivation step: maxwell_rod. Extension and bending carry
    E(s) = 9 K(s) G(s)/(3 K(s) + G(s)) = E_inf + sum_k E_k s theta_k/(1 + s theta_k) with
    up to 2M terms: one at each branch time theta = tau_j with the branch's own Young's
    modulus E_j = 9 K_j G_j/(3 K_j + G_j) (from the residue -E_j/tau_j at -1/tau_j), and one at each
    theta_k = -1/s_k, s_k a zero of D(s) = 3 K(s) + G(s), with the residue formula
    E_k = -3 G(s_k)^2/(s_k D'(s_k)). The zeros are found numerically: they are real, negative
    and interlace the branch poles (the eigenvalues of a symmetric diagonal-plus-rank-one
    matrix, see ``_secular_zeros``); clearing denominators into a polynomial instead would be
    badly conditioned when the tau_j span decades. Shear and torsion carry G(s): its Prony
    terms are the branches' own (G_j, tau_j).
    G_inf, K_inf: equilibrium moduli [Pa] (>= 0); G_j, K_j: branch moduli [Pa] (>= 0),
    tau_j: branch relaxation times [s] (> 0), 1-D arrays of one length M >= 0. Branches with
    equal tau_j are merged (their moduli add; the same branch split in two); branches with
    G_j = K_j = 0 are dropped, and so are extension terms whose modulus is below 4 eps of the
    instantaneous modulus (a zero of D that cancels, e.g. when every branch has the Poisson
    ratio of the equilibrium part, comes out as a rounding-level modulus).
    Returns dict: "E_inf" [Pa]; "G_inf" [Pa]; "extension": (E_k [Pa], theta_k [s]) and
    "shear": (G_j [Pa], tau_j [s]), each sorted by relaxation time. Multiply by A or I1, I2
    (and kappa_1 A, kappa_2 A, kappa_3 I3 for shear) for the rod's C_F(s), C_M(s).
    """
    G_inf, K_inf, G_j, K_j, tau_j = _maxwell_branches(G_inf, K_inf, G_j, K_j, tau_j)
    tau_u, inverse = numpy.unique(tau_j, return_inverse=True)        # merge equal times
    G_u = numpy.bincount(inverse, weights=G_j, minlength=tau_u.size).astype(float)
    K_u = numpy.bincount(inverse, weights=K_j, minlength=tau_u.size).astype(float)
    keep = (G_u > 0.0) | (K_u > 0.0)
    tau_u, G_u, K_u = tau_u[keep], G_u[keep], K_u[keep]
    K_j, G_j = K_u, G_u
    c_inf = G_inf + 3*K_inf
    c = G_j + 3*K_j
    E_inf = 9*G_inf*K_inf/(G_inf + 3*K_inf) if c_inf > 0.0 else 0.0
    E_at_tau = 9*G_j*K_j/(G_j + 3*K_j)
    # zeros of D(s), increasing decay rate x = -s_k <-> decreasing theta_k = 1/x
    lam = 1.0 / tau_u[::-1]
    x = _secular_zeros(c_inf, c[::-1], lam)
    s_k = -x
    s_b = s_k[:, numpy.newaxis]
    tau_j = tau_u
    G_k = G_inf + numpy.sum(G_j*s_b*tau_j/(s_b*tau_j + 1), axis=-1)
    dD_k = numpy.sum(tau_j*(G_j + 3*K_j)/(s_b*tau_j + 1)**2, axis=-1)
    E_at_zero = -3*G_k**2/(dD_k*s_k)
    E_k = numpy.concatenate((E_at_tau, E_at_zero))
    theta = numpy.concatenate((tau_u, 1.0 / x))
    order = numpy.argsort(theta, kind="stable")
    E_k, theta = E_k[order], theta[order]
    nonzero = E_k > 4.0 * numpy.finfo(float).eps * (E_inf + numpy.sum(E_k))
    shear = G_u > 0.0
    return {"E_inf": E_inf, "G_inf": G_inf,
            "extension": (E_k[nonzero], theta[nonzero]),
            "shear": (G_u[shear], tau_u[shear])}


def _check_matrix_inputs(E, nu, A, I1, I2, I3, kappa_1, kappa_2, kappa_3) -> None:
    _check("E", E)
    _check("nu", nu)
    for name, value in (("A", A), ("I1", I1), ("I2", I2), ("I3", I3)):
        _check(name, value, "section")
    for name, value in (("kappa_1", kappa_1), ("kappa_2", kappa_2), ("kappa_3", kappa_3)):
        _check(name, value, "kappa")


def stiffness_matrices(E, nu, A, I1, I2, I3, kappa_1=1.0, kappa_2=1.0, kappa_3=1.0):
    """Shear-corrected rod stiffness matrices (C_F, C_M) of (7) as 3x3 arrays.

    C_F [N] = diag(G A kappa_1, G A kappa_2, E A); C_M [N m^2] = diag(E I1, E I2, G I3 kappa_3)
    with G = E/(2(1+nu)). Derivation step: stored_energy.
    """
    _check_matrix_inputs(E, nu, A, I1, I2, I3, kappa_1, kappa_2, kappa_3)
    return (numpy.diag([(1/2)*A*E*kappa_1/(nu + 1), (1/2)*A*E*kappa_2/(nu + 1), A*E]),
            numpy.diag([E*I1, E*I2, (1/2)*E*I3*kappa_3/(nu + 1)]))


def damping_matrices(E, nu, tau_S, tau_B, A, I1, I2, I3, kappa_1=1.0, kappa_2=1.0,
                     kappa_3=1.0, route="consistent"):
    """Rod damping matrices (V_F, V_M) of (8)-(9) as 3x3 arrays [N s], [N m^2 s].

    route="consistent": eta_E from the dissipation function (5), V = C diag(tau);
    route="naive": eta~_E of the stress-resultant route (Sect. 4.2), which misses the
    in-plane dissipation. Derivation steps: dissipation, naive_resultants.
    """
    _check_matrix_inputs(E, nu, A, I1, I2, I3, kappa_1, kappa_2, kappa_3)
    _check("tau_S", tau_S)
    _check("tau_B", tau_B)
    if route == "consistent":
        return (numpy.diag([(1/2)*A*E*kappa_1*tau_S/(nu + 1), (1/2)*A*E*kappa_2*tau_S/(nu + 1), -1/3*A*E*tau_B*(2*nu - 1) + (2/3)*A*E*tau_S*(nu + 1)]),
                numpy.diag([-1/3*E*I1*tau_B*(2*nu - 1) + (2/3)*E*I1*tau_S*(nu + 1), -1/3*E*I2*tau_B*(2*nu - 1) + (2/3)*E*I2*tau_S*(nu + 1), (1/2)*E*I3*kappa_3*tau_S/(nu + 1)]))
    if route == "naive":
        return (numpy.diag([(1/2)*A*E*kappa_1*tau_S/(nu + 1), (1/2)*A*E*kappa_2*tau_S/(nu + 1), (1/3)*A*E*tau_B + (2/3)*A*E*tau_S]),
                numpy.diag([(1/3)*E*I1*tau_B + (2/3)*E*I1*tau_S, (1/3)*E*I2*tau_B + (2/3)*E*I2*tau_S, (1/2)*E*I3*kappa_3*tau_S/(nu + 1)]))
    raise ParameterError(f"parameter 'route' = {route!r} is outside the allowed range: "
                         "'consistent' or 'naive'")
