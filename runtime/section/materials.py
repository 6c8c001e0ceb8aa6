"""Materials of a cross-section: 3-D Kelvin-Voigt solids as Voigt matrices.

Voigt order 11, 22, 33, 23, 13, 12 with axis 3 along the rod and (1, 2) along the section's
directors (d1, d2); engineering shear strains (gamma_23 = 2 eps_23, ...), so that the 6x6
stiffness ``C`` [Pa] of an isotropic material has C44 = C55 = C66 = G and the viscosity ``V``
[Pa s] gives the viscous stress V . d(eps)/dt.

Isotropic (``[materials.NAME]`` without a ``stiffness_matrix``): ``youngs_modulus`` E [Pa],
``poisson_ratio`` nu (-1 < nu < 1/2), ``density`` [kg/m^3], and the viscosity as kvrod's
``[material]`` takes it: ``tau`` (tau_S = tau_B = tau), or ``tau_S``/``tau_B`` [s], or the
shear and bulk viscosities ``eta``/``zeta`` [Pa s] (tau_S = eta/G, tau_B = zeta/K); none of
them: an elastic material (V = 0). The viscous stress is
zeta tr(d eps/dt) I + 2 eta dev(d eps/dt) (paper eqs. (28)-(30)).

Anisotropic: ``stiffness_matrix`` [Pa] and ``viscosity_matrix`` [Pa s] (6x6, in the
material's own axes; the viscosity may be omitted: V = 0), ``density``, and
``orientation = { rotation = beta, off_axis = theta }`` in degrees: the material axes are
the section axes turned first about d2 by theta (the material's axis 3, e.g. its fibre,
tilts from the rod axis towards d1) and then about the rod axis d3 by beta (the tilt turns
towards cos(beta) d1 + sin(beta) d2). A fibre wound at theta in a wall whose tangent is t
(in the section plane) has beta = the angle of t from d1.

Checks: C symmetric positive definite, V symmetric positive semi-definite (errors name the
key and the unit).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from runtime.errors import ParameterError
from runtime.section import _checks as ck

#: Voigt index pairs, order 11, 22, 33, 23, 13, 12
VOIGT = ((0, 0), (1, 1), (2, 2), (1, 2), (0, 2), (0, 1))
#: the volumetric strain is M_VOL . eps (Voigt)
M_VOL = np.array([1.0, 1.0, 1.0, 0.0, 0.0, 0.0])
#: above this bulk-to-shear modulus ratio an isotropic region's bulk modulus is split and
#: its excess is taken on element-mean volumetric strain (no volumetric locking); K/G = 10
#: is nu = 14/31 = 0.4516
BULK_RATIO_SPLIT = 10.0


#: the speed of light [m/s]: no solid carries elastic waves faster (real solids: below
#: 2e4 m/s); a modulus and density whose wave speed sqrt(E / density) exceeds it are off
#: by orders of magnitude (E = 1e300 Pa was blamed on the run's t_end, after the periods
#: it gave)
WAVE_SPEED_MAX = 299_792_458.0
#: a solid's typical modulus [Pa] and density [kg/m^3]: of the two, the one further from
#: its typical value (in decades) is named when the wave speed is impossible
TYPICAL_MODULUS, TYPICAL_DENSITY = 1e9, 1e3


def check_wave_speed(modulus: float, density: float, modulus_path: str,
                     density_path: str) -> None:
    """ParameterError unless sqrt(modulus / density) <= :data:`WAVE_SPEED_MAX`, naming the
    modulus [Pa] or the density [kg/m^3], whichever is further in decades from a typical
    solid's (:data:`TYPICAL_MODULUS`, :data:`TYPICAL_DENSITY`); both > 0."""
    c2 = WAVE_SPEED_MAX * WAVE_SPEED_MAX
    if modulus <= c2 * density:
        return
    why = "a wave speed sqrt(E / density) below the speed of light, 3e8 m/s"
    if abs(math.log10(modulus / TYPICAL_MODULUS)) >= abs(math.log10(density /
                                                                    TYPICAL_DENSITY)):
        raise ParameterError(modulus_path, modulus, f"at most density x c^2 = "
                             f"{c2 * density:.3g} Pa for {density_path} = {density:g} "
                             f"kg/m^3 ({why})")
    raise ParameterError(density_path, density, f"at least E / c^2 = {modulus / c2:.3g} "
                         f"kg/m^3 for {modulus_path} = {modulus:g} Pa ({why})")


def shear_modulus(E: float, nu: float) -> float:
    """G = E / (2 (1 + nu)) [Pa]."""
    return E / (2.0 * (1.0 + nu))


def bulk_modulus(E: float, nu: float) -> float:
    """K = E / (3 (1 - 2 nu)) [Pa] (nu < 1/2)."""
    return E / (3.0 * (1.0 - 2.0 * nu))


def isotropic_matrix(lam: float, mu: float) -> np.ndarray:
    """Voigt matrix of lam tr(e) I + 2 mu e in engineering shear strains (6x6)."""
    m = np.zeros((6, 6))
    m[:3, :3] = lam
    m[[0, 1, 2], [0, 1, 2]] = lam + 2.0 * mu
    m[[3, 4, 5], [3, 4, 5]] = mu
    return m


def isotropic_stiffness(E: float, nu: float) -> np.ndarray:
    """C [Pa] of an isotropic material (Lame lambda = E nu / ((1 + nu)(1 - 2 nu)), mu = G)."""
    return isotropic_matrix(E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)), shear_modulus(E, nu))


def isotropic_viscosity(eta: float, zeta: float) -> np.ndarray:
    """V [Pa s] of zeta tr(de) I + 2 eta dev(de): lambda_v = zeta - 2 eta / 3, mu_v = eta."""
    return isotropic_matrix(zeta - 2.0 * eta / 3.0, eta)


def viscosities_from_times(E: float, nu: float, tau_S: float, tau_B: float
                           ) -> tuple[float, float]:
    """(eta, zeta) [Pa s] from the retardation times tau_S = eta/G and tau_B = zeta/K [s]."""
    return shear_modulus(E, nu) * tau_S, (bulk_modulus(E, nu) * tau_B if tau_B else 0.0)


def rotation(rotation_deg: float, off_axis_deg: float) -> np.ndarray:
    """3x3 matrix whose columns are the material axes in section components:
    R = R_3(beta) R_2(theta) (see the module docstring)."""
    b, t = math.radians(rotation_deg), math.radians(off_axis_deg)
    cb, sb, ct, st = math.cos(b), math.sin(b), math.cos(t), math.sin(t)
    r3 = np.array([[cb, -sb, 0.0], [sb, cb, 0.0], [0.0, 0.0, 1.0]])
    r2 = np.array([[ct, 0.0, st], [0.0, 1.0, 0.0], [-st, 0.0, ct]])
    return r3 @ r2


def stress_transform(R: np.ndarray) -> np.ndarray:
    """6x6 T with sigma_section = T sigma_material (Voigt) for sigma_s = R sigma_m R^T.

    With engineering shear strains the strain transforms with T^-T, so a stiffness or
    viscosity matrix transforms as T M T^T.
    """
    T = np.empty((6, 6))
    for p, (i, j) in enumerate(VOIGT):
        for q, (k, l) in enumerate(VOIGT):
            T[p, q] = R[i, k] * R[j, l] + (R[i, l] * R[j, k] if k != l else 0.0)
    return T


@dataclass(frozen=True)
class SectionMaterial:
    """A named 3-D Kelvin-Voigt material in section axes.

    ``stiffness`` C [Pa] and ``viscosity`` V [Pa s] (6x6, Voigt, section axes),
    ``density`` [kg/m^3]. ``bulk_excess`` [Pa] and ``bulk_viscosity_excess`` [Pa s]: the parts
    of the bulk modulus and bulk viscosity that the analysis takes on the element-mean
    volumetric strain (nearly incompressible isotropic materials; 0 otherwise); C and V hold
    the whole material, the split is only how the analysis integrates it.
    ``isotropic``: (E, nu, tau_S, tau_B) for an isotropic material, else None.
    """

    name: str
    stiffness: np.ndarray
    viscosity: np.ndarray
    density: float
    isotropic: tuple[float, float, float, float] | None = None
    orientation: tuple[float, float] = (0.0, 0.0)
    bulk_excess: float = 0.0
    bulk_viscosity_excess: float = 0.0
    warnings: tuple[str, ...] = field(default=())
    #: the ``[materials.NAME]`` table this material was read from (``to_mapping`` gives it
    #: back as written, so a problem written out and read again is the same problem)
    source: Mapping[str, Any] | None = field(default=None, compare=False, repr=False)

    def to_mapping(self) -> dict[str, Any]:
        """The ``[materials.NAME]`` table of this material: the table it was read from, else
        E, nu, density and the retardation times (isotropic) or the Voigt matrices in the
        material's own axes with the orientation (anisotropic)."""
        if self.source is not None:
            return _plain(self.source)
        if self.isotropic is not None:
            E, nu, tS, tB = self.isotropic
            return {"youngs_modulus": E, "poisson_ratio": nu, "density": self.density,
                    "tau_S": tS, "tau_B": tB}
        T = stress_transform(rotation(*self.orientation))
        Ti = np.linalg.inv(T)
        out: dict[str, Any] = {"stiffness_matrix": (Ti @ self.stiffness @ Ti.T).tolist(),
                               "density": self.density}
        if np.any(self.viscosity):
            out["viscosity_matrix"] = (Ti @ self.viscosity @ Ti.T).tolist()
        if any(self.orientation):
            out["orientation"] = {"rotation": self.orientation[0],
                                  "off_axis": self.orientation[1]}
        return out

    @property
    def eta_E(self) -> float:
        """Consistent extensional viscosity (5) [Pa s] of an isotropic material."""
        if self.isotropic is None:
            raise ValueError(f"material {self.name!r} is not isotropic")
        E, nu, tS, tB = self.isotropic
        eta, zeta = viscosities_from_times(E, nu, tS, tB)
        return zeta * (1 - 2 * nu) ** 2 + 4.0 / 3.0 * eta * (1 + nu) ** 2


def _plain(m: Any) -> Any:
    """A deep copy of a TOML-like value (tables, arrays, numbers, strings)."""
    if isinstance(m, Mapping):
        return {str(k): _plain(v) for k, v in m.items()}
    if isinstance(m, (list, tuple)):
        return [_plain(v) for v in m]
    return m


def _check_matrices(path: str, C: np.ndarray, V: np.ndarray, keys: tuple[str, str]) -> None:
    scale = float(np.max(np.abs(C)))
    if not np.allclose(C, C.T, rtol=0.0, atol=1e-12 * scale):
        raise ParameterError(f"{path}.{keys[0]}", C.tolist(), "a symmetric 6x6 matrix in Pa "
                             f"(C - C^T reaches {np.max(np.abs(C - C.T)):.3g} Pa)")
    lam = np.linalg.eigvalsh(0.5 * (C + C.T))
    if not lam[0] > 1e-12 * scale:
        raise ParameterError(f"{path}.{keys[0]}", C.tolist(), "a positive definite 6x6 "
                             f"matrix in Pa (its smallest eigenvalue is {lam[0]:.6g} Pa)")
    vscale = float(np.max(np.abs(V))) if V.size else 0.0
    if vscale == 0.0:
        return
    if not np.allclose(V, V.T, rtol=0.0, atol=1e-12 * vscale):
        raise ParameterError(f"{path}.{keys[1]}", V.tolist(), "a symmetric 6x6 matrix in "
                             f"Pa s (V - V^T reaches {np.max(np.abs(V - V.T)):.3g} Pa s)")
    mu = np.linalg.eigvalsh(0.5 * (V + V.T))
    if mu[0] < -1e-12 * vscale:
        raise ParameterError(f"{path}.{keys[1]}", V.tolist(), "a positive semi-definite 6x6 "
                             f"matrix in Pa s (its smallest eigenvalue is {mu[0]:.6g} Pa s)")


def isotropic(name: str, E: float, nu: float, density: float, tau_S: float = 0.0,
              tau_B: float = 0.0, *, path: str | None = None) -> SectionMaterial:
    """An isotropic Kelvin-Voigt material from E [Pa], nu, density [kg/m^3] and the
    retardation times tau_S, tau_B [s] (paper eqs. (4)-(6))."""
    p = path or f"materials.{name}"
    ck.positive(f"{p}.youngs_modulus", E, "Pa")
    ck.number(f"{p}.poisson_ratio", nu, "-1 < nu < 1/2 (a nearly incompressible region, "
              "e.g. rubber, may take nu = 0.4999)", low=-1.0, high=0.5, low_incl=False,
              high_incl=False)
    ck.positive(f"{p}.density", density, "kg/m^3")
    check_wave_speed(float(E), float(density), f"{p}.youngs_modulus", f"{p}.density")
    ck.nonnegative(f"{p}.tau_S", tau_S, "s")
    ck.nonnegative(f"{p}.tau_B", tau_B, "s")
    eta, zeta = viscosities_from_times(E, nu, tau_S, tau_B)
    C = isotropic_stiffness(E, nu)
    V = isotropic_viscosity(eta, zeta)
    G, K = shear_modulus(E, nu), bulk_modulus(E, nu)
    k_exc = max(0.0, K - BULK_RATIO_SPLIT * G)
    return SectionMaterial(name=name, stiffness=C, viscosity=V, density=float(density),
                           isotropic=(float(E), float(nu), float(tau_S), float(tau_B)),
                           bulk_excess=k_exc, bulk_viscosity_excess=tau_B * k_exc)


def anisotropic(name: str, stiffness: np.ndarray, viscosity: np.ndarray | None,
                density: float, orientation: tuple[float, float] = (0.0, 0.0), *,
                path: str | None = None) -> SectionMaterial:
    """An anisotropic material from Voigt matrices in its own axes (C [Pa], V [Pa s]),
    turned into the section by ``orientation`` = (rotation about the rod axis, off-axis
    angle) in degrees (see the module docstring)."""
    p = path or f"materials.{name}"
    C = np.asarray(stiffness, dtype=float)
    V = np.zeros((6, 6)) if viscosity is None else np.asarray(viscosity, dtype=float)
    _check_matrices(p, C, V, ("stiffness_matrix", "viscosity_matrix"))
    ck.positive(f"{p}.density", density, "kg/m^3")
    check_wave_speed(float(np.max(np.diag(C))), float(density), f"{p}.stiffness_matrix",
                     f"{p}.density")
    C, V = 0.5 * (C + C.T), 0.5 * (V + V.T)
    T = stress_transform(rotation(*orientation))
    Cs, Vs = T @ C @ T.T, T @ V @ T.T
    warn: tuple[str, ...] = ()
    # Reuss bulk modulus against the smallest shear-like stiffness: a nearly
    # incompressible anisotropic material is integrated without the bulk split
    k_reuss = 1.0 / float(M_VOL @ np.linalg.solve(Cs, M_VOL))
    g_min = float(np.min(np.linalg.eigvalsh(Cs[3:, 3:])))
    if k_reuss > 50.0 * g_min:
        warn = (f"material {name!r}: Reuss bulk modulus {k_reuss:.4g} Pa is "
                f"{k_reuss / g_min:.0f} times its smallest shear stiffness; anisotropic "
                "regions are integrated without the volumetric split, so a nearly "
                "incompressible one may come out too stiff (volumetric locking)",)
    return SectionMaterial(name=name, stiffness=Cs, viscosity=Vs, density=float(density),
                           orientation=(float(orientation[0]), float(orientation[1])),
                           warnings=warn)


_ISO_KEYS = ("model", "youngs_modulus", "poisson_ratio", "density", "tau", "tau_S", "tau_B",
             "eta", "zeta")
_ANI_KEYS = ("model", "stiffness_matrix", "viscosity_matrix", "density", "orientation")


def material_from_mapping(name: str, m: Any, path: str | None = None) -> SectionMaterial:
    """A material from a ``[materials.NAME]`` table (see the module docstring).

    Raises
    ------
    ParameterError
        A key is unknown or missing, or a value outside its range; the message names the
        key path (``materials.NAME.KEY``) and the unit.
    """
    p = path or f"materials.{name}"
    m = ck.table(p, m)
    model = m.get("model", "kelvin_voigt")
    if model != "kelvin_voigt":
        raise ParameterError(f"{p}.model", model, "'kelvin_voigt': the regions of a "
                             "composite section are Kelvin-Voigt materials; generalized "
                             "Maxwell regions are not supported yet (a homogeneous rod "
                             "takes a generalized Maxwell material in [material])")
    if "stiffness_matrix" in m:
        ck.no_unknown_keys(p, m, _ANI_KEYS)
        C = ck.matrix6(f"{p}.stiffness_matrix", m["stiffness_matrix"], "Pa")
        V = (ck.matrix6(f"{p}.viscosity_matrix", m["viscosity_matrix"], "Pa s")
             if "viscosity_matrix" in m else None)
        rho = ck.required(p, m, "density", "a density in kg/m^3 (> 0)")
        orient = (0.0, 0.0)
        if "orientation" in m:
            o = ck.table(f"{p}.orientation", m["orientation"])
            ck.no_unknown_keys(f"{p}.orientation", o, ("rotation", "off_axis"))
            orient = (ck.number(f"{p}.orientation.rotation", o.get("rotation", 0.0),
                                "an angle in degrees"),
                      ck.number(f"{p}.orientation.off_axis", o.get("off_axis", 0.0),
                                "an angle in degrees, -90 ... 90", low=-90.0, high=90.0))
        return replace(anisotropic(name, C, V, rho, orient, path=p), source=_plain(m))
    ck.no_unknown_keys(p, m, _ISO_KEYS)
    groups = (("tau",), ("tau_S", "tau_B"), ("eta", "zeta"))
    present = [g for g in groups if any(k in m for k in g)]
    if len(present) > 1:
        first = next(k for k in present[0] if k in m)
        second = next(k for k in present[1] if k in m)
        raise ParameterError(f"{p}.{second}", m[second], f"not together with {first!r}: give "
                             "tau, or tau_S/tau_B, or eta/zeta")
    for key, what in (("youngs_modulus", "a Young's modulus in Pa (> 0)"),
                      ("poisson_ratio", "a Poisson ratio, -1 < nu < 1/2"),
                      ("density", "a density in kg/m^3 (> 0)")):
        ck.required(p, m, key, what)
    E = ck.positive(f"{p}.youngs_modulus", m["youngs_modulus"], "Pa")
    nu = ck.number(f"{p}.poisson_ratio", m["poisson_ratio"], "-1 < nu < 1/2 (a nearly "
                   "incompressible region, e.g. rubber, may take nu = 0.4999)", low=-1.0,
                   high=0.5, low_incl=False, high_incl=False)
    tS = tB = 0.0
    if "tau" in m:
        tS = tB = ck.nonnegative(f"{p}.tau", m["tau"], "s")
    tS = ck.nonnegative(f"{p}.tau_S", m.get("tau_S", tS), "s")
    tB = ck.nonnegative(f"{p}.tau_B", m.get("tau_B", tB), "s")
    if "eta" in m:
        tS = ck.nonnegative(f"{p}.eta", m["eta"], "Pa s") / shear_modulus(E, nu)
    if "zeta" in m:
        tB = ck.nonnegative(f"{p}.zeta", m["zeta"], "Pa s") / bulk_modulus(E, nu)
    return replace(isotropic(name, E, nu, m["density"], tS, tB, path=p), source=_plain(m))


def materials_from_mapping(m: Any, path: str = "materials") -> dict[str, SectionMaterial]:
    """All materials of a ``[materials]`` table: {name: SectionMaterial}."""
    m = ck.table(path, m)
    if not m:
        raise ParameterError(path, {}, "at least one material [materials.NAME]")
    return {str(k): material_from_mapping(str(k), v, f"{path}.{k}") for k, v in m.items()}


def as_material_map(materials: Mapping[str, SectionMaterial] | Any) -> dict[str,
                                                                            SectionMaterial]:
    """Materials given as SectionMaterial objects or as a ``[materials]`` table."""
    if isinstance(materials, Mapping) and all(isinstance(v, SectionMaterial)
                                              for v in materials.values()):
        return dict(materials)
    return materials_from_mapping(materials)
