# GENERATED FILE - do not edit; regenerate with `kvrod generate`.
# source: derive/templates/constitutive.py.jinja
# derivation step: isotropic_moduli, stored_energy, dissipation, naive_resultants, cross_sections
# inputs sha256: d85754a43411f22c1551b7bc11b2f5985ed6951c849dc935b69e42e91e03d61c
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
}


def _check(name: str, value, key: str | None = None) -> None:
    """Raise ParameterError unless every entry of ``value`` is finite and in range."""
    low, high, low_incl, high_incl, unit = PARAMETER_RANGES[key or name]
    arr = numpy.asarray(value, dtype=float)
    ok = numpy.isfinite(arr)
    ok &= (arr >= low) if low_incl else (arr > low)
    ok &= (arr <= high) if high_incl else (arr < high)
    if not numpy.all(ok):
        bad = arr[~ok][0] if arr.ndim else float(arr)
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
            "kappa_3": J_T / (I1 + I2)}


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
